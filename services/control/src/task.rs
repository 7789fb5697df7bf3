//! The task: a cyclic Cartesian path of minimum-jerk segments through
//! waypoints, and closed-loop inverse kinematics that turns it into a joint
//! reference with the redundancy pulling towards a posture.

use nalgebra::{Matrix3, Matrix6xX, Vector3};
use phri_model::{Data, Model};

/// Minimum-jerk blend `p(u) = 10u³ − 15u⁴ + 6u⁵` and its derivative, u ∈ [0, 1].
#[inline]
pub fn min_jerk(u: f64) -> (f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (
        u3 * (10.0 - 15.0 * u + 6.0 * u2),
        30.0 * u2 * (1.0 - 2.0 * u + u2),
    )
}

/// Cyclic path through waypoints, parametrised by path time `s` [s].
#[derive(Clone, Debug)]
pub struct Path {
    pub waypoints: Vec<Vector3<f64>>,
    pub segment_time: f64,
}

impl Path {
    /// One full cycle [s].
    pub fn period(&self) -> f64 {
        self.segment_time * self.waypoints.len() as f64
    }

    /// Index of the waypoint the segment at `s` ends in.
    pub fn target_index(&self, s: f64) -> usize {
        let k = (s.rem_euclid(self.period()) / self.segment_time).floor() as usize;
        (k + 1) % self.waypoints.len()
    }

    /// Position [m] and its derivative with respect to path time [m/s] at `s`.
    pub fn sample(&self, s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let n = self.waypoints.len();
        let s = s.rem_euclid(self.period());
        let k = ((s / self.segment_time).floor() as usize).min(n - 1);
        let u = (s - k as f64 * self.segment_time) / self.segment_time;
        let (a, b) = (self.waypoints[k], self.waypoints[(k + 1) % n]);
        let (p, dp) = min_jerk(u);
        (a + (b - a) * p, (b - a) * (dp / self.segment_time))
    }
}

/// A straight minimum-jerk move of the end effector from `from` to `to`.
#[derive(Clone, Copy, Debug)]
pub struct Approach {
    pub from: Vector3<f64>,
    pub to: Vector3<f64>,
    pub duration: f64,
    pub t: f64,
}

impl Approach {
    pub fn new(from: Vector3<f64>, to: Vector3<f64>, speed: f64) -> Approach {
        // a minimum-jerk move peaks at 1.875× its mean speed
        let duration = ((to - from).norm() * 1.875 / speed.max(1e-3)).max(0.5);
        Approach {
            from,
            to,
            duration,
            t: 0.0,
        }
    }

    pub fn done(&self) -> bool {
        self.t >= self.duration
    }

    /// Advance by `dt`; returns position and velocity.
    pub fn step(&mut self, dt: f64) -> (Vector3<f64>, Vector3<f64>) {
        self.t = (self.t + dt).min(self.duration);
        let (p, dp) = min_jerk(self.t / self.duration);
        (
            self.from + (self.to - self.from) * p,
            (self.to - self.from) * (dp / self.duration),
        )
    }
}

/// `out = J# v = Jᵀ (J Jᵀ + λ² I)⁻¹ v` with the 3 linear rows of `jac`.
fn pinv_apply(jac: &Matrix6xX<f64>, v: &Vector3<f64>, damping: f64, out: &mut [f64]) {
    let n = out.len();
    let mut jjt = Matrix3::identity() * (damping * damping);
    for r in 0..3 {
        for c in 0..3 {
            jjt[(r, c)] += (0..n).map(|k| jac[(r, k)] * jac[(c, k)]).sum::<f64>();
        }
    }
    let y = jjt
        .cholesky()
        .map(|ch| ch.solve(v))
        .unwrap_or_else(Vector3::zeros);
    for (k, o) in out.iter_mut().enumerate() {
        *o = jac[(0, k)] * y.x + jac[(1, k)] * y.y + jac[(2, k)] * y.z;
    }
}

/// Closed-loop inverse kinematics on the position of one point, with a damped
/// pseudoinverse and a null-space posture term. Preallocated; no allocation per step.
pub struct Clik {
    frame: usize,
    jac: Matrix6xX<f64>,
    qd: Vec<f64>,
    z: Vec<f64>,
    proj: Vec<f64>,
}

/// Gains of [`Clik::step`].
#[derive(Clone, Copy, Debug)]
pub struct ClikGains {
    /// Cartesian error gain [1/s]
    pub clik: f64,
    /// null-space posture gain [1/s]
    pub posture: f64,
    /// pseudoinverse damping [m]
    pub damping: f64,
}

impl Clik {
    pub fn new(model: &Model, frame: usize) -> Clik {
        let n = model.nv();
        Clik {
            frame,
            jac: Data::jacobian_buffer(model),
            qd: vec![0.0; n],
            z: vec![0.0; n],
            proj: vec![0.0; n],
        }
    }

    pub fn frame(&self) -> usize {
        self.frame
    }

    /// Position of the point at `q` [m].
    pub fn position(&self, model: &Model, data: &mut Data, q: &[f64]) -> Vector3<f64> {
        if phri_model::forward_kinematics(model, data, q).is_err() {
            return Vector3::zeros();
        }
        phri_model::frame_placement(model, data, self.frame).p
    }

    /// One step: move `q_ref` so the point follows (`x_d`, `xd_d`), the
    /// redundancy pulling towards `posture`; velocities scaled uniformly into
    /// `vmax`. Returns the reference velocity [rad/s].
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        model: &Model,
        data: &mut Data,
        q_ref: &mut [f64],
        x_d: &Vector3<f64>,
        xd_d: &Vector3<f64>,
        dt: f64,
        gains: ClikGains,
        posture: &[f64],
        vmax: &[f64],
    ) -> &[f64] {
        let n = q_ref.len();
        let ok = phri_model::forward_kinematics(model, data, q_ref).is_ok()
            && phri_model::point_jacobian(
                model,
                data,
                self.frame,
                &Vector3::zeros(),
                &mut self.jac,
            )
            .is_ok();
        if !ok {
            self.qd.fill(0.0);
            return &self.qd;
        }
        let x = phri_model::frame_placement(model, data, self.frame).p;
        let v = xd_d + (x_d - x) * gains.clik;
        pinv_apply(&self.jac, &v, gains.damping, &mut self.qd);
        // null space: z − J#(J z)
        for k in 0..n {
            self.z[k] = gains.posture * (posture[k] - q_ref[k]);
        }
        let mut jz = Vector3::zeros();
        for r in 0..3 {
            jz[r] = (0..n).map(|k| self.jac[(r, k)] * self.z[k]).sum();
        }
        pinv_apply(&self.jac, &jz, gains.damping, &mut self.proj);
        for k in 0..n {
            self.qd[k] += self.z[k] - self.proj[k];
        }
        // uniform scaling into the velocity limits keeps the direction
        let scale = (0..n)
            .map(|k| {
                if self.qd[k].abs() > vmax[k] {
                    vmax[k] / self.qd[k].abs()
                } else {
                    1.0
                }
            })
            .fold(1.0, f64::min);
        for k in 0..n {
            self.qd[k] *= scale;
            q_ref[k] += self.qd[k] * dt;
        }
        &self.qd
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_jerk_is_smooth_at_the_ends() {
        assert_eq!(min_jerk(0.0), (0.0, 0.0));
        let (p, dp) = min_jerk(1.0);
        assert!((p - 1.0).abs() < 1e-15 && dp.abs() < 1e-12);
        // derivative matches finite differences
        let h = 1e-6;
        let u = 0.37;
        assert!(((min_jerk(u + h).0 - min_jerk(u - h).0) / (2.0 * h) - min_jerk(u).1).abs() < 1e-8);
    }

    #[test]
    fn path_is_continuous_and_cyclic() {
        let p = Path {
            waypoints: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
            ],
            segment_time: 1.0,
        };
        for k in 0..300 {
            let s = k as f64 * 0.01;
            let (a, _) = p.sample(s);
            let (b, _) = p.sample(s + 1e-6);
            assert!((a - b).norm() < 1e-4);
        }
        assert!((p.sample(1.0).0 - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        assert!((p.sample(3.0).0 - p.sample(0.0).0).norm() < 1e-12);
        assert_eq!(p.target_index(0.5), 1);
        assert_eq!(p.target_index(2.5), 0);
    }
}
