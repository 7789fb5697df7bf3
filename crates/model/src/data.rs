//! The preallocated workspace the algorithms write into.

use nalgebra::{DMatrix, DVector, Matrix6, Matrix6xX};

use crate::model::{Model, Placement};
use crate::spatial::{Force, Inertia, Motion};

/// Workspace for one [`Model`]: every buffer an algorithm needs, allocated
/// once. Quantities are in the base frame; per-body arrays are indexed by joint
/// (all of [`Model::joints`], mimic ones included), joint-space arrays have
/// [`Model::nv`] entries.
#[derive(Clone, Debug)]
pub struct Data {
    /// body frames in the base frame (after forward kinematics)
    pub body: Vec<Placement>,
    /// motion subspace `S_i` of each joint, base frame: body `i`'s spatial
    /// velocity per unit velocity of its column `idx_v` (for a mimic joint,
    /// multiplier × its own axis)
    pub s: Vec<Motion>,
    /// `Ṡ_i = v_i × S_i`, base frame
    pub s_dot: Vec<Motion>,
    /// body spatial velocities, base frame
    pub v: Vec<Motion>,
    /// body spatial accelerations, base frame
    pub a: Vec<Motion>,
    /// body forces and subtree force sums, base frame
    pub f: Vec<Force>,
    /// body spatial inertias, base frame
    pub inertia: Vec<Inertia>,
    /// composite (subtree) inertias, base frame
    pub composite: Vec<Inertia>,
    /// 6×6 composite inertias and composite body-Coriolis matrices
    pub(crate) ic6: Vec<Matrix6<f64>>,
    pub(crate) bc6: Vec<Matrix6<f64>>,
    /// joint-space inertia matrix `M(q)` [kg m² / kg]
    pub m: DMatrix<f64>,
    /// Coriolis matrix `C(q, q̇)` (Christoffel-consistent)
    pub c: DMatrix<f64>,
    /// gravity torque `g(q)` \[Nm\]
    pub g: DVector<f64>,
    /// inverse dynamics result `τ` \[Nm\]
    pub tau: DVector<f64>,
    /// generalized momentum `p = M q̇`
    pub p: DVector<f64>,
    /// `C(q, q̇) q̇` \[Nm\]
    pub c_qd: DVector<f64>,
    /// `C(q, q̇)ᵀ q̇` \[Nm\]
    pub ct_qd: DVector<f64>,
    /// `Cᵀ q̇ − g`, the residual's integrand besides `τ` and `r` \[Nm\]
    pub residual_bias: DVector<f64>,
    /// forward dynamics result `q̈`
    pub qdd: DVector<f64>,
    /// Cholesky factor workspace
    pub(crate) chol: DMatrix<f64>,
}

impl Data {
    /// Allocate the workspace for `model`.
    pub fn new(model: &Model) -> Data {
        let n = model.nv();
        let bodies = model.joints.len();
        Data {
            body: vec![Placement::IDENTITY; bodies],
            s: vec![Motion::ZERO; bodies],
            s_dot: vec![Motion::ZERO; bodies],
            v: vec![Motion::ZERO; bodies],
            a: vec![Motion::ZERO; bodies],
            f: vec![Force::ZERO; bodies],
            inertia: vec![Inertia::ZERO; bodies],
            composite: vec![Inertia::ZERO; bodies],
            ic6: vec![Matrix6::zeros(); bodies],
            bc6: vec![Matrix6::zeros(); bodies],
            m: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            tau: DVector::zeros(n),
            p: DVector::zeros(n),
            c_qd: DVector::zeros(n),
            ct_qd: DVector::zeros(n),
            residual_bias: DVector::zeros(n),
            qdd: DVector::zeros(n),
            chol: DMatrix::zeros(n, n),
        }
    }

    /// A 6×n Jacobian buffer for [`crate::point_jacobian`].
    pub fn jacobian_buffer(model: &Model) -> Matrix6xX<f64> {
        Matrix6xX::zeros(model.nv())
    }

    /// Placement of a body (`None` = root) in the base frame.
    #[inline]
    pub fn body_placement(&self, body: Option<usize>) -> Placement {
        match body {
            Some(b) => self.body[b],
            None => Placement::IDENTITY,
        }
    }
}
