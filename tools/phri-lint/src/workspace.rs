//! The functions of the whole workspace longer than a limit.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::functions::{scan_file, FileScan, Function};
use crate::{rust_files, LintError};

/// Every function of the workspace at `root` longer than `limit` lines
/// outside test code, ordered by file and line. A file that is an
/// out-of-line module of test code (`#[cfg(test)] mod tests;`, or any module
/// declared inside one) is test code as a whole.
pub fn long_functions(root: &Path, limit: usize) -> Result<Vec<Function>, LintError> {
    let mut scans = BTreeMap::new();
    for file in rust_files(root)? {
        let scan = scan_file(root, &file)?;
        scans.insert(file, scan);
    }
    let tests = test_files(&scans);
    Ok(scans
        .into_iter()
        .filter(|(file, _)| !tests.contains(file))
        .flat_map(|(_, scan)| scan.functions)
        .filter(|f| f.lines > limit)
        .collect())
}

/// The files that are test modules: declared test by their parent, or
/// declared (test or not) by a test module's file.
fn test_files(scans: &BTreeMap<PathBuf, FileScan>) -> BTreeSet<PathBuf> {
    let mut tests = BTreeSet::new();
    loop {
        let before = tests.len();
        for (file, scan) in scans {
            let parent_test = tests.contains(file);
            for module in &scan.modules {
                if module.test || parent_test {
                    tests.insert(module.path.clone());
                }
            }
        }
        if tests.len() == before {
            return tests;
        }
    }
}
