//! A supervised process: a child this supervisor started, or one adopted
//! from a supervisor that died (not our child: watched through /proc); how a
//! pid read from a file is recognised before anything signals it; how a
//! service binary is checked and asked to check its configuration.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use phri_config::ServiceSpec;

/// The fields of `/proc/<pid>/stat` after the parenthesised command name
/// (which may hold spaces and parentheses): state, ppid, ...
fn stat_fields(pid: u32) -> Option<Vec<String>> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let (_, rest) = stat.rsplit_once(')')?;
    Some(rest.split_whitespace().map(str::to_string).collect())
}

/// `pid` is a process a pid read from a file may name: above 1 (never init,
/// never "every process" or a process group), running (not a zombie), of
/// this user, and its command line contains every one of `needles`. Nothing
/// else is ever signalled.
pub fn process_matches(pid: u32, needles: &[impl AsRef<str>]) -> bool {
    if pid <= 1 || pid > i32::MAX as u32 {
        return false;
    }
    let Some(fields) = stat_fields(pid) else {
        return false;
    };
    let state = fields.first().map_or("?", String::as_str);
    if state == "Z" || state == "X" {
        return false;
    }
    // the owner of /proc/<pid> is the process's effective user
    let mine = std::fs::metadata(format!("/proc/{pid}"))
        .is_ok_and(|m| m.uid() == phri_runtime::rundir::euid());
    if !mine {
        return false;
    }
    let Ok(cmdline) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
        return false;
    };
    let cmdline: String = cmdline
        .iter()
        .map(|&b| if b == 0 { ' ' } else { b as char })
        .collect();
    needles
        .iter()
        .all(|n| contains_words(cmdline.trim_end(), n.as_ref()))
}

/// `line` contains `needle` as whole words: `--prefix p_` is not in
/// `--prefix p_x`; a program name may follow a `/`.
fn contains_words(line: &str, needle: &str) -> bool {
    if needle.is_empty() {
        return true;
    }
    line.match_indices(needle).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + needle.len()..].chars().next();
        matches!(before, None | Some(' ') | Some('/')) && matches!(after, None | Some(' '))
    })
}

pub use phri_runtime::cputime::cpu_time_ns;

/// Why a service binary cannot be run.
#[derive(Debug, thiserror::Error)]
pub enum BinaryError {
    /// no file at the path (or the path cannot be read)
    #[error("not found")]
    Missing,
    /// the path is a directory or another non-regular file
    #[error("not a regular file")]
    NotAFile,
    /// this process may not execute it: its permission bits (mode & 0o7777)
    #[error("not executable (mode {0:o})")]
    NotExecutable(u32),
}

/// `path` is a regular file this process may execute.
pub fn check_executable(path: &Path) -> Result<(), BinaryError> {
    use std::os::unix::ffi::OsStrExt;
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(_) => return Err(BinaryError::Missing),
    };
    if !meta.is_file() {
        return Err(BinaryError::NotAFile);
    }
    let mode = meta.mode() & 0o7777;
    let Ok(c) = std::ffi::CString::new(path.as_os_str().as_bytes()) else {
        return Err(BinaryError::Missing);
    };
    // SAFETY: access(2) on a NUL-terminated path. As root, X_OK succeeds if
    // any execute bit is set: the mode is checked as well.
    let may = unsafe { libc::access(c.as_ptr(), libc::X_OK) } == 0;
    if !may || mode & 0o111 == 0 {
        return Err(BinaryError::NotExecutable(mode));
    }
    Ok(())
}

/// How this run starts its services: where the binaries are, what every
/// service is told (configuration, prefix, its name, the cell's clock, the
/// run directory).
#[derive(Clone, Debug)]
pub struct Launch {
    /// directory of the service binaries (the supervisor's own)
    pub bin_dir: PathBuf,
    /// the merged configuration (`<run-dir>/config.toml`)
    pub config: PathBuf,
    /// iceoryx2 prefix of the run
    pub prefix: String,
    /// when the cell started [ns, CLOCK_MONOTONIC]
    pub cell_start_ns: u64,
    /// run directory (state files, the simulator's last state)
    pub run_dir: PathBuf,
}

impl Launch {
    /// The command that starts service `name`: `BINARY --config C --prefix P
    /// --name NAME --rt-priority N ARGS...`, with the cell's start, the
    /// run directory and [`phri_runtime::service::SUPERVISED_ENV`] (its
    /// dead-man) in its environment, in its own process group (a
    /// terminal's Ctrl-C reaches the supervisor only, which stops the rest in
    /// order), pinned to `spec.cpus` (those this machine has).
    pub fn command(&self, name: &str, spec: &ServiceSpec) -> Command {
        use std::os::unix::process::CommandExt;
        let mut cmd = Command::new(self.bin_dir.join(&spec.binary));
        cmd.arg("--config")
            .arg(&self.config)
            .arg("--prefix")
            .arg(&self.prefix)
            .arg("--name")
            .arg(name)
            .arg("--rt-priority")
            .arg(spec.rt_priority.to_string())
            .args(&spec.args)
            .env(
                phri_runtime::service::CELL_START_ENV,
                self.cell_start_ns.to_string(),
            )
            .env(phri_runtime::service::RUN_DIR_ENV, &self.run_dir)
            .env(phri_runtime::service::SUPERVISED_ENV, "1")
            .stdin(Stdio::null());
        cmd.process_group(0);
        let online = std::thread::available_parallelism().map_or(1, |n| n.get());
        let cpus: Vec<usize> = spec.cpus.iter().copied().filter(|&c| c < online).collect();
        if !cpus.is_empty() {
            // SAFETY: between fork and exec only async-signal-safe calls: CPU_SET on a
            // stack value and sched_setaffinity.
            unsafe {
                cmd.pre_exec(move || {
                    let mut set: libc::cpu_set_t = std::mem::zeroed();
                    for &c in &cpus {
                        libc::CPU_SET(c, &mut set);
                    }
                    libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
                    Ok(())
                });
            }
        }
        cmd
    }

    /// The command that asks service `name` whether it accepts the
    /// configuration in `config` (a private copy of the merged one): the same
    /// flags it will be started with, plus [`phri_runtime::service::CHECK_FLAG`];
    /// it builds its steps, opens no channel, and exits (0: accepted; 2 and
    /// one line on stderr: refused). Output captured.
    pub fn check_command(&self, name: &str, spec: &ServiceSpec, config: &Path) -> Command {
        let launch = Launch {
            config: config.to_path_buf(),
            ..self.clone()
        };
        let mut cmd = launch.command(name, spec);
        cmd.arg(phri_runtime::service::CHECK_FLAG)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        cmd
    }

    /// What the command line of this run's service `name` contains
    /// ([`process_matches`]): how a supervisor recognises a service it adopts.
    pub fn needles(&self, name: &str) -> [String; 2] {
        [self.run_needle(), format!("--name {name}")]
    }

    /// What the command line of every service of this run contains.
    pub fn run_needle(&self) -> String {
        format!("--prefix {}", self.prefix)
    }
}

/// A running supervised process.
pub enum Proc {
    /// a child this supervisor started
    Child(Child),
    /// adopted from a dead supervisor: its pid and what its command line must contain
    Adopted {
        /// its pid
        pid: u32,
        /// what its command line must contain (`--prefix P` of the run)
        prefix: String,
    },
}

impl Proc {
    /// The process's pid.
    pub fn pid(&self) -> u32 {
        match self {
            Proc::Child(c) => c.id(),
            Proc::Adopted { pid, .. } => *pid,
        }
    }

    /// Send signal `sig` (`libc::SIGTERM`, ...) to the process; errors are ignored.
    pub fn signal(&self, sig: i32) {
        // SAFETY: kill(2) on a pid this supervisor started or adopted after checking its command line.
        unsafe { libc::kill(self.pid() as i32, sig) };
    }

    /// `Some(how)` once the process has ended.
    pub fn try_exited(&mut self) -> Option<String> {
        match self {
            Proc::Child(c) => match c.try_wait() {
                Ok(Some(st)) => Some(status_text(st)),
                Ok(None) => None,
                Err(e) => Some(format!("lost: {e}")),
            },
            Proc::Adopted { pid, prefix } => (!process_matches(*pid, &[prefix.as_str()]))
                .then(|| "ended (adopted: exit status unknown)".to_string()),
        }
    }
}

/// The cause of a failed run in its stderr: the service's one-line error
/// (`phri-…: …`), else a panic's message (never the backtrace's notes),
/// else the last line.
pub fn cause_line(stderr: &str) -> Option<String> {
    let lines: Vec<&str> = stderr
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    if let Some(l) = lines
        .iter()
        .rev()
        .find(|l| l.starts_with("phri-") && l.contains(": "))
    {
        return Some(l.to_string());
    }
    if let Some(i) = lines.iter().position(|l| l.contains("panicked at")) {
        let message = lines.get(i + 1).filter(|m| !m.starts_with("note:"));
        return Some(match message {
            Some(m) => format!("{} {m}", lines[i]),
            None => lines[i].to_string(),
        });
    }
    lines
        .iter()
        .rev()
        .find(|l| !l.starts_with("note:") && !l.starts_with("stack backtrace"))
        .map(|l| l.to_string())
}

/// How [`status_text`] begins for a service its dead-man stopped.
pub const DEADMAN_TEXT: &str = "stopped by its dead-man";

/// How a process ended, in words: `exited with status N`, `killed by signal N`, or
/// [`DEADMAN_TEXT`] when its dead-man stopped it.
pub fn status_text(st: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (st.code(), st.signal()) {
        (Some(c), _) if c == i32::from(phri_runtime::service::DEADMAN_EXIT) => {
            format!("{DEADMAN_TEXT} (no supervisor heard; status {c})")
        }
        (Some(c), _) => format!("exited with status {c}"),
        (_, Some(s)) => format!("killed by signal {s}"),
        _ => "ended".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cause_of_a_failed_check_is_its_error_or_its_panic_not_the_backtrace() {
        let e = "2026 WARN something\nphri-sim: sim.dt_s: 1e-9 is not in [0.0001, 0.01]\n";
        assert_eq!(
            cause_line(e).unwrap(),
            "phri-sim: sim.dt_s: 1e-9 is not in [0.0001, 0.01]"
        );
        let p = "thread 'main' panicked at src/x.rs:3:5:\ncapacity overflow\nnote: run with `RUST_BACKTRACE=1` environment variable to display a backtrace\n";
        assert_eq!(
            cause_line(p).unwrap(),
            "thread 'main' panicked at src/x.rs:3:5: capacity overflow"
        );
        assert_eq!(cause_line("\n"), None);
    }

    #[test]
    fn process_matching_checks_the_command_line() {
        let me = std::process::id();
        assert!(process_matches(me, &[] as &[&str]));
        assert!(!process_matches(me, &["--prefix certainly-not-this-one"]));
        assert!(!process_matches(0, &[] as &[&str]));
        // init, "every process", and pids of other users are never matched
        assert!(!process_matches(1, &[] as &[&str]));
        assert!(!process_matches(u32::MAX, &[] as &[&str]));
    }

    #[test]
    fn cpu_time_counts_what_a_process_burns() {
        // a child of one thread that only burns CPU (this test process's
        // own threads come and go with the other tests, and an ended
        // thread's time leaves /proc's count)
        let mut child = std::process::Command::new("sh")
            .args(["-c", "while :; do :; done"])
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        let pid = child.id();
        let mut last = 0;
        let deadline = start + std::time::Duration::from_secs(20);
        while last < 50_000_000 && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(10));
            let t = cpu_time_ns(pid).unwrap();
            // never backwards, never more than one thread can burn
            assert!(t >= last, "{t} ns after {last} ns");
            assert!(
                t as u128 <= start.elapsed().as_nanos() + 10_000_000,
                "{t} ns in {:?}",
                start.elapsed()
            );
            last = t;
        }
        let _ = child.kill();
        let _ = child.wait();
        assert!(last >= 50_000_000, "{last} ns in {:?}", start.elapsed());
        assert_eq!(cpu_time_ns(0), None);
    }

    #[test]
    fn needles_match_whole_words() {
        let line = "/opt/phri/phri-control --config c --prefix p_x --name control";
        assert!(contains_words(line, "phri-control"));
        assert!(contains_words(line, "--prefix p_x"));
        assert!(!contains_words(line, "--prefix p_"));
        assert!(!contains_words(line, "--name contr"));
        assert!(contains_words(line, "--name control"));
        assert!(!contains_words(line, "control --config"));
        assert!(!contains_words(line, "hri-control"));
    }

    #[test]
    fn a_binary_must_be_an_executable_file() {
        use std::os::unix::fs::PermissionsExt;
        let d = std::env::temp_dir().join(format!("phri-sup-exec-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let f = d.join("svc");
        std::fs::write(&f, "#!/bin/sh\n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o644)).unwrap();
        let e = check_executable(&f).unwrap_err().to_string();
        assert_eq!(e, "not executable (mode 644)");
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o755)).unwrap();
        check_executable(&f).unwrap();
        assert!(matches!(check_executable(&d), Err(BinaryError::NotAFile)));
        assert!(matches!(
            check_executable(&d.join("nope")),
            Err(BinaryError::Missing)
        ));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_service_is_told_its_configuration_prefix_and_name_and_is_recognised_by_them() {
        let launch = Launch {
            bin_dir: "/opt/phri".into(),
            config: "/run/x/config.toml".into(),
            prefix: "p_".into(),
            cell_start_ns: 12,
            run_dir: "/run/x".into(),
        };
        let spec = phri_config::Config::defaults().services["repulsion1"].clone();
        let cmd = launch.command("repulsion1", &spec);
        assert_eq!(cmd.get_program(), "/opt/phri/phri-repulsion");
        let args: Vec<String> = cmd
            .get_args()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            args,
            [
                "--config",
                "/run/x/config.toml",
                "--prefix",
                "p_",
                "--name",
                "repulsion1",
                "--rt-priority",
                "22",
                "--worker",
                "1"
            ]
        );
        // the command line as /proc shows it holds what adoption looks for
        let line = format!("{} {}", cmd.get_program().to_string_lossy(), args.join(" "));
        assert!(launch
            .needles("repulsion1")
            .iter()
            .all(|n| line.contains(n.as_str())));
        assert!(!launch
            .needles("repulsion0")
            .iter()
            .all(|n| line.contains(n.as_str())));
        let env: Vec<(String, String)> = cmd
            .get_envs()
            .filter_map(|(k, v)| Some((k.to_str()?.into(), v?.to_str()?.into())))
            .collect();
        assert!(env.contains(&(phri_runtime::service::CELL_START_ENV.into(), "12".into())));
        assert!(env.contains(&(phri_runtime::service::RUN_DIR_ENV.into(), "/run/x".into())));
        assert!(env.contains(&(phri_runtime::service::SUPERVISED_ENV.into(), "1".into())));
        // the check runs the same command on another file, with --check
        let check = launch.check_command("repulsion1", &spec, Path::new("/run/x/.check.toml"));
        let cargs: Vec<String> = check
            .get_args()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        assert_eq!(cargs[1], "/run/x/.check.toml");
        assert_eq!(cargs[2..args.len()], args[2..]);
        assert_eq!(cargs.last().map(String::as_str), Some("--check"));
    }
}
