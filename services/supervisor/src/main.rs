//! `phri-supervisor`: starts the services of `[services]`, restarts what dies
//! (with back-off), kills what freezes (or what starves it), publishes
//! `supervisor/health`, shuts everything down in order on SIGINT/SIGTERM or
//! after `--duration`, leaves no process and no shared-memory file behind,
//! and writes `--report`.
//!
//! The cell starts whole or not at all: everything is checked before the
//! first process starts (the configuration, the run length, the binaries,
//! every service's acceptance of the configuration (`--check`), the report
//! file, the run directory, iceoryx2's node counter), and a start that fails
//! stops what it started. A service that crash-loops, or a process other than
//! the supervised controller publishing on `robot/command`, ends the run:
//! ordered shutdown, a report with `clean: false`, a non-zero exit.
//!
//! The decisions are the library's state machine
//! ([`phri_supervisor::supervision`]), the I/O around it its [`run`]; this
//! file reads the command line and the plan.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use phri_supervisor::run::{self, Options};
use phri_supervisor::{Plan, SupervisorError};

/// The supervisor's command line.
#[derive(clap::Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Starts the phri cell's services, supervises them (restarts, the dead-man, CPU use) and writes the run's report",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    /// Cell configuration (TOML)
    #[arg(long, value_name = "FILE", default_value = "deploy/phri.toml")]
    config: PathBuf,
    /// Scenario to run: a name under deploy/scenarios/ or a file
    #[arg(long, value_name = "NAME|FILE")]
    scenario: Option<String>,
    /// Stop the cell after this long [s] (default: the scenario's own length)
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Write the run's report (JSON) to this file
    #[arg(long, value_name = "FILE")]
    report: Option<String>,
    /// The arm: its robot file deploy/robots/NAME/robot.toml (lwr4, the
    /// default; fr3; panda); the same as `--set robot.name=NAME`
    #[arg(long, value_name = "NAME")]
    robot: Option<String>,
    /// Drive the arm `--robot` names over FCI at this address (host[:port]:
    /// a Franka's control box, or franka-sim) instead of simulating it: the
    /// simulator then simulates the person and the world only (the same as
    /// `--set robot.ip=ADDRESS`)
    #[arg(long, value_name = "ADDRESS")]
    robot_ip: Option<String>,
    /// Where the camera's frames come from: sim (the simulated camera, the
    /// default), freenect (a Kinect v1), ros2 (a ROS 2 depth camera, [camera]
    /// image_topic and info_topic), replay (recorded frames, [camera]
    /// replay_dir); the same as `--set camera.source=SOURCE`
    #[arg(long, value_name = "SOURCE", value_parser = ["sim", "freenect", "ros2", "replay"])]
    camera: Option<String>,
    /// Override one configuration value, e.g. `--set control.avoidance=false` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Refuse to start unless real-time scheduling (SCHED_FIFO at the
    /// services' priorities) and CPU pinning are permitted (also: `supervisor.require_rt`)
    #[arg(long)]
    require_rt: bool,
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// Run directory (state files, report) [default: one per prefix under $XDG_RUNTIME_DIR, else /tmp/phri-UID]
    #[arg(long, value_name = "DIR")]
    run_dir: Option<PathBuf>,
    /// Draw the cell's processes and the channels between them as SVG into
    /// FILE and exit, starting nothing (docs/cell.svg: the default cell)
    #[arg(long, value_name = "FILE")]
    draw_cell: Option<PathBuf>,
    #[command(subcommand)]
    completions: Option<phri_runtime::cli::CompletionsCmd>,
}

/// `--robot NAME`, `--robot-ip ADDRESS` and `--camera SOURCE` as the first
/// `--set`s (a later `--set robot.name`, `robot.ip` or `camera.source` wins).
fn robot_and_sets(
    robot: Option<&str>,
    ip: Option<&str>,
    camera: Option<&str>,
    sets: &[String],
) -> Vec<String> {
    robot
        .map(|r| format!("robot.name={r}"))
        .into_iter()
        .chain(ip.map(|a| format!("robot.ip={a}")))
        .chain(camera.map(|c| format!("camera.source=\"{c}\"")))
        .chain(sets.iter().cloned())
        .collect()
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-supervisor", body)
}

fn body() -> Result<(), SupervisorError> {
    let args: Cli = phri_runtime::cli::parse("phri-supervisor");
    if let Some(phri_runtime::cli::CompletionsCmd::Completions { shell }) = args.completions {
        phri_runtime::cli::completions::<Cli>("phri-supervisor", shell);
        return Ok(());
    }
    // everything is checked before anything starts: the configuration, the
    // scenario, the robot model, the run length, the binaries
    let sets = robot_and_sets(
        args.robot.as_deref(),
        args.robot_ip.as_deref(),
        args.camera.as_deref(),
        &args.set,
    );
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    let plan = Plan::load(&args.config, args.scenario.as_deref(), &sets, args.duration)?;
    if let Some(path) = &args.draw_cell {
        return phri_supervisor::drawing::write(&plan, path);
    }
    let bin_dir = std::env::current_exe()
        .map_err(SupervisorError::CurrentExe)?
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    plan.check_binaries(&bin_dir)?;
    let options = Options {
        bin_dir,
        require_rt: args.require_rt,
        prefix: args.prefix,
        run_dir: args.run_dir,
        report: args.report,
    };
    run::run(plan, options)
}
