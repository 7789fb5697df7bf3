//! The joint reference every behaviour writes, and the two joint laws that
//! turn it into an acceleration for the computed-torque law
//! `τ = M a + C q̇ + g`.

use nalgebra::Vector3;

use crate::snapshot::snapshot_fields;

/// Gains of the computed-torque tracking (`[control] kp`, `kd`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackingGains {
    /// stiffness [1/s²]
    pub kp: f64,
    /// damping [1/s]
    pub kd: f64,
}

/// The joint reference and where the arm is held.
#[derive(Clone, Debug)]
pub struct JointReference {
    /// joint reference \[rad\]
    pub q_ref: Vec<f64>,
    /// its velocity [rad/s]
    pub qd_ref: Vec<f64>,
    /// the reference velocity of the previous period [rad/s] (feed-forward)
    pub qd_ref_prev: Vec<f64>,
    /// the reference acceleration fed forward last period [rad/s²] (0 at a hold)
    pub qdd_ref: Vec<f64>,
    /// joint positions held \[rad\]
    pub q_hold: Vec<f64>,
    /// end-effector position held while recovering \[m\], base frame
    pub x_hold: Vector3<f64>,
}

snapshot_fields!(JointReference {
    q_ref,
    qd_ref,
    qd_ref_prev,
    qdd_ref,
    q_hold,
    x_hold
});

impl JointReference {
    /// All zero, for `n` joints.
    pub fn new(n: usize) -> JointReference {
        JointReference {
            q_ref: vec![0.0; n],
            qd_ref: vec![0.0; n],
            qd_ref_prev: vec![0.0; n],
            qdd_ref: vec![0.0; n],
            q_hold: vec![0.0; n],
            x_hold: Vector3::zeros(),
        }
    }

    /// Hold the measured `q`: reference and hold there, at rest.
    pub fn hold_here(&mut self, q: &[f64]) {
        self.q_hold.copy_from_slice(q);
        self.q_ref.copy_from_slice(q);
        self.qd_ref.fill(0.0);
        self.qd_ref_prev.fill(0.0);
        self.qdd_ref.fill(0.0);
    }

    /// Track (`q_ref`, `qd_ref`) with the feed-forward of the reference's
    /// change over `dt` \[s\]: `a = q̈_ref + K_P (q_ref − q) + K_D (q̇_ref − q̇)`.
    pub fn track(&mut self, q: &[f64], qd: &[f64], dt: f64, g: TrackingGains, accel: &mut [f64]) {
        for i in 0..accel.len() {
            let qdd_ref = if dt > 0.0 {
                (self.qd_ref[i] - self.qd_ref_prev[i]) / dt
            } else {
                0.0
            };
            self.qdd_ref[i] = qdd_ref;
            accel[i] = qdd_ref + g.kp * (self.q_ref[i] - q[i]) + g.kd * (self.qd_ref[i] - qd[i]);
        }
        self.qd_ref_prev.copy_from_slice(&self.qd_ref);
    }

    /// Hold `q_hold` at rest: `a = K_P (q_hold − q) − K_D q̇`.
    pub fn hold(&self, q: &[f64], qd: &[f64], g: TrackingGains, accel: &mut [f64]) {
        for i in 0..accel.len() {
            accel[i] = g.kp * (self.q_hold[i] - q[i]) - g.kd * qd[i];
        }
    }
}
