//! `[avoidance]`: which law turns perception into the arm's evasion: the
//! paper's (eqs. 16-20 with SNS) or a control-barrier safety filter.

use serde::{Deserialize, Serialize};

use crate::check::{non_negative, positive};
use crate::error::Invalid;

const S: &str = "avoidance";

/// The avoidance law (`[avoidance] law`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AvoidanceLaw {
    /// the paper's: the end effector's repulsion added to its task (eq. 19),
    /// every other control point shaping the joint velocity bounds (eq. 20),
    /// SNS resolving the task within them
    Paper,
    /// a control-barrier safety filter: the joint velocities closest to
    /// what the task asks, each control point's distance shrinking no
    /// faster than `gamma · (d − d_s)`
    Cbf,
}

/// `[avoidance]` (defaults and their reasons: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AvoidanceConfig {
    /// the law: `paper` or `cbf`
    pub law: AvoidanceLaw,
    /// γ: a control point's distance may shrink no faster than
    /// `γ (d − d_s)` \[1/s\]
    pub gamma: f64,
    /// the fixed part of d_s: the clearance kept at rest \[m\]
    pub margin_m: f64,
    /// the person's speed that perception's latency is charged at
    /// (ISO 13855: 1.6 m/s): d_s = margin_m + this × the results' age \[m/s\]
    pub human_speed_m_s: f64,
    /// weight of the end effector's task velocity in the filter's
    /// objective, against 1 for each joint velocity: the null space gives
    /// way first \[s²\]
    pub task_weight: f64,
    /// a waypoint the filter has held the end effector from for this long
    /// is passed over: the reference goes straight on to the waypoint after
    /// it, the waypoint not counted \[s\] (0: the path waits for it); and
    /// the longest the path waits at a waypoint for an end effector led
    /// round a person (`phri_control::modes::arrival`)
    pub pass_after_s: f64,
    /// the filter's joint velocities reach the reference through this
    /// slew limit \[rad/s²\] (the paper's law: `control.reference_accel_limit`)
    pub accel_limit: f64,
    /// … and this jerk limit \[rad/s³\]: the reference's acceleration, fed
    /// forward into the torque, changes by at most this × the period (0:
    /// the slew alone)
    pub jerk_limit: f64,
    /// during a collaboration's approach and follow, the person's measured
    /// approach toward a control point counts up to this \[m/s\] (a hand
    /// thrust faster is a push on purpose); in contact, not at all
    pub collaboration_speed_m_s: f64,
}

impl AvoidanceConfig {
    /// γ, margin, speed, weight, the pass's wait, the slew and jerk limits are
    /// finite and non-negative; γ and the slew limit > 0.
    pub fn validate(&self) -> Result<(), Invalid> {
        for (name, v) in [
            ("gamma", self.gamma),
            ("margin_m", self.margin_m),
            ("human_speed_m_s", self.human_speed_m_s),
            ("task_weight", self.task_weight),
            ("pass_after_s", self.pass_after_s),
            ("accel_limit", self.accel_limit),
            ("jerk_limit", self.jerk_limit),
            ("collaboration_speed_m_s", self.collaboration_speed_m_s),
        ] {
            non_negative(S, name, v)?;
        }
        positive(S, "gamma", self.gamma)?;
        positive(S, "accel_limit", self.accel_limit)
    }

    /// d_s for perception results `age_s` old \[m\].
    pub fn safe_distance_m(&self, age_s: f64) -> f64 {
        self.margin_m + self.human_speed_m_s * age_s.max(0.0)
    }
}
