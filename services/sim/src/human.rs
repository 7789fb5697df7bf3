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

use nalgebra::Vector3;

/// A body region, with the contact stiffness used for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyPart {
    Head,
    Torso,
    Pelvis,
    UpperArmLeft,
    UpperArmRight,
    ForearmLeft,
    ForearmRight,
    HandLeft,
    HandRight,
    ThighLeft,
    ThighRight,
    ShinLeft,
    ShinRight,
}

impl BodyPart {
    /// Every part, in the order [`Human::pose_at`] returns their capsules.
    pub const ALL: [BodyPart; 13] = [
        BodyPart::Head,
        BodyPart::Torso,
        BodyPart::Pelvis,
        BodyPart::UpperArmLeft,
        BodyPart::UpperArmRight,
        BodyPart::ForearmLeft,
        BodyPart::ForearmRight,
        BodyPart::HandLeft,
        BodyPart::HandRight,
        BodyPart::ThighLeft,
        BodyPart::ThighRight,
        BodyPart::ShinLeft,
        BodyPart::ShinRight,
    ];

    /// snake_case name, as written in scenario files (e.g. `"forearm_right"`).
    pub fn name(self) -> &'static str {
        match self {
            BodyPart::Head => "head",
            BodyPart::Torso => "torso",
            BodyPart::Pelvis => "pelvis",
            BodyPart::UpperArmLeft => "upper_arm_left",
            BodyPart::UpperArmRight => "upper_arm_right",
            BodyPart::ForearmLeft => "forearm_left",
            BodyPart::ForearmRight => "forearm_right",
            BodyPart::HandLeft => "hand_left",
            BodyPart::HandRight => "hand_right",
            BodyPart::ThighLeft => "thigh_left",
            BodyPart::ThighRight => "thigh_right",
            BodyPart::ShinLeft => "shin_left",
            BodyPart::ShinRight => "shin_right",
        }
    }

    /// The part called `name` (see [`BodyPart::name`]).
    pub fn from_name(name: &str) -> Option<BodyPart> {
        BodyPart::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Contact spring constant [N/m] of the body region, after the effective
    /// spring constants of ISO/TS 15066 Table A.2 (N/mm × 1000): hand 75,
    /// forearm 40, upper arm 30, head 150, chest 25, abdomen/pelvis 10,
    /// thigh 50, lower leg 60.
    pub fn stiffness_n_per_m(self) -> f64 {
        let n_per_mm = match self {
            BodyPart::Head => 150.0,
            BodyPart::Torso => 25.0,
            BodyPart::Pelvis => 10.0,
            BodyPart::UpperArmLeft | BodyPart::UpperArmRight => 30.0,
            BodyPart::ForearmLeft | BodyPart::ForearmRight => 40.0,
            BodyPart::HandLeft | BodyPart::HandRight => 75.0,
            BodyPart::ThighLeft | BodyPart::ThighRight => 50.0,
            BodyPart::ShinLeft | BodyPart::ShinRight => 60.0,
        };
        n_per_mm * 1000.0
    }
}

impl std::fmt::Display for BodyPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One body part as a capsule: the segment `a`–`b` \[m\] swept by a sphere of
/// `radius` \[m\], robot base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanCapsule {
    pub part: BodyPart,
    pub a: Vector3<f64>,
    pub b: Vector3<f64>,
    pub radius: f64,
}

/// The human's pose at one instant of the script.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// time \[s\] (scenario time, the simulator's clock)
    pub t: f64,
    /// `[x, y, yaw]`: floor position \[m\] and heading \[rad\] (angle of the
    /// human's forward direction about the base z axis), robot base frame
    pub base: [f64; 3],
    /// right-hand target \[m\], robot base frame; `None`: the arm hangs down
    pub right_hand: Option<[f64; 3]>,
    /// left-hand target \[m\], robot base frame; `None`: the arm hangs down
    pub left_hand: Option<[f64; 3]>,
}

/// A validated human script: keyframes sorted by strictly increasing time,
/// every number finite (build it with [`HumanScript::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct HumanScript {
    floor_z: f64,
    keyframes: Vec<Keyframe>,
    /// the script starts over every `repeat_s` \[s\] (`None`: plays once)
    repeat_s: Option<f64>,
}

/// Why a [`HumanScript`] was refused. `index` is the keyframe's position.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ScriptError {
    #[error("floor_z: {0} is not a finite number")]
    FloorZ(f64),
    #[error("keyframe: a human needs at least one keyframe")]
    NoKeyframe,
    #[error("keyframe[{index}].{field}: not a finite number")]
    NotFinite { index: usize, field: &'static str },
    #[error("keyframe[{index}].t: {t} s is not after the previous keyframe's {previous} s (keyframes must be sorted by strictly increasing t)")]
    Unsorted { index: usize, t: f64, previous: f64 },
    #[error("repeat_s: {repeat_s} s must be finite and at least the last keyframe's time {last} s (and > 0)")]
    Repeat { repeat_s: f64, last: f64 },
}

impl HumanScript {
    /// Default floor height \[m\]: the robot stands on a 0.8 m table.
    pub const DEFAULT_FLOOR_Z: f64 = -0.8;

    /// Check and keep a script. `floor_z` \[m\] is the height of the human's
    /// soles in the robot base frame.
    pub fn new(floor_z: f64, keyframes: Vec<Keyframe>) -> Result<HumanScript, ScriptError> {
        if !floor_z.is_finite() {
            return Err(ScriptError::FloorZ(floor_z));
        }
        if keyframes.is_empty() {
            return Err(ScriptError::NoKeyframe);
        }
        for (index, k) in keyframes.iter().enumerate() {
            let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
            if !k.t.is_finite() {
                return Err(ScriptError::NotFinite { index, field: "t" });
            }
            if !fin(&k.base) {
                return Err(ScriptError::NotFinite {
                    index,
                    field: "base",
                });
            }
            if k.right_hand.is_some_and(|h| !fin(&h)) {
                return Err(ScriptError::NotFinite {
                    index,
                    field: "right_hand",
                });
            }
            if k.left_hand.is_some_and(|h| !fin(&h)) {
                return Err(ScriptError::NotFinite {
                    index,
                    field: "left_hand",
                });
            }
            if index > 0 {
                let previous = keyframes[index - 1].t;
                if k.t <= previous {
                    return Err(ScriptError::Unsorted {
                        index,
                        t: k.t,
                        previous,
                    });
                }
            }
        }
        Ok(HumanScript {
            floor_z,
            keyframes,
            repeat_s: None,
        })
    }

    /// Play the script over and over, starting again every `repeat_s` \[s\]
    /// (at least the last keyframe's time, so the keyframes never overlap;
    /// the first keyframe should match the last for a continuous loop).
    pub fn repeating(mut self, repeat_s: f64) -> Result<HumanScript, ScriptError> {
        let last = self.end_time();
        if !(repeat_s.is_finite() && repeat_s > 0.0 && repeat_s >= last) {
            return Err(ScriptError::Repeat { repeat_s, last });
        }
        self.repeat_s = Some(repeat_s);
        Ok(self)
    }

    /// The loop period \[s\], if the script repeats.
    pub fn repeat_s(&self) -> Option<f64> {
        self.repeat_s
    }

    /// Height of the soles \[m\], robot base frame.
    pub fn floor_z(&self) -> f64 {
        self.floor_z
    }

    /// The keyframes, sorted by time.
    pub fn keyframes(&self) -> &[Keyframe] {
        &self.keyframes
    }

    /// Time of the last keyframe \[s\]: the human stands still afterwards.
    pub fn end_time(&self) -> f64 {
        self.keyframes.last().map_or(0.0, |k| k.t)
    }
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
        let t = match self.script.repeat_s {
            Some(period) if t > 0.0 => t.rem_euclid(period),
            _ => t,
        };
        let (base, right, left) = self.interpolate(t);
        let fl = Frame::new(base, self.script.floor_z);
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
        let ks = &self.script.keyframes;
        let floor_z = self.script.floor_z;
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

    #[test]
    fn names_round_trip() {
        for (i, p) in BodyPart::ALL.into_iter().enumerate() {
            assert_eq!(BodyPart::from_name(p.name()), Some(p));
            assert_eq!(p as usize, i, "ALL is in declaration order");
        }
        assert_eq!(BodyPart::ForearmRight.name(), "forearm_right");
        assert_eq!(BodyPart::HandRight.stiffness_n_per_m(), 75_000.0);
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
    fn refuses_bad_scripts() {
        let k = |t: f64| Keyframe {
            t,
            base: [0.0; 3],
            right_hand: None,
            left_hand: None,
        };
        assert_eq!(HumanScript::new(-0.8, vec![]), Err(ScriptError::NoKeyframe));
        assert!(matches!(
            HumanScript::new(-0.8, vec![k(1.0), k(0.5)]),
            Err(ScriptError::Unsorted { index: 1, .. })
        ));
        assert!(matches!(
            HumanScript::new(-0.8, vec![k(f64::NAN)]),
            Err(ScriptError::NotFinite {
                index: 0,
                field: "t"
            })
        ));
        assert!(matches!(
            HumanScript::new(f64::INFINITY, vec![k(0.0)]),
            Err(ScriptError::FloorZ(_))
        ));
        let two = || HumanScript::new(-0.8, vec![k(0.0), k(10.0)]).unwrap();
        for bad in [5.0, 0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(
                matches!(two().repeating(bad), Err(ScriptError::Repeat { .. })),
                "repeat_s {bad}"
            );
        }
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
