//! `phri-supervisor`: starts the services of `[services]`, restarts what dies
//! (with back-off), kills what freezes (or what starves it), publishes
//! `supervisor/health`, shuts everything down in order on SIGINT/SIGTERM or
//! after `--duration`, leaves no process and no shared-memory file behind,
//! and writes `--report`.
//!
//! The cell starts whole or not at all: everything is checked before the
//! first process starts (the configuration, the run length, the binaries,
//! every service's acceptance of the configuration (`--check`), the report
//! file, the run directory, iceoryx2's node counter), and a start that fails
//! stops what it started. A service that crash-loops, or a process other than
//! the supervised controller publishing on `robot/command`, ends the run:
//! ordered shutdown, a report with `clean: false`, a non-zero exit.
//!
//! The decisions are the library's ([`Plan`], [`Roster`], [`cpu`], the
//! report's evaluator); this file starts, signals and reaps processes, reads
//! and publishes the channels and writes the files, every 10 ms.

use std::fs::File;
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use phri_ipc::liveness::{self, Beat, Pulse, Wake, Watched};
use phri_ipc::{
    node, FrameSubscriber, Health, IpcError, IpcNode, Publisher, Queue, Subscriber, Zeroed,
    COLLAB_STATE, CONTROL_SSM, CONTROL_STATUS, DYNAMICS_RESIDUAL, ROBOT_COMMAND,
    ROBOT_COMMAND_STANDBY, ROBOT_STATS, SIM_CONTACTS, SIM_TRUTH, SUPERVISOR_HEALTH,
};
use phri_runtime::rundir::{create_private_dir, default_run_dir, write_private};
use phri_runtime::{now_ns, Shutdown};
use phri_supervisor::cpu::{self, CpuUse};
use phri_supervisor::owned::{self, AuditLog};
use phri_supervisor::process::{cpu_time_ns, process_matches, Launch, Proc};
use phri_supervisor::realtime::{self, RealtimeWatch};
use phri_supervisor::shm::{self, SHM_DIR};
use phri_supervisor::state::{StateJson, STATE_FILE};
use phri_supervisor::verdict::{self, ExitVerdict};
use phri_supervisor::{Plan, Roster, SupervisorError, SupervisorState};

/// The supervisor's command line.
#[derive(clap::Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Starts the phri cell's services, supervises them (restarts, the dead-man, CPU use) and writes the run's report",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    /// Cell configuration (TOML)
    #[arg(long, value_name = "FILE", default_value = "deploy/phri.toml")]
    config: PathBuf,
    /// Scenario to run: a name under deploy/scenarios/ or a file
    #[arg(long, value_name = "NAME|FILE")]
    scenario: Option<String>,
    /// Stop the cell after this long [s] (default: the scenario's own length)
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Write the run's report (JSON) to this file
    #[arg(long, value_name = "FILE")]
    report: Option<String>,
    /// The arm: its robot file deploy/robots/NAME/robot.toml (lwr4, the
    /// default; fr3; panda); the same as `--set robot.name=NAME`
    #[arg(long, value_name = "NAME")]
    robot: Option<String>,
    /// Drive the arm `--robot` names over FCI at this address (host[:port]:
    /// a Franka's control box, or franka-sim) instead of simulating it: the
    /// simulator then simulates the person and the world only (the same as
    /// `--set robot.ip=ADDRESS`)
    #[arg(long, value_name = "ADDRESS")]
    robot_ip: Option<String>,
    /// Where the camera's frames come from: sim (the simulated camera, the
    /// default), freenect (a Kinect v1), ros2 (a ROS 2 depth camera, [camera]
    /// image_topic and info_topic), replay (recorded frames, [camera]
    /// replay_dir); the same as `--set camera.source=SOURCE`
    #[arg(long, value_name = "SOURCE", value_parser = ["sim", "freenect", "ros2", "replay"])]
    camera: Option<String>,
    /// Override one configuration value, e.g. `--set control.avoidance=false` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Refuse to start unless real-time scheduling (SCHED_FIFO at the
    /// services' priorities) and CPU pinning are permitted (also: `supervisor.require_rt`)
    #[arg(long)]
    require_rt: bool,
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// Run directory (state files, report) [default: one per prefix under $XDG_RUNTIME_DIR, else /tmp/phri-UID]
    #[arg(long, value_name = "DIR")]
    run_dir: Option<PathBuf>,
    #[command(subcommand)]
    completions: Option<phri_runtime::cli::CompletionsCmd>,
}

/// `--robot NAME`, `--robot-ip ADDRESS` and `--camera SOURCE` as the first
/// `--set`s (a later `--set robot.name`, `robot.ip` or `camera.source` wins).
fn robot_and_sets(
    robot: Option<&str>,
    ip: Option<&str>,
    camera: Option<&str>,
    sets: &[String],
) -> Vec<String> {
    robot
        .map(|r| format!("robot.name={r}"))
        .into_iter()
        .chain(ip.map(|a| format!("robot.ip={a}")))
        .chain(camera.map(|c| format!("camera.source=\"{c}\"")))
        .chain(sets.iter().cloned())
        .collect()
}

/// Period of the supervision loop [ns].
const TICK_NS: u64 = 10_000_000;
/// Period of the watch over who publishes on `robot/command` [ns].
const WATCH_NS: u64 = 50_000_000;
/// Period of the samples of the services' CPU time [ns].
const CPU_SAMPLE_NS: u64 = 20_000_000;
/// How long health goes out every tick after a (re)start [ns].
const FAST_HEALTH_NS: u64 = 1_000_000_000;
/// A supervision loop later than this was a stall of the supervisor itself [ns].
const STALL_NS: u64 = 100_000_000;
/// A service's `--check` must answer within this.
const CHECK_TIMEOUT: Duration = Duration::from_secs(60);

fn main() -> ExitCode {
    phri_runtime::service::run("phri-supervisor", body)
}

/// The supervisor's ports on the cell's channels.
struct Ports {
    health: Publisher<Health>,
    health_more: Publisher<Health>,
    stats: Subscriber<phri_ipc::RobotStats>,
    truth: Subscriber<phri_ipc::Truth>,
    contacts: Subscriber<phri_ipc::ContactEvent>,
    residual: Subscriber<phri_ipc::Residual>,
    status: Subscriber<phri_ipc::ControlStatus>,
    /// per camera: its frames, its ingestion's, its repulsion results
    frames: Vec<FrameSubscriber>,
    filtered: Vec<FrameSubscriber>,
    repulsion: Vec<Subscriber<phri_ipc::RepulsionResult>>,
    /// per camera: its skeletons (their latency from the frame's arrival)
    skeletons: Vec<Subscriber<phri_ipc::Skeleton>>,
    collab: Subscriber<phri_ipc::CollabState>,
    ssm: Subscriber<phri_ipc::SsmStatus>,
    requests: Subscriber<phri_ipc::HriRequest>,
    /// what the ROS 2 bridge did with `/phri/request`
    bridge_requests: Subscriber<phri_ipc::BridgeRequests>,
    /// what each camera's and the microphone's process did
    camera_status: Subscriber<phri_ipc::CameraStatus>,
    mic_status: Subscriber<phri_ipc::MicStatus>,
    utterances: Subscriber<phri_ipc::Utterance>,
    audits: Subscriber<phri_ipc::InputAudit>,
    boxes: Subscriber<phri_ipc::BoxStatus>,
    /// the adapter's takeovers
    commanders: Subscriber<phri_ipc::CommanderStats>,
    /// the supervisor's beats (`liveness/supervisor`), one with each health:
    /// what the services' dead-man watches
    beat: Beat,
    standby_residual: Subscriber<phri_ipc::Residual>,
}

impl Ports {
    fn open(node: &IpcNode, cameras: usize) -> Result<Ports, IpcError> {
        let cameras = phri_ipc::cameras(cameras);
        Ok(Ports {
            health: SUPERVISOR_HEALTH.publisher(node)?,
            health_more: phri_ipc::SUPERVISOR_HEALTH_MORE.publisher(node)?,
            stats: ROBOT_STATS.subscriber(node, Queue::Drain)?,
            truth: SIM_TRUTH.subscriber(node, Queue::Drain)?,
            contacts: SIM_CONTACTS.subscriber(node, Queue::Drain)?,
            residual: DYNAMICS_RESIDUAL.subscriber(node, Queue::Drain)?,
            status: CONTROL_STATUS.subscriber(node, Queue::Drain)?,
            frames: cameras
                .iter()
                .map(|c| c.depth.frame_subscriber(node, Queue::Latest))
                .collect::<Result<_, _>>()?,
            filtered: cameras
                .iter()
                .map(|c| c.perception.frame_subscriber(node, Queue::Latest))
                .collect::<Result<_, _>>()?,
            repulsion: cameras
                .iter()
                .map(|c| c.repulsion.subscriber(node, Queue::Drain))
                .collect::<Result<_, _>>()?,
            skeletons: cameras
                .iter()
                .map(|c| c.skeleton.subscriber(node, Queue::Drain))
                .collect::<Result<_, _>>()?,
            collab: COLLAB_STATE.subscriber(node, Queue::Drain)?,
            ssm: CONTROL_SSM.subscriber(node, Queue::Drain)?,
            requests: phri_ipc::HRI_REQUEST.subscriber(node, Queue::Drain)?,
            bridge_requests: phri_ipc::ROS2_REQUESTS.subscriber(node, Queue::Drain)?,
            camera_status: phri_ipc::CAMERA_STATUS.subscriber(node, Queue::Drain)?,
            mic_status: phri_ipc::AUDIO_MIC_STATUS.subscriber(node, Queue::Drain)?,
            utterances: phri_ipc::VOICE_UTTERANCE.subscriber(node, Queue::Drain)?,
            audits: phri_ipc::INPUT_AUDIT.subscriber(node, Queue::Drain)?,
            boxes: phri_ipc::ROBOT_BOX.subscriber(node, Queue::Drain)?,
            commanders: phri_ipc::ROBOT_COMMANDERS.subscriber(node, Queue::Drain)?,
            standby_residual: phri_ipc::DYNAMICS_RESIDUAL_STANDBY.subscriber(node, Queue::Drain)?,
            beat: Beat::create(node, liveness::SUPERVISOR)?,
        })
    }

    /// Publish the roster's health (`supervisor/health`, and
    /// `supervisor/health/more` past its first page) and beat with it (the
    /// services wake for it).
    fn publish_health(&mut self, roster: &Roster, pages: &mut [Health; 2], now_ns: u64) {
        roster.fill_health(&mut pages[0], now_ns);
        if roster.fill_health_more(&mut pages[1], now_ns) {
            let _ = self.health_more.publish(&pages[1]);
        }
        let _ = self.health.publish(&pages[0]);
        self.beat.now(now_ns);
    }
}

/// The watched services' liveness (`liveness/<service>`, each created with
/// its deadline before the service starts): the supervisor hears of beats,
/// deaths and missed deadlines through one WaitSet ([`liveness::Vigil`]).
struct Watch {
    watched: Vec<Watched>,
    /// roster index of each watched service
    index: Vec<usize>,
}

impl Watch {
    fn open(node: &IpcNode, roster: &Roster) -> Result<Watch, IpcError> {
        let (mut watched, mut index) = (Vec::new(), Vec::new());
        for (i, deadline) in roster.deadlines() {
            watched.push(Watched::create(node, &roster.get(i).name, deadline)?);
            index.push(i);
        }
        Ok(Watch { watched, index })
    }
}

/// `--report FILE`, opened (created if need be) before anything starts, so
/// that an unwritable place is refused at once. A file this run created is
/// removed again unless the report was written into it.
struct ReportFile {
    path: PathBuf,
    file: File,
    created: bool,
    written: bool,
}

impl ReportFile {
    fn open(path: Option<&str>) -> Result<Option<ReportFile>, SupervisorError> {
        let Some(path) = path else { return Ok(None) };
        let report_err = |source| SupervisorError::Report {
            path: path.into(),
            source,
        };
        let created = !Path::new(path).exists();
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(report_err)?;
        Ok(Some(ReportFile {
            path: path.into(),
            file,
            created,
            written: false,
        }))
    }

    fn write(&mut self, json: &str) -> Result<(), SupervisorError> {
        let report_err = |source| SupervisorError::Report {
            path: self.path.clone(),
            source,
        };
        self.file.set_len(0).map_err(report_err)?;
        self.file.rewind().map_err(report_err)?;
        self.file
            .write_all(json.as_bytes())
            .and_then(|_| self.file.write_all(b"\n"))
            .map_err(report_err)?;
        self.written = true;
        Ok(())
    }
}

impl Drop for ReportFile {
    fn drop(&mut self) {
        if self.created && !self.written {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// The running cell: the roster and its processes, and where its state lies.
struct Cell {
    roster: Roster,
    procs: Vec<Option<Proc>>,
    launch: Launch,
}

impl Cell {
    /// Start service `i`.
    fn spawn(&self, i: usize) -> Result<std::process::Child, SupervisorError> {
        let (name, spec) = (&self.roster.get(i).name, &self.roster.get(i).spec);
        let mut cmd = self.launch.command(name, spec);
        if self.roster.get(i).started_before() {
            cmd.env(phri_runtime::service::RESTARTED_ENV, "1");
        }
        cmd.spawn().map_err(|source| SupervisorError::Spawn {
            service: name.clone(),
            binary: spec.binary.clone(),
            source,
        })
    }

    /// `state.json` and `supervisor.state`, each replaced atomically, owner-only.
    fn write_state(&self) {
        let me = std::process::id();
        let (dir, prefix) = (&self.launch.run_dir, &self.launch.prefix);
        let written = self.roster.state_json(prefix, me).write(dir).and_then(|_| {
            self.roster
                .state(prefix, me, self.launch.cell_start_ns)
                .write(dir)
        });
        if let Err(e) = written {
            tracing::warn!("{e}");
        }
    }

    fn remove_state(&self) {
        let _ = std::fs::remove_file(StateJson::path(&self.launch.run_dir));
        let _ = std::fs::remove_file(self.launch.run_dir.join(STATE_FILE));
    }

    /// The first service of the start that has ended, and how.
    fn first_exit(&mut self) -> Option<(usize, String)> {
        self.procs
            .iter_mut()
            .enumerate()
            .find_map(|(i, p)| Some((i, p.as_mut()?.try_exited()?)))
    }

    /// Ordered shutdown in start order: the robot first (it brakes the arm as
    /// it exits), then what depends on it; SIGTERM, then SIGKILL after the
    /// grace period.
    fn stop(&mut self) {
        let grace_ns = self.roster.config().shutdown_grace_ms * 1_000_000;
        for (i, slot) in self.procs.iter_mut().enumerate() {
            let Some(mut child) = slot.take() else {
                continue;
            };
            let name = &self.roster.get(i).name;
            child.signal(libc::SIGTERM);
            let deadline = now_ns() + grace_ns;
            let mut killed = false;
            while child.try_exited().is_none() {
                if now_ns() > deadline + 2_000_000_000 {
                    tracing::warn!(
                        "{name} (pid {}) does not end even after SIGKILL",
                        child.pid()
                    );
                    break;
                }
                if now_ns() > deadline && !killed {
                    tracing::warn!("{name} ignored SIGTERM, killing it");
                    child.signal(libc::SIGKILL);
                    killed = true;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
}

/// A service's real-time process is judged no earlier than this after its
/// (re)start: it opens its ports before it asks for SCHED_FIFO [ns].
const RT_SETTLE_NS: u64 = 200_000_000;

/// A watch over each owned channel (the further cameras' too) that the
/// supervisor reads for strangers.
fn owned_watches(n_cameras: usize) -> Vec<phri_ipc::PublisherWatch> {
    use phri_ipc::*;
    let mut watches = Vec::new();
    for (name, _) in owners::PUBLISHERS {
        let watch = match *name {
            n if n == ROBOT_STATE.name => ROBOT_STATE.publisher_watch(),
            n if n == DYNAMICS_RESIDUAL.name => DYNAMICS_RESIDUAL.publisher_watch(),
            n if n == PERCEPTION_REPULSION.name => PERCEPTION_REPULSION.publisher_watch(),
            n if n == PERCEPTION_SKELETON.name => PERCEPTION_SKELETON.publisher_watch(),
            n if n == PERCEPTION_HAND.name => PERCEPTION_HAND.publisher_watch(),
            n if n == HRI_REQUEST.name => HRI_REQUEST.publisher_watch(),
            n if n == AUDIO_MIC.name => AUDIO_MIC.publisher_watch(),
            _ => continue,
        };
        watches.push(watch);
    }
    for c in CAMERAS.iter().take(n_cameras).skip(1) {
        watches.push(c.repulsion.publisher_watch());
        watches.push(c.skeleton.publisher_watch());
        watches.push(c.hand.publisher_watch());
    }
    watches
}

/// A channel the supervisor's watch could not read: logged (the first and
/// then every 100th), the channel taken as having no publisher this time.
fn watch_error(e: IpcError, count: &mut u64) -> Option<Vec<i32>> {
    *count += 1;
    if *count == 1 || count.is_multiple_of(100) {
        tracing::warn!("watch ({count} so far): {e}");
    }
    None
}

/// What `[services.*]` asks for a service: its priority and its CPUs.
fn wanted_of(spec: &phri_config::ServiceSpec) -> realtime::Wanted {
    realtime::Wanted {
        priority: spec.rt_priority,
        cpus: spec.cpus.clone(),
    }
}

/// How a user attaches the monitor from another terminal: the binary's
/// path (it is not on the PATH), with the prefix when not the default.
fn attach_hint(bin_dir: &Path, prefix: &str) -> String {
    let bin = bin_dir.join("phri-monitor");
    let shown = std::env::current_dir()
        .ok()
        .and_then(|d| bin.strip_prefix(d).ok().map(Path::to_path_buf))
        .unwrap_or(bin);
    phri_runtime::attach_hint(prefix, &shown.display().to_string())
}

/// Drop the supervisor's node and remove what the run left in shared memory.
fn close_ipc(node: IpcNode, ports: Option<Ports>, prefix: &str) {
    let _ = node.try_cleanup_dead_nodes();
    drop(ports);
    drop(node);
    match phri_ipc::remove_leftovers(prefix) {
        Ok(0) => {}
        Ok(n) => tracing::info!("removed {n} shared-memory files the run left"),
        Err(alive) => tracing::warn!("{alive} node(s) of prefix {prefix} still attached (a monitor or recorder?): the last one out cleans up"),
    }
}

/// `pid` exists and is not a zombie.
fn alive(pid: i32) -> bool {
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
fn cmdline_of(pid: i32) -> String {
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
fn run_dir_of(pid: i32, prefix: &str) -> String {
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

/// Run every enabled service once with `--check` on a private copy of the
/// merged configuration, with the flags it will be started with, all at
/// once: each must accept it (exit 0) within [`CHECK_TIMEOUT`]. The first
/// refusal is returned, naming the service and quoting its line.
fn check_services(plan: &Plan, launch: &Launch) -> Result<(), SupervisorError> {
    let tmp = launch
        .run_dir
        .join(format!(".config.check.{}.toml", std::process::id()));
    write_private(&tmp, plan.merged_toml().as_bytes())?;
    let result = (|| {
        let (tx, rx) = std::sync::mpsc::channel();
        let mut pending: Vec<(String, u32)> = Vec::new();
        let kill_pending = |pending: &[(String, u32)]| {
            for (_, pid) in pending {
                // SAFETY: kill(2) on a check process this function started
                unsafe { libc::kill(*pid as i32, libc::SIGKILL) };
            }
        };
        for (name, spec) in &plan.services {
            let child = match launch.check_command(name, spec, &tmp).spawn() {
                Ok(c) => c,
                Err(source) => {
                    kill_pending(&pending);
                    return Err(SupervisorError::Spawn {
                        service: name.clone(),
                        binary: spec.binary.clone(),
                        source,
                    });
                }
            };
            pending.push((name.clone(), child.id()));
            let (tx, name) = (tx.clone(), name.clone());
            std::thread::spawn(move || {
                let _ = tx.send((name, child.wait_with_output()));
            });
        }
        drop(tx);
        let deadline = Instant::now() + CHECK_TIMEOUT;
        while !pending.is_empty() {
            let left = deadline.saturating_duration_since(Instant::now());
            let Ok((name, out)) = rx.recv_timeout(left) else {
                kill_pending(&pending);
                return Err(SupervisorError::Refused {
                    service: pending[0].0.clone(),
                    line: format!(
                        "its --check did not finish within {} s",
                        CHECK_TIMEOUT.as_secs()
                    ),
                });
            };
            pending.retain(|(n, _)| *n != name);
            let refusal = match out {
                Ok(out) if out.status.success() => None,
                Ok(out) => {
                    let err = String::from_utf8_lossy(&out.stderr);
                    Some(
                        phri_supervisor::process::cause_line(&err)
                            .unwrap_or_else(|| phri_supervisor::process::status_text(out.status)),
                    )
                }
                Err(e) => Some(format!("its --check could not be waited for: {e}")),
            };
            if let Some(line) = refusal {
                kill_pending(&pending);
                return Err(SupervisorError::Refused {
                    service: name,
                    line,
                });
            }
        }
        Ok(())
    })();
    let _ = std::fs::remove_file(&tmp);
    result
}

fn body() -> Result<(), SupervisorError> {
    let args: Cli = phri_runtime::cli::parse("phri-supervisor");
    if let Some(phri_runtime::cli::CompletionsCmd::Completions { shell }) = args.completions {
        phri_runtime::cli::completions::<Cli>("phri-supervisor", shell);
        return Ok(());
    }
    let me = std::process::id();
    // everything is checked before anything starts: the configuration, the
    // scenario, the robot model, the run length, the binaries
    let plan = Plan::load(
        &args.config,
        args.scenario.as_deref(),
        &robot_and_sets(
            args.robot.as_deref(),
            args.robot_ip.as_deref(),
            args.camera.as_deref(),
            &args.set,
        )
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>(),
        args.duration,
    )?;
    let bin_dir = std::env::current_exe()
        .map_err(SupervisorError::CurrentExe)?
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    plan.check_binaries(&bin_dir)?;
    // real-time scheduling: permitted here, or the run is degraded (or refused)
    let require_rt = args.require_rt || plan.loaded.config.supervisor.require_rt;
    let online = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut wanted: Vec<(String, realtime::Wanted)> = plan
        .services
        .iter()
        .map(|(name, spec)| (name.clone(), wanted_of(spec)))
        .collect();
    realtime::role_ranked(&mut wanted);
    let mut rt_refusal =
        realtime::probe_services(wanted.iter().map(|(n, w)| (n.as_str(), w)), online).err();
    if let Some(why) = rt_refusal {
        if require_rt {
            return Err(SupervisorError::RealtimeRequired(why));
        }
        tracing::warn!(
            "real-time scheduling refused ({why}): the cell runs under the normal scheduler and the run will be reported degraded; docs/safety.md \"Real-time scheduling\" says how to grant it, --require-rt refuses instead"
        );
        rt_refusal = Some(why);
    }
    let mut rt_watch = RealtimeWatch::new(rt_refusal.map(|e| e.to_string()));
    // one namespace by default (PHRI_PREFIX, else phri_): tools in another
    // terminal find the cell without flags; a second cell there is refused
    let prefix = phri_runtime::prefix_or_default(args.prefix.as_deref().filter(|p| !p.is_empty()));

    // the run directory is this user's alone
    let run_dir = match &args.run_dir {
        Some(d) => d.clone(),
        None => default_run_dir(&prefix)?,
    };
    let run_dir_existed = run_dir.exists();
    create_private_dir(&run_dir)?;
    // a cell of this prefix whose supervisor lives: refused, writing nothing
    let previous = SupervisorState::read(&run_dir, &prefix)?;
    if let Some(p) = &previous {
        if p.supervisor_pid != me && process_matches(p.supervisor_pid, &["phri-supervisor"]) {
            return Err(SupervisorError::AlreadyRunning {
                pid: p.supervisor_pid,
                prefix,
                run_dir: run_dir.display().to_string(),
            });
        }
    }
    // iceoryx2's node counter of this prefix: not another user's, not altered
    shm::check_global_mgmt(Path::new(SHM_DIR), &prefix)?;
    let mut report_file = ReportFile::open(args.report.as_deref())?;
    let shutdown = Shutdown::install().map_err(SupervisorError::Signals)?;
    let mut launch = Launch {
        bin_dir,
        config: run_dir.join("config.toml"),
        prefix: prefix.clone(),
        cell_start_ns: now_ns(),
        run_dir: run_dir.clone(),
    };
    // every service accepts the configuration, with the flags it will get
    check_services(&plan, &launch)?;
    if shutdown.requested() {
        return Err(SupervisorError::StartFailed("interrupted".into()));
    }

    let node = node("supervisor", &prefix)?;
    // a supervisor of this prefix with another run directory
    if let Some(pid) = SUPERVISOR_HEALTH
        .publisher_pids(&node)?
        .unwrap_or_default()
        .into_iter()
        .find(|&p| p as u32 != me && alive(p))
    {
        // the other cell's shared memory is not ours to clean up
        drop(node);
        if !run_dir_existed {
            let _ = std::fs::remove_dir(&run_dir);
        }
        return Err(SupervisorError::AlreadyRunning {
            pid: pid as u32,
            run_dir: run_dir_of(pid, &prefix),
            prefix,
        });
    }
    // the node counter exists now: owner-only from here on
    if let Err(e) = shm::restrict_global_mgmt(Path::new(SHM_DIR), &prefix) {
        close_ipc(node, None, &prefix);
        return Err(e.into());
    }
    let mut ports = match Ports::open(&node, plan.loaded.config.cameras.len()) {
        Ok(p) => p,
        Err(e) => {
            close_ipc(node, None, &prefix);
            return Err(e.into());
        }
    };
    if let Err(e) = write_private(&launch.config, plan.merged_toml().as_bytes()) {
        close_ipc(node, Some(ports), &prefix);
        return Err(e.into());
    }
    tracing::info!("cell {prefix}, run directory {}", run_dir.display());
    tracing::info!(
        "attach from another terminal: {}",
        attach_hint(&launch.bin_dir, &prefix)
    );

    let t0 = now_ns();
    // the cell's clock survives a takeover, and the report counts from it
    let cell_start_ns = SupervisorState::cell_start_ns(previous.as_ref(), t0);
    launch.cell_start_ns = cell_start_ns;
    let mut eval = plan.evaluator(cell_start_ns);
    // a safety function switched off on purpose: every report of the run says so
    for line in plan.safety_off() {
        tracing::warn!("{line}: the run will be reported degraded");
        eval.degrade(line);
    }
    let mut audits = AuditLog::default();
    let mut box_eval = phri_supervisor::box_report::BoxEval::new(cell_start_ns);
    // (owned channel, pid) of every stranger reported, each once
    let mut strangers_seen: Vec<(&'static str, i32)> = Vec::new();
    let mut watch_errors = 0u64;
    let deadman_ns = (plan.loaded.config.supervisor.deadman_s * 1e9) as u64;
    let mut collab_eval = plan.collab_evaluator(cell_start_ns);
    let standby = plan.loaded.config.control.standby;
    let mut standby_eval = phri_supervisor::standby_report::StandbyEvaluator::new(standby);
    let mut residual_pair = phri_supervisor::standby_report::ResidualPair::new(standby);
    let reaction = plan.reaction().name();
    let mut cell = Cell {
        roster: Roster::new(plan.loaded.config.supervisor.clone(), plan.services.clone()),
        procs: Vec::with_capacity(plan.services.len()),
        launch,
    };
    let mut health = [Health::zeroed(); 2];
    // every watched service's liveness exists before it starts
    let watch = match Watch::open(&node, &cell.roster) {
        Ok(w) => w,
        Err(e) => {
            close_ipc(node, Some(ports), &prefix);
            return Err(e.into());
        }
    };

    // start (or adopt) every service in order; a start that fails stops what it started
    let mut adopted_any = false;
    let mut start_error: Option<String> = None;
    for i in 0..cell.roster.len() {
        let name = cell.roster.get(i).name.clone();
        let adopt = previous
            .as_ref()
            .and_then(|p| p.service(&name))
            .filter(|s| process_matches(s.pid, &cell.launch.needles(&name)));
        let now = now_ns();
        match adopt {
            Some(prev) => {
                tracing::info!(
                    "adopted {name} (pid {}) from the previous supervisor",
                    prev.pid
                );
                cell.roster.adopted(i, now, prev.pid, prev.restarts);
                cell.procs.push(Some(Proc::Adopted {
                    pid: prev.pid,
                    prefix: cell.launch.run_needle(),
                }));
                adopted_any = true;
            }
            None => match cell.spawn(i) {
                Ok(child) => {
                    tracing::info!("started {name} (pid {})", child.id());
                    cell.roster.started(i, now, child.id());
                    cell.procs.push(Some(Proc::Child(child)));
                }
                Err(e) => {
                    start_error = Some(e.to_string());
                    break;
                }
            },
        }
        cell.write_state();
        // the services' dead-man hears a supervisor from their start
        let now = now_ns();
        ports.publish_health(&cell.roster, &mut health, now);
        let delay = cell.roster.get(i).spec.start_delay_ms;
        if delay > 0 {
            std::thread::sleep(Duration::from_millis(delay));
        }
        if !adopted_any {
            if let Some((j, detail)) = cell.first_exit() {
                start_error = Some(format!(
                    "{} {detail} during start-up",
                    cell.roster.get(j).name
                ));
                break;
            }
        }
        if shutdown.requested() {
            break;
        }
    }
    if adopted_any {
        eval.event(
            now_ns(),
            "takeover",
            "supervisor",
            "adopted the services of a supervisor that died",
        );
    }
    cell.write_state();

    let end_ns = plan.duration_s.map(|d| t0 + (d * 1e9) as u64);
    let sup = cell.roster.config().clone();
    let health_period = (1e9 / sup.health_hz.max(0.1)) as u64;
    // start-up lasts startup_s after the last start: an exit before then fails
    // the start (not in a takeover: the adopted services were running)
    let mut starting_until = (!adopted_any).then(|| now_ns() + (sup.startup_s * 1e9) as u64);
    let mut stop_reason: Option<String> = None;
    let mut cpu_use = CpuUse::new(cell.roster.len());
    let mut next_health = now_ns();
    // after a (re)start, health every tick for a while: a new service waits
    // for it (its inputs' owners) before its loop starts, and iceoryx2 hands
    // a new subscriber the last sample only with the next one published
    let mut fast_health_until = now_ns() + FAST_HEALTH_NS;
    let mut next_watch = now_ns();
    let mut next_cpu_sample = now_ns();
    // one WaitSet: the tick, and each watched service's liveness with its
    // deadline; it sleeps until one of them wakes it
    let waitset = liveness::waitset()?;
    let vigil = liveness::Vigil::new(&waitset, &watch.watched, Duration::from_nanos(TICK_NS))?;
    let mut woke: Vec<Wake> = Vec::with_capacity(watch.watched.len() + 1);
    // the watch loop outranks the services it must be able to blame (one
    // spinning at real-time priority would otherwise starve it too)
    let watchdog_priority = plan.loaded.config.supervisor.rt_priority;
    if rt_watch.permitted() && watchdog_priority > 0 {
        if let Err(e) = phri_runtime::rt::make_watchdog(watchdog_priority) {
            tracing::warn!(
                "supervisor.rt_priority: {e}; the supervisor runs under the normal scheduler"
            );
        }
    }
    // who publishes on the robot's command channels and on the owned ones:
    // each service opened once, then only its publisher list read
    let mut command_watches = [
        ROBOT_COMMAND.publisher_watch(),
        ROBOT_COMMAND_STANDBY.publisher_watch(),
    ];
    let mut owned = owned_watches(ports.frames.len());
    let mut last_round = now_ns();
    while start_error.is_none()
        && stop_reason.is_none()
        && !shutdown.requested()
        && end_ns.is_none_or(|e| now_ns() < e)
    {
        woke.clear();
        vigil.wait(Duration::from_nanos(TICK_NS), |w| woke.push(w))?;
        let now = now_ns();
        // beats, deaths and missed deadlines; a round of the duties below
        // at each tick, and at once when a service died or fell silent
        let mut round = false;
        for &w in &woke {
            match w {
                Wake::Tick => round = true,
                Wake::Missed(k) => {
                    cell.roster.deadline_missed(watch.index[k]);
                    round = true;
                }
                Wake::Pulse(k) => watch.watched[k].take(|p| match p {
                    Pulse::Beat => cell.roster.heard(watch.index[k], now),
                    // reaped below (a child) or found gone (adopted)
                    Pulse::Ended | Pulse::Dead => round = true,
                })?,
            }
        }
        if !round && now.saturating_sub(last_round) < TICK_NS {
            continue;
        }
        // this process did not run for longer than a tick (a stopped
        // supervisor, a starved CPU): the services' silence meanwhile is
        // not theirs to answer for
        let stalled_ns = now.saturating_sub(last_round).saturating_sub(TICK_NS);
        last_round = now;
        let roster = &mut cell.roster;
        // evaluation streams
        ports.stats.drain(|m| eval.on_stats(m))?;
        ports.contacts.drain(|m| eval.on_contact_event(m))?;
        ports.collab.drain(|m| {
            if m.request_kind == phri_ipc::RequestKind::Stop as u32 && m.request_accepted != 0 {
                let source = phri_ipc::RequestSource::name_of(m.request_source);
                eval.stop_requested_by(source, m.request_seq);
            }
            collab_eval.on_state(m);
        })?;
        ports.ssm.drain(|m| eval.on_ssm(m))?;
        ports.commanders.drain(|m| {
            standby_eval.on_commanders(m, eval.time_s(m.stamp_ns));
            box_eval.on_commanders(m);
        })?;
        // commands the robot refused from a process this supervisor did not start
        for reason in box_eval.intruders(|pid| !roster.runs(pid as u32)) {
            tracing::warn!("{reason}");
            eval.event(now, "intruder", "robot", reason.clone());
            eval.degrade(reason);
        }
        let mut resume = false;
        ports.requests.drain(|m| {
            resume |= m.kind == phri_ipc::RequestKind::Resume as u32;
            collab_eval.on_request(m);
        })?;
        ports.bridge_requests.drain(|m| collab_eval.on_bridge(m))?;
        ports.camera_status.drain(|m| eval.on_camera_status(m))?;
        ports.mic_status.drain(|m| eval.on_mic_status(m))?;
        ports.audits.drain(|m| audits.on_audit(m))?;
        ports.boxes.drain(|m| box_eval.on_box(m))?;
        if resume && roster.resume(now) {
            tracing::warn!("resumed by the operator: starting the services the dead-man stopped");
            eval.event(
                now,
                "resume",
                "supervisor",
                "the operator resumed the cell the dead-man stopped",
            );
        }
        ports.utterances.drain(|m| collab_eval.on_utterance(m))?;
        ports.truth.drain(|m| {
            eval.on_truth(m);
            collab_eval.on_truth(m);
        })?;
        ports.residual.drain(|m| {
            eval.on_residual(m);
            residual_pair.on_residual(0, m);
        })?;
        ports
            .standby_residual
            .drain(|m| residual_pair.on_residual(1, m))?;
        ports.status.drain(|m| eval.on_status(m, reaction))?;
        for camera in 0..ports.frames.len() {
            let (Some(frames), Some(filtered), Some(results)) = (
                ports.frames.get(camera),
                ports.filtered.get(camera),
                ports.repulsion.get(camera),
            ) else {
                break;
            };
            while let Some(f) = frames.receive()? {
                eval.on_frame(camera, f.user_header());
            }
            while let Some(f) = filtered.receive()? {
                eval.on_filtered(camera, f.user_header());
            }
            results.drain(|m| eval.on_repulsion(camera, m))?;
            if let Some(skeletons) = ports.skeletons.get(camera) {
                skeletons.drain(|m| eval.on_skeleton(camera, m))?;
            }
        }
        if stalled_ns > STALL_NS {
            tracing::warn!(
                "stalled for {} ms: heartbeats judged afresh",
                stalled_ns / 1_000_000
            );
            if let Some(reason) = verdict::on_stall(roster, stalled_ns, deadman_ns, now) {
                tracing::warn!("{reason}");
                eval.event(now, "deadman", "supervisor", reason.clone());
                eval.degrade(reason);
            }
        }

        // who uses the CPUs, and who commands the robot
        if now >= next_cpu_sample {
            next_cpu_sample = now + CPU_SAMPLE_NS;
            for i in 0..roster.len() {
                cpu_use.record(i, now, roster.get(i).pid.and_then(cpu_time_ns));
            }
        }
        if now >= next_watch {
            next_watch = now + WATCH_NS;
            // a channel that cannot be read now (being removed as its last
            // user exits) is read again at the next watch
            let mut intruder = None;
            for channel in command_watches.iter_mut() {
                let pid = channel
                    .publisher_pids(&node)
                    .unwrap_or_else(|e| watch_error(e, &mut watch_errors))
                    .unwrap_or_default()
                    .into_iter()
                    .find(|&p| p > 0 && !roster.runs(p as u32) && alive(p));
                if let Some(pid) = pid {
                    intruder.get_or_insert((pid, channel.name()));
                }
            }
            if let Some((pid, channel)) = intruder {
                let who = cmdline_of(pid);
                tracing::warn!(
                    "pid {pid} ({who}) publishes on {channel}, and is not a controller this supervisor started: stopping the cell (the robot first: it brakes)"
                );
                let reason = format!(
                    "pid {pid} ({who}) published on {channel} instead of the supervised controller"
                );
                eval.event(now, "intruder", "supervisor", reason.clone());
                eval.degrade(reason.clone());
                stop_reason = Some(reason);
            }
            // the owned channels: a stranger's messages are refused by their
            // readers; it is reported here, once per channel and process
            for watch in owned.iter_mut() {
                let channel = watch.name();
                let pids = watch
                    .publisher_pids(&node)
                    .unwrap_or_else(|e| watch_error(e, &mut watch_errors))
                    .unwrap_or_default();
                for pid in owned::strangers(channel, &pids, roster, me as i32) {
                    if strangers_seen.contains(&(channel, pid)) || !alive(pid) {
                        continue;
                    }
                    strangers_seen.push((channel, pid));
                    let reason = format!(
                        "pid {pid} ({}) published on {channel}, not a service this supervisor started for it: its messages are refused",
                        cmdline_of(pid)
                    );
                    tracing::warn!("{reason}");
                    eval.event(now, "intruder", "supervisor", reason.clone());
                    eval.degrade(reason);
                }
            }
        }

        // what each real-time service got, once per process, when it has
        // run its loop (heard) or had the start-up's time to get there
        for (i, (name, want)) in wanted.iter().enumerate() {
            let sv = cell.roster.get(i);
            let Some(pid) = sv
                .pid
                .filter(|&p| want.priority > 0 && rt_watch.due(name, p))
            else {
                continue;
            };
            let ready = sv.heard_since_start
                || now.saturating_sub(sv.started_ns) > (sup.startup_s * 1e9) as u64;
            if !ready || now.saturating_sub(sv.started_ns) < RT_SETTLE_NS {
                continue;
            }
            let Some(got) = realtime::observe(pid) else {
                continue;
            };
            let short = rt_watch.record(name, pid, want, &got, online);
            if short.is_empty() {
                continue;
            }
            let what: Vec<String> = short.iter().map(ToString::to_string).collect();
            tracing::warn!("{name} (pid {pid}): {}", what.join("; "));
            if require_rt {
                let reason = format!(
                    "--require-rt: {name} did not get real-time scheduling ({})",
                    what.join("; ")
                );
                eval.degrade(reason.clone());
                stop_reason = Some(reason);
            }
        }

        // reap and schedule restarts
        let mut changed = false;
        for i in 0..cell.procs.len() {
            let Some(detail) = cell.procs[i].as_mut().and_then(Proc::try_exited) else {
                continue;
            };
            cell.procs[i] = None;
            changed = true;
            // noticed now (this round began before the reaping)
            let now = now_ns();
            let _ = node.try_cleanup_dead_nodes();
            let name = cell.roster.get(i).name.clone();
            eval.event(now, "exit", &name, detail.clone());
            cpu_use.restarted(i);
            match verdict::on_exit(&mut cell.roster, i, now, &detail, starting_until.is_some()) {
                ExitVerdict::DeadmanHold(held) => {
                    if let Some(reason) = held {
                        tracing::warn!("{reason}");
                        eval.event(now, "deadman", &name, reason.clone());
                        eval.degrade(reason);
                    }
                }
                ExitVerdict::StartFailed(reason) => {
                    start_error = Some(reason);
                    break;
                }
                ExitVerdict::CrashLoop(reason) => {
                    tracing::warn!("{reason}; stopping the cell");
                    eval.degrade(reason.clone());
                    stop_reason = Some(reason);
                    break;
                }
                ExitVerdict::PartnerCrashLoop(reason, at) => {
                    tracing::warn!("{reason}");
                    eval.event(now, "crash_loop", &name, reason.clone());
                    eval.degrade(reason);
                    if let Some(at) = at {
                        tracing::warn!("{name} restarting in {} ms", (at - now) / 1_000_000);
                    }
                }
                ExitVerdict::Restart(Some(at)) => tracing::warn!(
                    "{name} {detail}; restarting in {} ms",
                    (at - now) / 1_000_000
                ),
                ExitVerdict::Restart(None) => tracing::warn!("{name} {detail}"),
            }
        }
        if start_error.is_some() || stop_reason.is_some() {
            break;
        }
        if starting_until.is_some_and(|until| now >= until) {
            starting_until = None;
            if !cell.roster.whole() {
                tracing::warn!(
                    "{} s after the start, not heard yet: {}",
                    sup.startup_s,
                    cell.roster.unheard().join(", ")
                );
            }
        }
        // frozen services: alive, their dependencies heard from, but silent
        // themselves; a service that starves them on their CPUs dies instead
        let mut killed: Vec<usize> = Vec::new();
        for f in cell.roster.frozen(now) {
            let sv = cell.roster.get(f.index);
            let heartbeat = liveness::liveness_name(&sv.name);
            let victim = match cpu::judge(&cell.roster, &cpu_use, f.index, f.silent_ns) {
                Some(cpu::Verdict::Starved { culprit: c, share }) => {
                    let culprit = &cell.roster.get(c).name;
                    tracing::warn!(
                        "{} silent on {heartbeat} for {} ms while {culprit} used {:.0} % of a CPU they share: killing {culprit} instead",
                        sv.name,
                        f.silent_ns / 1_000_000,
                        share.min(1.0) * 100.0
                    );
                    eval.event(
                        now,
                        "frozen",
                        &sv.name,
                        format!(
                            "no beat on {heartbeat} for {} ms; starved by {culprit}",
                            f.silent_ns / 1_000_000
                        ),
                    );
                    eval.event(
                        now,
                        "blame",
                        culprit,
                        format!(
                            "used {:.0} % of a CPU while {} starved: killed",
                            share.min(1.0) * 100.0,
                            sv.name
                        ),
                    );
                    c
                }
                Some(cpu::Verdict::Frozen { busiest: b, share }) => {
                    tracing::warn!(
                        "{} silent on {heartbeat} for {} ms: frozen, killing it (busiest on its CPUs: {} at {:.0} %)",
                        sv.name,
                        f.silent_ns / 1_000_000,
                        cell.roster.get(b).name,
                        share.min(1.0) * 100.0
                    );
                    eval.event(
                        now,
                        "frozen",
                        &sv.name,
                        format!("no beat on {heartbeat} for {} ms", f.silent_ns / 1_000_000),
                    );
                    f.index
                }
                // no CPU samples over its silence (this process was held
                // up too): no verdict without evidence, judged again
                None => {
                    tracing::warn!(
                        "{} silent on {heartbeat} for {} ms; no CPU samples over that time: judged again",
                        sv.name,
                        f.silent_ns / 1_000_000
                    );
                    continue;
                }
            };
            if !killed.contains(&victim) {
                killed.push(victim);
                if let Some(p) = &cell.procs[victim] {
                    p.signal(libc::SIGKILL);
                }
            }
        }
        for i in 0..cell.roster.len() {
            if !cell.roster.restart_due(i, now) {
                continue;
            }
            match cell.spawn(i) {
                Ok(child) => {
                    let name = &cell.roster.get(i).name;
                    tracing::info!("restarted {name} (pid {})", child.id());
                    eval.event(
                        now,
                        "restart",
                        name,
                        format!("restart {}", cell.roster.get(i).restarts()),
                    );
                    cell.roster.started(i, now, child.id());
                    cell.procs[i] = Some(Proc::Child(child));
                    cpu_use.restarted(i);
                    fast_health_until = now + FAST_HEALTH_NS;
                    changed = true;
                }
                Err(e) => {
                    tracing::warn!("{e}");
                    cell.roster.restart_failed(i, now);
                    if let Some(n) = cell.roster.crash_looping(i, now) {
                        let reason = format!(
                            "{} could not be started {n} times within {} s ({e})",
                            cell.roster.get(i).name,
                            sup.crash_loop_window_s
                        );
                        eval.degrade(reason.clone());
                        stop_reason = Some(reason);
                    }
                }
            }
        }
        if changed {
            cell.write_state();
            // the services learn the new pids (the owners of their inputs) at once
            ports.publish_health(&cell.roster, &mut health, now);
            // a restart opened a node: the node counter must still be ours alone
            if let Err(e) = shm::check_global_mgmt(Path::new(SHM_DIR), &prefix) {
                let reason = e.to_string();
                tracing::warn!("{reason}; stopping the cell");
                eval.degrade(reason.clone());
                stop_reason = Some(reason);
            }
        }
        if now >= next_health || now < fast_health_until {
            next_health = now + health_period;
            ports.publish_health(&cell.roster, &mut health, now);
        }
    }

    // stopping and reporting wait on others: not at real-time priority
    phri_runtime::rt::make_normal();
    drop(command_watches);
    drop(owned);
    // the liveness services go with the cell's other ports
    drop(vigil);
    drop(waitset);
    drop(watch);
    if let Some(reason) = start_error {
        tracing::warn!("{reason}: stopping everything started");
        cell.stop();
        close_ipc(node, Some(ports), &prefix);
        cell.remove_state();
        return Err(SupervisorError::StartFailed(reason));
    }
    let end = now_ns();
    let services_report = cell.roster.reports();
    // drain what arrived in the last period before stopping anything
    let _ = ports.contacts.drain(|m| eval.on_contact_event(m));
    let _ = ports.collab.drain(|m| collab_eval.on_state(m));
    let _ = ports.ssm.drain(|m| eval.on_ssm(m));
    let _ = ports.requests.drain(|m| collab_eval.on_request(m));
    let _ = ports.bridge_requests.drain(|m| collab_eval.on_bridge(m));
    let _ = ports.camera_status.drain(|m| eval.on_camera_status(m));
    let _ = ports.mic_status.drain(|m| eval.on_mic_status(m));
    let _ = ports.utterances.drain(|m| collab_eval.on_utterance(m));
    let _ = ports.truth.drain(|m| {
        eval.on_truth(m);
        collab_eval.on_truth(m);
    });
    let _ = ports.residual.drain(|m| eval.on_residual(m));
    let _ = ports.status.drain(|m| eval.on_status(m, reaction));
    let _ = ports.stats.drain(|m| eval.on_stats(m));
    // each service's CPU over the run, sampled once more before the stop
    let now = now_ns();
    for i in 0..cell.roster.len() {
        cpu_use.record(i, now, cell.roster.get(i).pid.and_then(cpu_time_ns));
    }
    let cpu_report = cpu_use.report(&cell.roster);
    cell.stop();
    let _ = ports.commanders.drain(|m| {
        standby_eval.on_commanders(m, eval.time_s(m.stamp_ns));
        box_eval.on_commanders(m);
    });
    // what the services said last (the simulator's contacts as it braked)
    let _ = ports.contacts.drain(|m| eval.on_contact_event(m));
    eval.set_realtime(rt_watch.report());
    let _ = ports.audits.drain(|m| audits.on_audit(m));
    let _ = ports.boxes.drain(|m| box_eval.on_box(m));
    let inputs = audits.report();
    for line in inputs.degraded() {
        eval.degrade(line);
    }
    let mut report = eval.report(end, plan.scenario_name(), services_report);
    report.inputs = inputs;
    report.cpu = cpu_report;
    report.control = standby_eval.report();
    report.dynamics = residual_pair.report();
    report.robot = plan.robot_report();
    box_eval.fill(&mut report);
    (
        report.robot.max_joint_step_rad,
        report.robot.max_joint_step_t_s,
    ) = eval.max_joint_step();
    report.collaboration =
        collab_eval.report(report.contacts.iter().map(|c| (c.intended, c.peak_force_n)));
    if !eval.has_truth() {
        // a real arm: the collaboration's touches as F̂ tells them
        let link = &plan.loaded.config.collaboration.robot_link;
        collab_eval.judge_estimated(&mut report.iso_ts_15066, link);
    }
    // judged from everything the report holds now
    eval.conclude(&mut report);
    close_ipc(node, Some(ports), &prefix);
    cell.remove_state();
    if let Some(file) = report_file.as_mut() {
        let json = serde_json::to_string_pretty(&report).map_err(|e| SupervisorError::Report {
            path: file.path.clone(),
            source: std::io::Error::other(e),
        })?;
        file.write(&json)?;
    }
    let intended = report.contacts.iter().filter(|c| c.intended).count();
    tracing::info!(
        "{} done after {:.1} s: {} cycles, {} missed deadlines, latency p99 {:.0} µs, {} unintended contacts, {} intended touches, {} false detections; {}",
        report.scenario,
        report.duration_s,
        report.torque_loop.cycles,
        report.torque_loop.missed_deadlines,
        report.torque_loop.latency_us.p99,
        report.contacts.len() - intended,
        report.collaboration.contacts_intended,
        report.false_detections,
        report.summary
    );
    match stop_reason {
        Some(reason) => Err(SupervisorError::Degraded(reason)),
        None => Ok(()),
    }
}
