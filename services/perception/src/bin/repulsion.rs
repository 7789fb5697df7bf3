//! `phri-repulsion --worker I`: for the control points worker I owns, the
//! depth-space distance and repulsive vector of every `perception/depth`
//! frame (eqs. 15-18), published on `perception/repulsion` with the frame's
//! sequence and the processing time.

use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::*;
use phri_perception::repulsion::Worker;
use phri_perception::RepulsionConfig;
use phri_runtime::{now_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-repulsion", body)
}

fn body() -> Result<(), String> {
    let ctx = ServiceContext::from_args("repulsion", &["--worker"])?;
    let worker: u32 = ctx
        .args
        .parse_value("--worker")?
        .ok_or("--worker is required")?;
    let cfg: RepulsionConfig = ctx.section("repulsion")?;
    let model = ctx.robot_model(MAX_DOF)?;
    let mut w = Worker::new(model, &cfg, worker)?;
    let s = |x: IpcError| x.to_string();
    let node = node(&ctx.name, &ctx.prefix).map_err(s)?;
    let frames = frame_subscriber(&node, PERCEPTION_DEPTH).map_err(s)?;
    let event = listener(&node, PERCEPTION_DEPTH).map_err(s)?;
    let results = publisher::<RepulsionResult>(&node, PERCEPTION_REPULSION).map_err(s)?;
    ctx.go_realtime();
    let mut msg = RepulsionResult::zeroed();
    msg.worker = worker;
    msg.workers = cfg.workers;
    let mut seq = 0u64;
    let mut errors = 0u64;
    while !ctx.shutdown.requested() {
        let _ = event.timed_wait(|_| {}, Duration::from_millis(50));
        // the newest frame only: an old one is worth nothing to avoidance
        let mut newest = None;
        while let Some(f) = frames
            .receive()
            .map_err(|x| ipc_err(PERCEPTION_DEPTH, x).to_string())?
        {
            newest = Some(f);
        }
        let Some(frame) = newest else { continue };
        let t0 = now_ns();
        let header = *frame.user_header();
        match w.step(&header, frame.payload()) {
            Ok(points) => {
                msg.n_points = points.len() as u32;
                msg.points[..points.len()].copy_from_slice(points);
            }
            Err(e) => {
                errors += 1;
                if errors.is_power_of_two() {
                    eprintln!("phri-repulsion {worker}: {e} ({errors} frames failed)");
                }
                continue;
            }
        }
        drop(frame);
        seq += 1;
        msg.seq = seq;
        msg.frame_seq = header.seq;
        msg.capture_ns = header.capture_ns;
        msg.frame_capture_wall_ns = header.capture_wall_ns;
        msg.compute_ns = now_ns() - t0;
        msg.published_ns = now_ns();
        publish(&results, PERCEPTION_REPULSION, &msg).map_err(s)?;
    }
    Ok(())
}
