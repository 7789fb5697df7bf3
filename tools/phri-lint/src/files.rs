//! Which Rust files of the workspace the checks read.

use std::path::{Path, PathBuf};

use crate::LintError;

/// Directories skipped wherever they sit: build output, and test code
/// (integration tests, their support modules and fixtures, benchmarks).
const SKIPPED_DIRS: &[&str] = &["target", "tests", "benches"];

/// Directories skipped at the workspace's root only: the vendored crates.
const SKIPPED_ROOT_DIRS: &[&str] = &["patches"];

/// Every `.rs` file under `root` (absolute paths, sorted) but those in
/// `SKIPPED_DIRS`, `SKIPPED_ROOT_DIRS` and hidden directories (`.git`,
/// `.cargo`).
pub fn rust_files(root: &Path) -> Result<Vec<PathBuf>, LintError> {
    let mut files = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|source| LintError::Io {
            path: dir.clone(),
            source,
        })?;
        for entry in entries {
            let entry = entry.map_err(|source| LintError::Io {
                path: dir.clone(),
                source,
            })?;
            let path = entry.path();
            let name = entry.file_name();
            let name = name.to_string_lossy();
            let kind = entry.file_type().map_err(|source| LintError::Io {
                path: path.clone(),
                source,
            })?;
            if kind.is_dir() {
                let skipped = name.starts_with('.')
                    || SKIPPED_DIRS.contains(&name.as_ref())
                    || (dir == root && SKIPPED_ROOT_DIRS.contains(&name.as_ref()));
                if !skipped {
                    dirs.push(path);
                }
            } else if kind.is_file() && name.ends_with(".rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skips_tests_target_patches_and_hidden_directories() {
        let root = std::env::temp_dir().join(format!("phri-lint-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        for dir in [
            "a/src",
            "a/tests",
            "a/benches",
            "a/examples",
            "target",
            "patches/x/src",
            ".git",
            "tools/patches",
        ] {
            std::fs::create_dir_all(root.join(dir)).unwrap();
        }
        for file in [
            "a/src/lib.rs",
            "a/src/notes.txt",
            "a/tests/t.rs",
            "a/benches/b.rs",
            "a/examples/e.rs",
            "a/build.rs",
            "target/gen.rs",
            "patches/x/src/lib.rs",
            ".git/x.rs",
            "tools/patches/p.rs",
        ] {
            std::fs::write(root.join(file), "").unwrap();
        }
        let found: Vec<String> = rust_files(&root)
            .unwrap()
            .iter()
            .map(|f| {
                f.strip_prefix(&root)
                    .unwrap()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        std::fs::remove_dir_all(&root).unwrap();
        assert_eq!(
            found,
            [
                "a/build.rs",
                "a/examples/e.rs",
                "a/src/lib.rs",
                "tools/patches/p.rs"
            ]
        );
    }
}
