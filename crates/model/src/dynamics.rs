//! Rigid-body dynamics `M(q) q̈ + C(q,q̇) q̇ + g(q) = τ`, base-frame recursions.
//!
//! Every term is per actuated joint (`nv` of them). A mimic joint's body
//! moves with `S_i` scaled by its multiplier ([`crate::Data::s`]) and
//! projects onto its leader's column `idx_v`, so the terms are those of the
//! reduced model `Gᵀ (·) G`, as in Pinocchio.

use nalgebra::{DVector, Vector3};

use crate::cholesky::{cholesky_factor, cholesky_solve};
use crate::data::Data;
use crate::error::{check_len, ModelError};
use crate::kinematics::{fk_pass, inertia_pass, velocity_pass};
use crate::model::Model;
use crate::spatial::{crf, crm, icrf, Force, Inertia, Motion};

fn check_q_qd(model: &Model, q: &[f64], qd: &[f64]) -> Result<(), ModelError> {
    check_len("q", model.nv(), q.len())?;
    Ok(check_len("qd", model.nv(), qd.len())?)
}

/// Spatial acceleration of the base that stands in for gravity: `(0, −g)`.
#[inline]
fn base_acceleration(model: &Model) -> Motion {
    Motion::new(Vector3::zeros(), -model.gravity)
}

/// Recursive Newton-Euler: `τ = M q̈ + C q̇ + g` into `data.tau`.
pub fn rnea<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a DVector<f64>, ModelError> {
    check_q_qd(model, q, qd)?;
    check_len("qdd", model.nv(), qdd.len())?;
    fk_pass(model, data, q);
    inertia_pass(model, data);
    rnea_pass(model, data, qd, Some(qdd), base_acceleration(model));
    project(model, data, |d| &mut d.tau);
    for k in 0..model.nv() {
        data.tau[k] += model.armature[k] * qdd[k];
    }
    Ok(&data.tau)
}

/// `out_k = Σ_{i: idx_v(i) = k} S_iᵀ f_i` over every body (after [`rnea_pass`]):
/// joint-space torques from the subtree forces in `data.f`.
#[inline]
fn project(model: &Model, data: &mut Data, out: fn(&mut Data) -> &mut DVector<f64>) {
    out(data).fill(0.0);
    for (i, j) in model.joints.iter().enumerate() {
        let t = data.s[i].dot(&data.f[i]);
        out(data)[j.idx_v] += t;
    }
}

/// RNEA passes after FK and inertias (`qdd = None`: q̈ = 0, nothing allocated;
/// `a0`: the base's acceleration, `(0, −g)` for gravity); leaves subtree
/// forces in `data.f`, so that `τ_i = S_iᵀ f_i`.
fn rnea_pass(model: &Model, data: &mut Data, qd: &[f64], qdd: Option<&[f64]>, a0: Motion) {
    for &i in model.order() {
        let j = &model.joints[i];
        let (vp, ap) = match j.parent {
            Some(p) => (data.v[p], data.a[p]),
            None => (Motion::ZERO, a0),
        };
        let s = data.s[i];
        let k = j.idx_v;
        let v = vp + s.scale(qd[k]);
        let a = ap + s.scale(qdd.map_or(0.0, |x| x[k])) + v.cross_motion(&s.scale(qd[k]));
        let inertia = &data.inertia[i];
        data.v[i] = v;
        data.a[i] = a;
        data.f[i] = inertia.apply(&a) + v.cross_force(&inertia.apply(&v));
    }
    for &i in model.order().iter().rev() {
        if let Some(p) = model.joints[i].parent {
            let fi = data.f[i];
            data.f[p] += fi;
        }
    }
}

/// `C(q, q̇) q̇` into `data.c_qd` (RNEA without gravity and with `q̈ = 0`).
pub fn coriolis_times_qd<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, ModelError> {
    check_q_qd(model, q, qd)?;
    fk_pass(model, data, q);
    inertia_pass(model, data);
    // q̈ = 0 and no gravity
    rnea_pass(model, data, qd, None, Motion::ZERO);
    project(model, data, |d| &mut d.c_qd);
    Ok(&data.c_qd)
}

/// Gravity torque `g(q)` into `data.g`, O(n) from subtree masses.
pub fn gravity<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
) -> Result<&'a DVector<f64>, ModelError> {
    check_len("q", model.nv(), q.len())?;
    fk_pass(model, data, q);
    let a0 = -model.gravity;
    // subtree mass and first moment, kept in composite[i].m / .h
    for (i, j) in model.joints.iter().enumerate() {
        let c = data.body[i].apply(&j.com);
        data.composite[i].m = j.mass;
        data.composite[i].h = c * j.mass;
    }
    gravity_from_composite_mass(model, data, &a0);
    Ok(&data.g)
}

/// Accumulate subtree mass moments (in `data.composite[i].{m,h}`, per body on
/// entry) and evaluate `g_k = Σ_{i: idx_v(i) = k} S_iᵀ (h_i × a0, m_i a0)`.
#[inline]
fn gravity_from_composite_mass(model: &Model, data: &mut Data, a0: &Vector3<f64>) {
    data.g.fill(0.0);
    for &i in model.order().iter().rev() {
        let ci = data.composite[i];
        data.g[model.joints[i].idx_v] += data.s[i].dot(&Force {
            n: ci.h.cross(a0),
            f: a0 * ci.m,
        });
        if let Some(p) = model.joints[i].parent {
            data.composite[p].m += ci.m;
            data.composite[p].h += ci.h;
        }
    }
}

/// Composite rigid-body algorithm: `M(q)` into `data.m` (both triangles).
pub fn crba<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
) -> Result<&'a nalgebra::DMatrix<f64>, ModelError> {
    check_len("q", model.nv(), q.len())?;
    fk_pass(model, data, q);
    inertia_pass(model, data);
    crba_pass(model, data);
    Ok(&data.m)
}

/// `M = Σ` over body pairs `j ⪯ i` (j an ancestor of or equal to i) of
/// `S_jᵀ I^C_i S_i`, into row and column `idx_v` of each: entries of joints on
/// different branches stay zero, a mimic joint adds to its leader's.
fn crba_pass(model: &Model, data: &mut Data) {
    data.composite.copy_from_slice(&data.inertia);
    for &i in model.order().iter().rev() {
        if let Some(p) = model.joints[i].parent {
            let ci = data.composite[i];
            data.composite[p] += ci;
        }
    }
    data.m.fill(0.0);
    for (i, ji) in model.joints.iter().enumerate() {
        let f = data.composite[i].apply(&data.s[i]);
        let ci = ji.idx_v;
        data.m[(ci, ci)] += data.s[i].dot(&f);
        let mut k = ji.parent;
        while let Some(j) = k {
            let mij = data.s[j].dot(&f);
            let cj = model.joints[j].idx_v;
            data.m[(ci, cj)] += mij;
            data.m[(cj, ci)] += mij;
            k = model.joints[j].parent;
        }
    }
    for k in 0..model.nv() {
        data.m[(k, k)] += model.armature[k];
    }
}

/// Christoffel-consistent Coriolis matrix `C(q, q̇)` into `data.c`
/// (Echeandia & Wensing 2021, composite body-level Coriolis matrices), so
/// that `Ṁ = C + Cᵀ` and `C q̇` equals the RNEA bias without gravity.
pub fn coriolis_matrix<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a nalgebra::DMatrix<f64>, ModelError> {
    check_q_qd(model, q, qd)?;
    fk_pass(model, data, q);
    inertia_pass(model, data);
    velocity_pass(model, data, qd);
    for i in 0..model.joints.len() {
        let ii = data.inertia[i].to_matrix();
        let v = data.v[i];
        let iv = data.inertia[i].apply(&v);
        data.ic6[i] = ii;
        data.bc6[i] = (crf(&v) * ii + icrf(&iv) - ii * crm(&v)) * 0.5;
    }
    for &i in model.order().iter().rev() {
        if let Some(p) = model.joints[i].parent {
            let (ic, bc) = (data.ic6[i], data.bc6[i]);
            data.ic6[p] += ic;
            data.bc6[p] += bc;
        }
    }
    // body pairs j ⪯ i, into rows and columns idx_v (a mimic joint adds to its leader's)
    data.c.fill(0.0);
    for (i, ji) in model.joints.iter().enumerate() {
        let si = data.s[i].to_vector();
        let sdi = data.s_dot[i].to_vector();
        let ic = &data.ic6[i];
        let bc = &data.bc6[i];
        // column i, rows j ≺ i:  C_ji = S_jᵀ (I^C_i Ṡ_i + B^C_i S_i)
        let col = ic * sdi + bc * si;
        // row i, columns j ⪯ i:  C_ij = (I^C_i S_i)ᵀ Ṡ_j + (B^C_iᵀ S_i)ᵀ S_j
        let u1 = ic * si;
        let u2 = bc.transpose() * si;
        let ci = ji.idx_v;
        data.c[(ci, ci)] += u1.dot(&sdi) + u2.dot(&si);
        let mut k = ji.parent;
        while let Some(j) = k {
            let sj = data.s[j].to_vector();
            let sdj = data.s_dot[j].to_vector();
            let cj = model.joints[j].idx_v;
            data.c[(cj, ci)] += sj.dot(&col);
            data.c[(ci, cj)] += u1.dot(&sdj) + u2.dot(&sj);
            k = model.joints[j].parent;
        }
    }
    Ok(&data.c)
}

/// Generalized momentum `p = M(q) q̇` into `data.p`, O(n).
pub fn momentum<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, ModelError> {
    residual_terms(model, data, q, qd)?;
    Ok(&data.p)
}

/// `C(q, q̇)ᵀ q̇` into `data.ct_qd`, O(n).
pub fn coriolis_transpose_times_qd<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, ModelError> {
    residual_terms(model, data, q, qd)?;
    Ok(&data.ct_qd)
}

/// Everything the momentum residual needs per cycle, in O(n) recursions and
/// without forming any matrix: `data.p = M q̇`, `data.ct_qd = Cᵀ q̇`,
/// `data.g = g(q)` and `data.residual_bias = Cᵀ q̇ − g`.
///
/// With body momenta `h_k = I_k v_k` summed over subtrees (`H_i`):
/// `p_i = S_iᵀ H_i` and `(Cᵀ q̇)_i = Ṡ_iᵀ H_i = −S_iᵀ (v_i ×* H_i)`.
pub fn residual_terms(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<(), ModelError> {
    check_q_qd(model, q, qd)?;
    fk_pass(model, data, q);
    for &i in model.order() {
        let j = &model.joints[i];
        let vp = match j.parent {
            Some(p) => data.v[p],
            None => Motion::ZERO,
        };
        let v = vp + data.s[i].scale(qd[j.idx_v]);
        data.v[i] = v;
        // momentum of body i about the base origin without forming its inertia:
        // linear m v_c, angular R I_c Rᵀ ω + c × m v_c
        let b = &data.body[i];
        let c = b.apply(&j.com);
        let lin = v.velocity_at(&c) * j.mass;
        let ang = b.r * (j.inertia_com * (b.r.transpose() * v.w)) + c.cross(&lin);
        data.f[i] = Force { n: ang, f: lin };
        data.composite[i].m = j.mass;
        data.composite[i].h = c * j.mass;
    }
    let a0 = -model.gravity;
    data.p.fill(0.0);
    data.ct_qd.fill(0.0);
    data.g.fill(0.0);
    for &i in model.order().iter().rev() {
        let h = data.f[i];
        let s = &data.s[i];
        let k = model.joints[i].idx_v;
        data.p[k] += s.dot(&h);
        data.ct_qd[k] -= s.dot(&data.v[i].cross_force(&h));
        let ci = data.composite[i];
        data.g[k] += s.dot(&Force {
            n: ci.h.cross(&a0),
            f: a0 * ci.m,
        });
        if let Some(p) = model.joints[i].parent {
            data.f[p] += h;
            data.composite[p].m += ci.m;
            data.composite[p].h += ci.h;
        }
    }
    for k in 0..model.nv() {
        data.p[k] += model.armature[k] * qd[k];
        data.residual_bias[k] = data.ct_qd[k] - data.g[k];
    }
    Ok(())
}

/// Every term the torque law needs at one state, in one pass of the
/// kinematics, as Pinocchio's `computeAllTerms`: the body placements and
/// motion subspaces (so [`crate::frame_placement`] and
/// [`crate::point_jacobian`] may follow without another
/// [`crate::forward_kinematics`]), `M(q)` into `data.m`, `g(q)` into `data.g`
/// and the bias `C(q, q̇) q̇ + g(q)` into `data.tau`. Gravity comes from the
/// subtree masses and first moments the CRBA has summed anyway. Allocates
/// nothing.
pub fn all_terms(model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) -> Result<(), ModelError> {
    check_q_qd(model, q, qd)?;
    fk_pass(model, data, q);
    inertia_pass(model, data);
    crba_pass(model, data);
    // data.composite[i] now holds subtree i's inertia: its m and h are the
    // subtree mass and first moment gravity needs
    let a0 = -model.gravity;
    data.g.fill(0.0);
    for (i, j) in model.joints.iter().enumerate() {
        let ci = &data.composite[i];
        data.g[j.idx_v] += data.s[i].dot(&Force {
            n: ci.h.cross(&a0),
            f: a0 * ci.m,
        });
    }
    rnea_pass(model, data, qd, None, base_acceleration(model));
    project(model, data, |d| &mut d.tau);
    Ok(())
}

/// Forward dynamics `q̈ = M⁻¹ (τ − C q̇ − g)` into `data.qdd` (CRBA, RNEA and
/// an in-place Cholesky solve; nothing allocated).
pub fn forward_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> Result<&'a DVector<f64>, ModelError> {
    check_q_qd(model, q, qd)?;
    check_len("tau", model.nv(), tau.len())?;
    fk_pass(model, data, q);
    inertia_pass(model, data);
    crba_pass(model, data);
    // bias = RNEA(q, q̇, 0) with gravity
    rnea_pass(model, data, qd, None, base_acceleration(model));
    data.qdd.copy_from_slice(tau);
    for (i, j) in model.joints.iter().enumerate() {
        data.qdd[j.idx_v] -= data.s[i].dot(&data.f[i]);
    }
    cholesky_solve_in_place(data)?;
    Ok(&data.qdd)
}

/// Solve `M x = data.qdd` in place with a Cholesky factor in `data.chol`.
fn cholesky_solve_in_place(data: &mut Data) -> Result<(), ModelError> {
    data.chol.copy_from(&data.m);
    cholesky_factor(data.chol.as_view_mut(), 0.0).map_err(|_| ModelError::NotPositiveDefinite)?;
    cholesky_solve(data.chol.as_view(), data.qdd.as_mut_slice());
    Ok(())
}

/// Kinetic energy `½ q̇ᵀ M q̇` \[J\].
pub fn kinetic_energy(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<f64, ModelError> {
    residual_terms(model, data, q, qd)?;
    Ok(0.5 * data.p.iter().zip(qd).map(|(p, v)| p * v).sum::<f64>())
}

/// Potential energy `−Σ m_k gᵀ c_k` \[J\] (zero at the base origin).
pub fn potential_energy(model: &Model, data: &mut Data, q: &[f64]) -> Result<f64, ModelError> {
    check_len("q", model.nv(), q.len())?;
    fk_pass(model, data, q);
    Ok(model
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| -j.mass * model.gravity.dot(&data.body[i].apply(&j.com)))
        .sum())
}

/// Total spatial inertia of the robot's moving bodies (after any pass that ran FK).
pub fn total_inertia(model: &Model, data: &mut Data) -> Inertia {
    inertia_pass(model, data);
    let mut sum = Inertia::ZERO;
    for i in 0..model.joints.len() {
        sum += data.inertia[i];
    }
    sum
}
