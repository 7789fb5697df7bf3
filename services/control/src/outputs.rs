//! The one conversion from a step's result to the cell's messages:
//! `robot/command`, `control/status`, `collab/state`, `control/ssm` and
//! `control/barrier`, for `main.rs` and the lock-step cell.

use phri_ipc::{
    BarrierStatus, CollabState, ControlStatus, JointState, SsmStatus, TorqueCommand, Zeroed,
};

use crate::controller::Controller;

/// When the controller woke for a state and when its answer was ready
/// [ns, CLOCK_MONOTONIC] (the lock-step cell may pass its robot clock).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stamps {
    /// the controller woke for the state
    pub woke_ns: u64,
    /// its answer was ready (the messages' stamp)
    pub done_ns: u64,
}

/// Fill the command and the status answering `state` from the controller
/// after its step (the torque, mode and counters of that step); `seq` numbers
/// both. Every field of both messages is written.
pub fn write_messages(
    ctl: &Controller,
    state: &JointState,
    seq: u64,
    stamps: Stamps,
    cmd: &mut TorqueCommand,
    status: &mut ControlStatus,
) {
    let tau = ctl.tau();
    let n = tau.len();
    cmd.seq = seq;
    cmd.stamp_ns = stamps.done_ns;
    cmd.state_seq = state.seq;
    cmd.state_stamp_ns = state.stamp_ns;
    cmd.dof = n as u32;
    cmd.mode = ctl.mode() as u32;
    cmd.tau = [0.0; phri_ipc::MAX_DOF];
    cmd.tau[..n].copy_from_slice(tau);

    let c = ctl.counters();
    status.seq = seq;
    status.stamp_ns = stamps.done_ns;
    status.state_seq = state.seq;
    status.state_stamp_ns = state.stamp_ns;
    status.mode = ctl.mode() as u32;
    status.reaction = ctl.reaction() as u32;
    status.waypoints_reached = c.waypoints_reached;
    status.detections = c.detections;
    status.protective_stops = c.protective_stops;
    status.resumes = c.resumes;
    status.residual_age_ns = ctl.residual_age_ns();
    status.q_ref = [0.0; phri_ipc::MAX_DOF];
    status.q_ref[..n].copy_from_slice(ctl.q_ref());
    let ee = ctl.ee();
    status.ee = [ee.x, ee.y, ee.z];
    status.compute_ns = stamps.done_ns.saturating_sub(stamps.woke_ns);
    status.wake_latency_ns = stamps.woke_ns.saturating_sub(state.published_ns);
    status.perception_age_ns = ctl.perception_age_ns();
    status.min_distance = ctl.last_min_distance();
    status.risk = ctl.risk();
    status.task_scale = ctl.task_scale();
    status.model_errors = ctl.model_errors();
}

/// Fill `collab/state` for the period that answered `state` (`seq` numbers
/// it, `stamp_ns` [ns, CLOCK_MONOTONIC] is its publish time). Every field is
/// written; without a collaboration layer the phase is `idle`.
pub fn write_collab_state(
    ctl: &Controller,
    state: &JointState,
    seq: u64,
    stamp_ns: u64,
    out: &mut CollabState,
) {
    *out = CollabState::zeroed();
    out.seq = seq;
    out.stamp_ns = stamp_ns;
    out.state_stamp_ns = state.stamp_ns;
    out.robot_frame = -1;
    out.person = u32::MAX;
    out.hand_age_ns = u64::MAX;
    let Some(c) = ctl.collaboration() else {
        return;
    };
    let m = c.machine();
    out.phase = m.phase() as u32;
    out.reason = m.reason() as u32;
    out.person = m.person();
    out.human_part = m.part() as u32;
    if m.active() {
        out.robot_frame = c.robot_frame() as i32;
    }
    if let Some(a) = c.last_answer() {
        out.request_source = a.request.source;
        out.request_kind = a.request.kind;
        out.request_part = a.request.part;
        out.request_accepted = a.answer.accepted as u32;
        out.request_reason = a.answer.reason as u32;
        out.request_seq = a.request.seq;
        out.request_stamp_ns = a.request.stamp_ns;
    }
    if let Some(h) = c.hand() {
        out.hand = [h.x, h.y, h.z];
    }
    if let Some(t) = c.hand_capture_ns() {
        out.hand_age_ns = state.stamp_ns.saturating_sub(t);
    }
    if let Some(e) = c.estimate().filter(|_| m.active()) {
        out.unexplained_norm = e.unexplained;
        let n = e.n.min(out.forces.len());
        out.n_forces = n as u32;
        for (f, i) in out.forces.iter_mut().zip(0..n) {
            f.point = [e.points[i].x, e.points[i].y, e.points[i].z];
            f.force = [e.forces[i].x, e.forces[i].y, e.forces[i].z];
            f.frame = c.contact_frame() as i32;
            f.observable = e.observable[i] as u32;
        }
    }
}

/// Fill `control/ssm` for the period that answered `state` (`seq` numbers
/// it, `stamp_ns` [ns, CLOCK_MONOTONIC] is its publish time). Every field is
/// written.
pub fn write_ssm_status(
    ctl: &Controller,
    state: &JointState,
    seq: u64,
    stamp_ns: u64,
    out: &mut SsmStatus,
) {
    let p = ctl.ssm_period();
    let c = ctl.ssm_counters();
    *out = SsmStatus {
        seq,
        stamp_ns,
        state_stamp_ns: state.stamp_ns,
        enabled: u32::from(ctl.ssm_enabled()),
        monitoring: u32::from(p.reaction_s.is_finite()),
        limiting: u32::from(p.limiting),
        violating: u32::from(p.violating),
        limited_periods: c.limited_periods,
        violation_periods: c.violation_periods,
        violations: c.violations,
        violations_standard: c.violations_standard,
        min_margin_m: p.min_margin_m,
        human_speed_m_s: p.human_speed_m_s,
        reaction_s: p.reaction_s,
    };
}

/// Fill `control/barrier` for the period that answered `state` (`seq`
/// numbers it, `stamp_ns` [ns, CLOCK_MONOTONIC] is its publish time) from
/// the control-barrier filter's counts, `out` holding the message of this
/// controller's last period in charge (or zeroed): this period's flags are
/// the counts that grew since. Every field is written; false (and `out` as
/// it was) under the paper's law, which publishes nothing.
pub fn write_barrier_status(
    ctl: &Controller,
    state: &JointState,
    seq: u64,
    stamp_ns: u64,
    out: &mut BarrierStatus,
) -> bool {
    let Some(c) = ctl.cbf_counters() else {
        return false;
    };
    let grew = |now: u64, before: u64| u32::from(now > before);
    *out = BarrierStatus {
        seq,
        stamp_ns,
        state_stamp_ns: state.stamp_ns,
        braking: grew(c.braking_periods, out.braking_periods),
        slack: grew(c.slack_periods, out.slack_periods),
        failed: grew(c.infeasible_periods, out.failed_periods),
        _pad: 0,
        periods: c.periods,
        braking_periods: c.braking_periods,
        slack_periods: c.slack_periods,
        failed_periods: c.infeasible_periods,
        max_iterations: c.max_iterations,
    };
    true
}
