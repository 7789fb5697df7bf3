//! The people the body trackers see, as ROS4HRI (REP 155) publishes them:
//! pure functions, no I/O.
//!
//! - `/humans/bodies/tracked` (`hri_msgs/IdsList`): the ids of the bodies
//!   tracked now, one message per `perception/skeleton` message read (an
//!   empty one too: `ids = []`), over every camera ([`Tracked`]).
//! - `/tf`: per tracked body a frame `body_<id>` whose parent is the robot's
//!   base frame, and per joint seen (confidence > 0) a frame whose parent is
//!   `body_<id>` (REP 155: "the other skeleton points ... parented to the
//!   root `body_<bodyID>` frame, and all suffixed with the same
//!   `_<bodyID>`").
//!
//! **Body ids**: `b<camera><tracker id>`, the camera's index in one digit
//! ([`MAX_CAMERAS`] ≤ 10) and the tracker's id in decimal: camera 0's
//! person 7 (`perception/skeleton`) is `b07`, camera 1's person 7
//! (`perception/1/skeleton`) is `b17`; unique across cameras, stable while
//! the tracker keeps its id, short (REP 155), and a valid ROS name token
//! (`/humans/bodies/b07/`: it starts with a letter).
//!
//! **Joint frames** are named after the links of ROS4HRI's human model
//! (`human_description`'s `human-tpl.xacro`, which `hri_fullbody` publishes
//! through `robot_state_publisher`), suffixed `_<id>`, each at the link
//! whose origin is the same point of the body ([`joint_link`]):
//!
//! | phri (OpenNI) | ROS4HRI | where |
//! | --- | --- | --- |
//! | head | `head_<id>` | head |
//! | neck | `torso_<id>` | top of the trunk, between the shoulders (the model has no neck link: its head and shoulders hang from `torso`) |
//! | torso | `waist_<id>` | mid-trunk |
//! | left/right shoulder | `l_shoulder_<id>`, `r_shoulder_<id>` | |
//! | left/right elbow | `l_elbow_<id>`, `r_elbow_<id>` | |
//! | left/right hand | `l_wrist_<id>`, `r_wrist_<id>` | end of the forearm |
//! | left/right hip | `l_hip_<id>`, `r_hip_<id>` | |
//! | left/right knee | `l_knee_<id>`, `r_knee_<id>` | |
//! | left/right foot | `l_ankle_<id>`, `r_ankle_<id>` | end of the shin |
//!
//! **The body frame** (REP 155): its origin at the middle of the hips (both
//! seen), else at phri's torso joint, else at the mean of the joints seen;
//! z toward the head (the neck, else the head, seen; else the base frame's
//! z), x forward, y to the person's left (from the right hip to the left
//! one, else from the right shoulder to the left one). Without a
//! left-right pair, the base frame's axes. Joint frames carry the body
//! frame's orientation (the tracker gives points, not segment
//! orientations). A body with no joint seen has no frame (its id is still
//! tracked).
//!
//! Stamps: the skeleton's capture time ([`stamp_ns`], CLOCK_MONOTONIC) on
//! ROS time, as every other stamp of the bridge ([`crate::Clock`]).

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3 as V3};
use phri_ipc::{Skeleton, SkeletonJoint, TrackedPerson, MAX_CAMERAS, MAX_PEOPLE};

use crate::msgs::{Header, IdsList, Quaternion, Time, Transform, TransformStamped, Vector3};

/// ROS4HRI's topic of the tracked bodies.
pub const TRACKED_TOPIC: &str = "/humans/bodies/tracked";

/// A camera's bodies stay in `/humans/bodies/tracked` while its newest
/// skeleton is at most this much older than the one just read \[ns\].
pub const FRESH_NS: u64 = 500_000_000;

// the camera's index is one digit of the body id
const _: () = assert!(MAX_CAMERAS <= 10);

/// The ROS4HRI body id of camera `camera`'s tracked person `id`.
pub fn body_id(camera: usize, id: u32) -> String {
    format!("b{camera}{id}")
}

/// The ROS4HRI link (frame name without its `_<id>`) at phri's joint `j`.
pub fn joint_link(j: SkeletonJoint) -> &'static str {
    use SkeletonJoint::*;
    match j {
        Head => "head",
        Neck => "torso",
        Torso => "waist",
        LeftShoulder => "l_shoulder",
        RightShoulder => "r_shoulder",
        LeftElbow => "l_elbow",
        RightElbow => "r_elbow",
        LeftHand => "l_wrist",
        RightHand => "r_wrist",
        LeftHip => "l_hip",
        RightHip => "r_hip",
        LeftKnee => "l_knee",
        RightKnee => "r_knee",
        LeftFoot => "l_ankle",
        RightFoot => "r_ankle",
    }
}

/// The skeleton's time on phri's clock: its capture time, else its publish
/// time [ns, CLOCK_MONOTONIC].
pub fn stamp_ns(s: &Skeleton) -> u64 {
    if s.capture_wall_ns > 0 {
        s.capture_wall_ns
    } else {
        s.published_ns
    }
}

/// The people of `s` that are tracked.
fn tracked(s: &Skeleton) -> impl Iterator<Item = &TrackedPerson> {
    let n = (s.n_people as usize).min(MAX_PEOPLE);
    s.people[..n].iter().filter(|p| p.tracked != 0)
}

/// Joint `j` of `p` [m, base frame] if seen: confidence > 0, finite.
fn seen(p: &TrackedPerson, j: SkeletonJoint) -> Option<V3<f64>> {
    let i = j as usize;
    let v = V3::from(*p.joints.get(i)?);
    (p.confidence[i] > 0.0 && v.iter().all(|x| x.is_finite())).then_some(v)
}

/// `a` → `b` of two joints both seen.
fn between(p: &TrackedPerson, a: SkeletonJoint, b: SkeletonJoint) -> Option<V3<f64>> {
    Some(seen(p, b)? - seen(p, a)?)
}

/// The body frame of `p` in the base frame: origin and orientation (see
/// the module's doc); `None` when no joint is seen.
pub fn body_pose(p: &TrackedPerson) -> Option<(V3<f64>, UnitQuaternion<f64>)> {
    use SkeletonJoint::*;
    let origin = match (seen(p, LeftHip), seen(p, RightHip)) {
        (Some(l), Some(r)) => (l + r) / 2.0,
        _ => match seen(p, Torso) {
            Some(t) => t,
            None => {
                let all: Vec<V3<f64>> = SkeletonJoint::ALL
                    .iter()
                    .filter_map(|j| seen(p, *j))
                    .collect();
                if all.is_empty() {
                    return None;
                }
                all.iter().sum::<V3<f64>>() / all.len() as f64
            }
        },
    };
    let long = |v: &V3<f64>| v.norm() > 1e-3;
    let up = seen(p, Neck)
        .or_else(|| seen(p, Head))
        .map(|t| t - origin)
        .filter(long)
        .unwrap_or_else(V3::z);
    let left = between(p, RightHip, LeftHip)
        .filter(long)
        .or_else(|| between(p, RightShoulder, LeftShoulder).filter(long));
    let z = up.normalize();
    let orientation = left
        .map(|l| l - z * l.dot(&z))
        .filter(long)
        .map(|y| {
            let y = y.normalize();
            let x = y.cross(&z);
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                Matrix3::from_columns(&[x, y, z]),
            ))
        })
        .unwrap_or_else(UnitQuaternion::identity);
    Some((origin, orientation))
}

fn transform(
    stamp: Time,
    parent: &str,
    child: String,
    p: V3<f64>,
    q: UnitQuaternion<f64>,
) -> TransformStamped {
    TransformStamped {
        header: Header {
            stamp,
            frame_id: parent.to_string(),
        },
        child_frame_id: child,
        transform: Transform {
            translation: Vector3 {
                x: p.x,
                y: p.y,
                z: p.z,
            },
            rotation: Quaternion {
                x: q.i,
                y: q.j,
                z: q.k,
                w: q.w,
            },
        },
    }
}

/// Camera `camera`'s skeleton `s` as ROS4HRI: the ids of its tracked
/// bodies (this message's alone, header in `base_frame` at `stamp`) and
/// their frames on `/tf` (`body_<id>` in `base_frame`, each joint seen in
/// `body_<id>`).
pub fn bodies(
    s: &Skeleton,
    camera: usize,
    base_frame: &str,
    stamp: Time,
) -> (IdsList, Vec<TransformStamped>) {
    let mut ids: Vec<String> = Vec::with_capacity(MAX_PEOPLE);
    let mut transforms = Vec::new();
    for p in tracked(s) {
        let id = body_id(camera, p.id);
        if ids.contains(&id) {
            continue;
        }
        if let Some((origin, q)) = body_pose(p) {
            let body = format!("body_{id}");
            transforms.push(transform(stamp, base_frame, body.clone(), origin, q));
            let inverse = q.inverse();
            for j in SkeletonJoint::ALL {
                if let Some(v) = seen(p, *j) {
                    transforms.push(transform(
                        stamp,
                        &body,
                        format!("{}_{id}", joint_link(*j)),
                        inverse * (v - origin),
                        UnitQuaternion::identity(),
                    ));
                }
            }
        }
        ids.push(id);
    }
    let list = IdsList {
        header: Header {
            stamp,
            frame_id: base_frame.to_string(),
        },
        ids,
    };
    (list, transforms)
}

/// `/humans/bodies/tracked` over every camera: each camera's newest ids,
/// those of a camera whose newest skeleton is more than [`FRESH_NS`] older
/// than the one just read left out (a tracker that stopped), in camera
/// order. With one camera, each message's own ids.
#[derive(Clone, Debug, Default)]
pub struct Tracked {
    /// per camera: its newest skeleton's time [ns] and ids
    newest: [Option<(u64, Vec<String>)>; MAX_CAMERAS],
}

impl Tracked {
    /// Camera `camera`'s newest `ids`, of a skeleton at `stamp_ns` [ns,
    /// CLOCK_MONOTONIC]: the bodies tracked now.
    pub fn update(&mut self, camera: usize, ids: Vec<String>, stamp_ns: u64) -> Vec<String> {
        let Some(slot) = self.newest.get_mut(camera) else {
            return ids;
        };
        *slot = Some((stamp_ns, ids));
        self.newest
            .iter()
            .flatten()
            .filter(|(t, _)| stamp_ns.saturating_sub(*t) <= FRESH_NS)
            .flat_map(|(_, ids)| ids.iter().cloned())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;
    use SkeletonJoint::*;

    const STAMP: Time = Time {
        sec: 1_764_000_000,
        nanosec: 5,
    };

    /// A person standing 2 m ahead of the base, facing it (toward −x): their
    /// left toward −y.
    fn person(id: u32) -> TrackedPerson {
        let mut p = TrackedPerson {
            id,
            tracked: 1,
            joints: [[0.0; 3]; phri_ipc::SKELETON_JOINTS],
            confidence: [1.0; phri_ipc::SKELETON_JOINTS],
        };
        let at = |y: f64, z: f64| [2.0, y, z];
        for (j, v) in [
            (Head, at(0.0, 1.7)),
            (Neck, at(0.0, 1.5)),
            (Torso, at(0.0, 1.2)),
            (LeftShoulder, at(-0.2, 1.5)),
            (RightShoulder, at(0.2, 1.5)),
            (LeftElbow, at(-0.25, 1.2)),
            (RightElbow, at(0.25, 1.2)),
            (LeftHand, at(-0.3, 0.95)),
            (RightHand, at(0.3, 0.95)),
            (LeftHip, at(-0.1, 0.9)),
            (RightHip, at(0.1, 0.9)),
            (LeftKnee, at(-0.1, 0.5)),
            (RightKnee, at(0.1, 0.5)),
            (LeftFoot, at(-0.1, 0.1)),
            (RightFoot, at(0.1, 0.1)),
        ] {
            p.joints[j as usize] = v;
        }
        p
    }

    fn skeleton(people: &[TrackedPerson]) -> Skeleton {
        let mut s = Skeleton::zeroed();
        s.n_people = people.len() as u32;
        s.people[..people.len()].copy_from_slice(people);
        s
    }

    fn v(t: &TransformStamped) -> V3<f64> {
        let t = &t.transform.translation;
        V3::new(t.x, t.y, t.z)
    }

    fn q(t: &TransformStamped) -> UnitQuaternion<f64> {
        let r = &t.transform.rotation;
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(r.w, r.x, r.y, r.z))
    }

    fn find<'a>(tf: &'a [TransformStamped], child: &str) -> Option<&'a TransformStamped> {
        tf.iter().find(|t| t.child_frame_id == child)
    }

    #[test]
    fn ids_are_short_unique_across_cameras_and_ros_name_tokens() {
        assert_eq!(body_id(0, 7), "b07");
        assert_eq!(body_id(1, 7), "b17");
        assert_eq!(body_id(3, 123), "b3123");
        let mut all = std::collections::HashSet::new();
        for c in 0..MAX_CAMERAS {
            for id in [0, 1, 2, 10, 12, 21, 99, 100, u32::MAX] {
                let b = body_id(c, id);
                assert!(b.starts_with('b') && b.chars().all(|c| c.is_ascii_alphanumeric()));
                assert!(all.insert(b), "camera {c} id {id}");
            }
        }
    }

    #[test]
    fn every_joint_has_its_own_ros4hri_link() {
        let links: std::collections::HashSet<&str> =
            SkeletonJoint::ALL.iter().map(|j| joint_link(*j)).collect();
        assert_eq!(links.len(), SkeletonJoint::ALL.len());
        assert!(!links.contains("body"));
        assert_eq!(joint_link(LeftHand), "l_wrist");
        assert_eq!(joint_link(Neck), "torso");
    }

    #[test]
    fn a_body_frame_in_the_base_and_its_joints_in_it() {
        let s = skeleton(&[person(7)]);
        let (ids, tf) = bodies(&s, 0, "base_link", STAMP);
        assert_eq!(ids.ids, ["b07"]);
        assert_eq!(ids.header.frame_id, "base_link");
        assert_eq!(ids.header.stamp, STAMP);
        assert_eq!(tf.len(), 1 + 15);
        assert!(tf.iter().all(|t| t.header.stamp == STAMP));
        // the body frame first, in the base, at the middle of the hips
        assert_eq!(tf[0].child_frame_id, "body_b07");
        assert_eq!(tf[0].header.frame_id, "base_link");
        assert!((v(&tf[0]) - V3::new(2.0, 0.0, 0.9)).norm() < 1e-12);
        // REP 155's axes: z up, x forward (toward the robot: −x), y left (−y)
        let body = q(&tf[0]);
        assert!((body * V3::z() - V3::z()).norm() < 1e-9);
        assert!((body * V3::x() + V3::x()).norm() < 1e-9);
        assert!((body * V3::y() + V3::y()).norm() < 1e-9);
        let names: Vec<&str> = tf[1..].iter().map(|t| t.child_frame_id.as_str()).collect();
        assert_eq!(
            names,
            [
                "head_b07",
                "torso_b07",
                "waist_b07",
                "l_shoulder_b07",
                "r_shoulder_b07",
                "l_elbow_b07",
                "r_elbow_b07",
                "l_wrist_b07",
                "r_wrist_b07",
                "l_hip_b07",
                "r_hip_b07",
                "l_knee_b07",
                "r_knee_b07",
                "l_ankle_b07",
                "r_ankle_b07"
            ]
        );
        // each joint in body_b07, where the tracker saw it
        let p = person(7);
        for (t, j) in tf[1..].iter().zip(SkeletonJoint::ALL) {
            assert_eq!(t.header.frame_id, "body_b07");
            let in_base = v(&tf[0]) + body * v(t);
            assert!(
                (in_base - V3::from(p.joints[*j as usize])).norm() < 1e-9,
                "{j:?}"
            );
        }
        // the left hand is on the person's left (+y of their body)
        assert!(v(find(&tf, "l_wrist_b07").unwrap()).y > 0.2);
    }

    #[test]
    fn joints_not_seen_get_no_frame() {
        let mut p = person(4);
        p.confidence[RightFoot as usize] = 0.0;
        p.confidence[Head as usize] = f64::NAN;
        p.joints[LeftKnee as usize][2] = f64::NAN;
        let (ids, tf) = bodies(&skeleton(&[p]), 2, "base_link", STAMP);
        assert_eq!(ids.ids, ["b24"]);
        assert_eq!(tf.len(), 1 + 12);
        for gone in ["r_ankle_b24", "head_b24", "l_knee_b24"] {
            assert!(find(&tf, gone).is_none(), "{gone}");
        }
        assert!(find(&tf, "l_ankle_b24").is_some());
    }

    #[test]
    fn the_body_frame_without_hips_or_left_right_pairs() {
        // no hips: at the torso joint, still upright and facing −x
        let mut p = person(1);
        p.confidence[LeftHip as usize] = 0.0;
        let (_, tf) = bodies(&skeleton(&[p]), 0, "base_link", STAMP);
        assert!((v(&tf[0]) - V3::new(2.0, 0.0, 1.2)).norm() < 1e-12);
        assert!((q(&tf[0]) * V3::x() + V3::x()).norm() < 1e-9);
        // only a hand: at the hand, the base's axes
        let mut p = person(1);
        p.confidence = [0.0; phri_ipc::SKELETON_JOINTS];
        p.confidence[RightHand as usize] = 0.5;
        let (ids, tf) = bodies(&skeleton(&[p]), 0, "base_link", STAMP);
        assert_eq!(ids.ids, ["b01"]);
        assert_eq!(tf.len(), 2);
        assert!((v(&tf[0]) - V3::new(2.0, 0.3, 0.95)).norm() < 1e-12);
        assert_eq!(q(&tf[0]), UnitQuaternion::identity());
        assert!(v(&tf[1]).norm() < 1e-12);
        // nothing seen: tracked, no frame
        p.confidence = [0.0; phri_ipc::SKELETON_JOINTS];
        let (ids, tf) = bodies(&skeleton(&[p]), 0, "base_link", STAMP);
        assert_eq!((ids.ids.len(), tf.len()), (1, 0));
    }

    #[test]
    fn only_tracked_people_within_n_people_count_in_order() {
        let mut gone = person(9);
        gone.tracked = 0;
        let mut s = skeleton(&[person(3), gone, person(12)]);
        // past n_people: not there
        s.people[3] = person(5);
        let (ids, tf) = bodies(&s, 1, "world", STAMP);
        assert_eq!(ids.ids, ["b13", "b112"]);
        let bodies_: Vec<(&str, &str)> = tf
            .iter()
            .filter(|t| t.child_frame_id.starts_with("body_"))
            .map(|t| (t.header.frame_id.as_str(), t.child_frame_id.as_str()))
            .collect();
        assert_eq!(bodies_, [("world", "body_b13"), ("world", "body_b112")]);
        assert_eq!(tf.len(), 2 * 16);
        // each body's frame comes before its joints
        let at = |c: &str| tf.iter().position(|t| t.child_frame_id == c).unwrap();
        assert!(at("body_b112") < at("head_b112") && at("r_ankle_b13") < at("body_b112"));
    }

    #[test]
    fn an_empty_skeleton_gives_an_empty_list_and_no_frame() {
        let (ids, tf) = bodies(&Skeleton::zeroed(), 0, "base_link", STAMP);
        assert!(ids.ids.is_empty());
        assert_eq!(ids.header.stamp, STAMP);
        assert!(tf.is_empty());
        // n_people past MAX_PEOPLE is bounded
        let mut s = skeleton(&[person(1); MAX_PEOPLE]);
        s.n_people = 1000;
        assert_eq!(bodies(&s, 0, "base_link", STAMP).0.ids, ["b01"]);
    }

    #[test]
    fn the_stamp_is_the_capture_time_else_the_publication() {
        let mut s = Skeleton::zeroed();
        s.published_ns = 20;
        assert_eq!(stamp_ns(&s), 20);
        s.capture_wall_ns = 10;
        assert_eq!(stamp_ns(&s), 10);
    }

    #[test]
    fn tracked_is_every_fresh_cameras_newest() {
        let mut t = Tracked::default();
        let ids = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(t.update(0, ids(&["b07"]), 1_000_000_000), ["b07"]);
        assert_eq!(t.update(1, ids(&["b12"]), 1_010_000_000), ["b07", "b12"]);
        // camera 0 loses its person: empty for it, camera 1's stays
        assert_eq!(t.update(0, vec![], 1_033_000_000), ["b12"]);
        assert_eq!(t.update(0, vec![], 1_066_000_000), ["b12"]);
        // camera 1 silent for longer than FRESH_NS: left out
        assert!(t.update(0, vec![], 1_010_000_000 + FRESH_NS + 1).is_empty());
        // one camera: each message's own
        let mut one = Tracked::default();
        assert_eq!(one.update(0, ids(&["b01", "b02"]), 5), ["b01", "b02"]);
        assert!(one.update(0, vec![], 6).is_empty());
        // no camera of that index: its own ids
        assert_eq!(one.update(MAX_CAMERAS, ids(&["b91"]), 7), ["b91"]);
    }
}
