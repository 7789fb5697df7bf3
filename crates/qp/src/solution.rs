//! A solve's result, borrowed from the workspace.

/// The minimiser and its multipliers; the slices live in the workspace
/// until its next solve.
#[derive(Clone, Copy, Debug)]
pub struct Solution<'w> {
    /// The minimiser x, length n
    pub x: &'w [f64],
    /// The multiplier λ_i ≥ 0 of every row, in the layout of
    /// [`crate::Problem::rows`] (general rows, then upper bounds, then lower
    /// bounds); zero for inactive rows. KKT: `Hx + g + Cᵀλ_C + λ_hi − λ_lo = 0`.
    pub lambda: &'w [f64],
    /// The active rows at the solution (indices in the same layout), in
    /// the order they were factored
    pub active: &'w [usize],
    /// `½ xᵀHx + gᵀx` at the solution
    pub objective: f64,
    /// Main-loop iterations: rows added or dropped while searching
    pub iterations: usize,
    /// Rows of the warm-start hint kept as the starting active set (0 for a
    /// cold start); each cost one O(n²) factor update, no search
    pub warm_rows: usize,
}
