//! `task` (and `slow`, the task under stale perception): the end effector
//! cycles through the configured waypoints on minimum-jerk segments. After
//! a (re)start it first approaches the path on a straight minimum-jerk move,
//! then the path's time law ramps smoothly from rest. The path time runs
//! slower while perception is stale, and as much as an obstacle ahead of the
//! end effector needs: ṡ is scaled by `speed_scale · (1 − f)`, where `f` is
//! the component of the end effector's repulsive vector against the path's
//! direction over `V_max` (`path_pace = "opposing"`; an obstacle beside the
//! path does not slow it, the end effector goes around it by eq. 19), or its
//! whole risk `‖V_Call(P_e)‖/V_max` (`"risk"`). Under the barrier filter
//! the time law runs at the share of the end effector's progress along the
//! path the filter lets through, a waypoint waits for an end effector led
//! round a person ([`crate::modes::arrival`]), and a waypoint the end
//! effector is held from (`pass_after_s`) is passed over: the reference
//! goes straight on to the waypoint after it.

use nalgebra::Vector3;
use phri_config::{ControlConfig, PathPace};

use crate::modes::arrival::Arrival;
use crate::modes::CartesianRef;
use crate::path::{Approach, Path};
use crate::snapshot::{Reader, Snapshot, Writer};

/// Where the task is on its path.
#[derive(Clone, Debug)]
pub struct TaskState {
    path: Path,
    approach: Option<Approach>,
    /// path time \[s\]
    s: f64,
    /// progress of the path's time-law ramp, 0 → 1
    ramp_u: f64,
    /// the waypoint the current segment ends in
    last_target: usize,
    /// the time law ramps over this \[s\]
    path_ramp_s: f64,
    /// largest end-effector speed of the approach [m/s]
    approach_speed: f64,
    /// a waypoint counts as reached within this \[m\]
    waypoint_tolerance: f64,
    /// waypoints reached since the start
    waypoints_reached: u64,
    /// segments ended (the path's, reached or not, and each rejoining approach)
    segments_ended: u64,
    /// what slows the path near an obstacle
    pace: PathPace,
    /// `V_max` of eq. 16 [m/s]
    v_max: f64,
    /// a waypoint the end effector is held from this long is passed over
    /// \[s\] (0: never; `[avoidance] pass_after_s` under the barrier filter)
    pass_after_s: f64,
    /// how long the end effector has been held on this segment: the time
    /// an obstacle has left the time law less than [`HELD_SHARE`] of its
    /// rate \[s\] (from 0 at each segment and start)
    held_s: f64,
    /// the path passes over a held waypoint: the bypass to the waypoint after
    /// it runs whatever holds the end effector, until that waypoint
    passing: bool,
    /// under the barrier filter, the wait at the segment's waypoint for the
    /// end effector
    arrival: Arrival,
}

/// The time law runs at less than this share of its rate: the end
/// effector is held.
pub const HELD_SHARE: f64 = 0.5;

/// A bypass ends this much path time before the waypoint it goes to (the
/// end of that waypoint's segment) \[s\].
const BYPASS_END_S: f64 = 1e-9;

/// The share of the time law an obstacle takes away, `f ∈ [0, 1]`: the
/// component of the end effector's repulsive vector `v_call` [m/s] against
/// the unit direction of motion `dir` over `v_max` (`Opposing`), or its
/// whole norm (`Risk`). A non-finite `v_call` is full risk.
pub fn path_slowdown(pace: PathPace, v_call: &Vector3<f64>, dir: &Vector3<f64>, v_max: f64) -> f64 {
    let against = match pace {
        PathPace::Opposing => (-v_call.dot(dir)).max(0.0),
        PathPace::Risk => v_call.norm(),
    };
    let f = against / v_max.max(1e-9);
    if f.is_nan() || !v_call.iter().all(|x| x.is_finite()) {
        1.0
    } else {
        f.clamp(0.0, 1.0)
    }
}

/// Where the task is (its path and settings are configuration).
impl Snapshot for TaskState {
    fn save(&self, w: &mut Writer<'_>) {
        self.approach.save(w);
        self.s.save(w);
        self.ramp_u.save(w);
        self.last_target.save(w);
        self.waypoints_reached.save(w);
        self.segments_ended.save(w);
        self.held_s.save(w);
        self.passing.save(w);
        self.arrival.save(w);
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        self.approach.load(r);
        self.s.load(r);
        self.ramp_u.load(r);
        // an index into the waypoints
        let target = r.usize();
        if target >= self.path.waypoints.len() {
            r.fail();
        }
        r.store(&mut self.last_target, target);
        self.waypoints_reached.load(r);
        self.segments_ended.load(r);
        self.held_s.load(r);
        self.passing.load(r);
        self.arrival.load(r);
    }
}

impl TaskState {
    /// The number of waypoints (the snapshot's layout check).
    pub(crate) fn waypoints(&self) -> usize {
        self.path.waypoints.len()
    }

    /// The path of `[control]` (`waypoints`, `segment_time_s`), at its start.
    pub fn new(cfg: &ControlConfig) -> TaskState {
        TaskState {
            path: Path {
                waypoints: cfg.waypoints.iter().map(|w| Vector3::from(*w)).collect(),
                segment_time: cfg.segment_time_s,
            },
            approach: None,
            s: 0.0,
            ramp_u: 0.0,
            last_target: 0,
            path_ramp_s: cfg.path_ramp_s,
            approach_speed: cfg.approach_speed,
            waypoint_tolerance: cfg.waypoint_tolerance,
            waypoints_reached: 0,
            segments_ended: 0,
            pace: cfg.path_pace,
            v_max: cfg.avoidance_params.v_max_repulsion,
            pass_after_s: 0.0,
            held_s: 0.0,
            passing: false,
            arrival: Arrival::default(),
        }
    }

    /// Pass over a waypoint the end effector has been held from for
    /// `after_s` \[s\] (0: wait for it, the default).
    pub fn pass_held_waypoints(&mut self, after_s: f64) {
        self.pass_after_s = after_s.max(0.0);
    }

    /// (Re)join the path where it was left, from the end effector at `from`
    /// \[m\], base frame: approach, then ramp the time law from rest.
    pub fn start(&mut self, from: Vector3<f64>) {
        let (to, _) = self.path.sample(self.s);
        self.approach = Some(Approach::new(from, to, self.approach_speed));
        self.ramp_u = 0.0;
        self.last_target = self.path.target_index(self.s);
        self.held_s = 0.0;
        self.passing = false;
        self.arrival.reset();
    }

    /// Path time \[s\].
    pub fn path_time(&self) -> f64 {
        self.s
    }

    /// Set the path time \[s\] (the retreat walks it back).
    pub fn set_path_time(&mut self, s: f64) {
        self.s = s;
    }

    /// Waypoints reached since the start.
    pub fn waypoints_reached(&self) -> u64 {
        self.waypoints_reached
    }

    /// Segments ended since the start: of the path (its waypoint reached or
    /// not) and rejoining approaches.
    pub fn segments_ended(&self) -> u64 {
        self.segments_ended
    }

    /// One period of `dt` \[s\]: the end effector's reference. `speed_scale`
    /// (1, or slower while perception is stale) scales the joint velocity
    /// bounds and the time law; `pace` (0-1: the share of the end
    /// effector's progress along the path the barrier filter let through, 1
    /// otherwise) and the end effector's repulsive vector `v_call` [m/s] (0
    /// without fresh perception) slow the time law only
    /// ([`path_slowdown`]), never the bounds: an arm held back keeps its
    /// room to back away; `ee` is the measured end effector \[m\]
    /// (to count waypoints reached). A segment held up for `pass_after_s`
    /// is passed over: the reference goes straight on to the waypoint after
    /// it, at `speed_scale`, its own waypoint not counted.
    pub fn step(
        &mut self,
        dt: f64,
        (speed_scale, pace): (f64, f64),
        v_call: &Vector3<f64>,
        ee: &Vector3<f64>,
    ) -> CartesianRef {
        let dir = match &self.approach {
            Some(a) => a.direction(),
            None => self.path.direction(self.s),
        };
        let slowdown = path_slowdown(self.pace, v_call, &dir, self.v_max);
        // the share of the time law what is near leaves
        let share = pace * (1.0 - slowdown);
        let (x_d, xd_d) = match self.approach.as_mut() {
            Some(a) => {
                // a bypass runs whatever holds the end effector, as a pass does
                let out = match self.passing {
                    true => a.step(dt * speed_scale),
                    false => a.step(dt * speed_scale * share),
                };
                if a.done() {
                    self.approach = None;
                    self.segments_ended += 1;
                }
                out
            }
            None => {
                if self.pass_after_s > 0.0 && !self.passing {
                    if share < HELD_SHARE {
                        self.held_s += dt;
                    }
                    if self.held_s >= self.pass_after_s {
                        // go round, straight to the waypoint after the held one
                        return self.bypass(speed_scale);
                    }
                }
                let time_scale = match self.passing {
                    true => speed_scale,
                    false => speed_scale * share,
                };
                // time scaling: ṡ = smoothstep(u) ramps 0 → 1, so that a path resumed
                // mid-segment starts without a jump in velocity or acceleration
                self.ramp_u = (self.ramp_u + dt / self.path_ramp_s.max(1e-3)).min(1.0);
                let u = self.ramp_u;
                let rate = u * u * (3.0 - 2.0 * u) * time_scale;
                let s = self.s + dt * rate;
                // waypoint reached: the segment ended with the end effector there
                let target = self.path.target_index(s);
                if target != self.last_target {
                    let distance = (ee - self.path.waypoints[self.last_target]).norm();
                    let there = distance <= self.waypoint_tolerance;
                    if !there
                        && self.pass_after_s > 0.0
                        && self.arrival.wait(distance, dt, self.pass_after_s)
                    {
                        // the segment ends at rest: its waypoint waits for the end effector
                        return self.reference(
                            self.path.sample(self.s).0,
                            Vector3::zeros(),
                            speed_scale,
                        );
                    }
                    if there {
                        self.waypoints_reached += 1;
                    }
                    self.segments_ended += 1;
                    self.last_target = target;
                    self.held_s = 0.0;
                    self.passing = false;
                    self.arrival.reset();
                }
                self.s = s;
                let (x, dx) = self.path.sample(self.s);
                (x, dx * rate)
            }
        };
        self.reference(x_d, xd_d, speed_scale)
    }

    /// Pass over the held segment's waypoint: the reference goes from where
    /// it is straight to the waypoint after it, on a minimum-jerk move of one
    /// segment's time from rest that runs whatever holds the end effector,
    /// and the path goes on from there (the end of the segment after, so
    /// that the waypoint counts, or waits, as any other). This period: the
    /// reference at rest where it is.
    fn bypass(&mut self, speed_scale: f64) -> CartesianRef {
        let n = self.path.waypoints.len();
        let t = self.path.segment_time;
        let (from, _) = self.path.sample(self.s);
        let next = (self.last_target + 1) % n;
        // the end of the segment after this one, just before its waypoint
        self.s = (self.s / t).floor() * t + 2.0 * t - BYPASS_END_S;
        self.approach = Some(Approach::lasting(from, self.path.waypoints[next], t));
        self.last_target = next;
        self.segments_ended += 1;
        self.held_s = 0.0;
        self.passing = true;
        self.arrival.reset();
        self.reference(from, Vector3::zeros(), speed_scale)
    }

    /// The end effector's reference at `x_d` \[m\], `xd_d` [m/s].
    fn reference(&self, x_d: Vector3<f64>, xd_d: Vector3<f64>, speed_scale: f64) -> CartesianRef {
        CartesianRef {
            x_d,
            xd_d,
            speed_scale,
            path_time: Some(self.s),
            collab_hand: None,
            collab_touching: false,
            collab_point: 0,
            collab_speed_limit: f64::INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn task() -> TaskState {
        TaskState::new(&phri_config::Config::defaults().control)
    }

    #[test]
    fn approaches_then_follows_the_path_and_counts_waypoints() {
        let mut t = task();
        let w: Vec<Vector3<f64>> = t.path.waypoints.clone();
        let from = w[0] + Vector3::new(0.0, 0.0, 0.1);
        t.start(from);
        let dt = 0.001;
        // the approach ends at the path's start, at rest, without moving the path time
        let mut last = t.step(dt, (1.0, 1.0), &Vector3::zeros(), &from);
        while t.approach.is_some() {
            last = t.step(dt, (1.0, 1.0), &Vector3::zeros(), &last.x_d);
        }
        assert!((last.x_d - w[0]).norm() < 1e-12 && last.xd_d.norm() < 1e-9);
        assert_eq!(last.path_time, Some(0.0));
        // the end effector following perfectly reaches every waypoint of two cycles
        let cycle = t.path.period();
        let mut ee = last.x_d;
        for _ in 0..((2.0 * cycle + 0.6) / dt) as usize {
            ee = t.step(dt, (1.0, 1.0), &Vector3::zeros(), &ee).x_d;
        }
        assert_eq!(t.waypoints_reached(), 6);
    }

    /// The path time after 100 ms at full pace from the path's start, with
    /// `v_call` at the end effector, under `pace`.
    fn path_time_after(pace: PathPace, speed_scale: f64, v_call: Vector3<f64>) -> f64 {
        let mut t = task();
        t.pace = pace;
        t.approach = None;
        t.ramp_u = 1.0;
        for _ in 0..100 {
            t.step(0.001, (speed_scale, 1.0), &v_call, &Vector3::zeros());
        }
        t.path_time()
    }

    #[test]
    fn only_an_obstacle_ahead_slows_the_time_law() {
        let t = task();
        let v_max = t.v_max;
        // the first segment, P1 → P2
        let dir = t.path.direction(0.0);
        let w = &t.path.waypoints;
        assert!((dir - (w[1] - w[0]).normalize()).norm() < 1e-12);
        let side = dir.cross(&Vector3::z()).normalize();
        let opposing = PathPace::Opposing;
        // nothing near, or a person beside the path: full pace
        assert!((path_time_after(opposing, 1.0, Vector3::zeros()) - 0.1).abs() < 1e-12);
        assert!((path_time_after(opposing, 1.0, side * v_max) - 0.1).abs() < 1e-12);
        // behind the end effector (pushing it along): full pace
        assert!((path_time_after(opposing, 1.0, dir * v_max) - 0.1).abs() < 1e-12);
        // ahead, at half risk: half pace; at full risk: halted
        assert!((path_time_after(opposing, 1.0, -dir * 0.5 * v_max) - 0.05).abs() < 1e-12);
        assert_eq!(path_time_after(opposing, 1.0, -dir * v_max), 0.0);
        // ahead and to the side: only the component against the path counts
        let v = (-dir + side) * (0.5 * v_max);
        assert!((path_time_after(opposing, 1.0, v) - 0.05).abs() < 1e-12);
        // stale perception: slow_scale on top
        assert!((path_time_after(opposing, 0.3, -dir * 0.5 * v_max) - 0.015).abs() < 1e-12);
        // a malformed repulsion halts the path
        let nan = Vector3::new(f64::NAN, 0.0, 0.0);
        assert_eq!(path_time_after(opposing, 1.0, nan), 0.0);
    }

    #[test]
    fn the_filter_s_pace_slows_the_time_law_never_the_bounds() {
        let mut t = task();
        t.approach = None;
        t.ramp_u = 1.0;
        let mut c = t.step(0.001, (0.3, 1.0), &Vector3::zeros(), &Vector3::zeros());
        for _ in 1..100 {
            c = t.step(0.001, (0.3, 0.5), &Vector3::zeros(), &Vector3::zeros());
        }
        // 1 ms at 0.3, then 99 ms at 0.3 × 0.5
        assert!((t.path_time() - (0.0003 + 0.099 * 0.15)).abs() < 1e-12);
        // the joints' bounds: stale perception's scale alone
        assert_eq!(c.speed_scale, 0.3);
    }

    #[test]
    fn a_waypoint_held_from_the_end_effector_is_passed_over_not_counted() {
        // (time the path went on to P3's segment, time it began P3 → P1,
        // waypoints reached, largest step of the reference [m])
        let run = |pass_after_s: f64| {
            let mut t = task();
            t.pass_held_waypoints(pass_after_s);
            t.approach = None;
            t.ramp_u = 1.0;
            let w = t.path.waypoints.clone();
            let dt = 0.001;
            // the end effector held 10 cm short of P2, the filter letting 10 % through
            let held = w[1] + (w[0] - w[1]).normalize() * 0.1;
            let (mut passed_at, mut at_p3, mut step) = (None, None, 0.0_f64);
            let mut x_d = w[0];
            for k in 0..5500 {
                let toward_p2 = t.approach.is_none() && t.path.target_index(t.s) == 1;
                let (ee, pace) = match toward_p2 {
                    true => (held, 0.1),
                    false => (x_d, 1.0),
                };
                let r = t.step(dt, (1.0, pace), &Vector3::zeros(), &ee);
                step = step.max((r.x_d - x_d).norm());
                x_d = r.x_d;
                let target = t.path.target_index(t.s);
                if passed_at.is_none() && target == 2 {
                    passed_at = Some(k as f64 * dt);
                }
                if at_p3.is_none() && target == 0 {
                    at_p3 = Some(k as f64 * dt);
                }
            }
            (passed_at, at_p3, t.waypoints_reached(), step)
        };
        // waiting: 5.5 s at a tenth of the rate, P2 still ahead
        let (passed_at, _, reached, _) = run(0.0);
        assert_eq!((passed_at, reached), (None, 0));
        // passing after 1 s held: straight on to P3 in one segment's time (1.33
        // s), P2 not counted, P3 and P1 reached
        let (passed_at, at_p3, reached, step) = run(1.0);
        let passed_at = passed_at.expect("the path went on to P3");
        assert!((0.99..1.01).contains(&passed_at), "passed at {passed_at} s");
        let at_p3 = at_p3.expect("P3 reached");
        assert!((2.32..2.35).contains(&at_p3), "at P3 at {at_p3} s");
        assert_eq!(reached, 2, "P3 and P1, not the held P2");
        // no jump: 1 mm in a period at most (the path peaks at 0.55 m/s)
        assert!(step < 1e-3, "the reference stepped {step} m");
        // the pass ends with the bypass: the next segment is paced by the filter again
        let mut t = task();
        t.pass_held_waypoints(1.0);
        t.approach = None;
        t.ramp_u = 1.0;
        for _ in 0..1500 {
            t.step(0.001, (1.0, 0.1), &Vector3::zeros(), &Vector3::zeros());
        }
        assert!(
            t.passing && t.approach.is_some(),
            "held 1 s at a tenth of the rate"
        );
        let p3 = t.path.waypoints[2];
        while t.path.target_index(t.s) == 2 {
            t.step(0.001, (1.0, 0.1), &Vector3::zeros(), &p3);
        }
        assert!(!t.passing && t.held_s == 0.0);
        assert_eq!(t.waypoints_reached(), 1, "P3");
    }

    /// Waypoints reached in 4 s of path by an end effector that trails its
    /// reference by `lag` periods (led round something), the held
    /// waypoints passed over after `pass_after_s`.
    fn reached_trailing_by(lag: usize, pass_after_s: f64) -> u64 {
        let mut t = task();
        t.pass_held_waypoints(pass_after_s);
        t.approach = None;
        t.ramp_u = 1.0;
        let start = t.path.waypoints[0];
        let mut trail = std::collections::VecDeque::from(vec![start; lag]);
        for _ in 0..4000 {
            let ee = trail.pop_front().unwrap_or(start);
            trail.push_back(t.step(0.001, (1.0, 1.0), &Vector3::zeros(), &ee).x_d);
        }
        t.waypoints_reached()
    }

    #[test]
    fn under_the_filter_a_waypoint_waits_for_the_end_effector_closing_in() {
        // 0.4 s behind, the end effector is 6 cm short of the first two
        // waypoints when their segments end
        assert!(
            reached_trailing_by(400, 0.0) <= 1,
            "the paper's law: not counted"
        );
        assert_eq!(
            reached_trailing_by(400, 1.0),
            3,
            "the filter's: each, a little later"
        );
        // right behind it: every waypoint in time, either way
        assert_eq!(reached_trailing_by(1, 0.0), 3);
        assert_eq!(reached_trailing_by(1, 1.0), 3);
    }

    #[test]
    fn risk_pace_slows_for_any_repulsion() {
        let t = task();
        let side = t.path.direction(0.0).cross(&Vector3::z()).normalize();
        let risk = PathPace::Risk;
        assert!((path_time_after(risk, 1.0, Vector3::zeros()) - 0.1).abs() < 1e-12);
        assert!((path_time_after(risk, 0.3, side * 0.5 * t.v_max) - 0.015).abs() < 1e-12);
        assert_eq!(
            path_time_after(risk, 1.0, side * t.v_max),
            0.0,
            "full risk at the end effector halts the path"
        );
    }
}
