//! The report's `barrier`: what the control-barrier safety filter
//! (`[avoidance] law = "cbf"`) did, from `control/barrier`. Counted from each
//! period's flags, so that a restarted controller or a takeover by the hot
//! standby neither loses nor repeats a period. A period the solver failed
//! (the reference braked to rest) degrades the run; the periods that needed
//! the slack (no motion within the joints' bounds kept every barrier) are
//! named as events, one per episode.

use phri_ipc::BarrierStatus;
use serde::Serialize;

/// Slack periods closer together than this are one episode \[s\].
const EPISODE_GAP_S: f64 = 0.1;

/// `barrier` in the report (null under the paper's law).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BarrierReport {
    /// periods the filter ran in charge (`control/barrier` messages)
    pub periods: u64,
    /// time a barrier changed the motion \[s\]
    pub braking_s: f64,
    /// time no motion within the joints' bounds kept every barrier: the
    /// slack moved the points away as well as it could \[s\]
    pub slack_s: f64,
    /// episodes of slack (periods less than 0.1 s apart are one)
    pub slack_episodes: u64,
    /// periods the solver failed: the reference braked to rest
    pub failed_periods: u64,
    /// the most active-set changes of one solve
    pub max_iterations: u64,
}

/// What happened to the filter in one message, for the run's events.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BarrierEvent {
    /// an episode of slack began
    Slack,
    /// the solver failed (one event per failed period)
    Failed,
}

impl BarrierEvent {
    /// the event's kind in the report
    pub fn kind(self) -> &'static str {
        match self {
            BarrierEvent::Slack => "barrier_slack",
            BarrierEvent::Failed => "barrier_failed",
        }
    }

    /// the event's words
    pub fn detail(self) -> &'static str {
        match self {
            BarrierEvent::Slack => {
                "no motion within the joints' bounds kept every barrier: \
                 the slack moved the points away as well as it could"
            }
            BarrierEvent::Failed => {
                "the barrier filter's solver failed: the reference braked to rest"
            }
        }
    }
}

/// The filter's figures so far.
#[derive(Clone, Debug)]
pub struct BarrierEval {
    /// the control period \[s\]
    period_s: f64,
    report: BarrierReport,
    braking_periods: u64,
    slack_periods: u64,
    /// the last period with slack \[s, the message's clock\]
    last_slack_s: Option<f64>,
}

impl BarrierEval {
    /// Nothing seen yet; the controller's period is `period_s` \[s\].
    pub fn new(period_s: f64) -> BarrierEval {
        BarrierEval {
            period_s,
            report: BarrierReport::default(),
            braking_periods: 0,
            slack_periods: 0,
            last_slack_s: None,
        }
    }

    /// A `control/barrier` message published at `t_s` \[s\]: what, if
    /// anything, the run's events must name.
    pub fn on_status(&mut self, m: &BarrierStatus, t_s: f64) -> Option<BarrierEvent> {
        let r = &mut self.report;
        r.periods += 1;
        r.max_iterations = r.max_iterations.max(m.max_iterations);
        self.braking_periods += u64::from(m.braking != 0);
        if m.failed != 0 {
            r.failed_periods += 1;
            return Some(BarrierEvent::Failed);
        }
        if m.slack == 0 {
            return None;
        }
        self.slack_periods += 1;
        let new = self
            .last_slack_s
            .is_none_or(|last| t_s - last >= EPISODE_GAP_S);
        self.last_slack_s = Some(t_s);
        r.slack_episodes += u64::from(new);
        new.then_some(BarrierEvent::Slack)
    }

    /// `barrier` in the report: None when the filter never ran.
    pub fn report(&self) -> Option<BarrierReport> {
        (self.report.periods > 0).then(|| BarrierReport {
            braking_s: self.braking_periods as f64 * self.period_s,
            slack_s: self.slack_periods as f64 * self.period_s,
            ..self.report.clone()
        })
    }

    /// The lines it adds to `degraded`: the periods the solver failed.
    pub fn degraded(&self) -> Option<String> {
        let n = self.report.failed_periods;
        (n > 0).then(|| {
            format!(
                "barrier filter failed: {n} period{} braked to rest",
                if n == 1 { "" } else { "s" }
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn msg(braking: u32, slack: u32, failed: u32, iterations: u64) -> BarrierStatus {
        BarrierStatus {
            braking,
            slack,
            failed,
            max_iterations: iterations,
            ..BarrierStatus::zeroed()
        }
    }

    #[test]
    fn periods_are_counted_from_their_flags_and_slack_in_episodes() {
        let mut e = BarrierEval::new(0.001);
        assert_eq!(e.report(), None, "no message: the paper's law");
        let mut events = Vec::new();
        for k in 0..1000u32 {
            let t = f64::from(k) * 0.001;
            // braking 100-399 ms; slack 200-219 ms and, 50 ms later, 270-279
            // ms (one episode); again 600-609 ms (another)
            let braking = u32::from((100..400).contains(&k));
            let slack = u32::from(
                (200..220).contains(&k) || (270..280).contains(&k) || (600..610).contains(&k),
            );
            let it = if k == 500 { 9 } else { 2 };
            events.extend(e.on_status(&msg(braking, slack, 0, it), t));
        }
        assert_eq!(events, [BarrierEvent::Slack, BarrierEvent::Slack]);
        let r = e.report().unwrap();
        assert_eq!(r.periods, 1000);
        assert!((r.braking_s - 0.3).abs() < 1e-9, "{r:?}");
        assert!((r.slack_s - 0.04).abs() < 1e-9, "{r:?}");
        assert_eq!(
            (r.slack_episodes, r.failed_periods, r.max_iterations),
            (2, 0, 9)
        );
        assert_eq!(e.degraded(), None);
    }

    #[test]
    fn a_failed_solve_is_an_event_and_degrades_the_run() {
        let mut e = BarrierEval::new(0.001);
        assert_eq!(e.on_status(&msg(0, 0, 0, 1), 0.0), None);
        assert_eq!(
            e.on_status(&msg(0, 0, 1, 1), 0.001),
            Some(BarrierEvent::Failed)
        );
        assert_eq!(e.report().unwrap().failed_periods, 1);
        assert_eq!(
            e.degraded().as_deref(),
            Some("barrier filter failed: 1 period braked to rest")
        );
    }
}
