//! Everything the run's report is built from, fed by what flows on the
//! channels: the main evaluator ([`Evaluator`]: the torque loop, contacts,
//! perception, events), the collaboration's, the robot box's, the hot
//! standby's, the residual pair's and the refused inputs'. The supervision's
//! records and degradations land here too ([`Evaluation::apply`]).

use std::collections::BTreeMap;

use crate::barrier_report::BarrierEval;
use crate::box_report::BoxEval;
use crate::collab_report::CollabEvaluator;
use crate::cpu::CpuReport;
use crate::owned::AuditLog;
use crate::realtime::RealtimeReport;
use crate::report::{Evaluator, Report, ServiceReport};
use crate::standby_report::{ResidualPair, StandbyEvaluator};
use crate::supervision::Action;
use crate::Plan;

/// The run's evaluators, from the cell's start.
pub struct Evaluation {
    /// the torque loop, contacts, perception, the run's events and degradations
    pub eval: Evaluator,
    /// the collaboration: requests, utterances, touches
    pub collab: CollabEvaluator,
    /// the robot box: refused states and commands, its errors, intruders
    pub boxes: BoxEval,
    /// the hot standby's takeovers
    pub standby: StandbyEvaluator,
    /// the two residuals of a hot-standby pair
    pub residuals: ResidualPair,
    /// the inputs the services refused
    pub audits: AuditLog,
    /// the control-barrier filter
    pub barrier: BarrierEval,
    /// the configured reaction to a collision, as the events name it
    pub reaction: &'static str,
}

impl Evaluation {
    /// The evaluation of `plan`'s run, its clock from `cell_start_ns`.
    pub fn new(plan: &Plan, cell_start_ns: u64) -> Evaluation {
        let standby = plan.loaded.config.control.standby;
        Evaluation {
            eval: plan.evaluator(cell_start_ns),
            collab: plan.collab_evaluator(cell_start_ns),
            boxes: BoxEval::new(cell_start_ns),
            standby: StandbyEvaluator::new(standby),
            residuals: ResidualPair::new(standby),
            audits: AuditLog::default(),
            barrier: BarrierEval::new(plan.loaded.config.sim.dt_s),
            reaction: plan.reaction().name(),
        }
    }

    /// A `control/barrier` message: the filter's figures, and an event for
    /// a failed solve or an episode of slack.
    pub fn on_barrier(&mut self, m: &phri_ipc::BarrierStatus) {
        let t_s = self.eval.time_s(m.stamp_ns);
        if let Some(e) = self.barrier.on_status(m, t_s) {
            self.eval.event(m.stamp_ns, e.kind(), "control", e.detail());
        }
    }

    /// Take the report's part of a supervision `action` (an event, a
    /// degradation); false: not the report's.
    pub fn apply(&mut self, action: &Action) -> bool {
        match action {
            Action::Record {
                at_ns,
                kind,
                service,
                detail,
            } => self.eval.event(*at_ns, kind, service, detail.clone()),
            Action::Degrade(reason) => self.eval.degrade(reason.clone()),
            _ => return false,
        }
        true
    }

    /// The report of `plan`'s run that ended at `end_ns`, with the
    /// services' bookkeeping, CPU use and real-time scheduling, judged.
    pub fn report(
        &mut self,
        plan: &Plan,
        end_ns: u64,
        services: BTreeMap<String, ServiceReport>,
        cpu: BTreeMap<String, CpuReport>,
        realtime: RealtimeReport,
    ) -> Report {
        self.eval.set_realtime(realtime);
        let inputs = self.audits.report();
        for line in inputs.degraded() {
            self.eval.degrade(line);
        }
        if let Some(line) = self.barrier.degraded() {
            self.eval.degrade(line);
        }
        let mut report = self.eval.report(end_ns, plan.scenario_name(), services);
        report.inputs = inputs;
        report.cpu = cpu;
        report.control = self.standby.report();
        report.dynamics = self.residuals.report();
        report.barrier = self.barrier.report();
        report.robot = plan.robot_report();
        self.boxes.fill(&mut report);
        (
            report.robot.max_joint_step_rad,
            report.robot.max_joint_step_t_s,
        ) = self.eval.max_joint_step();
        (
            report.robot.max_restart_step_rad,
            report.robot.max_restart_step_t_s,
        ) = self.eval.max_restart_step();
        report.collaboration = self
            .collab
            .report(report.contacts.iter().map(|c| (c.intended, c.peak_force_n)));
        if !self.eval.has_truth() {
            // a real arm: the collaboration's touches as F̂ tells them
            let link = &plan.loaded.config.collaboration.robot_link;
            self.collab.judge_estimated(&mut report.iso_ts_15066, link);
        }
        // judged from everything the report holds now
        self.eval.conclude(&mut report);
        report
    }
}
