//! The hybrid cell against a control box nobody here wrote: the FR3 of
//! franka-sim (MuJoCo, the FCI wire protocol) on 127.0.0.1, driven by the
//! supervisor's phri-franka, with phri-sim simulating only the person and
//! the world the camera sees. The real processes, started by the real
//! supervisor (`--robot fr3 --robot-ip`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;

mod support;

#[path = "../services/franka/tests/common/mod.rs"]
mod franka_sim;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// The supervisor's run of `scenario` for `duration` s on the FR3 behind
/// franka-sim at `port`: its report.
fn run(test: &str, port: u16, scenario: &str, duration: f64, sets: &[&str]) -> Value {
    support::loud_panics();
    let prefix = format!("h{}{}_", std::process::id(), test);
    let run_dir = std::env::temp_dir().join(format!("phri-test-{prefix}"));
    let _ = std::fs::remove_dir_all(&run_dir);
    let report = run_dir.join("report.json");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_phri-supervisor"));
    cmd.current_dir(repo())
        .args(["--config", "deploy/phri.toml", "--robot", "fr3"])
        .arg("--robot-ip")
        .arg(format!("127.0.0.1:{port}"))
        .args(["--scenario", scenario, "--duration", &duration.to_string()])
        .arg("--prefix")
        .arg(&prefix)
        .arg("--run-dir")
        .arg(&run_dir)
        .arg("--report")
        .arg(&report);
    for s in sets {
        cmd.arg("--set").arg(s);
    }
    let mut child = cmd.spawn().expect("the supervisor starts");
    let deadline = Instant::now() + Duration::from_secs_f64(duration + 60.0);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the supervisor did not stop");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "the supervisor failed: {status}");
    serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap()
}

#[test]
fn the_supervisor_drives_the_fr3_behind_franka_sim_with_the_cell_around_it() {
    let port = franka_sim::port(0);
    let _server = franka_sim::serve(port);
    let r = run("free", port, "free-motion", 15.0, &[]);
    eprintln!(
        "robot {} torque_loop {} task {} services {} degraded {}",
        r["robot"], r["torque_loop"], r["task"], r["services"], r["degraded"]
    );
    assert_eq!(r["robot"]["kind"], "franka");
    assert_eq!(r["robot"]["name"], "fr3");
    // the adapter, not the simulator, serves the arm: its states at the
    // box's 1 kHz (franka-sim runs at 0.9-1.0 × real time here), answered
    // by the controller, with no restart of the adapter
    let tl = &r["torque_loop"];
    assert!(tl["cycles"].as_u64().unwrap() > 10_000, "{tl}");
    assert!(tl["braked_cycles"].as_u64().unwrap() < 1_000, "{tl}");
    for s in [
        "franka",
        "sim",
        "dynamics",
        "control",
        "camera",
        "perception",
    ] {
        assert_eq!(
            r["services"][s]["alive_at_end"], true,
            "{s}: {}",
            r["services"]
        );
        assert_eq!(r["services"][s]["restarts"], 0, "{s}: {}", r["services"]);
    }
    // the controller took the arm over from the adapter's first state
    assert!(
        r["events"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "sync" && e["service"] == "control"),
        "{}",
        r["events"]
    );
}
