//! The scripted person of a scenario, as data: keyframes in time, checked.
//! The simulator turns it into capsules (`phri-sim`'s `Human`).
//!
//! Between two keyframes the body moves linearly from one pose to the next
//! (base, hand and foot targets). A keyframe can also start an action that
//! lasts until the next keyframe (or, on the last keyframe, until the script
//! ends or starts over): a [`Wave`] of one hand or a [`Push`] on a robot link.

use phri_ipc::BodyPart;

/// One of the person's hands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hand {
    /// the right hand
    Right,
    /// the left hand
    Left,
}

impl Hand {
    /// The hand's body part ([`BodyPart::HandRight`] or [`BodyPart::HandLeft`]).
    pub fn part(self) -> BodyPart {
        match self {
            Hand::Right => BodyPart::HandRight,
            Hand::Left => BodyPart::HandLeft,
        }
    }

    /// The name in scenario files: `right` or `left`.
    pub fn name(self) -> &'static str {
        match self {
            Hand::Right => "right",
            Hand::Left => "left",
        }
    }
}

/// A waving hand, from its keyframe until the next: the hand is raised above
/// its elbow (forearm about vertical, elbow a little below shoulder height,
/// out to the side) and swings along the person's left–right axis,
/// `amplitude_m · sin(2π · frequency_hz · (t − t_keyframe))` about the elbow.
/// The wave blends in and out over 0.5 s at the ends of its interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    /// the waving hand
    pub hand: Hand,
    /// \[Hz\], in (0, [`Wave::MAX_FREQUENCY_HZ`]]
    pub frequency_hz: f64,
    /// peak lateral excursion of the hand \[m\], in (0, [`Wave::MAX_AMPLITUDE_M`]]
    pub amplitude_m: f64,
}

impl Wave {
    /// Highest wave frequency a script may ask for \[Hz\].
    pub const MAX_FREQUENCY_HZ: f64 = 5.0;
    /// Largest wave amplitude a script may ask for \[m\].
    pub const MAX_AMPLITUDE_M: f64 = 0.5;
}

/// A hand pushing a robot link, from its keyframe until the next: the
/// simulator applies a force of `force_n` at `point` (fixed in `link`'s
/// frame), horizontal, along the direction from the person's base position
/// (floor x, y) to the point, ramped up over [`Push::RAMP_S`] after the
/// keyframe and down over the same time before the next. The `hand` is
/// placed on the link at the point and the force is a ground-truth contact of
/// that hand with that link.
#[derive(Clone, Debug, PartialEq)]
pub struct Push {
    /// robot link name (checked against the robot model by the simulator),
    /// or a role: [`Push::WRIST`], [`Push::FLANGE`]
    pub link: String,
    /// point of application \[m\], in the link's frame (|point| ≤ [`Push::MAX_POINT_M`])
    pub point: [f64; 3],
    /// force magnitude once ramped up \[N\], in (0, [`Push::MAX_FORCE_N`]]
    pub force_n: f64,
    /// the pushing hand
    pub hand: Hand,
    /// the contact is intended (collaboration) rather than a collision
    pub intended: bool,
}

impl Push {
    /// The link given by role: the arm's wrist (`collaboration.wrist_link`).
    pub const WRIST: &'static str = "wrist";
    /// The link given by role: the arm's end-effector link (`control.ee_link`).
    pub const FLANGE: &'static str = "flange";

    /// Ramp time \[s\] of the force, at the start and the end of the push.
    pub const RAMP_S: f64 = 0.2;
    /// Largest push force a script may ask for \[N\].
    pub const MAX_FORCE_N: f64 = 500.0;
    /// Farthest a push's point may be from its link's frame origin \[m\].
    pub const MAX_POINT_M: f64 = 1.0;
}

/// The human's pose at one instant of the script, and the action it starts.
/// `Keyframe { t, base, ..Keyframe::default() }` is a person standing with
/// arms hanging.
#[derive(Clone, Debug, Default, PartialEq)]
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
    /// right-foot (ankle) target \[m\], robot base frame; `None`: the leg
    /// stands straight under the hip
    pub right_foot: Option<[f64; 3]>,
    /// left-foot (ankle) target \[m\], robot base frame; `None`: standing
    pub left_foot: Option<[f64; 3]>,
    /// forward lean of the upper body (torso, head, shoulders) about the
    /// hips \[rad\]: 0 upright, positive bowing forward (at most
    /// [`HumanScript::MAX_LEAN_RAD`]), negative leaning back; `None`: upright
    pub lean: Option<f64>,
    /// a hand waves from this keyframe until the next
    pub wave: Option<Wave>,
    /// a hand pushes a robot link from this keyframe until the next
    pub push: Option<Push>,
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
    /// the floor height \[m\] is not a finite number
    #[error("floor_z: {0} is not a finite number")]
    FloorZ(f64),
    /// the script has no keyframe
    #[error("keyframe: a human needs at least one keyframe")]
    NoKeyframe,
    /// the script has more than [`HumanScript::MAX_KEYFRAMES`] keyframes
    #[error("keyframe: {count} keyframes, more than the {max} a script may have")]
    TooMany {
        /// the keyframes given
        count: usize,
        /// the most a script may have
        max: usize,
    },
    /// a number of a keyframe is not finite
    #[error("keyframe[{index}].{field}: not a finite number")]
    NotFinite {
        /// the keyframe's position
        index: usize,
        /// its key (`t`, `base`, `right_hand`, …)
        field: &'static str,
    },
    /// a keyframe's time is not after the previous keyframe's
    #[error("keyframe[{index}].t: {t} s is not after the previous keyframe's {previous} s (keyframes must be sorted by strictly increasing t)")]
    Unsorted {
        /// the keyframe's position
        index: usize,
        /// its time \[s\]
        t: f64,
        /// the previous keyframe's time \[s\]
        previous: f64,
    },
    /// the loop period is not finite and positive, or before the last
    /// keyframe
    #[error("repeat_s: {repeat_s} s must be finite and at least the last keyframe's time {last} s (and > 0)")]
    Repeat {
        /// the loop period asked for \[s\]
        repeat_s: f64,
        /// the last keyframe's time \[s\]
        last: f64,
    },
    /// a wave or push value out of range; `field` is the key below the
    /// keyframe, such as `wave.frequency_hz` or `push.force_n`
    #[error("keyframe[{index}].{field}: {reason}")]
    Invalid {
        /// the keyframe's position
        index: usize,
        /// the key below the keyframe
        field: &'static str,
        /// why the value is refused
        reason: String,
    },
}

impl HumanScript {
    /// Default floor height \[m\]: the robot stands on a 0.8 m table.
    pub const DEFAULT_FLOOR_Z: f64 = -0.8;

    /// The most a person bows forward \[rad\] (the torso horizontal).
    pub const MAX_LEAN_RAD: f64 = std::f64::consts::FRAC_PI_2;

    /// The most a person leans back \[rad\].
    pub const MAX_BACK_LEAN_RAD: f64 = 0.5;

    /// Most keyframes a script may have (the deployed ones have at most 15;
    /// the simulator searches them every period).
    pub const MAX_KEYFRAMES: usize = 10_000;

    /// Check and keep a script. `floor_z` \[m\] is the height of the human's
    /// soles in the robot base frame.
    pub fn new(floor_z: f64, keyframes: Vec<Keyframe>) -> Result<HumanScript, ScriptError> {
        if !floor_z.is_finite() {
            return Err(ScriptError::FloorZ(floor_z));
        }
        if keyframes.is_empty() {
            return Err(ScriptError::NoKeyframe);
        }
        if keyframes.len() > Self::MAX_KEYFRAMES {
            return Err(ScriptError::TooMany {
                count: keyframes.len(),
                max: Self::MAX_KEYFRAMES,
            });
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
            if k.right_foot.is_some_and(|h| !fin(&h)) {
                return Err(ScriptError::NotFinite {
                    index,
                    field: "right_foot",
                });
            }
            if k.left_foot.is_some_and(|h| !fin(&h)) {
                return Err(ScriptError::NotFinite {
                    index,
                    field: "left_foot",
                });
            }
            if let Some(lean) = k.lean {
                if !(-Self::MAX_BACK_LEAN_RAD..=Self::MAX_LEAN_RAD).contains(&lean) {
                    return Err(ScriptError::Invalid {
                        index,
                        field: "lean",
                        reason: format!(
                            "{lean} rad is not in [-{}, {}] rad",
                            Self::MAX_BACK_LEAN_RAD,
                            Self::MAX_LEAN_RAD
                        ),
                    });
                }
            }
            check_actions(index, k)?;
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

    /// The pushes' links given by role, named: [`Push::WRIST`] becomes
    /// `wrist` (the arm's `collaboration.wrist_link`), [`Push::FLANGE`]
    /// `flange` (its `control.ee_link`), so one scenario fits every arm.
    pub fn name_link_roles(&mut self, wrist: &str, flange: &str) {
        for p in self.keyframes.iter_mut().filter_map(|k| k.push.as_mut()) {
            match p.link.as_str() {
                Push::WRIST => p.link = wrist.to_string(),
                Push::FLANGE => p.link = flange.to_string(),
                _ => {}
            }
        }
    }

    /// Time of the last keyframe \[s\]: the human stands still afterwards.
    pub fn end_time(&self) -> f64 {
        self.keyframes.last().map_or(0.0, |k| k.t)
    }

    /// Script time \[s\] at scenario time `t` \[s\]: `t` itself, or within
    /// the loop period of a repeating script.
    pub fn script_time(&self, t: f64) -> f64 {
        match self.repeat_s {
            Some(period) if t > 0.0 => t.rem_euclid(period),
            _ => t,
        }
    }

    /// The keyframe whose interval holds script time `t` \[s\] (its index,
    /// the interval's start and end \[s\]): from the keyframe's time until the
    /// next keyframe's, for the last keyframe until the loop period of a
    /// repeating script or forever. `None` before the first keyframe (or for NaN).
    pub fn interval_at(&self, t: f64) -> Option<(usize, f64, f64)> {
        let ks = &self.keyframes;
        if !(t >= ks.first()?.t) {
            return None;
        }
        // ks is sorted and t is at or after the first: the last keyframe at or before t
        let i = ks.partition_point(|k| k.t <= t).max(1) - 1;
        let end = match ks.get(i + 1) {
            Some(next) => next.t,
            None => self.repeat_s.unwrap_or(f64::INFINITY),
        };
        Some((i, ks[i].t, end))
    }
}

/// The keyframe's wave and push in range, and not both with the same hand.
fn check_actions(index: usize, k: &Keyframe) -> Result<(), ScriptError> {
    let invalid = |field: &'static str, reason: String| ScriptError::Invalid {
        index,
        field,
        reason,
    };
    if let Some(w) = &k.wave {
        if !(w.frequency_hz.is_finite()
            && w.frequency_hz > 0.0
            && w.frequency_hz <= Wave::MAX_FREQUENCY_HZ)
        {
            return Err(invalid(
                "wave.frequency_hz",
                format!(
                    "{} Hz is not in (0, {}]",
                    w.frequency_hz,
                    Wave::MAX_FREQUENCY_HZ
                ),
            ));
        }
        if !(w.amplitude_m.is_finite()
            && w.amplitude_m > 0.0
            && w.amplitude_m <= Wave::MAX_AMPLITUDE_M)
        {
            return Err(invalid(
                "wave.amplitude_m",
                format!(
                    "{} m is not in (0, {}]",
                    w.amplitude_m,
                    Wave::MAX_AMPLITUDE_M
                ),
            ));
        }
    }
    if let Some(p) = &k.push {
        if p.link.trim().is_empty() {
            return Err(invalid("push.link", "a robot link name is needed".into()));
        }
        if !p.point.iter().all(|x| x.is_finite()) {
            return Err(invalid("push.point", "not a finite number".into()));
        }
        let norm = p.point.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > Push::MAX_POINT_M {
            return Err(invalid(
                "push.point",
                format!(
                    "{norm} m from the link's origin: more than {} m",
                    Push::MAX_POINT_M
                ),
            ));
        }
        if !(p.force_n.is_finite() && p.force_n > 0.0 && p.force_n <= Push::MAX_FORCE_N) {
            return Err(invalid(
                "push.force_n",
                format!("{} N is not in (0, {}]", p.force_n, Push::MAX_FORCE_N),
            ));
        }
        if k.wave.as_ref().is_some_and(|w| w.hand == p.hand) {
            return Err(invalid(
                "push.part",
                format!(
                    "the {} hand cannot push while it waves (wave.hand)",
                    p.hand.name()
                ),
            ));
        }
    }
    Ok(())
}
