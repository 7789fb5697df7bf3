//! `[dynamics]`: the momentum residual and its detector.

use serde::{Deserialize, Serialize};

use crate::check::{non_negative, positive};
use crate::error::Invalid;
use crate::PerJoint;

const S: &str = "dynamics";

/// Residual and detection settings (defaults: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResidualConfig {
    /// observer gain K_I [1/s]: each residual is a first-order low-pass of τ_ext with this bandwidth
    pub gain: PerJoint,
    /// cut-off of the velocity estimate from positions [Hz]
    pub velocity_cutoff_hz: f64,
    /// |r_i| above this is a *contact* [Nm]
    pub contact_threshold: PerJoint,
    /// |r_i| above this is a *collision* [Nm]
    pub collision_threshold: PerJoint,
    /// ‖r‖ above this is a collision [Nm]
    pub collision_norm_threshold: f64,
    /// nominal viscous friction compensated before integrating [Nm s/rad]
    pub viscous_friction: PerJoint,
    /// nominal Coulomb friction compensated before integrating [Nm]
    pub coulomb_friction: PerJoint,
    /// velocity scale of the smoothed Coulomb term tanh(q̇ / v) [rad/s]
    pub coulomb_velocity: f64,
    /// use a wrist F/T reading when the robot reports one (modified residual, eq. 8)
    pub use_ft_sensor: bool,
    /// link whose frame the F/T reading refers to (empty: the last joint's link)
    pub ft_link: String,
    /// samples after (re)start before the residual is declared valid
    pub warmup_samples: u32,
    /// largest gap between two states integrated as one step [s]; longer gaps re-initialise
    pub max_gap_s: f64,
}

impl ResidualConfig {
    /// Range checks of every field (joint counts are checked against the model).
    pub fn validate(&self) -> Result<(), Invalid> {
        self.gain.check("dynamics.gain")?;
        positive(S, "velocity_cutoff_hz", self.velocity_cutoff_hz)?;
        self.contact_threshold.check("dynamics.contact_threshold")?;
        self.collision_threshold
            .check("dynamics.collision_threshold")?;
        positive(S, "collision_norm_threshold", self.collision_norm_threshold)?;
        self.viscous_friction.check("dynamics.viscous_friction")?;
        self.coulomb_friction.check("dynamics.coulomb_friction")?;
        positive(S, "coulomb_velocity", self.coulomb_velocity)?;
        positive(S, "max_gap_s", self.max_gap_s)?;
        non_negative(S, "warmup_samples", self.warmup_samples as f64)?;
        Ok(())
    }
}
