//! The paper's collision-avoidance layer (Sect. V, eqs. 19-20) around
//! [`SnsSolver`]: the end effector's repulsive vector is added to its task
//! velocity, the repulsive vectors of the other control points shrink the
//! joint velocity bounds on the side that moves the point toward the
//! obstacle, and SNS resolves the task inside the resulting bounds (scaling
//! it down only when it must).
//!
//! Per cycle, with [`Avoidance`]:
//! 1. joint-limit bounds ([`joint_limit_bounds`], sns_ik's
//!    `shapeJointVelocityBound`) from the position, velocity and acceleration
//!    limits;
//! 2. for every body control point, [`shape_bounds_for_point`] (eq. 20),
//!    keeping the most restrictive bound over all points;
//! 3. the global speed scale (e.g. slower while perception is stale)
//!    multiplies both bounds;
//! 4. `ẋ_r = ẋ_t + V_Call(P_e)` ([`end_effector_velocity`], eq. 19) is
//!    resolved by SNS within the bounds;
//! 5. with the body task on ([`Avoidance::set_body_task`], `[control]
//!    body_avoidance = "null_space"`), each body point moving away from its
//!    obstacle is a task below the end effector's, in its null space
//!    ([`crate::body_task`]).
//!
//! # Sign convention of eq. 20
//!
//! `V_Call(P)` is the *repulsive* vector: it points from the obstacle toward
//! `P`, i.e. away from the obstacle (that is why eq. 19 can simply add it to
//! the end-effector velocity). Let `u = V_Call/‖V_Call‖`. To first order the
//! distance `d` between `P` and the obstacle changes as
//! `ḋ = uᵀ Ṗ = uᵀ J_P q̇ = Σ_j (S_j/‖V_Call‖) q̇_j` with `S = J_Pᵀ V_Call`.
//! Joint `j` alone therefore moves `P` toward the obstacle (`ḋ < 0`) exactly
//! when `S_j q̇_j < 0`:
//! - `S_j > 0`: positive `q̇_j` moves `P` away, *negative* `q̇_j` moves it
//!   closer, so the lower bound is shrunk: `q̇min,j ← max(q̇min,j, −V_max,j (1 − f))`;
//! - `S_j < 0`: positive `q̇_j` moves `P` closer, so
//!   `q̇max,j ← min(q̇max,j, V_max,j (1 − f))`;
//! - `S_j ≈ 0` (`|S_j| ≤ 1e-6 ‖J_P,j‖ ‖V_Call‖`, the joint does not move `P`
//!   or moves it tangentially): unchanged.
//!
//! with the risk `f = ‖V_Call‖/V_max ∈ [0, 1]` (`V_max` of eq. 16). The escape
//! side is never restricted. The rule quoted from third-party code ("if
//! `s_j ≥ 0` then `q̇max,j = V_max,j (1 − f)`") is the mirror image: it is only
//! right when the vector it maps points *toward* the obstacle (the distance
//! vector `D = O − P` before the sign flip that makes it repulsive). Applied to
//! the repulsive `V_Call` it would brake the escape and leave the approach
//! free, the opposite of the paper's text ("joint motions that will move the
//! robot point `P_r` toward an obstacle will be slowed down"). It would also
//! brake joints that do not move `P` at all (`S_j = 0`), for nothing.
//!
//! Consequence, checked in the tests: after shaping, for every joint
//! `−(uᵀ J_P,j) q̇_j ≤ |uᵀ J_P,j| V_max,j (1 − f)`, so the speed of `P` toward
//! the obstacle is at most `(1 − f) Σ_j |uᵀ J_P,j| V_max,j` (times the speed
//! scale), and it is 0 when `f = 1`.
//!
//! A shaped bound never crosses the opposite bound: if the joint-limit bounds
//! force a joint to move toward the obstacle (only possible when the joint is
//! outside its position range), the position recovery wins, at the smallest
//! speed the joint-limit bounds allow.
//!
//! No allocation per cycle: [`Avoidance`] holds preallocated buffers.

use nalgebra::{DMatrixView, Dim, Matrix, RawStorage, Vector3};
pub use phri_config::AvoidanceParams;
use phri_model::{check_len, Model};

use crate::body_task::{BodyTask, BodyTaskOutcome};
use crate::sns::{SnsError, SnsSolver};

/// Most body points of one cycle the null-space task takes.
pub const MAX_BODY_POINTS: usize = 64;

/// Joint velocity bounds from the position, velocity and acceleration limits
/// (sns_ik's `shapeJointVelocityBound`), written into `qd_min`, `qd_max`:
///
/// `q̇min_i = max{(Q_min,i − q_i)/T, −V_max,i, −√(2 A_max,i (q_i − Q_min,i))}`,
/// `q̇max_i = min{(Q_max,i − q_i)/T,  V_max,i,  √(2 A_max,i (Q_max,i − q_i))}`.
///
/// Inside the position range this is exactly the formula above. Outside it
/// (where the square root has a negative argument) the root term is 0 and the
/// velocity driving the joint back is capped at `V_max,i`, so the bounds stay
/// consistent. `horizon_t ≤ 0` drops the `(Q − q)/T` term. A non-finite result
/// (NaN input) gives `[0, 0]` (the joint is held).
///
/// # Panics
/// If an input slice is shorter than `qd_min`, or `qd_max` has another length.
#[allow(clippy::too_many_arguments)]
pub fn joint_limit_bounds(
    q: &[f64],
    q_min: &[f64],
    q_max: &[f64],
    v_max: &[f64],
    a_max: &[f64],
    horizon_t: f64,
    qd_min: &mut [f64],
    qd_max: &mut [f64],
) {
    assert_eq!(qd_min.len(), qd_max.len(), "joint_limit_bounds: outputs");
    for i in 0..qd_min.len() {
        let (v, a) = (v_max[i].abs(), a_max[i].abs());
        let below = q[i] - q_min[i]; // distance to the lower limit
        let above = q_max[i] - q[i]; // distance to the upper limit
        let mut lo = (-v).max(-(2.0 * a * below.max(0.0)).sqrt());
        let mut hi = v.min((2.0 * a * above.max(0.0)).sqrt());
        if horizon_t > 0.0 {
            lo = lo.max(-below / horizon_t);
            hi = hi.min(above / horizon_t);
        }
        // outside the range: return no faster than the velocity limit
        lo = lo.min(v);
        hi = hi.max(-v);
        if lo.is_nan() || hi.is_nan() {
            lo = 0.0;
            hi = 0.0;
        } else if lo > hi {
            // degenerate limits (e.g. Q_min > Q_max, A = 0 outside the range)
            let mid = 0.5 * (lo + hi);
            lo = mid;
            hi = mid;
        }
        qd_min[i] = lo;
        qd_max[i] = hi;
    }
}

/// Eq. 20 for one body control point `P`: shrink `qd_min`/`qd_max` on the
/// side of each joint that moves `P` toward the obstacle (see the module
/// documentation for the sign), keeping the more restrictive of the old and
/// new bound. `jp` is the point's Jacobian (at least 3 rows, the first three
/// linear, base frame; n columns), `v_call` its repulsive vector `V_Call(P)`
/// (pointing away from the obstacle, base frame) [m/s], `v_max_repulsion` the
/// `V_max` of eq. 16 [m/s], `v_max_joint` the joint velocity limits.
///
/// Returns the risk `f = ‖V_Call‖/V_max ∈ [0, 1]`. A zero `V_Call` changes
/// nothing. A non-finite `V_Call` (no usable direction) counts as `f = 1` and
/// holds (both sides at 0) every joint that moves `P`.
///
/// # Panics
/// If `jp` has fewer than 3 rows or not `qd_min.len()` columns, or the slices
/// differ in length.
pub fn shape_bounds_for_point<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
    jp: &Matrix<f64, R, C, S>,
    v_call: Vector3<f64>,
    v_max_repulsion: f64,
    v_max_joint: &[f64],
    qd_min: &mut [f64],
    qd_max: &mut [f64],
) -> f64 {
    let n = qd_min.len();
    assert!(
        jp.nrows() >= 3 && jp.ncols() == n && qd_max.len() == n && v_max_joint.len() == n,
        "shape_bounds_for_point: dimensions"
    );
    let norm = v_call.norm();
    if norm == 0.0 {
        return 0.0;
    }
    if !norm.is_finite() {
        for k in 0..n {
            let moves = (0..3).any(|r| jp[(r, k)] != 0.0);
            if moves {
                let lo = 0.0f64.min(qd_max[k]);
                let hi = 0.0f64.max(qd_min[k]);
                qd_min[k] = qd_min[k].max(lo);
                qd_max[k] = qd_max[k].min(hi);
            }
        }
        return 1.0;
    }
    let f = if v_max_repulsion > 0.0 {
        (norm / v_max_repulsion).min(1.0)
    } else {
        1.0
    };
    for k in 0..n {
        let col = Vector3::new(jp[(0, k)], jp[(1, k)], jp[(2, k)]);
        let s = col.dot(&v_call); // S_k of eq. 20
        if s.abs() <= 1e-6 * col.norm() * norm {
            continue; // does not move P toward or away from the obstacle
        }
        let lim = v_max_joint[k].abs() * (1.0 - f);
        if s > 0.0 {
            // negative q̇_k moves P toward the obstacle
            let lo = (-lim).min(qd_max[k]);
            qd_min[k] = qd_min[k].max(lo);
        } else {
            // positive q̇_k moves P toward the obstacle
            let hi = lim.max(qd_min[k]);
            qd_max[k] = qd_max[k].min(hi);
        }
    }
    f
}

/// Eq. 19: `ẋ_r = ẋ_t + V_Call(P_e)`.
#[inline]
pub fn end_effector_velocity(xdot_task: &Vector3<f64>, v_call_ee: &Vector3<f64>) -> Vector3<f64> {
    xdot_task + v_call_ee
}

/// A body control point for [`Avoidance::step`]: its Jacobian (at least 3
/// rows, the first three linear, base frame; `(&jac).into()` works for a
/// `Matrix6xX`, `Matrix3xX` or `DMatrix`) and its repulsive vector.
#[derive(Clone, Copy, Debug)]
pub struct ControlPoint<'a> {
    /// the point's Jacobian, base frame (at least 3 rows, the first three linear)
    pub jacobian: DMatrixView<'a, f64>,
    /// `V_Call(P)`, pointing away from the obstacle, base frame [m/s]
    pub v_call: Vector3<f64>,
}

impl<'a> ControlPoint<'a> {
    /// The point of `jacobian` (any matrix that views as a `DMatrixView`) and `v_call`.
    pub fn new(jacobian: impl Into<DMatrixView<'a, f64>>, v_call: Vector3<f64>) -> Self {
        ControlPoint {
            jacobian: jacobian.into(),
            v_call,
        }
    }
}

/// What [`Avoidance`] computed in one cycle (borrows its buffers).
#[derive(Clone, Copy, Debug)]
pub struct AvoidanceOutput<'a> {
    /// joint velocity reference [rad/s], inside `[qd_min, qd_max]`
    pub qd: &'a [f64],
    /// task scale of SNS, `J q̇ ≈ s ẋ_r`
    pub scale: f64,
    /// joints SNS held at a bound (bit per joint)
    pub saturated: u32,
    /// SNS's pseudoinverse solutions plus simplex steps
    pub iterations: u32,
    /// largest correction of SNS's final safety clamp (round-off only)
    pub clamp_correction: f64,
    /// largest risk `f` over the body control points of this cycle
    pub risk: f64,
    /// the velocity bounds SNS used (speed scale included)
    pub qd_min: &'a [f64],
    /// the upper of those bounds \[rad/s\]
    pub qd_max: &'a [f64],
    /// the body points' null-space task (all zero when it is off)
    pub body: BodyTaskOutcome,
}

/// Per-cycle avoidance and SNS, preallocated for one robot.
///
/// Either [`Avoidance::step`] with all points at once, or the same in parts:
/// [`Avoidance::begin`], [`Avoidance::add_point`] for each body point (one
/// Jacobian buffer can be reused between points), [`Avoidance::solve`].
#[derive(Clone, Debug)]
pub struct Avoidance {
    params: AvoidanceParams,
    q_min: Vec<f64>,
    q_max: Vec<f64>,
    /// position range less the margin
    range_lo: Vec<f64>,
    range_hi: Vec<f64>,
    v_max: Vec<f64>,
    a_max: Vec<f64>,
    /// bounds of the cycle before the speed scale
    qd_min: Vec<f64>,
    qd_max: Vec<f64>,
    /// the same times the speed scale: what SNS gets
    sol_min: Vec<f64>,
    sol_max: Vec<f64>,
    risk: f64,
    sns: SnsSolver,
    /// the body points' repulsion as a task below the end effector's
    /// (`None`: eq. 20's bounds only)
    body: Option<BodyTask>,
    /// the body points' repulsion, and the posture below it, apply this
    /// cycle ([`Avoidance::pause_body_task`])
    body_active: bool,
    posture_active: bool,
    /// the solution: SNS's, plus the body task's correction
    qd: Vec<f64>,
}

impl Avoidance {
    /// Limits from the model's joints (position range less
    /// `params.position_margin`, velocity), acceleration from the params.
    pub fn new(model: &Model, params: AvoidanceParams) -> Avoidance {
        let lower: Vec<f64> = model.actuated().iter().map(|j| j.lower).collect();
        let upper: Vec<f64> = model.actuated().iter().map(|j| j.upper).collect();
        let velocity: Vec<f64> = model.actuated().iter().map(|j| j.velocity).collect();
        Avoidance::from_limits(&lower, &upper, &velocity, params)
    }

    /// Limits given directly (position range, velocity limits, one per joint).
    ///
    /// # Panics
    /// If the slices differ in length or there are 0 or more than
    /// [`crate::sns::MAX_JOINTS`] joints.
    pub fn from_limits(
        lower: &[f64],
        upper: &[f64],
        velocity: &[f64],
        params: AvoidanceParams,
    ) -> Avoidance {
        let n = lower.len();
        assert!(
            upper.len() == n && velocity.len() == n,
            "Avoidance: limit lengths"
        );
        let mut a = Avoidance {
            params,
            q_min: vec![0.0; n],
            q_max: vec![0.0; n],
            range_lo: vec![0.0; n],
            range_hi: vec![0.0; n],
            v_max: velocity.iter().map(|v| v.abs()).collect(),
            a_max: vec![0.0; n],
            qd_min: vec![0.0; n],
            qd_max: vec![0.0; n],
            sol_min: vec![0.0; n],
            sol_max: vec![0.0; n],
            risk: 0.0,
            sns: SnsSolver::new(n, 3),
            body: None,
            body_active: true,
            posture_active: true,
            qd: vec![0.0; n],
        };
        a.q_min.copy_from_slice(lower);
        a.q_max.copy_from_slice(upper);
        a.set_params(params);
        a
    }

    /// Replace the settings (no allocation).
    pub fn set_params(&mut self, params: AvoidanceParams) {
        self.params = params;
        self.a_max.fill(params.accel_limit.abs());
        let m = params.position_margin.abs();
        for i in 0..self.q_min.len() {
            let (lo, hi) = (self.q_min[i] + m, self.q_max[i] - m);
            // the middle if the margin eats the whole range
            let mid = 0.5 * (self.q_min[i] + self.q_max[i]);
            (self.range_lo[i], self.range_hi[i]) = if lo <= hi { (lo, hi) } else { (mid, mid) };
        }
    }

    /// The settings in use.
    pub fn params(&self) -> &AvoidanceParams {
        &self.params
    }

    /// Body points: besides eq. 20's bounds, each one's repulsion as a task
    /// below the end effector's, moving away at `gain × ‖V_Call‖`
    /// ([`crate::body_task`]); `None`: eq. 20 only (the default).
    pub fn set_body_task(&mut self, gain: Option<f64>) {
        self.body = gain.map(|g| {
            let mut b = BodyTask::new(self.n(), MAX_BODY_POINTS);
            b.set_gain(g);
            b.reserve_posture();
            b
        });
    }

    /// Number of joints.
    pub fn n(&self) -> usize {
        self.qd_min.len()
    }

    /// Joint velocity limits (from the model).
    pub fn velocity_limits(&self) -> &[f64] {
        &self.v_max
    }

    /// Bounds of the current cycle before the speed scale (joint limits and
    /// the points added so far).
    pub fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.qd_min, &self.qd_max)
    }

    /// Leave the body points' repulsion (`repulsion`) and the posture below
    /// it (`posture`) out of the body task in the following cycles, or take
    /// them again (a no-op without a body task): e.g. while the end effector
    /// goes to a person's hand, whose arm the body points would roll away
    /// from (and the wrist into the hand), and, in contact, the posture (the
    /// arm yields to the hand in its null space as it did before).
    pub fn pause_body_task(&mut self, repulsion: bool, posture: bool) {
        self.body_active = !repulsion;
        self.posture_active = !posture;
    }

    /// With the body task on: the posture its null space pulls toward when
    /// no body point asks to move away, `gain × (posture − q)` for this
    /// cycle's `q` (call after [`Avoidance::begin`]; empty: none).
    pub fn set_posture(&mut self, posture: &[f64], q: &[f64], gain: f64) {
        if let Some(b) = self.body.as_mut() {
            b.set_posture(posture, q, gain);
        }
    }

    /// Start a cycle: joint-limit bounds at `q`.
    pub fn begin(&mut self, q: &[f64]) -> Result<(), SnsError> {
        let n = self.n();
        check_len("q", n, q.len())?;
        joint_limit_bounds(
            q,
            &self.range_lo,
            &self.range_hi,
            &self.v_max,
            &self.a_max,
            self.params.horizon_s,
            &mut self.qd_min,
            &mut self.qd_max,
        );
        self.risk = 0.0;
        if let Some(b) = self.body.as_mut() {
            b.clear();
        }
        Ok(())
    }

    /// A control point's Jacobian: at least 3 rows (the first three
    /// linear), `n` columns.
    fn check_point_jacobian<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        n: usize,
        jacobian: &Matrix<f64, R, C, S>,
    ) -> Result<(), SnsError> {
        if jacobian.nrows() < 3 {
            return Err(SnsError::TooFewRows {
                what: "control point jacobian",
                min: 3,
                got: jacobian.nrows(),
            });
        }
        check_len("control point jacobian columns", n, jacobian.ncols())?;
        Ok(())
    }

    /// Eq. 20 for one body control point (after [`Avoidance::begin`]);
    /// returns its risk `f`.
    pub fn add_point<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        jacobian: &Matrix<f64, R, C, S>,
        v_call: Vector3<f64>,
    ) -> Result<f64, SnsError> {
        let n = self.n();
        Self::check_point_jacobian(n, jacobian)?;
        let f = shape_bounds_for_point(
            jacobian,
            v_call,
            self.params.v_max_repulsion,
            &self.v_max,
            &mut self.qd_min,
            &mut self.qd_max,
        );
        self.risk = self.risk.max(f);
        if let Some(b) = self.body.as_mut().filter(|_| self.body_active) {
            b.add(jacobian, v_call);
        }
        Ok(f)
    }

    /// Speed and separation monitoring for one control point (after
    /// [`Avoidance::begin`]): bound its speed toward its obstacle, along
    /// unit `away` (from the obstacle to the point, base frame), to
    /// `allowed` \[m/s\], by eq. 20's shaping with the risk
    /// `f = 1 − allowed / Σ_j |awayᵀ J_j| V_max,j` (the point's fastest
    /// approach within the joint limits): after it the point approaches at
    /// most `allowed`. `jacobian`: the point's (at least 3 rows, the first
    /// three linear). Returns `f` (0: no bound needed; a NaN `allowed`
    /// holds every joint that moves the point toward the obstacle).
    pub fn limit_approach<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        jacobian: &Matrix<f64, R, C, S>,
        away: &Vector3<f64>,
        allowed: f64,
    ) -> Result<f64, SnsError> {
        let n = self.n();
        Self::check_point_jacobian(n, jacobian)?;
        let mut reach = 0.0;
        for k in 0..n {
            let along =
                away.x * jacobian[(0, k)] + away.y * jacobian[(1, k)] + away.z * jacobian[(2, k)];
            reach += along.abs() * self.v_max[k].abs();
        }
        if !(reach > 0.0) {
            return Ok(0.0);
        }
        let f = match allowed.is_nan() {
            true => 1.0,
            false => (1.0 - allowed / reach).clamp(0.0, 1.0),
        };
        if f <= 0.0 {
            return Ok(0.0);
        }
        Ok(shape_bounds_for_point(
            jacobian,
            away * f,
            1.0,
            &self.v_max,
            &mut self.qd_min,
            &mut self.qd_max,
        ))
    }

    /// Finish a cycle: scale the bounds by `speed_scale` (clamped to [0, 1];
    /// NaN counts as 0; the cycle's bounds are kept, so `solve` may be called
    /// again, e.g. with another task) and resolve `ẋ_r = ẋ_t + V_Call(P_e)` (eq. 19) by SNS
    /// for the task Jacobian (at least 3 rows, the first three the position
    /// rows of the end effector, n columns).
    pub fn solve<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        task_jacobian: &Matrix<f64, R, C, S>,
        xdot_task: &Vector3<f64>,
        v_call_ee: &Vector3<f64>,
        speed_scale: f64,
    ) -> Result<AvoidanceOutput<'_>, SnsError> {
        if task_jacobian.nrows() < 3 {
            return Err(SnsError::TooFewRows {
                what: "task jacobian",
                min: 3,
                got: task_jacobian.nrows(),
            });
        }
        let k = if speed_scale.is_nan() {
            0.0
        } else {
            speed_scale.clamp(0.0, 1.0)
        };
        let scaled = |x: f64| {
            if x.is_finite() {
                x * k + 0.0 // + 0.0: no −0
            } else if k == 0.0 {
                0.0
            } else {
                x
            }
        };
        for i in 0..self.qd_min.len() {
            self.sol_min[i] = scaled(self.qd_min[i]);
            self.sol_max[i] = scaled(self.qd_max[i]);
        }
        let xr = end_effector_velocity(xdot_task, v_call_ee);
        let r = self.sns.solve(
            &task_jacobian.rows(0, 3),
            xr.as_slice(),
            &self.sol_min,
            &self.sol_max,
            self.params.damping,
        )?;
        self.qd.copy_from_slice(r.qd);
        let body = match self.body.as_mut().filter(|_| self.posture_active) {
            Some(b) => b.apply(
                &task_jacobian.rows(0, 3),
                r.saturated,
                &mut self.qd,
                &self.sol_min,
                &self.sol_max,
            ),
            None => BodyTaskOutcome::default(),
        };
        Ok(AvoidanceOutput {
            qd: &self.qd,
            body,
            scale: r.scale,
            saturated: r.saturated,
            iterations: r.iterations,
            clamp_correction: r.clamp_correction,
            risk: self.risk,
            qd_min: &self.sol_min,
            qd_max: &self.sol_max,
        })
    }

    /// The whole cycle: [`Avoidance::begin`] at `q`, [`Avoidance::add_point`]
    /// for each of `points`, [`Avoidance::solve`].
    pub fn step<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        q: &[f64],
        task_jacobian: &Matrix<f64, R, C, S>,
        xdot_task: &Vector3<f64>,
        v_call_ee: &Vector3<f64>,
        points: &[ControlPoint<'_>],
        speed_scale: f64,
    ) -> Result<AvoidanceOutput<'_>, SnsError> {
        self.begin(q)?;
        for p in points {
            self.add_point(&p.jacobian, p.v_call)?;
        }
        self.solve(task_jacobian, xdot_task, v_call_ee, speed_scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3xX;

    #[test]
    fn joint_limit_bounds_inside_match_the_formula() {
        let (mut lo, mut hi) = ([0.0], [0.0]);
        joint_limit_bounds(
            &[0.5],
            &[-1.0],
            &[1.0],
            &[2.0],
            &[4.0],
            0.1,
            &mut lo,
            &mut hi,
        );
        // lower: max(−15, −2, −√12) = −2; upper: min(5, 2, √4) = 2
        assert_eq!((lo[0], hi[0]), (-2.0, 2.0));
        joint_limit_bounds(
            &[0.9],
            &[-1.0],
            &[1.0],
            &[2.0],
            &[4.0],
            0.1,
            &mut lo,
            &mut hi,
        );
        assert!((hi[0] - 0.8f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn a_point_not_moved_by_a_joint_leaves_it_free() {
        let jp = Matrix3xX::from_column_slice(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let (mut lo, mut hi) = ([-1.0, -1.0], [1.0, 1.0]);
        let f = shape_bounds_for_point(
            &jp,
            Vector3::new(0.1, 0.0, 0.0),
            0.2,
            &[1.0, 1.0],
            &mut lo,
            &mut hi,
        );
        assert!((f - 0.5).abs() < 1e-12);
        assert_eq!((lo, hi), ([-0.5, -1.0], [1.0, 1.0]));
    }

    #[test]
    fn a_limited_approach_is_at_most_the_allowed_speed_at_every_corner_of_the_bounds() {
        // three joints; the point moves along x with joints 0 and 1, along y with 2
        let jp = Matrix3xX::from_column_slice(&[0.5, 0.0, 0.0, -0.3, 0.0, 0.0, 0.0, 0.4, 0.0]);
        let params = phri_config::Config::defaults().control.avoidance_params;
        let mut a = Avoidance::from_limits(&[-3.0; 3], &[3.0; 3], &[2.0; 3], params);
        // the obstacle lies ahead in +x: away is −x
        let away = Vector3::new(-1.0, 0.0, 0.0);
        let toward = |qd: &[f64]| -(away.x * (0.5 * qd[0] - 0.3 * qd[1]));
        for allowed in [0.0, 0.2, 0.9] {
            a.begin(&[0.0; 3]).unwrap();
            let before = (a.bounds().0[2], a.bounds().1[2]);
            let f = a.limit_approach(&jp, &away, allowed).unwrap();
            // fastest approach within the joint limits: (0.5 + 0.3) · 2 = 1.6 m/s
            assert!((f - (1.0 - allowed / 1.6)).abs() < 1e-12, "{f}");
            let (lo, hi) = a.bounds();
            let mut fastest = f64::NEG_INFINITY;
            for corner in 0..8 {
                let qd: Vec<f64> = (0..3)
                    .map(|j| if corner >> j & 1 == 1 { hi[j] } else { lo[j] })
                    .collect();
                fastest = fastest.max(toward(&qd));
            }
            assert!(fastest <= allowed + 1e-12, "allowed {allowed}: {fastest}");
            // the joint that does not move the point keeps its whole range
            assert_eq!((lo[2], hi[2]), before);
            // moving away stays free: both joints keep their escape side
            assert!(hi[1] > 0.0 && lo[0] < 0.0);
        }
        // nothing to bound: an allowed speed above the fastest approach
        a.begin(&[0.0; 3]).unwrap();
        assert_eq!(a.limit_approach(&jp, &away, 5.0).unwrap(), 0.0);
        // no number: hold the approach
        a.begin(&[0.0; 3]).unwrap();
        assert_eq!(a.limit_approach(&jp, &away, f64::NAN).unwrap(), 1.0);
    }

    #[test]
    fn effective_range_and_params() {
        let params = phri_config::Config::defaults().control.avoidance_params;
        let a = Avoidance::from_limits(&[-1.0], &[1.0], &[2.0], params);
        assert_eq!((a.range_lo[0], a.range_hi[0]), (-0.95, 0.95));
        assert_eq!(a.n(), 1);
    }
}
