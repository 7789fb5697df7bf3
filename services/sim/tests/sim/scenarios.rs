//! The shipped scenarios in the simulator: the collision scenario's geometry
//! and the person's motion. (Parsing and its errors are tested with the
//! parser, in `crates/config/tests/scenario.rs`.)

use crate::common;

use phri_config::Scenario;
use phri_ipc::BodyPart;
use phri_model::{gravity, Data};
use phri_sim::Simulator;

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
            Simulator::from_scenario(model.clone(), common::ideal(), &sc, None).expect("sim");
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
    let mut sim = Simulator::from_scenario(model.clone(), common::ideal(), &sc, None).expect("sim");
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
