//! Hardening of the supervisor (issue 10): the cell starts whole or not at
//! all, trusts nothing another user can write, says who commands the robot,
//! stops when its supervisor is gone for good, and blames the service that
//! starves the others. Each reproduction of the issue is a test here, with
//! the fixed behaviour; real processes, really killed. Tests that start a
//! cell are serialised (the 2 cores), each with its own prefix and run
//! directory. Steps that need another user (root: `setpriv` to nobody,
//! `chown`) have a mode-based variant that runs when the tests are not root.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::Value;

mod support;

static SERIAL: Mutex<()> = Mutex::new(());

const NOBODY: u32 = 65534;

fn serial() -> std::sync::MutexGuard<'static, ()> {
    support::loud_panics();
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

fn bin_dir() -> PathBuf {
    Path::new(env!("CARGO_BIN_EXE_phri-supervisor"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn bin(name: &str) -> PathBuf {
    let p = bin_dir().join(name);
    assert!(
        p.is_file(),
        "{} not built (cargo test --workspace builds it; else cargo build --release --bins)",
        p.display()
    );
    p
}

fn is_root() -> bool {
    // SAFETY: geteuid cannot fail
    unsafe { libc::geteuid() == 0 }
}

fn prefix(test: &str) -> String {
    format!("h{}{test}_", std::process::id())
}

/// A fresh, private scratch directory.
fn scratch(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-hardening-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o700)).unwrap();
    d
}

fn chown(path: &Path, uid: u32) {
    let c = std::ffi::CString::new(path.to_string_lossy().as_bytes()).unwrap();
    // SAFETY: chown on a path this test created
    assert_eq!(
        unsafe { libc::chown(c.as_ptr(), uid, uid) },
        0,
        "chown {}",
        path.display()
    );
}

/// `cmd` run as the user nobody (root only).
fn as_nobody(cmd: &[&str]) -> Output {
    Command::new("setpriv")
        .args(["--reuid=65534", "--regid=65534", "--clear-groups"])
        .args(cmd)
        .output()
        .expect("setpriv")
}

/// The supervisor's command for cell `prefix`: the deployed configuration,
/// the run directory if given, and `args`.
fn supervisor(prefix: &str, run_dir: Option<&Path>, args: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_phri-supervisor"));
    cmd.current_dir(repo())
        .arg("--config")
        .arg(repo().join("deploy/phri.toml"))
        .arg("--prefix")
        .arg(prefix);
    if let Some(d) = run_dir {
        cmd.arg("--run-dir").arg(d);
    }
    cmd.args(args).stdin(Stdio::null());
    cmd
}

/// Run a supervisor that is expected to refuse: its exit code and stderr.
fn refused(mut cmd: Command) -> (i32, String) {
    let out = cmd.output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Processes whose command line names `--prefix <prefix>` (the whole word).
fn processes_of(prefix: &str) -> Vec<String> {
    let out = Command::new("pgrep")
        .arg("-af")
        .arg(format!("--prefix {prefix}( |$)"))
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.contains("pgrep"))
        .map(str::to_string)
        .collect()
}

/// Files of `prefix` in iceoryx2's directories and /dev/shm.
fn shm_files_of(prefix: &str) -> Vec<PathBuf> {
    phri_ipc::files_of(prefix)
}

/// No process of the cell and no shared-memory file of its prefix remain.
fn assert_nothing_left(prefix: &str) {
    let procs = processes_of(prefix);
    assert!(procs.is_empty(), "processes left: {procs:?}");
    let files = shm_files_of(prefix);
    assert!(files.is_empty(), "left behind: {files:?}");
}

fn files_in(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

fn mode(path: &Path) -> u32 {
    std::fs::symlink_metadata(path)
        .unwrap()
        .permissions()
        .mode()
        & 0o7777
}

fn wait_until(what: &str, timeout_s: f64, mut cond: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs_f64(timeout_s);
    while !cond() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn wait(s: f64) {
    std::thread::sleep(Duration::from_secs_f64(s));
}

fn alive(pid: i32) -> bool {
    // SAFETY: probing a pid with signal 0
    let exists = unsafe { libc::kill(pid, 0) } == 0;
    exists
        && std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| !s.contains(") Z "))
}

/// A running supervisor, its stderr in a file.
struct Running {
    child: Child,
    prefix: String,
    stderr: PathBuf,
}

impl Running {
    fn start(mut cmd: Command, prefix: &str, scratch: &Path) -> Running {
        for b in [
            "phri-sim",
            "phri-dynamics",
            "phri-control",
            "phri-test-service",
        ] {
            bin(b);
        }
        let stderr = scratch.join(format!("{prefix}stderr.txt"));
        let file = std::fs::File::create(&stderr).unwrap();
        cmd.stdout(Stdio::null()).stderr(file);
        Running {
            child: cmd.spawn().unwrap(),
            prefix: prefix.to_string(),
            stderr,
        }
    }

    fn stderr(&self) -> String {
        std::fs::read_to_string(&self.stderr).unwrap_or_default()
    }

    /// The run directory the supervisor printed.
    fn run_dir(&self) -> PathBuf {
        let mut found = None;
        wait_until("the supervisor's run directory line", 20.0, || {
            found = self.stderr().lines().find_map(|l| {
                l.split_once(", run directory ")
                    .map(|(_, d)| PathBuf::from(d.trim()))
            });
            found.is_some()
        });
        found.unwrap()
    }

    fn state(&self, run_dir: &Path) -> Value {
        let mut v = Value::Null;
        wait_until("state.json", 20.0, || {
            v = std::fs::read_to_string(run_dir.join("state.json"))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok())
                .unwrap_or(Value::Null);
            // every service started (the voice services start last)
            v["services"]
                .as_object()
                .is_some_and(|s| !s.is_empty() && s.values().all(|x| x["pid"].is_i64()))
        });
        v
    }

    /// Wait for the end: exit code and stderr.
    fn finish(mut self) -> (i32, String) {
        let deadline = Instant::now() + Duration::from_secs(90);
        let status = loop {
            if let Some(st) = self.child.try_wait().unwrap() {
                break st;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("the supervisor did not end: {}", self.stderr());
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        (status.code().unwrap_or(-1), self.stderr())
    }

    fn signal(&self, sig: i32) {
        // SAFETY: a signal to our own child
        unsafe { libc::kill(self.child.id() as i32, sig) };
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        // a failed test must not leave its cell running
        if self.child.try_wait().ok().flatten().is_none() {
            self.signal(libc::SIGINT);
            let _ = self.child.wait();
        }
        let _ = &self.prefix;
    }
}

fn report(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn events<'a>(r: &'a Value, kind: &str, service: &str) -> Vec<&'a Value> {
    r["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == kind && (service.is_empty() || e["service"] == service))
        .collect()
}

fn fault(args: &[&str]) -> (i32, String) {
    let out = Command::new(bin("phri-fault")).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Repro 1: a run directory another user prepared (or could write) is
/// refused before anything starts; nothing is written into it.
#[test]
fn a_run_dir_another_user_prepared_or_can_write_is_refused() {
    let p = prefix("rd");
    let d = scratch("rd");
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let expect_refusal = |run_dir: &Path, needle: &str| {
        let (code, err) = refused(supervisor(
            &p,
            Some(run_dir),
            &["--scenario", "free-motion", "--duration", "20"],
        ));
        assert_eq!(code, 2, "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(
            err.contains(&*run_dir.to_string_lossy()) && err.contains(needle),
            "{err}"
        );
        assert_nothing_left(&p);
        assert!(files_in(run_dir).is_empty(), "{:?}", files_in(run_dir));
    };
    if is_root() {
        // as in the issue: nobody prepares the run directory
        let rd = d.join("rd");
        let rd_s = rd.to_string_lossy().into_owned();
        let out = as_nobody(&["mkdir", "-m", "0777", &rd_s]);
        assert!(out.status.success(), "{out:?}");
        expect_refusal(&rd, "owned by uid 65534");
        // nobody's directory with a safe mode: still not ours
        std::fs::set_permissions(&rd, std::fs::Permissions::from_mode(0o700)).unwrap();
        expect_refusal(&rd, "owned by uid 65534");
    }
    // ours, but writable by others
    let open = d.join("open");
    std::fs::create_dir(&open).unwrap();
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o777)).unwrap();
    expect_refusal(&open, "writable by other users");
    // a link to a private directory: it could point anywhere
    let private = d.join("private");
    std::fs::create_dir(&private).unwrap();
    std::fs::set_permissions(&private, std::fs::Permissions::from_mode(0o700)).unwrap();
    let link = d.join("link");
    std::os::unix::fs::symlink(&private, &link).unwrap();
    expect_refusal(&link, "symbolic link");
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 1: the default run directory is private to the user, every state
/// file is owner-only, another user cannot rewrite the configuration the
/// services read, and state files someone could have replaced are never
/// trusted: `phri-fault` signals only the cell's own services, a second
/// supervisor refuses a state file others can write.
#[test]
fn run_state_is_private_and_tampered_state_is_never_trusted() {
    let _g = serial();
    let p = prefix("priv");
    let d = scratch("priv");
    let cell = Running::start(
        supervisor(&p, None, &["--scenario", "free-motion", "--duration", "25"]),
        &p,
        &d,
    );
    let rd = cell.run_dir();
    // the default: <runtime dir>/phri/run-<prefix> or <tmp>/phri-<uid>/run-<prefix>
    assert!(rd.ends_with(format!("run-{p}")), "{}", rd.display());
    assert_eq!(mode(&rd), 0o700, "{}", rd.display());
    assert_eq!(mode(rd.parent().unwrap()) & 0o022, 0);
    let st = cell.state(&rd);
    for f in ["config.toml", "state.json", "supervisor.state"] {
        assert_eq!(mode(&rd.join(f)), 0o600, "{f}");
    }
    let config = rd.join("config.toml");
    let before = std::fs::read(&config).unwrap();
    if is_root() {
        // the issue's attack: another user rewrites the configuration
        let script = format!("echo '[control]\navoidance = false' > {}", config.display());
        let out = as_nobody(&["sh", "-c", &script]);
        assert!(!out.status.success(), "nobody wrote {}", config.display());
        let out = as_nobody(&["cat", &rd.join("state.json").to_string_lossy()]);
        assert!(!out.status.success(), "nobody read state.json");
    }
    assert_eq!(std::fs::read(&config).unwrap(), before);

    // phri-fault finds the run directory from the prefix and kills the
    // controller (after the start-up, when an exit fails the start)
    wait(3.0);
    let control = st["services"]["control"]["pid"].as_i64().unwrap() as i32;
    let (code, err) = fault(&["--prefix", &p, "control", "kill"]);
    assert_eq!(code, 0, "{err}");
    wait_until("the controller's restart", 10.0, || {
        let v = cell.state(&rd);
        v["services"]["control"]["restarts"] == 1 && v["services"]["control"]["pid"].is_i64()
    });
    assert!(!alive(control));

    // a state.json naming pids that are not the cell's services
    let sup = cell.child.id();
    let mut bystander = Command::new("sleep").arg("60").spawn().unwrap();
    let json = |sup_pid: u32, pid: u32| {
        format!(
            r#"{{"prefix":"{p}","services":{{"control":{{"pid":{pid},"restarts":0}}}},"supervisor_pid":{sup_pid}}}"#
        )
    };
    let state_path = rd.join("state.json");
    let original = std::fs::read(&state_path).unwrap();
    let replace = |text: &str, mode: u32| {
        let tmp = rd.join("forged.tmp");
        std::fs::write(&tmp, text).unwrap();
        std::fs::set_permissions(&tmp, std::fs::Permissions::from_mode(mode)).unwrap();
        std::fs::rename(&tmp, &state_path).unwrap();
    };
    for (text, mode, needle) in [
        (json(sup, 1), 0o600, "not service control"),
        (json(sup, bystander.id()), 0o600, "not service control"),
        (json(0, bystander.id()), 0o600, "stale state.json"),
        (json(sup, bystander.id()), 0o666, "writable by other users"),
    ] {
        replace(&text, mode);
        let (code, err) = fault(&["--run-dir", &rd.to_string_lossy(), "control", "kill"]);
        assert_eq!(code, 2, "{text}: {err}");
        assert!(err.contains(needle), "{text}: {err}");
        assert!(
            bystander.try_wait().unwrap().is_none(),
            "the bystander was signalled"
        );
    }
    bystander.kill().unwrap();
    bystander.wait().unwrap();
    replace(&String::from_utf8_lossy(&original), 0o600);

    // a supervisor.state others could have written: a second supervisor refuses it, naming it
    let sup_state = rd.join("supervisor.state");
    std::fs::set_permissions(&sup_state, std::fs::Permissions::from_mode(0o666)).unwrap();
    let (code, err) = refused(supervisor(&p, None, &["--duration", "5"]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("supervisor.state") && err.contains("writable by other users"),
        "{err}"
    );
    std::fs::set_permissions(&sup_state, std::fs::Permissions::from_mode(0o600)).unwrap();

    cell.signal(libc::SIGINT);
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    // the one kill that was the cell's own: its restart is said, nothing else
    // of the refused attempts
    let last = err
        .lines()
        .rev()
        .find(|l| l.contains(" done after "))
        .unwrap_or("");
    assert!(
        last.contains("degraded (") && last.contains("restarts: control 1"),
        "{last}"
    );
    assert_nothing_left(&p);
    assert!(!rd.join("state.json").exists() && !rd.join("supervisor.state").exists());
    let _ = std::fs::remove_dir_all(&rd);
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 2: a service binary that exists but cannot be executed is refused
/// before anything starts (no half cell, no state).
#[test]
fn a_binary_that_cannot_be_executed_starts_nothing() {
    let p = prefix("noexec");
    let d = scratch("noexec");
    let name = format!("phri-hardening-noexec-{}", std::process::id());
    let path = bin_dir().join(&name);
    std::fs::write(&path, "#!/bin/sh\nexit 0\n").unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).unwrap();
    let rd = d.join("rd");
    let set = format!("services.control.binary=\"{name}\"");
    let (code, err) = refused(supervisor(
        &p,
        Some(&rd),
        &[
            "--scenario",
            "free-motion",
            "--duration",
            "20",
            "--set",
            &set,
        ],
    ));
    let _ = std::fs::remove_file(&path);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("[services.control]") && err.contains("not executable"),
        "{err}"
    );
    assert_nothing_left(&p);
    assert!(!rd.exists(), "{:?}", files_in(&rd));
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 2: a service that dies during start-up fails the start: everything
/// already started is stopped, shared memory and state files removed, exit 2.
#[test]
fn a_service_that_dies_during_start_up_stops_everything_started() {
    let _g = serial();
    let p = prefix("dies");
    let d = scratch("dies");
    let rd = d.join("rd");
    let report = d.join("report.json");
    let (code, err) = refused(supervisor(
        &p,
        Some(&rd),
        &[
            "--scenario",
            "free-motion",
            "--duration",
            "20",
            "--report",
            &report.to_string_lossy(),
            "--set",
            "services.dier.binary=\"phri-test-service\"",
            "--set",
            "services.dier.order=3",
            "--set",
            "services.dier.args=[\"--exit-after\", \"0.3\"]",
        ],
    ));
    assert_eq!(code, 2, "{err}");
    let last = err.trim().lines().last().unwrap_or("");
    assert!(
        last.contains("start-up failed") && last.contains("dier") && last.contains("stopped"),
        "{err}"
    );
    // the services started before and after it ran, and are gone now
    assert!(err.contains("started sim"), "{err}");
    assert_nothing_left(&p);
    assert!(!rd.join("state.json").exists() && !rd.join("supervisor.state").exists());
    assert!(!report.exists(), "a failed start writes no report");
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 3 (and the refusal naming the running supervisor): a second
/// supervisor for a running cell writes nothing (the running cell's
/// configuration stays as it is, and its controller restarts with it), and
/// its one line names the running supervisor and its run directory.
#[test]
fn a_refused_second_supervisor_writes_nothing_and_names_the_running_one() {
    let _g = serial();
    let p = prefix("second");
    let d = scratch("second");
    let rd = d.join("rd");
    let report_path = d.join("report.json");
    let cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                "12",
                "--report",
                &report_path.to_string_lossy(),
            ],
        ),
        &p,
        &d,
    );
    cell.state(&rd);
    let snapshot = || {
        ["config.toml", "supervisor.state", "state.json"]
            .map(|f| std::fs::read(rd.join(f)).unwrap())
    };
    let mtime = || {
        std::fs::metadata(rd.join("config.toml"))
            .unwrap()
            .modified()
            .unwrap()
    };
    // the cell's files settle once every service has started (the binary
    // state gains the last pids a little after state.json)
    let settle = std::time::Instant::now() + std::time::Duration::from_secs(10);
    let mut before = snapshot();
    loop {
        std::thread::sleep(std::time::Duration::from_millis(300));
        let again = snapshot();
        if again == before || std::time::Instant::now() > settle {
            break;
        }
        before = again;
    }
    let before_mtime = mtime();
    let sup = cell.child.id();
    // the issue's refused supervisor: a configuration error, named
    let (code, err) = refused(supervisor(&p, Some(&rd), &["--set", "control.kp=abc"]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("control.kp") && err.trim().lines().count() == 1,
        "{err}"
    );
    // a valid one: refused because the cell runs, naming its supervisor and run directory
    let (code, err) = refused(supervisor(&p, Some(&rd), &["--duration", "5"]));
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!("pid {sup}"))
            && err.contains(&*rd.to_string_lossy())
            && !err.contains("supervisor/health"),
        "{err}"
    );
    // the same prefix with another run directory: found by its health channel
    let other = d.join("other");
    let (code, err) = refused(supervisor(&p, Some(&other), &["--duration", "5"]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("pid {sup}")) && err.contains(&*rd.to_string_lossy()),
        "{err}"
    );
    assert!(!other.exists(), "{:?}", files_in(&other));
    let after = snapshot();
    let text = |s: &[Vec<u8>; 3]| {
        s.iter()
            .map(|b| String::from_utf8_lossy(b).into_owned())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        after,
        before,
        "the running cell's files changed: before {:?}, after {:?}; supervisor: {}",
        text(&before),
        text(&after),
        cell.stderr()
    );
    assert_eq!(mtime(), before_mtime);
    // the running cell restarts its controller with its own configuration
    // (once started: an exit during the start-up fails the start)
    wait(2.5);
    let (code, err) = fault(&["--run-dir", &rd.to_string_lossy(), "control", "kill"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    let r = report(&report_path);
    // a restart is something the user must know about: not clean, and said
    assert_eq!(r["clean"], false, "{}", r["degraded"]);
    assert!(
        r["degraded"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l.as_str().unwrap_or("") == "restarts: control 1"),
        "{}",
        r["degraded"]
    );
    assert!(
        err.contains("degraded (") && err.contains("restarts: control 1"),
        "{err}"
    );
    assert_eq!(r["services"]["control"]["restarts"], 1);
    assert_eq!(r["services"]["control"]["alive_at_end"], true);
    assert!(
        !events(&r, "resume", "control").is_empty() || !events(&r, "sync", "control").is_empty()
    );
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 4: every configuration error (a type, an enum value, an unknown key
/// or section, keyframes out of order, a scenario length, a URDF, a service
/// refusing its configuration, a run length, an unwritable report) is
/// refused before anything starts, with one line naming it, exit 2.
#[test]
fn configuration_errors_are_refused_before_anything_starts() {
    let d = scratch("config");
    let scenario = d.join("backwards.toml");
    std::fs::write(
        &scenario,
        "name = \"backwards\"\nduration_s = 10.0\n[human]\nfloor_z = -0.8\n\
         [[human.keyframe]]\nt = 5.0\nbase = [1.2, 0.0, 3.14]\n\
         [[human.keyframe]]\nt = 2.0\nbase = [1.0, 0.0, 3.14]\n",
    )
    .unwrap();
    let negative = d.join("negative.toml");
    std::fs::write(&negative, "name = \"negative\"\nduration_s = -5.0\n").unwrap();
    let urdf = d.join("broken.urdf");
    std::fs::write(&urdf, "<robot name=\"x\"><link name=\"a\"></robot>").unwrap();
    let urdf_set = format!("robot.urdf=\"{}\"", urdf.display());
    let report = "/nonexistent-phri-dir/report.json".to_string();
    let (scenario, negative) = (
        scenario.to_string_lossy().into_owned(),
        negative.to_string_lossy().into_owned(),
    );
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (vec!["--set", "control.kp=abc"], vec!["control.kp"]),
        (
            vec!["--set", "control.reaction=explode"],
            vec!["control.reaction"],
        ),
        (vec!["--set", "control.nosuch=1"], vec!["nosuch"]),
        (vec!["--set", "nonsense.x=1"], vec!["nonsense"]),
        (vec!["--scenario", &scenario], vec!["backwards.toml"]),
        (vec!["--scenario", &negative], vec!["duration_s"]),
        (vec!["--set", &urdf_set], vec!["broken.urdf"]),
        (
            vec!["--set", "services.control.args=[\"--bogus\"]"],
            vec!["[services.control]", "--bogus"],
        ),
        (vec!["--duration", "inf"], vec!["--duration"]),
        (vec!["--duration", "-5"], vec!["--duration"]),
        (
            vec!["--report", &report],
            vec!["--report", "/nonexistent-phri-dir"],
        ),
    ];
    for (i, (args, needles)) in cases.iter().enumerate() {
        let p = prefix(&format!("cfg{i}"));
        let rd = d.join(format!("rd{i}"));
        let (code, err) = refused(supervisor(&p, Some(&rd), args));
        assert_eq!(code, 2, "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {err}");
        }
        assert_nothing_left(&p);
        // nothing written: no configuration, no state
        assert!(files_in(&rd).is_empty(), "{args:?}: {:?}", files_in(&rd));
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 4: a service that keeps crashing ends the run (not the duration):
/// ordered shutdown, exit non-zero, a report with `clean: false` saying why,
/// and a summary line that says the run was not clean.
#[test]
fn a_service_that_keeps_crashing_ends_the_run_degraded() {
    let _g = serial();
    let p = prefix("loop");
    let d = scratch("loop");
    let rd = d.join("rd");
    let report_path = d.join("report.json");
    let started = Instant::now();
    let cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                "30",
                "--report",
                &report_path.to_string_lossy(),
                "--set",
                "services.dier.binary=\"phri-test-service\"",
                "--set",
                "services.dier.order=3",
                "--set",
                "services.dier.args=[\"--exit-after\", \"1.0\"]",
                "--set",
                "supervisor.startup_s=0.5",
                "--set",
                "supervisor.crash_loop_restarts=2",
                "--set",
                "supervisor.crash_loop_window_s=30",
            ],
        ),
        &p,
        &d,
    );
    let (code, err) = cell.finish();
    assert!(
        started.elapsed() < Duration::from_secs(20),
        "the run went on for {:?}",
        started.elapsed()
    );
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("degraded (") && err.contains("dier"), "{err}");
    let r = report(&report_path);
    assert_eq!(r["clean"], false);
    let why = r["degraded"][0].as_str().unwrap_or("");
    assert!(why.contains("dier") && why.contains("3 times"), "{why}");
    assert_eq!(r["services"]["dier"]["restarts"], 3);
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// The name of the node-counter segment iceoryx2 gives `prefix`, found by
/// creating (and removing) one node.
fn node_counter_name(prefix: &str) -> String {
    let node = phri_ipc::node("probe", prefix).unwrap();
    let name = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .find(|n| n.starts_with(prefix) && n.ends_with(".global_mgmt"))
        .expect("no global_mgmt segment");
    drop(node);
    phri_ipc::remove_leftovers(prefix).unwrap();
    assert!(shm_files_of(prefix).is_empty());
    name
}

/// Repro 6: a node counter of the cell's prefix that another user created,
/// or that was altered, is refused at start with a line naming it; the
/// cell's own is owner-only while it runs.
#[test]
fn a_foreign_or_altered_node_counter_is_refused_and_the_cells_own_is_private() {
    let _g = serial();
    let p = prefix("shm");
    let d = scratch("shm");
    let name = node_counter_name(&p);
    let seg = Path::new("/dev/shm").join(&name);
    let forge = |version: u64| {
        let mut b = version.to_ne_bytes().to_vec();
        b.extend([0u8; 8]);
        std::fs::write(&seg, b).unwrap();
        std::fs::set_permissions(&seg, std::fs::Permissions::from_mode(0o666)).unwrap();
    };
    let mut cases = vec![(0xdead_beef_u64, "altered")];
    if is_root() {
        cases.push((10 << 16, "owned by uid 65534"));
    }
    for (version, needle) in cases {
        forge(version);
        if needle.contains("65534") {
            chown(&seg, NOBODY);
        }
        let rd = d.join("rd");
        let (code, err) = refused(supervisor(
            &p,
            Some(&rd),
            &["--scenario", "free-motion", "--duration", "5"],
        ));
        assert_eq!(code, 2, "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(&name) && err.contains(needle), "{err}");
        assert!(processes_of(&p).is_empty());
        assert_eq!(
            shm_files_of(&p),
            std::slice::from_ref(&seg),
            "only the forged segment"
        );
        std::fs::remove_file(&seg).unwrap();
    }
    // the cell's own counter: nobody else may write it
    let rd = d.join("rd");
    let cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &["--scenario", "free-motion", "--duration", "6"],
        ),
        &p,
        &d,
    );
    cell.state(&rd);
    assert_eq!(mode(&seg), 0o600);
    if is_root() {
        let script = format!("printf xxxxxxxx > {}", seg.display());
        let out = as_nobody(&["sh", "-c", &script]);
        assert!(!out.status.success(), "nobody wrote {}", seg.display());
    }
    // a restart (after the start-up) opens a node through the restricted counter
    wait(2.5);
    let (code, err) = fault(&["--run-dir", &rd.to_string_lossy(), "dynamics", "kill"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("restarted dynamics") && err.contains("restarts: dynamics 1"),
        "{err}"
    );
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 8: a process that takes `robot/command` while the controller
/// restarts is found within 100 ms: the cell stops (the robot first), the
/// line names the intruder's pid, the report says the run was not clean.
#[test]
fn an_intruder_on_the_command_channel_stops_the_cell() {
    let _g = serial();
    let p = prefix("intr");
    let d = scratch("intr");
    let rd = d.join("rd");
    let report_path = d.join("report.json");
    let cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                "25",
                "--report",
                &report_path.to_string_lossy(),
                // a long restart gap, for the intruder to step in
                "--set",
                "supervisor.restart_backoff_min_ms=3000",
                "--set",
                "supervisor.restart_backoff_max_ms=3000",
            ],
        ),
        &p,
        &d,
    );
    let st = cell.state(&rd);
    wait(3.0);
    let control = st["services"]["control"]["pid"].as_i64().unwrap() as i32;
    // SAFETY: kill(2) on the cell's controller, read from its state.json
    assert_eq!(unsafe { libc::kill(control, libc::SIGKILL) }, 0);
    wait_until("the controller's exit", 5.0, || !alive(control));
    wait(0.1);
    // an unsupervised controller of the same user grabs the command channel
    let mut intruder = Command::new(bin("phri-control"))
        .arg("--config")
        .arg(rd.join("config.toml"))
        .arg("--prefix")
        .arg(&p)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let ipid = intruder.id();
    let (code, err) = cell.finish();
    let _ = intruder.kill();
    let _ = intruder.wait();
    let _ = phri_ipc::remove_leftovers(&p);
    assert_ne!(code, 0, "{err}");
    let line = err
        .lines()
        .find(|l| l.contains("publishes on robot/command"))
        .unwrap_or_else(|| panic!("no intruder line: {err}"));
    assert!(line.contains(&format!("pid {ipid}")), "{line}");
    let r = report(&report_path);
    assert_eq!(r["clean"], false);
    assert!(
        r["degraded"][0]
            .as_str()
            .unwrap_or("")
            .contains(&format!("pid {ipid}")),
        "{}",
        r["degraded"]
    );
    // one intrusion on the command channel; the intruder's other channels
    // (a controller's call for the standby residual) may be named beside
    let intr = events(&r, "intruder", "supervisor");
    let detail = |e: &Value| e["detail"].as_str().unwrap_or("").to_string();
    let on_commands = intr
        .iter()
        .filter(|e| detail(e).contains("on robot/command instead"))
        .count();
    assert_eq!(on_commands, 1, "{}", r["events"]);
    assert!(
        intr.iter()
            .all(|e| detail(e).contains(&format!("pid {ipid}"))),
        "{}",
        r["events"]
    );
    // found long before the controller's restart was due (3 s after its death)
    assert_eq!(r["services"]["control"]["restarts"], 1);
    assert!(
        events(&r, "restart", "control").is_empty(),
        "{}",
        r["events"]
    );
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// Repro 9: a cell whose supervisor died and was never replaced stops by
/// itself: every service exits within `deadman_s` + 2 s, the robot braked.
#[test]
fn a_cell_whose_supervisor_died_stops_by_its_dead_man() {
    let _g = serial();
    let p = prefix("dead");
    let d = scratch("dead");
    let rd = d.join("rd");
    let mut cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--set",
                "supervisor.deadman_s=2",
            ],
        ),
        &p,
        &d,
    );
    let st = cell.state(&rd);
    wait(2.0);
    let pids: Vec<(String, i32)> = st["services"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(n, s)| (n.clone(), s["pid"].as_i64().unwrap() as i32))
        .collect();
    assert!(pids.len() >= 3);
    cell.signal(libc::SIGKILL);
    let _ = cell.child.wait();
    let killed = Instant::now();
    wait_until("every service's exit", 4.0, || {
        pids.iter().all(|(_, pid)| !alive(*pid))
    });
    let took = killed.elapsed();
    assert!(
        took >= Duration::from_millis(1500),
        "stopped after {took:?}: too soon"
    );
    let err = cell.stderr();
    for (name, _) in &pids {
        assert!(
            err.contains(&format!(
                "{name}: no supervisor has published supervisor/health"
            )),
            "{name}: {err}"
        );
    }
    // the controller stopped: the robot braked (or the simulator ended first, braking as it exits)
    assert!(
        err.contains("brakes engaged") || err.contains("sim: no supervisor"),
        "{err}"
    );
    assert!(processes_of(&p).is_empty());
    // what a supervisor killed with SIGKILL leaves: its counter, its state
    let _ = phri_ipc::remove_leftovers(&p);
    assert!(shm_files_of(&p).is_empty());
    let _ = std::fs::remove_dir_all(&d);
}

/// A `free-motion` cell of `duration` seconds (its own prefix and scratch
/// from `name`) with `phri-test-service` added as `spinner`, pinned to
/// `cpu` at real-time `priority`, spinning from 3 s to `until_s` of the
/// cell's clock in whichever process runs then. Its exit code, stderr and
/// report, the prefix and the scratch directory.
fn run_with_a_spinner(
    name: &str,
    duration: &str,
    cpu: usize,
    priority: i32,
    until_s: &str,
) -> (i32, String, Value, String, PathBuf) {
    let p = prefix(name);
    let d = scratch(name);
    let rd = d.join("rd");
    let report_path = d.join("report.json");
    let cpus = format!("services.spinner.cpus=[{cpu}]");
    let prio = format!("services.spinner.rt_priority={priority}");
    let args = format!(
        "services.spinner.args=[\"--spin-from\", \"3.0\", \"--spin-until\", \"{until_s}\"]"
    );
    let cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                duration,
                "--report",
                &report_path.to_string_lossy(),
                "--set",
                "services.spinner.binary=\"phri-test-service\"",
                "--set",
                "services.spinner.order=8",
                "--set",
                &cpus,
                "--set",
                &prio,
                "--set",
                &args,
                // the supervisor's own liveness deadline for the camera
                // (deploy/phri.toml gives a camera 1.5 s on loaded machines):
                // a 0.4 s starvation is then a frozen camera, whose culprit
                // the watchdog must find
                "--set",
                "services.camera.heartbeat_timeout_ms=200",
            ],
        ),
        &p,
        &d,
    );
    let (code, err) = cell.finish();
    let r = report(&report_path);
    (code, err, r, p, d)
}

/// Repro 7 (the watchdog): a service spinning at real-time priority on the
/// perception CPU starves the camera, which falls silent; the supervisor
/// kills the spinner (the culprit), not the camera, and the report says so.
#[test]
fn the_watchdog_kills_the_service_that_starves_the_others() {
    let _g = serial();
    // on the perception CPU, above the camera, for 0.4 s
    let (code, err, r, p, d) = run_with_a_spinner("spin", "8", 0, 30, "3.4");
    assert_eq!(code, 0, "{err}");
    let blamed = events(&r, "blame", "spinner");
    assert!(!blamed.is_empty(), "no blame: {}\n{err}", r["events"]);
    assert!(
        events(&r, "frozen", "camera").iter().all(|e| e["detail"]
            .as_str()
            .unwrap_or("")
            .contains("starved by spinner")),
        "{}\n{err}",
        r["events"]
    );
    assert_eq!(r["services"]["camera"]["restarts"], 0, "{}", r["events"]);
    assert!(r["services"]["spinner"]["restarts"].as_u64().unwrap() >= 1);
    assert_eq!(r["services"]["camera"]["alive_at_end"], true);
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// A robot loop that slips is reported: a process spinning above the
/// torque loop on its CPU for 0.3 s keeps the simulated robot from waking;
/// its schedule slips, and the run is degraded, the summary naming the
/// overruns and the report the cycles the loop did not run.
#[test]
fn a_robot_loop_starved_of_its_cpu_makes_the_run_degraded_with_its_counts() {
    let _g = serial();
    // on the torque loop's CPU, above every one of its services, for 0.3 s
    let (code, err, r, p, d) = run_with_a_spinner("slip", "6", 1, 90, "3.3");
    assert_eq!(code, 0, "{err}");
    let tl = &r["torque_loop"];
    assert!(tl["overruns"].as_u64().unwrap_or(0) >= 1, "{tl}");
    assert!(tl["cycles_short"].as_u64().unwrap_or(0) >= 150, "{tl}");
    assert!(tl["startup_braked_cycles"].as_u64().is_some(), "{tl}");
    assert_eq!(r["clean"], false);
    let summary = r["summary"].as_str().unwrap_or("");
    assert!(summary.contains("robot loop behind: "), "{summary}");
    assert!(
        r["degraded"].as_array().unwrap().iter().any(|l| l
            .as_str()
            .unwrap_or("")
            .contains("cycles short of the run's")),
        "{}",
        r["degraded"]
    );
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// `cmd` without the right to real-time scheduling: as root, CAP_SYS_NICE
/// dropped from the inheritable and bounding sets (a container without
/// `--cap-add SYS_NICE`); otherwise an rtprio limit of 0.
fn without_realtime(cmd: &Command) -> Command {
    let mut c = if is_root() {
        let mut c = Command::new("setpriv");
        c.args(["--inh-caps=-sys_nice", "--bounding-set=-sys_nice", "--"]);
        c
    } else {
        let mut c = Command::new("prlimit");
        c.args(["--rtprio=0:0", "--"]);
        c
    };
    c.arg(cmd.get_program()).args(cmd.get_args());
    if let Some(d) = cmd.get_current_dir() {
        c.current_dir(d);
    }
    c.stdin(Stdio::null());
    c
}

/// A run refused real-time scheduling completes, but says so: one line at
/// the start, the report's `realtime` and `degraded` naming every service
/// of the torque loop and perception, the summary line "degraded (no
/// real-time scheduling)". With `--require-rt` the cell refuses to start
/// in one line, starting nothing.
#[test]
fn a_run_without_real_time_scheduling_is_a_degraded_run() {
    let _g = serial();
    let p = prefix("nort");
    let d = scratch("nort");
    let report_path = d.join("report.json");
    let rp = report_path.to_string_lossy().into_owned();
    let cmd = supervisor(
        &p,
        Some(&d.join("rd")),
        &[
            "--scenario",
            "free-motion",
            "--duration",
            "4",
            "--report",
            &rp,
        ],
    );
    let cell = Running::start(without_realtime(&cmd), &p, &d);
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    let refusals: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("real-time scheduling refused"))
        .collect();
    assert_eq!(refusals.len(), 1, "{err}");
    // the services do not each repeat it
    assert!(!err.contains("running under SCHED_OTHER"), "{err}");
    let last = err
        .lines()
        .rev()
        .find(|l| l.contains(" done after "))
        .unwrap_or("");
    assert!(last.contains("degraded (no real-time scheduling"), "{last}");
    let r = report(&report_path);
    assert_eq!(r["clean"], false);
    assert_eq!(r["realtime"]["permitted"], false, "{}", r["realtime"]);
    assert!(
        r["summary"]
            .as_str()
            .unwrap_or("")
            .starts_with("degraded (no real-time scheduling"),
        "{}",
        r["summary"]
    );
    let degraded: Vec<&str> = r["degraded"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .collect();
    // the two controllers swap priorities with their role: both judged against the lower
    for (service, priority) in [
        ("sim", 78),
        ("dynamics", 80),
        ("control", 77),
        ("control_standby", 77),
    ] {
        let want = format!("real-time: {service} SCHED_OTHER instead of SCHED_FIFO {priority}");
        assert!(
            degraded.iter().any(|l| l.starts_with(&want)),
            "{want}: {degraded:?}"
        );
        assert_eq!(r["realtime"]["services"][service]["priority"], Value::Null);
    }
    assert!(
        degraded
            .iter()
            .any(|l| l.starts_with("real-time: repulsion0 SCHED_OTHER")),
        "{degraded:?}"
    );
    assert_nothing_left(&p);

    // --require-rt: refused at once, one line, nothing started or left
    let rt_report = d.join("refused.json");
    let mut cmd = supervisor(
        &p,
        Some(&d.join("rd2")),
        &[
            "--scenario",
            "free-motion",
            "--duration",
            "4",
            "--require-rt",
            "--report",
            &rt_report.to_string_lossy(),
        ],
    );
    let (code, err) = refused(without_realtime(&cmd));
    assert_eq!(code, 2, "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].contains("--require-rt") && lines[0].contains("SCHED_FIFO"),
        "{err}"
    );
    assert!(!rt_report.exists(), "a refused start wrote a report");
    assert_nothing_left(&p);
    // the same with the configuration key
    cmd = supervisor(
        &p,
        Some(&d.join("rd3")),
        &["--duration", "4", "--set", "supervisor.require_rt=true"],
    );
    let (code, err) = refused(without_realtime(&cmd));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--require-rt"), "{err}");
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// With real-time scheduling permitted (root here, as in CI), every
/// service of the torque loop gets the priority and the CPU it asked for
/// and the report says so.
#[test]
fn a_run_with_real_time_scheduling_reports_what_each_service_got() {
    let _g = serial();
    if realtime_refused_here() {
        // the refused case is the test above; this one needs the right
        panic!("this machine refuses SCHED_FIFO to the tests: run them as root or with an rtprio limit");
    }
    let p = prefix("rt");
    let d = scratch("rt");
    let report_path = d.join("report.json");
    let cell = Running::start(
        supervisor(
            &p,
            Some(&d.join("rd")),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                "4",
                "--require-rt",
                "--report",
                &report_path.to_string_lossy(),
            ],
        ),
        &p,
        &d,
    );
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    let r = report(&report_path);
    assert_eq!(r["realtime"]["permitted"], true);
    let online = std::thread::available_parallelism().map_or(1, |n| n.get());
    // the two controllers swap priorities with their role (79 in charge,
    // 77 not): both are judged against the lower and hold one of the two
    for (service, wanted, got) in [
        ("sim", 78, &[78][..]),
        ("dynamics", 80, &[80][..]),
        ("control", 77, &[77, 79][..]),
        ("control_standby", 77, &[77, 79][..]),
    ] {
        let s = &r["realtime"]["services"][service];
        assert_eq!(s["wanted_priority"], wanted, "{service}: {s}");
        assert!(
            s["priority"].as_i64().is_some_and(|p| got.contains(&p)),
            "{service}: {s}"
        );
        assert_eq!(s["memory_locked"], true, "{service}: {s}");
        if online > 1 {
            assert_eq!(s["cpus"], serde_json::json!([1]), "{service}: {s}");
        }
        assert_eq!(s["shortfalls"], serde_json::json!([]), "{service}: {s}");
    }
    assert!(
        !r["degraded"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l.as_str().unwrap_or("").starts_with("real-time")),
        "{}",
        r["degraded"]
    );
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// This process may not take SCHED_FIFO (as its children could not).
fn realtime_refused_here() -> bool {
    std::thread::spawn(|| {
        let param = libc::sched_param { sched_priority: 1 };
        // SAFETY: plain syscalls on this scratch thread
        let rc = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
        let normal = libc::sched_param { sched_priority: 0 };
        // SAFETY: as above
        unsafe { libc::sched_setscheduler(0, libc::SCHED_OTHER, &normal) };
        rc != 0
    })
    .join()
    .unwrap_or(true)
}

/// Issue: one forged message must not switch off avoidance. During
/// `coexistence`, a process the supervisor did not start publishes one
/// "nothing near" result per worker with a capture time 2^63 ns (which the
/// controller once latched as its newest, making every genuine result look
/// old), and a result of worker 0 for worker 1's point. The controller
/// refuses them all (they are not from a worker it knows), the supervisor
/// names the intruder, the run is not clean, and the person is avoided.
#[test]
fn forged_repulsion_results_are_refused_and_reported() {
    let _g = serial();
    let p = prefix("forge");
    let d = scratch("forge");
    let report_path = d.join("report.json");
    let cell = Running::start(
        supervisor(
            &p,
            Some(&d.join("rd")),
            &[
                "--scenario",
                "coexistence",
                // the person's script from 5 s: the hand in the path from
                // the run's 6 s to its end
                "--set",
                "sim.human_offset_s=5",
                "--duration",
                "13",
                "--report",
                &report_path.to_string_lossy(),
            ],
        ),
        &p,
        &d,
    );
    cell.state(&d.join("rd"));
    wait(4.5);
    let node = phri_ipc::node("forger", &p).unwrap();
    let publisher = phri_ipc::PERCEPTION_REPULSION.publisher(&node).unwrap();
    for worker in 0..4u32 {
        let mut m = <phri_ipc::RepulsionResult as phri_ipc::Zeroed>::zeroed();
        m.seq = 1;
        m.worker = worker;
        m.workers = 4;
        m.capture_ns = 1 << 63;
        m.n_points = 4;
        for (k, slot) in m.points.iter_mut().take(4).enumerate() {
            slot.point = worker + 4 * k as u32;
            slot.min_distance = f64::INFINITY;
        }
        publisher.publish(&m).unwrap();
    }
    // a plausible time, but worker 0 speaking for worker 1's point
    let mut m = <phri_ipc::RepulsionResult as phri_ipc::Zeroed>::zeroed();
    m.worker = 0;
    m.workers = 4;
    m.capture_ns = 1;
    m.n_points = 1;
    m.points[0].point = 1;
    m.points[0].min_distance = f64::INFINITY;
    publisher.publish(&m).unwrap();
    // stays attached until the supervisor has seen it
    wait(1.0);
    drop(publisher);
    drop(node);
    let me = std::process::id();
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    let r = report(&report_path);
    assert_eq!(r["clean"], false, "{}", r["degraded"]);
    let intruders = events(&r, "intruder", "supervisor");
    assert!(
        intruders.iter().any(|e| {
            let d = e["detail"].as_str().unwrap_or("");
            d.contains(&format!("pid {me}")) && d.contains("perception/repulsion")
        }),
        "{}",
        r["events"]
    );
    let refused = &r["inputs"]["control"]["perception/repulsion"];
    assert!(
        refused["stranger"].as_u64().unwrap_or(0) >= 5,
        "{}",
        r["inputs"]
    );
    assert_eq!(refused["stranger_pid"], me, "{}", r["inputs"]);
    let unintended = r["contacts"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["intended"] == false)
        .count();
    assert_eq!(unintended, 0, "{}", r["contacts"]);
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// Issue: after the dead-man stopped the cell (the supervisor was stopped
/// longer than `deadman_s`), the cell must not restart itself when the
/// supervisor comes back: it stays stopped, the robot braked, until an
/// operator resumes it (`phri-hri resume`); the report says dead-man.
#[test]
fn a_dead_man_stop_stays_stopped_until_an_operator_resumes() {
    let _g = serial();
    let p = prefix("dm");
    let d = scratch("dm");
    let rd = d.join("rd");
    let report_path = d.join("report.json");
    let cell = Running::start(
        supervisor(
            &p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                "40",
                "--set",
                "supervisor.deadman_s=2",
                "--report",
                &report_path.to_string_lossy(),
            ],
        ),
        &p,
        &d,
    );
    let st = cell.state(&rd);
    let sim = st["services"]["sim"]["pid"].as_i64().unwrap() as i32;
    wait(3.0);
    cell.signal(libc::SIGSTOP);
    wait(3.5);
    // every service stopped itself (the robot braked as it exited)
    wait_until("the services' dead-man", 10.0, || !alive(sim));
    cell.signal(libc::SIGCONT);
    wait(2.0);
    let procs = processes_of(&p);
    assert!(
        procs.iter().all(|l| l.contains("phri-supervisor")),
        "restarted without an operator: {procs:?}"
    );
    let out = Command::new(bin("phri-hri"))
        .args(["--prefix", &p, "resume", "--wait", "15"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}\nthe supervisor's log:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
        cell.stderr()
    );
    let st = cell.state(&rd);
    assert_ne!(st["services"]["sim"]["pid"].as_i64().unwrap() as i32, sim);
    wait(1.0);
    cell.signal(libc::SIGINT);
    let (code, err) = cell.finish();
    assert_eq!(code, 0, "{err}");
    let r = report(&report_path);
    assert_eq!(r["clean"], false);
    assert!(
        r["degraded"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l.as_str().unwrap_or("").starts_with("dead-man")),
        "{}",
        r["degraded"]
    );
    assert!(!events(&r, "deadman", "").is_empty(), "{}", r["events"]);
    assert_eq!(
        events(&r, "resume", "supervisor").len(),
        1,
        "{}",
        r["events"]
    );
    assert_nothing_left(&p);
    let _ = std::fs::remove_dir_all(&d);
}

/// The command channel is checked per sample where the robot applies it: a
/// process that takes `robot/command` for 25 ms at a time while the
/// controller restarts (three episodes, answering every state with 20 Nm on
/// every joint), between the supervisor's 50 ms looks at the channel, gets
/// none of its commands applied: the arm stays braked, the robot counts
/// them (`robot.refused.commands`) and the supervisor names the pid (an
/// `intruder` event), the run not clean.
///
/// On a loaded machine the probe may stall between taking the channel and
/// its first command long enough for the supervisor to stop the cell
/// first; then the robot had nothing to refuse and the cell runs again (at
/// most three times): each run's arm must stay braked, and one run's robot
/// must have refused a command.
#[test]
fn commands_from_a_process_the_supervisor_did_not_start_are_never_applied() {
    let _g = serial();
    for run in 1..=3 {
        let p = prefix(&format!("cmdgate{run}"));
        let d = scratch(&format!("cmdgate{run}"));
        let probe = probe_commands_while_the_controller_restarts(&p, &d);
        let refused = probe.after.refused_stranger[0] >= 1;
        if refused || run == 3 {
            probe.judge();
            assert_nothing_left(&p);
            let _ = std::fs::remove_dir_all(&d);
            return;
        }
        eprintln!("run {run}: the cell stopped before the robot read a forged command; again");
        assert_nothing_left(&p);
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// What one probe of `robot/command` saw.
struct CommandProbe {
    /// commands published, states read, states not braked
    forged: u64,
    applied: u64,
    before: phri_ipc::CommanderStats,
    after: phri_ipc::CommanderStats,
    /// the supervisor's stderr and its report
    err: String,
    report: PathBuf,
}

/// Start a cell with one controller, kill the controller and, in its
/// restart gap, publish forged commands on `robot/command` (three
/// episodes of 25 ms); with every state read, checks no one was applied
/// (each run's assertions, whatever the supervisor did).
fn probe_commands_while_the_controller_restarts(p: &str, d: &Path) -> CommandProbe {
    use phri_ipc::{robot_status, Queue, TorqueCommand, Zeroed};
    let rd = d.join("rd");
    let report_path = d.join("report.json");
    let cell = Running::start(
        supervisor(
            p,
            Some(&rd),
            &[
                "--scenario",
                "free-motion",
                "--duration",
                "14",
                "--report",
                &report_path.to_string_lossy(),
                // one controller: its slot is the one that commands
                "--set",
                "control.standby=false",
                // a long restart gap, for the probe to step in
                "--set",
                "supervisor.restart_backoff_min_ms=3000",
                "--set",
                "supervisor.restart_backoff_max_ms=3000",
            ],
        ),
        p,
        d,
    );
    let st = cell.state(&rd);
    wait(3.0);
    let node = phri_ipc::node("command-probe", p).unwrap();
    let states = phri_ipc::ROBOT_STATE
        .subscriber(&node, Queue::Latest)
        .unwrap();
    let commanders = phri_ipc::ROBOT_COMMANDERS
        .subscriber(&node, Queue::Drain)
        .unwrap();
    let newest_commanders = || {
        let mut last = None;
        while let Some(m) = commanders.receive().unwrap() {
            last = Some(m);
        }
        last
    };
    let control = st["services"]["control"]["pid"].as_i64().unwrap() as i32;
    // SAFETY: kill(2) on the cell's controller, read from its state.json
    assert_eq!(unsafe { libc::kill(control, libc::SIGKILL) }, 0);
    wait_until("the controller's exit", 5.0, || !alive(control));
    // the robot brakes; its commanders message after that
    wait(0.3);
    let before = newest_commanders().expect("robot/commanders");
    const FORGED_NM: f64 = 20.0;
    let (mut forged, mut seen, mut applied) = (0u64, 0u64, 0u64);
    for _episode in 0..3 {
        // the free slot (the dead controller's port goes with its node)
        let deadline = Instant::now() + Duration::from_secs(2);
        let publisher = loop {
            match phri_ipc::ROBOT_COMMAND.publisher(&node) {
                Ok(publisher) => break publisher,
                Err(e) => {
                    assert!(Instant::now() < deadline, "robot/command never free: {e}");
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
        };
        let until = Instant::now() + Duration::from_millis(25);
        let mut answered = 0;
        while Instant::now() < until {
            if let Some(s) = states.latest().unwrap() {
                seen += 1;
                let n = (s.dof as usize).min(s.tau.len());
                let braking = s.status & robot_status::BRAKING != 0;
                if !braking || s.tau[..n].iter().all(|&t| t == FORGED_NM) {
                    applied += 1;
                }
                if s.seq != answered {
                    answered = s.seq;
                    forged += 1;
                    let mut c = TorqueCommand::zeroed();
                    c.seq = forged;
                    c.state_seq = s.seq;
                    c.state_stamp_ns = s.stamp_ns;
                    c.dof = s.dof;
                    c.tau[..n].fill(FORGED_NM);
                    publisher.publish(&c).unwrap();
                }
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        drop(publisher);
        // what the robot did with the last of them shows in its next states
        let until = Instant::now() + Duration::from_millis(300);
        while Instant::now() < until {
            if let Some(s) = states.latest().unwrap() {
                seen += 1;
                applied += u64::from(s.status & robot_status::BRAKING == 0);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    // the robot's figures, before the controller's restart (3 s after its death)
    wait(0.2);
    let after = newest_commanders().expect("robot/commanders");
    drop((states, commanders, node));
    let (code, err) = cell.finish();
    let _ = phri_ipc::remove_leftovers(p);
    eprintln!(
        "forged {forged} commands in 3 episodes; {seen} states read, {applied} not braked; \
         robot/commanders before {:?}, after {:?} (slot periods, refused stranger, stranger pid); supervisor exit {code}",
        (before.periods, before.refused_stranger, before.stranger_pid),
        (after.periods, after.refused_stranger, after.stranger_pid),
    );
    // (the supervisor's own look at the channel may stop the cell at any
    // episode: the robot's refusals are judged by the caller)
    assert!(forged >= 1, "{forged} commands forged");
    // none applied: the arm stayed braked, no period was the slot's answer
    assert_eq!(
        applied, 0,
        "{applied} states not braked while the probe commanded"
    );
    assert_eq!(
        after.periods[0], before.periods[0],
        "a forged command was applied"
    );
    CommandProbe {
        forged,
        applied,
        before,
        after,
        err,
        report: report_path,
    }
}

impl CommandProbe {
    /// The robot refused, counted and named the probe; the supervisor
    /// reported it as an intruder.
    fn judge(&self) {
        let (after, err) = (&self.after, &self.err);
        let me = std::process::id() as i32;
        assert!(
            after.refused_stranger[0] >= 1,
            "{:?} after {} forged commands, {} applied, from {:?}",
            after.refused_stranger,
            self.forged,
            self.applied,
            self.before.refused_stranger
        );
        assert_eq!(after.stranger_pid, me);
        let r = report(&self.report);
        assert_eq!(r["clean"], false, "{}", r["degraded"]);
        let refused = &r["robot"]["refused"]["commands"];
        assert!(
            refused["stranger"][0].as_u64().unwrap_or(0) >= after.refused_stranger[0],
            "{}",
            r["robot"]
        );
        assert!(
            refused["stranger_pids"]
                .as_array()
                .is_some_and(|a| a.iter().any(|p| p == me)),
            "{}\ndegraded: {}\nintruder events: {:?}\nsupervisor: {err}",
            r["robot"],
            r["degraded"],
            events(&r, "intruder", "")
        );
        let named = events(&r, "intruder", "").into_iter().any(|e| {
            e["detail"]
                .as_str()
                .unwrap_or("")
                .contains(&format!("pid {me}"))
        });
        assert!(named, "{err}\n{}", r["events"]);
    }
}
