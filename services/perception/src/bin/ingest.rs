//! `phri-perception`: depth ingestion. Takes frames from `camera/depth`
//! (whatever its source: simulated, a Kinect, a ROS 2 camera, a replay),
//! validates them, removes the robot's own pixels at the joint state nearest the
//! capture time ([`Ingest`]), and publishes `perception/depth` (a loaned
//! `[u16]` slice with a header: sequence, capture time, intrinsics, camera
//! pose, joint state used). While a collaboration is on (`collab/state`) it
//! removes the collaborative hand of the newest `perception/skeleton` from
//! the frame (the paper's Fig. 5) and publishes the hand refined from those
//! pixels on `perception/hand`.
//! `--camera I` serves camera I of `[[camera]]`: `camera/I/depth` in,
//! `perception/I/depth` out; the skeleton it masks by is every camera's
//! merged (a hand either camera sees is masked), and the hand it refines
//! goes out on `perception/I/hand` (the controller takes the first camera's
//! that observes it, `phri_ipc::best_hand`).

use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use phri_config::CollaborationConfig;
use phri_ipc::{
    merge_newest, CollabState, FrameHeader, FramePublisher, HandObservation, IpcError,
    LatestReader, Publisher, Queue, Skeleton, Zeroed, COLLAB_STATE, FRAME_PIXELS, ROBOT_STATE,
};
use phri_perception::mask::{hand_observation, MaskHold};
use phri_perception::{CameraFlag, Ingest, StateHistory};
use phri_runtime::{now_ns, ServiceContext};

/// A camera's skeleton older than this is left out of the merge [ns]
/// (six frames at 30 Hz).
const SKELETON_MAX_AGE_NS: u64 = 200_000_000;

fn main() -> ExitCode {
    phri_runtime::service::run("phri-perception", body)
}

/// Ingestion and what it publishes to.
struct Out {
    ingest: Ingest,
    history: StateHistory,
    frames: FramePublisher,
    refused: u64,
    collab: Option<Collab>,
}

/// What masking the collaborative hand reads and publishes.
struct Collab {
    cfg: CollaborationConfig,
    states: LatestReader<CollabState>,
    /// every camera's body tracker
    skeletons: Vec<LatestReader<Skeleton>>,
    merged: Skeleton,
    /// where the refined hand goes (this camera's channel)
    hands: Publisher<HandObservation>,
    hold: MaskHold,
}

impl Out {
    /// Ingest one frame into a loaned sample and publish it; a refused frame
    /// is counted and logged (rate-limited), not an error.
    /// `arrived_ns`: when the frame arrived here [ns, CLOCK_MONOTONIC].
    fn handle(
        &mut self,
        header: &mut FrameHeader,
        input: &[u16],
        arrived_ns: u64,
    ) -> Result<(), IpcError> {
        let mut sample = self.frames.loan(input.len())?;
        let now = self.history.newest_ns();
        // the collaborative hand, while a collaboration is on
        let mut masking = None;
        if let Some(c) = self.collab.as_mut() {
            c.states.update()?;
            let mono = now_ns();
            let mut views = [None; phri_ipc::MAX_CAMERAS];
            for (v, r) in views.iter_mut().zip(c.skeletons.iter_mut()) {
                r.update()?;
                // a dead camera's last skeleton says nothing of now
                *v = r
                    .get()
                    .filter(|s| mono.saturating_sub(s.published_ns) <= SKELETON_MAX_AGE_NS);
            }
            let any = merge_newest(&views, SKELETON_MAX_AGE_NS, &mut c.merged);
            // a stale state (its controller stopped or dead) masks nothing
            let part = phri_perception::mask::collaborating_part(c.states.get(), now_ns());
            masking = c
                .hold
                .mask(any.then_some(&c.merged), part, &c.cfg, header.capture_ns)
                .zip(part)
                .map(|(m, p)| (p, m));
        }
        self.ingest.set_mask(masking.map(|(_, m)| m));
        match self
            .ingest
            .step(header, input, &self.history, now, sample.payload_mut())
        {
            Ok(outcome) => {
                header.published_ns = now_ns();
                header.ingest_ns = saturating_u32(header.published_ns.saturating_sub(arrived_ns));
                *sample.user_header_mut() = *header;
                self.frames.send(sample)?;
                if let (Some(c), Some((part, mask))) = (self.collab.as_ref(), masking) {
                    let h = hand_observation(header, part, &mask, &outcome.masked, now_ns());
                    c.hands.publish(&h)?;
                }
            }
            Err(e) => {
                self.refused += 1;
                if self.refused.is_power_of_two() {
                    tracing::warn!("refused {e} ({} refused so far)", self.refused);
                }
            }
        }
        Ok(())
    }
}

fn body() -> Result<(), Box<dyn Error>> {
    let (ctx, flag) = ServiceContext::from_cli::<CameraFlag>(
        "phri-perception",
        "perception",
        "Depth ingestion: filters camera/depth, removes the robot, publishes perception/depth, the skeleton and the hand",
    )?;
    let cfg = &ctx.config().perception;
    let (camera_cfg, channels) = flag.resolve(ctx.config())?;
    let model = ctx.robot_model()?;
    let n = model.nv();
    let ingest = Ingest::new(model, cfg)?;
    if ctx.checking() {
        return Ok(());
    }
    let node = ctx.node()?;
    let states = ROBOT_STATE.subscriber(&node, Queue::Drain)?;
    let pixels_max = camera_cfg.intrinsics.pixel_count().max(FRAME_PIXELS);
    let mut out = Out {
        ingest,
        history: StateHistory::new(n, 2000),
        frames: channels.perception.frame_publisher(&node, pixels_max)?,
        refused: 0,
        collab: match ctx.config().collaboration.enabled {
            true => Some(Collab {
                cfg: ctx.config().collaboration.clone(),
                states: COLLAB_STATE.latest_reader(&node)?,
                skeletons: phri_ipc::cameras(ctx.config().cameras.len())
                    .iter()
                    .map(|c| c.skeleton.latest_reader(&node))
                    .collect::<Result<_, _>>()?,
                merged: Skeleton::zeroed(),
                hands: channels.hand.publisher(&node)?,
                hold: MaskHold::default(),
            }),
            false => None,
        },
    };
    let frames = channels
        .depth
        .waking_frame_subscriber(&node, Queue::Latest)?;
    ctx.start_deadman()?;
    let mut beat = ctx.beat(&node)?;
    ctx.go_realtime();
    while !ctx.shutdown.requested() {
        // wait for the next frame (a wake-up without one just loops)
        let _ = frames.wait(Duration::from_millis(50));
        beat.beat(now_ns());
        states.drain(|s| {
            out.history.push_state(s);
        })?;
        while let Some(frame) = frames.receive()? {
            let arrived = now_ns();
            let mut header = *frame.user_header();
            out.handle(&mut header, frame.payload(), arrived)?;
        }
    }
    Ok(())
}

/// `ns` as a u32, saturating (4.29 s).
fn saturating_u32(ns: u64) -> u32 {
    u32::try_from(ns).unwrap_or(u32::MAX)
}
