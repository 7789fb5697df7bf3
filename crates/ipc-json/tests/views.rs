//! The JSON views: every message survives `to_json` → `from_json`, the shape
//! users' scripts parse is pinned, and bad input names the field at fault.

use phri_ipc::*;
use phri_ipc_json::{from_json, to_json, JsonError};
use serde_json::{json, Value};

/// Copy `xs` into the front of a zeroed array.
fn front<const N: usize>(xs: &[f64]) -> [f64; N] {
    let mut a = [0.0; N];
    a[..xs.len()].copy_from_slice(xs);
    a
}

fn joint_state() -> JointState {
    let mut m = JointState::zeroed();
    m.seq = 1234;
    m.stamp_ns = 5_000_000_000;
    m.published_ns = 5_000_021_500;
    m.dof = 7;
    m.status = robot_status::FT_VALID | robot_status::COMMAND_FRESH;
    m.q = front(&[0.1, -0.5, 0.25, 1.5, -0.75, 0.3, 0.0]);
    m.tau = front(&[1.5, -20.25, 3.0, 10.0, -0.5, 0.125, 0.0625]);
    m.wrench = [1.0, 2.0, -3.5, 0.1, 0.2, f64::NAN];
    m.command_seq = 1233;
    m.missed_commands = 2;
    m
}

fn torque_command() -> TorqueCommand {
    let mut m = TorqueCommand::zeroed();
    m.seq = 1233;
    m.stamp_ns = 5_000_400_000;
    m.state_seq = 1233;
    m.state_stamp_ns = 4_999_000_000;
    m.dof = 7;
    m.mode = ControlMode::Task as u32;
    m.tau = front(&[1.5, -20.25, 3.0, 10.0, -0.5, 0.125, 0.0625]);
    m
}

fn residual() -> Residual {
    let mut m = Residual::zeroed();
    m.seq = 77;
    m.stamp_ns = 5_000_100_000;
    m.state_seq = 1234;
    m.state_stamp_ns = 5_000_000_000;
    m.dof = 7;
    m.flags = residual_flags::VALID | residual_flags::CONTACT;
    m.isolated_joint = -1;
    m.r = front(&[0.5, -1.25, 3.5, 0.0, 0.25, -0.125, 0.0]);
    m.qd = front(&[0.01, -0.02, 0.0, 0.5, 0.0, 0.0, -1.0]);
    m.norm = f64::NAN;
    m.compute_ns = 12_345;
    m
}

fn control_status() -> ControlStatus {
    let mut m = ControlStatus::zeroed();
    m.seq = 4321;
    m.stamp_ns = 5_000_500_000;
    m.state_seq = 1234;
    m.state_stamp_ns = 5_000_000_000;
    m.mode = ControlMode::Reaction as u32;
    m.reaction = Reaction::Admittance as u32;
    m.waypoints_reached = 3;
    m.detections = 1;
    m.protective_stops = 0;
    m.resumes = 2;
    m.residual_age_ns = u64::MAX;
    m.q_ref = front(&[0.1, -0.5, 0.25, 1.5, -0.75, 0.3, f64::NAN]);
    m.ee = [0.55, -0.125, 0.75];
    m.compute_ns = 45_000;
    m.wake_latency_ns = 60_000;
    m.perception_age_ns = 33_000_000;
    m.min_distance = f64::INFINITY;
    m.risk = 0.25;
    m.task_scale = 1.0;
    m
}

fn truth() -> Truth {
    let mut m = Truth::zeroed();
    m.seq = 1234;
    m.stamp_ns = 5_000_000_000;
    m.state_seq = 1234;
    m.n_contacts = 1;
    m.dof = 7;
    m.tau_ext = front(&[0.0, 2.5, -1.0, 0.5, 0.0, 0.0, 0.0]);
    m.q = front(&[0.1, -0.5, 0.25, 1.5, -0.75, 0.3, 0.0]);
    m.qd = front(&[0.0, 0.25, 0.0, -0.5, 0.0, 0.0, 0.0]);
    m.min_distance = -0.002;
    m.contacts[0] = ContactTruth {
        robot_object: 5,
        human_part: BodyPart::Torso as i32,
        intended: 1,
        _pad: 0,
        force: [10.0, -2.5, 0.0],
        point: [0.5, 0.125, 0.75],
        depth: 0.002,
    };
    m
}

fn truth_without_human() -> Truth {
    let mut m = truth();
    m.n_contacts = 0;
    m.contacts[0] = ContactTruth::default();
    m.min_distance = f64::INFINITY;
    m
}

fn robot_stats() -> RobotStats {
    let mut m = RobotStats::zeroed();
    m.seq = 50;
    m.stamp_ns = 5_000_000_000;
    m.cycles = 10_000;
    m.missed_deadlines = 3;
    m.braked_cycles = 0;
    m.brake_events = 0;
    m.overruns = 1;
    m.latency_max_ns = 2_500_000;
    m.latency_hist[30] = 5;
    m.latency_hist[45] = 9_994;
    m.latency_hist[LATENCY_BINS - 1] = 1;
    m
}

fn service(name: &str, pid: i32, alive: u32, restarts: u32) -> ServiceHealth {
    let mut s = ServiceHealth {
        name: [0; 32],
        pid,
        alive,
        restarts,
        _pad: 0,
        started_ns: 1_000_000_000 + pid as u64,
    };
    s.name[..name.len()].copy_from_slice(name.as_bytes());
    s
}

fn health() -> Health {
    let mut m = Health::zeroed();
    m.seq = 9;
    m.stamp_ns = 5_000_000_000;
    m.count = 3;
    m.services[0] = service("sim", 4101, 1, 0);
    m.services[1] = service("dynamics", 4102, 0, 2);
    m.services[2] = service("control", 4103, 1, 1);
    m
}

fn world_state() -> WorldState {
    let mut m = WorldState::zeroed();
    m.seq = 1234;
    m.stamp_ns = 5_000_000_000;
    m.dof = 7;
    m.n_human = 2;
    m.q = front(&[0.1, -0.5, 0.25, 1.5, -0.75, 0.3, 0.0]);
    m.human[0] = WorldCapsule {
        a: [1.0, 0.0, 1.25],
        b: [1.0, 0.0, 1.75],
        radius: 0.125,
        part: BodyPart::Head as i32,
        _pad: 0,
    };
    m.human[1] = WorldCapsule {
        a: [1.0, 0.0, 0.9],
        b: [1.0, 0.0, 1.4],
        radius: 0.2,
        part: BodyPart::Torso as i32,
        _pad: 0,
    };
    m
}

fn repulsion() -> RepulsionResult {
    let mut m = RepulsionResult::zeroed();
    m.seq = 88;
    m.frame_seq = 120;
    m.capture_ns = 4_990_000_000;
    m.published_ns = 5_001_000_000;
    m.frame_capture_wall_ns = 4_990_500_000;
    m.worker = 1;
    m.workers = 2;
    m.n_points = 2;
    m.compute_ns = 800_000;
    m.points[0] = PointRepulsion {
        point: 2,
        active: 1,
        v_call: [-0.25, 0.0, 0.125],
        min_distance: 0.35,
        obstacle: [1.0, 0.0, 1.0],
        position: [0.65, 0.0, 1.0],
    };
    m.points[1] = PointRepulsion {
        point: 3,
        active: 0,
        v_call: [0.0; 3],
        min_distance: f64::INFINITY,
        obstacle: [f64::NAN; 3],
        position: [0.5, 0.25, 0.75],
    };
    m
}

fn depth_fault() -> DepthFault {
    let mut m = DepthFault::zeroed();
    m.seq = 1;
    m.stamp_ns = 5_000_000_000;
    m.kind = DepthFaultKind::Delay as u32;
    m.frames = 0;
    m.delay_ms = 100.0;
    m.duration_s = 2.5;
    m
}

fn contact_event() -> ContactEvent {
    let mut m = ContactEvent::zeroed();
    m.seq = 3;
    m.stamp_ns = 6_100_000_000;
    m.start_ns = 6_000_000_000;
    m.episode = 2;
    m.phase = ContactPhase::Update as u32;
    m.robot_object = 5;
    m.human_part = BodyPart::HandRight as i32;
    m.intended = 1;
    m.force = [10.0, -2.5, 0.0];
    m.peak_force_n = 12.5;
    m.point = [0.5, 0.0, 0.75];
    m
}

/// `m` back from its view: the same fields, bit for bit (NaN, inf and
/// u64::MAX included), and the same view again.
fn round_trip<T: Message>(m: T) {
    let v = to_json(&m);
    let back: T = from_json(&v).unwrap_or_else(|e| panic!("{e}\n{v}"));
    assert_eq!(format!("{back:?}"), format!("{m:?}"), "{v}");
    assert_eq!(to_json(&back), v);
    // as a recording stores it: text
    let text = serde_json::to_string(&v).unwrap();
    let again: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(to_json(&from_json::<T>(&again).unwrap()), v, "{text}");
}

#[test]
fn every_message_survives_its_view() {
    round_trip(joint_state());
    round_trip(torque_command());
    round_trip(residual());
    round_trip(control_status());
    round_trip(truth());
    round_trip(truth_without_human());
    round_trip(robot_stats());
    round_trip(RobotStats::zeroed());
    round_trip(health());
    round_trip(world_state());
    round_trip(repulsion());
    round_trip(depth_fault());
    for p in ContactPhase::ALL {
        let mut e = contact_event();
        e.phase = *p as u32;
        round_trip(e);
    }
    assert_eq!(to_json(&contact_event())["phase"], "update");
    assert_eq!(to_json(&contact_event())["intended"], true);
    for m in ControlMode::ALL {
        let mut s = control_status();
        s.mode = *m as u32;
        round_trip(s);
    }
    for k in DepthFaultKind::ALL {
        let mut f = depth_fault();
        f.kind = *k as u32;
        round_trip(f);
    }
    // audio: the samples as numbers, cut to their count
    let mut a = AudioChunk::zeroed();
    a.seq = 3;
    a.capture_ns = 1_000_000;
    a.rate_hz = AUDIO_RATE_HZ;
    a.samples = 5;
    a.pcm[..5].copy_from_slice(&[-32768, -1, 0, 1, 32767]);
    round_trip(a);
    assert_eq!(
        to_json(&a)["pcm"],
        serde_json::json!([-32768, -1, 0, 1, 32767])
    );
    for v in VoiceVerdict::ALL {
        for i in VoiceIntent::ALL {
            let mut u = Utterance::zeroed();
            u.seq = 2;
            u.verdict = *v as u32;
            u.intent = *i as u32;
            u.score = -1.5;
            u.text = json::to_c_str("stop");
            round_trip(u);
        }
    }
}

/// Every name a message lists in `COUNTED` is a count and arrays of its view.
fn counted_fields_are_in_the_view<T: Message>(m: T) {
    let v = to_json(&m);
    for (count, arrays) in T::COUNTED {
        assert!(v[*count].is_u64(), "{count} in {v}");
        for a in *arrays {
            let n = v[*a]
                .as_array()
                .unwrap_or_else(|| panic!("{a} in {v}"))
                .len();
            assert_eq!(n as u64, v[*count].as_u64().unwrap(), "{a} in {v}");
        }
    }
}

#[test]
fn counted_arrays_are_cut_to_their_count() {
    counted_fields_are_in_the_view(joint_state());
    counted_fields_are_in_the_view(torque_command());
    counted_fields_are_in_the_view(residual());
    counted_fields_are_in_the_view(truth());
    counted_fields_are_in_the_view(health());
    counted_fields_are_in_the_view(world_state());
    counted_fields_are_in_the_view(repulsion());
    assert_eq!(Truth::COUNTED.len(), 2);
    assert!(ControlStatus::COUNTED.is_empty());
}

// The shapes below are what the hand-written views printed before the views
// came from serde (users' scripts parse them); only `latency_hist.bins` is new.

#[test]
fn joint_state_view_is_pinned() {
    assert_eq!(
        to_json(&joint_state()),
        json!({
            "seq": 1234, "stamp_ns": 5_000_000_000u64, "published_ns": 5_000_021_500u64,
            "dof": 7, "status": 6,
            "q": [0.1, -0.5, 0.25, 1.5, -0.75, 0.3, 0.0],
            "tau": [1.5, -20.25, 3.0, 10.0, -0.5, 0.125, 0.0625],
            "wrench": [1.0, 2.0, -3.5, 0.1, 0.2, null],
            "command_seq": 1233, "missed_commands": 2,
        })
    );
}

#[test]
fn control_status_view_is_pinned() {
    assert_eq!(
        to_json(&control_status()),
        json!({
            "seq": 4321, "stamp_ns": 5_000_500_000u64, "state_seq": 1234,
            "state_stamp_ns": 5_000_000_000u64, "mode": "reaction", "reaction": 1,
            "waypoints_reached": 3, "detections": 1, "protective_stops": 0, "resumes": 2,
            "residual_age_ns": null,
            "q_ref": [0.1, -0.5, 0.25, 1.5, -0.75, 0.3, null, 0.0, 0.0, 0.0, 0.0, 0.0],
            "ee": [0.55, -0.125, 0.75], "compute_ns": 45_000, "wake_latency_ns": 60_000,
            "perception_age_ns": 33_000_000, "min_distance": null, "risk": 0.25,
            "task_scale": 1.0,
            "model_errors": 0,
        })
    );
}

#[test]
fn truth_view_is_pinned() {
    assert_eq!(
        to_json(&truth()),
        json!({
            "seq": 1234, "stamp_ns": 5_000_000_000u64, "state_seq": 1234,
            "n_contacts": 1, "dof": 7,
            "tau_ext": [0.0, 2.5, -1.0, 0.5, 0.0, 0.0, 0.0],
            "q": [0.1, -0.5, 0.25, 1.5, -0.75, 0.3, 0.0],
            "qd": [0.0, 0.25, 0.0, -0.5, 0.0, 0.0, 0.0],
            "min_distance": -0.002,
            "contacts": [{"robot_object": 5, "human_part": 1, "intended": true,
                          "force": [10.0, -2.5, 0.0], "point": [0.5, 0.125, 0.75],
                          "depth": 0.002}],
        })
    );
    let none = to_json(&truth_without_human());
    assert_eq!(none["contacts"], json!([]));
    assert_eq!(none["min_distance"], Value::Null);
}

#[test]
fn repulsion_view_is_pinned() {
    assert_eq!(
        to_json(&repulsion()),
        json!({
            "seq": 88, "frame_seq": 120, "capture_ns": 4_990_000_000u64,
            "published_ns": 5_001_000_000u64, "frame_capture_wall_ns": 4_990_500_000u64,
            "worker": 1, "workers": 2, "n_points": 2, "compute_ns": 800_000,
            "since_arrival_ns": 0,
            "points": [
                {"point": 2, "active": true, "v_call": [-0.25, 0.0, 0.125],
                 "min_distance": 0.35, "obstacle": [1.0, 0.0, 1.0], "position": [0.65, 0.0, 1.0]},
                {"point": 3, "active": false, "v_call": [0.0, 0.0, 0.0],
                 "min_distance": null, "obstacle": [null, null, null], "position": [0.5, 0.25, 0.75]},
            ],
        })
    );
}

#[test]
fn the_other_views_are_pinned() {
    assert_eq!(
        to_json(&torque_command()),
        json!({
            "seq": 1233, "stamp_ns": 5_000_400_000u64, "state_seq": 1233,
            "state_stamp_ns": 4_999_000_000u64, "dof": 7, "mode": "task",
            "tau": [1.5, -20.25, 3.0, 10.0, -0.5, 0.125, 0.0625],
        })
    );
    assert_eq!(
        to_json(&residual()),
        json!({
            "seq": 77, "stamp_ns": 5_000_100_000u64, "state_seq": 1234,
            "state_stamp_ns": 5_000_000_000u64, "dof": 7, "flags": 9, "isolated_joint": -1,
            "r": [0.5, -1.25, 3.5, 0.0, 0.25, -0.125, 0.0],
            "qd": [0.01, -0.02, 0.0, 0.5, 0.0, 0.0, -1.0],
            "norm": null, "compute_ns": 12_345,
        })
    );
    assert_eq!(
        to_json(&robot_stats()),
        json!({
            "seq": 50, "stamp_ns": 5_000_000_000u64, "cycles": 10_000,
            "missed_deadlines": 3, "braked_cycles": 0, "brake_events": 0, "overruns": 1,
            "latency_max_ns": 2_500_000,
            "latency_hist": {"bin_us": 1, "count": 10_000, "first_bin": 30, "last_bin": 1999,
                             "bins": [[30, 5], [45, 9994], [1999, 1]]},
        })
    );
    assert_eq!(
        to_json(&RobotStats::zeroed())["latency_hist"],
        json!({"bin_us": 1, "count": 0, "first_bin": null, "last_bin": null, "bins": []})
    );
    assert_eq!(
        to_json(&health()),
        json!({
            "seq": 9, "stamp_ns": 5_000_000_000u64, "count": 3,
            "services": [
                {"name": "sim", "pid": 4101, "alive": true, "restarts": 0, "started_ns": 1_000_004_101},
                {"name": "dynamics", "pid": 4102, "alive": false, "restarts": 2, "started_ns": 1_000_004_102},
                {"name": "control", "pid": 4103, "alive": true, "restarts": 1, "started_ns": 1_000_004_103},
            ],
        })
    );
    assert_eq!(
        to_json(&world_state()),
        json!({
            "seq": 1234, "stamp_ns": 5_000_000_000u64, "dof": 7, "n_human": 2,
            "q": [0.1, -0.5, 0.25, 1.5, -0.75, 0.3, 0.0],
            "human": [
                {"a": [1.0, 0.0, 1.25], "b": [1.0, 0.0, 1.75], "radius": 0.125, "part": 0},
                {"a": [1.0, 0.0, 0.9], "b": [1.0, 0.0, 1.4], "radius": 0.2, "part": 1},
            ],
        })
    );
    assert_eq!(
        to_json(&depth_fault()),
        json!({"seq": 1, "stamp_ns": 5_000_000_000u64, "kind": "delay", "frames": 0,
               "delay_ms": 100.0, "duration_s": 2.5})
    );
}

fn field_at_fault<T: Message + std::fmt::Debug>(v: Value) -> String {
    match from_json::<T>(&v) {
        Err(JsonError::Field { field, .. }) => field,
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_views_name_the_field_at_fault() {
    let mut v = to_json(&joint_state());
    v["q"] = json!("not joints");
    assert_eq!(field_at_fault::<JointState>(v), "q");
    let mut v = to_json(&joint_state());
    v["wrench"] = json!(vec![0.0; 7]);
    assert_eq!(field_at_fault::<JointState>(v), "wrench");
    let mut v = to_json(&joint_state());
    v["q"] = json!(vec![0.0; 13]);
    assert_eq!(field_at_fault::<JointState>(v), "q");
    let mut v = to_json(&control_status());
    v["mode"] = json!("dance");
    let e = from_json::<ControlStatus>(&v).unwrap_err().to_string();
    assert!(e.contains("'mode'") && e.contains("dance"), "{e}");
    let mut v = to_json(&repulsion());
    v["points"][1]["active"] = json!(3);
    assert_eq!(field_at_fault::<RepulsionResult>(v), "points");
    let mut v = to_json(&health());
    v["services"][0]["name"] = json!("a name much longer than thirty-two bytes");
    assert_eq!(field_at_fault::<Health>(v), "services");
    let mut v = to_json(&robot_stats());
    v["latency_hist"]["count"] = json!(3);
    assert_eq!(field_at_fault::<RobotStats>(v), "latency_hist");
    let mut v = to_json(&joint_state());
    v.as_object_mut().unwrap().remove("seq");
    let e = from_json::<JointState>(&v).unwrap_err().to_string();
    assert!(e.starts_with("JointState:") && e.contains("seq"), "{e}");
    let e = from_json::<JointState>(&json!([1, 2]))
        .unwrap_err()
        .to_string();
    assert_eq!(e, "JointState: not a JSON object");
}

#[test]
fn reading_pads_arrays_and_trusts_only_the_entries_given() {
    // fewer contacts than n_contacts says: the count follows the entries
    let mut v = to_json(&truth());
    v["n_contacts"] = json!(3);
    let t: Truth = from_json(&v).unwrap();
    assert_eq!(t.n_contacts, 1);
    assert_eq!(t.contacts[0].robot_object, 5);
    assert_eq!(t.contacts[1].robot_object, 0);
    // joint arrays shorter than dof are zero-filled, the count kept to them
    let mut v = to_json(&joint_state());
    v["q"] = json!([1.0, 2.0]);
    let s: JointState = from_json(&v).unwrap();
    assert_eq!((s.dof, s.q[1], s.q[2]), (2, 2.0, 0.0));
    // a fixed array shorter than its size: the rest is 0
    let mut v = to_json(&control_status());
    v["ee"] = json!([0.5]);
    let c: ControlStatus = from_json(&v).unwrap();
    assert_eq!(c.ee, [0.5, 0.0, 0.0]);
}
