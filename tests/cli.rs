//! Every binary of the workspace (found in the members' Cargo.toml files, so
//! a new one cannot be forgotten) answers `--help`, `-h` and `--version`
//! with exit 0 and text on stdout, writes a bash completion script, and
//! refuses a mistyped flag with one line naming it and a non-zero exit.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// The `[[bin]]` names of every workspace member (a package without
/// `[[bin]]` sections but with `src/main.rs` has one named after it).
fn binaries() -> Vec<String> {
    let root = repo();
    let ws: toml::Value =
        toml::from_str(&std::fs::read_to_string(root.join("Cargo.toml")).unwrap()).unwrap();
    let mut out = Vec::new();
    for m in ws["workspace"]["members"].as_array().unwrap() {
        let dir = root.join(m.as_str().unwrap());
        let pkg: toml::Value =
            toml::from_str(&std::fs::read_to_string(dir.join("Cargo.toml")).unwrap()).unwrap();
        match pkg.get("bin").and_then(|b| b.as_array()) {
            Some(bins) => out.extend(bins.iter().map(|b| b["name"].as_str().unwrap().to_string())),
            None if dir.join("src/main.rs").is_file() => {
                out.push(pkg["package"]["name"].as_str().unwrap().to_string())
            }
            None => {}
        }
    }
    out.sort();
    out
}

fn bin(name: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_BIN_EXE_phri-supervisor"))
        .parent()
        .unwrap()
        .join(name);
    assert!(
        p.is_file(),
        "{} not built (cargo test --workspace builds it)",
        p.display()
    );
    p
}

/// Run `name args`: (exit code, stdout, stderr). No channel is opened:
/// nothing here reaches a cell, whatever the prefix.
fn run(name: &str, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(bin(name))
        .args(args)
        .current_dir(repo())
        .env("PHRI_PREFIX", "phri_cli_walk_")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_walk_finds_every_binary() {
    let all = binaries();
    // the cell's services and the tools, as the README lists them
    for must in [
        "phri-supervisor",
        "phri-sim",
        "phri-control",
        "phri-dynamics",
        "phri-perception",
        "phri-repulsion",
        "phri-tracker",
        "phri-camera",
        "phri-voice",
        "phri-mic",
        "phri-monitor",
        "phri-record",
        "phri-replay",
        "phri-plot",
        "phri-viz",
        "phri-model",
    ] {
        assert!(all.iter().any(|b| b == must), "{must} missing from {all:?}");
    }
    assert!(all.len() >= 20, "{all:?}");
}

#[test]
fn every_binary_answers_help_and_version() {
    for name in binaries() {
        for flag in ["--help", "-h"] {
            let (code, out, err) = run(&name, &[flag]);
            assert_eq!(code, 0, "{name} {flag}: {err}");
            assert!(out.contains("Usage:"), "{name} {flag}: {out}");
            assert!(out.contains("--version"), "{name} {flag}: {out}");
        }
        let (code, out, err) = run(&name, &["--version"]);
        assert_eq!(code, 0, "{name} --version: {err}");
        assert_eq!(
            out.trim(),
            format!("{name} {}", env!("CARGO_PKG_VERSION")),
            "{name} --version"
        );
    }
}

#[test]
fn every_binary_writes_completions() {
    for name in binaries() {
        for shell in ["bash", "zsh", "fish"] {
            let (code, out, err) = run(&name, &["completions", shell]);
            assert_eq!(code, 0, "{name} completions {shell}: {err}");
            assert!(out.contains(&name), "{name} completions {shell}: {out}");
        }
    }
}

#[test]
fn every_binary_refuses_a_mistyped_flag_in_one_line() {
    for name in binaries() {
        let (code, out, err) = run(&name, &["--no-such-flag"]);
        // 2, or 1 where a tool documents 1 as its usage error (phri-fault, phri-hri)
        assert!(code == 2 || code == 1, "{name}: exit {code}: {err}");
        assert!(out.is_empty(), "{name}: {out}");
        assert_eq!(err.trim().lines().count(), 1, "{name}: {err}");
        assert!(
            err.starts_with(&format!("{name}: ")) && err.contains("--no-such-flag"),
            "{name}: {err}"
        );
    }
}
