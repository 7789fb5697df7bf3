//! SNS (Saturation in the Null Space) and the avoidance layer around it
//! (paper Sect. V, eqs. 19-20): hand-checked problems, random problems that
//! must all reach the exact linear-programming optimum (two independent
//! exhaustive references, checked against each other), the joint-limit
//! bounds, the sign of eq. 20, the whole layer on the KUKA LWR-IV model, no
//! allocation per call, and an ignored timing (`bench_solve_3x7`).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use nalgebra::{DMatrix, Matrix3xX, Matrix6xX, Vector3};
use phri_control::avoidance::{
    end_effector_velocity, joint_limit_bounds, shape_bounds_for_point, Avoidance, AvoidanceParams,
    ControlPoint,
};
use phri_control::sns::{max_iterations, SnsError, SnsSolver};
use phri_model::{Data, Model};

/// The avoidance settings these tests were written for (V_max = 0.21 m/s).
fn avoidance_params() -> AvoidanceParams {
    AvoidanceParams {
        accel_limit: 10.0,
        horizon_s: 0.05,
        v_max_repulsion: 0.21,
        damping: 0.02,
        position_margin: 0.05,
    }
}

// ---------------------------------------------------------------------------
// allocation counter (per thread, so parallel tests do not interfere)

struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCS.with(|c| c.get())
}

// ---------------------------------------------------------------------------
// helpers

/// splitmix64: a small seeded generator (no extra dependency).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// uniform in [lo, hi)
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

fn lwr4() -> Model {
    Model::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/robots/kuka_lwr4.urdf"
    ))
    .unwrap()
}

fn within(qd: &[f64], lo: &[f64], hi: &[f64]) -> bool {
    qd.iter()
        .zip(lo.iter().zip(hi))
        .all(|(q, (l, h))| q >= l && q <= h)
}

fn mat_vec(j: &DMatrix<f64>, v: &[f64]) -> Vec<f64> {
    (0..j.nrows())
        .map(|r| (0..j.ncols()).map(|c| j[(r, c)] * v[c]).sum())
        .collect()
}

/// `a x = b` for a k×k row-major `a` by Gaussian elimination with partial
/// pivoting, in place (`b` becomes `x`); false if (numerically) singular.
fn solve_square(a: &mut [f64], b: &mut [f64], k: usize) -> bool {
    let scale = a[..k * k].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for c in 0..k {
        let p = (c..k)
            .max_by(|&x, &y| a[x * k + c].abs().total_cmp(&a[y * k + c].abs()))
            .unwrap();
        if !(a[p * k + c].abs() > 1e-11 * scale) {
            return false;
        }
        if p != c {
            for i in 0..k {
                a.swap(p * k + i, c * k + i);
            }
            b.swap(p, c);
        }
        for r in c + 1..k {
            let f = a[r * k + c] / a[c * k + c];
            for i in c..k {
                a[r * k + i] -= f * a[c * k + i];
            }
            b[r] -= f * b[c];
        }
    }
    for r in (0..k).rev() {
        let mut v = b[r];
        for i in r + 1..k {
            v -= a[r * k + i] * b[i];
        }
        b[r] = v / a[r * k + r];
    }
    true
}

/// Determinant of a k×k row-major matrix (consumed), 1 for k = 0.
fn det(a: &mut [f64], k: usize) -> f64 {
    let mut d = 1.0;
    for c in 0..k {
        let p = (c..k)
            .max_by(|&x, &y| a[x * k + c].abs().total_cmp(&a[y * k + c].abs()))
            .unwrap();
        if a[p * k + c] == 0.0 {
            return 0.0;
        }
        if p != c {
            for i in 0..k {
                a.swap(p * k + i, c * k + i);
            }
            d = -d;
        }
        d *= a[c * k + c];
        for r in c + 1..k {
            let f = a[r * k + c] / a[c * k + c];
            for i in c..k {
                a[r * k + i] -= f * a[c * k + i];
            }
        }
    }
    d
}

/// The k-element subsets of `0..n` as bit masks, in increasing order
/// (Gosper's hack).
fn subsets(n: usize, k: usize) -> impl Iterator<Item = u64> {
    let first = if k == 0 { 0 } else { (1u64 << k) - 1 };
    let end = 1u64 << n;
    std::iter::successors((k <= n).then_some(first), move |&x| {
        if x == 0 {
            return None;
        }
        let c = x & x.wrapping_neg();
        let r = x + c;
        let next = (((r ^ x) >> 2) / c) | r;
        (next < end).then_some(next)
    })
}

/// First reference: the exact optimum of the linear programme
/// `max s s.t. J q̇ = s ẋ, lo ≤ q̇ ≤ hi, 0 ≤ s ≤ 1` by enumerating the
/// vertices of its feasible set (every saturation set and every choice of
/// bounds): n + 1 independent active constraints among the m equalities, one
/// finite bound per saturated joint and `s ∈ {0, 1}`. With `s` at 0 or 1,
/// n − m joints are saturated; with `s` free, n − m + 1. `None` when no
/// `s ∈ [0, 1]` is feasible. Needs a vertex to exist: at most one joint with
/// both bounds infinite (its column is not zero).
fn vertex_max_scale(j: &DMatrix<f64>, xd: &[f64], lo: &[f64], hi: &[f64]) -> Option<f64> {
    let (m, n) = j.shape();
    let mut best: Option<f64> = None;
    let (mut a, mut b) = (vec![0.0; m * m], vec![0.0; m]);
    let mut q = vec![0.0; n];
    let ok = |i: usize, v: f64| {
        v >= lo[i] - 1e-10 * (1.0 + lo[i].abs()) && v <= hi[i] + 1e-10 * (1.0 + hi[i].abs())
    };
    let sizes = [n.checked_sub(m), n.checked_sub(m - 1)];
    for subset in sizes.into_iter().flatten().flat_map(|k| subsets(n, k)) {
        let k = subset.count_ones() as usize;
        let s_free = k + m == n + 1;
        let at: Vec<usize> = (0..n).filter(|i| subset & (1 << i) != 0).collect();
        let free: Vec<usize> = (0..n).filter(|i| subset & (1 << i) == 0).collect();
        'choice: for choice in 0u64..(1 << k) {
            for (t, &i) in at.iter().enumerate() {
                q[i] = if choice & (1 << t) != 0 { hi[i] } else { lo[i] };
                if !q[i].is_finite() {
                    continue 'choice;
                }
            }
            let s_values: &[f64] = if s_free { &[f64::NAN] } else { &[0.0, 1.0] };
            for &s_fixed in s_values {
                for r in 0..m {
                    let mut rhs: f64 = -at.iter().map(|&i| j[(r, i)] * q[i]).sum::<f64>();
                    if !s_free {
                        rhs += s_fixed * xd[r];
                    }
                    b[r] = rhs;
                    for (c, &i) in free.iter().enumerate() {
                        a[r * m + c] = j[(r, i)];
                    }
                    if s_free {
                        a[r * m + m - 1] = -xd[r];
                    }
                }
                if !solve_square(&mut a, &mut b, m) {
                    continue;
                }
                let s = if s_free { b[m - 1] } else { s_fixed };
                let nf = if s_free { m - 1 } else { m };
                if (-1e-12..=1.0 + 1e-12).contains(&s)
                    && free.iter().take(nf).enumerate().all(|(c, &i)| ok(i, b[c]))
                {
                    let s = s.clamp(0.0, 1.0);
                    best = Some(best.map_or(s, |x| x.max(s)));
                }
            }
        }
    }
    best
}

/// Second reference, independent of the first: `s ẋ` must lie in the
/// zonotope `Z = {J q̇ : lo ≤ q̇ ≤ hi}` (unbounded with infinite bounds),
/// whose facet normals are orthogonal to m − 1 of its generators (the
/// columns of J). For each such normal `u` (both signs), with the support
/// function `h(u) = Σ_i max(uᵀJ_i lo_i, uᵀJ_i hi_i)`, `s uᵀẋ ≤ h(u)`; the
/// largest `s ∈ [0, 1]` meeting all of them is the optimum (`None` if none
/// does). Needs `J` of full row rank and columns in general position.
fn facet_max_scale(j: &DMatrix<f64>, xd: &[f64], lo: &[f64], hi: &[f64]) -> Option<f64> {
    let (m, n) = j.shape();
    let (mut s_hi, mut s_lo) = (1.0f64, 0.0f64);
    let mut minor = vec![0.0; m * m];
    let mut u = vec![0.0; m];
    for subset in subsets(n, m - 1) {
        let cols: Vec<usize> = (0..n).filter(|i| subset & (1 << i) != 0).collect();
        // generalised cross product: u_r = (−1)^r det(columns without row r)
        for r in 0..m {
            let mut t = 0;
            for rr in (0..m).filter(|&rr| rr != r) {
                for &c in &cols {
                    minor[t] = j[(rr, c)];
                    t += 1;
                }
            }
            let sign = if r % 2 == 0 { 1.0 } else { -1.0 };
            u[r] = sign * det(&mut minor, m - 1);
        }
        let norm = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm < 1e-9 {
            continue;
        }
        for sign in [1.0, -1.0] {
            let mut h = 0.0;
            for i in (0..n).filter(|i| subset & (1 << i) == 0) {
                let g: f64 = (0..m).map(|r| sign * u[r] / norm * j[(r, i)]).sum();
                h += if g > 0.0 {
                    g * hi[i]
                } else if g < 0.0 {
                    g * lo[i]
                } else {
                    0.0
                };
            }
            if h == f64::INFINITY {
                continue;
            }
            let ux: f64 = (0..m).map(|r| sign * u[r] / norm * xd[r]).sum();
            if ux > 0.0 {
                s_hi = s_hi.min(h / ux);
            } else if ux < 0.0 {
                s_lo = s_lo.max(h / ux);
            } else if h < 0.0 {
                return None;
            }
        }
    }
    (s_lo <= s_hi + 1e-12 && s_hi >= 0.0).then_some(s_hi.max(0.0))
}

/// Greedy SNS as described in the module doc (never releasing a joint),
/// written with nalgebra's pseudoinverse: the scale the solver reached
/// before the optimal phase, to show how many problems need a release.
fn greedy_sns_scale(j: &DMatrix<f64>, xd: &[f64], lo: &[f64], hi: &[f64]) -> f64 {
    let (m, n) = j.shape();
    let x = nalgebra::DVector::from_column_slice(xd);
    let tol = |i: usize| 1e-10 * (1.0 + lo[i].abs().max(hi[i].abs()));
    let mut free = vec![true; n];
    let mut qn = nalgebra::DVector::zeros(n);
    let mut best = 0.0f64;
    loop {
        // (JW)⁺ = (JW)ᵀ (JW (JW)ᵀ)⁻¹: the rows of saturated joints exactly zero
        let jw = DMatrix::from_fn(m, n, |r, c| if free[c] { j[(r, c)] } else { 0.0 });
        let gram = &jw * jw.transpose();
        let eig = gram.clone().symmetric_eigenvalues();
        if eig.min() <= 1e-10 * eig.max() {
            return best;
        }
        let p = jw.transpose() * gram.cholesky().unwrap().inverse();
        let a = &p * &x;
        let q = &qn + &p * (&x - j * &qn);
        if (0..n).all(|i| q[i] >= lo[i] - tol(i) && q[i] <= hi[i] + tol(i)) {
            return 1.0;
        }
        let (mut s_hi, mut c_hi, mut s_lo, mut c_lo) = (f64::INFINITY, 0, f64::NEG_INFINITY, 0);
        for i in 0..n {
            let b = q[i] - a[i];
            let (l, h) = if a[i].abs() <= tol(i) {
                if b >= lo[i] - tol(i) && b <= hi[i] + tol(i) {
                    (f64::NEG_INFINITY, f64::INFINITY)
                } else {
                    (f64::INFINITY, f64::NEG_INFINITY)
                }
            } else {
                let (t0, t1) = ((lo[i] - b) / a[i], (hi[i] - b) / a[i]);
                (t0.min(t1), t0.max(t1))
            };
            if h < s_hi {
                (s_hi, c_hi) = (h, i);
            }
            if l > s_lo {
                (s_lo, c_lo) = (l, i);
            }
        }
        let cap = s_hi.min(1.0);
        if s_hi >= 0.0 && s_lo <= cap {
            best = best.max(cap);
        }
        let c = if s_hi < 1.0 {
            c_hi
        } else if s_lo > 1.0 {
            c_lo
        } else {
            return best;
        };
        free[c] = false;
        qn[c] = q[c].clamp(lo[c], hi[c]);
        if free.iter().filter(|&&f| f).count() < m {
            return best;
        }
    }
}

/// Kinds of random bounds.
#[derive(Clone, Copy, Debug)]
enum BoundKind {
    /// `q̇min < 0 < q̇max`
    AroundZero,
    /// about a third of the joints must move: `0 < q̇min < q̇max` or `q̇min < q̇max < 0`
    Offset,
    /// as `Offset`, and about a fifth of the bounds infinite (one joint at
    /// most with both)
    Infinite,
    /// degenerate: about a third of the joints with a bound exactly at zero
    /// (a joint at its position limit) and a tenth with `q̇min = q̇max`
    Degenerate,
}

type Problem = (DMatrix<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

fn random_problem(rng: &mut Rng, m: usize, n: usize, kind: BoundKind, mag_max: f64) -> Problem {
    let j = DMatrix::from_fn(m, n, |_, _| rng.uniform(-1.0, 1.0));
    let mag = rng.uniform(0.1, mag_max);
    let xd: Vec<f64> = (0..m).map(|_| rng.uniform(-1.0, 1.0) * mag).collect();
    let mut lo: Vec<f64> = (0..n).map(|_| -rng.uniform(0.02, 1.0)).collect();
    let mut hi: Vec<f64> = (0..n).map(|_| rng.uniform(0.02, 1.0)).collect();
    if matches!(kind, BoundKind::Offset | BoundKind::Infinite) {
        for i in 0..n {
            if rng.uniform(0.0, 1.0) < 0.3 {
                let (a, w) = (rng.uniform(0.02, 0.5), rng.uniform(0.05, 0.6));
                if rng.uniform(0.0, 1.0) < 0.5 {
                    (lo[i], hi[i]) = (a, a + w);
                } else {
                    (lo[i], hi[i]) = (-a - w, -a);
                }
            }
        }
    }
    if matches!(kind, BoundKind::Degenerate) {
        for i in 0..n {
            let u = rng.uniform(0.0, 1.0);
            if u < 0.15 {
                lo[i] = 0.0;
            } else if u < 0.3 {
                hi[i] = 0.0;
            } else if u < 0.35 {
                (lo[i], hi[i]) = (0.0, 0.0);
            } else if u < 0.4 {
                lo[i] = rng.uniform(-0.5, 0.5);
                hi[i] = lo[i];
            }
        }
    }
    if matches!(kind, BoundKind::Infinite) {
        for i in 0..n {
            if rng.uniform(0.0, 1.0) < 0.2 {
                lo[i] = f64::NEG_INFINITY;
            }
            if rng.uniform(0.0, 1.0) < 0.2 {
                hi[i] = f64::INFINITY;
            }
        }
        // at most one joint free on both sides (the programme keeps a vertex)
        let mut both = (0..n).filter(|&i| lo[i].is_infinite() && hi[i].is_infinite());
        if let Some(first) = both.next() {
            for i in both.collect::<Vec<_>>() {
                hi[i] = rng.uniform(0.02, 1.0);
            }
            let _ = first;
        }
    }
    (j, xd, lo, hi)
}

// ---------------------------------------------------------------------------
// (a)-(d) SNS

/// (a) 1-D task on 2 joints, generous bounds: the pseudoinverse solution.
#[test]
fn free_task_gives_the_pseudoinverse() {
    let mut sns = SnsSolver::new(2, 1);
    let j = DMatrix::from_row_slice(1, 2, &[1.0, 2.0]);
    let r = sns.solve(&j, &[1.0], &[-10.0; 2], &[10.0; 2], 0.0).unwrap();
    // J⁺ = Jᵀ/(J Jᵀ) = [1, 2]/5
    assert_eq!(r.scale, 1.0);
    assert!((r.qd[0] - 0.2).abs() < 1e-15 && (r.qd[1] - 0.4).abs() < 1e-15);
    assert_eq!((r.saturated, r.iterations), (0, 1));
    assert!(!r.clamped());
    // damped: Jᵀ (J Jᵀ + λ²)⁻¹ ẋ with λ = 1: [1, 2]/6, still scale 1
    let r = sns.solve(&j, &[1.0], &[-10.0; 2], &[10.0; 2], 1.0).unwrap();
    assert_eq!(r.scale, 1.0);
    assert!((r.qd[0] - 1.0 / 6.0).abs() < 1e-15 && (r.qd[1] - 2.0 / 6.0).abs() < 1e-15);
}

/// (b) One bound active: that joint saturates at its bound and the other
/// compensates fully, the task exactly achieved.
#[test]
fn one_saturated_joint_is_compensated() {
    let mut sns = SnsSolver::new(2, 1);
    // J = [1 1], ẋ = 1: the pseudoinverse asks 0.5 of each; joint 0 may do 0.2
    let r = sns
        .solve_row_major(&[1.0, 1.0], &[1.0], &[-0.2, -1.0], &[0.2, 1.0], 0.0)
        .unwrap();
    assert_eq!(r.scale, 1.0);
    assert_eq!(r.qd[0], 0.2);
    assert!((r.qd[1] - 0.8).abs() < 1e-15);
    assert_eq!(r.saturated, 0b01);
    assert_eq!(r.iterations, 2);
    // the same on the negative side
    let r = sns
        .solve_row_major(&[1.0, 1.0], &[-1.0], &[-0.2, -1.0], &[0.2, 1.0], 0.0)
        .unwrap();
    assert_eq!((r.scale, r.qd[0]), (1.0, -0.2));
    assert!((r.qd[1] + 0.8).abs() < 1e-15);
}

/// (c) Bounds too tight for the full task: the task is scaled by the
/// hand-computed factor, every bound holds and the direction is kept.
#[test]
fn too_tight_bounds_scale_the_task() {
    // 1-D: q̇0 + q̇1 = s, |q̇i| ≤ 0.3  →  s = 0.6, q̇ = (0.3, 0.3)
    let mut sns = SnsSolver::new(2, 1);
    let r = sns
        .solve_row_major(&[1.0, 1.0], &[1.0], &[-0.3; 2], &[0.3; 2], 0.0)
        .unwrap();
    assert!((r.scale - 0.6).abs() < 1e-15);
    assert!((r.qd[0] - 0.3).abs() < 1e-15 && (r.qd[1] - 0.3).abs() < 1e-15);
    assert!(r.rank_limited);

    // 2-D: J = [1 0 1; 0 1 0], ẋ = (2, 0.5), |q̇0|,|q̇2| ≤ 0.5, |q̇1| ≤ 1.
    // x needs q̇0 + q̇2 = 2s ≤ 1 → s = 0.5, q̇ = (0.5, 0.25, 0.5).
    let mut sns = SnsSolver::new(3, 2);
    let j = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 1.0, 0.0, 1.0, 0.0]);
    let (lo, hi) = ([-0.5, -1.0, -0.5], [0.5, 1.0, 0.5]);
    let r = sns.solve(&j, &[2.0, 0.5], &lo, &hi, 0.0).unwrap();
    assert!((r.scale - 0.5).abs() < 1e-15, "scale {}", r.scale);
    let want = [0.5, 0.25, 0.5];
    for (got, want) in r.qd.iter().zip(want) {
        assert!((got - want).abs() < 1e-15, "{:?}", r.qd);
    }
    assert!(within(r.qd, &lo, &hi));
    // direction preserved: J q̇ = s ẋ
    let jq = mat_vec(&j, r.qd);
    assert!((jq[0] - 1.0).abs() < 1e-15 && (jq[1] - 0.25).abs() < 1e-15);
    assert!(!r.clamped());
}

#[test]
fn bad_inputs_are_refused() {
    let mut sns = SnsSolver::new(2, 3);
    let j = [1.0, 1.0];
    assert_eq!(
        sns.solve_row_major(&j, &[1.0], &[0.1, -1.0], &[0.0, 1.0], 0.0)
            .unwrap_err(),
        SnsError::InconsistentBounds { joint: 0 }
    );
    assert!(matches!(
        sns.solve_row_major(&j, &[f64::NAN], &[-1.0; 2], &[1.0; 2], 0.0),
        Err(SnsError::NonFinite { .. })
    ));
    assert!(matches!(
        sns.solve_row_major(&j, &[1.0, 1.0, 1.0, 1.0], &[-1.0; 2], &[1.0; 2], 0.0),
        Err(SnsError::TaskDimension { m: 4, m_max: 3 })
    ));
    assert!(matches!(
        sns.solve_row_major(&j, &[1.0], &[-1.0; 3], &[1.0; 2], 0.0),
        Err(SnsError::Dimension { .. })
    ));
    // bounds that exclude zero are fine: joint 0 must move at ≥ 0.1
    let r = sns
        .solve_row_major(&j, &[0.0], &[0.1, -1.0], &[0.5, 1.0], 0.0)
        .unwrap();
    assert!(
        r.qd[0] >= 0.1 && (r.qd[0] + r.qd[1]).abs() < 1e-12,
        "{:?}",
        r.qd
    );
    assert_eq!(r.scale, 1.0);
    // a zero Jacobian with zero damping is degenerate: stand still
    let r = sns
        .solve_row_major(&[0.0, 0.0], &[1.0], &[-1.0; 2], &[1.0; 2], 0.0)
        .unwrap();
    assert_eq!((r.qd[0], r.qd[1], r.scale), (0.0, 0.0, 0.0));
}

/// A joint saturated early is released: greedy SNS saturates joint 3 first
/// and ends at s = 2/3; the optimum (the only vertex with the largest
/// scale, found by hand from the vertex enumeration) is s = 5/6 with
/// q̇ = (1/2, 11/6, −3, −1, −1): joints 2, 3 and 4 at a bound.
#[test]
fn a_joint_saturated_early_is_released() {
    let j = DMatrix::from_row_slice(
        3,
        5,
        &[
            -2.0, -1.0, 0.0, -1.0, -1.0, //
            1.0, 2.0, 1.0, 1.0, 1.0, //
            -1.0, 0.0, 0.0, -1.0, -2.0,
        ],
    );
    let xd = [-1.0, -1.0, 3.0];
    let lo = [-2.0, -2.0, -3.0, -1.0, -1.0];
    let hi = [1.0, 3.0, 3.0, 3.0, 2.0];
    assert!((greedy_sns_scale(&j, &xd, &lo, &hi) - 2.0 / 3.0).abs() < 1e-12);
    let mut sns = SnsSolver::new(5, 3);
    let r = sns.solve(&j, &xd, &lo, &hi, 0.0).unwrap();
    assert!((r.scale - 5.0 / 6.0).abs() < 1e-14, "scale {}", r.scale);
    let want = [0.5, 11.0 / 6.0, -3.0, -1.0, -1.0];
    for (got, want) in r.qd.iter().zip(want) {
        assert!((got - want).abs() < 1e-14, "{:?}", r.qd);
    }
    assert_eq!(r.saturated, 0b11100);
    assert!(r.rank_limited && !r.clamped());
    assert!(r.iterations <= max_iterations(5, 3));
    let jq = mat_vec(&j, r.qd);
    for k in 0..3 {
        assert!((jq[k] - r.scale * xd[k]).abs() < 1e-14);
    }
    // the references agree
    let v = vertex_max_scale(&j, &xd, &lo, &hi).unwrap();
    let f = facet_max_scale(&j, &xd, &lo, &hi).unwrap();
    assert!((v - 5.0 / 6.0).abs() < 1e-14 && (f - 5.0 / 6.0).abs() < 1e-14);
}

/// Tolerance on the scale against the exact optimum.
const SCALE_TOL: f64 = 1e-9;

/// (d) Seeded random problems of several sizes (3×7, 2×5, 6×7, 3×8), with
/// bounds around zero, bounds that exclude zero for some joints, and some
/// infinite bounds: every one reaches the exact optimum of the linear
/// programme `max s` (within [`SCALE_TOL`]), given by two independent
/// exhaustive references that are checked against each other (vertex
/// enumeration over all saturation sets, and the facets of the zonotope
/// `J·box`). Bounds always hold, `J q̇ = s ẋ`, `s = 1` with the unchanged
/// pseudoinverse solution whenever that fits, and the iteration count stays
/// within [`max_iterations`]. The counts of problems where greedy SNS (no
/// release) stays below the optimum are printed and must not be trivial.
/// `SNS_TRIALS=n` multiplies the number of problems by n.
#[test]
fn random_problems_reach_the_optimum() {
    let factor: usize = std::env::var("SNS_TRIALS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    // (m, n, problems per bound kind, largest task magnitude)
    let sizes = [
        (3, 7, 1000, 3.0),
        (2, 5, 400, 2.0),
        (6, 7, 400, 1.0),
        (3, 8, 400, 3.0),
    ];
    let kinds = [
        BoundKind::AroundZero,
        BoundKind::Offset,
        BoundKind::Infinite,
        BoundKind::Degenerate,
    ];
    let mut rng = Rng(0x5eed_2012);
    let mut total = 0;
    let mut total_released = 0;
    for (m, n, count, mag_max) in sizes {
        let mut sns = SnsSolver::new(n, m);
        for kind in kinds {
            let (mut pinv_fits, mut scaled, mut infeasible, mut greedy_below) = (0, 0, 0, 0);
            let (mut worst_err, mut worst_ref, mut max_iter) = (0.0f64, 0.0f64, 0);
            let mut worst_res = 0.0f64;
            for t in 0..count * factor {
                let (j, xd, lo, hi) = random_problem(&mut rng, m, n, kind, mag_max);
                let ctx = format!("{m}×{n} {kind:?} trial {t}");
                if j.clone().svd(false, false).singular_values.min() < 1e-3 {
                    continue; // the references assume a well-conditioned J
                }
                total += 1;
                let s_vertex = vertex_max_scale(&j, &xd, &lo, &hi);
                let s_facet = facet_max_scale(&j, &xd, &lo, &hi);
                match (s_vertex, s_facet) {
                    (Some(v), Some(f)) => {
                        worst_ref = worst_ref.max((v - f).abs());
                        assert!((v - f).abs() <= SCALE_TOL, "{ctx}: references {v} vs {f}");
                    }
                    (None, None) => {}
                    _ => panic!("{ctx}: references {s_vertex:?} vs {s_facet:?}"),
                }
                let pinv = j.clone().pseudo_inverse(1e-12).unwrap();
                let q_pinv = mat_vec(&pinv, &xd);
                let fits = within(&q_pinv, &lo, &hi);

                let r = sns.solve(&j, &xd, &lo, &hi, 0.0).unwrap();
                assert!(within(r.qd, &lo, &hi), "{ctx}: bounds");
                assert!(!r.clamped(), "{ctx}: clamp {}", r.clamp_correction);
                assert!((0.0..=1.0).contains(&r.scale), "{ctx}: scale");
                assert!(r.iterations <= max_iterations(n, m), "{ctx}: iterations");
                max_iter = max_iter.max(r.iterations);
                let s_opt = s_facet.unwrap_or(0.0);
                let err = (r.scale - s_opt).abs();
                worst_err = worst_err.max(err);
                assert!(
                    err <= SCALE_TOL,
                    "{ctx}: scale {} vs optimum {s_opt}",
                    r.scale
                );
                if s_facet.is_some() {
                    // J q̇ = s ẋ (when no s is feasible: the box point nearest 0)
                    let jq = mat_vec(&j, r.qd);
                    let xn = xd.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                    for k in 0..m {
                        worst_res = worst_res.max((jq[k] - r.scale * xd[k]).abs() / (1.0 + xn));
                        assert!(
                            (jq[k] - r.scale * xd[k]).abs() < 1e-9 * (1.0 + xn),
                            "{ctx}: J q̇ = s ẋ ({jq:?} vs {} × {xd:?})",
                            r.scale
                        );
                    }
                } else {
                    infeasible += 1;
                    assert_eq!(r.scale, 0.0, "{ctx}");
                }
                if fits {
                    pinv_fits += 1;
                    assert_eq!(r.scale, 1.0, "{ctx}");
                    for (got, want) in r.qd.iter().zip(&q_pinv) {
                        assert!((got - want).abs() < 1e-9, "{ctx}: not J⁺ẋ");
                    }
                }
                if r.scale < 1.0 {
                    scaled += 1;
                }
                if greedy_sns_scale(&j, &xd, &lo, &hi) < s_opt - SCALE_TOL {
                    greedy_below += 1;
                }
            }
            total_released += greedy_below;
            println!(
                "random SNS {m}×{n} {kind:?}: {} problems, {pinv_fits} pinv fits, {scaled} scaled, \
                 {infeasible} infeasible, {greedy_below} where greedy SNS is below the optimum; \
                 all at the optimum (worst |s − s*| {worst_err:.1e}, references agree to \
                 {worst_ref:.1e}), |J q̇ − s ẋ| ≤ {worst_res:.1e}·(1 + |ẋ|), at most {max_iter} \
                 iterations",
                count * factor
            );
            assert!(scaled * 10 >= count * factor, "too few scaled problems");
        }
    }
    println!("random SNS: {total} problems, {total_released} released to the optimum");
    assert!(total_released * 50 >= total, "the set should need releases");
}

/// The end effector's position task of the KUKA LWR-IV at random
/// configurations (structured Jacobians rather than random ones), bounds
/// like the avoidance layer's (some joints at a position limit: a bound
/// exactly 0), a task of up to 1 m/s: every problem at the optimum.
#[test]
fn lwr_problems_reach_the_optimum() {
    let model = lwr4();
    let mut data = Data::new(&model);
    let n = model.nv();
    let ee = model.frame_id("lwr_link_7").unwrap();
    let mut j6 = Matrix6xX::zeros(n);
    let mut sns = SnsSolver::new(n, 3);
    let mut rng = Rng(0x1_f4);
    let (mut scaled, mut greedy_below, mut worst) = (0, 0, 0.0f64);
    let trials = 500;
    for t in 0..trials {
        let q: Vec<f64> = (0..n).map(|_| rng.uniform(-2.0, 2.0)).collect();
        phri_model::forward_kinematics(&model, &mut data, &q).unwrap();
        phri_model::point_jacobian(&model, &data, ee, &Vector3::zeros(), &mut j6).unwrap();
        let j = DMatrix::from_fn(3, n, |r, c| j6[(r, c)]);
        let v = rng.uniform(0.05, 1.0);
        let xd: Vec<f64> = (0..3).map(|_| rng.uniform(-1.0, 1.0) * v).collect();
        let mut lo: Vec<f64> = (0..n).map(|_| -rng.uniform(0.05, 1.9)).collect();
        let mut hi: Vec<f64> = (0..n).map(|_| rng.uniform(0.05, 1.9)).collect();
        for k in 0..n {
            match rng.uniform(0.0, 1.0) {
                u if u < 0.1 => lo[k] = 0.0,
                u if u < 0.2 => hi[k] = 0.0,
                _ => {}
            }
        }
        let r = sns.solve(&j, &xd, &lo, &hi, 0.0).unwrap();
        let ctx = format!("lwr trial {t}");
        assert!(within(r.qd, &lo, &hi) && !r.clamped(), "{ctx}");
        assert!(r.iterations <= max_iterations(n, 3), "{ctx}");
        let s_facet = facet_max_scale(&j, &xd, &lo, &hi).unwrap();
        let s_vertex = vertex_max_scale(&j, &xd, &lo, &hi).unwrap();
        assert!(
            (s_facet - s_vertex).abs() <= SCALE_TOL,
            "{ctx}: {s_facet} {s_vertex}"
        );
        assert!(
            (r.scale - s_facet).abs() <= SCALE_TOL,
            "{ctx}: {} vs {s_facet}",
            r.scale
        );
        worst = worst.max((r.scale - s_facet).abs());
        let jq = mat_vec(&j, r.qd);
        for k in 0..3 {
            assert!((jq[k] - r.scale * xd[k]).abs() < 1e-9, "{ctx}: J q̇ = s ẋ");
        }
        scaled += usize::from(r.scale < 1.0);
        greedy_below += usize::from(greedy_sns_scale(&j, &xd, &lo, &hi) < s_facet - SCALE_TOL);
    }
    println!(
        "lwr SNS: {trials} problems, {scaled} scaled, {greedy_below} where greedy SNS is below \
         the optimum; all at the optimum (worst |s − s*| {worst:.1e})"
    );
    assert!(
        scaled >= trials / 10 && greedy_below >= 5,
        "{scaled} {greedy_below}"
    );
}

/// Corners: more task rows than joints, a zero task with bounds that
/// exclude zero, every joint fixed, and the largest solver (32 joints).
#[test]
fn corner_problems_reach_the_optimum() {
    // 3 rows, 2 joints: only ẋ in the span of J can be followed
    let mut sns = SnsSolver::new(2, 3);
    let j = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    let r = sns
        .solve(&j, &[1.0, 2.0, 3.0], &[-0.5; 2], &[0.5; 2], 0.0)
        .unwrap();
    assert!((r.scale - 0.25).abs() < 1e-15, "{r:?}");
    assert!((r.qd[0] - 0.25).abs() < 1e-15 && (r.qd[1] - 0.5).abs() < 1e-15);
    let r = sns
        .solve(&j, &[1.0, 2.0, 0.0], &[-0.5; 2], &[0.5; 2], 0.0)
        .unwrap();
    assert_eq!((r.scale, r.qd[0], r.qd[1]), (0.0, 0.0, 0.0));

    // zero task, joint 0 must move: J q̇ = 0 with q̇0 ≥ 0.2 at scale 1
    let mut sns = SnsSolver::new(3, 2);
    let j = DMatrix::from_row_slice(2, 3, &[1.0, 1.0, 0.0, 0.0, 1.0, 1.0]);
    let (lo, hi) = ([0.2, -1.0, -1.0], [0.4, 1.0, 1.0]);
    let r = sns.solve(&j, &[0.0, 0.0], &lo, &hi, 0.0).unwrap();
    assert_eq!(r.scale, 1.0);
    assert!(within(r.qd, &lo, &hi) && mat_vec(&j, r.qd).iter().all(|v| v.abs() < 1e-15));

    // every joint fixed: the task is followed as far as those velocities allow
    let r = sns
        .solve(&j, &[1.0, 0.0], &[0.5, -0.5, 0.5], &[0.5, -0.5, 0.5], 0.0)
        .unwrap();
    assert_eq!((r.scale, r.qd[0], r.qd[1], r.qd[2]), (0.0, 0.5, -0.5, 0.5));
    let r = sns
        .solve(&j, &[0.0, 0.0], &[0.5, -0.5, 0.5], &[0.5, -0.5, 0.5], 0.0)
        .unwrap();
    assert_eq!((r.scale, r.qd[0], r.qd[1], r.qd[2]), (1.0, 0.5, -0.5, 0.5));

    // 32 joints, 3 rows (the facet reference only: 2³² saturation sets)
    let (m, n) = (3, 32);
    let mut sns = SnsSolver::new(n, m);
    let mut rng = Rng(32);
    let mut scaled = 0;
    for t in 0..60 {
        let kind = [
            BoundKind::AroundZero,
            BoundKind::Offset,
            BoundKind::Degenerate,
        ][t % 3];
        let (j, xd, lo, hi) = random_problem(&mut rng, m, n, kind, 12.0);
        let r = sns.solve(&j, &xd, &lo, &hi, 0.0).unwrap();
        assert!(within(r.qd, &lo, &hi) && !r.clamped(), "trial {t}");
        assert!(r.iterations <= max_iterations(n, m), "trial {t}");
        let s_opt = facet_max_scale(&j, &xd, &lo, &hi).unwrap_or(0.0);
        assert!(
            (r.scale - s_opt).abs() <= SCALE_TOL,
            "trial {t}: {} vs {s_opt}",
            r.scale
        );
        scaled += usize::from(r.scale < 1.0);
    }
    assert!(scaled >= 20, "{scaled}");
}

/// With damping the task is met only approximately, but the bounds hold
/// exactly, and the scale is never below the exact optimum without damping
/// (the programme's vertex is a candidate).
#[test]
fn damped_random_problems_keep_the_bounds() {
    let mut rng = Rng(0xda_3ed);
    for (m, n) in [(3, 7), (2, 5), (6, 7), (3, 8)] {
        let mut sns = SnsSolver::new(n, m);
        for kind in [
            BoundKind::AroundZero,
            BoundKind::Offset,
            BoundKind::Infinite,
            BoundKind::Degenerate,
        ] {
            for t in 0..100 {
                let (j, xd, lo, hi) = random_problem(&mut rng, m, n, kind, 3.0);
                let s_opt = facet_max_scale(&j, &xd, &lo, &hi).unwrap_or(0.0);
                for damping in [1e-3, 0.02, 0.1] {
                    let r = sns.solve(&j, &xd, &lo, &hi, damping).unwrap();
                    let ctx = format!("{m}×{n} {kind:?} trial {t} damping {damping}");
                    assert!(within(r.qd, &lo, &hi) && !r.clamped(), "{ctx}");
                    assert!((0.0..=1.0).contains(&r.scale), "{ctx}");
                    assert!(r.scale >= s_opt - SCALE_TOL, "{ctx}: {} < {s_opt}", r.scale);
                    assert!(r.iterations <= max_iterations(n, m), "{ctx}");
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------
// (e) joint-limit bounds

#[test]
fn joint_limit_bounds_at_and_near_the_limits() {
    let (lo, hi, v, a, t) = ([-1.0], [1.0], [2.0], [2.0], 0.01);
    let at = |q: f64| {
        let (mut dmin, mut dmax) = ([0.0], [0.0]);
        joint_limit_bounds(&[q], &lo, &hi, &v, &a, t, &mut dmin, &mut dmax);
        (dmin[0], dmax[0])
    };
    let (mut dmin, mut dmax) = ([0.0], [0.0]);
    // at the upper limit: cannot go further up, can go down
    let (l, h) = at(1.0);
    assert!(h <= 0.0 && h == 0.0 && l < 0.0, "{l} {h}");
    // at the lower limit: mirror image
    let (l, h) = at(-1.0);
    assert!(l >= 0.0 && l == 0.0 && h > 0.0, "{l} {h}");
    // near the upper limit: braking distance term √(2 A (Q_max − q))
    let (l, h) = at(0.99);
    assert!((h - (2.0f64 * 2.0 * 0.01).sqrt()).abs() < 1e-12 && h < 2.0);
    assert_eq!(l, -2.0);
    // position term (Q_max − q)/T wins with a long horizon
    joint_limit_bounds(&[0.99], &lo, &hi, &v, &a, 1.0, &mut dmin, &mut dmax);
    assert!((dmax[0] - 0.01).abs() < 1e-12);
    // far from the limits: the velocity limit
    let (l, h) = at(0.0);
    assert_eq!((l, h), (-2.0, 2.0));
    // beyond the upper limit: must come back, no faster than the velocity limit
    let (l, h) = at(1.5);
    assert!(h < 0.0 && l <= h && l >= -2.0, "{l} {h}");
    // continuous joint (infinite range): just the velocity limit
    joint_limit_bounds(
        &[100.0],
        &[f64::NEG_INFINITY],
        &[f64::INFINITY],
        &v,
        &a,
        t,
        &mut dmin,
        &mut dmax,
    );
    assert_eq!((dmin[0], dmax[0]), (-2.0, 2.0));
}

// ---------------------------------------------------------------------------
// (f) eq. 20: the sign

/// A point P approaching an obstacle: the joint velocity that reduces the
/// distance is bounded to `(1 − f) V_max` while the escape stays free, and
/// joints that do not move P toward the obstacle are untouched.
#[test]
fn eq20_restricts_the_approach_not_the_escape() {
    // joint 0 moves P along +x, joint 1 along +y, joint 2 along −x, joint 3 not at all
    let jp = Matrix3xX::from_column_slice(&[
        1.0, 0.0, 0.0, //
        0.0, 1.0, 0.0, //
        -0.5, 0.0, 0.0, //
        0.0, 0.0, 0.0,
    ]);
    let p = Vector3::new(0.0, 0.0, 0.0);
    let obstacle = Vector3::new(0.1, 0.0, 0.0); // on the +x side of P
    let (v_max_rep, v) = (0.2, 0.15);
    // repulsive: from the obstacle toward P
    let v_call = (p - obstacle).normalize() * v;
    let f_expected = v / v_max_rep;
    let vmax = [1.0, 1.5, 2.0, 1.0];
    let (mut lo, mut hi) = ([-1.0, -1.5, -2.0, -1.0], [1.0, 1.5, 2.0, 1.0]);
    let f = shape_bounds_for_point(&jp, v_call, v_max_rep, &vmax, &mut lo, &mut hi);
    assert!((f - f_expected).abs() < 1e-12);
    let limit = |k: usize| vmax[k] * (1.0 - f_expected);

    // joint 0: +q̇ moves P toward the obstacle → q̇max shrunk, q̇min free
    assert!((hi[0] - limit(0)).abs() < 1e-12 && lo[0] == -1.0);
    // joint 2: −q̇ moves P toward the obstacle → q̇min shrunk, q̇max free
    assert!((lo[2] + limit(2)).abs() < 1e-12 && hi[2] == 2.0);
    // joint 1 moves P sideways, joint 3 not at all: untouched
    assert_eq!((lo[1], hi[1], lo[3], hi[3]), (-1.5, 1.5, -1.0, 1.0));

    // the distance really shrinks on the restricted side and grows on the free one
    let dist = |k: usize, qd: f64| (obstacle - (p + jp.column(k) * qd * 1e-3)).norm();
    let d0 = (obstacle - p).norm();
    assert!(dist(0, hi[0]) < d0 && dist(0, lo[0]) > d0);
    assert!(dist(2, lo[2]) < d0 && dist(2, hi[2]) > d0);
    // approach speed of P per joint is at most (1 − f) V_max
    let u = v_call.normalize();
    for k in 0..4 {
        for qd in [lo[k], hi[k]] {
            let toward = -u.dot(&(jp.column(k) * qd));
            assert!(toward <= (1.0 - f) * vmax[k] * jp.column(k).norm() + 1e-12);
        }
    }
    // the rule quoted from third-party code (s ≥ 0 → shrink q̇max) would have
    // left joint 0's approach at full speed: S_0 = −0.15 < 0 and S_2 = 0.075 ≥ 0
    let s = jp.transpose() * v_call;
    assert!(s[0] < 0.0 && s[2] > 0.0);

    // full risk stops the approach completely; several points keep the tightest bound
    let (mut lo2, mut hi2) = ([-1.0; 4], [1.0; 4]);
    shape_bounds_for_point(&jp, v_call * 0.5, v_max_rep, &vmax, &mut lo2, &mut hi2);
    let after_one = hi2[0];
    shape_bounds_for_point(&jp, v_call * 10.0, v_max_rep, &vmax, &mut lo2, &mut hi2);
    assert!(after_one > 0.0 && hi2[0] == 0.0 && lo2[2] == 0.0);
    shape_bounds_for_point(&jp, v_call * 0.1, v_max_rep, &vmax, &mut lo2, &mut hi2);
    assert_eq!(hi2[0], 0.0, "a milder point must not relax the bound");
    assert_eq!((lo2[0], hi2[2]), (-1.0, 1.0));

    // a joint whose bounds force motion toward the obstacle (outside its
    // position range) keeps consistent bounds
    let (mut lo3, mut hi3) = ([0.4, -1.0, -1.0, -1.0], [0.6, 1.0, 1.0, 1.0]);
    shape_bounds_for_point(&jp, v_call * 10.0, v_max_rep, &vmax, &mut lo3, &mut hi3);
    assert!(lo3[0] <= hi3[0] && lo3[0] == 0.4);
}

#[test]
fn eq19_adds_the_repulsion() {
    let x = end_effector_velocity(&Vector3::new(0.1, 0.0, 0.0), &Vector3::new(0.0, -0.2, 0.0));
    assert_eq!(x, Vector3::new(0.1, -0.2, 0.0));
}

// ---------------------------------------------------------------------------
// (g) the layer on the KUKA LWR-IV

/// Eq. 16: `v = V_max / (1 + exp((‖D‖ 2/ρ − 1) α))`.
fn repulsion_magnitude(d: f64) -> f64 {
    let (v_max, rho, alpha) = (0.21, 0.4, 6.0);
    v_max / (1.0 + ((d * 2.0 / rho - 1.0) * alpha).exp())
}

#[test]
fn avoidance_on_the_lwr_keeps_the_elbow_from_the_obstacle() {
    let model = lwr4();
    let mut data = Data::new(&model);
    let n = model.nv();
    let ee = model.frame_id("lwr_link_7").unwrap();
    let elbow = model.frame_id("lwr_link_4").unwrap();
    let q = [0.2, 0.7, -0.3, -1.3, 0.4, 0.9, 0.0];
    phri_model::forward_kinematics(&model, &mut data, &q).unwrap();
    let mut j_ee = Matrix6xX::zeros(n);
    let mut j_el = Matrix6xX::zeros(n);
    phri_model::point_jacobian(&model, &data, ee, &Vector3::zeros(), &mut j_ee).unwrap();
    phri_model::point_jacobian(&model, &data, elbow, &Vector3::zeros(), &mut j_el).unwrap();
    let p_elbow = phri_model::frame_placement(&model, &data, elbow).p;

    let params = avoidance_params();
    let mut av = Avoidance::new(&model, params);
    let xdot_t = Vector3::new(0.0, 0.25, -0.25); // end-effector task velocity
    let zero = Vector3::zeros();

    // without the obstacle: where would the elbow go?
    let plain: Vec<f64> = av
        .step(&q, &j_ee, &xdot_t, &zero, &[], 1.0)
        .unwrap()
        .qd
        .to_vec();
    let v_el_plain = j_el.fixed_rows::<3>(0) * nalgebra::DVector::from_column_slice(&plain);
    assert!(v_el_plain.norm() > 0.05, "elbow barely moves: {v_el_plain}");

    // an obstacle 8 cm ahead of the elbow, along its motion
    let to_obstacle = v_el_plain.normalize();
    let d = 0.08;
    let obstacle = p_elbow + to_obstacle * d;
    let v_call = (p_elbow - obstacle).normalize() * repulsion_magnitude(d);
    let f = v_call.norm() / params.v_max_repulsion;
    assert!(f > 0.8 && f < 1.0, "f = {f}");

    let vmax = av.velocity_limits().to_vec();
    let bound_for = |scale: f64| {
        scale
            * (1.0 - f)
            * (0..n)
                .map(|k| {
                    let c = Vector3::new(j_el[(0, k)], j_el[(1, k)], j_el[(2, k)]);
                    c.dot(&to_obstacle).abs() * vmax[k]
                })
                .sum::<f64>()
    };
    let approach_plain = v_el_plain.dot(&to_obstacle);
    assert!(
        approach_plain > bound_for(1.0),
        "the test needs an approach faster than the bound: {approach_plain} vs {}",
        bound_for(1.0)
    );

    for speed_scale in [1.0, 0.5] {
        let points = [ControlPoint::new(&j_el, v_call)];
        let out = av
            .step(&q, &j_ee, &xdot_t, &zero, &points, speed_scale)
            .unwrap();
        let qd = nalgebra::DVector::from_column_slice(out.qd);
        assert!(within(out.qd, out.qd_min, out.qd_max) && out.clamp_correction < 1e-9);
        assert!((out.risk - f).abs() < 1e-12);
        // the elbow's speed toward the obstacle stays within what eq. 20 allows
        let approach = (j_el.fixed_rows::<3>(0) * &qd).dot(&to_obstacle);
        let bound = bound_for(speed_scale);
        assert!(
            approach <= bound + 1e-9,
            "elbow approaches at {approach} > {bound} (scale {speed_scale})"
        );
        assert!(approach < approach_plain);
        // the end-effector task is still (partly) achieved, in its direction
        let v_ee = j_ee.fixed_rows::<3>(0) * &qd;
        assert!(out.scale > 0.05, "task scale {}", out.scale);
        let expected = xdot_t * out.scale;
        assert!(
            (v_ee - expected).norm() < 0.02 * xdot_t.norm(),
            "ee velocity {v_ee} vs s ẋ = {expected}"
        );
        println!(
            "lwr avoidance: speed scale {speed_scale}: task scale {:.3}, elbow approach {:.4} m/s \
             (bound {:.4}, unconstrained {:.4}), saturated {:07b}",
            out.scale, approach, bound, approach_plain, out.saturated
        );
    }

    // eq. 19 on the robot: with generous bounds the end effector follows ẋ_t + V_Call(P_e)
    let v_ee_rep = Vector3::new(-0.05, 0.0, 0.02);
    let out = av.step(&q, &j_ee, &xdot_t, &v_ee_rep, &[], 1.0).unwrap();
    let v_ee = j_ee.fixed_rows::<3>(0) * nalgebra::DVector::from_column_slice(out.qd);
    if out.scale == 1.0 {
        assert!((v_ee - (xdot_t + v_ee_rep)).norm() < 0.01 * (xdot_t + v_ee_rep).norm());
    }

    // stale perception: a zero speed scale holds the arm
    let out = av.step(&q, &j_ee, &xdot_t, &zero, &[], 0.0).unwrap();
    assert!(out.qd.iter().all(|&v| v == 0.0) && out.scale == 0.0);
    // the speed scale multiplies the bounds of the cycle, which are kept:
    // solving again at full speed gives the unscaled bounds back
    let before: Vec<f64> = av.bounds().1.to_vec();
    let out = av.solve(&j_ee, &xdot_t, &zero, 1.0).unwrap();
    assert_eq!(out.qd_max, &before[..]);
    let out = av.solve(&j_ee, &xdot_t, &zero, 0.25).unwrap();
    for (a, b) in out.qd_max.iter().zip(&before) {
        assert!((a - 0.25 * b).abs() < 1e-15);
    }
}

// ---------------------------------------------------------------------------
// no allocation per call

#[test]
fn solve_and_step_do_not_allocate() {
    let (n, m) = (7, 3);
    let mut rng = Rng(7);
    let mut sns = SnsSolver::new(n, m);
    type Problem3 = (DMatrix<f64>, [f64; 3], Vec<f64>, Vec<f64>);
    let problems: Vec<Problem3> = (0..20)
        .map(|_| {
            (
                DMatrix::from_fn(m, n, |_, _| rng.uniform(-1.0, 1.0)),
                [
                    rng.uniform(-2.0, 2.0),
                    rng.uniform(-2.0, 2.0),
                    rng.uniform(-2.0, 2.0),
                ],
                (0..n).map(|_| -rng.uniform(0.05, 0.5)).collect(),
                (0..n).map(|_| rng.uniform(0.05, 0.5)).collect(),
            )
        })
        .collect();
    let mut iterations = 0;
    let before = allocations();
    for (j, xd, lo, hi) in &problems {
        let r = sns.solve(j, xd, lo, hi, 0.01).unwrap();
        iterations += r.iterations;
    }
    assert_eq!(allocations() - before, 0, "SnsSolver::solve allocated");
    assert!(iterations > 20, "the problems should need saturations");
    // the optimal phase too, with all kinds of bounds, with and without damping
    let problems: Vec<Problem> = [
        BoundKind::AroundZero,
        BoundKind::Offset,
        BoundKind::Infinite,
        BoundKind::Degenerate,
    ]
    .into_iter()
    .flat_map(|kind| (0..10).map(move |_| kind))
    .map(|kind| random_problem(&mut rng, m, n, kind, 3.0))
    .collect();
    let mut scaled = 0;
    let before = allocations();
    for (j, xd, lo, hi) in &problems {
        for damping in [0.0, 0.01] {
            let r = sns.solve(j, xd, lo, hi, damping).unwrap();
            scaled += usize::from(r.scale < 1.0);
        }
    }
    assert_eq!(allocations() - before, 0, "SnsSolver::solve allocated");
    assert!(scaled > 20, "the problems should need the optimal phase");

    let model = lwr4();
    let mut data = Data::new(&model);
    let q = [0.2, 0.7, -0.3, -1.3, 0.4, 0.9, 0.0];
    let mut j_ee = Matrix6xX::zeros(7);
    let mut j_el = Matrix6xX::zeros(7);
    let mut j_wr = Matrix6xX::zeros(7);
    let (ee, el, wr) = (
        model.frame_id("lwr_link_7").unwrap(),
        model.frame_id("lwr_link_4").unwrap(),
        model.frame_id("lwr_link_6").unwrap(),
    );
    let mut av = Avoidance::new(&model, avoidance_params());
    let before = allocations();
    phri_model::forward_kinematics(&model, &mut data, &q).unwrap();
    phri_model::point_jacobian(&model, &data, ee, &Vector3::zeros(), &mut j_ee).unwrap();
    phri_model::point_jacobian(&model, &data, el, &Vector3::zeros(), &mut j_el).unwrap();
    phri_model::point_jacobian(&model, &data, wr, &Vector3::zeros(), &mut j_wr).unwrap();
    let points = [
        ControlPoint::new(&j_el, Vector3::new(0.1, -0.1, 0.05)),
        ControlPoint::new(&j_wr, Vector3::new(0.0, 0.15, 0.0)),
    ];
    for k in 0..10 {
        let xd = Vector3::new(0.3, -0.2 + 0.05 * k as f64, 0.1);
        av.step(&q, &j_ee, &xd, &Vector3::new(0.0, 0.0, 0.05), &points, 0.7)
            .unwrap();
        // the same in parts, reusing one Jacobian buffer per point
        av.begin(&q).unwrap();
        av.add_point(&j_el, points[0].v_call).unwrap();
        av.add_point(&j_wr.fixed_rows::<3>(0), points[1].v_call)
            .unwrap();
        av.solve(&j_ee.fixed_rows::<3>(0), &xd, &Vector3::zeros(), 1.0)
            .unwrap();
    }
    assert_eq!(allocations() - before, 0, "Avoidance allocated");
}

// ---------------------------------------------------------------------------
// cost per solve

/// Nanoseconds per solve of random 3×7 problems (bounds around zero), by
/// class: the pseudoinverse fits (one iteration), scaled where greedy SNS
/// already reaches the optimum, scaled where a release is needed; without
/// damping and with the avoidance layer's 0.02. Timing only, so ignored by
/// default: `cargo test --release -p phri-control --test sns -- --ignored
/// --nocapture bench`.
#[test]
#[ignore]
fn bench_solve_3x7() {
    use std::time::Instant;
    let (m, n) = (3, 7);
    let mut rng = Rng(0xbe_0c4);
    let mut sns = SnsSolver::new(n, m);
    let mut classes: [Vec<Problem>; 3] = [Vec::new(), Vec::new(), Vec::new()];
    while classes.iter().any(|c| c.len() < 500) {
        let p = random_problem(&mut rng, m, n, BoundKind::AroundZero, 3.0);
        let (j, xd, lo, hi) = &p;
        let r = sns.solve(j, xd, lo, hi, 0.0).unwrap();
        let class = if r.scale == 1.0 && r.iterations == 1 {
            0
        } else if greedy_sns_scale(j, xd, lo, hi) >= r.scale - SCALE_TOL {
            1
        } else {
            2
        };
        if classes[class].len() < 500 {
            classes[class].push(p);
        }
    }
    // row-major copies, as the avoidance layer's buffers would be
    type RowMajor = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);
    let classes: Vec<Vec<RowMajor>> = classes
        .iter()
        .map(|c| {
            c.iter()
                .map(|(j, xd, lo, hi)| {
                    let jr: Vec<f64> = (0..m * n).map(|k| j[(k / n, k % n)]).collect();
                    (jr, xd.clone(), lo.clone(), hi.clone())
                })
                .collect()
        })
        .collect();
    let names = [
        "pinv fits",
        "scaled, greedy optimal",
        "scaled, release needed",
    ];
    for damping in [0.0, 0.02] {
        for (name, set) in names.iter().zip(&classes) {
            let reps = 400;
            let (mut sink, mut iterations) = (0.0, 0u64);
            let t0 = Instant::now();
            for _ in 0..reps {
                for (j, xd, lo, hi) in set {
                    let r = sns.solve_row_major(j, xd, lo, hi, damping).unwrap();
                    sink += r.scale;
                    iterations += u64::from(r.iterations);
                }
            }
            let solves = (reps * set.len()) as f64;
            let ns = t0.elapsed().as_nanos() as f64 / solves;
            println!(
                "bench 3×7 damping {damping}: {name}: {ns:.0} ns/solve, {:.1} iterations \
                 (mean scale {:.3})",
                iterations as f64 / solves,
                sink / solves
            );
        }
    }
}
