//! Contact forces from the residual and the contact points (paper Sect. VI-B):
//!
//! `r ≈ τ_ext = Σ_k J_kᵀ(q) F_k` (eq. 21), so with the contact points known
//! (from depth) the forces follow by pseudoinversion, one contact (eq. 22) or
//! several stacked (eq. 23): `F̂ = (J_cᵀ)^# r`, `J_c = [J_1; J_2]` the linear
//! rows of the contact points' Jacobians (3k × n). Damped:
//! `F̂ = (J_c J_cᵀ + λ² I)⁻¹ J_c r`.
//!
//! A force component in the null space of `J_kᵀ` does no work on the joints
//! and cannot be recovered: a contact on links 1-2 of a 7-joint arm (whose
//! Jacobian has one or two non-zero columns), or contacts whose stacked
//! Jacobian lost rank, are flagged not observable rather than guessed
//! ([`ForceEstimate::observable`]). What the estimate does not explain,
//! `r − J_cᵀ F̂` ([`ForceEstimate::unexplained`]), is the residual of every
//! other contact: a collision elsewhere shows there.
//!
//! Forces are those the human applies to the robot \[N\], base frame.
//! Allocation-free after construction.

use nalgebra::{DMatrixViewMut, Matrix3, Matrix6xX, Vector3};
use phri_model::{check_len, cholesky_factor, cholesky_solve, Data, LengthError, Model, Placement};

/// Contacts estimated at once (eq. 23 with two).
pub const MAX_FORCE_CONTACTS: usize = 2;

/// Joints whose unexplained residual [`ForceEstimate::left`] keeps, one by one.
pub const MAX_JOINTS: usize = 16;

/// Why an estimate could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ForceError {
    /// `q` or `r` of the wrong length
    #[error(transparent)]
    Length(#[from] LengthError),
    /// a kinematics call on the model failed (e.g. a contact's frame unknown)
    #[error(transparent)]
    Model(#[from] phri_model::ModelError),
    /// more contacts than [`MAX_FORCE_CONTACTS`]: how many were given
    #[error("at most {MAX_FORCE_CONTACTS} contacts, got {0}")]
    TooMany(usize),
    /// the named input holds a NaN or an infinity
    #[error("{0}: not a finite number")]
    NotFinite(&'static str),
    /// a frame index the model does not have
    #[error("no frame {0} in the model")]
    UnknownFrame(usize),
}

/// A contact point: a point fixed on a link frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// the link frame (`Model::frame_id`)
    pub frame: usize,
    /// the point \[m\], in that frame
    pub point: Vector3<f64>,
}

/// The estimate of one call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceEstimate {
    /// contacts estimated (the first `n` entries are meaningful)
    pub n: usize,
    /// force the human applies at each contact \[N\], base frame
    pub forces: [Vector3<f64>; MAX_FORCE_CONTACTS],
    /// each contact point \[m\], base frame
    pub points: [Vector3<f64>; MAX_FORCE_CONTACTS],
    /// the residual sees every component of the force (false: a contact on
    /// links 1-2, or rank loss of the stacked Jacobian; `forces` then holds
    /// only what the damped solution recovers)
    pub observable: [bool; MAX_FORCE_CONTACTS],
    /// ‖r − J_cᵀ F̂‖: the residual these contacts do not explain \[Nm\]
    pub unexplained: f64,
    /// `r − J_cᵀ F̂` joint by joint \[Nm\] (the first `min(n, MAX_JOINTS)` entries)
    pub left: [f64; MAX_JOINTS],
}

/// Relative size of the smallest singular value² of a contact's Jacobian
/// (linear rows) below which its force is not observable.
const OBSERVABLE_RATIO: f64 = 1e-4;

/// The estimator, with its workspace.
pub struct ForceEstimator {
    model: Model,
    data: Data,
    jac: [Matrix6xX<f64>; MAX_FORCE_CONTACTS],
    /// damping λ [m]
    damping: f64,
    last: ForceEstimate,
    /// the joints `data` holds the kinematics of, when `kinematics_valid`
    kinematics_of: Vec<f64>,
    kinematics_valid: bool,
}

impl ForceEstimator {
    /// An estimator for `model` with pseudoinverse damping `damping` \[m\].
    pub fn new(model: Model, damping: f64) -> ForceEstimator {
        ForceEstimator {
            data: Data::new(&model),
            jac: [Data::jacobian_buffer(&model), Data::jacobian_buffer(&model)],
            damping: if damping.is_finite() {
                damping.abs()
            } else {
                0.0
            },
            last: ForceEstimate {
                n: 0,
                forces: [Vector3::zeros(); MAX_FORCE_CONTACTS],
                points: [Vector3::zeros(); MAX_FORCE_CONTACTS],
                observable: [false; MAX_FORCE_CONTACTS],
                unexplained: 0.0,
                left: [0.0; MAX_JOINTS],
            },
            kinematics_of: vec![0.0; model.nv()],
            kinematics_valid: false,
            model,
        }
    }

    /// Forward kinematics at `q` (checked for length), unless `data` holds
    /// them already: several estimates and placements at the same joints in
    /// one period cost one.
    fn kinematics(&mut self, q: &[f64]) -> Result<(), ForceError> {
        if self.kinematics_valid && self.kinematics_of == q {
            return Ok(());
        }
        self.kinematics_valid = false;
        phri_model::forward_kinematics(&self.model, &mut self.data, q)?;
        self.kinematics_of.copy_from_slice(q);
        self.kinematics_valid = true;
        Ok(())
    }

    /// Take the kinematics at joints `q` \[rad\] that `from` holds (a
    /// workspace of the same model after [`phri_model::all_terms`] or
    /// [`phri_model::forward_kinematics`] at `q`), so the estimates and
    /// placements of this period cost no pass of their own. A workspace of
    /// another size is ignored (returns false): the estimator computes its own.
    pub fn share_kinematics(&mut self, from: &Data, q: &[f64]) -> bool {
        if from.body.len() != self.data.body.len() || q.len() != self.kinematics_of.len() {
            return false;
        }
        self.data.body.copy_from_slice(&from.body);
        self.data.s.copy_from_slice(&from.s);
        self.kinematics_of.copy_from_slice(q);
        self.kinematics_valid = true;
        true
    }

    /// The robot model the estimator runs on.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The forces at `contacts` explaining the residual `r` \[Nm\] at joints `q`.
    pub fn estimate(
        &mut self,
        q: &[f64],
        r: &[f64],
        contacts: &[ContactPoint],
    ) -> Result<&ForceEstimate, ForceError> {
        let n = self.model.nv();
        check_len("q", n, q.len())?;
        check_len("r", n, r.len())?;
        if contacts.len() > MAX_FORCE_CONTACTS {
            return Err(ForceError::TooMany(contacts.len()));
        }
        if q.iter().chain(r).any(|x| !x.is_finite()) {
            return Err(ForceError::NotFinite("q or r"));
        }
        self.kinematics(q)?;
        let k = contacts.len();
        let mut out = ForceEstimate {
            n: k,
            forces: [Vector3::zeros(); MAX_FORCE_CONTACTS],
            points: [Vector3::zeros(); MAX_FORCE_CONTACTS],
            observable: [true; MAX_FORCE_CONTACTS],
            unexplained: r.iter().map(|x| x * x).sum::<f64>().sqrt(),
            left: [0.0; MAX_JOINTS],
        };
        for (l, x) in out.left.iter_mut().zip(r) {
            *l = *x;
        }
        if k == 0 {
            self.last = out;
            return Ok(&self.last);
        }
        for (i, c) in contacts.iter().enumerate() {
            phri_model::point_jacobian(
                &self.model,
                &self.data,
                c.frame,
                &c.point,
                &mut self.jac[i],
            )?;
            out.points[i] =
                phri_model::frame_placement(&self.model, &self.data, c.frame).apply(&c.point);
            // observability of this contact alone: the 3×3 Gram J_k J_kᵀ
            let mut g = Matrix3::<f64>::zeros();
            for a in 0..3 {
                for b in 0..3 {
                    g[(a, b)] = (0..n)
                        .map(|j| self.jac[i][(a, j)] * self.jac[i][(b, j)])
                        .sum();
                }
            }
            let eig: Vector3<f64> = g.symmetric_eigenvalues();
            let (lo, hi) = (eig.min(), eig.max());
            if !(hi > 0.0 && lo > OBSERVABLE_RATIO * hi) {
                out.observable[i] = false;
            }
        }
        // stacked normal equations: (J_c J_cᵀ + λ² I) F = J_c r, m = 3k
        let m = 3 * k;
        let mut gram = [0.0; 36];
        let mut rhs = [0.0; 6];
        let row = |jac: &[Matrix6xX<f64>; 2], a: usize, j: usize| jac[a / 3][(a % 3, j)];
        let mut largest = 0.0f64;
        for a in 0..m {
            for b in 0..m {
                gram[a * m + b] = (0..n)
                    .map(|j| row(&self.jac, a, j) * row(&self.jac, b, j))
                    .sum();
            }
            largest = largest.max(gram[a * m + a]);
            gram[a * m + a] += self.damping * self.damping;
            rhs[a] = (0..n).map(|j| row(&self.jac, a, j) * r[j]).sum();
        }
        // rank of the stacked Jacobian: a factor without damping must exist
        let mut undamped = gram;
        for a in 0..m {
            undamped[a * m + a] -= self.damping * self.damping;
        }
        if cholesky_factor(
            DMatrixViewMut::from_slice(&mut undamped[..m * m], m, m),
            largest * OBSERVABLE_RATIO,
        )
        .is_err()
        {
            for o in out.observable[..k].iter_mut() {
                *o = false;
            }
        }
        if cholesky_factor(DMatrixViewMut::from_slice(&mut gram[..m * m], m, m), 0.0).is_ok() {
            cholesky_solve(
                nalgebra::DMatrixView::from_slice(&gram[..m * m], m, m),
                &mut rhs[..m],
            );
            for i in 0..k {
                out.forces[i] = Vector3::new(rhs[3 * i], rhs[3 * i + 1], rhs[3 * i + 2]);
            }
        } else {
            // no damping and a singular Jacobian: nothing is recovered
            rhs = [0.0; 6];
            for o in out.observable[..k].iter_mut() {
                *o = false;
            }
        }
        let mut unexplained = 0.0;
        for j in 0..n {
            let explained: f64 = (0..m).map(|a| row(&self.jac, a, j) * rhs[a]).sum();
            let e = r[j] - explained;
            if j < MAX_JOINTS {
                out.left[j] = e;
            }
            unexplained += e * e;
        }
        out.unexplained = unexplained.sqrt();
        self.last = out;
        Ok(&self.last)
    }

    /// The placement of `frame` in the base frame at joints `q` \[rad\].
    pub fn placement(&mut self, q: &[f64], frame: usize) -> Result<Placement, ForceError> {
        check_len("q", self.model.nv(), q.len())?;
        if q.iter().any(|x| !x.is_finite()) {
            return Err(ForceError::NotFinite("q"));
        }
        self.kinematics(q)?;
        if frame >= self.model.frames.len() {
            return Err(ForceError::UnknownFrame(frame));
        }
        Ok(phri_model::frame_placement(&self.model, &self.data, frame))
    }

    /// The origin of `frame` \[m\], base frame, at the joints of the last
    /// [`ForceEstimator::estimate`] or [`ForceEstimator::placement`] (the
    /// origin before the first).
    pub fn frame_origin(&self, frame: usize) -> Vector3<f64> {
        if frame >= self.model.frames.len() {
            return Vector3::zeros();
        }
        phri_model::frame_placement(&self.model, &self.data, frame).apply(&Vector3::zeros())
    }

    /// The kinematics of the last [`ForceEstimator::estimate`] or
    /// [`ForceEstimator::placement`] (body placements, base frame).
    pub fn data(&self) -> &Data {
        &self.data
    }

    /// The last estimate.
    pub fn last(&self) -> &ForceEstimate {
        &self.last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lwr4() -> Model {
        Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap()
    }

    /// τ_ext = Σ J_kᵀ F_k for forces at `contacts`.
    fn tau_ext(model: &Model, q: &[f64], contacts: &[(ContactPoint, Vector3<f64>)]) -> Vec<f64> {
        let mut d = Data::new(model);
        phri_model::forward_kinematics(model, &mut d, q).unwrap();
        let mut j = Data::jacobian_buffer(model);
        let mut tau = vec![0.0; model.nv()];
        for (c, f) in contacts {
            phri_model::point_jacobian(model, &d, c.frame, &c.point, &mut j).unwrap();
            for (i, t) in tau.iter_mut().enumerate() {
                *t += (0..3).map(|a| j[(a, i)] * f[a]).sum::<f64>();
            }
        }
        tau
    }

    #[test]
    fn forces_are_recovered_where_observable_and_flagged_where_not() {
        let model = lwr4();
        let q = [0.1, -0.4, 0.2, 1.6, -0.3, -0.7, 0.4];
        let mut est = ForceEstimator::new(model.clone(), 1e-3);
        let at = |link: &str, p: [f64; 3]| ContactPoint {
            frame: model.frame_id(link).unwrap(),
            point: Vector3::from(p),
        };
        let f = Vector3::new(20.0, -10.0, 15.0);
        for link in ["lwr_link_7", "lwr_link_6", "lwr_link_4"] {
            let c = at(link, [0.0, 0.05, 0.03]);
            let r = tau_ext(&model, &q, &[(c, f)]);
            let e = *est.estimate(&q, &r, &[c]).unwrap();
            assert!(e.observable[0], "{link}");
            let err = (e.forces[0] - f).norm() / f.norm();
            assert!(err < 1e-3, "{link}: {} vs {f}: {err}", e.forces[0]);
            assert!(e.unexplained < 1e-3, "{link}: {}", e.unexplained);
        }
        // two contacts at once (eq. 23)
        // off the wrist axis, so that joint 7 sees it too
        let (c1, c2) = (
            at("lwr_link_7", [0.0, 0.06, 0.04]),
            at("lwr_link_4", [0.0, -0.1, 0.0]),
        );
        let f2 = Vector3::new(-5.0, 12.0, 3.0);
        let r = tau_ext(&model, &q, &[(c1, f), (c2, f2)]);
        let e = *est.estimate(&q, &r, &[c1, c2]).unwrap();
        assert!(e.observable[0] && e.observable[1]);
        assert!(
            (e.forces[0] - f).norm() / f.norm() < 1e-2,
            "{}",
            e.forces[0]
        );
        assert!(
            (e.forces[1] - f2).norm() / f2.norm() < 1e-2,
            "{}",
            e.forces[1]
        );
        // a contact on link 2: two joints cannot see a 3-D force
        let c = at("lwr_link_2", [0.0, 0.1, 0.0]);
        let r = tau_ext(&model, &q, &[(c, f)]);
        let e = *est.estimate(&q, &r, &[c]).unwrap();
        assert!(!e.observable[0]);
        // what the estimate does not explain: a push elsewhere
        // (a hand-held contact alone leaves < 1e-3 Nm, see above)
        let c = at("lwr_link_7", [0.0, 0.06, 0.04]);
        let r = tau_ext(
            &model,
            &q,
            &[(c, f), (at("lwr_link_3", [0.0, 0.1, 0.1]), f2 * 3.0)],
        );
        let e = *est.estimate(&q, &r, &[c]).unwrap();
        assert!(e.unexplained > 0.5, "an elbow hit shows: {}", e.unexplained);
        // the kinematics follow the joints: elsewhere and back, the same estimate
        let q2 = [0.3, -0.2, 0.1, 1.2, 0.2, -0.5, 0.0];
        let before = est.estimate(&q, &r, &[c]).unwrap().forces[0];
        let there = est.placement(&q2, c.frame).unwrap().p;
        assert!((there - est.placement(&q, c.frame).unwrap().p).norm() > 1e-3);
        est.estimate(&q2, &r, &[c]).unwrap();
        assert_eq!(est.estimate(&q, &r, &[c]).unwrap().forces[0], before);
        // bad inputs are errors
        assert!(est.estimate(&q[..3], &r, &[c]).is_err());
        assert!(est.estimate(&q, &[f64::NAN; 7], &[c]).is_err());
        assert!(est.estimate(&q, &r, &[c, c, c]).is_err());
    }
}
