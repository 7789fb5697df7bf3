//! `phri-freenect`: a Kinect v1 through libfreenect as the cell's camera
//! (`[camera] source = "freenect"`, the Kinect `device_index`). Each raw
//! 11-bit disparity frame becomes millimetres written straight into a
//! loaned `camera/depth` sample, with the Kinect's nominal intrinsics and
//! its capture time mapped from the device's timestamp; `camera/status`
//! counts frames and drops. Frames wait with a 50 ms timeout, so the
//! heartbeat beats whether or not the camera sends: a stream that stops
//! (fakenect at the end of its recording, a stalled USB link) is no crash.
//! No Kinect at that index, or no frame within 5 s of the start, is an error
//! in one line naming the device.

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_freenect::{
    Device, Disparity, FreenectError, TimestampMapper, FIRST_FRAME_TIMEOUT_S, KINECT_DEPTH,
};
use phri_perception::live::{CameraOut, CameraStamps, DropCause};
use phri_perception::CameraFlag;
use phri_runtime::{now_ns, ServiceContext};

/// The longest wait for a frame in one loop turn (the heartbeat's pace).
const WAIT: Duration = Duration::from_millis(50);
/// After failed event processing, the longest pause before trying again [ns].
const MAX_BACKOFF_NS: u64 = 1_000_000_000;

fn main() -> ExitCode {
    phri_runtime::service::run("phri-freenect", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flag) = ServiceContext::from_cli::<CameraFlag>(
        "phri-freenect",
        "camera",
        "A Kinect v1 through libfreenect: its depth frames in millimetres on camera/depth",
    )?;
    let (cfg, channels) = flag.resolve(ctx.config())?;
    let stamps = CameraStamps::new(flag.camera, cfg)?;
    let k = KINECT_DEPTH;
    let table = Disparity::new();
    if ctx.checking() {
        return Ok(());
    }
    let index = cfg.device_index;
    let mut device = Device::open(index)?;
    let node = ctx.node()?;
    let mut out = CameraOut::new(&node, &channels.depth, stamps)?;
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    let start = now_ns();
    // frames libfreenect delivered that a newer one replaced before this loop took them
    let mut overwritten = 0;
    let mut mapper = TimestampMapper::new();
    let mut frames = 0u64;
    // failed event processing: no retry before `pause_until`
    let (mut pause_until, mut backoff_ns) = (0u64, 0u64);
    let mut failures = 0u64;
    while !ctx.shutdown.requested() {
        let now = now_ns();
        beat.beat(now);
        out.status_tick(now, false)?;
        if frames == 0 && now.saturating_sub(start) > FIRST_FRAME_TIMEOUT_S * 1_000_000_000 {
            return Err(FreenectError::NeverAnswered {
                index,
                seconds: FIRST_FRAME_TIMEOUT_S,
            }
            .into());
        }
        if now < pause_until {
            std::thread::sleep(WAIT.min(Duration::from_nanos(pause_until - now)));
            continue;
        }
        match device.next_frame(WAIT) {
            Ok(frame) => {
                frames += 1;
                backoff_ns = 0;
                let capture = mapper.map(frame.timestamp, frame.callback_mono_ns);
                out.publish(&k, capture.mono_ns, now_ns(), |px| {
                    table
                        .frame_to_mm(&frame.raw, px)
                        .map_err(|_| DropCause::Malformed)
                })?;
                device.recycle(frame);
                let behind = device.overwritten();
                out.stamps()
                    .count_n(DropCause::Behind, behind.saturating_sub(overwritten));
                overwritten = behind;
            }
            Err(FreenectError::Timeout { .. }) => {}
            Err(e @ FreenectError::Events { .. }) => {
                // a stalled link, or fakenect past its recording: keep
                // beating, retry less and less often (up to once a second)
                failures += 1;
                if failures == 1 || failures.is_power_of_two() {
                    tracing::warn!("{e} ({failures} times so far)");
                }
                backoff_ns = (backoff_ns * 2).clamp(WAIT.as_nanos() as u64, MAX_BACKOFF_NS);
                pause_until = now_ns() + backoff_ns;
            }
            Err(e) => return Err(e.into()),
        }
    }
    out.status_tick(now_ns(), true)?;
    tracing::info!(
        "{frames} frames from freenect device {index}, {} overwritten unread, {} timestamp restarts",
        device.overwritten(),
        mapper.restarts()
    );
    Ok(())
}
