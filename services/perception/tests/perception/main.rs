//! Perception's tests that share one test binary (one build and one link
//! instead of one per file): each module is a file of this folder, and
//! `cargo test --release -p phri-perception --test perception MODULE` runs one.

mod bad_inputs_cli;
mod flying;
mod pipeline;
mod png_process;
mod source;
#[path = "../../../../tests/support/workspace.rs"]
mod workspace;
