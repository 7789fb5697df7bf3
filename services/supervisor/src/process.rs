//! A supervised process: a child this supervisor started, or one adopted
//! from a supervisor that died (not our child: watched through /proc).

use std::process::Child;

use serde::{Deserialize, Serialize};

/// What the supervisor keeps on disk (`<run-dir>/supervisor.state`, bincode),
/// so that a supervisor started after this one died adopts the running
/// services instead of starting a second cell.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SupervisorState {
    pub version: u32,
    pub supervisor_pid: u32,
    pub prefix: String,
    /// when the cell started [ns, CLOCK_MONOTONIC]: a supervisor that takes
    /// the cell over keeps it (services get it in `PHRI_CELL_START_NS`)
    pub cell_start_ns: u64,
    pub services: Vec<ServiceState>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ServiceState {
    pub name: String,
    /// 0: not running
    pub pid: u32,
    pub restarts: u32,
}

pub const STATE_VERSION: u32 = 2;

impl SupervisorState {
    pub fn encode(&self) -> Vec<u8> {
        bincode::serde::encode_to_vec(self, bincode::config::standard()).unwrap_or_default()
    }

    /// `None` for anything that is not a state file of this version (a
    /// malformed length cannot make it allocate more than 1 MiB).
    pub fn decode(bytes: &[u8]) -> Option<SupervisorState> {
        let config = bincode::config::standard().with_limit::<{ 1 << 20 }>();
        let (s, _): (SupervisorState, usize) =
            bincode::serde::decode_from_slice(bytes, config).ok()?;
        (s.version == STATE_VERSION).then_some(s)
    }
}

/// `pid` runs (not a zombie) and its command line contains every one of `needles`.
pub fn process_matches(pid: u32, needles: &[&str]) -> bool {
    if pid == 0 {
        return false;
    }
    let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
        return false;
    };
    // state is the field after the parenthesised command name
    let state = stat
        .rsplit_once(')')
        .and_then(|(_, rest)| rest.split_whitespace().next())
        .unwrap_or("?");
    if state == "Z" || state == "X" {
        return false;
    }
    let Ok(cmdline) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
        return false;
    };
    let cmdline: String = cmdline
        .iter()
        .map(|&b| if b == 0 { ' ' } else { b as char })
        .collect();
    needles.iter().all(|n| cmdline.contains(n))
}

/// A running supervised process.
pub enum Proc {
    Child(Child),
    /// adopted from a dead supervisor: its pid and what its command line must contain
    Adopted {
        pid: u32,
        prefix: String,
    },
}

impl Proc {
    pub fn pid(&self) -> u32 {
        match self {
            Proc::Child(c) => c.id(),
            Proc::Adopted { pid, .. } => *pid,
        }
    }

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

pub fn status_text(st: std::process::ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (st.code(), st.signal()) {
        (Some(c), _) => format!("exited with status {c}"),
        (_, Some(s)) => format!("killed by signal {s}"),
        _ => "ended".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_round_trips_and_garbage_is_refused() {
        let s = SupervisorState {
            version: STATE_VERSION,
            supervisor_pid: 42,
            prefix: "p_".into(),
            cell_start_ns: 123_456_789,
            services: vec![ServiceState {
                name: "sim".into(),
                pid: 7,
                restarts: 2,
            }],
        };
        assert_eq!(SupervisorState::decode(&s.encode()), Some(s));
        assert_eq!(SupervisorState::decode(b"garbage"), None);
        assert_eq!(SupervisorState::decode(&[]), None);
        // version 2, pid 1, then a prefix that claims 2^56 bytes
        let huge = [2u8, 1, 0xfd, 0, 0, 0, 0, 0, 0, 0, 1, b'p'];
        assert_eq!(SupervisorState::decode(&huge), None);
    }

    #[test]
    fn process_matching_checks_the_command_line() {
        let me = std::process::id();
        assert!(process_matches(me, &[]));
        assert!(!process_matches(me, &["--prefix certainly-not-this-one"]));
        assert!(!process_matches(0, &[]));
    }
}
