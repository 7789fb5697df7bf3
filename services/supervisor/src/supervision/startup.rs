//! The start-up: every service started (or taken over from a supervisor
//! that died) in order, each given its start delay; a service that cannot
//! be started, or ends before the last one started, fails the start.

use std::time::Duration;

use super::{Action, Stage, Supervision, Timers, FAST_HEALTH_NS};

impl Supervision {
    /// [`super::Event::Start`]: the first service is launched.
    pub(super) fn start(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        if self.roster.is_empty() {
            self.begin(now_ns, out);
            return;
        }
        self.stage = Stage::Starting(0);
        out.push(Action::Launch(0));
    }

    /// Service `index` was taken over from a supervisor that died.
    pub(super) fn adopted(
        &mut self,
        index: usize,
        now_ns: u64,
        pid: u32,
        restarts: u32,
        out: &mut Vec<Action>,
    ) {
        let name = &self.roster.get(index).name;
        out.push(Action::Info(format!(
            "adopted {name} (pid {pid}) from the previous supervisor"
        )));
        self.roster.adopted(index, now_ns, pid, restarts);
        self.adopted_any = true;
        self.launched(index, now_ns, out);
    }

    /// Service `index` started as `pid`: at the start-up, or a restart.
    pub(super) fn started(&mut self, index: usize, now_ns: u64, pid: u32, out: &mut Vec<Action>) {
        let name = self.roster.get(index).name.clone();
        if let Stage::Starting(_) = self.stage {
            out.push(Action::Info(format!("started {name} (pid {pid})")));
            self.roster.started(index, now_ns, pid);
            self.launched(index, now_ns, out);
            return;
        }
        out.push(Action::Info(format!("restarted {name} (pid {pid})")));
        let restarts = format!("restart {}", self.roster.get(index).restarts());
        self.record(out, now_ns, "restart", &name, &restarts);
        self.roster.started(index, now_ns, pid);
        self.cpu.restarted(index);
        self.timers.fast_health_until = now_ns + FAST_HEALTH_NS;
        self.changed = true;
    }

    /// Service `index` runs: the state written, the health published (the
    /// services' dead-man hears a supervisor from their start), its delay
    /// waited, and an early exit of any looked for (not in a takeover).
    fn launched(&mut self, index: usize, now_ns: u64, out: &mut Vec<Action>) {
        out.push(Action::WriteState);
        out.push(Action::PublishHealth { now_ns });
        let delay = self.roster.get(index).spec.start_delay_ms;
        if delay > 0 {
            out.push(Action::Pause(Duration::from_millis(delay)));
        }
        if !self.adopted_any {
            out.push(Action::CheckStart);
        }
    }

    /// After service `index`'s start: the next one, unless the start failed
    /// or a signal came; else supervision begins.
    pub(super) fn next_start(&mut self, index: usize, now_ns: u64, out: &mut Vec<Action>) {
        if self.start_error.is_some() {
            self.stage = Stage::Idle;
            return;
        }
        if self.signalled || index + 1 >= self.roster.len() {
            self.begin(now_ns, out);
            return;
        }
        self.stage = Stage::Starting(index + 1);
        out.push(Action::Launch(index + 1));
    }

    /// The start-up is over at `now_ns`: a takeover is reported, the state
    /// written, and the loop's clocks set.
    fn begin(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        self.stage = Stage::Idle;
        if self.adopted_any {
            self.record(
                out,
                now_ns,
                "takeover",
                "supervisor",
                "adopted the services of a supervisor that died",
            );
        }
        out.push(Action::WriteState);
        let sup = self.roster.config();
        // start-up lasts startup_s after the last start: an exit before then
        // fails the start (not in a takeover: the adopted services were running)
        self.timers = Timers {
            starting_until: (!self.adopted_any).then(|| now_ns + (sup.startup_s * 1e9) as u64),
            next_health: now_ns,
            // after a (re)start, health every tick for a while: a new
            // service waits for it (its inputs' owners) before its loop
            // starts, and iceoryx2 hands a new subscriber the last sample
            // only with the next one published
            fast_health_until: now_ns + FAST_HEALTH_NS,
            next_watch: now_ns,
            next_cpu_sample: now_ns,
            last_round: now_ns,
            health_period: (1e9 / sup.health_hz.max(0.1)) as u64,
        };
    }
}
