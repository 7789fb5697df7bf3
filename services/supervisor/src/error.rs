//! Why the supervisor refuses to start or stops: each error names the file,
//! key, flag, service or channel at fault, in one line.

use std::path::PathBuf;

use phri_config::{ConfigError, Invalid};
use phri_ipc::IpcError;

/// Everything that stops the supervisor (its binary prints it and exits 2).
#[derive(Debug, thiserror::Error)]
pub enum SupervisorError {
    /// the configuration, the scenario or the robot model (file and key named)
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// a value that does not fit the robot model (key named)
    #[error(transparent)]
    Invalid(#[from] Invalid),
    #[error("--duration: must be a positive number of seconds, at most 1e7 (116 days)")]
    Duration,
    #[error("[services.{service}] binary '{binary}' not found in {} (build with: cargo build --release)", dir.display())]
    MissingBinary {
        service: String,
        binary: String,
        dir: PathBuf,
    },
    #[error("[services.{service}] binary {}: {reason}", path.display())]
    BadBinary {
        service: String,
        path: PathBuf,
        reason: String,
    },
    /// the service, run with `--check` on the merged configuration, refused it
    #[error("[services.{service}] refuses the configuration: {line}")]
    Refused { service: String, line: String },
    #[error("[services.{service}]: cannot start {binary}: {source}")]
    Spawn {
        service: String,
        binary: String,
        source: std::io::Error,
    },
    /// a file or directory of the run (run directory, merged configuration, report)
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// the report file of `--report`
    #[error("--report {}: {source}", path.display())]
    Report {
        path: PathBuf,
        source: std::io::Error,
    },
    /// the run directory, or a state file in it, is not private to this user
    #[error("{0}")]
    Untrusted(#[from] phri_runtime::rundir::TrustError),
    #[error(transparent)]
    State(#[from] crate::state::StateError),
    #[error("a supervisor (pid {pid}) already runs the cell of prefix {prefix} (run directory {run_dir}): nothing was started or written")]
    AlreadyRunning {
        pid: u32,
        prefix: String,
        run_dir: String,
    },
    /// iceoryx2's node counter of the prefix is foreign or altered
    #[error(transparent)]
    SharedMemory(#[from] crate::shm::ShmError),
    /// `--require-rt` (or `supervisor.require_rt`) and real-time scheduling
    /// is refused here
    #[error("--require-rt: {0}; nothing was started (docs/safety.md: Real-time scheduling)")]
    RealtimeRequired(#[source] crate::realtime::Refused),
    /// the cell did not start whole: everything started was stopped
    #[error("start-up failed: {0}; everything started was stopped")]
    StartFailed(String),
    /// the run ended early or was degraded: the report says why
    #[error("the run was degraded: {0}")]
    Degraded(String),
    #[error(transparent)]
    Ipc(#[from] IpcError),
    #[error("signal handlers: {0}")]
    Signals(std::io::Error),
    /// this executable's own path (the services are looked up beside it)
    #[error("current executable: {0}")]
    CurrentExe(std::io::Error),
}
