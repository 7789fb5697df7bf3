//! A hot standby adopts the primary's behaviour state and then commands
//! what the primary commands, bit for bit (bumpless transfer); snapshots of
//! another configuration, truncated or malformed ones are refused and
//! change nothing.
//!
//! The cell: the LWR-IV of the default configuration (collaboration, speed
//! and separation monitoring, avoidance on) on exact dynamics, driven by the
//! primary's torque, with the residual observer in the loop, repulsion
//! results every 33 ms (a person at 0.5-0.9 m, coming and going), a push on
//! the forearm, or a person's hand and a request to collaborate.

use std::path::Path;

use nalgebra::{Matrix6xX, Vector3};
use phri_config::{Config, Loaded, PerJoint, ResidualConfig, DEFAULT_DEPLOY_DIR};
use phri_control::snapshot::HEADER_BYTES;
use phri_control::{
    write_collab_state, write_messages, write_ssm_status, CollabInput, ControlConfig, ControlInput,
    ControlMode, Controller, ControllerParams, Reaction, RepulsionInputs, ResidualView,
    SnapshotError, Stamps, BEHAVIOUR_BYTES,
};
use phri_estimation::ResidualObserver;
use phri_ipc::{
    CollabPart, CollabPhase, CollabState, ControlStatus, HriRequest, JointState, PointRepulsion,
    RepulsionResult, RequestKind, RequestSource, Skeleton, SkeletonJoint, SsmStatus, TorqueCommand,
    Zeroed,
};
use phri_model::{Data, Model};

use ControlMode as M;

const MS: u64 = 1_000_000;

/// What happens in the cell.
#[derive(Clone, Copy, Debug, Default)]
struct Script {
    /// a 60 N push on the forearm over [from, to) \[s\]
    push: Option<(f64, f64)>,
    /// from then \[s\] a person holds the right hand out 0.25 m beside the
    /// end effector and asks (every 100 ms until the primary collaborates)
    /// to follow it, moving it on a 2 cm circle every 2 s; the hand presses
    /// on the end effector with 10 N while the primary's gap to it is below 4 cm
    collab_from: Option<f64>,
    /// a person's right hand at the end effector until then \[s\], then 1 m away
    hand_at_robot_until: Option<f64>,
    /// the collaborating hand shoves the end effector with 120 N over [from, to) \[s\]
    shove: Option<(f64, f64)>,
    /// no repulsion results over [from, to) \[s\] (perception stale)
    perception_gap: Option<(f64, f64)>,
}

/// The arm, its sensors and the person.
struct Cell {
    cfg: Config,
    model: Model,
    data: Data,
    jac: Matrix6xX<f64>,
    observer: ResidualObserver,
    repulsion: RepulsionInputs,
    script: Script,
    k: u64,
    q: Vec<f64>,
    qd: Vec<f64>,
    r: Vec<f64>,
    /// valid, contact, collision
    flags: (bool, bool, bool),
    r_stamp: u64,
    skeleton: Skeleton,
    skeleton_seen: bool,
    hand: Option<[f64; 3]>,
    request: HriRequest,
    asking: bool,
}

impl Cell {
    fn new(loaded: &Loaded, script: Script) -> Cell {
        let cfg = loaded.config.clone();
        let model = loaded.model().unwrap();
        let rcfg = ResidualConfig {
            viscous_friction: PerJoint::All(0.0),
            coulomb_friction: PerJoint::All(0.0),
            ..cfg.dynamics.clone()
        };
        let mut request = HriRequest::zeroed();
        request.source = RequestSource::Cli as u32;
        request.kind = RequestKind::Follow as u32;
        request.part = CollabPart::RightHand as u32;
        request.person = u32::MAX;
        let mut skeleton = Skeleton::zeroed();
        skeleton.n_people = 1;
        skeleton.people[0].id = 1;
        skeleton.people[0].tracked = 1;
        skeleton.people[0].confidence = [0.9; 15];
        let n = model.nv();
        Cell {
            observer: ResidualObserver::new(model.clone(), &rcfg).unwrap(),
            repulsion: RepulsionInputs::from_config(&cfg.repulsion),
            data: Data::new(&model),
            jac: Data::jacobian_buffer(&model),
            q: cfg.sim.q0.clone(),
            qd: vec![0.0; n],
            r: vec![0.0; n],
            flags: (false, false, false),
            r_stamp: 0,
            skeleton,
            skeleton_seen: false,
            hand: None,
            request,
            asking: false,
            script,
            k: 0,
            model,
            cfg,
        }
    }

    /// The arm moves for one period under `tau` \[Nm\] (10 sub-steps), the
    /// primary's; the sensors see state `k + 1`.
    fn advance(&mut self, tau: &[f64], primary: &Controller) {
        self.k += 1;
        let (k, n) = (self.k, self.q.len());
        let t_s = k as f64 * 1e-3;
        let ee = primary.ee();
        let collab = primary.collaboration();
        let collaborating = collab.is_some_and(|c| c.phase() != CollabPhase::Idle);
        let within = |w: Option<(f64, f64)>| w.is_some_and(|(from, to)| (from..to).contains(&t_s));
        // a 60 N push on the forearm, the hand's shove or its 10 N on the end effector
        let push = if within(self.script.push) {
            Some(("lwr_link_4", 0.0, 60.0))
        } else if within(self.script.shove) {
            Some(("lwr_link_7", 0.07, -120.0))
        } else if collaborating && collab.is_some_and(|c| c.near_gap_m() < 0.04) {
            Some(("lwr_link_7", 0.07, -10.0))
        } else {
            None
        };
        for _ in 0..10 {
            let mut total = tau.to_vec();
            if let Some((link, z, f)) = push {
                let frame = self.model.frame_id(link).unwrap();
                phri_model::forward_kinematics(&self.model, &mut self.data, &self.q).unwrap();
                phri_model::point_jacobian(
                    &self.model,
                    &self.data,
                    frame,
                    &Vector3::new(0.0, 0.0, z),
                    &mut self.jac,
                )
                .unwrap();
                for (i, t) in total.iter_mut().enumerate() {
                    *t += f * self.jac[(1, i)];
                }
            }
            let qdd = phri_model::forward_dynamics(
                &self.model,
                &mut self.data,
                &self.q,
                &self.qd,
                &total,
            )
            .unwrap()
            .clone();
            for i in 0..n {
                self.qd[i] += 1e-4 * qdd[i];
                self.q[i] += 1e-4 * self.qd[i];
            }
        }
        let stamp = k * MS;
        let out = self.observer.step(t_s, &self.q, tau, None).unwrap();
        self.r.copy_from_slice(out.r);
        self.flags = (out.valid, out.detection.contact, out.detection.collision);
        self.r_stamp = stamp;
        // every worker answers a frame every 33 ms, 20 ms after its capture
        if k % 33 == 0 && !within(self.script.perception_gap) {
            for w in 0..self.cfg.repulsion.workers {
                let res = worker_result(&self.cfg, w, stamp - 20 * MS, t_s);
                self.repulsion.push(&res).unwrap();
            }
        }
        // the body tracker's skeleton: one every 33 ms, 30 ms after its capture
        let right = SkeletonJoint::RightHand as usize;
        let frame = k % 33 == 0;
        self.asking = false;
        if self.script.collab_from.is_some_and(|from| t_s >= from) {
            let h = *self.hand.get_or_insert([ee.x, ee.y + 0.25, ee.z]);
            let phase = std::f64::consts::PI * t_s;
            if frame {
                self.skeleton.people[0].joints[right] =
                    [h[0] + 0.02 * phase.sin(), h[1], h[2] + 0.02 * phase.cos()];
                self.skeleton.capture_ns = stamp - 30 * MS;
            }
            self.skeleton_seen = true;
            self.asking = !collaborating && k % 100 == 0;
        }
        if let Some(until) = self.script.hand_at_robot_until.filter(|_| frame) {
            let away = if t_s < until { 0.0 } else { 1.0 };
            self.skeleton.people[0].joints[right] = [ee.x + away, ee.y, ee.z];
            self.skeleton.capture_ns = stamp - 30 * MS;
            self.skeleton_seen = true;
        }
    }

    /// The controllers' input of state `k`.
    fn input(&self) -> ControlInput<'_> {
        ControlInput {
            state_stamp_ns: self.k * MS,
            q: &self.q,
            residual: Some(ResidualView {
                state_stamp_ns: self.r_stamp,
                r: &self.r,
                valid: self.flags.0,
                contact: self.flags.1,
                collision: self.flags.2,
            }),
            perception: Some(self.repulsion.view()),
            collab: CollabInput {
                requests: match self.asking {
                    true => std::slice::from_ref(&self.request),
                    false => &[],
                },
                skeleton: self.skeleton_seen.then_some(&self.skeleton),
                hand: None,
            },
        }
    }
}

/// Worker `w`'s result for its points: a person 0.5-0.9 m away, coming and
/// going (the monitor measures their speed), a small repulsion turning.
fn worker_result(cfg: &Config, w: u32, capture_ns: u64, t_s: f64) -> RepulsionResult {
    let mut r = RepulsionResult::zeroed();
    r.worker = w;
    r.workers = cfg.repulsion.workers;
    r.capture_ns = capture_ns;
    let points = cfg.repulsion.points_of(w);
    r.n_points = points.len() as u32;
    for (slot, &p) in r.points.iter_mut().zip(&points) {
        let a = 0.05 * (t_s + p as f64).sin().max(0.0);
        let d = 0.7 + 0.2 * (1.3 * t_s + p as f64).sin();
        *slot = PointRepulsion {
            point: p as u32,
            active: u32::from(a > 0.0),
            v_call: [a, 0.5 * a, 0.0],
            min_distance: d,
            position: [0.5, 0.0, 0.4],
            obstacle: [0.5 + d, 0.0, 0.4],
        };
    }
    r
}

/// One period of both controllers.
#[derive(Clone, Debug)]
struct Period {
    k: u64,
    tau_a: Vec<f64>,
    mode_a: ControlMode,
    /// the primary's task segments ended so far
    segments: u64,
    /// the standby's torque and mode (`None`: it did not step); in a period
    /// it adopts in, its own (before adopting)
    b: Option<(Vec<f64>, ControlMode)>,
    /// what both report (from the period asked for, when the standby stepped)
    reports: Option<(String, String)>,
}

/// What a controller reports after its step of state `k` at `q`: its
/// command, its status, collaboration and speed and separation messages,
/// and what its accessors say of the task and the reference (not of the
/// path history, whose entries each controller records).
fn report(ctl: &Controller, k: u64, q: &[f64]) -> String {
    let mut state = JointState::zeroed();
    state.seq = k;
    state.stamp_ns = k * MS;
    state.dof = q.len() as u32;
    state.q[..q.len()].copy_from_slice(q);
    let (mut cmd, mut status) = (TorqueCommand::zeroed(), ControlStatus::zeroed());
    let (mut collab, mut ssm) = (CollabState::zeroed(), SsmStatus::zeroed());
    let stamps = Stamps {
        woke_ns: k * MS,
        done_ns: k * MS + 1,
    };
    write_messages(ctl, &state, k, stamps, &mut cmd, &mut status);
    write_collab_state(ctl, &state, k, k * MS + 1, &mut collab);
    write_ssm_status(ctl, &state, k, k * MS + 1, &mut ssm);
    let more = (
        ctl.task_reference(),
        ctl.task_segments_ended(),
        ctl.q_ref(),
        ctl.velocity(),
    );
    format!("{cmd:?}\n{status:?}\n{collab:?}\n{ssm:?}\n{more:?}")
}

/// A hot-standby situation: the cell of `loaded` under `script` over
/// periods `1..=end`, driven by the primary's (A's) torque; the standby (B)
/// steps the same states from period `b_from` on (except `b_misses`).
struct Situation {
    loaded: Loaded,
    script: Script,
    /// the primary restarted (`Controller::restarted`)
    a_restarted: bool,
    /// the standby restarted
    b_restarted: bool,
    b_from: u64,
    /// a state the standby misses (it still adopts after it)
    b_misses: Option<u64>,
    end: u64,
}

fn situation(loaded: Loaded, script: Script, b_from: u64, end: u64) -> Situation {
    Situation {
        loaded,
        script,
        a_restarted: false,
        b_restarted: false,
        b_from,
        b_misses: None,
        end,
    }
}

impl Situation {
    /// The periods, B adopting A's snapshot after its step of period `k`
    /// (from `b_from` on) when `adopt(k)`; both reports from `report_from` on.
    fn run(&self, adopt: impl Fn(u64) -> bool, report_from: u64) -> Vec<Period> {
        let mut cell = Cell::new(&self.loaded, self.script);
        let (mut a, mut b) = (controller(&self.loaded), controller(&self.loaded));
        if self.a_restarted {
            a.restarted();
        }
        if self.b_restarted {
            b.restarted();
        }
        let mut tau = phri_model::gravity(&cell.model, &mut cell.data, &cell.q)
            .unwrap()
            .as_slice()
            .to_vec();
        let mut buf = [0u8; BEHAVIOUR_BYTES];
        let mut out = Vec::new();
        while cell.k < self.end {
            cell.advance(&tau, &a);
            let k = cell.k;
            let input = cell.input();
            let (tau_a, mode_a) = {
                let o = a.step(&input);
                (o.tau.to_vec(), o.mode)
            };
            let b_out = (k >= self.b_from && Some(k) != self.b_misses).then(|| {
                let o = b.step(&input);
                (o.tau.to_vec(), o.mode)
            });
            let reports = (k >= report_from && b_out.is_some())
                .then(|| (report(&a, k, &cell.q), report(&b, k, &cell.q)));
            if k >= self.b_from && adopt(k) {
                let len = a.save_behaviour(&mut buf).unwrap();
                b.adopt_behaviour(&buf[..len]).unwrap();
            }
            tau.copy_from_slice(&tau_a);
            out.push(Period {
                k,
                tau_a,
                mode_a,
                segments: a.task_segments_ended(),
                b: b_out,
                reports,
            });
        }
        out
    }

    /// Adopting in the periods `adopt` says, the standby commands what the
    /// primary does from period `from` on, in its mode, and reports what it
    /// does (command, status, collaboration, speed and separation); without
    /// adopting it would not have. Returns the periods (adopting).
    fn assert_bumpless(&self, adopt: impl Fn(u64) -> bool, from: u64, what: &str) -> Vec<Period> {
        let alone = self.run(|_| false, u64::MAX);
        let diff = largest_difference(&alone, from..=self.end);
        assert!(diff > 1e-6, "{what}: as much without adopting: {diff} Nm");
        let periods = self.run(adopt, from);
        let mut compared = 0;
        for p in periods.iter().filter(|p| p.k >= from) {
            let (tau_b, mode_b) = p.b.as_ref().expect("the standby stepped");
            assert_eq!(p.mode_a, *mode_b, "{what}: period {}: modes", p.k);
            for (i, (x, y)) in p.tau_a.iter().zip(tau_b).enumerate() {
                assert!(
                    x.to_bits() == y.to_bits() || x == y,
                    "{what}: period {}, joint {i}: {x} Nm vs {y} Nm",
                    p.k
                );
            }
            let (ra, rb) = p.reports.as_ref().expect("reported");
            if let Some((la, lb)) = ra.lines().zip(rb.lines()).find(|(a, b)| a != b) {
                panic!("{what}: period {}: the reports differ:\n{la}\n{lb}", p.k);
            }
            compared += 1;
        }
        assert!(compared >= 200, "{what}: {compared} periods compared");
        periods
    }
}

/// The largest difference between A's and B's torques over periods `range` \[Nm\].
fn largest_difference(periods: &[Period], range: std::ops::RangeInclusive<u64>) -> f64 {
    periods
        .iter()
        .filter(|p| range.contains(&p.k))
        .filter_map(|p| p.b.as_ref().map(|(tau_b, _)| (&p.tau_a, tau_b)))
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max)
}

fn lwr(reaction: Reaction) -> Loaded {
    let mut loaded = Loaded::defaults();
    loaded.config.control.reaction = reaction;
    loaded
}

fn controller(loaded: &Loaded) -> Controller {
    Controller::from_config(loaded.model().unwrap(), &loaded.config).unwrap()
}

/// The primary's modes over periods `range`, each once, in order.
fn modes(periods: &[Period], range: std::ops::RangeInclusive<u64>) -> Vec<ControlMode> {
    let mut out: Vec<ControlMode> = Vec::new();
    for p in periods.iter().filter(|p| range.contains(&p.k)) {
        if out.last() != Some(&p.mode_a) {
            out.push(p.mode_a);
        }
    }
    out
}

// The timeline of the LWR-IV's default task in this cell: the approach to
// the path ends at 4.77 s, path segments end at 6.35 s and 7.68 s and every
// 1.33 s of path time after. A push on the forearm at 9.0-9.15 s is
// detected at 9.006 s; the reaction lasts its least 0.3 s (the retreat to
// 9.8 s), the recovery 1 s more.

#[test]
fn a_standby_that_adopts_mid_task_commands_what_the_primary_does() {
    // mid-path, B started 100 or 2 periods before it adopts at 7 s (its
    // velocity estimate, repulsion filters, monitor unsettled; in the
    // latter it misses the state the primary saved after), or started at
    // 7.12 s with perception stale since 7.11 s (the task slows: the safety
    // monitor last saw the person far enough) and adopting at 7.15 s; the
    // posture configured or taken from the arm at the task's start
    let script = Script {
        perception_gap: Some((7.05, 7.2)),
        ..Script::default()
    };
    for posture in [true, false] {
        for (b_from, at) in [(6901, 7000), (6998, 7000), (7120, 7150)] {
            let mut loaded = lwr(Reaction::Reflex);
            if !posture {
                loaded.config.control.posture.clear();
            }
            let mut s = situation(loaded, script, b_from, 7400);
            if b_from == 6998 {
                s.b_misses = Some(7000);
            }
            let what = format!("mid-task (posture configured {posture}, B from {b_from})");
            let periods = s.assert_bumpless(|k| k == at, at + 1, &what);
            let path = &periods[at as usize - 1];
            assert!(matches!(path.mode_a, M::Task | M::Slow), "{what}");
            assert_eq!(path.segments, 2, "{what}");
            assert!(modes(&periods, at..=7400).contains(&M::Slow), "{what}");
        }
    }
}

#[test]
fn a_late_standby_without_adoption_diverges() {
    let s = situation(lwr(Reaction::Reflex), Script::default(), 6901, 7400);
    let periods = s.run(|_| false, u64::MAX);
    let diff = largest_difference(&periods, 7001..=7400);
    assert!(
        diff > 1e-2,
        "the standby's torque differs measurably: {diff} Nm"
    );
}

/// A push on the forearm at 9.0-9.15 s.
const PUSH: Script = Script {
    push: Some((9.0, 9.15)),
    collab_from: None,
    hand_at_robot_until: None,
    shove: None,
    perception_gap: None,
};

#[test]
fn a_standby_that_adopts_mid_reaction_reacts_as_the_primary_does() {
    // B started 50 ms before it adopts, 100 ms into the reaction (the
    // reaction's start time decides its end); compared through the
    // recovery and the task's resumption (its approach back to the path
    // where it was left)
    for reaction in [
        Reaction::Reflex,
        Reaction::Admittance,
        Reaction::Stop,
        Reaction::Float,
    ] {
        let s = situation(lwr(reaction), PUSH, 9051, 10600);
        let what = format!("mid-{reaction}");
        let periods = s.assert_bumpless(|k| k == 9100, 9101, &what);
        assert_eq!(
            modes(&periods, 9100..=10600),
            [M::Reaction, M::Recover, M::Task],
            "{what}"
        );
    }
}

#[test]
fn a_standby_that_adopts_while_recovering_resumes_with_the_primary() {
    // 500 ms into the recovery: its quiet residual's timer travels
    let s = situation(lwr(Reaction::Reflex), PUSH, 9751, 10600);
    let periods = s.assert_bumpless(|k| k == 9800, 9801, "recovering");
    assert_eq!(modes(&periods, 9800..=10600), [M::Recover, M::Task]);
}

#[test]
fn a_standby_adopting_every_period_retreats_along_the_same_path() {
    // the retreat walks back 0.6 s through the path history, which does not
    // travel: a standby started 1 s before and adopting every period has
    // recorded the primary's; the primary dies 150 ms into the retreat
    let s = situation(lwr(Reaction::Retreat), PUSH, 8001, 10000);
    let periods = s.assert_bumpless(|k| k <= 9150, 8002, "retreat");
    let retreating = periods
        .iter()
        .filter(|p| p.k > 9150 && p.mode_a == ControlMode::Reaction)
        .count();
    assert!(retreating > 500, "the standby retreated on its own");
}

/// The person holds the hand out from 0.8 s and asks to be followed: the
/// approach from 0.9 s, contact from 1.66 s; the hand shoves at 2.6-2.9 s:
/// back off from 2.61 s, recover from 2.76 s (the shove's residual a
/// collision but detection re-arming), the task from 3.93 s, a new
/// approach from 4.0 s.
const COLLABORATION: Script = Script {
    push: None,
    collab_from: Some(0.8),
    hand_at_robot_until: None,
    shove: Some((2.6, 2.9)),
    perception_gap: None,
};

#[test]
fn a_standby_that_adopts_mid_collaboration_collaborates_as_the_primary_does() {
    // (B from, adoption, the primary's mode then, what): mid-approach (B
    // restarted: its collaboration over, holding for hands), in contact,
    // backing off, recovering while the shove goes on (detection re-arming)
    for (b_from, at, mode, what) in [
        (101, 1300, M::Approach, "mid-approach"),
        (1951, 2000, M::Contact, "in contact"),
        (2651, 2680, M::BackOff, "backing off"),
        (2751, 2800, M::Recover, "re-arming"),
    ] {
        let mut s = situation(lwr(Reaction::Reflex), COLLABORATION, b_from, 4300);
        s.b_restarted = b_from == 101;
        let periods = s.assert_bumpless(|k| k == at, at + 1, what);
        assert_eq!(periods[at as usize - 1].mode_a, mode, "{what}");
        let after = modes(&periods, at..=4300);
        assert!(
            after.ends_with(&[M::Recover, M::Task, M::Approach]),
            "{what}: {after:?}"
        );
    }
}

#[test]
fn a_standby_adopts_a_restarted_primarys_hold() {
    // the primary restarted with a hand at the robot: it holds until the
    // hand stayed away; a standby that never restarted adopts the hold
    let script = Script {
        hand_at_robot_until: Some(0.6),
        ..Script::default()
    };
    let mut s = situation(lwr(Reaction::Reflex), script, 101, 1400);
    s.a_restarted = true;
    let periods = s.assert_bumpless(|k| k == 400, 401, "restart hold");
    assert_eq!(modes(&periods, 400..=1400), [M::ProtectiveStop, M::Recover]);
    let released = periods
        .iter()
        .position(|p| p.k > 400 && p.mode_a == M::Recover);
    assert!(
        released.is_some_and(|i| i > 600),
        "held while the hand was there: {released:?}"
    );
}

#[test]
fn the_path_history_keeps_the_newest_entries_both_hold() {
    // A from the start (its history full), B from 2 s, C from 2.99 s
    let loaded = lwr(Reaction::Retreat);
    let mut cell = Cell::new(&loaded, Script::default());
    let mut c: Vec<Controller> = (0..3).map(|_| controller(&loaded)).collect();
    let mut tau = phri_model::gravity(&cell.model, &mut cell.data, &cell.q)
        .unwrap()
        .as_slice()
        .to_vec();
    for k in 1..=3000u64 {
        cell.advance(&tau, &c[0]);
        let input = cell.input();
        tau.copy_from_slice(c[0].step(&input).tau);
        for (i, from) in [(1, 2001), (2, 2991)] {
            if k >= from {
                c[i].step(&input);
            }
        }
    }
    let entries: Vec<usize> = c.iter().map(Controller::path_history_entries).collect();
    assert_eq!(entries, [1102, 1000, 10]);
    let mut buf = [0u8; BEHAVIOUR_BYTES];
    // a standby with fewer keeps its own; one with more keeps the peer's count
    let len = c[0].save_behaviour(&mut buf).unwrap();
    c[1].adopt_behaviour(&buf[..len]).unwrap();
    let len = c[2].save_behaviour(&mut buf).unwrap();
    c[0].adopt_behaviour(&buf[..len]).unwrap();
    let entries: Vec<usize> = c.iter().map(Controller::path_history_entries).collect();
    assert_eq!(entries, [10, 1000, 10]);
}

/// Three controllers of `loaded` in the cell, driven by A's torque; B and
/// its twin C start 50 periods late. After period 300, `bad` gets B and A's
/// snapshot; then B and C, stepped alike, must command the same to period 500.
fn refused_and_unchanged(loaded: &Loaded, bad: impl Fn(&mut Controller, &[u8])) {
    let mut cell = Cell::new(loaded, Script::default());
    let (mut a, mut b, mut c) = (controller(loaded), controller(loaded), controller(loaded));
    let mut tau = phri_model::gravity(&cell.model, &mut cell.data, &cell.q)
        .unwrap()
        .as_slice()
        .to_vec();
    let mut buf = [0u8; BEHAVIOUR_BYTES];
    for k in 1..=500u64 {
        cell.advance(&tau, &a);
        let input = cell.input();
        tau.copy_from_slice(a.step(&input).tau);
        // B and C start late: unlike A (its clock, velocity estimate, task)
        if k >= 51 {
            b.step(&input);
            c.step(&input);
            let (rb, rc) = (report(&b, k, &cell.q), report(&c, k, &cell.q));
            assert_eq!(rb, rc, "period {k}: B and its twin");
        }
        if k == 300 {
            assert_ne!(a.tau(), b.tau(), "adopting would change B");
            let len = a.save_behaviour(&mut buf).unwrap();
            bad(&mut b, &buf[..len]);
        }
    }
}

#[test]
fn truncated_and_malformed_snapshots_are_refused_and_change_nothing() {
    let loaded = lwr(Reaction::Reflex);
    refused_and_unchanged(&loaded, |b, bytes| {
        let len = bytes.len();
        let e = b.adopt_behaviour(&bytes[..len - 1]).unwrap_err();
        assert_eq!(
            e,
            SnapshotError::Truncated {
                need: len,
                have: len - 1
            }
        );
        // following the path history reads the record the snapshot begins
        // with, and refuses a snapshot cut short as well
        assert!(b.follow_behaviour(&bytes[..len - 1]).is_err());
        assert!(b.follow_behaviour(&bytes[..10]).is_err());
        let e = b.adopt_behaviour(&bytes[..10]).unwrap_err();
        assert_eq!(
            e,
            SnapshotError::Truncated {
                need: HEADER_BYTES,
                have: 10
            }
        );
        let mut bad = bytes.to_vec();
        bad[0] ^= 1;
        assert!(matches!(
            b.adopt_behaviour(&bad),
            Err(SnapshotError::Magic { .. })
        ));
        let mut bad = bytes.to_vec();
        bad[4] = 77;
        assert!(matches!(
            b.adopt_behaviour(&bad),
            Err(SnapshotError::Version { got: 77, .. })
        ));
        // the mode, the first value after the path history's record (its
        // pushes, path time and n joints): no such mode
        let mode_at = HEADER_BYTES + 8 * (2 + b.model().nv());
        let mut bad = bytes.to_vec();
        bad[mode_at..mode_at + 4].copy_from_slice(&99u32.to_le_bytes());
        assert_eq!(
            b.adopt_behaviour(&bad),
            Err(SnapshotError::Malformed { at: mode_at })
        );
        // the last values: the restart hold's tag (1 + judged, near, clear_since's
        // tag and value): a fault after everything else was read
        let mut bad = bytes.to_vec();
        let at = len - (1 + 1 + 1 + 1 + 8);
        bad[at] = 7;
        assert_eq!(
            b.adopt_behaviour(&bad),
            Err(SnapshotError::Malformed { at })
        );
    });
}

#[test]
fn a_snapshot_of_another_configuration_is_refused_and_changes_nothing() {
    let with = lwr(Reaction::Reflex);
    let mut without = lwr(Reaction::Reflex);
    without.config.collaboration.enabled = false;
    // collaboration on (A) and off (B), and the other way round
    for (theirs, ours) in [(&with, &without), (&without, &with)] {
        let mut a = controller(theirs);
        let mut bytes = [0u8; BEHAVIOUR_BYTES];
        let mut cell = Cell::new(theirs, Script::default());
        let mut tau = phri_model::gravity(&cell.model, &mut cell.data, &cell.q)
            .unwrap()
            .as_slice()
            .to_vec();
        for _ in 0..300 {
            cell.advance(&tau, &a);
            tau.copy_from_slice(a.step(&cell.input()).tau);
        }
        let len = a.save_behaviour(&mut bytes).unwrap();
        refused_and_unchanged(ours, |b, _| {
            let e = b.adopt_behaviour(&bytes[..len]).unwrap_err();
            assert!(matches!(e, SnapshotError::Layout { .. }), "{e}");
        });
    }
    // another robot (the FR3: 7 joints too, other control points), and an
    // LWR-IV with its last joint locked (6 joints)
    let fr3 = fr3();
    let other = controller(&fr3);
    let mut bytes = [0u8; BEHAVIOUR_BYTES];
    let len = other.save_behaviour(&mut bytes).unwrap();
    let cfg = Config::defaults();
    let model = Model::from_urdf_file_locked(&cfg.robot.urdf, &["lwr_joint_7".into()]).unwrap();
    assert_eq!(model.nv(), 6);
    let control = ControlConfig {
        posture: Vec::new(),
        ..cfg.control
    };
    let six = Controller::new(model, control, ControllerParams { period_s: 0.001 }).unwrap();
    let mut six_bytes = [0u8; BEHAVIOUR_BYTES];
    let six_len = six.save_behaviour(&mut six_bytes).unwrap();
    refused_and_unchanged(&with, |b, _| {
        let e = b.adopt_behaviour(&bytes[..len]).unwrap_err();
        assert!(matches!(e, SnapshotError::Layout { .. }), "{e}");
        let e = b.adopt_behaviour(&six_bytes[..six_len]).unwrap_err();
        assert_eq!(
            e,
            SnapshotError::Dof {
                expected: 7,
                got: 6
            }
        );
    });
}

#[test]
fn a_buffer_too_small_is_refused_and_trailing_bytes_are_ignored() {
    let loaded = lwr(Reaction::Reflex);
    refused_and_unchanged(&loaded, |b, bytes| {
        let len = bytes.len();
        let mut small = [0u8; 64];
        assert_eq!(
            b.save_behaviour(&mut small),
            Err(SnapshotError::BufferTooSmall {
                need: len,
                have: 64
            })
        );
        let mut exact = vec![0u8; len];
        assert_eq!(b.save_behaviour(&mut exact), Ok(len));
        // its own snapshot, in a message's whole array: adopting it changes nothing
        let mut whole = [0xffu8; BEHAVIOUR_BYTES];
        whole[..len].copy_from_slice(&exact);
        b.adopt_behaviour(&whole).unwrap();
    });
}

/// The FR3's configuration (`--robot fr3`).
fn fr3() -> Loaded {
    let path = Path::new(DEFAULT_DEPLOY_DIR).join("phri.toml");
    Loaded::load(&path, None, &["robot.name=fr3"]).unwrap()
}

#[test]
fn the_default_configurations_snapshots_fit_the_message() {
    for (name, loaded) in [("lwr4", Loaded::defaults()), ("fr3", fr3())] {
        assert!(loaded.config.collaboration.enabled && loaded.config.ssm.enabled);
        let c = controller(&loaded);
        let mut buf = [0u8; BEHAVIOUR_BYTES];
        let len = c.save_behaviour(&mut buf).unwrap();
        eprintln!(
            "{name}: {len} bytes ({} control points)",
            loaded.config.repulsion.points.len()
        );
        assert!(len <= BEHAVIOUR_BYTES);
    }
}
