//! Temporal association: a detection continues the track whose predicted
//! centre (constant velocity) is nearest across the floor (the vertical is
//! left out: a person half hidden has its centre higher or lower), within a gate that grows while the
//! person is hidden; a person hidden up to `max_hidden_s` keeps its id when it
//! reappears near its prediction. Joints are smoothed per track with a
//! [`OneEuro`] filter; a joint not seen keeps its last position, confidence 0.

use crate::config::TrackerConfig;
use crate::filter::{OneEuro, OneEuroParams};
use crate::skeleton::RawSkeleton;
use crate::{JOINTS, MAX_PEOPLE};

/// Speed beyond which a track's velocity is not believed \[m/s\].
const MAX_SPEED_MPS: f64 = 2.0;

/// One person followed over frames.
#[derive(Debug, Clone, Copy, Default)]
pub struct Track {
    /// stable id (> 0) while `alive`
    pub id: u32,
    /// the slot holds a person (seen, or hidden for at most `max_hidden_s`)
    pub alive: bool,
    /// seen in the last frame
    pub seen: bool,
    /// time since last seen \[s\]
    pub hidden_s: f64,
    /// last seen centroid \[m\] and its velocity \[m/s\], camera frame
    pub centroid: [f64; 3],
    /// velocity of the centroid \[m/s\], camera frame
    pub velocity: [f64; 3],
    /// smoothed joints \[m\] and this frame's confidences
    pub joints: [[f64; 3]; JOINTS],
    /// this frame's confidence of each joint in \[0, 1\] (0: not seen)
    pub confidence: [f64; JOINTS],
    filters: [OneEuro; JOINTS],
}

impl Track {
    fn predicted(&self, dt: f64) -> [f64; 3] {
        let t = self.hidden_s + dt;
        [
            self.centroid[0] + self.velocity[0] * t,
            self.centroid[1] + self.velocity[1] * t,
            self.centroid[2] + self.velocity[2] * t,
        ]
    }
}

/// Up to [`MAX_PEOPLE`] tracks.
#[derive(Debug, Clone, Default)]
pub struct Tracks {
    /// the tracks, alive or not (see [`Track::alive`])
    pub slots: [Track; MAX_PEOPLE],
    next_id: u32,
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Distance \[m\] of `a` and `b` across the floor: their difference without
/// its component along `up` (a person half hidden has its centre higher or lower).
pub fn ground_dist(a: [f64; 3], b: [f64; 3], up: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let h = d[0] * up[0] + d[1] * up[1] + d[2] * up[2];
    dist(d, [up[0] * h, up[1] * h, up[2] * h])
}

impl Tracks {
    /// No tracks; ids restart at 1.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Associates this frame's detections (`dt` \[s\] after the last frame)
    /// and updates the tracks; `slot_of[k]` receives the slot of detection `k`
    /// (`usize::MAX` if no slot was free).
    pub fn update(
        &mut self,
        dets: &[RawSkeleton],
        dt: f64,
        cfg: &TrackerConfig,
        slot_of: &mut [usize; MAX_PEOPLE],
    ) {
        let n = dets.len().min(MAX_PEOPLE);
        slot_of.fill(usize::MAX);
        let up = cfg.up();
        // candidate pairs within the gate, nearest first
        let mut pairs = [(f64::INFINITY, 0usize, 0usize); MAX_PEOPLE * MAX_PEOPLE];
        let mut np = 0;
        for (t, tr) in self.slots.iter().enumerate() {
            if !tr.alive {
                continue;
            }
            let pred = tr.predicted(dt);
            let gate = cfg.gate_m + cfg.gate_growth_mps * tr.hidden_s;
            for (k, d) in dets.iter().enumerate().take(n) {
                let e = ground_dist(pred, d.centroid, up);
                if e <= gate {
                    pairs[np] = (e, t, k);
                    np += 1;
                }
            }
        }
        pairs[..np]
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut track_used = [false; MAX_PEOPLE];
        for &(_, t, k) in &pairs[..np] {
            if track_used[t] || slot_of[k] != usize::MAX {
                continue;
            }
            track_used[t] = true;
            slot_of[k] = t;
        }
        // new tracks for the rest
        for k in 0..n {
            if slot_of[k] != usize::MAX {
                continue;
            }
            if let Some(t) = (0..MAX_PEOPLE).find(|&t| !self.slots[t].alive && !track_used[t]) {
                self.next_id = self.next_id.wrapping_add(1).max(1);
                self.slots[t] = Track {
                    id: self.next_id,
                    alive: true,
                    centroid: dets[k].centroid,
                    ..Track::default()
                };
                track_used[t] = true;
                slot_of[k] = t;
            }
        }
        let params = OneEuroParams {
            min_cutoff_hz: cfg.filter_min_cutoff_hz,
            beta: cfg.filter_beta,
            d_cutoff_hz: cfg.filter_d_cutoff_hz,
            snap_m: cfg.filter_snap_m,
        };
        for t in 0..MAX_PEOPLE {
            let tr = &mut self.slots[t];
            if !tr.alive {
                continue;
            }
            let Some(k) = (0..n).find(|&k| slot_of[k] == t) else {
                tr.seen = false;
                tr.hidden_s += dt;
                tr.confidence = [0.0; JOINTS];
                if tr.hidden_s > cfg.max_hidden_s {
                    tr.alive = false;
                }
                continue;
            };
            let d = &dets[k];
            let elapsed = tr.hidden_s + dt;
            if tr.seen && elapsed > 0.0 {
                for i in 0..3 {
                    let v = (d.centroid[i] - tr.centroid[i]) / elapsed;
                    tr.velocity[i] = 0.5 * tr.velocity[i] + 0.5 * v;
                }
                let s = dist(tr.velocity, [0.0; 3]);
                if s > MAX_SPEED_MPS {
                    for v in &mut tr.velocity {
                        *v *= MAX_SPEED_MPS / s;
                    }
                }
            } else {
                tr.velocity = [0.0; 3];
            }
            tr.centroid = d.centroid;
            for j in 0..JOINTS {
                if d.confidence[j] > 0.0 {
                    tr.joints[j] = tr.filters[j].update(d.joints[j], elapsed, &params);
                } else if tr.filters[j] == OneEuro::default() {
                    // never seen: the guess
                    tr.joints[j] = d.joints[j];
                }
                tr.confidence[j] = d.confidence[j];
            }
            tr.seen = true;
            tr.hidden_s = 0.0;
        }
    }
}
