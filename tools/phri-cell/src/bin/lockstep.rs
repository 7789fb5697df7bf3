//! `phri-lockstep`: run a scenario with the whole cell in one process, in
//! lock-step (deterministic, faster than real time), and print what happened
//! as JSON. With several `--offset` values (or `--sweep FROM,TO,STEP`) it runs
//! once per offset of the person's script against the robot's cycle.
//!
//!   phri-lockstep --scenario coexistence [--duration S] [--config deploy/phri.toml]
//!                 [--set section.key=value ...] [--offset S ...] [--sweep FROM,TO,STEP]
//!                 [--latency-ms MS] [--outage perception|dynamics|control|standby|camera|camera-I:FROM:TO ...]
//!                 [--no-perception] [--trace FILE [--trace-every-ms MS]]
//!   phri-lockstep completions bash|zsh|fish

use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

use phri_cell::{Cell, CellOptions, Outage};
use phri_config::Loaded;
use phri_runtime::cli::CompletionsCmd;

const BIN: &str = "phri-lockstep";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Runs a scenario with the whole cell in one process, in lock-step (deterministic, faster than real time), and prints what happened as JSON",
    long_about = "Runs a scenario with the whole cell in one process, in lock-step (deterministic, faster than real time), \
and prints what happened as JSON on stdout (one line per run on stderr). With several --offset values (or --sweep \
FROM,TO,STEP) it runs once per offset of the person's script against the robot's cycle.",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    args_override_self = true
)]
struct Cli {
    /// Scenario: a name of the configuration's scenarios, or a scenario file
    #[arg(long, value_name = "NAME|FILE", required = true)]
    scenario: Option<String>,
    /// Simulated time of each run \[s\] (default: the scenario's duration)
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Cell configuration (TOML)
    #[arg(long, value_name = "FILE", default_value = "deploy/phri.toml")]
    config: PathBuf,
    /// The arm: its robot file deploy/robots/NAME/robot.toml (lwr4, the
    /// default; fr3; panda); the same as `--set robot.name=NAME`
    #[arg(long, value_name = "NAME")]
    robot: Option<String>,
    /// Override one configuration value, e.g. `--set control.avoidance=false` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Offset of the person's script against the robot's cycle \[s\] (repeatable: one run each)
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = finite)]
    offset: Vec<f64>,
    /// Offsets FROM, FROM+STEP, … up to TO \[s\], one run each (after the --offset runs), e.g. `--sweep -4,0,0.5`
    #[arg(long, value_name = "FROM,TO,STEP", allow_hyphen_values = true)]
    sweep: Option<String>,
    /// Capture → repulsion results at the controller \[ms\] (default 6.5: the multi-process cell's p99 before the vector lanes; 4.3-4.5 ms since, so the default errs late)
    #[arg(long = "latency-ms", value_name = "MS", allow_negative_numbers = true)]
    latency_ms: Option<f64>,
    /// A service outage in simulated time \[s\], `perception|dynamics|control|standby|camera|camera-I:FROM:TO` (repeatable; `control` is the first controller, `standby` the hot standby, `camera` the first camera, `camera-I` camera I of `[[camera]]`)
    #[arg(long, value_name = "SERVICE:FROM:TO")]
    outage: Vec<Outage>,
    /// Run without the camera and perception
    #[arg(long)]
    no_perception: bool,
    /// Perception that hides nothing: every control point's distance, closest point and repulsion
    /// from the simulated person's body itself (the cameras still run, for the skeleton and the
    /// hand); what the avoidance does when no camera limits it
    #[arg(long, conflicts_with = "no_perception")]
    truth_perception: bool,
    /// Write the run's time series as CSV to FILE (one run only): end effector and its path
    /// reference, waypoints, the closest human–robot pair (ground truth), what perception told the
    /// controller, the collaboration's hand as the controller follows it and its error
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// One trace row every MS of simulated time
    #[arg(long = "trace-every-ms", value_name = "MS", default_value_t = 100.0, value_parser = finite)]
    trace_every_ms: f64,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

/// A finite number.
fn finite(v: &str) -> Result<f64, String> {
    v.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| "not a number".to_string())
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    phri_runtime::service::run(BIN, || body(cli))
}

/// `FROM,TO,STEP` as the offsets it spans.
fn sweep(s: &str) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--sweep: expected FROM,TO,STEP, got {s}"))?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) || !(v[2] > 0.0) || v[1] < v[0] {
        return Err(format!(
            "--sweep: expected FROM,TO,STEP with STEP > 0 and TO ≥ FROM, got {s}"
        ));
    }
    let steps = ((v[1] - v[0]) / v[2] + 1e-9).floor() as usize;
    if steps > 10_000 {
        return Err(format!("--sweep: {} runs, at most 10001", steps + 1));
    }
    Ok((0..=steps).map(|k| v[0] + k as f64 * v[2]).collect())
}

fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    // clap requires it unless a subcommand is given
    let name = cli.scenario.as_deref().ok_or("--scenario is required")?;
    let robot = cli.robot.as_ref().map(|r| format!("robot.name={r}"));
    let sets: Vec<&str> = robot.iter().chain(&cli.set).map(String::as_str).collect();
    let loaded = Loaded::load(&cli.config, Some(name), &sets)?;
    let model = loaded.model()?;
    let duration = cli.duration.unwrap_or(loaded.scenario.duration_s);
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(
            format!("--duration: must be a positive number of seconds, got {duration}").into(),
        );
    }
    let mut offsets = cli.offset.clone();
    if let Some(s) = &cli.sweep {
        offsets.extend(sweep(s)?);
    }
    if offsets.is_empty() {
        offsets.push(0.0);
    }
    if cli.trace.is_some() && offsets.len() > 1 {
        return Err(format!(
            "--trace: one run only, got {} offsets (drop --sweep or extra --offset)",
            offsets.len()
        )
        .into());
    }
    if !(cli.trace_every_ms > 0.0) {
        return Err(format!("--trace-every-ms: must be > 0, got {}", cli.trace_every_ms).into());
    }
    let mut trace = match &cli.trace {
        Some(path) => {
            let file = std::fs::File::create(path)
                .map_err(|e| format!("--trace: cannot write {}: {e}", path.display()))?;
            Some(phri_cell::trace::Trace::new(
                std::io::BufWriter::new(file),
                (cli.trace_every_ms * 1e6) as u64,
            )?)
        }
        None => None,
    };
    let mut opts = CellOptions {
        perception: !cli.no_perception,
        truth_perception: cli.truth_perception,
        standby: loaded.config.control.standby,
        ..CellOptions::default()
    };
    opts.outages.extend(cli.outage.iter().copied());
    if let Some(l) = cli.latency_ms {
        opts.perception_latency_ms = l;
    }
    let periods = (duration / loaded.config.sim.dt_s).round() as u64;
    let mut runs = Vec::new();
    let mut total = 0usize;
    for (i, &offset) in offsets.iter().enumerate() {
        opts.human_time_offset_s = offset;
        let mut cell = Cell::new(&loaded, model.clone(), &opts)?;
        for _ in 0..periods {
            cell.tick()?;
            if let Some(t) = trace.as_mut() {
                t.sample(&cell)?;
            }
        }
        let s = cell.summary();
        eprintln!(
            "[{}/{}] offset {offset:+.2} s: {} unintended contacts, closest {:.3} m, {} waypoints, {} detections",
            i + 1,
            offsets.len(),
            s.unintended_contacts,
            s.min_distance_m,
            s.waypoints,
            s.detections
        );
        total += s.unintended_contacts;
        runs.push(serde_json::json!({"offset_s": offset, "summary": s}));
    }
    if let Some(t) = trace {
        t.finish()?;
    }
    let out = serde_json::json!({
        "scenario": loaded.scenario.name,
        "duration_s": duration,
        "perception_latency_ms": opts.perception_latency_ms,
        "unintended_contacts": total,
        "runs": runs,
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// clap's own consistency checks (names, conflicts, positionals), which
    /// release builds skip at run time.
    #[test]
    fn the_command_is_consistent() {
        super::Cli::command().debug_assert();
    }
}
