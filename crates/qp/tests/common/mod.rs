//! Random problems and the clarabel cross-check shared by the tests.

#![allow(dead_code)]

pub mod sequence;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use rand::rngs::SmallRng;
use rand::Rng;

/// A problem owned by the test: H, g row-major, C, d, optional bounds.
#[derive(Clone, Debug)]
pub struct Qp {
    pub n: usize,
    pub h: Vec<f64>,
    pub g: Vec<f64>,
    pub c: Vec<f64>,
    pub d: Vec<f64>,
    pub bounds: Option<(Vec<f64>, Vec<f64>)>,
}

impl Qp {
    pub fn problem(&self) -> phri_qp::Problem<'_> {
        phri_qp::Problem {
            n: self.n,
            h: &self.h,
            g: &self.g,
            c: &self.c,
            d: &self.d,
            bounds: self
                .bounds
                .as_ref()
                .map(|(lo, hi)| (lo.as_slice(), hi.as_slice())),
        }
    }

    pub fn m(&self) -> usize {
        self.d.len()
    }

    /// All rows, bounds included, as (C_all, d_all) in the solution's layout.
    pub fn all_rows(&self) -> (Vec<f64>, Vec<f64>) {
        let n = self.n;
        let (mut c, mut d) = (self.c.clone(), self.d.clone());
        if let Some((lo, hi)) = &self.bounds {
            for (sign, b) in [(1.0, hi), (-1.0, lo)] {
                for k in 0..n {
                    let mut row = vec![0.0; n];
                    // an infinite bound as a row that binds nothing
                    if b[k].is_finite() {
                        row[k] = sign;
                        d.push(sign * b[k]);
                    } else {
                        d.push(1.0);
                    }
                    c.extend(row);
                }
            }
        }
        (c, d)
    }

    pub fn objective(&self, x: &[f64]) -> f64 {
        let n = self.n;
        (0..n)
            .map(|i| {
                x[i] * (0.5 * (0..n).map(|k| self.h[i * n + k] * x[k]).sum::<f64>() + self.g[i])
            })
            .sum()
    }
}

pub fn uniform(rng: &mut SmallRng, k: usize, half: f64) -> Vec<f64> {
    (0..k).map(|_| rng.gen_range(-half..half)).collect()
}

/// H = MᵀM + μI with M uniform in [−1, 1]: SPD, condition number up to ~1e3.
pub fn random_spd(rng: &mut SmallRng, n: usize) -> Vec<f64> {
    let m = uniform(rng, n * n, 1.0);
    let mu = rng.gen_range(0.05..1.0);
    let mut h = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            h[i * n + j] = (0..n).map(|k| m[k * n + i] * m[k * n + j]).sum::<f64>()
                + if i == j { mu } else { 0.0 };
        }
    }
    h
}

/// A feasible problem: rows through or around a feasible point x_f (a
/// third of them tight there), the unconstrained minimum pulled away from
/// it so that several rows bind.
pub fn random_feasible(rng: &mut SmallRng, n: usize, m: usize) -> Qp {
    let h = random_spd(rng, n);
    let xf = uniform(rng, n, 1.0);
    let c = uniform(rng, m * n, 1.0);
    let d = (0..m)
        .map(|i| {
            let cx: f64 = (0..n).map(|k| c[i * n + k] * xf[k]).sum();
            let slack = if rng.gen_bool(0.3) {
                0.0
            } else {
                rng.gen_range(0.0..1.0)
            };
            cx + slack
        })
        .collect();
    let pull = rng.gen_range(0.5..5.0);
    let xu: Vec<f64> = xf
        .iter()
        .map(|v| v + pull * rng.gen_range(-1.0..1.0))
        .collect();
    let g = (0..n)
        .map(|i| -(0..n).map(|k| h[i * n + k] * xu[k]).sum::<f64>())
        .collect();
    Qp {
        n,
        h,
        g,
        c,
        d,
        bounds: None,
    }
}

/// The interior-point answer: Some((x, objective)) if clarabel solved it,
/// None if it found the problem primal infeasible.
pub fn clarabel(qp: &Qp) -> Option<(Vec<f64>, f64)> {
    let n = qp.n;
    let (c, d) = qp.all_rows();
    let m = d.len();
    // P: upper triangle, column by column
    let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
    for j in 0..n {
        for i in 0..=j {
            rowval.push(i);
            nzval.push(qp.h[i * n + j]);
        }
        colptr.push(rowval.len());
    }
    let p = CscMatrix::new(n, n, colptr, rowval, nzval);
    let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
    for j in 0..n {
        for i in 0..m {
            if c[i * n + j] != 0.0 {
                rowval.push(i);
                nzval.push(c[i * n + j]);
            }
        }
        colptr.push(rowval.len());
    }
    let a = CscMatrix::new(m, n, colptr, rowval, nzval);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-11)
        .tol_gap_rel(1e-11)
        .tol_feas(1e-11)
        .max_iter(200)
        .build()
        .expect("clarabel settings");
    let cones = [NonnegativeConeT(m)];
    let mut solver =
        DefaultSolver::new(&p, &qp.g, &a, &d, &cones, settings).expect("clarabel problem");
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            Some((solver.solution.x.clone(), solver.solution.obj_val))
        }
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => None,
        s => panic!("clarabel: {s:?}"),
    }
}

/// The KKT conditions of `x`, `lambda` (solution layout) for `qp`, checked
/// directly; returns the largest residual of each: (primal, dual,
/// complementarity, stationarity).
pub fn kkt(qp: &Qp, x: &[f64], lambda: &[f64]) -> (f64, f64, f64, f64) {
    let n = qp.n;
    let (c, d) = qp.all_rows();
    let rows = d.len();
    assert_eq!(lambda.len(), rows);
    let (mut primal, mut dual, mut comp) = (0.0f64, 0.0f64, 0.0f64);
    let mut grad: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|k| qp.h[i * n + k] * x[k]).sum::<f64>() + qp.g[i])
        .collect();
    for i in 0..rows {
        let row = &c[i * n..(i + 1) * n];
        let norm = row.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
        let viol = (row.iter().zip(x).map(|(u, v)| u * v).sum::<f64>() - d[i]) / norm;
        primal = primal.max(viol);
        dual = dual.max(-lambda[i]);
        comp = comp.max((lambda[i] * norm * viol).abs());
        for k in 0..n {
            grad[k] += row[k] * lambda[i];
        }
    }
    let stat = grad.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    (primal, dual, comp, stat)
}
