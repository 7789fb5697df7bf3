//! Other processes as `/proc` shows them: alive, their command line, the
//! run directory another supervisor uses.

use phri_runtime::rundir::default_run_dir;

/// `pid` exists and is not a zombie.
pub fn alive(pid: i32) -> bool {
    // SAFETY: signal 0 only probes the pid
    let exists = pid > 0
        && (unsafe { libc::kill(pid, 0) } == 0
            || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM));
    exists
        && std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
            s.rsplit_once(')')
                .is_some_and(|(_, r)| !r.starts_with(" Z"))
        })
}

/// `pid`'s command line, shortened, for messages.
pub fn cmdline_of(pid: i32) -> String {
    let raw = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
    let line: String = String::from_utf8_lossy(&raw)
        .split('\0')
        .filter(|a| !a.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    if line.is_empty() {
        "?".into()
    } else if line.chars().count() > 120 {
        format!("{}…", line.chars().take(120).collect::<String>())
    } else {
        line
    }
}

/// The run directory another supervisor (`pid`) of `prefix` uses, from its
/// command line (else the default for the prefix).
pub fn run_dir_of(pid: i32, prefix: &str) -> String {
    let raw = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
    let text = String::from_utf8_lossy(&raw);
    let args: Vec<&str> = text.split('\0').collect();
    args.windows(2)
        .rev()
        .find(|w| w[0] == "--run-dir")
        .map(|w| w[1].to_string())
        .or_else(|| Some(default_run_dir(prefix).ok()?.display().to_string()))
        .unwrap_or_else(|| "the default".into())
}
