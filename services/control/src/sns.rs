//! Saturation in the Null Space (SNS): velocity-level inverse kinematics of a
//! single task under hard joint-velocity bounds, scaling the task down when it
//! cannot be met (Flacco, De Luca, Khatib, ICRA 2012 / T-RO 2015; the
//! paper's ref. \[23\]).
//!
//! Given a task Jacobian `J` (m×n), a task velocity `ẋ` (m) and joint velocity
//! bounds `q̇min ≤ q̇ ≤ q̇max`:
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
//!    else go to 2.
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
//! Limitation (of SNS itself, not of this implementation): the saturation is
//! greedy, a saturated joint is never released, so the scale found is not
//! always the largest feasible one (the linear programme `max s` subject to
//! `J q̇ = s ẋ` and the bounds). On random 3×7 problems (`tests/sns.rs`)
//! about 93 % reach that optimum, the worst gap seen was 0.31, and about
//! 0.2 % are scaled although the full task was feasible. The scale is never
//! above the optimum, and it is 1 whenever the pseudoinverse solution fits.
//!
//! `(JW)^# = (JW)ᵀ (JW (JW)ᵀ + λ² I)⁻¹` with the caller's damping `λ` (0 for
//! the exact pseudoinverse; with `λ > 0` the task is met only approximately,
//! `J q̇ ≈ s ẋ`, but everything about the bounds still holds exactly).
//!
//! Guarantees: the returned `q̇` satisfies the bounds; it is clamped into them
//! at the very end as a safety net and [`SnsResult::clamp_correction`]
//! reports by how much (round-off only, ≤ a few 1e-10; larger means a bug).
//! When the unconstrained (damped) pseudoinverse solution is feasible it is
//! returned unchanged with scale 1. When no scale `s > 0` was found feasible,
//! the result is the point of the box nearest to zero (zero when the bounds
//! contain it), scale 0.
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
//! [`phri_model::cholesky_factor`]).

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

/// Why [`SnsSolver::solve`] refused a problem.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum SnsError {
    #[error(transparent)]
    Dimension(#[from] LengthError),
    /// a Jacobian with fewer rows than the task needs
    #[error("{what}: expected at least {min} rows, got {got}")]
    TooFewRows {
        what: &'static str,
        min: usize,
        got: usize,
    },
    #[error("task dimension {m} is outside 1..={m_max}")]
    TaskDimension { m: usize, m_max: usize },
    #[error("joint {joint}: velocity bounds are inconsistent (min > max)")]
    InconsistentBounds { joint: usize },
    #[error("non-finite {what}")]
    NonFinite { what: &'static str },
}

/// The answer of [`SnsSolver::solve`], borrowing the solver's buffer.
#[derive(Clone, Copy, Debug)]
pub struct SnsResult<'a> {
    /// joint velocity (n), inside the bounds
    pub qd: &'a [f64],
    /// task scale `s ∈ [0, 1]`: `J q̇ = s ẋ` (exactly for zero damping)
    pub scale: f64,
    /// joints held at a bound in the returned solution (bit per joint)
    pub saturated: u32,
    /// pseudoinverse solutions computed in the loop
    pub iterations: u32,
    /// the loop ended because `rank(JW) < m` (or the pseudoinverse was
    /// degenerate) and the best scaled solution was returned
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

        let all: u32 = if n == 32 { u32::MAX } else { (1u32 << n) - 1 };
        let mut free = all;
        self.qd_n.fill(0.0);
        let mut best_s = 0.0f64;
        let mut best_free = all;
        let mut have_best = false;
        let mut iterations = 0u32;
        let mut rank_limited = false;
        let mut feasible = false;

        loop {
            iterations += 1;
            if !self.factor(m, free, lambda2) {
                rank_limited = true;
                break;
            }
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
            if (0..n).all(|k| {
                self.qd[k] >= qd_min[k] - self.tol[k] && self.qd[k] <= qd_max[k] + self.tol[k]
            }) {
                feasible = true;
                break;
            }

            // admissible interval of s per joint from q̇min ≤ s a + b ≤ q̇max
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
            let s_cap = s_hi.min(1.0);
            let scale = if s_hi >= 0.0 && s_lo <= s_cap {
                s_cap
            } else {
                0.0
            };
            if scale > best_s {
                best_s = scale;
                best_free = free;
                for k in 0..n {
                    self.best_a[k] = self.a[k];
                    self.best_b[k] = self.qd[k] - self.a[k];
                }
                have_best = true;
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

        let (scale, saturated);
        if feasible {
            scale = 1.0;
            saturated = all & !free;
        } else if have_best {
            // q̇ = q̇_N* + (JW*)^# (s* ẋ − J q̇_N*) = s* a* + b*, evaluated from the
            // very a*, b* whose intervals gave s*: no second factorisation
            // whose round-off could differ from the one the scale came from
            for k in 0..n {
                self.qd[k] = best_s * self.best_a[k] + self.best_b[k];
            }
            scale = best_s;
            saturated = all & !best_free;
        } else {
            // nothing better than standing still: the box point nearest to 0
            let mut held = 0u32;
            for k in 0..n {
                self.qd[k] = 0.0f64.clamp(qd_min[k], qd_max[k]);
                if self.qd[k] != 0.0 {
                    held |= 1 << k;
                }
            }
            scale = 0.0;
            saturated = held;
        }

        // safety net: the solution is inside by construction, up to round-off
        let mut clamp_correction = 0.0f64;
        for k in 0..n {
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
        Ok(SnsResult {
            qd: &self.qd,
            scale,
            saturated,
            iterations,
            rank_limited,
            clamp_correction,
        })
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
}
