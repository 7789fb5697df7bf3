//! Every camera's perception as one step, for the runners that hold the
//! whole cell in one process (the lock-step cell, its sweeps, the tests):
//! camera frame → ingestion → repulsion workers, camera by camera, with the
//! same steps the binaries call ([`CameraSim`], [`SkeletonTracker`],
//! [`Ingest`], [`Worker`]) and the same rules: the body trackers' skeletons
//! merged ([`merge_views`]), the collaborative hand masked from every
//! camera's frame while the newest `collab/state` says a collaboration is on
//! and is fresh ([`collaborating_part`]), the hand refined from every
//! camera's frame and the first camera's that observes it kept ([`best_hand`]), and each camera's distances bounded by what it watches
//! when the cell has several ([`Worker::bounded_by`]). The controller fuses
//! the cameras' results (`phri_control::RepulsionInputs`).

use phri_config::{Config, Invalid};
use phri_ipc::{
    best_hand, CollabState, FrameHeader, HandObservation, RepulsionResult, Skeleton, WorldState,
    Zeroed,
};
use phri_model::Model;

use crate::camera::{CameraError, CameraSim};
use crate::ingest::{FrameError, Ingest, StateHistory};
use crate::mask::{collaborating_part, hand_observation, MaskHold};
use crate::repulsion::{RepulsionError, Worker};
use crate::skeleton::{merge_views, SkeletonTracker};
use crate::surfaces::SeenSurfaces;
use crate::tracker::{DepthTracker, TrackerError};

/// Why a perception step failed, by the service whose step it was.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// the simulated camera could not be built or could not render
    #[error("camera {camera}: {source}")]
    Camera {
        /// index of the camera in `[[camera]]`
        camera: usize,
        /// the camera's error
        #[source]
        source: CameraError,
    },
    /// ingestion refused the camera's frame
    #[error("camera {camera}: {source}")]
    Frame {
        /// index of the camera in `[[camera]]`
        camera: usize,
        /// why
        #[source]
        source: FrameError,
    },
    /// a repulsion worker could not be built or could not answer
    #[error("camera {camera}: {source}")]
    Repulsion {
        /// index of the camera in `[[camera]]`
        camera: usize,
        /// the worker's error
        #[source]
        source: RepulsionError,
    },
    /// the tracker on depth failed on the camera's frame
    #[error("camera {camera}: {source}")]
    Tracker {
        /// index of the camera in `[[camera]]`
        camera: usize,
        /// the tracker's error
        #[source]
        source: TrackerError,
    },
    /// a configuration section that does not fit (ingestion, the tracker on
    /// depth, a worker's camera view)
    #[error(transparent)]
    Config(#[from] Invalid),
}

impl PipelineError {
    /// The service whose step failed (`camera`, `perception`, `repulsion`).
    pub fn service(&self) -> &'static str {
        match self {
            PipelineError::Camera { .. } => "camera",
            PipelineError::Frame { .. } | PipelineError::Config(_) => "perception",
            PipelineError::Repulsion { .. } => "repulsion",
            PipelineError::Tracker { .. } => "tracker",
        }
    }
}

/// One camera with its tracker, its ingestion and its repulsion workers.
struct Eye {
    camera: CameraSim,
    tracker: SkeletonTracker,
    /// the tracker on depth, where this camera's skeletons come from depth
    depth: Option<DepthTracker>,
    skeleton: Skeleton,
    ingest: Ingest,
    workers: Vec<Worker>,
    header: FrameHeader,
    frame: Vec<u16>,
    filtered: Vec<u16>,
    results: Vec<RepulsionResult>,
    /// sends nothing (a killed or silent camera process): no capture, no
    /// skeleton, no results
    dark: bool,
}

/// Every camera of a cell, stepped together.
pub struct Perception {
    eyes: Vec<Eye>,
    /// per worker, with several cameras: the surfaces every camera showed it
    seen: Vec<SeenSurfaces>,
    /// the trackers' skeletons merged, the first camera's first
    skeleton: Skeleton,
    mask_hold: MaskHold,
    collab: phri_config::CollaborationConfig,
}

impl Perception {
    /// The cameras (`[[camera]]`), ingestion, workers and trackers of `config`.
    pub fn new(model: &Model, config: &Config) -> Result<Perception, PipelineError> {
        let several = config.cameras.len() > 1;
        let mut eyes = Vec::with_capacity(config.cameras.len());
        for (i, c) in config.cameras.iter().enumerate() {
            let camera = CameraSim::new(model.clone(), c)
                .map_err(|source| PipelineError::Camera { camera: i, source })?;
            let pixels = camera.pixels();
            let mut workers = Vec::with_capacity(config.repulsion.workers as usize);
            for w in 0..config.repulsion.workers {
                let repulsion = |source| PipelineError::Repulsion { camera: i, source };
                let worker = Worker::new(model.clone(), &config.repulsion, w).map_err(repulsion)?;
                workers.push(match several {
                    true => worker.bounded_by(c)?,
                    false => worker,
                });
            }
            let depth = match config.skeleton_source(i) {
                phri_config::SkeletonSource::Depth => Some(DepthTracker::new(
                    model.clone(),
                    &config.skeleton,
                    &config.perception,
                    c,
                )?),
                phri_config::SkeletonSource::Sim => None,
            };
            eyes.push(Eye {
                tracker: SkeletonTracker::new(&config.skeleton, c.intrinsics, camera.pose()),
                depth,
                skeleton: Skeleton::zeroed(),
                ingest: Ingest::new(model.clone(), &config.perception)?,
                header: FrameHeader::zeroed(),
                frame: vec![0; pixels],
                filtered: vec![0; pixels],
                results: Vec::with_capacity(workers.len()),
                dark: false,
                workers,
                camera,
            });
        }
        let seen = match several {
            true => (0..config.repulsion.workers)
                .map(|_| SeenSurfaces::for_cell(config))
                .collect(),
            false => Vec::new(),
        };
        Ok(Perception {
            eyes,
            seen,
            skeleton: Skeleton::zeroed(),
            mask_hold: MaskHold::default(),
            collab: config.collaboration.clone(),
        })
    }

    /// Cameras.
    pub fn cameras(&self) -> usize {
        self.eyes.len()
    }

    /// Camera `camera` sends nothing while `dark` (its process killed or
    /// silent): from the next capture on, no frame, skeleton or result of it
    /// until it is lit again. Out of range: nothing.
    pub fn set_dark(&mut self, camera: usize, dark: bool) {
        if let Some(e) = self.eyes.get_mut(camera) {
            e.dark = dark;
        }
    }

    /// Every worker of every camera places its control points only
    /// ([`crate::Worker::set_positions_only`]): for a caller that replaces
    /// the distances by the truth.
    pub fn set_positions_only(&mut self, on: bool) {
        for w in self.eyes.iter_mut().flat_map(|e| e.workers.iter_mut()) {
            w.set_positions_only(on);
        }
    }

    /// Whether some camera is not dark ([`Perception::set_dark`]).
    pub fn any_lit(&self) -> bool {
        self.eyes.iter().any(|e| !e.dark)
    }

    /// Every camera captures `world` at `now_ns` (robot clock, also its
    /// capture wall time), and its tracker finds the people of that frame
    /// (`frame_period_s` apart; the tracker on depth removes the robot at
    /// its state in `history`); the skeletons are merged (a joint either
    /// camera sees is seen). Returns the merged skeleton.
    pub fn capture(
        &mut self,
        world: &WorldState,
        now_ns: u64,
        frame_period_s: f64,
        history: &StateHistory,
    ) -> Result<&Skeleton, PipelineError> {
        self.capture_some(world, now_ns, frame_period_s, history, |_| true)
    }

    /// Camera `camera` alone captures `world` at `now_ns`, as
    /// [`Perception::capture`]; the merged skeleton takes its new view and
    /// every other camera's last (cameras that capture in turn,
    /// [`Perception::turn`]).
    pub fn capture_one(
        &mut self,
        camera: usize,
        world: &WorldState,
        now_ns: u64,
        frame_period_s: f64,
        history: &StateHistory,
    ) -> Result<&Skeleton, PipelineError> {
        self.capture_some(world, now_ns, frame_period_s, history, |i| i == camera)
    }

    fn capture_some(
        &mut self,
        world: &WorldState,
        now_ns: u64,
        frame_period_s: f64,
        history: &StateHistory,
        which: impl Fn(usize) -> bool,
    ) -> Result<&Skeleton, PipelineError> {
        let mut newest = None;
        for (i, eye) in self.eyes.iter_mut().enumerate() {
            if eye.dark || !which(i) {
                continue;
            }
            eye.header = FrameHeader::zeroed();
            eye.camera
                .step(world, now_ns, &mut eye.frame, &mut eye.header)
                .map_err(|source| PipelineError::Camera { camera: i, source })?;
            match eye.depth.as_mut() {
                Some(t) => {
                    t.step(&eye.header, &eye.frame, history, now_ns, &mut eye.skeleton)
                        .map_err(|source| PipelineError::Tracker { camera: i, source })?;
                }
                None => eye.tracker.step(
                    world,
                    &eye.header,
                    &eye.frame,
                    frame_period_s,
                    &mut eye.skeleton,
                ),
            }
            newest.get_or_insert(i);
        }
        // the new view first, then every other camera's last (as
        // `merge_newest` merges for the services): a joint either sees is seen
        let others = self
            .eyes
            .iter()
            .enumerate()
            .filter(|&(i, e)| Some(i) != newest && !e.dark && e.header.capture_ns != 0)
            .map(|(_, e)| e);
        let lead = newest.and_then(|i| self.eyes.get(i));
        let mut merged = false;
        for eye in lead.into_iter().chain(others) {
            match merged {
                false => self.skeleton = eye.skeleton,
                true => merge_views(&mut self.skeleton, &eye.skeleton),
            }
            merged = true;
        }
        if !merged {
            // every camera dark: nobody seen (a tracker's skeleton of no
            // frame; the readers' age checks see it never published again)
            self.skeleton = Skeleton::zeroed();
        }
        Ok(&self.skeleton)
    }

    /// Which camera captures at `slot` of a frame period cut in as many
    /// slots as there are cameras (`slot` counted from any start): cameras
    /// that capture in turn, camera `i` at `i`/N of the period, so that the
    /// newest of N views is never older than a period over N (the camera
    /// services' phase, [`crate::turns`]).
    pub fn turn(&self, slot: u64) -> usize {
        (slot % self.eyes.len().max(1) as u64) as usize
    }

    /// Whether `camera` is the first camera that is not dark (whose new
    /// view leads the merged skeleton, as in the gesture service).
    pub fn leads(&self, camera: usize) -> bool {
        self.eyes.iter().position(|e| !e.dark) == Some(camera)
    }

    /// The merged skeleton of the last capture.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// Ingestion and the workers on every camera's last capture, handled at
    /// `ready_ns` (robot clock). While `collab` (the newest `collab/state`,
    /// stamped on the same clock as `ready_ns`) says a collaboration is on,
    /// its hand is masked from every frame and refined from each: the one
    /// [`best_hand`] takes is the returned `perception/hand` message.
    pub fn perceive(
        &mut self,
        history: &StateHistory,
        collab: Option<&CollabState>,
        ready_ns: u64,
    ) -> Result<Option<HandObservation>, PipelineError> {
        let capture_ns = self
            .eyes
            .iter()
            .find(|e| !e.dark)
            .map_or(0, |e| e.header.capture_ns);
        self.perceive_some(history, collab, (capture_ns, ready_ns), |_| true)
    }

    /// [`Perception::perceive`] of camera `camera`'s last capture alone
    /// (the others' results are left as they were).
    pub fn perceive_one(
        &mut self,
        camera: usize,
        history: &StateHistory,
        collab: Option<&CollabState>,
        ready_ns: u64,
    ) -> Result<Option<HandObservation>, PipelineError> {
        let capture_ns = self.eyes.get(camera).map_or(0, |e| e.header.capture_ns);
        self.perceive_some(history, collab, (capture_ns, ready_ns), |i| i == camera)
    }

    fn perceive_some(
        &mut self,
        history: &StateHistory,
        collab: Option<&CollabState>,
        (capture_ns, ready_ns): (u64, u64),
        which: impl Fn(usize) -> bool,
    ) -> Result<Option<HandObservation>, PipelineError> {
        let part = collaborating_part(collab, ready_ns);
        let mask = self
            .mask_hold
            .mask(Some(&self.skeleton), part, &self.collab, capture_ns);
        let mut hands = [None; phri_ipc::MAX_CAMERAS];
        for (i, eye) in self.eyes.iter_mut().enumerate() {
            if !which(i) {
                continue;
            }
            eye.results.clear();
            if eye.dark {
                continue;
            }
            eye.ingest.set_mask(mask);
            let outcome = eye
                .ingest
                .step(
                    &mut eye.header,
                    &eye.frame,
                    history,
                    ready_ns,
                    &mut eye.filtered,
                )
                .map_err(|source| PipelineError::Frame { camera: i, source })?;
            if let (Some(slot), Some(p), Some(m)) = (hands.get_mut(i), part, mask) {
                *slot = Some(hand_observation(
                    &eye.header,
                    p,
                    &m,
                    &outcome.masked,
                    ready_ns,
                ));
            }
            for (k, w) in eye.workers.iter_mut().enumerate() {
                let msg = w
                    .respond_among(&eye.header, &eye.filtered, i, self.seen.get_mut(k))
                    .map_err(|source| PipelineError::Repulsion { camera: i, source })?;
                msg.published_ns = ready_ns;
                eye.results.push(*msg);
            }
        }
        // the controller's choice among the cameras' channels
        let seen: [Option<&HandObservation>; phri_ipc::MAX_CAMERAS] =
            std::array::from_fn(|i| hands[i].as_ref());
        Ok(best_hand(&seen, u64::MAX).copied())
    }

    /// Camera `camera`'s workers' results of the last [`Perception::perceive`].
    pub fn results(&self, camera: usize) -> &[RepulsionResult] {
        self.eyes.get(camera).map_or(&[], |e| &e.results)
    }

    /// Camera `camera`'s last frame: its header and its depths \[mm\] as
    /// captured and as filtered by ingestion.
    pub fn frame(&self, camera: usize) -> Option<(&FrameHeader, &[u16], &[u16])> {
        self.eyes
            .get(camera)
            .map(|e| (&e.header, e.frame.as_slice(), e.filtered.as_slice()))
    }
}
