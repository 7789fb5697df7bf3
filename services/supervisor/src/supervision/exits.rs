//! What ends a service, and what a start that fails does: at the start-up
//! the start fails; later a crash is restarted with back-off, a crash loop
//! ends the run (or, of one of a hot-standby pair, is reported while its
//! partner carries the cell), a dead-man stop holds the cell.

use super::{Action, Stage, Supervision};
use crate::verdict::{self, ExitVerdict};

impl Supervision {
    /// Service `index` ended at `now_ns` as `detail` says.
    pub(super) fn exited(
        &mut self,
        index: usize,
        now_ns: u64,
        detail: String,
        out: &mut Vec<Action>,
    ) {
        let name = self.roster.get(index).name.clone();
        if let Stage::Starting(_) = self.stage {
            self.start_error = Some(format!("{name} {detail} during start-up"));
            return;
        }
        if self.reaped_enough {
            return;
        }
        self.changed = true;
        self.record(out, now_ns, "exit", &name, &detail);
        self.cpu.restarted(index);
        let starting = self.timers.starting_until.is_some();
        match verdict::on_exit(&mut self.roster, index, now_ns, &detail, starting) {
            ExitVerdict::DeadmanHold(held) => {
                if let Some(reason) = held {
                    out.push(Action::Warn(reason.clone()));
                    self.record(out, now_ns, "deadman", &name, &reason);
                    out.push(Action::Degrade(reason));
                }
            }
            ExitVerdict::StartFailed(reason) => {
                self.start_error = Some(reason);
                self.reaped_enough = true;
            }
            ExitVerdict::CrashLoop(reason) => {
                out.push(Action::Warn(format!("{reason}; stopping the cell")));
                self.stop(reason, out);
                self.reaped_enough = true;
            }
            ExitVerdict::PartnerCrashLoop(reason, at) => {
                out.push(Action::Warn(reason.clone()));
                self.record(out, now_ns, "crash_loop", &name, &reason);
                out.push(Action::Degrade(reason));
                if let Some(at) = at {
                    out.push(Action::Warn(format!(
                        "{name} restarting in {} ms",
                        (at - now_ns) / 1_000_000
                    )));
                }
            }
            ExitVerdict::Restart(Some(at)) => out.push(Action::Warn(format!(
                "{name} {detail}; restarting in {} ms",
                (at - now_ns) / 1_000_000
            ))),
            ExitVerdict::Restart(None) => out.push(Action::Warn(format!("{name} {detail}"))),
        }
    }

    /// Service `index` could not be started at `now_ns` (`error`): at the
    /// start-up the start fails; a restart is tried again after the next
    /// back-off, and too many failures end the run.
    pub(super) fn spawn_failed(
        &mut self,
        index: usize,
        now_ns: u64,
        error: String,
        out: &mut Vec<Action>,
    ) {
        if let Stage::Starting(_) = self.stage {
            self.start_error = Some(error);
            return;
        }
        out.push(Action::Warn(error.clone()));
        self.roster.restart_failed(index, now_ns);
        if let Some(n) = self.roster.crash_looping(index, now_ns) {
            let reason = format!(
                "{} could not be started {n} times within {} s ({error})",
                self.roster.get(index).name,
                self.roster.config().crash_loop_window_s
            );
            self.stop(reason, out);
        }
    }
}
