//! Hand waving on a tracked skeleton, as a pure step: skeletons in, a wave
//! out (which person, which hand). `main.rs` wires `perception/skeleton` to
//! `hri/request` (a `follow` request for the waving hand).
//!
//! A wave, after the Kinect-era detectors (NiTE 1 counts about four direction
//! changes; a widely copied Kinect SDK detector wants six alternating
//! segments with the hand above the elbow, REFERENCE §4):
//! - the hand is above the elbow by [`GestureConfig::hand_above_elbow_m`] and
//!   both are tracked with at least [`GestureConfig::min_confidence`];
//! - its lateral offset from the elbow (along the shoulder line, horizontal)
//!   reverses direction [`GestureConfig::reversals`] times within
//!   [`GestureConfig::window_s`], each swing at least
//!   [`GestureConfig::min_swing_m`] (a swing shorter than that is tracker
//!   noise, not a wave), consecutive reversals between
//!   [`GestureConfig::min_half_period_s`] and [`GestureConfig::max_half_period_s`]
//!   apart (faster is noise, slower a reach and its return);
//! - after a wave the same person's next wave counts only after
//!   [`GestureConfig::refractory_s`].
//!
//! Any frame that breaks the first condition restarts that hand's count:
//! reaching, pointing, walking with swinging arms or a hand waving below the
//! elbow never make a wave. Times are the frames' capture times.

#![deny(missing_docs)]

use phri_config::{GestureConfig, Invalid};
use phri_ipc::{
    CollabPart, HriRequest, RequestKind, RequestSource, Skeleton, SkeletonJoint, Zeroed, MAX_PEOPLE,
};

/// Largest number of reversals a track remembers (≥ the configured count).
const MAX_REVERSALS: usize = 20;
/// Time constant of the low-pass on the lateral offset [s]: tracker noise
/// (a few cm per frame) is smoothed, a 3 Hz wave passes.
const SMOOTHING_S: f64 = 0.03;

/// A recognised wave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    /// the tracker's id of the person
    pub person: u32,
    /// the waving hand
    pub part: CollabPart,
    /// capture time of the first reversal counted \[ns\]
    pub onset_ns: u64,
    /// capture time of the frame that completed it \[ns\]
    pub detected_ns: u64,
    /// the smallest confidence of hand and elbow over the wave [0, 1]
    pub confidence: f64,
}

#[derive(Clone, Copy, Debug)]
struct Track {
    active: bool,
    person: u32,
    part: CollabPart,
    /// low-passed lateral offset of the hand from the elbow [m]
    x: f64,
    last_ns: u64,
    /// direction of the current swing (+1, −1; 0 before the first)
    dir: i8,
    /// extreme of the current swing [m], and where the swing began
    extreme: f64,
    extreme_ns: u64,
    start: f64,
    reversals: [u64; MAX_REVERSALS],
    n: usize,
    confidence: f64,
}

impl Track {
    const EMPTY: Track = Track {
        active: false,
        person: 0,
        part: CollabPart::None,
        x: 0.0,
        last_ns: 0,
        dir: 0,
        extreme: 0.0,
        extreme_ns: 0,
        start: 0.0,
        reversals: [0; MAX_REVERSALS],
        n: 0,
        confidence: 1.0,
    };

    fn restart(&mut self, x: f64, t: u64) {
        self.x = x;
        self.last_ns = t;
        self.dir = 0;
        self.extreme = x;
        self.extreme_ns = t;
        self.start = x;
        self.n = 0;
        self.confidence = 1.0;
    }

    /// The hand's smoothed lateral position moved to `x` \[m\] at `t` \[ns\]:
    /// follow the swing to its extreme; a turn back by a swing long enough
    /// counts a reversal (one too soon or too late after the previous starts
    /// the count over); reversals older than the window are forgotten.
    fn swing_to(&mut self, x: f64, t: u64, r: &SwingRules) {
        match self.dir {
            0 => {
                if (x - self.start).abs() >= r.swing_m * 0.5 {
                    self.dir = if x > self.start { 1 } else { -1 };
                    self.extreme = x;
                    self.extreme_ns = t;
                }
            }
            d => {
                let further = if d > 0 {
                    x > self.extreme
                } else {
                    x < self.extreme
                };
                if further {
                    self.extreme = x;
                    self.extreme_ns = t;
                } else if (self.extreme - x).abs() >= r.swing_m
                    && (self.extreme - self.start).abs() >= r.swing_m * 0.5
                {
                    // a reversal at the extreme, after a swing long enough;
                    // one too soon or too late after the previous starts a new count
                    if self.n > 0 {
                        let gap = self.extreme_ns.saturating_sub(self.reversals[self.n - 1]);
                        if gap < r.half_min_ns || gap > r.half_max_ns {
                            self.n = 0;
                            self.confidence = 1.0;
                        }
                    }
                    if self.n == MAX_REVERSALS {
                        self.reversals.copy_within(1.., 0);
                        self.n -= 1;
                    }
                    self.reversals[self.n] = self.extreme_ns;
                    self.n += 1;
                    self.start = self.extreme;
                    self.dir = -d;
                    self.extreme = x;
                    self.extreme_ns = t;
                }
            }
        }
        // reversals older than the window are forgotten
        let keep_from = self.reversals[..self.n]
            .iter()
            .position(|&rv| t.saturating_sub(rv) <= r.window_ns)
            .unwrap_or(self.n);
        self.reversals.copy_within(keep_from..self.n, 0);
        self.n -= keep_from;
    }
}

/// What counts as a wave's swing, from the configuration: a swing's
/// least length, the half period's bounds and the window, in the track's
/// units \[m, ns\].
struct SwingRules {
    swing_m: f64,
    half_min_ns: u64,
    half_max_ns: u64,
    window_ns: u64,
}

impl SwingRules {
    fn of(cfg: &GestureConfig) -> SwingRules {
        SwingRules {
            swing_m: cfg.min_swing_m,
            half_min_ns: (cfg.min_half_period_s * 1e9) as u64,
            half_max_ns: (cfg.max_half_period_s * 1e9) as u64,
            window_ns: (cfg.window_s * 1e9) as u64,
        }
    }
}

/// The detector: one track per (person, hand), preallocated.
#[derive(Clone, Debug)]
pub struct WaveDetector {
    cfg: GestureConfig,
    tracks: [Track; 2 * MAX_PEOPLE],
    /// (person, capture time of their last wave)
    last_wave: [(u32, u64); MAX_PEOPLE],
}

impl WaveDetector {
    /// A detector with the `[gesture]` settings `cfg` (validated here), tracking no one yet.
    pub fn new(cfg: &GestureConfig) -> Result<WaveDetector, Invalid> {
        cfg.validate()?;
        Ok(WaveDetector {
            cfg: cfg.clone(),
            tracks: [Track::EMPTY; 2 * MAX_PEOPLE],
            last_wave: [(u32::MAX, 0); MAX_PEOPLE],
        })
    }

    fn refractory(&self, person: u32, t: u64) -> bool {
        let gap = (self.cfg.refractory_s * 1e9) as u64;
        self.last_wave
            .iter()
            .any(|&(p, w)| p == person && w > 0 && t < w + gap)
    }

    fn remember_wave(&mut self, person: u32, t: u64) {
        let slot = self
            .last_wave
            .iter()
            .position(|&(p, _)| p == person)
            .or_else(|| {
                // the oldest entry makes room
                (0..MAX_PEOPLE).min_by_key(|&i| self.last_wave[i].1)
            })
            .unwrap_or(0);
        self.last_wave[slot] = (person, t);
    }

    fn track(&mut self, person: u32, part: CollabPart) -> &mut Track {
        let i = self
            .tracks
            .iter()
            .position(|k| k.active && k.person == person && k.part == part)
            .or_else(|| self.tracks.iter().position(|k| !k.active))
            .unwrap_or_else(|| {
                (0..self.tracks.len())
                    .min_by_key(|&i| self.tracks[i].last_ns)
                    .unwrap_or(0)
            });
        let k = &mut self.tracks[i];
        if !(k.active && k.person == person && k.part == part) {
            *k = Track::EMPTY;
            k.active = true;
            k.person = person;
            k.part = part;
        }
        k
    }

    /// One skeleton frame; a wave completed in it, if any (at most one per frame).
    pub fn step(&mut self, sk: &Skeleton) -> Option<Wave> {
        let t = sk.capture_ns;
        let n = (sk.n_people as usize).min(MAX_PEOPLE);
        // people no longer tracked lose their tracks
        for k in self.tracks.iter_mut().filter(|k| k.active) {
            let seen = sk.people[..n]
                .iter()
                .any(|p| p.tracked != 0 && p.id == k.person);
            if !seen {
                k.active = false;
            }
        }
        let mut out = None;
        for p in sk.people[..n].iter().filter(|p| p.tracked != 0) {
            let j = |s: SkeletonJoint| (p.joints[s as usize], p.confidence[s as usize]);
            let (ls, lsc) = j(SkeletonJoint::LeftShoulder);
            let (rs, rsc) = j(SkeletonJoint::RightShoulder);
            // lateral: along the shoulder line, horizontal (left → right)
            let (lx, ly) = (rs[0] - ls[0], rs[1] - ls[1]);
            let norm = lx.hypot(ly);
            // the shoulder line gives only a direction: one shoulder seen is
            // enough (seen from the side the other is hidden by the torso, and
            // a tracker still places it)
            let shoulders_ok = (lsc >= self.cfg.min_confidence || rsc >= self.cfg.min_confidence)
                && norm > 0.1
                && ls.iter().chain(rs.iter()).all(|x| x.is_finite());
            for (part, hand, elbow) in [
                (
                    CollabPart::RightHand,
                    SkeletonJoint::RightHand,
                    SkeletonJoint::RightElbow,
                ),
                (
                    CollabPart::LeftHand,
                    SkeletonJoint::LeftHand,
                    SkeletonJoint::LeftElbow,
                ),
            ] {
                let (h, hc) = j(hand);
                let (e, ec) = j(elbow);
                let ok = shoulders_ok
                    && hc >= self.cfg.min_confidence
                    && ec >= self.cfg.min_confidence
                    && h[2] - e[2] >= self.cfg.hand_above_elbow_m
                    && h.iter().chain(e.iter()).all(|x| x.is_finite());
                let raw = ((h[0] - e[0]) * lx + (h[1] - e[1]) * ly) / norm.max(1e-9);
                let wanted = self.cfg.reversals as usize;
                let rules = SwingRules::of(&self.cfg);
                let k = self.track(p.id, part);
                if !ok {
                    k.restart(raw, t);
                    k.n = 0;
                    continue;
                }
                if k.last_ns == 0 || t <= k.last_ns || t - k.last_ns > 200_000_000 {
                    // a new track, or a gap: start over
                    k.restart(raw, t);
                    continue;
                }
                let dt = (t - k.last_ns) as f64 * 1e-9;
                let alpha = 1.0 - (-dt / SMOOTHING_S).exp();
                k.x += (raw - k.x) * alpha;
                k.last_ns = t;
                k.confidence = k.confidence.min(hc).min(ec);
                k.swing_to(k.x, t, &rules);
                if k.n >= wanted && out.is_none() {
                    let wave = Wave {
                        person: p.id,
                        part,
                        onset_ns: k.reversals[0],
                        detected_ns: t,
                        confidence: k.confidence,
                    };
                    k.n = 0;
                    k.confidence = 1.0;
                    if !self.refractory(p.id, t) {
                        self.remember_wave(p.id, t);
                        out = Some(wave);
                    }
                }
            }
        }
        out
    }
}

/// The `follow` request for `wave`: numbered `seq`, made at `stamp_ns` [ns, CLOCK_MONOTONIC].
pub fn follow_request(wave: &Wave, seq: u64, stamp_ns: u64) -> HriRequest {
    let mut r = HriRequest::zeroed();
    r.seq = seq;
    r.stamp_ns = stamp_ns;
    r.source = RequestSource::Gesture as u32;
    r.kind = RequestKind::Follow as u32;
    r.part = wave.part as u32;
    r.person = wave.person;
    r.confidence = wave.confidence;
    r.text = phri_ipc::json::to_c_str(&format!("wave {}", wave.part.name()));
    r
}
