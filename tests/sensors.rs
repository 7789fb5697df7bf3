//! The cell with real sensors' sources behind the same channels, run by the
//! real supervisor: a replay of real Kinect frames of a person in place of
//! the simulated camera, beside the simulated robot (a hybrid cell). The
//! report names each sensor's source with its frames, drops, rate, latency
//! and intrinsics. One cell at a time.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::Mutex;

use serde_json::Value;

mod support;

static SERIAL: Mutex<()> = Mutex::new(());

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// The real Kinect frames of a person (`../shared/data/kinect-person`,
/// beside the clone: never copied into it).
fn kinect_person() -> PathBuf {
    let d = repo().join("../shared/data/kinect-person");
    assert!(
        d.is_dir(),
        "{}: the real Kinect frames are missing beside the clone",
        d.display()
    );
    d.canonicalize().unwrap()
}

/// A supervisor run of `scenario` for `seconds` with `args`; its report.
fn run(test: &str, scenario: &str, seconds: f64, args: &[&str]) -> Value {
    run_under(None, test, scenario, seconds, args)
}

/// As [`run`], the supervisor started by `wrapper` (`fakenect DIR`) when given.
fn run_under(
    wrapper: Option<&[&str]>,
    test: &str,
    scenario: &str,
    seconds: f64,
    args: &[&str],
) -> Value {
    let place = support::RunPlace::new('s', test);
    let mut cmd = place.command(env!("CARGO_BIN_EXE_phri-supervisor"), &repo());
    if let Some(w) = wrapper {
        // the same command behind the wrapper: `fakenect DIR phri-supervisor …`
        let inner = cmd;
        cmd = std::process::Command::new(w[0]);
        cmd.args(&w[1..])
            .arg(inner.get_program())
            .args(inner.get_args())
            .current_dir(repo());
    }
    cmd.arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .args(["--scenario", scenario])
        .args(["--duration", &seconds.to_string()])
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::inherit());
    let status = cmd.status().unwrap();
    assert!(status.success(), "supervisor failed: {status}");
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&place.report).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&place.run_dir);
    r
}

/// The collaboration on the person tracker's skeletons of the simulated
/// camera's frames (`[skeleton] source = "depth"`, `phri-tracker`) instead of
/// the simulation's truth: the wave is recognised as the right hand's, the
/// arm approaches and touches it, follows it and touches it again, the wrist
/// push ends it, the force at the hand is estimated within the paper's
/// bounds, nothing else is touched.
#[test]
fn a_collaboration_runs_on_the_depth_trackers_skeletons() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // the push on the wrist is at 15.5-16.5 s of the scenario, on the
    // robot's clock: 20 s of wall clock leave room for a robot loop that
    // slipped (on these virtual machines up to 12 % of periods, reported as
    // `robot loop behind`)
    let r = run(
        "depth-collab",
        "collaboration",
        20.0,
        &["--set", "skeleton.source=\"depth\""],
    );
    let cam = &r["perception"]["cameras"][0];
    let c = &r["collaboration"];
    eprintln!("camera 0: {cam}");
    eprintln!("collaboration: {c}");
    assert_eq!(cam["skeleton_source"], "depth");
    assert_eq!(r["services"]["tracker"]["alive_at_end"], true);
    assert!(
        cam["skeletons_with_people"].as_u64().unwrap() > 200,
        "{cam}"
    );
    let requests = c["requests"].as_array().unwrap();
    assert_eq!(requests.len(), 1, "{requests:?}");
    assert_eq!(requests[0]["part"], "right_hand");
    assert_eq!(requests[0]["accepted"], true);
    let phases: Vec<&str> = c["phases"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|p| p["phase"].as_str())
        .collect();
    let after = |m: &str, from: usize| {
        phases[from..]
            .iter()
            .position(|p| *p == m)
            .map(|i| i + from)
    };
    let second_contact = after("approach", 0)
        .and_then(|a| after("contact", a))
        .and_then(|c| after("follow", c))
        .and_then(|f| after("contact", f));
    assert!(second_contact.is_some(), "{phases:?}");
    // the push on the wrist lasts 1 s (15.5-16.5 s of the scenario): under
    // the suite's load the approach may lag by a second (5.8 s instead of
    // 4.8 s, the tracker's skeleton p99 37 ms in one run), and the second
    // contact then begins as the push does and the push can pass unseen;
    // the lock-step cell asserts the push on the tracker's skeletons
    // deterministically. An on-time second contact must be ended by it.
    let second_contact_t = c["phases"][second_contact.unwrap()]["t_s"]
        .as_f64()
        .unwrap();
    if c["ended_by"].is_null() {
        assert!(
            second_contact_t > 15.0,
            "no end after an on-time second contact: {c}"
        );
    } else {
        assert_eq!(c["ended_by"], "wrist_push", "{c}");
    }
    let f = &c["force_error"];
    assert!(f["samples"].as_u64().unwrap() > 100, "{f}");
    assert!(f["p50"].as_f64().unwrap() <= 0.10, "{f}");
    assert!(f["p95"].as_f64().unwrap() <= 0.25, "{f}");
    let contacts = r["contacts"].as_array().unwrap();
    assert!(
        contacts.iter().all(|k| k["intended"] == true),
        "{contacts:?}"
    );
    // 17 services, one past the first health message: every reader knew
    // every publisher the supervisor started (nothing refused as a stranger)
    let strangers: Vec<String> = r["inputs"]
        .as_object()
        .into_iter()
        .flatten()
        .flat_map(|(reader, channels)| {
            channels
                .as_object()
                .into_iter()
                .flatten()
                .filter(|(_, c)| c["stranger"].as_u64().unwrap_or(0) > 0)
                .map(move |(channel, c)| format!("{reader} on {channel}: {c}"))
        })
        .collect();
    assert!(strangers.is_empty(), "{strangers:?}");
}

#[test]
fn a_replay_of_real_kinect_frames_drives_the_simulated_arm_s_perception() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = kinect_person();
    let replay_dir = format!("camera.replay_dir=\"{}\"", dir.display());
    // the recorded frames' own intrinsics (the Kinect v1's nominal ones)
    let r = run(
        "replay",
        "coexistence",
        10.0,
        &[
            "--camera",
            "replay",
            "--set",
            &replay_dir,
            "--set",
            "camera.intrinsics.fx=580.0",
            "--set",
            "camera.intrinsics.fy=580.0",
            "--set",
            "camera.intrinsics.cx=320.0",
            "--set",
            "camera.intrinsics.cy=240.0",
        ],
    );
    let cam = &r["perception"]["cameras"][0];
    eprintln!("camera 0: {cam}");
    eprintln!("torque loop: {}", r["torque_loop"]);
    assert_eq!(cam["source"], "replay");
    assert_eq!(r["voice"]["mic"]["source"], "sim");
    let frames = cam["frames"].as_u64().unwrap();
    assert!(frames >= 200, "{frames} frames in 10 s at 30 Hz");
    let rate = cam["rate_hz"].as_f64().unwrap();
    assert!((27.0..=33.0).contains(&rate), "{rate} Hz");
    let k = &cam["intrinsics"];
    assert_eq!(
        (k["fx"].as_f64(), k["cx"].as_f64()),
        (Some(580.0), Some(320.0))
    );
    let drops = &cam["drop_causes"];
    assert_eq!(drops["malformed"], 0, "{drops}");
    // the replayed frames reached the repulsion workers
    assert!(cam["frame_to_repulsion_ms"]["p50"].as_f64().unwrap() > 0.0);
    // a camera that is not simulated has its people tracked on depth: the
    // person of the recording is in (nearly) every skeleton
    assert_eq!(cam["skeleton_source"], "depth");
    assert_eq!(r["services"]["tracker"]["restarts"], 0, "{}", r["services"]);
    assert_eq!(r["services"]["tracker"]["alive_at_end"], true);
    let skeletons = cam["skeletons"].as_u64().unwrap();
    let with_people = cam["skeletons_with_people"].as_u64().unwrap();
    // the tracker takes the newest frame: under load it may skip one
    assert!(
        skeletons * 10 >= frames * 9,
        "{skeletons} skeletons of {frames} frames"
    );
    assert!(
        with_people * 10 >= skeletons * 8,
        "a person in {with_people} of {skeletons} skeletons"
    );
    assert!(cam["capture_to_arrival_ms"]["p99"].as_f64().unwrap() < 30.0);
    // the torque loop beside it answered every state (its pace, a
    // machine's figure, is the report's `robot loop behind`)
    let tl = &r["torque_loop"];
    assert!(tl["cycles"].as_u64().unwrap() > 5_000, "{tl}");
    assert_eq!(tl["missed_deadlines"], 0, "{tl}");
}

/// A fakenect recording of `seconds` at 30 Hz of the real frames, looped:
/// the 12 depth files written once (11-bit disparity, the Kinect's own
/// conversion) and hard-linked under every later name fakenect plays.
fn fakenect_recording(seconds: f64) -> PathBuf {
    use phri_depth::kinect::Disparity;
    let dir = std::env::temp_dir().join(format!("phri-sensors-fakenect-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let table = Disparity::new();
    let mut sources: Vec<PathBuf> = std::fs::read_dir(kinect_person())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_none())
        .collect();
    sources.sort();
    let mut written = Vec::new();
    let mut index = String::new();
    for i in 0..(seconds * 30.0) as usize {
        let t = 1.0 + i as f64 / 30.0;
        let name = format!("d-{t:.6}-{}.pgm", 1_000_000 + i as u64 * 2_000_000);
        let path = dir.join(&name);
        match written.get(i % sources.len()) {
            Some(first) => std::fs::hard_link(first, &path).unwrap(),
            None => {
                let bytes = std::fs::read(&sources[i]).unwrap();
                let mut pgm = b"P5 640 480 65535\n".to_vec();
                for px in bytes.chunks_exact(2) {
                    let mm = u16::from_le_bytes([px[0], px[1]]);
                    pgm.extend_from_slice(&table.mm_to_raw(mm).to_le_bytes());
                }
                std::fs::write(&path, pgm).unwrap();
                written.push(path.clone());
            }
        }
        index.push_str(&name);
        index.push('\n');
    }
    std::fs::write(dir.join("INDEX.txt"), index).unwrap();
    dir
}

#[test]
fn a_kinect_under_fakenect_drives_the_simulated_arm_s_perception() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let fakenect = Path::new("/usr/bin/fakenect");
    assert!(
        fakenect.is_file(),
        "fakenect missing: deploy/packages installs it (Debian libfreenect-bin)"
    );
    let dir = fakenect_recording(14.0);
    let d = dir.display().to_string();
    let r = run_under(
        Some(&["/usr/bin/fakenect", &d]),
        "fakenect",
        "coexistence",
        8.0,
        &["--camera", "freenect"],
    );
    let _ = std::fs::remove_dir_all(&dir);
    let cam = &r["perception"]["cameras"][0];
    eprintln!("camera 0: {cam}");
    eprintln!("torque loop: {}", r["torque_loop"]);
    assert_eq!(cam["source"], "freenect");
    assert!(
        r["services"]["camera"]["restarts"] == 0,
        "{}",
        r["services"]["camera"]
    );
    let frames = cam["frames"].as_u64().unwrap();
    assert!(frames >= 150, "{frames} frames in 8 s at 30 Hz");
    let rate = cam["rate_hz"].as_f64().unwrap();
    assert!((27.0..=33.0).contains(&rate), "{rate} Hz");
    // the Kinect's own intrinsics, not the configuration's
    let k = &cam["intrinsics"];
    assert_eq!(
        (k["fx"].as_f64(), k["cy"].as_f64()),
        (Some(580.0), Some(240.0))
    );
    assert!(cam["frame_to_repulsion_ms"]["p50"].as_f64().unwrap() > 0.0);
    assert_eq!(r["torque_loop"]["missed_deadlines"], 0);
    // phri-freenect's loop ran at the camera's real-time priority
    let rt = &r["realtime"]["services"]["camera"];
    assert_eq!(rt["shortfalls"], serde_json::json!([]), "{rt}");
}
