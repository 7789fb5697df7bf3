//! The supervisor's ports on the cell's channels: the health it publishes
//! (and its beat), the samples the report is built from, the operator's
//! requests; and the watched services' liveness.

use phri_ipc::liveness::{self, Beat, Watched};
use phri_ipc::{
    FrameSubscriber, Health, IpcError, IpcNode, Publisher, Queue, Subscriber, Zeroed, COLLAB_STATE,
    CONTROL_BARRIER, CONTROL_SSM, CONTROL_STATUS, DYNAMICS_RESIDUAL, ROBOT_STATS, SIM_CONTACTS,
    SIM_TRUTH, SUPERVISOR_HEALTH,
};

use super::ordered::Ordered;
use crate::evaluation::Evaluation;
use crate::Roster;

/// The supervisor's ports on the cell's channels.
pub struct Ports {
    health: Publisher<Health>,
    health_more: Publisher<Health>,
    /// the two pages of the health
    pages: [Health; 2],
    stats: Subscriber<phri_ipc::RobotStats>,
    truth: Subscriber<phri_ipc::Truth>,
    contacts: Subscriber<phri_ipc::ContactEvent>,
    residual: Subscriber<phri_ipc::Residual>,
    /// the controller in charge's, in publication order (two take turns)
    status: Ordered<phri_ipc::ControlStatus>,
    /// per camera: its frames, its ingestion's, its repulsion results
    frames: Vec<FrameSubscriber>,
    filtered: Vec<FrameSubscriber>,
    repulsion: Vec<Subscriber<phri_ipc::RepulsionResult>>,
    /// per camera: its skeletons (their latency from the frame's arrival)
    skeletons: Vec<Subscriber<phri_ipc::Skeleton>>,
    collab: Ordered<phri_ipc::CollabState>,
    ssm: Ordered<phri_ipc::SsmStatus>,
    barrier: Ordered<phri_ipc::BarrierStatus>,
    requests: Subscriber<phri_ipc::HriRequest>,
    /// what the ROS 2 bridge did with `/phri/request`
    bridge_requests: Subscriber<phri_ipc::BridgeRequests>,
    /// what each camera's and the microphone's process did
    camera_status: Subscriber<phri_ipc::CameraStatus>,
    mic_status: Subscriber<phri_ipc::MicStatus>,
    utterances: Subscriber<phri_ipc::Utterance>,
    audits: Subscriber<phri_ipc::InputAudit>,
    boxes: Subscriber<phri_ipc::BoxStatus>,
    /// the adapter's takeovers
    commanders: Subscriber<phri_ipc::CommanderStats>,
    /// the supervisor's beats (`liveness/supervisor`), one with each health:
    /// what the services' dead-man watches
    beat: Beat,
    standby_residual: Subscriber<phri_ipc::Residual>,
}

impl Ports {
    /// Open every port, for `cameras` cameras.
    pub fn open(node: &IpcNode, cameras: usize) -> Result<Ports, IpcError> {
        let cameras = phri_ipc::cameras(cameras);
        Ok(Ports {
            health: SUPERVISOR_HEALTH.publisher(node)?,
            health_more: phri_ipc::SUPERVISOR_HEALTH_MORE.publisher(node)?,
            pages: [Health::zeroed(); 2],
            stats: ROBOT_STATS.subscriber(node, Queue::Drain)?,
            truth: SIM_TRUTH.subscriber(node, Queue::Drain)?,
            contacts: SIM_CONTACTS.subscriber(node, Queue::Drain)?,
            residual: DYNAMICS_RESIDUAL.subscriber(node, Queue::Drain)?,
            status: Ordered::new(CONTROL_STATUS.subscriber(node, Queue::Drain)?, |m| {
                m.stamp_ns
            }),
            frames: cameras
                .iter()
                .map(|c| c.depth.frame_subscriber(node, Queue::Latest))
                .collect::<Result<_, _>>()?,
            filtered: cameras
                .iter()
                .map(|c| c.perception.frame_subscriber(node, Queue::Latest))
                .collect::<Result<_, _>>()?,
            repulsion: cameras
                .iter()
                .map(|c| c.repulsion.subscriber(node, Queue::Drain))
                .collect::<Result<_, _>>()?,
            skeletons: cameras
                .iter()
                .map(|c| c.skeleton.subscriber(node, Queue::Drain))
                .collect::<Result<_, _>>()?,
            collab: Ordered::new(COLLAB_STATE.subscriber(node, Queue::Drain)?, |m| m.stamp_ns),
            ssm: Ordered::new(CONTROL_SSM.subscriber(node, Queue::Drain)?, |m| m.stamp_ns),
            barrier: Ordered::new(CONTROL_BARRIER.subscriber(node, Queue::Drain)?, |m| {
                m.stamp_ns
            }),
            requests: phri_ipc::HRI_REQUEST.subscriber(node, Queue::Drain)?,
            bridge_requests: phri_ipc::ROS2_REQUESTS.subscriber(node, Queue::Drain)?,
            camera_status: phri_ipc::CAMERA_STATUS.subscriber(node, Queue::Drain)?,
            mic_status: phri_ipc::AUDIO_MIC_STATUS.subscriber(node, Queue::Drain)?,
            utterances: phri_ipc::VOICE_UTTERANCE.subscriber(node, Queue::Drain)?,
            audits: phri_ipc::INPUT_AUDIT.subscriber(node, Queue::Drain)?,
            boxes: phri_ipc::ROBOT_BOX.subscriber(node, Queue::Drain)?,
            commanders: phri_ipc::ROBOT_COMMANDERS.subscriber(node, Queue::Drain)?,
            standby_residual: phri_ipc::DYNAMICS_RESIDUAL_STANDBY.subscriber(node, Queue::Drain)?,
            beat: Beat::create(node, liveness::SUPERVISOR)?,
        })
    }

    /// How many cameras the ports read.
    pub fn cameras(&self) -> usize {
        self.frames.len()
    }

    /// Publish the roster's health (`supervisor/health`, and
    /// `supervisor/health/more` past its first page) and beat with it (the
    /// services wake for it).
    pub fn publish_health(&mut self, roster: &Roster, now_ns: u64) {
        let pages = &mut self.pages;
        roster.fill_health(&mut pages[0], now_ns);
        if roster.fill_health_more(&mut pages[1], now_ns) {
            let _ = self.health_more.publish(&pages[1]);
        }
        let _ = self.health.publish(&pages[0]);
        self.beat.now(now_ns);
    }

    /// A round's first reading: the robot, contacts, the collaboration, the
    /// protective separation, the barrier filter, the commanders.
    pub fn read_robot(&mut self, ev: &mut Evaluation) -> Result<(), IpcError> {
        self.stats.drain(|m| ev.eval.on_stats(m))?;
        self.contacts.drain(|m| ev.eval.on_contact_event(m))?;
        self.collab.drain(|m| {
            if m.request_kind == phri_ipc::RequestKind::Stop as u32 && m.request_accepted != 0 {
                let source = phri_ipc::RequestSource::name_of(m.request_source);
                ev.eval.stop_requested_by(source, m.request_seq);
            }
            ev.collab.on_state(m);
        })?;
        self.ssm.drain(|m| ev.eval.on_ssm(m))?;
        self.barrier.drain(|m| ev.on_barrier(m))?;
        self.commanders.drain(|m| {
            ev.standby.on_commanders(m, ev.eval.time_s(m.stamp_ns));
            ev.boxes.on_commanders(m);
        })?;
        Ok(())
    }

    /// A round's requests and the sensors' and box's status: whether an
    /// operator asked to resume.
    pub fn read_requests(&mut self, ev: &mut Evaluation) -> Result<bool, IpcError> {
        let mut resume = false;
        self.requests.drain(|m| {
            resume |= m.kind == phri_ipc::RequestKind::Resume as u32;
            ev.collab.on_request(m);
        })?;
        self.bridge_requests.drain(|m| ev.collab.on_bridge(m))?;
        self.camera_status.drain(|m| ev.eval.on_camera_status(m))?;
        self.mic_status.drain(|m| ev.eval.on_mic_status(m))?;
        self.audits.drain(|m| ev.audits.on_audit(m))?;
        self.boxes.drain(|m| ev.boxes.on_box(m))?;
        Ok(resume)
    }

    /// A round's last reading: utterances, truth, residuals, the
    /// controller's status, and per camera its frames and results.
    pub fn read_rest(&mut self, ev: &mut Evaluation) -> Result<(), IpcError> {
        self.utterances.drain(|m| ev.collab.on_utterance(m))?;
        self.truth.drain(|m| {
            ev.eval.on_truth(m);
            ev.collab.on_truth(m);
        })?;
        self.residual.drain(|m| {
            ev.eval.on_residual(m);
            ev.residuals.on_residual(0, m);
        })?;
        self.standby_residual
            .drain(|m| ev.residuals.on_residual(1, m))?;
        let reaction = ev.reaction;
        self.status.drain(|m| ev.eval.on_status(m, reaction))?;
        for camera in 0..self.frames.len() {
            let (Some(frames), Some(filtered), Some(results)) = (
                self.frames.get(camera),
                self.filtered.get(camera),
                self.repulsion.get(camera),
            ) else {
                break;
            };
            while let Some(f) = frames.receive()? {
                ev.eval.on_frame(camera, f.user_header());
            }
            while let Some(f) = filtered.receive()? {
                ev.eval.on_filtered(camera, f.user_header());
            }
            results.drain(|m| ev.eval.on_repulsion(camera, m))?;
            if let Some(skeletons) = self.skeletons.get(camera) {
                skeletons.drain(|m| ev.eval.on_skeleton(camera, m))?;
            }
        }
        Ok(())
    }

    /// What arrived in the last period, read before anything is stopped
    /// (errors ignored: the run is over).
    pub fn read_last(&mut self, ev: &mut Evaluation) {
        let _ = self.contacts.drain(|m| ev.eval.on_contact_event(m));
        let _ = self.collab.drain(|m| ev.collab.on_state(m));
        let _ = self.ssm.drain(|m| ev.eval.on_ssm(m));
        let _ = self.barrier.drain(|m| ev.on_barrier(m));
        let _ = self.requests.drain(|m| ev.collab.on_request(m));
        let _ = self.bridge_requests.drain(|m| ev.collab.on_bridge(m));
        let _ = self.camera_status.drain(|m| ev.eval.on_camera_status(m));
        let _ = self.mic_status.drain(|m| ev.eval.on_mic_status(m));
        let _ = self.utterances.drain(|m| ev.collab.on_utterance(m));
        let _ = self.truth.drain(|m| {
            ev.eval.on_truth(m);
            ev.collab.on_truth(m);
        });
        let _ = self.residual.drain(|m| ev.eval.on_residual(m));
        let reaction = ev.reaction;
        let _ = self.status.drain(|m| ev.eval.on_status(m, reaction));
        let _ = self.stats.drain(|m| ev.eval.on_stats(m));
    }

    /// What the services said last, as they stopped (the simulator's
    /// contacts as it braked, the takeovers, the refused inputs, the box).
    pub fn read_after_stop(&mut self, ev: &mut Evaluation) {
        let _ = self.commanders.drain(|m| {
            ev.standby.on_commanders(m, ev.eval.time_s(m.stamp_ns));
            ev.boxes.on_commanders(m);
        });
        let _ = self.contacts.drain(|m| ev.eval.on_contact_event(m));
        let _ = self.audits.drain(|m| ev.audits.on_audit(m));
        let _ = self.boxes.drain(|m| ev.boxes.on_box(m));
    }
}

/// The watched services' liveness (`liveness/<service>`, each created with
/// its deadline before the service starts): the supervisor hears of beats,
/// deaths and missed deadlines through one WaitSet ([`liveness::Vigil`]).
pub struct Liveness {
    /// per watched service: its liveness service
    pub watched: Vec<Watched>,
    /// roster index of each watched service
    pub index: Vec<usize>,
}

impl Liveness {
    /// Create the liveness service of every watched service of `roster`.
    pub fn open(node: &IpcNode, roster: &Roster) -> Result<Liveness, IpcError> {
        let (mut watched, mut index) = (Vec::new(), Vec::new());
        for (i, deadline) in roster.deadlines() {
            watched.push(Watched::create(node, &roster.get(i).name, deadline)?);
            index.push(i);
        }
        Ok(Liveness { watched, index })
    }
}
