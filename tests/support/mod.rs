//! What the multi-process test files share.

use std::io::Write;
use std::sync::Once;

/// Print every test's panic message straight to the process's standard
/// error as well, where the supervisors' own lines go: the harness keeps a
/// failing test's message for its summary at the end, which a CI log cut
/// to its first part never shows.
pub fn loud_panics() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let thread = std::thread::current();
            let _ = writeln!(
                std::io::stderr().lock(),
                "test {} failed: {info}",
                thread.name().unwrap_or("?")
            );
            previous(info);
        }));
    });
}

/// Where one supervisor run of a test lives: its iceoryx2 prefix (the
/// test process's own), its run directory (emptied) and its report.
#[allow(dead_code)] // not every test file starts a supervisor
pub struct RunPlace {
    pub prefix: String,
    pub run_dir: std::path::PathBuf,
    pub report: std::path::PathBuf,
}

#[allow(dead_code)]
impl RunPlace {
    /// For `test` of this file (`kind`: a letter per test file, so that two
    /// files' runs never share a prefix).
    pub fn new(kind: char, test: &str) -> RunPlace {
        loud_panics();
        let prefix = format!("{kind}{}{test}_", std::process::id());
        let run_dir = std::env::temp_dir().join(format!("phri-test-{prefix}"));
        let _ = std::fs::remove_dir_all(&run_dir);
        let report = run_dir.join("report.json");
        RunPlace {
            prefix,
            run_dir,
            report,
        }
    }

    /// `supervisor` started from `repo` with this run's prefix, run directory and report.
    pub fn command(&self, supervisor: &str, repo: &std::path::Path) -> std::process::Command {
        let mut cmd = std::process::Command::new(supervisor);
        cmd.current_dir(repo)
            .arg("--prefix")
            .arg(&self.prefix)
            .arg("--run-dir")
            .arg(&self.run_dir)
            .arg("--report")
            .arg(&self.report);
        cmd
    }
}
