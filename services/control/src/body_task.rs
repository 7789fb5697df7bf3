//! Body control points that move away (issue 14, beyond the paper's eq. 20):
//! each body point's repulsion as a task of lower priority, in the null
//! space of the end effector's task (SNS with a task hierarchy, Flacco et
//! al. T-RO 2015, Sect. V).
//!
//! Eq. 20 only slows the joint motions that bring a body point closer to
//! its obstacle; a hand moving into a still elbow still reaches it. Here,
//! after SNS has solved the end effector's task `q̇₁` within the bounds,
//! every body point `k` with a repulsive vector `V_k` asks to move away
//! from its obstacle at `g ‖V_k‖` (`g` = `[control] body_repulsion_gain`):
//! one row `a_k = u_kᵀ J_k` (`u_k = V_k/‖V_k‖`, `J_k` the point's linear
//! Jacobian) with the rate still missing, `e_k = g ‖V_k‖ − a_k q̇₁` (a point
//! already moving away fast enough asks nothing). The correction
//!
//! `Δ = P z`, `z = argmin ‖A P z − e‖² + μ² ‖z‖²`,
//!
//! lies in the null space of the end effector's task and of the joints SNS
//! saturated: `P` projects onto `{y : J_e y = 0, y_S = 0}`, so the end
//! effector's velocity and the saturated joints are exactly unchanged. The
//! damping `μ` keeps the correction bounded near singular rows. `q̇₁ + t Δ`
//! then stays inside the bounds with the largest `t ∈ [0, 1]`; when a joint
//! limits `t`, it is held too and the correction is computed again (at
//! most [`MAX_PASSES`] passes), keeping the pass that leaves the least of
//! `e` unanswered.
//!
//! Below it, the posture: while no body point asks to move away, the null
//! space pulls the arm back toward the null-space posture,
//! `Δ = P K_p (q_posture − q)` (the same gain as CLIK's `posture_gain`;
//! scaled into the bounds as above), so that an arm that moved away from a
//! person returns to its working posture instead of drifting.
//!
//! No allocation after [`BodyTask::new`].

use nalgebra::{DMatrix, Dim, Matrix, RawStorage, Vector3};
use phri_model::{cholesky_factor, cholesky_solve};

/// Passes of the hold-and-recompute loop (the first included).
pub const MAX_PASSES: usize = 3;

/// Damping `μ` of the least squares [m/rad]: a row whose joints move its
/// point by less than about this per radian gets a damped answer.
const DAMPING: f64 = 0.05;

/// The rows and buffers of the body points' task, preallocated.
#[derive(Clone, Debug)]
pub struct BodyTask {
    n: usize,
    gain: f64,
    /// rows `a_k` (row-major, `capacity × n`) and their target rates \[m/s\]
    rows: Vec<f64>,
    rate: Vec<f64>,
    len: usize,
    capacity: usize,
    /// rows not taken for lack of room, since the start
    dropped: u64,
    /// null-space projector `P` (n×n, row-major)
    p: Vec<f64>,
    /// `P AᵀA P + μ² I`, factored in place
    h: DMatrix<f64>,
    /// `AᵀA` (n×n, row-major)
    ata: Vec<f64>,
    /// `Aᵀ e` → `z` (n)
    z: Vec<f64>,
    /// scratch: `e` of the rows (capacity), `P AᵀA` (n×n)
    e: Vec<f64>,
    pa: Vec<f64>,
    /// the task Jacobian's columns of the free joints (3×n, row-major) and
    /// its Gram matrix (3×3)
    jw: Vec<f64>,
    gram: DMatrix<f64>,
    /// the correction of the best pass, and of the current pass
    best: Vec<f64>,
    delta: Vec<f64>,
    /// the posture's joint velocity `K_p (q_posture − q)` of this cycle
    /// [rad/s] (`None`: no posture task)
    posture_velocity: Option<Vec<f64>>,
}

/// What [`BodyTask::apply`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyTaskOutcome {
    /// rows asking for more speed away from their obstacle
    pub rows: usize,
    /// the fraction `t` of the correction applied
    pub fraction: f64,
    /// largest change of a joint velocity [rad/s]
    pub max_change: f64,
}

impl BodyTask {
    /// For `n` joints and up to `capacity` body points per cycle.
    pub fn new(n: usize, capacity: usize) -> BodyTask {
        BodyTask {
            n,
            gain: 1.0,
            rows: vec![0.0; capacity * n],
            rate: vec![0.0; capacity],
            len: 0,
            capacity,
            dropped: 0,
            p: vec![0.0; n * n],
            h: DMatrix::zeros(n, n),
            ata: vec![0.0; n * n],
            z: vec![0.0; n],
            e: vec![0.0; capacity],
            pa: vec![0.0; n * n],
            jw: vec![0.0; 3 * n],
            gram: DMatrix::zeros(3, 3),
            best: vec![0.0; n],
            delta: vec![0.0; n],
            posture_velocity: None,
        }
    }

    /// The lowest task of this cycle: `gain × (posture − q)` [rad/s] (gain
    /// [1/s]); an empty `posture`, wrong lengths or a non-finite value: none.
    pub fn set_posture(&mut self, posture: &[f64], q: &[f64], gain: f64) {
        let ok = posture.len() == self.n
            && q.len() == self.n
            && gain > 0.0
            && posture.iter().chain(q).all(|x| x.is_finite());
        match (&mut self.posture_velocity, ok) {
            (Some(v), true) => {
                for i in 0..self.n {
                    v[i] = gain * (posture[i] - q[i]);
                }
            }
            (None, true) => {
                // the one allocation, at the first cycle with a posture
                self.posture_velocity =
                    Some((0..self.n).map(|i| gain * (posture[i] - q[i])).collect());
            }
            (Some(v), false) => v.fill(0.0),
            (None, false) => {}
        }
    }

    /// Make room for the posture task, so that no cycle allocates.
    pub fn reserve_posture(&mut self) {
        self.posture_velocity
            .get_or_insert_with(|| vec![0.0; self.n]);
    }

    /// A point moves away at `gain × ‖V_Call‖` (negative or NaN: 0).
    pub fn set_gain(&mut self, gain: f64) {
        self.gain = if gain > 0.0 { gain } else { 0.0 };
    }

    /// Start a cycle: no rows.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Rows not taken for lack of room since the start.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// A body point with Jacobian `jp` (at least 3 rows, the first three
    /// linear, base frame; n columns) and repulsive vector `v_call` [m/s]
    /// (pointing away from its obstacle). A zero, non-finite or unusable
    /// vector adds nothing (eq. 20's bounds still hold the point).
    pub fn add<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        jp: &Matrix<f64, R, C, S>,
        v_call: Vector3<f64>,
    ) {
        let norm = v_call.norm();
        if !(norm > 1e-9 && norm.is_finite()) || self.gain == 0.0 {
            return;
        }
        if jp.nrows() < 3 || jp.ncols() != self.n {
            return;
        }
        if self.len == self.capacity {
            self.dropped += 1;
            return;
        }
        let u = v_call / norm;
        let row = &mut self.rows[self.len * self.n..(self.len + 1) * self.n];
        for (c, r) in row.iter_mut().enumerate() {
            *r = u.x * jp[(0, c)] + u.y * jp[(1, c)] + u.z * jp[(2, c)];
        }
        if row.iter().any(|x| !x.is_finite()) {
            return;
        }
        self.rate[self.len] = self.gain * norm;
        self.len += 1;
    }

    /// Add the body points' correction to `qd` (SNS's solution of the task
    /// with Jacobian `j_task`, whose first 3 rows are the end effector's
    /// linear ones; `saturated`: the joints SNS held, a bit each), keeping
    /// `qd` inside `[lo, hi]`.
    pub fn apply<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        j_task: &Matrix<f64, R, C, S>,
        saturated: u32,
        qd: &mut [f64],
        lo: &[f64],
        hi: &[f64],
    ) -> BodyTaskOutcome {
        let n = self.n;
        let mut out = BodyTaskOutcome::default();
        if j_task.nrows() < 3
            || j_task.ncols() != n
            || qd.len() != n
            || lo.len() != n
            || hi.len() != n
        {
            return out;
        }
        // the rate each row still misses
        let mut rows = 0;
        for k in 0..self.len {
            let a = &self.rows[k * n..(k + 1) * n];
            let now: f64 = a.iter().zip(qd.iter()).map(|(x, y)| x * y).sum();
            self.e[k] = (self.rate[k] - now).max(0.0);
            rows += usize::from(self.e[k] > 0.0);
        }
        out.rows = rows;
        if rows == 0 {
            // nothing to move away from: the posture, below everything
            return self.apply_posture(j_task, saturated, qd, lo, hi);
        }
        // AᵀA and Aᵀe over the rows (rows asking nothing have e = 0 but
        // still weigh: the correction should not push them back)
        self.ata.fill(0.0);
        for k in 0..self.len {
            let a = &self.rows[k * n..(k + 1) * n];
            for i in 0..n {
                for j in 0..n {
                    self.ata[i * n + j] += a[i] * a[j];
                }
            }
        }
        let mut held = saturated;
        let mut best_unanswered = f64::INFINITY;
        self.best.fill(0.0);
        let mut best_t = 0.0;
        for _ in 0..MAX_PASSES {
            if !self.correction(j_task, held) {
                break;
            }
            let (t, limiting) = self.room(qd, lo, hi);
            // what the rows still miss after t Δ
            let mut unanswered = 0.0;
            for k in 0..self.len {
                let a = &self.rows[k * n..(k + 1) * n];
                let got: f64 = a.iter().zip(&self.delta).map(|(x, y)| x * y).sum();
                unanswered += (self.e[k] - t * got).max(0.0).powi(2);
            }
            if unanswered < best_unanswered {
                best_unanswered = unanswered;
                best_t = t;
                for (b, d) in self.best.iter_mut().zip(&self.delta) {
                    *b = t * d;
                }
            }
            match limiting {
                Some(j) if t < 1.0 => held |= 1 << j,
                _ => break,
            }
        }
        for j in 0..n {
            let v = (qd[j] + self.best[j]).clamp(lo[j].min(hi[j]), hi[j].max(lo[j]));
            out.max_change = out.max_change.max((v - qd[j]).abs());
            qd[j] = v;
        }
        out.fraction = best_t;
        out
    }

    /// The posture's velocity projected into the null space of the task and
    /// of the held joints, scaled into the bounds.
    fn apply_posture<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        j_task: &Matrix<f64, R, C, S>,
        saturated: u32,
        qd: &mut [f64],
        lo: &[f64],
        hi: &[f64],
    ) -> BodyTaskOutcome {
        let n = self.n;
        let mut out = BodyTaskOutcome::default();
        // taken out for the cycle (no allocation), put back below
        let Some(pv) = self.posture_velocity.take() else {
            return out;
        };
        let usable = !pv.iter().all(|x| *x == 0.0) && self.projector(j_task, saturated);
        if usable {
            for i in 0..n {
                self.delta[i] = (0..n).map(|k| self.p[i * n + k] * pv[k]).sum();
            }
        }
        self.posture_velocity = Some(pv);
        if !usable {
            return out;
        }
        let t = self.room(qd, lo, hi).0;
        for j in 0..n {
            let v = (qd[j] + t * self.delta[j]).clamp(lo[j].min(hi[j]), hi[j].max(lo[j]));
            out.max_change = out.max_change.max((v - qd[j]).abs());
            qd[j] = v;
        }
        out.fraction = t;
        out
    }

    /// The largest `t ∈ [0, 1]` keeping `qd + t Δ` inside the bounds, and
    /// the joint that limits it.
    fn room(&self, qd: &[f64], lo: &[f64], hi: &[f64]) -> (f64, Option<usize>) {
        let (mut t, mut limiting) = (1.0f64, None);
        for j in 0..self.n {
            let d = self.delta[j];
            let room = if d > 0.0 {
                (hi[j] - qd[j]) / d
            } else if d < 0.0 {
                (lo[j] - qd[j]) / d
            } else {
                continue;
            };
            let room = room.max(0.0);
            if room < t {
                t = room;
                limiting = Some(j);
            }
        }
        (t, limiting)
    }

    /// `P`, the projector onto `{y : J_e y = 0, y_held = 0}`; false when the
    /// free columns cannot keep the task (rank < 3).
    fn projector<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        j_task: &Matrix<f64, R, C, S>,
        held: u32,
    ) -> bool {
        let n = self.n;
        let free = |j: usize| held & (1 << j) == 0;
        // J W and its Gram matrix
        let mut scale = 0.0f64;
        for r in 0..3 {
            for c in 0..n {
                let v = if free(c) { j_task[(r, c)] } else { 0.0 };
                self.jw[r * n + c] = v;
                scale = scale.max(v.abs());
            }
        }
        if !(scale > 0.0 && scale.is_finite()) {
            return false;
        }
        for r in 0..3 {
            for s in 0..3 {
                let mut g = 0.0;
                for c in 0..n {
                    g += self.jw[r * n + c] * self.jw[s * n + c];
                }
                self.gram[(r, s)] = g;
            }
        }
        if cholesky_factor(self.gram.as_view_mut(), 1e-10 * scale * scale).is_err() {
            return false;
        }
        // P = W − (JW)ᵀ G⁻¹ (JW), column by column
        let mut col = [0.0f64; 3];
        for c in 0..n {
            for r in 0..3 {
                col[r] = self.jw[r * n + c];
            }
            cholesky_solve(self.gram.as_view(), &mut col);
            for i in 0..n {
                let mut v = 0.0;
                for r in 0..3 {
                    v += self.jw[r * n + i] * col[r];
                }
                let w = if i == c && free(c) { 1.0 } else { 0.0 };
                self.p[i * n + c] = w - v;
            }
        }
        true
    }

    /// `Δ = P z` for the joints not in `held`; false when the free columns
    /// of the task cannot keep the end effector's task (rank < 3) or a
    /// factorisation fails.
    fn correction<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        j_task: &Matrix<f64, R, C, S>,
        held: u32,
    ) -> bool {
        let n = self.n;
        if !self.projector(j_task, held) {
            return false;
        }
        // H = P AᵀA P + μ² I, z = H⁻¹ P Aᵀ e
        for i in 0..n {
            for j in 0..n {
                let mut v = 0.0;
                for k in 0..n {
                    v += self.p[i * n + k] * self.ata[k * n + j];
                }
                self.pa[i * n + j] = v;
            }
        }
        for i in 0..n {
            for j in 0..n {
                let mut v = 0.0;
                for k in 0..n {
                    v += self.pa[i * n + k] * self.p[k * n + j];
                }
                self.h[(i, j)] = v + if i == j { DAMPING * DAMPING } else { 0.0 };
            }
        }
        // Aᵀ e, then P Aᵀ e
        for v in self.delta.iter_mut() {
            *v = 0.0;
        }
        for k in 0..self.len {
            let a = &self.rows[k * n..(k + 1) * n];
            for (d, x) in self.delta.iter_mut().zip(a) {
                *d += x * self.e[k];
            }
        }
        for i in 0..n {
            self.z[i] = (0..n).map(|k| self.p[i * n + k] * self.delta[k]).sum();
        }
        if cholesky_factor(self.h.as_view_mut(), 1e-300).is_err() {
            return false;
        }
        cholesky_solve(self.h.as_view(), &mut self.z);
        // Δ = P z
        for i in 0..n {
            self.delta[i] = (0..n).map(|k| self.p[i * n + k] * self.z[k]).sum();
        }
        self.delta.iter().all(|x| x.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3xX;

    /// A planar-ish 4-joint toy: the task moves x only; the body point's
    /// Jacobian has a part in the task's null space.
    #[test]
    fn the_correction_keeps_the_task_and_moves_the_point_away() {
        let jt = Matrix3xX::from_row_slice(&[
            1.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            0.0, 0.0, 0.0, 1.0,
        ]);
        // the point moves with joints 0 (+x) and 1 (−x): away along +x
        let jp = Matrix3xX::from_row_slice(&[
            1.0, -1.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0,
        ]);
        let mut b = BodyTask::new(4, 4);
        b.clear();
        b.add(&jp, Vector3::new(0.2, 0.0, 0.0));
        let mut qd = [0.1, 0.1, 0.0, 0.0];
        let before = &jt * nalgebra::DVector::from_column_slice(&qd);
        let (lo, hi) = ([-1.0; 4], [1.0; 4]);
        let out = b.apply(&jt, 0, &mut qd, &lo, &hi);
        let after = &jt * nalgebra::DVector::from_column_slice(&qd);
        assert!((before - after).norm() < 1e-12, "the task is unchanged");
        let away = qd[0] - qd[1];
        // damped: 2/(2 + μ²) of the asked 0.2 m/s
        assert!(
            (away - 0.2 * 2.0 / (2.0 + DAMPING * DAMPING)).abs() < 1e-12,
            "{away}"
        );
        assert_eq!((out.rows, out.fraction), (1, 1.0));
    }

    #[test]
    fn bounds_and_saturated_joints_hold() {
        let jt = Matrix3xX::from_row_slice(&[
            1.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            0.0, 0.0, 0.0, 1.0,
        ]);
        let jp = Matrix3xX::from_row_slice(&[
            1.0, -1.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0,
        ]);
        let mut b = BodyTask::new(4, 4);
        b.add(&jp, Vector3::new(0.2, 0.0, 0.0));
        // little room on joint 0: the correction is cut to fit
        let mut qd = [0.1, 0.1, 0.0, 0.0];
        let (lo, hi) = ([-1.0; 4], [0.12, 1.0, 1.0, 1.0]);
        let out = b.apply(&jt, 0, &mut qd, &lo, &hi);
        assert!(qd[0] <= 0.12 + 1e-15 && out.fraction < 1.0 && out.fraction > 0.0);
        assert!((qd[0] + qd[1] - 0.2).abs() < 1e-12, "the task is unchanged");
        // joint 1 saturated by SNS: no null space left for the point
        let mut b = BodyTask::new(4, 4);
        b.add(&jp, Vector3::new(0.2, 0.0, 0.0));
        let mut qd = [0.1, 0.1, 0.0, 0.0];
        let out = b.apply(&jt, 0b10, &mut qd, &[-1.0; 4], &[1.0; 4]);
        assert_eq!(qd, [0.1, 0.1, 0.0, 0.0]);
        assert_eq!(out.max_change, 0.0);
    }

    #[test]
    fn without_rows_the_posture_pulls_in_the_null_space() {
        let jt = Matrix3xX::from_row_slice(&[
            1.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            0.0, 0.0, 0.0, 1.0,
        ]);
        let mut b = BodyTask::new(4, 4);
        b.reserve_posture();
        // joint 0 is 0.2 rad below its posture, joint 1 at it: gain 2/s
        b.set_posture(&[0.2, 0.0, 0.0, 0.0], &[0.0; 4], 2.0);
        let mut qd = [0.1, 0.1, 0.0, 0.0];
        let out = b.apply(&jt, 0, &mut qd, &[-1.0; 4], &[1.0; 4]);
        // the null space of the task is (1, −1, 0, 0)/√2: half of (0.4, 0, 0, 0)
        assert!(
            (qd[0] - 0.3).abs() < 1e-12 && (qd[1] + 0.1).abs() < 1e-12,
            "{qd:?}"
        );
        assert!((qd[0] + qd[1] - 0.2).abs() < 1e-12, "the task is unchanged");
        assert_eq!(out.fraction, 1.0);
        // a row asking to move away takes precedence over the posture
        let jp = Matrix3xX::from_row_slice(&[
            -1.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0,
        ]);
        b.add(&jp, Vector3::new(0.1, 0.0, 0.0));
        let mut qd = [0.1, 0.1, 0.0, 0.0];
        b.apply(&jt, 0, &mut qd, &[-1.0; 4], &[1.0; 4]);
        assert!(
            qd[1] - qd[0] > 0.09,
            "moved away against the posture: {qd:?}"
        );
    }

    #[test]
    fn nothing_asked_nothing_changed() {
        let jt = Matrix3xX::from_row_slice(&[
            1.0, 1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, 0.0, //
            0.0, 0.0, 0.0, 1.0,
        ]);
        let jp = Matrix3xX::from_row_slice(&[
            1.0, -1.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0,
        ]);
        let mut b = BodyTask::new(4, 1);
        b.add(&jp, Vector3::new(f64::NAN, 0.0, 0.0));
        b.add(&jp, Vector3::zeros());
        let mut qd = [0.1, 0.1, 0.0, 0.0];
        assert_eq!(b.apply(&jt, 0, &mut qd, &[-1.0; 4], &[1.0; 4]).rows, 0);
        // already moving away faster than asked
        b.add(&jp, Vector3::new(0.2, 0.0, 0.0));
        b.add(&jp, Vector3::new(0.2, 0.0, 0.0));
        assert_eq!(b.dropped(), 1, "capacity 1");
        let mut qd = [0.5, 0.0, 0.0, 0.0];
        let out = b.apply(&jt, 0, &mut qd, &[-1.0; 4], &[1.0; 4]);
        assert_eq!((out.rows, qd), (0, [0.5, 0.0, 0.0, 0.0]));
    }
}
