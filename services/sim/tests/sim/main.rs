//! The simulator's tests that share one test binary (one build and one link
//! instead of one per file): each module is a file of this folder, and
//! `cargo test --release -p phri-sim --test sim MODULE` runs one.

#[path = "../common/mod.rs"]
mod common;

mod contact_parry;
mod person;
mod physics;
mod resume;
mod scenarios;
mod world;
