//! What a service binary does before its loop: arguments, configuration,
//! shutdown handlers, real-time scheduling, and one-line errors.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use phri_config::{Config, ConfigError, Loaded, Scenario};
use phri_ipc::{IpcError, IpcNode, Zeroed};

use crate::cli::ServiceFlags;
use crate::Shutdown;

/// Why a service could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// the configuration could not be loaded or was refused
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// an iceoryx2 node or port could not be opened
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// the SIGINT / SIGTERM handlers could not be installed
    #[error("signal handlers: {0}")]
    Signals(std::io::Error),
    /// the `--config` file is not one this user can trust
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
    /// set on SIGINT / SIGTERM, or by the dead-man; the service's loop ends then
    pub shutdown: Shutdown,
    /// the command line's shared flags
    pub flags: ServiceFlags,
    /// who may publish the owned channels this service reads (filled from
    /// `supervisor/health` by the supervision thread when supervised)
    owners: Arc<phri_ipc::OwnerTable>,
    /// publish what the owned channels refused (`audit/inputs`)
    audit: AtomicBool,
}

/// Exit status of a service that stopped because no supervisor was heard
/// for `[supervisor] deadman_s` (the dead-man): the supervisor does not
/// restart it until an operator resumes the cell.
pub const DEADMAN_EXIT: u8 = 3;

/// Set once the dead-man has stopped this process.
static DEADMAN_FIRED: AtomicBool = AtomicBool::new(false);

/// How often the supervision thread reads `supervisor/health` (the owners
/// of the owned channels follow restarts this fast) [ms].
const SUPERVISION_POLL_MS: u64 = 5;

/// How long [`ServiceContext::start_deadman`] waits for the supervisor's
/// first health, so the owners of the inputs are known before the loop
/// starts [ms].
const FIRST_HEALTH_MS: u64 = 500;

/// How often the supervision thread publishes `audit/inputs` [ms].
const AUDIT_PERIOD_MS: u64 = 500;

/// The configured services as owners of channels: name, binary, worker number.
fn roles(config: &Config) -> Vec<phri_ipc::ServiceRole> {
    config
        .services
        .iter()
        .filter(|(_, s)| s.enabled)
        .map(|(name, s)| phri_ipc::ServiceRole {
            name: name.clone(),
            binary: s.binary.clone(),
            worker: phri_ipc::owners::worker_of(&s.args),
        })
        .collect()
}

/// `pid` is a supervisor of the cell of `prefix`: the parent that started
/// this service, or (after a takeover) a `phri-supervisor` of this prefix.
fn is_supervisor(pid: i32, prefix: &str) -> bool {
    if pid <= 0 {
        return false;
    }
    // SAFETY: getppid cannot fail
    if pid == unsafe { libc::getppid() } {
        return true;
    }
    let Ok(raw) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
        return false;
    };
    let args: Vec<&[u8]> = raw.split(|&b| b == 0).collect();
    let is_sup = args
        .first()
        .is_some_and(|a| a.ends_with(b"phri-supervisor"));
    let ours = args
        .windows(2)
        .any(|w| w[0] == b"--prefix" && w[1] == prefix.as_bytes());
    // without --prefix it runs the prefix of its environment (PHRI_PREFIX)
    let unnamed = !args.iter().any(|a| *a == b"--prefix");
    is_sup && (ours || unnamed)
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

/// Environment variable the supervisor sets (to `1`) for a service it starts
/// again in the same cell (after a crash, a freeze, a dead-man stop): a
/// restarted controller ends whatever collaboration its predecessor ran
/// and holds while a hand is at the robot.
pub const RESTARTED_ENV: &str = "PHRI_RESTARTED";

/// This process is a service started again in its cell ([`RESTARTED_ENV`]).
pub fn restarted() -> bool {
    std::env::var_os(RESTARTED_ENV).is_some_and(|v| v == "1")
}

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
        // settings that another user could write are never read: the file
        // (a regular one: a FIFO is refused, not waited on) and every
        // directory above it (phri-config's rule, which the loader applies
        // to the robot file, the scenario and the URDF it pulls in as well)
        phri_config::trust::check_file(&flags.config).map_err(ConfigError::from)?;
        let sets: Vec<&str> = flags.set.iter().map(String::as_str).collect();
        let loaded = Loaded::load(&flags.config, None, &sets)?;
        let prefix = flags.prefix();
        let shutdown = Shutdown::install().map_err(ServiceError::Signals)?;
        let name = flags
            .name
            .clone()
            .unwrap_or_else(|| default_name.to_string());
        crate::log::set_service(&name);
        let supervised = std::env::var_os(SUPERVISED_ENV).is_some();
        let owners = Arc::new(phri_ipc::OwnerTable::new(roles(&loaded.config), supervised));
        Ok(ServiceContext {
            name,
            loaded,
            prefix,
            rt_priority: flags.rt_priority,
            shutdown,
            flags,
            owners,
            audit: AtomicBool::new(false),
        })
    }

    /// Started with [`CHECK_FLAG`]: the service returns (exit 0) once its
    /// steps are built from the configuration, before it opens any channel.
    pub fn checking(&self) -> bool {
        self.flags.check
    }

    /// The owners of the channels a safety decision reads (see
    /// [`phri_ipc::owners`]); this service publishes what its readers
    /// refused on `audit/inputs` (call it before [`ServiceContext::start_deadman`]).
    pub fn watch_inputs(&self) -> Arc<phri_ipc::OwnerTable> {
        self.audit.store(true, Ordering::Relaxed);
        Arc::clone(&self.owners)
    }

    /// Start the supervision thread when supervised ([`SUPERVISED_ENV`]), at
    /// normal priority (call it before [`ServiceContext::go_realtime`]). It
    /// reads `supervisor/health`, from the supervisor only (the parent that
    /// started this service, or a supervisor of this prefix that took the
    /// cell over): the pid of each service fills the owners of the owned
    /// channels; when no supervisor has published for `[supervisor]
    /// deadman_s` (one that died and was not replaced) it requests shutdown
    /// and the process exits with [`DEADMAN_EXIT`] (the dead-man). It
    /// publishes `audit/inputs` when [`ServiceContext::watch_inputs`] was
    /// called. Unsupervised, it does nothing.
    pub fn start_deadman(&self) -> Result<(), IpcError> {
        if std::env::var_os(SUPERVISED_ENV).is_none() {
            return Ok(());
        }
        let (node_name, prefix) = (format!("{}-deadman", self.name), self.prefix.clone());
        let limit_ns = (self.config().supervisor.deadman_s * 1e9) as u64;
        let shutdown = self.shutdown.clone();
        let owners = Arc::clone(&self.owners);
        let audit = self.audit.load(Ordering::Relaxed);
        let service = self.name.clone();
        let (ready, started) = std::sync::mpsc::channel::<Result<(), IpcError>>();
        std::thread::spawn(move || {
            // the node and its port live on this thread (iceoryx2 ports are not Send)
            // the supervisor beats on its liveness service with each health:
            // this thread sleeps until then, the dead-man's deadline or the
            // audit's tick (without one, it reads health every few ms)
            let deadline = std::time::Duration::from_nanos(limit_ns.max(1));
            let opened = phri_ipc::node(&node_name, &prefix).and_then(|node| {
                let sub = phri_ipc::SUPERVISOR_HEALTH.subscriber(&node, phri_ipc::Queue::Drain)?;
                let more =
                    phri_ipc::SUPERVISOR_HEALTH_MORE.subscriber(&node, phri_ipc::Queue::Drain)?;
                let audits = if audit {
                    Some(phri_ipc::INPUT_AUDIT.publisher(&node)?)
                } else {
                    None
                };
                let watched: Vec<phri_ipc::liveness::Watched> = phri_ipc::liveness::Watched::open(
                    &node,
                    phri_ipc::liveness::SUPERVISOR,
                    deadline,
                )?
                .into_iter()
                .collect();
                let waitset = phri_ipc::liveness::waitset()?;
                Ok((node, [sub, more], audits, watched, waitset))
            });
            let (_node, health, audits, watched, waitset) = match opened {
                Ok(x) => x,
                Err(e) => {
                    let _ = ready.send(Err(e));
                    return;
                }
            };
            let tick_ms = if watched.is_empty() {
                SUPERVISION_POLL_MS
            } else {
                AUDIT_PERIOD_MS
            };
            let vigil = match phri_ipc::liveness::Vigil::new(
                &waitset,
                &watched,
                std::time::Duration::from_millis(tick_ms),
            ) {
                Ok(v) => v,
                Err(e) => {
                    let _ = ready.send(Err(e));
                    return;
                }
            };
            let mut last = crate::now_ns();
            let mut supervisor = Trusted::default();
            // the first health before the service's loop starts: its inputs'
            // owners are known from its first sample on
            let first_by = last + FIRST_HEALTH_MS * 1_000_000;
            let mut first = true;
            let mut told_dead = false;
            let mut report = phri_ipc::InputAudit::zeroed();
            report.service = phri_ipc::json::to_c_str(&service);
            let mut next_audit = last;
            while !shutdown.requested() {
                if first && watched.is_empty() {
                    std::thread::sleep(std::time::Duration::from_millis(1));
                } else {
                    let timeout = if first { 1 } else { tick_ms };
                    if supervisor_gone(&vigil, &watched, timeout) && !told_dead {
                        told_dead = true;
                        tracing::warn!(
                            "the supervisor's node is gone (iceoryx2): the dead-man stops this service in {:.1} s unless another supervisor takes the cell over",
                            limit_ns as f64 * 1e-9
                        );
                    }
                }
                let now = crate::now_ns();
                let newest = read_health(&health, &mut supervisor, &prefix, &owners);
                if newest.is_some() {
                    last = now;
                    told_dead = false;
                }
                if first {
                    if newest.is_none() && now <= first_by {
                        continue;
                    }
                    first = false;
                    let _ = ready.send(Ok(()));
                }
                if now.saturating_sub(last) > limit_ns {
                    tracing::warn!(
                        "no supervisor has published supervisor/health for {:.1} s: stopping safely (dead-man)",
                        now.saturating_sub(last) as f64 * 1e-9
                    );
                    DEADMAN_FIRED.store(true, Ordering::Relaxed);
                    shutdown.request();
                }
                if let Some(p) = &audits {
                    if now >= next_audit {
                        next_audit = now + AUDIT_PERIOD_MS * 1_000_000;
                        fill_audit(&mut report, &owners, now);
                        let _ = p.publish(&report);
                    }
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

    /// This service's liveness beats (`liveness/<name>`, which the
    /// supervisor watches with the service's deadline, its
    /// `heartbeat_timeout_ms`): its loop calls
    /// [`phri_ipc::liveness::Beat::beat`] every iteration. Unsupervised, or
    /// not watched (no `heartbeat`), the beats do nothing.
    pub fn beat(&self, node: &IpcNode) -> Result<phri_ipc::liveness::Beat, IpcError> {
        if std::env::var_os(SUPERVISED_ENV).is_none() {
            return Ok(phri_ipc::liveness::Beat::none());
        }
        let config = self.config();
        let ms = config
            .services
            .get(&self.name)
            .and_then(|s| s.heartbeat_timeout_ms)
            .unwrap_or(config.supervisor.heartbeat_timeout_ms);
        phri_ipc::liveness::Beat::open(node, &self.name, std::time::Duration::from_millis(ms))
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
        Ok(()) if DEADMAN_FIRED.load(Ordering::Relaxed) => ExitCode::from(DEADMAN_EXIT),
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let line = e.to_string().replace('\n', " ");
            eprintln!("{name}: {line}");
            ExitCode::from(2)
        }
    }
}

/// The supervisor whose `supervisor/health` a service trusts: the first
/// sender that is this cell's supervisor; the last sender refused (one
/// warning per stranger).
#[derive(Default)]
struct Trusted {
    pid: Option<i32>,
    refused_pid: i32,
}

/// Waits up to `timeout_ms` for the supervisor's liveness pulses (the
/// first of `watched`): whether one said its node is gone.
fn supervisor_gone(
    vigil: &phri_ipc::liveness::Vigil<'_>,
    watched: &[phri_ipc::liveness::Watched],
    timeout_ms: u64,
) -> bool {
    let mut dead = false;
    let _ = vigil.wait(std::time::Duration::from_millis(timeout_ms), |w| {
        if let phri_ipc::liveness::Wake::Pulse(0) = w {
            let _ = watched[0].take(|p| {
                dead |= p != phri_ipc::liveness::Pulse::Beat;
            });
        }
    });
    dead
}

/// The newest `supervisor/health` of the trusted supervisor of the cell of
/// `prefix`, read into `owners` (every service's pid, 0 when dead) from
/// both pages (the first services, and those past them); the first page's.
fn read_health(
    pages: &[phri_ipc::Subscriber<phri_ipc::Health>; 2],
    trusted: &mut Trusted,
    prefix: &str,
    owners: &phri_ipc::OwnerTable,
) -> Option<phri_ipc::Health> {
    let mut newest: [Option<phri_ipc::Health>; 2] = [None, None];
    for (page, sub) in newest.iter_mut().zip(pages) {
        let _ = sub.drain_from(|pid, h| {
            if trusted.pid == Some(pid) || is_supervisor(pid, prefix) {
                trusted.pid = Some(pid);
                *page = Some(*h);
            } else if trusted.refused_pid != pid {
                trusted.refused_pid = pid;
                tracing::warn!(
                    "supervisor/health from pid {pid}, not this cell's supervisor: ignored"
                );
            }
        });
    }
    for (k, h) in newest.iter().enumerate() {
        let Some(h) = h else { continue };
        let listed = (h.count as usize)
            .saturating_sub(k * phri_ipc::MAX_SERVICES)
            .min(h.services.len());
        for s in &h.services[..listed] {
            owners.set_pid(s.name_str(), if s.alive != 0 { s.pid } else { 0 });
        }
    }
    newest[0]
}

/// `audit/inputs`' next report at `now` \[ns\]: what each owned channel
/// refused, and the last stranger's pid.
fn fill_audit(report: &mut phri_ipc::InputAudit, owners: &phri_ipc::OwnerTable, now: u64) {
    report.seq += 1;
    report.stamp_ns = now;
    for (k, (name, _)) in phri_ipc::owners::PUBLISHERS.iter().enumerate() {
        if let Some(c) = phri_ipc::Owned::of(name) {
            let (counts, pid) = owners.refused(c);
            report.refused[k] = counts;
            report.stranger_pid[k] = pid;
        }
    }
}
