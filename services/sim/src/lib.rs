//! Simulated robot cell for phri.
//!
//! A rigid-body arm ([`phri_model`]) driven by torque commands at a fixed
//! control period, with what a real arm adds: joint friction (viscous and
//! smoothed Coulomb), motor torque noise, effort limits, end stops, brakes,
//! quantized encoders and an optional wrist force/torque sensor. A scripted
//! human made of capsules ([`human`]) walks through the cell; where it
//! overlaps the robot's link capsules a compliant contact with the body
//! region's ISO/TS 15066 stiffness pushes on the robot ([`contact`]).
//! Configuration (`[sim]`) and scenarios come from [`phri_config`].
//!
//! Two layers, as a real cell has them:
//! - [`Simulator`] ([`sim`]): the arm and the person; torque and brake in,
//!   sensor readings and ground truth out, one control period per
//!   [`Simulator::step`];
//! - [`RobotLink`] ([`link`]): the robot side of the 1 kHz protocol, what a
//!   real robot adapter wraps: which command to apply, when to brake, the
//!   loop statistics. It knows commands and time, not the simulator.
//!
//! With a robot outside (`[robot] ip`), [`WorldFollower`] ([`world`]) puts
//! the simulated arm where the real one is and the simulator serves only
//! the person and the world the camera sees.
//!
//! [`messages`] fills the cell's messages from both. `main.rs` only wires
//! them to channels and keeps the real-time schedule.
//!
//! Everything is in the robot base frame (x forward, z up) and SI units. Runs
//! are deterministic given the seed; [`Simulator::step`] and
//! [`RobotLink::cycle`] allocate nothing.

#![deny(missing_docs)]

pub mod contact;
pub mod contact_log;
pub mod error;
pub mod forces_out;
pub mod human;
/// The robot side of the protocol (crate `phri-robot`), as the simulator applies it.
pub use phri_robot::link;
pub mod messages;
pub mod sim;
pub mod snapshot;
pub mod world;

pub use contact::{
    capsule_distance, closest_points_segments, contact_force_magnitude, stiffness_n_per_m,
    CapsuleDistance, SegmentClosest,
};
pub use contact_log::ContactLog;
pub use error::SimError;
pub use human::{ActivePush, Human, HumanCapsule, Reach, WAVE_BLEND_S};
pub use link::{CycleTiming, LinkError, LinkOutput, MissRun, RobotLink, Wake};
pub use messages::{fill_state, fill_truth, fill_world};
pub use sim::{
    ContactTruth, ExternalForce, Measurement, RobotCapsule, ScriptedPush, Simulator, Truth,
    MAX_CONTACTS, MAX_JOINTS,
};
pub use world::WorldFollower;
