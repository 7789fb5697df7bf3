//! A dense, strictly convex quadratic-program solver for the 1 kHz loop
//! (a control-barrier-function safety filter on joint velocities,
//! REFERENCE §16):
//!
//! ```text
//! minimise ½ xᵀHx + gᵀx   subject to   C x ≤ d,   lo ≤ x ≤ hi (optional)
//! ```
//!
//! The Goldfarb-Idnani dual active-set method (Math. Programming 27, 1983),
//! in Pinocchio's split: a [`Workspace`] sized once for `n_max` variables
//! and `m_max` rows holds every buffer and the [`Settings`]; [`solve()`]
//! fills it and allocates nothing; its iterations are bounded
//! ([`Settings::max_iterations`], default 200). [`Start::Warm`] starts from
//! the last solve's active set (re-verified: rows whose multiplier would be
//! negative are dropped), which in a control loop usually leaves nothing to
//! search.
//!
//! - [`problem`]: the problem's numbers ([`Problem`]), [`Settings`], [`Start`];
//! - [`workspace`]: the preallocated buffers;
//! - [`solve()`](solve::solve): the method, [`Solution`] its result;
//! - [`QpError`]: infeasible, iteration limit, H not positive definite, bad
//!   sizes, non-finite numbers.
//!
//! Checked against the interior-point solver `clarabel` on thousands of
//! random problems (`tests/against_clarabel.rs`); `tests/no_alloc.rs`
//! counts allocations during solves (none).
//!
//! Benchmark (n = 7, 16 and 32 rows, cold and warm over a slowly changing
//! sequence as in a control loop; prints p50/p99/max in µs and iteration
//! counts):
//!
//! ```text
//! cargo run --release -p phri-qp --example qp-bench [-- STEPS]
//! ```

#![deny(missing_docs)]

pub mod error;
mod factor;
mod load;
pub mod problem;
pub mod solution;
pub mod solve;
pub mod workspace;

pub use error::QpError;
pub use problem::{Problem, Settings, Start};
pub use solution::Solution;
pub use solve::solve;
pub use workspace::Workspace;
