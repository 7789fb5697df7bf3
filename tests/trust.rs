//! What the cell trusts of its configuration, through the real supervisor:
//! a file another user could have written (the configuration, the
//! scenario, the robot file, the URDF) is refused in one line naming it,
//! its owner and its mode, and nothing starts; so is a `--config` that is a
//! FIFO (at once, no hang), and a value outside its safe range. A safety
//! function switched off on purpose runs, and the report says `degraded`,
//! naming the function and the `--set` that switched it off.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod support;

const NOBODY: u32 = 65534;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

fn is_root() -> bool {
    // SAFETY: geteuid cannot fail
    unsafe { libc::geteuid() == 0 }
}

fn prefix(test: &str) -> String {
    format!("r{}{test}_", std::process::id())
}

/// A fresh scratch directory of ours, 0755 (under the root-owned, sticky temporary directory).
fn scratch(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-trust-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o755)).unwrap();
    d
}

/// The supervisor for cell `prefix` with run directory `run_dir` and `args`.
fn supervisor(prefix: &str, run_dir: &Path, args: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_phri-supervisor"));
    cmd.current_dir(repo())
        .arg("--prefix")
        .arg(prefix)
        .arg("--run-dir")
        .arg(run_dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    cmd
}

/// Run a supervisor expected to refuse at once: its exit code and stderr;
/// killed (and the test failed) if it is still running after `limit`.
fn refused(mut cmd: Command, limit: Duration) -> (i32, String) {
    let mut child = cmd.spawn().unwrap();
    let t0 = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            if let Some(mut e) = child.stderr.take() {
                let _ = std::io::Read::read_to_string(&mut e, &mut err);
            }
            return (status.code().unwrap_or(-1), err);
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the supervisor still ran after {limit:?}: it hung");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
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

/// Nothing started: no process of the cell, no shared memory of its
/// prefix, nothing written in its run directory.
fn assert_nothing_started(prefix: &str, run_dir: &Path) {
    let procs = processes_of(prefix);
    assert!(procs.is_empty(), "processes: {procs:?}");
    let files = phri_ipc::files_of(prefix);
    assert!(files.is_empty(), "shared memory: {files:?}");
    let written: Vec<_> = std::fs::read_dir(run_dir)
        .map(|rd| rd.flatten().map(|e| e.file_name()).collect())
        .unwrap_or_default();
    assert!(written.is_empty(), "run directory: {written:?}");
}

/// The default arm's robot directory copied to `dir/robots/` with
/// `robot_extra` appended to its robot file, and a configuration file in
/// `dir` choosing it: (configuration, robot file, URDF).
fn arm_copy(dir: &Path, robot_extra: &str) -> (PathBuf, PathBuf, PathBuf) {
    let robots = dir.join("robots");
    std::fs::create_dir_all(robots.join("lwr4")).unwrap();
    let robot = robots.join("lwr4/robot.toml");
    let text = std::fs::read_to_string(repo().join("deploy/robots/lwr4/robot.toml")).unwrap();
    std::fs::write(&robot, format!("{text}\n{robot_extra}")).unwrap();
    let urdf = robots.join("kuka_lwr4.urdf");
    std::fs::copy(repo().join("deploy/robots/kuka_lwr4.urdf"), &urdf).unwrap();
    let config = dir.join("cell.toml");
    std::fs::write(&config, "[robot]\nname = \"lwr4\"\n").unwrap();
    (config, robot, urdf)
}

/// The probe of the issue: a world-writable robot file of user `nobody`
/// that turns off avoidance, speed and separation monitoring and the
/// residual was accepted. Now it is refused in one line naming it, its
/// owner and its mode, exit 2, and nothing starts; so is the URDF it pulls in.
#[test]
fn a_world_writable_robot_file_of_nobody_is_refused_and_nothing_starts() {
    support::loud_panics();
    let d = scratch("robot");
    let (config, robot, urdf) = arm_copy(
        &d,
        "[ssm]\nenabled = false\n[services.dynamics]\nenabled = false\n",
    );
    let config_arg = config.to_string_lossy().into_owned();
    std::fs::set_permissions(&robot, std::fs::Permissions::from_mode(0o666)).unwrap();
    if is_root() {
        std::os::unix::fs::chown(&robot, Some(NOBODY), Some(NOBODY)).unwrap();
    }
    let p = prefix("robot");
    let rd = d.join("rd");
    let (code, err) = refused(
        supervisor(&p, &rd, &["--config", &config_arg, "--duration", "2"]),
        Duration::from_secs(20),
    );
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    let owner = match is_root() {
        true => "owned by uid 65534 (nobody)".to_string(),
        false => "owned by uid".to_string(),
    };
    assert!(
        err.contains(&format!(
            "{}: {owner}",
            robot.canonicalize().unwrap().display()
        )) && err.contains("mode 0666, writable by other users: refused"),
        "{err}"
    );
    assert_nothing_started(&p, &rd);
    // the URDF it pulls in, another user's
    std::fs::remove_file(&robot).unwrap();
    let (_, robot2, _) = arm_copy(&d, "");
    assert_eq!(robot, robot2);
    if is_root() {
        std::os::unix::fs::chown(&urdf, Some(NOBODY), Some(NOBODY)).unwrap();
        let (code, err) = refused(
            supervisor(&p, &rd, &["--config", &config_arg, "--duration", "2"]),
            Duration::from_secs(20),
        );
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(&format!(
                "{}: owned by uid 65534 (nobody), mode 0644: refused",
                urdf.canonicalize().unwrap().display()
            )),
            "{err}"
        );
        assert_nothing_started(&p, &rd);
    }
    // a scenario in a directory others can write
    let open = d.join("open");
    std::fs::create_dir_all(&open).unwrap();
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o777)).unwrap();
    let scenario = open.join("walk.toml");
    std::fs::write(&scenario, "name = \"walk\"\nduration_s = 2.0\n").unwrap();
    let (code, err) = refused(
        supervisor(
            &p,
            &rd,
            &[
                "--config",
                &repo().join("deploy/phri.toml").to_string_lossy(),
                "--scenario",
                &scenario.to_string_lossy(),
            ],
        ),
        Duration::from_secs(20),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("directory {} above it is owned", open.display()))
            && err.contains("mode 0777"),
        "{err}"
    );
    assert_nothing_started(&p, &rd);
    let _ = std::fs::remove_dir_all(&d);
}

/// `--config` naming a FIFO: refused at once (regular files only), no hang
/// waiting for a writer.
#[test]
fn a_fifo_as_configuration_is_refused_at_once() {
    support::loud_panics();
    let d = scratch("fifo");
    let fifo = d.join("phri.toml");
    let c = std::ffi::CString::new(fifo.to_string_lossy().as_bytes()).unwrap();
    // SAFETY: a valid C string naming a path in our scratch directory
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let p = prefix("fifo");
    let rd = d.join("rd");
    let t0 = Instant::now();
    let (code, err) = refused(
        supervisor(&p, &rd, &["--config", &fifo.to_string_lossy()]),
        Duration::from_secs(10),
    );
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    assert_eq!(code, 2, "{err}");
    assert_eq!(
        err.trim(),
        format!(
            "phri-supervisor: {}: is a FIFO, not a regular file: refused",
            fifo.display()
        )
    );
    assert_nothing_started(&p, &rd);
    let _ = std::fs::remove_dir_all(&d);
}

/// A value outside its safe range: one line naming the `--set`, the key,
/// the value and the range; nothing starts.
#[test]
fn a_value_outside_its_safe_range_is_refused_before_anything_starts() {
    support::loud_panics();
    let d = scratch("range");
    let p = prefix("range");
    let rd = d.join("rd");
    let config = repo().join("deploy/phri.toml");
    let (code, err) = refused(
        supervisor(
            &p,
            &rd,
            &[
                "--config",
                &config.to_string_lossy(),
                "--set",
                "perception.self_filter.margin_m=3",
            ],
        ),
        Duration::from_secs(20),
    );
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("--set perception.self_filter.margin_m=3: perception.self_filter.margin_m: 3 is outside its safe range [0, 0.1] m"),
        "{err}"
    );
    assert_nothing_started(&p, &rd);
    let _ = std::fs::remove_dir_all(&d);
}

/// Avoidance switched off on purpose runs, and its report is degraded,
/// naming avoidance and the `--set` that switched it off.
#[test]
fn avoidance_switched_off_runs_and_the_report_is_degraded_naming_it_and_the_flag() {
    let run = support::RunPlace::new('r', "off");
    let out = run
        .command(env!("CARGO_BIN_EXE_phri-supervisor"), &repo())
        .args([
            "--config",
            &repo().join("deploy/phri.toml").to_string_lossy(),
            "--scenario",
            "free-motion",
            "--duration",
            "3",
            "--set",
            "control.avoidance=false",
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&run.report)
            .unwrap_or_else(|e| panic!("no report ({e}); exit {:?}: {err}", out.status.code())),
    )
    .unwrap();
    let line =
        "collision avoidance switched off (control.avoidance by --set control.avoidance=false)";
    assert_eq!(report["clean"], false, "{report:#}");
    let degraded: Vec<&str> = report["degraded"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert!(degraded.contains(&line), "{degraded:?}");
    let summary = report["summary"].as_str().unwrap();
    assert!(
        summary.starts_with("degraded (") && summary.contains(line),
        "{summary}"
    );
    assert!(err.contains(line), "{err}");
    let _ = std::fs::remove_dir_all(&run.run_dir);
}
