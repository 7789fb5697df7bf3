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

/// The robot's newest state, through one node and subscriber: its clock
/// (the scenario's time, which the person, the microphone and the contacts
/// follow and a loaded machine's wall clock sees run slower) and who
/// commands it. Opened once, early (a subscriber created mid-run makes the
/// robot's publisher connect it in its 1 kHz loop); dropped before the cell
/// finishes (the last one out of the prefix cleans up).
#[allow(dead_code)] // not every test file waits on the robot
pub struct RobotClock {
    _node: phri_ipc::IpcNode,
    states: phri_ipc::Subscriber<phri_ipc::JointState>,
}

#[allow(dead_code)]
impl RobotClock {
    /// The robot's clock of the cell of `prefix`.
    pub fn watch(prefix: &str) -> RobotClock {
        let node = phri_ipc::node("test-robot-clock", prefix).unwrap();
        let states = phri_ipc::ROBOT_STATE
            .subscriber(&node, phri_ipc::Queue::Latest)
            .unwrap();
        RobotClock {
            _node: node,
            states,
        }
    }

    /// The controller in charge now (`control` or `control_standby`).
    pub fn now(&self) -> &'static str {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(2);
        loop {
            if let Some(s) = self.states.latest().unwrap() {
                return match s.status & phri_ipc::robot_status::STANDBY_IN_CHARGE {
                    0 => "control",
                    _ => "control_standby",
                };
            }
            assert!(std::time::Instant::now() < deadline, "no robot/state");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }

    /// Wait until the robot has run `t_s` seconds of its 1 kHz periods (its
    /// state's sequence number) since it started; at most `t_s` + 30 s of
    /// the wall clock.
    pub fn wait_until(&self, t_s: f64) {
        use std::time::{Duration, Instant};
        let deadline = Instant::now() + Duration::from_secs_f64(t_s + 30.0);
        let mut seq = 0u64;
        loop {
            if let Some(s) = self.states.latest().unwrap() {
                seq = s.seq;
            }
            if seq as f64 * 1e-3 >= t_s {
                return;
            }
            assert!(
                Instant::now() < deadline,
                "the robot's clock at {} s, not {t_s} s",
                seq as f64 * 1e-3
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// Who commands the robot, read from its newest state through one node and
/// subscriber opened before the faults: a node and subscriber created
/// mid-run make the robot's publisher connect them in its 1 kHz loop, and
/// the test should not be what costs a deadline ([`RobotClock::now`]).
#[allow(dead_code)] // not every test file kills a controller
pub type Charge = RobotClock;
