//! `phri-repulsion --worker I`: for the control points worker I owns, the
//! depth-space distance and repulsive vector of the newest frame of every
//! camera of the cell (eqs. 15-18, [`Worker::respond`]): `perception/depth`
//! answered on `perception/repulsion`, camera C's `perception/C/depth` on
//! `perception/C/repulsion`, each with the frame's sequence and the
//! processing time. With several cameras each answer is bounded by what its
//! camera watches ([`Worker::bounded_by`]) and capped by the nearest surface
//! any camera showed the worker ([`Worker::respond_among`]). A camera that
//! stops sending frames delays none of the others' answers.

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::{wait_any, FrameSubscriber, Publisher, Queue, RepulsionResult};
use phri_perception::{SeenSurfaces, Worker};
use phri_runtime::{now_ns, ServiceContext};

/// The worker's own flag.
#[derive(clap::Args, Debug)]
struct WorkerFlag {
    /// Index of this worker: it owns the control points `[repulsion]` assigns to it
    #[arg(long, value_name = "I", required = true)]
    worker: Option<u32>,
}

/// One camera as this worker serves it.
struct Served {
    worker: Worker,
    frames: FrameSubscriber,
    results: Publisher<RepulsionResult>,
    errors: u64,
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
    let cfg = ctx.config();
    let cameras = &cfg.cameras;
    let mut workers = Vec::with_capacity(cameras.len());
    for camera in cameras {
        let w = Worker::new(ctx.robot_model()?, &cfg.repulsion, worker)?;
        workers.push(match cameras.len() {
            1 => w,
            _ => w.bounded_by(camera)?,
        });
    }
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let mut served = Vec::with_capacity(workers.len());
    for (w, channels) in workers.into_iter().zip(phri_ipc::cameras(cameras.len())) {
        served.push(Served {
            worker: w,
            frames: channels
                .perception
                .waking_frame_subscriber(&node, Queue::Latest)?,
            results: channels.repulsion.publisher(&node)?,
            errors: 0,
        });
    }
    // with several cameras: the surfaces each showed this worker's points
    let mut seen = (served.len() > 1).then(|| SeenSurfaces::for_cell(cfg));
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    while !ctx.shutdown.requested() {
        {
            let subs: Vec<&FrameSubscriber> = served.iter().map(|s| &s.frames).collect();
            let _ = wait_any(&subs, Duration::from_millis(50));
        }
        beat.beat(now_ns());
        for (camera, s) in served.iter_mut().enumerate() {
            // the newest frame only: an old one is worth nothing to avoidance
            let Some(frame) = s.frames.latest()? else {
                continue;
            };
            let t0 = now_ns();
            let header = *frame.user_header();
            let (h, f) = (frame.user_header(), frame.payload());
            let answer = s.worker.respond_among(h, f, camera, seen.as_mut());
            let msg = match answer {
                Ok(msg) => msg,
                Err(e) => {
                    s.errors += 1;
                    if s.errors.is_power_of_two() {
                        tracing::warn!(
                            "worker {worker}, camera {camera}: {e} ({} frames failed)",
                            s.errors
                        );
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
            s.results.publish(msg)?;
        }
    }
    Ok(())
}
