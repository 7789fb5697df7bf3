//! The workspace's root and its built binaries, for any package's
//! integration tests (included with `#[path = ".../tests/support/workspace.rs"]`).

use std::path::{Path, PathBuf};

/// The workspace's root (the folder holding `deploy/phri.toml`).
pub fn repo() -> PathBuf {
    let mut dir = Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf();
    while !dir.join("deploy/phri.toml").is_file() {
        assert!(
            dir.pop(),
            "no deploy/phri.toml above {}",
            env!("CARGO_MANIFEST_DIR")
        );
    }
    dir.canonicalize().expect("the workspace's root")
}

/// A binary of the workspace: in the profile's folder of the target
/// directory, the parent of this test executable's `deps/`.
#[allow(dead_code)]
pub fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("this test's executable");
    let p = exe
        .parent()
        .and_then(Path::parent)
        .expect("a test executable in <target>/<profile>/deps")
        .join(name);
    assert!(
        p.is_file(),
        "{} not built: run `cargo build --release --bins` (cargo test --workspace builds it)",
        p.display()
    );
    p
}
