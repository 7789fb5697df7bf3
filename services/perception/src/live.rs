//! What every camera process shares, whatever its source (the simulated
//! camera, a Kinect, a ROS 2 camera, a replay): the frame's header (frame
//! number, intrinsics as used on the channel, the configured pose, capture
//! times), the checks of a real capture time (not from the future, not older
//! than `[camera] max_age_s`), the drops counted by cause and the camera's
//! status message. [`CameraStamps`] is the pure part; [`CameraOut`] wires it
//! to `camera/depth` and `camera/status`.

use phri_config::{CameraConfig, CameraSource, Invalid};
use phri_depth::{CameraPose, Intrinsics};
use phri_ipc::{
    CameraStatus, FrameChannel, FrameHeader, FramePublisher, IpcError, IpcNode, JointState,
    LatestReader, Publisher, Zeroed, CAMERA_STATUS, FRAME_PIXELS, ROBOT_STATE,
};

use crate::camera::fill_camera_header;

/// How often a camera publishes its status \[ns\]: 2 Hz.
pub const STATUS_PERIOD_NS: u64 = 500_000_000;

/// A stamp this far ahead of the clock still counts as now \[ns\] (the
/// clocks of a camera's host and of this one, mapped, differ by this much).
pub const FUTURE_TOLERANCE_NS: u64 = 5_000_000;

/// Why a frame was not published.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DropCause {
    /// captured longer ago than `[camera] max_age_s`
    Old,
    /// stamped in the future
    Future,
    /// wrong size or step, an encoding refused, values that are not depths
    Malformed,
    /// no usable intrinsics yet
    NoInfo,
    /// the source ran behind its rate
    Behind,
}

/// A camera's frame numbers, header fields, capture-time checks and drop
/// counts; no I/O.
#[derive(Clone, Debug)]
pub struct CameraStamps {
    pose: CameraPose,
    max_age_ns: u64,
    seq: u64,
    status: CameraStatus,
}

impl CameraStamps {
    /// Camera `index` of `[[camera]]`, configured by `cfg` (its pose, its
    /// age bound, its source).
    pub fn new(index: usize, cfg: &CameraConfig) -> Result<CameraStamps, Invalid> {
        let mut status = CameraStatus::zeroed();
        status.camera = index as u32;
        status.source = source_code(cfg.source);
        Ok(CameraStamps {
            pose: cfg.pose()?,
            max_age_ns: (cfg.max_age_s * 1e9) as u64,
            seq: 0,
            status,
        })
    }

    /// The camera's pose in the base frame.
    pub fn pose(&self) -> CameraPose {
        self.pose
    }

    /// Whether a frame captured at `capture_ns` may still be published at
    /// `now_ns` (both [ns, CLOCK_MONOTONIC]): not from the future (beyond
    /// [`FUTURE_TOLERANCE_NS`]), not older than the age bound. A refusal is
    /// counted.
    pub fn admit(&mut self, capture_ns: u64, now_ns: u64) -> Result<(), DropCause> {
        let cause = if capture_ns > now_ns.saturating_add(FUTURE_TOLERANCE_NS) {
            DropCause::Future
        } else if now_ns.saturating_sub(capture_ns) > self.max_age_ns {
            DropCause::Old
        } else {
            return Ok(());
        };
        self.count(cause);
        Err(cause)
    }

    /// One frame dropped for `cause`.
    pub fn count(&mut self, cause: DropCause) {
        let s = &mut self.status;
        let n = match cause {
            DropCause::Old => &mut s.dropped_old,
            DropCause::Future => &mut s.dropped_future,
            DropCause::Malformed => &mut s.dropped_malformed,
            DropCause::NoInfo => &mut s.dropped_no_info,
            DropCause::Behind => &mut s.dropped_behind,
        };
        *n += 1;
    }

    /// `n` frames dropped for `cause` (a source that counts its own).
    pub fn count_n(&mut self, cause: DropCause, n: u64) {
        for _ in 0..n.min(1 << 20) {
            self.count(cause);
        }
    }

    /// The whole header of the next frame: its number, intrinsics `k` as
    /// used on the channel, the pose, capture at `capture_robot_ns` [ns,
    /// robot clock] and `capture_wall_ns` [ns, CLOCK_MONOTONIC], the valid
    /// pixels of `depths`. Counts the frame as published.
    pub fn stamp(
        &mut self,
        header: &mut FrameHeader,
        k: &Intrinsics,
        capture_robot_ns: u64,
        capture_wall_ns: u64,
        depths: &[u16],
    ) {
        self.seq += 1;
        *header = FrameHeader::zeroed();
        fill_camera_header(header, self.seq, k, &self.pose);
        header.capture_ns = capture_robot_ns;
        header.capture_wall_ns = capture_wall_ns;
        header.valid_pixels = depths.iter().filter(|&&d| d > 0).count() as u32;
        self.status.frames += 1;
    }

    /// One frame published by a source that stamps its own header (the
    /// simulated camera).
    pub fn published(&mut self) {
        self.status.frames += 1;
    }

    /// The status message as of `now_ns`, its number advanced.
    pub fn status(&mut self, now_ns: u64) -> CameraStatus {
        self.status.seq += 1;
        self.status.stamp_ns = now_ns;
        self.status
    }

    /// The counts so far.
    pub fn counts(&self) -> &CameraStatus {
        &self.status
    }
}

/// `CameraStatus::source` of a source.
pub fn source_code(s: CameraSource) -> u32 {
    match s {
        CameraSource::Sim => 0,
        CameraSource::Freenect => 1,
        CameraSource::Ros2 => 2,
        CameraSource::Replay => 3,
    }
}

/// The source a `CameraStatus::source` names.
pub fn source_of_code(code: u32) -> Option<CameraSource> {
    CameraSource::ALL
        .into_iter()
        .find(|s| source_code(*s) == code)
}

/// The robot's clock from CLOCK_MONOTONIC: the newest `robot/state` tells
/// both (measured at `stamp_ns`, published at `published_ns`); without one,
/// the robot's clock is taken as CLOCK_MONOTONIC (the simulated robot's is).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RobotClock {
    /// robot clock − CLOCK_MONOTONIC [ns]
    offset_ns: i64,
}

impl RobotClock {
    /// From the newest robot state, if any.
    pub fn from_state(state: Option<&JointState>) -> RobotClock {
        RobotClock {
            offset_ns: state.map_or(0, |s| s.stamp_ns as i64 - s.published_ns as i64),
        }
    }

    /// `mono_ns` [ns, CLOCK_MONOTONIC] on the robot's clock.
    pub fn robot_ns(&self, mono_ns: u64) -> u64 {
        (mono_ns as i64).saturating_add(self.offset_ns).max(0) as u64
    }
}

/// A camera process's output: frames on its `camera/depth` channel, written
/// in place in shared memory, and its status on `camera/status`.
pub struct CameraOut {
    frames: FramePublisher,
    status: Publisher<CameraStatus>,
    states: LatestReader<JointState>,
    stamps: CameraStamps,
    next_status_ns: u64,
}

impl CameraOut {
    /// Camera `index`'s output on `channel`, frames of at most the
    /// channel's 640×480.
    pub fn new(
        node: &IpcNode,
        channel: &FrameChannel,
        stamps: CameraStamps,
    ) -> Result<CameraOut, IpcError> {
        Ok(CameraOut {
            frames: channel.frame_publisher(node, FRAME_PIXELS)?,
            status: CAMERA_STATUS.publisher(node)?,
            states: ROBOT_STATE.latest_reader(node)?,
            stamps,
            next_status_ns: 0,
        })
    }

    /// The checks and counts.
    pub fn stamps(&mut self) -> &mut CameraStamps {
        &mut self.stamps
    }

    /// Publish a frame of `k.pixel_count()` depths \[mm\] captured at
    /// `capture_wall_ns` [ns, CLOCK_MONOTONIC], written by `fill` straight
    /// into the shared-memory sample. Refused (and counted) when the capture
    /// time is not admitted or `fill` refuses the frame: no part of a
    /// refused frame is ever sent.
    pub fn publish(
        &mut self,
        k: &Intrinsics,
        capture_wall_ns: u64,
        now_ns: u64,
        fill: impl FnOnce(&mut [u16]) -> Result<(), DropCause>,
    ) -> Result<Option<DropCause>, IpcError> {
        let pixels = k.pixel_count();
        if pixels == 0 || pixels > FRAME_PIXELS {
            self.stamps.count(DropCause::Malformed);
            return Ok(Some(DropCause::Malformed));
        }
        if let Err(cause) = self.stamps.admit(capture_wall_ns, now_ns) {
            return Ok(Some(cause));
        }
        let mut sample = self.frames.loan(pixels)?;
        if let Err(cause) = fill(sample.payload_mut()) {
            self.stamps.count(cause);
            return Ok(Some(cause));
        }
        self.states.update()?;
        let clock = RobotClock::from_state(self.states.get());
        let mut header = FrameHeader::zeroed();
        self.stamps.stamp(
            &mut header,
            k,
            clock.robot_ns(capture_wall_ns),
            capture_wall_ns,
            sample.payload(),
        );
        header.published_ns = phri_runtime::now_ns();
        *sample.user_header_mut() = header;
        self.frames.send(sample)?;
        Ok(None)
    }

    /// Publish the status when due (2 Hz) or when `force`d (at exit).
    pub fn status_tick(&mut self, now_ns: u64, force: bool) -> Result<(), IpcError> {
        if force || now_ns >= self.next_status_ns {
            self.next_status_ns = now_ns + STATUS_PERIOD_NS;
            let s = self.stamps.status(now_ns);
            self.status.publish(&s)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamps() -> CameraStamps {
        let mut cfg = phri_config::Config::defaults().camera;
        cfg.max_age_s = 0.1;
        CameraStamps::new(1, &cfg).unwrap()
    }

    #[test]
    fn a_capture_from_the_future_or_too_old_is_dropped_and_counted() {
        let mut s = stamps();
        let now = 10_000_000_000;
        assert_eq!(s.admit(now, now), Ok(()));
        assert_eq!(s.admit(now + FUTURE_TOLERANCE_NS, now), Ok(()));
        assert_eq!(s.admit(now + 6_000_000, now), Err(DropCause::Future));
        assert_eq!(s.admit(now - 100_000_000, now), Ok(()));
        assert_eq!(s.admit(now - 100_000_001, now), Err(DropCause::Old));
        s.count(DropCause::Malformed);
        let st = s.status(now);
        assert_eq!(
            (
                st.dropped_future,
                st.dropped_old,
                st.dropped_malformed,
                st.frames
            ),
            (1, 1, 1, 0)
        );
        assert_eq!((st.camera, st.seq), (1, 1));
    }

    #[test]
    fn a_frame_is_numbered_and_stamped_on_both_clocks() {
        let mut s = stamps();
        let k = phri_config::Config::defaults().camera.intrinsics;
        let mut h = FrameHeader::zeroed();
        let depths = [0u16, 700, 0, 1200];
        s.stamp(&mut h, &k, 5, 7, &depths);
        s.stamp(&mut h, &k, 6, 8, &depths);
        assert_eq!((h.seq, h.capture_ns, h.capture_wall_ns), (2, 6, 8));
        assert_eq!((h.fx, h.cx, h.valid_pixels), (k.fx, k.cx, 2));
        assert_eq!(s.counts().frames, 2);
    }

    #[test]
    fn the_robot_clock_follows_the_newest_state() {
        assert_eq!(RobotClock::from_state(None).robot_ns(42), 42);
        let mut st = JointState::zeroed();
        st.stamp_ns = 1_000;
        st.published_ns = 1_300;
        assert_eq!(RobotClock::from_state(Some(&st)).robot_ns(2_000), 1_700);
        assert_eq!(RobotClock::from_state(Some(&st)).robot_ns(100), 0);
    }

    #[test]
    fn every_source_has_its_own_code() {
        for s in CameraSource::ALL {
            assert_eq!(source_of_code(source_code(s)), Some(s));
        }
    }
}
