//! phri's people as ROS4HRI (REP 155) shows them, read by a DDS peer
//! nobody here wrote: Eclipse Cyclone DDS's Python binding
//! (`deploy/ros2/peer.py`) on this host's loopback
//! (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, a ROS domain and an iceoryx2
//! prefix of the test's own). The bridge runs with two cameras
//! (`deploy/two-cameras.toml`); the test is their body trackers, at 30 Hz
//! on `perception/skeleton` and `perception/1/skeleton`: camera 0 tracks
//! person 7 (its right foot not seen) beside an untracked person 3, camera
//! 1 person 2; then camera 1 loses its person, then camera 0 too. The peer
//! sees `/humans/bodies/tracked` go from `[b07, b12]` to `[b07]` to `[]`,
//! and on `/tf` `body_b07` and `body_b12` in `base_link` with a frame per
//! joint seen (none for the foot, none of person 3), where the trackers
//! put them.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use phri_ipc::{Skeleton, SkeletonJoint, TrackedPerson, Zeroed, CAMERAS, SKELETON_JOINTS};
use serde_json::Value;

#[path = "../../../tests/support/workspace.rs"]
mod workspace;
use workspace::repo;
#[allow(dead_code)]
mod netns;
use netns::{peer_python, wait_at_most};

/// Cyclone DDS on this host's loopback only: no multicast, unicast
/// discovery of 127.0.0.1, participant announcements every 0.5 s.
const LOOPBACK_PEER: &str = "<CycloneDDS><Domain id=\"any\"><General><Interfaces>\
    <NetworkInterface name=\"lo\"/></Interfaces><AllowMulticast>false</AllowMulticast>\
    </General><Discovery><ParticipantIndex>auto</ParticipantIndex>\
    <Peers><Peer address=\"127.0.0.1\"/></Peers><SPDPInterval>0.5s</SPDPInterval>\
    </Discovery></Domain></CycloneDDS>";

/// How long the peer listens [s]; the phases of the trackers, from the
/// peer's start: both cameras track someone until `ONE_S`, camera 0 alone
/// until `NONE_S`, then nobody.
const LISTEN_S: f64 = 13.0;
const ONE_S: f64 = 7.0;
const NONE_S: f64 = 9.5;

/// A child killed (if still running) when dropped: no leftovers on a panic.
struct Reaped(Option<Child>);

impl Drop for Reaped {
    fn drop(&mut self) {
        if let Some(c) = self.0.as_mut() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// A person facing the robot's base (toward −x) at (`x`, `y`): their left
/// toward −y.
fn person(id: u32, x: f64, y: f64) -> TrackedPerson {
    use SkeletonJoint::*;
    let mut p = TrackedPerson {
        id,
        tracked: 1,
        joints: [[0.0; 3]; SKELETON_JOINTS],
        confidence: [0.9; SKELETON_JOINTS],
    };
    for (j, dy, z) in [
        (Head, 0.0, 1.7),
        (Neck, 0.0, 1.5),
        (Torso, 0.0, 1.2),
        (LeftShoulder, -0.2, 1.5),
        (RightShoulder, 0.2, 1.5),
        (LeftElbow, -0.25, 1.2),
        (RightElbow, 0.25, 1.2),
        (LeftHand, -0.3, 0.95),
        (RightHand, 0.3, 0.95),
        (LeftHip, -0.1, 0.9),
        (RightHip, 0.1, 0.9),
        (LeftKnee, -0.1, 0.5),
        (RightKnee, 0.1, 0.5),
        (LeftFoot, -0.1, 0.1),
        (RightFoot, 0.1, 0.1),
    ] {
        p.joints[j as usize] = [x, y + dy, z];
    }
    p
}

fn skeleton(seq: u64, people: &[TrackedPerson]) -> Skeleton {
    let mut s = Skeleton::zeroed();
    let now = phri_runtime::now_ns();
    (s.seq, s.capture_ns, s.capture_wall_ns, s.published_ns) = (seq, now, now, now);
    s.n_people = people.len() as u32;
    s.people[..people.len()].copy_from_slice(people);
    s
}

/// A transform the peer saw last: its parent, translation and rotation.
fn last(tf: &Value, child: &str) -> (String, Vector3<f64>, UnitQuaternion<f64>) {
    let t = &tf["last"][child];
    let f = |v: &Value, i: usize| v[i].as_f64().unwrap_or_else(|| panic!("{child}: {t}"));
    let (p, q) = (&t["t"], &t["q"]);
    (
        t["parent"].as_str().unwrap_or_default().to_string(),
        Vector3::new(f(p, 0), f(p, 1), f(p, 2)),
        UnitQuaternion::from_quaternion(Quaternion::new(f(q, 3), f(q, 0), f(q, 1), f(q, 2))),
    )
}

#[test]
fn a_dds_peer_sees_the_tracked_bodies_and_their_frames_as_ros4hri() {
    let python = peer_python(&repo());
    let prefix = format!("ros2h{}_", std::process::id());
    let domain = 110 + std::process::id() % 100;
    let _ = phri_ipc::remove_leftovers(&prefix);

    // the bridge, two cameras, on the loopback
    let mut bridge = Command::new(env!("CARGO_BIN_EXE_phri-ros2"));
    bridge
        .current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/two-cameras.toml"))
        .args(["--prefix", &prefix])
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env_remove("ROS_LOCALHOST_ONLY")
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env_remove("RUST_LOG")
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = bridge.spawn().expect("phri-ros2 starts");
    let stderr = child.stderr.take().unwrap();
    let mut bridge = Reaped(Some(child));
    let lines = Arc::new(Mutex::new(Vec::<String>::new()));
    let kept = Arc::clone(&lines);
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            eprintln!("{line}");
            kept.lock().unwrap().push(line);
        }
    });
    let log = || lines.lock().unwrap().join("\n");
    let t0 = Instant::now();
    while !lines
        .lock()
        .unwrap()
        .iter()
        .any(|l| l.contains("on ROS 2 domain"))
    {
        if let Some(s) = bridge.0.as_mut().unwrap().try_wait().unwrap() {
            panic!("phri-ros2 exited ({s}):\n{}", log());
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "no start line");
        std::thread::sleep(Duration::from_millis(20));
    }
    let started = log();
    assert!(
        started.contains("/humans/bodies/tracked (2 camera(s))"),
        "{started}"
    );

    // the peer, then the trackers while it listens
    let node = phri_ipc::node("test-ros2-humans", &prefix).unwrap();
    let trackers = [
        CAMERAS[0].skeleton.publisher(&node).unwrap(),
        CAMERAS[1].skeleton.publisher(&node).unwrap(),
    ];
    let peer = Command::new(&python)
        .arg(repo().join("deploy/ros2/peer.py"))
        .args(["--duration", &LISTEN_S.to_string()])
        .args(["--topics", "humans,tf", "--domain", &domain.to_string()])
        .env("CYCLONEDDS_URI", LOOPBACK_PEER)
        .stdout(Stdio::piped())
        .spawn()
        .expect("peer.py starts");
    let mut peer = Reaped(Some(peer));
    let mut seven = person(7, 2.0, 0.0);
    seven.confidence[SkeletonJoint::RightFoot as usize] = 0.0;
    let mut three = person(3, 2.5, -1.0);
    three.tracked = 0;
    let two = person(2, 1.5, 1.0);
    let t0 = Instant::now();
    let mut seq = 0;
    let mut published = [0u64; 3];
    while peer.0.as_mut().unwrap().try_wait().unwrap().is_none() {
        assert!(
            t0.elapsed() < Duration::from_secs_f64(LISTEN_S + 30.0),
            "peer.py did not end"
        );
        let t = t0.elapsed().as_secs_f64();
        seq += 1;
        let phase = if t < ONE_S {
            0
        } else if t < NONE_S {
            1
        } else {
            2
        };
        published[phase] += 1;
        let (first, second): (&[TrackedPerson], &[TrackedPerson]) = match phase {
            0 => (&[seven, three], &[two]),
            1 => (&[seven, three], &[]),
            _ => (&[], &[]),
        };
        trackers[0].publish(&skeleton(seq, first)).unwrap();
        trackers[1].publish(&skeleton(seq, second)).unwrap();
        std::thread::sleep(Duration::from_millis(33));
    }
    let out = peer.0.take().unwrap().wait_with_output().unwrap();
    assert!(out.status.success(), "peer.py: {}", out.status);
    let got: Value = serde_json::from_slice(&out.stdout).expect("peer.py prints JSON");
    drop(trackers);
    drop(node);

    // the bridge stops cleanly and counts what it published
    let c = bridge.0.as_mut().unwrap();
    // SAFETY: kill(2) of our own child
    unsafe { libc::kill(c.id() as i32, libc::SIGINT) };
    let status = wait_at_most(c, Duration::from_secs(20), "phri-ros2");
    bridge.0 = None;
    reader.join().unwrap();
    let _ = phri_ipc::remove_leftovers(&prefix);
    let log = log();
    assert!(status.success(), "phri-ros2: {status}\n{log}");
    let summary = log
        .lines()
        .rfind(|l| l.contains("/humans/bodies/tracked ") && l.contains("published"))
        .unwrap_or_else(|| panic!("no summary in\n{log}"));
    eprintln!("skeletons published per phase {published:?}; {summary}");

    // /humans/bodies/tracked: every camera's tracked bodies, as they changed
    let humans = &got["humans"];
    eprintln!("/humans/bodies/tracked {humans}");
    let lists: Vec<Vec<String>> = serde_json::from_value(humans["lists"].clone()).unwrap();
    let count = humans["count"].as_u64().unwrap_or(0);
    assert!(count >= 100, "{count} IdsList received: {humans}");
    let both = lists
        .iter()
        .rposition(|l| l == &["b07", "b12"])
        .unwrap_or_else(|| panic!("never [b07, b12]: {lists:?}"));
    let one = lists[both..]
        .iter()
        .position(|l| l == &["b07"])
        .unwrap_or_else(|| panic!("never [b07] after [b07, b12]: {lists:?}"));
    assert!(both + one < lists.len() - 1, "{lists:?}");
    assert_eq!(lists.last(), Some(&Vec::new()), "{lists:?}");
    assert!(
        lists.iter().flatten().all(|id| id == "b07" || id == "b12"),
        "{lists:?}"
    );
    // stamped with the capture time on ROS time: received soon after it
    let p50 = humans["latency_us"]["p50"].as_f64().unwrap();
    assert!((-5_000.0..2_000_000.0).contains(&p50), "{humans}");

    // /tf: body_<id> in base_link, each joint seen in it
    let tf = &got["tf"];
    let frames: Vec<String> = serde_json::from_value(tf["frames"].clone()).unwrap();
    eprintln!("/tf {frames:?}");
    let children = |body: &str| {
        frames
            .iter()
            .filter(|f| f.starts_with(&format!("{body}>")))
            .count()
    };
    for f in [
        "base_link>body_b07",
        "body_b07>head_b07",
        "body_b07>torso_b07",
        "body_b07>waist_b07",
        "body_b07>l_wrist_b07",
        "body_b07>r_elbow_b07",
        "body_b07>l_ankle_b07",
        "base_link>body_b12",
        "body_b12>r_ankle_b12",
    ] {
        assert!(frames.iter().any(|x| x == f), "no {f} in {frames:?}");
    }
    assert_eq!((children("body_b07"), children("body_b12")), (14, 15));
    assert!(!frames.iter().any(|f| f.contains("r_ankle_b07")));
    assert!(!frames.iter().any(|f| f.contains("b03")));
    assert_eq!(
        frames
            .iter()
            .filter(|f| f.starts_with("base_link>"))
            .count(),
        2,
        "{frames:?}"
    );
    // where the tracker put them: the body at the middle of the hips, z up,
    // x toward the robot; each joint there through it
    let (parent, body, q) = last(tf, "body_b07");
    assert_eq!(parent, "base_link");
    assert!((body - Vector3::new(2.0, 0.0, 0.9)).norm() < 1e-9, "{body}");
    assert!((q * Vector3::z() - Vector3::z()).norm() < 1e-9, "{q}");
    assert!((q * Vector3::x() + Vector3::x()).norm() < 1e-9, "{q}");
    for (child, joint) in [
        ("l_wrist_b07", SkeletonJoint::LeftHand),
        ("head_b07", SkeletonJoint::Head),
        ("l_ankle_b07", SkeletonJoint::LeftFoot),
    ] {
        let (parent, t, _) = last(tf, child);
        assert_eq!(parent, "body_b07");
        let at = body + q * t;
        let want = Vector3::from(seven.joints[joint as usize]);
        assert!((at - want).norm() < 1e-9, "{child}: {at} ≠ {want}");
    }
    let (_, body, _) = last(tf, "body_b12");
    assert!((body - Vector3::new(1.5, 1.0, 0.9)).norm() < 1e-9, "{body}");

    // the bridge's own count of the lists it published
    let sent: u64 = summary
        .split_once("/humans/bodies/tracked ")
        .and_then(|(_, rest)| rest.split([';', ',', ' ']).next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{summary}"));
    assert!(sent >= count, "{summary}");
}
