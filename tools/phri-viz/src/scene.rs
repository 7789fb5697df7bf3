//! The 3-D scene as `foxglove.SceneUpdate`s, one per topic, each a whole
//! replacement (every earlier entity of the topic deleted, the current ones
//! added), all posed in the base frame \[m\].

use foxglove::messages::Color;
use foxglove::messages::{
    scene_entity_deletion, FrameTransform, FrameTransforms, KeyValuePair, SceneEntity,
    SceneEntityDeletion, SceneUpdate,
};
use nalgebra::Vector3;
use phri_ipc::{
    BodyPart, CollabPart, CollabPhase, CollabState, FrameHeader, HandObservation, JointState,
    RepulsionResult, WorldState, MAX_DOF,
};

use crate::geometry::{arrow, capsule, rgba, rotation, segments, sphere, timestamp, vec3};
use crate::{BASE_FRAME, CAMERA_FRAME};
use phri_view::RobotView;

/// Robot links.
pub const ROBOT_COLOR: Color = rgba(0.55, 0.6, 0.7, 0.9);
/// The robot link allowed to touch the person in a collaboration.
pub const ROBOT_COLLAB_COLOR: Color = rgba(0.2, 0.75, 0.35, 0.95);
/// The person's capsules.
pub const PERSON_COLOR: Color = rgba(0.95, 0.65, 0.4, 0.8);
/// The person's collaborative part, and the collaborative hand.
pub const COLLAB_PART_COLOR: Color = rgba(0.2, 0.8, 0.3, 0.9);
/// A control point with something in its surveillance region; its distance line.
pub const ACTIVE_COLOR: Color = rgba(0.95, 0.2, 0.15, 1.0);
/// A control point with nothing near.
pub const QUIET_COLOR: Color = rgba(0.3, 0.5, 0.95, 0.6);
/// A repulsive velocity.
pub const REPULSION_COLOR: Color = rgba(1.0, 0.85, 0.1, 1.0);
/// An estimated contact force; one only partly observable.
pub const FORCE_COLOR: Color = rgba(0.85, 0.1, 0.85, 1.0);
pub const FORCE_PARTIAL_COLOR: Color = rgba(0.85, 0.5, 0.85, 0.7);

/// Length of a repulsive-velocity arrow per speed [m per m/s]: 1 s of motion.
pub const VELOCITY_ARROW_S: f64 = 1.0;
/// Length of a contact-force arrow per force [m/N]: 10 N → 10 cm.
pub const FORCE_ARROW_M_PER_N: f64 = 0.01;
/// Radius of a control point's marker \[m\].
pub const POINT_RADIUS: f64 = 0.015;
/// Radius of the collaborative hand's marker \[m\].
pub const HAND_RADIUS: f64 = 0.04;

fn v3(a: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

fn finite3(a: &[f64; 3]) -> bool {
    a.iter().all(|x| x.is_finite())
}

fn entity(id: String, t: u64) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(t)),
        frame_id: BASE_FRAME.to_string(),
        id,
        ..SceneEntity::default()
    }
}

fn meta(key: &str, value: impl ToString) -> KeyValuePair {
    KeyValuePair {
        key: key.to_string(),
        value: value.to_string(),
    }
}

/// A whole replacement of a topic's scene at `t` \[ns\]: what was there before goes.
pub fn replace_all(t: u64, entities: Vec<SceneEntity>) -> SceneUpdate {
    SceneUpdate {
        deletions: vec![SceneEntityDeletion {
            timestamp: Some(timestamp(t)),
            r#type: scene_entity_deletion::Type::All as i32,
            id: String::new(),
        }],
        entities,
    }
}

fn add_capsule(e: &mut SceneEntity, a: &Vector3<f64>, b: &Vector3<f64>, r: f64, c: Color) {
    let (cyl, spheres) = capsule(a, b, r, c);
    e.cylinders.extend(cyl);
    e.spheres.extend(spheres);
}

/// The robot's link capsules at `state`'s joint positions (one entity per
/// link, id `robot/<link>`); the link named `collab_link` (the collaborative
/// robot part) is coloured apart. Empty when the state does not fit the model.
pub fn robot(
    view: &mut RobotView,
    state: &JointState,
    collab_link: Option<&str>,
    t: u64,
) -> SceneUpdate {
    let n = (state.dof as usize).min(MAX_DOF);
    let mut entities: Vec<SceneEntity> = Vec::new();
    if view.pose(&state.q[..n]).is_ok() && view.is_posed() {
        for (link, c) in view.capsules() {
            let id = format!("robot/{link}");
            let color = if Some(link) == collab_link {
                ROBOT_COLLAB_COLOR
            } else {
                ROBOT_COLOR
            };
            // a link with several collision objects is one entity
            let i = match entities.iter().position(|e| e.id == id) {
                Some(i) => i,
                None => {
                    let mut e = entity(id, t);
                    e.metadata.push(meta("link", link));
                    entities.push(e);
                    entities.len() - 1
                }
            };
            add_capsule(&mut entities[i], &c.a, &c.b, c.radius, color);
        }
    }
    replace_all(t, entities)
}

/// The person's capsules from the simulated world (id `person/<i>`); the
/// part `collab` (the collaborative one) is coloured apart.
pub fn person(world: &WorldState, collab: Option<BodyPart>, t: u64) -> SceneUpdate {
    let n = (world.n_human as usize).min(world.human.len());
    let mut entities = Vec::with_capacity(n);
    for (i, c) in world.human[..n].iter().enumerate() {
        if !(finite3(&c.a) && finite3(&c.b) && c.radius.is_finite() && c.radius > 0.0) {
            continue;
        }
        let part = BodyPart::name_of_index(c.part);
        let color = if collab.is_some_and(|p| p as i32 == c.part) {
            COLLAB_PART_COLOR
        } else {
            PERSON_COLOR
        };
        let mut e = entity(format!("person/{i}"), t);
        e.metadata.push(meta("part", part));
        add_capsule(&mut e, &v3(&c.a), &v3(&c.b), c.radius, color);
        entities.push(e);
    }
    replace_all(t, entities)
}

/// Per control point of the repulsion workers' latest results (id
/// `repulsion/<name>`): a marker at the point, and while something is in its
/// surveillance region the minimum-distance line to the closest obstacle
/// point and the repulsive velocity `V_Call` as an arrow
/// ([`VELOCITY_ARROW_S`] long per m/s). `names[i]` names point `i`.
pub fn repulsion(results: &[RepulsionResult], names: &[String], t: u64) -> SceneUpdate {
    let mut entities = Vec::new();
    for r in results {
        let n = (r.n_points as usize).min(r.points.len());
        for p in &r.points[..n] {
            if !finite3(&p.position) {
                continue;
            }
            let name = names
                .get(p.point as usize)
                .cloned()
                .unwrap_or_else(|| format!("point{}", p.point));
            let mut e = entity(format!("repulsion/{name}"), t);
            e.metadata.push(meta("point", &name));
            let pos = v3(&p.position);
            let active = p.active != 0;
            e.spheres.push(sphere(
                &pos,
                POINT_RADIUS,
                if active { ACTIVE_COLOR } else { QUIET_COLOR },
            ));
            if active && finite3(&p.obstacle) {
                e.lines
                    .push(segments(&[(pos, v3(&p.obstacle))], 0.004, ACTIVE_COLOR));
                if p.min_distance.is_finite() {
                    e.metadata
                        .push(meta("min_distance_m", format!("{:.3}", p.min_distance)));
                }
            }
            if active && finite3(&p.v_call) {
                e.arrows.extend(arrow(
                    &pos,
                    &(v3(&p.v_call) * VELOCITY_ARROW_S),
                    0.01,
                    REPULSION_COLOR,
                ));
            }
            entities.push(e);
        }
    }
    replace_all(t, entities)
}

/// The collaboration: the hand the controller uses while a collaboration is
/// on (else the hand perception sees, if any), and each estimated contact
/// force as an arrow pointing the way the person pushes
/// ([`FORCE_ARROW_M_PER_N`] long per N).
pub fn collab(state: Option<&CollabState>, hand: Option<&HandObservation>, t: u64) -> SceneUpdate {
    let mut entities = Vec::new();
    let on = state.is_some_and(|c| c.phase != CollabPhase::Idle as u32);
    let used = state.filter(|c| on && c.hand_age_ns != u64::MAX && finite3(&c.hand));
    let hand_at = match (used, hand) {
        (Some(c), _) => Some((v3(&c.hand), "controller")),
        (None, Some(h)) if finite3(&h.position) => Some((v3(&h.position), "perception")),
        _ => None,
    };
    if let Some((p, source)) = hand_at {
        let mut e = entity("collab/hand".to_string(), t);
        e.metadata.push(meta("source", source));
        if let Some(c) = state {
            e.metadata
                .push(meta("phase", CollabPhase::name_of(c.phase)));
            e.metadata
                .push(meta("part", CollabPart::name_of(c.human_part)));
        }
        e.spheres.push(sphere(&p, HAND_RADIUS, COLLAB_PART_COLOR));
        entities.push(e);
    }
    if let Some(c) = state {
        let n = (c.n_forces as usize).min(c.forces.len());
        for (i, f) in c.forces[..n].iter().enumerate() {
            if !(finite3(&f.point) && finite3(&f.force)) {
                continue;
            }
            let force = v3(&f.force);
            let mut e = entity(format!("collab/force{i}"), t);
            e.metadata
                .push(meta("force_n", format!("{:.2}", force.norm())));
            e.metadata.push(meta("observable", f.observable != 0));
            let color = if f.observable != 0 {
                FORCE_COLOR
            } else {
                FORCE_PARTIAL_COLOR
            };
            // the arrow ends at the contact point: the person pushes along it
            let v = force * FORCE_ARROW_M_PER_N;
            e.arrows
                .extend(arrow(&(v3(&f.point) - v), &v, 0.012, color));
            entities.push(e);
        }
    }
    replace_all(t, entities)
}

/// `base` → every link (at the last pose of `view`) and `base` → `camera`
/// (from the latest depth frame's header, when there is one).
pub fn transforms(view: &RobotView, camera: Option<&FrameHeader>, t: u64) -> FrameTransforms {
    let mut transforms = Vec::new();
    let tf = |child: &str, r: &nalgebra::Matrix3<f64>, p: &Vector3<f64>| FrameTransform {
        timestamp: Some(timestamp(t)),
        parent_frame_id: BASE_FRAME.to_string(),
        child_frame_id: child.to_string(),
        translation: Some(vec3(p)),
        rotation: Some(crate::geometry::quaternion(&rotation(r))),
    };
    if view.is_posed() {
        for (link, p) in view.link_frames() {
            transforms.push(tf(link, &p.r, &p.p));
        }
    }
    if let Some(h) = camera {
        let (r, p) = phri_view::depth::camera_pose(h);
        if r.iter().chain(p.iter()).all(|x| x.is_finite()) {
            transforms.push(tf(CAMERA_FRAME, &r, &p));
        }
    }
    FrameTransforms { transforms }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::{ContactForce, PointRepulsion, WorldCapsule, Zeroed};

    fn view() -> RobotView {
        RobotView::new(phri_config::Loaded::defaults().model().unwrap())
    }

    fn state(q: &[f64]) -> JointState {
        let mut s = JointState::zeroed();
        s.dof = q.len() as u32;
        s.q[..q.len()].copy_from_slice(q);
        s
    }

    fn is_replacement(u: &SceneUpdate, t: u64) {
        assert_eq!(u.deletions.len(), 1);
        assert_eq!(
            u.deletions[0].r#type,
            scene_entity_deletion::Type::All as i32
        );
        assert_eq!(u.deletions[0].timestamp, Some(timestamp(t)));
    }

    #[test]
    fn the_robot_is_one_capsule_per_collision_object() {
        let mut v = view();
        let objects = v.model().collisions.len();
        let u = robot(&mut v, &state(&[0.1; 7]), Some("lwr_link_7"), 42);
        is_replacement(&u, 42);
        let cylinders: usize = u.entities.iter().map(|e| e.cylinders.len()).sum();
        let spheres: usize = u.entities.iter().map(|e| e.spheres.len()).sum();
        assert_eq!(spheres, 2 * objects);
        assert!(cylinders <= objects && cylinders > 0);
        assert!(u.entities.iter().all(|e| e.frame_id == BASE_FRAME));
        let link7 = u
            .entities
            .iter()
            .find(|e| e.id == "robot/lwr_link_7")
            .expect("link 7");
        assert_eq!(link7.spheres[0].color, Some(ROBOT_COLLAB_COLOR));
        // a state that does not fit the model shows no robot rather than a wrong one
        let u = robot(&mut v, &state(&[0.1; 3]), None, 43);
        assert!(u.entities.is_empty());
        is_replacement(&u, 43);
    }

    #[test]
    fn the_person_shows_each_capsule_and_its_collaborative_part() {
        let mut w = WorldState::zeroed();
        w.n_human = 2;
        w.human[0] = WorldCapsule {
            a: [1.0, 0.0, 1.0],
            b: [1.0, 0.0, 1.5],
            radius: 0.15,
            part: BodyPart::Torso as i32,
            _pad: 0,
        };
        w.human[1] = WorldCapsule {
            a: [0.8, 0.0, 1.2],
            b: [0.7, 0.0, 1.2],
            radius: 0.05,
            part: BodyPart::HandRight as i32,
            _pad: 0,
        };
        w.human[2].radius = 1.0; // beyond n_human: not shown
        let u = person(&w, Some(BodyPart::HandRight), 7);
        assert_eq!(u.entities.len(), 2);
        assert_eq!(u.entities[0].spheres[0].color, Some(PERSON_COLOR));
        assert_eq!(u.entities[1].spheres[0].color, Some(COLLAB_PART_COLOR));
        assert_eq!(u.entities[1].metadata[0].value, "hand_right");
    }

    #[test]
    fn active_points_get_a_distance_line_and_a_velocity_arrow() {
        let mut r = RepulsionResult::zeroed();
        r.n_points = 2;
        r.points[0] = PointRepulsion {
            point: 0,
            active: 1,
            v_call: [0.0, 0.0, 0.2],
            min_distance: 0.25,
            obstacle: [0.5, 0.0, 0.5],
            position: [0.5, 0.0, 0.75],
        };
        r.points[1] = PointRepulsion {
            point: 5,
            active: 0,
            position: [0.3, 0.0, 0.6],
            ..PointRepulsion::default()
        };
        let names = vec!["end_effector".to_string()];
        let u = repulsion(&[r], &names, 9);
        assert_eq!(u.entities.len(), 2);
        let ee = &u.entities[0];
        assert_eq!(ee.id, "repulsion/end_effector");
        assert_eq!(ee.lines.len(), 1);
        assert_eq!(ee.lines[0].points.len(), 2);
        assert_eq!(ee.lines[0].points[1].z, 0.5);
        assert_eq!(ee.arrows.len(), 1);
        let a = &ee.arrows[0];
        assert!((a.shaft_length + a.head_length - 0.2 * VELOCITY_ARROW_S).abs() < 1e-12);
        let quiet = &u.entities[1];
        assert_eq!(quiet.id, "repulsion/point5");
        assert!(quiet.lines.is_empty() && quiet.arrows.is_empty());
        assert_eq!(quiet.spheres[0].color, Some(QUIET_COLOR));
    }

    #[test]
    fn the_collaboration_shows_the_hand_used_and_the_forces() {
        let mut c = CollabState::zeroed();
        c.phase = CollabPhase::Contact as u32;
        c.hand = [0.5, 0.1, 0.4];
        c.hand_age_ns = 1_000_000;
        c.n_forces = 1;
        c.forces[0] = ContactForce {
            point: [0.5, 0.1, 0.45],
            force: [0.0, 0.0, -20.0],
            frame: 7,
            observable: 1,
        };
        let mut h = HandObservation::zeroed();
        h.position = [9.0, 9.0, 9.0];
        let u = collab(Some(&c), Some(&h), 3);
        assert_eq!(u.entities.len(), 2);
        let hand = u.entities[0].spheres[0].pose.unwrap().position.unwrap();
        assert_eq!(
            (hand.x, hand.y, hand.z),
            (0.5, 0.1, 0.4),
            "the controller's hand"
        );
        let f = &u.entities[1].arrows[0];
        assert!(
            (f.shaft_length + f.head_length - 0.2).abs() < 1e-12,
            "20 N → 0.2 m"
        );
        // the arrow ends at the contact point
        let tail = f.pose.unwrap().position.unwrap();
        assert!((tail.z - 0.65).abs() < 1e-12, "{tail:?}");
        // idle: perception's hand, no controller hand
        c.phase = CollabPhase::Idle as u32;
        c.n_forces = 0;
        let u = collab(Some(&c), Some(&h), 4);
        assert_eq!(u.entities.len(), 1);
        assert_eq!(
            u.entities[0].spheres[0].pose.unwrap().position.unwrap().x,
            9.0
        );
        assert!(collab(None, None, 5).entities.is_empty());
    }

    #[test]
    fn transforms_name_every_link_and_the_camera() {
        let mut v = view();
        let none = transforms(&v, None, 1);
        assert!(none.transforms.is_empty(), "not posed yet");
        v.pose(&[0.0; 7]).unwrap();
        let mut h = FrameHeader::zeroed();
        h.pose_r = [0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0];
        h.pose_t = [1.5, 0.0, 1.2];
        let tf = transforms(&v, Some(&h), 2);
        assert_eq!(tf.transforms.len(), 8);
        let cam = tf.transforms.last().unwrap();
        assert_eq!(cam.child_frame_id, CAMERA_FRAME);
        assert_eq!(cam.parent_frame_id, BASE_FRAME);
        assert_eq!(cam.translation.unwrap().x, 1.5);
    }
}
