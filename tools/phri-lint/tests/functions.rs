//! No function over 120 lines outside test code (phri_lint's rules of what
//! counts), but those on [`ALLOWED`] (none today), each waiting to be split
//! by concern.
//!
//! The check: `cargo test --release -p phri-lint` (and `deploy/test`, which
//! runs every test of the workspace). `cargo run --release -p phri-lint`
//! lists the long functions, longest first.
//!
//! The list only shrinks: the test fails on a long function it does not name
//! and on a name whose function is no longer long (remove it then).

use std::path::Path;

use phri_lint::{long_functions, MAX_FUNCTION_LINES};

/// The functions over the limit today, as (file, name): split each by
/// concern, not into numbered parts, then strike it off. One line each,
/// sorted by file.
#[rustfmt::skip]
const ALLOWED: &[(&str, &str)] = &[
];

#[test]
fn no_function_over_the_limit_outside_tests() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let long = long_functions(&root, MAX_FUNCTION_LINES).expect("the workspace parses");
    let unlisted: Vec<String> = long
        .iter()
        .filter(|f| !ALLOWED.contains(&(f.path.as_str(), f.name.as_str())))
        .map(|f| format!("{}:{}: {} is {} lines", f.path, f.line, f.name, f.lines))
        .collect();
    let shortened: Vec<String> = ALLOWED
        .iter()
        .filter(|(path, name)| !long.iter().any(|f| f.path == *path && f.name == *name))
        .map(|(path, name)| format!("{path}: {name}"))
        .collect();
    assert!(
        unlisted.is_empty() && shortened.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines outside tests (split each by concern):\n  {}\n\
         on ALLOWED in {} but no longer over {MAX_FUNCTION_LINES} lines (strike them off):\n  {}",
        unlisted.join("\n  "),
        file!(),
        shortened.join("\n  "),
    );
}
