//! Simulator configuration: integration, sensor and actuator imperfections.

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;

use crate::error::SimError;

/// A per-joint parameter: one value for every joint, or one per joint.
/// In TOML either `0.5` or `[0.5, 0.5, 0.4, 0.4, 0.3, 0.2, 0.2]`.
#[derive(Clone, Debug, PartialEq)]
pub enum PerJoint {
    /// the same value for every joint
    All(f64),
    /// one value per joint, in the model's joint order
    Each(Vec<f64>),
}

impl PerJoint {
    /// One value per joint for an `n`-joint model, checked to be finite and
    /// non-negative; `field` names the parameter in errors.
    pub fn resolve(&self, n: usize, field: &'static str) -> Result<Vec<f64>, SimError> {
        let v = match self {
            PerJoint::All(x) => vec![*x; n],
            PerJoint::Each(v) if v.len() == n => v.clone(),
            PerJoint::Each(v) => {
                return Err(SimError::Config {
                    field,
                    reason: format!("has {} values, the model has {n} joints", v.len()),
                })
            }
        };
        match v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            Some(i) => Err(SimError::Config {
                field,
                reason: format!("joint {i}: {} is not a finite non-negative number", v[i]),
            }),
            None => Ok(v),
        }
    }
}

impl<'de> Deserialize<'de> for PerJoint {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<PerJoint, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = PerJoint;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of numbers (one per joint)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<PerJoint, E> {
                Ok(PerJoint::All(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<PerJoint, E> {
                Ok(PerJoint::All(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<PerJoint, E> {
                Ok(PerJoint::All(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<PerJoint, A::Error> {
                let mut v = Vec::with_capacity(seq.size_hint().unwrap_or(7));
                while let Some(x) = seq.next_element::<f64>()? {
                    v.push(x);
                }
                Ok(PerJoint::Each(v))
            }
        }
        deserializer.deserialize_any(V)
    }
}

/// Configuration of the simulated arm. Every field has a default; in TOML
/// unknown fields are refused.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    /// control period \[s\]: one [`crate::Simulator::step`] advances this much
    pub dt_s: f64,
    /// integration sub-steps per control period (semi-implicit Euler with
    /// implicit joint damping; contacts are stable with 4 at 1 ms)
    pub substeps: u32,
    /// encoder quantization step of the measured joint positions \[rad\]
    /// (0: no quantization)
    pub encoder_resolution_rad: f64,
    /// viscous joint friction [N·m·s/rad], per joint or one for all
    pub viscous_friction: PerJoint,
    /// Coulomb joint friction [N·m], smoothed as `τ_c tanh(q̇ / coulomb_smoothing_rad_s)`
    pub coulomb_friction: PerJoint,
    /// velocity scale of the Coulomb smoothing [rad/s]
    pub coulomb_smoothing_rad_s: f64,
    /// standard deviation of the Gaussian noise added to the applied motor
    /// torque [N·m], drawn once per control period (not seen by the measurement)
    pub torque_noise_std: f64,
    /// contact damping `d` of the human–robot contact law [N·s/m]
    pub contact_damping: f64,
    /// brake damping [N·m·s/rad]: braked joints get `g(q) − sat(brake_damping q̇)`
    pub brake_damping: f64,
    /// saturation of the brake damping torque [N·m], per joint or one for all
    pub brake_torque_max: PerJoint,
    /// initial joint positions \[rad\] (one per joint)
    pub q0: Vec<f64>,
    /// seed of the torque-noise generator (the run is deterministic given it)
    pub seed: u64,
    /// simulate a wrist force/torque sensor at the last joint's link frame
    /// that measures the external wrench applied to that link
    pub ft_sensor: bool,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            dt_s: 0.001,
            substeps: 4,
            encoder_resolution_rad: std::f64::consts::TAU / (1u64 << 20) as f64,
            viscous_friction: PerJoint::All(0.5),
            coulomb_friction: PerJoint::All(0.3),
            coulomb_smoothing_rad_s: 0.01,
            torque_noise_std: 0.05,
            contact_damping: 100.0,
            brake_damping: 50.0,
            brake_torque_max: PerJoint::All(40.0),
            q0: vec![0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0],
            seed: 0,
            ft_sensor: false,
        }
    }
}

impl SimConfig {
    /// A config with friction and noise switched off (ideal actuators), for tests.
    pub fn ideal() -> SimConfig {
        SimConfig {
            viscous_friction: PerJoint::All(0.0),
            coulomb_friction: PerJoint::All(0.0),
            torque_noise_std: 0.0,
            ..SimConfig::default()
        }
    }

    /// Parse from TOML text (a table of the fields above).
    pub fn from_toml_str(text: &str) -> Result<SimConfig, SimError> {
        toml::from_str(text).map_err(|e| SimError::Toml(e.to_string().trim_end().to_string()))
    }

    /// Check the scalar fields (per-joint fields are checked against the model
    /// by [`crate::Simulator::new`]).
    pub fn validate(&self) -> Result<(), SimError> {
        let positive = |x: f64, field: &'static str| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(SimError::Config {
                    field,
                    reason: format!("{x} is not a positive number"),
                })
            }
        };
        let non_negative = |x: f64, field: &'static str| {
            if x.is_finite() && x >= 0.0 {
                Ok(())
            } else {
                Err(SimError::Config {
                    field,
                    reason: format!("{x} is not a finite non-negative number"),
                })
            }
        };
        positive(self.dt_s, "dt_s")?;
        if !(1..=1000).contains(&self.substeps) {
            return Err(SimError::Config {
                field: "substeps",
                reason: format!("{} is not in 1..=1000", self.substeps),
            });
        }
        non_negative(self.encoder_resolution_rad, "encoder_resolution_rad")?;
        positive(self.coulomb_smoothing_rad_s, "coulomb_smoothing_rad_s")?;
        non_negative(self.torque_noise_std, "torque_noise_std")?;
        non_negative(self.contact_damping, "contact_damping")?;
        non_negative(self.brake_damping, "brake_damping")?;
        Ok(())
    }
}
