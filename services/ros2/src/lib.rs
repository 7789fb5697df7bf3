//! phri-ros2: the cell's channels as ROS 2 topics over DDS (RTPS, CDR), with
//! no ROS installation: `ros2-client` on RustDDS, pure Rust.
//!
//! [`Bridge`] is the pure part: it turns the cell's messages into ROS 2
//! messages ([`msgs`], [`convert`]) at the configured rates (`[ros2]`) and
//! `/phri/request` texts into `hri/request` requests ([`request`]); the
//! binary wires iceoryx2 and DDS to it. Topics, types and QoS:
//!
//! | topic | type | QoS |
//! | --- | --- | --- |
//! | `/joint_states` | `sensor_msgs/JointState` | best effort, keep last 5 |
//! | `/tf` | `tf2_msgs/TFMessage` | best effort, keep last 5 |
//! | `/phri/status` | `diagnostic_msgs/DiagnosticArray` | reliable, keep last 10 |
//! | `/phri/contact_force` | `geometry_msgs/WrenchStamped` | best effort, keep last 5 |
//! | `/phri/repulsion` | `visualization_msgs/MarkerArray` | best effort, keep last 5 |
//! | `/phri/depth` | `sensor_msgs/Image` (16UC1) | best effort, keep last 1 |
//! | `/phri/points` | `sensor_msgs/PointCloud2` | best effort, keep last 1 |
//! | `/phri/request` (taken) | `std_msgs/String` | reliable, keep last 10 |

pub mod convert;
pub mod msgs;
pub mod request;

use phri_config::{Config, Ros2Config};
use phri_ipc::{CollabState, ControlStatus, FrameHeader, HriRequest, Residual};
use phri_viz::status::{Status, Thresholds};
use phri_viz::RobotView;

pub use convert::{Clock, BASE_FRAME, CAMERA_FRAME};
use msgs::{
    DiagnosticArray, DiagnosticStatus, Header, Image, JointState, KeyValue, PointCloud2, TfMessage,
    WrenchStamped,
};
pub use request::RequestError;

/// Why the bridge cannot start.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    #[error("{0}")]
    Config(String),
}

/// A `/phri/request` the bridge did not pass on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refused {
    /// `[ros2] accept_requests = false`: ROS 2 peers are not trusted
    #[error("requests from ROS 2 are refused (ros2.accept_requests = false)")]
    NotAccepted,
    #[error(transparent)]
    Malformed(#[from] RequestError),
}

/// Published and refused, per topic, since the bridge started.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub joint_states: u64,
    pub tf: u64,
    pub status: u64,
    pub contact_force: u64,
    pub repulsion: u64,
    pub depth: u64,
    pub points: u64,
    pub requests: u64,
    pub requests_refused: u64,
}

/// What one robot state gives.
pub struct StateOut<'a> {
    pub joint_state: Option<&'a JointState>,
    pub tf: Option<TfMessage>,
}

/// What one depth frame gives.
pub struct FrameOut<'a> {
    pub image: Option<&'a Image>,
    pub points: Option<&'a PointCloud2>,
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
    /// the arm's name (`[robot] name`)
    robot: String,
    pub counts: Counts,
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
            robot: config.robot.name.clone(),
            counts: Counts::default(),
        })
    }

    /// The joints' names, in `/joint_states`' order (the model's).
    pub fn joint_names(&self) -> &[String] {
        self.view.joint_names()
    }

    /// A robot state: `/joint_states` every `joint_states_every`-th, `/tf`
    /// (each moving link in [`BASE_FRAME`]) every `tf_every`-th.
    pub fn state(&mut self, s: &phri_ipc::JointState, clock: &Clock) -> StateOut<'_> {
        self.states += 1;
        let stamp = clock.ros(s.published_ns);
        let mut tf = None;
        if self.states.is_multiple_of(u64::from(self.cfg.tf_every)) {
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
        if self
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
    /// thresholds as one `DiagnosticStatus` named `phri`, its level ERROR on
    /// a collision, WARN on a contact, STALE before the controller reported.
    pub fn status(
        &mut self,
        now_ns: u64,
        clock: &Clock,
        control: Option<&ControlStatus>,
        collab: Option<&CollabState>,
        residual: Option<&Residual>,
    ) -> Option<DiagnosticArray> {
        if !self.status_every.due(now_ns) {
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
        let values = match serde_json::to_value(&s) {
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
        if !self.force_every.due(now_ns) {
            return None;
        }
        self.counts.contact_force += 1;
        Some(convert::contact_wrench(c, clock.ros(c.stamp_ns)))
    }

    /// `/phri/repulsion` due at phri's clock `now_ns`?
    pub fn repulsion_due(&mut self, now_ns: u64) -> bool {
        let due = self.repulsion_every.due(now_ns);
        if due {
            self.counts.repulsion += 1;
        }
        due
    }

    /// A new filtered depth frame: `/phri/depth` every `depth_every`-th,
    /// `/phri/points` every `points_every`-th.
    pub fn frame(&mut self, h: &FrameHeader, depth: &[u16], clock: &Clock) -> FrameOut<'_> {
        self.frames += 1;
        let stamp = clock.ros(if h.capture_wall_ns > 0 {
            h.capture_wall_ns
        } else {
            h.published_ns
        });
        let image = self.frames.is_multiple_of(u64::from(self.cfg.depth_every))
            && convert::depth_image(h, depth, stamp, &mut self.image);
        let points = self.frames.is_multiple_of(u64::from(self.cfg.points_every))
            && convert::points(
                h,
                depth,
                self.cfg.points_stride as usize,
                stamp,
                &mut self.cloud,
            );
        self.counts.depth += u64::from(image);
        self.counts.points += u64::from(points);
        FrameOut {
            image: image.then_some(&self.image),
            points: points.then_some(&self.cloud),
        }
    }

    /// A `/phri/request` text received at `now_ns` [CLOCK_MONOTONIC]: the
    /// request for `hri/request`, or why it is refused.
    pub fn request(&mut self, text: &str, now_ns: u64) -> Result<HriRequest, Refused> {
        if !self.cfg.accept_requests {
            self.counts.requests_refused += 1;
            return Err(Refused::NotAccepted);
        }
        // numbers that grow across restarts: microseconds of CLOCK_MONOTONIC
        self.request_seq = (now_ns / 1_000).max(self.request_seq + 1);
        match request::parse(text, self.request_seq, now_ns) {
            Ok(r) => {
                self.counts.requests += 1;
                Ok(r)
            }
            Err(e) => {
                self.counts.requests_refused += 1;
                Err(e.into())
            }
        }
    }
}
