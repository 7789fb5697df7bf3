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

use common::{loaded, Uniform};
use nalgebra::{Point3, Vector3};
use phri_cell::CellOptions;
use phri_config::Loaded;
use phri_control::clik::{Clik, ClikGains};
use phri_depth::{Capsule, PointOfInterest};
use phri_ipc::{WorldState, Zeroed};
use phri_model::{forward_kinematics, frame_placement, Data, Model};
use phri_perception::ingest::StateHistory;
use phri_perception::Perception;
use phri_sim::{fill_world, Simulator};

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

/// [`postures`] (1000 samples) at waypoint `i` of `control`, the person
/// posed as the scenario has them at `t` \[s\].
fn postures_at(
    sim: &mut Simulator,
    frame: usize,
    control: &phri_config::ControlConfig,
    (t, i): (f64, usize),
) -> Vec<(f64, Vec<f64>)> {
    sim.set_human_time_offset(t);
    postures(
        sim,
        frame,
        control.waypoints[i],
        control.waypoint_tolerance,
        1000,
    )
}

/// The depth-space view of the arm at the simulator's state, from one
/// camera per azimuth (the paper's set-up around the base): the cell's own
/// perception step ([`Perception`]: every camera, its ingestion with the
/// self-filter, the repulsion workers), each camera's distance bounded by
/// the space it watches, as the cell with several cameras runs it.
struct Perceiver {
    perception: Perception,
    history: StateHistory,
    world: WorldState,
    /// the control points' link radii [m]
    radii: Vec<f64>,
    /// the depth-space scan's reach ρ [m]
    rho: f64,
    /// the camera's frame period [s]
    frame_period_s: f64,
    now_ns: u64,
}

impl Perceiver {
    fn new(l: &Loaded, azimuths: &[f64]) -> Perceiver {
        let mut cfg = l.config.clone();
        cfg.cameras = azimuths
            .iter()
            .map(|&azimuth_rad| {
                let mut c = cfg.camera.clone();
                c.azimuth_rad = azimuth_rad;
                c
            })
            .collect();
        cfg.camera = cfg.cameras[0].clone();
        let model = l.model().unwrap();
        Perceiver {
            perception: Perception::new(&model, &cfg).unwrap(),
            history: StateHistory::new(model.nv(), 8),
            world: WorldState::zeroed(),
            radii: cfg.repulsion.points.iter().map(|p| p.radius).collect(),
            rho: cfg.repulsion.params.rho,
            frame_period_s: 1.0 / cfg.camera.rate_hz,
            now_ns: 1_000_000_000,
        }
    }

    /// Per camera, per control point: its lower bound of the clearance
    /// [m]: the depth-space distance (ρ when nothing is near), no farther
    /// than the space the camera does not watch; then per control point
    /// the true clearance from the person [m].
    fn perceive(&mut self, sim: &Simulator) -> (Vec<Vec<f64>>, Vec<f64>) {
        self.now_ns += (self.frame_period_s * 1e9) as u64;
        let now = self.now_ns;
        fill_world(sim, 0, now, &mut self.world);
        self.history.push(now, &sim.truth().q);
        let person: Vec<Capsule> = self.world.human[..self.world.n_human as usize]
            .iter()
            .map(|c| Capsule::new(Point3::from(c.a), Point3::from(c.b), c.radius))
            .collect();
        self.perception
            .capture(&self.world, now, self.frame_period_s, &self.history)
            .unwrap();
        self.perception.perceive(&self.history, None, now).unwrap();
        let n = self.radii.len();
        let mut truth = vec![f64::INFINITY; n];
        let mut out = Vec::with_capacity(self.perception.cameras());
        for camera in 0..self.perception.cameras() {
            let mut points = vec![f64::INFINITY; n];
            for r in self.perception.results(camera) {
                for p in &r.points[..r.n_points as usize] {
                    let i = p.point as usize;
                    points[i] = p.min_distance;
                    let point = PointOfInterest::new(Point3::from(p.position), self.radii[i]);
                    truth[i] = person
                        .iter()
                        .map(|c| c.distance_to_point(&point.position) - point.radius)
                        .fold(f64::INFINITY, f64::min)
                        .max(0.0);
                }
            }
            out.push(points);
        }
        (out, truth)
    }
}

/// Where the end effector reaches a waypoint in `free-motion` over
/// `seconds` (configuration overrides `sets`): (time \[s\], waypoint
/// index), in the order reached.
fn free_motion_waypoints(seconds: f64, sets: &[&str]) -> Vec<(f64, usize)> {
    let l = loaded("free-motion", sets);
    let model = l.model().unwrap();
    let mut data = Data::new(&model);
    let flange = model.frame_id(&l.config.control.ee_link).unwrap();
    let mut c = common::cell_of(&l, &CellOptions::default());
    let (mut reached, mut out) = (0, Vec::new());
    for k in 1..=(seconds * 1000.0).round() as usize {
        c.tick().unwrap();
        // the controller's own count (the summary sorts the run's figures)
        let now = c.in_charge().counters().waypoints_reached;
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

/// The first camera alone, a mirrored second and one beside the robot
/// (1.6 rad), in one pass over the waypoints (the search for postures is
/// most of the time).
#[test]
fn the_held_hand_hides_p1_and_p2_from_one_camera_a_mirrored_second_opens_them() {
    let (rows, f) = camera_sets(&[-0.6, 1.6]);
    let seconds = 60.0;
    for &(t, i, best_true, ee, all) in &rows {
        eprintln!(
            "t {t:5.2} s P{}: clearest posture {best_true:.3} m; perceived at the end effector {ee:.3} m, at every control point {all:.3} m (the first camera)",
            i + 1
        );
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
    // the mirrored second camera: every perceived bound stays under the
    // truth (to 2 cm: the sensor's noise is 6 mm at 2 m), and the waypoints
    // the held hand's shadow closed (P1, P2) open: at least 80 % of free
    // motion's
    let (one, two) = (&f[0], &f[1]);
    assert_eq!(one.over, 0, "{one:?}");
    assert_eq!(two.over, 0, "the fused bound over the truth: {two:?}");
    assert!(two.open_5cm as f64 >= 0.8 * n as f64, "{two:?} of {n}");
    assert!(two.open_5cm > one.open_5cm, "{two:?} against {one:?}");
    // beside the robot the arm hides the person from the second camera,
    // whose own bound then exceeds the truth by up to 3 cm (9 bounds over
    // by 2 cm); capped by the surfaces the first camera saw, none is
    let beside = &f[2];
    assert_eq!(beside.over, 0, "beside the robot: {beside:?}");
    assert!(beside.largest_excess < 0.02, "{beside:?}");
}

/// What a set of cameras makes of the waypoints: how many have a posture
/// whose end effector is perceived clear beyond 5 cm and beyond 2 cm, at
/// every control point beyond 2 cm, and how often (and by how much \[m\]) a
/// perceived bound exceeded the true clearance by 2 cm or more, of how many
/// compared.
/// A waypoint as the first camera alone perceives it: time \[s\], index,
/// the clearest posture's true clearance \[m\], the clearest perceived end
/// effector \[m\] and the clearest least control point \[m\] (depth-space
/// distances, as the cell with one camera runs).
type FirstCamera = (f64, usize, f64, f64, f64);

#[derive(Debug)]
struct SetFigures {
    open_5cm: usize,
    open_2cm: usize,
    all_open_2cm: usize,
    over: usize,
    largest_excess: f64,
    /// where: the waypoint, the control point, each camera's bound and the truth [m]
    worst: Option<(usize, usize, Vec<f64>, f64)>,
    /// per control point: its bounds 2 cm or more over the truth
    over_by_point: Vec<usize>,
    compared: usize,
}

/// The waypoints of 60 s of free motion, the person as `coexistence` has
/// them then, seen by the first camera of the configuration alone and by it
/// with a second at each of `second` \[rad\] (the paper's set-up around
/// the base), each pair a cell of its own whose workers cap every bound by
/// the nearest surface either camera saw, distances fused point by point
/// (the larger bound): per
/// waypoint what the first camera alone perceives, then the first camera's
/// figures and each pair's.
fn camera_sets(second: &[f64]) -> (Vec<FirstCamera>, Vec<SetFigures>) {
    let free = free_motion_waypoints(60.0, &[]);
    let l = loaded("coexistence", &[]);
    let model = l.model().unwrap();
    let control = &l.config.control;
    let mut sim = Simulator::from_scenario(model, l.config.sim.clone(), &l.scenario, None).unwrap();
    let ee = sim.model().frame_id(&control.ee_link).unwrap();
    // the first camera alone, then with each second: a cell each, as it
    // runs (the pair's workers cap each bound by the surfaces both saw)
    let first_azimuth = l.config.camera.azimuth_rad;
    let mut eyes: Vec<Perceiver> = std::iter::once(Perceiver::new(&l, &[first_azimuth]))
        .chain(
            second
                .iter()
                .map(|&a| Perceiver::new(&l, &[first_azimuth, a])),
        )
        .collect();
    let rho = eyes[0].rho;
    let points = eyes[0].radii.len();
    let zeros = vec![0.0; sim.model().nv()];
    let sets = eyes.len();
    let mut figures: Vec<SetFigures> = (0..sets)
        .map(|_| SetFigures {
            open_5cm: 0,
            open_2cm: 0,
            all_open_2cm: 0,
            over: 0,
            largest_excess: 0.0,
            worst: None,
            over_by_point: vec![0; points],
            compared: 0,
        })
        .collect();
    let mut rows = Vec::with_capacity(free.len());
    for &(t, i) in &free {
        let found = postures_at(&mut sim, ee, control, (t, i));
        let best_true = found.first().map_or(f64::NEG_INFINITY, |b| b.0);
        // per set: the clearest end effector and the clearest least point
        let mut best = vec![(f64::NEG_INFINITY, f64::NEG_INFINITY); sets];
        let mut first = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (_, q) in found.iter().take(40) {
            sim.set_state(q, &zeros).unwrap();
            let views: Vec<(Vec<Vec<f64>>, Vec<f64>)> =
                eyes.iter_mut().map(|e| e.perceive(&sim)).collect();
            let own = &views[0].0[0];
            first.0 = first.0.max(own[0]);
            first.1 = first
                .1
                .max(own.iter().copied().fold(f64::INFINITY, f64::min));
            for ((b, f), (seen, truth)) in best.iter_mut().zip(figures.iter_mut()).zip(&views) {
                // the controller's fusion: the largest bound
                let fused = |p: usize| seen.iter().map(|c| c[p]).fold(f64::NEG_INFINITY, f64::max);
                for (p, t) in truth.iter().enumerate() {
                    // beyond ρ depth space says nothing
                    let excess = fused(p).min(rho) - t.min(rho);
                    f.compared += 1;
                    if excess >= 0.02 {
                        f.over += 1;
                        f.over_by_point[p] += 1;
                    }
                    if excess > f.largest_excess {
                        f.largest_excess = excess;
                        f.worst = Some((i, p, seen.iter().map(|c| c[p]).collect(), *t));
                    }
                }
                let all = (0..truth.len()).map(fused).fold(f64::INFINITY, f64::min);
                *b = (b.0.max(fused(0)), b.1.max(all));
            }
        }
        rows.push((t, i, best_true, first.0, first.1));
        for (b, f) in best.iter().zip(figures.iter_mut()) {
            f.open_5cm += usize::from(b.0 > 0.05);
            f.open_2cm += usize::from(b.0 > 0.02);
            f.all_open_2cm += usize::from(b.1 > 0.02);
        }
    }
    for (k, f) in figures.iter().enumerate() {
        let name = match k {
            0 => "the first camera alone".to_string(),
            _ => format!("with a second at azimuth {:.2} rad", second[k - 1]),
        };
        eprintln!(
            "{name}: {} of {} waypoints open beyond 5 cm at the end effector, {} beyond 2 cm, {} at every control point beyond 2 cm; bounds 2 cm or more over the truth: {} of {}, largest excess {:.3} m",
            f.open_5cm,
            free.len(),
            f.open_2cm,
            f.all_open_2cm,
            f.over,
            f.compared,
            f.largest_excess
        );
        if let Some((w, p, bounds, t)) = &f.worst {
            eprintln!(
                "    largest at waypoint {w}, control point {p}: bounds {bounds:.3?} against {t:.3}; over by point {:?}",
                f.over_by_point
            );
        }
    }
    (rows, figures)
}

/// Placements of a second camera around the base, as figures: `cargo test
/// --release -p phri-cell --test waypoint_clearance second_camera_placements
/// -- --ignored --nocapture` (60 s). Behind and beside the robot the robot
/// hides the person from the second camera, whose self-filtered pixels then
/// read as free space: its bound is capped by the surfaces the first camera
/// saw, and exceeds the truth only where neither saw the nearest part.
#[test]
#[ignore = "figures (60 s): run with --ignored"]
fn second_camera_placements() {
    let pi = std::f64::consts::PI;
    let (rows, f) = camera_sets(&[-0.6, -1.5, 1.6, 2.4, -2.4, pi]);
    assert_eq!(f.len(), 7);
    assert!(!rows.is_empty());
}

/// The bound the barrier's d_s puts on `coexistence`'s pace with perception
/// that hides nothing, per arm: `cargo test --release -p phri-cell --test
/// waypoint_clearance truth_bound_per_arm -- --ignored --nocapture` (about a
/// minute per arm). For each waypoint free motion reaches in 60 s, the
/// person posed as `coexistence` has them then, the true clearance of the
/// arm's clearest posture (1000 inverse-kinematics solutions over its
/// redundancy): how many are clearer than d_s = 5 cm + 1.6 m/s × the
/// perception's age, at the freshest (8 ms: 6.3 cm) and at a frame's age
/// (33 ms: 10.3 cm).
#[test]
#[ignore = "figures (3 min): run with --ignored"]
fn truth_bound_per_arm() {
    for robot in ["lwr4", "fr3", "panda"] {
        let arm = format!("robot.name=\"{robot}\"");
        let free = free_motion_waypoints(60.0, &[arm.as_str()]);
        let l = loaded("coexistence", &[arm.as_str()]);
        let model = l.model().unwrap();
        let control = &l.config.control;
        let mut sim =
            Simulator::from_scenario(model, l.config.sim.clone(), &l.scenario, None).unwrap();
        let ee = sim.model().frame_id(&control.ee_link).unwrap();
        let mut clearest = Vec::with_capacity(free.len());
        for &(t, i) in &free {
            let found = postures_at(&mut sim, ee, control, (t, i));
            clearest.push(found.first().map_or(f64::NEG_INFINITY, |b| b.0));
        }
        let n = free.len();
        assert!(n > 0, "{robot}: free motion reached no waypoint");
        let open = |d_s: f64| clearest.iter().filter(|&&c| c > d_s).count();
        let pct = |k: usize| 100.0 * k as f64 / n as f64;
        let (fresh, frame) = (0.05 + 1.6 * 0.008, 0.05 + 1.6 * 0.033);
        eprintln!(
            "{robot}: {n} waypoints of free motion in 60 s; clearest posture beyond 5 cm: {}, beyond {:.1} cm: {} ({:.0} %), beyond {:.1} cm: {} ({:.0} %)",
            open(0.05),
            fresh * 100.0,
            open(fresh),
            pct(open(fresh)),
            frame * 100.0,
            open(frame),
            pct(open(frame)),
        );
        // the search works: far from the person every waypoint is clear
        assert!(clearest.iter().any(|&c| c > 0.3), "{robot}: {clearest:?}");
    }
}
