//! System test: a real cell (the supervisor and every service) whose camera is
//! told, again and again, to put 2 % flying pixels into its frames
//! (`phri-fault camera corrupt noise`). Ingestion removes them: the report
//! has no false detection and no contact, and ingestion never restarts.
//! Before the flying-pixel filter this gave a false collision detection in
//! 2 of 2 runs. Two runs, one after the other, each with its own iceoryx2
//! prefix and run directory.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

#[path = "../../../tests/support/workspace.rs"]
mod workspace;
use workspace::{bin, repo};

/// One run of `scenario` for `duration_s`, with noise injected every
/// `every_s` from `first_s` on; the report.
fn run_with_noise(run: u32, scenario: &str, duration_s: f64, first_s: f64, every_s: f64) -> Value {
    for b in [
        "phri-sim",
        "phri-dynamics",
        "phri-control",
        "phri-camera",
        "phri-repulsion",
    ] {
        bin(b);
    }
    let prefix = format!("noise{}r{run}_", std::process::id());
    let run_dir = std::env::temp_dir().join(format!("phri-test-{prefix}"));
    let _ = std::fs::remove_dir_all(&run_dir);
    let report = std::env::temp_dir().join(format!("phri-test-{prefix}report.json"));
    let _ = std::fs::remove_file(&report);
    let mut supervisor = Command::new(bin("phri-supervisor"))
        .current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--scenario", scenario, "--prefix", &prefix])
        .arg("--run-dir")
        .arg(&run_dir)
        .arg("--report")
        .arg(&report)
        .arg("--duration")
        .arg(duration_s.to_string())
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let mut injected = 0;
    let mut at = first_s;
    while at + 2.5 < duration_s {
        let wait = Duration::from_secs_f64(at).saturating_sub(t0.elapsed());
        std::thread::sleep(wait);
        let out = Command::new(bin("phri-fault"))
            .arg("--run-dir")
            .arg(&run_dir)
            .args(["camera", "corrupt", "noise", "--frames", "60"])
            .output()
            .unwrap();
        if !out.status.success() {
            // never leave the cell running behind a failed assertion
            let _ = supervisor.kill();
            let _ = supervisor.wait();
            panic!(
                "phri-fault camera corrupt noise: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        injected += 1;
        at += every_s;
    }
    let status = supervisor.wait().unwrap();
    assert!(injected >= 4, "{injected} injections");
    let text = std::fs::read_to_string(&report)
        .unwrap_or_else(|e| panic!("{}: {e} (supervisor {status})", report.display()));
    let r: Value = serde_json::from_str(&text).unwrap();
    assert_nothing_left(&prefix);
    let _ = std::fs::remove_dir_all(&run_dir);
    let _ = std::fs::remove_file(&report);
    eprintln!(
        "run {run}: {injected} noise injections; false detections {}, contacts {}, detections {}, protective stops {}, waypoints {}, min distance {}, torque loop {}",
        r["false_detections"],
        r["contacts"].as_array().map_or(0, Vec::len),
        r["detections"],
        r["protective_stops"],
        r["task"]["waypoints_reached"],
        r["min_distance_m"],
        r["torque_loop"]
    );
    r
}

/// No process of the run and no shared-memory file of its prefix remain.
fn assert_nothing_left(prefix: &str) {
    let out = Command::new("pgrep")
        .arg("-f")
        .arg(format!("--prefix {prefix}"))
        .output()
        .unwrap();
    assert!(
        out.stdout.is_empty(),
        "processes left: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    let files = phri_ipc::files_of(prefix);
    assert!(files.is_empty(), "left behind: {files:?}");
}

#[test]
fn flying_pixels_cause_no_false_detection_in_a_running_cell() {
    for run in 1..=2 {
        let r = run_with_noise(run, "free-motion", 20.0, 3.0, 2.5);
        assert_eq!(r["false_detections"], 0, "run {run}: {}", r["events"]);
        assert!(
            r["contacts"].as_array().unwrap().is_empty(),
            "run {run}: {}",
            r["contacts"]
        );
        // ingestion filtered every noisy frame and lived on
        assert_eq!(
            r["services"]["perception"]["restarts"], 0,
            "run {run}: {}",
            r["events"]
        );
        // perception's latencies, from capture and from the frame's arrival
        // at ingestion (carried through perception/depth and the results)
        let p = &r["perception"];
        let capture = p["frame_to_repulsion_ms"]["p50"].as_f64().unwrap();
        let arrival = p["arrival_to_repulsion_ms"]["p50"].as_f64().unwrap();
        assert!(
            arrival > 0.0 && arrival < capture,
            "run {run}: arrival → result {arrival} ms, capture → result {capture} ms"
        );
        // the arm went on with its task through the noise
        assert!(
            r["task"]["waypoints_reached"].as_u64().unwrap() >= 5,
            "run {run}: {}",
            r["task"]
        );
    }
}
