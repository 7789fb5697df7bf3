//! `phri-hri` as a user runs it: bad command lines are one line and exit 1,
//! a cell that is not there is one line naming the channel and exit 2.

use std::process::{Command, Output};

fn hri(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_phri-hri"))
        .args(args)
        .output()
        .expect("run phri-hri")
}

fn first_line(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr)
        .lines()
        .next()
        .unwrap_or("")
        .to_string()
}

#[test]
fn help_and_usage_errors() {
    for flag in ["--help", "-h"] {
        let o = hri(&[flag]);
        assert_eq!(o.status.code(), Some(0), "{flag}");
        let text = String::from_utf8_lossy(&o.stdout);
        for needle in ["request", "watch", "--prefix", "PHRI_PREFIX", "--json"] {
            assert!(text.contains(needle), "{flag}: {needle} missing: {text}");
        }
    }
    let o = hri(&["request", "--help"]);
    assert_eq!(o.status.code(), Some(0));
    let text = String::from_utf8_lossy(&o.stdout);
    for needle in [
        "<KIND>",
        "[PART]",
        "follow",
        "right_hand",
        "--wait",
        "--person",
        "--text",
    ] {
        assert!(
            text.contains(needle),
            "request --help: {needle} missing: {text}"
        );
    }
    let o = hri(&["watch", "--help"]);
    assert_eq!(o.status.code(), Some(0));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("--once") && text.contains("--seconds"),
        "{text}"
    );
    for (args, says) in [
        (&["--prefix", "x_", "request"][..], "KIND"),
        (&["--prefix", "x_", "request", "dance"][..], "dance"),
        (&["--prefix", "x_", "request", "follow", "nose"][..], "nose"),
        (
            &["--prefix", "x_", "request", "end", "right_hand"][..],
            "takes no part",
        ),
        (
            &["--prefix", "x_", "request", "follow", "--wait", "-1"][..],
            "--wait",
        ),
        (
            &["--prefix", "x_", "request", "follow", "--wait", "nan"][..],
            "--wait",
        ),
        (&["--prefix", "x_", "watch", "--seconds"][..], "--seconds"),
        (&["--prefix", "x_", "fly"][..], "fly"),
        (&["--prefix", "x_", "watch", "--bogus"][..], "--bogus"),
        (&["--prefix", "x_", "watch", "--onec"][..], "'--once'"),
        (
            &["--prefix", "x_", "request", "follow", "--wiat", "2"][..],
            "'--wait'",
        ),
        (&["--prefix", "x_", "reqest", "end"][..], "'request'"),
    ] {
        let o = hri(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let line = first_line(&o);
        assert!(
            line.starts_with("phri-hri: ") && line.contains(says),
            "{args:?}: {line}"
        );
        let lines = String::from_utf8_lossy(&o.stderr).trim().lines().count();
        assert_eq!(lines, 1, "{args:?}");
    }
    // no command: the help on stderr, and the usage status
    let o = hri(&[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("request"));
}

#[test]
fn version_and_completions() {
    let o = hri(&["--version"]);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        format!("phri-hri {}", env!("CARGO_PKG_VERSION"))
    );
    for shell in ["bash", "zsh", "fish"] {
        let o = hri(&["completions", shell]);
        assert_eq!(o.status.code(), Some(0), "{shell}");
        let script = String::from_utf8_lossy(&o.stdout);
        assert!(
            script.contains("phri-hri") && script.contains("request") && script.contains("watch"),
            "{shell}: {script}"
        );
    }
}

/// `--flag=value`, flags before the command and the prefix from the
/// environment all reach the cell (none here: exit 2 naming the channel and
/// the prefix).
#[test]
fn flag_equals_value_and_the_prefix_from_the_environment() {
    let prefix = format!("hrieq{}_", std::process::id());
    let flag = format!("--prefix={prefix}");
    for args in [
        vec![flag.as_str(), "--json", "watch", "--once"],
        vec!["watch", flag.as_str(), "--seconds=0.2"],
        vec![
            flag.as_str(),
            "request",
            "begin",
            "--wait=0.1",
            "--person=3",
            "--text=hi",
        ],
    ] {
        let o = hri(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let line = first_line(&o);
        assert!(
            line.contains("collab/state") && line.contains(&prefix),
            "{args:?}: {line}"
        );
    }
    let o = Command::new(env!("CARGO_BIN_EXE_phri-hri"))
        .args(["watch", "--once"])
        .env("PHRI_PREFIX", &prefix)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(first_line(&o).contains(&prefix), "{}", first_line(&o));
    let files = phri_ipc::files_of(&prefix);
    assert!(files.is_empty(), "left behind: {files:?}");
}

#[test]
fn no_cell_is_one_line_naming_the_channel() {
    let prefix = format!("hri{}_", std::process::id());
    let o = hri(&["--prefix", &prefix, "request", "follow", "right_hand"]);
    assert_eq!(o.status.code(), Some(2));
    let line = first_line(&o);
    assert!(line.contains("collab/state"), "{line}");
    let o = hri(&["--prefix", &prefix, "watch", "--once"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        first_line(&o).contains("collab/state"),
        "{}",
        first_line(&o)
    );
    // nothing of the prefix is left behind
    let files = phri_ipc::files_of(&prefix);
    assert!(files.is_empty(), "left behind: {files:?}");
}
