//! `phri-camera`: a camera served from this machine's own means, on
//! `camera/depth` (`camera/I/depth` with `--camera I`) and `camera/status`.
//! `[camera] source = "sim"`: the simulated depth camera. At `[camera]
//! rate_hz` (several simulated cameras in turn, camera I at I/N of the
//! period: [`phri_perception::turns`]) it takes the newest `sim/world`,
//! renders it straight into a loaned `camera/depth` sample (zero-copy: the
//! frame is written once, in shared memory), applies the faults `fault/depth` asked for (the first
//! camera only), waits the sensor latency and publishes. With `[skeleton]
//! enabled` and `source = "sim"` it also stands in for a body tracker: the
//! person's skeleton of that frame from the truth on `perception/skeleton`,
//! right after it (with `source = "depth"`, `phri-tracker` publishes it).
//! `source = "replay"`: the recorded frames of `replay_dir`
//! ([`phri_perception::replay`]) at `rate_hz`.
//! A Kinect (`freenect`) and a ROS 2 camera (`ros2`) have binaries of their
//! own (`phri-freenect`, `phri-camera-ros2`), which the supervisor runs.

use std::error::Error;
use std::process::ExitCode;

use phri_config::{CameraConfig, CameraSource, SkeletonSource};
use phri_ipc::{CameraChannels, Queue, Skeleton, Zeroed, CAMERA_STATUS, FAULT_DEPTH, SIM_WORLD};
use phri_perception::live::STATUS_PERIOD_NS;
use phri_perception::replay::Replay;
use phri_perception::skeleton::SkeletonTracker;
use phri_perception::turns::last_turn_ns;
use phri_perception::{
    CameraFlag, CameraOut, CameraSim, CameraStamps, DropCause, FaultState, RateLimited, Ticks,
};
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-camera", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flag) = ServiceContext::from_cli::<CameraFlag>(
        "phri-camera",
        "camera",
        "A depth camera on camera/depth: [camera] source = \"sim\" renders the simulated cell at the camera rate, \"replay\" plays the recorded frames of [camera] replay_dir",
    )?;
    let (cfg, channels) = flag.resolve(ctx.config())?;
    match cfg.source {
        CameraSource::Sim => simulated(&ctx, flag, cfg, channels),
        CameraSource::Replay => replay(&ctx, flag, cfg, channels),
        other => Err(format!(
            "--camera {}: [camera] source = \"{}\" is served by {}, not phri-camera",
            flag.camera,
            other.name(),
            other.binary()
        )
        .into()),
    }
}

/// The simulated camera.
fn simulated(
    ctx: &ServiceContext,
    flag: CameraFlag,
    cfg: &CameraConfig,
    channels: &CameraChannels,
) -> Result<(), Box<dyn Error>> {
    let mut camera = CameraSim::new(ctx.robot_model()?, cfg)?;
    let mut stamps = CameraStamps::new(flag.camera, cfg)?;
    let pixels = camera.pixels();
    let skeleton_cfg = &ctx.config().skeleton;
    // the stand-in tracker from the truth, unless this camera's skeletons come from depth
    let from_truth = ctx.config().skeleton_source(flag.camera) == SkeletonSource::Sim;
    let mut tracker = (skeleton_cfg.enabled && from_truth)
        .then(|| SkeletonTracker::new(skeleton_cfg, cfg.intrinsics, camera.pose()));
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let mut worlds = SIM_WORLD.latest_reader(&node)?;
    let frames = channels.depth.frame_publisher(&node, pixels)?;
    let status = CAMERA_STATUS.publisher(&node)?;
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
    // several cameras capture in turn, this one at its phase of the period
    let turn = |now| last_turn_ns(now, period, flag.camera, ctx.config().cameras.len());
    let mut tick = turn(now_ns());
    let mut next_status = now_ns();
    while !ctx.shutdown.requested() {
        tick += period;
        sleep_until_ns(tick);
        beat.beat(now_ns());
        if now_ns() > tick + period {
            tick = turn(now_ns()); // fell behind: skip frames rather than burst
        }
        if now_ns() >= next_status {
            next_status = now_ns() + STATUS_PERIOD_NS;
            status.publish(&stamps.status(now_ns()))?;
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
        stamps.published();
        if let Some(p) = skeletons.as_ref() {
            skeleton.published_ns = now_ns();
            p.publish(&skeleton)?;
        }
    }
    status.publish(&stamps.status(now_ns()))?;
    Ok(())
}

/// A recording replayed at the camera's rate: a tick handled late drops the
/// ones it overran (counted as behind), never frames back to back; a file
/// that cannot be read at its turn is dropped (counted as malformed), one
/// line a second.
fn replay(
    ctx: &ServiceContext,
    flag: CameraFlag,
    cfg: &CameraConfig,
    channels: &CameraChannels,
) -> Result<(), Box<dyn Error>> {
    let mut replay = Replay::open(cfg, &ctx.loaded.origin)?;
    let stamps = CameraStamps::new(flag.camera, cfg)?;
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let mut out = CameraOut::new(&node, &channels.depth, stamps)?;
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    let k = *replay.intrinsics();
    let mut ticks = Ticks::new(now_ns(), replay.period_ns());
    let mut unreadable = RateLimited::new(RateLimited::SECOND_NS);
    let mut behind = 0;
    while !ctx.shutdown.requested() {
        sleep_until_ns(ticks.deadline_ns());
        let woke = now_ns();
        beat.beat(woke);
        out.status_tick(woke, false)?;
        // the replay's own work: reading a frame (what follows, its
        // readers at higher priorities on this CPU, is not the replay's)
        let mut worked = now_ns();
        if !replay.done() {
            let mut failed = None;
            out.publish(&k, woke, woke, |px| {
                let read = replay.next_into(px);
                worked = now_ns();
                match read {
                    Some(Ok(())) => Ok(()),
                    Some(Err(e)) => {
                        failed = Some(e);
                        Err(DropCause::Malformed)
                    }
                    None => Err(DropCause::Behind),
                }
            })?;
            if let Some(e) = failed {
                if let Some(n) = unreadable.hit(now_ns()) {
                    tracing::warn!("dropped {e} ({n} unreadable files since the last line)");
                }
            }
        }
        ticks.done(woke, worked);
        out.stamps()
            .count_n(DropCause::Behind, ticks.dropped() - behind);
        behind = ticks.dropped();
    }
    out.status_tick(now_ns(), true)?;
    Ok(())
}
