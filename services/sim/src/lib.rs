//! Simulated robot cell for phri.
//!
//! A rigid-body arm ([`phri_model`]) driven by torque commands at a fixed
//! control period, with what a real arm adds: joint friction (viscous and
//! smoothed Coulomb), motor torque noise, effort limits, end stops, brakes,
//! quantized encoders and an optional wrist force/torque sensor. A scripted
//! human made of capsules ([`human`]) walks through the cell; where it
//! overlaps the robot's link capsules a compliant contact with the body
//! region's ISO/TS 15066 stiffness pushes on the robot ([`contact`]).
//! Scenarios ([`scenario`]) bundle a human script with configuration.
//!
//! Everything is in the robot base frame (x forward, z up) and SI units. Runs
//! are deterministic given the seed; [`Simulator::step`] allocates nothing.

pub mod config;
pub mod contact;
pub mod error;
pub mod human;
pub mod scenario;
pub mod sim;
pub mod snapshot;
pub mod world;

pub use config::{PerJoint, SimConfig};
pub use contact::{
    capsule_distance, closest_points_segments, contact_force_magnitude, CapsuleDistance,
    SegmentClosest,
};
pub use error::SimError;
pub use human::{BodyPart, Human, HumanCapsule, HumanScript, Keyframe, ScriptError};
pub use scenario::{Scenario, ScenarioError};
pub use sim::{
    ContactTruth, Measurement, RobotCapsule, Simulator, Truth, MAX_CONTACTS, MAX_JOINTS,
};
