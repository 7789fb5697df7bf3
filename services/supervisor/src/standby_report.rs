//! `control` in the report: the hot standby's takeovers, from the robot
//! adapter's `robot/commanders` (cumulative counts, 10 Hz and at every
//! takeover). A restarted adapter counts anew: its counts add to its
//! predecessor's.

use std::collections::BTreeMap;

use phri_ipc::{residual_flags, CommanderStats, Residual, ROBOT_COMMAND, ROBOT_COMMAND_STANDBY};
use serde::Serialize;

/// The command channel of slot `s` (0: `robot/command`, 1: `robot/command/standby`).
fn channel(slot: u32) -> &'static str {
    match slot {
        0 => ROBOT_COMMAND.name,
        _ => ROBOT_COMMAND_STANDBY.name,
    }
}

/// One takeover: the controller not in charge answered for the one in charge.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TakeoverReport {
    /// when \[s\] since the cell started
    pub t_s: f64,
    /// the command channel of the controller that took over
    pub to: String,
    /// the state it answered
    pub state_seq: u64,
    /// the largest joint difference between its command and the last one
    /// applied before \[Nm\]
    pub command_diff_nm: f64,
}

/// `control` in the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ControlReport {
    /// a hot standby ran (`[control] standby`)
    pub standby: bool,
    /// every takeover, with its time and the command difference
    pub takeovers: Vec<TakeoverReport>,
    /// takeovers counted by the adapter but not seen one by one (two within
    /// one message); they count in `takeover_count`
    pub takeovers_unlisted: u64,
    /// every takeover the adapter counted, summed over its restarts
    pub takeover_count: u64,
    /// periods each controller's fresh command was applied, by its command channel
    pub periods_commanded: BTreeMap<String, u64>,
    /// periods both controllers answered the same state
    pub both_answered: u64,
    /// the largest command difference at a takeover \[Nm\] (null: none)
    pub max_takeover_diff_nm: Option<f64>,
    /// the largest joint difference between the two controllers' answers to
    /// the same state \[Nm\] (null: never both)
    pub max_answer_diff_nm: Option<f64>,
    /// the yardstick of `max_takeover_diff_nm`: the largest joint change of
    /// the applied command from one period to the next without a takeover
    /// \[Nm\] (null: no two fresh periods)
    pub max_period_step_nm: Option<f64>,
}

/// Reads `robot/commanders` into a [`ControlReport`].
#[derive(Clone, Debug, Default)]
pub struct StandbyEvaluator {
    report: ControlReport,
    /// the adapter's counts before its last restart: periods per slot, both, takeovers
    base: ([u64; 2], u64, u64),
    last: Option<CommanderStats>,
    max_answer: f64,
    max_takeover: f64,
    max_step: f64,
}

impl StandbyEvaluator {
    /// An evaluator with nothing read yet (`standby`: a hot standby runs).
    pub fn new(standby: bool) -> StandbyEvaluator {
        StandbyEvaluator {
            report: ControlReport {
                standby,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// A `robot/commanders` message, published at `t_s` \[s\] since the cell started.
    pub fn on_commanders(&mut self, m: &CommanderStats, t_s: f64) {
        let prev = match self.last {
            // a restarted adapter: its predecessor's counts are the base
            Some(l) if m.seq < l.seq => {
                self.base.0[0] += l.periods[0];
                self.base.0[1] += l.periods[1];
                self.base.1 += l.both_answered;
                self.base.2 += l.takeovers;
                None
            }
            other => other,
        };
        let before = prev.map_or(0, |p| p.takeovers);
        let new = m.takeovers.saturating_sub(before);
        if new > 0 {
            self.report.takeovers.push(TakeoverReport {
                t_s,
                to: channel(m.last_takeover_to).into(),
                state_seq: m.last_takeover_state_seq,
                command_diff_nm: m.last_takeover_diff_nm,
            });
            self.report.takeovers_unlisted += new - 1;
        }
        if m.takeovers > 0 {
            self.max_takeover = self.max_takeover.max(m.max_takeover_diff_nm);
        }
        if m.both_answered > 0 {
            self.max_answer = self.max_answer.max(m.max_answer_diff_nm);
        }
        if m.max_step_nm.is_finite() {
            self.max_step = self.max_step.max(f64::from(m.max_step_nm));
        }
        self.last = Some(*m);
    }

    /// The report so far.
    pub fn report(&self) -> ControlReport {
        let mut r = self.report.clone();
        let l = self.last.unwrap_or_else(phri_ipc::Zeroed::zeroed);
        let periods = [self.base.0[0] + l.periods[0], self.base.0[1] + l.periods[1]];
        r.periods_commanded = (0..2)
            .map(|s| (channel(s as u32).to_string(), periods[s]))
            .collect();
        r.both_answered = self.base.1 + l.both_answered;
        r.takeover_count = self.base.2 + l.takeovers;
        r.max_takeover_diff_nm = (r.takeover_count > 0).then_some(self.max_takeover);
        r.max_answer_diff_nm = (r.both_answered > 0).then_some(self.max_answer);
        r.max_period_step_nm = (self.max_step > 0.0).then_some(self.max_step);
        r
    }
}

/// `dynamics` in the report: the two residual services side by side.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DynamicsReport {
    /// the hot standby's residual ran (`[control] standby`)
    pub standby: bool,
    /// states both residuals answered, both valid
    pub residuals_compared: u64,
    /// the largest joint difference between their residuals of the same
    /// state \[Nm\] (null: never both)
    pub max_residual_disagreement_nm: Option<f64>,
}

/// Residuals kept per service to meet the other's of the same state.
const KEPT: usize = 64;

/// Compares `dynamics/residual` with `dynamics/residual/standby` state by state.
#[derive(Clone, Debug)]
pub struct ResidualPair {
    /// per service: (state, residual) of the newest valid ones, a ring
    kept: [Vec<(u64, Residual)>; 2],
    next: [usize; 2],
    report: DynamicsReport,
    max: f64,
}

impl ResidualPair {
    /// A pair with nothing read yet (`standby`: the standby's residual runs).
    pub fn new(standby: bool) -> ResidualPair {
        ResidualPair {
            kept: [Vec::with_capacity(KEPT), Vec::with_capacity(KEPT)],
            next: [0, 0],
            report: DynamicsReport {
                standby,
                ..Default::default()
            },
            max: 0.0,
        }
    }

    /// A residual of service `slot` (0: `dynamics/residual`, 1: the standby's).
    pub fn on_residual(&mut self, slot: usize, r: &Residual) {
        if slot > 1 || r.flags & residual_flags::VALID == 0 {
            return;
        }
        let n = (r.dof as usize).min(r.r.len());
        if let Some((_, other)) = self.kept[1 - slot].iter().find(|(s, _)| *s == r.state_seq) {
            if other.dof == r.dof {
                let d = (0..n).fold(0.0f64, |m, k| m.max((r.r[k] - other.r[k]).abs()));
                self.max = self.max.max(d);
                self.report.residuals_compared += 1;
            }
        }
        let kept = &mut self.kept[slot];
        if kept.len() < KEPT {
            kept.push((r.state_seq, *r));
        } else {
            kept[self.next[slot]] = (r.state_seq, *r);
        }
        self.next[slot] = (self.next[slot] + 1) % KEPT;
    }

    /// The report so far.
    pub fn report(&self) -> DynamicsReport {
        let mut r = self.report.clone();
        r.max_residual_disagreement_nm = (r.residuals_compared > 0).then_some(self.max);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn stats(seq: u64, periods: [u64; 2], takeovers: u64, diff: f64) -> CommanderStats {
        CommanderStats {
            seq,
            periods,
            both_answered: periods[0],
            takeovers,
            last_takeover_to: (takeovers % 2) as u32,
            last_takeover_state_seq: periods[0] + periods[1],
            last_takeover_diff_nm: diff,
            max_takeover_diff_nm: diff,
            max_answer_diff_nm: 0.01,
            max_step_nm: 0.5 * seq as f32,
            ..CommanderStats::zeroed()
        }
    }

    #[test]
    fn takeovers_are_listed_with_their_time_and_counted_across_an_adapter_restart() {
        let mut e = StandbyEvaluator::new(true);
        e.on_commanders(&stats(1, [100, 0], 0, 0.0), 0.1);
        e.on_commanders(&stats(2, [150, 50], 1, 0.4), 0.2);
        e.on_commanders(&stats(3, [150, 150], 1, 0.4), 0.3);
        // the adapter restarts: counts anew
        e.on_commanders(&stats(1, [80, 0], 0, 0.0), 1.0);
        e.on_commanders(&stats(2, [90, 10], 1, 0.2), 1.1);
        let r = e.report();
        assert_eq!(r.takeover_count, 2);
        assert_eq!(r.takeovers.len(), 2);
        assert_eq!(r.takeovers[0].t_s, 0.2);
        assert_eq!(r.takeovers[0].to, "robot/command/standby");
        assert_eq!(r.takeovers[0].command_diff_nm, 0.4);
        assert_eq!(r.takeovers[1].state_seq, 100);
        assert_eq!(r.periods_commanded["robot/command"], 240);
        assert_eq!(r.periods_commanded["robot/command/standby"], 160);
        assert_eq!(r.max_takeover_diff_nm, Some(0.4));
        assert_eq!(r.max_answer_diff_nm, Some(0.01));
        // the largest step over both adapters' runs
        assert_eq!(r.max_period_step_nm, Some(1.5));
    }

    #[test]
    fn residuals_of_the_same_state_are_compared_and_warm_ups_are_not() {
        let residual = |seq: u64, r0: f64, valid: bool| {
            let mut r = Residual::zeroed();
            r.state_seq = seq;
            r.dof = 7;
            r.r[0] = r0;
            r.flags = if valid { residual_flags::VALID } else { 0 };
            r
        };
        let mut p = ResidualPair::new(true);
        for seq in 1..=100 {
            p.on_residual(0, &residual(seq, 1.0, true));
        }
        // the standby's answers to states 60..100 (the older ones left the ring)
        for seq in 60..=100 {
            p.on_residual(1, &residual(seq, 1.25, seq > 70));
        }
        let r = p.report();
        assert_eq!(r.residuals_compared, 30);
        assert_eq!(r.max_residual_disagreement_nm, Some(0.25));
        assert!(ResidualPair::new(false)
            .report()
            .max_residual_disagreement_nm
            .is_none());
    }

    #[test]
    fn without_takeovers_no_difference_is_reported() {
        let mut e = StandbyEvaluator::new(false);
        e.on_commanders(&stats(1, [100, 0], 0, 0.0), 0.1);
        let r = e.report();
        assert_eq!((r.takeover_count, r.max_takeover_diff_nm), (0, None));
        assert!(r.takeovers.is_empty() && !r.standby);
    }
}
