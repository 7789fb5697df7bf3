//! The control box behind a real robot's adapter, for the report: FCI's
//! command success rate and every error of the box with its time, from
//! `robot/box` (kept across restarts of the adapter); and what the robot
//! refused: the box's state datagrams and states the adapter did not act on
//! (`robot/box`), commands from a process other than the slot's controller
//! or malformed (`robot/commanders`, the simulator's and the adapter's).

use phri_ipc::{BoxStatus, CommanderStats};
use serde::Serialize;

use crate::report::{Event, Report};

/// One error of the control box.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxErrorReport {
    /// when the adapter heard it [s from the run's start]
    pub t_s: f64,
    /// the box's error names (libfranka's)
    pub error: String,
}

/// `robot.refused.states` in the report: the control box's state datagrams
/// the adapter's FCI client dropped and the states it did not act on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RefusedStates {
    /// from another address or port than the box's
    pub foreign: u64,
    /// of the wrong size
    pub malformed: u64,
    /// a message id not above the newest one (a duplicate, a replay)
    pub stale_id: u64,
    /// a message id more than 100 ahead of what the time since the newest allows
    pub id_ahead: u64,
    /// joint positions not finite
    pub non_finite: u64,
    /// joints moved faster than their velocity limits allow
    pub too_fast: u64,
}

impl RefusedStates {
    fn of(m: &BoxStatus) -> RefusedStates {
        RefusedStates {
            foreign: m.refused_foreign,
            malformed: m.refused_malformed,
            stale_id: m.refused_stale_id,
            id_ahead: m.refused_id_ahead,
            non_finite: m.refused_non_finite,
            too_fast: m.refused_too_fast,
        }
    }

    fn add(&mut self, o: &RefusedStates) {
        self.foreign += o.foreign;
        self.malformed += o.malformed;
        self.stale_id += o.stale_id;
        self.id_ahead += o.id_ahead;
        self.non_finite += o.non_finite;
        self.too_fast += o.too_fast;
    }
}

/// `robot.refused.commands` in the report: commands the robot never
/// applied, per slot (`robot/command`, `robot/command/standby`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RefusedCommands {
    /// sent by a process other than the controller the supervisor started for the slot
    pub stranger: [u64; 2],
    /// wrong joint count or a non-finite torque
    pub malformed: [u64; 2],
    /// the strangers' pids, each once
    pub stranger_pids: Vec<i32>,
}

/// `robot.refused` in the report.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RobotRefused {
    /// the control box's states (null: no control box, a simulated arm)
    pub states: Option<RefusedStates>,
    /// the commands the robot never applied, per slot
    pub commands: RefusedCommands,
}

/// `robot/box` and the refusals of `robot/commanders` over a run.
#[derive(Debug)]
pub struct BoxEval {
    t0_ns: u64,
    /// the adapter's newest message (this incarnation)
    last: Option<BoxStatus>,
    /// sums of the adapter's earlier incarnations: controlled states, rate sum, recoveries
    base: (u64, f64, u64),
    /// states refused by the adapter's earlier incarnations
    base_refused: RefusedStates,
    min: f64,
    errors: Vec<BoxErrorReport>,
    /// the robot's newest `robot/commanders` (this incarnation): seq,
    /// refused per slot (stranger, malformed)
    commanders: Option<(u64, [u64; 2], [u64; 2])>,
    /// commands refused by the robot's earlier incarnations
    base_commands: ([u64; 2], [u64; 2]),
    stranger_pids: Vec<i32>,
    /// strangers' pids heard and not yet judged ([`BoxEval::intruders`])
    unjudged: Vec<i32>,
}

impl BoxEval {
    /// At most this many errors are listed (the count goes on).
    pub const MAX_ERRORS: usize = 1000;

    /// For a run that started at `t0_ns` \[ns, CLOCK_MONOTONIC\].
    pub fn new(t0_ns: u64) -> BoxEval {
        BoxEval {
            t0_ns,
            last: None,
            base: (0, 0.0, 0),
            base_refused: RefusedStates::default(),
            min: 1.0,
            errors: Vec::new(),
            commanders: None,
            base_commands: ([0; 2], [0; 2]),
            stranger_pids: Vec::new(),
            unjudged: Vec::new(),
        }
    }

    /// A `robot/commanders` message (the simulator's or the adapter's):
    /// what it refused, kept across restarts of the robot.
    pub fn on_commanders(&mut self, m: &CommanderStats) {
        if let Some((seq, stranger, malformed)) = self.commanders {
            if m.seq < seq {
                // a new robot process: keep what the last one counted
                for k in 0..2 {
                    self.base_commands.0[k] += stranger[k];
                    self.base_commands.1[k] += malformed[k];
                }
            }
        }
        self.commanders = Some((m.seq, m.refused_stranger, m.refused_malformed));
        let pid = m.stranger_pid;
        if pid > 0 && !self.stranger_pids.contains(&pid) && !self.unjudged.contains(&pid) {
            self.unjudged.push(pid);
        }
    }

    /// The strangers whose commands the robot refused since the last call,
    /// each once over the run, that `is_stranger` confirms (not a
    /// controller the supervisor runs: one whose pid the robot learned late
    /// is not an intruder): one line each, for an `intruder` event.
    pub fn intruders(&mut self, is_stranger: impl Fn(i32) -> bool) -> Vec<String> {
        let mut out = Vec::new();
        for pid in std::mem::take(&mut self.unjudged) {
            if !is_stranger(pid) {
                continue;
            }
            self.stranger_pids.push(pid);
            out.push(format!(
                "the robot refused commands from pid {pid}, not the controller the supervisor started for the command channel: none was applied"
            ));
        }
        out
    }

    /// A `robot/box` message.
    pub fn on_box(&mut self, m: &BoxStatus) {
        let (seen_errors, restarted) = match &self.last {
            Some(l) if m.seq < l.seq => (0, true),
            Some(l) => (l.errors, false),
            None => (0, false),
        };
        if restarted {
            if let Some(l) = self.last.take() {
                self.base.0 += l.controlled;
                self.base.1 += l.success_sum;
                self.base.2 += l.recoveries;
                self.base_refused.add(&RefusedStates::of(&l));
            }
        }
        if m.errors > seen_errors && self.errors.len() < Self::MAX_ERRORS {
            // a message comes at every error: the newest is the one it names
            self.errors.push(BoxErrorReport {
                t_s: (m.last_error_ns as f64 - self.t0_ns as f64) * 1e-9,
                error: m.last_error_str().to_owned(),
            });
        }
        if m.success_min.is_finite() {
            self.min = self.min.min(m.success_min);
        }
        self.last = Some(*m);
    }

    /// The report's `robot` keys of the box (none heard: a simulated arm,
    /// the rates stay null), and a `box_error` event per error.
    pub fn fill(&self, report: &mut Report) {
        let tl = &report.torque_loop;
        report.robot.latency_us = tl.latency_us.clone();
        report.robot.missed_deadlines = tl.missed_deadlines;
        let (mut stranger, mut malformed) = self.base_commands;
        if let Some((_, s, m)) = self.commanders {
            for k in 0..2 {
                stranger[k] += s[k];
                malformed[k] += m[k];
            }
        }
        report.robot.refused.commands = RefusedCommands {
            stranger,
            malformed,
            stranger_pids: self.stranger_pids.clone(),
        };
        let Some(l) = &self.last else {
            return;
        };
        let mut states = self.base_refused;
        states.add(&RefusedStates::of(l));
        report.robot.refused.states = Some(states);
        let controlled = self.base.0 + l.controlled;
        if controlled > 0 {
            report.robot.control_command_success_rate =
                Some((self.base.1 + l.success_sum) / controlled as f64);
            report.robot.control_command_success_rate_min = Some(self.min);
        }
        report.robot.box_recoveries = self.base.2 + l.recoveries;
        report.robot.box_errors = self.errors.clone();
        for e in &self.errors {
            report.events.push(Event {
                t_s: e.t_s,
                kind: "box_error".into(),
                service: "franka".into(),
                detail: e.error.clone(),
            });
        }
        report.events.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{DetectorInfo, Evaluator};
    use phri_ipc::Zeroed;

    fn report() -> Report {
        let det = DetectorInfo {
            collision_threshold: vec![12.0; 7],
            gain: 100.0,
            dynamics: phri_config::Config::defaults().dynamics,
        };
        Evaluator::new(0, det, vec![]).report(10_000_000_000, "free-motion", Default::default())
    }

    fn status(seq: u64, controlled: u64, sum: f64, min: f64, errors: u64, at: u64) -> BoxStatus {
        let mut m = BoxStatus::zeroed();
        m.seq = seq;
        m.controlled = controlled;
        m.success_sum = sum;
        m.success_min = min;
        m.errors = errors;
        m.last_error_ns = at;
        if errors > 0 {
            m.last_error = phri_ipc::json::to_c_str("communication_constraints_violation");
        }
        m
    }

    #[test]
    fn the_rate_and_the_errors_survive_a_restart_of_the_adapter() {
        let t0 = 1_000_000_000;
        let mut e = BoxEval::new(t0);
        e.on_box(&status(1, 100, 100.0, 1.0, 0, 0));
        e.on_box(&status(2, 200, 199.0, 0.98, 0, 0));
        e.on_box(&status(3, 200, 199.0, 0.98, 1, t0 + 2_500_000_000));
        e.on_box(&status(4, 300, 298.0, 0.98, 1, t0 + 2_500_000_000));
        // the adapter restarted: its counts begin again
        e.on_box(&status(1, 100, 99.0, 0.9, 0, 0));
        e.on_box(&status(2, 100, 99.0, 0.9, 1, t0 + 7_000_000_000));
        let mut r = report();
        e.fill(&mut r);
        let rate = r.robot.control_command_success_rate.unwrap();
        assert!((rate - 397.0 / 400.0).abs() < 1e-12, "{rate}");
        assert_eq!(r.robot.control_command_success_rate_min, Some(0.9));
        assert_eq!(r.robot.box_errors.len(), 2);
        assert!((r.robot.box_errors[0].t_s - 2.5).abs() < 1e-9);
        assert!((r.robot.box_errors[1].t_s - 7.0).abs() < 1e-9);
        assert_eq!(
            r.robot.box_errors[0].error,
            "communication_constraints_violation"
        );
        assert_eq!(r.events.iter().filter(|e| e.kind == "box_error").count(), 2);
    }

    #[test]
    fn refused_states_and_commands_survive_restarts_and_strangers_are_named_once() {
        let mut e = BoxEval::new(0);
        let mut m = status(3, 100, 100.0, 1.0, 0, 0);
        m.refused_foreign = 4;
        m.refused_too_fast = 1;
        e.on_box(&m);
        // the adapter restarted: its counts begin again
        let mut m = status(1, 10, 10.0, 1.0, 0, 0);
        m.refused_foreign = 2;
        m.refused_id_ahead = 3;
        e.on_box(&m);
        let mut c = CommanderStats::zeroed();
        c.seq = 5;
        c.refused_stranger = [7, 0];
        c.stranger_pid = 4242;
        e.on_commanders(&c);
        // the robot restarted; then a controller whose pid it learned late
        let mut c = CommanderStats::zeroed();
        c.seq = 1;
        c.refused_stranger = [1, 2];
        c.refused_malformed = [0, 1];
        c.stranger_pid = 77;
        e.on_commanders(&c);
        c.seq = 2;
        e.on_commanders(&c);
        let lines = e.intruders(|pid| pid != 77);
        assert_eq!(lines.len(), 1);
        assert!(lines[0].contains("pid 4242"), "{}", lines[0]);
        assert!(e.intruders(|_| true).is_empty(), "each once");
        let mut r = report();
        e.fill(&mut r);
        let states = r.robot.refused.states.unwrap();
        assert_eq!(
            (states.foreign, states.too_fast, states.id_ahead),
            (6, 1, 3)
        );
        let commands = &r.robot.refused.commands;
        assert_eq!(commands.stranger, [8, 2]);
        assert_eq!(commands.malformed, [0, 1]);
        assert_eq!(commands.stranger_pids, vec![4242]);
    }

    #[test]
    fn a_simulated_arm_has_no_rate() {
        let mut r = report();
        BoxEval::new(0).fill(&mut r);
        assert_eq!(r.robot.control_command_success_rate, None);
        assert!(r.robot.box_errors.is_empty());
        assert_eq!(r.robot.refused.states, None);
    }
}
