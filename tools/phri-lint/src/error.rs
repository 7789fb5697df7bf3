//! Typed errors of the checks: a file that cannot be read or parsed.

use std::path::PathBuf;

/// What stops a check before it can judge the code.
#[derive(Debug, thiserror::Error)]
pub enum LintError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}: not Rust that syn parses: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
}
