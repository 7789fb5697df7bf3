//! `robot/state` from the control box's state.

use phri_ipc::{robot_status, JointState, MAX_DOF};
use phri_robot::LinkOutput;

use crate::cycle::JOINTS;

/// Fill `state` for state `seq`: the measured joints `q` \[rad\] and the
/// joint torques `tau` \[Nm\] applied ([`crate::FciCycle::applied`]), the protocol's status
/// of the last period (`link`), stamped `stamp_ns` on the robot's clock and
/// published at `published_ns`.
pub fn fill_state(
    q: &[f64; JOINTS],
    tau: &[f64; JOINTS],
    link: &LinkOutput,
    seq: u64,
    stamp_ns: u64,
    published_ns: u64,
    state: &mut JointState,
) {
    let n = JOINTS.min(MAX_DOF);
    state.seq = seq;
    state.dof = n as u32;
    state.q[..n].copy_from_slice(&q[..n]);
    state.tau[..n].copy_from_slice(&tau[..n]);
    // under the brakes the box holds the arm with a torque of its own
    state.status = match link.status & robot_status::BRAKING {
        0 => link.status,
        _ => link.status | robot_status::TORQUE_UNKNOWN,
    };
    state.wrench = [0.0; 6];
    state.command_seq = link.command_seq;
    state.missed_commands = link.missed;
    state.stamp_ns = stamp_ns;
    state.published_ns = published_ns;
}
