//! `phri-test-service`: a stand-in service for the supervisor's own tests
//! (`tests/hardening.rs`), started by the supervisor like any service (same
//! flags, `--check`, the dead-man, real-time priority, CPU pinning). It
//! publishes nothing and misbehaves on request:
//!
//! - `--spin-from S --spin-until S`: busy-loops (no sleep) while the cell's
//!   clock (`PHRI_CELL_START_NS`) is in [S, S'), starving every
//!   lower-priority process pinned to its CPUs;
//! - `--exit-after S`: exits with status 1 after running S seconds.
//!
//! Otherwise it sleeps in 10 ms steps until SIGINT/SIGTERM or its dead-man.

use std::process::ExitCode;
use std::time::Duration;

use phri_runtime::{now_ns, ServiceContext};

/// How the stand-in misbehaves.
#[derive(clap::Args, Debug)]
struct Misbehave {
    /// Busy-loop from this cell time on \[s\]
    #[arg(long, value_name = "S")]
    spin_from: Option<f64>,
    /// Stop busy-looping at this cell time \[s\]
    #[arg(long, value_name = "S")]
    spin_until: Option<f64>,
    /// Exit with status 1 after running this long \[s\]
    #[arg(long, value_name = "S")]
    exit_after: Option<f64>,
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-test-service", body)
}

fn body() -> Result<(), Box<dyn std::error::Error>> {
    let (
        ctx,
        Misbehave {
            spin_from,
            spin_until,
            exit_after,
        },
    ) = ServiceContext::from_cli(
        "phri-test-service",
        "test-service",
        "A stand-in service for the supervisor's tests, misbehaving on request",
    )?;
    if ctx.checking() {
        return Ok(());
    }
    ctx.start_deadman()?;
    let node = ctx.node()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    let started = now_ns();
    let cell_start = phri_runtime::service::cell_start_ns().unwrap_or(started);
    let cell_s = || now_ns().saturating_sub(cell_start) as f64 * 1e-9;
    let spinning = |t: f64| spin_from.is_some_and(|a| t >= a) && spin_until.is_none_or(|b| t < b);
    while !ctx.shutdown.requested() {
        if exit_after.is_some_and(|s| now_ns().saturating_sub(started) as f64 * 1e-9 >= s) {
            return Err("exiting as --exit-after asks".into());
        }
        if spinning(cell_s()) {
            // burn the CPU; the shutdown flag is checked all along
            while spinning(cell_s()) && !ctx.shutdown.requested() {
                std::hint::spin_loop();
            }
        } else {
            std::thread::sleep(Duration::from_millis(10));
            beat.beat(now_ns());
        }
    }
    Ok(())
}
