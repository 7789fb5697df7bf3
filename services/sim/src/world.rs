//! The simulated world as the camera sees it: the `sim/world` message.

use phri_ipc::{WorldState, MAX_HUMAN_CAPSULES};

use crate::{BodyPart, Simulator};

/// Fill `world` with the arm's true joint positions \[rad\] and the human's
/// capsules (base frame) at the simulator's current time, stamped `seq` and
/// `stamp_ns` (robot clock). Allocates nothing.
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
        dst.part = BodyPart::ALL
            .iter()
            .position(|p| *p == h.part)
            .map_or(-1, |i| i as i32);
    }
}
