//! `[robot]`: which arm, and what the cell knows about it beyond its URDF.
//! An arm's robot file, `deploy/robots/<name>/robot.toml`, holds its
//! `[robot]` (URDF, capsules) and whatever else belongs to the arm (postures,
//! thresholds per joint, links, control points): the loader merges it under
//! the configuration file ([`crate::Loaded::load`]).

use serde::{Deserialize, Serialize};

use crate::{Invalid, PerJoint};

/// The default arm's name (`[robot] name`).
pub const DEFAULT_ROBOT: &str = "lwr4";

/// The default arm's robot file, `deploy/robots/lwr4/robot.toml`, as built.
pub const DEFAULT_ROBOT_FILE: &str = include_str!("../../../deploy/robots/lwr4/robot.toml");

/// `[robot]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSection {
    /// the arm: its robot file `robots/<name>/robot.toml` (beside the
    /// configuration file, else in the built-in `deploy/`) merges under the
    /// configuration file
    #[serde(default = "default_robot_name")]
    pub name: String,
    /// robot description (URDF), relative to the file that gives it (the
    /// robot file, or a configuration file that overrides it)
    pub urdf: String,
    /// a robot outside the cell (`--robot-ip`): the address of its control
    /// box, which `phri-franka` drives (`phri-sim` then simulates the person
    /// and the world only); "" for the simulated arm
    #[serde(default)]
    pub ip: String,
    /// the robot file merged (absolute; written by the loader, "" for none)
    #[serde(default)]
    pub file: String,
    /// rotor inertia reflected at each joint [kg m²] (one number or one per
    /// joint), added to the model's `M` (a URDF has no place for it)
    #[serde(default = "no_armature")]
    pub armature: PerJoint,
    /// collision capsules added to the URDF's (a URDF with mesh collisions
    /// only has none phri can use): the camera's self-filter and scene, the
    /// simulated contacts
    #[serde(default)]
    pub capsules: Vec<CapsuleConfig>,
    /// URDF joints held at their zero (a gripper's fingers, with a
    /// controller of their own): the model keeps the arm's joints only
    #[serde(default)]
    pub locked_joints: Vec<String>,
}

/// `[[robot.capsules]]`: the segment `a`–`b` \[m\] on `link` (its frame)
/// swept by a sphere of `radius` \[m\].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CapsuleConfig {
    /// the link the capsule is fixed on
    pub link: String,
    /// one end of the segment \[m\], link frame
    pub a: [f64; 3],
    /// the other end of the segment \[m\], link frame
    pub b: [f64; 3],
    /// the sphere's radius \[m\], in (0, 1\]
    pub radius: f64,
}

impl RobotSection {
    /// Finite segments, positive radii.
    pub fn validate(&self) -> Result<(), Invalid> {
        let armature = match &self.armature {
            PerJoint::All(x) => std::slice::from_ref(x),
            PerJoint::Each(v) => v.as_slice(),
        };
        if armature
            .iter()
            .any(|a| !(a.is_finite() && (0.0..=100.0).contains(a)))
        {
            return Err(Invalid::new("robot.armature", "must be in [0, 100] kg m²"));
        }
        for (i, c) in self.capsules.iter().enumerate() {
            if !c.a.iter().chain(&c.b).all(|x| x.is_finite()) {
                return Err(Invalid::new(
                    format!("robot.capsules[{i}].a"),
                    "a and b must be finite [m]",
                ));
            }
            if !(c.radius.is_finite() && c.radius > 0.0 && c.radius <= 1.0) {
                return Err(Invalid::new(
                    format!("robot.capsules[{i}].radius"),
                    "must be in (0, 1] m",
                ));
            }
        }
        Ok(())
    }
}

fn no_armature() -> PerJoint {
    PerJoint::All(0.0)
}

fn default_robot_name() -> String {
    DEFAULT_ROBOT.into()
}
