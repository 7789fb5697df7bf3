//! Every command of the guide marked runnable runs as written: each fenced
//! block whose info string is `sh runnable` in `README.md` and `docs/*.md`
//! runs with `bash -euo pipefail` from the workspace's root (where the guide
//! says to type its commands), in a namespace of its own: its own iceoryx2
//! prefix (`PHRI_PREFIX`), run directory (`XDG_RUNTIME_DIR`), ROS 2 on the
//! loopback only. The release binaries are first on `PATH` (and deploy/up's
//! `CARGO_TARGET_DIR` is theirs); a runnable block builds nothing. A block
//! that fails or outlasts [`BLOCK_TIMEOUT`] is reported with its file and
//! line, its text and its output; every block runs even when one fails.
//! Files a block writes in the workspace's root under a name it spells
//! (`--report report.json`) are removed after it.

use std::collections::BTreeSet;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "support/workspace.rs"]
mod workspace;

/// The info string that marks a block runnable (docs/README.md says so).
const MARKER: &str = "runnable";

/// The longest a block may take (they are written to take a few seconds).
const BLOCK_TIMEOUT: Duration = Duration::from_secs(45);

/// The fewest runnable blocks the guide has: removing the markers fails.
const MIN_BLOCKS: usize = 5;

struct Block {
    /// `docs/getting-started.md:8` (the opening fence's line)
    at: String,
    script: String,
}

/// The runnable blocks of `text` (the file `name`).
fn blocks_of(name: &str, text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut open: Option<(usize, bool, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim_start().starts_with("```");
        match open.take() {
            None if fence => {
                let info: Vec<&str> = line.trim_start()[3..].split_whitespace().collect();
                let runnable = info.first() == Some(&"sh") && info.contains(&MARKER);
                open = Some((i + 1, runnable, String::new()));
            }
            None => {}
            Some((at, true, script)) if fence => out.push(Block {
                at: format!("{name}:{at}"),
                script,
            }),
            // the end of a block not marked runnable
            Some(_) if fence => {}
            Some((at, runnable, mut script)) => {
                script.push_str(line);
                script.push('\n');
                open = Some((at, runnable, script));
            }
        }
    }
    out
}

/// Every runnable block of the README and the guide, in file order.
fn blocks(repo: &Path) -> Vec<Block> {
    let mut files = vec![PathBuf::from("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo.join("docs"))
        .expect("docs/")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .filter_map(|p| p.strip_prefix(repo).ok().map(Path::to_path_buf))
        .collect();
    docs.sort();
    files.extend(docs);
    files
        .iter()
        .flat_map(|f| {
            let text = std::fs::read_to_string(repo.join(f)).unwrap_or_default();
            blocks_of(&f.display().to_string(), &text)
        })
        .collect()
}

/// The last `n` lines of `text`.
fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let from = lines.len().saturating_sub(n);
    let cut = if from > 0 { "…\n" } else { "" };
    format!("{cut}{}", lines[from..].join("\n"))
}

/// SIGTERM, then SIGKILL, to what is left of the block's process group.
fn end_group(pgid: u32) {
    let pgid = -(pgid as libc::pid_t);
    // SAFETY: kill(2) on the block's own process group, no memory involved
    unsafe { libc::kill(pgid, libc::SIGTERM) };
    let until = Instant::now() + Duration::from_secs(3);
    // SAFETY: signal 0 only asks whether the group still has a member
    while Instant::now() < until && unsafe { libc::kill(pgid, 0) } == 0 {
        std::thread::sleep(Duration::from_millis(50));
    }
    // SAFETY: as above
    unsafe { libc::kill(pgid, libc::SIGKILL) };
}

/// The names in the workspace's root.
fn root_names(repo: &Path) -> BTreeSet<String> {
    std::fs::read_dir(repo)
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

/// Run block `i`: its time, or why it failed.
fn run(repo: &Path, bin_dir: &Path, i: usize, block: &Block) -> Result<Duration, String> {
    let prefix = format!("d{}b{i}_", std::process::id());
    let scratch = std::env::temp_dir().join(format!("phri-docs-{prefix}"));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch).map_err(|e| e.to_string())?;
    let script = scratch.join("block.sh");
    std::fs::write(&script, &block.script).map_err(|e| e.to_string())?;
    let out_path = scratch.join("stdout");
    let err_path = scratch.join("stderr");
    let file = |p: &Path| std::fs::File::create(p).map_err(|e| e.to_string());
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    // deploy/up (--help) finds the supervisor in the binaries' own target directory
    let target = bin_dir.parent().unwrap_or(bin_dir);
    let before = root_names(repo);
    let start = Instant::now();
    let mut child = Command::new("bash")
        .args(["-e", "-u", "-o", "pipefail"])
        .arg(&script)
        .current_dir(repo)
        .env("PATH", path)
        .env("PHRI_PREFIX", &prefix)
        .env("XDG_RUNTIME_DIR", &scratch)
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("CARGO_TARGET_DIR", target)
        .env_remove("ROS_LOCALHOST_ONLY")
        .stdin(Stdio::null())
        .stdout(file(&out_path)?)
        .stderr(file(&err_path)?)
        .process_group(0)
        .spawn()
        .map_err(|e| format!("bash: {e}"))?;
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break Some(s),
            Ok(None) if start.elapsed() > BLOCK_TIMEOUT => break None,
            Ok(None) => std::thread::sleep(Duration::from_millis(50)),
            Err(e) => return Err(format!("waiting for bash: {e}")),
        }
    };
    let took = start.elapsed();
    // what the block left running (a cell started with `&` and not waited for)
    end_group(child.id());
    let _ = child.wait();
    // what it wrote in the root under a name it spells
    for name in root_names(repo).difference(&before) {
        if block.script.contains(name.as_str()) {
            let p = repo.join(name);
            let _ = std::fs::remove_file(&p).or_else(|_| std::fs::remove_dir_all(&p));
        }
    }
    let read = |p: &Path| std::fs::read_to_string(p).unwrap_or_default();
    let (out, err) = (read(&out_path), read(&err_path));
    let verdict = match status {
        Some(s) if s.success() => None,
        Some(s) => Some(format!("{s}")),
        None => Some(format!("still running after {} s", BLOCK_TIMEOUT.as_secs())),
    };
    let _ = std::fs::remove_dir_all(&scratch);
    match verdict {
        None => Ok(took),
        Some(why) => Err(format!(
            "{}: {why} after {:.1} s\n--- block ---\n{}--- stdout ---\n{}\n--- stderr ---\n{}\n",
            block.at,
            took.as_secs_f64(),
            block.script,
            tail(&out, 40),
            tail(&err, 40)
        )),
    }
}

#[test]
fn the_marker_is_read_as_documented() {
    let text =
        "a\n```sh runnable\necho one\n```\n```sh\nnot this\n```\n```text runnable\nnor this\n```\n";
    let b = blocks_of("x.md", text);
    assert_eq!(b.len(), 1);
    assert_eq!(b[0].at, "x.md:2");
    assert_eq!(b[0].script, "echo one\n");
}

#[test]
fn every_runnable_block_of_the_guide_runs() {
    let repo = workspace::repo();
    let bin_dir = workspace::bin("phri-supervisor")
        .parent()
        .expect("the binaries' folder")
        .to_path_buf();
    let blocks = blocks(&repo);
    assert!(
        blocks.len() >= MIN_BLOCKS,
        "{} runnable blocks in README.md and docs/*.md, expected at least {MIN_BLOCKS} (```sh {MARKER})",
        blocks.len()
    );
    let start = Instant::now();
    let mut failed = Vec::new();
    for (i, block) in blocks.iter().enumerate() {
        match run(&repo, &bin_dir, i, block) {
            Ok(took) => eprintln!("docs: {} ran in {:.1} s", block.at, took.as_secs_f64()),
            Err(why) => {
                eprintln!("docs: {why}");
                failed.push(why);
            }
        }
    }
    eprintln!(
        "docs: {} runnable blocks in {:.1} s",
        blocks.len(),
        start.elapsed().as_secs_f64()
    );
    assert!(
        failed.is_empty(),
        "{} of {} runnable blocks failed:\n{}",
        failed.len(),
        blocks.len(),
        failed.join("\n")
    );
}
