//! Depth ingestion: validate a frame, remove isolated flying pixels (sensor
//! noise that would be an obstacle next to the robot) and the robot's own
//! pixels at the joint state nearest the frame's capture time.

use phri_config::{IngestConfig, Invalid};
use phri_depth::{
    Capsule, DepthError, Filtered, FlyingPixels, Intrinsics, SelfFilter, SelfFilterParams,
};
use phri_ipc::{FrameHeader, JointState, MAX_DOF};
use phri_model::{Data, Model, ModelError};

use crate::camera::{header_camera, HeaderError, DEPTH_SCALE_M};
use crate::mask::{self, HandMask, Masked};
use crate::robot::robot_capsules;

/// A frame sequence at or below this after a higher one means the camera restarted.
const RESTARTED_SEQ: u64 = 2;

/// Why a frame was refused.
#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    /// the payload is not the header's width × height (or the output is smaller)
    #[error("frame {seq}: {got} pixels, the header says {width}×{height}")]
    Size {
        /// the frame's sequence number
        seq: u64,
        /// depths in the payload
        got: usize,
        /// width in the header \[px\]
        width: u32,
        /// height in the header \[px\]
        height: u32,
    },
    /// the header's intrinsics or pose describe no camera
    #[error("frame {seq}: {source}")]
    Camera {
        /// the frame's sequence number
        seq: u64,
        /// what is wrong with the header
        source: HeaderError,
    },
    /// the self-filter refused the camera or the frame
    #[error("frame {seq}: self-filter: {source}")]
    Filter {
        /// the frame's sequence number
        seq: u64,
        /// the filter's error
        source: DepthError,
    },
    /// the joint state could not be placed (kinematics)
    #[error("frame {seq}: {source}")]
    Model {
        /// the frame's sequence number
        seq: u64,
        /// the kinematics error
        source: ModelError,
    },
    /// depths in another unit than millimetres
    #[error("frame {seq}: depth scale {scale} m per unit (this pipeline works in millimetres)")]
    Scale {
        /// the frame's sequence number
        seq: u64,
        /// the header's depth scale \[m\] per unit
        scale: f64,
    },
    /// captured longer ago than `[perception] max_frame_age_ms`
    #[error("frame {seq}: captured {age_ms:.0} ms ago (limit {limit_ms:.0} ms)")]
    Stale {
        /// the frame's sequence number
        seq: u64,
        /// time since the capture \[ms\]
        age_ms: f64,
        /// the age allowed \[ms\]
        limit_ms: f64,
    },
    /// captured more than 5 ms after the time the frame is handled
    #[error("frame {seq}: capture time lies {ahead_ms:.1} ms in the future")]
    Future {
        /// the frame's sequence number
        seq: u64,
        /// how far ahead \[ms\]
        ahead_ms: f64,
    },
    /// a frame number not above the last accepted one (a camera that
    /// restarted, numbering its frames from 1 again, is accepted)
    #[error("frame {seq}: sequence went back from {last}")]
    Sequence {
        /// the frame's sequence number
        seq: u64,
        /// the last accepted frame's sequence number
        last: u64,
    },
    /// no pixel with a reading (once isolated flying pixels are removed)
    #[error("frame {seq}: no valid pixel")]
    Empty {
        /// the frame's sequence number
        seq: u64,
    },
    /// no joint state within `[perception] max_state_gap_ms` of the capture time
    #[error("frame {seq}: no joint state within {limit_ms:.0} ms of the capture time")]
    NoJointState {
        /// the frame's sequence number
        seq: u64,
        /// the gap allowed \[ms\]
        limit_ms: f64,
    },
}

/// Recent joint states (stamp [ns, robot clock], q \[rad\]), newest last;
/// fixed capacity, the oldest overwritten.
pub struct StateHistory {
    n: usize,
    stamps: Vec<u64>,
    q: Vec<f64>,
    head: usize,
    len: usize,
    newest_ns: u64,
}

impl StateHistory {
    /// Room for `capacity` (≥ 1) states of `n` joints.
    pub fn new(n: usize, capacity: usize) -> StateHistory {
        let capacity = capacity.max(1);
        StateHistory {
            n,
            stamps: vec![0; capacity],
            q: vec![0.0; capacity * n],
            head: 0,
            len: 0,
            newest_ns: 0,
        }
    }

    /// Keep positions `q` (at least `n` of them) measured at `stamp_ns`.
    pub fn push(&mut self, stamp_ns: u64, q: &[f64]) {
        let cap = self.stamps.len();
        self.stamps[self.head] = stamp_ns;
        self.q[self.head * self.n..(self.head + 1) * self.n].copy_from_slice(&q[..self.n]);
        self.head = (self.head + 1) % cap;
        self.len = (self.len + 1).min(cap);
        self.newest_ns = self.newest_ns.max(stamp_ns);
    }

    /// Keep a robot state if it has this history's joint count; `false` (and
    /// nothing kept) otherwise.
    pub fn push_state(&mut self, s: &JointState) -> bool {
        if s.dof as usize != self.n || self.n > s.q.len() {
            return false;
        }
        self.push(s.stamp_ns, &s.q[..self.n]);
        true
    }

    /// The latest stamp kept [ns, robot clock] (0: none yet): ingestion's
    /// "now" for judging a frame's age.
    pub fn newest_ns(&self) -> u64 {
        self.newest_ns
    }

    /// No state pushed yet.
    pub fn is_empty(&self) -> bool {
        self.len == 0
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
    /// the filters of the current camera (its intrinsics, the self-filter,
    /// the flying-pixel filter): rebuilt when the intrinsics change, the
    /// self-filter moved to every frame's pose
    filter: Option<(Intrinsics, SelfFilter, FlyingPixels)>,
    robot: Vec<Capsule>,
    last_seq: Option<u64>,
    max_state_gap_ns: u64,
    max_age_ns: u64,
    /// the collaborative hand to remove (while a collaboration is on)
    mask: Option<HandMask>,
    /// remove isolated flying pixels (off for a reader that ignores them,
    /// the person tracker)
    flying: bool,
}

/// What [`Ingest::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IngestOutcome {
    /// the robot's own pixels removed
    pub removed: u32,
    /// isolated flying pixels removed ([`FlyingPixels`])
    pub flying: u32,
    /// pixels with a reading left
    pub valid: u32,
    /// the collaborative hand's pixels removed, and the hand refined from them
    pub masked: Masked,
}

impl Ingest {
    /// Ingestion for `model` with `[perception]` settings `cfg` (validated here).
    pub fn new(model: Model, cfg: &IngestConfig) -> Result<Ingest, Invalid> {
        cfg.validate()?;
        Ok(Ingest {
            data: Data::new(&model),
            params: cfg.self_filter,
            filter: None,
            robot: Vec::with_capacity(32),
            last_seq: None,
            max_state_gap_ns: (cfg.max_state_gap_ms * 1e6) as u64,
            max_age_ns: (cfg.max_frame_age_ms * 1e6) as u64,
            mask: None,
            flying: true,
            model,
        })
    }

    /// Leave isolated flying pixels in (a reader that ignores them anyway:
    /// the person tracker, whose segmentation drops what is too small).
    pub fn keep_flying_pixels(mut self) -> Ingest {
        self.flying = false;
        self
    }

    /// From the next frame on, remove the collaborative hand of `mask` (the
    /// paper's Fig. 5); `None`: remove nothing (no collaboration).
    pub fn set_mask(&mut self, mask: Option<HandMask>) {
        self.mask = mask;
    }

    /// Frame `seq` has no joint state within the gap allowed.
    fn no_joint_state(&self, seq: u64) -> FrameError {
        FrameError::NoJointState {
            seq,
            limit_ms: self.max_state_gap_ns as f64 * 1e-6,
        }
    }

    /// Frame `seq` captured at `capture_ns` handled at `now_ns` (both [ns,
    /// robot clock]): a state to match it exists, it is not from the future
    /// (5 ms) and not older than the age bound.
    fn check_time(
        &self,
        seq: u64,
        capture_ns: u64,
        states: &StateHistory,
        now_ns: u64,
    ) -> Result<(), FrameError> {
        // no state at all (a service's first frames, `now_ns` its newest
        // state's stamp, still 0): no state to match, not a frame from the
        // future
        if states.is_empty() {
            return Err(self.no_joint_state(seq));
        }
        if capture_ns > now_ns + 5_000_000 {
            return Err(FrameError::Future {
                seq,
                ahead_ms: (capture_ns - now_ns) as f64 * 1e-6,
            });
        }
        let age = now_ns.saturating_sub(capture_ns);
        if age > self.max_age_ns {
            return Err(FrameError::Stale {
                seq,
                age_ms: age as f64 * 1e-6,
                limit_ms: self.max_age_ns as f64 * 1e-6,
            });
        }
        Ok(())
    }

    /// Validate `header`/`input` (size, camera, millimetres, age, sequence),
    /// copy the depths \[mm\] into `out` without isolated flying pixels
    /// ([`FlyingPixels`]) and without the robot's pixels (the arm at the state
    /// of `states` nearest the capture time), and complete `header` (joint
    /// state used, the robot's removed pixels, valid pixels left). `now_ns` [ns, robot
    /// clock] is when the frame is handled: the service passes the newest
    /// state's stamp ([`StateHistory::newest_ns`]), the lock-step cell the
    /// capture time plus the perception latency.
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
        let (k, pose) =
            header_camera(header).map_err(|source| FrameError::Camera { seq, source })?;
        if (header.depth_scale - DEPTH_SCALE_M).abs() > 1e-12 {
            return Err(FrameError::Scale {
                seq,
                scale: header.depth_scale,
            });
        }
        self.check_time(seq, header.capture_ns, states, now_ns)?;
        // a repeated or older frame is refused; a sequence that starts over is a
        // camera that restarted: its frames are accepted
        if let Some(last) = self.last_seq {
            if seq <= last && seq > RESTARTED_SEQ {
                return Err(FrameError::Sequence { seq, last });
            }
        }
        let (stamp, q) = states
            .nearest(header.capture_ns)
            .ok_or_else(|| self.no_joint_state(seq))?;
        if stamp.abs_diff(header.capture_ns) > self.max_state_gap_ns {
            return Err(self.no_joint_state(seq));
        }
        let out = &mut out[..pixels];
        // filters per camera (rebuilt only when its intrinsics change; a
        // camera that moves moves the self-filter, allocating nothing)
        let filter_err = |source| FrameError::Filter { seq, source };
        match self.filter.as_mut() {
            Some((k0, f, _)) if *k0 == k => f.set_pose(pose),
            _ => {
                self.filter = Some((
                    k,
                    SelfFilter::new(k, pose, self.params).map_err(filter_err)?,
                    FlyingPixels::new(&k).map_err(filter_err)?,
                ))
            }
        }
        let filtered = match self.filter.as_ref() {
            Some((_, _, fp)) if self.flying => fp.filter(input, out).map_err(filter_err)?,
            _ => {
                out.copy_from_slice(input);
                Filtered {
                    removed: 0,
                    valid: out.iter().filter(|&&d| d > 0).count(),
                }
            }
        };
        let (flying, valid_in) = (filtered.removed, filtered.valid);
        if valid_in == 0 {
            return Err(FrameError::Empty { seq });
        }
        let n = self.model.nv().min(MAX_DOF);
        phri_model::forward_kinematics(&self.model, &mut self.data, &q[..n])
            .map_err(|source| FrameError::Model { seq, source })?;
        robot_capsules(&self.model, &self.data, 0.0, &mut self.robot);
        let removed = match self.filter.as_mut() {
            Some((_, f, _)) => f
                .apply(&self.robot, out)
                .map_err(|source| FrameError::Filter { seq, source })?,
            None => 0,
        };
        let masked = match self.mask.as_ref() {
            Some(m) => mask::apply(&k, &pose, m, out),
            None => Masked::default(),
        };
        let removed = removed + masked.pixels as usize;
        self.last_seq = Some(seq);
        header.q = [0.0; MAX_DOF];
        header.q[..n].copy_from_slice(&q[..n]);
        header.q_stamp_ns = stamp;
        header.dof = n as u32;
        header.removed_pixels = removed as u32;
        header.valid_pixels = valid_in.saturating_sub(removed) as u32;
        Ok(IngestOutcome {
            removed: removed as u32 - masked.pixels,
            flying: flying as u32,
            valid: header.valid_pixels,
            masked,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn state(stamp_ns: u64, dof: u32, q0: f64) -> JointState {
        let mut s = JointState::zeroed();
        s.stamp_ns = stamp_ns;
        s.dof = dof;
        s.q[..dof as usize].fill(q0);
        s
    }

    #[test]
    fn the_history_keeps_the_robots_states_and_finds_the_nearest() {
        let mut h = StateHistory::new(2, 3);
        assert!(h.nearest(5).is_none());
        assert_eq!(h.newest_ns(), 0);
        assert!(!h.push_state(&state(10, 3, 1.0)), "another joint count");
        assert!(h.nearest(10).is_none());
        for (t, q) in [(10, 0.1), (20, 0.2), (30, 0.3), (40, 0.4)] {
            assert!(h.push_state(&state(t, 2, q)));
        }
        assert_eq!(h.newest_ns(), 40);
        assert_eq!(h.nearest(24), Some((20, &[0.2, 0.2][..])));
        // capacity 3: the oldest (10) is gone
        assert_eq!(h.nearest(0).map(|x| x.0), Some(20));
        // an older stamp arriving late does not move "now" back
        h.push_state(&state(35, 2, 0.35));
        assert_eq!(h.newest_ns(), 40);
    }
}
