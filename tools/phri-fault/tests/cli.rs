//! Command-line contract of `phri-fault`: usage errors exit 1 with one line
//! naming the flag or argument, a cell that cannot be acted on exits 2 (the
//! live injections are exercised by the system tests in the top-level `tests/`);
//! `--help`, `--version` and `completions` exit 0.

use std::process::Command;

fn fault(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_phri-fault"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn frame_faults_only_target_the_camera_and_check_their_arguments() {
    let d = std::env::temp_dir().to_string_lossy().into_owned();
    for (args, needle) in [
        (
            vec!["--run-dir", &d, "dynamics", "corrupt", "zeros"],
            "SERVICE must be camera",
        ),
        (
            vec!["--run-dir", &d, "camera", "corrupt", "purple"],
            "unknown KIND",
        ),
        (vec!["--run-dir", &d, "camera", "corrupt"], "needs KIND"),
        (
            vec![
                "--run-dir",
                &d,
                "camera",
                "corrupt",
                "noise",
                "--frames",
                "0",
            ],
            "--frames",
        ),
        (vec!["--run-dir", &d, "camera", "delay", "100"], "--for"),
        (
            vec!["--run-dir", &d, "camera", "delay", "-3", "--for", "1"],
            "delay",
        ),
    ] {
        let (code, err) = fault(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}

fn out(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_phri-fault"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn help_version_and_completions() {
    for flag in ["--help", "-h"] {
        let (code, stdout, _) = out(&[flag]);
        assert_eq!(code, 0, "{flag}");
        for needle in [
            "SERVICE",
            "ACTION",
            "--run-dir",
            "--prefix",
            "PHRI_PREFIX",
            "--times",
            "--random",
            "--json",
        ] {
            assert!(
                stdout.contains(needle),
                "{flag}: {needle} missing: {stdout}"
            );
        }
    }
    let (_, long, _) = out(&["--help"]);
    assert!(
        long.contains("corrupt KIND") && long.contains("Exit status"),
        "{long}"
    );
    let (code, stdout, _) = out(&["--version"]);
    assert_eq!(code, 0);
    assert_eq!(
        stdout.trim(),
        format!("phri-fault {}", env!("CARGO_PKG_VERSION"))
    );
    for shell in ["bash", "zsh", "fish"] {
        let (code, stdout, err) = out(&["completions", shell]);
        assert_eq!(code, 0, "{shell}: {err}");
        assert!(
            stdout.contains("phri-fault") && stdout.contains("run-dir"),
            "{shell}"
        );
    }
}

#[test]
fn mistyped_flags_and_actions_get_a_suggestion_in_one_line() {
    let d = std::env::temp_dir().to_string_lossy().into_owned();
    for (args, needles) in [
        (
            vec!["--run-dir", &d, "sim", "kill", "--tims", "3"],
            ["--tims", "'--times'"],
        ),
        (vec!["--run-dir", &d, "sim", "kil"], ["kil", "'kill'"]),
        (
            vec![
                "--run-dir",
                &d,
                "sim",
                "kill",
                "--every",
                "1",
                "--random",
                "1,2",
            ],
            ["--every", "--random"],
        ),
        (
            vec!["--run-dir", &d, "sim", "kill", "--random", "2,1"],
            ["--random", "MIN > MAX"],
        ),
        (
            vec!["--run-dir", &d, "sim", "kill", "--times", "many"],
            ["--times", "many"],
        ),
        (
            vec!["--run-dir", &d, "sim", "kill", "--every", "-1"],
            ["--every", "-1"],
        ),
        (vec!["--run-dir", &d, "sim"], ["ACTION", "required"]),
    ] {
        let (code, err) = fault(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("phri-fault: "), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n} not in {err}");
        }
    }
}

/// `--flag=value` and flags after the positionals reach the same checks:
/// with a run directory that has no state.json, a well-formed command line
/// gets as far as the cell (exit 2), a bad value stops at the usage (exit 1).
#[test]
fn flag_equals_value_is_accepted() {
    let dir = std::env::temp_dir().join(format!("phri-fault-eq-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run_dir = format!("--run-dir={}", dir.display());
    let (code, err) = fault(&[
        &run_dir,
        "camera",
        "corrupt",
        "noise",
        "--frames=5",
        "--times=2",
        "--json",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("state.json"), "{err}");
    let (code, err) = fault(&[&run_dir, "sim", "slow", "50", "--for=-1"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--for"), "{err}");
    let (code, err) = fault(&[
        &run_dir,
        "sim",
        "kill",
        "--random=0.5,1",
        "--seed=7",
        "--until=3",
    ]);
    assert_eq!(code, 2, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_cell_means_exit_2_naming_the_state_file() {
    let dir = std::env::temp_dir().join(format!("phri-fault-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let d = dir.to_string_lossy().into_owned();
    for action in [vec!["kill"], vec!["corrupt", "size"]] {
        let mut args = vec!["--run-dir", d.as_str(), "camera"];
        args.extend(action);
        let (code, err) = fault(&args);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("state.json"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    std::fs::write(dir.join("state.json"), "{not json").unwrap();
    let (code, err) = fault(&["--run-dir", &d, "camera", "corrupt", "size"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a state file"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_run_dir_comes_from_the_prefix_or_the_default_namespace() {
    // no flag: PHRI_PREFIX's (here a namespace with no cell: no state.json)
    let out = Command::new(env!("CARGO_BIN_EXE_phri-fault"))
        .args(["camera", "kill"])
        .env("PHRI_PREFIX", "phri_fault_cli_env_")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run-phri_fault_cli_env_") && err.contains("state.json"),
        "{err}"
    );
    // the prefix finds the supervisor's default run directory (no cell: no state.json)
    let (code, err) = fault(&["--prefix", "phri_fault_cli_nocell_", "camera", "kill"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("run-phri_fault_cli_nocell_") && err.contains("state.json"),
        "{err}"
    );
}

/// A state file another user could have written, or one naming pids that
/// are not the cell's services (init, this test, a dead supervisor), is
/// never acted on: nothing is signalled.
#[test]
fn untrusted_or_stale_state_is_refused_and_nothing_is_signalled() {
    use std::os::unix::fs::PermissionsExt;
    let dir = std::env::temp_dir().join(format!("phri-fault-trust-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let d = dir.to_string_lossy().into_owned();
    let state = dir.join("state.json");
    // a process of ours that must survive: it is not the cell's service
    let mut bystander = Command::new("sleep").arg("30").spawn().unwrap();
    let me = std::process::id();
    for (sup, pid) in [
        (0, bystander.id()),
        (me, bystander.id()),
        (me, 1),
        (me, 0),
        (1, bystander.id()),
    ] {
        let text = format!(
            r#"{{"prefix":"p_","services":{{"sim":{{"pid":{pid},"restarts":0}}}},"supervisor_pid":{sup}}}"#
        );
        std::fs::write(&state, text).unwrap();
        let (code, err) = fault(&["--run-dir", &d, "sim", "kill"]);
        assert_eq!(code, 2, "supervisor {sup}, pid {pid}: {err}");
        assert!(
            err.contains("stale state.json") || err.contains("is down"),
            "{err}"
        );
        assert!(
            bystander.try_wait().unwrap().is_none(),
            "the bystander was signalled"
        );
    }
    // writable by others: not read at all
    std::fs::set_permissions(&state, std::fs::Permissions::from_mode(0o666)).unwrap();
    let (code, err) = fault(&["--run-dir", &d, "sim", "kill"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("writable by other users"), "{err}");
    bystander.kill().unwrap();
    bystander.wait().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
