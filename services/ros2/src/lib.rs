//! phri-ros2: the cell's channels as ROS 2 topics over DDS (RTPS, CDR), with
//! no ROS installation: `ros2-client` on RustDDS, pure Rust.
//!
//! [`Bridge`] is the pure part: it turns the cell's messages into ROS 2
//! messages ([`msgs`], [`convert`]) at the configured rates (`[ros2]`) and
//! `/phri/request` texts into `hri/request` requests ([`request`]), stops
//! first and each peer rate-limited ([`gate`], [`intake`]); [`service`]'s
//! loop wires iceoryx2 and DDS ([`topics`]) to it, on the loopback only
//! unless `[ros2] discovery = "subnet"` ([`discovery`]); the binary only
//! opens both sides and runs it. Topics, types and QoS:
//!
//! | topic | type | QoS |
//! | --- | --- | --- |
//! | `/joint_states` | `sensor_msgs/JointState` | best effort, keep last 200 (0.2 s at 1 kHz) |
//! | `/tf` | `tf2_msgs/TFMessage` | best effort, keep last 5 |
//! | `/phri/status` | `diagnostic_msgs/DiagnosticArray` | reliable, keep last 10 |
//! | `/phri/contact_force` | `geometry_msgs/WrenchStamped` | best effort, keep last 5 |
//! | `/phri/repulsion` | `visualization_msgs/MarkerArray` | best effort, keep last 5 |
//! | `/phri/depth` | `sensor_msgs/Image` (16UC1) | best effort, keep last 1 |
//! | `/phri/points` | `sensor_msgs/PointCloud2` | best effort, keep last 1 |
//! | `/humans/bodies/tracked` | `hri_msgs/IdsList` | reliable, keep last 10 |
//! | `/phri/request` (taken) | `std_msgs/String` | reliable, keep last 64 |
//!
//! The people the body trackers see (every camera's `perception/skeleton`)
//! are published as ROS4HRI does (REP 155, [`humans`]): the ids of the
//! bodies tracked on `/humans/bodies/tracked`, and on `/tf` a frame
//! `body_<id>` per body and one per joint seen (`head_<id>`,
//! `l_wrist_<id>`, ...).
//!
//! A topic nobody subscribes to costs nothing: the loop tells the bridge
//! which topics DDS has matched readers for ([`Subscribed`]), and the bridge
//! converts only those (ROS 2's "lazy publisher"; the cell's CPU is not
//! spent on images nobody looks at).

#![deny(missing_docs)]

pub mod camera;
pub mod convert;
pub mod discovery;
pub mod gate;
pub mod humans;
pub mod intake;
pub mod msgs;
pub mod participant;
pub mod report;
pub mod request;
pub mod service;
pub mod topics;

use phri_config::{Config, Ros2Config};
use phri_ipc::{
    CollabState, ControlStatus, FrameHeader, HriRequest, RepulsionResult, RequestKind, Residual,
    Skeleton,
};
use phri_view::{RobotView, Status, Thresholds};

pub use convert::{Clock, BASE_FRAME, CAMERA_FRAME};
pub use gate::{PeerId, RefusalKind};
use msgs::{
    DiagnosticArray, DiagnosticStatus, Header, IdsList, Image, JointState, KeyValue, MarkerArray,
    PointCloud2, TfMessage, WrenchStamped,
};
pub use request::RequestError;

/// Why the bridge cannot start.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// `[dynamics]`'s contact or collision threshold does not fit the model: why
    #[error("{0}")]
    Config(String),
}

/// A `/phri/request` the bridge did not pass on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refused {
    /// `[ros2] accept_requests = false`: ROS 2 peers are not trusted
    #[error("requests from ROS 2 are refused (ros2.accept_requests = false)")]
    NotAccepted,
    /// not a request the cell takes from ROS 2
    #[error(transparent)]
    NotARequest(#[from] RequestError),
    /// its peer (DDS writer) sent more than `[ros2] requests_per_s` and
    /// `requests_burst` allow
    #[error("over the rate limit of its peer (ros2.requests_per_s, ros2.requests_burst)")]
    RateLimited,
}

impl Refused {
    /// This refusal's kind, for the refusal counts and log lines.
    pub fn kind(&self) -> RefusalKind {
        match self {
            Refused::NotAccepted => RefusalKind::NotAccepted,
            Refused::NotARequest(_) => RefusalKind::NotARequest,
            Refused::RateLimited => RefusalKind::RateLimited,
        }
    }
}

/// Is this parsed request a stop?
fn is_stop(r: &Result<HriRequest, RequestError>) -> bool {
    matches!(r, Ok(q) if q.kind == RequestKind::Stop as u32)
}

/// One `/phri/request` sample as DDS delivered it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RequestSample {
    /// the DDS writer that sent it
    pub peer: PeerId,
    /// the `std_msgs/String`'s text, as received
    pub text: String,
}

/// Published and refused, per topic, since the bridge started.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// `/joint_states`
    pub joint_states: u64,
    /// `/tf` messages of the arm's links
    pub tf: u64,
    /// `/phri/status`
    pub status: u64,
    /// `/phri/contact_force`
    pub contact_force: u64,
    /// `/phri/repulsion`
    pub repulsion: u64,
    /// `/phri/depth` images
    pub depth: u64,
    /// `/phri/points` clouds
    pub points: u64,
    /// `/humans/bodies/tracked`
    pub humans: u64,
    /// `/tf` messages of the bodies' frames
    pub bodies_tf: u64,
    /// requests passed into `hri/request` (stops among them)
    pub requests: u64,
    /// stops passed into `hri/request`
    pub requests_stops: u64,
    /// refused: `accept_requests = false`, or not a request
    pub requests_refused: u64,
    /// dropped: over their peer's rate limit
    pub requests_dropped: u64,
    /// samples DDS could not make a `std_msgs/String` of
    pub requests_malformed: u64,
}

/// Which published topics have at least one matched subscriber (DDS
/// discovery). The bridge converts and publishes only these.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Subscribed {
    /// `/joint_states`
    pub joint_states: bool,
    /// `/tf` (the arm's links, the camera's frame and the bodies' frames)
    pub tf: bool,
    /// `/phri/status`
    pub status: bool,
    /// `/phri/contact_force`
    pub contact_force: bool,
    /// `/phri/repulsion`
    pub repulsion: bool,
    /// `/phri/depth`
    pub depth: bool,
    /// `/phri/points`
    pub points: bool,
    /// `/humans/bodies/tracked`
    pub humans: bool,
}

impl Subscribed {
    /// Every topic.
    pub const ALL: Subscribed = Subscribed {
        joint_states: true,
        tf: true,
        status: true,
        contact_force: true,
        repulsion: true,
        depth: true,
        points: true,
        humans: true,
    };

    /// Does any subscriber need every robot state (1 kHz wake-ups)?
    /// Otherwise the binary reads `robot/state` in batches.
    pub fn every_state(&self) -> bool {
        self.joint_states
    }
}

/// What one robot state gives.
pub struct StateOut<'a> {
    /// `/joint_states`, when due and subscribed
    pub joint_state: Option<&'a JointState>,
    /// `/tf`: each moving link in [`BASE_FRAME`], when due and subscribed
    pub tf: Option<TfMessage>,
}

/// What one depth frame gives.
pub struct FrameOut<'a> {
    /// `/phri/depth`, when due and subscribed
    pub image: Option<&'a Image>,
    /// `/phri/points`, when due and subscribed
    pub points: Option<&'a PointCloud2>,
    /// the camera's optical frame in [`BASE_FRAME`] at the frame's time
    pub camera_tf: Option<TfMessage>,
}

/// What one skeleton gives.
pub struct SkeletonOut {
    /// `/humans/bodies/tracked`
    pub tracked: Option<IdsList>,
    /// its bodies' frames (none without a body seen)
    pub tf: Option<TfMessage>,
}

/// A rate limit on phri's clock: due at most once per period.
#[derive(Clone, Copy, Debug)]
struct Every {
    period_ns: u64,
    last_ns: Option<u64>,
}

impl Every {
    fn hz(hz: f64) -> Every {
        Every {
            period_ns: (1e9 / hz) as u64,
            last_ns: None,
        }
    }

    fn due(&mut self, now_ns: u64) -> bool {
        let due = self
            .last_ns
            .is_none_or(|t| now_ns.saturating_sub(t) >= self.period_ns);
        if due {
            // keep the cadence: the next one is due a period after this one was
            self.last_ns = Some(match self.last_ns {
                Some(t) if now_ns - t < 2 * self.period_ns => t + self.period_ns,
                _ => now_ns,
            });
        }
        due
    }
}

/// The bridge's state: the robot's view for `/tf`, reused messages,
/// decimation counters and rate limits.
pub struct Bridge {
    cfg: Ros2Config,
    view: RobotView,
    thresholds: Thresholds,
    joint_state: JointState,
    states: u64,
    frames: u64,
    image: Image,
    cloud: PointCloud2,
    status_every: Every,
    force_every: Every,
    repulsion_every: Every,
    request_seq: u64,
    /// `/phri/request` per peer
    limit: gate::RateLimit,
    /// the newest repulsion result of each worker
    results: Vec<RepulsionResult>,
    /// the arm's name (`[robot] name`)
    robot: String,
    /// the topics with subscribers (the binary keeps it current)
    pub subscribed: Subscribed,
    /// what was published and refused since the bridge started
    pub counts: Counts,
    /// the last `ros2/requests` message's sequence number
    requests_seq: u64,
    /// the bodies every camera tracks
    tracked: humans::Tracked,
}

impl Bridge {
    /// For `config`'s `[ros2]` and `[dynamics]` thresholds, on `model`.
    pub fn new(config: &Config, model: phri_model::Model) -> Result<Bridge, BridgeError> {
        let n = model.nv();
        let d = &config.dynamics;
        let thresholds = Thresholds {
            contact: d
                .contact_threshold
                .resolve(n, "dynamics.contact_threshold")
                .map_err(|e| BridgeError::Config(e.to_string()))?,
            collision: d
                .collision_threshold
                .resolve(n, "dynamics.collision_threshold")
                .map_err(|e| BridgeError::Config(e.to_string()))?,
            collision_norm: d.collision_norm_threshold,
        };
        let view = RobotView::new(model);
        let cfg = config.ros2.clone();
        let joint_state = JointState {
            header: Header {
                frame_id: String::new(),
                ..Header::default()
            },
            name: view.joint_names().to_vec(),
            ..JointState::default()
        };
        Ok(Bridge {
            status_every: Every::hz(cfg.status_hz),
            force_every: Every::hz(cfg.contact_force_hz),
            repulsion_every: Every::hz(cfg.repulsion_hz),
            cfg,
            view,
            thresholds,
            joint_state,
            states: 0,
            frames: 0,
            image: Image::default(),
            cloud: PointCloud2::default(),
            request_seq: 0,
            limit: gate::RateLimit::new(config.ros2.requests_per_s, config.ros2.requests_burst),
            results: Vec::new(),
            robot: config.robot.name.clone(),
            subscribed: Subscribed::default(),
            counts: Counts::default(),
            requests_seq: 0,
            tracked: humans::Tracked::default(),
        })
    }

    /// The joints' names, in `/joint_states`' order (the model's).
    pub fn joint_names(&self) -> &[String] {
        self.view.joint_names()
    }

    /// A robot state: `/joint_states` every `joint_states_every`-th, `/tf`
    /// (each moving link in [`BASE_FRAME`]) every `tf_every`-th; each only
    /// when subscribed.
    pub fn state(&mut self, s: &phri_ipc::JointState, clock: &Clock) -> StateOut<'_> {
        self.states += 1;
        let stamp = clock.ros(s.published_ns);
        let mut tf = None;
        if self.subscribed.tf && self.states.is_multiple_of(u64::from(self.cfg.tf_every)) {
            let n = (s.dof as usize).min(s.q.len());
            if n == self.view.joint_names().len() && self.view.pose(&s.q[..n]).is_ok() {
                let transforms = self
                    .view
                    .link_frames()
                    .filter(|(link, _)| *link != BASE_FRAME)
                    .map(|(link, p)| convert::transform(stamp, BASE_FRAME, link, &p))
                    .collect();
                self.counts.tf += 1;
                tf = Some(TfMessage { transforms });
            }
        }
        let mut joint_state = None;
        if self.subscribed.joint_states
            && self
                .states
                .is_multiple_of(u64::from(self.cfg.joint_states_every))
        {
            convert::joint_state(s, stamp, &mut self.joint_state);
            self.counts.joint_states += 1;
            joint_state = Some(&self.joint_state);
        }
        StateOut { joint_state, tf }
    }

    /// `/phri/status` at `status_hz` (phri's clock `now_ns`): the
    /// controller's mode, the collaboration's phase, the residual and its
    /// thresholds, and the bridge's `/phri/request` counts (`requests_passed`,
    /// `_stops`, `_refused`, `_dropped`, `_malformed`) as one
    /// `DiagnosticStatus` named `phri`, its level ERROR on
    /// a collision, WARN on a contact, STALE before the controller reported.
    pub fn status(
        &mut self,
        now_ns: u64,
        clock: &Clock,
        control: Option<&ControlStatus>,
        collab: Option<&CollabState>,
        residual: Option<&Residual>,
    ) -> Option<DiagnosticArray> {
        if !self.subscribed.status || !self.status_every.due(now_ns) {
            return None;
        }
        let s = Status::from_latest(control, collab, residual, &self.thresholds);
        let level = if control.is_none() {
            DiagnosticStatus::STALE
        } else if s.collision {
            DiagnosticStatus::ERROR
        } else if s.contact {
            DiagnosticStatus::WARN
        } else {
            DiagnosticStatus::OK
        };
        let mut values = match serde_json::to_value(&s) {
            Ok(serde_json::Value::Object(m)) => m
                .into_iter()
                .filter(|(k, _)| k != "stale" && k != "input_age")
                .map(|(key, v)| KeyValue {
                    key,
                    value: match v {
                        serde_json::Value::String(s) => s,
                        v => v.to_string(),
                    },
                })
                .collect(),
            _ => Vec::new(),
        };
        // what became of /phri/request since the bridge started
        let c = &self.counts;
        values.extend(
            [
                ("requests_passed", c.requests),
                ("requests_stops", c.requests_stops),
                ("requests_refused", c.requests_refused),
                ("requests_dropped", c.requests_dropped),
                ("requests_malformed", c.requests_malformed),
            ]
            .map(|(key, n)| KeyValue {
                key: key.to_string(),
                value: n.to_string(),
            }),
        );
        self.counts.status += 1;
        Some(DiagnosticArray {
            header: Header {
                stamp: clock.ros(now_ns),
                frame_id: BASE_FRAME.to_string(),
            },
            status: vec![DiagnosticStatus {
                level,
                name: "phri".to_string(),
                message: format!("{} / {}", s.mode, s.phase),
                hardware_id: self.robot.clone(),
                values,
            }],
        })
    }

    /// `/phri/contact_force` at `contact_force_hz`: the collaboration's
    /// estimated contact forces (zero when none).
    pub fn contact_force(
        &mut self,
        now_ns: u64,
        clock: &Clock,
        collab: Option<&CollabState>,
    ) -> Option<WrenchStamped> {
        let c = collab?;
        if !self.subscribed.contact_force || !self.force_every.due(now_ns) {
            return None;
        }
        self.counts.contact_force += 1;
        Some(convert::contact_wrench(c, clock.ros(c.stamp_ns)))
    }

    /// A repulsion worker's result: the newest of each worker is kept.
    pub fn result(&mut self, r: &RepulsionResult) {
        match self.results.iter_mut().find(|x| x.worker == r.worker) {
            Some(x) => *x = *r,
            None => self.results.push(*r),
        }
    }

    /// `/phri/repulsion` at `repulsion_hz` (phri's clock `now_ns`): each
    /// worker's newest result as arrows.
    pub fn repulsion(&mut self, now_ns: u64, clock: &Clock) -> Option<MarkerArray> {
        if !self.subscribed.repulsion
            || self.results.is_empty()
            || !self.repulsion_every.due(now_ns)
        {
            return None;
        }
        self.counts.repulsion += 1;
        Some(convert::repulsion_markers(&self.results, clock.ros(now_ns)))
    }

    /// A new filtered depth frame: `/phri/depth` every `depth_every`-th,
    /// `/phri/points` every `points_every`-th, the camera's frame on `/tf`
    /// with each; each only when subscribed.
    pub fn frame(&mut self, h: &FrameHeader, depth: &[u16], clock: &Clock) -> FrameOut<'_> {
        self.frames += 1;
        let stamp = clock.ros(phri_view::depth::stamp(h));
        let image = self.subscribed.depth
            && self.frames.is_multiple_of(u64::from(self.cfg.depth_every))
            && convert::depth_image(h, depth, stamp, &mut self.image);
        let points = self.subscribed.points
            && self.frames.is_multiple_of(u64::from(self.cfg.points_every))
            && convert::points(
                h,
                depth,
                self.cfg.points_stride as usize,
                stamp,
                &mut self.cloud,
            );
        self.counts.depth += u64::from(image);
        self.counts.points += u64::from(points);
        let camera_tf = self.subscribed.tf.then(|| TfMessage {
            transforms: vec![convert::camera_transform(clock.ros(h.published_ns), h)],
        });
        FrameOut {
            image: image.then_some(&self.image),
            points: points.then_some(&self.cloud),
            camera_tf,
        }
    }

    /// Camera `camera`'s skeleton (`perception/skeleton`, `perception/1/skeleton`, ...)
    /// as ROS4HRI ([`humans`]): `/humans/bodies/tracked` (every camera's
    /// bodies), and its bodies' frames on `/tf`; each only when subscribed.
    pub fn skeleton(&mut self, camera: usize, s: &Skeleton, clock: &Clock) -> SkeletonOut {
        if !self.subscribed.humans && !self.subscribed.tf {
            return SkeletonOut {
                tracked: None,
                tf: None,
            };
        }
        let t = humans::stamp_ns(s);
        let (mut list, transforms) = humans::bodies(s, camera, BASE_FRAME, clock.ros(t));
        list.ids = self.tracked.update(camera, list.ids, t);
        self.counts.humans += u64::from(self.subscribed.humans);
        let tf = (self.subscribed.tf && !transforms.is_empty()).then_some(TfMessage { transforms });
        self.counts.bodies_tf += u64::from(tf.is_some());
        SkeletonOut {
            tracked: self.subscribed.humans.then_some(list),
            tf,
        }
    }

    /// The `/phri/request` samples received since the last call, at
    /// `now_ns` [ns, CLOCK_MONOTONIC]: what becomes of each, as (its index
    /// in `batch`, the request for `hri/request` or why it is refused), in
    /// the order to publish them: every stop first (never rate-limited),
    /// then the others in arrival order, each within its peer's rate.
    /// Every refusal is counted.
    pub fn requests(
        &mut self,
        batch: &[RequestSample],
        now_ns: u64,
    ) -> Vec<(usize, Result<HriRequest, Refused>)> {
        let mut out = Vec::with_capacity(batch.len());
        if !self.cfg.accept_requests {
            self.counts.requests_refused += batch.len() as u64;
            out.extend((0..batch.len()).map(|i| (i, Err(Refused::NotAccepted))));
            return out;
        }
        let parsed: Vec<Result<HriRequest, RequestError>> = batch
            .iter()
            .map(|s| request::parse(&s.text, 0, now_ns))
            .collect();
        let stops = parsed.iter().enumerate().filter(|(_, r)| is_stop(r));
        let others = parsed.iter().enumerate().filter(|(_, r)| !is_stop(r));
        for (i, r) in stops.chain(others) {
            let result = match r {
                Err(e) => Err(Refused::NotARequest(e.clone())),
                Ok(q) if is_stop(r) => Ok(*q),
                Ok(q) if self.limit.admit(batch[i].peer, now_ns) => Ok(*q),
                Ok(_) => Err(Refused::RateLimited),
            };
            let result = result.map(|mut q| {
                // numbers that grow across restarts: microseconds of CLOCK_MONOTONIC
                self.request_seq = (now_ns / 1_000).max(self.request_seq + 1);
                q.seq = self.request_seq;
                q
            });
            match &result {
                Ok(q) => {
                    self.counts.requests += 1;
                    self.counts.requests_stops += u64::from(q.kind == RequestKind::Stop as u32);
                }
                Err(Refused::RateLimited) => self.counts.requests_dropped += 1,
                Err(_) => self.counts.requests_refused += 1,
            }
            out.push((i, result));
        }
        out
    }

    /// A `/phri/request` sample DDS could not make a `std_msgs/String` of.
    pub fn malformed_request(&mut self) {
        self.counts.requests_malformed += 1;
    }

    /// The next `ros2/requests` message, stamped `now_ns`: what the bridge
    /// did with `/phri/request` so far; `undelivered`, the requests
    /// `hri/request` did not deliver to some reader
    /// (`phri_ipc::Publisher::undelivered`), count as dropped.
    pub fn requests_message(&mut self, now_ns: u64, undelivered: u64) -> phri_ipc::BridgeRequests {
        self.requests_seq += 1;
        let c = &self.counts;
        phri_ipc::BridgeRequests {
            seq: self.requests_seq,
            stamp_ns: now_ns,
            passed: c.requests,
            stops: c.requests_stops,
            refused: c.requests_refused,
            dropped: c.requests_dropped + undelivered,
            malformed: c.requests_malformed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn bridge() -> Bridge {
        let model = phri_model::Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        Bridge::new(&Config::defaults(), model).unwrap()
    }

    fn accepting() -> Bridge {
        let model = phri_model::Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        let mut c = Config::defaults();
        c.ros2.accept_requests = true;
        (c.ros2.requests_per_s, c.ros2.requests_burst) = (2.0, 3);
        Bridge::new(&c, model).unwrap()
    }

    fn sample(peer: u8, text: &str) -> RequestSample {
        RequestSample {
            peer: [peer; 16],
            text: text.to_string(),
        }
    }

    #[test]
    fn stops_go_first_and_past_every_rate_limit() {
        let mut b = accepting();
        // one peer floods with begins, another asks to stop at the end of it
        let mut batch: Vec<RequestSample> = (0..20).map(|_| sample(1, "begin")).collect();
        batch.push(sample(1, "stop"));
        batch.push(sample(2, "STOP"));
        batch.push(sample(2, "follow left_hand"));
        let out = b.requests(&batch, 10_000_000_000);
        assert_eq!(out.len(), batch.len(), "every sample has an outcome");
        let kinds: Vec<u32> = out
            .iter()
            .filter_map(|(_, r)| r.as_ref().ok().map(|q| q.kind))
            .collect();
        let stop = RequestKind::Stop as u32;
        assert_eq!(&kinds[..2], &[stop, stop], "{kinds:?}");
        assert_eq!((out[0].0, out[1].0), (20, 21));
        // peer 1: its burst of 3 begins; peer 2: its follow
        assert_eq!(kinds.len(), 2 + 3 + 1, "{kinds:?}");
        let dropped = out
            .iter()
            .filter(|(_, r)| r.as_ref().err() == Some(&Refused::RateLimited))
            .count();
        assert_eq!(dropped, 17);
        assert_eq!(
            (
                b.counts.requests,
                b.counts.requests_stops,
                b.counts.requests_dropped,
                b.counts.requests_refused
            ),
            (6, 2, 17, 0)
        );
        // the requests passed are numbered in the order published
        let seqs: Vec<u64> = out
            .iter()
            .filter_map(|(_, r)| r.as_ref().ok().map(|q| q.seq))
            .collect();
        assert!(seqs.windows(2).all(|w| w[0] < w[1]), "{seqs:?}");
        // ROS 2 sees the counts on /phri/status
        b.subscribed.status = true;
        let clock = Clock::new(0, 1_764_000_000_000_000_000);
        let m = b.status(10_000_000_000, &clock, None, None, None).unwrap();
        let value = |key: &str| {
            m.status[0]
                .values
                .iter()
                .find(|kv| kv.key == key)
                .map(|kv| kv.value.clone())
        };
        assert_eq!(value("requests_dropped").as_deref(), Some("17"));
        assert_eq!(value("requests_stops").as_deref(), Some("2"));
        // a stop while the flood goes on still passes
        let out = b.requests(&[sample(1, "begin"), sample(1, "stop")], 10_100_000_000);
        assert_eq!(out[0].1.as_ref().map(|q| q.kind).ok(), Some(stop));
        assert!(matches!(out[1].1, Err(Refused::RateLimited)));
    }

    #[test]
    fn refused_requests_are_counted_and_not_rate_limited_tokens() {
        let mut b = accepting();
        let batch = [sample(1, "dance"), sample(1, "resume"), sample(1, "end")];
        let out = b.requests(&batch, 1_000_000_000);
        assert!(matches!(out[0].1, Err(Refused::NotARequest(_))));
        assert!(matches!(
            out[1].1,
            Err(Refused::NotARequest(RequestError::Resume))
        ));
        assert!(out[2].1.is_ok());
        assert_eq!((b.counts.requests, b.counts.requests_refused), (1, 2));
        b.malformed_request();
        assert_eq!(b.counts.requests_malformed, 1);
    }

    #[test]
    fn without_accept_requests_every_request_is_refused_stops_too() {
        let mut b = bridge();
        let out = b.requests(&[sample(1, "stop"), sample(2, "begin")], 1);
        assert!(out
            .iter()
            .all(|(_, r)| matches!(r, Err(Refused::NotAccepted))));
        assert_eq!((b.counts.requests, b.counts.requests_refused), (0, 2));
    }

    fn state(k: u64) -> phri_ipc::JointState {
        let mut s = phri_ipc::JointState::zeroed();
        s.dof = 7;
        s.q[3] = 1.0 + k as f64 * 1e-3;
        s.published_ns = 1_000_000_000 + k * 1_000_000;
        s
    }

    fn frame(seq: u64) -> FrameHeader {
        let mut f = FrameHeader::zeroed();
        (f.width, f.height, f.seq) = (4, 2, seq);
        (f.fx, f.fy, f.cx, f.cy, f.depth_scale) = (500.0, 500.0, 2.0, 1.0, 0.001);
        f.pose_r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        f.published_ns = 1_000_000_000 + seq * 33_000_000;
        f
    }

    /// Everything the bridge would publish over 30 robot states, 6 depth
    /// frames and 1 s of status, force and repulsion.
    fn run(b: &mut Bridge) -> (u64, u64, u64, u64, u64, u64, u64) {
        let clock = Clock::new(0, 1_764_000_000_000_000_000);
        let (mut js, mut tf, mut img, mut pc, mut cam) = (0, 0, 0, 0, 0);
        for k in 0..30 {
            let out = b.state(&state(k), &clock);
            js += u64::from(out.joint_state.is_some());
            tf += u64::from(out.tf.is_some());
        }
        let depth = [1000u16; 8];
        for seq in 1..=6 {
            let out = b.frame(&frame(seq), &depth, &clock);
            img += u64::from(out.image.is_some());
            pc += u64::from(out.points.is_some());
            cam += u64::from(out.camera_tf.is_some());
        }
        let collab = CollabState::zeroed();
        let mut r = RepulsionResult::zeroed();
        r.worker = 2;
        b.result(&r);
        let (mut st, mut f, mut rep) = (0, 0, 0);
        for ms in 0..1000u64 {
            let now = 2_000_000_000 + ms * 1_000_000;
            st += u64::from(b.status(now, &clock, None, Some(&collab), None).is_some());
            f += u64::from(b.contact_force(now, &clock, Some(&collab)).is_some());
            rep += u64::from(b.repulsion(now, &clock).is_some());
        }
        (js, tf, img, pc, cam, st, f + 1000 * rep)
    }

    #[test]
    fn nothing_is_converted_for_a_topic_nobody_subscribes_to() {
        let mut b = bridge();
        assert_eq!(b.subscribed, Subscribed::default());
        assert_eq!(run(&mut b), (0, 0, 0, 0, 0, 0, 0));
        assert_eq!(b.counts, Counts::default());
    }

    #[test]
    fn every_subscribed_topic_comes_at_its_configured_rate() {
        let mut b = bridge();
        b.subscribed = Subscribed::ALL;
        // 30 states: /joint_states each, /tf every 10th; 6 frames: an image
        // each, points every 3rd, the camera's frame each; status 10 Hz,
        // force 100 Hz, repulsion 10 Hz
        assert_eq!(run(&mut b), (30, 3, 6, 2, 6, 10, 100 + 1000 * 10));
        assert_eq!(b.joint_names().len(), 7);
    }

    fn skeleton_of(camera_wall_ns: u64, ids: &[u32]) -> Skeleton {
        let mut s = Skeleton::zeroed();
        (s.capture_wall_ns, s.published_ns) = (camera_wall_ns, camera_wall_ns + 20_000_000);
        s.n_people = ids.len() as u32;
        for (p, id) in s.people.iter_mut().zip(ids) {
            (p.id, p.tracked) = (*id, 1);
            p.confidence[phri_ipc::SkeletonJoint::Head as usize] = 1.0;
            p.joints[phri_ipc::SkeletonJoint::Head as usize] = [1.0, 0.0, 1.7];
        }
        s
    }

    #[test]
    fn skeletons_become_ros4hri_bodies_only_when_subscribed() {
        let clock = Clock::new(1_000_000_000, 1_764_000_000_000_000_000);
        let mut b = bridge();
        let out = b.skeleton(0, &skeleton_of(2_000_000_000, &[7]), &clock);
        assert!(out.tracked.is_none() && out.tf.is_none());
        assert_eq!(b.counts, Counts::default());
        // /humans/bodies/tracked only: every camera's bodies, stamped with
        // the capture time on ROS time; empty messages too
        b.subscribed.humans = true;
        let out = b.skeleton(0, &skeleton_of(2_000_000_000, &[7]), &clock);
        let list = out.tracked.unwrap();
        assert_eq!(list.ids, ["b07"]);
        assert_eq!(list.header.stamp.to_ns(), 1_764_000_001_000_000_000);
        assert!(out.tf.is_none());
        let out = b.skeleton(1, &skeleton_of(2_010_000_000, &[7, 8]), &clock);
        assert_eq!(out.tracked.unwrap().ids, ["b07", "b17", "b18"]);
        b.skeleton(1, &skeleton_of(2_040_000_000, &[]), &clock);
        let out = b.skeleton(0, &skeleton_of(2_033_000_000, &[]), &clock);
        assert!(out.tracked.unwrap().ids.is_empty());
        // /tf only: the bodies' frames, none for an empty skeleton
        b.subscribed = Subscribed {
            tf: true,
            ..Subscribed::default()
        };
        let out = b.skeleton(0, &skeleton_of(2_066_000_000, &[7]), &clock);
        assert!(out.tracked.is_none());
        let frames: Vec<(String, String)> = out
            .tf
            .unwrap()
            .transforms
            .into_iter()
            .map(|t| (t.header.frame_id, t.child_frame_id))
            .collect();
        assert_eq!(
            frames,
            [
                (BASE_FRAME.to_string(), "body_b07".to_string()),
                ("body_b07".to_string(), "head_b07".to_string())
            ]
        );
        assert!(b
            .skeleton(0, &skeleton_of(2_100_000_000, &[]), &clock)
            .tf
            .is_none());
        assert_eq!((b.counts.humans, b.counts.bodies_tf), (4, 1));
    }

    #[test]
    fn only_the_subscribed_topics_are_converted() {
        let mut b = bridge();
        b.subscribed = Subscribed {
            tf: true,
            points: true,
            ..Subscribed::default()
        };
        assert!(!b.subscribed.every_state());
        assert_eq!(run(&mut b), (0, 3, 0, 2, 6, 0, 0));
        assert_eq!((b.counts.joint_states, b.counts.depth), (0, 0));
    }
}
