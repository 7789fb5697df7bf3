//! `phri-replay --file FILE.mcap --prefix P [--speed X] [--channels a,b]`
//!
//! Publishes the recorded messages of the chosen channels into the cell with
//! prefix `P` at their recorded timing (scaled by `--speed`), rebuilding the
//! `#[repr(C)]` messages from their JSON. Replayable: `robot/state`,
//! `dynamics/residual`, `control/status`, `sim/truth`, `sim/world`,
//! `perception/repulsion` (the default: those of them present in the file).
//! `robot/command` is never published, nor are depth frames (they were
//! recorded downsampled), nor `robot/stats` and `supervisor/health` (live
//! summaries of processes, not data). Repulsion results steer a controller's
//! avoidance, so they are refused into a cell whose robot is commanded.

use std::collections::BTreeMap;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use iceoryx2::prelude::*;
use phri_ipc::*;
use phri_record::json::FromJson;
use phri_record::{is_frame_channel, read_file};
use phri_runtime::{Args, Shutdown};
use serde_json::Value;

const USAGE: &str = "usage: phri-replay --file FILE.mcap --prefix P [--speed X] [--channels a,b]";
/// Channels phri-replay can rebuild.
const REPLAYABLE: &[&str] = &[
    ROBOT_STATE,
    DYNAMICS_RESIDUAL,
    CONTROL_STATUS,
    SIM_TRUTH,
    SIM_WORLD,
    PERCEPTION_REPULSION,
];

fn main() -> ExitCode {
    phri_runtime::service::run("phri-replay", body)
}

trait Out {
    fn send(&mut self, v: &Value) -> Result<(), String>;
}

struct P<T: FromJson> {
    name: &'static str,
    publisher: Pub<T>,
    notifier: Option<Notifier>,
}

impl<T: FromJson> Out for P<T> {
    fn send(&mut self, v: &Value) -> Result<(), String> {
        let m = T::from_json(v).map_err(|e| format!("{}: {e}", self.name))?;
        publish(&self.publisher, self.name, &m).map_err(|e| e.to_string())?;
        if let Some(n) = &self.notifier {
            let _ = n.notify();
        }
        Ok(())
    }
}

fn out_for(node: &Node<ipc::Service>, name: &'static str) -> Result<Box<dyn Out>, String> {
    fn p<T: FromJson>(
        node: &Node<ipc::Service>,
        name: &'static str,
    ) -> Result<Box<dyn Out>, String> {
        let publisher = publisher::<T>(node, name)
            .map_err(|e| format!("{e} (does a running service already publish it?)"))?;
        // readers of robot/state and dynamics/residual wait on the event of the same name
        let notifier = match name {
            ROBOT_STATE | DYNAMICS_RESIDUAL => notifier(node, name).ok(),
            _ => None,
        };
        Ok(Box::new(P::<T> {
            name,
            publisher,
            notifier,
        }))
    }
    match name {
        ROBOT_STATE => p::<JointState>(node, name),
        DYNAMICS_RESIDUAL => p::<Residual>(node, name),
        CONTROL_STATUS => p::<ControlStatus>(node, name),
        SIM_TRUTH => p::<Truth>(node, name),
        SIM_WORLD => p::<WorldState>(node, name),
        PERCEPTION_REPULSION => p::<RepulsionResult>(node, name),
        _ => Err(format!("cannot replay '{name}'")),
    }
}

fn body() -> Result<(), String> {
    let args = Args::parse(
        std::env::args().skip(1),
        &["--file", "--prefix", "--speed", "--channels"],
        &[],
    )
    .map_err(|e| format!("{e}; {USAGE}"))?;
    let file = args
        .get("--file")
        .ok_or_else(|| format!("--file is required; {USAGE}"))?;
    let prefix = args
        .get("--prefix")
        .ok_or_else(|| format!("--prefix is required; {USAGE}"))?;
    let speed = args.parse_value::<f64>("--speed")?.unwrap_or(1.0);
    if !(speed > 0.0 && speed.is_finite()) {
        return Err("--speed must be positive".into());
    }
    let requested: Option<Vec<String>> = args.get("--channels").map(|s| {
        s.split(',')
            .map(|c| c.trim().to_string())
            .filter(|c| !c.is_empty())
            .collect()
    });
    if let Some(req) = &requested {
        for c in req {
            if c == ROBOT_COMMAND {
                return Err(format!(
                    "refusing to publish '{ROBOT_COMMAND}': replay never commands the robot"
                ));
            }
            if is_frame_channel(c) {
                return Err(format!(
                    "cannot replay '{c}': frames are recorded downsampled"
                ));
            }
            if !REPLAYABLE.contains(&c.as_str()) {
                return Err(format!(
                    "cannot replay '{c}'; replayable channels: {}",
                    REPLAYABLE.join(", ")
                ));
            }
        }
    }

    let buf = read_file(file)?;
    // messages of the chosen channels: (log time, channel, JSON bytes)
    let mut msgs: Vec<(u64, &'static str, Vec<u8>)> = Vec::new();
    let mut in_file: BTreeMap<String, u64> = BTreeMap::new();
    for m in mcap::MessageStream::new(&buf).map_err(|e| format!("{file}: {e}"))? {
        let m = m.map_err(|e| format!("{file}: {e}"))?;
        let topic = m.channel.topic.as_str();
        *in_file.entry(topic.to_string()).or_default() += 1;
        let Some(&name) = REPLAYABLE.iter().find(|c| **c == topic) else {
            continue;
        };
        if requested
            .as_ref()
            .is_none_or(|r| r.iter().any(|c| c == name))
        {
            msgs.push((m.log_time, name, m.data.into_owned()));
        }
    }
    msgs.sort_by_key(|m| m.0);
    let mut chosen: Vec<&'static str> = msgs.iter().map(|m| m.1).collect();
    chosen.sort();
    chosen.dedup();
    if let Some(req) = &requested {
        for c in req {
            if !chosen.contains(&c.as_str()) {
                return Err(format!("{file} holds no '{c}' messages"));
            }
        }
    }
    if msgs.is_empty() {
        return Err(format!("{file}: nothing to replay"));
    }
    let skipped: Vec<&String> = in_file
        .keys()
        .filter(|k| !chosen.contains(&k.as_str()))
        .collect();
    eprintln!(
        "phri-replay: {} messages of {} at {speed}x; not replayed: {}",
        msgs.len(),
        chosen.join(", "),
        skipped
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );

    let shutdown = Shutdown::install().map_err(|e| e.to_string())?;
    let node = node(&format!("replay{}", std::process::id()), prefix).map_err(|e| e.to_string())?;
    if chosen.contains(&PERCEPTION_REPULSION) {
        // recorded obstacles would steer a live controller's avoidance
        let commanded = open_existing_pubsub::<TorqueCommand>(&node, ROBOT_COMMAND)
            .map_err(|e| e.to_string())?
            .is_some_and(|f| f.dynamic_config().number_of_publishers() > 0);
        if commanded {
            return Err(format!(
                "refusing to replay '{PERCEPTION_REPULSION}' into prefix '{prefix}': a controller publishes '{ROBOT_COMMAND}' there and would avoid recorded obstacles (leave it out with --channels)"
            ));
        }
    }
    let mut outs: BTreeMap<&'static str, Box<dyn Out>> = BTreeMap::new();
    for c in &chosen {
        outs.insert(c, out_for(&node, c)?);
    }
    let mut counts: BTreeMap<&'static str, u64> = chosen.iter().map(|c| (*c, 0)).collect();
    let t_first = msgs[0].0;
    let t0 = Instant::now();
    let mut next_report = t0 + Duration::from_secs(1);
    for (t, name, data) in &msgs {
        if shutdown.requested() {
            break;
        }
        let due = t0 + Duration::from_secs_f64((t - t_first) as f64 * 1e-9 / speed);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        let v: Value = serde_json::from_slice(data).map_err(|e| format!("{file}: {name}: {e}"))?;
        outs.get_mut(name).unwrap().send(&v)?;
        *counts.get_mut(name).unwrap() += 1;
        if Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            eprintln!(
                "phri-replay: {:.0} s (recording {:.1} s)  {}",
                t0.elapsed().as_secs_f64(),
                (t - t_first) as f64 * 1e-9,
                progress(&counts)
            );
        }
    }
    eprintln!(
        "phri-replay: done after {:.1} s: {}",
        t0.elapsed().as_secs_f64(),
        progress(&counts)
    );
    drop(outs);
    drop(node);
    let _ = remove_leftovers(prefix);
    Ok(())
}

fn progress(counts: &BTreeMap<&'static str, u64>) -> String {
    counts
        .iter()
        .map(|(c, n)| format!("{c}={n}"))
        .collect::<Vec<_>>()
        .join(" ")
}
