//! Time per 640×480 frame of the tracker, p50 and p99, on one core:
//! the 12 real Kinect frames of `../shared/data/kinect-person/` (if present)
//! and rendered frames of two capsule people with the floor (RANSAC).
//!
//! `cargo run --release -p phri-people --example bench [-- ROUNDS]`

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::{Point3, Vector3};
use phri_depth::{CameraPose, Capsule, Intrinsics, RenderOptions, Renderer};
use phri_people::{FloorMode, Person, Tracker, TrackerConfig, MAX_PEOPLE};

fn percentile(sorted: &[f64], q: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

fn time_frames(
    name: &str,
    tracker: &mut Tracker,
    frames: &[Vec<u16>],
    rounds: usize,
    sequence: bool,
) {
    let mut out = [Person::default(); MAX_PEOPLE];
    let mut ms = Vec::with_capacity(frames.len() * rounds);
    let mut people = 0usize;
    for _ in 0..rounds {
        for f in frames {
            if !sequence {
                tracker.reset();
            }
            let t0 = Instant::now();
            let n = tracker.step(f, 1.0 / 30.0, &mut out).unwrap();
            ms.push(t0.elapsed().as_secs_f64() * 1e3);
            people += n;
        }
    }
    ms.sort_by(f64::total_cmp);
    println!(
        "{name:<36} frames {:>5}  p50 {:.3} ms  p99 {:.3} ms  max {:.3} ms  people/frame {:.2}",
        ms.len(),
        percentile(&ms, 0.5),
        percentile(&ms, 0.99),
        ms[ms.len() - 1],
        people as f64 / ms.len() as f64
    );
}

/// Capsules of a standing person at `(x, y)` facing −x (the camera), one hand raised.
fn person(x: f64, y: f64, raise: f64) -> Vec<Capsule> {
    let p = |f: f64, l: f64, u: f64| Point3::new(x - f, y - l, u);
    let mut c = vec![
        Capsule::new(p(0.0, 0.0, 1.56), p(0.0, 0.0, 1.65), 0.10),
        Capsule::new(p(0.0, 0.0, 1.08), p(0.0, 0.0, 1.33), 0.15),
        Capsule::new(p(0.0, -0.08, 0.95), p(0.0, 0.08, 0.95), 0.12),
    ];
    for s in [1.0, -1.0] {
        c.push(Capsule::new(
            p(0.0, s * 0.1, 0.88),
            p(0.0, s * 0.1, 0.1),
            0.07,
        ));
        let sh = p(0.0, s * 0.19, 1.45);
        let (el, wr) = if s > 0.0 {
            (
                p(0.0, 0.42, 1.45 + 0.2 * raise),
                p(0.05, 0.5, 1.45 + 0.45 * raise),
            )
        } else {
            (p(0.0, -0.26, 1.16), p(0.02, -0.33, 0.89))
        };
        c.push(Capsule::new(sh, el, 0.05));
        c.push(Capsule::new(el, wr, 0.045));
    }
    c
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(40);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/kinect-person");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    names.retain(|p| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("depth-data-"))
    });
    names.sort();
    let real: Vec<Vec<u16>> = names
        .iter()
        .filter_map(|p| std::fs::read(p).ok())
        .filter(|b| b.len() == 640 * 480 * 2)
        .map(|b| {
            b.chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .collect()
        })
        .collect();
    let kinect580 = Intrinsics::KINECT_NOMINAL;
    if real.is_empty() {
        println!("no real frames in {}", dir.display());
    } else {
        let mut t = Tracker::new(kinect580, TrackerConfig::default()).unwrap();
        time_frames(
            "real Kinect frames, each alone",
            &mut t,
            &real,
            rounds,
            false,
        );
        time_frames(
            "real Kinect frames, as a sequence",
            &mut t,
            &real,
            rounds,
            true,
        );
    }

    // two people walking toward each other in front of the camera
    let k = Intrinsics::KINECT;
    let pose = CameraPose::look_at(
        &Point3::new(0.0, 0.0, 1.3),
        &Point3::new(3.0, 0.0, 1.0),
        &Vector3::z(),
    )
    .unwrap();
    let mut r = Renderer::new(k, pose, RenderOptions::default()).unwrap();
    let mut rendered = Vec::new();
    for i in 0..60 {
        let s = i as f64 / 60.0;
        let mut caps = person(2.6, 0.9 - 0.3 * s, s);
        caps.extend(person(3.0, -0.9 + 0.3 * s, 1.0 - s));
        let mut out = vec![0u16; k.pixel_count()];
        r.reseed(i);
        r.render(&caps, &[], Some(0.0), &mut out).unwrap();
        rendered.push(out);
    }
    let up = pose.rotation().transpose() * Vector3::z();
    let cfg = TrackerConfig {
        up_camera: [up.x, up.y, up.z],
        floor: FloorMode::Ransac,
        ..TrackerConfig::default()
    };
    let mut t = Tracker::new(k, cfg).unwrap();
    time_frames(
        "rendered, two people, floor RANSAC",
        &mut t,
        &rendered,
        rounds.div_ceil(5),
        true,
    );
    let mut t = Tracker::new(
        k,
        TrackerConfig {
            floor: FloorMode::None,
            ..cfg
        },
    )
    .unwrap();
    let mut t2 = Tracker::new(k, cfg).unwrap();
    // the floor given (as a service with a calibrated camera would)
    let mut o = [Person::default(); MAX_PEOPLE];
    t2.step(&rendered[0], 0.0, &mut o).unwrap();
    if let Some(p) = t2.floor() {
        t = Tracker::new(
            k,
            TrackerConfig {
                floor: FloorMode::Given(p),
                ..cfg
            },
        )
        .unwrap();
    }
    time_frames(
        "rendered, two people, floor given",
        &mut t,
        &rendered,
        rounds.div_ceil(5),
        true,
    );
}
