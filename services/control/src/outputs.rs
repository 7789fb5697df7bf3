//! The one conversion from a step's result to the cell's messages:
//! `robot/command` and `control/status`, for `main.rs` and the lock-step cell.

use phri_ipc::{ControlStatus, JointState, TorqueCommand};

use crate::controller::Controller;

/// When the controller woke for a state and when its answer was ready
/// [ns, CLOCK_MONOTONIC] (the lock-step cell may pass its robot clock).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stamps {
    pub woke_ns: u64,
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
