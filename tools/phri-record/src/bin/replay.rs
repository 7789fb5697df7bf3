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
use std::error::Error;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use phri_ipc::*;
use phri_record::json::{from_json, JsonError};
use phri_record::{is_frame_channel, read_file, ReadError};
use phri_runtime::{Args, Shutdown};
use serde_json::Value;

const USAGE: &str = "usage: phri-replay --file FILE.mcap --prefix P [--speed X] [--channels a,b]";
/// Channels phri-replay can rebuild.
const REPLAYABLE: &[&str] = &[
    ROBOT_STATE.name,
    DYNAMICS_RESIDUAL.name,
    CONTROL_STATUS.name,
    SIM_TRUTH.name,
    SIM_WORLD.name,
    PERCEPTION_REPULSION.name,
];

fn main() -> ExitCode {
    phri_runtime::service::run("phri-replay", || body().map_err(|e| e.to_string()))
}

/// A recorded message that could not be published.
#[derive(Debug, thiserror::Error)]
enum SendError {
    #[error("{channel}: {source}")]
    Json {
        channel: &'static str,
        #[source]
        source: JsonError,
    },
    #[error(transparent)]
    Ipc(#[from] IpcError),
}

trait Out {
    fn send(&mut self, v: &Value) -> Result<(), SendError>;
}

/// Publishes one channel's recorded messages (waking its readers when the channel wakes).
struct P<T: Message> {
    publisher: Publisher<T>,
}

impl<T: Message> Out for P<T> {
    fn send(&mut self, v: &Value) -> Result<(), SendError> {
        let m: T = from_json(v).map_err(|source| SendError::Json {
            channel: self.publisher.channel(),
            source,
        })?;
        Ok(self.publisher.publish(&m)?)
    }
}

/// The publisher of one channel, by name.
struct Outs<'a> {
    node: &'a IpcNode,
    out: Option<Result<Box<dyn Out>, IpcError>>,
}

impl ChannelVisitor for Outs<'_> {
    fn message<T: Message>(&mut self, channel: Channel<T>) {
        self.out = Some(
            channel
                .publisher(self.node)
                .map(|publisher| Box::new(P { publisher }) as Box<dyn Out>),
        );
    }
    fn frames(&mut self, _: FrameChannel) {}
}

fn out_for(node: &IpcNode, name: &str) -> Result<Box<dyn Out>, Box<dyn Error>> {
    let mut outs = Outs { node, out: None };
    if !REPLAYABLE.contains(&name) || !visit_named(name, &mut outs) {
        return Err(format!("cannot replay '{name}'").into());
    }
    match outs.out {
        Some(out) => Ok(out?),
        None => Err(format!("cannot replay '{name}'").into()),
    }
}

fn body() -> Result<(), Box<dyn Error>> {
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
            if c == ROBOT_COMMAND.name {
                return Err(format!(
                    "refusing to publish '{}': replay never commands the robot",
                    ROBOT_COMMAND.name
                )
                .into());
            }
            if is_frame_channel(c) {
                return Err(format!("cannot replay '{c}': frames are recorded downsampled").into());
            }
            if !REPLAYABLE.contains(&c.as_str()) {
                return Err(format!(
                    "cannot replay '{c}'; replayable channels: {}",
                    REPLAYABLE.join(", ")
                )
                .into());
            }
        }
    }

    let buf = read_file(file)?;
    // messages of the chosen channels: (log time, channel, JSON bytes)
    let mut msgs: Vec<(u64, &'static str, Vec<u8>)> = Vec::new();
    let mut in_file: BTreeMap<String, u64> = BTreeMap::new();
    for m in mcap::MessageStream::new(&buf).map_err(ReadError::mcap(file))? {
        let m = m.map_err(ReadError::mcap(file))?;
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
                return Err(format!("{file} holds no '{c}' messages").into());
            }
        }
    }
    if msgs.is_empty() {
        return Err(format!("{file}: nothing to replay").into());
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

    let shutdown = Shutdown::install()?;
    let node = node(&format!("replay{}", std::process::id()), prefix)?;
    if chosen.contains(&PERCEPTION_REPULSION.name) {
        // recorded obstacles would steer a live controller's avoidance
        let commanded = ROBOT_COMMAND
            .ports(&node)?
            .is_some_and(|(publishers, _)| publishers > 0);
        if commanded {
            return Err(format!(
                "refusing to replay '{}' into prefix '{prefix}': a controller publishes '{}' there and would avoid recorded obstacles (leave it out with --channels)",
                PERCEPTION_REPULSION.name, ROBOT_COMMAND.name
            )
            .into());
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
