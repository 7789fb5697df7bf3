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
    let o = hri(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("request KIND"));
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
    ] {
        let o = hri(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let line = first_line(&o);
        assert!(
            line.starts_with("phri-hri: ") && line.contains(says),
            "{args:?}: {line}"
        );
    }
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
