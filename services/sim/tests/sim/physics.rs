//! Physics of the simulated arm: energy, gravity, friction, brakes, end
//! stops, encoders, contact forces and the dynamic identity they satisfy.

use crate::common;

use std::path::Path;

use nalgebra::{Matrix6xX, Vector3};
use phri_config::{HumanScript, Keyframe, Loaded, PerJoint, SimConfig, DEFAULT_DEPLOY_DIR};
use phri_ipc::BodyPart;
use phri_model::{gravity, rnea, Data, Model};
use phri_sim::{stiffness_n_per_m, Simulator};

fn no_limits(mut model: Model) -> Model {
    for j in model.joints.iter_mut() {
        j.lower = f64::NEG_INFINITY;
        j.upper = f64::INFINITY;
    }
    model
}

fn sim(model: Model, cfg: SimConfig) -> Simulator {
    Simulator::new(model, cfg, None, &[], None).expect("simulator")
}

/// No torque, no friction, no noise, no end stops: `T + V` stays within 1 %
/// of the largest kinetic energy reached while the arm falls for 1 s.
#[test]
fn torque_free_arm_conserves_energy() {
    let model = no_limits(common::model());
    let mut data = Data::new(&model);
    let mut s = sim(model.clone(), common::ideal());
    let zero = [0.0; 7];
    let (q, qd) = s.state();
    let e0 = common::energy(&model, &mut data, q, qd);
    let (mut drift, mut t_max): (f64, f64) = (0.0, 0.0);
    for _ in 0..1000 {
        s.step(&zero, false);
        let (q, qd) = s.state();
        let e = common::energy(&model, &mut data, q, qd);
        drift = drift.max((e - e0).abs());
        t_max = t_max.max(phri_model::kinetic_energy(&model, &mut data, q, qd).expect("T"));
    }
    println!("largest kinetic energy {t_max:.3} J, largest energy drift {drift:.2e} J");
    assert!(t_max > 5.0, "the arm really fell ({t_max} J)");
    assert!(
        drift < 0.01 * t_max,
        "energy drift {drift} J vs kinetic energy {t_max} J"
    );
}

/// Commanding `g(q)` of the measured (quantized) position holds the arm
/// within 1 mrad for 1 s (no friction, no noise).
#[test]
fn gravity_compensation_holds_the_arm() {
    let model = common::model();
    let mut data = Data::new(&model);
    let mut s = sim(model.clone(), common::ideal());
    let q0 = s.state().0.to_vec();
    let mut tau = [0.0; 7];
    for _ in 0..1000 {
        let q_meas = s.measurement().q.clone();
        tau.copy_from_slice(gravity(&model, &mut data, &q_meas).expect("g").as_slice());
        s.step(&tau, false);
    }
    let err = s
        .state()
        .0
        .iter()
        .zip(&q0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("largest deviation after 1 s: {err:.2e} rad");
    assert!(err < 1e-3);
}

/// With friction, `T + V` never increases (no torque commanded) and a
/// spinning arm loses most of its energy; without it the energy stays.
#[test]
fn friction_dissipates_energy() {
    let model = common::model();
    let mut data = Data::new(&model);
    let qd0 = [1.0, -1.0, 1.5, 1.0, -2.0, 2.0, 3.0];
    let mut run = |viscous: f64, coulomb: f64| {
        let cfg = SimConfig {
            viscous_friction: PerJoint::All(viscous),
            coulomb_friction: PerJoint::All(coulomb),
            torque_noise_std: 0.0,
            ..common::sim_config()
        };
        let mut s = sim(model.clone(), cfg);
        let q0 = s.state().0.to_vec();
        s.set_state(&q0, &qd0).expect("state");
        let e0 = common::energy(&model, &mut data, &q0, &qd0);
        let mut prev = e0;
        let mut largest_rise: f64 = 0.0;
        let mut tau = [0.0; 7];
        for _ in 0..500 {
            // gravity compensation keeps the arm off the end stops
            let q = s.state().0.to_vec();
            tau.copy_from_slice(gravity(&model, &mut data, &q).expect("g").as_slice());
            s.step(&tau, false);
            let (q, qd) = s.state();
            let e = phri_model::kinetic_energy(&model, &mut data, q, qd).expect("T");
            largest_rise = largest_rise.max(e - prev);
            prev = e;
        }
        let t0 = phri_model::kinetic_energy(&model, &mut data, &q0, &qd0).expect("T");
        let _ = e0;
        (t0, prev, largest_rise)
    };
    let (t0, t_end, rise) = run(0.5, 0.3);
    println!("with friction: kinetic energy {t0:.3} J -> {t_end:.3} J in 0.5 s, largest rise per step {rise:.2e} J");
    // the proximal joints carry most of the inertia: 0.5 N m s/rad slows them over seconds
    assert!(t_end < 0.6 * t0);
    assert!(rise < 1e-3 * t0, "friction never adds energy");
    let (t0, t_end, _) = run(0.0, 0.0);
    println!("without friction: kinetic energy {t0:.3} J -> {t_end:.3} J");
    assert!(t_end > 0.95 * t0);
}

/// The brakes bring a moving arm to rest within 0.5 s and hold it.
#[test]
fn brake_stops_and_holds_the_arm() {
    let model = common::model();
    let mut s = sim(
        model,
        SimConfig {
            seed: 3,
            ..common::sim_config()
        },
    );
    let q0 = s.state().0.to_vec();
    s.set_state(&q0, &[1.0, -1.0, 1.5, 1.0, -2.0, 2.0, 3.0])
        .expect("state");
    let nothing = [0.0; 7];
    for _ in 0..500 {
        s.step(&nothing, true);
    }
    let qd_max = s.state().1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!("|q̇| after 0.5 s of braking: {qd_max:.2e} rad/s");
    assert!(qd_max < 0.01);
    let q_stop = s.state().0.to_vec();
    for _ in 0..1000 {
        let m = s.step(&nothing, true);
        // the reported torque is the brake torque, about g(q) at rest
        assert!(m.tau_applied.iter().all(|t| t.is_finite()));
    }
    let moved = s
        .state()
        .0
        .iter()
        .zip(&q_stop)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(moved < 1e-3, "drifted {moved} rad while braked");
}

/// Measured positions are multiples of the encoder resolution, within half a
/// step of the truth.
#[test]
fn measured_positions_are_quantized() {
    let cfg = common::sim_config();
    let res = cfg.encoder_resolution_rad;
    let mut s = sim(common::model(), cfg);
    let tau = [0.0, 5.0, 0.0, 2.0, 0.0, 0.5, 0.1];
    for _ in 0..200 {
        let m = s.step(&tau, false).clone();
        for (qm, qt) in m.q.iter().zip(&s.truth().q) {
            let k = qm / res;
            assert!(
                (k - k.round()).abs() < 1e-6,
                "{qm} is not a multiple of {res}"
            );
            assert!((qm - qt).abs() <= 0.5 * res + 1e-15);
        }
    }
}

/// Commands are clamped to the effort limits and that is what is reported;
/// non-finite and missing entries count as zero.
#[test]
fn commands_are_clamped_and_reported() {
    let model = common::model();
    let effort: Vec<f64> = model.joints.iter().map(|j| j.effort).collect();
    let mut s = sim(model, common::ideal());
    let m = s.step(&[1000.0, -1000.0, f64::NAN, 5.0], false);
    assert_eq!(
        m.tau_applied,
        vec![effort[0], -effort[1], 0.0, 5.0, 0.0, 0.0, 0.0]
    );
    assert!(m.wrench.is_none());
}

/// A joint driven into its end stop stops there.
#[test]
fn end_stops_hold_the_joint() {
    let model = common::model();
    let upper = model.joints[3].upper;
    let mut s = sim(model, common::ideal());
    let mut tau = [0.0; 7];
    tau[3] = 60.0;
    for _ in 0..1000 {
        s.step(&tau, false);
        assert!(s.state().0[3] <= upper);
    }
    assert!((s.state().0[3] - upper).abs() < 1e-12);
    assert!(s.state().1[3] <= 0.0);
}

/// The same seed gives the same run; another seed another.
#[test]
fn runs_are_deterministic() {
    let run = |seed| {
        let mut s = Simulator::new(common::model(), common::sim_config(), None, &[], Some(seed))
            .expect("sim");
        for _ in 0..300 {
            s.step(&[0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0], false);
        }
        s.truth().q.clone()
    };
    assert_eq!(run(1), run(1));
    assert_ne!(run(1), run(2));
}

/// A right hand keyframed into the robot's forearm (the robot floats under
/// gravity compensation). Without contact damping the contact force is
/// exactly `k δ` along the normal, `tau_ext = Σ J_cᵀ F` with `J_c` from
/// `point_jacobian`, and over each period `M q̈ + C q̇ + g = τ_motor + τ_f + τ_ext`.
#[test]
fn hand_pushing_the_forearm() {
    let model = common::model();
    let q_front = common::ik(&model, common::P2);
    // the hand comes in from the side of the forearm (links 4 and 5 at y = 0)
    // a person on the robot's right (y < 0) facing +y
    let base = [0.35, -0.6, std::f64::consts::FRAC_PI_2];
    let script = HumanScript::new(
        -0.8,
        vec![
            Keyframe {
                t: 0.0,
                base,
                right_hand: Some([0.33, -0.25, 0.60]),
                ..Keyframe::default()
            },
            Keyframe {
                t: 0.3,
                base,
                right_hand: Some([0.33, -0.07, 0.60]),
                ..Keyframe::default()
            },
        ],
    )
    .expect("script");
    let cfg = SimConfig {
        q0: q_front.clone(),
        contact_damping: 0.0,
        ft_sensor: true,
        ..common::ideal()
    };
    let mut s = Simulator::new(
        model.clone(),
        cfg,
        Some(script),
        &[BodyPart::HandRight],
        None,
    )
    .expect("sim");
    assert_eq!(s.truth().contacts.len(), 0, "no contact at the start");
    let mut data = Data::new(&model);
    let mut jac = Matrix6xX::zeros(7);
    let mut tau = [0.0; 7];
    let (mut worst_force, mut worst_tau, mut worst_identity, mut largest_tau_ext): (
        f64,
        f64,
        f64,
        f64,
    ) = (0.0, 0.0, 0.0, 0.0);
    let mut seen_forearm = false;
    for _ in 0..500 {
        let before = s.truth().clone();
        let q_meas = s.measurement().q.clone();
        tau.copy_from_slice(gravity(&model, &mut data, &q_meas).expect("g").as_slice());
        s.step(&tau, false);
        let after = s.truth().clone();
        // every contact: F = k δ n, on a forearm-area link, intended (hand)
        let mut tau_ext = [0.0; 7];
        phri_model::forward_kinematics(&model, &mut data, &after.q).expect("fk");
        for c in &after.contacts {
            let link = s.collision_link(c.collision).expect("link");
            seen_forearm |= link == "lwr_link_4" || link == "lwr_link_5";
            let k = stiffness_n_per_m(c.part);
            worst_force = worst_force.max((c.force.norm() - k * c.depth).abs() / (k * c.depth));
            assert_eq!(c.intended, c.part == BodyPart::HandRight);
            // J_c of the contact point, fixed in the link frame
            let frame = model.frame_id(link).expect("frame");
            let pl = phri_model::frame_placement(&model, &data, frame);
            let local = pl.r.transpose() * (c.point - pl.p);
            phri_model::point_jacobian(&model, &data, frame, &local, &mut jac).expect("jacobian");
            let jt_f = jac.fixed_rows::<3>(0).transpose() * c.force;
            for (acc, x) in tau_ext.iter_mut().zip(jt_f.iter()) {
                *acc += x;
            }
        }
        if after.contact_pairs <= after.contacts.len() {
            for (ours, sim) in tau_ext.iter().zip(&after.tau_ext) {
                worst_tau = worst_tau.max((ours - sim).abs());
                largest_tau_ext = largest_tau_ext.max(sim.abs());
            }
        }
        // dynamic identity over the period, at the midpoint state
        if !after.contacts.is_empty() && !before.contacts.is_empty() {
            let dt = after.t_s - before.t_s;
            let qm: Vec<f64> = before
                .q
                .iter()
                .zip(&after.q)
                .map(|(a, b)| 0.5 * (a + b))
                .collect();
            let qdm: Vec<f64> = before
                .qd
                .iter()
                .zip(&after.qd)
                .map(|(a, b)| 0.5 * (a + b))
                .collect();
            let qdd: Vec<f64> = before
                .qd
                .iter()
                .zip(&after.qd)
                .map(|(a, b)| (b - a) / dt)
                .collect();
            let lhs = rnea(&model, &mut data, &qm, &qdm, &qdd)
                .expect("rnea")
                .clone();
            for i in 0..7 {
                let rhs = after.tau_motor[i]
                    + after.tau_friction[i]
                    + 0.5 * (before.tau_ext[i] + after.tau_ext[i]);
                let scale = 1.0 + after.tau_ext[i].abs().max(before.tau_ext[i].abs());
                worst_identity = worst_identity.max((lhs[i] - rhs).abs() / scale);
            }
        }
    }
    println!(
        "largest |tau_ext| {largest_tau_ext:.1} N m; worst |F| - k δ (relative) {worst_force:.1e}, worst tau_ext vs J_cᵀF {worst_tau:.1e} N m, worst identity residual (relative) {worst_identity:.2e}"
    );
    assert!(seen_forearm, "the hand touched link 4 or 5");
    assert!(largest_tau_ext > 5.0, "the contact pushes noticeably");
    assert!(worst_force < 1e-9);
    assert!(worst_tau < 1e-9 * (1.0 + largest_tau_ext));
    assert!(
        worst_identity < 0.05,
        "M q̈ + C q̇ + g = τ + τ_ext within 5 %"
    );
}

/// The wrist sensor sees contacts on the last link only: force and moment
/// about the last link's frame origin.
#[test]
fn wrist_sensor_measures_contacts_beyond_the_wrist() {
    let model = common::model();
    let q = common::ik(&model, common::P2);
    // hand pressed onto the flange side of link 7
    let script = HumanScript::new(
        -0.8,
        vec![Keyframe {
            t: 0.0,
            base: [0.95, 0.0, std::f64::consts::PI],
            right_hand: Some([0.63, 0.0, 0.34]),
            ..Keyframe::default()
        }],
    )
    .expect("script");
    let cfg = SimConfig {
        q0: q.clone(),
        contact_damping: 0.0,
        ft_sensor: true,
        ..common::ideal()
    };
    let s = Simulator::new(model.clone(), cfg, Some(script), &[], None).expect("sim");
    let last = model.joints.len() - 1;
    let mut data = Data::new(&model);
    phri_model::forward_kinematics(&model, &mut data, &q).expect("fk");
    let origin = data.body[last].p;
    let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
    let mut on_link7 = 0;
    for c in &s.truth().contacts {
        if s.collision_link(c.collision) == Some("lwr_link_7") {
            f += c.force;
            m += (c.point - origin).cross(&c.force);
            on_link7 += 1;
        }
    }
    assert!(
        on_link7 > 0 && s.truth().contacts.len() > on_link7,
        "contacts on link 7 and elsewhere"
    );
    let w = s.measurement().wrench.expect("sensor on");
    for a in 0..3 {
        assert!((w[a] - f[a]).abs() < 1e-9 && (w[3 + a] - m[a]).abs() < 1e-9);
    }
}

/// Bad configurations and states are refused with the field named.
#[test]
fn refuses_bad_configuration() {
    let model = common::model();
    let bad = |cfg: SimConfig| {
        Simulator::new(model.clone(), cfg, None, &[], None)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    assert!(bad(SimConfig {
        q0: vec![0.0; 6],
        ..common::sim_config()
    })
    .contains("q0"));
    assert!(bad(SimConfig {
        q0: vec![0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ..common::sim_config()
    })
    .contains("q0"));
    assert!(bad(SimConfig {
        dt_s: 0.0,
        ..common::sim_config()
    })
    .contains("dt_s"));
    assert!(bad(SimConfig {
        substeps: 0,
        ..common::sim_config()
    })
    .contains("substeps"));
    assert!(bad(SimConfig {
        viscous_friction: PerJoint::Each(vec![0.5; 3]),
        ..common::sim_config()
    })
    .contains("viscous_friction"));
    assert!(bad(SimConfig {
        coulomb_friction: PerJoint::All(-1.0),
        ..common::sim_config()
    })
    .contains("coulomb_friction"));
    assert!(bad(SimConfig {
        torque_noise_std: f64::NAN,
        ..common::sim_config()
    })
    .contains("torque_noise_std"));
    let mut s = sim(model.clone(), common::sim_config());
    assert!(s.reset_state(&[0.0; 3]).is_err());
    assert!(s.reset_state(&[f64::NAN; 7]).is_err());
    assert!(s.set_state(&[0.0; 7], &[0.0; 6]).is_err());
    // TOML config ([sim] over the defaults): defaults, per-joint arrays, unknown fields refused
    let sim_section = |text: &str| {
        Loaded::load_text(
            &format!("[sim]\n{text}"),
            &Path::new(DEFAULT_DEPLOY_DIR).join("phri.toml"),
            None,
            &[],
        )
        .map(|l| l.config.sim)
    };
    let cfg = sim_section("substeps = 8\nviscous_friction = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.2]\nbrake_torque_max = 30\n").expect("valid");
    assert_eq!(cfg.substeps, 8);
    assert_eq!(
        cfg.viscous_friction,
        PerJoint::Each(vec![0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.2])
    );
    assert_eq!(cfg.brake_torque_max, PerJoint::All(30.0));
    assert_eq!(cfg.dt_s, 0.001);
    assert!(sim_section("substep = 8\n")
        .expect_err("unknown")
        .to_string()
        .contains("substep"));
    assert!(sim_section("coulomb_friction = \"high\"\n").is_err());
}
