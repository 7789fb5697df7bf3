//! A scripted human made of capsules.
//!
//! The human is a standing adult of about 1.75 m. Its pose at time `t` comes
//! from keyframes (linear interpolation, clamped before the first and after
//! the last): where it stands and which way it faces, and optionally where
//! each hand is. Arms are shoulder → elbow → hand chains solved with a
//! two-link inverse kinematics; a hand without a target hangs down. Legs and
//! trunk are rigid (no gait).
//!
//! Frames: everything is in the robot base frame (x forward, z up, SI units).
//! The human's own frame has its origin on the floor between the feet, `x`
//! along its heading, `y` to its left and `z` up.
//!
//! The script itself (keyframes, checked) is [`phri_config::HumanScript`];
//! body parts are numbered as on the wire ([`phri_ipc::BodyPart`]).

use nalgebra::Vector3;
use phri_config::{HumanScript, Keyframe};
use phri_ipc::BodyPart;

/// One body part as a capsule: the segment `a`–`b` \[m\] swept by a sphere of
/// `radius` \[m\], robot base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanCapsule {
    pub part: BodyPart,
    pub a: Vector3<f64>,
    pub b: Vector3<f64>,
    pub radius: f64,
}

/// Body dimensions \[m\] of the standing adult (about 1.75 m tall), human frame.
mod body {
    /// shoulder joint centres: height above the floor and half width
    pub const SHOULDER_Z: f64 = 1.45;
    pub const SHOULDER_Y: f64 = 0.19;
    /// upper arm (shoulder → elbow) and forearm (elbow → hand centre) lengths
    pub const UPPER_ARM: f64 = 0.30;
    pub const FOREARM: f64 = 0.28;
    /// the forearm capsule ends at the wrist, this far before the hand centre;
    /// the hand capsule runs from the wrist to `HAND_TIP` past the hand centre
    pub const WRIST_BEFORE_HAND: f64 = 0.07;
    pub const HAND_TIP: f64 = 0.02;
    pub const R_UPPER_ARM: f64 = 0.05;
    pub const R_FOREARM: f64 = 0.04;
    pub const R_HAND: f64 = 0.045;
    /// a hanging hand, relative to its shoulder: forward, outward, down
    pub const HANG: [f64; 3] = [0.03, 0.05, -0.55];
    /// head: vertical segment and radius (top of the head at 1.75 m)
    pub const HEAD: [f64; 2] = [1.56, 1.65];
    pub const R_HEAD: f64 = 0.10;
    /// torso (chest and abdomen): vertical segment and radius
    pub const TORSO: [f64; 2] = [1.08, 1.33];
    pub const R_TORSO: f64 = 0.15;
    /// pelvis: horizontal segment across the hips at this height, radius
    pub const PELVIS_Z: f64 = 0.95;
    pub const PELVIS_Y: f64 = 0.08;
    pub const R_PELVIS: f64 = 0.12;
    /// legs: hip, knee and ankle heights, half stance width, radii
    pub const HIP_Z: f64 = 0.88;
    pub const KNEE_Z: f64 = 0.50;
    pub const ANKLE_Z: f64 = 0.10;
    pub const LEG_Y: f64 = 0.10;
    pub const R_THIGH: f64 = 0.075;
    pub const R_SHIN: f64 = 0.055;
}

/// The human's frame: origin on the floor, unit forward and left axes.
#[derive(Clone, Copy)]
struct Frame {
    o: Vector3<f64>,
    fwd: Vector3<f64>,
    left: Vector3<f64>,
}

impl Frame {
    fn new(base: [f64; 3], floor_z: f64) -> Frame {
        let (s, c) = base[2].sin_cos();
        Frame {
            o: Vector3::new(base[0], base[1], floor_z),
            fwd: Vector3::new(c, s, 0.0),
            left: Vector3::new(-s, c, 0.0),
        }
    }

    /// A point given in the human frame (forward, left, up) \[m\].
    fn point(&self, x: f64, y: f64, z: f64) -> Vector3<f64> {
        self.o + self.fwd * x + self.left * y + Vector3::z() * z
    }
}

/// Right (`side = -1`) or left (`side = +1`) arm: capsule endpoints of upper
/// arm, forearm and hand for a hand target (`None`: hanging).
fn arm(
    frame: &Frame,
    side: f64,
    target: Option<Vector3<f64>>,
) -> [(Vector3<f64>, Vector3<f64>); 3] {
    use body::*;
    let shoulder = frame.point(0.0, side * SHOULDER_Y, SHOULDER_Z);
    let target = target.unwrap_or_else(|| hang_point(frame, side));
    let reach_max = UPPER_ARM + FOREARM - 1e-6;
    let reach_min = (UPPER_ARM - FOREARM).abs() + 0.05;
    let to = target - shoulder;
    let d_raw = to.norm();
    let u = if d_raw > 1e-9 {
        to / d_raw
    } else {
        -Vector3::z()
    };
    let d = d_raw.clamp(reach_min, reach_max);
    let hand = shoulder + u * d;
    // elbow in the plane of the arm and a hint pointing down and outwards
    let outward = frame.left * side;
    let mut hint = (outward * 0.5 - Vector3::z()).normalize();
    let mut perp = hint - u * hint.dot(&u);
    if perp.norm() < 0.2 {
        // reaching along the hint: bend the elbow backwards instead
        hint = -frame.fwd;
        perp = hint - u * hint.dot(&u);
    }
    let perp = perp.normalize();
    // law of cosines: distance along u from the shoulder to the elbow's foot
    let along = (UPPER_ARM * UPPER_ARM - FOREARM * FOREARM + d * d) / (2.0 * d);
    let height = (UPPER_ARM * UPPER_ARM - along * along).max(0.0).sqrt();
    let elbow = shoulder + u * along + perp * height;
    let fore = (hand - elbow) / FOREARM;
    let wrist = hand - fore * WRIST_BEFORE_HAND;
    [
        (shoulder, elbow),
        (elbow, wrist),
        (wrist, hand + fore * HAND_TIP),
    ]
}

/// Where a hanging hand is \[m\], base frame.
fn hang_point(frame: &Frame, side: f64) -> Vector3<f64> {
    use body::*;
    frame.point(HANG[0], side * (SHOULDER_Y + HANG[1]), SHOULDER_Z + HANG[2])
}

/// A runnable human: the script plus the capsule buffer [`Human::pose_at`]
/// fills (allocated once in [`Human::new`]).
#[derive(Clone, Debug)]
pub struct Human {
    script: HumanScript,
    capsules: Vec<HumanCapsule>,
}

impl Human {
    pub fn new(script: HumanScript) -> Human {
        let capsules = BodyPart::ALL
            .iter()
            .map(|&part| HumanCapsule {
                part,
                a: Vector3::zeros(),
                b: Vector3::zeros(),
                radius: 0.0,
            })
            .collect();
        let mut h = Human { script, capsules };
        h.pose_at(0.0);
        h
    }

    pub fn script(&self) -> &HumanScript {
        &self.script
    }

    /// The capsules of the last [`Human::pose_at`], in [`BodyPart::ALL`] order.
    pub fn capsules(&self) -> &[HumanCapsule] {
        &self.capsules
    }

    /// Pose the body at time `t` \[s\] and return its capsules (base frame, in
    /// [`BodyPart::ALL`] order). Allocates nothing.
    pub fn pose_at(&mut self, t: f64) -> &[HumanCapsule] {
        use body::*;
        let t = match self.script.repeat_s() {
            Some(period) if t > 0.0 => t.rem_euclid(period),
            _ => t,
        };
        let (base, right, left) = self.interpolate(t);
        let fl = Frame::new(base, self.script.floor_z());
        let mut set = |part: BodyPart, a: Vector3<f64>, b: Vector3<f64>, radius: f64| {
            // ALL lists the parts in declaration order, so the discriminant is the index
            self.capsules[part as usize] = HumanCapsule { part, a, b, radius };
        };
        set(
            BodyPart::Head,
            fl.point(0.0, 0.0, HEAD[0]),
            fl.point(0.0, 0.0, HEAD[1]),
            R_HEAD,
        );
        set(
            BodyPart::Torso,
            fl.point(0.0, 0.0, TORSO[0]),
            fl.point(0.0, 0.0, TORSO[1]),
            R_TORSO,
        );
        set(
            BodyPart::Pelvis,
            fl.point(0.0, -PELVIS_Y, PELVIS_Z),
            fl.point(0.0, PELVIS_Y, PELVIS_Z),
            R_PELVIS,
        );
        for (side, target, parts) in [
            (
                1.0,
                left,
                [
                    BodyPart::UpperArmLeft,
                    BodyPart::ForearmLeft,
                    BodyPart::HandLeft,
                ],
            ),
            (
                -1.0,
                right,
                [
                    BodyPart::UpperArmRight,
                    BodyPart::ForearmRight,
                    BodyPart::HandRight,
                ],
            ),
        ] {
            let segs = arm(&fl, side, target);
            for ((a, b), (part, r)) in
                segs.into_iter()
                    .zip(parts.into_iter().zip([R_UPPER_ARM, R_FOREARM, R_HAND]))
            {
                set(part, a, b, r);
            }
        }
        for (side, thigh, shin) in [
            (1.0, BodyPart::ThighLeft, BodyPart::ShinLeft),
            (-1.0, BodyPart::ThighRight, BodyPart::ShinRight),
        ] {
            let y = side * LEG_Y;
            set(
                thigh,
                fl.point(0.0, y, HIP_Z),
                fl.point(0.0, y, KNEE_Z),
                R_THIGH,
            );
            set(
                shin,
                fl.point(0.0, y, KNEE_Z),
                fl.point(0.0, y, ANKLE_Z),
                R_SHIN,
            );
        }
        &self.capsules
    }

    /// Interpolated `[x, y, yaw]` and hand targets at `t` (clamped to the script).
    fn interpolate(&self, t: f64) -> ([f64; 3], Option<Vector3<f64>>, Option<Vector3<f64>>) {
        let ks = self.script.keyframes();
        let floor_z = self.script.floor_z();
        let v3 = |h: [f64; 3]| Vector3::new(h[0], h[1], h[2]);
        let first = &ks[0];
        let last = &ks[ks.len() - 1];
        let single = |k: &Keyframe| (k.base, k.right_hand.map(v3), k.left_hand.map(v3));
        if t.is_nan() || t <= first.t {
            return single(first);
        }
        if t >= last.t {
            return single(last);
        }
        // ks is sorted and t lies strictly inside it: find the segment
        let i = ks.partition_point(|k| k.t <= t).clamp(1, ks.len() - 1);
        let (k0, k1) = (&ks[i - 1], &ks[i]);
        let s = (t - k0.t) / (k1.t - k0.t);
        let lerp = |a: f64, b: f64| a + (b - a) * s;
        let base = [
            lerp(k0.base[0], k1.base[0]),
            lerp(k0.base[1], k1.base[1]),
            lerp(k0.base[2], k1.base[2]),
        ];
        // a missing target stands for the hanging hand at that keyframe, so the
        // blend is continuous; two missing targets hang from the blended body
        let hand =
            |h0: Option<[f64; 3]>, h1: Option<[f64; 3]>, side: f64| -> Option<Vector3<f64>> {
                if h0.is_none() && h1.is_none() {
                    return None;
                }
                let p0 = h0
                    .map(v3)
                    .unwrap_or_else(|| hang_point(&Frame::new(k0.base, floor_z), side));
                let p1 = h1
                    .map(v3)
                    .unwrap_or_else(|| hang_point(&Frame::new(k1.base, floor_z), side));
                Some(p0 + (p1 - p0) * s)
            };
        (
            base,
            hand(k0.right_hand, k1.right_hand, -1.0),
            hand(k0.left_hand, k1.left_hand, 1.0),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn script(ks: Vec<Keyframe>) -> HumanScript {
        HumanScript::new(-0.8, ks).expect("valid script")
    }

    /// The capsules are indexed by the part's wire number: `ALL` must be in that order.
    #[test]
    fn names_round_trip() {
        for (i, p) in BodyPart::ALL.iter().copied().enumerate() {
            assert_eq!(BodyPart::from_name(p.name()), Ok(p));
            assert_eq!(p as usize, i, "ALL is in declaration order");
        }
        assert_eq!(BodyPart::ForearmRight.name(), "forearm_right");
        assert_eq!(crate::stiffness_n_per_m(BodyPart::HandRight), 75_000.0);
    }

    #[test]
    fn arm_segments_have_their_lengths_and_reach_the_target() {
        let mut h = Human::new(script(vec![Keyframe {
            t: 0.0,
            base: [1.0, 0.0, std::f64::consts::PI],
            right_hand: Some([0.6, 0.1, 0.5]),
            left_hand: None,
        }]));
        let c = h.pose_at(0.0).to_vec();
        let ua = c[BodyPart::UpperArmRight as usize];
        let fa = c[BodyPart::ForearmRight as usize];
        let hand = c[BodyPart::HandRight as usize];
        assert!(((ua.b - ua.a).norm() - body::UPPER_ARM).abs() < 1e-9);
        let hand_centre = hand.b - (fa.b - fa.a).normalize() * body::HAND_TIP;
        assert!(((hand_centre - fa.a).norm() - body::FOREARM).abs() < 1e-9);
        assert!((hand_centre - Vector3::new(0.6, 0.1, 0.5)).norm() < 1e-9);
        // elbow below the shoulder–hand line
        let mid = (ua.a + hand_centre) * 0.5;
        assert!(ua.b.z < mid.z);
        // right side of a human facing -x is +y
        assert!(ua.a.y > 0.1);
        // head top near 1.75 m above the floor
        let head = c[BodyPart::Head as usize];
        assert!((head.b.z + head.radius - (-0.8 + 1.75)).abs() < 0.01);
    }

    #[test]
    fn a_repeating_script_starts_over_every_period() {
        let k = |t: f64, x: f64| Keyframe {
            t,
            base: [x, 0.0, 0.0],
            right_hand: None,
            left_hand: None,
        };
        let script = HumanScript::new(-0.8, vec![k(0.0, 1.0), k(4.0, 2.0)])
            .unwrap()
            .repeating(10.0)
            .unwrap();
        assert_eq!(script.repeat_s(), Some(10.0));
        let mut h = Human::new(script);
        let at = |h: &mut Human, t: f64| h.pose_at(t).to_vec();
        for t in [1.0, 3.0, 6.0] {
            assert_eq!(at(&mut h, t), at(&mut h, t + 10.0), "t = {t}");
            assert_eq!(at(&mut h, t), at(&mut h, t + 30.0), "t = {t}");
        }
        // within one period it plays like the script
        assert_ne!(at(&mut h, 1.0), at(&mut h, 3.0));
    }
}
