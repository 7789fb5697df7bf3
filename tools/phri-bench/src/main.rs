//! `phri-bench transport`: see [`transport`].
//!
//! `phri-bench loop [--duration S] [--scenario NAME]`: starts the cell with its
//! own prefix, listens to the torque loop's channels and prints the latency
//! distribution of each hop of one cycle (JSON, microseconds):
//! state published → residual published → controller woke → command
//! published → command received by the robot.
//!
//! `phri-bench cell [--scenario NAME] [--duration S] [--set K=V]... [--json]`:
//! one run of the cell with the machine's floor measured beside it (a
//! thread at the torque loop's priority on its CPU, as `cyclictest`): each
//! service's CPU share against its budget, the torque loop's pace and
//! latency beside the floor's, perception's latency. `deploy/bench` runs it
//! over the scenarios.
//!
//! `phri-bench completions bash|zsh|fish`: a shell completion script.

mod cell;
mod floor;
mod transport;

use std::collections::VecDeque;
use std::error::Error;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use phri_ipc::*;
use phri_runtime::{now_ns, sleep_until_ns};
use serde_json::json;

const BIN: &str = "phri-bench";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Reproducible performance figures: the torque loop's hop latencies, the transport's hand-off time (JSON on stdout)",
    long_about = "Reproducible performance figures, as JSON on stdout. Each benchmark runs under its own private \
iceoryx2 prefix (bench<pid>_, benchtx<pid>_): it never attaches to, nor disturbs, a running cell's channels.",
    args_override_self = true
)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Start a cell of its own, listen to the torque loop and print each hop's latency distribution \[µs\]
    Loop {
        /// Length of the measured run \[s\] (the first 1.5 s are start-up, not measured)
        #[arg(long, value_name = "SECONDS", default_value_t = 30.0, allow_negative_numbers = true, value_parser = positive)]
        duration: f64,
        /// Scenario the cell runs
        #[arg(long, value_name = "NAME", default_value = "free-motion")]
        scenario: String,
        /// Cell configuration (TOML) [default: deploy/phri.toml of the build's checkout]
        #[arg(long, value_name = "FILE")]
        config: Option<PathBuf>,
    },
    /// Run the cell once with the machine's floor measured beside it: CPU per service, the torque loop's pace and latency against the floor's, perception's latency
    Cell {
        /// Length of the run \[s\] (the floor is measured after its first 1.5 s)
        #[arg(long, value_name = "SECONDS", default_value_t = 60.0, allow_negative_numbers = true, value_parser = positive)]
        duration: f64,
        /// Scenario the cell runs
        #[arg(long, value_name = "NAME", default_value = "free-motion")]
        scenario: String,
        /// Cell configuration (TOML) [default: deploy/phri.toml of the build's checkout]
        #[arg(long, value_name = "FILE")]
        config: Option<PathBuf>,
        /// A configuration value for the run (`section.key=value`, as the supervisor's --set)
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// The floor thread's CPU (the torque loop's, deploy/phri.toml: 1)
        #[arg(long, value_name = "CPU", default_value_t = 1)]
        floor_cpu: usize,
        /// The floor thread's SCHED_FIFO priority (the simulated robot's, deploy/phri.toml: 78; 0: normal scheduler)
        #[arg(long, value_name = "PRIORITY", default_value_t = 78)]
        floor_priority: i32,
        /// Print JSON instead of a table
        #[arg(long)]
        json: bool,
    },
    /// Hand-off time of one payload between two processes: iceoryx2 zero-copy against a Unix socket \[µs\]
    Transport {
        /// Round trips per payload size (at least 10)
        #[arg(long, value_name = "N", default_value_t = 2000)]
        iterations: usize,
    },
    /// The answering side of `transport` (started by it)
    #[command(name = "transport-peer", hide = true)]
    TransportPeer {
        /// iceoryx2 prefix of the benchmark's services
        prefix: String,
        /// Unix socket to answer on
        socket: String,
    },
    /// Print a shell completion script to stdout (bash, zsh, fish, elvish or powershell)
    Completions {
        /// Shell to write the script for
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

/// A positive, finite number.
fn positive(v: &str) -> Result<f64, String> {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err("must be a positive number".into()),
    }
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Cmd::Completions { shell } = cli.command {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    phri_runtime::service::run(BIN, || body(cli.command).map_err(|e| e.to_string()))
}

fn percentiles(mut v: Vec<f64>) -> serde_json::Value {
    if v.is_empty() {
        return json!(null);
    }
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    json!({"n": v.len(), "p50": at(0.5), "p99": at(0.99), "p999": at(0.999), "max": v[v.len() - 1]})
}

/// `phri-bench cell`: the run, the floor beside it, the figures.
fn cell_run(
    scenario: &str,
    duration: f64,
    config: Option<&std::path::Path>,
    sets: &[String],
    floor_at: (usize, i32),
    as_json: bool,
) -> Result<(), Box<dyn Error>> {
    let run = cell::BenchCell::start(config, scenario, duration, sets)?;
    let from = now_ns() + 1_500_000_000;
    let until = now_ns() + (duration * 1e9) as u64;
    let floor = std::thread::spawn(move || {
        floor::measure(Some(floor_at.0), floor_at.1, 1_000_000, from, until)
    })
    .join()
    .map_err(|_| "the floor thread panicked")?;
    let report = run.finish()?;
    let f = cell::figures(scenario, &report, &floor.to_json());
    if as_json {
        println!("{}", serde_json::to_string_pretty(&f)?);
    } else {
        print!("{}", cell::table(&f));
    }
    Ok(())
}

fn body(command: Cmd) -> Result<(), Box<dyn Error>> {
    let (duration, scenario, config) = match command {
        Cmd::Loop {
            duration,
            scenario,
            config,
        } => (duration, scenario, config),
        Cmd::Transport { iterations } => {
            let out = transport::run(iterations.max(10))?;
            println!("{}", serde_json::to_string_pretty(&out)?);
            return Ok(());
        }
        Cmd::TransportPeer { prefix, socket } => return Ok(transport::peer(&prefix, &socket)?),
        Cmd::Cell {
            duration,
            scenario,
            config,
            sets,
            floor_cpu,
            floor_priority,
            json,
        } => {
            return cell_run(
                &scenario,
                duration,
                config.as_deref(),
                &sets,
                (floor_cpu, floor_priority),
                json,
            )
        }
        Cmd::Completions { .. } => return Ok(()),
    };
    let sup = cell::BenchCell::start(config.as_deref(), &scenario, duration + 1.0, &[])?;
    let node = node("bench", &sup.prefix)?;
    let states = ROBOT_STATE.subscriber(&node, Queue::Drain)?;
    let residuals = DYNAMICS_RESIDUAL.subscriber(&node, Queue::Drain)?;
    let commands = ROBOT_COMMAND.subscriber(&node, Queue::Drain)?;
    let status = CONTROL_STATUS.subscriber(&node, Queue::Drain)?;
    // published time of recent states, by sequence number
    let mut published: VecDeque<(u64, u64)> = VecDeque::with_capacity(4096);
    let lookup = |p: &VecDeque<(u64, u64)>, seq: u64| {
        p.iter().rev().find(|(s, _)| *s == seq).map(|(_, t)| *t)
    };
    let (mut to_residual, mut to_wake, mut to_command, mut ctl_compute, mut res_compute) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // skip the first second (start-up)
    let t_start = now_ns() + 1_500_000_000;
    let t_end = now_ns() + (duration * 1e9) as u64;
    let mut tick = now_ns();
    while now_ns() < t_end {
        tick += 5_000_000;
        sleep_until_ns(tick);
        let measuring = now_ns() > t_start;
        while let Some(m) = states.receive()? {
            if published.len() == 4096 {
                published.pop_front();
            }
            published.push_back((m.seq, m.published_ns));
        }
        while let Some(m) = residuals.receive()? {
            if let (true, Some(p)) = (measuring, lookup(&published, m.state_seq)) {
                to_residual.push(m.stamp_ns.saturating_sub(p) as f64 / 1e3);
                res_compute.push(m.compute_ns as f64 / 1e3);
            }
        }
        while let Some(m) = commands.receive()? {
            if let (true, Some(p)) = (measuring, lookup(&published, m.state_seq)) {
                to_command.push(m.stamp_ns.saturating_sub(p) as f64 / 1e3);
            }
        }
        while let Some(m) = status.receive()? {
            if measuring && m.wake_latency_ns > 0 {
                to_wake.push(m.wake_latency_ns as f64 / 1e3);
                ctl_compute.push(m.compute_ns as f64 / 1e3);
            }
        }
    }
    drop((states, residuals, commands, status));
    drop(node);
    let r = sup.finish()?;
    let out = json!({
        "duration_s": duration,
        "scenario": scenario,
        "scheduler_note": "services run under SCHED_FIFO when permitted (see deploy/phri.toml rt_priority)",
        "state_to_residual_published_us": percentiles(to_residual),
        "state_to_controller_woke_us": percentiles(to_wake),
        "state_to_command_published_us": percentiles(to_command),
        "state_to_command_received_us": r["torque_loop"]["latency_us"],
        "controller_compute_us": percentiles(ctl_compute),
        "residual_compute_us": percentiles(res_compute),
        "cycles": r["torque_loop"]["cycles"],
        "missed_deadlines": r["torque_loop"]["missed_deadlines"],
        "robot_overruns": r["torque_loop"]["overruns"],
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
