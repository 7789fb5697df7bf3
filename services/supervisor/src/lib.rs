//! The supervisor's logic as plain data and pure functions: which services to
//! run and how to restart them ([`spec`], [`restart`]), and the run report
//! built from what flowed on the channels ([`report`]). `main.rs` does the I/O.

pub mod process;
pub mod report;
pub mod restart;
pub mod spec;
