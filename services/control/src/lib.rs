//! The torque loop as a pure, deterministic step: joint positions and the
//! newest residual in, a limited joint torque and a mode out.
//!
//! - Task: the end effector cycles through Cartesian waypoints on
//!   minimum-jerk segments, resolved by closed-loop inverse kinematics with a
//!   damped pseudoinverse; the redundancy holds a comfortable posture; a
//!   computed-torque law tracks the joint reference with gravity compensated.
//! - On a detected collision it switches at once to the configured reaction
//!   (reflex torque eq. 9, admittance eq. 13, stop, float, time-scaled retreat
//!   along the past path), then holds until the residual falls back and
//!   resumes the task (configurable).
//! - Without a fresh, valid residual it holds a protective stop.
//! - After (re)start it re-syncs to the measured state: the first command
//!   holds where the arm is and the task approaches its path smoothly.
//! - Torque, velocity and position limits are enforced at the last step.

pub mod avoidance;
pub mod config;
pub mod controller;
pub mod limits;
pub mod sns;
pub mod task;

pub use config::{ControlConfig, Reaction};
pub use controller::{ControlInput, ControlOutput, Controller, PerceptionView, ResidualView};
