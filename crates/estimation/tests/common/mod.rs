//! An analytic joint trajectory of the default robot and the torque that
//! produces it exactly: no simulation, so the residual's identities can be
//! checked against known values.
//!
//! Along a smooth `q(t)` the rigid-body dynamics give the torque the motors
//! must apply, `τ = M q̈ + C q̇ + g − τ_ext` (`phri_model::rnea` computes
//! `M q̈ + C q̇ + g`). The robot holds each command over one period, so the
//! torque of the sample at `t_k` is the mean over `(t_{k−1}, t_k]`, taken here
//! at the midpoint (error O(Δt²), far below the tolerances).

#![allow(dead_code)] // each test file uses its own part

use nalgebra::{Matrix6xX, Vector3};
use phri_config::{Loaded, PerJoint, ResidualConfig};
use phri_model::{Data, Model};

/// Sample period of the robot [s].
pub const DT: f64 = 1e-3;
/// Start posture [rad].
pub const Q0: [f64; 7] = [0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0];

/// The default robot (KUKA LWR IV) of `deploy/phri.toml`.
pub fn lwr4() -> Model {
    Loaded::defaults().model().unwrap()
}

/// `[dynamics]` as deployed, without friction compensation (the torques
/// below are frictionless).
pub fn frictionless() -> ResidualConfig {
    ResidualConfig {
        viscous_friction: PerJoint::All(0.0),
        coulomb_friction: PerJoint::All(0.0),
        ..Loaded::defaults().config.dynamics
    }
}

/// The configured gain K_I of joint `i` [1/s].
pub fn gain(cfg: &ResidualConfig, i: usize) -> f64 {
    cfg.gain.resolve(7, "dynamics.gain").unwrap()[i]
}

/// `q_i(t) = q0_i + a (sin(ω t + i) − sin i)` with its first two derivatives
/// [rad, rad/s, rad/s²]: every joint moves (0.3 rad at 1.5 rad/s, as the old
/// closed-loop reference did), from `Q0` at `t = 0`.
pub fn trajectory(t: f64) -> ([f64; 7], [f64; 7], [f64; 7]) {
    const A: f64 = 0.3;
    const W: f64 = 1.5;
    let (mut q, mut qd, mut qdd) = ([0.0; 7], [0.0; 7], [0.0; 7]);
    for i in 0..7 {
        let ph = W * t + i as f64;
        q[i] = Q0[i] + A * (ph.sin() - (i as f64).sin());
        qd[i] = A * W * ph.cos();
        qdd[i] = -A * W * W * ph.sin();
    }
    (q, qd, qdd)
}

/// The arm following [`trajectory`], and what acts on it.
pub struct Motion {
    pub model: Model,
    data: Data,
    jac: Matrix6xX<f64>,
}

impl Motion {
    pub fn new(model: Model) -> Motion {
        Motion {
            data: Data::new(&model),
            jac: Data::jacobian_buffer(&model),
            model,
        }
    }

    /// `M q̈ + C q̇ + g` at time `t` [Nm].
    pub fn inverse_dynamics(&mut self, t: f64) -> [f64; 7] {
        let (q, qd, qdd) = trajectory(t);
        let tau = phri_model::rnea(&self.model, &mut self.data, &q, &qd, &qdd).unwrap();
        std::array::from_fn(|i| tau[i])
    }

    /// τ_ext = Jᵀ f of a force `f` [N, base frame] at `point` [m, in the frame
    /// of `link`], at the trajectory's posture at `t`.
    pub fn tau_ext(
        &mut self,
        t: f64,
        link: &str,
        point: Vector3<f64>,
        f: Vector3<f64>,
    ) -> [f64; 7] {
        let (q, _, _) = trajectory(t);
        let frame = self.model.frame_id(link).unwrap();
        phri_model::forward_kinematics(&self.model, &mut self.data, &q).unwrap();
        phri_model::point_jacobian(&self.model, &self.data, frame, &point, &mut self.jac).unwrap();
        std::array::from_fn(|i| (0..3).map(|k| self.jac[(k, i)] * f[k]).sum())
    }

    /// The motor torque held over the period ending at `t`, given the
    /// external torque `ext(t)` acting meanwhile: `M q̈ + C q̇ + g − τ_ext`
    /// at the period's midpoint.
    pub fn held_torque(
        &mut self,
        t: f64,
        ext: impl FnOnce(&mut Motion, f64) -> [f64; 7],
    ) -> [f64; 7] {
        let tm = t - 0.5 * DT;
        let id = self.inverse_dynamics(tm);
        let te = ext(self, tm);
        std::array::from_fn(|i| id[i] - te[i])
    }
}

/// Samples `k = 0, 1, …`: time `k Δt` [s] and the measured positions [rad].
pub fn sample(k: usize) -> (f64, [f64; 7]) {
    let t = k as f64 * DT;
    (t, trajectory(t).0)
}
