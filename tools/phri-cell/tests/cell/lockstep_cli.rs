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
            "--trace",
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
            vec!["--scenario", "elbow", "--outage", "camera-9:1:2"],
            vec!["--outage", "camera-9:1:2"],
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

/// `--trace FILE`: one row per 100 ms of the run, whose ground truth agrees
/// with the run's summary (the sampled closest distance is never below the
/// per-period minimum, and comes within 2 cm of it; the waypoints count up to
/// the summary's); more than one run, or an unwritable file, is refused.
#[test]
fn the_trace_is_the_runs_time_series() {
    let dir = std::env::temp_dir().join(format!("phri-trace-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("trace.csv");
    let path = file.to_string_lossy().into_owned();
    let o = lockstep(&[
        "--config",
        &config(),
        "--scenario",
        "coexistence",
        "--duration",
        "14",
        "--trace",
        &path,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON on stdout");
    let summary = &v["runs"][0]["summary"];
    let text = std::fs::read_to_string(&file).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 140, "one row per 100 ms of 14 s");
    let num = |r: &Vec<&str>, name: &str| r[col(name)].parse::<f64>().expect(name);
    let closest = rows
        .iter()
        .map(|r| num(r, "closest_true_m"))
        .fold(f64::INFINITY, f64::min);
    let min = summary["min_distance_m"].as_f64().unwrap();
    assert!(
        closest >= min - 1e-3 && closest < min + 0.02,
        "{closest} vs {min}"
    );
    let wp: Vec<f64> = rows.iter().map(|r| num(r, "waypoints")).collect();
    assert!(wp.windows(2).all(|w| w[1] >= w[0]));
    assert_eq!(wp.last().copied(), summary["waypoints"].as_f64());
    // the end effector follows its path reference while nobody is near (the first 4 s)
    for r in rows.iter().take(40).skip(20) {
        let e: f64 = ["x", "y", "z"]
            .iter()
            .map(|a| (num(r, &format!("ee_{a}_m")) - num(r, &format!("ref_{a}_m"))).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(e < 0.03, "{e} m off the path at {}", r[0]);
    }
    let o = lockstep(&[
        "--config",
        &config(),
        "--scenario",
        "coexistence",
        "--sweep",
        "0,1,1",
        "--trace",
        &path,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--trace"), "{}", stderr(&o));
    let bad = dir.join("missing").join("trace.csv");
    let o = lockstep(&[
        "--config",
        &config(),
        "--scenario",
        "coexistence",
        "--trace",
        &bad.to_string_lossy(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--trace") && stderr(&o).lines().count() == 1,
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
