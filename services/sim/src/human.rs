//! A scripted human made of capsules.
//!
//! The human is a standing adult of about 1.75 m. Its pose at time `t` comes
//! from keyframes (linear interpolation, clamped before the first and after
//! the last): where it stands and which way it faces, and optionally where
//! each hand and each foot is. Arms are shoulder → elbow → hand chains and
//! legs hip → knee → ankle chains, solved with a two-link inverse kinematics
//! (elbows bend down and outwards, knees forwards); a hand without a target
//! hangs down, a leg without one stands straight. The trunk is rigid (no gait).
//!
//! Actions of a keyframe, until the next keyframe:
//! - a [`Wave`]: the hand is raised above its elbow and swings along the
//!   person's left–right axis about a fixed elbow (the hand's target is
//!   ignored meanwhile); it blends in and out over [`WAVE_BLEND_S`];
//! - a [`phri_config::Push`]: the simulator knows where the link is and puts
//!   the hand there through [`Human::pose_reaching`] ([`Human::push_at`]
//!   tells which push acts and how far it has ramped up).
//!
//! Frames: everything is in the robot base frame (x forward, z up, SI units).
//! The human's own frame has its origin on the floor between the feet, `x`
//! along its heading, `y` to its left and `z` up.
//!
//! The script itself (keyframes, checked) is [`phri_config::HumanScript`];
//! body parts are numbered as on the wire ([`phri_ipc::BodyPart`]).

use nalgebra::Vector3;
use phri_config::{Hand, HumanScript, Keyframe, Push, Wave};
use phri_ipc::BodyPart;

/// One body part as a capsule: the segment `a`–`b` \[m\] swept by a sphere of
/// `radius` \[m\], robot base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanCapsule {
    /// the body part it stands for
    pub part: BodyPart,
    /// one end of the axis segment \[m\], base frame
    pub a: Vector3<f64>,
    /// the other end of the axis segment \[m\], base frame
    pub b: Vector3<f64>,
    /// radius of the swept sphere \[m\]
    pub radius: f64,
}

/// A wave blends in over this time \[s\] after its keyframe and out over this
/// time before the next keyframe (shorter intervals: a partial wave).
pub const WAVE_BLEND_S: f64 = 0.5;

/// Body dimensions \[m\] of the standing adult (about 1.75 m tall), human frame.
pub mod body {
    /// shoulder joint centres: height above the floor and half width
    pub const SHOULDER_Z: f64 = 1.45;
    /// shoulder joint centres: distance from the body's mid plane (half width)
    pub const SHOULDER_Y: f64 = 0.19;
    /// upper arm (shoulder → elbow) and forearm (elbow → hand centre) lengths
    pub const UPPER_ARM: f64 = 0.30;
    /// forearm length, elbow → hand centre
    pub const FOREARM: f64 = 0.28;
    /// the forearm capsule ends at the wrist, this far before the hand centre;
    /// the hand capsule runs from the wrist to `HAND_TIP` past the hand centre
    pub const WRIST_BEFORE_HAND: f64 = 0.07;
    /// how far the hand capsule reaches past the hand centre
    pub const HAND_TIP: f64 = 0.02;
    /// upper arm capsule radius
    pub const R_UPPER_ARM: f64 = 0.05;
    /// forearm capsule radius
    pub const R_FOREARM: f64 = 0.04;
    /// hand capsule radius
    pub const R_HAND: f64 = 0.045;
    /// a hanging hand, relative to its shoulder: forward, outward, down
    pub const HANG: [f64; 3] = [0.03, 0.05, -0.55];
    /// a waving arm: direction of the upper arm from the shoulder (forward,
    /// outward, up; normalized where used): the elbow ends up about 0.1 m in
    /// front, 0.24 m out and 0.15 m below the shoulder
    pub const WAVE_UPPER_ARM: [f64; 3] = [0.3, 0.8, -0.5];
    /// largest lateral swing of the hand about the elbow \[m\] (forearm tilted
    /// by 45°); a larger amplitude swings the upper arm (the elbow) too
    pub const WAVE_SWING_MAX: f64 = 0.2;
    /// head: vertical segment and radius (top of the head at 1.75 m)
    pub const HEAD: [f64; 2] = [1.56, 1.65];
    /// head capsule radius
    pub const R_HEAD: f64 = 0.10;
    /// torso (chest and abdomen): vertical segment and radius
    pub const TORSO: [f64; 2] = [1.08, 1.33];
    /// torso capsule radius
    pub const R_TORSO: f64 = 0.15;
    /// pelvis: horizontal segment across the hips at this height, radius
    pub const PELVIS_Z: f64 = 0.95;
    /// pelvis: half length of the segment across the hips
    pub const PELVIS_Y: f64 = 0.08;
    /// pelvis capsule radius
    pub const R_PELVIS: f64 = 0.12;
    /// legs: hip, knee and ankle heights of the standing leg (thigh 0.38 m,
    /// shin 0.40 m), half stance width, radii
    pub const HIP_Z: f64 = 0.88;
    /// knee height of the standing leg
    pub const KNEE_Z: f64 = 0.50;
    /// ankle height of the standing leg
    pub const ANKLE_Z: f64 = 0.10;
    /// half stance width: the legs' distance from the body's mid plane
    pub const LEG_Y: f64 = 0.10;
    /// thigh capsule radius
    pub const R_THIGH: f64 = 0.075;
    /// shin capsule radius
    pub const R_SHIN: f64 = 0.055;
}

/// The human's frame: origin on the floor, unit forward and left axes, and
/// the upper body's forward lean about the hips (its sine and cosine).
#[derive(Clone, Copy)]
struct Frame {
    o: Vector3<f64>,
    fwd: Vector3<f64>,
    left: Vector3<f64>,
    lean_sin: f64,
    lean_cos: f64,
}

impl Frame {
    fn new(base: [f64; 3], floor_z: f64) -> Frame {
        let (s, c) = base[2].sin_cos();
        Frame {
            o: Vector3::new(base[0], base[1], floor_z),
            fwd: Vector3::new(c, s, 0.0),
            left: Vector3::new(-s, c, 0.0),
            lean_sin: 0.0,
            lean_cos: 1.0,
        }
    }

    /// The same frame with the upper body leaning `lean` \[rad\] forward.
    fn leaning(self, lean: f64) -> Frame {
        let (lean_sin, lean_cos) = lean.sin_cos();
        Frame {
            lean_sin,
            lean_cos,
            ..self
        }
    }

    /// A point given in the human frame (forward, left, up) \[m\].
    fn point(&self, x: f64, y: f64, z: f64) -> Vector3<f64> {
        self.o + self.fwd * x + self.left * y + Vector3::z() * z
    }

    /// A point of the upper body given in the upright human frame
    /// (forward, left, up) \[m\], turned with the lean about the hips'
    /// axis (left, at the pelvis' height).
    fn upper(&self, x: f64, y: f64, z: f64) -> Vector3<f64> {
        if self.lean_sin == 0.0 {
            // upright: exactly the standing body's point
            return self.point(x, y, z);
        }
        let up = z - body::PELVIS_Z;
        self.point(
            x * self.lean_cos + up * self.lean_sin,
            y,
            body::PELVIS_Z - x * self.lean_sin + up * self.lean_cos,
        )
    }
}

/// Two-link chain `root` → `mid` → `end` with segment lengths `l1`, `l2`
/// \[m\] reaching for `target` (clamped to the reachable shell): the middle
/// joint bends towards `hint`, or towards `fallback` when the chain points
/// along `hint`. Returns `(mid, end)`.
fn two_link(
    root: Vector3<f64>,
    target: Vector3<f64>,
    l1: f64,
    l2: f64,
    hint: Vector3<f64>,
    fallback: Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let reach_max = l1 + l2 - 1e-6;
    let reach_min = (l1 - l2).abs() + 0.05;
    let to = target - root;
    let d_raw = to.norm();
    let u = if d_raw > 1e-9 {
        to / d_raw
    } else {
        -Vector3::z()
    };
    let d = d_raw.clamp(reach_min, reach_max);
    let end = root + u * d;
    let mut perp = hint - u * hint.dot(&u);
    if perp.norm() < 0.2 {
        perp = fallback - u * fallback.dot(&u);
    }
    let perp = perp.normalize();
    // law of cosines: distance along u from the root to the middle joint's foot
    let along = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
    let height = (l1 * l1 - along * along).max(0.0).sqrt();
    (root + u * along + perp * height, end)
}

/// Right (`side = -1`) or left (`side = +1`) arm: shoulder, elbow and hand
/// centre for a hand target (`None`: hanging).
fn arm_joints(
    frame: &Frame,
    side: f64,
    target: Option<Vector3<f64>>,
) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    use body::*;
    let shoulder = frame.upper(0.0, side * SHOULDER_Y, SHOULDER_Z);
    let target = target.unwrap_or_else(|| hang_point(frame, side));
    // elbow in the plane of the arm and a hint pointing down and outwards;
    // reaching along the hint, the elbow bends backwards instead
    let hint = (frame.left * side * 0.5 - Vector3::z()).normalize();
    let (elbow, hand) = two_link(shoulder, target, UPPER_ARM, FOREARM, hint, -frame.fwd);
    (shoulder, elbow, hand)
}

/// The waving arm's elbow and hand centre at `tau` \[s\] into the wave.
fn wave_joints(
    frame: &Frame,
    side: f64,
    shoulder: Vector3<f64>,
    wave: &Wave,
    tau: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    use body::*;
    let [f, o, u] = WAVE_UPPER_ARM;
    let dir = (frame.fwd * f + frame.left * (side * o) + Vector3::z() * u).normalize();
    let x = wave.amplitude_m * (std::f64::consts::TAU * wave.frequency_hz * tau).sin();
    // the forearm swings up to WAVE_SWING_MAX about the elbow, the upper arm the rest
    let swing = x.clamp(-WAVE_SWING_MAX, WAVE_SWING_MAX);
    let excess = x - swing;
    let elbow = if excess == 0.0 {
        shoulder + dir * UPPER_ARM
    } else {
        shoulder + (dir * UPPER_ARM + frame.left * excess).normalize() * UPPER_ARM
    };
    let up = (FOREARM * FOREARM - swing * swing).max(0.0).sqrt();
    (elbow, elbow + frame.left * swing + Vector3::z() * up)
}

/// Capsule segments of upper arm, forearm and hand for the joint centres.
fn arm_segments(
    shoulder: Vector3<f64>,
    elbow: Vector3<f64>,
    hand: Vector3<f64>,
) -> [(Vector3<f64>, Vector3<f64>); 3] {
    use body::*;
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
    if frame.lean_sin == 0.0 {
        return frame.point(HANG[0], side * (SHOULDER_Y + HANG[1]), SHOULDER_Z + HANG[2]);
    }
    // the arm hangs from the shoulder whatever the lean
    let shoulder = frame.upper(0.0, side * SHOULDER_Y, SHOULDER_Z);
    shoulder + frame.fwd * HANG[0] + frame.left * (side * HANG[1]) + Vector3::z() * HANG[2]
}

/// Where the ankle of a straight standing leg is \[m\], base frame.
fn stand_point(frame: &Frame, side: f64) -> Vector3<f64> {
    use body::*;
    frame.point(0.0, side * LEG_Y, ANKLE_Z)
}

/// `+1` for the left side, `−1` for the right (the human frame's y).
fn side_of(hand: Hand) -> f64 {
    match hand {
        Hand::Right => -1.0,
        Hand::Left => 1.0,
    }
}

/// A hand placed at a point for a while, by the simulator: the hand centre
/// moves from its scripted target to `point` \[m\] (base frame) as `weight`
/// goes from 0 to 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// the hand placed
    pub hand: Hand,
    /// where the hand centre goes at full weight \[m\], base frame
    pub point: Vector3<f64>,
    /// in \[0, 1\]
    pub weight: f64,
}

/// The push acting at some instant ([`Human::push_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActivePush<'s> {
    /// index of the keyframe that starts it
    pub keyframe: usize,
    /// the push as the keyframe scripts it
    pub push: &'s Push,
    /// ramp factor in \[0, 1\]: 0 → 1 over [`Push::RAMP_S`] after the
    /// keyframe, 1 → 0 over the same time before the interval's end
    pub ramp: f64,
}

/// Interpolated pose inputs at one instant.
struct Interpolated {
    base: [f64; 3],
    /// the upper body's forward lean \[rad\]
    lean: f64,
    hands: [Option<Vector3<f64>>; 2],
    feet: [Option<Vector3<f64>>; 2],
}

/// A runnable human: the script plus the capsule buffer [`Human::pose_at`]
/// fills (allocated once in [`Human::new`]).
#[derive(Clone, Debug)]
pub struct Human {
    script: HumanScript,
    capsules: Vec<HumanCapsule>,
}

impl Human {
    /// A human following `script`, posed at time 0.
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

    /// The script it follows.
    pub fn script(&self) -> &HumanScript {
        &self.script
    }

    /// The capsules of the last [`Human::pose_at`], in [`BodyPart::ALL`] order.
    pub fn capsules(&self) -> &[HumanCapsule] {
        &self.capsules
    }

    /// Floor position \[m\] and heading \[rad\] `[x, y, yaw]` at time `t` \[s\], base frame.
    pub fn base_at(&self, t: f64) -> [f64; 3] {
        self.interpolate(self.script.script_time(t)).base
    }

    /// The push acting at time `t` \[s\], if any, with its ramp factor.
    pub fn push_at(&self, t: f64) -> Option<ActivePush<'_>> {
        let ts = self.script.script_time(t);
        let (i, start, end) = self.script.interval_at(ts)?;
        let push = self.script.keyframes()[i].push.as_ref()?;
        let ramp = ramp(ts, start, end, Push::RAMP_S);
        (ramp > 0.0).then_some(ActivePush {
            keyframe: i,
            push,
            ramp,
        })
    }

    /// Pose the body at time `t` \[s\] and return its capsules (base frame, in
    /// [`BodyPart::ALL`] order). Allocates nothing.
    pub fn pose_at(&mut self, t: f64) -> &[HumanCapsule] {
        self.pose_reaching(t, None)
    }

    /// [`Human::pose_at`] with one hand placed by the caller (`reach`): the
    /// simulator puts a pushing hand on the robot link. Allocates nothing.
    pub fn pose_reaching(&mut self, t: f64, reach: Option<Reach>) -> &[HumanCapsule] {
        use body::*;
        let t = self.script.script_time(t);
        let ip = self.interpolate(t);
        let fl = Frame::new(ip.base, self.script.floor_z()).leaning(ip.lean);
        // the wave acting now, with its blend factor and time since it started
        let wave = self.script.interval_at(t).and_then(|(i, start, end)| {
            let w = self.script.keyframes()[i].wave?;
            let blend = ramp(t, start, end, WAVE_BLEND_S);
            (blend > 0.0).then_some((w, blend, t - start))
        });
        let capsules = &mut self.capsules;
        let mut set = |part: BodyPart, a: Vector3<f64>, b: Vector3<f64>, radius: f64| {
            // ALL lists the parts in declaration order, so the discriminant is the index
            capsules[part as usize] = HumanCapsule { part, a, b, radius };
        };
        set(
            BodyPart::Head,
            fl.upper(0.0, 0.0, HEAD[0]),
            fl.upper(0.0, 0.0, HEAD[1]),
            R_HEAD,
        );
        set(
            BodyPart::Torso,
            fl.upper(0.0, 0.0, TORSO[0]),
            fl.upper(0.0, 0.0, TORSO[1]),
            R_TORSO,
        );
        set(
            BodyPart::Pelvis,
            fl.point(0.0, -PELVIS_Y, PELVIS_Z),
            fl.point(0.0, PELVIS_Y, PELVIS_Z),
            R_PELVIS,
        );
        for (hand, target, parts) in [
            (
                Hand::Left,
                ip.hands[1],
                [
                    BodyPart::UpperArmLeft,
                    BodyPart::ForearmLeft,
                    BodyPart::HandLeft,
                ],
            ),
            (
                Hand::Right,
                ip.hands[0],
                [
                    BodyPart::UpperArmRight,
                    BodyPart::ForearmRight,
                    BodyPart::HandRight,
                ],
            ),
        ] {
            let side = side_of(hand);
            let target = match reach {
                Some(r) if r.hand == hand => {
                    let from = target.unwrap_or_else(|| hang_point(&fl, side));
                    let w = r.weight.clamp(0.0, 1.0);
                    Some(from + (r.point - from) * w)
                }
                _ => target,
            };
            let (shoulder, mut elbow, mut centre) = arm_joints(&fl, side, target);
            if let Some((w, blend, tau)) = wave.filter(|(w, _, _)| w.hand == hand) {
                let (we, wh) = wave_joints(&fl, side, shoulder, &w, tau);
                // rotate the upper arm and the forearm from the scripted pose
                // to the wave's (lengths kept); the forearm turns up through
                // the horizontal, forwards and outwards, as one raises a hand
                let upper = slerp(
                    (elbow - shoulder) / UPPER_ARM,
                    (we - shoulder) / UPPER_ARM,
                    blend,
                );
                let (fa, fb) = ((centre - elbow) / FOREARM, (wh - we) / FOREARM);
                let mid = (fl.fwd * 0.3 + fl.left * side).normalize();
                let fore = if blend < 0.5 {
                    slerp(fa, mid, 2.0 * blend)
                } else {
                    slerp(mid, fb, 2.0 * blend - 1.0)
                };
                elbow = shoulder + upper * UPPER_ARM;
                centre = elbow + fore * FOREARM;
            }
            for ((a, b), (part, r)) in arm_segments(shoulder, elbow, centre)
                .into_iter()
                .zip(parts.into_iter().zip([R_UPPER_ARM, R_FOREARM, R_HAND]))
            {
                set(part, a, b, r);
            }
        }
        for (side, target, thigh, shin) in [
            (1.0, ip.feet[1], BodyPart::ThighLeft, BodyPart::ShinLeft),
            (-1.0, ip.feet[0], BodyPart::ThighRight, BodyPart::ShinRight),
        ] {
            let y = side * LEG_Y;
            let hip = fl.point(0.0, y, HIP_Z);
            let (knee, ankle) = match target {
                None => (fl.point(0.0, y, KNEE_Z), fl.point(0.0, y, ANKLE_Z)),
                // the knee bends forwards (or, along the forward axis, up)
                Some(target) => two_link(
                    hip,
                    target,
                    HIP_Z - KNEE_Z,
                    KNEE_Z - ANKLE_Z,
                    fl.fwd,
                    Vector3::z(),
                ),
            };
            set(thigh, hip, knee, R_THIGH);
            set(shin, knee, ankle, R_SHIN);
        }
        &self.capsules
    }

    /// Interpolated `[x, y, yaw]`, hand targets `[right, left]` and foot
    /// targets `[right, left]` at script time `t` (clamped to the script).
    fn interpolate(&self, t: f64) -> Interpolated {
        let ks = self.script.keyframes();
        let floor_z = self.script.floor_z();
        let v3 = |h: [f64; 3]| Vector3::new(h[0], h[1], h[2]);
        let first = &ks[0];
        let last = &ks[ks.len() - 1];
        let single = |k: &Keyframe| Interpolated {
            base: k.base,
            lean: k.lean.unwrap_or(0.0),
            hands: [k.right_hand.map(v3), k.left_hand.map(v3)],
            feet: [k.right_foot.map(v3), k.left_foot.map(v3)],
        };
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
        // a missing target stands for the rest position (hanging hand,
        // standing foot) at that keyframe, so the blend is continuous; two
        // missing targets rest on the blended body
        let lean = |k: &Keyframe| k.lean.unwrap_or(0.0);
        let (f0, f1) = (
            Frame::new(k0.base, floor_z).leaning(lean(k0)),
            Frame::new(k1.base, floor_z).leaning(lean(k1)),
        );
        let blend = |h0: Option<[f64; 3]>,
                     h1: Option<[f64; 3]>,
                     rest: fn(&Frame, f64) -> Vector3<f64>,
                     side: f64|
         -> Option<Vector3<f64>> {
            if h0.is_none() && h1.is_none() {
                return None;
            }
            let p0 = h0.map(v3).unwrap_or_else(|| rest(&f0, side));
            let p1 = h1.map(v3).unwrap_or_else(|| rest(&f1, side));
            Some(p0 + (p1 - p0) * s)
        };
        Interpolated {
            base,
            lean: lerp(lean(k0), lean(k1)),
            hands: [
                blend(k0.right_hand, k1.right_hand, hang_point, -1.0),
                blend(k0.left_hand, k1.left_hand, hang_point, 1.0),
            ],
            feet: [
                blend(k0.right_foot, k1.right_foot, stand_point, -1.0),
                blend(k0.left_foot, k1.left_foot, stand_point, 1.0),
            ],
        }
    }
}

/// Rotation of unit vector `a` towards unit vector `b` by the fraction `s`
/// of the angle between them (about any perpendicular axis when they are
/// opposite). A unit vector.
fn slerp(a: Vector3<f64>, b: Vector3<f64>, s: f64) -> Vector3<f64> {
    let angle = a.dot(&b).clamp(-1.0, 1.0).acos();
    let sin = angle.sin();
    if sin > 1e-6 {
        return (a * ((1.0 - s) * angle).sin() + b * (s * angle).sin()) / sin;
    }
    if angle < 1.0 {
        return (a + (b - a) * s).normalize();
    }
    // opposite: through a perpendicular
    let p = a.cross(&Vector3::x());
    let p = if p.norm() > 0.1 {
        p
    } else {
        a.cross(&Vector3::y())
    }
    .normalize();
    a * (s * angle).cos() + p * (s * angle).sin()
}

/// Trapezoid in time: 0 at `start`, 1 after `ramp_s`, back to 0 at `end`
/// (linear ramps; a short interval peaks below 1). 0 outside `[start, end]`.
fn ramp(t: f64, start: f64, end: f64, ramp_s: f64) -> f64 {
    ((t - start) / ramp_s)
        .min((end - t) / ramp_s)
        .clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn script(ks: Vec<Keyframe>) -> HumanScript {
        HumanScript::new(-0.8, ks).expect("valid script")
    }

    /// `lean` bows the torso, the head and the shoulders about the hips'
    /// axis; the pelvis and the legs stay, the hanging hands hang from the
    /// bowed shoulders, and a script without the key is the upright body.
    #[test]
    fn a_lean_bows_the_upper_body_about_the_hips_and_leaves_the_legs() {
        use body::*;
        let upright = Keyframe {
            t: 0.0,
            base: [1.0, 0.0, std::f64::consts::PI],
            ..Keyframe::default()
        };
        let bowed = Keyframe {
            t: 1.0,
            lean: Some(0.9),
            ..upright.clone()
        };
        let mut h = Human::new(script(vec![upright.clone(), bowed]));
        let stand = h.pose_at(0.0).to_vec();
        let half = h.pose_at(0.5).to_vec();
        let bow = h.pose_at(1.0).to_vec();
        let mut plain = Human::new(script(vec![upright]));
        assert_eq!(plain.pose_at(0.0), &stand[..]);
        let of = |caps: &[HumanCapsule], p: BodyPart| caps[p as usize];
        // facing -x (yaw π): the head's top moves towards the robot by
        // h sin(lean) and down by h (1 - cos(lean)), h its height above the hips
        let h_top = HEAD[1] - PELVIS_Z;
        for (caps, lean) in [(&half, 0.45f64), (&bow, 0.9)] {
            let (top0, top) = (of(&stand, BodyPart::Head).b, of(caps, BodyPart::Head).b);
            assert!((top0.x - top.x - h_top * lean.sin()).abs() < 1e-9, "{lean}");
            assert!((top0.z - top.z - h_top * (1.0 - lean.cos())).abs() < 1e-9);
            assert!((top.y - top0.y).abs() < 1e-12);
        }
        for p in [
            BodyPart::Pelvis,
            BodyPart::ThighLeft,
            BodyPart::ShinLeft,
            BodyPart::ThighRight,
            BodyPart::ShinRight,
        ] {
            assert_eq!(of(&stand, p), of(&bow, p), "{p:?}");
        }
        // the bowed torso keeps its length; the hands hang below the shoulders
        let len = |c: HumanCapsule| (c.b - c.a).norm();
        let torso = of(&bow, BodyPart::Torso);
        assert!((len(torso) - (TORSO[1] - TORSO[0])).abs() < 1e-9);
        let shoulder = of(&bow, BodyPart::UpperArmRight).a;
        let hand = of(&bow, BodyPart::HandRight).b;
        assert!(shoulder.z - hand.z > 0.5, "{shoulder} {hand}");
        assert!(shoulder.x < of(&stand, BodyPart::UpperArmRight).a.x - 0.3);
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
            ..Keyframe::default()
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
            ..Keyframe::default()
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
