//! phri's structural checks, run as tests (`tests/functions.rs`), so
//! `deploy/test` and CI run them with the rest of the workspace.
//!
//! The one check today: no function longer than [`MAX_FUNCTION_LINES`] lines
//! outside test code. [`rust_files`] lists the workspace's Rust sources that
//! count, [`scan_file`] measures every function of one of them,
//! [`long_functions`] gathers the workspace's long ones.
//!
//! What counts as test code, and is not checked: files under a `tests/` or
//! `benches/` directory, modules and items under `#[cfg(test)]` (inline or
//! in their own file), `#[test]` and `#[bench]` functions. Examples
//! (`examples/`) and build scripts count: users run and read them. Vendored
//! crates (`patches/`) and build output (`target/`) are not phri's code.
//! Closures count as part of the function that holds them; a function
//! inside a function is measured on its own as well.

pub mod error;
pub mod files;
pub mod functions;
pub mod workspace;

pub use error::LintError;
pub use files::rust_files;
pub use functions::{scan_file, Function};
pub use workspace::long_functions;

/// The longest a function may be outside test code \[lines\], from the line of
/// its `fn` keyword to the line of its closing brace, both counted.
pub const MAX_FUNCTION_LINES: usize = 120;
