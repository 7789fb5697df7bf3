//! What is checked before the first process starts: real-time scheduling
//! permitted (or the run degraded, or refused), no other supervisor of the
//! prefix, and every service's acceptance of the configuration.

use std::time::{Duration, Instant};

use phri_runtime::rundir::write_private;

use crate::process::{cause_line, process_matches, status_text, Launch};
use crate::realtime::{self, RealtimeWatch, Wanted};
use crate::{Plan, SupervisorError, SupervisorState};

/// A service's `--check` must answer within this.
const CHECK_TIMEOUT: Duration = Duration::from_secs(60);

/// What `[services.*]` asks for each service: its priority and its CPUs
/// (the hot standby's pair judged against the lower priority), and whether
/// the kernel grants it here: a refusal degrades the run, or with
/// `require_rt` refuses it.
pub fn realtime_probe(
    plan: &Plan,
    require_rt: bool,
    online: usize,
) -> Result<(Vec<Wanted>, RealtimeWatch), SupervisorError> {
    let mut wanted: Vec<(String, Wanted)> = plan
        .services
        .iter()
        .map(|(name, spec)| {
            let want = Wanted {
                priority: spec.rt_priority,
                cpus: spec.cpus.clone(),
            };
            (name.clone(), want)
        })
        .collect();
    realtime::role_ranked(&mut wanted);
    let refusal =
        realtime::probe_services(wanted.iter().map(|(n, w)| (n.as_str(), w)), online).err();
    let watch = match refusal {
        Some(why) if require_rt => return Err(SupervisorError::RealtimeRequired(why)),
        Some(why) => {
            tracing::warn!(
                "real-time scheduling refused ({why}): the cell runs under the normal scheduler and the run will be reported degraded; docs/safety.md \"Real-time scheduling\" says how to grant it, --require-rt refuses instead"
            );
            RealtimeWatch::new(Some(why.to_string()))
        }
        None => RealtimeWatch::new(None),
    };
    Ok((wanted.into_iter().map(|(_, w)| w).collect(), watch))
}

/// A cell of `prefix` whose supervisor lives (not this process, `me`):
/// refused, writing nothing.
pub fn no_live_supervisor(
    previous: Option<&SupervisorState>,
    me: u32,
    prefix: &str,
    run_dir: &std::path::Path,
) -> Result<(), SupervisorError> {
    if let Some(p) = previous {
        if p.supervisor_pid != me && process_matches(p.supervisor_pid, &["phri-supervisor"]) {
            return Err(SupervisorError::AlreadyRunning {
                pid: p.supervisor_pid,
                prefix: prefix.to_string(),
                run_dir: run_dir.display().to_string(),
            });
        }
    }
    Ok(())
}

/// Run every enabled service once with `--check` on a private copy of the
/// merged configuration, with the flags it will be started with, all at
/// once: each must accept it (exit 0) within `CHECK_TIMEOUT`. The first
/// refusal is returned, naming the service and quoting its line.
pub fn check_services(plan: &Plan, launch: &Launch) -> Result<(), SupervisorError> {
    let tmp = launch
        .run_dir
        .join(format!(".config.check.{}.toml", std::process::id()));
    write_private(&tmp, plan.merged_toml().as_bytes())?;
    let (tx, rx) = std::sync::mpsc::channel();
    let mut pending: Vec<(String, u32)> = Vec::new();
    let mut result = Ok(());
    for (name, spec) in &plan.services {
        let child = match launch.check_command(name, spec, &tmp).spawn() {
            Ok(c) => c,
            Err(source) => {
                result = Err(SupervisorError::Spawn {
                    service: name.clone(),
                    binary: spec.binary.clone(),
                    source,
                });
                break;
            }
        };
        pending.push((name.clone(), child.id()));
        let (tx, name) = (tx.clone(), name.clone());
        std::thread::spawn(move || {
            let _ = tx.send((name, child.wait_with_output()));
        });
    }
    drop(tx);
    if result.is_ok() {
        result = await_checks(&rx, &mut pending);
    }
    for (_, pid) in &pending {
        // SAFETY: kill(2) on a check process this function started
        unsafe { libc::kill(*pid as i32, libc::SIGKILL) };
    }
    let _ = std::fs::remove_file(&tmp);
    result
}

/// What one service's `--check` said.
type CheckOutput = (String, std::io::Result<std::process::Output>);

/// Wait for the `pending` checks' answers (taken off as they come): the
/// first refusal, or a check that did not finish in time, is the error.
fn await_checks(
    rx: &std::sync::mpsc::Receiver<CheckOutput>,
    pending: &mut Vec<(String, u32)>,
) -> Result<(), SupervisorError> {
    let deadline = Instant::now() + CHECK_TIMEOUT;
    while !pending.is_empty() {
        let left = deadline.saturating_duration_since(Instant::now());
        let Ok((name, out)) = rx.recv_timeout(left) else {
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
                Some(cause_line(&err).unwrap_or_else(|| status_text(out.status)))
            }
            Err(e) => Some(format!("its --check could not be waited for: {e}")),
        };
        if let Some(line) = refusal {
            return Err(SupervisorError::Refused {
                service: name,
                line,
            });
        }
    }
    Ok(())
}
