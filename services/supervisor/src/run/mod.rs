//! The supervisor's run, the I/O around its state machine
//! ([`crate::supervision`]): everything checked before the first process
//! starts ([`checks`]), the node and its ports opened ([`ipc`], [`ports`]),
//! the services started and supervised ([`driver`]: the processes of
//! [`cell`], the publishers of [`publishers`], dead processes' resources
//! removed by [`cleaner`], the state files written by [`state_writer`]),
//! then stopped in order and the report written ([`finish`],
//! [`report_file`]).

pub mod cell;
pub mod checks;
pub mod cleaner;
pub mod driver;
pub mod finish;
pub mod ipc;
pub mod ordered;
pub mod ports;
pub mod procfs;
pub mod publishers;
pub mod report_file;
pub mod state_writer;

use std::path::{Path, PathBuf};

use phri_runtime::rundir::{create_private_dir, default_run_dir};
use phri_runtime::{now_ns, Shutdown};

use crate::evaluation::Evaluation;
use crate::process::Launch;
use crate::shm::{self, SHM_DIR};
use crate::supervision::{Setup, Supervision};
use crate::{Plan, SupervisorError, SupervisorState};
use driver::Driver;
use ports::Liveness;
use publishers::Publishers;
use report_file::ReportFile;

/// How the run was asked for, beside its plan (the command line).
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// directory of the service binaries (the supervisor's own)
    pub bin_dir: PathBuf,
    /// `--require-rt`
    pub require_rt: bool,
    /// `--prefix` (empty or `None`: the default)
    pub prefix: Option<String>,
    /// `--run-dir` (`None`: the default for the prefix)
    pub run_dir: Option<PathBuf>,
    /// `--report`
    pub report: Option<String>,
}

/// Run the cell of `plan`: start it whole or not at all, supervise it until
/// a signal, the run's length or a verdict ends it, stop it in order and
/// write the report.
pub fn run(plan: Plan, opts: Options) -> Result<(), SupervisorError> {
    // real-time scheduling: permitted here, or the run is degraded (or refused)
    let require_rt = opts.require_rt || plan.loaded.config.supervisor.require_rt;
    let online = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (wanted, realtime) = checks::realtime_probe(&plan, require_rt, online)?;
    // one namespace by default (PHRI_PREFIX, else phri_): tools in another
    // terminal find the cell without flags; a second cell there is refused
    let prefix = phri_runtime::prefix_or_default(opts.prefix.as_deref().filter(|p| !p.is_empty()));
    // the run directory is this user's alone
    let run_dir = match &opts.run_dir {
        Some(d) => d.clone(),
        None => default_run_dir(&prefix)?,
    };
    let run_dir_existed = run_dir.exists();
    create_private_dir(&run_dir)?;
    // a cell of this prefix whose supervisor lives: refused, writing nothing
    let previous = SupervisorState::read(&run_dir, &prefix)?;
    checks::no_live_supervisor(previous.as_ref(), std::process::id(), &prefix, &run_dir)?;
    // iceoryx2's node counter of this prefix: not another user's, not altered
    shm::check_global_mgmt(Path::new(SHM_DIR), &prefix)?;
    let report_file = ReportFile::open(opts.report.as_deref())?;
    let shutdown = Shutdown::install().map_err(SupervisorError::Signals)?;
    let mut launch = Launch {
        bin_dir: opts.bin_dir,
        config: run_dir.join("config.toml"),
        prefix: prefix.clone(),
        cell_start_ns: now_ns(),
        run_dir,
    };
    // every service accepts the configuration, with the flags it will get
    checks::check_services(&plan, &launch)?;
    if shutdown.requested() {
        return Err(SupervisorError::StartFailed("interrupted".into()));
    }
    let (node, ports) = ipc::open(&plan, &launch, run_dir_existed)?;
    let t0 = now_ns();
    // the cell's clock survives a takeover, and the report counts from it
    launch.cell_start_ns = SupervisorState::cell_start_ns(previous.as_ref(), t0);
    let mut evaluation = Evaluation::new(&plan, launch.cell_start_ns);
    // a safety function switched off on purpose: every report of the run says so
    for line in plan.safety_off() {
        tracing::warn!("{line}: the run will be reported degraded");
        evaluation.eval.degrade(line);
    }
    let mut sup = Supervision::new(Setup {
        sup: plan.loaded.config.supervisor.clone(),
        services: plan.services.clone(),
        wanted,
        realtime,
        online,
        require_rt,
        t0_ns: t0,
        duration_s: plan.duration_s,
        robot_clock: plan.loaded.config.robot.ip.is_empty(),
    });
    // every watched service's liveness exists before it starts
    let liveness = match Liveness::open(&node, sup.roster()) {
        Ok(l) => l,
        Err(e) => {
            ipc::close(node, Some(ports), &prefix);
            return Err(e.into());
        }
    };
    let mut driver = Driver {
        cleaner: cleaner::Cleaner::new(&prefix),
        publishers: Publishers::new(ports.cameras()),
        cell: cell::Cell::new(launch, plan.services.len()),
        node,
        ports,
        evaluation,
        previous,
        prefix,
    };
    driver.start(&mut sup, &shutdown)?;
    watchdog(&plan, &sup);
    driver.supervise(&mut sup, &liveness, &shutdown)?;
    // stopping and reporting wait on others: not at real-time priority
    phri_runtime::rt::make_normal();
    drop(liveness);
    finish::finish(driver, &mut sup, &plan, report_file)
}

/// The watch loop outranks the services it must be able to blame (one
/// spinning at real-time priority would otherwise starve it too).
fn watchdog(plan: &Plan, sup: &Supervision) {
    let priority = plan.loaded.config.supervisor.rt_priority;
    if sup.realtime_permitted() && priority > 0 {
        if let Err(e) = phri_runtime::rt::make_watchdog(priority) {
            tracing::warn!(
                "supervisor.rt_priority: {e}; the supervisor runs under the normal scheduler"
            );
        }
    }
}
