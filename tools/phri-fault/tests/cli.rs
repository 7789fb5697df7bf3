//! Command-line contract of `phri-fault`: usage errors exit 1 with one line,
//! a cell that cannot be acted on exits 2 (the live injections are exercised
//! by the system tests in the top-level `tests/`).

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
    }
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
    assert!(err.contains("not JSON"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
