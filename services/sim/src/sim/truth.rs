//! What the simulator reports after a step: the sensors' [`Measurement`]
//! (what a controller may see) and the ground [`Truth`] (evaluation only),
//! with the bookkeeping that keeps the deepest contacts.

use nalgebra::Vector3;
use phri_ipc::BodyPart;
use phri_model::Model;

use super::{Simulator, MAX_CONTACTS};

/// What the robot's sensors report after a step.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// simulation time at the end of the step \[s\]
    pub t_s: f64,
    /// joint positions \[rad\], quantized to the encoder resolution
    pub q: Vec<f64>,
    /// the torque the drives applied [N·m]: the command clamped to the effort
    /// limits, or while braking the brake torque (mean over the period);
    /// neither includes the torque noise or friction
    pub tau_applied: Vec<f64>,
    /// wrist force/torque sensor (only with `ft_sensor`): external force \[N\]
    /// then moment [N·m] on the last link, base-frame axes, moment about the
    /// last joint's link frame origin
    pub wrench: Option<[f64; 6]>,
}

/// One contact between the human and a robot capsule (ground truth): a
/// penetration of the capsules, or a scripted push of a hand on a link
/// ([`super::ScriptedPush`]: `depth` is then the force over the hand's stiffness).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactTruth {
    /// index into `model.collisions` of the robot capsule (link name via
    /// [`Simulator::collision_link`])
    pub collision: usize,
    /// the human body part
    pub part: BodyPart,
    /// intended (collaboration) rather than a collision: a capsule contact
    /// is intended when the human part is one of the scenario's
    /// `collaborative_parts` (whatever robot capsule it touches); a scripted
    /// push as its keyframe says
    pub intended: bool,
    /// force on the robot \[N\], base frame
    pub force: Vector3<f64>,
    /// application point on the robot capsule's surface \[m\], base frame
    pub point: Vector3<f64>,
    /// penetration depth \[m\] (> 0)
    pub depth: f64,
}

impl ContactTruth {
    /// Name of the robot link touched (`model` is the simulator's, see [`Simulator::model`]).
    pub fn link<'m>(&self, model: &'m Model) -> &'m str {
        model
            .collisions
            .get(self.collision)
            .map_or("", |c| c.link.as_str())
    }
}

/// Ground truth after a step, for evaluation only (a controller must not read it).
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    /// simulation time \[s\]
    pub t_s: f64,
    /// joint positions \[rad\] and velocities [rad/s], unquantized
    pub q: Vec<f64>,
    /// joint velocities \[rad/s\], unquantized
    pub qd: Vec<f64>,
    /// external joint torque `Σ J_cᵀ F` of every contact at the current state [N·m]
    pub tau_ext: Vec<f64>,
    /// torque the motors or brakes really applied (noise included), mean over the last period [N·m]
    pub tau_motor: Vec<f64>,
    /// friction torque, mean over the last period [N·m]
    pub tau_friction: Vec<f64>,
    /// the deepest contacts at the current state (at most [`MAX_CONTACTS`])
    pub contacts: Vec<ContactTruth>,
    /// number of penetrating human–robot capsule pairs, plus one while a
    /// scripted push acts (may exceed `contacts.len()`)
    pub contact_pairs: usize,
    /// smallest surface distance between any human and robot capsule \[m\],
    /// negative when penetrating; +∞ without a human
    pub min_distance: f64,
    /// sub-steps whose dynamics failed (left the state unchanged); 0 in a sane run
    pub faults: u64,
}

impl Simulator {
    /// Copy the state into the measurement (quantized, with the wrist sensor's
    /// wrench) and the truth.
    pub(super) fn update_readings(&mut self) {
        let res = self.cfg.encoder_resolution_rad;
        self.meas.t_s = self.t;
        for i in 0..self.n {
            self.meas.q[i] = if res > 0.0 {
                (self.q[i] / res).round() * res
            } else {
                self.q[i]
            };
        }
        self.meas.wrench = self.cfg.ft_sensor.then_some(self.wrench);
        self.truth.t_s = self.t;
        self.truth.q.copy_from_slice(&self.q);
        self.truth.qd.copy_from_slice(&self.qd);
    }
}

/// Insert `c` into `list` (capacity [`MAX_CONTACTS`]), replacing the
/// shallowest contact when full and `c` is deeper.
pub(super) fn keep_deepest(list: &mut Vec<ContactTruth>, c: ContactTruth) {
    if list.len() < MAX_CONTACTS {
        list.push(c);
        return;
    }
    if let Some((i, shallowest)) = list
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.depth.total_cmp(&b.1.depth))
    {
        if c.depth > shallowest.depth {
            list[i] = c;
        }
    }
}
