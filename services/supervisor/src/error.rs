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
    /// `--duration` is not a positive number of seconds of at most
    /// [`phri_config::scenario::MAX_DURATION_S`]
    #[error("--duration: must be a positive number of seconds, at most 1e7 (116 days)")]
    Duration,
    /// a service's binary is not in the directory of the service binaries
    #[error("[services.{service}] binary '{binary}' not found in {} (build with: cargo build --release)", dir.display())]
    MissingBinary {
        /// the service, as named in `[services.NAME]`
        service: String,
        /// its binary's file name
        binary: String,
        /// the directory it was looked for in (the supervisor's own)
        dir: PathBuf,
    },
    /// a service's binary is there but cannot be run
    #[error("[services.{service}] binary {}: {reason}", path.display())]
    BadBinary {
        /// the service, as named in `[services.NAME]`
        service: String,
        /// the binary's path
        path: PathBuf,
        /// why it cannot be run (not a regular file, not executable)
        reason: String,
    },
    /// the service, run with `--check` on the merged configuration, refused it
    #[error("[services.{service}] refuses the configuration: {line}")]
    Refused {
        /// the service, as named in `[services.NAME]`
        service: String,
        /// the service's one-line reason (or why its check did not finish)
        line: String,
    },
    /// a service's binary could not be started (to run, or to check its
    /// configuration)
    #[error("[services.{service}]: cannot start {binary}: {source}")]
    Spawn {
        /// the service, as named in `[services.NAME]`
        service: String,
        /// its binary's file name
        binary: String,
        /// the error of the spawn
        source: std::io::Error,
    },
    /// a file or directory of the run (run directory, merged configuration, report)
    #[error("{}: {source}", path.display())]
    Io {
        /// the file or directory
        path: PathBuf,
        /// the error of the operation on it
        source: std::io::Error,
    },
    /// the report file of `--report`
    #[error("--report {}: {source}", path.display())]
    Report {
        /// the report file
        path: PathBuf,
        /// the error of opening or writing it
        source: std::io::Error,
    },
    /// the run directory, or a state file in it, is not private to this user
    #[error("{0}")]
    Untrusted(#[from] phri_runtime::rundir::TrustError),
    /// a state file of the run directory cannot be used
    #[error(transparent)]
    State(#[from] crate::state::StateError),
    /// another supervisor lives and runs the cell of this prefix
    #[error("a supervisor (pid {pid}) already runs the cell of prefix {prefix} (run directory {run_dir}): nothing was started or written")]
    AlreadyRunning {
        /// the other supervisor's pid
        pid: u32,
        /// iceoryx2 prefix of the cell
        prefix: String,
        /// the other supervisor's run directory (as displayed)
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
    /// iceoryx2: the node, a port or a channel could not be opened or used
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// the SIGINT and SIGTERM handlers could not be installed
    #[error("signal handlers: {0}")]
    Signals(std::io::Error),
    /// this executable's own path (the services are looked up beside it)
    #[error("current executable: {0}")]
    CurrentExe(std::io::Error),
}
