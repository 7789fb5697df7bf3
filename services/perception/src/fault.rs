//! Faults the simulated camera injects into its own frames when `phri-fault`
//! asks (channel `fault/depth`), to measure what perception faults cost: a
//! corruption of the next frames, or a publish delay until a deadline. A real
//! camera driver has none of this.

use std::fmt;

use phri_ipc::{DepthFault, DepthFaultKind, FrameHeader};

/// Longest publish delay accepted \[ms\]; longer requests are clamped.
pub const MAX_DELAY_MS: f64 = 10_000.0;
/// Longest delay period accepted \[s\]; longer requests are clamped.
pub const MAX_DELAY_DURATION_S: f64 = 3600.0;
/// A [`DepthFaultKind::Stale`] frame's capture time is moved back this much \[ns\].
pub const STALE_BY_NS: u64 = 1_000_000_000;
/// One pixel in this many becomes a flying pixel under [`DepthFaultKind::Noise`] (2 %).
pub const NOISE_ONE_IN: u64 = 50;
/// Flying pixels' depths: `[NOISE_MIN_MM, NOISE_MIN_MM + NOISE_SPAN_MM)` \[mm\].
pub const NOISE_MIN_MM: u16 = 500;
/// Width of the flying pixels' depth range \[mm\].
pub const NOISE_SPAN_MM: u16 = 3500;

/// What an accepted fault will do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaultAccepted {
    /// frames published `delay_ms` late for `duration_s` (as requested; clamped
    /// to [`MAX_DELAY_MS`], [`MAX_DELAY_DURATION_S`])
    Delay {
        /// the delay requested \[ms\]
        delay_ms: f64,
        /// for how long, as requested \[s\]
        duration_s: f64,
    },
    /// the next `frames` frames corrupted
    Corrupt {
        /// the corruption
        kind: DepthFaultKind,
        /// how many frames it corrupts
        frames: u32,
    },
}

impl fmt::Display for FaultAccepted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FaultAccepted::Delay {
                delay_ms,
                duration_s,
            } => write!(f, "frames {delay_ms} ms late for {duration_s} s"),
            FaultAccepted::Corrupt { kind, frames } => {
                write!(f, "{kind} on the next {frames} frames")
            }
        }
    }
}

/// A fault request the camera ignores; its state is unchanged.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum FaultRefused {
    /// a delay or a duration that is negative or not finite
    #[error("delay {delay_ms} ms for {duration_s} s refused")]
    Delay {
        /// the delay requested \[ms\]
        delay_ms: f64,
        /// the duration requested \[s\]
        duration_s: f64,
    },
    /// a kind code that names no [`DepthFaultKind`]
    #[error("unknown kind {0} ignored")]
    UnknownKind(u32),
}

/// The faults in force: a corruption with the frames it has left, and a
/// publish delay with its deadline. Deterministic: the flying pixels follow
/// from the request's sequence number.
#[derive(Clone, Debug, Default)]
pub struct FaultState {
    kind: Option<DepthFaultKind>,
    frames_left: u32,
    delay_ns: u64,
    delay_until_ns: u64,
    rng: u64,
}

impl FaultState {
    /// Take request `f` at `now_ns` [ns, the clock `apply` is given]. A delay
    /// replaces the delay in force and leaves a corruption running; a
    /// corruption replaces the corruption in force.
    pub fn accept(&mut self, f: &DepthFault, now_ns: u64) -> Result<FaultAccepted, FaultRefused> {
        match DepthFaultKind::try_from(f.kind) {
            Ok(DepthFaultKind::Delay) => {
                let ok = f.delay_ms.is_finite()
                    && f.delay_ms >= 0.0
                    && f.duration_s.is_finite()
                    && f.duration_s >= 0.0;
                if !ok {
                    return Err(FaultRefused::Delay {
                        delay_ms: f.delay_ms,
                        duration_s: f.duration_s,
                    });
                }
                self.delay_ns = (f.delay_ms.min(MAX_DELAY_MS) * 1e6) as u64;
                self.delay_until_ns =
                    now_ns + (f.duration_s.min(MAX_DELAY_DURATION_S) * 1e9) as u64;
                Ok(FaultAccepted::Delay {
                    delay_ms: f.delay_ms,
                    duration_s: f.duration_s,
                })
            }
            Ok(kind) => {
                self.kind = Some(kind);
                self.frames_left = f.frames;
                self.rng = f.seq.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
                Ok(FaultAccepted::Corrupt {
                    kind,
                    frames: f.frames,
                })
            }
            Err(_) => Err(FaultRefused::UnknownKind(f.kind)),
        }
    }

    /// Corrupt this frame (`depth` \[mm\] and its `header`) if a corruption has
    /// frames left; returns the extra publish delay in force at `now_ns` \[ns\].
    /// - noise: one pixel in [`NOISE_ONE_IN`] gets a random depth in
    ///   `[NOISE_MIN_MM, NOISE_MIN_MM + NOISE_SPAN_MM)`
    /// - zeros: every pixel 0 (a blind frame)
    /// - size: the header's width one less than the payload's
    /// - stale: the capture time [`STALE_BY_NS`] earlier
    pub fn apply(&mut self, depth: &mut [u16], header: &mut FrameHeader, now_ns: u64) -> u64 {
        if self.frames_left > 0 {
            self.frames_left -= 1;
            match self.kind {
                Some(DepthFaultKind::Noise) => {
                    for d in depth.iter_mut() {
                        // xorshift64
                        self.rng ^= self.rng << 13;
                        self.rng ^= self.rng >> 7;
                        self.rng ^= self.rng << 17;
                        if self.rng.is_multiple_of(NOISE_ONE_IN) {
                            *d = NOISE_MIN_MM + ((self.rng >> 20) % NOISE_SPAN_MM as u64) as u16;
                        }
                    }
                }
                Some(DepthFaultKind::Zeros) => depth.fill(0),
                Some(DepthFaultKind::Size) => header.width = header.width.saturating_sub(1),
                Some(DepthFaultKind::Stale) => {
                    header.capture_ns = header.capture_ns.saturating_sub(STALE_BY_NS)
                }
                Some(DepthFaultKind::Delay) | None => {}
            }
        }
        if now_ns < self.delay_until_ns {
            self.delay_ns
        } else {
            0
        }
    }

    /// Frames the corruption in force has left.
    pub fn frames_left(&self) -> u32 {
        self.frames_left
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    const W: u32 = 640;
    const H: u32 = 480;
    const DEPTH: u16 = 1000;

    fn request(seq: u64, kind: DepthFaultKind, frames: u32) -> DepthFault {
        let mut f = DepthFault::zeroed();
        f.seq = seq;
        f.kind = kind as u32;
        f.frames = frames;
        f
    }

    fn delay(delay_ms: f64, duration_s: f64) -> DepthFault {
        let mut f = request(9, DepthFaultKind::Delay, 0);
        f.delay_ms = delay_ms;
        f.duration_s = duration_s;
        f
    }

    fn frame() -> (Vec<u16>, FrameHeader) {
        let mut h = FrameHeader::zeroed();
        h.width = W;
        h.height = H;
        h.capture_ns = 5_000_000_000;
        (vec![DEPTH; (W * H) as usize], h)
    }

    /// Apply one frame; (depths, header, extra delay).
    fn apply(s: &mut FaultState, now: u64) -> (Vec<u16>, FrameHeader, u64) {
        let (mut d, mut h) = frame();
        let extra = s.apply(&mut d, &mut h, now);
        (d, h, extra)
    }

    fn untouched(d: &[u16], h: &FrameHeader) -> bool {
        let (d0, h0) = frame();
        d == d0 && h.width == h0.width && h.capture_ns == h0.capture_ns
    }

    #[test]
    fn no_fault_leaves_frames_alone() {
        let mut s = FaultState::default();
        let (d, h, extra) = apply(&mut s, 0);
        assert!(untouched(&d, &h) && extra == 0);
    }

    #[test]
    fn noise_puts_two_percent_flying_pixels_in_range_for_the_frames_asked() {
        let mut s = FaultState::default();
        let ok = s.accept(&request(7, DepthFaultKind::Noise, 2), 0).unwrap();
        assert_eq!(
            ok,
            FaultAccepted::Corrupt {
                kind: DepthFaultKind::Noise,
                frames: 2
            }
        );
        let mut first = None;
        for _ in 0..2 {
            let (d, h, extra) = apply(&mut s, 0);
            assert_eq!((h.width, h.capture_ns, extra), (W, 5_000_000_000, 0));
            let changed: Vec<u16> = d.iter().copied().filter(|&x| x != DEPTH).collect();
            let share = changed.len() as f64 / d.len() as f64;
            assert!(
                (0.017..0.023).contains(&share),
                "{share} of the pixels changed"
            );
            assert!(changed
                .iter()
                .all(|&x| (NOISE_MIN_MM..NOISE_MIN_MM + NOISE_SPAN_MM).contains(&x)));
            // spread over the range, not one value
            let lo = changed.iter().filter(|&&x| x < 2000).count();
            assert!(lo > changed.len() / 4 && lo < changed.len() * 3 / 4);
            match &first {
                None => first = Some(d),
                Some(f) => assert_ne!(f, &d, "each frame its own flying pixels"),
            }
        }
        assert_eq!(s.frames_left(), 0);
        let (d, h, _) = apply(&mut s, 0);
        assert!(untouched(&d, &h), "only the frames asked for");
        // the same request gives the same pixels (deterministic)
        let mut again = FaultState::default();
        again
            .accept(&request(7, DepthFaultKind::Noise, 1), 0)
            .unwrap();
        assert_eq!(Some(apply(&mut again, 0).0), first);
    }

    #[test]
    fn zeros_size_and_stale_do_what_they_say() {
        let mut s = FaultState::default();
        s.accept(&request(1, DepthFaultKind::Zeros, 1), 0).unwrap();
        let (d, h, _) = apply(&mut s, 0);
        assert!(d.iter().all(|&x| x == 0));
        assert_eq!((h.width, h.capture_ns), (W, 5_000_000_000));

        s.accept(&request(2, DepthFaultKind::Size, 1), 0).unwrap();
        let (d, h, _) = apply(&mut s, 0);
        assert_eq!(h.width, W - 1);
        assert_ne!(
            (h.width * h.height) as usize,
            d.len(),
            "the header disagrees with the payload"
        );
        assert!(d.iter().all(|&x| x == DEPTH));

        s.accept(&request(3, DepthFaultKind::Stale, 3), 0).unwrap();
        for _ in 0..3 {
            let (d, h, _) = apply(&mut s, 0);
            assert_eq!(h.capture_ns, 5_000_000_000 - STALE_BY_NS);
            assert!(d.iter().all(|&x| x == DEPTH));
        }
        let (d, h, _) = apply(&mut s, 0);
        assert!(untouched(&d, &h));
    }

    #[test]
    fn a_delay_holds_until_its_deadline_within_its_bounds() {
        let mut s = FaultState::default();
        let t0 = 1_000_000_000;
        assert_eq!(
            s.accept(&delay(40.0, 2.0), t0),
            Ok(FaultAccepted::Delay {
                delay_ms: 40.0,
                duration_s: 2.0
            })
        );
        let (d, h, extra) = apply(&mut s, t0);
        assert!(untouched(&d, &h), "a delay does not touch the frame");
        assert_eq!(extra, 40_000_000);
        assert_eq!(apply(&mut s, t0 + 1_999_999_999).2, 40_000_000);
        assert_eq!(apply(&mut s, t0 + 2_000_000_000).2, 0);
        // clamped to 10 s late and one hour
        s.accept(&delay(1e6, 1e9), t0).unwrap();
        assert_eq!(apply(&mut s, t0).2, 10_000_000_000);
        assert_eq!(apply(&mut s, t0 + 3_599_000_000_000).2, 10_000_000_000);
        assert_eq!(apply(&mut s, t0 + 3_600_000_000_000).2, 0);
        // negative or non-finite: refused, the delay in force stays
        s.accept(&delay(5.0, 10.0), t0).unwrap();
        for (ms, s_) in [
            (-1.0, 1.0),
            (f64::NAN, 1.0),
            (5.0, -1.0),
            (5.0, f64::INFINITY),
        ] {
            assert!(matches!(
                s.accept(&delay(ms, s_), t0),
                Err(FaultRefused::Delay { .. })
            ));
        }
        assert_eq!(apply(&mut s, t0 + 9_000_000_000).2, 5_000_000);
        // a zero delay is a way to cancel
        s.accept(&delay(0.0, 0.0), t0).unwrap();
        assert_eq!(apply(&mut s, t0).2, 0);
    }

    #[test]
    fn a_delay_and_a_corruption_run_together() {
        let mut s = FaultState::default();
        s.accept(&request(1, DepthFaultKind::Zeros, 2), 0).unwrap();
        s.accept(&delay(10.0, 1.0), 0).unwrap();
        let (d, _, extra) = apply(&mut s, 0);
        assert!(d.iter().all(|&x| x == 0));
        assert_eq!(extra, 10_000_000);
    }

    #[test]
    fn an_unknown_kind_is_ignored() {
        let mut s = FaultState::default();
        s.accept(&request(1, DepthFaultKind::Zeros, 2), 0).unwrap();
        for kind in [0, 6, 99] {
            let mut f = request(2, DepthFaultKind::Noise, 5);
            f.kind = kind;
            assert_eq!(s.accept(&f, 0), Err(FaultRefused::UnknownKind(kind)));
        }
        // the corruption in force is unchanged: two blind frames, then clean ones
        assert_eq!(s.frames_left(), 2);
        for _ in 0..2 {
            assert!(apply(&mut s, 0).0.iter().all(|&x| x == 0));
        }
        let (d, h, extra) = apply(&mut s, 0);
        assert!(untouched(&d, &h) && extra == 0);
    }
}
