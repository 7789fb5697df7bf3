//! The Kinect v1's 32-bit frame timestamps mapped onto CLOCK_MONOTONIC.
//!
//! The device stamps each frame with a free-running counter at 60 MHz
//! (libfreenect's OpenNI driver divides it by 60 for microseconds; a
//! maintainer's note in OpenKinect/libfreenect issue 681: "the clock runs at
//! 60MHz"); consecutive depth frames at 30 Hz differ by ~2 000 000 ticks.
//! It wraps every 2³²/60 MHz ≈ 71.6 s.
//!
//! The estimate: every frame arrives some delay after its capture (USB
//! transfer, libfreenect's processing, our scheduling). Writing the device
//! time (unwrapped) as t and the callback time as c, the offset c − t is
//! the clock offset plus that delay; its minimum over a recent window is
//! the offset plus the smallest delay seen, so capture ≈ min(c − t) + t:
//! never after the callback, as close to the capture as the best-served
//! frame of the window allows. The two clocks run at slightly different
//! rates (a crystal's parts per million; a fakenect recording played a
//! little slower than it was stamped): the offset drifts, and the window's
//! minimum would lag that drift by up to the window's length. So the
//! minimum is taken along the drift: the drift is the slope between the
//! smallest offsets of the window's older and newer halves (at most
//! [`MAX_SKEW`]), and each frame's offset is carried to now along it. Timestamps that go backwards (a new stream,
//! a replay starting over), repeat, or disagree with the callback clock by
//! more than [`MAX_DISAGREEMENT_NS`] restart the estimate; that frame's
//! capture is its callback time.

use std::collections::VecDeque;

/// The device timestamp's rate [ticks/s].
pub const TICK_HZ: u64 = 60_000_000;
/// Frames in the minimum's window (3 s at 30 Hz).
pub const WINDOW: usize = 90;
/// The largest drift of the callback clock against the device's the
/// estimate follows [ns per ns]: 5 %.
pub const MAX_SKEW: f64 = 0.05;
/// Device and callback clocks disagreeing this much between two frames
/// restarts the estimate \[ns\]; also bounds the gap between frames below
/// half a wrap (35.8 s), where a wrap could not be told apart.
pub const MAX_DISAGREEMENT_NS: u64 = 1_000_000_000;

/// Device ticks → ns.
pub fn ticks_to_ns(ticks: u64) -> u64 {
    (ticks as u128 * 1_000_000_000 / TICK_HZ as u128) as u64
}

/// One frame's capture time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capture {
    /// when the frame was captured [ns, CLOCK_MONOTONIC]
    pub mono_ns: u64,
    /// from the device's timestamp (false: the callback time, the estimate
    /// just (re)started)
    pub from_device: bool,
}

/// The device clock → CLOCK_MONOTONIC mapping; pure.
#[derive(Clone, Debug, Default)]
pub struct TimestampMapper {
    /// previous frame's (device timestamp, callback time [ns])
    last: Option<(u32, u64)>,
    /// device ticks since the estimate started (unwrapped)
    ticks: u64,
    /// the window's frames: (device time [ns], callback time − device time [ns])
    offsets: VecDeque<(i128, i128)>,
    /// restarts so far (timestamps backwards, repeated, disagreeing)
    restarts: u64,
}

impl TimestampMapper {
    /// A mapper that has seen no frame yet.
    pub fn new() -> TimestampMapper {
        TimestampMapper::default()
    }

    /// Times the estimate restarted (the first frame not counted).
    pub fn restarts(&self) -> u64 {
        self.restarts
    }

    /// The capture time of a frame stamped `timestamp` [60 MHz ticks] by
    /// the device whose callback ran at `callback_ns` [ns,
    /// CLOCK_MONOTONIC]; never after `callback_ns`.
    pub fn map(&mut self, timestamp: u32, callback_ns: u64) -> Capture {
        let consistent = match self.last {
            None => false,
            Some((ts, cb)) => {
                let delta = timestamp.wrapping_sub(ts);
                let forward = delta != 0 && delta < 1 << 31;
                let device_ns = ticks_to_ns(delta as u64);
                let callback_elapsed = callback_ns.saturating_sub(cb);
                let agree = device_ns.abs_diff(callback_elapsed) <= MAX_DISAGREEMENT_NS;
                if forward && agree && callback_ns >= cb {
                    self.ticks += delta as u64;
                    true
                } else {
                    self.restarts += 1;
                    false
                }
            }
        };
        self.last = Some((timestamp, callback_ns));
        if !consistent {
            self.ticks = 0;
            self.offsets.clear();
        }
        let device_ns = ticks_to_ns(self.ticks) as i128;
        if self.offsets.len() == WINDOW {
            self.offsets.pop_front();
        }
        self.offsets
            .push_back((device_ns, callback_ns as i128 - device_ns));
        if !consistent {
            return Capture {
                mono_ns: callback_ns,
                from_device: false,
            };
        }
        let offset = self.offset_at(device_ns);
        let mono = (offset + device_ns).clamp(0, callback_ns as i128) as u64;
        Capture {
            mono_ns: mono,
            from_device: true,
        }
    }
}

impl TimestampMapper {
    /// The smallest offset of the window carried to device time `now` along
    /// the window's drift.
    fn offset_at(&self, now: i128) -> i128 {
        let lowest =
            |part: &mut dyn Iterator<Item = &(i128, i128)>| part.min_by_key(|(_, o)| *o).copied();
        // a drift needs half a second of frames to be told from jitter
        let half = self.offsets.len() / 2;
        let skew = match (
            lowest(&mut self.offsets.iter().take(half)),
            lowest(&mut self.offsets.iter().skip(half)),
        ) {
            (Some((d1, o1)), Some((d2, o2))) if d2 > d1 && self.offsets.len() >= 16 => {
                ((o2 - o1) as f64 / (d2 - d1) as f64).clamp(-MAX_SKEW, MAX_SKEW)
            }
            _ => 0.0,
        };
        self.offsets
            .iter()
            .map(|&(d, o)| o + (skew * (now - d) as f64) as i128)
            .min()
            .unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 30 Hz in device ticks.
    const FRAME_TICKS: u32 = 2_000_000;
    const FRAME_NS: u64 = 33_333_333;

    #[test]
    fn the_minimum_delay_is_recovered() {
        let mut m = TimestampMapper::new();
        let t0 = 5_000_000_000u64;
        // delays 8..20 ms, the smallest (8 ms) in the second frame
        let delays = [12u64, 8, 15, 20, 9, 11, 13, 18];
        let mut got = Vec::new();
        for (i, d) in delays.iter().enumerate() {
            let capture = t0 + i as u64 * FRAME_NS;
            let ts = 123_456u32.wrapping_add(i as u32 * FRAME_TICKS);
            got.push((capture, m.map(ts, capture + d * 1_000_000)));
        }
        // first: the callback time
        assert_eq!(got[0].1.mono_ns, t0 + 12_000_000);
        assert!(!got[0].1.from_device);
        // from the second on: capture + 8 ms (the smallest delay seen),
        // within the ns rounding of 30 Hz in ticks
        for (capture, c) in &got[1..] {
            assert!(c.from_device);
            let err = c.mono_ns as i64 - (*capture + 8_000_000) as i64;
            assert!(err.abs() < 10, "{err} ns");
        }
    }

    #[test]
    fn a_wrap_of_the_32_bit_counter_is_followed() {
        let mut m = TimestampMapper::new();
        let start = u32::MAX - 3 * FRAME_TICKS;
        let t0 = 1_000_000_000u64;
        for i in 0..8u32 {
            let ts = start.wrapping_add(i * FRAME_TICKS);
            let cb = t0 + i as u64 * FRAME_NS + 5_000_000;
            let c = m.map(ts, cb);
            if i > 0 {
                assert!(c.from_device, "frame {i}");
                assert!((c.mono_ns as i64 - cb as i64).abs() < 10);
            }
        }
        assert_eq!(m.restarts(), 0);
    }

    #[test]
    fn timestamps_going_backwards_fall_back_to_the_callback_time() {
        let mut m = TimestampMapper::new();
        let t0 = 1_000_000_000u64;
        for i in 0..5u32 {
            m.map(10 * FRAME_TICKS + i * FRAME_TICKS, t0 + i as u64 * FRAME_NS);
        }
        // a replay starting over: backwards
        let cb = t0 + 5 * FRAME_NS;
        assert_eq!(
            m.map(10 * FRAME_TICKS, cb),
            Capture {
                mono_ns: cb,
                from_device: false
            }
        );
        // a repeated stamp too
        let cb2 = cb + FRAME_NS;
        assert!(!m.map(10 * FRAME_TICKS, cb2).from_device);
        assert_eq!(m.restarts(), 2);
        // and then mapped again
        assert!(m.map(11 * FRAME_TICKS, cb2 + FRAME_NS).from_device);
    }

    #[test]
    fn clocks_that_disagree_restart_and_old_minima_are_forgotten() {
        let mut m = TimestampMapper::new();
        let t0 = 1_000_000_000u64;
        m.map(0, t0);
        // the device says 33 ms passed, the host 5 s: a gap of unknown wraps
        let c = m.map(FRAME_TICKS, t0 + 5_000_000_000);
        assert!(!c.from_device);
        // a short delay once, then a slower link: forgotten after the window
        let mut m = TimestampMapper::new();
        let mut last = None;
        for i in 0..(WINDOW as u32 + 10) {
            let delay = if i == 1 { 1_000_000 } else { 10_000_000 };
            let capture = t0 + i as u64 * FRAME_NS;
            let c = m.map(i * FRAME_TICKS, capture + delay);
            last = Some((capture, c));
        }
        let (capture, c) = last.unwrap();
        assert!((c.mono_ns as i64 - (capture + 10_000_000) as i64).abs() < 10);
    }

    #[test]
    fn a_drift_between_the_clocks_is_followed_not_lagged() {
        // frames stamped 30 Hz but delivered 2.3 % slower (a fakenect
        // recording played back), 5 ms after their capture
        let mut m = TimestampMapper::new();
        let t0 = 1_000_000_000u64;
        let mut worst = 0i64;
        for i in 0..(3 * WINDOW as u32) {
            let capture = t0 + (i as f64 * FRAME_NS as f64 * 1.023) as u64;
            let c = m.map(i * FRAME_TICKS, capture + 5_000_000);
            if i as usize > WINDOW {
                worst = worst.max((c.mono_ns as i64 - (capture + 5_000_000) as i64).abs());
            }
        }
        // the window's plain minimum lagged by 2.3 % of 3 s: 69 ms
        assert!(worst < 1_000_000, "{worst} ns");
    }
}
