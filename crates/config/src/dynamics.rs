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
    /// observer gain K_I [1/s]: each residual is a low-pass of τ_ext with
    /// this bandwidth, behind the velocity estimate's own ([`ResidualConfig::step_response`])
    pub gain: PerJoint,
    /// cut-off of the velocity estimate from positions \[Hz\]
    pub velocity_cutoff_hz: f64,
    /// |r_i| above this is a *contact* \[Nm\]
    pub contact_threshold: PerJoint,
    /// |r_i| above this is a *collision* \[Nm\]
    pub collision_threshold: PerJoint,
    /// ‖r‖ above this is a collision \[Nm\]
    pub collision_norm_threshold: f64,
    /// nominal viscous friction compensated before integrating [Nm s/rad]
    pub viscous_friction: PerJoint,
    /// nominal Coulomb friction compensated before integrating \[Nm\]
    pub coulomb_friction: PerJoint,
    /// velocity scale of the smoothed Coulomb term tanh(q̇ / v) [rad/s]
    pub coulomb_velocity: f64,
    /// use a wrist F/T reading when the robot reports one (modified residual, eq. 8)
    pub use_ft_sensor: bool,
    /// link whose frame the F/T reading refers to (empty: the last joint's link)
    pub ft_link: String,
    /// samples after (re)start before the residual is declared valid
    pub warmup_samples: u32,
    /// largest gap between two states integrated as one step \[s\]; longer gaps re-initialise
    pub max_gap_s: f64,
    /// the hot standby's residual (`[control] standby`) wakes this often and
    /// steps every state queued since \[ms\], and at once when the
    /// controller in charge calls it (`dynamics/residual/call`: the first
    /// residual is two periods behind or gone); 0: woken by every state,
    /// as the one in charge
    pub standby_wake_ms: f64,
}

impl ResidualConfig {
    /// The residual's response to a unit step of τ_ext, `t` \[s\] after it,
    /// for a joint of gain `k_i` [1/s]: the observer's `K/(s + K)` behind the
    /// low-pass that makes q̇ from positions, `a/(s + a)`, `a = 2π
    /// velocity_cutoff_hz` (the observer filters the momentum's rate as the
    /// estimate filters q̇, so that both lag alike):
    /// `1 − (a e^{−K t} − K e^{−a t})/(a − K)`.
    pub fn step_response(&self, k_i: f64, t: f64) -> f64 {
        let a = 2.0 * std::f64::consts::PI * self.velocity_cutoff_hz;
        if t <= 0.0 {
            return 0.0;
        }
        if (a - k_i).abs() < 1e-9 * a.max(k_i) {
            return 1.0 - (1.0 + k_i * t) * (-k_i * t).exp();
        }
        1.0 - (a * (-k_i * t).exp() - k_i * (-a * t).exp()) / (a - k_i)
    }

    /// When [`ResidualConfig::step_response`] reaches `fraction` ∈ (0, 1) \[s\]
    /// (a step of F crosses a threshold θ at `fraction = θ/F`); `None`
    /// outside (0, 1) or for a gain that is not positive.
    pub fn time_to_reach(&self, k_i: f64, fraction: f64) -> Option<f64> {
        if !(fraction > 0.0 && fraction < 1.0 && k_i > 0.0) {
            return None;
        }
        // the response rises monotonically: bisect
        let (mut lo, mut hi) = (0.0, 1.0 / k_i);
        while self.step_response(k_i, hi) < fraction {
            hi *= 2.0;
            if hi > 1e6 {
                return None;
            }
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            match self.step_response(k_i, mid) < fraction {
                true => lo = mid,
                false => hi = mid,
            }
        }
        Some(hi)
    }

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
        non_negative(S, "standby_wake_ms", self.standby_wake_ms)?;
        Ok(())
    }
}
