//! `[ssm]`: speed and separation monitoring (ISO/TS 15066 clause 5.5.4)
//! from depth space, in the standard's terms.

use serde::{Deserialize, Serialize};

use crate::check::non_negative;
use crate::error::Invalid;

const S: &str = "ssm";

/// How fast the person is taken to approach a control point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HumanSpeed {
    /// measured in depth space: the rate at which each control point's
    /// clearance closes, less the point's own approach
    Measured,
    /// ISO 13855's: 2.0 m/s within 0.5 m, 1.6 m/s beyond
    Iso13855,
}

/// `[ssm]` (defaults and their reasons: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SsmConfig {
    /// monitor outside the collaboration (it lets a person touch the robot
    /// on purpose: power and force limiting instead)
    pub enabled: bool,
    /// how fast the person is taken to approach: measured or ISO 13855's
    pub human_speed: HumanSpeed,
    /// T_s: the robot's stopping time \[s\]
    pub stop_time_s: f64,
    /// S_s = this × the speed toward the person \[s\]
    pub stop_distance_per_speed_s: f64,
    /// C: intrusion distance \[m\]
    pub intrusion_m: f64,
    /// Z_d: the person's position uncertainty (the sensor's) \[m\]
    pub sensor_uncertainty_m: f64,
    /// Z_r: the robot's position uncertainty \[m\]
    pub robot_uncertainty_m: f64,
    /// measured human speed: it falls by at most this [m/s²] (a rise counts at once)
    pub human_speed_decay: f64,
}

impl SsmConfig {
    /// Every time, distance, uncertainty and the speed's decay is non-negative.
    pub fn validate(&self) -> Result<(), Invalid> {
        for (name, v) in [
            ("stop_time_s", self.stop_time_s),
            ("stop_distance_per_speed_s", self.stop_distance_per_speed_s),
            ("intrusion_m", self.intrusion_m),
            ("sensor_uncertainty_m", self.sensor_uncertainty_m),
            ("robot_uncertainty_m", self.robot_uncertainty_m),
            ("human_speed_decay", self.human_speed_decay),
        ] {
            non_negative(S, name, v)?;
        }
        Ok(())
    }
}
