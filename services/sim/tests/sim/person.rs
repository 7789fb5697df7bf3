//! What the scripted person can do for the collaboration experiments:
//! wave a hand, raise a foot, push a robot link with a given force (a
//! ground-truth contact whose joint torque is `Jᵀ F`). Geometry and physics,
//! measured on the capsules and the simulator's truth.

use crate::common;

use nalgebra::{DMatrix, DVector, Vector3};
use phri_config::{Scenario, SimConfig};
use phri_ipc::BodyPart;
use phri_model::{crba, forward_kinematics, frame_placement, gravity, point_jacobian, Data};
use phri_sim::{Human, HumanCapsule, Simulator};

fn human(toml: &str) -> Human {
    let sc = Scenario::from_str(toml).expect("scenario");
    Human::new(sc.human.expect("a human"))
}

fn part(capsules: &[HumanCapsule], p: BodyPart) -> HumanCapsule {
    capsules[p as usize]
}

/// Elbow and hand centre of one arm.
fn elbow_and_hand(capsules: &[HumanCapsule], right: bool) -> (Vector3<f64>, Vector3<f64>) {
    let (fore, hand) = if right {
        (BodyPart::ForearmRight, BodyPart::HandRight)
    } else {
        (BodyPart::ForearmLeft, BodyPart::HandLeft)
    };
    let fore = part(capsules, fore);
    let hand = part(capsules, hand);
    let dir = (fore.b - fore.a).normalize();
    (fore.a, hand.b - dir * 0.02)
}

/// A waving hand stays above its elbow, the elbow still, and swings along the
/// person's left–right axis at the scripted frequency (zero crossings over
/// 2 s) and amplitude (±20 %); no capsule jumps when the wave blends in or out.
#[test]
fn a_waving_hand_swings_sideways_above_its_elbow() {
    for (hand, right, f_hz, amp) in [("right", true, 1.5, 0.12), ("left", false, 2.0, 0.08)] {
        let yaw = 2.5;
        let mut h = human(&format!(
            "name = \"w\"\n[human]\n\
             [[human.keyframe]]\nt = 0.0\nbase = [1.2, 0.3, {yaw}]\n\
             [[human.keyframe]]\nt = 1.0\nbase = [1.2, 0.3, {yaw}]\nwave = {{ hand = \"{hand}\", frequency_hz = {f_hz}, amplitude_m = {amp} }}\n\
             [[human.keyframe]]\nt = 4.0\nbase = [1.2, 0.3, {yaw}]\n"
        ));
        let left_axis = Vector3::new(-f64::sin(yaw), f64::cos(yaw), 0.0);
        let fwd_axis = Vector3::new(f64::cos(yaw), f64::sin(yaw), 0.0);
        let shoulder_z = -0.8 + 1.45;
        let dt = 1e-3;
        let (elbow0, _) = elbow_and_hand(h.pose_at(1.5), right);
        let (mut lateral, mut forward) = (Vec::new(), Vec::new());
        let mut elbow_moved: f64 = 0.0;
        let mut lowest_above_elbow = f64::INFINITY;
        let mut t = 1.5;
        while t <= 3.5 + 1e-9 {
            let (elbow, centre) = elbow_and_hand(h.pose_at(t), right);
            elbow_moved = elbow_moved.max((elbow - elbow0).norm());
            lowest_above_elbow = lowest_above_elbow.min(centre.z - elbow.z);
            assert!(
                centre.z > shoulder_z,
                "{hand}: the waving hand is raised above the shoulder at t = {t}"
            );
            lateral.push((centre - elbow).dot(&left_axis));
            forward.push((centre - elbow).dot(&fwd_axis));
            t += dt;
        }
        let mean = lateral.iter().sum::<f64>() / lateral.len() as f64;
        let crossings = lateral
            .windows(2)
            .filter(|w| (w[0] - mean).signum() != (w[1] - mean).signum())
            .count();
        let (lo, hi) = lateral
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(*x), hi.max(*x))
            });
        let measured_amp = (hi - lo) / 2.0;
        let fwd_span = forward.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - forward.iter().cloned().fold(f64::INFINITY, f64::min);
        println!(
            "{hand}: {crossings} zero crossings in 2 s, amplitude {measured_amp:.3} m, hand ≥ {lowest_above_elbow:.3} m above the elbow, elbow moved {elbow_moved:.1e} m, forward span {fwd_span:.3} m"
        );
        // 2 crossings per period
        let expected = (2.0 * f_hz * 2.0) as usize;
        assert!(
            crossings.abs_diff(expected) <= 1,
            "{hand}: {crossings} crossings, expected {expected}"
        );
        assert!(
            (measured_amp - amp).abs() <= 0.2 * amp,
            "{hand}: amplitude {measured_amp} m, scripted {amp} m"
        );
        assert!(lowest_above_elbow > 0.2, "{hand}: hand above the elbow");
        assert!(elbow_moved < 1e-3, "{hand}: the elbow stays put");
        // sideways, not to and fro: the forward offset varies far less
        assert!(fwd_span < 0.1 * amp, "{hand}: forward span {fwd_span} m");

        // continuous through the blend in (t = 1) and out (t = 4), and back down after
        let mut prev = h.pose_at(0.0).to_vec();
        let mut fastest: f64 = 0.0;
        let mut t = 0.0;
        while t < 5.0 {
            t += dt;
            let now = h.pose_at(t);
            for (a, b) in prev.iter().zip(now) {
                fastest = fastest.max((a.a - b.a).norm().max((a.b - b.b).norm()) / dt);
            }
            prev = now.to_vec();
        }
        println!("{hand}: fastest capsule end {fastest:.2} m/s");
        assert!(
            fastest < 3.0,
            "{hand}: a capsule end moved at {fastest} m/s"
        );
        let (elbow, centre) = elbow_and_hand(h.pose_at(4.5), right);
        assert!(
            centre.z < elbow.z,
            "{hand}: the hand hangs again after the wave"
        );
    }
}

/// A foot target moves the ankle (the shin capsule's lower end) there, with
/// the segment lengths kept and the knee bent forwards; the other leg stands.
#[test]
fn a_foot_target_raises_the_leg() {
    let target = Vector3::new(0.9, 0.1, -0.5);
    let mut h = human(
        "name = \"step\"\n[human]\n\
         [[human.keyframe]]\nt = 0.0\nbase = [1.2, 0.0, 3.141592653589793]\n\
         [[human.keyframe]]\nt = 1.0\nbase = [1.2, 0.0, 3.141592653589793]\nright_foot = [0.9, 0.1, -0.5]\n\
         [[human.keyframe]]\nt = 2.0\nbase = [1.2, 0.0, 3.141592653589793]\nright_foot = [0.9, 0.1, -0.5]\n",
    );
    let standing = h.pose_at(0.0).to_vec();
    for t in [1.0, 1.5, 2.0, 5.0] {
        let c = h.pose_at(t).to_vec();
        let thigh = part(&c, BodyPart::ThighRight);
        let shin = part(&c, BodyPart::ShinRight);
        assert!(
            (shin.b - target).norm() < 0.02,
            "t = {t}: ankle at {:?}",
            shin.b
        );
        assert!(((thigh.b - thigh.a).norm() - 0.38).abs() < 1e-9);
        assert!(((shin.b - shin.a).norm() - 0.40).abs() < 1e-9);
        assert!((thigh.b - shin.a).norm() < 1e-12, "knee shared");
        // facing −x: the knee is in front (smaller x) of the hip–ankle line
        let mid = (thigh.a + shin.b) * 0.5;
        assert!(thigh.b.x < mid.x - 0.05, "knee forwards: {:?}", thigh.b);
        // hip unchanged, other leg untouched
        assert!((thigh.a - part(&standing, BodyPart::ThighRight).a).norm() < 1e-12);
        for p in [BodyPart::ThighLeft, BodyPart::ShinLeft] {
            assert_eq!(part(&c, p), part(&standing, p));
        }
    }
    // halfway there at t = 0.5
    let ankle0 = part(&standing, BodyPart::ShinRight).b;
    let half = part(h.pose_at(0.5), BodyPart::ShinRight).b;
    assert!((half - (ankle0 + target) * 0.5).norm() < 0.02, "{half:?}");
    // a left foot too, and out of reach: the leg stretches towards it
    let mut h = human(
        "name = \"reach\"\n[human]\n\
         [[human.keyframe]]\nt = 0.0\nbase = [1.2, 0.0, 3.141592653589793]\nleft_foot = [0.2, -0.1, 0.5]\n",
    );
    let c = h.pose_at(0.0).to_vec();
    let (thigh, shin) = (part(&c, BodyPart::ThighLeft), part(&c, BodyPart::ShinLeft));
    assert!(((shin.b - thigh.a).norm() - 0.78).abs() < 1e-5, "stretched");
    assert!(((shin.b - shin.a).norm() - 0.40).abs() < 1e-9);
}

/// The person 0.95 m in front of the robot pushes link 7 from t = 0.5 s to 1.5 s.
fn push_scenario(force_n: f64, intended: &str) -> Scenario {
    Scenario::from_str(&format!(
        "name = \"push\"\nduration_s = 3.0\n[human]\n\
         [[human.keyframe]]\nt = 0.0\nbase = [0.95, 0.0, 3.141592653589793]\n\
         [[human.keyframe]]\nt = 0.5\nbase = [0.95, 0.0, 3.141592653589793]\n\
         push = {{ link = \"lwr_link_7\", point = [0.0, 0.0, 0.04], force_n = {force_n}, part = \"right_hand\"{intended} }}\n\
         [[human.keyframe]]\nt = 1.5\nbase = [0.95, 0.0, 3.141592653589793]\n"
    ))
    .expect("push scenario")
}

/// A push keyframe is a ground-truth contact of the hand on the link with
/// the scripted force (after the 0.2 s ramp), intended as scripted, and its
/// external joint torque is `Jᵀ F` at the point; the hand is on the link.
#[test]
fn a_push_is_a_ground_truth_contact_with_the_scripted_force() {
    let model = common::model();
    let q = common::ik(&model, common::P2);
    let link7 = model.frame_id("lwr_link_7").expect("link 7");
    let mut data = Data::new(&model);
    let g = gravity(&model, &mut data, &q)
        .expect("g")
        .as_slice()
        .to_vec();
    let mut jac = Data::jacobian_buffer(&model);
    for (intended_key, intended) in [
        (", intended = true", true),
        (", intended = false", false),
        ("", false),
    ] {
        let sc = push_scenario(30.0, intended_key);
        let cfg = SimConfig {
            q0: q.clone(),
            ..common::ideal()
        };
        let mut sim = Simulator::from_scenario(model.clone(), cfg, &sc, None).expect("sim");
        let (mut full, mut ramping, mut outside) = (0usize, 0usize, 0usize);
        while sim.time_s() < 2.0 - 1e-9 {
            sim.reset_state(&q).expect("pose");
            sim.step(&g, false);
            let truth = sim.truth();
            let t = truth.t_s;
            if !(0.5 - 1e-9..=1.5 + 1e-9).contains(&t) {
                assert!(truth.contacts.is_empty(), "no push at t = {t}");
                outside += 1;
                continue;
            }
            if truth.contacts.is_empty() {
                // the ramp's two ends
                assert!((t - 0.5).abs() < 2e-3 || (t - 1.5).abs() < 2e-3, "t = {t}");
                continue;
            }
            assert_eq!(truth.contacts.len(), 1, "t = {t}: only the push");
            let c = truth.contacts[0];
            assert_eq!(c.part, BodyPart::HandRight);
            assert_eq!(c.link(sim.model()), "lwr_link_7");
            assert_eq!(c.intended, intended);
            assert!(c.depth > 0.0);
            // horizontal, from the person (x = 0.95) towards the robot
            assert!(c.force.z.abs() < 1e-12 && c.force.x < 0.0);
            // at the scripted point, link frame (the arm moved during the step)
            let q = &truth.q;
            forward_kinematics(&model, &mut data, q).expect("fk");
            let point = frame_placement(&model, &data, link7).apply(&Vector3::new(0.0, 0.0, 0.04));
            assert!((c.point - point).norm() < 1e-9);
            // tau_ext = Jᵀ F
            point_jacobian(
                &model,
                &data,
                link7,
                &Vector3::new(0.0, 0.0, 0.04),
                &mut jac,
            )
            .expect("J");
            let jt_f = jac.fixed_rows::<3>(0).transpose() * c.force;
            for i in 0..7 {
                assert!(
                    (truth.tau_ext[i] - jt_f[i]).abs() < 1e-9 * (1.0 + jt_f[i].abs()),
                    "t = {t}: tau_ext[{i}] {} vs Jᵀ F {}",
                    truth.tau_ext[i],
                    jt_f[i]
                );
            }
            let f = c.force.norm();
            if (0.7..=1.3).contains(&t) {
                assert!(jt_f.norm() > 1.0, "the push loads the joints: {jt_f:?}");
                assert!((f - 30.0).abs() <= 0.05 * 30.0, "t = {t}: {f} N");
                full += 1;
                // the pushing hand is on the link: its surface on the capsule's
                let hand = sim.human_capsules()[BodyPart::HandRight as usize];
                let fore = sim.human_capsules()[BodyPart::ForearmRight as usize];
                let centre = hand.b - (fore.b - fore.a).normalize() * 0.02;
                let rc = sim.robot_capsule_poses()[c.collision];
                let d =
                    phri_sim::capsule_distance(&centre, &centre, 0.045, &rc.a, &rc.b, rc.radius);
                assert!(
                    d.distance.abs() < 1e-3,
                    "t = {t}: hand {} m off the link",
                    d.distance
                );
                assert!((centre - point).norm() < 0.1, "hand near the point");
            } else {
                assert!(f < 30.0 + 1e-9);
                ramping += 1;
            }
            if (t - 0.6).abs() < 1e-6 {
                assert!(
                    (f - 15.0).abs() < 0.2,
                    "half way up the ramp at 0.6 s: {f} N"
                );
            }
        }
        assert!(
            full >= 590 && ramping >= 350 && outside > 400,
            "{full} {ramping} {outside}"
        );
    }
}

/// The push moves the arm: from rest at full force, the first step's change of
/// velocity against the same run without the push is `M⁻¹ Jᵀ F · dt`, and the
/// pushed point then moves along the force.
#[test]
fn a_push_accelerates_the_arm_by_the_inverse_mass_times_jt_f() {
    let model = common::model();
    let q = common::ik(&model, common::P2);
    let link7 = model.frame_id("lwr_link_7").expect("link 7");
    let p7 = Vector3::new(0.0, 0.0, 0.04);
    let mut data = Data::new(&model);
    let g = gravity(&model, &mut data, &q)
        .expect("g")
        .as_slice()
        .to_vec();
    let cfg = SimConfig {
        q0: q.clone(),
        ..common::ideal()
    };
    let with = push_scenario(30.0, "");
    let mut without = with.clone();
    if let Some(h) = without.human.as_mut() {
        let ks: Vec<_> = h
            .keyframes()
            .iter()
            .cloned()
            .map(|mut k| {
                k.push = None;
                k
            })
            .collect();
        *h = phri_config::HumanScript::new(h.floor_z(), ks).expect("script");
    }
    let mut a = Simulator::from_scenario(model.clone(), cfg.clone(), &with, None).expect("sim");
    let mut b = Simulator::from_scenario(model.clone(), cfg, &without, None).expect("sim");
    // run to t = 1.0 held at q (push at full force), then let go
    for s in [&mut a, &mut b] {
        while s.time_s() < 1.0 - 1e-9 {
            s.reset_state(&q).expect("pose");
            s.step(&g, false);
        }
        s.reset_state(&q).expect("pose");
    }
    let force = a.truth().contacts[0].force;
    assert!((force.norm() - 30.0).abs() < 1e-9);
    assert!(b.truth().contacts.is_empty());
    a.step(&g, false);
    b.step(&g, false);
    let dt = a.config().dt_s;
    forward_kinematics(&model, &mut data, &q).expect("fk");
    let mut jac = Data::jacobian_buffer(&model);
    point_jacobian(&model, &data, link7, &p7, &mut jac).expect("J");
    let jt_f = jac.fixed_rows::<3>(0).transpose() * force;
    let m: DMatrix<f64> = crba(&model, &mut data, &q).expect("M").clone();
    let expected: DVector<f64> = m
        .lu()
        .solve(&DVector::from_iterator(7, jt_f.iter().cloned()))
        .expect("M⁻¹")
        * dt;
    let (qa, qda) = a.state();
    let (_, qdb) = b.state();
    let dqd = DVector::from_iterator(7, qda.iter().zip(qdb).map(|(x, y)| x - y));
    let err = (&dqd - &expected).norm() / expected.norm();
    println!(
        "Δq̇ after one step {:.3e} rad/s, M⁻¹JᵀF·dt {:.3e}, relative error {err:.2e}",
        dqd.norm(),
        expected.norm()
    );
    assert!(err < 0.05, "Δq̇ {dqd} vs {expected}");
    // and the point gives way along the force over the next 0.1 s
    let _ = qa;
    for _ in 0..100 {
        a.step(&g, false);
        b.step(&g, false);
    }
    let at = |s: &Simulator, data: &mut Data| {
        forward_kinematics(&model, data, s.state().0).expect("fk");
        frame_placement(&model, data, link7).apply(&p7)
    };
    let moved = at(&a, &mut data) - at(&b, &mut data);
    println!(
        "after 0.1 s the pushed point is {:.1} mm further along the force",
        moved.dot(&force.normalize()) * 1e3
    );
    assert!(
        moved.dot(&force.normalize()) > 0.002,
        "gives way: {moved:?}"
    );
}

/// A push on a link the robot does not have is refused when the simulator is
/// built, naming the keyframe's key.
#[test]
fn a_push_on_an_unknown_link_is_refused_by_key() {
    let sc = Scenario::from_str(
        "name = \"push\"\n[human]\n\
         [[human.keyframe]]\nt = 0.0\nbase = [0.95, 0.0, 3.14]\n\
         [[human.keyframe]]\nt = 0.5\nbase = [0.95, 0.0, 3.14]\n\
         push = { link = \"lwr_link_9\", point = [0.0, 0.0, 0.0], force_n = 10.0, part = \"left_hand\" }\n",
    )
    .expect("the parser does not know the robot");
    let e = Simulator::from_scenario(common::model(), common::ideal(), &sc, None)
        .err()
        .expect("unknown link refused")
        .to_string();
    assert!(e.starts_with("keyframe[1].push.link: 'lwr_link_9'"), "{e}");
    assert!(e.contains("lwr_link_7"), "lists the links: {e}");
    // the flange has no capsule of its own: the push reports link 7's
    let sc = Scenario::from_str(
        "name = \"push\"\n[human]\n\
         [[human.keyframe]]\nt = 0.0\nbase = [0.95, 0.0, 3.14]\n\
         push = { link = \"lwr_flange\", point = [0.0, 0.0, 0.0], force_n = 10.0, part = \"left_hand\" }\n",
    )
    .expect("scenario");
    Simulator::from_scenario(common::model(), common::ideal(), &sc, None).expect("flange accepted");
}

/// The shipped `wave.toml`: the right hand waves from 3 s to 6 s, is then held
/// out in front of the robot until 10 s and lowered.
#[test]
fn wave_scenario_waves_then_holds_the_hand_out() {
    let sc = Scenario::from_file(common::scenario_path("wave.toml")).expect("wave.toml loads");
    assert_eq!(sc.name, "wave");
    let mut h = Human::new(sc.human.expect("human"));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut t = 3.5;
    while t < 5.5 {
        let (elbow, centre) = elbow_and_hand(h.pose_at(t), true);
        assert!(centre.z > elbow.z + 0.2, "raised at t = {t}");
        lo = lo.min(centre.y - elbow.y);
        hi = hi.max(centre.y - elbow.y);
        t += 0.01;
    }
    assert!(
        ((hi - lo) / 2.0 - 0.12).abs() < 0.024,
        "amplitude {}",
        (hi - lo) / 2.0
    );
    for t in [7.5, 9.0, 9.9] {
        let (_, centre) = elbow_and_hand(h.pose_at(t), true);
        assert!(
            (centre - Vector3::new(0.55, 0.1, 0.35)).norm() < 0.03,
            "held out at t = {t}: {centre:?}"
        );
    }
    let (elbow, centre) = elbow_and_hand(h.pose_at(12.0), true);
    assert!(centre.z < elbow.z, "lowered");
}
