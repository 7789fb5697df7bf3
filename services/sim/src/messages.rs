//! The simulator's state as the cell's messages: `robot/state`
//! ([`JointState`], what a real arm would report), `sim/truth` ([`Truth`],
//! evaluation only) and `sim/world` ([`WorldState`], what the simulated
//! camera renders). Used by `phri-sim` and by the lock-step cell alike; each
//! fills a preallocated message and allocates nothing.

use phri_ipc::{
    robot_status, JointState, Truth, WorldState, MAX_CONTACTS, MAX_DOF, MAX_HUMAN_CAPSULES,
};

use crate::link::LinkOutput;
use crate::Simulator;

/// Fill `state` with the arm's measurement after a step (quantized joint
/// positions \[rad\], the applied torque [N·m], the wrist wrench when the
/// sensor is on) and the link's decision for that period (`status` bits,
/// command applied, missed commands). `stamp_ns` is the measurement time on
/// the robot's clock, `published_ns` when it goes out.
pub fn fill_state(
    sim: &Simulator,
    link: &LinkOutput,
    seq: u64,
    stamp_ns: u64,
    published_ns: u64,
    state: &mut JointState,
) {
    let m = sim.measurement();
    let n = m.q.len().min(MAX_DOF);
    state.seq = seq;
    state.dof = n as u32;
    state.q[..n].copy_from_slice(&m.q[..n]);
    state.tau[..n].copy_from_slice(&m.tau_applied[..n]);
    state.status = link.status
        | if m.wrench.is_some() {
            robot_status::FT_VALID
        } else {
            0
        };
    state.wrench = m.wrench.unwrap_or([0.0; 6]);
    state.command_seq = link.command_seq;
    state.missed_commands = link.missed;
    state.stamp_ns = stamp_ns;
    state.published_ns = published_ns;
}

/// Fill `truth` with the simulator's ground truth at its current state
/// (unquantized joint positions \[rad\] and velocities [rad/s], external joint
/// torque [N·m], the deepest contacts, base frame), for state `seq` stamped
/// `stamp_ns` (robot clock).
pub fn fill_truth(sim: &Simulator, seq: u64, stamp_ns: u64, truth: &mut Truth) {
    let t = sim.truth();
    let n = t.q.len().min(MAX_DOF);
    truth.seq = seq;
    truth.stamp_ns = stamp_ns;
    truth.state_seq = seq;
    truth.dof = n as u32;
    truth.tau_ext[..n].copy_from_slice(&t.tau_ext[..n]);
    truth.q[..n].copy_from_slice(&t.q[..n]);
    truth.qd[..n].copy_from_slice(&t.qd[..n]);
    truth.min_distance = t.min_distance;
    truth.n_contacts = t.contacts.len().min(MAX_CONTACTS) as u32;
    for (dst, c) in truth.contacts.iter_mut().zip(&t.contacts) {
        dst.robot_object = c.collision as i32;
        dst.human_part = c.part as i32;
        dst.intended = c.intended as u32;
        dst.force = [c.force.x, c.force.y, c.force.z];
        dst.point = [c.point.x, c.point.y, c.point.z];
        dst.depth = c.depth;
    }
}

/// Fill `world` with the arm's true joint positions \[rad\] and the human's
/// capsules (base frame) at the simulator's current time, stamped `seq` and
/// `stamp_ns` (robot clock).
pub fn fill_world(sim: &Simulator, seq: u64, stamp_ns: u64, world: &mut WorldState) {
    let t = sim.truth();
    let n = t.q.len().min(world.q.len());
    world.seq = seq;
    world.stamp_ns = stamp_ns;
    world.dof = n as u32;
    world.q[..n].copy_from_slice(&t.q[..n]);
    let humans = sim.human_capsules();
    world.n_human = humans.len().min(MAX_HUMAN_CAPSULES) as u32;
    for (dst, h) in world.human.iter_mut().zip(humans) {
        dst.a = [h.a.x, h.a.y, h.a.z];
        dst.b = [h.b.x, h.b.y, h.b.z];
        dst.radius = h.radius;
        dst.part = h.part as i32;
    }
}
