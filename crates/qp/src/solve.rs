//! The Goldfarb-Idnani dual active-set method (Goldfarb & Idnani 1983,
//! "A numerically stable dual method for solving strictly convex quadratic
//! programs", Math. Programming 27, 1-33), warm-startable.
//!
//! The method moves through S-pairs: points x that minimise the objective
//! on the active rows' planes with non-negative multipliers (dual
//! feasible). Each iteration takes the most violated row p (by distance to
//! its plane) and steps along `z = J₂ d₂` (primal) and `−r = −R⁻¹d₁`
//! (dual): a full step makes p active; a partial step, limited by an active
//! row's multiplier reaching zero, drops that row first. The dual objective
//! rises at every step, so no active set repeats (in exact arithmetic); a
//! violated row with no primal direction and no multiplier to trade is
//! proof of infeasibility.

use crate::factor::{
    add_row, drop_row, primal_direction, project, solve_upper, solve_upper_transposed,
};
use crate::{Problem, QpError, Solution, Start, Workspace};

/// Solve `p` in `ws`, from the unconstrained minimum ([`Start::Cold`]) or
/// from the last successful solve's active set ([`Start::Warm`]); allocates
/// nothing. The solution borrows the workspace's buffers; its active set
/// becomes the workspace's next warm-start hint.
///
/// Errors: [`QpError::BadSize`] / [`QpError::NonFinite`] for inputs that do
/// not fit, [`QpError::NotPositiveDefinite`] when H's Cholesky fails,
/// [`QpError::Infeasible`] when no point satisfies the rows,
/// [`QpError::IterationLimit`] after [`crate::Settings::max_iterations`]
/// active-set changes.
pub fn solve<'w>(
    ws: &'w mut Workspace,
    p: &Problem<'_>,
    start: Start,
) -> Result<Solution<'w>, QpError> {
    let rows = ws.load(p)?;
    let n = p.n;
    ws.q = 0;
    ws.x[..n].copy_from_slice(&ws.x0[..n]);
    let warm_rows = match start {
        Start::Cold => 0,
        Start::Warm => ws.warm_start(n, rows),
    };
    let iterations = ws.iterate(n, rows)?;
    Ok(ws.finish(p, rows, iterations, warm_rows))
}

impl Workspace {
    /// Drop active row `k` (its position in the active list).
    fn drop_active(&mut self, n: usize, k: usize) {
        let q = self.q;
        drop_row(&mut self.j, &mut self.r, n, q, k);
        self.is_active[self.active[k]] = false;
        self.active.copy_within(k + 1..q, k);
        self.lam.copy_within(k + 1..q, k);
        self.q = q - 1;
    }

    /// Whether `d = Jᵀa` leaves a usable component outside the active
    /// rows' span; returns `‖d₂‖²` if so.
    fn independent_part(&self, n: usize) -> Option<f64> {
        let q = self.q;
        if q >= n {
            return None;
        }
        let all: f64 = self.d[..n].iter().map(|v| v * v).sum();
        let d2: f64 = self.d[q..n].iter().map(|v| v * v).sum();
        let tol = self.settings.dependence_tol;
        (d2 > tol * tol * all && d2 > 0.0).then_some(d2)
    }

    /// Make the hint's rows active (skipping absent, unusable and linearly
    /// dependent ones), then drop rows while a multiplier of the
    /// equality-constrained minimum is negative. Leaves an S-pair: x the
    /// minimum on the remaining rows' planes, multipliers ≥ 0. Returns the
    /// number of rows kept.
    fn warm_start(&mut self, n: usize, rows: usize) -> usize {
        for h in 0..self.hint_len {
            let row = self.hint[h];
            if row >= rows || self.is_active[row] || self.scale[row] == 0.0 {
                continue;
            }
            self.gather_row(n, row);
            project(&self.j, n, &self.ap, &mut self.d);
            if self.independent_part(n).is_none() {
                continue;
            }
            add_row(&mut self.j, &mut self.r, n, self.q, &mut self.d);
            self.active[self.q] = row;
            self.is_active[row] = true;
            self.q += 1;
        }
        // the minimum on the active planes: with v_i = b_i − a_iᵀx0,
        // y = R⁻ᵀv, multipliers λ = R⁻¹y and x = x0 + J₁y
        loop {
            let q = self.q;
            if q == 0 {
                break;
            }
            let rows = self.rows;
            for (k, &row) in self.active[..q].iter().enumerate() {
                let ax0: f64 = (0..n).map(|t| self.a[t * rows + row] * self.x0[t]).sum();
                self.rv[k] = self.b[row] - ax0;
            }
            solve_upper_transposed(&self.r, n, q, &self.rv, &mut self.tmp);
            solve_upper(&self.r, n, q, &self.tmp, &mut self.lam);
            let (k_min, lam_min) =
                self.lam[..q]
                    .iter()
                    .enumerate()
                    .fold(
                        (0, f64::INFINITY),
                        |acc, (k, &l)| if l < acc.1 { (k, l) } else { acc },
                    );
            if lam_min >= 0.0 {
                break;
            }
            self.drop_active(n, k_min);
        }
        let q = self.q;
        self.x[..n].copy_from_slice(&self.x0[..n]);
        for c in 0..q {
            let y = self.tmp[c];
            for (xi, ji) in self.x[..n].iter_mut().zip(&self.j[c * n..(c + 1) * n]) {
                *xi += y * ji;
            }
        }
        q
    }

    /// The main loop from the current S-pair; returns the number of
    /// iterations (rows added or dropped).
    fn iterate(&mut self, n: usize, rows: usize) -> Result<usize, QpError> {
        let max_iterations = self.settings.max_iterations;
        let tol = self.settings.feasibility_tol;
        let mut iterations = 0;
        if rows == 0 {
            return Ok(0);
        }
        loop {
            // step 1: the most violated row (distance to its plane); the
            // slacks s = A x − b column by column (contiguous, vectorised)
            let s = &mut self.s[..rows];
            for (si, bi) in s.iter_mut().zip(&self.b[..rows]) {
                *si = -bi;
            }
            for (k, col) in self.a.chunks_exact(rows).take(n).enumerate() {
                let xk = self.x[k];
                for (si, ai) in s.iter_mut().zip(col) {
                    *si += ai * xk;
                }
            }
            let mut p = usize::MAX;
            let mut worst = -tol;
            for (i, &si) in s.iter().enumerate() {
                if si < worst && !self.is_active[i] && self.scale[i] != 0.0 {
                    worst = si;
                    p = i;
                }
            }
            if p == usize::MAX {
                return Ok(iterations);
            }
            // step 2: move until p is active
            let mut u = 0.0; // p's multiplier
            self.gather_row(n, p);
            loop {
                if iterations >= max_iterations {
                    return Err(QpError::IterationLimit { max_iterations });
                }
                iterations += 1;
                let q = self.q;
                project(&self.j, n, &self.ap, &mut self.d);
                let zn = self.independent_part(n);
                if zn.is_some() {
                    primal_direction(&self.j, n, q, &self.d, &mut self.z);
                }
                solve_upper(&self.r, n, q, &self.d, &mut self.rv);
                // partial step: the first active multiplier to reach zero
                let mut t1 = f64::INFINITY;
                let mut k = usize::MAX;
                for c in 0..q {
                    if self.rv[c] > 0.0 {
                        // a multiplier rounded below zero limits the step to zero
                        let t = (self.lam[c] / self.rv[c]).max(0.0);
                        if t < t1 {
                            t1 = t;
                            k = c;
                        }
                    }
                }
                let s_p = self.ap[..n]
                    .iter()
                    .zip(&self.x[..n])
                    .map(|(u, v)| u * v)
                    .sum::<f64>()
                    - self.b[p];
                let Some(zn) = zn else {
                    // no primal direction: trade multipliers, or infeasible
                    if k == usize::MAX {
                        return Err(QpError::Infeasible { row: p });
                    }
                    for c in 0..q {
                        self.lam[c] -= t1 * self.rv[c];
                    }
                    u += t1;
                    self.drop_active(n, k);
                    continue;
                };
                // full step: p's plane reached
                let t2 = (-s_p / zn).max(0.0);
                let t = t1.min(t2);
                for (xi, zi) in self.x[..n].iter_mut().zip(&self.z[..n]) {
                    *xi += t * zi;
                }
                for c in 0..q {
                    self.lam[c] -= t * self.rv[c];
                }
                u += t;
                if t2 <= t1 {
                    add_row(&mut self.j, &mut self.r, n, q, &mut self.d);
                    self.active[q] = p;
                    self.lam[q] = u;
                    self.is_active[p] = true;
                    self.q = q + 1;
                    break;
                }
                self.drop_active(n, k);
            }
        }
    }

    /// Unscale the multipliers into the rows' layout, evaluate the
    /// objective, keep the active set as the next hint.
    fn finish(
        &mut self,
        p: &Problem<'_>,
        rows: usize,
        iterations: usize,
        warm_rows: usize,
    ) -> Solution<'_> {
        let n = p.n;
        let q = self.q;
        self.lambda[..rows].fill(0.0);
        for c in 0..q {
            let row = self.active[c];
            // a_i = −c_i/‖c_i‖: λ for c_iᵀx ≤ d_i is λ_scaled / ‖c_i‖
            self.lambda[row] = self.lam[c].max(0.0) / self.scale[row];
        }
        self.hint[..q].copy_from_slice(&self.active[..q]);
        self.hint_len = q;
        let x = &self.x[..n];
        let mut objective = 0.0;
        for i in 0..n {
            let hx: f64 = (0..n).map(|k| p.h[i * n + k] * x[k]).sum();
            objective += x[i] * (0.5 * hx + p.g[i]);
        }
        Solution {
            x,
            lambda: &self.lambda[..rows],
            active: &self.active[..q],
            objective,
            iterations,
            warm_rows,
        }
    }
}
