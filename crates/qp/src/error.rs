//! The solver's typed errors.

/// Why a solve or a workspace's construction failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QpError {
    /// The rows admit no point: the dual is unbounded (Goldfarb-Idnani step
    /// 2(a): a violated row that no step can satisfy), a zero row with a
    /// negative right-hand side, or a lower bound above its upper bound.
    #[error("infeasible: row {row} cannot be satisfied together with the active rows")]
    Infeasible {
        /// The row (index in the solution's row layout) found unsatisfiable
        row: usize,
    },
    /// The iteration budget ran out before every row was satisfied.
    #[error("no solution within {max_iterations} iterations")]
    IterationLimit {
        /// The budget that ran out ([`crate::Settings::max_iterations`])
        max_iterations: usize,
    },
    /// The Cholesky factorisation of H met a pivot that is not positive (or
    /// not finite): H is not symmetric positive definite.
    #[error("H is not positive definite (pivot {pivot} at column {column})")]
    NotPositiveDefinite {
        /// The column of H where the factorisation failed
        column: usize,
        /// The offending pivot `H_jj − Σ L_jk²`
        pivot: f64,
    },
    /// An argument's size does not match the problem's or exceeds the
    /// workspace's capacity.
    #[error("bad size: {what} is {got}, expected {expected}")]
    BadSize {
        /// Which argument
        what: &'static str,
        /// Its size
        got: usize,
        /// The size it should have (or its upper limit)
        expected: usize,
    },
    /// An input number is NaN or infinite where a finite number is needed
    /// (bounds may be infinite, never NaN).
    #[error("non-finite input in {what}")]
    NonFinite {
        /// Which argument
        what: &'static str,
    },
}
