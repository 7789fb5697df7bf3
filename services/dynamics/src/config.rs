//! `[dynamics]` section of `deploy/phri.toml`.

use serde::Deserialize;

/// Residual and detection settings. Per-joint lists shorter than the robot's
/// joint count repeat their last entry.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ResidualConfig {
    /// observer gain K_I per joint [1/s]: each residual is a first-order low-pass of τ_ext with this bandwidth
    pub gain: Vec<f64>,
    /// cut-off of the velocity estimate from positions [Hz]
    pub velocity_cutoff_hz: f64,
    /// |r_i| above this is a *contact* [Nm]
    pub contact_threshold: Vec<f64>,
    /// |r_i| above this is a *collision* [Nm]
    pub collision_threshold: Vec<f64>,
    /// ‖r‖ above this is a collision [Nm]
    pub collision_norm_threshold: f64,
    /// nominal viscous friction compensated before integrating [Nm s/rad]
    pub viscous_friction: Vec<f64>,
    /// nominal Coulomb friction compensated before integrating [Nm]
    pub coulomb_friction: Vec<f64>,
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

impl Default for ResidualConfig {
    fn default() -> Self {
        ResidualConfig {
            gain: vec![100.0],
            velocity_cutoff_hz: 60.0,
            contact_threshold: vec![4.0, 4.0, 3.0, 3.0, 2.0, 1.5, 1.0],
            collision_threshold: vec![8.0, 8.0, 6.0, 6.0, 4.0, 3.0, 2.0],
            collision_norm_threshold: 12.0,
            viscous_friction: vec![0.4],
            coulomb_friction: vec![0.25],
            coulomb_velocity: 0.01,
            use_ft_sensor: true,
            ft_link: String::new(),
            warmup_samples: 50,
            max_gap_s: 0.05,
        }
    }
}

/// `v` stretched to `n` entries by repeating its last one; error if empty or non-finite.
pub fn per_joint(name: &str, v: &[f64], n: usize) -> Result<Vec<f64>, String> {
    let last = *v.last().ok_or_else(|| format!("{name}: empty list"))?;
    let out: Vec<f64> = (0..n).map(|i| v.get(i).copied().unwrap_or(last)).collect();
    if out.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return Err(format!("{name}: values must be finite and non-negative"));
    }
    Ok(out)
}
