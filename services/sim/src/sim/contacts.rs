//! Contacts: the robot's collision capsules posed at the current state,
//! measured against the human's capsules; each penetration gives a compliant
//! contact force ([`crate::contact`], with the body region's
//! [`crate::stiffness_n_per_m`]) whose joint torque `J_cᵀ F` enters the
//! dynamics (`truth.tau_ext`) and, beyond the wrist, the force/torque sensor.
//! A scripted push ([`super::ScriptedPush`]) is one more contact, of the
//! pushing hand on its link, with the scripted force.

use nalgebra::Vector3;
use phri_model::spatial::Force;
use phri_model::{forward_kinematics, frame_placement, CollisionObject, Data, Model, Placement};

use super::truth::keep_deepest;
use super::{ContactTruth, Simulator};
use crate::contact::{capsule_distance, contact_force_magnitude, stiffness_n_per_m};
use crate::human::{body, Human, HumanCapsule, Reach};
use phri_ipc::BodyPart;

/// Human–robot capsule pairs whose bounding spheres are farther apart than
/// this \[m\] are not measured in intermediate sub-steps: neither body moves
/// 5 cm in a sub-step.
const CULL_MARGIN: f64 = 0.05;

/// A robot collision primitive as a capsule, with its current pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotCapsule {
    /// index into `model.collisions`
    pub collision: usize,
    /// body (joint index) it rides on, `None` for the base
    pub body: Option<usize>,
    /// axis endpoints \[m\], base frame, at the current state
    pub a: Vector3<f64>,
    /// the other axis endpoint \[m\], base frame, at the current state
    pub b: Vector3<f64>,
    /// \[m\]
    pub radius: f64,
    /// shape frame in the body frame and half length \[m\] of the axis along its z
    placement: Placement,
    half_length: f64,
    /// centre \[m\] (base frame) and radius \[m\] of a sphere around the capsule
    centre: Vector3<f64>,
    bound_radius: f64,
}

impl RobotCapsule {
    /// The capsule standing in for collision object `collision` of the model
    /// ([`phri_model::Shape::capsule`]), not yet posed.
    pub(super) fn new(collision: usize, c: &CollisionObject) -> RobotCapsule {
        let (radius, half_length, rot) = c.shape.capsule();
        let placement = c.placement.compose(&Placement {
            r: rot,
            p: Vector3::zeros(),
        });
        RobotCapsule {
            collision,
            body: c.body,
            a: Vector3::zeros(),
            b: Vector3::zeros(),
            radius,
            placement,
            half_length,
            centre: Vector3::zeros(),
            bound_radius: half_length + radius,
        }
    }
}

impl Simulator {
    /// Robot capsule poses, human pose, pair distances, contact forces and
    /// `tau_ext` at the current `(t, q)`. `dt`: time since the previous
    /// evaluation, for the penetration rate (`None`: rate 0). Unless `exact`,
    /// pairs whose bounding spheres are more than [`CULL_MARGIN`] apart are
    /// skipped (they cannot touch within a sub-step); with `exact` every pair
    /// is measured, so `truth.min_distance` is exact.
    pub(super) fn update_contacts(&mut self, dt: Option<f64>, exact: bool) {
        if !self.place_robot() {
            return;
        }
        self.truth.tau_ext.fill(0.0);
        self.truth.contacts.clear();
        self.truth.contact_pairs = 0;
        self.truth.min_distance = f64::INFINITY;
        self.wrench = [0.0; 6];
        if let Some(push) = self.push {
            let f = &self.model.frames[push.frame];
            let point = frame_placement(&self.model, &self.data, push.frame).apply(&push.point);
            apply_force(
                &self.model,
                &self.data,
                &mut self.truth.tau_ext,
                &mut self.wrench,
                f.body,
                point,
                push.force,
            );
        }
        // the person out of `self` while their contacts are computed
        let Some(mut human) = self.human.take() else {
            return;
        };
        let t_human = self.human_time_s();
        let (pushing, reach) = self.scripted_push(&human, t_human);
        let capsules: &[HumanCapsule] = human.pose_reaching(t_human, reach);
        self.human_contacts(capsules, pushing, dt, exact);
        self.human = Some(human);
    }

    /// The arm's kinematics at `q` and its capsules' poses; false (a fault
    /// counted) when the model refused them.
    fn place_robot(&mut self) -> bool {
        if forward_kinematics(&self.model, &mut self.data, &self.q).is_err() {
            self.truth.faults += 1;
            return false;
        }
        for rc in self.robot.iter_mut() {
            let pose = self.data.body_placement(rc.body).compose(&rc.placement);
            let half = pose.r.column(2) * rc.half_length;
            rc.a = pose.p - half;
            rc.b = pose.p + half;
            rc.centre = pose.p;
        }
        true
    }

    /// A scripted push at the person's time `t_human` \[s\]: a contact of the
    /// hand on the link with the scripted force (the hand put there): the
    /// pushing part, and where its hand reaches.
    fn scripted_push(&mut self, human: &Human, t_human: f64) -> (Option<BodyPart>, Option<Reach>) {
        let mut pushing = None;
        let mut reach = None;
        let active = human
            .push_at(t_human)
            .map(|a| (a.keyframe, a.ramp, a.push.hand));
        if let Some((keyframe, ramp, hand)) = active {
            if let Some(sp) = self.scripted_pushes.get(keyframe).and_then(Option::as_ref) {
                let point = frame_placement(&self.model, &self.data, sp.frame).apply(&sp.point);
                let base = human.base_at(t_human);
                let horizontal = Vector3::new(point.x - base[0], point.y - base[1], 0.0);
                let d = if horizontal.norm() > 1e-6 {
                    horizontal.normalize()
                } else {
                    Vector3::new(base[2].cos(), base[2].sin(), 0.0)
                };
                let magnitude = sp.force_n * ramp;
                let force = d * magnitude;
                apply_force(
                    &self.model,
                    &self.data,
                    &mut self.truth.tau_ext,
                    &mut self.wrench,
                    sp.body,
                    point,
                    force,
                );
                self.truth.contact_pairs += 1;
                keep_deepest(
                    &mut self.truth.contacts,
                    ContactTruth {
                        collision: sp.collision,
                        part: sp.part,
                        intended: sp.intended,
                        force,
                        point,
                        depth: magnitude / stiffness_n_per_m(sp.part),
                    },
                );
                pushing = Some(sp.part);
                reach = self.robot.get(sp.collision).map(|rc| Reach {
                    hand,
                    point: hand_against(point, d, rc),
                    weight: ramp,
                });
            }
        }
        (pushing, reach)
    }

    /// Every pair of the person's `capsules` and the arm's: distances, the
    /// penetration rate over `dt` \[s\], contact forces into `tau_ext` (the
    /// `pushing` part's contacts are its scripted push's); pairs far apart
    /// culled unless `exact`.
    fn human_contacts(
        &mut self,
        capsules: &[HumanCapsule],
        pushing: Option<BodyPart>,
        dt: Option<f64>,
        exact: bool,
    ) {
        let n_robot = self.robot.len();
        for (hi, hc) in capsules.iter().enumerate() {
            let k = stiffness_n_per_m(hc.part);
            let h_centre = (hc.a + hc.b) * 0.5;
            let h_bound = (hc.b - hc.a).norm() * 0.5 + hc.radius;
            for (ri, rc) in self.robot.iter().enumerate() {
                let slot = &mut self.prev_distance[hi * n_robot + ri];
                if !exact {
                    // a lower bound of the surface distance
                    let apart = (h_centre - rc.centre).norm() - h_bound - rc.bound_radius;
                    if apart > CULL_MARGIN {
                        *slot = f64::NAN;
                        self.truth.min_distance = self.truth.min_distance.min(apart);
                        continue;
                    }
                }
                let cd = capsule_distance(&hc.a, &hc.b, hc.radius, &rc.a, &rc.b, rc.radius);
                let rate = match dt {
                    Some(dt) if slot.is_finite() => (*slot - cd.distance) / dt,
                    _ => 0.0,
                };
                *slot = cd.distance;
                self.truth.min_distance = self.truth.min_distance.min(cd.distance);
                let depth = -cd.distance;
                let magnitude = contact_force_magnitude(depth, rate, k, self.cfg.contact_damping);
                // the pushing hand's contacts are the scripted push's
                if depth <= 0.0 || pushing == Some(hc.part) {
                    continue;
                }
                self.truth.contact_pairs += 1;
                // the normal points from the human's axis to the robot's: out of the human
                let force = cd.normal * magnitude;
                let point = cd.point_b;
                apply_force(
                    &self.model,
                    &self.data,
                    &mut self.truth.tau_ext,
                    &mut self.wrench,
                    rc.body,
                    point,
                    force,
                );
                let contact = ContactTruth {
                    collision: rc.collision,
                    part: hc.part,
                    intended: self.collaborative[hc.part as usize],
                    force,
                    point,
                    depth,
                };
                keep_deepest(&mut self.truth.contacts, contact);
            }
        }
    }
}

/// Centre \[m\] of a hand pushing along `d` at `point` on robot capsule
/// `rc`: on the line through the point, back along `−d` until the hand's
/// sphere touches the capsule (at the point itself if that is already
/// outside it).
fn hand_against(point: Vector3<f64>, d: Vector3<f64>, rc: &RobotCapsule) -> Vector3<f64> {
    let touch = rc.radius + body::R_HAND;
    let axis = rc.b - rc.a;
    let len2 = axis.norm_squared();
    let mut back = 0.0;
    // the distance to the axis grows at most as fast as `back`: steps of the
    // shortfall approach the touching point from inside, never overshoot
    for _ in 0..32 {
        let c = point - d * back;
        let s = if len2 > 0.0 {
            ((c - rc.a).dot(&axis) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let short = touch - (c - (rc.a + axis * s)).norm();
        if short <= 1e-7 {
            break;
        }
        back += short;
    }
    point - d * back
}

/// Add a force `force` \[N\] (base frame) acting at `point` \[m\] (base frame)
/// on `body` to the external joint torque `tau_ext`, and to the wrist sensor's
/// `wrench` (force, then moment about the last link's origin) when the body
/// is the last link or beyond it. Needs the body placements and motion
/// subspaces of `data` (after forward kinematics).
fn apply_force(
    model: &Model,
    data: &Data,
    tau_ext: &mut [f64],
    wrench: &mut [f64; 6],
    body: Option<usize>,
    point: Vector3<f64>,
    force: Vector3<f64>,
) {
    let w = Force {
        n: point.cross(&force),
        f: force,
    };
    let mut b = body;
    while let Some(j) = b {
        // a mimic joint acts on its leader's column (S_j carries the multiplier)
        tau_ext[model.joints[j].idx_v] += data.s[j].dot(&w);
        b = model.joints[j].parent;
    }
    let last = model.nv() - 1;
    if body.is_some_and(|b| model.supports(last, b)) {
        let m = (point - data.body[last].p).cross(&force);
        for a in 0..3 {
            wrench[a] += force[a];
            wrench[3 + a] += m[a];
        }
    }
}
