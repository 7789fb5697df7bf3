//! Thousands of random problems against the interior-point solver
//! clarabel, and each answer's KKT conditions checked directly.

mod common;

use common::{clarabel, kkt, random_feasible, Qp};
use phri_qp::{solve, QpError, Settings, Start, Workspace};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

const N: usize = 7;

/// Solve `qp` cold, check KKT and agreement with clarabel; returns the
/// iterations.
fn check(ws: &mut Workspace, qp: &Qp, case: usize) -> usize {
    let sol = solve(ws, &qp.problem(), Start::Cold).unwrap_or_else(|e| panic!("case {case}: {e}"));
    let (primal, dual, comp, stat) = kkt(qp, sol.x, sol.lambda);
    let scale = 1.0 + qp.g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(primal <= 1e-8, "case {case}: primal violation {primal:e}");
    assert!(dual <= 0.0, "case {case}: negative multiplier {dual:e}");
    assert!(
        comp <= 1e-8 * scale,
        "case {case}: complementarity {comp:e}"
    );
    assert!(stat <= 1e-8 * scale, "case {case}: stationarity {stat:e}");
    let (x_ref, obj_ref) =
        clarabel(qp).unwrap_or_else(|| panic!("case {case}: clarabel says infeasible"));
    let dx = sol
        .x
        .iter()
        .zip(&x_ref)
        .fold(0.0f64, |a, (u, v)| a.max((u - v).abs()));
    let xmax = x_ref.iter().fold(1.0f64, |a, v| a.max(v.abs()));
    assert!(dx <= 1e-6 * xmax, "case {case}: |x − x_clarabel| = {dx:e}");
    let dobj = (sol.objective - obj_ref).abs();
    assert!(
        dobj <= 1e-8 * (1.0 + obj_ref.abs()),
        "case {case}: objective {} vs {obj_ref} ({dobj:e})",
        sol.objective
    );
    // the objective is the lower of the two (clarabel stops a little inside)
    assert!(
        sol.objective <= obj_ref + 1e-9 * (1.0 + obj_ref.abs()),
        "case {case}"
    );
    sol.iterations
}

#[test]
fn agrees_with_clarabel_on_3000_random_problems() {
    let mut rng = SmallRng::seed_from_u64(44);
    let mut ws = Workspace::new(N, 32, Settings::default()).expect("workspace");
    let mut total = 0;
    let mut max_it = 0;
    for case in 0..3000 {
        let m = [4, 16, 32][case % 3];
        let qp = random_feasible(&mut rng, N, m);
        let it = check(&mut ws, &qp, case);
        total += it;
        max_it = max_it.max(it);
    }
    eprintln!("3000 problems: {total} iterations, at most {max_it}");
}

#[test]
fn agrees_with_clarabel_with_bounds() {
    let mut rng = SmallRng::seed_from_u64(15066);
    let mut ws = Workspace::new(N, 16, Settings::default()).expect("workspace");
    for case in 0..500 {
        let mut qp = random_feasible(&mut rng, N, 16);
        // bounds around the feasible point's region, some infinite
        let lo: Vec<f64> = (0..N)
            .map(|_| {
                if rng.gen_bool(0.2) {
                    f64::NEG_INFINITY
                } else {
                    rng.gen_range(-3.0..-1.0)
                }
            })
            .collect();
        let hi: Vec<f64> = (0..N)
            .map(|_| {
                if rng.gen_bool(0.2) {
                    f64::INFINITY
                } else {
                    rng.gen_range(1.0..3.0)
                }
            })
            .collect();
        qp.bounds = Some((lo, hi));
        check(&mut ws, &qp, case);
    }
}

#[test]
fn other_sizes_in_one_workspace() {
    let mut rng = SmallRng::seed_from_u64(7);
    let mut ws = Workspace::new(16, 64, Settings::default()).expect("workspace");
    for case in 0..300 {
        let n = rng.gen_range(1..=16);
        let m = rng.gen_range(0..=64);
        let qp = random_feasible(&mut rng, n, m);
        check(&mut ws, &qp, case);
    }
}

#[test]
fn detects_infeasible_problems() {
    let mut rng = SmallRng::seed_from_u64(13855);
    let mut ws = Workspace::new(N, 32, Settings::default()).expect("workspace");
    for case in 0..1000 {
        let m = [4, 16, 32][case % 3];
        let mut qp = random_feasible(&mut rng, N, m - 1);
        // a row against a positive combination of others: Σ w_i c_iᵀx ≤ Σ w_i d_i
        // contradicts −Σ w_i c_iᵀx ≤ −Σ w_i d_i − 1
        let k = rng.gen_range(1..=(m - 1).min(N + 2));
        let (mut row, mut rhs) = (vec![0.0; N], -1.0 - rng.gen_range(0.0..1.0));
        for i in 0..k {
            let w = rng.gen_range(0.1..1.0);
            for j in 0..N {
                row[j] -= w * qp.c[i * N + j];
            }
            rhs -= w * qp.d[i];
        }
        qp.c.extend(row);
        qp.d.push(rhs);
        match solve(&mut ws, &qp.problem(), Start::Cold) {
            Err(QpError::Infeasible { .. }) => {}
            other => panic!("case {case}: expected infeasible, got {other:?}"),
        }
        assert!(
            clarabel(&qp).is_none(),
            "case {case}: clarabel found a solution"
        );
    }
    // bounds that cross, rows that cannot hold
    let qp = Qp {
        n: 2,
        h: vec![1.0, 0.0, 0.0, 1.0],
        g: vec![0.0, 0.0],
        c: vec![1.0, 0.0, -1.0, 0.0],
        d: vec![-1.0, -1.0],
        bounds: None,
    };
    assert!(matches!(
        solve(&mut ws, &qp.problem(), Start::Cold),
        Err(QpError::Infeasible { .. })
    ));
}
