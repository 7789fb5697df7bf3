//! Starts a real cell (the release supervisor, coexistence scenario) and
//! `phri-viz` on a free port, connects a client speaking Foxglove's WebSocket
//! protocol (`foxglove.sdk.v1`: JSON `serverInfo`/`advertise`, a JSON
//! `subscribe`, binary message data `0x01 | u32 subscription | u64 log time |
//! payload`), and checks the rates and contents it receives, and that the
//! torque loop missed no deadline with the viewer attached.

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{connect, repo, start_viz, Proc, VIZ};
use foxglove::messages::{JointStates, RawImage, SceneUpdate};
use foxglove::Decode;
use serde_json::{json, Value};
use tungstenite::Message;

/// What the client saw on one topic.
#[derive(Default)]
struct Seen {
    count: u64,
    last: Vec<u8>,
}

#[test]
fn a_foxglove_client_gets_the_scene_and_joint_states_and_the_loop_misses_nothing() {
    let supervisor = Path::new(VIZ).with_file_name("phri-supervisor");
    assert!(
        supervisor.exists(),
        "{} is not built: cargo build --release --bins first",
        supervisor.display()
    );
    let prefix = format!("vizlive{}_", std::process::id());
    let run_dir = std::env::temp_dir().join(format!("phri-viz-live-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&run_dir);
    let report = run_dir.join("report.json");
    let mut cell = Proc(
        Command::new(&supervisor)
            .current_dir(repo())
            .args(["--config", "deploy/phri.toml", "--scenario", "coexistence"])
            .args(["--duration", "16", "--prefix", &prefix, "--run-dir"])
            .arg(&run_dir)
            .arg("--report")
            .arg(&report)
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start the supervisor"),
    );
    std::thread::sleep(Duration::from_secs(3));
    let (mut viz, port) = start_viz(&prefix, &[]);
    let mut ws = connect(port);

    // serverInfo, then the advertised channels
    let mut channels: HashMap<u64, (String, String)> = HashMap::new();
    let t0 = Instant::now();
    while channels.len() < phri_viz::TOPICS.len() && t0.elapsed() < Duration::from_secs(10) {
        match ws.read() {
            Ok(Message::Text(t)) => {
                let v: Value = serde_json::from_str(t.as_str()).expect("JSON");
                if v["op"] == "advertise" {
                    for c in v["channels"].as_array().expect("channels") {
                        channels.insert(
                            c["id"].as_u64().expect("id"),
                            (
                                c["topic"].as_str().unwrap_or("").to_string(),
                                c["schemaName"].as_str().unwrap_or("").to_string(),
                            ),
                        );
                    }
                }
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("reading the advertisements: {e}"),
        }
    }
    let schema_of = |topic: &str| {
        channels
            .values()
            .find(|(t, _)| t == topic)
            .map(|(_, s)| s.clone())
            .unwrap_or_else(|| panic!("{topic} advertised: {channels:?}"))
    };
    assert_eq!(schema_of("/viz/robot"), "foxglove.SceneUpdate");
    assert_eq!(schema_of("/viz/person"), "foxglove.SceneUpdate");
    assert_eq!(schema_of("/viz/joints"), "foxglove.JointStates");
    assert_eq!(schema_of("/viz/depth/points"), "foxglove.PointCloud");
    assert_eq!(schema_of("/viz/status"), "phri.viz.Status");

    // subscribe to everything: subscription id = channel id
    let subs: Vec<Value> = channels
        .keys()
        .map(|id| json!({"id": id, "channelId": id}))
        .collect();
    ws.send(Message::text(
        json!({"op": "subscribe", "subscriptions": subs}).to_string(),
    ))
    .unwrap();

    // let the subscriptions settle, then count for 6 s
    let mut seen: HashMap<String, Seen> = HashMap::new();
    let settle = Instant::now() + Duration::from_secs(1);
    let mut counting_since: Option<Instant> = None;
    let end = settle + Duration::from_secs(6);
    while Instant::now() < end {
        let msg = match ws.read() {
            Ok(m) => m,
            Err(tungstenite::Error::Io(e))
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut =>
            {
                continue
            }
            Err(e) => panic!("reading messages: {e}"),
        };
        let Message::Binary(b) = msg else {
            continue;
        };
        if Instant::now() < settle {
            continue;
        }
        counting_since.get_or_insert_with(Instant::now);
        assert_eq!(b[0], 0x01, "message data");
        let sub = u32::from_le_bytes(b[1..5].try_into().unwrap()) as u64;
        let topic = channels
            .get(&sub)
            .map(|c| c.0.clone())
            .expect("a subscribed channel");
        let s = seen.entry(topic).or_default();
        s.count += 1;
        s.last = b[13..].to_vec();
    }
    let secs = counting_since
        .expect("messages arrived")
        .elapsed()
        .as_secs_f64();
    let rate = |topic: &str| seen.get(topic).map_or(0.0, |s| s.count as f64 / secs);
    let mut rates: Vec<String> = seen
        .keys()
        .map(|t| format!("{t} {:.1} Hz", rate(t)))
        .collect();
    rates.sort();
    eprintln!("received over {secs:.2} s: {}", rates.join(", "));

    for topic in [
        "/viz/robot",
        "/viz/person",
        "/viz/repulsion",
        "/viz/collab",
        "/viz/tf",
    ] {
        assert!(rate(topic) >= 10.0, "{topic}: {:.1} Hz", rate(topic));
    }
    assert!(
        rate("/viz/joints") >= 100.0,
        "joints: {:.1} Hz",
        rate("/viz/joints")
    );
    assert!(
        rate("/viz/status") >= 100.0,
        "status: {:.1} Hz",
        rate("/viz/status")
    );
    // the camera gives 30 frames/s; the scene rate passes them on
    assert!(
        rate("/viz/depth/points") >= 5.0,
        "points: {:.1} Hz",
        rate("/viz/depth/points")
    );
    assert!(
        rate("/viz/depth/image") >= 5.0,
        "image: {:.1} Hz",
        rate("/viz/depth/image")
    );

    // what they hold
    let joints = JointStates::decode(&seen["/viz/joints"].last[..]).expect("JointStates");
    assert_eq!(joints.joints.len(), 7);
    assert!(joints
        .joints
        .iter()
        .all(|j| j.position.is_some_and(f64::is_finite)));
    let robot = SceneUpdate::decode(&seen["/viz/robot"].last[..]).expect("SceneUpdate");
    assert!(
        robot.entities.len() >= 7,
        "a capsule per link: {}",
        robot.entities.len()
    );
    assert!(robot
        .entities
        .iter()
        .all(|e| e.spheres.len() >= 2 && e.frame_id == "base"));
    let person = SceneUpdate::decode(&seen["/viz/person"].last[..]).expect("SceneUpdate");
    assert!(
        !person.entities.is_empty(),
        "the person of the coexistence scenario"
    );
    let image = RawImage::decode(&seen["/viz/depth/image"].last[..]).expect("RawImage");
    assert_eq!(
        (image.width, image.height, image.encoding.as_str()),
        (320, 240, "16UC1")
    );
    let status: Value = serde_json::from_slice(&seen["/viz/status"].last).expect("JSON status");
    assert_ne!(status["mode"], "none", "{status}");
    assert_eq!(
        status["residual"].as_array().map(Vec::len),
        Some(7),
        "{status}"
    );
    assert_eq!(status["collision_norm_threshold"], 12.0, "{status}");

    // the viewer stops cleanly on SIGTERM
    let _ = ws.close(None);
    let _ = ws.flush();
    drop(ws);
    // SAFETY: kill(2) on our own child's pid.
    unsafe { libc::kill(viz.0.id() as i32, libc::SIGTERM) };
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = viz.0.try_wait().unwrap() {
            break s;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "phri-viz did not stop"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "phri-viz: {status}");

    // the run, with the viewer attached most of it
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = cell.0.try_wait().unwrap() {
            break s;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the supervisor did not exit"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "supervisor: {status}");
    let r: Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("report")).unwrap();
    eprintln!("torque loop: {}", r["torque_loop"]);
    assert!(
        r["torque_loop"]["cycles"].as_u64() > Some(10_000),
        "{}",
        r["torque_loop"]
    );
    assert_eq!(
        r["torque_loop"]["missed_deadlines"], 0,
        "{}",
        r["torque_loop"]
    );
    let _ = std::fs::remove_dir_all(&run_dir);
}

#[test]
fn bad_flags_are_one_line_naming_the_flag() {
    for (args, needle) in [
        (vec!["--addr", "nowhere"], "--addr"),
        (vec!["--rate", "0"], "--rate"),
        (vec!["--joint-rate=-5"], "--joint-rate"),
        (vec!["--depth-downsample", "0"], "--depth-downsample"),
        (vec!["--cloud-downsample", "65"], "--cloud-downsample"),
        (vec!["--config", "/no/such/phri.toml"], "--config"),
        (vec!["--max-clients", "0"], "--max-clients"),
        (vec!["--client-buffer", "0"], "--client-buffer"),
        (vec!["--stale-after", "1"], "--stale-after"),
    ] {
        let out = Command::new(VIZ)
            .current_dir(repo())
            .args(["--prefix", &format!("viznone{}_", std::process::id())])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    // a port already taken names --addr
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = Command::new(VIZ)
        .current_dir(repo())
        .args([
            "--prefix",
            &format!("viznone{}_", std::process::id()),
            "--addr",
            &addr,
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.lines().last().unwrap_or("").contains("--addr"), "{err}");
    // completions
    let out = Command::new(VIZ)
        .args(["completions", "bash"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("--joint-rate"));
    assert!(String::from_utf8_lossy(&out.stdout).contains("--max-clients"));
}
