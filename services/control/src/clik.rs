//! Closed-loop inverse kinematics (CLIK) on the position of one point: a
//! damped pseudoinverse of the point's linear Jacobian, the redundancy
//! pulling towards a posture. What resolves the task's Cartesian reference
//! when the controller runs without perception (with perception, SNS does:
//! [`crate::avoidance`]).

use nalgebra::{DMatrixView, DMatrixViewMut, Matrix6xX, Vector3};
use phri_model::{Data, Model, ModelError};

/// `out = J# v = Jᵀ (J Jᵀ + λ² I)⁻¹ v` with the 3 linear rows of `jac` and
/// damping `λ`; zero if `J Jᵀ + λ² I` is not positive definite.
fn pinv_apply(jac: &Matrix6xX<f64>, v: &Vector3<f64>, damping: f64, out: &mut [f64]) {
    let n = out.len();
    // J Jᵀ + λ² I, 3×3 column-major on the stack, factored in place
    let mut jjt = [0.0f64; 9];
    for r in 0..3 {
        for c in 0..3 {
            let diag = if r == c { damping * damping } else { 0.0 };
            jjt[c * 3 + r] = diag + (0..n).map(|k| jac[(r, k)] * jac[(c, k)]).sum::<f64>();
        }
    }
    let mut y = [v.x, v.y, v.z];
    if phri_model::cholesky_factor(DMatrixViewMut::from_slice(&mut jjt, 3, 3), 0.0).is_ok() {
        phri_model::cholesky_solve(DMatrixView::from_slice(&jjt, 3, 3), &mut y);
    } else {
        y = [0.0; 3];
    }
    for (k, o) in out.iter_mut().enumerate() {
        *o = jac[(0, k)] * y[0] + jac[(1, k)] * y[1] + jac[(2, k)] * y[2];
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
    /// pseudoinverse damping \[m\]
    pub damping: f64,
}

impl Clik {
    /// CLIK of the origin of `frame`.
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

    /// The frame whose origin is the point.
    pub fn frame(&self) -> usize {
        self.frame
    }

    /// Position of the point at `q` \[m\], base frame.
    pub fn position(
        &self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
    ) -> Result<Vector3<f64>, ModelError> {
        phri_model::forward_kinematics(model, data, q)?;
        Ok(phri_model::frame_placement(model, data, self.frame).p)
    }

    /// One step: move `q_ref` so the point follows (`x_d` \[m\], `xd_d` [m/s],
    /// base frame), the redundancy pulling towards `posture`; velocities
    /// scaled uniformly into `vmax`. Returns the reference velocity [rad/s].
    /// When the model refuses `q_ref` the velocity is zero, `q_ref` is left
    /// alone and the error returned.
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
    ) -> Result<&[f64], ModelError> {
        let n = q_ref.len();
        let kinematics = phri_model::forward_kinematics(model, data, q_ref).and_then(|_| {
            phri_model::point_jacobian(model, data, self.frame, &Vector3::zeros(), &mut self.jac)
        });
        if let Err(e) = kinematics {
            self.qd.fill(0.0);
            return Err(e);
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
        Ok(&self.qd)
    }

    /// The reference velocity of the last step [rad/s].
    pub fn velocity(&self) -> &[f64] {
        &self.qd
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damped_pseudoinverse_solves_the_normal_equations() {
        let mut jac = Matrix6xX::<f64>::zeros(4);
        for k in 0..4 {
            for r in 0..3 {
                jac[(r, k)] = ((r * 5 + k * 3) % 7) as f64 - 3.0;
            }
        }
        let v = Vector3::new(0.3, -0.2, 0.5);
        let lambda = 0.1;
        let mut out = [0.0; 4];
        pinv_apply(&jac, &v, lambda, &mut out);
        // out = Jᵀ y with (J Jᵀ + λ² I) y = v
        let j = jac.rows(0, 3);
        let a = j * j.transpose() + nalgebra::Matrix3::identity() * (lambda * lambda);
        let y = a.try_inverse().unwrap() * v;
        let expected = j.transpose() * y;
        for k in 0..4 {
            assert!((out[k] - expected[k]).abs() < 1e-12, "{out:?} {expected}");
        }
    }
}
