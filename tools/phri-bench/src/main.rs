//! `phri-bench transport`: see [`transport`].
//!
//! `phri-bench loop [--duration S] [--scenario NAME]`: starts the cell with its
//! own prefix, listens to the torque loop's channels and prints the latency
//! distribution of each hop of one cycle (JSON, microseconds):
//! state published → residual published → controller woke → command
//! published → command received by the robot.

mod transport;

use std::collections::VecDeque;
use std::error::Error;
use std::path::PathBuf;
use std::process::{Command, ExitCode, Stdio};

use phri_ipc::*;
use phri_runtime::{now_ns, sleep_until_ns, Args};
use serde_json::json;

fn main() -> ExitCode {
    phri_runtime::service::run("phri-bench", || body().map_err(|e| e.to_string()))
}

fn percentiles(mut v: Vec<f64>) -> serde_json::Value {
    if v.is_empty() {
        return json!(null);
    }
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    json!({"n": v.len(), "p50": at(0.5), "p99": at(0.99), "p999": at(0.999), "max": v[v.len() - 1]})
}

const USAGE: &str = "usage: phri-bench loop [--duration SECONDS] [--scenario NAME] [--config FILE]\n       phri-bench transport [--iterations N]";

fn body() -> Result<(), Box<dyn Error>> {
    let mut argv = std::env::args().skip(1);
    match argv.next().as_deref() {
        Some("loop") => {}
        Some("transport") => {
            let args = Args::parse(argv, &["--iterations"], &[])?;
            let n = args
                .parse_value::<usize>("--iterations")?
                .unwrap_or(2000)
                .max(10);
            let out = transport::run(n)?;
            println!("{}", serde_json::to_string_pretty(&out)?);
            return Ok(());
        }
        Some("transport-peer") => {
            let prefix = argv.next().ok_or("transport-peer PREFIX SOCKET")?;
            let socket = argv.next().ok_or("transport-peer PREFIX SOCKET")?;
            return Ok(transport::peer(&prefix, &socket)?);
        }
        _ => return Err(USAGE.into()),
    }
    let args = Args::parse(argv, &["--duration", "--scenario", "--config"], &[])?;
    let duration = args.parse_value::<f64>("--duration")?.unwrap_or(30.0);
    let scenario = args.get("--scenario").unwrap_or("free-motion").to_string();
    let exe_dir = std::env::current_exe()?
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default();
    let repo = exe_dir.join("../..");
    let config = args
        .get("--config")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo.join("deploy/phri.toml"));
    let prefix = format!("bench{}_", std::process::id());
    let report = std::env::temp_dir().join(format!("phri-bench-{prefix}.json"));
    let mut sup = Command::new(exe_dir.join("phri-supervisor"))
        .arg("--config")
        .arg(&config)
        .arg("--scenario")
        .arg(&scenario)
        .arg("--duration")
        .arg((duration + 1.0).to_string())
        .arg("--prefix")
        .arg(&prefix)
        .arg("--report")
        .arg(&report)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start phri-supervisor: {e}"))?;

    let node = node("bench", &prefix)?;
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
    let st = sup.wait()?;
    if let Err(alive) = phri_ipc::remove_leftovers(&prefix) {
        eprintln!(
            "phri-bench: {alive} node(s) of {prefix} still attached: their shared memory stays"
        );
    }
    if !st.success() {
        return Err(format!("phri-supervisor failed: {st}").into());
    }
    let r: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&report).map_err(|e| format!("{}: {e}", report.display()))?,
    )?;
    let _ = std::fs::remove_file(&report);
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
