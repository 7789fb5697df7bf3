//! The model's tests that share one test binary (one build and one link
//! instead of one per file): each module is a file of this folder, and
//! `cargo test --release -p phri-model --test model MODULE` runs one.

#[path = "../common/mod.rs"]
mod common;

mod armature;
mod capsules;
mod locked;
mod mimic;
mod physics;
mod pinocchio;
mod refused;
