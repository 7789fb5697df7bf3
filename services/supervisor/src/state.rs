//! What the supervisor leaves in its run directory while the cell runs:
//! `state.json` ([`StateJson`]: pids, for people and tools such as
//! `phri-fault`) and `supervisor.state` ([`SupervisorState`], bincode: what a
//! supervisor started after this one died needs to adopt the running
//! services instead of starting a second cell). Both are removed at the end
//! of the run.
//!
//! Both are written owner-only and atomically, and read only when no other
//! user can have written them ([`phri_runtime::rundir`]); the pids they hold
//! are still checked ([`crate::process::process_matches`]) before anything
//! is signalled or adopted.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use phri_runtime::rundir::{read_trusted, write_private, TrustError};
use serde::{Deserialize, Serialize};

/// File name of [`StateJson`] in the run directory.
pub const STATE_JSON: &str = "state.json";
/// File name of [`SupervisorState`] in the run directory.
pub const STATE_FILE: &str = "supervisor.state";
/// Largest state file read \[bytes\] (a cell of 64 services needs a few KiB).
pub const MAX_STATE_LEN: u64 = 1 << 20;

/// A state file that cannot be used, naming it.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    /// it cannot be read, or is not trusted: a symbolic link, another user's,
    /// writable by others, or too large
    #[error(transparent)]
    Untrusted(#[from] TrustError),
    /// it is not a state file of this version
    #[error("{}: not a state file of this version: {reason}", path.display())]
    Malformed {
        /// the state file
        path: PathBuf,
        /// the parser's error
        reason: String,
    },
}

/// `<run-dir>/state.json`:
/// `{"prefix": P, "services": {NAME: {"pid": PID|null, "restarts": N}}, "supervisor_pid": PID}`.
/// Fields are declared in name order so that the text is the same as a JSON
/// map's (keys sorted).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StateJson {
    /// iceoryx2 prefix of the run
    pub prefix: String,
    /// every supervised service by name
    pub services: BTreeMap<String, ServiceJson>,
    /// the supervisor's process id (the services are its children, unless adopted)
    pub supervisor_pid: u32,
}

/// One service in [`StateJson`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ServiceJson {
    /// process id; `null` while the service is down (a restart pending)
    pub pid: Option<u32>,
    /// restarts so far
    pub restarts: u32,
}

impl StateJson {
    /// Where it lies in `run_dir`.
    pub fn path(run_dir: &Path) -> PathBuf {
        run_dir.join(STATE_JSON)
    }

    /// The file's text (compact JSON).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Parse the file's text.
    pub fn from_json(text: &str) -> Result<StateJson, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The file in `run_dir`, if there is one and it is trusted.
    pub fn read(run_dir: &Path) -> Result<Option<StateJson>, StateError> {
        let path = Self::path(run_dir);
        let Some(bytes) = read_trusted(&path, MAX_STATE_LEN)? else {
            return Ok(None);
        };
        let text = String::from_utf8_lossy(&bytes);
        Self::from_json(&text)
            .map(Some)
            .map_err(|e| StateError::Malformed {
                path,
                reason: e.to_string(),
            })
    }

    /// Replace the file in `run_dir` (owner-only, atomically).
    pub fn write(&self, run_dir: &Path) -> Result<(), TrustError> {
        write_private(&Self::path(run_dir), self.to_json().as_bytes())
    }
}

/// `<run-dir>/supervisor.state` (bincode), so that a supervisor started after
/// this one died adopts the running services instead of starting a second cell.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SupervisorState {
    /// format version of the file ([`STATE_VERSION`]); another is not read
    pub version: u32,
    /// the process id of the supervisor that wrote it
    pub supervisor_pid: u32,
    /// iceoryx2 prefix of the run
    pub prefix: String,
    /// when the cell started [ns, CLOCK_MONOTONIC]: a supervisor that takes
    /// the cell over keeps it (services get it in `PHRI_CELL_START_NS`)
    pub cell_start_ns: u64,
    /// every supervised service, in start order
    pub services: Vec<ServiceState>,
}

/// One service in [`SupervisorState`].
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ServiceState {
    /// the service, as named in `[services.NAME]`
    pub name: String,
    /// 0: not running
    pub pid: u32,
    /// restarts so far
    pub restarts: u32,
}

/// Format version of [`SupervisorState`]: a file of another version is not read.
pub const STATE_VERSION: u32 = 2;

impl SupervisorState {
    /// The file's bytes (bincode, standard configuration).
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

    /// The state a supervisor of `prefix` left, if `bytes` is one: a state of
    /// another run is none of ours.
    pub fn previous(bytes: &[u8], prefix: &str) -> Option<SupervisorState> {
        Self::decode(bytes).filter(|p| p.prefix == prefix)
    }

    /// The state a supervisor of `prefix` left in `run_dir`: `Ok(None)` when
    /// there is none (or one of another run, or of another version); an
    /// error when the file is there but another user could have written it.
    pub fn read(run_dir: &Path, prefix: &str) -> Result<Option<SupervisorState>, StateError> {
        let bytes = read_trusted(&run_dir.join(STATE_FILE), MAX_STATE_LEN)?;
        Ok(bytes.and_then(|b| Self::previous(&b, prefix)))
    }

    /// Replace `supervisor.state` in `run_dir` (owner-only, atomically).
    pub fn write(&self, run_dir: &Path) -> Result<(), TrustError> {
        write_private(&run_dir.join(STATE_FILE), &self.encode())
    }

    /// When the cell started \[ns\]: the previous supervisor's start survives a
    /// takeover (if it is plausible: set and not after `now_ns`), else `now_ns`.
    pub fn cell_start_ns(previous: Option<&SupervisorState>, now_ns: u64) -> u64 {
        previous
            .map(|p| p.cell_start_ns)
            .filter(|&t| t > 0 && t <= now_ns)
            .unwrap_or(now_ns)
    }

    /// The previous run's entry for service `name`, if it had a process.
    pub fn service(&self, name: &str) -> Option<&ServiceState> {
        self.services.iter().find(|s| s.name == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> SupervisorState {
        SupervisorState {
            version: STATE_VERSION,
            supervisor_pid: 42,
            prefix: "p_".into(),
            cell_start_ns: 123_456_789,
            services: vec![ServiceState {
                name: "sim".into(),
                pid: 7,
                restarts: 2,
            }],
        }
    }

    #[test]
    fn state_round_trips_and_garbage_is_refused() {
        let s = state();
        assert_eq!(SupervisorState::decode(&s.encode()), Some(s));
        assert_eq!(SupervisorState::decode(b"garbage"), None);
        assert_eq!(SupervisorState::decode(&[]), None);
        // version 2, pid 1, then a prefix that claims 2^56 bytes
        let huge = [2u8, 1, 0xfd, 0, 0, 0, 0, 0, 0, 0, 1, b'p'];
        assert_eq!(SupervisorState::decode(&huge), None);
    }

    #[test]
    fn a_takeover_keeps_the_cell_clock_of_its_own_run_only() {
        let s = state();
        let bytes = s.encode();
        assert_eq!(SupervisorState::previous(&bytes, "q_"), None);
        let prev = SupervisorState::previous(&bytes, "p_").unwrap();
        assert_eq!(prev.service("sim").map(|s| s.pid), Some(7));
        assert_eq!(prev.service("control"), None);
        assert_eq!(
            SupervisorState::cell_start_ns(Some(&prev), 200_000_000),
            123_456_789
        );
        // a start in the future (another boot) or unset: the cell starts now
        assert_eq!(
            SupervisorState::cell_start_ns(Some(&prev), 100_000_000),
            100_000_000
        );
        let unset = SupervisorState {
            cell_start_ns: 0,
            ..prev
        };
        assert_eq!(SupervisorState::cell_start_ns(Some(&unset), 5), 5);
        assert_eq!(SupervisorState::cell_start_ns(None, 5), 5);
    }

    #[test]
    fn state_files_are_private_and_read_only_when_trusted() {
        use std::os::unix::fs::PermissionsExt;
        let d = std::env::temp_dir().join(format!("phri-sup-state-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        phri_runtime::rundir::create_private_dir(&d).unwrap();
        assert_eq!(SupervisorState::read(&d, "p_").unwrap(), None);
        assert_eq!(StateJson::read(&d).unwrap(), None);
        let s = state();
        s.write(&d).unwrap();
        let j = StateJson {
            prefix: "p_".into(),
            services: BTreeMap::new(),
            supervisor_pid: 42,
        };
        j.write(&d).unwrap();
        for f in [STATE_FILE, STATE_JSON] {
            let mode = std::fs::metadata(d.join(f)).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o600, "{f}");
        }
        assert_eq!(SupervisorState::read(&d, "p_").unwrap(), Some(s));
        assert_eq!(SupervisorState::read(&d, "q_").unwrap(), None);
        assert_eq!(StateJson::read(&d).unwrap(), Some(j));
        // a file another user could have written is refused, naming it
        for f in [STATE_FILE, STATE_JSON] {
            std::fs::set_permissions(d.join(f), std::fs::Permissions::from_mode(0o622)).unwrap();
        }
        let e = SupervisorState::read(&d, "p_").unwrap_err().to_string();
        assert!(
            e.contains(STATE_FILE) && e.contains("writable by other users"),
            "{e}"
        );
        let e = StateJson::read(&d).unwrap_err().to_string();
        assert!(e.contains(STATE_JSON), "{e}");
        std::fs::write(d.join("x"), "{").unwrap();
        std::fs::remove_file(d.join(STATE_JSON)).unwrap();
        std::fs::rename(d.join("x"), d.join(STATE_JSON)).unwrap();
        let e = StateJson::read(&d).unwrap_err().to_string();
        assert!(e.contains("not a state file"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn state_json_is_the_documented_object() {
        let mut services = BTreeMap::new();
        services.insert(
            "sim".to_string(),
            ServiceJson {
                pid: Some(7),
                restarts: 0,
            },
        );
        services.insert(
            "control".to_string(),
            ServiceJson {
                pid: None,
                restarts: 3,
            },
        );
        let s = StateJson {
            prefix: "p_".into(),
            services,
            supervisor_pid: 42,
        };
        let text = s.to_json();
        // the text a serde_json::Value with these keys gives (keys sorted)
        let v = serde_json::json!({
            "supervisor_pid": 42,
            "prefix": "p_",
            "services": {
                "sim": {"pid": 7, "restarts": 0},
                "control": {"pid": null, "restarts": 3},
            },
        });
        assert_eq!(text, v.to_string());
        assert_eq!(StateJson::from_json(&text).unwrap(), s);
        assert!(StateJson::from_json("{not json").is_err());
        assert_eq!(StateJson::path(Path::new("/r")), Path::new("/r/state.json"));
    }
}
