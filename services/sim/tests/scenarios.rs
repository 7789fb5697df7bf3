//! Scenario files: parsing, errors, and the collision scenario's geometry.

mod common;

use phri_model::{gravity, Data};
use phri_sim::{BodyPart, Scenario, ScenarioError, SimConfig, Simulator};

/// Hold the robot at `q` (reset before every step, gravity compensated) until
/// time `t_end`; returns the largest total contact force [N] and penetration
/// [m] seen at or after `t_from`, with the links touched.
fn held_contacts(
    sim: &mut Simulator,
    q: &[f64],
    t_from: f64,
    t_end: f64,
) -> (f64, f64, Vec<String>) {
    let model = sim.model().clone();
    let mut data = Data::new(&model);
    let g = gravity(&model, &mut data, q)
        .expect("g")
        .as_slice()
        .to_vec();
    let mut worst: f64 = 0.0;
    let mut deepest: f64 = 0.0;
    let mut links = Vec::new();
    while sim.time_s() < t_end - 1e-9 {
        sim.reset_state(q).expect("pose within limits");
        sim.step(&g, false);
        let truth = sim.truth();
        if truth.t_s >= t_from {
            let total = truth
                .contacts
                .iter()
                .map(|c| c.force)
                .sum::<nalgebra::Vector3<f64>>()
                .norm();
            worst = worst.max(total);
            for c in &truth.contacts {
                deepest = deepest.max(c.depth);
                let l = sim.collision_link(c.collision).unwrap_or("?").to_string();
                if !links.contains(&l) {
                    links.push(l);
                }
            }
        }
    }
    (worst, deepest, links)
}

#[test]
fn collision_scenario_hits_a_robot_held_on_the_path_in_both_phases() {
    let model = common::model();
    let sc =
        Scenario::from_file(common::scenario_path("collision.toml")).expect("collision.toml loads");
    assert!(sc.collaborative_parts.is_empty());
    let poses = [
        ("P2", common::ik(&model, common::P2)),
        ("P1-P2", common::ik(&model, mid(common::P1, common::P2))),
        ("P2-P3", common::ik(&model, mid(common::P2, common::P3))),
        ("q0 of deploy/phri.toml", common::FRONT.to_vec()),
    ];
    for (name, q) in poses {
        let mut sim =
            Simulator::from_scenario(model.clone(), SimConfig::ideal(), &sc, None).expect("sim");
        let (before, _, _) = held_contacts(&mut sim, &q, 0.0, 3.0);
        let (phase1, depth1, links1) = held_contacts(&mut sim, &q, 4.3, 5.5);
        let (between, _, _) = held_contacts(&mut sim, &q, 6.8, 8.2);
        let (phase2, depth2, links2) = held_contacts(&mut sim, &q, 9.4, 10.6);
        let (after, _, _) = held_contacts(&mut sim, &q, 13.0, 16.0);
        println!(
            "{name}: before {before:.0} N, phase 1 {phase1:.0} N ({:.1} cm deep) on {links1:?}, between {between:.0} N, phase 2 {phase2:.0} N ({:.1} cm deep) on {links2:?}, after {after:.0} N",
            depth1 * 100.0,
            depth2 * 100.0
        );
        assert_eq!(before, 0.0);
        assert_eq!(between, 0.0);
        assert_eq!(after, 0.0);
        if name == "P2" {
            assert!(
                phase1 > 20.0 && phase2 > 20.0,
                "{name}: phase 1 {phase1} N, phase 2 {phase2} N"
            );
            assert!(
                depth1 < 0.06 && depth2 < 0.06,
                "a few centimetres: {depth1} m, {depth2} m"
            );
            assert!(
                links1
                    .iter()
                    .any(|l| l == "lwr_link_4" || l == "lwr_link_5"),
                "phase 1 touches the forearm: {links1:?}"
            );
            assert!(
                links2
                    .iter()
                    .any(|l| l == "lwr_link_6" || l == "lwr_link_7"),
                "phase 2 touches the end effector: {links2:?}"
            );
        }
    }
}

fn mid(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        (a[0] + b[0]) / 2.0,
        (a[1] + b[1]) / 2.0,
        (a[2] + b[2]) / 2.0,
    ]
}

/// Joint positions along one unperturbed task cycle P1 → P2 → P3 → P1,
/// `per_segment` samples per segment, uniform in time along minimum-jerk
/// segments (4 s per cycle).
fn cycle_poses(model: &phri_model::Model, per_segment: usize) -> Vec<Vec<f64>> {
    let wps = [common::P1, common::P2, common::P3];
    let mut poses = Vec::with_capacity(3 * per_segment);
    for seg in 0..3 {
        let (a, b) = (wps[seg], wps[(seg + 1) % 3]);
        for k in 0..per_segment {
            let u = k as f64 / per_segment as f64;
            let s = 10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5);
            poses.push(common::ik(
                model,
                [
                    a[0] + (b[0] - a[0]) * s,
                    a[1] + (b[1] - a[1]) * s,
                    a[2] + (b[2] - a[2]) * s,
                ],
            ));
        }
    }
    poses
}

/// While the person holds still in each phase, the robot running its cycle
/// touches them (more than 5 mm deep) at most 1.3 s apart, so the 1.5 s stay is
/// hit whatever the phase of the cycle; never deeper than about 5 cm.
#[test]
fn collision_scenario_is_hit_whatever_the_cycle_phase() {
    let model = common::model();
    let sc =
        Scenario::from_file(common::scenario_path("collision.toml")).expect("collision.toml loads");
    let poses = cycle_poses(&model, 40);
    let n = poses.len();
    let mut sim =
        Simulator::from_scenario(model.clone(), SimConfig::ideal(), &sc, None).expect("sim");
    let mut data = Data::new(&model);
    let tau = gravity(&model, &mut data, &poses[0])
        .expect("g")
        .as_slice()
        .to_vec();
    for t_phase in [5.0, 10.0] {
        while sim.time_s() < t_phase - 1e-9 {
            sim.reset_state(&poses[0]).expect("pose");
            sim.step(&tau, false);
        }
        let hit: Vec<bool> = poses
            .iter()
            .map(|q| {
                sim.reset_state(q).expect("pose");
                sim.truth().min_distance < -0.005
            })
            .collect();
        let deepest = poses
            .iter()
            .map(|q| {
                sim.reset_state(q).expect("pose");
                -sim.truth().min_distance
            })
            .fold(f64::NEG_INFINITY, f64::max);
        let (mut gap, mut longest) = (0usize, 0usize);
        for i in 0..2 * n {
            gap = if hit[i % n] { 0 } else { gap + 1 };
            longest = longest.max(gap.min(n));
        }
        let share = hit.iter().filter(|h| **h).count() as f64 / n as f64;
        let longest_s = longest as f64 / n as f64 * 4.0;
        println!("t = {t_phase} s: contact during {:.0} % of the cycle, longest gap {longest_s:.2} s, deepest {:.1} cm", share * 100.0, deepest * 100.0);
        assert!(
            longest_s < 1.4,
            "a gap of {longest_s} s could miss the 1.5 s stay"
        );
        assert!(deepest < 0.055, "a few centimetres, not {deepest} m");
    }
}

#[test]
fn shipped_scenarios_load() {
    let free = Scenario::from_file(common::scenario_path("free-motion.toml"))
        .expect("free-motion.toml loads");
    assert_eq!(free.name, "free-motion");
    assert_eq!(free.duration_s, 60.0);
    assert!(free.human.is_none() && free.collaborative_parts.is_empty() && free.config.is_empty());
    let col =
        Scenario::from_file(common::scenario_path("collision.toml")).expect("collision.toml loads");
    assert_eq!(col.duration_s, 16.0);
    let human = col.human.expect("collision has a human");
    assert_eq!(human.floor_z(), -0.8);
    assert!(human.end_time() <= 13.0);
}

#[test]
fn optional_fields_and_config_table() {
    let sc = Scenario::from_str(&format!(
        "{HEAD}collaborative_parts = [\"hand_right\", \"forearm_right\"]\n[[human.keyframe]]\nt = 0\nbase = [1, 0, 3]\nleft_hand = [0.5, 0.1, 0.4]\n[config.sim]\nsubsteps = 8\n[config.control]\nreaction = \"stop\"\n"
    ))
    .expect("valid");
    assert_eq!(
        sc.collaborative_parts,
        vec![BodyPart::HandRight, BodyPart::ForearmRight]
    );
    let human = sc.human.expect("human");
    assert_eq!(human.floor_z(), -0.8, "default floor");
    assert_eq!(human.keyframes()[0].left_hand, Some([0.5, 0.1, 0.4]));
    assert_eq!(human.keyframes()[0].right_hand, None);
    let sim = sc
        .config
        .get("sim")
        .and_then(|v| v.as_table())
        .expect("config.sim kept");
    assert_eq!(sim.get("substeps").and_then(|v| v.as_integer()), Some(8));
    assert!(sc.config.contains_key("control"));
}

/// Only `name` is required: no human, the default run length, no overrides.
#[test]
fn minimal_scenario() {
    let sc = Scenario::from_str("name = \"free-motion\"").expect("a name is enough");
    assert_eq!(sc.duration_s, Scenario::DEFAULT_DURATION_S);
    assert!(sc.human.is_none() && sc.description.is_empty() && sc.config.is_empty());
}

fn parse_err(text: &str) -> ScenarioError {
    match Scenario::from_str(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

const HEAD: &str = "name = \"x\"\nduration_s = 5.0\n[human]\n";
const K0: &str = "[[human.keyframe]]\nt = 0.0\nbase = [1.0, 0.0, 0.0]\n";

/// Every malformed input is refused with an error naming the field.
#[test]
fn parse_errors_name_the_field() {
    let cases: Vec<(String, &str)> = vec![
        (format!("{HEAD}[[human.keyframe]]\nt = \"soon\"\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[0].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0]\n"), "human.keyframe[1].base"),
        (format!("{HEAD}{K0}righthand = [1.0, 0.0, 0.0]\n"), "righthand"),
        (format!("{HEAD}[[human.keyframe]]\nt = 0.0\n"), "missing field `base`"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 2.0\nbase = [1.0, 0.0, 0.0]\n[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[2].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 0.0\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[1].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = nan\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[1].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, inf, 0.0]\n"), "human.keyframe[1].base"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\nright_hand = [0.5, nan, 0.3]\n"), "human.keyframe[1].right_hand"),
        (format!("{HEAD}collaborative_parts = [\"tail\"]\n{K0}"), "human.collaborative_parts[0]"),
        (format!("{HEAD}floor_z = inf\n{K0}"), "human.floor_z"),
        (HEAD.to_string(), "human.keyframe"),
        ("name = \"x\"\nduration_s = -1.0\n".to_string(), "duration_s"),
        ("name = \"x\"\nduration_s = 1.0\nspeed = 2\n".to_string(), "speed"),
        ("duration_s = 1.0\n".to_string(), "missing field `name`"),
        ("name = 3\nduration_s = 1.0\n".to_string(), "name"),
        ("name = \"x\"\nduration_s = 1.0\nconfig = 3\n".to_string(), "config"),
        ("name = \"x\"\nduration_s = [1.0\n".to_string(), "<scenario>:"),
    ];
    for (text, field) in cases {
        let e = parse_err(&text).to_string();
        assert!(
            e.contains(field),
            "error for\n{text}\ndoes not name {field}: {e}"
        );
        assert!(e.starts_with("<scenario>:"), "error names the origin: {e}");
    }
    // a structured error carries the line and the field
    match parse_err(&format!(
        "{HEAD}{K0}[[human.keyframe]]\nt = \"x\"\nbase = [1.0, 0.0, 0.0]\n"
    )) {
        ScenarioError::Parse { line, field, .. } => {
            assert_eq!((line, field.as_str()), (8, "human.keyframe[1].t"))
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn file_errors_name_the_file() {
    let e = Scenario::from_file("/nonexistent/phri/scenario.toml").expect_err("missing file");
    assert!(matches!(e, ScenarioError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/phri/scenario.toml"));
    let dir = std::env::temp_dir().join(format!("phri-sim-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        format!("{HEAD}{K0}[[human.keyframe]]\nt = -1.0\nbase = [1.0, 0.0, 0.0]\n"),
    )
    .expect("write");
    let e = Scenario::from_file(&path)
        .expect_err("unsorted")
        .to_string();
    assert!(
        e.contains("bad.toml") && e.contains("human.keyframe[1].t"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Garbage never panics: truncations and byte flips of a valid file.
#[test]
fn malformed_input_never_panics() {
    let text = std::fs::read_to_string(common::scenario_path("collision.toml")).expect("read");
    let bytes = text.as_bytes();
    let mut state = 12345u64;
    for i in 0..3000 {
        let mut b = bytes[..(i * 7919) % bytes.len()].to_vec();
        for _ in 0..(i % 4) {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            if !b.is_empty() {
                let k = (state >> 33) as usize % b.len();
                b[k] = b"=[]\"#.,0x\n-e"[(state >> 20) as usize % 12];
            }
        }
        let _ = Scenario::from_str(&String::from_utf8_lossy(&b));
    }
}

/// The body moves continuously through keyframes, including where a hand
/// target appears or disappears, and never faster than a plausible limb.
#[test]
fn keyframe_interpolation_is_continuous() {
    let sc = Scenario::from_file(common::scenario_path("collision.toml")).expect("loads");
    let mut human = phri_sim::Human::new(sc.human.expect("human"));
    let dt = 1e-3;
    let mut prev = human.pose_at(-1.0).to_vec();
    let mut t = -1.0;
    let mut fastest: f64 = 0.0;
    while t < 17.0 {
        t += dt;
        let now = human.pose_at(t);
        for (a, b) in prev.iter().zip(now) {
            let step = (a.a - b.a).norm().max((a.b - b.b).norm());
            fastest = fastest.max(step / dt);
        }
        prev = now.to_vec();
    }
    // walking at 0.5 m/s, hands raised within 0.4 s: capsule ends stay below 3 m/s
    assert!(fastest < 3.0, "a capsule end moved at {fastest} m/s");
    // just before and at a keyframe where the hand target appears
    let before = human.pose_at(3.7 - 1e-9).to_vec();
    let at = human.pose_at(3.7).to_vec();
    for (a, b) in before.iter().zip(&at) {
        assert!((a.a - b.a).norm() < 1e-6 && (a.b - b.b).norm() < 1e-6);
    }
    // clamped outside the script
    assert_eq!(human.pose_at(-5.0).to_vec(), human.pose_at(0.0).to_vec());
    assert_eq!(human.pose_at(100.0).to_vec(), human.pose_at(13.0).to_vec());
    // the hand centre reaches its target while held
    let hand = human.pose_at(5.0)[BodyPart::HandRight as usize];
    let forearm = human.pose_at(5.0)[BodyPart::ForearmRight as usize];
    let centre = hand.b - (forearm.b - forearm.a).normalize() * 0.02;
    assert!((centre - nalgebra::Vector3::new(0.38, 0.02, 0.62)).norm() < 1e-9);
}
