//! Contact forces from the residual (paper eqs. 21-23) against the
//! simulator's truth: static pushes at the end effector, on link 6 and on
//! link 4 in lock-step while the arm works its task (detection set out of
//! the way, thresholds raised, so that the task keeps moving the arm), and
//! two at once (a person's push on link 4 while a force acts at the end
//! effector) on the simulated arm held in a posture away from the
//! shoulder's singularity, where two contacts are observable. The estimate
//! is `(J_cᵀ)^# r` at the true contact points with the residual computed
//! from joint positions only.

use crate::common;

use nalgebra::Vector3;
use phri_cell::CellOptions;
use phri_estimation::ResidualObserver;
use phri_estimation::{ContactPoint, ForceEstimator};
use phri_sim::ExternalForce;

/// Detection out of the way: each threshold at the largest value its safe
/// range allows for the LWR-IV (the joints' effort limits and their norm)
const NO_DETECTION: [&str; 2] = [
    "dynamics.collision_threshold=[176.0, 176.0, 100.0, 100.0, 100.0, 38.0, 38.0]",
    "dynamics.collision_norm_threshold=307.0",
];

/// A person who stands back and, from 8.0 s to 9.5 s, pushes link 4 with
/// the left hand (30 N).
fn pushing_person(sets: &[&str]) -> phri_config::Loaded {
    let base = [1.3, 0.0, std::f64::consts::PI];
    common::rescript("collaboration", sets, |keyframes| {
        *keyframes = vec![
            common::keyframe(0.0, base),
            phri_config::Keyframe {
                push: Some(phri_config::Push {
                    link: "lwr_link_4".into(),
                    point: [0.0, -0.1, 0.0],
                    force_n: 30.0,
                    hand: phri_config::Hand::Left,
                    intended: false,
                }),
                ..common::keyframe(8.0, base)
            },
            common::keyframe(9.5, base),
        ];
    })
}

/// Relative errors ‖F̂ − F‖/‖F‖ of each contact, sorted.
struct Errors(Vec<Vec<f64>>);

impl Errors {
    fn p(&self, i: usize, q: f64) -> f64 {
        let v = &self.0[i];
        v[((v.len() - 1) as f64 * q).round() as usize]
    }
}

#[test]
fn forces_at_the_end_effector_on_link_6_and_on_link_4_while_the_task_runs() {
    let mut c = common::cell("free-motion", &CellOptions::default(), &NO_DETECTION);
    let model = c.sim.model().clone();
    let mut est = ForceEstimator::new(model.clone(), 1e-3);
    let frame = |link: &str| model.frame_id(link).unwrap();
    // (from, to [s], link, point [m] link frame, force [N] base frame)
    let pushes = [
        (
            2.0,
            3.0,
            "lwr_link_7",
            [0.0, 0.05, 0.06],
            [15.0, -10.0, 20.0],
        ),
        (
            4.0,
            5.0,
            "lwr_link_6",
            [0.0, 0.06, 0.0],
            [-20.0, 15.0, 10.0],
        ),
        (
            6.0,
            7.0,
            "lwr_link_4",
            [0.0, 0.05, 0.03],
            [10.0, 25.0, -15.0],
        ),
    ];
    let mut errors = Errors(vec![Vec::new(); 3]);
    for k in 1..=10_000u64 {
        let t = k as f64 * 1e-3;
        let active = pushes.iter().find(|p| (p.0..p.1).contains(&t));
        c.sim.set_external_force(active.map(|p| ExternalForce {
            frame: frame(p.2),
            point: Vector3::from(p.3),
            force: Vector3::from(p.4),
        }));
        c.tick().unwrap();
        // graded once the force has held for 0.1 s (ten residual time constants)
        let Some(p) = active.filter(|p| t >= p.0 + 0.1) else {
            continue;
        };
        let (q, r) = (c.sim.truth().q.clone(), c.residual.unwrap().r);
        let applied = ContactPoint {
            frame: frame(p.2),
            point: Vector3::from(p.3),
        };
        let f = Vector3::from(p.4);
        let e = *est.estimate(&q, &r[..7], &[applied]).unwrap();
        assert!(
            e.observable[0],
            "{} at {t:.3} s: not observable, q {q:?}",
            p.2
        );
        let i = pushes.iter().position(|x| x.0 == p.0).unwrap();
        errors.0[i].push((e.forces[0] - f).norm() / f.norm());
    }
    for v in errors.0.iter_mut() {
        v.sort_by(f64::total_cmp);
    }
    let names = ["end effector", "link 6", "link 4"];
    for (i, name) in names.iter().enumerate() {
        eprintln!(
            "{name}: {} samples, error p50 {:.3} p95 {:.3} max {:.3}",
            errors.0[i].len(),
            errors.p(i, 0.5),
            errors.p(i, 0.95),
            errors.p(i, 1.0)
        );
        assert!(
            errors.0[i].len() > 800,
            "{name}: {} samples",
            errors.0[i].len()
        );
        assert!(
            errors.p(i, 0.5) < 0.05,
            "{name}: p50 {:.3}",
            errors.p(i, 0.5)
        );
        assert!(
            errors.p(i, 0.95) < 0.10,
            "{name}: p95 {:.3}",
            errors.p(i, 0.95)
        );
    }
}

#[test]
fn two_forces_at_once_on_an_arm_held_still() {
    // the unit test's posture: both contacts observable. The arm is held by
    // its brakes (the drives' torque is then the brake torque, which the
    // residual takes as applied): a servo's motion would pass through the
    // wrist's three joints, which alone tell the end effector's force from
    // the person's, with levers of centimetres
    let q0 = [0.1, -0.4, 0.2, 1.6, -0.3, -0.7, 0.4];
    let set = format!("sim.q0={q0:?}");
    let l = pushing_person(&[set.as_str()]);
    let model = l.model().unwrap();
    let cfg = &l.config;
    let mut sim =
        phri_sim::Simulator::from_scenario(model.clone(), cfg.sim.clone(), &l.scenario, None)
            .unwrap();
    let mut observer = ResidualObserver::new(model.clone(), &cfg.dynamics).unwrap();
    let mut est = ForceEstimator::new(model.clone(), 1e-3);
    let mut data = phri_model::Data::new(&model);
    let (link4, link7) = (
        model.frame_id("lwr_link_4").unwrap(),
        model.frame_id("lwr_link_7").unwrap(),
    );
    let at_ee = ContactPoint {
        frame: link7,
        point: Vector3::new(0.0, 0.06, 0.04),
    };
    let f_ee = Vector3::new(15.0, -10.0, 20.0);
    let mut tau = vec![0.0; 7];
    let (mut e_ee, mut e_person) = (Vec::new(), Vec::new());
    for k in 1..=9_500u64 {
        let t = k as f64 * 1e-3;
        // from 7.5 s a force at the end effector; the person pushes link 4 at 8.0-9.5 s
        sim.set_external_force((t >= 7.5).then_some(ExternalForce {
            frame: link7,
            point: at_ee.point,
            force: f_ee,
        }));
        let m = sim.step(&tau, k > 50).clone();
        let out = observer.step(m.t_s, &m.q, &m.tau_applied, None).unwrap();
        let r = out.r.to_vec();
        // held: gravity compensation, then (from 50 ms) the brakes
        let g = phri_model::gravity(&model, &mut data, &m.q).unwrap();
        tau.copy_from_slice(g.as_slice());
        let truth = sim.truth();
        let Some(touch) = truth.contacts.iter().find(|c| c.force.norm() > 1.0) else {
            continue;
        };
        // graded once the push has ramped up (0.2 s) and held 0.1 s, while
        // the braked arm yields only a little (0.6 s)
        if !(8.3..8.9).contains(&t) {
            continue;
        }
        phri_model::forward_kinematics(&model, &mut data, &truth.q).unwrap();
        let pose = phri_model::frame_placement(&model, &data, link4);
        let second = ContactPoint {
            frame: link4,
            point: pose.r.transpose() * (touch.point - pose.p),
        };
        let e = *est.estimate(&truth.q, &r, &[at_ee, second]).unwrap();
        assert!(
            e.observable[0] && e.observable[1],
            "{:?} at {t:.3} s",
            e.observable
        );
        e_ee.push((e.forces[0] - f_ee).norm() / f_ee.norm());
        e_person.push((e.forces[1] - touch.force).norm() / touch.force.norm());
    }
    for (name, v) in [
        ("end effector", &mut e_ee),
        ("link 4 (the person)", &mut e_person),
    ] {
        v.sort_by(f64::total_cmp);
        let p = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        eprintln!(
            "two at once, {name}: {} samples, error p50 {:.3} p95 {:.3} max {:.3}",
            v.len(),
            p(0.5),
            p(0.95),
            p(1.0)
        );
        // two contacts condition the estimate worse than one (measured:
        // 4 % at the end effector, 12-14 % on link 4, the braked arm creeping)
        assert!(v.len() >= 550, "{name}: {} samples", v.len());
        assert!(p(0.5) < 0.15, "{name}: p50 {:.3}", p(0.5));
        assert!(p(0.95) < 0.20, "{name}: p95 {:.3}", p(0.95));
    }
}

#[test]
fn the_collaboration_scenario_meets_the_force_error_goal_in_lock_step() {
    // issue 11's figure as the report grades it: ‖F̂ − F_true‖/‖F_true‖ in
    // the contact phase, over the samples where the collaborative hand's
    // true force is at least 5 N (deploy/scenarios/collaboration.toml)
    let mut c = common::cell("collaboration", &CellOptions::default(), &[]);
    let mut errors = Vec::new();
    for _ in 0..16_000 {
        c.tick().unwrap();
        let col = c.controller.collaboration().unwrap();
        if col.phase() != phri_ipc::CollabPhase::Contact {
            continue;
        }
        let f: Vector3<f64> = c
            .sim
            .truth()
            .contacts
            .iter()
            .filter(|k| k.intended && k.part == phri_ipc::BodyPart::HandRight)
            .map(|k| k.force)
            .sum();
        let Some(e) = col.estimate().filter(|e| e.observable[0]) else {
            continue;
        };
        if f.norm() >= 5.0 {
            errors.push((e.forces[0] - f).norm() / f.norm());
        }
    }
    errors.sort_by(f64::total_cmp);
    let p = |q: f64| errors[((errors.len() - 1) as f64 * q).round() as usize];
    eprintln!(
        "collaboration: {} samples, F̂ error p50 {:.3} p95 {:.3}",
        errors.len(),
        p(0.5),
        p(0.95)
    );
    assert!(errors.len() > 2000, "{} samples", errors.len());
    assert!(p(0.5) <= 0.10, "p50 {:.3}", p(0.5));
    assert!(p(0.95) <= 0.25, "p95 {:.3}", p(0.95));
}
