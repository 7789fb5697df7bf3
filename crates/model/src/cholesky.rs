//! The one Cholesky of phri's numerics: `A = L Lᵀ` for a symmetric positive
//! definite `A`, factored in place (the lower triangle holds `L`), and the
//! solve `A x = b` by forward and back substitution. No allocation: the
//! dynamics (`M q̈ = τ − b`), the simulator's implicit step and the SNS
//! solver's `J W Jᵀ + λ² I` all use it.

use nalgebra::{DMatrixView, DMatrixViewMut};

/// `A` is not (numerically) positive definite: pivot `index` was `pivot`.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("not positive definite: pivot {index} is {pivot}")]
pub struct NotPositiveDefinite {
    /// row (and column) of the failing pivot
    pub index: usize,
    /// the pivot's value before its square root: `≤ min_pivot` or not finite
    pub pivot: f64,
}

/// Factor `a` (n×n; its lower triangle is read) in place into `L` (lower
/// triangle; the strict upper triangle is left as it was). A pivot `≤ min_pivot`
/// (or not finite) is an error: pass 0 for exact positive definiteness, a
/// small multiple of the largest diagonal entry to refuse near-singular ones.
pub fn cholesky_factor(
    mut a: DMatrixViewMut<'_, f64>,
    min_pivot: f64,
) -> Result<(), NotPositiveDefinite> {
    let n = a.nrows();
    debug_assert_eq!(n, a.ncols());
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(j, k)];
        }
        if !(d > min_pivot && d.is_finite()) {
            return Err(NotPositiveDefinite { index: j, pivot: d });
        }
        let d = d.sqrt();
        a[(j, j)] = d;
        for i in (j + 1)..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= a[(i, k)] * a[(j, k)];
            }
            a[(i, j)] = s / d;
        }
    }
    Ok(())
}

/// Solve `L Lᵀ x = b` in place (`x` holds `b` on entry), `L` the lower triangle
/// of `l` as [`cholesky_factor`] left it.
pub fn cholesky_solve(l: DMatrixView<'_, f64>, x: &mut [f64]) {
    let n = l.nrows();
    debug_assert_eq!(x.len(), n);
    for i in 0..n {
        let mut s = x[i];
        for k in 0..i {
            s -= l[(i, k)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in (i + 1)..n {
            s -= l[(k, i)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn solves_a_positive_definite_system_and_refuses_an_indefinite_one() {
        let b = DMatrix::from_fn(5, 5, |i, j| ((i * 7 + j * 3) % 5) as f64 - 2.0);
        let a = &b * b.transpose() + DMatrix::identity(5, 5) * 0.5;
        let x_true = DVector::from_fn(5, |i, _| i as f64 - 1.5);
        let rhs = &a * &x_true;
        let mut l = a.clone();
        cholesky_factor(l.as_view_mut(), 0.0).unwrap();
        let mut x = rhs.as_slice().to_vec();
        cholesky_solve(l.as_view(), &mut x);
        for i in 0..5 {
            assert!((x[i] - x_true[i]).abs() < 1e-10, "{x:?}");
        }
        let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert_eq!(
            cholesky_factor(bad.as_view_mut(), 0.0).unwrap_err().index,
            1
        );
        let mut nan = DMatrix::from_element(2, 2, f64::NAN);
        assert!(cholesky_factor(nan.as_view_mut(), 0.0).is_err());
    }
}
