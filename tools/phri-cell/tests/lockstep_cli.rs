//! `phri-lockstep`'s command line: `--help`, `--version` and `completions`
//! exit 0; a bad command line is one line naming the flag (exit 2);
//! `--flag=value` and values that start with a minus (`--sweep -4,0,2`,
//! `--offset -1`) reach the runs.

use std::process::{Command, Output};

fn config() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../deploy/phri.toml").to_string()
}

fn lockstep(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_phri-lockstep"))
        .args(args)
        .output()
        .expect("run phri-lockstep")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The offsets of the runs of a successful invocation.
fn offsets(o: &Output) -> Vec<f64> {
    assert_eq!(o.status.code(), Some(0), "{}", stderr(o));
    let v: serde_json::Value = serde_json::from_str(&stdout(o)).expect("JSON on stdout");
    v["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .map(|r| r["offset_s"].as_f64().expect("offset_s"))
        .collect()
}

#[test]
fn help_version_and_completions() {
    for flag in ["--help", "-h"] {
        let o = lockstep(&[flag]);
        assert_eq!(o.status.code(), Some(0), "{flag}");
        let text = stdout(&o);
        for needle in [
            "--scenario",
            "--duration",
            "--config",
            "--set",
            "--offset",
            "--sweep",
            "--latency-ms",
            "--outage",
            "--no-perception",
        ] {
            assert!(text.contains(needle), "{flag}: {needle} missing: {text}");
        }
    }
    let o = lockstep(&["--version"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(
        stdout(&o).trim(),
        format!("phri-lockstep {}", env!("CARGO_PKG_VERSION"))
    );
    for shell in ["bash", "zsh", "fish"] {
        let o = lockstep(&["completions", shell]);
        assert_eq!(o.status.code(), Some(0), "{shell}: {}", stderr(&o));
        let script = stdout(&o);
        assert!(
            script.contains("phri-lockstep") && script.contains("sweep"),
            "{shell}"
        );
    }
}

#[test]
fn bad_command_lines_are_one_line_naming_the_flag() {
    let c = config();
    for (args, needles) in [
        (
            vec!["--scenario", "elbow", "--duratoin", "1"],
            vec!["--duratoin", "'--duration'"],
        ),
        (vec!["--duration", "1"], vec!["--scenario"]),
        (
            vec!["--scenario", "elbow", "--offset", "soon"],
            vec!["--offset", "soon"],
        ),
        (
            vec!["--scenario", "elbow", "--outage", "camera:1:2"],
            vec!["--outage", "camera:1:2"],
        ),
        (
            vec!["--config", &c, "--scenario", "elbow", "--sweep", "-4,0"],
            vec!["--sweep"],
        ),
        (
            vec!["--config", &c, "--scenario", "elbow", "--duration", "-1"],
            vec!["--duration"],
        ),
    ] {
        let o = lockstep(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("phri-lockstep: "), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n} not in {err}");
        }
    }
}

#[test]
fn negative_values_and_flag_equals_value_reach_the_runs() {
    let c = config();
    let o = lockstep(&[
        "--config",
        &c,
        "--scenario",
        "elbow",
        "--duration",
        "0.1",
        "--sweep",
        "-4,0,2",
    ]);
    assert_eq!(offsets(&o), [-4.0, -2.0, 0.0]);
    assert_eq!(
        stderr(&o).lines().count(),
        3,
        "one line per run: {}",
        stderr(&o)
    );
    let config_eq = format!("--config={c}");
    let o = lockstep(&[
        &config_eq,
        "--scenario=elbow",
        "--duration=0.1",
        "--offset",
        "-1",
        "--offset=-0.5",
        "--sweep=0,0.2,0.1",
        "--latency-ms=3",
        "--set=skeleton.seed=7",
        "--outage=dynamics:0.02:0.05",
    ]);
    let got = offsets(&o);
    assert_eq!(got.len(), 5, "{got:?}");
    for (a, b) in got.iter().zip([-1.0, -0.5, 0.0, 0.1, 0.2]) {
        assert!((a - b).abs() < 1e-9, "{got:?}");
    }
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["perception_latency_ms"], 3.0);
    assert_eq!(v["duration_s"], 0.1);
}
