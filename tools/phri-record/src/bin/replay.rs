//! `phri-replay --file FILE.mcap [--prefix P] [--speed X] [--channels a,b]`
//!
//! Publishes the recorded messages of the chosen channels into the cell with
//! prefix `P` (`--prefix`, else `PHRI_PREFIX`, else `phri_`, like every
//! tool) at their recorded timing (scaled by `--speed`), rebuilding the
//! `#[repr(C)]` messages from their JSON. Replayable: `robot/state`,
//! `dynamics/residual`, `control/status`, `sim/truth`, `sim/world`,
//! `perception/repulsion` (the default: those of them present in the file).
//! `robot/command` is never published, nor are depth frames (they were
//! recorded downsampled), nor `robot/stats` and `supervisor/health` (live
//! summaries of processes, not data). Repulsion results steer a controller's
//! avoidance, so they are refused into a cell whose robot is commanded.
//! Into a prefix where a live cell runs, the others are refused as well: every
//! replayable channel but the repulsion results takes one publisher, and the
//! cell's own holds it. A progress bar on stderr when it is a terminal; in a
//! pipe, the per-second lines it always printed.

use std::collections::BTreeMap;
use std::error::Error;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use phri_ipc::*;
use phri_record::json::{from_json, JsonError};
use phri_record::progress::Progress;
use phri_record::{is_frame_channel, read_file, ReadError};
use phri_runtime::cli::CompletionsCmd;
use phri_runtime::Shutdown;
use serde_json::Value;

const BIN: &str = "phri-replay";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Publishes a phri-record recording (MCAP) into a cell at its recorded timing: robot/state, dynamics/residual, control/status, sim/truth, sim/world, perception/repulsion; never robot/command",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    /// Recording to replay (MCAP written by phri-record)
    #[arg(long, value_name = "FILE.mcap", required = true)]
    file: Option<String>,
    /// iceoryx2 prefix of the cell to publish into [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// Replay speed: 2 replays twice as fast as recorded, 0.5 at half speed
    #[arg(long, value_name = "X", default_value_t = 1.0, value_parser = positive)]
    speed: f64,
    /// Channels to replay, comma-separated [default: every replayable channel in the file]
    #[arg(long, value_name = "a,b")]
    channels: Option<String>,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

/// A finite speed above 0.
fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        Ok(_) => Err("must be positive".to_string()),
        Err(e) => Err(e.to_string()),
    }
}
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
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()))
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

fn out_for(node: &IpcNode, prefix: &str, name: &str) -> Result<Box<dyn Out>, Box<dyn Error>> {
    let mut outs = Outs { node, out: None };
    if !REPLAYABLE.contains(&name) || !visit_named(name, &mut outs) {
        return Err(format!("cannot replay '{name}'").into());
    }
    match outs.out {
        Some(Ok(out)) => Ok(out),
        // a live cell's own publisher holds the channel
        Some(Err(e @ IpcError::PublisherTaken { .. })) => Err(format!(
            "refusing to replay into prefix '{prefix}': {e}; a cell runs there: choose another with --prefix"
        )
        .into()),
        Some(Err(e)) => Err(e.into()),
        None => Err(format!("cannot replay '{name}'").into()),
    }
}

/// One recorded message to replay: (log time \[ns\], channel, JSON bytes).
type Recorded = (u64, &'static str, Vec<u8>);

fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    // clap requires --file unless a subcommand is given
    let Some(file) = cli.file.as_deref() else {
        return Err("--file is required".into());
    };
    let prefix = &phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let speed = cli.speed;
    let requested = requested_channels(cli.channels.as_deref())?;
    let buf = read_file(file)?;
    let (msgs, chosen, in_file) = recorded(&buf, file, requested.as_deref())?;
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
        refuse_if_commanded(&node, prefix)?;
    }
    let mut outs: BTreeMap<&'static str, Box<dyn Out>> = BTreeMap::new();
    for c in &chosen {
        outs.insert(c, out_for(&node, prefix, c)?);
    }
    let counts: BTreeMap<&'static str, u64> = chosen.iter().map(|c| (*c, 0)).collect();
    play(&msgs, &mut outs, counts, &shutdown, speed, file)?;
    drop(outs);
    drop(node);
    let _ = remove_leftovers(prefix);
    Ok(())
}

/// The channels `--channels` names (none: every replayable one in the
/// file), refusing `robot/command`, frames and the unreplayable.
fn requested_channels(channels: Option<&str>) -> Result<Option<Vec<String>>, Box<dyn Error>> {
    let requested: Option<Vec<String>> = channels.map(|s| {
        s.split(',')
            .map(|c| c.trim().to_string())
            .filter(|c| !c.is_empty())
            .collect()
    });
    for c in requested.iter().flatten() {
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
    Ok(requested)
}

/// The messages of the recording `buf` (read from `file`) to replay, in
/// time order: those of the `requested` channels, else of every replayable
/// one; the channels they are on; the messages per topic in the file.
#[allow(clippy::type_complexity)]
fn recorded(
    buf: &[u8],
    file: &str,
    requested: Option<&[String]>,
) -> Result<(Vec<Recorded>, Vec<&'static str>, BTreeMap<String, u64>), Box<dyn Error>> {
    let mut msgs: Vec<Recorded> = Vec::new();
    let mut in_file: BTreeMap<String, u64> = BTreeMap::new();
    for m in mcap::MessageStream::new(buf).map_err(ReadError::mcap(file))? {
        let m = m.map_err(ReadError::mcap(file))?;
        let topic = m.channel.topic.as_str();
        *in_file.entry(topic.to_string()).or_default() += 1;
        let Some(&name) = REPLAYABLE.iter().find(|c| **c == topic) else {
            continue;
        };
        if requested.is_none_or(|r| r.iter().any(|c| c == name)) {
            msgs.push((m.log_time, name, m.data.into_owned()));
        }
    }
    msgs.sort_by_key(|m| m.0);
    let mut chosen: Vec<&'static str> = msgs.iter().map(|m| m.1).collect();
    chosen.sort();
    chosen.dedup();
    for c in requested.into_iter().flatten() {
        if !chosen.contains(&c.as_str()) {
            return Err(format!("{file} holds no '{c}' messages").into());
        }
    }
    if msgs.is_empty() {
        return Err(format!("{file}: nothing to replay").into());
    }
    Ok((msgs, chosen, in_file))
}

/// Refuses repulsion results into a cell whose robot is commanded: recorded
/// obstacles would steer a live controller's avoidance.
fn refuse_if_commanded(node: &IpcNode, prefix: &str) -> Result<(), Box<dyn Error>> {
    let commanded = ROBOT_COMMAND
        .ports(node)?
        .is_some_and(|(publishers, _)| publishers > 0);
    if commanded {
        return Err(format!(
            "refusing to replay '{}' into prefix '{prefix}': a controller publishes '{}' there and would avoid recorded obstacles (leave it out with --channels)",
            PERCEPTION_REPULSION.name, ROBOT_COMMAND.name
        )
        .into());
    }
    Ok(())
}

/// Publishes `msgs` through `outs` at their recorded timing scaled by
/// `speed`, until the end or `shutdown`; `counts` per channel, reported.
fn play(
    msgs: &[Recorded],
    outs: &mut BTreeMap<&'static str, Box<dyn Out>>,
    mut counts: BTreeMap<&'static str, u64>,
    shutdown: &Shutdown,
    speed: f64,
    file: &str,
) -> Result<(), Box<dyn Error>> {
    let t_first = msgs[0].0;
    let t0 = Instant::now();
    let mut next_report = t0 + Duration::from_secs(1);
    let bar = Progress::new(BIN, Some(msgs.len() as u64), "messages");
    for (t, name, data) in msgs {
        if shutdown.requested() {
            break;
        }
        let due = t0 + Duration::from_secs_f64((t - t_first) as f64 * 1e-9 / speed);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        let v: Value = serde_json::from_slice(data).map_err(|e| format!("{file}: {name}: {e}"))?;
        if let Some(out) = outs.get_mut(name) {
            out.send(&v)?;
        }
        *counts.entry(name).or_default() += 1;
        bar.inc(1);
        if bar.shown() {
            bar.set_message(format!("recording {:.1} s", (t - t_first) as f64 * 1e-9));
        } else if Instant::now() >= next_report {
            next_report += Duration::from_secs(1);
            eprintln!(
                "phri-replay: {:.0} s (recording {:.1} s)  {}",
                t0.elapsed().as_secs_f64(),
                (t - t_first) as f64 * 1e-9,
                progress(&counts)
            );
        }
    }
    bar.finish();
    eprintln!(
        "phri-replay: done after {:.1} s: {}",
        t0.elapsed().as_secs_f64(),
        progress(&counts)
    );
    Ok(())
}

fn progress(counts: &BTreeMap<&'static str, u64>) -> String {
    counts
        .iter()
        .map(|(c, n)| format!("{c}={n}"))
        .collect::<Vec<_>>()
        .join(" ")
}
