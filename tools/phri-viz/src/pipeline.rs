//! From the cell's messages to Foxglove's, at their rates: the latest message
//! of each channel is kept; each joint state may give a `foxglove.JointStates`
//! and a status (at most at the joint rate, by the robot's clock); a tick
//! gives the scene and the frames (at the scene rate) and the newest depth
//! frame as a point cloud and an image (at most at the scene rate).
//!
//! With a staleness bound ([`Pipeline::with_stale_after`]) the scene is only
//! sent while the robot's state keeps coming: when none arrived for that
//! long (by the clock `tick` is given), no scene or frame goes out stamped as
//! current; a status saying `stale`, with the state's age, goes out a few
//! times a second instead, until states come again. No I/O:
//! `phri-viz` logs the outputs to its WebSocket server, `phri-record` writes
//! them into its MCAP file.

use std::any::Any;

use foxglove::messages::{
    FrameTransforms, JointState as FgJoint, JointStates, PointCloud, RawImage, SceneUpdate,
};
use foxglove::Encode;
use phri_config::Loaded;
use phri_ipc::{
    CollabPart, CollabPhase, CollabState, ControlStatus, FrameHeader, HandObservation, JointState,
    RepulsionResult, Residual, WorldState, MAX_DOF,
};

use crate::geometry::timestamp;
use crate::status::{Status, StatusMessage, Thresholds};
use crate::{depth, scene, topics, VizError};
use phri_view::RobotView;

/// How often each kind of output is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    /// scene, frames, depth \[Hz\]
    pub scene_hz: f64,
    /// joint states and status \[Hz\] (by the robot's clock; ≥ its rate: every state)
    pub joints_hz: f64,
    /// the depth image keeps every k-th pixel per axis
    pub depth_downsample: usize,
    /// the point cloud keeps every k-th pixel per axis
    pub cloud_downsample: usize,
}

impl Default for Rates {
    fn default() -> Rates {
        Rates {
            scene_hz: 30.0,
            joints_hz: 250.0,
            depth_downsample: 2,
            cloud_downsample: 4,
        }
    }
}

/// Results older than this are no longer shown \[ns\]: a stopped worker's arrows vanish.
pub const REPULSION_MAX_AGE_NS: u64 = 500_000_000;
/// Time between two stale statuses \[ns\].
pub const STALE_STATUS_EVERY_NS: u64 = 250_000_000;

/// One Foxglove message.
#[derive(Clone, Debug, PartialEq)]
pub enum VizMessage {
    Scene(SceneUpdate),
    Transforms(FrameTransforms),
    Cloud(PointCloud),
    Image(RawImage),
    Joints(JointStates),
    Status(Status),
}

impl VizMessage {
    /// The message in its topic's encoding (protobuf; JSON for the status), appended to `buf`.
    pub fn encode(&self, buf: &mut Vec<u8>) -> Result<(), EncodeError> {
        fn pb<E: std::fmt::Display>(e: E) -> EncodeError {
            EncodeError::Protobuf(e.to_string())
        }
        match self {
            VizMessage::Scene(m) => m.encode(buf).map_err(pb),
            VizMessage::Transforms(m) => m.encode(buf).map_err(pb),
            VizMessage::Cloud(m) => m.encode(buf).map_err(pb),
            VizMessage::Image(m) => m.encode(buf).map_err(pb),
            VizMessage::Joints(m) => m.encode(buf).map_err(pb),
            VizMessage::Status(m) => StatusMessage(m).encode(buf).map_err(EncodeError::Json),
        }
    }
}

/// A message that could not be encoded.
#[derive(Debug, thiserror::Error)]
pub enum EncodeError {
    #[error("protobuf: {0}")]
    Protobuf(String),
    #[error("json: {0}")]
    Json(#[from] serde_json::Error),
}

/// One output: the topic ([`topics::ALL`]), its log time [ns, CLOCK_MONOTONIC], the message.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    pub topic: &'static str,
    pub log_ns: u64,
    pub message: VizMessage,
}

/// The latest message of each channel the scene is made of.
#[derive(Default)]
struct Latest {
    state: Option<JointState>,
    world: Option<WorldState>,
    /// per worker, its newest result
    repulsion: Vec<RepulsionResult>,
    collab: Option<CollabState>,
    control: Option<ControlStatus>,
    residual: Option<Residual>,
    hand: Option<HandObservation>,
    /// the newest depth frame's header (the camera's pose)
    camera: Option<FrameHeader>,
}

/// The scene builder with its rates (see the module's doc).
pub struct Pipeline {
    view: RobotView,
    thresholds: Thresholds,
    point_names: Vec<String>,
    rates: Rates,
    latest: Latest,
    /// robot clock of the last joint state forwarded [ns]
    last_joints_ns: Option<u64>,
    /// when the next scene is due [ns, CLOCK_MONOTONIC]
    next_scene_ns: u64,
    next_depth_ns: u64,
    /// the newest depth frame not yet sent: header and depths
    frame: Option<FrameHeader>,
    depths: Vec<u16>,
    /// a robot state came since the last tick
    state_came: bool,
    /// the tick that saw the newest robot state [ns, tick's clock]
    state_seen_ns: Option<u64>,
    /// no robot state for longer than this: stale [ns] (None: never stale)
    stale_after_ns: Option<u64>,
    /// stale at the last tick
    stale: bool,
    next_stale_status_ns: u64,
}

impl Pipeline {
    /// A pipeline for `view`'s robot; `point_names[i]` names control point `i`.
    pub fn new(
        view: RobotView,
        thresholds: Thresholds,
        point_names: Vec<String>,
        rates: Rates,
    ) -> Pipeline {
        Pipeline {
            view,
            thresholds,
            point_names,
            rates,
            latest: Latest::default(),
            last_joints_ns: None,
            next_scene_ns: 0,
            next_depth_ns: 0,
            frame: None,
            depths: Vec::new(),
            state_came: false,
            state_seen_ns: None,
            stale_after_ns: None,
            stale: false,
            next_stale_status_ns: 0,
        }
    }

    /// Stale when no robot state came for `after` (None, the default: never;
    /// a recording of a past run ticks on its own clock).
    pub fn with_stale_after(mut self, after: Option<std::time::Duration>) -> Pipeline {
        self.stale_after_ns = after.map(|d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        self
    }

    /// Whether the last tick found the robot's state stale.
    pub fn is_stale(&self) -> bool {
        self.stale
    }

    /// Time since the tick that saw the newest robot state, at `now_ns` \[ns\]
    /// (None: no state yet).
    pub fn input_age_ns(&self, now_ns: u64) -> Option<u64> {
        self.state_seen_ns.map(|t| now_ns.saturating_sub(t))
    }

    /// A pipeline from a loaded configuration: its robot model, `[dynamics]`
    /// thresholds and `[[repulsion.points]]` names.
    pub fn from_config(loaded: &Loaded, rates: Rates) -> Result<Pipeline, VizError> {
        let model = loaded.model()?;
        let n = model.nv();
        let d = &loaded.config.dynamics;
        let thresholds = Thresholds {
            contact: d
                .contact_threshold
                .resolve(n, "dynamics.contact_threshold")?,
            collision: d
                .collision_threshold
                .resolve(n, "dynamics.collision_threshold")?,
            collision_norm: d.collision_norm_threshold,
        };
        let names = loaded
            .config
            .repulsion
            .points
            .iter()
            .map(|p| p.name.clone())
            .collect();
        Ok(Pipeline::new(
            RobotView::new(model),
            thresholds,
            names,
            rates,
        ))
    }

    /// The robot's joints, in the messages' order.
    pub fn joint_names(&self) -> &[String] {
        self.view.joint_names()
    }

    /// Take in one message of the cell (any type: those the scene is not made
    /// of are ignored). A joint state due at the joint rate adds the joint
    /// states and the status to `out`, if `wanted` says a client wants them.
    pub fn offer<T: Any>(&mut self, msg: &T, wanted: &dyn Fn(&str) -> bool, out: &mut Vec<Output>) {
        let m = msg as &dyn Any;
        if let Some(s) = m.downcast_ref::<JointState>() {
            self.on_state(s, wanted, out);
        } else if let Some(w) = m.downcast_ref::<WorldState>() {
            self.latest.world = Some(*w);
        } else if let Some(r) = m.downcast_ref::<RepulsionResult>() {
            let slot = self
                .latest
                .repulsion
                .iter_mut()
                .find(|x| x.worker == r.worker);
            match slot {
                Some(x) => *x = *r,
                None => self.latest.repulsion.push(*r),
            }
        } else if let Some(c) = m.downcast_ref::<CollabState>() {
            self.latest.collab = Some(*c);
        } else if let Some(c) = m.downcast_ref::<ControlStatus>() {
            self.latest.control = Some(*c);
        } else if let Some(r) = m.downcast_ref::<Residual>() {
            self.latest.residual = Some(*r);
        } else if let Some(h) = m.downcast_ref::<HandObservation>() {
            self.latest.hand = Some(*h);
        }
    }

    /// Take in a filtered depth frame (`perception/depth`): the newest one is
    /// sent at the next tick due.
    pub fn offer_frame(&mut self, header: &FrameHeader, depths: &[u16]) {
        self.latest.camera = Some(*header);
        self.frame = Some(*header);
        self.depths.clear();
        self.depths.extend_from_slice(depths);
    }

    fn on_state(&mut self, s: &JointState, wanted: &dyn Fn(&str) -> bool, out: &mut Vec<Output>) {
        self.latest.state = Some(*s);
        self.state_came = true;
        let period_ns = (1e9 / self.rates.joints_hz.max(1e-3)) as u64;
        // a little early still counts: the robot's clock ticks exactly, the rate need not divide it
        let due = match self.last_joints_ns {
            Some(last) => s.stamp_ns < last || s.stamp_ns - last + period_ns / 10 >= period_ns,
            None => true,
        };
        if !due {
            return;
        }
        self.last_joints_ns = Some(s.stamp_ns);
        let t = if s.published_ns > 0 {
            s.published_ns
        } else {
            s.stamp_ns
        };
        if wanted(topics::JOINTS) {
            out.push(Output {
                topic: topics::JOINTS,
                log_ns: t,
                message: VizMessage::Joints(self.joint_states(s)),
            });
        }
        if wanted(topics::STATUS) {
            let l = &self.latest;
            out.push(Output {
                topic: topics::STATUS,
                log_ns: t,
                message: VizMessage::Status(Status {
                    input_age: Some(0.0),
                    ..Status::from_latest(
                        l.control.as_ref(),
                        l.collab.as_ref(),
                        l.residual.as_ref(),
                        &self.thresholds,
                    )
                }),
            });
        }
    }

    /// `foxglove.JointStates` of a joint state: position [rad] and applied
    /// torque [Nm]; velocity [rad/s] from the latest residual's estimate when
    /// there is one.
    fn joint_states(&self, s: &JointState) -> JointStates {
        let n = (s.dof as usize)
            .min(MAX_DOF)
            .min(self.view.joint_names().len());
        let qd = self.latest.residual.as_ref().map(|r| r.qd);
        let joints = (0..n)
            .map(|i| FgJoint {
                name: self.view.joint_names()[i].clone(),
                position: Some(s.q[i]),
                velocity: qd.map(|v| v[i]),
                acceleration: None,
                effort: Some(s.tau[i]),
            })
            .collect();
        JointStates {
            timestamp: Some(timestamp(if s.published_ns > 0 {
                s.published_ns
            } else {
                s.stamp_ns
            })),
            joints,
        }
    }

    /// At `now_ns` \[CLOCK_MONOTONIC\]: the scene and the frames when due (the
    /// scene needs a joint state), and the newest depth frame when one came;
    /// when the robot's state is stale, a stale status instead of the scene.
    pub fn tick(&mut self, now_ns: u64, wanted: &dyn Fn(&str) -> bool, out: &mut Vec<Output>) {
        let period_ns = (1e9 / self.rates.scene_hz.max(1e-3)) as u64;
        if std::mem::take(&mut self.state_came) {
            self.state_seen_ns = Some(now_ns);
        }
        if let Some(after) = self.stale_after_ns {
            let age = self.input_age_ns(now_ns);
            if age.is_none_or(|a| a > after) {
                if !self.stale || now_ns >= self.next_stale_status_ns {
                    self.next_stale_status_ns = now_ns + STALE_STATUS_EVERY_NS;
                    if wanted(topics::STATUS) {
                        out.push(Output {
                            topic: topics::STATUS,
                            log_ns: now_ns,
                            message: VizMessage::Status(self.stale_status(age)),
                        });
                    }
                }
                self.stale = true;
                // a frame of a camera still running is its own time's
                if self.frame.is_some() && now_ns >= self.next_depth_ns {
                    self.next_depth_ns = now_ns + period_ns * 9 / 10;
                    self.depth(wanted, out);
                }
                return;
            }
            if self.stale {
                // back: the scene at once
                self.stale = false;
                self.next_scene_ns = now_ns;
            }
        }
        if now_ns >= self.next_scene_ns {
            self.next_scene_ns = if now_ns > self.next_scene_ns + period_ns {
                now_ns + period_ns // behind (a stall): start afresh
            } else {
                self.next_scene_ns + period_ns
            };
            self.scene(now_ns, wanted, out);
        }
        if self.frame.is_some() && now_ns >= self.next_depth_ns {
            self.next_depth_ns = now_ns + period_ns * 9 / 10;
            self.depth(wanted, out);
        }
    }

    fn scene(&mut self, t: u64, wanted: &dyn Fn(&str) -> bool, out: &mut Vec<Output>) {
        let l = &self.latest;
        let collab_on = l
            .collab
            .as_ref()
            .filter(|c| c.phase != CollabPhase::Idle as u32);
        let collab_link = collab_on
            .and_then(|c| usize::try_from(c.robot_frame).ok())
            .and_then(|i| self.view.model().frames.get(i))
            .map(|f| f.name.clone());
        let collab_part = collab_on
            .and_then(|c| CollabPart::try_from(c.human_part).ok())
            .and_then(CollabPart::body_part);
        let mut push = |topic: &'static str, message: VizMessage| {
            out.push(Output {
                topic,
                log_ns: t,
                message,
            })
        };
        if let Some(s) = l.state {
            // posed even when nobody watches the robot: the frames need the pose
            let robot = scene::robot(&mut self.view, &s, collab_link.as_deref(), t);
            if wanted(topics::ROBOT) {
                push(topics::ROBOT, VizMessage::Scene(robot));
            }
        }
        let l = &self.latest;
        if wanted(topics::PERSON) {
            let person = match &l.world {
                Some(w) => scene::person(w, collab_part, t),
                None => scene::replace_all(t, Vec::new()),
            };
            push(topics::PERSON, VizMessage::Scene(person));
        }
        if wanted(topics::REPULSION) {
            let fresh: Vec<RepulsionResult> = l
                .repulsion
                .iter()
                .filter(|r| r.published_ns + REPULSION_MAX_AGE_NS >= t)
                .copied()
                .collect();
            push(
                topics::REPULSION,
                VizMessage::Scene(scene::repulsion(&fresh, &self.point_names, t)),
            );
        }
        if wanted(topics::COLLAB) {
            push(
                topics::COLLAB,
                VizMessage::Scene(scene::collab(l.collab.as_ref(), l.hand.as_ref(), t)),
            );
        }
        if wanted(topics::TF) {
            let tf = scene::transforms(&self.view, l.camera.as_ref(), t);
            if !tf.transforms.is_empty() {
                push(topics::TF, VizMessage::Transforms(tf));
            }
        }
    }

    /// The status of a stale cell: stale, the state's age [s], nothing of
    /// the controller (what it said last is not what it says now).
    fn stale_status(&self, age_ns: Option<u64>) -> Status {
        Status {
            stale: true,
            input_age: age_ns.map(|a| a as f64 * 1e-9),
            ..Status::from_latest(None, None, None, &self.thresholds)
        }
    }

    fn depth(&mut self, wanted: &dyn Fn(&str) -> bool, out: &mut Vec<Output>) {
        let Some(h) = self.frame.take() else {
            return;
        };
        let t = phri_view::depth::stamp(&h);
        if wanted(topics::POINTS) {
            if let Some(c) = depth::point_cloud(&h, &self.depths, self.rates.cloud_downsample) {
                out.push(Output {
                    topic: topics::POINTS,
                    log_ns: t,
                    message: VizMessage::Cloud(c),
                });
            }
        }
        if wanted(topics::IMAGE) {
            if let Some(im) = depth::image(&h, &self.depths, self.rates.depth_downsample) {
                out.push(Output {
                    topic: topics::IMAGE,
                    log_ns: t,
                    message: VizMessage::Image(im),
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::{ControlMode, Zeroed};

    fn pipeline(rates: Rates) -> Pipeline {
        Pipeline::from_config(&Loaded::defaults(), rates).expect("the defaults")
    }

    fn all(_: &str) -> bool {
        true
    }

    fn state(seq: u64, stamp_ns: u64) -> JointState {
        let mut s = JointState::zeroed();
        s.seq = seq;
        s.dof = 7;
        s.stamp_ns = stamp_ns;
        s.published_ns = stamp_ns + 1000;
        s.q[..7].copy_from_slice(&[0.0, 0.3, 0.0, -1.2, 0.0, 0.5, 0.0]);
        s.tau[0] = 2.5;
        s
    }

    fn topics_of(out: &[Output]) -> Vec<&'static str> {
        out.iter().map(|o| o.topic).collect()
    }

    #[test]
    fn joint_states_follow_the_joint_rate_by_the_robots_clock() {
        let mut p = pipeline(Rates {
            joints_hz: 250.0,
            ..Rates::default()
        });
        let mut out = Vec::new();
        // one second of 1 kHz states
        for i in 0..1000u64 {
            p.offer(&state(i, 1_000_000_000 + i * 1_000_000), &all, &mut out);
        }
        let joints = out.iter().filter(|o| o.topic == topics::JOINTS).count();
        let status = out.iter().filter(|o| o.topic == topics::STATUS).count();
        assert_eq!(joints, 250);
        assert_eq!(status, 250);
        let VizMessage::Joints(j) = &out[0].message else {
            panic!("joint states first: {:?}", topics_of(&out));
        };
        assert_eq!(j.joints.len(), 7);
        assert_eq!(j.joints[0].name, p.joint_names()[0]);
        assert_eq!(j.joints[3].position, Some(-1.2));
        assert_eq!(j.joints[0].effort, Some(2.5));
        assert_eq!(out[0].log_ns, 1_000_001_000, "logged at the publish time");
        // a rate above the robot's forwards every state
        let mut p = pipeline(Rates {
            joints_hz: 2000.0,
            ..Rates::default()
        });
        let mut out = Vec::new();
        for i in 0..100u64 {
            p.offer(
                &state(i, i * 1_000_000),
                &|t: &str| t == topics::JOINTS,
                &mut out,
            );
        }
        assert_eq!(out.len(), 100, "every state, and no unwanted status");
    }

    #[test]
    fn the_scene_comes_at_the_scene_rate_with_every_topic() {
        let mut p = pipeline(Rates {
            scene_hz: 20.0,
            ..Rates::default()
        });
        let mut out = Vec::new();
        p.tick(0, &all, &mut out);
        // nothing received yet: the scenes of absent inputs are empty, no robot, no frames
        assert!(!topics_of(&out).contains(&topics::ROBOT));
        assert!(!topics_of(&out).contains(&topics::TF));
        out.clear();
        let mut c = ControlStatus::zeroed();
        c.mode = ControlMode::Task as u32;
        p.offer(&c, &all, &mut out);
        p.offer(&state(1, 1), &all, &mut out);
        out.clear();
        let mut scenes = 0;
        // 1 s in 5 ms ticks
        for i in 1..=200u64 {
            let n0 = out.len();
            p.tick(i * 5_000_000, &all, &mut out);
            if out[n0..].iter().any(|o| o.topic == topics::ROBOT) {
                scenes += 1;
                let t: Vec<_> = topics_of(&out[n0..]);
                for topic in [
                    topics::ROBOT,
                    topics::PERSON,
                    topics::REPULSION,
                    topics::COLLAB,
                    topics::TF,
                ] {
                    assert!(t.contains(&topic), "{topic} in {t:?}");
                }
            }
        }
        assert!(
            (19..=21).contains(&scenes),
            "{scenes} scenes in 1 s at 20 Hz"
        );
        let VizMessage::Scene(robot) = &out
            .iter()
            .find(|o| o.topic == topics::ROBOT)
            .unwrap()
            .message
        else {
            panic!("a scene");
        };
        assert!(!robot.entities.is_empty());
        // the status carries the mode
        let mut out = Vec::new();
        p.offer(&state(2, 1_000_000_000), &all, &mut out);
        let status = out.iter().find_map(|o| match &o.message {
            VizMessage::Status(s) => Some(s.clone()),
            _ => None,
        });
        assert_eq!(status.expect("a status").mode, "task");
    }

    #[test]
    fn a_depth_frame_is_sent_once_as_cloud_and_image() {
        let mut p = pipeline(Rates::default());
        let mut h = FrameHeader::zeroed();
        h.width = 4;
        h.height = 4;
        h.fx = 2.0;
        h.fy = 2.0;
        h.depth_scale = 0.001;
        h.pose_r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        h.capture_wall_ns = 77;
        p.offer_frame(&h, &[1000; 16]);
        let mut out = Vec::new();
        p.tick(
            1_000_000_000,
            &|t: &str| t == topics::POINTS || t == topics::IMAGE,
            &mut out,
        );
        assert_eq!(topics_of(&out), vec![topics::POINTS, topics::IMAGE]);
        assert!(out.iter().all(|o| o.log_ns == 77));
        let VizMessage::Image(im) = out[1].message.clone() else {
            panic!("an image")
        };
        assert_eq!((im.width, im.height), (2, 2), "downsampled by 2");
        out.clear();
        p.tick(2_000_000_000, &all, &mut out);
        assert!(!topics_of(&out).contains(&topics::POINTS), "sent once");
        // encoded: protobuf and JSON
        let mut buf = Vec::new();
        VizMessage::Image(im).encode(&mut buf).unwrap();
        assert!(buf.len() > 8);
    }

    #[test]
    fn stale_repulsion_results_vanish() {
        let mut p = pipeline(Rates::default());
        let mut r = RepulsionResult::zeroed();
        r.n_points = 1;
        r.published_ns = 1_000_000_000;
        r.points[0].position = [0.5, 0.0, 0.5];
        let mut out = Vec::new();
        p.offer(&r, &all, &mut out);
        let repulsion = |out: &[Output]| -> usize {
            out.iter()
                .filter_map(|o| match (&o.message, o.topic) {
                    (VizMessage::Scene(s), topics::REPULSION) => Some(s.entities.len()),
                    _ => None,
                })
                .sum()
        };
        p.tick(1_100_000_000, &all, &mut out);
        assert_eq!(repulsion(&out), 1);
        out.clear();
        p.tick(2_000_000_000, &all, &mut out);
        assert_eq!(repulsion(&out), 0);
    }

    #[test]
    fn a_stopped_robot_makes_the_scene_stale_until_it_comes_back() {
        const MS: u64 = 1_000_000;
        let mut p = pipeline(Rates::default())
            .with_stale_after(Some(std::time::Duration::from_millis(500)));
        let statuses = |out: &[Output]| -> Vec<Status> {
            out.iter()
                .filter_map(|o| match &o.message {
                    VizMessage::Status(s) => Some(s.clone()),
                    _ => None,
                })
                .collect()
        };
        // nothing yet: stale, no age, no scene
        let mut out = Vec::new();
        p.tick(1000 * MS, &all, &mut out);
        assert!(p.is_stale());
        assert_eq!(topics_of(&out), vec![topics::STATUS]);
        let s = &statuses(&out)[0];
        assert!(
            s.stale && s.input_age.is_none() && s.mode == "none",
            "{s:?}"
        );
        // states, every ms for a second: live, the scene at its rate
        out.clear();
        let mut t = 2000 * MS;
        for i in 0..1000 {
            p.offer(&state(i, t), &all, &mut out);
            p.tick(t, &all, &mut out);
            t += MS;
        }
        assert!(!p.is_stale());
        assert!(topics_of(&out).contains(&topics::ROBOT));
        assert!(statuses(&out)
            .iter()
            .all(|s| !s.stale && s.input_age == Some(0.0)));
        // the robot stops: live until the bound, then stale statuses only
        let last = t - MS;
        out.clear();
        while t <= last + 500 * MS {
            p.tick(t, &all, &mut out);
            t += MS;
        }
        assert!(!p.is_stale(), "not before the bound");
        out.clear();
        while t < last + 2000 * MS {
            p.tick(t, &all, &mut out);
            t += MS;
        }
        assert!(p.is_stale());
        assert!(
            topics_of(&out).iter().all(|t| *t == topics::STATUS),
            "no scene stamped as current: {:?}",
            topics_of(&out)
        );
        let ages: Vec<f64> = statuses(&out)
            .iter()
            .map(|s| s.input_age.unwrap_or(-1.0))
            .collect();
        // one on entering, then every 250 ms
        assert_eq!(ages.len(), 6, "{ages:?}");
        assert!(
            ages[0] > 0.5 && ages.windows(2).all(|w| w[1] > w[0]),
            "{ages:?}"
        );
        assert_eq!(p.input_age_ns(last + 1000 * MS), Some(1000 * MS));
        // a state again: live, the scene at once
        out.clear();
        p.offer(&state(5000, t), &all, &mut out);
        p.tick(t, &all, &mut out);
        assert!(!p.is_stale());
        assert!(
            topics_of(&out).contains(&topics::ROBOT),
            "{:?}",
            topics_of(&out)
        );
    }

    #[test]
    fn without_a_bound_nothing_is_ever_stale() {
        let mut p = pipeline(Rates::default());
        let mut out = Vec::new();
        p.offer(&state(1, 1_000_000), &all, &mut out);
        p.tick(1_000_000, &all, &mut out);
        out.clear();
        p.tick(3_600_000_000_000, &all, &mut out);
        assert!(!p.is_stale());
        assert!(
            topics_of(&out).contains(&topics::ROBOT),
            "phri-record's scene, as before"
        );
    }
}
