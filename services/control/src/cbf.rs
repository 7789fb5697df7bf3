//! The control-barrier safety filter (`[avoidance] law = "cbf"`,
//! REFERENCE §16): each period, the joint velocities closest to the
//! nominal ones (what the task, its null-space posture and the
//! collaboration ask, resolved by SNS without any repulsion) such that
//! every control point's distance to its obstacle shrinks no faster than a
//! barrier allows:
//!
//! ```text
//! minimise   ½ (q̇ − q̇_nom)ᵀ W (q̇ − q̇_nom),   W = w_t J_eeᵀ J_ee + I
//!            + Σᵢ (ρ σᵢ + ½ σᵢ²)
//! subject to nᵢᵀ Jᵢ q̇ + σᵢ ≥ −γ (dᵢ − d_s) + v_h,i   (one row per control point)
//!            nᵢᵀ Jᵢ q̇ ≥ −v_ssm,i                   (where SSM bounds a point clear of d_s)
//!            q̇_min ≤ q̇ ≤ q̇_max,  σᵢ ≥ 0              (joint limits, speed scale)
//! ```
//!
//! `nᵢ` is the unit direction from the obstacle to the point, `Jᵢ` the
//! point's linear Jacobian, `dᵢ` its distance, `d_s` the distance kept
//! (a margin plus perception's age at a person's speed), `v_h,i ≥ 0` the
//! person's measured approach toward the point, `v_ssm,i ≥ 0` the approach
//! that speed and separation monitoring allows it: a hard row, which q̇ = 0
//! always keeps. Motion along or away from an obstacle costs nothing; only
//! the approach is braked, and with `w_t ≫ 1` the null space gives way
//! before the end effector does.
//!
//! σᵢ is row i's slack, priced linearly at ρ ([`SLACK_PRICE`]): an exact
//! penalty, so every σᵢ = 0 whenever the barriers can be kept, and where
//! they cannot, only the rows that cannot be kept give (an arm between a person's torso and a
//! hand reaching in, or a retreat faster than the joints allow) the
//! solution still moves every point away as well as it can instead of
//! freezing between them. Such periods are counted
//! ([`CbfCounters::slack_periods`]).
//!
//! Solved by `phri-qp` (Goldfarb-Idnani), warm-started from the last
//! period's active set while the same points carry rows; nothing is
//! allocated per period.

use nalgebra::{Matrix6xX, Vector3};
use phri_config::AvoidanceConfig;
use phri_qp::{Problem, QpError, Settings, Start, Workspace};

use crate::snapshot::{Reader, Snapshot, Writer};

/// Most control points that carry a row.
pub const MAX_ROWS: usize = 64;

/// ρ: the price of the barriers' shared slack per m/s, far above any
/// multiplier of a keepable barrier (W's entries are ≤ ~10³).
pub const SLACK_PRICE: f64 = 1e6;

/// The slack counts as needed above this \[m/s\].
const SLACK_NEEDED_M_S: f64 = 1e-6;

/// Room for the warm start's active set in a snapshot: as many rows as can
/// be active at once for the most joints a message carries.
pub const HINT_ROOM: usize = phri_ipc::MAX_DOF + MAX_ROWS;

/// The filter's figures over the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CbfCounters {
    /// periods the filter ran
    pub periods: u64,
    /// periods in which some barrier row was active (it changed the motion)
    pub braking_periods: u64,
    /// periods in which no velocity inside the bounds kept every barrier:
    /// the slack moved the points away as well as it could
    pub slack_periods: u64,
    /// periods the solver failed (the reference braked to rest)
    pub infeasible_periods: u64,
    /// the most active-set changes of one solve
    pub max_iterations: u64,
}

/// The filter, preallocated for `n` joints.
pub struct CbfFilter {
    cfg: AvoidanceConfig,
    n: usize,
    ws: Workspace,
    /// the rows' −nᵢᵀJᵢ, MAX_ROWS×n row-major
    a: Vec<f64>,
    /// H over (q̇, σ₁…σₘ): W and 1s, row-major
    h: Vec<f64>,
    /// (−W q̇_nom, ρ…ρ)
    g: Vec<f64>,
    /// the rows over (q̇, σ): [−nᵢᵀJᵢ, −eᵢ], row-major
    c: Vec<f64>,
    /// the bounds over (q̇, σ)
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// the rows' γ(dᵢ − d_s) − v_h,i (a barrier's), v_ssm,i (a separation's)
    d: Vec<f64>,
    /// per row: it has a slack (a barrier's) or not (a separation's)
    soft: Vec<bool>,
    rows: usize,
    /// the control points carrying this period's rows (bit k: point k)
    points: u64,
    /// ... and those carrying a separation's row too
    separated: u64,
    /// the rows' layout of the last solved period ([`CbfFilter::layout`])
    layout_before: u64,
    qd: Vec<f64>,
    counters: CbfCounters,
}

impl CbfFilter {
    /// A filter for `n` joints (at most 64) with the `[avoidance]` settings.
    pub fn new(n: usize, cfg: &AvoidanceConfig) -> Result<CbfFilter, QpError> {
        Ok(CbfFilter {
            cfg: cfg.clone(),
            n,
            ws: Workspace::new(n + MAX_ROWS, MAX_ROWS, Settings::default())?,
            a: vec![0.0; MAX_ROWS * n],
            h: vec![0.0; (n + MAX_ROWS) * (n + MAX_ROWS)],
            g: vec![0.0; n + MAX_ROWS],
            c: vec![0.0; MAX_ROWS * (n + MAX_ROWS)],
            lo: vec![0.0; n + MAX_ROWS],
            hi: vec![0.0; n + MAX_ROWS],
            d: vec![0.0; MAX_ROWS],
            soft: vec![true; MAX_ROWS],
            rows: 0,
            points: 0,
            separated: 0,
            layout_before: 0,
            qd: vec![0.0; n],
            counters: CbfCounters::default(),
        })
    }

    /// The settings in use.
    pub fn config(&self) -> &AvoidanceConfig {
        &self.cfg
    }

    /// The run's figures so far.
    pub fn counters(&self) -> CbfCounters {
        self.counters
    }

    /// Start a period: no rows.
    pub fn begin(&mut self) {
        self.rows = 0;
        self.points = 0;
        self.separated = 0;
    }

    /// The rows' layout this period, for the warm start: the points with a
    /// barrier, those with a separation's row too (a collision of two
    /// layouts costs a warm start's speed, never the solution).
    fn layout(&self) -> u64 {
        self.points.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ self.separated
    }

    /// The barrier of control point `k` (Jacobian `jac`, its first three
    /// rows linear, base frame): unit `away` from its obstacle to the point,
    /// distance `d` \[m\], the distance kept `d_s` \[m\], the person's
    /// approach toward it `v_h` \[m/s\] (≥ 0; 0 when unknown). Returns
    /// false (the point carries no row) when the rows are full or a number
    /// is not finite.
    pub fn add_point(
        &mut self,
        k: usize,
        jac: &Matrix6xX<f64>,
        away: &Vector3<f64>,
        d: f64,
        d_s: f64,
        v_h: f64,
    ) -> bool {
        let n = self.n;
        if self.rows >= MAX_ROWS || jac.ncols() != n || !(d.is_finite() && d_s.is_finite()) {
            return false;
        }
        let row = &mut self.a[self.rows * n..(self.rows + 1) * n];
        for (j, r) in row.iter_mut().enumerate() {
            *r = -(away.x * jac[(0, j)] + away.y * jac[(1, j)] + away.z * jac[(2, j)]);
        }
        if !row.iter().all(|x| x.is_finite()) || row.iter().all(|&x| x == 0.0) {
            return false;
        }
        self.d[self.rows] = self.cfg.gamma * (d - d_s) - v_h.max(0.0);
        self.soft[self.rows] = true;
        self.rows += 1;
        if k < 64 {
            self.points |= 1 << k;
        }
        true
    }

    /// The point of the barrier added last (control point `k`) approaches
    /// its obstacle at most `v_max` \[m/s\] (speed and separation
    /// monitoring's bound, ≥ 0; NaN: 0), a row without slack. Whether it
    /// is tighter than the point's barrier; `None` (no row) when the rows
    /// are full, the last row is not a barrier or `v_max` is infinite.
    pub fn bound_approach(&mut self, k: usize, v_max: f64) -> Option<bool> {
        let n = self.n;
        let last = self.rows.checked_sub(1)?;
        if self.rows >= MAX_ROWS || !self.soft[last] || v_max == f64::INFINITY {
            return None;
        }
        let v_max = match v_max.is_nan() {
            true => 0.0,
            false => v_max.max(0.0),
        };
        self.a.copy_within(last * n..(last + 1) * n, self.rows * n);
        self.d[self.rows] = v_max;
        self.soft[self.rows] = false;
        self.rows += 1;
        if k < 64 {
            self.separated |= 1 << k;
        }
        Some(v_max < self.d[last])
    }

    /// The filtered joint velocities \[rad/s\] for the nominal `qd_nom`
    /// within `[lo, hi]`, the end effector's Jacobian `jac_ee` weighting
    /// its task. An infeasible period is counted (the caller brakes).
    pub fn solve(
        &mut self,
        jac_ee: &Matrix6xX<f64>,
        qd_nom: &[f64],
        (lo, hi): (&[f64], &[f64]),
    ) -> Result<&[f64], QpError> {
        let n = self.n;
        self.counters.periods += 1;
        if self.rows == 0 {
            // nothing near: the nominal motion, as it is
            self.qd.copy_from_slice(qd_nom);
            self.layout_before = 0;
            return Ok(&self.qd);
        }
        // variables: the n joint velocities, then one slack per barrier
        let (w, rows) = (self.cfg.task_weight, self.rows);
        let m = n + self.soft[..rows].iter().filter(|&&s| s).count();
        self.h[..m * m].fill(0.0);
        for i in 0..n {
            for j in 0..n {
                let jj: f64 = (0..3).map(|r| jac_ee[(r, i)] * jac_ee[(r, j)]).sum();
                self.h[i * m + j] = w * jj + if i == j { 1.0 } else { 0.0 };
            }
        }
        for i in n..m {
            self.h[i * m + i] = 1.0;
        }
        for i in 0..n {
            self.g[i] = -(0..n).map(|j| self.h[i * m + j] * qd_nom[j]).sum::<f64>();
        }
        self.g[n..m].fill(SLACK_PRICE);
        self.c[..rows * m].fill(0.0);
        let mut slack = n;
        for r in 0..rows {
            self.c[r * m..r * m + n].copy_from_slice(&self.a[r * n..(r + 1) * n]);
            if self.soft[r] {
                self.c[r * m + slack] = -1.0;
                slack += 1;
            }
        }
        self.lo[..n].copy_from_slice(lo);
        self.hi[..n].copy_from_slice(hi);
        self.lo[n..m].fill(0.0);
        self.hi[n..m].fill(f64::INFINITY);
        let start = match self.layout() == self.layout_before {
            true => Start::Warm,
            false => Start::Cold,
        };
        let p = Problem {
            n: m,
            h: &self.h[..m * m],
            g: &self.g[..m],
            c: &self.c[..rows * m],
            d: &self.d[..rows],
            bounds: Some((&self.lo[..m], &self.hi[..m])),
        };
        match phri_qp::solve(&mut self.ws, &p, start) {
            Ok(s) => {
                self.qd.copy_from_slice(&s.x[..n]);
                let slack = s.x[n..m].iter().any(|&x| x > SLACK_NEEDED_M_S);
                self.counters.slack_periods += u64::from(slack);
                let braking = s.active.iter().any(|&r| r < self.rows);
                self.counters.braking_periods += u64::from(braking);
                self.counters.max_iterations =
                    self.counters.max_iterations.max(s.iterations as u64);
                self.layout_before = self.layout();
                Ok(&self.qd)
            }
            Err(e) => {
                self.counters.infeasible_periods += 1;
                self.ws.clear_hint();
                self.layout_before = 0;
                Err(e)
            }
        }
    }
}

/// What the filter carries from one period to the next: the control points
/// of the last solved period and the active set it ended with, the warm
/// start of the next solve. The solution does not depend on it, but its
/// rounding does: a standby that adopts it answers to the bit (its own
/// warm start, from the periods it rested through, answered up to 1e-6 Nm
/// apart). Fixed length: the set's length, then [`HINT_ROOM`] rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WarmStart {
    /// the rows' layout of the last solved period
    layout: u64,
    /// rows of the active set in `rows`
    len: u32,
    /// the active set's rows
    rows: [u32; HINT_ROOM],
}

impl Default for WarmStart {
    fn default() -> WarmStart {
        WarmStart {
            layout: 0,
            len: 0,
            rows: [0; HINT_ROOM],
        }
    }
}

impl Snapshot for WarmStart {
    fn save(&self, w: &mut Writer<'_>) {
        self.layout.save(w);
        self.len.save(w);
        self.rows.save(w);
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        let mut read = WarmStart::default();
        read.layout.load(r);
        read.len.load(r);
        read.rows.load(r);
        if read.len as usize > HINT_ROOM {
            r.fail();
        }
        r.store(self, read);
    }
}

impl CbfFilter {
    /// The warm start of the next solve, to carry to a peer.
    pub fn warm_start(&self) -> WarmStart {
        let hint = self.ws.hint();
        let len = hint.len().min(HINT_ROOM);
        let mut rows = [0; HINT_ROOM];
        for (r, &h) in rows.iter_mut().zip(&hint[..len]) {
            *r = h as u32;
        }
        WarmStart {
            layout: self.layout_before,
            len: len as u32,
            rows,
        }
    }

    /// Solve on from a peer's warm start.
    pub fn adopt_warm_start(&mut self, w: &WarmStart) {
        self.layout_before = w.layout;
        let mut hint = [0usize; HINT_ROOM];
        let len = (w.len as usize).min(HINT_ROOM);
        for (h, &r) in hint.iter_mut().zip(&w.rows[..len]) {
            *h = r as usize;
        }
        self.ws.set_hint(&hint[..len]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::AvoidanceLaw;

    fn cfg() -> AvoidanceConfig {
        AvoidanceConfig {
            law: AvoidanceLaw::Cbf,
            gamma: 5.0,
            margin_m: 0.05,
            human_speed_m_s: 1.6,
            task_weight: 100.0,
            pass_after_s: 1.0,
            accel_limit: 30.0,
            jerk_limit: 6000.0,
            collaboration_speed_m_s: 1.0,
        }
    }

    /// A planar 3-joint "arm" whose point moves as q̇ (identity Jacobian).
    fn identity_jac(n: usize) -> Matrix6xX<f64> {
        let mut j = Matrix6xX::zeros(n);
        for i in 0..3.min(n) {
            j[(i, i)] = 1.0;
        }
        j
    }

    #[test]
    fn motion_along_or_away_from_an_obstacle_passes_unchanged() {
        let mut f = CbfFilter::new(3, &cfg()).unwrap();
        let j = identity_jac(3);
        let away = Vector3::new(1.0, 0.0, 0.0);
        let (lo, hi) = ([-1.0; 3], [1.0; 3]);
        for nominal in [[0.0, 0.5, 0.0], [0.3, 0.2, -0.1]] {
            f.begin();
            assert!(f.add_point(1, &j, &away, 0.10, 0.06, 0.0));
            let qd = f.solve(&j, &nominal, (&lo, &hi)).unwrap().to_vec();
            for (a, b) in qd.iter().zip(nominal) {
                assert!((a - b).abs() < 1e-9, "{qd:?} vs {nominal:?}");
            }
        }
    }

    #[test]
    fn the_approach_is_braked_to_the_barrier_and_the_rest_kept() {
        let mut f = CbfFilter::new(3, &cfg()).unwrap();
        let j = identity_jac(3);
        let away = Vector3::new(1.0, 0.0, 0.0);
        let (lo, hi) = ([-1.0; 3], [1.0; 3]);
        f.begin();
        // 10 cm away, keep 6 cm: approach at most 5 × 0.04 = 0.2 m/s
        assert!(f.add_point(1, &j, &away, 0.10, 0.06, 0.0));
        let qd = f.solve(&j, &[-0.8, 0.3, 0.0], (&lo, &hi)).unwrap().to_vec();
        assert!((qd[0] + 0.2).abs() < 1e-9, "{qd:?}");
        assert!((qd[1] - 0.3).abs() < 1e-9, "{qd:?}");
        // the person approaching at 0.1 m/s takes that much off
        f.begin();
        assert!(f.add_point(1, &j, &away, 0.10, 0.06, 0.1));
        let qd = f.solve(&j, &[-0.8, 0.3, 0.0], (&lo, &hi)).unwrap().to_vec();
        assert!((qd[0] + 0.1).abs() < 1e-9, "{qd:?}");
        // inside d_s: the point must back off
        f.begin();
        assert!(f.add_point(1, &j, &away, 0.04, 0.06, 0.0));
        let qd = f.solve(&j, &[0.0, 0.0, 0.0], (&lo, &hi)).unwrap().to_vec();
        assert!((qd[0] - 0.1).abs() < 1e-9, "{qd:?}");
        assert_eq!(f.counters().slack_periods, 0);
        assert_eq!(f.counters().periods, 3);
        assert_eq!(f.counters().braking_periods, 3);
    }

    #[test]
    fn the_separation_bounds_the_approach_even_where_a_barrier_needs_slack() {
        let mut f = CbfFilter::new(3, &cfg()).unwrap();
        let j = identity_jac(3);
        let (lo, hi) = ([-1.0; 3], [1.0; 3]);
        assert_eq!(f.bound_approach(1, 0.1), None, "no barrier, no separation");
        // the barrier allows 0.2 m/s toward the obstacle, the separation 0.15
        f.begin();
        assert!(f.add_point(1, &j, &Vector3::x(), 0.10, 0.06, 0.0));
        assert_eq!(f.bound_approach(1, 0.15), Some(true));
        let qd = f.solve(&j, &[-0.8, 0.3, 0.0], (&lo, &hi)).unwrap().to_vec();
        assert!(
            (qd[0] + 0.15).abs() < 1e-9 && (qd[1] - 0.3).abs() < 1e-9,
            "{qd:?}"
        );
        // the separation allows more than the barrier: the barrier's 0.2
        f.begin();
        assert!(f.add_point(1, &j, &Vector3::x(), 0.10, 0.06, 0.0));
        assert_eq!(f.bound_approach(1, 0.5), Some(false));
        assert_eq!(f.bound_approach(1, 0.5), None, "one per barrier");
        let qd = f.solve(&j, &[-0.8, 0.3, 0.0], (&lo, &hi)).unwrap().to_vec();
        assert!((qd[0] + 0.2).abs() < 1e-9, "{qd:?}");
        assert_eq!(f.counters().slack_periods, 0);
        // a point between two obstacles, inside d_s of both: the barriers
        // trade their slack (without the separation, it approached the
        // first at 0.05 m/s), but the point does not approach the one where
        // the separation allows nothing (0, or no number), though the
        // barrier asks more there (it moves away)
        for v in [0.0, f64::NAN] {
            f.begin();
            assert!(f.add_point(1, &j, &Vector3::x(), 0.02, 0.06, 0.0));
            assert_eq!(f.bound_approach(1, v), Some(false));
            assert!(f.add_point(2, &j, &-Vector3::x(), 0.05, 0.06, 0.0));
            let qd = f.solve(&j, &[-0.8, 0.3, 0.5], (&lo, &hi)).unwrap().to_vec();
            assert!(qd[0] >= -1e-9 && (qd[2] - 0.5).abs() < 1e-9, "{qd:?}");
        }
        f.begin();
        assert!(f.add_point(1, &j, &Vector3::x(), 0.02, 0.06, 0.0));
        assert!(f.add_point(2, &j, &-Vector3::x(), 0.05, 0.06, 0.0));
        let qd = f.solve(&j, &[-0.8, 0.3, 0.5], (&lo, &hi)).unwrap().to_vec();
        assert!(qd[0] < -0.04, "{qd:?}");
        assert_eq!(f.counters().slack_periods, 3);
        assert_eq!(f.counters().infeasible_periods, 0);
    }

    #[test]
    fn a_barrier_the_bounds_cannot_keep_backs_off_as_fast_as_they_allow() {
        let mut f = CbfFilter::new(3, &cfg()).unwrap();
        let j = identity_jac(3);
        f.begin();
        // inside d_s by 10 cm: must back off at 0.5 m/s, bounds allow 0.1
        assert!(f.add_point(1, &j, &Vector3::x(), 0.0, 0.10, 0.0));
        let qd = f
            .solve(&j, &[0.0, 0.05, 0.0], (&[-0.1; 3], &[0.1; 3]))
            .unwrap()
            .to_vec();
        assert!(
            (qd[0] - 0.1).abs() < 1e-9 && (qd[1] - 0.05).abs() < 1e-9,
            "{qd:?}"
        );
        assert_eq!(f.counters().slack_periods, 1);
        assert_eq!(f.counters().infeasible_periods, 0);
    }

    #[test]
    fn a_point_between_two_obstacles_leaves_sideways() {
        // obstacles on both sides along x, 2 cm inside d_s: no x velocity
        // keeps both; the point must not freeze, y is free
        let mut f = CbfFilter::new(3, &cfg()).unwrap();
        let j = identity_jac(3);
        f.begin();
        assert!(f.add_point(1, &j, &Vector3::x(), 0.04, 0.06, 0.0));
        assert!(f.add_point(2, &j, &-Vector3::x(), 0.04, 0.06, 0.0));
        let qd = f
            .solve(&j, &[0.0, 0.2, 0.0], (&[-1.0; 3], &[1.0; 3]))
            .unwrap()
            .to_vec();
        assert!(qd[0].abs() < 1e-9 && (qd[1] - 0.2).abs() < 1e-9, "{qd:?}");
        assert_eq!(f.counters().slack_periods, 1);
    }

    #[test]
    fn the_null_space_gives_way_before_the_end_effector() {
        // 3 joints; the end effector moves with joints 0 and 1 (x, y), a
        // body point with joints 1 and 2; its obstacle lies along −y
        let mut f = CbfFilter::new(3, &cfg()).unwrap();
        let mut jee = Matrix6xX::zeros(3);
        jee[(0, 0)] = 1.0;
        jee[(1, 1)] = 1.0;
        let mut jp = Matrix6xX::zeros(3);
        jp[(1, 1)] = 1.0;
        jp[(1, 2)] = 1.0;
        f.begin();
        // the point must not approach: ẏ_p = q̇1 + q̇2 ≥ 0
        assert!(f.add_point(1, &jp, &Vector3::y(), 0.06, 0.06, 0.0));
        let nominal = [0.2, -0.3, 0.0];
        let qd = f
            .solve(&jee, &nominal, (&[-1.0; 3], &[1.0; 3]))
            .unwrap()
            .to_vec();
        // the end effector's task kept (nearly), the null-space joint pays
        assert!(
            (qd[0] - 0.2).abs() < 1e-6 && (qd[1] + 0.3).abs() < 0.01,
            "{qd:?}"
        );
        assert!(qd[1] + qd[2] >= -1e-9 && qd[2] > 0.28, "{qd:?}");
    }
}
