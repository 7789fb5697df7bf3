//! `phri-monitor`: attaches read-only to the live channels of a running cell
//! (subscribers only, never a publisher, never creating a channel; normal
//! scheduling, sleeping between polls).
//!
//! - `echo CHANNEL --prefix P [--count N] [--every N] [--json]`: print samples (frames summarised)
//! - `list --prefix P [--seconds S] [--json]`: live nodes, every channel's ports, rate, drops
//! - `hz CHANNEL --prefix P [--seconds S] [--once] [--json]`: rate, jitter, age, bandwidth, drops
//! - `top --prefix P [--seconds S] [--json]`: dashboard refreshing 4×/s

mod probe;

use std::collections::VecDeque;
use std::error::Error;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;
use phri_ipc::*;
use phri_runtime::{Args, Shutdown};
use serde_json::{json, Value};

use probe::{last, Probe};

type Result<T = (), E = Box<dyn Error>> = std::result::Result<T, E>;

const USAGE: &str = "usage: phri-monitor echo CHANNEL | hz CHANNEL | list | top  [--prefix PREFIX (default: $PHRI_PREFIX, else phri_)] [--seconds S] [--json] [--once] [--count N] [--every N]";

/// Pause between polls: the monitor never competes with the torque loop.
const POLL: Duration = Duration::from_millis(2);

fn main() -> ExitCode {
    phri_runtime::service::run("phri-monitor", || body().map_err(|e| e.to_string()))
}

struct NodeInfo {
    name: String,
    pid: i32,
    state: &'static str,
}

/// The cell's nodes under `prefix` (this process's own nodes left out).
fn cell_nodes(prefix: &str) -> Result<Vec<NodeInfo>> {
    let mut config = Config::default();
    config.global.prefix = FileName::new(prefix.as_bytes())
        .map_err(|e| format!("invalid prefix '{prefix}': {e:?}"))?;
    let me = std::process::id() as i32;
    let mut out = Vec::new();
    Node::<ipc::Service>::list(&config, |state| {
        let (view, st) = match &state {
            NodeState::Alive(v) => (Some(v.details().clone()), "alive"),
            NodeState::Dead(v) => (Some(v.details().clone()), "dead"),
            NodeState::Inaccessible(_) => (None, "inaccessible"),
            NodeState::Undefined(_) => (None, "undefined"),
        };
        let (name, pid) = match view.flatten() {
            Some(d) => (d.name().to_string(), d.process_id().value()),
            None => (String::new(), -1),
        };
        if pid != me {
            out.push(NodeInfo {
                name,
                pid,
                state: st,
            });
        }
        CallbackProgression::Continue
    })
    .map_err(|e| format!("cannot list the nodes under prefix '{prefix}': {e:?}"))?;
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// Parsed common options.
struct Opts {
    prefix: String,
    json: bool,
    seconds: Option<f64>,
    once: bool,
    count: u64,
    every: u64,
}

fn parse(argv: impl Iterator<Item = String>) -> Result<Opts> {
    let args = Args::parse(
        argv,
        &["--prefix", "--count", "--every", "--seconds"],
        &["--json", "--once"],
    )
    .map_err(|e| format!("{e}; {USAGE}"))?;
    let prefix = phri_runtime::prefix_or_default(args.get("--prefix"));
    let seconds = args.parse_value::<f64>("--seconds")?;
    if seconds.is_some_and(|s| !(s > 0.0 && s.is_finite())) {
        return Err("--seconds must be positive".into());
    }
    Ok(Opts {
        prefix,
        json: args.has("--json"),
        seconds,
        once: args.has("--once"),
        count: args.parse_value::<u64>("--count")?.unwrap_or(u64::MAX),
        every: args.parse_value::<u64>("--every")?.unwrap_or(1).max(1),
    })
}

/// Fail unless some live node runs under the prefix; return the nodes.
fn require_cell(prefix: &str) -> Result<Vec<NodeInfo>> {
    let nodes = cell_nodes(prefix)?;
    if !nodes.iter().any(|n| n.state == "alive") {
        return Err(format!(
            "no cell running under prefix '{prefix}' (no live iceoryx2 node; start one with deploy/up --prefix {prefix})"
        )
        .into());
    }
    Ok(nodes)
}

fn monitor_node(prefix: &str) -> Result<IpcNode, IpcError> {
    node(&format!("monitor{}", std::process::id()), prefix)
}

fn body() -> Result {
    let mut argv = std::env::args().skip(1);
    let cmd = argv.next().ok_or(USAGE)?;
    let channel = match cmd.as_str() {
        "echo" | "hz" => {
            let c = argv.next().ok_or(USAGE)?;
            probe::check_channel(&c)?;
            Some(c)
        }
        "list" | "top" => None,
        other => return Err(format!("unknown command '{other}'; {USAGE}").into()),
    };
    let opts = parse(argv)?;
    let nodes = require_cell(&opts.prefix)?;
    let shutdown = Shutdown::install()?;
    let node = monitor_node(&opts.prefix)?;
    match cmd.as_str() {
        "echo" => echo(&node, &channel.unwrap(), &opts, &shutdown),
        "hz" => hz(&node, &channel.unwrap(), &opts, &shutdown),
        "list" => list(&node, nodes, &opts, &shutdown),
        _ => top(&node, &opts, &shutdown),
    }
}

fn echo(node: &IpcNode, channel: &str, o: &Opts, sd: &Shutdown) -> Result {
    let mut p = probe::open(node, channel)?;
    if !p.present() {
        return Err(absent(channel, o));
    }
    let (mut seen, mut printed) = (0u64, 0u64);
    let json = o.json;
    let mut emit = |v: Value| -> bool {
        seen += 1;
        if seen % o.every == 0 {
            if json {
                println!("{v}");
            } else {
                println!("{}", text_line(&v));
            }
            printed += 1;
        }
        printed < o.count
    };
    let deadline = o
        .seconds
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    while !sd.requested() && deadline.is_none_or(|d| Instant::now() < d) {
        std::thread::sleep(POLL);
        if !p.poll(Some(&mut emit))? {
            break;
        }
    }
    Ok(())
}

/// One compact human-readable line from a JSON value: `key=value` pairs.
fn text_line(v: &Value) -> String {
    match v {
        Value::Object(m) => m
            .iter()
            .map(|(k, v)| format!("{k}={}", v))
            .collect::<Vec<_>>()
            .join(" "),
        other => other.to_string(),
    }
}

/// The error of a channel that does not exist.
fn absent(channel: &str, o: &Opts) -> Box<dyn Error> {
    format!(
        "channel '{channel}' does not exist under prefix '{}' (no service publishes it)",
        o.prefix
    )
    .into()
}

fn channel_json(node: &IpcNode, p: &dyn Probe) -> Result<Value, IpcError> {
    let (pubs, subs) = p.counts(node)?;
    let mut v = p.stats().summary();
    let m = v.as_object_mut().unwrap();
    m.insert("present".into(), json!(p.present()));
    m.insert("publishers".into(), json!(pubs));
    m.insert("subscribers".into(), json!(subs));
    Ok(v)
}

/// Every channel's figures, by name.
fn channels_json(
    node: &IpcNode,
    probes: &[Box<dyn Probe>],
) -> Result<serde_json::Map<String, Value>, IpcError> {
    probes
        .iter()
        .map(|p| Ok((p.name().to_string(), channel_json(node, p.as_ref())?)))
        .collect()
}

fn poll_all(probes: &mut [Box<dyn Probe>]) -> Result<(), IpcError> {
    for p in probes.iter_mut() {
        p.poll(None)?;
    }
    Ok(())
}

fn f(v: &Value, key: &str, digits: usize) -> String {
    match v.get(key).and_then(|x| x.as_f64()) {
        Some(x) => format!("{x:.digits$}"),
        None => "-".into(),
    }
}

fn human_bytes(v: &Value) -> String {
    let b = v
        .get("bandwidth_bps")
        .and_then(|x| x.as_f64())
        .unwrap_or(0.0);
    if b >= 1e6 {
        format!("{:.1} MB/s", b / 1e6)
    } else if b >= 1e3 {
        format!("{:.1} kB/s", b / 1e3)
    } else {
        format!("{b:.0} B/s")
    }
}

fn list(node: &IpcNode, nodes: Vec<NodeInfo>, o: &Opts, sd: &Shutdown) -> Result {
    let mut probes = probe::open_all(node)?;
    let t0 = Instant::now();
    let span = Duration::from_secs_f64(o.seconds.unwrap_or(1.0));
    while t0.elapsed() < span && !sd.requested() {
        std::thread::sleep(POLL);
        poll_all(&mut probes)?;
    }
    if o.json {
        let channels = channels_json(node, &probes)?;
        let nodes: Vec<Value> = nodes
            .iter()
            .map(|n| json!({"name": n.name, "pid": n.pid, "state": n.state}))
            .collect();
        println!(
            "{}",
            json!({"prefix": o.prefix, "nodes": nodes, "channels": channels})
        );
    } else {
        println!("nodes under prefix '{}':", o.prefix);
        for n in &nodes {
            println!("  {:<24} pid {:<8} {}", n.name, n.pid, n.state);
        }
        println!(
            "channels (over {:.1} s):\n  {:<22} {:>4} {:>4} {:>10} {:>8} {:>6}",
            span.as_secs_f64(),
            "name",
            "pub",
            "sub",
            "rate Hz",
            "samples",
            "drops"
        );
        for p in &probes {
            let v = channel_json(node, p.as_ref())?;
            if !p.present() {
                println!("  {:<22} (absent)", p.name());
                continue;
            }
            println!(
                "  {:<22} {:>4} {:>4} {:>10} {:>8} {:>6}",
                p.name(),
                v["publishers"].to_string(),
                v["subscribers"].to_string(),
                f(&v, "rate_hz", 1),
                v["samples"].to_string(),
                v["drops"].to_string()
            );
        }
    }
    Ok(())
}

fn hz(node: &IpcNode, channel: &str, o: &Opts, sd: &Shutdown) -> Result {
    let mut p = probe::open(node, channel)?;
    if !p.present() {
        return Err(absent(channel, o));
    }
    let span = Duration::from_secs_f64(o.seconds.unwrap_or(1.0));
    while !sd.requested() {
        let t0 = Instant::now();
        while t0.elapsed() < span && !sd.requested() {
            std::thread::sleep(POLL);
            p.poll(None)?;
        }
        let mut v = channel_json(node, p.as_ref())?;
        v.as_object_mut()
            .unwrap()
            .insert("channel".into(), json!(channel));
        if o.json {
            println!("{v}");
        } else {
            println!(
                "{channel}: {} Hz  interval mean {} ms max {} ms  age {} ms  {}  drops {}  ({} samples, pub {} sub {})",
                f(&v, "rate_hz", 1),
                f(&v, "mean_interval_ms", 3),
                f(&v, "max_interval_ms", 3),
                f(&v, "age_ms", 2),
                human_bytes(&v),
                v["drops"],
                v["samples"],
                v["publishers"],
                v["subscribers"]
            );
        }
        if o.once {
            break;
        }
        p.stats_mut().reset();
    }
    Ok(())
}

const BARS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];
const SPARK_LEN: usize = 60;

fn sparkline(values: &VecDeque<f64>) -> String {
    let finite = values.iter().copied().filter(|x| x.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
        (l.min(x), h.max(x))
    });
    values
        .iter()
        .map(|&x| {
            if !x.is_finite() {
                ' '
            } else if hi - lo < 1e-12 {
                BARS[0]
            } else {
                BARS[(((x - lo) / (hi - lo)) * 7.0).round().clamp(0.0, 7.0) as usize]
            }
        })
        .collect()
}

fn push(h: &mut VecDeque<f64>, x: f64) {
    if h.len() == SPARK_LEN {
        h.pop_front();
    }
    h.push_back(x);
}

fn top(node: &IpcNode, o: &Opts, sd: &Shutdown) -> Result {
    let mut probes = probe::open_all(node)?;
    let idx = |name: &str| probes.iter().position(|p| p.name() == name).unwrap();
    let (i_status, i_res, i_health, i_collab) = (
        idx(CONTROL_STATUS.name),
        idx(DYNAMICS_RESIDUAL.name),
        idx(SUPERVISOR_HEALTH.name),
        idx(COLLAB_STATE.name),
    );
    let (mut dist_h, mut norm_h) = (VecDeque::new(), VecDeque::new());
    let refresh = Duration::from_millis(250);
    let window_ns = 1_000_000_000;
    let t_start = Instant::now();
    let end = o.seconds.map(Duration::from_secs_f64);
    while !sd.requested() && end.is_none_or(|e| t_start.elapsed() < e) {
        let t0 = Instant::now();
        while t0.elapsed() < refresh && !sd.requested() {
            std::thread::sleep(POLL);
            poll_all(&mut probes)?;
        }
        for p in probes.iter_mut() {
            p.stats_mut().trim(window_ns);
        }
        let status: Option<ControlStatus> = last(probes[i_status].as_ref());
        let residual: Option<Residual> = last(probes[i_res].as_ref());
        let health: Option<Health> = last(probes[i_health].as_ref());
        let collab: Option<CollabState> = last(probes[i_collab].as_ref());
        let phase = collab.map(|c| CollabPhase::name_of(c.phase));
        // F̂ of the collaborative contact [N], base frame
        let force = collab
            .filter(|c| c.n_forces > 0 && c.phase != CollabPhase::Idle as u32)
            .map(|c| c.forces[0].force);
        if let Some(s) = &status {
            push(&mut dist_h, s.min_distance);
        }
        if let Some(r) = &residual {
            push(&mut norm_h, r.norm);
        }
        let services: Vec<Value> = health
            .map(|h| {
                h.services[..(h.count as usize).min(MAX_SERVICES)]
                    .iter()
                    .map(|s| {
                        json!({"name": s.name_str(), "pid": s.pid, "alive": s.alive != 0,
                               "restarts": s.restarts})
                    })
                    .collect()
            })
            .unwrap_or_default();
        let mode = status.map(|s| ControlMode::name_of(s.mode));
        let min_d = status.map(|s| s.min_distance).filter(|x| x.is_finite());
        let norm = residual.map(|r| r.norm).filter(|x| x.is_finite());
        if o.json {
            let channels = channels_json(node, &probes)?;
            println!(
                "{}",
                json!({"prefix": o.prefix, "t_s": t_start.elapsed().as_secs_f64(),
                       "mode": mode, "min_distance": min_d, "residual_norm": norm,
                       "collab_phase": phase, "contact_force_n": force,
                       "services": services, "channels": channels})
            );
        } else {
            let mut s = String::from("\x1b[2J\x1b[H");
            s += &format!(
                "phri-monitor top  prefix '{}'  t {:.1} s  (Ctrl-C quits)\n\n",
                o.prefix,
                t_start.elapsed().as_secs_f64()
            );
            s += &format!(
                "mode {}   min distance {}   residual norm {}\n",
                mode.unwrap_or("-"),
                min_d.map_or("-".into(), |d| format!("{d:.3} m")),
                norm.map_or("-".into(), |n| format!("{n:.2} Nm"))
            );
            s += &format!(
                "collaboration {}   F̂ {}\n",
                phase.unwrap_or("-"),
                force.map_or("-".into(), |f| {
                    let n = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
                    format!("{n:.1} N [{:.1}, {:.1}, {:.1}]", f[0], f[1], f[2])
                })
            );
            s += &format!("  distance {}\n", sparkline(&dist_h));
            s += &format!("  residual {}\n\n", sparkline(&norm_h));
            s += &format!(
                "{:<22} {:>4} {:>4} {:>9} {:>9} {:>9} {:>9} {:>11} {:>6}\n",
                "channel",
                "pub",
                "sub",
                "rate Hz",
                "mean ms",
                "max ms",
                "age ms",
                "bandwidth",
                "drops"
            );
            for p in &probes {
                if !p.present() {
                    s += &format!("{:<22} (absent)\n", p.name());
                    continue;
                }
                let v = channel_json(node, p.as_ref())?;
                s += &format!(
                    "{:<22} {:>4} {:>4} {:>9} {:>9} {:>9} {:>9} {:>11} {:>6}\n",
                    p.name(),
                    v["publishers"].to_string(),
                    v["subscribers"].to_string(),
                    f(&v, "rate_hz", 1),
                    f(&v, "mean_interval_ms", 3),
                    f(&v, "max_interval_ms", 3),
                    f(&v, "age_ms", 2),
                    human_bytes(&v),
                    v["total_drops"].to_string()
                );
            }
            s += &format!(
                "\n{:<16} {:>8} {:>6} {:>9}\n",
                "service", "pid", "alive", "restarts"
            );
            for sv in &services {
                s += &format!(
                    "{:<16} {:>8} {:>6} {:>9}\n",
                    sv["name"].as_str().unwrap_or("?"),
                    sv["pid"].to_string(),
                    if sv["alive"] == json!(true) {
                        "yes"
                    } else {
                        "NO"
                    },
                    sv["restarts"].to_string()
                );
            }
            print!("{s}");
            use std::io::Write;
            let _ = std::io::stdout().flush();
        }
    }
    Ok(())
}
