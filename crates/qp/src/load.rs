//! A solve's first stage: check the problem, copy its rows into the
//! workspace's normalised form and factor H.

use crate::{Problem, QpError, Workspace};

fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), QpError> {
    if got == expected {
        Ok(())
    } else {
        Err(QpError::BadSize {
            what,
            got,
            expected,
        })
    }
}

fn check_finite(what: &'static str, v: &[f64]) -> Result<(), QpError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(QpError::NonFinite { what })
    }
}

impl Workspace {
    /// Check `p` against the workspace, store its rows as `a_iᵀx ≥ b_i`
    /// with unit normals, factor `H = L Lᵀ` and set `J = L⁻ᵀ` and the
    /// unconstrained minimum `x0 = −H⁻¹g`. Returns the number of rows.
    pub(crate) fn load(&mut self, p: &Problem<'_>) -> Result<usize, QpError> {
        let n = p.n;
        let m = p.m();
        if n == 0 || n > self.n_max {
            return Err(QpError::BadSize {
                what: "n",
                got: n,
                expected: self.n_max,
            });
        }
        if m > self.m_max {
            return Err(QpError::BadSize {
                what: "d (rows)",
                got: m,
                expected: self.m_max,
            });
        }
        check_len("h", p.h.len(), n * n)?;
        check_len("g", p.g.len(), n)?;
        check_len("c", p.c.len(), m * n)?;
        check_finite("h", p.h)?;
        check_finite("g", p.g)?;
        check_finite("c", p.c)?;
        check_finite("d", p.d)?;
        let rows = p.rows();
        self.rows = rows;
        let a = &mut self.a;

        // general rows: c_iᵀx ≤ d_i  ⇔  (−c_i/‖c_i‖)ᵀx ≥ −d_i/‖c_i‖, in
        // passes over all rows so that the square roots and divisions of
        // different rows overlap (`s` holds −1/‖c_i‖ until the first solve
        // iteration overwrites it)
        for (i, c) in p.c.chunks_exact(n).enumerate() {
            self.scale[i] = c.iter().map(|v| v * v).sum::<f64>();
        }
        for v in &mut self.scale[..m] {
            *v = v.sqrt();
        }
        for (inv, &norm) in self.s[..m].iter_mut().zip(&self.scale[..m]) {
            *inv = if norm > 0.0 { -1.0 / norm } else { 0.0 };
        }
        for i in 0..m {
            if self.scale[i] == 0.0 && p.d[i] < -self.settings.feasibility_tol {
                return Err(QpError::Infeasible { row: i });
            }
            self.b[i] = p.d[i] * self.s[i];
        }
        for k in 0..n {
            let col = &mut a[k * rows..k * rows + m];
            for (i, (ak, inv)) in col.iter_mut().zip(&self.s[..m]).enumerate() {
                *ak = p.c[i * n + k] * inv;
            }
        }

        // bound rows: x_k ≤ hi_k (row m + k), −x_k ≤ −lo_k (row m + n + k)
        if let Some((lo, hi)) = p.bounds {
            check_len("lo", lo.len(), n)?;
            check_len("hi", hi.len(), n)?;
            for k in 0..n {
                a[k * rows + m..(k + 1) * rows].fill(0.0);
            }
            for k in 0..n {
                if lo[k].is_nan() || hi[k].is_nan() {
                    return Err(QpError::NonFinite { what: "bounds" });
                }
                if lo[k] > hi[k] {
                    return Err(QpError::Infeasible { row: m + n + k });
                }
                for (row, sign, bound) in [(m + k, -1.0, hi[k]), (m + n + k, 1.0, lo[k])] {
                    if bound.is_finite() {
                        a[k * rows + row] = sign;
                        self.b[row] = sign * bound;
                        self.scale[row] = 1.0;
                    } else {
                        self.b[row] = 0.0;
                        self.scale[row] = 0.0;
                    }
                }
            }
        }
        self.is_active[..rows].fill(false);
        self.factor_h(p.h, n)?;

        // x0 = −J Jᵀ g
        let (j, x0, w) = (&self.j, &mut self.x0, &mut self.tmp);
        crate::factor::project(j, n, p.g, w);
        x0[..n].fill(0.0);
        for c in 0..n {
            for (xi, ji) in x0[..n].iter_mut().zip(&j[c * n..(c + 1) * n]) {
                *xi -= w[c] * ji;
            }
        }
        Ok(rows)
    }

    /// Cholesky `H = L Lᵀ` (lower triangle of H read), then `J = L⁻ᵀ`
    /// (upper triangular, column-major: J's column i is L⁻¹'s row i).
    /// L is built in R's buffer, which the solve resets anyway.
    fn factor_h(&mut self, h: &[f64], n: usize) -> Result<(), QpError> {
        let l = &mut self.r; // row-major lower triangle, stride n
        let max_diag = (0..n).map(|i| h[i * n + i].abs()).fold(0.0, f64::max);
        // 1 / L_kk, kept in `inv` (x0's buffer, set after the factorisation)
        let inv = &mut self.x0;
        for i in 0..n {
            for k in 0..=i {
                let (li, lk) = (&l[i * n..i * n + k], &l[k * n..k * n + k]);
                let s: f64 = li.iter().zip(lk).map(|(u, v)| u * v).sum();
                let v = h[i * n + k] - s;
                if i == k {
                    if !(v > f64::EPSILON * max_diag) {
                        return Err(QpError::NotPositiveDefinite {
                            column: i,
                            pivot: v,
                        });
                    }
                    let lii = v.sqrt();
                    l[i * n + i] = lii;
                    inv[i] = 1.0 / lii;
                } else {
                    l[i * n + k] = v * inv[k];
                }
            }
        }
        // L⁻¹ row by row, stored as J's columns: j[i * n + k] = (L⁻¹)_ik
        let j = &mut self.j;
        j[..n * n].fill(0.0);
        for i in 0..n {
            j[i * n + i] = inv[i];
            for k in 0..i {
                let s: f64 = (k..i).map(|t| l[i * n + t] * j[t * n + k]).sum();
                j[i * n + k] = -s * inv[i];
            }
        }
        Ok(())
    }
}
