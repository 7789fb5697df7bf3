//! `phri-plot --file FILE.mcap --out DIR [--without FREE.mcap] [--format png|svg|both]`:
//! figures of a recording as PNG and SVG (`--format`, default both: each
//! figure's PNG where it always was, its SVG beside it), each with a title,
//! axis labels in SI units, tick values and a legend, the text in the
//! embedded DejaVu Sans (anti-aliased in the PNG, `<text>` in the SVG).
//! A progress bar on stderr while reading when stderr is a terminal; in a
//! pipe the output is what it always was.
//!
//! - `ee_trajectory.png` (like the paper's Fig. 7): end-effector x-y path
//!   (`control/status` `ee`), blue while the person is farther than the
//!   surveillance distance (0.4 m, `sim/truth` `min_distance`: the true
//!   person-robot distance, for evaluation), red while nearer;
//!   with `--without`, the path of a recording without the person (e.g.
//!   `free-motion`) underneath in grey
//! - `residual.png`: ‖r‖ over time (`dynamics/residual` `norm`), blue; the
//!   collision norm threshold from the recording's metadata (dashed red) when
//!   present; an orange vertical line where `flags & COLLISION` rises
//! - `min_distance.png`: `control/status` `min_distance` over time (non-finite skipped)
//! - with a collaboration in the recording (`collab/state` not idle):
//!   `collaboration.png` (the paper's Figs. 8 and 11): end-effector x, y, z
//!   (`control/status` `ee`) and the collaborative hand's (`collab/state`
//!   `hand`, while collaborating) against time, a grey line at each change of
//!   phase; `contact_force.png`: ‖F̂‖ (`collab/state`) and the true force of
//!   the collaborative hand (`sim/truth`, intended contacts of a hand)

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

use phri_ipc::{CONTROL_STATUS, DYNAMICS_RESIDUAL};
use phri_record::figures::save_all;
use phri_record::plot::Format;
use phri_record::progress::Progress;
use phri_record::read_file;
use phri_record::series::{ee_path, read_series, summary, PlotError};
use phri_runtime::cli::CompletionsCmd;

const BIN: &str = "phri-plot";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Draws the figures of a phri-record recording (MCAP) as PNG and SVG: end-effector path, momentum residual, minimum distance, and the collaboration's hand and contact force when the recording has a collaboration",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    /// Recording to plot (MCAP written by phri-record)
    #[arg(long, value_name = "FILE.mcap", required = true)]
    file: Option<String>,
    /// Directory to write the figures into (created if missing)
    #[arg(long, value_name = "DIR", required = true)]
    out: Option<PathBuf>,
    /// A recording without the person (e.g. free-motion): its end-effector path drawn underneath in grey
    #[arg(long, value_name = "FREE.mcap")]
    without: Option<String>,
    /// Which files each figure is written as: NAME.png, NAME.svg, or both
    #[arg(long, value_enum, value_name = "FORMAT", default_value_t = Format::Both)]
    format: Format,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()))
}

/// Reads the recording, writes its figures, says what they hold.
fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    // clap requires both unless a subcommand is given
    let (Some(file), Some(out)) = (cli.file.as_deref(), cli.out.clone()) else {
        return Err("--file and --out are required".into());
    };
    let buf = read_file(file)?;
    // the collision threshold from the recording's metadata; the message count
    let (threshold, total) = summary(&buf, file)?;
    let progress = Progress::new(BIN, total, "messages");
    let (series, n) = read_series(&buf, file, &progress)?;
    progress.finish();
    if series.ee.is_empty() && series.norm.is_empty() {
        return Err(PlotError::NoMessages {
            file: file.to_string(),
            what: format!("{} or {}", CONTROL_STATUS.name, DYNAMICS_RESIDUAL.name),
        }
        .into());
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create '{}': {e}", out.display()))?;
    // the same path without the person, if given
    let without = match cli.without.as_deref() {
        Some(f) => ee_path(f)?,
        None => Vec::new(),
    };
    save_all(&series, threshold, &without, &out, cli.format)?;
    eprintln!(
        "phri-plot: {n} messages; {} ee points, {} residuals ({} collision onsets, threshold {}), {} distances -> {}",
        series.ee.len(),
        series.norm.len(),
        series.rises.len(),
        threshold.map_or("none".into(), |t| format!("{t} Nm")),
        series.dist.len(),
        out.display()
    );
    Ok(())
}
