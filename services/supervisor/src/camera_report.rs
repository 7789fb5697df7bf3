//! The report's perception figures, camera by camera (`perception` and
//! `perception.cameras`): frames seen on each camera's channel, the frames
//! every repulsion worker answered, capture → last result and arrival at
//! ingestion → last result, ingestion's own time, the workers' compute, and
//! how often each camera gave the fused distance: each time a worker
//! answers a point, the camera whose distance is the largest among the
//! cameras that answered that point within the staleness bound gives it
//! (the controller's fusion, `phri_control::RepulsionInputs::fuse`).

use phri_ipc::{FrameHeader, RepulsionResult};
use serde::Serialize;

use crate::report::{Percentiles, PerceptionReport};

/// A frame some repulsion worker answered and not all yet.
#[derive(Debug, Clone, Copy)]
struct FrameInFlight {
    /// the frame's sequence number
    seq: u64,
    /// its capture time [ns, CLOCK_MONOTONIC]
    capture_ns: u64,
    /// bit i: worker i answered
    answered: u32,
    /// the latest answer's publication [ns]
    last_ns: u64,
    /// its earliest arrival at ingestion as the answers tell it [ns]
    /// (`u64::MAX` before the first; `None` once an answer did not carry it)
    arrival_ns: Option<u64>,
    /// the answers' compute times, summed [ns]
    compute_ns: u64,
}

/// One camera's figures so far.
#[derive(Debug, Clone, Default)]
pub struct CameraEval {
    frames_seen: u64,
    last_frame_seq: Option<u64>,
    in_flight: Vec<FrameInFlight>,
    complete_frames: u64,
    frame_latency_ms: Vec<f64>,
    arrival_latency_ms: Vec<f64>,
    ingest_ms: Vec<f64>,
    last_filtered_seq: Option<u64>,
    compute_ms: Vec<f64>,
    /// per control point: its newest distance [m] and that result's publication [ns]
    points: Vec<(f64, u64)>,
    /// fusion decisions this camera won
    gave: u64,
}

/// `perception.cameras[i]` in the report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CameraReport {
    /// the camera's index in `[[camera]]`
    pub camera: usize,
    /// frames seen on its channel (`camera/depth`, `camera/I/depth`)
    pub frames: u64,
    /// frames that never got a result from every repulsion worker
    pub dropped_frames: u64,
    /// capture → the last worker's result [ms]
    pub frame_to_repulsion_ms: Percentiles,
    /// the frame's arrival at its ingestion → the last worker's result [ms]
    pub arrival_to_repulsion_ms: Percentiles,
    /// its ingestion's own time [ms]
    pub ingest_ms: Percentiles,
    /// share of the fusion's decisions (a point, each time a worker
    /// answers it) this camera's distance won: 1 with one camera
    pub fused_share: f64,
}

/// Every camera's figures.
#[derive(Debug, Clone)]
pub struct CamerasEval {
    cameras: Vec<CameraEval>,
    /// a camera's answer older than this takes no part in a decision [ns]
    max_age_ns: u64,
    decisions: u64,
}

impl CamerasEval {
    /// `max_age_ns`: the controller's perception staleness bound.
    pub fn new(max_age_ns: u64) -> CamerasEval {
        CamerasEval {
            cameras: Vec::new(),
            max_age_ns,
            decisions: 0,
        }
    }

    fn camera(&mut self, camera: usize) -> &mut CameraEval {
        if self.cameras.len() <= camera {
            self.cameras.resize_with(camera + 1, CameraEval::default);
        }
        &mut self.cameras[camera]
    }

    /// Camera `camera` published a frame.
    pub fn on_frame(&mut self, camera: usize, h: &FrameHeader) {
        let c = self.camera(camera);
        if c.last_frame_seq != Some(h.seq) {
            c.frames_seen += 1;
            c.last_frame_seq = Some(h.seq);
        }
    }

    /// Camera `camera`'s ingestion published a frame.
    pub fn on_filtered(&mut self, camera: usize, h: &FrameHeader) {
        let c = self.camera(camera);
        if c.last_filtered_seq != Some(h.seq) && h.ingest_ns > 0 {
            c.ingest_ms.push(f64::from(h.ingest_ns) * 1e-6);
        }
        c.last_filtered_seq = Some(h.seq);
    }

    /// A repulsion worker answered a frame of camera `camera`.
    pub fn on_repulsion(&mut self, camera: usize, m: &RepulsionResult) {
        self.decide(camera, m);
        let c = self.camera(camera);
        let bit = 1u32 << m.worker.min(31);
        let all = if m.workers >= 32 {
            u32::MAX
        } else {
            (1u32 << m.workers) - 1
        };
        let idx = match c.in_flight.iter().position(|f| f.seq == m.frame_seq) {
            Some(i) => i,
            None => {
                // frames older than a second that never completed are dropped
                c.in_flight
                    .retain(|f| m.published_ns.saturating_sub(f.last_ns) < 1_000_000_000);
                c.in_flight.push(FrameInFlight {
                    seq: m.frame_seq,
                    capture_ns: m.frame_capture_wall_ns,
                    answered: 0,
                    last_ns: m.published_ns,
                    arrival_ns: Some(u64::MAX),
                    compute_ns: 0,
                });
                c.in_flight.len() - 1
            }
        };
        let f = &mut c.in_flight[idx];
        f.answered |= bit;
        f.last_ns = f.last_ns.max(m.published_ns);
        f.compute_ns = f.compute_ns.saturating_add(m.compute_ns);
        // the frame's arrival at ingestion, as each result tells it
        f.arrival_ns = match (f.arrival_ns, m.since_arrival_ns) {
            (Some(a), d) if d > 0 => Some(a.min(m.published_ns.saturating_sub(u64::from(d)))),
            _ => None,
        };
        if f.answered & all == all {
            let f = *f;
            c.complete_frames += 1;
            c.frame_latency_ms
                .push(f.last_ns.saturating_sub(f.capture_ns) as f64 * 1e-6);
            if let Some(a) = f.arrival_ns.filter(|a| *a != u64::MAX) {
                c.arrival_latency_ms
                    .push(f.last_ns.saturating_sub(a) as f64 * 1e-6);
            }
            c.compute_ms.push(f.compute_ns as f64 * 1e-6);
            c.in_flight.swap_remove(idx);
        }
    }

    /// The fusion's decision for each point `m` answers.
    fn decide(&mut self, camera: usize, m: &RepulsionResult) {
        let now = m.published_ns;
        let n = (m.n_points as usize).min(m.points.len());
        for p in &m.points[..n] {
            let k = p.point as usize;
            if k > 4096 {
                continue;
            }
            let c = self.camera(camera);
            if c.points.len() <= k {
                c.points.resize(k + 1, (f64::NAN, 0));
            }
            c.points[k] = (p.min_distance, now);
            let max_age = self.max_age_ns;
            let winner = self
                .cameras
                .iter()
                .enumerate()
                .filter_map(|(i, c)| {
                    let &(d, t) = c.points.get(k)?;
                    (!d.is_nan() && now.saturating_sub(t) <= max_age).then_some((i, d))
                })
                .fold(None, |best: Option<(usize, f64)>, (i, d)| match best {
                    Some((_, b)) if b >= d => best,
                    _ => Some((i, d)),
                });
            if let Some((i, _)) = winner {
                self.cameras[i].gave += 1;
                self.decisions += 1;
            }
        }
    }

    /// The report's `perception`: every camera's frames pooled in its own
    /// keys (frames, dropped frames, capture → result, arrival → result,
    /// ingestion, compute) and each camera's in `cameras`. `None` before
    /// any camera was seen.
    pub fn report(&self) -> Option<PerceptionReport> {
        if !self
            .cameras
            .iter()
            .any(|c| c.frames_seen > 0 || c.complete_frames > 0)
        {
            return None;
        }
        let mut pooled = PerceptionReport::default();
        let mut all: [Vec<f64>; 4] = Default::default();
        for (i, c) in self.cameras.iter().enumerate() {
            // the frame in flight at the end is not dropped
            let dropped = c
                .frames_seen
                .saturating_sub(c.complete_frames)
                .saturating_sub(2);
            pooled.frames += c.frames_seen;
            pooled.dropped_frames += dropped;
            all[0].extend_from_slice(&c.frame_latency_ms);
            all[1].extend_from_slice(&c.arrival_latency_ms);
            all[2].extend_from_slice(&c.ingest_ms);
            all[3].extend_from_slice(&c.compute_ms);
            pooled.cameras.push(CameraReport {
                camera: i,
                frames: c.frames_seen,
                dropped_frames: dropped,
                frame_to_repulsion_ms: percentiles(&c.frame_latency_ms),
                arrival_to_repulsion_ms: percentiles(&c.arrival_latency_ms),
                ingest_ms: percentiles(&c.ingest_ms),
                fused_share: match self.decisions {
                    0 => 0.0,
                    d => c.gave as f64 / d as f64,
                },
            });
        }
        pooled.frame_to_repulsion_ms = percentiles(&all[0]);
        pooled.arrival_to_repulsion_ms = percentiles(&all[1]);
        pooled.ingest_ms = percentiles(&all[2]);
        pooled.repulsion_compute_ms = percentiles(&all[3]);
        Some(pooled)
    }
}

/// p50, p99 and the largest of `samples`.
fn percentiles(samples: &[f64]) -> Percentiles {
    let mut v = samples.to_vec();
    v.sort_by(f64::total_cmp);
    let at = |p: f64| {
        if v.is_empty() {
            0.0
        } else {
            v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
        }
    };
    Percentiles {
        p50: at(0.5),
        p99: at(0.99),
        max: v.last().copied().unwrap_or(0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    const MS: u64 = 1_000_000;

    fn answer(worker: u32, seq: u64, published_ms: u64, distance: f64) -> RepulsionResult {
        let mut m = RepulsionResult::zeroed();
        m.frame_seq = seq;
        m.frame_capture_wall_ns = (published_ms - 5) * MS;
        m.worker = worker;
        m.workers = 1;
        m.published_ns = published_ms * MS;
        m.n_points = 2;
        m.points[0].point = 0;
        m.points[0].min_distance = distance;
        m.points[1].point = 1;
        m.points[1].min_distance = distance;
        m
    }

    #[test]
    fn the_camera_with_the_larger_fresh_distance_gives_the_fused_one() {
        let mut e = CamerasEval::new(100 * MS);
        let mut h = FrameHeader::zeroed();
        // camera 0 sees 2 cm, camera 1 sees 25 cm: camera 1 wins both points
        for k in 0..10u64 {
            h.seq = k;
            e.on_frame(0, &h);
            e.on_frame(1, &h);
            e.on_repulsion(0, &answer(0, k, 1000 + 33 * k, 0.02));
            e.on_repulsion(1, &answer(0, k, 1010 + 33 * k, 0.25));
        }
        let pooled = e.report().unwrap();
        let cams = &pooled.cameras;
        assert_eq!(cams.len(), 2);
        assert_eq!(pooled.frames, 20);
        assert_eq!(cams[1].frames, 10);
        // camera 0's first answers had no rival yet: 2 decisions of 40
        assert!((cams[0].fused_share - 2.0 / 40.0).abs() < 1e-12, "{cams:?}");
        assert!((cams[1].fused_share - 38.0 / 40.0).abs() < 1e-12);
        assert!((cams[1].frame_to_repulsion_ms.p50 - 5.0).abs() < 1e-9);
        // camera 1 falls silent: once stale, camera 0 gives every distance
        for k in 10..20u64 {
            e.on_repulsion(0, &answer(0, k, 2000 + 33 * k, 0.02));
        }
        let cams = e.report().unwrap().cameras;
        assert!(
            (cams[0].fused_share - 22.0 / 60.0).abs() < 1e-12,
            "{cams:?}"
        );
    }
}
