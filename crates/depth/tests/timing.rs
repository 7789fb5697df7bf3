//! Timing of the per-frame paths on the human + robot scene (printed, never
//! asserted): `cargo test -p phri-depth --release --test timing -- --nocapture`.

mod common;

use std::time::{Duration, Instant};

use phri_depth::{
    CameraPose, DepthSpaceDistance, FlyingPixels, Intrinsics, PointOfInterest, RenderOptions,
    Renderer, Repulsion, RepulsionParams, SelfFilter, SelfFilterParams,
};

fn stats(mut v: Vec<Duration>) -> (f64, f64, f64) {
    v.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    (
        ms(v[v.len() / 2]),
        ms(v[v.len() * 9 / 10]),
        ms(v[v.len() - 1]),
    )
}

#[test]
fn timing_of_render_selffilter_and_distance() {
    let k = Intrinsics::default();
    let pose = CameraPose::paper_default();
    let s = common::scene();
    let mut renderer = Renderer::new(k, pose, RenderOptions::default()).unwrap();
    let mut filter = SelfFilter::new(k, pose, SelfFilterParams::default()).unwrap();
    let dist = DepthSpaceDistance::new(k, pose, RepulsionParams::default(), 0.001).unwrap();
    let flying = FlyingPixels::new(&k).unwrap();
    let points: Vec<PointOfInterest> = common::lwr_points_of_interest(&common::Q_REACH)
        .into_iter()
        .map(|(p, r)| PointOfInterest::new(p, r))
        .collect();

    let mut frame = vec![0u16; k.pixel_count()];
    let mut filtered = vec![0u16; k.pixel_count()];
    let mut labels = vec![0u16; k.pixel_count()];
    let mut out = vec![Repulsion::NONE; points.len()];
    let (mut t_render, mut t_flying, mut t_filter, mut t_dist) = (vec![], vec![], vec![], vec![]);
    let (mut removed, mut flown) = (0, 0);
    let mut considered = 0;
    let frames = 40;
    for i in 0..frames + 3 {
        let t0 = Instant::now();
        renderer
            .render(&s.all, &s.boxes, s.floor_z, &mut frame)
            .unwrap();
        let t_a = Instant::now();
        flown = flying.apply(&frame, &mut filtered).unwrap();
        frame.copy_from_slice(&filtered);
        let t1 = Instant::now();
        removed = filter.apply(&s.robot, &mut frame).unwrap();
        let t2 = Instant::now();
        dist.repulsions(&frame, &points, &mut out).unwrap();
        let t3 = Instant::now();
        considered = out.iter().map(|r| r.pixels_considered).sum::<usize>();
        if i >= 3 {
            t_render.push(t_a - t0);
            t_flying.push(t1 - t_a);
            t_filter.push(t2 - t1);
            t_dist.push(t3 - t2);
        }
    }
    renderer
        .render_labeled(&s.all, &s.boxes, s.floor_z, &mut frame, &mut labels)
        .unwrap();
    let n_robot = labels
        .iter()
        .filter(|&&l| l >= 1 && usize::from(l) <= s.robot.len())
        .count();
    let n_human = labels
        .iter()
        .filter(|&&l| usize::from(l) > s.robot.len() && usize::from(l) <= s.all.len())
        .count();
    let windows: usize = points
        .iter()
        .map(|p| dist.window(p).map_or(0, |w| w.len()))
        .sum();
    let (r50, r90, rmax) = stats(t_render);
    let (f50, f90, fmax) = stats(t_filter);
    let (y50, y90, ymax) = stats(t_flying);
    let (d50, d90, dmax) = stats(t_dist);
    eprintln!(
        "scene: {} capsules ({} robot, {} human), {} box, floor; {}x{}; robot pixels {n_robot}, human pixels {n_human}",
        s.all.len(),
        s.robot.len(),
        s.human.len(),
        s.boxes.len(),
        k.width,
        k.height
    );
    eprintln!("render (noise, edge drop-out): median {r50:.2} ms, p90 {r90:.2} ms, max {rmax:.2} ms over {frames} frames");
    eprintln!("flying pixels (into a copy, copied back): median {y50:.2} ms, p90 {y90:.2} ms, max {ymax:.2} ms ({flown} pixels removed)");
    eprintln!("self-filter: median {f50:.2} ms, p90 {f90:.2} ms, max {fmax:.2} ms ({removed} pixels removed)");
    eprintln!(
        "distance, {} points: median {d50:.2} ms, p90 {d90:.2} ms, max {dmax:.2} ms ({windows} window pixels, {considered} in regions)",
        points.len()
    );
    for (p, r) in points.iter().zip(&out) {
        eprintln!(
            "  P = ({:.3}, {:.3}, {:.3}) r = {:.3}: min distance {:.3} m, |v| = {:.4} m/s, {} pixels",
            p.position.x,
            p.position.y,
            p.position.z,
            p.radius,
            r.min_distance,
            r.v_call.norm(),
            r.pixels_considered
        );
    }
    assert!(
        n_robot > 1000 && n_human > 1000,
        "both robot and human visible"
    );
}

#[test]
fn timing_of_distance_on_a_crowded_frame() {
    // the worst case of eq. 15's occlusion rule: something 1 m from the
    // camera in every pixel, in front of every point, so that every pixel of
    // every point's window is in its region
    let k = Intrinsics::default();
    let pose = CameraPose::paper_default();
    let dist = DepthSpaceDistance::new(k, pose, RepulsionParams::default(), 0.001).unwrap();
    let points: Vec<PointOfInterest> = common::lwr_points_of_interest(&common::Q_REACH)
        .into_iter()
        .map(|(p, r)| PointOfInterest::new(p, r))
        .collect();
    let frame = vec![1000u16; k.pixel_count()];
    let mut out = vec![Repulsion::NONE; points.len()];
    let mut t = vec![];
    for i in 0..43 {
        let t0 = Instant::now();
        dist.repulsions(&frame, &points, &mut out).unwrap();
        if i >= 3 {
            t.push(t0.elapsed());
        }
    }
    let considered = out.iter().map(|r| r.pixels_considered).sum::<usize>();
    let (d50, d90, dmax) = stats(t);
    eprintln!(
        "distance on a crowded frame, {} points: median {d50:.2} ms, p90 {d90:.2} ms, max {dmax:.2} ms ({considered} pixels in regions, {:.2} ns each)",
        points.len(),
        d50 * 1e6 / considered as f64
    );
    assert!(out.iter().all(|r| r.pixels_considered > 1000));
}
