//! `phri-repulsion --worker I`: for the control points worker I owns, the
//! depth-space distance and repulsive vector of the newest
//! `perception/depth` frame (eqs. 15-18, [`Worker::respond`]), published on
//! `perception/repulsion` with the frame's sequence and the processing time.

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::{Queue, PERCEPTION_DEPTH, PERCEPTION_REPULSION};
use phri_perception::Worker;
use phri_runtime::{now_ns, ServiceContext};

/// The worker's own flag.
#[derive(clap::Args, Debug)]
struct WorkerFlag {
    /// Index of this worker: it owns the control points `[repulsion]` assigns to it
    #[arg(long, value_name = "I", required = true)]
    worker: Option<u32>,
}

fn main() -> ExitCode {
    phri_runtime::service::run("phri-repulsion", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, WorkerFlag { worker }) = ServiceContext::from_cli(
        "phri-repulsion",
        "repulsion",
        "A repulsion worker: the depth-space distances and repulsive vectors (eqs. 15-18) of the control points it owns, on perception/repulsion",
    )?;
    // required by clap unless `completions` ran (and exited)
    let worker = worker.ok_or("--worker is required")?;
    let mut w = Worker::new(ctx.robot_model()?, &ctx.config().repulsion, worker)?;
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let frames = PERCEPTION_DEPTH.waking_frame_subscriber(&node, Queue::Latest)?;
    let results = PERCEPTION_REPULSION.publisher(&node)?;
    ctx.start_deadman()?;
    ctx.go_realtime();
    let mut errors = 0u64;
    while !ctx.shutdown.requested() {
        let _ = frames.wait(Duration::from_millis(50));
        // the newest frame only: an old one is worth nothing to avoidance
        let Some(frame) = frames.latest()? else {
            continue;
        };
        let t0 = now_ns();
        let header = *frame.user_header();
        let msg = match w.respond(frame.user_header(), frame.payload()) {
            Ok(msg) => msg,
            Err(e) => {
                errors += 1;
                if errors.is_power_of_two() {
                    tracing::warn!("worker {worker}: {e} ({errors} frames failed)");
                }
                continue;
            }
        };
        drop(frame);
        msg.compute_ns = now_ns() - t0;
        msg.published_ns = now_ns();
        // the frame arrived at ingestion ingest_ns before ingestion published it
        msg.since_arrival_ns = match header.ingest_ns {
            0 => 0,
            ingest => {
                let arrived = header.published_ns.saturating_sub(u64::from(ingest));
                u32::try_from(msg.published_ns.saturating_sub(arrived)).unwrap_or(u32::MAX)
            }
        };
        results.publish(msg)?;
    }
    Ok(())
}
