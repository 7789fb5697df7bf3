//! Who else acts on the cell: a process other than the supervised
//! controller commanding the robot (the run ends), a stranger publishing on
//! an owned channel (reported once), and what each real-time service got of
//! its scheduling (`--require-rt`: a shortfall ends the run).

use super::{Action, Supervision};
use crate::realtime::Observed;

impl Supervision {
    /// Process `pid` (`who`) publishes on the robot's command `channel`.
    pub(super) fn command_intruder(
        &mut self,
        now_ns: u64,
        pid: i32,
        who: &str,
        channel: &str,
        out: &mut Vec<Action>,
    ) {
        out.push(Action::Warn(format!(
            "pid {pid} ({who}) publishes on {channel}, and is not a controller this supervisor started: stopping the cell (the robot first: it brakes)"
        )));
        let reason = format!(
            "pid {pid} ({who}) published on {channel} instead of the supervised controller"
        );
        self.record(out, now_ns, "intruder", "supervisor", &reason);
        self.stop(reason, out);
    }

    /// Process `pid` (`who`) publishes on the owned `channel`: its messages
    /// are refused by their readers; it is reported here, once per channel
    /// and process.
    pub(super) fn stranger(
        &mut self,
        now_ns: u64,
        channel: &'static str,
        pid: i32,
        who: &str,
        out: &mut Vec<Action>,
    ) {
        if self.stranger_known(channel, pid) {
            return;
        }
        self.strangers_seen.push((channel, pid));
        let reason = format!(
            "pid {pid} ({who}) published on {channel}, not a service this supervisor started for it: its messages are refused"
        );
        out.push(Action::Warn(reason.clone()));
        self.record(out, now_ns, "intruder", "supervisor", &reason);
        out.push(Action::Degrade(reason));
    }

    /// Service `index`'s process `pid` got `observed` of real-time scheduling.
    pub(super) fn observed(
        &mut self,
        index: usize,
        pid: u32,
        observed: &Observed,
        out: &mut Vec<Action>,
    ) {
        let (Some(sv), Some(want)) = (self.roster.iter().nth(index), self.wanted.get(index)) else {
            return;
        };
        let name = sv.name.clone();
        let short = self
            .realtime
            .record(&name, pid, want, observed, self.online);
        if short.is_empty() {
            return;
        }
        let what: Vec<String> = short.iter().map(ToString::to_string).collect();
        out.push(Action::Warn(format!(
            "{name} (pid {pid}): {}",
            what.join("; ")
        )));
        if self.require_rt {
            let reason = format!(
                "--require-rt: {name} did not get real-time scheduling ({})",
                what.join("; ")
            );
            self.stop(reason, out);
        }
    }
}
