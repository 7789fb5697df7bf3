//! The tracker on the 12 real Kinect v1 frames of `../shared/data/kinect-person/`
//! (one person's upper body; a second person behind in the last two) against
//! hand labels (`fixtures/kinect-person-labels.toml`): head and both hands
//! within 10 cm in 3-D in every frame, each frame alone and as a 30 Hz sequence.

use std::collections::BTreeMap;
use std::path::PathBuf;

use phri_people::{Intrinsics, Joint, Person, Tracker, TrackerConfig, MAX_PEOPLE};
use serde::Deserialize;

/// The Kinect v1's nominal intrinsics (the data's README).
const K: Intrinsics = Intrinsics::KINECT_NOMINAL;
const TOLERANCE_M: f64 = 0.10;

#[derive(Deserialize)]
struct Labels {
    head: [usize; 2],
    left_hand: [usize; 2],
    right_hand: [usize; 2],
}

#[derive(Deserialize)]
struct Fixture {
    frames: BTreeMap<String, Labels>,
}

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/kinect-person")
}

fn load(name: &str) -> Vec<u16> {
    let bytes = std::fs::read(data_dir().join(name)).unwrap();
    assert_eq!(bytes.len(), 640 * 480 * 2, "{name}");
    bytes
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect()
}

/// A labelled pixel in 3-D: back-projected at the median depth of the 9×9 window around it.
fn label_point(depth: &[u16], [u, v]: [usize; 2]) -> [f64; 3] {
    let mut win: Vec<u16> = Vec::new();
    for y in v.saturating_sub(4)..(v + 5).min(480) {
        for x in u.saturating_sub(4)..(u + 5).min(640) {
            let d = depth[y * 640 + x];
            if d != 0 {
                win.push(d);
            }
        }
    }
    assert!(!win.is_empty(), "label ({u}, {v}) has no depth");
    win.sort_unstable();
    let z = f64::from(win[win.len() / 2]) / 1000.0;
    let p = K.back_project(u as f64, v as f64, z);
    [p.x, p.y, p.z]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Errors \[m\] of head, left hand, right hand of the reported person nearest
/// the labelled head (infinite for a joint not found).
fn errors(people: &[Person], truth: &[[f64; 3]; 3]) -> [f64; 3] {
    let Some(p) = people.iter().min_by(|a, b| {
        dist(a.joints[Joint::Head as usize], truth[0])
            .total_cmp(&dist(b.joints[Joint::Head as usize], truth[0]))
    }) else {
        return [f64::INFINITY; 3];
    };
    let mut e = [0.0; 3];
    for (k, j) in [Joint::Head, Joint::LeftHand, Joint::RightHand]
        .into_iter()
        .enumerate()
    {
        e[k] = if p.confidence[j as usize] > 0.0 {
            dist(p.joints[j as usize], truth[k])
        } else {
            f64::INFINITY
        };
    }
    e
}

fn run(sequence: bool) {
    assert!(
        data_dir().is_dir(),
        "{}: the real Kinect frames are missing beside the clone",
        data_dir().display()
    );
    let fixture: Fixture = toml::from_str(
        &std::fs::read_to_string(
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("tests/fixtures/kinect-person-labels.toml"),
        )
        .unwrap(),
    )
    .unwrap();
    assert_eq!(fixture.frames.len(), 12);
    let mut tracker = Tracker::new(K, TrackerConfig::default()).unwrap();
    let mut out = [Person::default(); MAX_PEOPLE];
    let mut failures = Vec::new();
    eprintln!(
        "{:<24} {:>8} {:>8} {:>8}  ({} frames, errors in cm)",
        "frame",
        "head",
        "l_hand",
        "r_hand",
        if sequence { "sequence" } else { "independent" }
    );
    for (name, labels) in &fixture.frames {
        let depth = load(name);
        let truth = [
            label_point(&depth, labels.head),
            label_point(&depth, labels.left_hand),
            label_point(&depth, labels.right_hand),
        ];
        if !sequence {
            tracker.reset();
        }
        let n = tracker.step(&depth, 1.0 / 30.0, &mut out).unwrap();
        let e = errors(&out[..n], &truth);
        eprintln!(
            "{name:<24} {:>8.1} {:>8.1} {:>8.1}  people {n}",
            e[0] * 100.0,
            e[1] * 100.0,
            e[2] * 100.0
        );
        for (k, what) in ["head", "left hand", "right hand"].iter().enumerate() {
            if !(e[k] <= TOLERANCE_M) {
                failures.push(format!("{name} {what}: {:.1} cm", e[k] * 100.0));
            }
        }
    }
    assert!(failures.is_empty(), "beyond 10 cm: {failures:#?}");
}

#[test]
fn head_and_hands_within_10_cm_each_frame_alone() {
    run(false);
}

#[test]
fn head_and_hands_within_10_cm_as_a_sequence() {
    run(true);
}
