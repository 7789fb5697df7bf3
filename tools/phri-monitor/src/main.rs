//! `phri-monitor`: attaches read-only to the live channels of a running cell
//! (subscribers only, never a publisher, never creating a channel; normal
//! scheduling, sleeping between polls).
//!
//! - `echo CHANNEL [--count N] [--every N] [--seconds S] [--json]`: print samples (frames summarised)
//! - `list [--seconds S] [--json]`: live nodes, every channel's ports, rate, drops
//! - `hz CHANNEL [--seconds S] [--once] [--json]`: rate, jitter, age, bandwidth, drops
//! - `top [--seconds S] [--json] [--once]`: dashboard (ratatui), refreshed 4×/s
//! - `completions SHELL`: a shell completion script
//!
//! Every command takes `--prefix P` (else `PHRI_PREFIX`, else `phri_`).
//! `top` needs a terminal on stdout: without one it says so in one line and
//! exits 2 (`top --once` prints one text snapshot, `top --json` JSON lines).

mod probe;
mod top;

use std::collections::HashMap;
use std::error::Error;
use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::builder::PossibleValuesParser;
use clap::{Parser, Subcommand};
use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;
use phri_ipc::*;
use phri_runtime::Shutdown;
use serde_json::{json, Value};

use probe::{last, Probe};
use top::{ChannelRow, CpuMeter, KeyOutcome, ServiceRow, Snapshot, TopState, View};

type Result<T = (), E = Box<dyn Error>> = std::result::Result<T, E>;

const BIN: &str = "phri-monitor";

/// Pause between polls: the monitor never competes with the torque loop.
const POLL: Duration = Duration::from_millis(2);
/// `top`'s refresh period: statistics trimmed, the newest values read, the screen redrawn.
const REFRESH: Duration = Duration::from_millis(250);
/// Window of `top`'s channel statistics \[ns\].
const WINDOW_NS: u64 = 1_000_000_000;
/// What `top --once` watches before printing its one snapshot.
const ONCE_SPAN: Duration = Duration::from_secs(1);
/// Size of `top --once`'s snapshot when stdout is not a terminal [columns, rows].
const SNAPSHOT_SIZE: (u16, u16) = (160, 48);

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Attaches read-only to the live channels of a running cell: echo a channel, measure its rate, list the nodes and channels, or watch a dashboard",
    propagate_version = true
)]
struct Cli {
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV, global = true)]
    prefix: Option<String>,
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Print a channel's samples as key=value lines (frames summarised)
    Echo {
        /// Channel to print
        #[arg(value_parser = channel_names())]
        channel: String,
        /// Stop after printing N samples
        #[arg(long, value_name = "N")]
        count: Option<u64>,
        /// Print one sample in N (0 counts as 1)
        #[arg(long, value_name = "N", default_value_t = 1)]
        every: u64,
        /// Stop after S seconds
        #[arg(long, value_name = "S", value_parser = positive)]
        seconds: Option<f64>,
        /// One JSON object per sample
        #[arg(long)]
        json: bool,
    },
    /// Measure a channel: rate, interval, age, bandwidth, drops, each window
    Hz {
        /// Channel to measure
        #[arg(value_parser = channel_names())]
        channel: String,
        /// Measuring window \[s\]
        #[arg(long, value_name = "S", value_parser = positive, default_value_t = 1.0)]
        seconds: f64,
        /// One window, then exit
        #[arg(long)]
        once: bool,
        /// One JSON object per window
        #[arg(long)]
        json: bool,
    },
    /// The cell's nodes and every channel's ports, rate, samples and drops
    List {
        /// Measuring window \[s\]
        #[arg(long, value_name = "S", value_parser = positive, default_value_t = 1.0)]
        seconds: f64,
        /// One JSON object
        #[arg(long)]
        json: bool,
    },
    /// Dashboard of the cell: channels (stale ones in red), services, the controller's mode, alarms and live plots; q quits, s sorts, Up/Down select a channel, Enter shows its newest message
    Top {
        /// Stop after S seconds [default: until q or Ctrl-C]
        #[arg(long, value_name = "S", value_parser = positive)]
        seconds: Option<f64>,
        /// A JSON object per refresh (4 per second) instead of the dashboard
        #[arg(long)]
        json: bool,
        /// Watch 1 s, print one snapshot (text, or JSON with --json) and exit; works without a terminal
        #[arg(long)]
        once: bool,
    },
    /// Print a shell completion script to stdout
    Completions {
        /// Shell to write the script for
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

/// The cell's channel names, for the CHANNEL argument (and its completion):
/// every channel, then the further cameras' (`camera/1/depth`, …).
fn channel_names() -> PossibleValuesParser {
    PossibleValuesParser::new(ALL.iter().chain(FURTHER_CAMERAS).copied())
}

/// A finite number of seconds above 0.
fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        Ok(_) => Err("must be positive".to_string()),
        Err(e) => Err(e.to_string()),
    }
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Cmd::Completions { shell } = cli.cmd {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let code = phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()));
    // the last node out of the prefix takes back what iceoryx2 left
    let _ = phri_ipc::remove_leftovers(&prefix);
    code
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

/// Options of `echo`, `hz` and `list`.
struct Opts {
    prefix: String,
    json: bool,
    seconds: Option<f64>,
    once: bool,
    count: u64,
    every: u64,
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

fn body(cli: Cli) -> Result {
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let mut o = Opts {
        prefix,
        json: false,
        seconds: None,
        once: false,
        count: u64::MAX,
        every: 1,
    };
    let dashboard = matches!(
        cli.cmd,
        Cmd::Top {
            json: false,
            once: false,
            ..
        }
    );
    if dashboard && !std::io::stdout().is_terminal() {
        return Err("top: stdout is not a terminal; use `top --once` for one text snapshot or `top --json` for a JSON line per refresh".into());
    }
    let nodes = require_cell(&o.prefix)?;
    let shutdown = Shutdown::install()?;
    let node = monitor_node(&o.prefix)?;
    match cli.cmd {
        Cmd::Echo {
            channel,
            count,
            every,
            seconds,
            json,
        } => {
            o.count = count.unwrap_or(u64::MAX);
            o.every = every.max(1);
            o.seconds = seconds;
            o.json = json;
            echo(&node, &channel, &o, &shutdown)
        }
        Cmd::Hz {
            channel,
            seconds,
            once,
            json,
        } => {
            o.seconds = Some(seconds);
            o.once = once;
            o.json = json;
            hz(&node, &channel, &o, &shutdown)
        }
        Cmd::List { seconds, json } => {
            o.seconds = Some(seconds);
            o.json = json;
            list(&node, nodes, &o, &shutdown)
        }
        Cmd::Top {
            seconds,
            json,
            once,
        } => {
            let end = seconds.map(Duration::from_secs_f64);
            if json || once {
                top_lines(&node, &o.prefix, end, json, once, &shutdown)
            } else {
                top_dashboard(&node, &o.prefix, end, &shutdown)
            }
        }
        Cmd::Completions { .. } => Ok(()),
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
                println!("{}", top::echo_fields(&v).join(" "));
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

/// Every channel's probe, their windows opened once all are open: opening
/// thirty channels on a loaded machine can take longer than the fastest
/// queue is deep (256 ms of robot/state), and what overflowed before the
/// first read would be missing from a window without showing as a drop.
fn open_windows(node: &IpcNode) -> Result<Vec<Box<dyn Probe>>, probe::ProbeError> {
    let mut probes = probe::open_all(node)?;
    for p in probes.iter_mut() {
        p.poll(None)?;
        p.stats_mut().reset();
    }
    Ok(probes)
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

fn list(node: &IpcNode, nodes: Vec<NodeInfo>, o: &Opts, sd: &Shutdown) -> Result {
    let mut probes = open_windows(node)?;
    let t0 = Instant::now();
    let span = Duration::from_secs_f64(o.seconds.unwrap_or(1.0));
    while t0.elapsed() < span && !sd.requested() {
        std::thread::sleep(POLL);
        poll_all(&mut probes)?;
    }
    // each window closes right after its own last read
    for p in probes.iter_mut() {
        p.poll(None)?;
        p.stats_mut().close();
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
        // the window closes at its last read, not after the counts
        // (which take time on a busy host)
        p.poll(None)?;
        p.stats_mut().close();
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
                top::human_bandwidth(v["bandwidth_bps"].as_f64().unwrap_or(0.0)),
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

/// `top`'s data side: every channel's probe, and the newest messages read into a [`TopState`].
struct Sampler {
    probes: Vec<Box<dyn Probe>>,
    i_state: usize,
    i_status: usize,
    i_res: usize,
    i_health: usize,
    i_health_more: usize,
    i_collab: usize,
    /// each stream's mean interval when last measured \[ms\]
    known_mean_ms: HashMap<&'static str, f64>,
    /// each service's CPU use
    cpu: CpuMeter,
    /// `[services.NAME] cpu_budget` of the run's configuration
    budgets: HashMap<String, f64>,
}

/// The services' CPU budgets in the configuration the cell with `prefix`
/// runs (its run directory's `config.toml`; none when it is not there).
fn cpu_budgets(prefix: &str) -> HashMap<String, f64> {
    let Ok(dir) = phri_runtime::rundir::default_run_dir(prefix) else {
        return HashMap::new();
    };
    let Ok(loaded) = phri_config::Loaded::load(&dir.join("config.toml"), None, &[]) else {
        return HashMap::new();
    };
    loaded
        .config
        .services
        .iter()
        .filter_map(|(n, s)| Some((n.clone(), s.cpu_budget?)))
        .collect()
}

impl Sampler {
    fn open(node: &IpcNode, prefix: &str) -> Result<Sampler> {
        let probes = open_windows(node)?;
        let idx = |name: &str| {
            probes
                .iter()
                .position(|p| p.name() == name)
                .ok_or_else(|| format!("channel '{name}' has no probe"))
        };
        Ok(Sampler {
            i_state: idx(ROBOT_STATE.name)?,
            i_status: idx(CONTROL_STATUS.name)?,
            i_res: idx(DYNAMICS_RESIDUAL.name)?,
            i_health: idx(SUPERVISOR_HEALTH.name)?,
            i_health_more: idx(SUPERVISOR_HEALTH_MORE.name)?,
            i_collab: idx(COLLAB_STATE.name)?,
            known_mean_ms: HashMap::new(),
            cpu: CpuMeter::default(),
            budgets: cpu_budgets(prefix),
            probes,
        })
    }

    /// Drain every channel's queue into its statistics.
    fn poll(&mut self) -> Result<(), IpcError> {
        poll_all(&mut self.probes)
    }

    /// One refresh at `t_s` [s since start]: trim the statistics to their
    /// window, read the newest messages into `st`, extend the plots; the
    /// channels' figures are returned as `top --json` prints them.
    fn refresh(
        &mut self,
        node: &IpcNode,
        st: &mut TopState,
        t_s: f64,
    ) -> Result<serde_json::Map<String, Value>, IpcError> {
        // each window ends at its last read, not after the counts
        for p in self.probes.iter_mut() {
            p.poll(None)?;
            p.stats_mut().trim(WINDOW_NS);
            p.stats_mut().close();
        }
        let state: Option<JointState> = last(self.probes[self.i_state].as_ref());
        let status: Option<ControlStatus> = last(self.probes[self.i_status].as_ref());
        let residual: Option<Residual> = last(self.probes[self.i_res].as_ref());
        let health: Option<Health> = last(self.probes[self.i_health].as_ref());
        let collab: Option<CollabState> = last(self.probes[self.i_collab].as_ref());
        st.t_s = t_s;
        st.snapshot = Snapshot {
            mode: status.map(|s| ControlMode::name_of(s.mode)),
            min_distance: status.map(|s| s.min_distance).filter(|x| x.is_finite()),
            residual_norm: residual.map(|r| r.norm).filter(|x| x.is_finite()),
            residual_flags: residual.map_or(0, |r| r.flags),
            collab_phase: collab.map(|c| CollabPhase::name_of(c.phase)),
            contact_force: collab
                .filter(|c| c.n_forces > 0 && c.phase != CollabPhase::Idle as u32)
                .map(|c| c.forces[0].force),
            braking: state.is_some_and(|s| s.status & robot_status::BRAKING != 0),
            health_seen: health.is_some(),
        };
        let more: Option<Health> = last(self.probes[self.i_health_more].as_ref());
        let listed = |h: &Health, first: usize| {
            let n = (h.count as usize).saturating_sub(first).min(MAX_SERVICES);
            h.services[..n].to_vec()
        };
        let mut services = health.map(|h| listed(&h, 0)).unwrap_or_default();
        if let (Some(h), Some(m)) = (health, more) {
            if h.count as usize > MAX_SERVICES {
                services.extend(listed(&m, MAX_SERVICES));
            }
        }
        st.services = services
            .iter()
            .map(|s| {
                let name = s.name_str().to_string();
                let cpu_ns = u32::try_from(s.pid)
                    .ok()
                    .filter(|_| s.alive != 0)
                    .and_then(phri_runtime::cputime::cpu_time_ns);
                let cpu_share = cpu_ns.and_then(|c| self.cpu.share(s.pid, t_s, c));
                ServiceRow {
                    cpu_budget: self.budgets.get(&name).copied(),
                    name,
                    pid: s.pid,
                    alive: s.alive != 0,
                    restarts: s.restarts,
                    cpu_share,
                }
            })
            .collect();
        let listed: Vec<i32> = st.services.iter().map(|s| s.pid).collect();
        self.cpu.keep_only(&listed);
        let channels = channels_json(node, &self.probes)?;
        st.channels = self
            .probes
            .iter()
            .map(|p| {
                let v = channels.get(p.name()).unwrap_or(&Value::Null);
                let name = p.name();
                if let Some(m) = v.get("mean_interval_ms").and_then(Value::as_f64) {
                    self.known_mean_ms.insert(name, m);
                }
                let known = self.known_mean_ms.get(name).copied();
                let recv_age = p.stats().recv_age_ms();
                ChannelRow::from_json(name, v, ON_DEMAND.contains(&name), known, recv_age)
            })
            .collect();
        let h = &mut st.history;
        if let Some(s) = status {
            h.distance.push(t_s, s.min_distance);
        }
        if let Some(r) = residual {
            h.residual.push(t_s, r.norm);
        }
        if let Some(s) = state {
            let dof = (s.dof as usize).min(MAX_DOF);
            h.torque.resize_with(dof, Default::default);
            for (series, &tau) in h.torque.iter_mut().zip(&s.tau[..dof]) {
                series.push(t_s, tau);
            }
        }
        self.follow_echo(st);
        Ok(channels)
    }

    /// Keep the echoed channel's newest message in `st` (and only that
    /// channel's frames summarised).
    fn follow_echo(&mut self, st: &mut TopState) {
        let shown = match st.view {
            View::Echo(name) => Some(name),
            View::Channels => None,
        };
        for p in self.probes.iter_mut() {
            let on = shown == Some(p.name());
            p.keep_latest(on);
            if on {
                if let Some(v) = p.latest() {
                    st.echo = Some(v);
                }
            }
        }
    }
}

/// `top`'s JSON line (`--json`): the snapshot, the services and every channel's figures.
fn top_json(
    prefix: &str,
    t_s: f64,
    st: &TopState,
    channels: serde_json::Map<String, Value>,
) -> Value {
    let s = &st.snapshot;
    let services: Vec<Value> = st
        .services
        .iter()
        .map(|s| {
            json!({"name": s.name, "pid": s.pid, "alive": s.alive, "restarts": s.restarts,
                   "cpu_share": s.cpu_share, "cpu_budget": s.cpu_budget})
        })
        .collect();
    json!({"prefix": prefix, "t_s": t_s,
           "mode": s.mode, "min_distance": s.min_distance, "residual_norm": s.residual_norm,
           "collab_phase": s.collab_phase, "contact_force_n": s.contact_force,
           "services": services, "channels": channels})
}

/// `top --json` (a line per refresh) and `top --once` (watch [`ONCE_SPAN`],
/// then one snapshot: the dashboard as text, or one JSON line).
fn top_lines(
    node: &IpcNode,
    prefix: &str,
    end: Option<Duration>,
    json: bool,
    once: bool,
    sd: &Shutdown,
) -> Result {
    let mut sampler = Sampler::open(node, prefix)?;
    let mut st = TopState::new(prefix);
    let t_start = Instant::now();
    let ended = |t: Duration| end.is_some_and(|e| t >= e);
    while !sd.requested() && !ended(t_start.elapsed()) {
        let t0 = Instant::now();
        while t0.elapsed() < REFRESH && !sd.requested() {
            std::thread::sleep(POLL);
            sampler.poll()?;
        }
        let channels = sampler.refresh(node, &mut st, t_start.elapsed().as_secs_f64())?;
        let t = t_start.elapsed();
        let done = once && (t >= ONCE_SPAN || sd.requested() || ended(t));
        if json && (!once || done) {
            println!("{}", top_json(prefix, t.as_secs_f64(), &st, channels));
        }
        if done {
            if !json {
                print!("{}", snapshot_text(&st));
            }
            break;
        }
    }
    Ok(())
}

/// The dashboard drawn off screen at the terminal's size (else
/// [`SNAPSHOT_SIZE`]), as plain text.
fn snapshot_text(st: &TopState) -> String {
    let (w, h) = if std::io::stdout().is_terminal() {
        ratatui::crossterm::terminal::size().unwrap_or(SNAPSHOT_SIZE)
    } else {
        SNAPSHOT_SIZE
    };
    let area = ratatui::layout::Rect::new(0, 0, w, h);
    let mut buf = ratatui::buffer::Buffer::empty(area);
    top::render(st, area, &mut buf);
    top::buffer_text(&buf)
}

/// Gives the terminal back (raw mode off, main screen) however the dashboard ends;
/// a panic is covered by the hook `ratatui::try_init` installs.
struct RestoreTerminal;

impl Drop for RestoreTerminal {
    fn drop(&mut self) {
        ratatui::restore();
    }
}

/// The live dashboard: redrawn (only the cells that changed) at each refresh,
/// key and resize; keys as [`top::on_key`].
fn top_dashboard(node: &IpcNode, prefix: &str, end: Option<Duration>, sd: &Shutdown) -> Result {
    use ratatui::crossterm::event::{self, Event};
    let mut sampler = Sampler::open(node, prefix)?;
    let mut st = TopState::new(prefix);
    let mut term =
        ratatui::try_init().map_err(|e| format!("top: cannot set up the terminal: {e}"))?;
    let _restore = RestoreTerminal;
    let t_start = Instant::now();
    let mut next = t_start + REFRESH;
    let mut dirty = true;
    while !sd.requested() && end.is_none_or(|e| t_start.elapsed() < e) {
        if dirty {
            term.draw(|f| top::render(&st, f.area(), f.buffer_mut()))?;
            dirty = false;
        }
        // waiting for a key is the pause between polls
        if event::poll(POLL)? {
            match event::read()? {
                Event::Key(k) => {
                    if top::on_key(&mut st, k) == KeyOutcome::Quit {
                        break;
                    }
                    sampler.follow_echo(&mut st);
                    dirty = true;
                }
                Event::Resize(..) => dirty = true,
                _ => {}
            }
        }
        sampler.poll()?;
        let now = Instant::now();
        if now >= next {
            sampler.refresh(node, &mut st, t_start.elapsed().as_secs_f64())?;
            next = (next + REFRESH).max(now);
            dirty = true;
        }
    }
    Ok(())
}
