//! `phri-camera`: the simulated depth camera. At `[camera] rate_hz` it takes
//! the newest `sim/world`, renders it straight into a loaned `camera/depth`
//! sample (zero-copy: the frame is written once, in shared memory), applies
//! the faults `fault/depth` asked for, waits the sensor latency and publishes.
//! With `[skeleton] enabled` it also stands in for a body tracker: the
//! person's skeleton of that frame on `perception/skeleton`, right after it.
//! `--camera I` serves the cell's camera I (`[[camera]]`) on its own channels
//! (`camera/I/depth`, `perception/I/skeleton`); only the first camera takes
//! `fault/depth`'s faults.

use std::error::Error;
use std::process::ExitCode;

use phri_ipc::{Queue, Skeleton, Zeroed, FAULT_DEPTH, SIM_WORLD};
use phri_perception::skeleton::SkeletonTracker;
use phri_perception::{CameraFlag, CameraSim, FaultState};
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-camera", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flag) = ServiceContext::from_cli::<CameraFlag>(
        "phri-camera",
        "camera",
        "The simulated depth camera: renders the cell at the camera rate on camera/depth",
    )?;
    let (cfg, channels) = flag.resolve(ctx.config())?;
    let mut camera = CameraSim::new(ctx.robot_model()?, cfg)?;
    let pixels = camera.pixels();
    let skeleton_cfg = &ctx.config().skeleton;
    let mut tracker = skeleton_cfg
        .enabled
        .then(|| SkeletonTracker::new(skeleton_cfg, cfg.intrinsics, camera.pose()));
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let mut worlds = SIM_WORLD.latest_reader(&node)?;
    let frames = channels.depth.frame_publisher(&node, pixels)?;
    let fault_requests = match flag.camera {
        0 => Some(FAULT_DEPTH.subscriber(&node, Queue::Drain)?),
        _ => None,
    };
    let skeletons = match tracker {
        Some(_) => Some(channels.skeleton.publisher(&node)?),
        None => None,
    };
    let mut skeleton = Skeleton::zeroed();
    let mut faults = FaultState::default();
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    let period = (1e9 / cfg.rate_hz) as u64;
    let latency = (cfg.latency_ms * 1e6) as u64;
    let mut tick = now_ns();
    while !ctx.shutdown.requested() {
        tick += period;
        sleep_until_ns(tick);
        beat.beat(now_ns());
        if now_ns() > tick + period {
            tick = now_ns(); // fell behind: skip frames rather than burst
        }
        if let Some(requests) = fault_requests.as_ref() {
            requests.drain(|f| {
                let said = match faults.accept(f, now_ns()) {
                    Ok(accepted) => accepted.to_string(),
                    Err(refused) => refused.to_string(),
                };
                tracing::warn!("{}: fault {}: {said}", FAULT_DEPTH.name, f.seq);
            })?;
        }
        worlds.update()?;
        let Some(world) = worlds.get() else { continue };
        let capture_wall = now_ns();
        let mut sample = frames.loan(pixels)?;
        let mut header = *sample.user_header();
        camera.step(world, capture_wall, sample.payload_mut(), &mut header)?;
        // the tracker sees the scene, not the sensor's faults
        if let Some(t) = tracker.as_mut() {
            t.step(
                world,
                &header,
                sample.payload(),
                1.0 / cfg.rate_hz,
                &mut skeleton,
            );
        }
        let extra = faults.apply(sample.payload_mut(), &mut header, capture_wall);
        sleep_until_ns(capture_wall + latency + extra);
        header.published_ns = now_ns();
        *sample.user_header_mut() = header;
        frames.send(sample)?;
        if let Some(p) = skeletons.as_ref() {
            skeleton.published_ns = now_ns();
            p.publish(&skeleton)?;
        }
    }
    Ok(())
}
