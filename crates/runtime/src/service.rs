//! What a service binary does before its loop: arguments, configuration,
//! shutdown handlers, real-time scheduling, and one-line errors.

use std::path::PathBuf;
use std::process::ExitCode;

use phri_config::{Config, ConfigError, Loaded, Scenario};
use phri_ipc::{IpcError, IpcNode};

use crate::cli::ServiceFlags;
use crate::Shutdown;

/// Why a service could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error(transparent)]
    Ipc(#[from] IpcError),
    #[error("signal handlers: {0}")]
    Signals(std::io::Error),
    #[error("--config {0}")]
    Untrusted(#[from] crate::rundir::TrustError),
}

/// Everything a service's `main` needs.
pub struct ServiceContext {
    /// service name as the supervisor knows it
    pub name: String,
    /// the configuration (`--config` file plus `--set`s), typed and checked
    pub loaded: Loaded,
    /// iceoryx2 prefix of this run
    pub prefix: String,
    /// SCHED_FIFO priority (0: normal scheduler)
    pub rt_priority: i32,
    pub shutdown: Shutdown,
    /// the command line's shared flags
    pub flags: ServiceFlags,
}

/// Environment variable the supervisor sets for every service: when the cell
/// started [ns, CLOCK_MONOTONIC]. A restarted simulator continues the
/// scenario's clock from it instead of replaying the scenario from the start.
pub const CELL_START_ENV: &str = "PHRI_CELL_START_NS";

/// Environment variable the supervisor sets for every service: the run
/// directory (state files, report). A restarted simulator finds the arm's
/// last state there.
pub const RUN_DIR_ENV: &str = "PHRI_RUN_DIR";

/// Environment variable the supervisor sets for every service it starts: the
/// service is supervised, and stops safely (the dead-man) when no supervisor
/// of its cell has published `supervisor/health` for `[supervisor] deadman_s`.
pub const SUPERVISED_ENV: &str = "PHRI_SUPERVISED";

/// Environment variable giving the iceoryx2 prefix when `--prefix` is absent.
pub const PREFIX_ENV: &str = "PHRI_PREFIX";

/// The prefix used when neither `--prefix` nor [`PREFIX_ENV`] gives one.
pub const DEFAULT_PREFIX: &str = "phri_";

/// The cell's prefix: `given` (a `--prefix`), else [`PREFIX_ENV`] when set
/// and not empty, else [`DEFAULT_PREFIX`]: a second terminal needs no flag.
pub fn prefix_or_default(given: Option<&str>) -> String {
    given
        .map(str::to_string)
        .or_else(|| std::env::var(PREFIX_ENV).ok().filter(|p| !p.is_empty()))
        .unwrap_or_else(|| DEFAULT_PREFIX.to_string())
}

/// How a user attaches the monitor (`monitor`: the command that runs
/// `phri-monitor`, e.g. its path) to the cell of `prefix`: `MONITOR top`,
/// with `PHRI_PREFIX=…` in front unless it is the default.
pub fn attach_hint(prefix: &str, monitor: &str) -> String {
    if prefix == DEFAULT_PREFIX {
        format!("{monitor} top")
    } else {
        format!("PHRI_PREFIX={prefix} {monitor} top")
    }
}

/// The run directory from [`RUN_DIR_ENV`], if set and not empty.
pub fn run_dir() -> Option<PathBuf> {
    std::env::var_os(RUN_DIR_ENV)
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
}

/// The cell's start time from [`CELL_START_ENV`], if set, valid and not in the future.
pub fn cell_start_ns() -> Option<u64> {
    let t = std::env::var(CELL_START_ENV)
        .ok()?
        .trim()
        .parse::<u64>()
        .ok()?;
    (t <= crate::now_ns()).then_some(t)
}

/// Switch every service accepts: build everything from the configuration,
/// check it, and exit (0: it would run; 2 and one line: what it refuses),
/// opening no channel. The supervisor runs it for every service before it
/// starts any.
pub const CHECK_FLAG: &str = "--check";

impl ServiceContext {
    /// Parse the process arguments (the flags every service takes, and the
    /// service's own `E`) and load the configuration. `bin` names the binary
    /// (help, errors), `default_name` is the service's node name unless
    /// `--name` gives one. `--help`, `--version`, `completions` and a refused
    /// flag exit here (see [`crate::cli`]).
    pub fn from_cli<E: clap::Args + clap::FromArgMatches>(
        bin: &'static str,
        default_name: &str,
        about: &'static str,
    ) -> Result<(ServiceContext, E), ServiceError> {
        let (flags, extra) = crate::cli::parse_service::<E>(bin, about);
        Ok((ServiceContext::from_flags(default_name, flags)?, extra))
    }

    /// The context of parsed [`ServiceFlags`]: loads and checks the configuration.
    pub fn from_flags(
        default_name: &str,
        flags: ServiceFlags,
    ) -> Result<ServiceContext, ServiceError> {
        // settings that another user could write are never read
        crate::rundir::check_trusted_file(&flags.config)?;
        let sets: Vec<&str> = flags.set.iter().map(String::as_str).collect();
        let loaded = Loaded::load(&flags.config, None, &sets)?;
        let prefix = flags.prefix();
        let shutdown = Shutdown::install().map_err(ServiceError::Signals)?;
        let name = flags
            .name
            .clone()
            .unwrap_or_else(|| default_name.to_string());
        crate::log::set_service(&name);
        Ok(ServiceContext {
            name,
            loaded,
            prefix,
            rt_priority: flags.rt_priority,
            shutdown,
            flags,
        })
    }

    /// Started with [`CHECK_FLAG`]: the service returns (exit 0) once its
    /// steps are built from the configuration, before it opens any channel.
    pub fn checking(&self) -> bool {
        self.flags.check
    }

    /// Start the dead-man when supervised ([`SUPERVISED_ENV`]): a thread at
    /// normal priority (call it before [`ServiceContext::go_realtime`]) that
    /// requests shutdown once no supervisor of this cell has published
    /// `supervisor/health` for `[supervisor] deadman_s` (a supervisor that
    /// died and was not replaced). Unsupervised, it does nothing.
    pub fn start_deadman(&self) -> Result<(), IpcError> {
        if std::env::var_os(SUPERVISED_ENV).is_none() {
            return Ok(());
        }
        let (node_name, prefix) = (format!("{}-deadman", self.name), self.prefix.clone());
        let limit_ns = (self.config().supervisor.deadman_s * 1e9) as u64;
        let shutdown = self.shutdown.clone();
        let (ready, started) = std::sync::mpsc::channel::<Result<(), IpcError>>();
        std::thread::spawn(move || {
            // the node and its port live on this thread (iceoryx2 ports are not Send)
            let opened = phri_ipc::node(&node_name, &prefix).and_then(|node| {
                let sub = phri_ipc::SUPERVISOR_HEALTH.subscriber(&node, phri_ipc::Queue::Latest)?;
                Ok((node, sub))
            });
            let (_node, health) = match opened {
                Ok(x) => {
                    let _ = ready.send(Ok(()));
                    x
                }
                Err(e) => {
                    let _ = ready.send(Err(e));
                    return;
                }
            };
            let mut last = crate::now_ns();
            while !shutdown.requested() {
                std::thread::sleep(std::time::Duration::from_millis(100));
                let now = crate::now_ns();
                if matches!(health.latest(), Ok(Some(_))) {
                    last = now;
                }
                if now.saturating_sub(last) > limit_ns {
                    tracing::warn!(
                        "no supervisor has published supervisor/health for {:.1} s: stopping safely (dead-man)",
                        now.saturating_sub(last) as f64 * 1e-9
                    );
                    shutdown.request();
                }
            }
        });
        started.recv().unwrap_or(Ok(()))?;
        Ok(())
    }

    /// The typed configuration.
    pub fn config(&self) -> &Config {
        &self.loaded.config
    }

    /// The scenario the cell runs.
    pub fn scenario(&self) -> &Scenario {
        &self.loaded.scenario
    }

    /// The robot model of `[robot] urdf`, checked against the configuration
    /// and the messages' joint capacity.
    pub fn robot_model(&self) -> Result<phri_model::Model, ConfigError> {
        self.loaded.model()
    }

    /// This service's iceoryx2 node under the run's prefix.
    pub fn node(&self) -> Result<IpcNode, IpcError> {
        phri_ipc::node(&self.name, &self.prefix)
    }

    /// A second node (for a helper thread) named `<name>-<suffix>`.
    pub fn node_named(&self, suffix: &str) -> Result<IpcNode, IpcError> {
        phri_ipc::node(&format!("{}-{suffix}", self.name), &self.prefix)
    }

    /// The mailbox through which a real-time loop logs (at `warn`): the
    /// events are formatted and written by a thread at normal priority,
    /// started here (call it before [`ServiceContext::go_realtime`]), that
    /// ends with the service.
    pub fn deferred_log<T: std::fmt::Display + Send + 'static>(&self) -> crate::log::Deferred<T> {
        let shutdown = self.shutdown.clone();
        let (mailbox, _thread) = crate::log::deferred(
            64,
            std::time::Duration::from_millis(50),
            move || !shutdown.requested(),
            crate::log::warn,
        );
        mailbox
    }

    /// Switch to SCHED_FIFO if configured and permitted; say what happened
    /// on stderr. Supervised, the supervisor says it once for the cell (and
    /// reports the run degraded): the service's own line is a debug line.
    pub fn go_realtime(&self) {
        if self.rt_priority > 0 {
            if let Err(e) = crate::rt::make_realtime(self.rt_priority) {
                if std::env::var_os(SUPERVISED_ENV).is_some() {
                    tracing::debug!("{e}; running under {}", crate::rt::policy());
                } else {
                    tracing::warn!("{e}; running under {}", crate::rt::policy());
                }
            }
        }
    }
}

/// Run a service body; print its error as one line and exit non-zero.
/// Logging ([`crate::log::init`]) runs for the body's time; its lines are
/// flushed before the error line, which stays the last one.
pub fn run<E: std::fmt::Display>(
    name: &'static str,
    body: impl FnOnce() -> Result<(), E>,
) -> ExitCode {
    let log = crate::log::init(name);
    let result = body();
    // the body's loop may have run at real-time priority: the log writer's
    // flush below waits for a thread at normal priority on the same CPU
    crate::rt::make_normal();
    drop(log);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let line = e.to_string().replace('\n', " ");
            eprintln!("{name}: {line}");
            ExitCode::from(2)
        }
    }
}
