//! `[skeleton]`, `[gesture]` and `[collaboration]`: the body tracker the
//! simulated camera stands in for, the waving detector, and the controller's
//! collaboration phases (paper Sect. VI).

use serde::{Deserialize, Serialize};

use crate::check::{non_negative, positive, within};
use crate::error::Invalid;

/// `[skeleton]`: the simulated body tracker (a Kinect/NiTE-class stand-in).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkeletonConfig {
    /// publish `perception/skeleton` with every frame of the simulated camera
    pub enabled: bool,
    /// where the skeletons come from: `sim`, the simulated camera's stand-in
    /// tracker from the simulation's truth (the settings below); `depth`,
    /// phri's own tracker (`phri-tracker`) on the depth frames. A camera
    /// whose source is not `sim` always uses `depth`.
    #[serde(default)]
    pub source: SkeletonSource,
    /// which way the depth tracker takes a person to face, for their own
    /// left and right (depth alone cannot tell front from back): `robot`,
    /// toward the robot's base (a person working with the arm faces it);
    /// `camera`, toward the camera
    #[serde(default)]
    pub facing: Facing,
    /// the depth tracker's settings (`[skeleton.tracker]`, defaults in
    /// `phri_people::TrackerConfig`)
    #[serde(default)]
    pub tracker: phri_people::TrackerConfig,
    /// standard deviation of the joint position jitter \[m\], per axis, white from frame to frame
    pub noise_m: f64,
    /// standard deviation of each joint's slowly drifting offset \[m\], per
    /// axis (a tracker's bias), and how fast it drifts: its correlation time \[s\]
    pub bias_m: f64,
    /// the drifting offset's correlation time \[s\]
    pub bias_time_s: f64,
    /// frames of latency: a frame's skeleton is computed from the world this many frames earlier
    pub latency_frames: u32,
    /// probability that a frame loses the person altogether (tracking dropout)
    pub dropout: f64,
    /// a joint whose pixel shows something this much nearer than the joint
    /// is occluded: its confidence falls to 0 \[m\]
    pub occlusion_margin_m: f64,
    /// confidence of a visible joint
    pub visible_confidence: f64,
    /// seed of the noise and dropouts
    pub seed: u64,
}

/// Where a camera's skeletons come from (`[skeleton] source`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SkeletonSource {
    /// the simulated camera's stand-in tracker, from the simulation's truth
    #[default]
    Sim,
    /// phri's own tracker on the depth frames (`phri-tracker`)
    Depth,
}

/// Which way a person seen in depth faces (`[skeleton] facing`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Facing {
    /// toward the robot's base
    #[default]
    Robot,
    /// toward the camera
    Camera,
}

impl SkeletonSource {
    /// The name the configuration gives it.
    pub fn name(self) -> &'static str {
        match self {
            SkeletonSource::Sim => "sim",
            SkeletonSource::Depth => "depth",
        }
    }
}

impl SkeletonConfig {
    /// Range checks of every field, the depth tracker's included.
    pub fn validate(&self) -> Result<(), Invalid> {
        const S: &str = "skeleton";
        self.tracker
            .validate()
            .map_err(|e| Invalid::new("skeleton.tracker", e.to_string()))?;
        within(S, "noise_m", self.noise_m, 0.0, 0.5)?;
        within(S, "bias_m", self.bias_m, 0.0, 0.5)?;
        positive(S, "bias_time_s", self.bias_time_s)?;
        if self.latency_frames > 30 {
            return Err(Invalid::new("skeleton.latency_frames", "at most 30"));
        }
        within(S, "dropout", self.dropout, 0.0, 1.0)?;
        non_negative(S, "occlusion_margin_m", self.occlusion_margin_m)?;
        within(S, "visible_confidence", self.visible_confidence, 0.0, 1.0)?;
        Ok(())
    }
}

/// `[gesture]`: the waving detector (`phri-gesture`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GestureConfig {
    /// lateral reversals of the hand relative to the elbow that make a wave
    pub reversals: u32,
    /// within this time \[s\]
    pub window_s: f64,
    /// consecutive reversals are this far apart at least and at most \[s\]
    /// (half periods of a 0.7-5 Hz wave): faster is tracker noise, slower
    /// is a reach and its return
    pub min_half_period_s: f64,
    /// the most time between consecutive reversals \[s\] (above
    /// `min_half_period_s`)
    pub max_half_period_s: f64,
    /// a swing between reversals moves the hand at least this far sideways \[m\]
    pub min_swing_m: f64,
    /// the hand stays at least this far above the elbow while waving \[m\]
    pub hand_above_elbow_m: f64,
    /// the hand and elbow are tracked at least this confidently
    pub min_confidence: f64,
    /// after a wave, the same person's next wave counts only after this \[s\]
    pub refractory_s: f64,
    /// a frame older than this is not used \[ms\]
    pub max_age_ms: f64,
}

impl GestureConfig {
    /// Range checks of every field; `min_half_period_s` below
    /// `max_half_period_s`.
    pub fn validate(&self) -> Result<(), Invalid> {
        const S: &str = "gesture";
        if !(2..=20).contains(&self.reversals) {
            return Err(Invalid::new(
                "gesture.reversals",
                format!("{} is not in 2..=20", self.reversals),
            ));
        }
        positive(S, "window_s", self.window_s)?;
        positive(S, "min_half_period_s", self.min_half_period_s)?;
        positive(S, "max_half_period_s", self.max_half_period_s)?;
        if self.min_half_period_s >= self.max_half_period_s {
            return Err(Invalid::new(
                "gesture.min_half_period_s",
                "must be below max_half_period_s",
            ));
        }
        positive(S, "min_swing_m", self.min_swing_m)?;
        non_negative(S, "hand_above_elbow_m", self.hand_above_elbow_m)?;
        within(S, "min_confidence", self.min_confidence, 0.0, 1.0)?;
        non_negative(S, "refractory_s", self.refractory_s)?;
        positive(S, "max_age_ms", self.max_age_ms)?;
        Ok(())
    }
}

/// What a collaboration request does to the task in progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnRequest {
    /// the approach starts at once
    Abort,
    /// the current segment is completed first
    Complete,
}

/// `[collaboration]`: the controller's collaboration phases.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollaborationConfig {
    /// accept collaboration requests at all
    pub enabled: bool,
    /// what a request does to the task segment in progress
    pub on_request: OnRequest,
    /// a request is accepted only when the named hand is tracked at least this confidently
    pub min_hand_confidence: f64,
    /// the collaborative robot part: the link that may touch the hand
    pub robot_link: String,
    /// a point of that link where the hand is met \[m\], link frame
    pub robot_point: [f64; 3],
    /// radius of the robot part around that point \[m\]
    pub robot_radius_m: f64,
    /// the robot part is a capsule: the segment `robot_point ± this` along
    /// the link frame's z axis, swept by `robot_radius_m` \[m\]
    pub robot_half_length_m: f64,
    /// radius of the hand around the tracked hand joint \[m\]
    pub hand_radius_m: f64,
    /// the link whose frame origin is the wrist centre (a wrist push acts there)
    pub wrist_link: String,
    /// approach: largest end-effector speed far from the hand [m/s]
    pub approach_speed: f64,
    /// approach: speed at contact [m/s] (ISO/TS 15066's hand figures allow far more; this is gentle)
    pub contact_speed: f64,
    /// approach: the speed falls from `approach_speed` to `contact_speed` over this distance \[m\]
    pub slow_down_m: f64,
    /// low-pass of the hand position the approach follows \[s\]
    pub hand_filter_s: f64,
    /// the approach aims this far into the modelled hand \[m\]: the hand seen
    /// in depth is off by centimetres, so the robot part goes on (at
    /// `contact_speed`) until it touches, as the estimated force tells
    pub reach_into_m: f64,
    /// a surface gap to the hand below this (negative: the modelled surfaces
    /// overlap), or an estimated force above `contact_force_n` near the hand,
    /// is contact \[m\]; at least `−reach_into_m`
    pub contact_gap_m: f64,
    /// an estimated force near the hand above this is contact \[N\]
    pub contact_force_n: f64,
    /// contact: admittance on the estimated force, end-effector velocity per newton [m/(N s)]
    pub admittance: f64,
    /// contact: at the touch the reference leads the end effector by at most
    /// this \[m\] (the approach's lead, cut back; the admittance builds the
    /// force from there)
    pub touch_lead_m: f64,
    /// contact: the end effector keeps pressing the hand with this force \[N\]
    /// (the admittance's reference: it yields to more, closes in on less)
    pub contact_hold_n: f64,
    /// contact → follow once the hand is this far from the robot's surface
    /// (the robot part's or the wrist's, whichever is nearer) \[m\] ...
    pub follow_gap_m: f64,
    /// ... and the estimated force below this \[N\] (at most `contact_force_n`) ...
    pub release_force_n: f64,
    /// ... both for this long without a break \[s\]
    pub release_s: f64,
    /// a restarted controller holds (protective stop) while a tracked hand
    /// is within this of the robot part's or the wrist's surface \[m\], until
    /// every hand is farther for `release_s`
    pub restart_clear_m: f64,
    /// the collaboration ends when the hand has not been seen for this long \[s\]
    pub hand_lost_s: f64,
    /// the approach stops and backs off when an estimated force passes this
    /// fraction of the touched body region's ISO/TS 15066 quasi-static limit
    pub force_limit_fraction: f64,
    /// quasi-static limits \[N\] (ISO/TS 15066 as transcribed publicly; check a licensed copy)
    pub iso_hand_n: f64,
    /// quasi-static limit of the lower arms and wrists \[N\]
    pub iso_lower_arm_n: f64,
    /// backing off after a force limit: this far along the force \[m\]
    pub back_off_m: f64,
    /// wrist push: the residual of joints 5-7 at most this fraction of joints 1-4's
    pub wrist_ratio: f64,
    /// wrist push: a force at the wrist centre must explain the residual but
    /// this fraction of its norm (a push on links 1-4 off the line from the
    /// shoulder to the wrist turns the elbow about it, which no force at the
    /// wrist does)
    pub wrist_fit: f64,
    /// wrist push: joints 1-4's residual at least this \[Nm\] ...
    pub wrist_min_nm: f64,
    /// ... for this long \[s\]
    pub wrist_hold_s: f64,
    /// wrist push: confirmed by a human part seen within this of the wrist \[m\]
    pub wrist_confirm_m: f64,
    /// full detection is re-armed only after the residual stayed below the
    /// contact level for this long after the collaboration \[s\]
    pub rearm_quiet_s: f64,
    /// depth masking around the collaborative hand: a sphere of this radius \[m\] ...
    pub mask_radius_m: f64,
    /// ... and a capsule of this length from the hand toward the elbow \[m\]
    pub mask_forearm_m: f64,
    /// the hand refined from depth: pixels within this of the tracked hand \[m\]
    pub refine_radius_m: f64,
}

impl CollaborationConfig {
    /// Range checks of every field, and of the pairs that must agree
    /// (`contact_speed` ≤ `approach_speed`, `release_force_n` ≤
    /// `contact_force_n`, `contact_gap_m` ≥ −`reach_into_m`).
    pub fn validate(&self) -> Result<(), Invalid> {
        const S: &str = "collaboration";
        within(S, "min_hand_confidence", self.min_hand_confidence, 0.0, 1.0)?;
        if self.robot_link.is_empty() {
            return Err(Invalid::new("collaboration.robot_link", "must name a link"));
        }
        if self.wrist_link.is_empty() {
            return Err(Invalid::new("collaboration.wrist_link", "must name a link"));
        }
        crate::check::finite(S, "robot_point", &self.robot_point)?;
        for (name, v) in [
            ("robot_radius_m", self.robot_radius_m),
            ("robot_half_length_m", self.robot_half_length_m),
            ("hand_radius_m", self.hand_radius_m),
            ("reach_into_m", self.reach_into_m),
            ("contact_hold_n", self.contact_hold_n),
            ("touch_lead_m", self.touch_lead_m),
            ("back_off_m", self.back_off_m),
            ("mask_forearm_m", self.mask_forearm_m),
            ("rearm_quiet_s", self.rearm_quiet_s),
        ] {
            non_negative(S, name, v)?;
        }
        for (name, v) in [
            ("approach_speed", self.approach_speed),
            ("contact_speed", self.contact_speed),
            ("slow_down_m", self.slow_down_m),
            ("hand_filter_s", self.hand_filter_s),
            ("contact_force_n", self.contact_force_n),
            ("admittance", self.admittance),
            ("follow_gap_m", self.follow_gap_m),
            ("release_force_n", self.release_force_n),
            ("release_s", self.release_s),
            ("restart_clear_m", self.restart_clear_m),
            ("hand_lost_s", self.hand_lost_s),
            ("iso_hand_n", self.iso_hand_n),
            ("iso_lower_arm_n", self.iso_lower_arm_n),
            ("wrist_min_nm", self.wrist_min_nm),
            ("wrist_hold_s", self.wrist_hold_s),
            ("wrist_confirm_m", self.wrist_confirm_m),
            ("mask_radius_m", self.mask_radius_m),
            ("refine_radius_m", self.refine_radius_m),
        ] {
            positive(S, name, v)?;
        }
        crate::check::finite(S, "contact_gap_m", &[self.contact_gap_m])?;
        if self.contact_gap_m < -self.reach_into_m {
            return Err(Invalid::new(
                "collaboration.contact_gap_m",
                "must be at least −reach_into_m (the approach stops there)",
            ));
        }
        if self.contact_speed > self.approach_speed {
            return Err(Invalid::new(
                "collaboration.contact_speed",
                "must not exceed approach_speed",
            ));
        }
        if self.release_force_n > self.contact_force_n {
            return Err(Invalid::new(
                "collaboration.release_force_n",
                "must not exceed contact_force_n (the contact would never hold)",
            ));
        }
        within(
            S,
            "force_limit_fraction",
            self.force_limit_fraction,
            0.0,
            1.0,
        )?;
        within(S, "wrist_ratio", self.wrist_ratio, 0.0, 1.0)?;
        within(S, "wrist_fit", self.wrist_fit, 0.0, 1.0)?;
        Ok(())
    }
}
