//! The controller's tests that share one test binary (one build and one link
//! instead of one per file): each module is a file of this folder, and
//! `cargo test --release -p phri-control --test control MODULE` runs one.

mod body_task;
mod malformed;
mod snapshot;
