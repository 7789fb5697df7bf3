//! The simulated body tracker: the stand-in for a Kinect/NiTE-class
//! skeleton tracker, as the simulated camera stands in for the depth sensor.
//! Per depth frame it publishes the person's 15 joints (`perception/skeleton`,
//! same sequence number and capture time as the frame), with what a real
//! tracker adds: a slowly drifting offset per joint and frame-to-frame jitter
//! ([`SkeletonConfig::bias_m`], [`SkeletonConfig::noise_m`]), a lag of
//! [`SkeletonConfig::latency_frames`] frames, confidence 0 for a joint that
//! something nearer hides in the rendered frame, and frames where the person
//! is lost ([`SkeletonConfig::dropout`]).
//!
//! The joints come from the scripted person's capsules in `sim/world` (the
//! simulator's numbering, [`BodyPart`]): head and torso at their capsules'
//! middles, the neck at the torso's top, shoulders, elbows, hips, knees and
//! feet at the limb capsules' ends, the hands at the hand capsules' middles.
//! Allocation-free per frame.

use nalgebra::Point3;
use phri_config::SkeletonConfig;
use phri_depth::{CameraPose, Intrinsics};
use phri_ipc::{
    BodyPart, FrameHeader, Skeleton, SkeletonJoint as J, TrackedPerson, WorldState, Zeroed,
    SKELETON_JOINTS,
};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// The tracker's id of the (one) scripted person.
pub const PERSON_ID: u32 = 1;
/// Frames of lag the tracker can hold.
const MAX_LAG: usize = 31;

/// True joint positions [m] and the radius of the body part around each [m].
type Pose = ([[f64; 3]; SKELETON_JOINTS], [f64; SKELETON_JOINTS]);

/// The person's joints from the world's capsules; `None` without a person.
pub fn joints_of(world: &WorldState) -> Option<Pose> {
    let n = (world.n_human as usize).min(world.human.len());
    let caps = &world.human[..n];
    let cap = |p: BodyPart| caps.iter().find(|c| c.part == p as i32);
    let mid = |a: [f64; 3], b: [f64; 3]| {
        [
            (a[0] + b[0]) / 2.0,
            (a[1] + b[1]) / 2.0,
            (a[2] + b[2]) / 2.0,
        ]
    };
    let mut j = [[0.0; 3]; SKELETON_JOINTS];
    let mut r = [0.0; SKELETON_JOINTS];
    let head = cap(BodyPart::Head)?;
    let torso = cap(BodyPart::Torso)?;
    j[J::Head as usize] = mid(head.a, head.b);
    r[J::Head as usize] = head.radius;
    let top = if torso.a[2] > torso.b[2] {
        torso.a
    } else {
        torso.b
    };
    j[J::Neck as usize] = top;
    r[J::Neck as usize] = torso.radius;
    j[J::Torso as usize] = mid(torso.a, torso.b);
    r[J::Torso as usize] = torso.radius;
    for (upper, fore, hand, shoulder, elbow, h) in [
        (
            BodyPart::UpperArmLeft,
            BodyPart::ForearmLeft,
            BodyPart::HandLeft,
            J::LeftShoulder,
            J::LeftElbow,
            J::LeftHand,
        ),
        (
            BodyPart::UpperArmRight,
            BodyPart::ForearmRight,
            BodyPart::HandRight,
            J::RightShoulder,
            J::RightElbow,
            J::RightHand,
        ),
    ] {
        let (u, f, hc) = (cap(upper)?, cap(fore)?, cap(hand)?);
        j[shoulder as usize] = u.a;
        r[shoulder as usize] = u.radius;
        j[elbow as usize] = f.a;
        r[elbow as usize] = f.radius;
        j[h as usize] = mid(hc.a, hc.b);
        r[h as usize] = hc.radius;
    }
    for (thigh, shin, hip, knee, foot) in [
        (
            BodyPart::ThighLeft,
            BodyPart::ShinLeft,
            J::LeftHip,
            J::LeftKnee,
            J::LeftFoot,
        ),
        (
            BodyPart::ThighRight,
            BodyPart::ShinRight,
            J::RightHip,
            J::RightKnee,
            J::RightFoot,
        ),
    ] {
        let (t, s) = (cap(thigh)?, cap(shin)?);
        j[hip as usize] = t.a;
        r[hip as usize] = t.radius;
        j[knee as usize] = t.b;
        r[knee as usize] = t.radius;
        j[foot as usize] = s.b;
        r[foot as usize] = s.radius;
    }
    Some((j, r))
}

/// The simulated tracker.
pub struct SkeletonTracker {
    cfg: SkeletonConfig,
    intrinsics: Intrinsics,
    pose: CameraPose,
    rng: SmallRng,
    /// each joint's drifting offset [m]
    bias: [[f64; 3]; SKELETON_JOINTS],
    /// the last poses seen (a ring), for the lag
    history: [Option<Pose>; MAX_LAG + 1],
    frames: usize,
}

fn gauss(rng: &mut SmallRng) -> f64 {
    let (u1, u2): (f64, f64) = (1.0 - rng.gen::<f64>(), rng.gen());
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

impl SkeletonTracker {
    /// The tracker of `[skeleton]` (`cfg`, its noise seeded by `cfg.seed`) for
    /// the camera of `intrinsics` at `pose` (base frame), no frame seen yet.
    pub fn new(cfg: &SkeletonConfig, intrinsics: Intrinsics, pose: CameraPose) -> SkeletonTracker {
        let mut rng = SmallRng::seed_from_u64(cfg.seed ^ 0x5EED_5EED);
        let mut bias = [[0.0; 3]; SKELETON_JOINTS];
        for b in bias.iter_mut().flatten() {
            *b = cfg.bias_m * gauss(&mut rng);
        }
        SkeletonTracker {
            cfg: cfg.clone(),
            intrinsics,
            pose,
            rng,
            bias,
            history: [None; MAX_LAG + 1],
            frames: 0,
        }
    }

    /// The skeleton of the frame `header` rendered from `world` (`depth`: the
    /// frame's depths, millimetres, row-major), into `out`.
    pub fn step(
        &mut self,
        world: &WorldState,
        header: &FrameHeader,
        depth: &[u16],
        frame_period_s: f64,
        out: &mut Skeleton,
    ) {
        *out = Skeleton::zeroed();
        out.seq = header.seq;
        out.capture_ns = header.capture_ns;
        out.capture_wall_ns = header.capture_wall_ns;
        let slot = self.frames % (MAX_LAG + 1);
        self.history[slot] = joints_of(world);
        self.frames += 1;
        // drift: a first-order Gauss-Markov process per joint and axis
        let phi = (-frame_period_s.max(1e-3) / self.cfg.bias_time_s).exp();
        let kick = self.cfg.bias_m * (1.0 - phi * phi).sqrt();
        for b in self.bias.iter_mut().flatten() {
            *b = phi * *b + kick * gauss(&mut self.rng);
        }
        let lag = (self.cfg.latency_frames as usize).min(self.frames - 1);
        let Some((joints, radius)) = self.history[(self.frames - 1 - lag) % (MAX_LAG + 1)] else {
            return;
        };
        out.n_people = 1;
        let lost = self.rng.gen::<f64>() < self.cfg.dropout;
        let p: &mut TrackedPerson = &mut out.people[0];
        p.id = PERSON_ID;
        p.tracked = (!lost) as u32;
        let (w, h) = (header.width as usize, header.height as usize);
        for i in 0..SKELETON_JOINTS {
            for a in 0..3 {
                p.joints[i][a] =
                    joints[i][a] + self.bias[i][a] + self.cfg.noise_m * gauss(&mut self.rng);
            }
            if lost {
                continue;
            }
            // occluded when the frame shows something nearer than the body part's surface
            let q = Point3::from(joints[i]);
            let visible = self.pose.project(&self.intrinsics, &q).is_some_and(|px| {
                let (u, v) = (px.px.round(), px.py.round());
                if u < 0.0 || v < 0.0 || u as usize >= w || v as usize >= h {
                    return false;
                }
                let d = depth.get(v as usize * w + u as usize).copied().unwrap_or(0);
                // no reading: the tracker still sees the person's silhouette around it
                d == 0 || d as f64 * 1e-3 >= px.depth - radius[i] - self.cfg.occlusion_margin_m
            });
            p.confidence[i] = if visible {
                self.cfg.visible_confidence
            } else {
                0.0
            };
        }
    }
}

pub use phri_ipc::merge_views;

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::Config;
    use phri_ipc::WorldCapsule;

    fn world_with_person() -> WorldState {
        let mut w = WorldState::zeroed();
        let mut put = |i: usize, part: BodyPart, a: [f64; 3], b: [f64; 3], r: f64| {
            w.human[i] = WorldCapsule {
                a,
                b,
                radius: r,
                part: part as i32,
                _pad: 0,
            };
        };
        let x = 1.0;
        put(0, BodyPart::Head, [x, 0.0, 0.75], [x, 0.0, 0.90], 0.1);
        put(1, BodyPart::Torso, [x, 0.0, 0.15], [x, 0.0, 0.62], 0.15);
        put(2, BodyPart::Pelvis, [x, -0.1, 0.1], [x, 0.1, 0.1], 0.12);
        put(
            3,
            BodyPart::UpperArmLeft,
            [x, -0.2, 0.62],
            [x, -0.22, 0.35],
            0.05,
        );
        put(
            4,
            BodyPart::UpperArmRight,
            [x, 0.2, 0.62],
            [x, 0.22, 0.35],
            0.05,
        );
        put(
            5,
            BodyPart::ForearmLeft,
            [x, -0.22, 0.35],
            [x, -0.23, 0.12],
            0.04,
        );
        put(
            6,
            BodyPart::ForearmRight,
            [x, 0.22, 0.35],
            [x, 0.23, 0.12],
            0.04,
        );
        put(
            7,
            BodyPart::HandLeft,
            [x, -0.23, 0.12],
            [x, -0.23, 0.02],
            0.04,
        );
        put(
            8,
            BodyPart::HandRight,
            [x, 0.23, 0.12],
            [x, 0.23, 0.02],
            0.04,
        );
        put(
            9,
            BodyPart::ThighLeft,
            [x, -0.1, 0.05],
            [x, -0.1, -0.35],
            0.07,
        );
        put(
            10,
            BodyPart::ThighRight,
            [x, 0.1, 0.05],
            [x, 0.1, -0.35],
            0.07,
        );
        put(
            11,
            BodyPart::ShinLeft,
            [x, -0.1, -0.35],
            [x, -0.1, -0.75],
            0.05,
        );
        put(
            12,
            BodyPart::ShinRight,
            [x, 0.1, -0.35],
            [x, 0.1, -0.75],
            0.05,
        );
        w.n_human = 13;
        w
    }

    #[test]
    fn joints_come_from_the_capsules() {
        let w = world_with_person();
        let (j, r) = joints_of(&w).unwrap();
        assert_eq!(j[J::Neck as usize], [1.0, 0.0, 0.62]);
        assert_eq!(j[J::RightElbow as usize], [1.0, 0.22, 0.35]);
        assert!((j[J::RightHand as usize][2] - 0.07).abs() < 1e-12);
        assert_eq!(j[J::LeftFoot as usize], [1.0, -0.1, -0.75]);
        assert_eq!(r[J::Torso as usize], 0.15);
        assert!(joints_of(&WorldState::zeroed()).is_none());
    }

    #[test]
    fn noise_lag_occlusion_and_dropouts() {
        let cfg = Config::defaults();
        let pose = cfg.camera.pose().unwrap();
        let k = cfg.camera.intrinsics;
        let mut s = cfg.skeleton.clone();
        s.dropout = 0.0;
        let mut t = SkeletonTracker::new(&s, k, pose);
        let mut w = world_with_person();
        let header = FrameHeader {
            seq: 5,
            capture_ns: 99,
            width: k.width,
            height: k.height,
            ..FrameHeader::zeroed()
        };
        // an empty frame (no reading anywhere): every joint visible
        let depth = vec![0u16; (k.width * k.height) as usize];
        let mut out = Skeleton::zeroed();
        let mut err2 = 0.0;
        let n = 300;
        for _ in 0..n {
            t.step(&w, &header, &depth, 1.0 / 30.0, &mut out);
            assert_eq!((out.seq, out.capture_ns, out.n_people), (5, 99, 1));
            let p = out.people[0];
            assert_eq!(p.tracked, 1);
            // the upper body is in view (the feet may be below the picture)
            for j in [J::Head, J::Torso, J::RightHand, J::LeftHand, J::RightElbow] {
                assert_eq!(p.confidence[j as usize], s.visible_confidence, "{j:?}");
            }
            let e = p.joints[J::RightHand as usize][0] - 1.0;
            err2 += e * e;
        }
        // a few centimetres: jitter and drift together
        let rms = (err2 / n as f64).sqrt();
        let expected = (s.noise_m.powi(2) + s.bias_m.powi(2)).sqrt();
        assert!(rms > 0.2 * expected && rms < 3.0 * expected, "rms {rms}");
        // one frame of lag: a moved hand shows a frame later
        w.human[8].a[1] += 0.5;
        w.human[8].b[1] += 0.5;
        let mut ideal = s.clone();
        ideal.noise_m = 0.0;
        ideal.bias_m = 0.0;
        let mut t = SkeletonTracker::new(&ideal, k, pose);
        t.step(&world_with_person(), &header, &depth, 1.0 / 30.0, &mut out);
        t.step(&w, &header, &depth, 1.0 / 30.0, &mut out);
        assert!((out.people[0].joints[J::RightHand as usize][1] - 0.23).abs() < 1e-9);
        t.step(&w, &header, &depth, 1.0 / 30.0, &mut out);
        assert!((out.people[0].joints[J::RightHand as usize][1] - 0.73).abs() < 1e-9);
        // something 0.5 m in front of everything: every joint occluded
        let near = vec![500u16; (k.width * k.height) as usize];
        t.step(&w, &header, &near, 1.0 / 30.0, &mut out);
        assert!(out.people[0].confidence.iter().all(|&c| c == 0.0));
        // dropouts
        let mut lossy = ideal.clone();
        lossy.dropout = 0.5;
        let mut t = SkeletonTracker::new(&lossy, k, pose);
        let lost = (0..400)
            .filter(|_| {
                t.step(&w, &header, &depth, 1.0 / 30.0, &mut out);
                out.people[0].tracked == 0
            })
            .count();
        assert!((120..280).contains(&lost), "{lost} of 400 lost");
    }
}
