//! The wave detector on synthetic skeleton tracks at 30 Hz with the default
//! tracker noise: waves of 1-3 Hz and 10-25 cm with either hand are
//! recognised, with the waving hand; reaching, walking, pointing, resting and
//! a hand waving below the elbow never are.

use phri_config::Config;
use phri_gesture::WaveDetector;
use phri_ipc::{CollabPart, Skeleton, SkeletonJoint as J, Zeroed};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

const FPS: f64 = 30.0;

/// A person facing the robot from `x` [m] (their right towards +y), arms
/// hanging; `pose(t)` may move joints.
#[derive(Clone, Copy)]
struct Body {
    j: [[f64; 3]; 15],
}

fn standing(x: f64, y: f64) -> Body {
    let mut j = [[0.0; 3]; 15];
    let mut set = |k: J, p: [f64; 3]| j[k as usize] = p;
    set(J::Head, [x, y, 0.85]);
    set(J::Neck, [x, y, 0.68]);
    set(J::Torso, [x, y, 0.40]);
    set(J::LeftShoulder, [x, y - 0.2, 0.65]);
    set(J::RightShoulder, [x, y + 0.2, 0.65]);
    set(J::LeftElbow, [x, y - 0.23, 0.37]);
    set(J::RightElbow, [x, y + 0.23, 0.37]);
    set(J::LeftHand, [x, y - 0.24, 0.12]);
    set(J::RightHand, [x, y + 0.24, 0.12]);
    set(J::LeftHip, [x, y - 0.1, 0.12]);
    set(J::RightHip, [x, y + 0.1, 0.12]);
    set(J::LeftKnee, [x, y - 0.1, -0.33]);
    set(J::RightKnee, [x, y + 0.1, -0.33]);
    set(J::LeftFoot, [x, y - 0.1, -0.78]);
    set(J::RightFoot, [x, y + 0.1, -0.78]);
    Body { j }
}

/// Run `seconds` of `pose(t)` through a detector with the tracker's noise;
/// the (time, part) of every wave.
fn run(seconds: f64, seed: u64, pose: impl Fn(f64) -> Body) -> Vec<(f64, CollabPart)> {
    let cfg = Config::defaults();
    let (sigma, bias_sigma) = (cfg.skeleton.noise_m, cfg.skeleton.bias_m);
    // each joint's drifting offset: a first-order Gauss-Markov process
    let phi = (-1.0 / (FPS * cfg.skeleton.bias_time_s)).exp();
    let mut bias = [[0.0f64; 3]; 15];
    let mut d = WaveDetector::new(&cfg.gesture).unwrap();
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut gauss = move || {
        // Box-Muller
        let (u1, u2): (f64, f64) = (1.0 - rng.gen::<f64>(), rng.gen());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    for b in bias.iter_mut().flatten() {
        *b = bias_sigma * gauss();
    }
    let mut out = Vec::new();
    for k in 0..(seconds * FPS) as usize {
        let t = k as f64 / FPS;
        let b = pose(t);
        let mut sk = Skeleton::zeroed();
        sk.seq = k as u64 + 1;
        sk.capture_ns = 1_000_000_000 + (t * 1e9) as u64;
        sk.n_people = 1;
        let p = &mut sk.people[0];
        p.id = 7;
        p.tracked = 1;
        for (i, q) in b.j.iter().enumerate() {
            for a in 0..3 {
                let b = &mut bias[i][a];
                *b = phi * *b + bias_sigma * (1.0 - phi * phi).sqrt() * gauss();
                p.joints[i][a] = q[a] + *b + sigma * gauss();
            }
            p.confidence[i] = 0.9;
        }
        if let Some(w) = d.step(&sk) {
            assert_eq!(w.person, 7);
            out.push((t, w.part));
        }
    }
    out
}

/// Waving: the forearm up, the hand swinging sideways by `swing` [m] peak to
/// peak at `f` [Hz], from `t0` [s].
fn waving(f: f64, swing: f64, part: CollabPart, t0: f64) -> impl Fn(f64) -> Body {
    move |t| {
        let mut b = standing(1.0, 0.0);
        if t >= t0 {
            let (side, e, h) = match part {
                CollabPart::LeftHand => (-1.0, J::LeftElbow, J::LeftHand),
                _ => (1.0, J::RightElbow, J::RightHand),
            };
            let elbow = [0.95, side * 0.32, 0.62];
            b.j[e as usize] = elbow;
            let s = 0.5 * swing * (std::f64::consts::TAU * f * (t - t0)).sin();
            b.j[h as usize] = [elbow[0] - 0.03, elbow[1] + s, elbow[2] + 0.26];
        }
        b
    }
}

#[test]
fn waves_of_either_hand_are_recognised() {
    let mut seed = 1;
    for part in [CollabPart::RightHand, CollabPart::LeftHand] {
        for f in [1.0, 2.0, 3.0] {
            for swing in [0.10, 0.25] {
                seed += 1;
                let waves = run(6.0, seed, waving(f, swing, part, 1.0));
                let (t, p) = *waves
                    .first()
                    .unwrap_or_else(|| panic!("{part:?} {f} Hz {swing} m: no wave"));
                assert_eq!(p, part, "{f} Hz {swing} m");
                let after = t - 1.0;
                eprintln!("{part:?} {f} Hz {swing} m: recognised {after:.2} s after it began");
                // a lazy, small wave (1 Hz, 10 cm) is at the edge of the
                // tracker's drift: it takes a few more swings
                let bound = if f < 1.5 && swing < 0.15 { 4.0 } else { 2.5 };
                assert!(after <= bound, "{part:?} {f} Hz {swing} m: {after:.2} s");
                // one request per wave: the refractory period holds the next
                assert_eq!(waves.len(), 1, "{waves:?}");
            }
        }
    }
}

#[test]
fn a_brisk_wave_is_recognised_well_within_two_seconds() {
    for seed in 0..10 {
        let waves = run(
            4.0,
            100 + seed,
            waving(2.0, 0.20, CollabPart::RightHand, 0.5),
        );
        let t = waves.first().expect("no wave").0 - 0.5;
        assert!(t <= 1.5, "seed {seed}: {t:.2} s");
    }
}

fn lerp(a: [f64; 3], b: [f64; 3], u: f64) -> [f64; 3] {
    let u = u.clamp(0.0, 1.0);
    [
        a[0] + (b[0] - a[0]) * u,
        a[1] + (b[1] - a[1]) * u,
        a[2] + (b[2] - a[2]) * u,
    ]
}

#[test]
fn reaching_walking_pointing_and_low_waving_are_not_waves() {
    let minute = 60.0;
    // resting: arms hanging
    assert!(run(minute, 11, |_| standing(1.0, 0.0)).is_empty());
    // reaching: the right hand goes to points in front, above the elbow, and back, every 3 s
    let reach = |t: f64| {
        let mut b = standing(1.0, 0.0);
        let targets = [[0.6, 0.1, 0.55], [0.55, -0.1, 0.7], [0.6, 0.25, 0.6]];
        let k = (t / 3.0) as usize;
        let u = ((t % 3.0) / 0.8).min(1.0) - ((t % 3.0 - 2.0) / 0.8).clamp(0.0, 1.0);
        let hand0 = b.j[J::RightHand as usize];
        let target = targets[k % targets.len()];
        b.j[J::RightHand as usize] = lerp(hand0, target, u);
        b.j[J::RightElbow as usize] = lerp(b.j[J::RightElbow as usize], [0.8, 0.2, 0.45], u);
        b
    };
    let w = run(minute, 12, reach);
    assert!(w.is_empty(), "reaching: {w:?}");
    // walking past with arms swinging (below the elbows), 0.5 m/s, back and forth
    let walk = |t: f64| {
        let y = 1.5 * ((t / 6.0) * std::f64::consts::PI).sin();
        let mut b = standing(1.2, y);
        let s = 0.15 * (std::f64::consts::TAU * 0.9 * t).sin();
        b.j[J::RightHand as usize][0] += s;
        b.j[J::LeftHand as usize][0] -= s;
        b
    };
    assert!(run(minute, 13, walk).is_empty());
    // pointing: the arm stretched sideways at shoulder height, held, moved slowly
    let point = |t: f64| {
        let mut b = standing(1.0, 0.0);
        let drift = 0.05 * (0.3 * t).sin();
        b.j[J::RightElbow as usize] = [0.9, 0.45, 0.66];
        b.j[J::RightHand as usize] = [0.8, 0.68 + drift, 0.70];
        b
    };
    assert!(run(minute, 14, point).is_empty());
    // waving with the hand below the elbow
    let low = |t: f64| {
        let mut b = standing(1.0, 0.0);
        let e = [0.95, 0.3, 0.45];
        b.j[J::RightElbow as usize] = e;
        let s = 0.1 * (std::f64::consts::TAU * 2.0 * t).sin();
        b.j[J::RightHand as usize] = [e[0], e[1] + s, e[2] - 0.15];
        b
    };
    assert!(run(minute, 15, low).is_empty());
}

#[test]
fn a_person_who_stops_being_tracked_starts_over() {
    // two reversals, then the tracker loses the person, then two more: no wave
    let cfg = Config::defaults();
    let mut d = WaveDetector::new(&cfg.gesture).unwrap();
    let pose = waving(2.0, 0.2, CollabPart::RightHand, 0.0);
    let mut waves = 0;
    for k in 0..60usize {
        let t = k as f64 / FPS;
        let mut sk = Skeleton::zeroed();
        sk.capture_ns = 1_000_000_000 + (t * 1e9) as u64;
        let lost = (25..30).contains(&k);
        sk.n_people = 1;
        sk.people[0].id = 3;
        sk.people[0].tracked = (!lost) as u32;
        sk.people[0].joints = pose(if k < 25 { t } else { t - 0.5 }).j;
        sk.people[0].confidence = [0.9; 15];
        // only ~0.8 s of waving on either side of the gap
        if k > 50 {
            break;
        }
        if d.step(&sk).is_some() {
            waves += 1;
        }
    }
    assert_eq!(waves, 0);
}
