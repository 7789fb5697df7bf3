//! One round of the supervision loop, in its stages: the channels read
//! (an operator's resume, a stall of the supervisor judged), the evidence
//! gathered (CPU samples, publishers, real-time scheduling, exits), the
//! frozen killed and the due restarted, the state written and the health
//! published.

use super::{
    Action, Stage, Supervision, CLEANUP_WAIT_NS, CPU_SAMPLE_NS, RT_SETTLE_NS, STALL_NS, TICK_NS,
    WATCH_NS,
};
use crate::verdict;

impl Supervision {
    /// [`super::Event::Round`]: a round begins when its wakes asked for one
    /// or a tick's time passed since the last; the channels are read first.
    pub(super) fn round(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        let asked = std::mem::take(&mut self.round_asked);
        if self.stage != Stage::Idle
            || (!asked && now_ns.saturating_sub(self.timers.last_round) < TICK_NS)
        {
            return;
        }
        // this process did not run for longer than a tick (a stopped
        // supervisor, a starved CPU): the services' silence meanwhile is
        // not theirs to answer for
        self.stalled_ns = now_ns
            .saturating_sub(self.timers.last_round)
            .saturating_sub(TICK_NS);
        self.timers.last_round = now_ns;
        self.reaped_enough = false;
        self.changed = false;
        self.stage = Stage::Reading;
        out.push(Action::Drain);
    }

    /// An operator resumed the cell the dead-man stopped.
    pub(super) fn resume(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        if !self.roster.resume(now_ns) {
            return;
        }
        out.push(Action::Warn(
            "resumed by the operator: starting the services the dead-man stopped".into(),
        ));
        self.record(
            out,
            now_ns,
            "resume",
            "supervisor",
            "the operator resumed the cell the dead-man stopped",
        );
    }

    /// The channels are read: a stall is judged, then what is due is gathered.
    pub(super) fn gather(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        if self.stalled_ns > STALL_NS {
            let ms = self.stalled_ns / 1_000_000;
            out.push(Action::Warn(format!(
                "stalled for {ms} ms: heartbeats judged afresh"
            )));
            // in the report: what the supervisor noticed late meanwhile is its own delay
            self.record(out, now_ns, "stall", "supervisor", &format!("{ms} ms"));
            if let Some(reason) =
                verdict::on_stall(&mut self.roster, self.stalled_ns, self.deadman_ns, now_ns)
            {
                out.push(Action::Warn(reason.clone()));
                self.record(out, now_ns, "deadman", "supervisor", &reason);
                out.push(Action::Degrade(reason));
            }
        }
        // who uses the CPUs, and who commands the robot
        if now_ns >= self.timers.next_cpu_sample {
            self.timers.next_cpu_sample = now_ns + CPU_SAMPLE_NS;
            out.push(Action::SampleCpu);
        }
        if now_ns >= self.timers.next_watch {
            self.timers.next_watch = now_ns + WATCH_NS;
            out.push(Action::Watch);
        }
        self.observe_due(now_ns, out);
        self.stage = Stage::Gathering;
        out.push(Action::Reap);
    }

    /// What each real-time service got is looked at once per process, when
    /// it has run its loop (heard) or had the start-up's time to get there.
    fn observe_due(&self, now_ns: u64, out: &mut Vec<Action>) {
        let startup_ns = (self.roster.config().startup_s * 1e9) as u64;
        for (index, (sv, want)) in self.roster.iter().zip(&self.wanted).enumerate() {
            let Some(pid) = sv
                .pid
                .filter(|&p| want.priority > 0 && self.realtime.due(&sv.name, p))
            else {
                continue;
            };
            let since_start = now_ns.saturating_sub(sv.started_ns);
            let ready = sv.heard_since_start || since_start > startup_ns;
            if ready && since_start >= RT_SETTLE_NS {
                out.push(Action::Observe { index, pid });
            }
        }
    }

    /// The evidence is in: unless a verdict ended the run, the start-up's
    /// end is noted, the frozen are killed and the due restarted.
    pub(super) fn act(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        if self.start_error.is_some() || self.stop_reason.is_some() {
            self.stage = Stage::Idle;
            return;
        }
        if self
            .timers
            .starting_until
            .is_some_and(|until| now_ns >= until)
        {
            self.timers.starting_until = None;
            if !self.roster.whole() {
                out.push(Action::Warn(format!(
                    "{} s after the start, not heard yet: {}",
                    self.roster.config().startup_s,
                    self.roster.unheard().join(", ")
                )));
            }
        }
        self.kill_frozen(now_ns, out);
        let cleaning = self
            .cleaning_since_ns
            .is_some_and(|since| now_ns < since + CLEANUP_WAIT_NS);
        for index in 0..self.roster.len() {
            if !cleaning && self.roster.restart_due(index, now_ns) {
                out.push(Action::Start(index));
            }
        }
        self.stage = Stage::Acting;
    }

    /// The round ends: after a change the state is written and the health
    /// published at once (the services learn the new pids, the owners of
    /// their inputs), and the node counter checked (a restart opened a
    /// node); the health goes out at its rate, or every tick for a while
    /// after a (re)start.
    pub(super) fn commit(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        self.stage = Stage::Idle;
        if std::mem::take(&mut self.changed) {
            out.push(Action::WriteState);
            out.push(Action::PublishHealth { now_ns });
            out.push(Action::CheckNodeCounter);
        }
        if now_ns >= self.timers.next_health || now_ns < self.timers.fast_health_until {
            self.timers.next_health = now_ns + self.timers.health_period;
            out.push(Action::PublishHealth { now_ns });
        }
    }
}
