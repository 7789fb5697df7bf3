//! `[sim]`: the simulated arm's integration and its sensor and actuator imperfections.

use serde::{Deserialize, Serialize};

use crate::check::{finite, non_negative, positive, within};
use crate::error::Invalid;
use crate::PerJoint;

const S: &str = "sim";

/// Configuration of the simulated arm (defaults and their reasons: `deploy/phri.toml`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimConfig {
    /// control period \[s\]: one simulator step advances this much
    pub dt_s: f64,
    /// integration sub-steps per control period
    pub substeps: u32,
    /// encoder quantization step of the measured joint positions \[rad\] (0: none)
    pub encoder_resolution_rad: f64,
    /// viscous joint friction [N·m·s/rad]
    pub viscous_friction: PerJoint,
    /// Coulomb joint friction [N·m], smoothed as `τ_c tanh(q̇ / coulomb_smoothing_rad_s)`
    pub coulomb_friction: PerJoint,
    /// velocity scale of the Coulomb smoothing [rad/s]
    pub coulomb_smoothing_rad_s: f64,
    /// standard deviation of the Gaussian noise on the applied motor torque [N·m]
    /// (drawn once per control period, not seen by the measurement)
    pub torque_noise_std: f64,
    /// contact damping `d` of the human–robot contact law [N·s/m]
    pub contact_damping: f64,
    /// brake damping [N·m·s/rad]: braked joints get `g(q) − sat(brake_damping q̇)`
    pub brake_damping: f64,
    /// saturation of the brake damping torque [N·m]
    pub brake_torque_max: PerJoint,
    /// initial joint positions \[rad\] (one per joint)
    pub q0: Vec<f64>,
    /// seed of the torque-noise generator (the run is deterministic given it)
    pub seed: u64,
    /// simulate a wrist force/torque sensor at the last joint's link frame
    pub ft_sensor: bool,
    /// in the hybrid cell, where the person's contact forces go (UDP,
    /// `ip:port`) to act on an arm that is itself simulated outside
    /// (franka-sim: `deploy/franka-sim/serve.py --forces-port`); "": nowhere
    pub forces_to: String,
    /// the person's script runs this far ahead of the simulator's clock
    /// \[s\]: the cell meets the person at that point of the scenario (the
    /// `[human]` keyframes; the scenario's voice lines keep the robot's
    /// clock). `phri-lockstep --offset` adds its own to it
    pub human_offset_s: f64,
}

impl SimConfig {
    /// Range checks of every field (joint counts are checked against the model).
    pub fn validate(&self) -> Result<(), Invalid> {
        // buffers and the scenario clock count periods: 0.1-10 ms
        within(S, "dt_s", self.dt_s, 1e-4, 1e-2)?;
        if !(1..=1000).contains(&self.substeps) {
            return Err(Invalid::new(
                "sim.substeps",
                format!("{} is not in 1..=1000", self.substeps),
            ));
        }
        non_negative(S, "encoder_resolution_rad", self.encoder_resolution_rad)?;
        within(S, "human_offset_s", self.human_offset_s, -3600.0, 3600.0)?;
        self.viscous_friction.check("sim.viscous_friction")?;
        self.coulomb_friction.check("sim.coulomb_friction")?;
        positive(S, "coulomb_smoothing_rad_s", self.coulomb_smoothing_rad_s)?;
        non_negative(S, "torque_noise_std", self.torque_noise_std)?;
        non_negative(S, "contact_damping", self.contact_damping)?;
        non_negative(S, "brake_damping", self.brake_damping)?;
        self.brake_torque_max.check("sim.brake_torque_max")?;
        finite(S, "q0", &self.q0)?;
        if !self.forces_to.is_empty() && self.forces_to.parse::<std::net::SocketAddr>().is_err() {
            return Err(Invalid::new(
                "sim.forces_to",
                format!("{:?} is not an address ip:port", self.forces_to),
            ));
        }
        Ok(())
    }

    /// Friction and noise off (ideal actuators), for tests.
    pub fn ideal(mut self) -> SimConfig {
        self.viscous_friction = PerJoint::All(0.0);
        self.coulomb_friction = PerJoint::All(0.0);
        self.torque_noise_std = 0.0;
        self
    }
}
