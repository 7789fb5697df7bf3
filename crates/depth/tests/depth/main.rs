//! Depth space's tests that share one test binary (one build and one link
//! instead of one per file): each module is a file of this folder, and
//! `cargo test --release -p phri-depth --test depth MODULE` runs one.

#[path = "../common/mod.rs"]
mod common;

mod camera;
mod distance;
mod fusion;
mod png;
mod render;
mod selffilter;
