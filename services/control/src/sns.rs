//! Saturation in the Null Space (SNS): velocity-level inverse kinematics of a
//! single task under hard joint-velocity bounds, scaling the task down when it
//! cannot be met (Flacco, De Luca, Khatib, ICRA 2012 / T-RO 2015; the
//! paper's ref. \[23\]), with the largest feasible task scale (issue 14,
//! "optimal SNS").
//!
//! Given a task Jacobian `J` (m×n), a task velocity `ẋ` (m) and joint velocity
//! bounds `q̇min ≤ q̇ ≤ q̇max`, phase 1 is greedy SNS:
//!
//! 1. `W = I`, `q̇_N = 0`, best scale `s* = 0`.
//! 2. `q̇ = q̇_N + (JW)^# (ẋ − J q̇_N)`. If it is inside the bounds (up to a
//!    tolerance of `1e-10·(1 + |bound|)`), return it with scale 1.
//! 3. `a = (JW)^# ẋ`, `b = q̇ − a`, so that `q̇(s) = s a + b` is the solution
//!    for the scaled task `s ẋ` with the same `W`, `q̇_N`. Per joint, the
//!    admissible interval of `s` from `q̇min ≤ s a + b ≤ q̇max` (if `|a_i|` is
//!    below the tolerance the joint hardly depends on `s`: the interval is
//!    everything if `b_i` is in bounds, empty otherwise). `s_hi` = the smallest
//!    upper end, `s_lo` = the largest lower end. The task scale is
//!    `min(s_hi, 1)` when `[max(s_lo, 0), min(s_hi, 1)]` is non-empty, else 0.
//! 4. If that scale beats `s*`, remember `s*`, `W*`, `q̇_N*` (stored as the
//!    `a*`, `b*` they give).
//! 5. Saturate the most critical joint: the joint achieving `s_hi` when
//!    `s_hi < 1` (it leaves its bounds first as the task grows), otherwise the
//!    joint achieving `s_lo` (only a lower end excludes `s = 1`). It is fixed
//!    (`W_jj = 0`) at the bound it violates at `s = 1`: `q̇_N,j = clamp(q̇_j)`.
//! 6. If `rank(JW) < m` (fewer free joints than task rows, or the Gram matrix
//!    of the free columns numerically singular), return
//!    `q̇ = q̇_N* + (JW*)^# (s* ẋ − J q̇_N*) = s* a* + b*` with scale `s*`
//!    (evaluated from the stored `a*`, `b*` whose intervals gave `s*`, so a
//!    second factorisation's round-off cannot push it out of the bounds);
//!    else go to 2. (When the scale is below 1, phase 2 follows.)
//!
//! Differences from Rethink's public MATLAB "basic" version, which is known
//! to fail: that one leaves the loop when limits *are* exceeded (inverted
//! test), writes the saturated value into `q̇` instead of `q̇_N` (so the
//! saturation is lost at the next iteration), divides by `a_i = 0` for
//! already-saturated joints (0/0 = NaN, or a saturated joint picked again),
//! has no critical joint when the interval is empty, and does not cap the
//! scale at 1. Here saturated joints have `a_i = 0` exactly (their column of
//! `JW` is zero, so their row of the pseudoinverse is zero) and an unbounded
//! interval, the full two-sided interval is used (Rethink's repaired `rr`
//! variant looks at one margin per joint only and does not check that the
//! other end of the interval admits the scale), and the critical joint is
//! always one that is violated at `s = 1`.
//!
//! Phase 2, the optimal scale. Greedy saturation never releases a joint, so
//! its scale is not always the largest feasible one: on random 3×7 problems
//! about 7 % ended below it (worst gap seen 0.31) and about 0.2 % were scaled
//! although the full task was feasible. So when phase 1 ends with a scale
//! below 1, the linear programme
//!
//! `max s` subject to `J q̇ = s ẋ`, `q̇min ≤ q̇ ≤ q̇max`, `0 ≤ s ≤ 1`
//!
//! is solved exactly by a dense bounded-variable primal simplex over
//! `(q̇, s)` with m equality rows (an m×m basis, refactored by LU at every
//! step; see `Lp` below). Its steps are SNS's moves in the spirit of Flacco's
//! Opt-SNS, made exact: a joint at a bound is *released* (enters the basis)
//! when its reduced cost, the Lagrange multiplier of its bound, says the scale
//! grows as it leaves the bound; the joint that then blocks is *saturated*
//! (leaves the basis at its bound). Without damping it starts from the greedy
//! solution (typically 0–2 steps); otherwise from `q̇ = clamp(0)`, `s = 0`,
//! with a phase of one artificial variable per task row when the bounds do
//! not contain 0. The answer:
//!
//! - zero damping: the programme's optimal vertex, scale `s*`,
//!   `J q̇ = s* ẋ` to round-off (the basis' LU is better conditioned than the
//!   Gram matrix of step 2, so it is preferred to an equal greedy solution).
//!   The tests compare `s*` with two independent exhaustive optima (all
//!   vertices, all facets of the zonotope `J·box`) on thousands of random
//!   problems (3×7, 2×5, 6×7, 3×8, 3×32, the LWR's Jacobian; bounds around
//!   0, excluding 0, at 0, infinite): every one is at the optimum, within
//!   about 1e-14.
//! - damping `λ > 0`: the greedy scale is that of the damped solution (the
//!   task met approximately), the vertex meets the task exactly; the vertex
//!   is returned only when its scale is larger. So the scale is never below
//!   the undamped optimum (unless the step cap stopped the simplex), and
//!   where damping gives the larger scale (near singularities) the damped
//!   greedy answer is kept as before.
//!
//! Iteration bound: the greedy loop computes at most `max(1, n − m + 1) ≤ n`
//! pseudoinverses, the simplex takes at most [`max_pivots`]`(n, m) =
//! 4 (n + m + 1)` steps (pivots and bound flips; 44 for 3×7). The entering
//! variable is the one with the largest reduced cost, or the smallest index
//! (Bland) after a degenerate step, so in exact arithmetic the simplex cannot
//! cycle, and the cap is a time bound against round-off, not part of the
//! method: the most steps seen in the tests
//! (about 115 000 solves with `SNS_TRIALS=20`) were 14 (3×8, 6×7). Should the
//! cap ever stop it, the better of its feasible point and the greedy solution
//! is returned (feasible, perhaps not optimal). [`SnsResult::iterations`]
//! counts both phases and stays within [`max_iterations`].
//!
//! Cost (3×7, one core of the development machine, release build): a cycle
//! whose pseudoinverse fits costs what it did (≈ 0.18 µs, one iteration);
//! a scaled one ≈ 1.5 µs (greedy already optimal) to 2.3 µs (releases
//! needed) without damping, ≈ 2.4–3.5 µs with the avoidance layer's damping
//! (a cold start), against ≈ 1.1–1.4 µs for greedy SNS alone.
//!
//! `(JW)^# = (JW)ᵀ (JW (JW)ᵀ + λ² I)⁻¹` with the caller's damping `λ` (0 for
//! the exact pseudoinverse; with `λ > 0` the task is met only approximately,
//! `J q̇ ≈ s ẋ`, but everything about the bounds still holds exactly).
//!
//! Guarantees: the returned `q̇` satisfies the bounds; it is clamped into them
//! at the very end as a safety net and [`SnsResult::clamp_correction`]
//! reports by how much (round-off only, ≤ a few 1e-10; larger means a bug).
//! When the unconstrained (damped) pseudoinverse solution is feasible it is
//! returned unchanged with scale 1 (phase 2 does not run). With zero damping
//! the scale is the largest feasible one. When no scale `s > 0` is feasible,
//! the result is the point of the box nearest to zero (zero when the bounds
//! contain it), scale 0. The result is deterministic (no randomness, fixed
//! tie-breaking).
//!
//! Bounds with `q̇min > q̇max` are refused with
//! [`SnsError::InconsistentBounds`] rather than silently repaired: which side
//! should win depends on where the bounds came from (see
//! [`crate::avoidance`], which builds consistent ones). Bounds that do not
//! contain zero (a joint that must move, e.g. back inside its position range)
//! are allowed; infinite bounds are allowed, NaN is not.
//!
//! No allocation after [`SnsSolver::new`]: all buffers are preallocated and
//! the small m×m factorisations are done in place (phri's one Cholesky,
//! [`phri_model::cholesky_factor`], for the pseudoinverses; an LU with
//! partial pivoting for the simplex basis, which is not symmetric).

use nalgebra::{DMatrixView, DMatrixViewMut, Dim, Matrix, RawStorage};
use phri_model::{check_len, cholesky_factor, cholesky_solve, LengthError};

/// Most joints a solver handles (the saturation set is a `u32` bitmask).
pub const MAX_JOINTS: usize = 32;

/// Clamping corrections above this are reported by [`SnsResult::clamped`].
pub const CLAMP_REPORT: f64 = 1e-9;

/// Relative tolerance of "inside the bounds".
const INSIDE_TOL: f64 = 1e-10;

/// Relative threshold (to the largest squared row norm of `J`) below which a
/// pivot of the Gram matrix `JW (JW)ᵀ` counts as zero in the rank test.
const RANK_EPS: f64 = 1e-10;

/// Round-off margin when the scales of the greedy and the optimal phase are
/// compared.
const SCALE_GAIN: f64 = 1e-12;

/// Relative pivot tolerance of the simplex ratio test (to the largest entry
/// of the direction).
const PIVOT_TOL: f64 = 1e-11;

/// Relative tolerance of a reduced cost (to the magnitude of its terms).
const COST_TOL: f64 = 1e-11;

/// Relative feasibility slack of the ratio test (Harris' first pass).
const RATIO_SLACK: f64 = 1e-12;

/// A column joins the crash basis when the part of it outside the span of
/// the columns taken is at least this fraction of its norm.
const CRASH_TOL: f64 = 1e-6;

/// Most simplex steps (pivots and bound flips) of the optimal phase for `n`
/// joints and `m` task rows.
pub const fn max_pivots(n: usize, m: usize) -> u32 {
    (4 * (n + m + 1)) as u32
}

/// Bound on [`SnsResult::iterations`] for `n` joints and `m` task rows: the
/// greedy loop (at most `n` pseudoinverses) and the simplex steps
/// ([`max_pivots`]).
pub const fn max_iterations(n: usize, m: usize) -> u32 {
    n as u32 + max_pivots(n, m)
}

/// Why [`SnsSolver::solve`] refused a problem.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum SnsError {
    /// a slice or Jacobian whose length does not fit the joints or the task
    #[error(transparent)]
    Dimension(#[from] LengthError),
    /// a Jacobian with fewer rows than the task needs
    #[error("{what}: expected at least {min} rows, got {got}")]
    TooFewRows {
        /// the Jacobian, e.g. `task jacobian`
        what: &'static str,
        /// the rows it needs at least
        min: usize,
        /// the rows it has
        got: usize,
    },
    /// a task of no rows, or of more than the solver was built for
    #[error("task dimension {m} is outside 1..={m_max}")]
    TaskDimension {
        /// the task's rows
        m: usize,
        /// the most the solver takes
        m_max: usize,
    },
    /// a joint whose lower velocity bound is above its upper one
    #[error("joint {joint}: velocity bounds are inconsistent (min > max)")]
    InconsistentBounds {
        /// the joint's index
        joint: usize,
    },
    /// a NaN or infinite input
    #[error("non-finite {what}")]
    NonFinite {
        /// the input: `task velocity`, `jacobian`, `damping` or `velocity bound`
        what: &'static str,
    },
}

/// The answer of [`SnsSolver::solve`], borrowing the solver's buffer.
#[derive(Clone, Copy, Debug)]
pub struct SnsResult<'a> {
    /// joint velocity (n), inside the bounds
    pub qd: &'a [f64],
    /// task scale `s ∈ [0, 1]`: `J q̇ = s ẋ` (exactly for zero damping)
    pub scale: f64,
    /// joints held at a bound in the returned solution (bit per joint): the
    /// greedy loop's saturated joints, or the programme's non-basic joints at
    /// a bound
    pub saturated: u32,
    /// pseudoinverse solutions computed by the greedy loop plus simplex steps
    /// of the optimal phase (at most [`max_iterations`])
    pub iterations: u32,
    /// the greedy loop ended because `rank(JW) < m` (or the pseudoinverse
    /// was degenerate) and a scaled solution was returned
    pub rank_limited: bool,
    /// largest change made by the final safety clamp (round-off only)
    pub clamp_correction: f64,
}

impl SnsResult<'_> {
    /// The final safety clamp changed something by more than [`CLAMP_REPORT`]
    /// (it should not).
    pub fn clamped(&self) -> bool {
        self.clamp_correction > CLAMP_REPORT
    }
}

/// Preallocated SNS solver for `n` joints and tasks of up to `m_max` rows.
#[derive(Clone, Debug)]
pub struct SnsSolver {
    n: usize,
    m_max: usize,
    /// task Jacobian, m×n row-major
    j: Vec<f64>,
    xd: Vec<f64>,
    qd_n: Vec<f64>,
    /// `a`, `b` of the best scaled solution: `q̇* = s* a* + b*`
    best_a: Vec<f64>,
    best_b: Vec<f64>,
    qd: Vec<f64>,
    a: Vec<f64>,
    tol: Vec<f64>,
    /// Cholesky factor of `JW (JW)ᵀ + λ² I`, m×m column-major (lower triangle)
    chol: Vec<f64>,
    /// scratch of the pivoted Cholesky of the rank test, m×m
    piv: Vec<f64>,
    y1: Vec<f64>,
    y2: Vec<f64>,
    r: Vec<f64>,
    /// the linear programme of the optimal phase
    lp: Lp,
}

impl SnsSolver {
    /// A solver for `n` joints (1..=[`MAX_JOINTS`]) and up to `m_max` task rows.
    ///
    /// # Panics
    /// If `n` or `m_max` is zero or `n > MAX_JOINTS`.
    pub fn new(n: usize, m_max: usize) -> SnsSolver {
        assert!(
            (1..=MAX_JOINTS).contains(&n),
            "SnsSolver: n = {n} outside 1..={MAX_JOINTS}"
        );
        assert!(m_max >= 1, "SnsSolver: m_max must be at least 1");
        SnsSolver {
            n,
            m_max,
            j: vec![0.0; m_max * n],
            xd: vec![0.0; m_max],
            qd_n: vec![0.0; n],
            best_a: vec![0.0; n],
            best_b: vec![0.0; n],
            qd: vec![0.0; n],
            a: vec![0.0; n],
            tol: vec![0.0; n],
            chol: vec![0.0; m_max * m_max],
            piv: vec![0.0; m_max * m_max],
            y1: vec![0.0; m_max],
            y2: vec![0.0; m_max],
            r: vec![0.0; m_max],
            lp: Lp::new(n, m_max),
        }
    }

    /// Number of joints.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Largest task dimension.
    pub fn m_max(&self) -> usize {
        self.m_max
    }

    /// The last solution (zeros before the first solve).
    pub fn qd(&self) -> &[f64] {
        &self.qd
    }

    /// Solve for a task Jacobian `j` (m×n, any nalgebra matrix or view; m =
    /// `xdot.len()`), task velocity `xdot`, bounds `qd_min`, `qd_max` (n) and
    /// pseudoinverse damping `damping` (≥ 0, task units).
    pub fn solve<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(
        &mut self,
        j: &Matrix<f64, R, C, S>,
        xdot: &[f64],
        qd_min: &[f64],
        qd_max: &[f64],
        damping: f64,
    ) -> Result<SnsResult<'_>, SnsError> {
        let m = self.check_task(xdot)?;
        let n = self.n;
        check_len("jacobian rows", m, j.nrows())?;
        check_len("jacobian columns", n, j.ncols())?;
        for r in 0..m {
            for c in 0..n {
                self.j[r * n + c] = j[(r, c)];
            }
        }
        self.solve_copied(m, qd_min, qd_max, damping)
    }

    /// As [`SnsSolver::solve`] with the Jacobian given row-major in a slice of
    /// length `xdot.len() × n`.
    pub fn solve_row_major(
        &mut self,
        j: &[f64],
        xdot: &[f64],
        qd_min: &[f64],
        qd_max: &[f64],
        damping: f64,
    ) -> Result<SnsResult<'_>, SnsError> {
        let m = self.check_task(xdot)?;
        check_len("jacobian (row-major m×n)", m * self.n, j.len())?;
        self.j[..m * self.n].copy_from_slice(j);
        self.solve_copied(m, qd_min, qd_max, damping)
    }

    fn check_task(&mut self, xdot: &[f64]) -> Result<usize, SnsError> {
        let m = xdot.len();
        if m == 0 || m > self.m_max {
            return Err(SnsError::TaskDimension {
                m,
                m_max: self.m_max,
            });
        }
        if xdot.iter().any(|x| !x.is_finite()) {
            return Err(SnsError::NonFinite {
                what: "task velocity",
            });
        }
        self.xd[..m].copy_from_slice(xdot);
        Ok(m)
    }

    fn solve_copied(
        &mut self,
        m: usize,
        qd_min: &[f64],
        qd_max: &[f64],
        damping: f64,
    ) -> Result<SnsResult<'_>, SnsError> {
        let n = self.n;
        self.check_inputs(m, qd_min, qd_max, damping)?;
        let lambda2 = damping * damping;
        // scale of J for the relative rank test: the largest squared row norm
        let jscale = (0..m)
            .map(|r| {
                self.j[r * n..(r + 1) * n]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
            })
            .fold(0.0f64, f64::max);

        // phase 1: greedy SNS
        let greedy = self.greedy(m, qd_min, qd_max, lambda2, jscale);
        let best = greedy.best;
        let mut iterations = greedy.iterations;
        let rank_limited = greedy.rank_limited;
        let mut answer = if greedy.feasible {
            Answer::Full(greedy.free)
        } else {
            Answer::Best
        };
        // phase 2: the linear programme, when the greedy scale may be improved
        if !greedy.feasible && best.s < 1.0 {
            let (vertex, pivots) = self.linear_programme(m, qd_min, qd_max, lambda2, &best);
            iterations += pivots;
            if let Some(s) = vertex {
                answer = Answer::Vertex(s);
            }
        }
        let (scale, saturated) = self.take_answer(answer, &best, qd_min, qd_max);
        let clamp_correction = self.clamp_inside(qd_min, qd_max);
        Ok(SnsResult {
            qd: &self.qd,
            scale,
            saturated,
            iterations,
            rank_limited,
            clamp_correction,
        })
    }

    /// The task's Jacobian (its first `m` rows), the damping and the bounds
    /// finite and consistent; each joint's tolerance of "inside" set.
    fn check_inputs(
        &mut self,
        m: usize,
        qd_min: &[f64],
        qd_max: &[f64],
        damping: f64,
    ) -> Result<(), SnsError> {
        let n = self.n;
        check_len("qd_min", n, qd_min.len())?;
        check_len("qd_max", n, qd_max.len())?;
        if self.j[..m * n].iter().any(|x| !x.is_finite()) {
            return Err(SnsError::NonFinite { what: "jacobian" });
        }
        if !damping.is_finite() {
            return Err(SnsError::NonFinite { what: "damping" });
        }
        for k in 0..n {
            let (lo, hi) = (qd_min[k], qd_max[k]);
            if lo.is_nan() || hi.is_nan() {
                return Err(SnsError::NonFinite {
                    what: "velocity bound",
                });
            }
            if lo > hi {
                return Err(SnsError::InconsistentBounds { joint: k });
            }
            let mag = [lo, hi]
                .iter()
                .filter(|x| x.is_finite())
                .fold(0.0f64, |acc, x| acc.max(x.abs()));
            self.tol[k] = INSIDE_TOL * (1.0 + mag);
        }
        Ok(())
    }

    /// Phase 2: the linear programme's vertex, warm-started from the greedy
    /// `best` without damping (`lambda2` = 0); its scale when it wins over
    /// the greedy one, and the pivots it took.
    fn linear_programme(
        &mut self,
        m: usize,
        qd_min: &[f64],
        qd_max: &[f64],
        lambda2: f64,
        best: &Best,
    ) -> (Option<f64>, u32) {
        let n = self.n;
        // without damping the greedy solution is a feasible start
        let start = if lambda2 == 0.0 && best.found {
            for k in 0..n {
                self.lp.z[k] = best.s * self.best_a[k] + self.best_b[k];
            }
            self.lp.z[n] = best.s;
            LpStart::Warm
        } else {
            LpStart::Cold
        };
        let lp = self
            .lp
            .solve(&self.j, &self.xd[..m], n, m, qd_min, qd_max, start);
        let s = self.lp.z[n].clamp(0.0, 1.0);
        // without damping the vertex is the optimum, computed with better
        // conditioning than the greedy solution (an LU of the basis, not a
        // Cholesky of the Gram matrix, whose round-off can put the greedy
        // scale a little above the optimum): it wins. With damping the
        // greedy solution meets the task only approximately, the vertex
        // exactly: the larger scale wins.
        let wins = if lambda2 == 0.0 {
            lp.optimal || s >= best.s - SCALE_GAIN
        } else {
            s > best.s + SCALE_GAIN
        };
        let finite = self.lp.z[..n].iter().all(|v| v.is_finite());
        let vertex = (lp.feasible && s > 0.0 && wins && finite).then_some(s);
        (vertex, lp.pivots)
    }

    /// The answer's solution into `self.qd`: its scale and the joints held
    /// at a bound (a bit per joint).
    fn take_answer(
        &mut self,
        answer: Answer,
        best: &Best,
        qd_min: &[f64],
        qd_max: &[f64],
    ) -> (f64, u32) {
        let n = self.n;
        let all: u32 = if n == 32 { u32::MAX } else { (1u32 << n) - 1 };
        match answer {
            // self.qd holds the solution that fits at scale 1
            Answer::Full(free) => (1.0, all & !free),
            Answer::Vertex(s) => {
                let mut held = 0u32;
                for k in 0..n {
                    let v = self.lp.z[k];
                    self.qd[k] = v;
                    if !self.lp.is_basic(k) && (v == qd_min[k] || v == qd_max[k]) {
                        held |= 1 << k;
                    }
                }
                (s, held)
            }
            Answer::Best if best.found => {
                // q̇ = q̇_N* + (JW*)^# (s* ẋ − J q̇_N*) = s* a* + b*, evaluated from the
                // very a*, b* whose intervals gave s*: no second factorisation
                // whose round-off could differ from the one the scale came from
                for k in 0..n {
                    self.qd[k] = best.s * self.best_a[k] + self.best_b[k];
                }
                (best.s, all & !best.free)
            }
            Answer::Best => {
                // nothing better than standing still: the box point nearest to 0
                let mut held = 0u32;
                for k in 0..n {
                    self.qd[k] = 0.0f64.clamp(qd_min[k], qd_max[k]);
                    if self.qd[k] != 0.0 {
                        held |= 1 << k;
                    }
                }
                (0.0, held)
            }
        }
    }

    /// The safety net: `self.qd` clamped into the bounds (inside by
    /// construction, up to round-off); the largest correction \[rad/s\]
    /// (∞: a joint was not finite, and stands still within its bounds).
    fn clamp_inside(&mut self, qd_min: &[f64], qd_max: &[f64]) -> f64 {
        let mut clamp_correction = 0.0f64;
        for k in 0..self.n {
            let v = self.qd[k];
            if v.is_finite() {
                let c = v.clamp(qd_min[k], qd_max[k]);
                clamp_correction = clamp_correction.max((c - v).abs());
                self.qd[k] = c;
            } else {
                self.qd[k] = 0.0f64.clamp(qd_min[k], qd_max[k]);
                clamp_correction = f64::INFINITY;
            }
        }
        clamp_correction
    }

    /// One greedy iteration's solution with the joints of `free` (the
    /// others held at `qd_n`): `a` = (JW)^# ẋ and `qd` = q̇_N + (JW)^# (ẋ − J q̇_N)
    /// (from the factorisation of [`SnsSolver::factor`]).
    fn solve_free(&mut self, m: usize, free: u32) {
        let n = self.n;
        // y1 = A⁻¹ ẋ, y2 = A⁻¹ (ẋ − J q̇_N)
        for r in 0..m {
            let row = &self.j[r * n..(r + 1) * n];
            let jqn: f64 = row.iter().zip(&self.qd_n).map(|(x, y)| x * y).sum();
            self.y1[r] = self.xd[r];
            self.r[r] = self.xd[r] - jqn;
        }
        Self::chol_solve(&self.chol, m, &mut self.y1);
        self.y2[..m].copy_from_slice(&self.r[..m]);
        Self::chol_solve(&self.chol, m, &mut self.y2);
        for k in 0..n {
            if free & (1 << k) != 0 {
                let (mut ak, mut ck) = (0.0, 0.0);
                for r in 0..m {
                    ak += self.j[r * n + k] * self.y1[r];
                    ck += self.j[r * n + k] * self.y2[r];
                }
                self.a[k] = ak;
                self.qd[k] = self.qd_n[k] + ck;
            } else {
                // the column of JW is zero: so is this row of (JW)^#
                self.a[k] = 0.0;
                self.qd[k] = self.qd_n[k];
            }
        }
    }

    /// The admissible interval of the task's scale s from every joint's
    /// q̇min ≤ s a + b ≤ q̇max: its lower and upper ends, each with the joint
    /// that sets it.
    #[allow(clippy::type_complexity)]
    fn admissible_scale(
        &self,
        qd_min: &[f64],
        qd_max: &[f64],
    ) -> ((f64, Option<usize>), (f64, Option<usize>)) {
        let n = self.n;
        let (mut s_hi, mut crit_hi) = (f64::INFINITY, None);
        let (mut s_lo, mut crit_lo) = (f64::NEG_INFINITY, None);
        for k in 0..n {
            let (a, b) = (self.a[k], self.qd[k] - self.a[k]);
            let (lo, hi) = if a.abs() <= self.tol[k] {
                // over s ∈ [0, 1] the joint moves by less than the tolerance
                if b >= qd_min[k] - self.tol[k] && b <= qd_max[k] + self.tol[k] {
                    (f64::NEG_INFINITY, f64::INFINITY)
                } else {
                    (f64::INFINITY, f64::NEG_INFINITY)
                }
            } else {
                let (t_min, t_max) = ((qd_min[k] - b) / a, (qd_max[k] - b) / a);
                if a > 0.0 {
                    (t_min, t_max)
                } else {
                    (t_max, t_min)
                }
            };
            if hi < s_hi {
                s_hi = hi;
                crit_hi = Some(k);
            }
            if lo > s_lo {
                s_lo = lo;
                crit_lo = Some(k);
            }
        }
        ((s_lo, crit_lo), (s_hi, crit_hi))
    }

    /// The greedy SNS loop (steps 1-6 of the module doc). The best scaled
    /// solution is left in `best_a`, `best_b`; when the solution fits at
    /// scale 1 it is left in `self.qd`.
    fn greedy(
        &mut self,
        m: usize,
        qd_min: &[f64],
        qd_max: &[f64],
        lambda2: f64,
        jscale: f64,
    ) -> GreedyEnd {
        let n = self.n;
        let mut free: u32 = if n == 32 { u32::MAX } else { (1u32 << n) - 1 };
        self.qd_n.fill(0.0);
        let mut best = Best {
            s: 0.0,
            free,
            found: false,
        };
        let mut iterations = 0u32;
        let mut rank_limited = false;
        let mut feasible = false;
        loop {
            iterations += 1;
            if !self.factor(m, free, lambda2) {
                rank_limited = true;
                break;
            }
            self.solve_free(m, free);
            if (0..n).all(|k| {
                self.qd[k] >= qd_min[k] - self.tol[k] && self.qd[k] <= qd_max[k] + self.tol[k]
            }) {
                feasible = true;
                break;
            }

            let ((s_lo, crit_lo), (s_hi, crit_hi)) = self.admissible_scale(qd_min, qd_max);
            let s_cap = s_hi.min(1.0);
            let scale = if s_hi >= 0.0 && s_lo <= s_cap {
                s_cap
            } else {
                0.0
            };
            if scale > best.s {
                best.s = scale;
                best.free = free;
                for k in 0..n {
                    self.best_a[k] = self.a[k];
                    self.best_b[k] = self.qd[k] - self.a[k];
                }
                best.found = true;
            }
            // the most critical joint: one that is violated at s = 1
            let crit = if s_hi < 1.0 {
                crit_hi
            } else if s_lo > 1.0 {
                crit_lo
            } else {
                None // inside up to round-off: keep the best found
            };
            let Some(c) = crit else { break };
            free &= !(1 << c);
            self.qd_n[c] = self.qd[c].clamp(qd_min[c], qd_max[c]);
            if (free.count_ones() as usize) < m || self.rank_deficient(m, free, jscale) {
                rank_limited = true;
                break;
            }
        }
        GreedyEnd {
            feasible,
            free,
            iterations,
            rank_limited,
            best,
        }
    }

    /// Cholesky factor of `JW (JW)ᵀ + λ² I` into `self.chol` (phri's one
    /// Cholesky, [`phri_model::cholesky_factor`]); false if it is not
    /// (numerically) positive definite.
    fn factor(&mut self, m: usize, free: u32, lambda2: f64) -> bool {
        gram(&self.j, self.n, m, free, &mut self.chol);
        let mut max_diag = 0.0f64;
        for r in 0..m {
            self.chol[r * m + r] += lambda2;
            max_diag = max_diag.max(self.chol[r * m + r]);
        }
        // the Gram matrix is symmetric: its row-major buffer is its column-major one
        let a = DMatrixViewMut::from_slice(&mut self.chol[..m * m], m, m);
        cholesky_factor(a, max_diag * 1e-14).is_ok()
    }

    /// Solve `(JW (JW)ᵀ + λ² I) x = b` in place with the factor of [`SnsSolver::factor`].
    fn chol_solve(chol: &[f64], m: usize, b: &mut [f64]) {
        cholesky_solve(DMatrixView::from_slice(&chol[..m * m], m, m), &mut b[..m]);
    }

    /// `rank(JW) < m`, by a diagonally pivoted Cholesky of `JW (JW)ᵀ`.
    ///
    /// This is a rank test, not a solver: the pivoting orders the columns by
    /// their remaining norm so that a (numerically) dependent row shows as a
    /// small pivot whatever its position. The solves use the unpivoted
    /// [`phri_model::cholesky_factor`] of the damped matrix ([`SnsSolver::factor`]).
    fn rank_deficient(&mut self, m: usize, free: u32, jscale: f64) -> bool {
        gram(&self.j, self.n, m, free, &mut self.piv);
        let tol = RANK_EPS * jscale;
        let a = &mut self.piv[..m * m];
        for k in 0..m {
            // pivot: the largest remaining diagonal entry
            let mut p = k;
            for i in k + 1..m {
                if a[i * m + i] > a[p * m + p] {
                    p = i;
                }
            }
            let d = a[p * m + p];
            if d.is_nan() || d <= tol {
                return true;
            }
            if p != k {
                for c in 0..m {
                    a.swap(k * m + c, p * m + c);
                }
                for r in 0..m {
                    a.swap(r * m + k, r * m + p);
                }
            }
            let l = d.sqrt();
            for i in k + 1..m {
                a[i * m + k] /= l;
            }
            for i in k + 1..m {
                for c in k + 1..=i {
                    let v = a[i * m + c] - a[i * m + k] * a[c * m + k];
                    a[i * m + c] = v;
                    a[c * m + i] = v;
                }
            }
        }
        false
    }
}

/// The best scaled solution of the greedy loop.
#[derive(Clone, Copy)]
struct Best {
    s: f64,
    free: u32,
    /// some iteration gave a scale above 0 (`s`, `free`, `best_a`, `best_b` valid)
    found: bool,
}

/// How a greedy loop ended.
struct GreedyEnd {
    /// the solution in `qd` fits at scale 1
    feasible: bool,
    /// the free set at the end
    free: u32,
    iterations: u32,
    rank_limited: bool,
    best: Best,
}

/// Which solution [`SnsSolver::solve`] returns.
enum Answer {
    /// `qd` fits at scale 1 with this free set
    Full(u32),
    /// the programme's vertex `lp.z` with this scale
    Vertex(f64),
    /// the best scaled greedy solution (or standing still)
    Best,
}

/// How the linear programme ended.
struct LpEnd {
    /// phase 2 was reached: `z` is a feasible point
    feasible: bool,
    /// and it is optimal (no step cap, no numerical stop)
    optimal: bool,
    /// simplex steps taken
    pivots: u32,
}

/// Where the simplex starts.
enum LpStart {
    /// `q̇ = clamp(0)`, `s = 0`; phase 1 (artificials) when `J q̇ ≠ 0`
    Cold,
    /// the feasible point already in `z[..=n]` (the greedy solution without
    /// damping): phase 2 directly
    Warm,
}

/// The optimal phase: `max s` subject to `J q̇ − s ẋ = 0`, `q̇min ≤ q̇ ≤ q̇max`,
/// `0 ≤ s ≤ 1`, by a dense bounded-variable primal simplex.
///
/// Variables: the `n` joint velocities, `s` (index `n`) and one artificial
/// per task row (index `n + 1 + r`, column `±e_r`). A cold start from
/// `q̇ = clamp(0)`, `s = 0` with `J q̇ ≠ 0` makes the artificials the basis,
/// absorbing the residual, and phase 1 drives them to 0; otherwise (a warm
/// start from the greedy solution, or bounds containing 0) the artificials
/// are fixed at 0 and only fill the basis where the other columns cannot
/// (`rank [J, −ẋ] < m`). The start basis is chosen by a crash (Gram-Schmidt
/// over the columns in order of preference: `s`, joints strictly inside
/// their bounds, the others, the artificials). Phase 2 maximises `s`.
/// Non-basic variables sit at a bound or, until they first move, at their
/// start value (infinite bounds need no special case). Every step refactors
/// the m×m basis (LU with partial pivoting) and recomputes the basic values
/// from the non-basic ones, so no round-off accumulates. Entering: the
/// largest reduced cost (Dantzig), or the smallest index (Bland) after a
/// degenerate step. Leaving: Harris' two-pass ratio test (the largest pivot
/// among the near-ties).
#[derive(Clone, Debug)]
struct Lp {
    /// columns of the n + 1 + m variables, m entries each: `J` for the
    /// joints, `−ẋ` for `s`, `±e_r` for the artificials
    a: Vec<f64>,
    /// values and bounds of the variables
    z: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// basic variable of each row, and each variable's row (`NONBASIC` if none)
    basis: Vec<usize>,
    pos: Vec<usize>,
    /// LU factor of the basis matrix (m×m column-major) and its row order
    lu: Vec<f64>,
    perm: Vec<usize>,
    y: Vec<f64>,
    alpha: Vec<f64>,
    tmp: Vec<f64>,
    /// crash: preference order of the variables, orthonormal directions taken
    order: Vec<usize>,
    ortho: Vec<f64>,
}

const NONBASIC: usize = usize::MAX;

impl Lp {
    fn new(n: usize, m_max: usize) -> Lp {
        let nv = n + 1 + m_max;
        Lp {
            a: vec![0.0; nv * m_max],
            z: vec![0.0; nv],
            lo: vec![0.0; nv],
            hi: vec![0.0; nv],
            basis: vec![0; m_max],
            pos: vec![NONBASIC; nv],
            lu: vec![0.0; m_max * m_max],
            perm: vec![0; m_max],
            y: vec![0.0; m_max],
            alpha: vec![0.0; m_max],
            tmp: vec![0.0; m_max],
            order: vec![0; nv],
            ortho: vec![0.0; m_max * m_max],
        }
    }

    fn is_basic(&self, v: usize) -> bool {
        self.pos[v] != NONBASIC
    }

    /// Objective coefficient of variable `v` in phase 1 (minimise the
    /// artificials) or phase 2 (maximise `s`).
    #[inline]
    fn cost(n: usize, v: usize, phase1: bool) -> f64 {
        match (phase1, v.cmp(&n)) {
            (true, std::cmp::Ordering::Greater) => -1.0,
            (false, std::cmp::Ordering::Equal) => 1.0,
            _ => 0.0,
        }
    }

    /// Run the simplex from `start`; when `feasible`, the optimum (or, if
    /// the step cap stopped it, the best point reached) is in `z`.
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &mut self,
        j: &[f64],
        xd: &[f64],
        n: usize,
        m: usize,
        qd_min: &[f64],
        qd_max: &[f64],
        start: LpStart,
    ) -> LpEnd {
        let nv = n + 1 + m;
        let infeasible = |pivots| LpEnd {
            feasible: false,
            optimal: false,
            pivots,
        };
        // columns and bounds
        for k in 0..n {
            for r in 0..m {
                self.a[k * m + r] = j[r * n + k];
            }
            self.lo[k] = qd_min[k];
            self.hi[k] = qd_max[k];
        }
        for r in 0..m {
            self.a[n * m + r] = -xd[r];
        }
        self.lo[n] = 0.0;
        self.hi[n] = 1.0;
        for r in 0..m {
            let v = n + 1 + r;
            self.a[v * m..(v + 1) * m].fill(0.0);
            self.a[v * m + r] = 1.0;
            self.lo[v] = 0.0;
            self.hi[v] = 0.0;
            self.z[v] = 0.0;
        }
        self.pos[..nv].fill(NONBASIC);

        let mut phase1 = false;
        let mut feas_tol = 0.0;
        match start {
            LpStart::Cold => {
                for k in 0..n {
                    let z = 0.0f64.clamp(qd_min[k], qd_max[k]);
                    if !z.is_finite() {
                        return infeasible(0);
                    }
                    self.z[k] = z;
                }
                self.z[n] = 0.0;
                let mut residual_scale = 0.0f64;
                for r in 0..m {
                    let (mut jq, mut mag) = (0.0, 0.0);
                    for k in 0..n {
                        let t = j[r * n + k] * self.z[k];
                        jq += t;
                        mag += t.abs();
                    }
                    residual_scale = residual_scale.max(mag);
                    if jq != 0.0 {
                        // J q̇ ± w e_r = 0 with w = |J q̇|_r ≥ 0
                        let v = n + 1 + r;
                        self.a[v * m + r] = if jq > 0.0 { -1.0 } else { 1.0 };
                        self.z[v] = jq.abs();
                        self.hi[v] = f64::INFINITY;
                        phase1 = true;
                    }
                }
                feas_tol = 1e-12 * (1.0 + residual_scale);
                if phase1 {
                    for r in 0..m {
                        self.basis[r] = n + 1 + r;
                        self.pos[n + 1 + r] = r;
                    }
                } else {
                    self.crash(n, m);
                }
            }
            LpStart::Warm => {
                // z[..=n] holds a feasible point; snap round-off onto the bounds
                for k in 0..n {
                    let t = INSIDE_TOL * (1.0 + self.z[k].abs());
                    if (self.z[k] - qd_min[k]).abs() <= t {
                        self.z[k] = qd_min[k];
                    } else if (self.z[k] - qd_max[k]).abs() <= t {
                        self.z[k] = qd_max[k];
                    }
                    self.z[k] = self.z[k].clamp(qd_min[k], qd_max[k]);
                }
                self.z[n] = self.z[n].clamp(0.0, 1.0);
                self.crash(n, m);
            }
        }

        self.run(n, m, phase1, feas_tol)
    }

    /// The simplex iterations from the start set up by [`Lp::solve`].
    fn run(&mut self, n: usize, m: usize, mut phase1: bool, feas_tol: f64) -> LpEnd {
        let nv = n + 1 + m;
        let Lp {
            a,
            z,
            lo,
            hi,
            basis,
            pos,
            lu,
            perm,
            y,
            alpha,
            tmp,
            ..
        } = self;
        let (a, z, lo, hi) = (&a[..nv * m], &mut z[..nv], &mut lo[..nv], &mut hi[..nv]);
        let (basis, pos) = (&mut basis[..m], &mut pos[..nv]);
        let (lu, perm) = (&mut lu[..m * m], &mut perm[..m]);
        let (y, alpha, tmp) = (&mut y[..m], &mut alpha[..m], &mut tmp[..m]);
        let end = |feasible: bool, optimal: bool, pivots: u32| LpEnd {
            feasible,
            optimal,
            pivots,
        };

        let cap = max_pivots(n, m);
        let mut pivots = 0u32;
        let mut degenerate = false;
        loop {
            if !lu_factor(a, basis, lu, perm, m) {
                // cannot happen with the pivot tolerance; keep what we have
                return end(!phase1, false, pivots);
            }
            // basic values from the non-basic ones: B z_B = −Σ_N A_v z_v
            alpha.fill(0.0);
            for v in 0..nv {
                let zv = z[v];
                if pos[v] == NONBASIC && zv != 0.0 {
                    for (x, c) in alpha.iter_mut().zip(&a[v * m..(v + 1) * m]) {
                        *x -= c * zv;
                    }
                }
            }
            lu_solve(lu, perm, alpha, tmp);
            for r in 0..m {
                z[basis[r]] = alpha[r];
            }
            if phase1 {
                let w: f64 = z[n + 1..].iter().sum();
                if w <= feas_tol {
                    // feasible: fix the artificials at 0 and maximise s
                    phase1 = false;
                    hi[n + 1..].fill(0.0);
                }
            }
            // simplex multipliers: Bᵀ y = c_B
            for r in 0..m {
                y[r] = Self::cost(n, basis[r], phase1);
            }
            lu_solve_t(lu, perm, y, tmp);
            // pricing
            let enter = price(
                Columns { a, m, n },
                y,
                (&*z, &*lo, &*hi),
                pos,
                phase1,
                degenerate,
            );
            let Some((e, dir)) = enter else {
                // optimal (phase 2), or no feasible point (phase 1)
                return end(!phase1, !phase1, pivots);
            };
            if pivots >= cap {
                return end(!phase1, false, pivots);
            }
            pivots += 1;

            // direction: B α = A_e; z_B moves by −dir t α
            alpha.copy_from_slice(&a[e * m..(e + 1) * m]);
            lu_solve(lu, perm, alpha, tmp);
            let Some(step) = ratio_step(
                e,
                dir,
                alpha,
                (&mut *z, &*lo, &*hi),
                (&mut *basis, &mut *pos),
                degenerate,
            ) else {
                return end(!phase1, false, pivots);
            };
            degenerate = step == 0.0;
        }
    }

    /// Choose a start basis (the artificials fixed at 0, phase 2): the first
    /// m linearly independent columns in the order `s`, joints strictly
    /// inside their bounds, the other joints that can move, the artificials
    /// (unit vectors, so the basis is always complete).
    fn crash(&mut self, n: usize, m: usize) {
        let mut len = 0;
        self.order[len] = n;
        len += 1;
        for pass in 0..2 {
            for k in 0..n {
                let inside = self.z[k] > self.lo[k] && self.z[k] < self.hi[k];
                if (pass == 0 && inside) || (pass == 1 && !inside && self.lo[k] < self.hi[k]) {
                    self.order[len] = k;
                    len += 1;
                }
            }
        }
        for r in 0..m {
            self.order[len] = n + 1 + r;
            len += 1;
        }
        let mut taken = 0;
        for i in 0..len {
            let v = self.order[i];
            let col = &self.a[v * m..(v + 1) * m];
            let norm0 = col.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm0 == 0.0 {
                continue;
            }
            self.tmp[..m].copy_from_slice(col);
            for t in 0..taken {
                let q = &self.ortho[t * m..(t + 1) * m];
                let d: f64 = q.iter().zip(&self.tmp[..m]).map(|(a, b)| a * b).sum();
                for r in 0..m {
                    self.tmp[r] -= d * q[r];
                }
            }
            let norm = self.tmp[..m].iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm <= CRASH_TOL * norm0 {
                continue;
            }
            for r in 0..m {
                self.ortho[taken * m + r] = self.tmp[r] / norm;
            }
            self.basis[taken] = v;
            self.pos[v] = taken;
            taken += 1;
            if taken == m {
                break;
            }
        }
    }
}

/// LU factor (partial pivoting) of the basis matrix (the columns of `a`, m
/// entries each, named by `basis`) into `lu` (m×m column-major) and the row
/// order `perm`; false if (numerically) singular.
fn lu_factor(a: &[f64], basis: &[usize], lu: &mut [f64], perm: &mut [usize], m: usize) -> bool {
    let mut amax = 0.0f64;
    for (c, &v) in basis.iter().enumerate() {
        for r in 0..m {
            let x = a[v * m + r];
            lu[r + c * m] = x;
            amax = amax.max(x.abs());
        }
    }
    for (r, p) in perm.iter_mut().enumerate() {
        *p = r;
    }
    let tiny = 1e-14 * amax;
    for k in 0..m {
        let mut p = k;
        for i in k + 1..m {
            if lu[i + k * m].abs() > lu[p + k * m].abs() {
                p = i;
            }
        }
        if !(lu[p + k * m].abs() > tiny) {
            return false;
        }
        if p != k {
            for c in 0..m {
                lu.swap(k + c * m, p + c * m);
            }
            perm.swap(k, p);
        }
        let piv = lu[k + k * m];
        for i in k + 1..m {
            let l = lu[i + k * m] / piv;
            lu[i + k * m] = l;
            for c in k + 1..m {
                lu[i + c * m] -= l * lu[k + c * m];
            }
        }
    }
    true
}

/// `b ← B⁻¹ b` with the factor of [`lu_factor`] (`tmp`: scratch of length m).
fn lu_solve(lu: &[f64], perm: &[usize], b: &mut [f64], tmp: &mut [f64]) {
    let m = b.len();
    for i in 0..m {
        let mut s = b[perm[i]];
        for k in 0..i {
            s -= lu[i + k * m] * tmp[k];
        }
        tmp[i] = s;
    }
    for i in (0..m).rev() {
        let mut s = tmp[i];
        for k in i + 1..m {
            s -= lu[i + k * m] * tmp[k];
        }
        tmp[i] = s / lu[i + i * m];
    }
    b.copy_from_slice(tmp);
}

/// `y ← B⁻ᵀ y` with the factor of [`lu_factor`] (`tmp`: scratch of length m).
fn lu_solve_t(lu: &[f64], perm: &[usize], y: &mut [f64], tmp: &mut [f64]) {
    let m = y.len();
    // Uᵀ w = y
    for i in 0..m {
        let mut s = y[i];
        for k in 0..i {
            s -= lu[k + i * m] * tmp[k];
        }
        tmp[i] = s / lu[i + i * m];
    }
    // Lᵀ v = w
    for i in (0..m).rev() {
        let mut s = tmp[i];
        for k in i + 1..m {
            s -= lu[k + i * m] * tmp[k];
        }
        tmp[i] = s;
    }
    for i in 0..m {
        y[perm[i]] = tmp[i];
    }
}

/// `out = JW (JW)ᵀ` (m×m row-major) for the columns in `free`.
fn gram(j: &[f64], n: usize, m: usize, free: u32, out: &mut [f64]) {
    for r in 0..m {
        for c in 0..=r {
            let mut s = 0.0;
            for k in 0..n {
                if free & (1 << k) != 0 {
                    s += j[r * n + k] * j[c * n + k];
                }
            }
            out[r * m + c] = s;
            out[c * m + r] = s;
        }
    }
}

/// The simplex's constraint columns: `n + 1 + m` variables of `m` entries.
#[derive(Clone, Copy)]
struct Columns<'a> {
    a: &'a [f64],
    m: usize,
    n: usize,
}

/// Pricing: the non-basic variable to enter, and the way it moves (+1 up,
/// −1 down), from the multipliers `y`: the largest reduced cost, or the
/// smallest index after a degenerate step (Bland); none at the optimum.
fn price(
    cols: Columns<'_>,
    y: &[f64],
    (z, lo, hi): (&[f64], &[f64], &[f64]),
    pos: &[usize],
    phase1: bool,
    degenerate: bool,
) -> Option<(usize, f64)> {
    let Columns { a, m, n } = cols;
    let nv = n + 1 + m;
    let mut enter: Option<(usize, f64)> = None;
    let mut enter_d = 0.0f64;
    for v in 0..nv {
        if pos[v] != NONBASIC || lo[v] >= hi[v] {
            continue;
        }
        let (mut aty, mut mag) = (0.0, 0.0);
        for (c, yr) in a[v * m..(v + 1) * m].iter().zip(y.iter()) {
            let t = c * yr;
            aty += t;
            mag += t.abs();
        }
        let c = Lp::cost(n, v, phase1);
        let d = c - aty;
        let tol = COST_TOL * (c.abs() + mag);
        let dir = if d > tol && z[v] < hi[v] {
            1.0
        } else if d < -tol && z[v] > lo[v] {
            -1.0
        } else {
            continue;
        };
        if degenerate {
            // Bland: the smallest index
            if enter.is_none() {
                enter = Some((v, dir));
            }
        } else if d.abs() > enter_d {
            enter_d = d.abs();
            enter = Some((v, dir));
        }
    }
    enter
}

/// The step of entering variable `e` moving `dir` along `alpha` (the basic
/// values move by −dir·t·α): to its other bound, or to where a basic
/// variable leaves (Harris' two passes: the largest pivot among the rows
/// that block within a relaxed step; Bland's smallest index after a
/// degenerate step). Moves `z`, and the basis when a variable leaves; the
/// step taken, none when the ray is unbounded or no row can leave (only
/// round-off can make either: s ≤ 1).
fn ratio_step(
    e: usize,
    dir: f64,
    alpha: &[f64],
    (z, lo, hi): (&mut [f64], &[f64], &[f64]),
    (basis, pos): (&mut [usize], &mut [usize]),
    degenerate: bool,
) -> Option<f64> {
    let m = basis.len();
    let amax = alpha.iter().fold(0.0f64, |acc, x| acc.max(x.abs()));
    let ptol = PIVOT_TOL * amax;
    let flip = if dir > 0.0 {
        hi[e] - z[e]
    } else {
        z[e] - lo[e]
    };
    // Harris pass 1: the step with the bounds relaxed by a slack
    let mut t_relaxed = f64::INFINITY;
    for r in 0..m {
        let delta = -dir * alpha[r];
        if delta.abs() <= ptol {
            continue;
        }
        let b = basis[r];
        let lim = if delta > 0.0 {
            (hi[b] + RATIO_SLACK * (1.0 + hi[b].abs()) - z[b]) / delta
        } else {
            (lo[b] - RATIO_SLACK * (1.0 + lo[b].abs()) - z[b]) / delta
        };
        t_relaxed = t_relaxed.min(lim.max(0.0));
    }
    let step;
    if flip <= t_relaxed {
        // the entering variable reaches its other bound first
        step = flip;
        if step.is_infinite() {
            // unbounded ray: only round-off can produce it (s ≤ 1)
            return None;
        }
        for r in 0..m {
            z[basis[r]] -= dir * step * alpha[r];
        }
        z[e] = if dir > 0.0 { hi[e] } else { lo[e] };
    } else {
        // Harris pass 2: among the blocking rows, the largest pivot
        let (mut leave, mut best_abs, mut t) = (usize::MAX, 0.0f64, 0.0f64);
        for r in 0..m {
            let delta = -dir * alpha[r];
            if delta.abs() <= ptol {
                continue;
            }
            let b = basis[r];
            let lim = if delta > 0.0 {
                (hi[b] - z[b]) / delta
            } else {
                (lo[b] - z[b]) / delta
            };
            let lim = lim.max(0.0);
            let better = if degenerate {
                // Bland: the smallest index among the ties
                leave == usize::MAX || lim < t || (lim == t && b < basis[leave])
            } else {
                delta.abs() > best_abs
            };
            if lim <= t_relaxed && better {
                leave = r;
                best_abs = delta.abs();
                t = lim;
            }
        }
        if leave == usize::MAX {
            return None;
        }
        step = t;
        for r in 0..m {
            z[basis[r]] -= dir * step * alpha[r];
        }
        z[e] += dir * step;
        let b = basis[leave];
        z[b] = if -dir * alpha[leave] > 0.0 {
            hi[b]
        } else {
            lo[b]
        };
        pos[b] = NONBASIC;
        basis[leave] = e;
        pos[e] = leave;
    }
    Some(step)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn free_problem_is_the_pseudoinverse() {
        let mut s = SnsSolver::new(2, 1);
        let j = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
        let r = s.solve(&j, &[1.0], &[-5.0; 2], &[5.0; 2], 0.0).unwrap();
        assert_eq!(r.scale, 1.0);
        assert!((r.qd[0] - 0.5).abs() < 1e-12 && (r.qd[1] - 0.5).abs() < 1e-12);
        assert_eq!(r.saturated, 0);
        assert_eq!(r.iterations, 1);
    }

    #[test]
    fn inconsistent_bounds_are_refused() {
        let mut s = SnsSolver::new(2, 1);
        let e = s
            .solve_row_major(&[1.0, 1.0], &[1.0], &[0.0, 1.0], &[1.0, 0.5], 0.0)
            .unwrap_err();
        assert_eq!(e, SnsError::InconsistentBounds { joint: 1 });
    }

    #[test]
    fn rank_test_sees_dependent_rows() {
        let mut s = SnsSolver::new(3, 2);
        s.j[..6].copy_from_slice(&[1.0, 2.0, 3.0, 2.0, 4.0, 6.0]);
        assert!(s.rank_deficient(2, 0b111, 56.0));
        s.j[..6].copy_from_slice(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        assert!(!s.rank_deficient(2, 0b111, 1.0));
        assert!(s.rank_deficient(2, 0b101, 1.0));
    }

    /// splitmix64, uniform in [lo, hi)
    fn uniform(state: &mut u64, lo: f64, hi: f64) -> f64 {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        lo + (hi - lo) * (((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64)
    }

    #[test]
    fn lu_solves_both_ways() {
        let m = 4;
        let mut rng = 3u64;
        let mut lp = Lp::new(5, m);
        for v in 0..5 * m {
            lp.a[v] = uniform(&mut rng, -1.0, 1.0);
        }
        let basis = [4, 0, 3, 1];
        assert!(lu_factor(&lp.a, &basis, &mut lp.lu, &mut lp.perm, m));
        let b = [0.3, -1.0, 2.0, 0.5];
        let (mut x, mut y) = (b, b);
        lu_solve(&lp.lu, &lp.perm, &mut x, &mut lp.tmp);
        lu_solve_t(&lp.lu, &lp.perm, &mut y, &mut lp.tmp);
        for r in 0..m {
            // B x = b and Bᵀ y = b, B's columns the basis' columns of a
            let bx: f64 = (0..m).map(|c| lp.a[basis[c] * m + r] * x[c]).sum();
            let bty: f64 = (0..m).map(|i| lp.a[basis[r] * m + i] * y[i]).sum();
            assert!((bx - b[r]).abs() < 1e-12 && (bty - b[r]).abs() < 1e-12);
        }
        // a dependent basis is refused
        let dependent = [0, 1, 2, 0];
        assert!(!lu_factor(&lp.a, &dependent, &mut lp.lu, &mut lp.perm, m));
    }

    /// The simplex from a cold start (phase 1 when the bounds exclude 0)
    /// and from the greedy solution reach the same scale.
    #[test]
    fn cold_and_warm_starts_agree() {
        let (m, n) = (3, 7);
        let mut rng = 11u64;
        let mut sns = SnsSolver::new(n, m);
        let mut compared = 0;
        for _ in 0..2000 {
            let j: Vec<f64> = (0..m * n).map(|_| uniform(&mut rng, -1.0, 1.0)).collect();
            let xd: Vec<f64> = (0..m).map(|_| uniform(&mut rng, -2.0, 2.0)).collect();
            let mut lo: Vec<f64> = (0..n).map(|_| -uniform(&mut rng, 0.02, 1.0)).collect();
            let mut hi: Vec<f64> = (0..n).map(|_| uniform(&mut rng, 0.02, 1.0)).collect();
            if uniform(&mut rng, 0.0, 1.0) < 0.5 {
                // a joint that must move
                lo[0] = uniform(&mut rng, 0.05, 0.3);
                hi[0] = lo[0] + 0.2;
            }
            let r = sns.solve_row_major(&j, &xd, &lo, &hi, 0.0).unwrap();
            let warm = r.scale;
            if warm == 1.0 || warm == 0.0 {
                continue;
            }
            let cold = sns.lp.solve(&j, &xd, n, m, &lo, &hi, LpStart::Cold);
            assert!(cold.feasible && cold.optimal && cold.pivots <= max_pivots(n, m));
            assert!(
                (sns.lp.z[n] - warm).abs() < 1e-12,
                "{} vs {warm}",
                sns.lp.z[n]
            );
            compared += 1;
        }
        assert!(compared > 500, "{compared}");
    }
}
