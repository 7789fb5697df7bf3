//! `phri-record --prefix P --out FILE.mcap [--seconds S] [--frame-every N] [--frame-downsample K] [--compression zstd|lz4|none] [--config phri.toml] [--threshold NM]`
//!
//! Attaches read-only to every channel of `phri_ipc::ALL` of a running cell
//! (subscribers only, never creating a channel, normal scheduling, 5 ms between
//! polls) and writes an MCAP file: one channel per phri channel (topic = its
//! name), `json` messages with a `jsonschema` schema, log time = the message's
//! publish/stamp time [ns, CLOCK_MONOTONIC] (else the receive time). Depth frames:
//! every N-th received frame, header fields plus the image downsampled K× per axis,
//! and the same image as `foxglove.RawImage` (16UC1) on `<channel>/image` for
//! Foxglove's Image panel. Chunks are compressed with zstd. N (10), K (4) and
//! the compression come from `[record]` of `--config`; the flags override them.
//!
//! Beside them, the 3-D scene as `phri-viz` serves it, on the same topics and
//! in Foxglove's own schemas (protobuf; the status in JSON): `/viz/robot`,
//! `/viz/person`, `/viz/repulsion`, `/viz/collab` (`foxglove.SceneUpdate`,
//! 30 Hz), `/viz/tf` (`foxglove.FrameTransforms`), `/viz/joints`
//! (`foxglove.JointStates`, 250 Hz), `/viz/status` (`phri.viz.Status`), and
//! the recorded `perception/depth` frames as `/viz/depth/points`
//! (`foxglove.PointCloud`) and `/viz/depth/image` (`foxglove.RawImage`): a
//! recording opens in Foxglove with `deploy/foxglove/phri-layout.json` as the
//! live cell does. The robot model is the configuration's (`--config`, else
//! the built-in defaults).
//!
//! Stops after `--seconds` or on Ctrl-C and writes the summary and indexes; a
//! progress bar on a terminal, a line per second otherwise.

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use phri_ipc::node;
use phri_record::recorder::{metadata, record, recorders, Flags, RecordError, Recording, Settings};
use phri_runtime::cli::CompletionsCmd;
use phri_runtime::Shutdown;

const BIN: &str = "phri-record";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Records a running cell to MCAP: every channel as JSON, depth frames downsampled, and the 3-D scene in Foxglove's schemas (read-only)",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// MCAP file to write
    #[arg(long, value_name = "FILE.mcap", required = true)]
    out: Option<PathBuf>,
    #[command(flatten)]
    flags: Flags,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let code = phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()));
    // the last node out of the prefix (the cell stopped first) takes back
    // what iceoryx2 left in shared memory; nothing while any node lives
    let _ = phri_ipc::remove_leftovers(&prefix);
    code
}

/// Resolves the flags, attaches to the running cell, records until the end.
fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    // clap requires it unless a subcommand is given
    let out_path = cli
        .out
        .as_ref()
        .ok_or("--out is required")?
        .display()
        .to_string();
    let settings = Settings::resolve(&cli.flags)?;
    let viz = settings.viz(BIN);
    if phri_ipc::live_nodes(&prefix) == 0 {
        return Err(RecordError::NoCell { prefix }.into());
    }
    let shutdown = Shutdown::install()?;
    let node = node(&format!("record{}", std::process::id()), &prefix)?;
    let recs = recorders(&settings.rc, settings.loaded.config.cameras.len());
    let scene = viz.pipeline.is_some();
    let mut recording = Recording::create(&out_path, &settings, &recs, scene)?;
    recording.write_metadata(metadata(&prefix, &settings, scene))?;
    record(
        recording,
        &out_path,
        recs,
        viz,
        &node,
        &shutdown,
        settings.seconds,
    )?;
    Ok(())
}
