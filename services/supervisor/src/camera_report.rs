//! The report's perception figures, camera by camera (`perception` and
//! `perception.cameras`): frames seen on each camera's channel, the frames
//! every repulsion worker answered, capture → last result and arrival at
//! ingestion → last result, ingestion's own time, the workers' compute, and
//! how often each camera gave the fused distance: each time a worker
//! answers a point, the camera whose distance is the largest among the
//! cameras that answered that point within the staleness bound gives it
//! (the controller's fusion, `phri_control::RepulsionInputs::fuse`).

use phri_ipc::{CameraStatus, FrameHeader, RepulsionResult};
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
    /// capture → publication on its channel [ms]
    arrival_ms: Vec<f64>,
    /// the first frame seen of its process (number, capture [ns,
    /// CLOCK_MONOTONIC]) and the last: frames published in between are
    /// counted by their numbers (this reader may miss some)
    first_frame: Option<(u64, u64)>,
    last_frame: (u64, u64),
    /// frames published and the time they spanned, of the processes before [ns]
    rate_before: (u64, u64),
    /// the intrinsics of its last frame
    intrinsics: Option<IntrinsicsReport>,
    /// its process's newest status and the counts of the processes before
    /// it (a restarted camera counts from 0 again)
    status: CameraStatus,
    before: DropCauses,
    before_frames: u64,
    /// its recent frames: number and publication [ns, CLOCK_MONOTONIC]
    recent: [(u64, u64); RECENT_FRAMES],
    /// its skeletons: the frame's publication (its arrival at the
    /// tracker) → the skeleton's [ms]
    skeleton_ms: Vec<f64>,
    last_skeleton_seq: Option<u64>,
    /// skeleton messages seen, and those with someone in them
    skeletons: u64,
    skeletons_with_people: u64,
}

/// Frames a camera's skeleton is looked up among.
const RECENT_FRAMES: usize = 16;

/// `perception.cameras[i]` in the report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CameraReport {
    /// the camera's index in `[[camera]]`
    pub camera: usize,
    /// frames published on its channel (`camera/depth`, `camera/I/depth`):
    /// as its processes counted them, or as seen there when more
    pub frames: u64,
    /// frames that never got a result from every repulsion worker
    pub dropped_frames: u64,
    /// capture → the last worker's result \[ms\]
    pub frame_to_repulsion_ms: Percentiles,
    /// the frame's arrival at its ingestion → the last worker's result \[ms\]
    pub arrival_to_repulsion_ms: Percentiles,
    /// its ingestion's own time \[ms\]
    pub ingest_ms: Percentiles,
    /// share of the fusion's decisions (a point, each time a worker
    /// answers it) this camera's distance won: 1 with one camera
    pub fused_share: f64,
    /// where its frames came from: `sim`, `freenect`, `ros2`, `replay`
    pub source: String,
    /// frames its process dropped before its channel, by cause
    pub drop_causes: DropCauses,
    /// frames per second on its channel (first to last capture)
    pub rate_hz: f64,
    /// capture → the frame's arrival on its channel (its publication) \[ms\]
    pub capture_to_arrival_ms: Percentiles,
    /// the intrinsics of its frames as used on the 640×480 channel (null:
    /// no frame)
    pub intrinsics: Option<IntrinsicsReport>,
    /// where its skeletons came from: `sim` (the simulation's truth) or
    /// `depth` (phri-tracker on its frames)
    pub skeleton_source: String,
    /// the frame's arrival on its channel → its skeleton on
    /// `perception/skeleton` \[ms\] (frames whose skeleton was seen)
    pub arrival_to_skeleton_ms: Percentiles,
    /// its skeleton messages seen on `perception/skeleton`, and those with
    /// at least one person
    pub skeletons: u64,
    /// of those, the ones with at least one person
    pub skeletons_with_people: u64,
}

/// A camera's dropped frames by cause (`camera/status`), summed over its
/// process's restarts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DropCauses {
    /// captured longer ago than `[camera] max_age_s` when they arrived
    pub too_old: u64,
    /// stamped in the future
    pub future: u64,
    /// malformed: wrong size or step, an encoding refused, a file unreadable
    pub malformed: u64,
    /// no usable intrinsics yet (a ROS 2 image before its CameraInfo)
    pub no_camera_info: u64,
    /// the source ran behind its rate
    pub behind: u64,
}

impl DropCauses {
    fn of(s: &CameraStatus) -> DropCauses {
        DropCauses {
            too_old: s.dropped_old,
            future: s.dropped_future,
            malformed: s.dropped_malformed,
            no_camera_info: s.dropped_no_info,
            behind: s.dropped_behind,
        }
    }

    fn plus(self, o: DropCauses) -> DropCauses {
        DropCauses {
            too_old: self.too_old + o.too_old,
            future: self.future + o.future,
            malformed: self.malformed + o.malformed,
            no_camera_info: self.no_camera_info + o.no_camera_info,
            behind: self.behind + o.behind,
        }
    }
}

/// Pinhole intrinsics \[px\].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct IntrinsicsReport {
    /// focal length along x \[px\]
    pub fx: f64,
    /// focal length along y \[px\]
    pub fy: f64,
    /// principal point, x \[px\]
    pub cx: f64,
    /// principal point, y \[px\]
    pub cy: f64,
}

impl CameraEval {
    /// Frames per second its processes published, from the frame numbers
    /// and capture times this reader saw.
    fn rate_hz(&self) -> f64 {
        let (mut frames, mut span) = self.rate_before;
        if let Some((seq, t)) = self.first_frame {
            frames += self.last_frame.0.saturating_sub(seq);
            span += self.last_frame.1.saturating_sub(t);
        }
        match span {
            0 => 0.0,
            s => frames as f64 / (s as f64 * 1e-9),
        }
    }
}

/// Every camera's figures.
#[derive(Debug, Clone)]
pub struct CamerasEval {
    cameras: Vec<CameraEval>,
    /// a camera's answer older than this takes no part in a decision [ns]
    max_age_ns: u64,
    decisions: u64,
    /// each camera's source, by index (`sim` past the list)
    sources: Vec<String>,
    /// where each camera's skeletons come from, by index (`sim` past the list)
    skeleton_sources: Vec<String>,
}

impl CamerasEval {
    /// `max_age_ns`: the controller's perception staleness bound.
    pub fn new(max_age_ns: u64) -> CamerasEval {
        CamerasEval {
            cameras: Vec::new(),
            max_age_ns,
            decisions: 0,
            sources: Vec::new(),
            skeleton_sources: Vec::new(),
        }
    }

    /// Each camera's source, by index, as configured.
    pub fn set_sources(&mut self, sources: Vec<String>) {
        self.sources = sources;
    }

    /// Where each camera's skeletons come from, by index, as configured.
    pub fn set_skeleton_sources(&mut self, sources: Vec<String>) {
        self.skeleton_sources = sources;
    }

    /// Camera `camera`'s body tracker published the people of a frame: its
    /// latency from the frame's arrival, when that frame was seen.
    pub fn on_skeleton(&mut self, camera: usize, m: &phri_ipc::Skeleton) {
        if camera >= phri_ipc::MAX_CAMERAS {
            return;
        }
        let c = self.camera(camera);
        if c.last_skeleton_seq == Some(m.seq) {
            return;
        }
        c.last_skeleton_seq = Some(m.seq);
        c.skeletons += 1;
        c.skeletons_with_people += u64::from(m.n_people > 0);
        let frame = c.recent.iter().find(|(seq, _)| *seq == m.seq && *seq > 0);
        if let Some(&(_, published)) = frame {
            if m.published_ns >= published && published > 0 {
                c.skeleton_ms
                    .push((m.published_ns - published) as f64 * 1e-6);
            }
        }
    }

    /// A camera's process said what it did (`camera/status`).
    pub fn on_status(&mut self, m: &CameraStatus) {
        let camera = m.camera as usize;
        if camera >= phri_ipc::MAX_CAMERAS {
            return;
        }
        let c = self.camera(camera);
        // a new process counts from 0 again: keep its predecessor's
        if m.frames < c.status.frames || m.seq < c.status.seq {
            c.before = c.before.plus(DropCauses::of(&c.status));
            c.before_frames += c.status.frames;
        }
        c.status = *m;
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
            c.recent[(c.frames_seen as usize) % RECENT_FRAMES] = (h.seq, h.published_ns);
            if h.published_ns >= h.capture_wall_ns && h.capture_wall_ns > 0 {
                c.arrival_ms
                    .push((h.published_ns - h.capture_wall_ns) as f64 * 1e-6);
            }
            // a restarted camera numbers its frames from 1 again
            if h.seq < c.last_frame.0 {
                if let Some(first) = c.first_frame.take() {
                    c.rate_before.0 += c.last_frame.0 - first.0;
                    c.rate_before.1 += c.last_frame.1.saturating_sub(first.1);
                }
            }
            c.first_frame.get_or_insert((h.seq, h.capture_wall_ns));
            c.last_frame = (h.seq, h.capture_wall_ns);
            c.intrinsics = Some(IntrinsicsReport {
                fx: h.fx,
                fy: h.fy,
                cx: h.cx,
                cy: h.cy,
            });
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
        let mut all: [Vec<f64>; 5] = Default::default();
        for (i, c) in self.cameras.iter().enumerate() {
            // the frame in flight at the end is not dropped
            let dropped = c
                .frames_seen
                .saturating_sub(c.complete_frames)
                .saturating_sub(2);
            pooled.dropped_frames += dropped;
            all[0].extend_from_slice(&c.frame_latency_ms);
            all[1].extend_from_slice(&c.arrival_latency_ms);
            all[2].extend_from_slice(&c.ingest_ms);
            all[3].extend_from_slice(&c.compute_ms);
            all[4].extend_from_slice(&c.skeleton_ms);
            // what its processes published, when they said (this reader,
            // at normal priority, may miss frames on a busy machine)
            let published = c.before_frames + c.status.frames;
            let frames = c.frames_seen.max(published);
            pooled.frames += frames;
            pooled.cameras.push(CameraReport {
                camera: i,
                frames,
                dropped_frames: dropped,
                frame_to_repulsion_ms: percentiles(&c.frame_latency_ms),
                arrival_to_repulsion_ms: percentiles(&c.arrival_latency_ms),
                ingest_ms: percentiles(&c.ingest_ms),
                fused_share: match self.decisions {
                    0 => 0.0,
                    d => c.gave as f64 / d as f64,
                },
                source: self.sources.get(i).cloned().unwrap_or_else(|| "sim".into()),
                drop_causes: c.before.plus(DropCauses::of(&c.status)),
                rate_hz: c.rate_hz(),
                capture_to_arrival_ms: percentiles(&c.arrival_ms),
                intrinsics: c.intrinsics,
                skeleton_source: self
                    .skeleton_sources
                    .get(i)
                    .cloned()
                    .unwrap_or_else(|| "sim".into()),
                arrival_to_skeleton_ms: percentiles(&c.skeleton_ms),
                skeletons: c.skeletons,
                skeletons_with_people: c.skeletons_with_people,
            });
        }
        pooled.frame_to_repulsion_ms = percentiles(&all[0]);
        pooled.arrival_to_repulsion_ms = percentiles(&all[1]);
        pooled.ingest_ms = percentiles(&all[2]);
        pooled.repulsion_compute_ms = percentiles(&all[3]);
        pooled.arrival_to_skeleton_ms = percentiles(&all[4]);
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

    #[test]
    fn a_camera_s_source_rate_latency_and_drops_survive_missed_frames_and_restarts() {
        let mut e = CamerasEval::new(100 * MS);
        e.set_sources(vec!["replay".into()]);
        let mut h = FrameHeader::zeroed();
        h.fx = 580.0;
        // 30 Hz for 1 s, this reader seeing every third frame, 2 ms each to the channel
        for seq in (1..=31u64).step_by(3) {
            h.seq = seq;
            h.capture_wall_ns = 1_000 * MS + (seq - 1) * 33_333_333;
            h.published_ns = h.capture_wall_ns + 2 * MS;
            e.on_frame(0, &h);
        }
        let st = |seq, frames, malformed| CameraStatus {
            seq,
            frames,
            dropped_malformed: malformed,
            dropped_old: 1,
            ..CameraStatus::default()
        };
        e.on_status(&st(1, 10, 2));
        e.on_status(&st(2, 30, 3));
        // restarted: numbers from 1 again, counts from 0
        e.on_status(&st(1, 5, 1));
        for seq in 1..=4u64 {
            h.seq = seq;
            h.capture_wall_ns = 3_000 * MS + (seq - 1) * 33_333_333;
            h.published_ns = h.capture_wall_ns + 2 * MS;
            e.on_frame(0, &h);
        }
        let c = &e.report().unwrap().cameras[0];
        assert_eq!(c.source, "replay");
        assert!((c.rate_hz - 30.0).abs() < 0.01, "{}", c.rate_hz);
        assert!((c.capture_to_arrival_ms.p99 - 2.0).abs() < 1e-9);
        assert_eq!((c.drop_causes.malformed, c.drop_causes.too_old), (4, 2));
        assert_eq!(c.intrinsics.map(|k| k.fx), Some(580.0));
    }
}
