//! Timing of the camera stand-in's frame and of ingestion on a person beside
//! the arm (printed, never asserted):
//! `cargo test -p phri-perception --release --test timing -- --nocapture`.

use std::time::{Duration, Instant};

use phri_config::Config;
use phri_ipc::{FrameHeader, WorldState, Zeroed};
use phri_perception::{CameraSim, Ingest, StateHistory};

const Q0: [f64; 7] = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];

/// Median, p90 and max [ms].
fn stats(mut v: Vec<Duration>) -> (f64, f64, f64) {
    v.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    (
        ms(v[v.len() / 2]),
        ms(v[v.len() * 9 / 10]),
        ms(v[v.len() - 1]),
    )
}

/// The arm at Q0 and a standing person (torso, head, an arm reaching in) 0.8 m in front.
fn world(seq: u64) -> WorldState {
    let mut w = WorldState::zeroed();
    w.seq = seq;
    w.stamp_ns = 1_000_000_000 + seq * 33_333_333;
    w.dof = 7;
    w.q[..7].copy_from_slice(&Q0);
    let parts: [([f64; 3], [f64; 3], f64); 5] = [
        ([0.8, -0.15, 0.28], [0.8, -0.15, 0.53], 0.15),
        ([0.8, -0.15, 0.76], [0.8, -0.15, 0.85], 0.10),
        ([0.8, 0.04, 0.65], [0.65, 0.0, 0.45], 0.05),
        ([0.65, 0.0, 0.45], [0.52, -0.16, 0.40], 0.04),
        ([0.8, -0.15, 0.15], [0.8, -0.15, -0.8], 0.12),
    ];
    w.n_human = parts.len() as u32;
    for (h, (a, b, r)) in w.human.iter_mut().zip(parts) {
        h.a = a;
        h.b = b;
        h.radius = r;
    }
    w
}

#[test]
fn timing_of_the_camera_and_ingestion() {
    let cfg = phri_config::Loaded::defaults();
    let model = cfg.model().unwrap();
    let mut camera = CameraSim::new(model.clone(), &Config::defaults().camera).unwrap();
    let mut ingest = Ingest::new(model, &Config::defaults().perception).unwrap();
    let mut frame = vec![0u16; camera.pixels()];
    let mut filtered = vec![0u16; camera.pixels()];
    let mut history = StateHistory::new(7, 10);
    let (mut t_camera, mut t_ingest) = (vec![], vec![]);
    let mut removed = 0;
    for seq in 1..=60u64 {
        let w = world(seq);
        history.push(w.stamp_ns, &Q0);
        let mut header = FrameHeader::zeroed();
        let t0 = Instant::now();
        camera.step(&w, 0, &mut frame, &mut header).unwrap();
        let t1 = Instant::now();
        let out = ingest
            .step(
                &mut header,
                &frame,
                &history,
                w.stamp_ns + 2_000_000,
                &mut filtered,
            )
            .unwrap();
        let t2 = Instant::now();
        removed = out.removed;
        if seq > 5 {
            t_camera.push(t1 - t0);
            t_ingest.push(t2 - t1);
        }
    }
    let (c50, c90, cmax) = stats(t_camera);
    let (i50, i90, imax) = stats(t_ingest);
    eprintln!("camera (render, noise): median {c50:.2} ms, p90 {c90:.2} ms, max {cmax:.2} ms");
    eprintln!(
        "ingestion (flying pixels, self-filter): median {i50:.2} ms, p90 {i90:.2} ms, max {imax:.2} ms ({removed} robot pixels removed)"
    );
}
