//! The bridge's loop, one [`Service::step`] at a time: it reads which
//! topics have readers now and then, waits for the robot's next state (or
//! for a batch of them without a `/joint_states` reader), turns what the
//! cell published since the last step into ROS 2 messages ([`Bridge`]) and
//! sends them ([`Topics`]), then takes `/phri/request` into `hri/request`
//! ([`Intake`]) and tells the supervisor what became of it (`ros2/requests`).
//! Wall-clock pacing only ([`Instant`]); the messages' times are phri's
//! clock [ns, CLOCK_MONOTONIC] and ROS time ([`Clock`]).

use std::time::{Duration, Instant};

use phri_ipc::liveness::Beat;
use phri_ipc::{
    BridgeRequests, CollabState, ControlStatus, FrameSubscriber, HriRequest, IpcError, JointState,
    LatestReader, Publisher, RepulsionResult, Residual, Skeleton, Subscriber,
};
use phri_runtime::now_ns;
use ros2_client::Node;

use crate::intake::Intake;
use crate::participant::realtime_ns;
use crate::topics::{Topics, Unsent};
use crate::{report, Bridge, Clock};

/// How often the topics' matched subscribers are read from DDS discovery.
pub const SUBSCRIBED_EVERY: Duration = Duration::from_millis(100);
/// Without a `/joint_states` subscriber, `robot/state` is read in batches
/// this far apart instead of at every state (no 1 kHz wake-ups).
pub const BATCH: Duration = Duration::from_millis(10);
/// With a `/joint_states` subscriber, the longest wait for a robot state
/// (the loop goes on without states).
pub const STATE_WAIT: Duration = Duration::from_millis(20);
/// How often `ros2/requests` tells the supervisor what became of `/phri/request`.
pub const REQUESTS_AUDIT_EVERY: Duration = Duration::from_millis(500);

/// The cell's channels the bridge reads and writes (iceoryx2).
pub struct Ports {
    /// `robot/state`, every state (its subscriber wakes the loop)
    pub states: Subscriber<JointState>,
    /// `control/status`, the newest
    pub control: LatestReader<ControlStatus>,
    /// `collab/state`, the newest
    pub collab: LatestReader<CollabState>,
    /// `dynamics/residual`, the newest
    pub residual: LatestReader<Residual>,
    /// `perception/repulsion`, every worker's results
    pub results: Subscriber<RepulsionResult>,
    /// `perception/depth`, the newest frame
    pub frames: FrameSubscriber,
    /// every camera's `perception/skeleton`, in camera order
    pub skeletons: Vec<Subscriber<Skeleton>>,
    /// `hri/request`: the requests passed from `/phri/request`
    pub requests: Publisher<HriRequest>,
    /// `ros2/requests`: what became of `/phri/request`, for the supervisor
    pub audit: Publisher<BridgeRequests>,
}

/// The bridge with its two sides and the loop's own state.
pub struct Service {
    bridge: Bridge,
    topics: Topics,
    ports: Ports,
    intake: Intake,
    unsent: Unsent,
    /// the sequence number of the last depth frame converted
    last_frame: u64,
    /// when the matched subscribers were last read (`None`: never)
    subscribed_at: Option<Instant>,
    /// when `ros2/requests` was last published
    audited_at: Instant,
}

impl Service {
    /// `bridge` between the cell (`ports`) and ROS 2 (`topics`).
    pub fn new(bridge: Bridge, topics: Topics, ports: Ports) -> Service {
        Service {
            bridge,
            topics,
            ports,
            intake: Intake::default(),
            unsent: Unsent::default(),
            last_frame: 0,
            subscribed_at: None,
            audited_at: Instant::now(),
        }
    }

    /// One turn of the loop; `node` is the ROS 2 node of the topics, `beat`
    /// the service's heartbeat. Only the cell's channels can fail it.
    pub fn step(&mut self, node: &Node, beat: &mut Beat) -> Result<(), IpcError> {
        self.watch_subscribers(node);
        self.wait();
        let now = now_ns();
        beat.beat(now);
        let clock = Clock::new(now, realtime_ns());
        self.states(&clock)?;
        self.summaries(now, &clock)?;
        self.depth(&clock)?;
        self.skeletons(&clock)?;
        // /phri/request: every sample waiting (up to a bound), stops first
        let now = now_ns();
        let (bridge, topics) = (&mut self.bridge, &self.topics);
        self.intake.take(bridge, now, || topics.take_request());
        let requests = &self.ports.requests;
        self.intake.pass(bridge, now, |r| requests.publish(r))?;
        if self.audited_at.elapsed() >= REQUESTS_AUDIT_EVERY {
            self.audited_at = Instant::now();
            self.audit(now)?;
        }
        Ok(())
    }

    /// After the last step: the final `ros2/requests`, and the counts in the log.
    pub fn finish(mut self) -> Result<(), IpcError> {
        self.audit(now_ns())?;
        tracing::info!(
            "{}",
            report::published(&self.bridge.counts, self.unsent.count)
        );
        tracing::info!("{}", report::requests(&self.bridge.counts));
        Ok(())
    }

    /// Every [`SUBSCRIBED_EVERY`], which topics have readers (logged when it changes).
    fn watch_subscribers(&mut self, node: &Node) {
        if self
            .subscribed_at
            .is_some_and(|t| t.elapsed() < SUBSCRIBED_EVERY)
        {
            return;
        }
        self.subscribed_at = Some(Instant::now());
        let was = self.bridge.subscribed;
        self.bridge.subscribed = self.topics.subscribed(node);
        if self.bridge.subscribed != was {
            tracing::info!("subscribed on ROS 2: {:?}", self.bridge.subscribed);
        }
    }

    /// Until the next robot state (at most [`STATE_WAIT`]) when every state
    /// is wanted, else a [`BATCH`] of them.
    fn wait(&self) {
        if self.bridge.subscribed.every_state() {
            // every robot state wakes us; without states, a poll every 20 ms
            let _ = self.ports.states.wait(STATE_WAIT);
        } else {
            std::thread::sleep(BATCH);
            // consume the wake-ups that came meanwhile
            let _ = self.ports.states.wait(Duration::ZERO);
        }
    }

    /// The robot states since the last step: `/joint_states` and `/tf`.
    fn states(&mut self, clock: &Clock) -> Result<(), IpcError> {
        let (bridge, topics, unsent) = (&mut self.bridge, &self.topics, &mut self.unsent);
        self.ports.states.drain(|s| {
            let out = bridge.state(s, clock);
            if let Some(js) = out.joint_state {
                unsent.send(&topics.joint_states, js.clone());
            }
            if let Some(t) = out.tf {
                unsent.send(&topics.tf, t);
            }
        })?;
        Ok(())
    }

    /// The rate-limited summaries at `now` [ns]: `/phri/status`,
    /// `/phri/contact_force` and `/phri/repulsion` (after the repulsion
    /// results since the last step).
    fn summaries(&mut self, now: u64, clock: &Clock) -> Result<(), IpcError> {
        let p = &mut self.ports;
        p.control.update()?;
        p.collab.update()?;
        p.residual.update()?;
        let (control, collab, residual) = (p.control.get(), p.collab.get(), p.residual.get());
        if let Some(m) = self.bridge.status(now, clock, control, collab, residual) {
            self.unsent.send(&self.topics.status, m);
        }
        if let Some(m) = self.bridge.contact_force(now, clock, collab) {
            self.unsent.send(&self.topics.contact_force, m);
        }
        let bridge = &mut self.bridge;
        p.results.drain(|r| bridge.result(r))?;
        if let Some(m) = self.bridge.repulsion(now, clock) {
            self.unsent.send(&self.topics.repulsion, m);
        }
        Ok(())
    }

    /// A new filtered depth frame: `/phri/depth`, `/phri/points` and the
    /// camera's frame on `/tf`.
    fn depth(&mut self, clock: &Clock) -> Result<(), IpcError> {
        let Some(f) = self.ports.frames.latest()? else {
            return Ok(());
        };
        let h = f.user_header();
        if h.seq == self.last_frame {
            return Ok(());
        }
        self.last_frame = h.seq;
        let out = self.bridge.frame(h, f.payload(), clock);
        if let Some(img) = out.image {
            self.unsent.send(&self.topics.depth, img.clone());
        }
        if let Some(pc) = out.points {
            self.unsent.send(&self.topics.points, pc.clone());
        }
        if let Some(t) = out.camera_tf {
            self.unsent.send(&self.topics.tf, t);
        }
        Ok(())
    }

    /// Every camera's skeletons since the last step: `/humans/bodies/tracked`
    /// and the bodies' frames on `/tf`.
    fn skeletons(&mut self, clock: &Clock) -> Result<(), IpcError> {
        let (bridge, topics, unsent) = (&mut self.bridge, &self.topics, &mut self.unsent);
        for (camera, skeleton) in self.ports.skeletons.iter().enumerate() {
            skeleton.drain(|s| {
                let out = bridge.skeleton(camera, s, clock);
                if let Some(m) = out.tracked {
                    unsent.send(&topics.humans, m);
                }
                if let Some(t) = out.tf {
                    unsent.send(&topics.tf, t);
                }
            })?;
        }
        Ok(())
    }

    /// `ros2/requests` at `now` [ns]: the bridge's request counts, with what
    /// `hri/request` did not deliver as dropped.
    fn audit(&mut self, now: u64) -> Result<(), IpcError> {
        let undelivered = self.ports.requests.undelivered();
        self.ports
            .audit
            .publish(&self.bridge.requests_message(now, undelivered))
    }
}
