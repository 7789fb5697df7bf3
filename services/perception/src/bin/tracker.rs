//! `phri-tracker`: the person tracker on depth, one per camera. Takes
//! frames from `camera/depth` (`camera/I/depth` with `--camera I`; any
//! source), removes the robot's own pixels at the joint state nearest the
//! capture time, finds the people with phri-people's model-free tracker
//! ([`DepthTracker`]) and publishes them on `perception/skeleton`
//! (`perception/I/skeleton`) in the robot's base frame, with the frame's
//! sequence number and capture times: one message per frame handled, empty
//! when nobody is in view. The supervisor runs it for a camera whose
//! skeletons come from depth (`[skeleton] source = "depth"`, or a camera
//! that is not simulated).

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::{Queue, Skeleton, Zeroed, ROBOT_STATE};
use phri_perception::{CameraFlag, DepthTracker, RateLimited, StateHistory};
use phri_runtime::{now_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-tracker", body)
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flag) = ServiceContext::from_cli::<CameraFlag>(
        "phri-tracker",
        "tracker",
        "The person tracker on depth: camera/depth → perception/skeleton (people, 15 joints each, robot base frame)",
    )?;
    let config = ctx.config();
    let (camera_cfg, channels) = flag.resolve(config)?;
    let model = ctx.robot_model()?;
    let n = model.nv();
    let mut tracker = DepthTracker::new(model, &config.skeleton, &config.perception, camera_cfg)?;
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let states = ROBOT_STATE.subscriber(&node, Queue::Drain)?;
    let skeletons = channels.skeleton.publisher(&node)?;
    let frames = channels
        .depth
        .waking_frame_subscriber(&node, Queue::Latest)?;
    let mut history = StateHistory::new(n, 2000);
    let mut skeleton = Skeleton::zeroed();
    let mut refused = 0u64;
    let mut log = RateLimited::new(RateLimited::SECOND_NS);
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    while !ctx.shutdown.requested() {
        // wait for the next frame (a wake-up without one just loops)
        let _ = frames.wait(Duration::from_millis(50));
        beat.beat(now_ns());
        states.drain(|s| {
            history.push_state(s);
        })?;
        while let Some(frame) = frames.receive()? {
            let header = *frame.user_header();
            let now = history.newest_ns();
            match tracker.step(&header, frame.payload(), &history, now, &mut skeleton) {
                Ok(_) => {
                    skeleton.published_ns = now_ns();
                    skeletons.publish(&skeleton)?;
                }
                Err(e) => {
                    refused += 1;
                    if let Some(k) = log.hit(now_ns()) {
                        tracing::warn!(
                            "refused {e} ({refused} refused so far, {k} since the last line)"
                        );
                    }
                }
            }
        }
    }
    Ok(())
}
