//! A hot standby killed six times (one more than `crash_loop_restarts`)
//! within the crash loop's window does not end a run whose controller in
//! charge is healthy: its crash loop is reported (a `crash_loop` event, a
//! `degraded` line), it is started again after its back-off, and the run
//! ends when it was meant to, with exit status 0.
//!
//! Multi-process: needs the release binaries (`cargo build --release --bins`).

#[path = "../../../tests/support/mod.rs"]
mod support;
#[path = "../../../tests/support/workspace.rs"]
mod workspace;

use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;
use support::RunPlace;
use workspace::{bin, repo};

fn state(place: &RunPlace) -> Value {
    std::fs::read_to_string(place.run_dir.join("state.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(Value::Null)
}

#[test]
fn a_standby_killed_six_times_does_not_end_a_run_whose_controller_in_charge_is_healthy() {
    let place = RunPlace::new('k', "sbloop");
    let scratch = std::env::temp_dir().join(format!("phri-test-{}err", place.prefix));
    std::fs::create_dir_all(&scratch).unwrap();
    let stderr = scratch.join("stderr.txt");
    let mut child = place
        .command(bin("phri-supervisor").to_str().unwrap(), &repo())
        .args(["--scenario", "free-motion", "--duration", "22"])
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&stderr).unwrap())
        .spawn()
        .unwrap();
    let log = || std::fs::read_to_string(&stderr).unwrap_or_default();
    // the first standby, then each restarted one as soon as it runs
    let mut killed: Vec<i64> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(40);
    let mut first_kill = None;
    while killed.len() < 6 {
        assert!(
            Instant::now() < deadline,
            "killed {killed:?} only: {}",
            log()
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended after {} kills: {}",
            killed.len(),
            log()
        );
        let s = state(&place);
        let pid = s["services"]["control_standby"]["pid"].as_i64();
        // every service started (the start-up's exits fail the start instead)
        let all_started = s["services"]
            .as_object()
            .is_some_and(|m| !m.is_empty() && m.values().all(|x| x["pid"].is_i64()));
        if let Some(p) = pid.filter(|p| *p > 1 && !killed.contains(p)) {
            // the first once the start-up is over
            if all_started && first_kill.is_none() {
                first_kill = Some(Instant::now() + Duration::from_secs(4));
            }
            if first_kill.is_some_and(|t| Instant::now() >= t) {
                // SAFETY: a process of this test's own cell
                unsafe { libc::kill(p as i32, libc::SIGKILL) };
                killed.push(p);
            }
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let six_within = first_kill.unwrap().elapsed();
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        assert!(
            Instant::now() < deadline + Duration::from_secs(40),
            "the supervisor did not end: {}",
            log()
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status.code(), Some(0), "{}", log());
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&place.report).unwrap()).unwrap();
    println!("6 kills within {six_within:?}; {}", r["summary"]);
    let loops: Vec<&Value> = r["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == "crash_loop" && e["service"] == "control_standby")
        .collect();
    assert!(!loops.is_empty(), "{}", r["events"]);
    assert!(
        r["degraded"].as_array().unwrap().iter().any(|l| l
            .as_str()
            .unwrap_or("")
            .starts_with("control_standby crash-loops")),
        "{}",
        r["degraded"]
    );
    assert_eq!(r["clean"], false);
    let sb = &r["services"]["control_standby"];
    assert_eq!(sb["restarts"], 6, "{sb}");
    assert_eq!(sb["alive_at_end"], true, "{sb}");
    assert_eq!(r["services"]["control"]["restarts"], 0);
    assert!(
        r["duration_s"].as_f64().unwrap() > 21.0,
        "{}",
        r["duration_s"]
    );
}
