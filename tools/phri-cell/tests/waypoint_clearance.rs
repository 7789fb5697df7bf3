//! Which waypoints of `coexistence` an avoidance working in depth space can
//! reach at all: for every waypoint free motion reaches in 60 s, the person
//! posed as `coexistence` has them at that moment, the arm's clearest
//! postures with the flange within the waypoint tolerance (many
//! inverse-kinematics solutions over its redundancy), their true clearance
//! and the end effector's clearance as the camera, ingestion and the
//! repulsion workers perceive it. While the hand is held in the path, P1
//! and P2 lie in the hand's and forearm's shadow, which depth space counts
//! as occupied (paper Sect. V): the bound on item 1 of issue 14
//! (BENCHMARKS.md, "Keeping the task's pace"):
//!
//! `cargo test --release -p phri-cell --test waypoint_clearance -- --nocapture`

mod common;

use common::loaded;
use nalgebra::Vector3;
use phri_cell::CellOptions;
use phri_config::Loaded;
use phri_control::clik::{Clik, ClikGains};
use phri_ipc::{FrameHeader, WorldState, Zeroed};
use phri_model::{forward_kinematics, frame_placement, Data, Model};
use phri_perception::camera::CameraSim;
use phri_perception::ingest::{Ingest, StateHistory};
use phri_perception::repulsion::Worker;
use phri_sim::{fill_world, Simulator};

/// A deterministic uniform sequence in [0, 1) (xorshift64*).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Joint positions \[rad\] that put the origin of `clik`'s frame at
/// `target` \[m\]: the controller's CLIK as Newton steps from `q` (no
/// posture term), kept inside the limits less `margin`; `None` if they do
/// not converge to 1 mm.
fn solve(
    model: &Model,
    data: &mut Data,
    clik: &mut Clik,
    target: &Vector3<f64>,
    mut q: Vec<f64>,
    margin: f64,
) -> Option<Vec<f64>> {
    let n = model.nv();
    let newton = ClikGains {
        clik: 1.0,
        posture: 0.0,
        damping: 0.01,
    };
    let unlimited = vec![f64::INFINITY; n];
    // no posture term (gain 0): any posture
    let posture = vec![0.0; n];
    for _ in 0..200 {
        if (target - clik.position(model, data, &q).ok()?).norm() < 1e-3 {
            return Some(q);
        }
        clik.step(
            model,
            data,
            &mut q,
            target,
            &Vector3::zeros(),
            1.0,
            newton,
            &posture,
            &unlimited,
        )
        .ok()?;
        for (qi, joint) in q.iter_mut().zip(&model.joints[..n]) {
            *qi = qi.clamp(joint.lower + margin, joint.upper - margin);
        }
    }
    None
}

/// Arm postures \[rad\] with the origin of `frame` (the end effector)
/// within `tolerance` \[m\] of `waypoint`, from `samples` random starts and
/// targets, each with its true clearance to the person [m] at the
/// simulator's script time; the clearest first.
fn postures(
    sim: &mut Simulator,
    frame: usize,
    waypoint: [f64; 3],
    tolerance: f64,
    samples: usize,
) -> Vec<(f64, Vec<f64>)> {
    let model = sim.model().clone();
    let mut data = Data::new(&model);
    let mut clik = Clik::new(&model, frame);
    let n = model.nv();
    let margin = 0.05;
    let mut rng = Uniform(0x9e37_79b9_7f4a_7c15);
    let zeros = vec![0.0; n];
    let mut out = Vec::with_capacity(samples);
    for _ in 0..samples {
        let q0: Vec<f64> = model.joints[..n]
            .iter()
            .map(|j| {
                let (lo, hi) = (j.lower + margin, j.upper - margin);
                lo + (hi - lo) * rng.next()
            })
            .collect();
        // a target uniform in the tolerance ball
        let target = loop {
            let v = Vector3::new(rng.next(), rng.next(), rng.next()) * 2.0 - Vector3::repeat(1.0);
            if v.norm() <= 1.0 {
                break Vector3::from(waypoint) + v * tolerance;
            }
        };
        let Some(q) = solve(&model, &mut data, &mut clik, &target, q0, margin) else {
            continue;
        };
        sim.set_state(&q, &zeros).unwrap();
        out.push((sim.truth().min_distance, q));
    }
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    out
}

/// The depth-space view of the arm at the simulator's state: the camera's
/// frame, ingestion's self-filter and every repulsion worker, as the cell
/// runs them.
struct Perceiver {
    camera: CameraSim,
    ingest: Ingest,
    history: StateHistory,
    workers: Vec<Worker>,
    world: WorldState,
    frame: Vec<u16>,
    filtered: Vec<u16>,
    now_ns: u64,
}

impl Perceiver {
    fn new(l: &Loaded) -> Perceiver {
        let cfg = &l.config;
        let model = l.model().unwrap();
        let camera = CameraSim::new(model.clone(), &cfg.camera).unwrap();
        let pixels = camera.pixels();
        Perceiver {
            ingest: Ingest::new(model.clone(), &cfg.perception).unwrap(),
            history: StateHistory::new(model.nv(), 8),
            workers: (0..cfg.repulsion.workers)
                .map(|w| Worker::new(model.clone(), &cfg.repulsion, w).unwrap())
                .collect(),
            world: WorldState::zeroed(),
            frame: vec![0; pixels],
            filtered: vec![0; pixels],
            now_ns: 1_000_000_000,
            camera,
        }
    }

    /// The perceived clearance [m] of the end effector's control point and
    /// the least over every control point.
    fn clearance(&mut self, sim: &Simulator) -> (f64, f64) {
        self.now_ns += 33_000_000;
        let now = self.now_ns;
        fill_world(sim, 0, now, &mut self.world);
        let mut header = FrameHeader::zeroed();
        self.camera
            .step(&self.world, now, &mut self.frame, &mut header)
            .unwrap();
        self.history.push(now, &sim.truth().q);
        self.ingest
            .step(
                &mut header,
                &self.frame,
                &self.history,
                now,
                &mut self.filtered,
            )
            .unwrap();
        let (mut ee, mut all) = (f64::INFINITY, f64::INFINITY);
        for w in self.workers.iter_mut() {
            let r = w.respond(&header, &self.filtered).unwrap();
            for p in &r.points[..r.n_points as usize] {
                if p.point == 0 {
                    ee = p.min_distance;
                }
                all = all.min(p.min_distance);
            }
        }
        (ee, all)
    }
}

/// Where the end effector reaches a waypoint in `free-motion` over
/// `seconds`: (time \[s\], waypoint index), in the order reached.
fn free_motion_waypoints(seconds: f64) -> Vec<(f64, usize)> {
    let l = loaded("free-motion", &[]);
    let model = l.model().unwrap();
    let mut data = Data::new(&model);
    let flange = model.frame_id(&l.config.control.ee_link).unwrap();
    let mut c = common::cell_of(&l, &CellOptions::default());
    let (mut reached, mut out) = (0, Vec::new());
    for k in 1..=(seconds * 1000.0).round() as usize {
        c.tick().unwrap();
        let now = c.summary().waypoints;
        if now != reached {
            reached = now;
            forward_kinematics(&model, &mut data, &c.sim.truth().q).unwrap();
            let ee = frame_placement(&model, &data, flange).p;
            let nearest = (0..l.config.control.waypoints.len())
                .min_by(|&a, &b| {
                    let d = |i: usize| (ee - Vector3::from(l.config.control.waypoints[i])).norm();
                    d(a).total_cmp(&d(b))
                })
                .unwrap();
            out.push((k as f64 * 1e-3, nearest));
        }
    }
    out
}

#[test]
fn the_held_hand_hides_p1_and_p2_from_the_depth_space() {
    let seconds = 60.0;
    let free = free_motion_waypoints(seconds);
    let l = loaded("coexistence", &[]);
    let model = l.model().unwrap();
    let control = &l.config.control;
    let mut sim = Simulator::from_scenario(model, l.config.sim.clone(), &l.scenario, None).unwrap();
    let ee = sim.model().frame_id(&control.ee_link).unwrap();
    let mut eye = Perceiver::new(&l);
    let zeros = vec![0.0; sim.model().nv()];
    // for each waypoint free motion reaches, the person as `coexistence` has
    // them then: the clearest postures within the tolerance, truly and in
    // depth space (the clearest 40 by the truth, as the camera sees them)
    let mut rows = Vec::new();
    for &(t, i) in &free {
        sim.set_human_time_offset(t);
        let found = postures(
            &mut sim,
            ee,
            control.waypoints[i],
            control.waypoint_tolerance,
            1000,
        );
        let best_true = found.first().map_or(f64::NEG_INFINITY, |b| b.0);
        let (mut ee, mut all) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (_, q) in found.iter().take(40) {
            sim.set_state(q, &zeros).unwrap();
            let (e, a) = eye.clearance(&sim);
            ee = ee.max(e);
            all = all.max(a);
        }
        eprintln!(
            "t {t:5.2} s P{}: clearest posture {best_true:.3} m; perceived at the end effector {ee:.3} m, at every control point {all:.3} m",
            i + 1
        );
        rows.push((t, i, best_true, ee, all));
    }
    let n = rows.len();
    let open = |limit: f64| rows.iter().filter(|r| r.3 > limit).count();
    for limit in [0.0, 0.02, 0.05, 0.1, 0.2] {
        eprintln!(
            "{} of the {n} waypoints of free motion in {seconds} s have a posture whose end effector is perceived more than {:.0} mm from the person ({:.1} %)",
            open(limit),
            limit * 1e3,
            100.0 * open(limit) as f64 / n as f64
        );
    }
    // fewer than the 70 % of issue 14 are open beyond the 5 cm it asks for
    assert!(
        (open(0.05) as f64) < 0.7 * n as f64,
        "{} of {n}: item 1 of issue 14 is within depth space's reach",
        open(0.05)
    );
    // the search works: far from the person every waypoint is clear
    assert!(rows.iter().any(|r| r.2 > 1.0 && r.3 > 0.3));
    // while the hand is held in the path (11-22 s of each visit), P1 and P2
    // lie inside what depth space counts as occupied (the hand's and the
    // forearm's shadow), though the arm could truly keep 5 cm or more there
    // from P1; P3 stays clear
    for &(t, i, best_true, ee, _) in &rows {
        if (11.5..21.5).contains(&t.rem_euclid(30.0)) {
            match i {
                0 => assert!(ee < 0.02 && best_true > 0.05, "t {t}: P1 {best_true} {ee}"),
                1 => assert!(ee < 0.02 && best_true < 0.1, "t {t}: P2 {best_true} {ee}"),
                _ => assert!(ee > 0.2, "t {t}: P3 {ee}"),
            }
        }
    }
}
