//! The scripted person of a scenario, as data: keyframes in time, checked.
//! The simulator turns it into capsules (`phri-sim`'s `Human`).

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
