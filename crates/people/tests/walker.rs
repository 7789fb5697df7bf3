//! A person walking through the camera's view while another stands still
//! keeps two ids, against the renderer's truth: frames rendered by phri-depth's
//! [`Renderer`] (Kinect-like noise and edge drop-outs, the floor in view and
//! found by RANSAC) from capsule people of the simulator's proportions (as in
//! `examples/accuracy.rs`), tracked as a 30 Hz sequence. The walker crosses at
//! 1 m/s from y = +1.6 to −1.6 m, once 0.9 m behind the still person (more than
//! half hidden by it for 16 frames, 0.53 s) and once 0.7 m in front of it
//! (hiding it for 7 frames). A body is "seen" in a frame when its torso centre
//! projects inside the image and at least half of its pixels show.
//!
//! Measured (tracker at commit fc0a0a1, these seeds; seeds +100 … +800 alike):
//! behind: still 97/97, walker 73/81 seen frames, ids [1] and [2], the same id
//! after the walker re-emerges; in front: still 90/90 seen (92/97 in all),
//! walker 57/65; at most 2 people. Heads: 2 of 170 and 8 of 149 reports more
//! than 25 cm off (worst 32.8 / 29.8 cm; other seeds up to 74 cm).

use nalgebra::{Point3, Vector3};
use phri_depth::{CameraPose, Capsule, Intrinsics, RenderOptions, Renderer};
use phri_people::{FloorMode, Joint, Person, Tracker, TrackerConfig, MAX_PEOPLE};

const K: Intrinsics = Intrinsics::KINECT;
const DT: f64 = 1.0 / 30.0;
const FRAMES: usize = 97;
const STILL: [f64; 2] = [2.5, 0.2];
/// body heights (simulator's proportions): head and torso capsule centres \[m\]
const HEAD_Z: f64 = 1.605;
const TORSO_Z: f64 = 1.205;

// --- bounds ---
/// the still person is reported in at least this share of the frames it is seen in
const STILL_REPORTED: f64 = 0.95;
/// ... and in at least this share of all frames (hidden or not)
const STILL_ALL_FRAMES: f64 = 0.90;
/// the walker is reported in at least this share of the frames it is seen in
const WALKER_REPORTED: f64 = 0.80;
/// a reported head lies at most this far from the nearest true head \[m\] ...
const HEAD_M: f64 = 0.25;
/// ... but for at most this share of the reported heads (the tracker takes a
/// side-on walker's shoulder nearer the camera for its head, ~29 cm off, and
/// a half-hidden person's fragment gives heads up to ~75 cm off) ...
const HEAD_OFF_SHARE: f64 = 0.10;
/// ... and none lies this far from every true head (a phantom person) \[m\]
const HEAD_ANY_M: f64 = 1.0;

/// A capsule person with its arms down at `(x, y)` on the floor facing `yaw`:
/// its capsules, true head and torso centre (base frame, z up, metres).
fn person(x: f64, y: f64, yaw: f64) -> (Vec<Capsule>, Point3<f64>, Point3<f64>) {
    let fwd = Vector3::new(yaw.cos(), yaw.sin(), 0.0);
    let lft = Vector3::new(-yaw.sin(), yaw.cos(), 0.0);
    let p = |f: f64, l: f64, u: f64| Point3::new(x, y, 0.0) + fwd * f + lft * l + Vector3::z() * u;
    let mut caps = vec![
        Capsule::new(p(0.0, 0.0, 1.56), p(0.0, 0.0, 1.65), 0.10),
        Capsule::new(p(0.0, 0.0, 1.08), p(0.0, 0.0, 1.33), 0.15),
        Capsule::new(p(0.0, -0.08, 0.95), p(0.0, 0.08, 0.95), 0.12),
    ];
    for s in [1.0, -1.0] {
        let (shoulder, hip, knee) = (
            p(0.0, s * 0.19, 1.45),
            p(0.0, s * 0.1, 0.88),
            p(0.0, s * 0.1, 0.5),
        );
        caps.push(Capsule::new(hip, knee, 0.075));
        caps.push(Capsule::new(knee, p(0.0, s * 0.1, 0.1), 0.055));
        // arm hanging a little away from the body (the simulator's lengths)
        let elbow = shoulder + (p(0.0, s * 0.26, 1.16) - shoulder).normalize() * 0.30;
        let fore = (p(0.03, s * 0.31, 0.89) - elbow).normalize();
        let wrist = elbow + fore * 0.21;
        caps.push(Capsule::new(shoulder, elbow, 0.05));
        caps.push(Capsule::new(elbow, wrist, 0.04));
        caps.push(Capsule::new(wrist, wrist + fore * 0.09, 0.045));
    }
    (caps, p(0.0, 0.0, HEAD_Z), p(0.0, 0.0, TORSO_Z))
}

/// What one walk gave, per frame; index 0 the still person, 1 the walker.
#[derive(Debug, Default)]
struct Walk {
    /// the id reported for each body (0 = not reported, `u32::MAX` = reported twice)
    ids: Vec<[u32; 2]>,
    /// the truth: the body's torso centre projects inside the image and at
    /// least half of its pixels (as rendered alone) are not hidden by the other
    seen: Vec<[bool; 2]>,
    /// distance of each reported head to the nearest true head, with that body \[m\]
    heads: Vec<Vec<(usize, f64)>>,
    /// people reported
    people: Vec<usize>,
}

/// Pixels whose label lies in `labels_of` (a body's capsules, 1-based).
fn pixels(labels: &[u16], labels_of: std::ops::RangeInclusive<usize>) -> usize {
    labels
        .iter()
        .filter(|&&l| labels_of.contains(&usize::from(l)))
        .count()
}

fn walk(walker_x: f64, seed: u64) -> Walk {
    let pose = CameraPose::look_at(
        &Point3::new(0.0, 0.0, 1.3),
        &Point3::new(3.0, 0.0, 1.0),
        &Vector3::z(),
    )
    .unwrap();
    let mut r = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let up = pose.rotation().transpose() * Vector3::z();
    let cfg = TrackerConfig {
        up_camera: [up.x, up.y, up.z],
        floor: FloorMode::Ransac,
        ..TrackerConfig::default()
    };
    let mut t = Tracker::new(K, cfg).unwrap();
    let mut out = [Person::default(); MAX_PEOPLE];
    let mut depth = vec![0u16; K.pixel_count()];
    let mut labels = vec![0u16; K.pixel_count()];
    let (still, still_head, still_torso) = person(STILL[0], STILL[1], std::f64::consts::PI);
    let ns = still.len();
    r.render_labeled(&still, &[], Some(0.0), &mut depth, &mut labels)
        .unwrap();
    let still_alone = pixels(&labels, 1..=ns);
    let in_image = |p: &Point3<f64>| {
        pose.project(&K, p).is_some_and(|pd| {
            (0.0..f64::from(K.width)).contains(&pd.px)
                && (0.0..f64::from(K.height)).contains(&pd.py)
        })
    };
    let mut w = Walk::default();
    for k in 0..FRAMES {
        let (walker, walker_head, walker_torso) =
            person(walker_x, 1.6 - k as f64 * DT, -std::f64::consts::FRAC_PI_2);
        r.render_labeled(&walker, &[], Some(0.0), &mut depth, &mut labels)
            .unwrap();
        let walker_alone = pixels(&labels, 1..=walker.len());
        let caps: Vec<Capsule> = still.iter().chain(&walker).copied().collect();
        r.reseed(seed + k as u64);
        r.render_labeled(&caps, &[], Some(0.0), &mut depth, &mut labels)
            .unwrap();
        let n = t.step(&depth, DT, &mut out).unwrap();
        w.seen.push([
            in_image(&still_torso) && 2 * pixels(&labels, 1..=ns) >= still_alone,
            in_image(&walker_torso) && 2 * pixels(&labels, ns + 1..=caps.len()) >= walker_alone,
        ]);
        let truth = [pose.to_camera(&still_head), pose.to_camera(&walker_head)];
        let mut ids = [0u32; 2];
        let mut heads = Vec::new();
        for p in &out[..n] {
            let h = Point3::from(p.joints[Joint::Head as usize]);
            let d = [(h - truth[0]).norm(), (h - truth[1]).norm()];
            let b = usize::from(d[1] < d[0]);
            heads.push((b, d[b]));
            ids[b] = if ids[b] == 0 { p.id } else { u32::MAX };
        }
        w.ids.push(ids);
        w.heads.push(heads);
        w.people.push(n);
    }
    w
}

/// Distinct ids of body `b` over the frames `keep`, in order of appearance.
fn ids_of(w: &Walk, b: usize, keep: impl Fn(usize) -> bool) -> Vec<u32> {
    let mut ids = Vec::new();
    for (k, f) in w.ids.iter().enumerate() {
        if f[b] != 0 && keep(k) && !ids.contains(&f[b]) {
            ids.push(f[b]);
        }
    }
    ids
}

/// Stretches `a..b` where body `b` is not seen between frames it is seen in.
fn hidden_stretches(w: &Walk, body: usize) -> Vec<(usize, usize)> {
    let seen: Vec<bool> = w.seen.iter().map(|s| s[body]).collect();
    let mut out = Vec::new();
    let mut k = seen.iter().position(|&s| s).unwrap_or(FRAMES);
    while let Some(a) = (k..FRAMES).find(|&i| !seen[i]) {
        let Some(b) = (a..FRAMES).find(|&i| seen[i]) else {
            break;
        };
        out.push((a, b));
        k = b;
    }
    out
}

/// Tracks one walk and checks it; `walker_hidden`: the walker passes behind
/// the still person (else in front of it, hiding it).
fn check(name: &str, walker_x: f64, seed: u64, walker_hidden: bool) {
    let w = walk(walker_x, seed);
    let mut failures = Vec::new();
    let mut ids = Vec::new();
    for (b, (who, share)) in [
        ("still person", STILL_REPORTED),
        ("walker", WALKER_REPORTED),
    ]
    .into_iter()
    .enumerate()
    {
        let letter = ['S', 'W'][b];
        let line: String = (0..FRAMES)
            .map(|k| match (w.seen[k][b], w.ids[k][b] != 0) {
                (true, true) => letter,
                (true, false) => '-',
                (false, true) => letter.to_ascii_lowercase(),
                (false, false) => '.',
            })
            .collect();
        let seen = w.seen.iter().filter(|s| s[b]).count();
        let reported = (0..FRAMES).filter(|&k| w.ids[k][b] != 0).count();
        let reported_seen = (0..FRAMES)
            .filter(|&k| w.seen[k][b] && w.ids[k][b] != 0)
            .count();
        let body_ids = ids_of(&w, b, |_| true);
        let stretches = hidden_stretches(&w, b);
        eprintln!("{name}, {who:>12}: {line}");
        eprintln!(
            "{name}, {who:>12}: reported in {reported_seen}/{seen} frames seen, {reported}/{FRAMES} \
             in all; ids {body_ids:?}; hidden (frames) {stretches:?}"
        );
        if seen < FRAMES / 2 || (reported_seen as f64) < share * seen as f64 {
            failures.push(format!(
                "the {who} reported in {reported_seen} of the {seen} frames it is seen in"
            ));
        }
        if body_ids.len() != 1 {
            failures.push(format!("the {who}'s ids {body_ids:?}"));
        }
        for &(a, z) in &stretches {
            let before = ids_of(&w, b, |k| k < a);
            let after = ids_of(&w, b, |k| k >= z);
            if (z - a) as f64 * DT >= 1.0 || before.is_empty() || before != after {
                failures.push(format!(
                    "the {who} hidden in frames {a}..{z}: ids before {before:?}, after {after:?}"
                ));
            }
        }
        if b == 1 && walker_hidden && stretches.is_empty() {
            failures.push("the walker never hidden: the scene is wrong".into());
        }
        ids.push(body_ids);
    }
    if ids[0] == ids[1] {
        failures.push(format!("one id for both: {:?}", ids[0]));
    }
    let still_reported = w.ids.iter().filter(|f| f[0] != 0).count();
    if (still_reported as f64) < STILL_ALL_FRAMES * FRAMES as f64 {
        failures.push(format!(
            "the still person reported in {still_reported} of {FRAMES} frames"
        ));
    }
    let max_people = w.people.iter().copied().max().unwrap_or(0);
    if max_people > 2 {
        failures.push(format!("{max_people} people reported in a frame"));
    }
    let heads: Vec<(usize, usize, f64)> = (0..FRAMES)
        .flat_map(|k| w.heads[k].iter().map(move |&(b, d)| (k, b, d)))
        .collect();
    let worst = heads.iter().map(|h| h.2).fold(0.0, f64::max);
    let off: Vec<String> = heads
        .iter()
        .filter(|h| h.2 > HEAD_M)
        .map(|(k, b, d)| format!("frame {k} body {b}: {:.1} cm", d * 100.0))
        .collect();
    eprintln!(
        "{name}: heads reported {}, worst {:.1} cm, more than {:.0} cm off: {off:?}; at most {max_people} people",
        heads.len(),
        worst * 100.0,
        HEAD_M * 100.0
    );
    if worst > HEAD_ANY_M || off.len() as f64 > HEAD_OFF_SHARE * heads.len() as f64 {
        failures.push(format!(
            "heads: worst {:.1} cm, {} of {} more than {:.0} cm off",
            worst * 100.0,
            off.len(),
            heads.len(),
            HEAD_M * 100.0
        ));
    }
    assert!(failures.is_empty(), "{name}: {failures:#?}");
}

#[test]
fn a_walker_passing_behind_a_still_person_keeps_its_own_id() {
    check("walker 0.9 m behind", 3.4, 1000, true);
}

#[test]
fn a_walker_passing_in_front_of_a_still_person_keeps_its_own_id() {
    check("walker 0.7 m in front", 1.8, 2000, false);
}
