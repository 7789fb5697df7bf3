//! The person tracker on depth (`phri-tracker`, and the lock-step cell's
//! `[skeleton] source = "depth"`): per frame of one camera, the robot's own
//! pixels removed by ingestion's self-filter (the arm at the joint state
//! nearest the capture time), phri-people's model-free [`Tracker`] on what
//! is left, and its people moved from the camera's optical frame into the
//! robot's base frame with the pose the frame's header carries: a
//! `perception/skeleton` message with the frame's sequence number and
//! capture times.
//!
//! Where the cell knows its static scene (a simulated camera: the table and
//! the floor of `[camera]`), the tracker's background is that scene
//! rendered once from the camera, so only what stands out of it can be a
//! person; a real camera's tracker finds people by the floor plane (RANSAC)
//! and depth continuity alone. The camera's up direction comes from its
//! pose (the base frame's z). Allocation-free per frame after the first.

use nalgebra::{Point3, Vector3};
use phri_config::{CameraConfig, Facing, IngestConfig, SkeletonConfig};
use phri_depth::{Aabb, CameraPose, Intrinsics, RenderOptions, Renderer};
use phri_ipc::{FrameHeader, Skeleton, Zeroed, SKELETON_JOINTS};
use phri_model::Model;
use phri_people::{FloorMode, Person, Plane, TrackError, Tracker, TrackerConfig, MAX_PEOPLE};

use crate::camera::header_camera;
use crate::ingest::{FrameError, Ingest, StateHistory};

/// Why a frame gave no skeleton.
#[derive(Debug, thiserror::Error)]
pub enum TrackerError {
    /// the frame itself (size, camera, age, sequence, no joint state)
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// the tracker refused the camera or the frame
    #[error("frame {seq}: {source}")]
    Track {
        /// the frame's sequence number
        seq: u64,
        /// the tracker's error
        #[source]
        source: TrackError,
    },
}

/// The static scene a simulated camera sees without robot or people.
#[derive(Clone, Copy, Debug)]
struct Scene {
    table: [Aabb; 1],
    floor_z: Option<f64>,
}

/// The tracker of one camera, built for the camera the frames describe.
pub struct DepthTracker {
    ingest: Ingest,
    cfg: TrackerConfig,
    facing: Facing,
    /// what the cell knows of the scene (a simulated camera's)
    scene: Option<Scene>,
    /// the tracker and the key of the camera it was built for
    tracker: Option<(u64, Tracker, CameraPose)>,
    /// the frame without the robot's pixels [mm]
    filtered: Vec<u16>,
    people: [Person; MAX_PEOPLE],
    /// each tracked person's hands as last believed, by id
    hands: [HandMemory; MAX_PEOPLE],
    last_capture_ns: Option<u64>,
    /// frame period assumed before the second frame [s]
    first_dt_s: f64,
}

impl DepthTracker {
    /// The tracker of camera `camera` (`[skeleton]`, `[perception]`'s
    /// self-filter and limits) for the robot `model`.
    pub fn new(
        model: Model,
        skeleton: &SkeletonConfig,
        ingest: &IngestConfig,
        camera: &CameraConfig,
    ) -> Result<DepthTracker, phri_config::Invalid> {
        let scene = (camera.source == phri_config::CameraSource::Sim).then(|| Scene {
            table: [Aabb::new(
                Point3::from(camera.table_min),
                Point3::from(camera.table_max),
            )],
            floor_z: camera.floor_z,
        });
        Ok(DepthTracker {
            ingest: Ingest::new(model, ingest)?.keep_flying_pixels(),
            cfg: skeleton.tracker,
            facing: skeleton.facing,
            scene,
            tracker: None,
            filtered: Vec::new(),
            people: [Person::default(); MAX_PEOPLE],
            hands: [HandMemory::default(); MAX_PEOPLE],
            last_capture_ns: None,
            first_dt_s: 1.0 / camera.rate_hz.max(1.0),
        })
    }

    /// The people of one frame (`header`, `depth` \[mm\]) into `out`, with
    /// the frame's sequence number and capture times, joints in the robot's
    /// base frame; `states` the robot's recent joint states (for the
    /// self-filter), `now_ns` [robot clock] when the frame is handled.
    /// Returns the people found.
    pub fn step(
        &mut self,
        header: &FrameHeader,
        depth: &[u16],
        states: &StateHistory,
        now_ns: u64,
        out: &mut Skeleton,
    ) -> Result<usize, TrackerError> {
        let seq = header.seq;
        let (mut h, input) = (*header, depth);
        let frame = h;
        if self.filtered.len() != input.len() {
            self.filtered.resize(input.len(), 0);
        }
        self.ingest
            .step(&mut h, input, states, now_ns, &mut self.filtered)?;
        let key = camera_key(&frame);
        if self.tracker.as_ref().is_none_or(|(k, _, _)| *k != key) {
            let (k, pose) =
                header_camera(&frame).map_err(|source| FrameError::Camera { seq, source })?;
            let tracker = self
                .build(k, pose)
                .map_err(|source| TrackerError::Track { seq, source })?;
            self.tracker = Some((key, tracker, pose));
            self.last_capture_ns = None;
        }
        let dt_s = match self.last_capture_ns {
            Some(t) if header.capture_ns > t => (header.capture_ns - t) as f64 * 1e-9,
            _ => self.first_dt_s,
        };
        self.last_capture_ns = Some(header.capture_ns);
        let Some((_, tracker, pose)) = self.tracker.as_mut() else {
            return Ok(0);
        };
        let n = tracker
            .step(&self.filtered, dt_s, &mut self.people)
            .map_err(|source| TrackerError::Track { seq, source })?;
        let k = *tracker.intrinsics();
        hold_hands_behind_the_robot(&mut self.hands, &mut self.people[..n], dt_s, |p| {
            robot_near(&k, &self.filtered, input, p)
        });
        write_skeleton(header, pose, self.facing, &self.people[..n], out);
        Ok(n)
    }

    /// A tracker for camera `k` at `pose`: up is the base frame's z, the
    /// floor and background the known scene's where there is one.
    fn build(&self, k: Intrinsics, pose: CameraPose) -> Result<Tracker, TrackError> {
        let to_camera = pose.rotation().inverse();
        let up = to_camera * Vector3::z();
        let mut cfg = self.cfg;
        cfg.up_camera = [up.x, up.y, up.z];
        if let Some(z) = self.scene.and_then(|s| s.floor_z) {
            // the floor z = floor_z of the base frame, in the camera's frame
            let origin = pose.base_from_camera().inverse() * Point3::new(0.0, 0.0, z);
            cfg.floor = FloorMode::Given(Plane {
                normal: [up.x, up.y, up.z],
                d: -(up.dot(&origin.coords)),
            });
        }
        let mut tracker = Tracker::new(k, cfg)?;
        if let Some(scene) = self.scene {
            let mut renderer = Renderer::new(k, pose, RenderOptions::ideal())
                .map_err(|e| TrackError::Intrinsics(e.to_string()))?;
            let mut background = vec![0u16; k.pixel_count()];
            renderer
                .render(&[], &scene.table, scene.floor_z, &mut background)
                .map_err(|e| TrackError::Intrinsics(e.to_string()))?;
            tracker.learn_background(&background)?;
        }
        Ok(tracker)
    }
}

/// A hand that jumps farther than this from where it was last believed
/// [m], plus [`HAND_SPEED_MPS`] × the time since, is not believed while the
/// robot is beside that place (the self-filter has removed the hand with
/// the robot it touches, and another extremum was taken for it), for at
/// most [`HAND_HOLD_S`]: its last position is kept with confidence 0.
const HAND_JUMP_M: f64 = 0.15;
/// A hand's largest speed [m/s].
const HAND_SPEED_MPS: f64 = 3.0;
/// The longest a hand is held at its last place [s].
const HAND_HOLD_S: f64 = 0.5;
/// The robot is beside a hand when one of its pixels lies this near it [m].
const ROBOT_NEAR_M: f64 = 0.15;
/// The hands' joints in the message's order (left, right).
const HANDS: [usize; 2] = [7, 8];

/// One person's hands as last believed (camera frame).
#[derive(Clone, Copy, Debug, Default)]
struct HandMemory {
    id: u32,
    /// per hand: its last believed position [m] and the time since [s]
    /// (`None`: never seen)
    last: [Option<([f64; 3], f64)>; 2],
}

/// Each person's hands in `people` checked against `memory` (`dt_s` after
/// the last frame); `robot_near(p)` says whether the robot's removed
/// pixels lie beside camera-frame point `p`.
fn hold_hands_behind_the_robot(
    memory: &mut [HandMemory; MAX_PEOPLE],
    people: &mut [Person],
    dt_s: f64,
    robot_near: impl Fn([f64; 3]) -> bool,
) {
    // people gone are forgotten
    for m in memory.iter_mut() {
        if m.id != 0 && !people.iter().any(|p| p.id == m.id) {
            *m = HandMemory::default();
        }
    }
    for p in people.iter_mut() {
        let slot = match memory.iter().position(|m| m.id == p.id) {
            Some(i) => i,
            None => match memory.iter().position(|m| m.id == 0) {
                Some(i) => {
                    memory[i] = HandMemory {
                        id: p.id,
                        last: [None; 2],
                    };
                    i
                }
                None => continue,
            },
        };
        let m = &mut memory[slot];
        for (h, &j) in HANDS.iter().enumerate() {
            let age = m.last[h].map(|(_, a)| a + dt_s);
            if p.confidence[j] > 0.0 {
                if let (Some((at, _)), Some(age)) = (m.last[h], age) {
                    let d = (0..3)
                        .map(|i| (p.joints[j][i] - at[i]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    if age <= HAND_HOLD_S
                        && d > HAND_JUMP_M + HAND_SPEED_MPS * age
                        && robot_near(at)
                    {
                        p.joints[j] = at;
                        p.confidence[j] = 0.0;
                        m.last[h] = Some((at, age));
                        continue;
                    }
                }
                m.last[h] = Some((p.joints[j], 0.0));
            } else if let (Some((at, _)), Some(age)) = (m.last[h], age) {
                m.last[h] = Some((at, age));
            }
        }
    }
}

/// Whether pixels the self-filter removed (the robot's: read in `input`,
/// 0 in `filtered`) lie within [`ROBOT_NEAR_M`] of camera-frame point `p`
/// in the image (a window around its projection).
fn robot_near(k: &Intrinsics, filtered: &[u16], input: &[u16], p: [f64; 3]) -> bool {
    if !(p[2] > 0.1) || !p.iter().all(|x| x.is_finite()) {
        return false;
    }
    let (w, h) = (k.width as i64, k.height as i64);
    let u = (k.fx * p[0] / p[2] + k.cx).round() as i64;
    let v = (k.fy * p[1] / p[2] + k.cy).round() as i64;
    let r = (ROBOT_NEAR_M * k.fx / p[2]).ceil() as i64;
    // every other pixel: the robot's removed region is never that thin
    for y in ((v - r).max(0)..(v + r + 1).min(h)).step_by(2) {
        for x in ((u - r).max(0)..(u + r + 1).min(w)).step_by(2) {
            let i = (y * w + x) as usize;
            if filtered.get(i) == Some(&0) && input.get(i).is_some_and(|&d| d != 0) {
                return true;
            }
        }
    }
    false
}

/// What identifies the camera a frame was taken with (size, focal length,
/// position): a change rebuilds the tracker.
fn camera_key(h: &FrameHeader) -> u64 {
    h.width as u64
        ^ (h.height as u64) << 16
        ^ h.fx.to_bits()
        ^ h.cx.to_bits().rotate_left(3)
        ^ h.pose_t[0].to_bits().rotate_left(7)
        ^ h.pose_t[1].to_bits().rotate_left(11)
        ^ h.pose_t[2].to_bits().rotate_left(13)
        ^ h.pose_r[0].to_bits().rotate_left(17)
        ^ h.pose_r[4].to_bits().rotate_left(19)
        ^ h.pose_r[8].to_bits().rotate_left(23)
}

/// The joints a person's left and right swap between, in the message's order.
const SIDES: [(usize, usize); 6] = [(3, 4), (5, 6), (7, 8), (9, 10), (11, 12), (13, 14)];

/// How much less surely a joint on the far side of a person's body is seen
/// than one on the near side, by a camera exactly beside them (a share of
/// its confidence): a hand the body hides leaves another extremum (a hip, a
/// fold of clothing) where it should be. Several cameras' views are merged
/// by confidence ([`phri_ipc::merge_views`]): a joint two cameras both
/// claim is taken from the one on its side. Small, so that a joint one
/// camera alone sees stays above the consumers' gates (0.5: an elbow found
/// at 0.6 keeps 0.54).
pub const FAR_SIDE_DOUBT: f64 = 0.1;

/// The confidences of a person facing the robot (horizontal directions from
/// the person to the robot's base and to the camera, base frame) lowered on
/// the side of the body turned away from the camera, by [`FAR_SIDE_DOUBT`]
/// times how far the camera stands to the other side (0 straight in front
/// or behind, 1 exactly beside). Labels are the person's own.
fn doubt_the_far_side(to_robot: [f64; 2], to_camera: [f64; 2], confidence: &mut [f64]) {
    let (f, c) = (
        to_robot[0].hypot(to_robot[1]),
        to_camera[0].hypot(to_camera[1]),
    );
    if f < 1e-6 || c < 1e-6 {
        return;
    }
    // the person's left: their facing turned a quarter to the left
    let left = [-to_robot[1] / f, to_robot[0] / f];
    let s = (left[0] * to_camera[0] + left[1] * to_camera[1]) / c;
    let keep = 1.0 - FAR_SIDE_DOUBT * s.abs();
    for (l, r) in SIDES {
        let far = if s < 0.0 { l } else { r };
        if let Some(v) = confidence.get_mut(far) {
            *v *= keep;
        }
    }
}

/// `people` (camera optical frame, labelled for a person facing the camera)
/// as a `perception/skeleton` message of frame `header` in the robot's base
/// frame; with `Facing::Robot` a person whose back the camera sees (the
/// robot's base and the camera on opposite sides of them, horizontally)
/// has left and right swapped.
pub fn write_skeleton(
    header: &FrameHeader,
    pose: &CameraPose,
    facing: Facing,
    people: &[Person],
    out: &mut Skeleton,
) {
    *out = Skeleton::zeroed();
    out.seq = header.seq;
    out.capture_ns = header.capture_ns;
    out.capture_wall_ns = header.capture_wall_ns;
    let base = pose.base_from_camera();
    let eye = pose.position();
    let mut n = 0;
    for (p, slot) in people.iter().zip(out.people.iter_mut()) {
        slot.id = p.id;
        slot.tracked = 1;
        for j in 0..SKELETON_JOINTS.min(p.joints.len()) {
            let [x, y, z] = p.joints[j];
            let q = base * Point3::new(x, y, z);
            slot.joints[j] = [q.x, q.y, q.z];
            slot.confidence[j] = p.confidence[j];
        }
        let [x, y, z] = p.centroid;
        let c = base * Point3::new(x, y, z);
        let to_robot = [-c.x, -c.y];
        let to_camera = [eye.x - c.x, eye.y - c.y];
        let back_seen = to_robot[0] * to_camera[0] + to_robot[1] * to_camera[1] < 0.0;
        if facing == Facing::Robot && back_seen {
            for (l, r) in SIDES {
                slot.joints.swap(l, r);
                slot.confidence.swap(l, r);
            }
        }
        if facing == Facing::Robot {
            doubt_the_far_side(to_robot, to_camera, &mut slot.confidence);
        }
        n += 1;
    }
    out.n_people = n as u32;
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_depth::CameraPose;

    /// A camera 2 m along +x of the base, 1.2 m up, looking back at the base.
    fn pose() -> CameraPose {
        CameraPose::look_at(
            &Point3::new(2.0, 0.0, 1.2),
            &Point3::new(0.0, 0.0, 0.5),
            &Vector3::z(),
        )
        .unwrap()
    }

    /// A person whose left hand (camera frame) is at +x of the image, centred at `centroid` (base frame).
    fn person(pose: &CameraPose, centroid: [f64; 3]) -> Person {
        let to_camera = pose.base_from_camera().inverse();
        let c = to_camera * Point3::from(centroid);
        let mut p = Person {
            id: 3,
            centroid: [c.x, c.y, c.z],
            ..Person::default()
        };
        for j in 0..SKELETON_JOINTS {
            p.joints[j] = [c.x, c.y, c.z];
            p.confidence[j] = 0.5;
        }
        p.joints[7] = [c.x + 0.3, c.y, c.z];
        p.confidence[7] = 1.0;
        p
    }

    #[test]
    fn joints_go_to_the_base_frame_and_left_is_the_persons_own() {
        let pose = pose();
        let header = FrameHeader {
            seq: 42,
            capture_ns: 7,
            capture_wall_ns: 9,
            ..FrameHeader::zeroed()
        };
        let mut out = Skeleton::zeroed();
        // beyond the robot, facing it: facing the camera too, the person's
        // left on the image's right (+x camera), the base frame's +y seen from +x
        let p = person(&pose, [-1.0, 0.0, 0.5]);
        write_skeleton(&header, &pose, Facing::Robot, &[p], &mut out);
        assert_eq!(
            (out.seq, out.capture_ns, out.capture_wall_ns, out.n_people),
            (42, 7, 9, 1)
        );
        let sk = out.people[0];
        assert_eq!((sk.id, sk.tracked), (3, 1));
        // the torso at the centroid, back in the base frame
        let t = sk.joints[2];
        assert!((t[0] + 1.0).abs() < 1e-9 && t[1].abs() < 1e-9 && (t[2] - 0.5).abs() < 1e-9);
        assert_eq!(sk.confidence[7], 1.0);
        assert!(sk.joints[7][1] > 0.29, "{:?}", sk.joints[7]);
        // between the camera and the robot, facing the robot: the camera
        // sees their back, the hand on the image's right is their right
        let p = person(&pose, [1.0, 0.0, 0.5]);
        write_skeleton(&header, &pose, Facing::Robot, &[p], &mut out);
        assert_eq!(out.people[0].confidence[8], 1.0);
        assert_eq!(out.people[0].confidence[7], 0.5);
        // facing the camera whatever the robot: not swapped
        write_skeleton(&header, &pose, Facing::Camera, &[p], &mut out);
        assert_eq!(out.people[0].confidence[7], 1.0);
    }

    #[test]
    fn the_side_of_the_body_turned_away_from_the_camera_is_seen_less_surely() {
        // a camera exactly on the right of a person facing the robot
        let beside = CameraPose::look_at(
            &Point3::new(1.0, 2.0, 1.2),
            &Point3::new(1.0, 0.0, 0.5),
            &Vector3::z(),
        )
        .unwrap();
        let mut p = person(&beside, [1.0, 0.0, 0.5]);
        p.confidence = [1.0; SKELETON_JOINTS];
        let mut out = Skeleton::zeroed();
        write_skeleton(
            &FrameHeader::zeroed(),
            &beside,
            Facing::Robot,
            &[p],
            &mut out,
        );
        let c = out.people[0].confidence;
        let doubted = 1.0 - FAR_SIDE_DOUBT;
        for (l, r) in SIDES {
            assert!((c[l] - doubted).abs() < 1e-9, "{l}: {}", c[l]);
            assert_eq!(c[r], 1.0, "{r}");
        }
        // head, neck and torso on no side
        assert_eq!(&c[..3], &[1.0; 3]);
        // a camera straight in front: nothing doubted
        let mut q = person(&pose(), [1.0, 0.0, 0.5]);
        q.confidence = [1.0; SKELETON_JOINTS];
        write_skeleton(
            &FrameHeader::zeroed(),
            &pose(),
            Facing::Robot,
            &[q],
            &mut out,
        );
        assert!(out.people[0].confidence.iter().all(|&v| v == 1.0));
        // facing the camera: it always sees the front
        write_skeleton(
            &FrameHeader::zeroed(),
            &beside,
            Facing::Camera,
            &[p],
            &mut out,
        );
        assert!(out.people[0].confidence.iter().all(|&v| v == 1.0));
    }

    #[test]
    fn a_hand_that_jumps_away_from_the_robot_beside_it_is_held_while_it_could_not_have_moved_there()
    {
        let mut memory = [HandMemory::default(); MAX_PEOPLE];
        let mut p = Person {
            id: 2,
            ..Person::default()
        };
        let at = [0.1, 0.0, 1.0];
        let step =
            |memory: &mut [HandMemory; MAX_PEOPLE], p: &mut Person, x: [f64; 3], near: bool| {
                p.joints[8] = x;
                p.confidence[8] = 1.0;
                hold_hands_behind_the_robot(memory, std::slice::from_mut(p), 1.0 / 30.0, |_| near);
            };
        step(&mut memory, &mut p, at, true);
        assert_eq!((p.joints[8], p.confidence[8]), (at, 1.0));
        // a hand moving at 1.5 m/s beside the robot: believed
        let moved = [0.15, 0.0, 1.0];
        step(&mut memory, &mut p, moved, true);
        assert_eq!((p.joints[8], p.confidence[8]), (moved, 1.0));
        // 60 cm away in a frame, the robot beside it: held, confidence 0,
        // while the hand could not have moved that far (3 m/s: 4 frames)
        let junk = [0.15, 0.6, 1.0];
        for _ in 0..4 {
            step(&mut memory, &mut p, junk, true);
            assert_eq!((p.joints[8], p.confidence[8]), (moved, 0.0));
        }
        step(&mut memory, &mut p, junk, true);
        assert_eq!((p.joints[8], p.confidence[8]), (junk, 1.0));
        // 3 m away: held for half a second at most
        let far = [0.15, 3.6, 1.0];
        for _ in 0..15 {
            step(&mut memory, &mut p, far, true);
            assert_eq!((p.joints[8], p.confidence[8]), (junk, 0.0));
        }
        step(&mut memory, &mut p, far, true);
        assert_eq!((p.joints[8], p.confidence[8]), (far, 1.0));
        // the same jump with no robot near: believed at once
        step(&mut memory, &mut p, at, false);
        assert_eq!((p.joints[8], p.confidence[8]), (at, 1.0));
        // a person gone is forgotten
        hold_hands_behind_the_robot(&mut memory, &mut [], 1.0 / 30.0, |_| true);
        assert!(memory.iter().all(|m| m.id == 0));
    }

    #[test]
    fn a_tracker_is_built_for_the_frames_camera_with_the_scene_as_background() {
        let loaded = phri_config::Loaded::defaults();
        let cfg = &loaded.config;
        let model = loaded.model().unwrap();
        let t = DepthTracker::new(model, &cfg.skeleton, &cfg.perception, &cfg.camera).unwrap();
        let pose = cfg.camera.pose().unwrap();
        let tracker = t.build(cfg.camera.intrinsics, pose).unwrap();
        // the simulated table and floor are learned; up is the base's z
        assert_eq!(tracker.background_frames(), 1);
        let up = tracker.config().up_camera;
        let z = pose.rotation() * Vector3::new(up[0], up[1], up[2]);
        assert!((z - Vector3::z()).norm() < 1e-9, "{z:?}");
    }
}
