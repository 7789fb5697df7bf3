//! The supervisor's node of the cell: opened once nothing else can refuse
//! the run (another supervisor of the prefix, a foreign node counter), and
//! closed with whatever the run left in shared memory.

use std::path::Path;

use phri_ipc::{node, IpcNode, SUPERVISOR_HEALTH};
use phri_runtime::rundir::write_private;

use super::ports::Ports;
use super::procfs::{alive, run_dir_of};
use crate::process::Launch;
use crate::shm::{self, SHM_DIR};
use crate::{Plan, SupervisorError};

/// Open the node and the ports of the cell of `launch.prefix`, and write the
/// merged configuration the services read. Refused when a supervisor of
/// the prefix with another run directory lives (the run directory is
/// removed again when this run created it: `run_dir_existed`).
pub fn open(
    plan: &Plan,
    launch: &Launch,
    run_dir_existed: bool,
) -> Result<(IpcNode, Ports), SupervisorError> {
    let (prefix, me) = (&launch.prefix, std::process::id());
    let node = node("supervisor", prefix)?;
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
            let _ = std::fs::remove_dir(&launch.run_dir);
        }
        return Err(SupervisorError::AlreadyRunning {
            pid: pid as u32,
            run_dir: run_dir_of(pid, prefix),
            prefix: prefix.clone(),
        });
    }
    // the node counter exists now: owner-only from here on
    if let Err(e) = shm::restrict_global_mgmt(Path::new(SHM_DIR), prefix) {
        close(node, None, prefix);
        return Err(e.into());
    }
    let ports = match Ports::open(&node, plan.loaded.config.cameras.len()) {
        Ok(p) => p,
        Err(e) => {
            close(node, None, prefix);
            return Err(e.into());
        }
    };
    if let Err(e) = write_private(&launch.config, plan.merged_toml().as_bytes()) {
        close(node, Some(ports), prefix);
        return Err(e.into());
    }
    tracing::info!("cell {prefix}, run directory {}", launch.run_dir.display());
    tracing::info!(
        "attach from another terminal: {}",
        attach_hint(&launch.bin_dir, prefix)
    );
    Ok((node, ports))
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
pub fn close(node: IpcNode, ports: Option<Ports>, prefix: &str) {
    let _ = node.try_cleanup_dead_nodes();
    drop(ports);
    drop(node);
    match phri_ipc::remove_leftovers(prefix) {
        Ok(0) => {}
        Ok(n) => tracing::info!("removed {n} shared-memory files the run left"),
        Err(alive) => tracing::warn!("{alive} node(s) of prefix {prefix} still attached (a monitor or recorder?): the last one out cleans up"),
    }
}
