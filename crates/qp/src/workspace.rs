//! The preallocated workspace: every buffer a solve needs, sized once for
//! the largest problem.

use crate::{QpError, Settings};

/// Buffers for problems of up to `n_max` variables and `m_max` general rows
/// (plus `2 n_max` bound rows), allocated once at construction; a solve
/// writes into them and allocates nothing. It also keeps the last
/// successful solve's active set, the hint of a [`crate::Start::Warm`].
///
/// Layouts: J and R column-major with stride n (the problem's n), the
/// internal rows column-major with stride `rows` (so that `A x` for every
/// row runs down contiguous columns).
#[derive(Clone, Debug)]
pub struct Workspace {
    pub(crate) n_max: usize,
    pub(crate) m_max: usize,
    pub(crate) settings: Settings,
    /// internal normals `a_i = −c_i / ‖c_i‖` (rows in the form
    /// `a_iᵀx ≥ b_i`), column-major: `a[k * rows + i]`
    pub(crate) a: Vec<f64>,
    /// the current problem's number of rows (a's stride)
    pub(crate) rows: usize,
    /// the rows' slacks `a_iᵀx − b_i` at the current point
    pub(crate) s: Vec<f64>,
    /// scratch: one row gathered from `a`
    pub(crate) ap: Vec<f64>,
    /// internal right-hand sides `b_i = −d_i / ‖c_i‖`
    pub(crate) b: Vec<f64>,
    /// `‖c_i‖`; 0 for a row that can never bind (zero or infinite bound)
    pub(crate) scale: Vec<f64>,
    /// whether row i is in the active set
    pub(crate) is_active: Vec<bool>,
    /// J = L⁻ᵀ Q, column-major
    pub(crate) j: Vec<f64>,
    /// R, upper triangular, column-major
    pub(crate) r: Vec<f64>,
    /// the unconstrained minimum −H⁻¹g
    pub(crate) x0: Vec<f64>,
    /// the current primal point
    pub(crate) x: Vec<f64>,
    /// scratch: d = Jᵀ a
    pub(crate) d: Vec<f64>,
    /// scratch: the primal direction z
    pub(crate) z: Vec<f64>,
    /// scratch: the multipliers' direction r (or warm-start terms)
    pub(crate) rv: Vec<f64>,
    /// scratch for the warm start
    pub(crate) tmp: Vec<f64>,
    /// active rows, in R's column order
    pub(crate) active: Vec<usize>,
    /// their (scaled) multipliers
    pub(crate) lam: Vec<f64>,
    /// the number of active rows q
    pub(crate) q: usize,
    /// multipliers of every row in the solution's layout (unscaled)
    pub(crate) lambda: Vec<f64>,
    /// the warm-start hint
    pub(crate) hint: Vec<usize>,
    pub(crate) hint_len: usize,
}

impl Workspace {
    /// A workspace for up to `n_max` variables and `m_max` general rows
    /// (bounds add `2 n_max` rows on top). Fails with
    /// [`QpError::BadSize`] for `n_max == 0` and [`QpError::NonFinite`] for
    /// non-finite or negative tolerances.
    pub fn new(n_max: usize, m_max: usize, settings: Settings) -> Result<Self, QpError> {
        if n_max == 0 {
            return Err(QpError::BadSize {
                what: "n_max",
                got: 0,
                expected: 1,
            });
        }
        let valid = |tol: f64| tol >= 0.0 && tol.is_finite();
        if !valid(settings.feasibility_tol) || !valid(settings.dependence_tol) {
            return Err(QpError::NonFinite { what: "settings" });
        }
        let rows = m_max + 2 * n_max;
        let nn = n_max * n_max;
        Ok(Self {
            n_max,
            m_max,
            settings,
            a: vec![0.0; rows * n_max],
            rows: 0,
            s: vec![0.0; rows],
            ap: vec![0.0; n_max],
            b: vec![0.0; rows],
            scale: vec![0.0; rows],
            is_active: vec![false; rows],
            j: vec![0.0; nn],
            r: vec![0.0; nn],
            x0: vec![0.0; n_max],
            x: vec![0.0; n_max],
            d: vec![0.0; n_max],
            z: vec![0.0; n_max],
            rv: vec![0.0; n_max],
            tmp: vec![0.0; n_max],
            active: vec![0; n_max],
            lam: vec![0.0; n_max],
            q: 0,
            lambda: vec![0.0; rows],
            hint: vec![0; n_max],
            hint_len: 0,
        })
    }

    /// The largest number of variables.
    pub fn n_max(&self) -> usize {
        self.n_max
    }

    /// The largest number of general rows (bounds not counted).
    pub fn m_max(&self) -> usize {
        self.m_max
    }

    /// The settings fixed at construction.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The active set a [`crate::Start::Warm`] starts from: row indices in
    /// the solution's layout (see [`crate::Problem::rows`]).
    pub fn hint(&self) -> &[usize] {
        &self.hint[..self.hint_len]
    }

    /// Replace the warm-start hint by `rows` (at most `n_max` are kept: no
    /// more rows can be active at once); allocates nothing.
    pub fn set_hint(&mut self, rows: &[usize]) {
        let k = rows.len().min(self.n_max);
        self.hint[..k].copy_from_slice(&rows[..k]);
        self.hint_len = k;
    }

    /// Copy row `row` of the internal normals into `ap`.
    #[inline]
    pub(crate) fn gather_row(&mut self, n: usize, row: usize) {
        let rows = self.rows;
        for (k, v) in self.ap[..n].iter_mut().enumerate() {
            *v = self.a[k * rows + row];
        }
    }

    /// Forget the warm-start hint (the next warm start is a cold one).
    pub fn clear_hint(&mut self) {
        self.hint_len = 0;
    }
}
