//! Starts a real cell (the release supervisor, free-motion scenario) and checks
//! what `phri-monitor list` and `hz` measure on it, and that the monitor only
//! ever subscribes (the cell's publisher counts are unchanged).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

fn monitor(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_phri-monitor"))
        .args(args)
        .output()
        .expect("run phri-monitor")
}

fn json_of(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "phri-monitor failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.lines().last().expect("one line")).expect("valid JSON")
}

fn within(x: f64, nominal: f64, tol: f64) -> bool {
    (x - nominal).abs() <= nominal * tol
}

#[test]
fn errors_are_one_line_and_exit_2() {
    let prefix = format!("monnone_{}_", std::process::id());
    for (args, needle) in [
        (vec!["list", "--prefix", prefix.as_str()], "no cell running"),
        (
            vec!["hz", "no/such", "--prefix", prefix.as_str()],
            "robot/state",
        ),
        (vec!["list"], "--prefix is required"),
    ] {
        let out = monitor(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn list_and_hz_on_a_live_cell() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // the cell's binaries sit beside this package's (same target directory)
    let supervisor =
        Path::new(env!("CARGO_BIN_EXE_phri-monitor")).with_file_name("phri-supervisor");
    assert!(
        supervisor.exists(),
        "{} is not built: run the workspace's tests (cargo test --workspace --release) or cargo build --release --bins first",
        supervisor.display()
    );
    let prefix = format!("monXXX_{}_", std::process::id());
    let run_dir = PathBuf::from(format!("/tmp/phri-monitor-live-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&run_dir);
    let mut cell = Command::new(&supervisor)
        .current_dir(&root)
        .args(["--config", "deploy/phri.toml", "--scenario", "free-motion"])
        .args(["--duration", "8", "--prefix", &prefix, "--run-dir"])
        .arg(&run_dir)
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start the supervisor");
    std::thread::sleep(Duration::from_secs(4));

    let list = json_of(&monitor(&[
        "list",
        "--json",
        "--prefix",
        &prefix,
        "--seconds",
        "2",
    ]));
    eprintln!("list: {list}");
    assert_eq!(list["prefix"], prefix.as_str());
    let nodes = list["nodes"].as_array().expect("nodes");
    for name in ["supervisor", "sim", "dynamics", "control"] {
        assert!(
            nodes
                .iter()
                .any(|n| n["name"] == name && n["state"] == "alive" && n["pid"].as_i64() > Some(0)),
            "node {name} alive in {nodes:?}"
        );
    }
    assert!(
        !nodes
            .iter()
            .any(|n| n["pid"].as_i64() == Some(std::process::id() as i64)),
        "the test itself has no node"
    );
    let ch = &list["channels"];
    let rate = |c: &str| ch[c]["rate_hz"].as_f64().unwrap_or(0.0);
    assert!(
        within(rate("robot/state"), 1000.0, 0.05),
        "robot/state {}",
        ch["robot/state"]
    );
    assert!(
        within(rate("camera/depth"), 30.0, 0.10),
        "camera/depth {}",
        ch["camera/depth"]
    );
    // the monitor never publishes: the cell's own publisher counts
    assert_eq!(
        ch["robot/command"]["publishers"], 1,
        "{}",
        ch["robot/command"]
    );
    assert_eq!(ch["robot/state"]["publishers"], 1, "{}", ch["robot/state"]);
    let channels = ch.as_object().expect("channels");
    assert_eq!(channels.len(), phri_ipc::ALL.len());
    for (name, c) in channels {
        // fault/depth exists once the camera listens, but only phri-fault publishes on it
        if c["present"] == true && !phri_ipc::ON_DEMAND.contains(&name.as_str()) {
            assert!(
                c["publishers"].as_u64() >= Some(1),
                "{name} has no publisher: {c}"
            );
            assert!(c["samples"].as_u64() > Some(0), "{name} is silent: {c}");
        }
    }
    for name in [
        "robot/state",
        "robot/command",
        "dynamics/residual",
        "control/status",
        "supervisor/health",
    ] {
        assert_eq!(ch[name]["present"], true, "{name} exists");
    }

    let hz = json_of(&monitor(&[
        "hz",
        "robot/state",
        "--once",
        "--json",
        "--prefix",
        &prefix,
        "--seconds",
        "1",
    ]));
    eprintln!("hz: {hz}");
    assert_eq!(hz["channel"], "robot/state");
    assert!(
        within(hz["rate_hz"].as_f64().unwrap_or(0.0), 1000.0, 0.05),
        "{hz}"
    );
    assert_eq!(hz["publishers"], 1, "{hz}");
    let mean = hz["mean_interval_ms"].as_f64().expect("mean interval");
    assert!(within(mean, 1.0, 0.05), "{hz}");
    assert!(hz["max_interval_ms"].as_f64().expect("max interval") >= mean);
    assert!(hz["age_ms"].as_f64().expect("age") < 100.0, "{hz}");
    let bw = hz["bandwidth_bps"].as_f64().unwrap_or(0.0);
    let expected_bw = 1000.0 * std::mem::size_of::<phri_ipc::JointState>() as f64;
    assert!(within(bw, expected_bw, 0.10), "{hz}");

    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = cell.try_wait().expect("wait") {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(40) {
            let _ = cell.kill();
            panic!("the supervisor did not exit after its duration");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "supervisor: {status}");
    let _ = std::fs::remove_dir_all(&run_dir);
}
