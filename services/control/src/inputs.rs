//! The step's inputs, and the one conversion from the cell's messages to
//! them: `main.rs` and the lock-step cell both feed [`ControlInput::from_messages`]
//! and [`RepulsionInputs`] the same `robot/state`, `dynamics/residual` and
//! `perception/repulsion` messages.

use nalgebra::Vector3;
use phri_config::{FusedDirection, RepulsionConfig};
use phri_ipc::{
    owners, residual_flags, HriRequest, JointState, Owned, OwnerTable, PointRepulsion, Refusal,
    RepulsionResult, RequestSource, Residual, Sender, DYNAMICS_RESIDUAL, MAX_POINTS_PER_WORKER,
    ROBOT_STATE,
};

use crate::error::InputError;
pub use crate::modes::collaborate::CollabInput;

/// The newest residual, as the controller sees it.
#[derive(Clone, Copy, Debug)]
pub struct ResidualView<'a> {
    /// stamp of the joint state the residual was computed from [ns, robot clock]
    pub state_stamp_ns: u64,
    /// residual r (paper eq. 5) \[Nm\], one per joint
    pub r: &'a [f64],
    /// the observer is past its warm-up
    pub valid: bool,
    /// some joint passed its contact level
    pub contact: bool,
    /// some joint (or the norm) passed its collision level
    pub collision: bool,
}

impl<'a> ResidualView<'a> {
    /// The view of a `dynamics/residual` message for an `n`-joint model
    /// (its flags decoded); refused when the message has another dof.
    pub fn from_message(msg: &'a Residual, n: usize) -> Result<ResidualView<'a>, InputError> {
        if msg.dof as usize != n || n > msg.r.len() {
            return Err(InputError::Dof {
                channel: DYNAMICS_RESIDUAL.name,
                seq: msg.seq,
                expected: n,
                got: msg.dof,
            });
        }
        Ok(ResidualView {
            state_stamp_ns: msg.state_stamp_ns,
            r: &msg.r[..n],
            valid: msg.flags & residual_flags::VALID != 0,
            contact: msg.flags & residual_flags::CONTACT != 0,
            collision: msg.flags & residual_flags::COLLISION != 0,
        })
    }
}

/// The newest perception results, as the controller sees them.
#[derive(Clone, Copy, Debug)]
pub struct PerceptionView<'a> {
    /// capture time of the oldest of the workers' newest results [ns, robot
    /// clock]; 0 while some worker has not answered yet
    pub capture_ns: u64,
    /// newest result per control point, indexed by point (0: the end effector)
    pub points: &'a [PointRepulsion],
    /// with several cameras, per point the camera whose result it is and
    /// that result's capture time (empty: one camera, every point its own
    /// at `capture_ns`), so that a rate is measured over one camera's frames
    pub sources: &'a [PointSource],
}

impl PerceptionView<'_> {
    /// How much older \[s\] control point `k`'s result is than the view
    /// (several cameras: the camera that gave its fused distance may lag
    /// the newest one); 0 with one camera or without a result.
    pub fn point_older_s(&self, k: usize) -> f64 {
        self.sources
            .get(k)
            .map_or(0.0, |s| older_s(self.capture_ns, s.capture_ns))
    }
}

/// How much older \[s\] a result captured at `then_ns` is than one captured
/// at `now_ns` (0 for a result never captured: `then_ns` 0).
fn older_s(now_ns: u64, then_ns: u64) -> f64 {
    match then_ns {
        0 => 0.0,
        t => now_ns.saturating_sub(t) as f64 * 1e-9,
    }
}

/// Which camera's result a fused point is ([`PerceptionView::sources`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PointSource {
    /// the camera's index in `[[camera]]`
    pub camera: usize,
    /// the result's capture time [ns, robot clock]
    pub capture_ns: u64,
}

/// One control period's inputs.
#[derive(Clone, Copy, Debug)]
pub struct ControlInput<'a> {
    /// measurement time of `q` [ns, robot clock]
    pub state_stamp_ns: u64,
    /// measured joint positions \[rad\]
    pub q: &'a [f64],
    /// the newest residual; `None`: none yet (the controller holds a protective stop)
    pub residual: Option<ResidualView<'a>>,
    /// newest repulsion results; `None`: this controller runs without perception
    pub perception: Option<PerceptionView<'a>>,
    /// the collaboration's inputs (requests, skeleton, refined hand); empty: none
    pub collab: CollabInput<'a>,
}

impl<'a> ControlInput<'a> {
    /// The inputs of one period from the messages, for an `n`-joint model: the
    /// joint state (refused with another dof), the newest residual (treated as
    /// absent with another dof: the controller then stops) and, when the
    /// controller avoids obstacles, the accumulated repulsion results.
    pub fn from_messages(
        state: &'a JointState,
        residual: Option<&'a Residual>,
        perception: Option<&'a RepulsionInputs>,
        n: usize,
    ) -> Result<ControlInput<'a>, InputError> {
        if state.dof as usize != n || n > state.q.len() {
            return Err(InputError::Dof {
                channel: ROBOT_STATE.name,
                seq: state.seq,
                expected: n,
                got: state.dof,
            });
        }
        Ok(ControlInput {
            state_stamp_ns: state.stamp_ns,
            q: &state.q[..n],
            residual: residual.and_then(|r| ResidualView::from_message(r, n).ok()),
            perception: perception.map(RepulsionInputs::view),
            collab: CollabInput::default(),
        })
    }
}

/// One camera's repulsion results: the newest per control point, and the
/// capture time of each worker's newest result.
#[derive(Clone, Debug)]
struct CameraResults {
    points: Vec<PointRepulsion>,
    /// capture time of the result held per point \[ns\] (0: none yet)
    point_capture_ns: Vec<u64>,
    /// capture time of each worker's newest result \[ns\] (0: none yet)
    worker_capture_ns: Vec<u64>,
}

impl CameraResults {
    fn new(workers: usize, points: usize) -> CameraResults {
        CameraResults {
            points: (0..points)
                .map(|i| PointRepulsion {
                    point: i as u32,
                    ..PointRepulsion::default()
                })
                .collect(),
            point_capture_ns: vec![0; points],
            worker_capture_ns: vec![0; workers.max(1)],
        }
    }

    /// The capture time of the oldest of the workers' newest results; 0
    /// while some worker has not answered yet.
    fn capture_ns(&self) -> u64 {
        self.worker_capture_ns.iter().copied().min().unwrap_or(0)
    }
}

/// The repulsion workers' results gathered into the controller's view,
/// camera by camera: the newest result per control point, and the capture
/// time of each worker's newest result. With several cameras each camera's
/// distances are lower bounds of the true ones (the workers bound them by
/// what their camera watches), and [`RepulsionInputs::fuse`] takes per point
/// the largest bound of the cameras that are fresh (answered within the
/// perception's staleness bound), with that camera's repulsive vector: a
/// camera gone stale or killed drops out; with none fresh the view is as
/// stale as the newest camera. Preallocated; nothing here allocates after
/// construction.
#[derive(Clone, Debug)]
pub struct RepulsionInputs {
    cameras: Vec<CameraResults>,
    /// the fused view's points and capture time (several cameras)
    fused: Vec<PointRepulsion>,
    /// ... each point's camera and capture time
    fused_sources: Vec<PointSource>,
    fused_capture_ns: u64,
    /// per camera: point-periods it gave the fused distance
    gave: Vec<u64>,
    /// a camera older than this is left out of the fusion \[ns\]
    max_age_ns: u64,
    /// whose direction a fused point takes
    direction: FusedDirection,
    /// the speed at which a camera's bound ages \[m/s\]: a camera's
    /// distance counts `age_speed × (how much older its result is than
    /// the fused view's)` less when the cameras' bounds are compared (0:
    /// the largest distance, however old)
    age_speed_m_s: f64,
    refused: u64,
}

impl RepulsionInputs {
    /// For `workers` workers sharing `points` control points, one camera.
    pub fn new(workers: usize, points: usize) -> RepulsionInputs {
        RepulsionInputs::with_cameras(1, workers, points, u64::MAX)
    }

    /// For `cameras` cameras (at least one), each answered by `workers`
    /// workers sharing `points` control points; a camera whose results are
    /// older than `max_age_ns` is left out of the fusion.
    pub fn with_cameras(
        cameras: usize,
        workers: usize,
        points: usize,
        max_age_ns: u64,
    ) -> RepulsionInputs {
        let cameras = cameras.max(1);
        RepulsionInputs {
            cameras: (0..cameras)
                .map(|_| CameraResults::new(workers, points))
                .collect(),
            fused: (0..points)
                .map(|i| PointRepulsion {
                    point: i as u32,
                    ..PointRepulsion::default()
                })
                .collect(),
            fused_sources: vec![PointSource::default(); points],
            fused_capture_ns: 0,
            gave: vec![0; cameras],
            max_age_ns,
            direction: FusedDirection::Largest,
            age_speed_m_s: 0.0,
            refused: 0,
        }
    }

    /// Compare the cameras' bounds as they stand at the fused view's
    /// capture time: a result `a` older than the newest fresh camera's
    /// counts `speed_m_s · a` \[m\] less (a person may have come that much
    /// nearer since). Default 0: the largest distance, however old.
    pub fn with_age_speed(mut self, speed_m_s: f64) -> RepulsionInputs {
        self.age_speed_m_s = match speed_m_s.is_finite() {
            true => speed_m_s.max(0.0),
            false => 0.0,
        };
        self
    }

    /// Fused points take `direction`'s repulsive direction (default:
    /// [`FusedDirection::Largest`], the baseline).
    pub fn with_direction(mut self, direction: FusedDirection) -> RepulsionInputs {
        self.direction = direction;
        self
    }

    /// For the workers and control points of `[repulsion]`, one camera.
    pub fn from_config(cfg: &RepulsionConfig) -> RepulsionInputs {
        RepulsionInputs::new(cfg.workers as usize, cfg.points.len())
    }

    /// For the cameras (`[[camera]]`), workers and control points of
    /// `config`, cameras staler than `[control] perception_max_age_ms` left
    /// out of the fusion; under the barrier filter the cameras' bounds
    /// compared at the same instant (`[avoidance] human_speed_m_s`,
    /// [`RepulsionInputs::with_age_speed`]), under the paper's law the
    /// largest.
    pub fn for_cell(config: &phri_config::Config) -> RepulsionInputs {
        let age_speed = match config.avoidance.law {
            phri_config::AvoidanceLaw::Cbf => config.avoidance.human_speed_m_s,
            phri_config::AvoidanceLaw::Paper => 0.0,
        };
        RepulsionInputs::with_cameras(
            config.cameras.len(),
            config.repulsion.workers as usize,
            config.repulsion.points.len(),
            (config.control.perception_max_age_ms * 1e6) as u64,
        )
        .with_direction(config.repulsion.fused_direction)
        .with_age_speed(age_speed)
    }

    /// Cameras whose results this gathers.
    pub fn cameras(&self) -> usize {
        self.cameras.len()
    }

    /// Take one worker's result on the first camera's frames.
    pub fn push(&mut self, msg: &RepulsionResult) -> Result<(), InputError> {
        self.push_camera(0, msg)
    }

    /// Take one worker's result on camera `camera`'s frames. A result that
    /// names an unknown camera, worker or point, claims more points than it
    /// carries, or carries a non-finite repulsive vector or a NaN distance
    /// (+∞: nothing in the region), is refused whole (its capture time does
    /// not count: perception turns stale rather than trusting it) and
    /// counted. A result older than the one held for a point (workers
    /// answering out of order) does not replace it.
    pub fn push_camera(&mut self, camera: usize, msg: &RepulsionResult) -> Result<(), InputError> {
        let checked = self.check(camera, msg);
        if checked.is_err() {
            self.refused += 1;
            return checked;
        }
        let c = &mut self.cameras[camera];
        let w = &mut c.worker_capture_ns[msg.worker as usize];
        *w = (*w).max(msg.capture_ns);
        for p in &msg.points[..msg.n_points as usize] {
            let k = p.point as usize;
            if msg.capture_ns >= c.point_capture_ns[k] {
                c.points[k] = *p;
                c.point_capture_ns[k] = msg.capture_ns;
            }
        }
        Ok(())
    }

    fn check(&self, camera: usize, msg: &RepulsionResult) -> Result<(), InputError> {
        let Some(c) = self.cameras.get(camera) else {
            return Err(InputError::Camera {
                camera,
                cameras: self.cameras.len(),
            });
        };
        let workers = c.worker_capture_ns.len();
        if msg.worker as usize >= workers {
            return Err(InputError::Worker {
                worker: msg.worker,
                workers,
            });
        }
        if msg.n_points as usize > MAX_POINTS_PER_WORKER {
            return Err(InputError::PointCount {
                worker: msg.worker,
                n_points: msg.n_points,
                max: MAX_POINTS_PER_WORKER,
            });
        }
        let points = c.points.len();
        for p in &msg.points[..msg.n_points as usize] {
            if p.point as usize >= points {
                return Err(InputError::Point {
                    worker: msg.worker,
                    point: p.point,
                    points,
                });
            }
            if !p.v_call.iter().all(|x| x.is_finite()) || p.min_distance.is_nan() {
                return Err(InputError::NonFinite {
                    worker: msg.worker,
                    point: p.point,
                });
            }
        }
        Ok(())
    }

    /// Fuse the cameras at robot time `now_ns` (several cameras; with one,
    /// nothing to do): per point, the largest distance among the cameras
    /// that are fresh (each less its age beyond the view's at
    /// [`RepulsionInputs::with_age_speed`]), with its camera's repulsive
    /// vector, or, with
    /// [`FusedDirection::First`], the first camera's direction at that
    /// vector's magnitude while the first camera is fresh and sees
    /// something near the point. The view's
    /// capture time is the newest fresh camera's; with none fresh, the
    /// newest camera's (stale: the controller's stale-perception rule).
    pub fn fuse(&mut self, now_ns: u64) {
        if self.cameras.len() == 1 {
            return;
        }
        let (cameras, max_age_ns) = (&self.cameras, self.max_age_ns);
        let fresh = |c: &CameraResults| {
            let t = c.capture_ns();
            t > 0 && now_ns.saturating_sub(t) <= max_age_ns
        };
        let any_fresh = cameras.iter().any(fresh);
        let capture_ns = cameras
            .iter()
            .filter(|c| !any_fresh || fresh(c))
            .map(CameraResults::capture_ns)
            .max()
            .unwrap_or(0);
        self.fused_capture_ns = capture_ns;
        for (k, (slot, source)) in self
            .fused
            .iter_mut()
            .zip(&mut self.fused_sources)
            .enumerate()
        {
            let mut best: Option<(usize, f64)> = None;
            for (i, c) in cameras.iter().enumerate() {
                let eligible = match any_fresh {
                    true => fresh(c),
                    // none fresh: the newest camera's, whatever it says
                    false => c.capture_ns() == capture_ns,
                };
                // its bound at the view's capture time
                let older = older_s(capture_ns, c.point_capture_ns[k]);
                let bound = c.points[k].min_distance - self.age_speed_m_s * older;
                if eligible && best.is_none_or(|(_, b)| bound > b) {
                    best = Some((i, bound));
                }
            }
            let best = best.map(|(i, _)| i);
            if let Some(b) = best {
                *slot = cameras[b].points[k];
                *source = PointSource {
                    camera: b,
                    capture_ns: cameras[b].point_capture_ns[k],
                };
                self.gave[b] += 1;
                // the first camera's direction at the fused magnitude
                let first = &cameras[0].points[k];
                let v_first = Vector3::from(first.v_call);
                let v = Vector3::from(slot.v_call);
                if self.direction == FusedDirection::First
                    && b != 0
                    && any_fresh
                    && fresh(&cameras[0])
                    && first.active != 0
                    && slot.active != 0
                    && v_first.norm() > 0.0
                {
                    slot.v_call = (v_first * (v.norm() / v_first.norm())).into();
                }
            }
        }
    }

    /// The controller's view: the newest result per point; the capture time
    /// of the oldest of the workers' newest results, 0 while some worker has
    /// not answered yet. With several cameras: the last [`RepulsionInputs::fuse`].
    pub fn view(&self) -> PerceptionView<'_> {
        match self.cameras.as_slice() {
            [one] => PerceptionView {
                capture_ns: one.capture_ns(),
                points: &one.points,
                sources: &[],
            },
            _ => PerceptionView {
                capture_ns: self.fused_capture_ns,
                points: &self.fused,
                sources: &self.fused_sources,
            },
        }
    }

    /// Per camera: how many point-periods it gave the fused distance.
    pub fn gave(&self) -> &[u64] {
        &self.gave
    }

    /// Results refused since the start.
    pub fn refused(&self) -> u64 {
        self.refused
    }
}

/// The gate of the controller's inputs: a sample counts only when the
/// service the supervisor started for its channel sent it ([`phri_ipc::owners`]),
/// and only with a stamp that is neither from the future (later than now
/// plus [`phri_ipc::owners::FUTURE_MARGIN_NS`]) nor older than its
/// staleness bound. A repulsion result counts only for the points its
/// worker owns (point i: worker i mod workers), and only from that worker;
/// a request's source is its sender (the gesture or voice service; any
/// other process of the cell's user is the operator's command line, `cli`),
/// never its own field. What it refuses is counted in the owner table
/// (published on `audit/inputs`). Allocates nothing.
pub struct InputGate {
    owners: std::sync::Arc<OwnerTable>,
    /// the residual's staleness bound [ns]
    residual_max_age_ns: u64,
    /// the perception results' staleness bound [ns]
    perception_max_age_ns: u64,
    workers: u32,
}

impl InputGate {
    /// The gate of `[control]`'s staleness bounds and `[repulsion]`'s workers.
    pub fn new(
        owners: std::sync::Arc<OwnerTable>,
        control: &phri_config::ControlConfig,
        repulsion: &RepulsionConfig,
    ) -> InputGate {
        InputGate {
            owners,
            residual_max_age_ns: (control.residual_max_age_ms * 1e6) as u64,
            perception_max_age_ns: (control.perception_max_age_ms * 1e6) as u64,
            workers: repulsion.workers.max(1),
        }
    }

    /// A gate that takes every sender as it is (no supervisor), with the
    /// time bounds of the configuration.
    pub fn unchecked(
        control: &phri_config::ControlConfig,
        repulsion: &RepulsionConfig,
    ) -> InputGate {
        InputGate::new(
            std::sync::Arc::new(OwnerTable::unchecked()),
            control,
            repulsion,
        )
    }

    /// The owner table: each input channel's sender, and what was refused.
    pub fn owners(&self) -> &OwnerTable {
        &self.owners
    }

    /// `robot/state` from `pid`.
    pub fn state(&self, pid: i32) -> bool {
        self.owners.admit(Owned::ROBOT_STATE, pid).accepted()
    }

    /// The other controller's behaviour state from `pid` (`control/behaviour`
    /// or `control/standby/behaviour`): a controller the supervisor started.
    pub fn behaviour(&self, pid: i32) -> bool {
        self.owners.admit(Owned::CONTROL_BEHAVIOUR, pid).accepted()
    }

    /// Refuse `stamp_ns` on `channel` when from the future or older than
    /// `max_age_ns` against `now_ns` (robot clock), counting it.
    fn timely(
        &self,
        channel: Owned,
        pid: i32,
        stamp_ns: u64,
        now_ns: u64,
        max_age_ns: u64,
    ) -> bool {
        if owners::from_the_future(stamp_ns, now_ns) {
            self.owners.refuse(channel, Refusal::Future, pid);
            false
        } else if now_ns.saturating_sub(stamp_ns) > max_age_ns {
            self.owners.refuse(channel, Refusal::Stale, pid);
            false
        } else {
            true
        }
    }

    /// `dynamics/residual` from `pid`, at robot time `now_ns` (the state's stamp).
    pub fn residual(&self, pid: i32, r: &Residual, now_ns: u64) -> bool {
        self.owners.admit(Owned::DYNAMICS_RESIDUAL, pid).accepted()
            && self.timely(
                Owned::DYNAMICS_RESIDUAL,
                pid,
                r.state_stamp_ns,
                now_ns,
                self.residual_max_age_ns,
            )
    }

    /// `perception/repulsion` from `pid`, at robot time `now_ns`.
    pub fn repulsion(&self, pid: i32, r: &RepulsionResult, now_ns: u64) -> bool {
        let c = Owned::PERCEPTION_REPULSION;
        let worker = match self.owners.admit(c, pid) {
            Sender::Stranger => return false,
            Sender::Owner { worker, .. } => worker,
            Sender::Unchecked => None,
        };
        let n = (r.n_points as usize).min(r.points.len());
        let its_own = worker.is_none_or(|w| w == r.worker)
            && r.points[..n]
                .iter()
                .all(|p| p.point % self.workers == r.worker % self.workers);
        if !its_own {
            self.owners.refuse(c, Refusal::NotItsPoint, pid);
            return false;
        }
        self.timely(c, pid, r.capture_ns, now_ns, self.perception_max_age_ns)
    }

    /// `perception/skeleton` from `pid`, at robot time `now_ns` (its age is
    /// judged by the collaboration).
    pub fn skeleton(&self, pid: i32, s: &phri_ipc::Skeleton, now_ns: u64) -> bool {
        self.owned_and_not_ahead(Owned::PERCEPTION_SKELETON, pid, s.capture_ns, now_ns)
    }

    /// `perception/hand` from `pid`, at robot time `now_ns`.
    pub fn hand(&self, pid: i32, h: &phri_ipc::HandObservation, now_ns: u64) -> bool {
        self.owned_and_not_ahead(Owned::PERCEPTION_HAND, pid, h.capture_ns, now_ns)
    }

    fn owned_and_not_ahead(&self, c: Owned, pid: i32, stamp_ns: u64, now_ns: u64) -> bool {
        if !self.owners.admit(c, pid).accepted() {
            return false;
        }
        if owners::from_the_future(stamp_ns, now_ns) {
            self.owners.refuse(c, Refusal::Future, pid);
            return false;
        }
        true
    }

    /// `hri/request` from `pid` at `mono_now_ns` \[CLOCK_MONOTONIC\]: refused
    /// from the future; its `source` set from its sender.
    pub fn request(&self, pid: i32, r: &mut HriRequest, mono_now_ns: u64) -> bool {
        let c = Owned::HRI_REQUEST;
        if owners::from_the_future(r.stamp_ns, mono_now_ns) {
            self.owners.refuse(c, Refusal::Future, pid);
            return false;
        }
        match self.owners.sender(c, pid) {
            Sender::Unchecked => {}
            Sender::Owner { slot, .. } => {
                r.source = match self.owners.binary(slot) {
                    "phri-gesture" => RequestSource::Gesture as u32,
                    "phri-voice" => RequestSource::Voice as u32,
                    "phri-ros2" => RequestSource::Ros2 as u32,
                    _ => RequestSource::Cli as u32,
                }
            }
            // the operator's command line (phri-hri, a script of the cell's user)
            Sender::Stranger => r.source = RequestSource::Cli as u32,
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    /// Worker `w`'s result for a frame captured at `capture_ns`, for `points`,
    /// each with `min_distance` = the capture time in ms (to tell them apart).
    fn result(w: u32, capture_ns: u64, points: &[u32]) -> RepulsionResult {
        let mut r = RepulsionResult::zeroed();
        r.worker = w;
        r.workers = 2;
        r.capture_ns = capture_ns;
        r.n_points = points.len() as u32;
        for (slot, &p) in r.points.iter_mut().zip(points) {
            *slot = PointRepulsion {
                point: p,
                active: 1,
                min_distance: capture_ns as f64 * 1e-6,
                ..PointRepulsion::default()
            };
        }
        r
    }

    #[test]
    fn capture_time_waits_for_every_worker_then_is_the_oldest_newest() {
        // two workers, points 0, 2 on worker 0 and 1, 3 on worker 1
        let mut acc = RepulsionInputs::new(2, 4);
        assert_eq!(acc.view().capture_ns, 0);
        acc.push(&result(1, 40_000_000, &[1, 3])).unwrap();
        assert_eq!(acc.view().capture_ns, 0, "worker 0 has not answered");
        acc.push(&result(0, 33_000_000, &[0, 2])).unwrap();
        assert_eq!(acc.view().capture_ns, 33_000_000);
        acc.push(&result(0, 66_000_000, &[0, 2])).unwrap();
        assert_eq!(acc.view().capture_ns, 40_000_000);
        let v = acc.view();
        let d: Vec<f64> = v.points.iter().map(|p| p.min_distance).collect();
        assert_eq!(d, [66.0, 40.0, 66.0, 40.0]);
        assert!(v
            .points
            .iter()
            .enumerate()
            .all(|(i, p)| p.point as usize == i));
    }

    /// Worker `w`'s result for `points` at `distance` [m], pushing away along +x.
    fn at(w: u32, capture_ns: u64, points: &[u32], distance: f64, vx: f64) -> RepulsionResult {
        let mut r = result(w, capture_ns, points);
        for p in &mut r.points[..points.len()] {
            p.min_distance = distance;
            p.v_call = [vx, 0.0, 0.0];
        }
        r
    }

    #[test]
    fn cameras_fuse_to_the_largest_fresh_bound_with_its_own_direction() {
        const MS: u64 = 1_000_000;
        // two cameras, two workers, four points; stale after 100 ms
        let mut acc = RepulsionInputs::with_cameras(2, 2, 4, 100 * MS);
        // camera 0 sees the person 2 cm from every point (its shadow),
        // camera 1 sees 25 cm, pushing the other way
        for w in 0..2 {
            let pts: &[u32] = if w == 0 { &[0, 2] } else { &[1, 3] };
            acc.push_camera(0, &at(w, 1000 * MS, pts, 0.02, 1.0))
                .unwrap();
            acc.push_camera(1, &at(w, 1010 * MS, pts, 0.25, -1.0))
                .unwrap();
        }
        acc.fuse(1050 * MS);
        let v = acc.view();
        assert_eq!(v.capture_ns, 1010 * MS, "the newest fresh camera's");
        for (i, p) in v.points.iter().enumerate() {
            assert_eq!(p.point as usize, i);
            assert_eq!(p.min_distance, 0.25);
            assert_eq!(p.v_call, [-1.0, 0.0, 0.0], "camera 1's direction");
        }
        assert_eq!(acc.gave(), [0, 4]);
        // camera 1 goes silent: once stale it drops out, camera 0 answers alone
        for w in 0..2 {
            let pts: &[u32] = if w == 0 { &[0, 2] } else { &[1, 3] };
            acc.push_camera(0, &at(w, 1100 * MS, pts, 0.02, 1.0))
                .unwrap();
        }
        acc.fuse(1105 * MS);
        assert_eq!(acc.view().points[0].min_distance, 0.25, "still fresh");
        acc.fuse(1111 * MS + 100 * MS);
        let v = acc.view();
        assert_eq!(v.capture_ns, 1100 * MS);
        assert!(v
            .points
            .iter()
            .all(|p| p.min_distance == 0.02 && p.v_call[0] == 1.0));
        // both stale: the newest camera's, as stale as it is (the controller stops)
        acc.fuse(5000 * MS);
        assert_eq!(acc.view().capture_ns, 1100 * MS);
        // one camera: the view is its results, no fusion needed
        let mut one = RepulsionInputs::new(2, 4);
        one.push(&at(0, 7, &[0, 2], 0.3, 0.0)).unwrap();
        one.push(&at(1, 8, &[1, 3], 0.4, 0.0)).unwrap();
        assert_eq!(one.view().capture_ns, 7);
        assert_eq!(one.view().points[1].min_distance, 0.4);
        // a result of a camera the cell lacks is refused
        assert_eq!(
            one.push_camera(1, &at(0, 9, &[0], 0.3, 0.0)),
            Err(InputError::Camera {
                camera: 1,
                cameras: 1
            })
        );
    }

    #[test]
    fn an_older_camera_s_bound_counts_as_it_stands_now() {
        const MS: u64 = 1_000_000;
        // camera 0 answered at 1000 ms: 20 cm; camera 1 a frame earlier
        // (967 ms): 24 cm. At 1.6 m/s the person may have come 5.3 cm
        // nearer since camera 1 looked: its bound is 18.7 cm at 1000 ms
        let fused = |speed: f64| {
            let mut acc = RepulsionInputs::with_cameras(2, 1, 1, 100 * MS).with_age_speed(speed);
            acc.push_camera(0, &at(0, 1000 * MS, &[0], 0.20, 1.0))
                .unwrap();
            acc.push_camera(1, &at(0, 967 * MS, &[0], 0.24, -1.0))
                .unwrap();
            acc.fuse(1005 * MS);
            let v = acc.view();
            (v.points[0].min_distance, v.sources[0], v.capture_ns)
        };
        let (d, source, capture) = fused(1.6);
        assert_eq!((d, source.camera, source.capture_ns), (0.20, 0, 1000 * MS));
        assert_eq!(capture, 1000 * MS);
        // without: the largest, however old (the paper's law)
        let (d, source, _) = fused(0.0);
        assert_eq!((d, source.camera, source.capture_ns), (0.24, 1, 967 * MS));
        // an older camera still gives the bound when it is enough larger
        let mut acc = RepulsionInputs::with_cameras(2, 1, 1, 100 * MS).with_age_speed(1.6);
        acc.push_camera(0, &at(0, 1000 * MS, &[0], 0.20, 1.0))
            .unwrap();
        acc.push_camera(1, &at(0, 967 * MS, &[0], 0.30, -1.0))
            .unwrap();
        acc.fuse(1005 * MS);
        assert_eq!(acc.view().points[0].min_distance, 0.30);
        assert_eq!(acc.view().sources[0].camera, 1);
        // a speed that is no speed compares the distances alone
        let acc = RepulsionInputs::with_cameras(2, 1, 1, 100 * MS).with_age_speed(f64::NAN);
        assert_eq!(acc.age_speed_m_s, 0.0);
    }

    #[test]
    fn a_point_fused_from_an_older_camera_is_as_old_as_its_camera() {
        const MS: u64 = 1_000_000;
        let points = [PointRepulsion::default(); 3];
        let sources = [
            PointSource {
                camera: 0,
                capture_ns: 1000 * MS,
            },
            PointSource {
                camera: 1,
                capture_ns: 967 * MS,
            },
            // no result yet: no age of its own
            PointSource {
                camera: 1,
                capture_ns: 0,
            },
        ];
        let v = PerceptionView {
            capture_ns: 1000 * MS,
            points: &points,
            sources: &sources,
        };
        assert_eq!(v.point_older_s(0), 0.0);
        assert!((v.point_older_s(1) - 0.033).abs() < 1e-12);
        assert_eq!(v.point_older_s(2), 0.0);
        assert_eq!(v.point_older_s(3), 0.0, "no such point");
        // one camera: the view's own age
        let one = PerceptionView { sources: &[], ..v };
        assert_eq!(one.point_older_s(1), 0.0);
    }

    #[test]
    fn the_first_camera_s_direction_at_the_fused_magnitude_when_asked() {
        const MS: u64 = 1_000_000;
        let mut acc =
            RepulsionInputs::with_cameras(2, 1, 1, 100 * MS).with_direction(FusedDirection::First);
        let mut a = at(0, 10 * MS, &[0], 0.05, 0.0);
        a.points[0].v_call = [0.0, 0.2, 0.0];
        let mut b = at(0, 10 * MS, &[0], 0.25, 0.0);
        b.points[0].v_call = [-0.03, 0.0, 0.04];
        acc.push_camera(0, &a).unwrap();
        acc.push_camera(1, &b).unwrap();
        acc.fuse(20 * MS);
        let p = acc.view().points[0];
        assert_eq!(p.min_distance, 0.25, "the largest bound");
        let v = Vector3::from(p.v_call);
        assert!((v.norm() - 0.05).abs() < 1e-12, "camera 1's magnitude");
        assert!(
            v.x.abs() < 1e-12 && v.y > 0.0,
            "camera 0's direction: {v:?}"
        );
        assert_eq!(acc.gave(), [0, 1]);
        // the first camera sees nothing near (its bound is its view's edge):
        // the distance's camera's vector
        let mut none = at(0, 40 * MS, &[0], 0.02, 0.0);
        none.points[0].active = 0;
        let mut b2 = b;
        b2.capture_ns = 40 * MS;
        acc.push_camera(0, &none).unwrap();
        acc.push_camera(1, &b2).unwrap();
        acc.fuse(50 * MS);
        assert_eq!(acc.view().points[0].v_call, [-0.03, 0.0, 0.04]);
    }

    #[test]
    fn a_camera_missing_a_worker_never_gives_the_fused_distance() {
        const MS: u64 = 1_000_000;
        let mut acc = RepulsionInputs::with_cameras(2, 2, 2, 100 * MS);
        acc.push_camera(0, &at(0, 10 * MS, &[0], 0.05, 1.0))
            .unwrap();
        acc.push_camera(0, &at(1, 10 * MS, &[1], 0.05, 1.0))
            .unwrap();
        // camera 1's worker 1 never answered: camera 1 is not fresh
        acc.push_camera(1, &at(0, 10 * MS, &[0], 0.4, 1.0)).unwrap();
        acc.fuse(20 * MS);
        assert!(acc.view().points.iter().all(|p| p.min_distance == 0.05));
        assert_eq!(acc.view().capture_ns, 10 * MS);
    }

    #[test]
    fn an_older_result_arriving_late_changes_nothing() {
        let mut acc = RepulsionInputs::new(2, 4);
        acc.push(&result(0, 66_000_000, &[0, 2])).unwrap();
        acc.push(&result(1, 66_000_000, &[1, 3])).unwrap();
        acc.push(&result(0, 33_000_000, &[0, 2])).unwrap();
        let v = acc.view();
        assert_eq!(v.capture_ns, 66_000_000);
        assert!(v.points.iter().all(|p| p.min_distance == 66.0));
        assert_eq!(acc.refused(), 0);
    }

    #[test]
    fn a_missing_worker_keeps_perception_unanswered_then_stale() {
        let mut acc = RepulsionInputs::new(3, 3);
        for k in 1..=5u64 {
            acc.push(&result(0, k * 33_000_000, &[0])).unwrap();
            acc.push(&result(2, k * 33_000_000, &[2])).unwrap();
        }
        assert_eq!(acc.view().capture_ns, 0, "worker 1 never answered");
        acc.push(&result(1, 33_000_000, &[1])).unwrap();
        // worker 1 answered once and fell silent: its result is the oldest
        assert_eq!(acc.view().capture_ns, 33_000_000);
    }

    #[test]
    fn malformed_results_are_refused_whole() {
        let mut acc = RepulsionInputs::new(2, 3);
        assert_eq!(
            acc.push(&result(2, 1, &[0])),
            Err(InputError::Worker {
                worker: 2,
                workers: 2
            })
        );
        // point 3 of 3: out of range; point 0 of the same result is not taken either
        assert_eq!(
            acc.push(&result(0, 5, &[0, 3])),
            Err(InputError::Point {
                worker: 0,
                point: 3,
                points: 3
            })
        );
        let mut r = result(1, 5, &[1]);
        r.n_points = MAX_POINTS_PER_WORKER as u32 + 1;
        assert!(matches!(acc.push(&r), Err(InputError::PointCount { .. })));
        let mut r = result(1, 5, &[1]);
        r.points[0].v_call[1] = f64::NAN;
        assert_eq!(
            acc.push(&r),
            Err(InputError::NonFinite {
                worker: 1,
                point: 1
            })
        );
        assert_eq!(acc.refused(), 4);
        let v = acc.view();
        assert_eq!(v.capture_ns, 0);
        assert!(v.points.iter().all(|p| p.active == 0));
    }

    #[test]
    fn residual_message_of_another_robot_is_refused_and_flags_decode() {
        let mut m = Residual::zeroed();
        m.dof = 6;
        m.seq = 9;
        let e = ResidualView::from_message(&m, 7).unwrap_err();
        assert_eq!(
            e,
            InputError::Dof {
                channel: "dynamics/residual",
                seq: 9,
                expected: 7,
                got: 6
            }
        );
        assert!(e.to_string().contains("dynamics/residual"));
        m.dof = 7;
        m.flags = residual_flags::VALID | residual_flags::COLLISION;
        m.r[2] = 4.5;
        m.state_stamp_ns = 77;
        let v = ResidualView::from_message(&m, 7).unwrap();
        assert!(v.valid && v.collision && !v.contact);
        assert_eq!((v.r.len(), v.r[2], v.state_stamp_ns), (7, 4.5, 77));
    }

    #[test]
    fn inputs_from_messages() {
        let mut state = JointState::zeroed();
        state.dof = 7;
        state.stamp_ns = 5_000_000;
        state.q[1] = 0.3;
        let mut res = Residual::zeroed();
        res.dof = 6;
        let acc = RepulsionInputs::new(1, 2);
        let i = ControlInput::from_messages(&state, Some(&res), Some(&acc), 7).unwrap();
        assert_eq!((i.state_stamp_ns, i.q.len(), i.q[1]), (5_000_000, 7, 0.3));
        assert!(
            i.residual.is_none(),
            "a residual of another robot is no residual"
        );
        assert_eq!(i.perception.map(|p| p.points.len()), Some(2));
        res.dof = 7;
        let i = ControlInput::from_messages(&state, Some(&res), None, 7).unwrap();
        assert!(i.residual.is_some() && i.perception.is_none());
        state.dof = 3;
        let e = ControlInput::from_messages(&state, None, None, 7).unwrap_err();
        assert!(e.to_string().starts_with("robot/state"));
    }

    /// The gate: only the owner of a channel, no stamp from the future or
    /// past its bound, a worker only for its own points, a request's source
    /// from its sender; each refusal counted on its channel.
    #[test]
    fn the_gate_takes_only_owners_in_time_and_counts_the_rest() {
        use phri_ipc::{ServiceRole, Zeroed};
        let cfg = phri_config::Config::defaults();
        let role = |name: &str, binary: &str, worker| ServiceRole {
            name: name.into(),
            binary: binary.into(),
            worker,
        };
        let owners = std::sync::Arc::new(OwnerTable::new(
            vec![
                role("dynamics", "phri-dynamics", None),
                role("repulsion0", "phri-repulsion", Some(0)),
                role("voice", "phri-voice", None),
            ],
            true,
        ));
        owners.set_pid("dynamics", 10);
        owners.set_pid("repulsion0", 20);
        owners.set_pid("voice", 30);
        let mut rep_cfg = cfg.repulsion.clone();
        rep_cfg.workers = 4;
        let gate = InputGate::new(owners.clone(), &cfg.control, &rep_cfg);
        let now = 50_000_000_000u64;
        // the residual: its owner, fresh; a stranger; from the future; stale
        let mut r = Residual::zeroed();
        r.state_stamp_ns = now - 1_000_000;
        assert!(gate.residual(10, &r, now));
        assert!(!gate.residual(99, &r, now));
        r.state_stamp_ns = 1 << 63;
        assert!(!gate.residual(10, &r, now));
        r.state_stamp_ns = now - 50_000_000;
        assert!(!gate.residual(10, &r, now));
        let (c, pid) = owners.refused(Owned::DYNAMICS_RESIDUAL);
        assert_eq!((c, pid), ([1, 1, 1, 0], 99));
        // repulsion: worker 0's own points only, and only from worker 0
        let mut m = result(0, now - 5_000_000, &[0, 4]);
        m.workers = 4;
        assert!(gate.repulsion(20, &m, now));
        let mut theirs = result(0, now - 5_000_000, &[1]);
        theirs.workers = 4;
        assert!(!gate.repulsion(20, &theirs, now));
        let mut claims_another = result(1, now - 5_000_000, &[1]);
        claims_another.workers = 4;
        assert!(!gate.repulsion(20, &claims_another, now));
        m.capture_ns = 1 << 63;
        assert!(!gate.repulsion(20, &m, now));
        let (c, _) = owners.refused(Owned::PERCEPTION_REPULSION);
        assert_eq!(c, [0, 1, 0, 2]);
        // a request's source is its sender, not its field
        let mut q = HriRequest::zeroed();
        q.stamp_ns = 1;
        q.source = RequestSource::Voice as u32;
        assert!(gate.request(77, &mut q, now));
        assert_eq!(q.source, RequestSource::Cli as u32);
        q.source = RequestSource::Gesture as u32;
        assert!(gate.request(30, &mut q, now));
        assert_eq!(q.source, RequestSource::Voice as u32);
        q.stamp_ns = 1 << 63;
        assert!(!gate.request(30, &mut q, now));
        // without a supervisor every sender counts, the clock still does not lie
        let open = InputGate::unchecked(&cfg.control, &rep_cfg);
        r.state_stamp_ns = now;
        assert!(open.residual(99, &r, now));
        r.state_stamp_ns = 1 << 63;
        assert!(!open.residual(99, &r, now));
    }
}
