//! The Goldfarb-Idnani factors and their updates.
//!
//! With `H = L Lᵀ` and N the active rows' normals (as columns), the method
//! keeps `J = L⁻ᵀ Q` (n×n) and an upper-triangular R (q×q) such that
//! `Jᵀ N = [R; 0]` (Goldfarb & Idnani 1983, §4). Then for a new normal `a`
//! and `d = Jᵀ a = [d₁; d₂]`:
//! - the primal step direction is `z = J₂ d₂` (J₂: J's last n − q columns),
//! - the multipliers' direction is `r = R⁻¹ d₁`,
//! - and `zᵀa = ‖d₂‖²`.
//!
//! Adding a row rotates `d₂` onto its first entry (Givens rotations applied
//! to J's columns) and appends `[d₁; ‖d₂‖]` to R; dropping one removes R's
//! column and restores R's triangle with rotations of adjacent rows (and of
//! J's matching columns). Both cost O(n²).
//!
//! Storage: J and R column-major with stride n (`j[col * n + row]`).

/// One Givens rotation `[c s; −s c]` that maps `(a, b)` to `(ρ, 0)`; `None`
/// when `b` is already zero. `√(a² + b²)` rather than `hypot` (several times
/// faster): the entries are those of `L⁻¹` times unit normals, far from
/// overflow for any H the Cholesky accepts.
#[inline]
fn givens(a: f64, b: f64) -> Option<(f64, f64, f64)> {
    if b == 0.0 {
        return None;
    }
    let rho = (a * a + b * b).sqrt();
    let inv = 1.0 / rho;
    Some((a * inv, b * inv, rho))
}

/// Replace J's columns `k` and `k + 1` by `c·J_k + s·J_{k+1}` and
/// `−s·J_k + c·J_{k+1}`.
#[inline]
fn rotate_columns(j: &mut [f64], n: usize, k: usize, c: f64, s: f64) {
    let (left, right) = j.split_at_mut((k + 1) * n);
    let a = &mut left[k * n..(k + 1) * n];
    let b = &mut right[..n];
    for (x, y) in a.iter_mut().zip(b.iter_mut()) {
        let (u, v) = (*x, *y);
        *x = c * u + s * v;
        *y = c * v - s * u;
    }
}

/// `d = Jᵀ a`: the normal `a` (length n) in J's coordinates.
#[inline]
pub(crate) fn project(j: &[f64], n: usize, a: &[f64], d: &mut [f64]) {
    for (col, dc) in j.chunks_exact(n).take(n).zip(d.iter_mut()) {
        *dc = col.iter().zip(a).map(|(u, v)| u * v).sum();
    }
}

/// `z = J₂ d₂ = Σ_{c ≥ q} d_c J_c`: the primal step direction.
#[inline]
pub(crate) fn primal_direction(j: &[f64], n: usize, q: usize, d: &[f64], z: &mut [f64]) {
    z[..n].fill(0.0);
    for c in q..n {
        let dc = d[c];
        for (zi, ji) in z[..n].iter_mut().zip(&j[c * n..(c + 1) * n]) {
            *zi += dc * ji;
        }
    }
}

/// Solve `R x = rhs` for the leading q×q triangle of R (back substitution),
/// `x` and `rhs` of length ≥ q.
#[inline]
pub(crate) fn solve_upper(r: &[f64], n: usize, q: usize, rhs: &[f64], x: &mut [f64]) {
    for i in (0..q).rev() {
        let mut s = rhs[i];
        for c in i + 1..q {
            s -= r[c * n + i] * x[c];
        }
        x[i] = s / r[i * n + i];
    }
}

/// Solve `Rᵀ x = rhs` for the leading q×q triangle of R (forward
/// substitution).
#[inline]
pub(crate) fn solve_upper_transposed(r: &[f64], n: usize, q: usize, rhs: &[f64], x: &mut [f64]) {
    for i in 0..q {
        let col = &r[i * n..i * n + i];
        let s: f64 = col.iter().zip(&x[..i]).map(|(u, v)| u * v).sum();
        x[i] = (rhs[i] - s) / r[i * n + i];
    }
}

/// Append the row whose projection is `d = Jᵀ a` (computed with the current
/// J) as R's column q; `d` is overwritten. The caller has checked that
/// `‖d₂‖` is not negligible (q < n).
pub(crate) fn add_row(j: &mut [f64], r: &mut [f64], n: usize, q: usize, d: &mut [f64]) {
    for k in (q + 1..n).rev() {
        if let Some((c, s, rho)) = givens(d[k - 1], d[k]) {
            d[k - 1] = rho;
            d[k] = 0.0;
            rotate_columns(j, n, k - 1, c, s);
        }
    }
    r[q * n..q * n + q + 1].copy_from_slice(&d[..=q]);
}

/// Remove R's column `k` of q (the k-th active row) and restore R's upper
/// triangle, rotating J's columns to match; R is then (q − 1)×(q − 1).
pub(crate) fn drop_row(j: &mut [f64], r: &mut [f64], n: usize, q: usize, k: usize) {
    // shift columns k+1..q left by one: R is then upper Hessenberg from k on
    r.copy_within((k + 1) * n..q * n, k * n);
    for i in k..q - 1 {
        let Some((c, s, rho)) = givens(r[i * n + i], r[i * n + i + 1]) else {
            continue;
        };
        r[i * n + i] = rho;
        r[i * n + i + 1] = 0.0;
        for col in i + 1..q - 1 {
            let (u, v) = (r[col * n + i], r[col * n + i + 1]);
            r[col * n + i] = c * u + s * v;
            r[col * n + i + 1] = c * v - s * u;
        }
        rotate_columns(j, n, i, c, s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jᵀ N = [R; 0] after adds and drops, with J = I to start (H = I).
    #[test]
    fn factors_stay_consistent() {
        let n = 4;
        let mut j = vec![0.0; n * n];
        for i in 0..n {
            j[i * n + i] = 1.0;
        }
        let mut r = vec![0.0; n * n];
        let rows = [
            [1.0, 2.0, 0.5, -1.0],
            [0.0, 1.0, -1.0, 2.0],
            [3.0, -1.0, 0.0, 1.0],
        ];
        let mut d = vec![0.0; n];
        for (q, a) in rows.iter().enumerate() {
            project(&j, n, a, &mut d);
            add_row(&mut j, &mut r, n, q, &mut d);
        }
        let check = |j: &[f64], r: &[f64], active: &[[f64; 4]]| {
            let mut d = vec![0.0; n];
            for (c, a) in active.iter().enumerate() {
                project(j, n, a, &mut d);
                for i in 0..n {
                    let want = if i <= c { r[c * n + i] } else { 0.0 };
                    assert!(
                        (d[i] - want).abs() < 1e-12,
                        "col {c} row {i}: {} vs {want}",
                        d[i]
                    );
                }
            }
        };
        check(&j, &r, &rows);
        drop_row(&mut j, &mut r, n, 3, 0);
        check(&j, &r, &rows[1..]);
        // J stays orthogonal (H = I)
        for a in 0..n {
            for b in 0..n {
                let dot: f64 = (0..n).map(|i| j[a * n + i] * j[b * n + i]).sum();
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((dot - want).abs() < 1e-12);
            }
        }
    }
}
