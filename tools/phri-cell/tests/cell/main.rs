//! The lock-step cell's tests that share one test binary (one build and one link
//! instead of one per file): each module is a file of this folder, and
//! `cargo test --release -p phri-cell --test cell MODULE` runs one.

#[path = "../common/mod.rs"]
mod common;

mod arms;
mod avoidance_pace;
mod barrier;
mod collaboration_limits;
mod control;
mod controller_restart;
mod coverage;
mod force_estimation;
mod lockstep_cli;
mod robot_link;
mod voice;
mod wrist_contact;
