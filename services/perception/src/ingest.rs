//! Depth ingestion: validate a frame, remove the robot's own pixels at the
//! joint state nearest the frame's capture time.

use phri_depth::{Capsule, SelfFilter, SelfFilterParams};
use phri_ipc::{FrameHeader, MAX_DOF};
use phri_model::{Data, Model};

use crate::camera::header_camera;
use crate::robot::robot_capsules;

/// A frame sequence at or below this after a higher one means the camera restarted.
const RESTARTED_SEQ: u64 = 2;

/// Why a frame was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FrameError {
    #[error("frame {seq}: {got} pixels, the header says {width}×{height}")]
    Size {
        seq: u64,
        got: usize,
        width: u32,
        height: u32,
    },
    #[error("frame {seq}: {0}", seq = .1)]
    Camera(String, u64),
    #[error("frame {seq}: depth scale {scale} m per unit (this pipeline works in millimetres)")]
    Scale { seq: u64, scale: f64 },
    #[error("frame {seq}: captured {age_ms:.0} ms ago (limit {limit_ms:.0} ms)")]
    Stale {
        seq: u64,
        age_ms: f64,
        limit_ms: f64,
    },
    #[error("frame {seq}: capture time lies {ahead_ms:.1} ms in the future")]
    Future { seq: u64, ahead_ms: f64 },
    #[error("frame {seq}: sequence went back from {last}")]
    Sequence { seq: u64, last: u64 },
    #[error("frame {seq}: no valid pixel")]
    Empty { seq: u64 },
    #[error("frame {seq}: no joint state within {limit_ms:.0} ms of the capture time")]
    NoJointState { seq: u64, limit_ms: f64 },
}

/// Recent joint states (stamp [ns], q), newest last; fixed capacity.
pub struct StateHistory {
    n: usize,
    stamps: Vec<u64>,
    q: Vec<f64>,
    head: usize,
    len: usize,
}

impl StateHistory {
    pub fn new(n: usize, capacity: usize) -> StateHistory {
        StateHistory {
            n,
            stamps: vec![0; capacity],
            q: vec![0.0; capacity * n],
            head: 0,
            len: 0,
        }
    }

    pub fn push(&mut self, stamp_ns: u64, q: &[f64]) {
        let cap = self.stamps.len();
        self.stamps[self.head] = stamp_ns;
        self.q[self.head * self.n..(self.head + 1) * self.n].copy_from_slice(&q[..self.n]);
        self.head = (self.head + 1) % cap;
        self.len = (self.len + 1).min(cap);
    }

    /// The state nearest `stamp_ns`: (stamp, q).
    pub fn nearest(&self, stamp_ns: u64) -> Option<(u64, &[f64])> {
        let cap = self.stamps.len();
        (0..self.len)
            .map(|k| (self.head + cap - 1 - k) % cap)
            .min_by_key(|&i| self.stamps[i].abs_diff(stamp_ns))
            .map(|i| (self.stamps[i], &self.q[i * self.n..(i + 1) * self.n]))
    }
}

/// Ingestion state; `step` allocates nothing after the first frame.
pub struct Ingest {
    model: Model,
    data: Data,
    params: SelfFilterParams,
    filter: Option<(u64, SelfFilter)>,
    robot: Vec<Capsule>,
    last_seq: Option<u64>,
    max_state_gap_ns: u64,
    max_age_ns: u64,
}

/// What [`Ingest::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IngestOutcome {
    pub removed: u32,
    pub valid: u32,
}

impl Ingest {
    pub fn new(
        model: Model,
        params: SelfFilterParams,
        max_state_gap_ms: f64,
        max_frame_age_ms: f64,
    ) -> Ingest {
        Ingest {
            data: Data::new(&model),
            params,
            filter: None,
            robot: Vec::with_capacity(32),
            last_seq: None,
            max_state_gap_ns: (max_state_gap_ms * 1e6) as u64,
            max_age_ns: (max_frame_age_ms * 1e6) as u64,
            model,
        }
    }

    /// Validate `header`/`input`, copy into `out` without the robot's pixels,
    /// and complete `header` (joint state used, counts). `now_ns` is on the
    /// robot's clock, as the capture time.
    pub fn step(
        &mut self,
        header: &mut FrameHeader,
        input: &[u16],
        states: &StateHistory,
        now_ns: u64,
        out: &mut [u16],
    ) -> Result<IngestOutcome, FrameError> {
        let seq = header.seq;
        let pixels = header.width as usize * header.height as usize;
        if input.len() != pixels || out.len() < pixels || pixels == 0 {
            return Err(FrameError::Size {
                seq,
                got: input.len(),
                width: header.width,
                height: header.height,
            });
        }
        let (k, pose) = header_camera(header).map_err(|e| FrameError::Camera(e, seq))?;
        if (header.depth_scale - 0.001).abs() > 1e-12 {
            return Err(FrameError::Scale {
                seq,
                scale: header.depth_scale,
            });
        }
        if header.capture_ns > now_ns + 5_000_000 {
            return Err(FrameError::Future {
                seq,
                ahead_ms: (header.capture_ns - now_ns) as f64 * 1e-6,
            });
        }
        let age = now_ns.saturating_sub(header.capture_ns);
        if age > self.max_age_ns {
            return Err(FrameError::Stale {
                seq,
                age_ms: age as f64 * 1e-6,
                limit_ms: self.max_age_ns as f64 * 1e-6,
            });
        }
        // a repeated or older frame is refused; a sequence that starts over is a
        // camera that restarted: its frames are accepted
        if let Some(last) = self.last_seq {
            if seq <= last && seq > RESTARTED_SEQ {
                return Err(FrameError::Sequence { seq, last });
            }
        }
        let (stamp, q) = states
            .nearest(header.capture_ns)
            .ok_or(FrameError::NoJointState {
                seq,
                limit_ms: self.max_state_gap_ns as f64 * 1e-6,
            })?;
        if stamp.abs_diff(header.capture_ns) > self.max_state_gap_ns {
            return Err(FrameError::NoJointState {
                seq,
                limit_ms: self.max_state_gap_ns as f64 * 1e-6,
            });
        }
        let out = &mut out[..pixels];
        out.copy_from_slice(input);
        let valid_in = out.iter().filter(|&&d| d > 0).count();
        if valid_in == 0 {
            return Err(FrameError::Empty { seq });
        }
        // a filter per camera geometry (rebuilt only when the camera changes)
        let key = header.width as u64
            ^ (header.height as u64) << 16
            ^ header.fx.to_bits()
            ^ header.pose_t[0].to_bits().rotate_left(7)
            ^ header.pose_t[2].to_bits().rotate_left(13);
        if self.filter.as_ref().is_none_or(|(k0, _)| *k0 != key) {
            self.filter = Some((
                key,
                SelfFilter::new(k, pose, self.params)
                    .map_err(|e| FrameError::Camera(e.to_string(), seq))?,
            ));
        }
        let n = self.model.nv().min(MAX_DOF);
        phri_model::forward_kinematics(&self.model, &mut self.data, &q[..n])
            .map_err(|e| FrameError::Camera(e.to_string(), seq))?;
        robot_capsules(&self.model, &self.data, 0.0, &mut self.robot);
        let removed = match self.filter.as_mut() {
            Some((_, f)) => f
                .apply(&self.robot, out)
                .map_err(|e| FrameError::Camera(e.to_string(), seq))?,
            None => 0,
        };
        self.last_seq = Some(seq);
        header.q = [0.0; MAX_DOF];
        header.q[..n].copy_from_slice(&q[..n]);
        header.q_stamp_ns = stamp;
        header.dof = n as u32;
        header.removed_pixels = removed as u32;
        header.valid_pixels = (valid_in - removed) as u32;
        Ok(IngestOutcome {
            removed: removed as u32,
            valid: header.valid_pixels,
        })
    }
}
