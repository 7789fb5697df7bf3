//! The step's inputs, and the one conversion from the cell's messages to
//! them: `main.rs` and the lock-step cell both feed [`ControlInput::from_messages`]
//! and [`RepulsionInputs`] the same `robot/state`, `dynamics/residual` and
//! `perception/repulsion` messages.

use phri_config::RepulsionConfig;
use phri_ipc::{
    residual_flags, JointState, PointRepulsion, RepulsionResult, Residual, DYNAMICS_RESIDUAL,
    MAX_POINTS_PER_WORKER, ROBOT_STATE,
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

/// The repulsion workers' results gathered into the controller's view:
/// the newest result per control point, and the capture time of each
/// worker's newest result. Preallocated; [`RepulsionInputs::push`] allocates nothing.
#[derive(Clone, Debug)]
pub struct RepulsionInputs {
    points: Vec<PointRepulsion>,
    /// capture time of the result held per point \[ns\] (0: none yet)
    point_capture_ns: Vec<u64>,
    /// capture time of each worker's newest result \[ns\] (0: none yet)
    worker_capture_ns: Vec<u64>,
    refused: u64,
}

impl RepulsionInputs {
    /// For `workers` workers sharing `points` control points.
    pub fn new(workers: usize, points: usize) -> RepulsionInputs {
        RepulsionInputs {
            points: (0..points)
                .map(|i| PointRepulsion {
                    point: i as u32,
                    ..PointRepulsion::default()
                })
                .collect(),
            point_capture_ns: vec![0; points],
            worker_capture_ns: vec![0; workers.max(1)],
            refused: 0,
        }
    }

    /// For the workers and control points of `[repulsion]`.
    pub fn from_config(cfg: &RepulsionConfig) -> RepulsionInputs {
        RepulsionInputs::new(cfg.workers as usize, cfg.points.len())
    }

    /// Take one worker's result. A result that names an unknown worker or
    /// point, claims more points than it carries, or carries a non-finite
    /// repulsive vector or a NaN distance (+∞: nothing in the region), is refused whole (its capture time does not count:
    /// perception turns stale rather than trusting it) and counted. A result older than the one held for a point
    /// (workers answering out of order) does not replace it.
    pub fn push(&mut self, msg: &RepulsionResult) -> Result<(), InputError> {
        let checked = self.check(msg);
        if checked.is_err() {
            self.refused += 1;
            return checked;
        }
        let w = &mut self.worker_capture_ns[msg.worker as usize];
        *w = (*w).max(msg.capture_ns);
        for p in &msg.points[..msg.n_points as usize] {
            let k = p.point as usize;
            if msg.capture_ns >= self.point_capture_ns[k] {
                self.points[k] = *p;
                self.point_capture_ns[k] = msg.capture_ns;
            }
        }
        Ok(())
    }

    fn check(&self, msg: &RepulsionResult) -> Result<(), InputError> {
        let workers = self.worker_capture_ns.len();
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
        let points = self.points.len();
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

    /// The controller's view: the newest result per point; the capture time
    /// of the oldest of the workers' newest results, 0 while some worker has
    /// not answered yet.
    pub fn view(&self) -> PerceptionView<'_> {
        PerceptionView {
            capture_ns: self.worker_capture_ns.iter().copied().min().unwrap_or(0),
            points: &self.points,
        }
    }

    /// Results refused since the start.
    pub fn refused(&self) -> u64 {
        self.refused
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
}
