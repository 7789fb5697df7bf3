//! The residual against a reference simulation of the arm: it stays near zero
//! in free motion, follows τ_ext as a first-order low-pass, detects within the
//! first-order bound, isolates the link, and ignores forces an F/T sensor sees.

use nalgebra::{DVector, Vector3};
use phri_dynamics::{ResidualConfig, ResidualObserver};
use phri_model::{Data, Model};

fn lwr4() -> Model {
    Model::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/robots/kuka_lwr4.urdf"
    ))
    .unwrap()
}

/// Exact-model simulation of the arm at 10 kHz, sampled at 1 kHz.
struct Arm {
    model: Model,
    data: Data,
    q: Vec<f64>,
    qd: Vec<f64>,
    t: f64,
}

impl Arm {
    fn new(model: Model) -> Arm {
        let data = Data::new(&model);
        Arm {
            q: vec![0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0],
            qd: vec![0.0; 7],
            t: 0.0,
            model,
            data,
        }
    }

    /// τ_ext of force `f` [N] at `point` [m] fixed on `link`.
    fn tau_ext(&mut self, link: &str, point: Vector3<f64>, f: Vector3<f64>) -> Vec<f64> {
        let frame = self.model.frame_id(link).unwrap();
        let mut j = Data::jacobian_buffer(&self.model);
        phri_model::forward_kinematics(&self.model, &mut self.data, &self.q).unwrap();
        phri_model::point_jacobian(&self.model, &self.data, frame, &point, &mut j).unwrap();
        (0..7)
            .map(|i| (0..3).map(|k| j[(k, i)] * f[k]).sum())
            .collect()
    }

    /// Advance 1 ms with motor torque `tau` plus external force `f` on `link`.
    fn step(&mut self, tau: &[f64], ext: Option<(&str, Vector3<f64>, Vector3<f64>)>) -> Vec<f64> {
        let mut te = vec![0.0; 7];
        for _ in 0..10 {
            te = match ext {
                Some((l, p, f)) => self.tau_ext(l, p, f),
                None => vec![0.0; 7],
            };
            let total: Vec<f64> = tau.iter().zip(&te).map(|(a, b)| a + b).collect();
            let qdd = phri_model::forward_dynamics(
                &self.model,
                &mut self.data,
                &self.q,
                &self.qd,
                &total,
            )
            .unwrap()
            .clone();
            for i in 0..7 {
                self.qd[i] += 1e-4 * qdd[i];
                self.q[i] += 1e-4 * self.qd[i];
            }
            self.t += 1e-4;
        }
        te
    }

    /// Gravity compensation plus an inertia-scaled joint PD towards a moving sinusoidal reference.
    fn controller(&mut self) -> Vec<f64> {
        let g: DVector<f64> = phri_model::gravity(&self.model, &mut self.data, &self.q)
            .unwrap()
            .clone();
        let m = phri_model::crba(&self.model, &mut self.data, &self.q)
            .unwrap()
            .clone();
        let acc = DVector::from_iterator(
            7,
            (0..7).map(|i| {
                let r =
                    0.3 * (1.5 * self.t + i as f64).sin() + [0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0][i];
                100.0 * (r - self.q[i]) - 20.0 * self.qd[i]
            }),
        );
        (m * acc + g).as_slice().to_vec()
    }
}

fn frictionless() -> ResidualConfig {
    ResidualConfig {
        viscous_friction: vec![0.0],
        coulomb_friction: vec![0.0],
        ..ResidualConfig::default()
    }
}

#[test]
fn free_motion_keeps_the_residual_near_zero() {
    let model = lwr4();
    let mut obs = ResidualObserver::new(model.clone(), &frictionless()).unwrap();
    let mut arm = Arm::new(model);
    let mut worst: f64 = 0.0;
    for k in 0..3000 {
        let tau = arm.controller();
        arm.step(&tau, None);
        let out = obs.step(arm.t, &arm.q, &tau, None).unwrap();
        // after the start-up transient of the PD (0.3 rad steps at t = 0)
        if k > 500 {
            worst = worst.max(out.norm);
            assert!(!out.detection.contact, "false contact at {k}: {:?}", out.r);
        }
    }
    assert!(worst < 0.5, "free-motion residual norm up to {worst} Nm");
}

#[test]
fn follows_a_step_as_a_first_order_low_pass_and_detects_within_the_bound() {
    let model = lwr4();
    let cfg = frictionless();
    let k_i = cfg.gain[0];
    let mut obs = ResidualObserver::new(model.clone(), &cfg).unwrap();
    let theta = obs.detector().collision.clone();
    let contact = obs.detector().contact.clone();
    let mut arm = Arm::new(model.clone());
    // 90 N on link 4, 0.15 m from the elbow, perpendicular to joint 4's axis and the lever
    let point = Vector3::new(0.0, -0.15, 0.0);
    let mut d = Data::new(&model);
    phri_model::forward_kinematics(&model, &mut d, &arm.q).unwrap();
    let frame = phri_model::frame_placement(&model, &d, model.frame_id("lwr_link_4").unwrap());
    let lever = frame.r * point;
    let force = d.s[3].w.cross(&lever).normalize() * 90.0 + Vector3::new(0.0, 0.0, -30.0);
    let ext = ("lwr_link_4", point, force);
    let onset = 1000;
    let mut detected_at = None;
    let mut tau_ext = vec![0.0; 7];
    for k in 0..1400 {
        let tau = arm.controller();
        let e = if k >= onset { Some(ext) } else { None };
        let te = arm.step(&tau, e);
        if k >= onset {
            tau_ext = te.clone();
        }
        let out = obs.step(arm.t, &arm.q, &tau, None).unwrap();
        if k >= onset && detected_at.is_none() && out.detection.collision {
            detected_at = Some(k - onset + 1);
            // a force on link 4 cannot show in components 5..7 (paper eq. 3)
            assert!(
                out.detection.isolated_joint.unwrap() <= 3,
                "isolated {:?}",
                out.detection.isolated_joint
            );
        }
        if k == onset + 300 {
            // settled: the isolated joint is the link's own joint
            assert!(
                te[3].abs() > contact[3],
                "test force must load joint 4: {te:?}"
            );
            assert_eq!(out.detection.isolated_joint, Some(3));
            // 300 ms after the step the residual equals τ_ext
            for i in 0..7 {
                assert!(
                    (out.r[i] - te[i]).abs() < 0.05 * (1.0 + te[i].abs()),
                    "joint {i}: r {} vs τ_ext {}",
                    out.r[i],
                    te[i]
                );
            }
        }
        if k == onset + 10 {
            // after 10 ms: r ≈ τ_ext (1 − e^{−K t}) within a sample
            for i in 0..4 {
                let expect = te[i] * (1.0 - (-k_i * 0.010).exp());
                assert!(
                    (out.r[i] - expect).abs() < 0.15 * te[i].abs() + 0.2,
                    "joint {i}: {} vs {expect}",
                    out.r[i]
                );
            }
        }
    }
    // first-order bound: −ln(1 − θ/F)/K_I + 2 ms, for the joint with the largest F/θ
    let (i, ratio) = (0..7)
        .map(|i| (i, tau_ext[i].abs() / theta[i]))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(ratio > 1.5, "test force too small: joint {i} F/θ = {ratio}");
    let bound_ms = -(1.0 - 1.0 / ratio).ln() / k_i * 1000.0 + 2.0;
    let got = detected_at.expect("collision not detected") as f64;
    assert!(
        got <= bound_ms,
        "detected after {got} ms, bound {bound_ms:.1} ms"
    );
}

#[test]
fn ft_sensor_reading_removes_tool_forces_from_the_residual() {
    let model = lwr4();
    let mut obs = ResidualObserver::new(model.clone(), &frictionless()).unwrap();
    let mut arm = Arm::new(model.clone());
    let f_max = Vector3::new(10.0, -15.0, 5.0);
    let mut data = Data::new(&model);
    for k in 0..1500 {
        let tau = arm.controller();
        // a contact force ramping up over 50 ms at the tool
        let f = f_max * ((k as f64 - 500.0) / 50.0).clamp(0.0, 1.0);
        let e = if k >= 500 {
            Some(("lwr_link_7", Vector3::zeros(), f))
        } else {
            None
        };
        arm.step(&tau, e);
        // the sensor measures the wrench at the link-7 origin: force, and zero moment there
        phri_model::forward_kinematics(&model, &mut data, &arm.q).unwrap();
        let w = if k >= 500 {
            [f.x, f.y, f.z, 0.0, 0.0, 0.0]
        } else {
            [0.0; 6]
        };
        let out = obs.step(arm.t, &arm.q, &tau, Some(&w)).unwrap();
        assert!(out.ft_used);
        if k > 500 {
            assert!(
                out.norm < 0.5,
                "k {k}: residual {} with the tool force measured",
                out.norm
            );
        }
    }
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let model = lwr4();
    let mut obs = ResidualObserver::new(model.clone(), &ResidualConfig::default()).unwrap();
    assert!(obs.step(0.0, &[0.0; 6], &[0.0; 7], None).is_err());
    assert!(obs.step(0.0, &[0.0; 7], &[0.0; 8], None).is_err());
    assert!(obs.step(0.0, &[f64::NAN; 7], &[0.0; 7], None).is_err());
    assert!(obs.step(f64::INFINITY, &[0.0; 7], &[0.0; 7], None).is_err());
    let bad = ResidualConfig {
        ft_link: "nope".into(),
        ..ResidualConfig::default()
    };
    assert!(ResidualObserver::new(model.clone(), &bad).is_err());
    let bad = ResidualConfig {
        gain: vec![],
        ..ResidualConfig::default()
    };
    assert!(ResidualObserver::new(model, &bad).is_err());
}
