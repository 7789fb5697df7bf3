//! The control box behind a real robot's adapter, for the report: FCI's
//! command success rate and every error of the box with its time, from
//! `robot/box` (kept across restarts of the adapter).

use phri_ipc::BoxStatus;
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

/// `robot/box` over a run.
#[derive(Debug)]
pub struct BoxEval {
    t0_ns: u64,
    /// the adapter's newest message (this incarnation)
    last: Option<BoxStatus>,
    /// sums of the adapter's earlier incarnations: controlled states, rate sum, recoveries
    base: (u64, f64, u64),
    min: f64,
    errors: Vec<BoxErrorReport>,
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
            min: 1.0,
            errors: Vec::new(),
        }
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
        let Some(l) = &self.last else {
            return;
        };
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
    fn a_simulated_arm_has_no_rate() {
        let mut r = report();
        BoxEval::new(0).fill(&mut r);
        assert_eq!(r.robot.control_command_success_rate, None);
        assert!(r.robot.box_errors.is_empty());
    }
}
