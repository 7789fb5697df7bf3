//! The tracker: per depth frame, segmentation, geodesic extrema, skeleton
//! labelling and temporal association, into caller-owned [`Person`]s.

use phri_depth::Intrinsics;

use crate::background::Background;
use crate::config::TrackerConfig;
use crate::error::{check_len, TrackError};
use crate::floor::{FloorFit, FloorMode, Plane};
use crate::geodesic::Geodesic;
use crate::grid::{Grid, SampleParams};
use crate::segment::{side_axis, JoinRule, Segmenter};
use crate::skeleton::{label, Body, RawSkeleton};
use crate::track::{ground_dist, Tracks};
use crate::{Joint, JOINTS, MAX_PEOPLE};

/// One tracked person in one frame, camera optical frame (x right, y down, z forward) \[m\].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Person {
    /// stable id (> 0) while the person is tracked
    pub id: u32,
    /// joint positions in [`crate::Joint`] order \[m\]; where the confidence
    /// is 0, the last position seen (or a guess from the body's proportions)
    pub joints: [[f64; 3]; JOINTS],
    /// confidence per joint in \[0, 1\]; 0 = not seen in this frame
    pub confidence: [f64; JOINTS],
    /// centroid of the person's visible surface \[m\]
    pub centroid: [f64; 3],
}

/// A model-free person tracker for one depth camera. All buffers are
/// allocated by [`Tracker::new`]; [`Tracker::step`] allocates nothing.
#[derive(Debug, Clone)]
pub struct Tracker {
    intrinsics: Intrinsics,
    cfg: TrackerConfig,
    up: [f64; 3],
    side: [f64; 3],
    grid: Grid,
    rule: JoinRule,
    seg: Segmenter,
    geo: Geodesic,
    floor: FloorFit,
    background: Background,
    tracks: Tracks,
    dets: [RawSkeleton; MAX_PEOPLE],
}

impl Tracker {
    /// A tracker for a camera with `intrinsics`; errors on unusable intrinsics or configuration.
    pub fn new(intrinsics: Intrinsics, cfg: TrackerConfig) -> Result<Self, TrackError> {
        intrinsics
            .validate()
            .map_err(|e| TrackError::Intrinsics(e.to_string()))?;
        cfg.validate()?;
        let grid = Grid::new(&intrinsics, cfg.grid_step_px);
        let n = grid.len();
        let up = cfg.up();
        Ok(Self {
            intrinsics,
            up,
            side: side_axis(up),
            rule: JoinRule::new(&cfg, &grid),
            seg: Segmenter::new(n),
            geo: Geodesic::new(n),
            floor: FloorFit::new(n),
            background: Background::new(intrinsics.width, intrinsics.height),
            tracks: Tracks::default(),
            dets: [RawSkeleton::default(); MAX_PEOPLE],
            grid,
            cfg,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &TrackerConfig {
        &self.cfg
    }

    /// The camera's intrinsics.
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// Forgets every track (ids restart at 1) and the last floor; keeps the background.
    pub fn reset(&mut self) {
        self.tracks.reset();
        self.floor.reset();
    }

    /// Learns one frame without people into the background model (depth in
    /// units of `depth_scale_m`, 0 = no reading). Once any frame is learned,
    /// only pixels clearly nearer than the background are people.
    pub fn learn_background(&mut self, depth: &[u16]) -> Result<(), TrackError> {
        self.background.learn(depth, self.cfg.depth_scale_m)
    }

    /// Forgets the background.
    pub fn clear_background(&mut self) {
        self.background.clear();
    }

    /// Frames learned into the background.
    pub fn background_frames(&self) -> u32 {
        self.background.frames()
    }

    /// The floor plane removed in the last frame, if any.
    pub fn floor(&self) -> Option<Plane> {
        match self.cfg.floor {
            FloorMode::None => None,
            FloorMode::Given(p) => Some(p),
            FloorMode::Ransac => self.floor.last(),
        }
    }

    /// [`Tracker::step_masked`] without a mask.
    pub fn step(
        &mut self,
        depth: &[u16],
        dt_s: f64,
        out: &mut [Person; MAX_PEOPLE],
    ) -> Result<usize, TrackError> {
        self.step_masked(depth, None, dt_s, out)
    }

    /// Tracks one frame taken `dt_s` seconds after the last: `depth` row-major
    /// `width × height` (units of `depth_scale_m`, 0 = no reading), `ignore`
    /// the pixels to leave out (the robot's own, from a self-filter; `true` =
    /// ignore). Writes the people seen in this frame into `out[..n]`, by
    /// increasing id, and returns `n`. A person hidden for less than
    /// `max_hidden_s` is not reported but keeps its id.
    pub fn step_masked(
        &mut self,
        depth: &[u16],
        ignore: Option<&[bool]>,
        dt_s: f64,
        out: &mut [Person; MAX_PEOPLE],
    ) -> Result<usize, TrackError> {
        if !(dt_s.is_finite() && dt_s >= 0.0) {
            return Err(TrackError::TimeStep(dt_s));
        }
        let n = self.detect(depth, ignore)?;
        let mut slot_of = [usize::MAX; MAX_PEOPLE];
        self.tracks
            .update(&self.dets[..n], dt_s, &self.cfg, &mut slot_of);
        let mut m = 0;
        for tr in self.tracks.slots.iter().filter(|t| t.alive && t.seen) {
            out[m] = Person {
                id: tr.id,
                joints: tr.joints,
                confidence: tr.confidence,
                centroid: tr.centroid,
            };
            m += 1;
        }
        out[..m].sort_unstable_by_key(|p| p.id);
        Ok(m)
    }

    /// The people of one frame without tracking (no ids, no smoothing): the
    /// number found, their skeletons in [`Tracker::detections`].
    pub fn detect(&mut self, depth: &[u16], ignore: Option<&[bool]>) -> Result<usize, TrackError> {
        let (w, h) = (self.intrinsics.width, self.intrinsics.height);
        check_len("depth frame", w, h, depth.len())?;
        if let Some(mask) = ignore {
            check_len("ignore mask", w, h, mask.len())?;
        }
        let cfg = &self.cfg;
        let background = (self.background.frames() > 0).then_some(&self.background);
        self.grid.sample(
            depth,
            &SampleParams {
                scale_m: cfg.depth_scale_m,
                min_m: cfg.min_depth_m,
                max_m: cfg.max_depth_m,
                ignore,
                background,
                bg_margin_m: cfg.bg_margin_m,
                bg_margin_sigmas: cfg.bg_margin_sigmas,
            },
        );
        let floor = match cfg.floor {
            FloorMode::None => None,
            FloorMode::Given(p) => Some(p),
            FloorMode::Ransac => self.floor.fit(&self.grid, self.up),
        };
        if let Some(plane) = floor {
            for c in 0..self.grid.len() {
                if self.grid.valid[c] && plane.height(self.grid.pts[c]) < cfg.floor_margin_m {
                    self.grid.valid[c] = false;
                }
            }
        }
        self.seg.run(&self.grid, &self.rule, cfg, self.up);
        let mut n = 0;
        for k in 0..self.seg.people.len() {
            if n == MAX_PEOPLE {
                break;
            }
            let person = self.seg.people[k];
            let comp = self.seg.components[person];
            self.geo.build(
                &self.grid,
                &self.seg,
                person,
                &self.rule,
                cfg.extrema,
                cfg.min_extremum_m as f32,
            );
            let body = Body {
                cfg,
                grid: &self.grid,
                seg: &self.seg,
                comp: &comp,
                person,
                up: self.up,
                side: self.side,
            };
            let skeleton = label(&body, &mut self.geo);
            // a body without a head is no person (a table, a box, a wall's
            // edge); a body beside a larger one is a piece of it
            let fragment = self.dets[..n]
                .iter()
                .any(|d| ground_dist(d.centroid, skeleton.centroid, self.up) < cfg.fragment_m);
            if skeleton.confidence[Joint::Head as usize] > 0.0 && !fragment {
                self.dets[n] = skeleton;
                n += 1;
            }
        }
        Ok(n)
    }

    /// The skeletons of the last [`Tracker::detect`] (or step), largest person
    /// first: the first `n` (as returned) are this frame's.
    pub fn detections(&self) -> &[RawSkeleton; MAX_PEOPLE] {
        &self.dets
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::SmallRng;
    use rand::{Rng, SeedableRng};

    const K: Intrinsics = Intrinsics {
        width: 160,
        height: 120,
        fx: 145.0,
        fy: 145.0,
        cx: 80.0,
        cy: 60.0,
    };

    fn out() -> [Person; MAX_PEOPLE] {
        [Person::default(); MAX_PEOPLE]
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let mut zero = K;
        zero.fx = 0.0;
        assert!(matches!(
            Tracker::new(zero, TrackerConfig::default()),
            Err(TrackError::Intrinsics(_))
        ));
        let mut nan = K;
        nan.cy = f64::NAN;
        assert!(Tracker::new(nan, TrackerConfig::default()).is_err());
        let mut empty = K;
        empty.width = 0;
        assert!(Tracker::new(empty, TrackerConfig::default()).is_err());
        let cfg = TrackerConfig {
            grid_step_px: 0,
            ..TrackerConfig::default()
        };
        assert!(matches!(Tracker::new(K, cfg), Err(TrackError::Config(_))));
        let cfg = TrackerConfig {
            up_camera: [0.0; 3],
            ..TrackerConfig::default()
        };
        assert!(Tracker::new(K, cfg).is_err());
        let mut t = Tracker::new(K, TrackerConfig::default()).unwrap();
        let mut o = out();
        assert!(matches!(
            t.step(&[0; 10], 0.03, &mut o),
            Err(TrackError::FrameSize { .. })
        ));
        let frame = vec![1000u16; K.pixel_count()];
        assert!(matches!(
            t.step(&frame, f64::NAN, &mut o),
            Err(TrackError::TimeStep(_))
        ));
        assert!(t.step(&frame, -1.0, &mut o).is_err());
        assert!(matches!(
            t.step_masked(&frame, Some(&[false; 3]), 0.03, &mut o),
            Err(TrackError::FrameSize { .. })
        ));
        assert!(t.learn_background(&[0; 5]).is_err());
    }

    #[test]
    fn never_panics_on_any_frame() {
        let mut rng = SmallRng::seed_from_u64(7);
        for step in [1, 2, 4, 6, 13] {
            for floor in [FloorMode::None, FloorMode::Ransac] {
                let cfg = TrackerConfig {
                    grid_step_px: step,
                    floor,
                    ..TrackerConfig::default()
                };
                let mut t = Tracker::new(K, cfg).unwrap();
                let mut o = out();
                let n = K.pixel_count();
                let mut frames: Vec<Vec<u16>> = vec![vec![0; n], vec![u16::MAX; n], vec![1; n]];
                for _ in 0..6 {
                    frames.push((0..n).map(|_| rng.gen()).collect());
                    frames.push((0..n).map(|_| rng.gen_range(0..5000)).collect());
                    // blobs of constant depth on noise
                    let mut f: Vec<u16> = (0..n)
                        .map(|_| {
                            if rng.gen_bool(0.3) {
                                rng.gen_range(400..4000)
                            } else {
                                0
                            }
                        })
                        .collect();
                    let (cu, cv, r) = (
                        rng.gen_range(0..160i32),
                        rng.gen_range(0..120i32),
                        rng.gen_range(5..60i32),
                    );
                    let z = rng.gen_range(500..3000);
                    for v in 0..120i32 {
                        for u in 0..160i32 {
                            if (u - cu).abs() < r / 3 || ((u - cu).pow(2) + (v - cv).pow(2)) < r * r
                            {
                                f[(v * 160 + u) as usize] = z + rng.gen_range(0..20);
                            }
                        }
                    }
                    frames.push(f);
                }
                for (k, f) in frames.iter().enumerate() {
                    let mask: Vec<bool> = (0..n).map(|_| rng.gen_bool(0.1)).collect();
                    let m = t
                        .step_masked(f, (k % 2 == 0).then_some(&mask[..]), 1.0 / 30.0, &mut o)
                        .unwrap();
                    assert!(m <= MAX_PEOPLE);
                    for p in &o[..m] {
                        assert!(p.id > 0);
                        for (j, c) in p.joints.iter().zip(p.confidence) {
                            assert!(j.iter().all(|x| x.is_finite()), "{j:?}");
                            assert!((0.0..=1.0).contains(&c));
                        }
                    }
                    if k == 3 {
                        t.learn_background(f).unwrap();
                    }
                }
                t.step(&frames[0], 0.0, &mut o).unwrap();
                t.reset();
                t.clear_background();
            }
        }
    }

    #[test]
    fn nothing_in_an_empty_or_flat_frame() {
        let mut t = Tracker::new(K, TrackerConfig::default()).unwrap();
        let mut o = out();
        assert_eq!(t.step(&vec![0; K.pixel_count()], 0.03, &mut o).unwrap(), 0);
        // a wall 2 m away filling the view
        assert_eq!(
            t.step(&vec![2000; K.pixel_count()], 0.03, &mut o).unwrap(),
            0
        );
    }
}
