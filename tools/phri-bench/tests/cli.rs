//! `phri-bench` as a user runs it: `--help`, `--version` and `completions`
//! exit 0, a bad command line is one line naming the flag (exit 2), and
//! `transport --iterations=N` runs the transport benchmark under its own
//! prefix (the loop benchmark starts a whole cell: the system tests' business).

use std::process::{Command, Output};

fn bench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_phri-bench"))
        .args(args)
        .output()
        .expect("run phri-bench")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn help_version_and_completions() {
    let o = bench(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    let text = stdout(&o);
    assert!(
        text.contains("loop") && text.contains("transport"),
        "{text}"
    );
    assert!(
        !text.contains("transport-peer"),
        "the internal peer is hidden: {text}"
    );
    let o = bench(&["loop", "-h"]);
    assert_eq!(o.status.code(), Some(0));
    let text = stdout(&o);
    for needle in [
        "--duration",
        "--scenario",
        "--config",
        "free-motion",
        "[default: 30]",
    ] {
        assert!(text.contains(needle), "loop -h: {needle} missing: {text}");
    }
    let o = bench(&["transport", "--help"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(stdout(&o).contains("--iterations"), "{}", stdout(&o));
    let o = bench(&["--version"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(
        stdout(&o).trim(),
        format!("phri-bench {}", env!("CARGO_PKG_VERSION"))
    );
    for shell in ["bash", "zsh", "fish"] {
        let o = bench(&["completions", shell]);
        assert_eq!(o.status.code(), Some(0), "{shell}: {}", stderr(&o));
        let script = stdout(&o);
        assert!(
            script.contains("phri-bench") && script.contains("transport"),
            "{shell}"
        );
    }
}

#[test]
fn bad_command_lines_are_one_line_naming_the_flag() {
    for (args, needles) in [
        (
            &["loop", "--duraton", "3"][..],
            &["--duraton", "'--duration'"][..],
        ),
        (&["lop"][..], &["lop", "'loop'"][..]),
        (
            &["loop", "--duration", "-3"][..],
            &["--duration", "positive"][..],
        ),
        (
            &["loop", "--duration=soon"][..],
            &["--duration", "soon"][..],
        ),
        (
            &["transport", "--iterations", "many"][..],
            &["--iterations", "many"][..],
        ),
    ] {
        let o = bench(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("phri-bench: "), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n} not in {err}");
        }
    }
}

#[test]
fn transport_with_flag_equals_value() {
    let o = bench(&["transport", "--iterations=10"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON on stdout");
    assert_eq!(v["iterations"], 10);
    let sizes = v["sizes"].as_array().expect("sizes");
    assert_eq!(sizes.len(), 5);
    for s in sizes {
        for k in ["iceoryx2_us", "unix_socket_us"] {
            let t = s[k].as_f64().expect(k);
            assert!(t.is_finite() && t > 0.0, "{k}: {t}");
        }
    }
    // at least 10 round trips, whatever is asked
    let o = bench(&["transport", "--iterations", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON on stdout");
    assert_eq!(v["iterations"], 10);
}
