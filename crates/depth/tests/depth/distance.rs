//! Depth-space distances (paper eqs. 15-18) against Cartesian geometry, the
//! occlusion rule and a brute-force scan of the whole image.

use crate::common;

use crate::common::front_camera;
use nalgebra::{Point3, Vector3};
use phri_depth::{
    Aabb, CameraPose, Capsule, DepthError, DepthSpaceDistance, Intrinsics, PointOfInterest,
    RenderOptions, Renderer, Repulsion, RepulsionParams, SelfFilter, SelfFilterParams,
};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

const K: Intrinsics = Intrinsics::KINECT;

fn params() -> RepulsionParams {
    RepulsionParams::default()
}

fn render_ideal(
    pose: CameraPose,
    capsules: &[Capsule],
    boxes: &[Aabb],
    floor: Option<f64>,
) -> Vec<u16> {
    let mut r = Renderer::new(K, pose, RenderOptions::ideal()).unwrap();
    let mut out = vec![0; K.pixel_count()];
    r.render(capsules, boxes, floor, &mut out).unwrap();
    out
}

#[test]
fn repulsion_magnitude_follows_eq_16() {
    let p = params();
    assert_eq!((p.rho, p.v_max, p.alpha), (0.4, 0.21, 6.0));
    let e = std::f64::consts::E;
    // ‖D‖ = 0: V_max/(1 + e^−α)
    assert!((p.magnitude(0.0) - 0.21 / (1.0 + e.powf(-6.0))).abs() < 1e-15);
    assert!(p.magnitude(0.0) > 0.99 * 0.21);
    // ‖D‖ = ρ/2: V_max/2
    assert!((p.magnitude(0.2) - 0.105).abs() < 1e-15);
    // ‖D‖ = ρ: V_max/(1 + e^α)
    assert!((p.magnitude(0.4) - 0.21 / (1.0 + e.powf(6.0))).abs() < 1e-15);
    assert!(p.magnitude(0.4) < 0.003 * 0.21);
    // monotonically decreasing
    let mut last = f64::INFINITY;
    for i in 0..=100 {
        let v = p.magnitude(0.4 * f64::from(i) / 100.0);
        assert!(v < last);
        last = v;
    }
    assert!(RepulsionParams {
        rho: 0.0,
        ..params()
    }
    .validate()
    .is_err());
}

/// Distance from `p` to the nearest *visible* point, sampled finely: the
/// ground truth for the depth-space method, which only sees the front surface.
fn analytic(c: &Capsule, p: &Point3<f64>) -> f64 {
    c.distance_to_point(p)
}

#[test]
fn min_distance_matches_the_cartesian_distance_to_a_visible_obstacle() {
    // A vertical capsule 2 m in front of the camera, in front of nothing.
    let pose = front_camera();
    let obstacle = Capsule::new(Point3::new(2.0, 0.0, 0.7), Point3::new(2.0, 0.0, 1.3), 0.1);
    let frame = render_ideal(pose, &[obstacle], &[], None);
    let dist = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    // points of interest between the camera and the obstacle, and beside it,
    // so that its nearest point faces the camera (visible, not occluded)
    let cases = [
        (Point3::new(1.7, 0.0, 1.0), 0.0),
        (Point3::new(1.75, 0.15, 1.1), 0.0),
        (Point3::new(1.8, -0.1, 0.9), 0.0),
        (Point3::new(1.85, 0.0, 1.45), 0.0),
        (Point3::new(1.6, 0.05, 1.0), 0.06),
        (Point3::new(1.88, 0.0, 1.0), 0.0),
        (Point3::new(1.9, 0.2, 0.6), 0.05),
    ];
    for (position, radius) in cases {
        let poi = PointOfInterest::new(position, radius);
        let rep = dist.repulsion(&frame, &poi).unwrap();
        let truth = analytic(&obstacle, &position);
        let err = rep.center_distance - truth;
        // Tolerance. Every used pixel is a point of the visible surface, with
        // its depth rounded to the millimetre: each sample lies within
        // 0.5 mm · |ray| (< 0.6 mm) of the surface, so the result cannot be
        // below the truth by more than that. From above, the nearest sampled
        // point is at most half a pixel diagonal (d/f · √2/2 ≈ 2.7 mm at 2 m,
        // more on a slanted surface) from the true nearest point, and the
        // distance grows only quadratically away from its minimum; one pixel
        // footprint d/f bounds it for these points.
        let pixel = 2.0 / K.fx;
        eprintln!("P = {position}: error {:+.3} mm", err * 1e3);
        assert!(
            err > -0.6e-3 && err < 0.6e-3 + pixel,
            "P = {position}: depth space {:.5}, Cartesian {truth:.5}, error {:.2} mm",
            rep.center_distance,
            err * 1e3
        );
        assert!((rep.min_distance - (rep.center_distance - radius).max(0.0)).abs() < 1e-15);
        let o_min = rep.obstacle_point.unwrap();
        assert!(
            analytic(&obstacle, &o_min).abs() < 1e-3,
            "O_min {o_min} lies on the obstacle surface"
        );
        assert!(((o_min - position).norm() - rep.center_distance).abs() < 1e-12);
        // magnitude (17): v at the clearance
        assert!((rep.v_call.norm() - params().magnitude(rep.min_distance)).abs() < 1e-12);
        assert!(rep.pixels_considered > 0);
    }
}

#[test]
fn points_of_interest_beside_the_obstacle_at_its_depth() {
    // P level with the obstacle's axis: the obstacle's nearest point is just
    // behind its silhouette (hidden), the visible silhouette pixels are nearer
    // than P and are moved to P's depth (occlusion rule), which pushes them
    // slightly outwards (by 0.25 mm here). The last pixel column that still hits
    // the obstacle lies up to one pixel footprint (d/f = 3.8 mm at 2 m) inside
    // the silhouette, so the result is within one footprint of the truth.
    let pose = front_camera();
    let obstacle = Capsule::new(Point3::new(2.0, 0.0, 0.7), Point3::new(2.0, 0.0, 1.3), 0.1);
    let frame = render_ideal(pose, &[obstacle], &[], None);
    let dist = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    for y in [0.2, 0.25, -0.3] {
        let p = Point3::new(2.0, y, 1.0);
        let rep = dist
            .repulsion(&frame, &PointOfInterest::new(p, 0.0))
            .unwrap();
        let truth = analytic(&obstacle, &p);
        let err = rep.center_distance - truth;
        let pixel = 2.0 / K.fx;
        assert!(err.abs() < pixel, "y = {y}: error {:.2} mm", err * 1e3);
    }
}

#[test]
fn occluded_point_uses_the_point_of_interest_depth() {
    // An obstacle sphere 1.5 m from the camera hides the point of interest
    // 2.5 m away on (nearly) the same pixel: d_o < d_p, so d_o := d_p.
    let pose = CameraPose::paper_default();
    let (pu, pv, d_p) = (320.3, 240.2, 2.5);
    let p = pose.back_project(&K, pu, pv, d_p);
    let sphere = Capsule::sphere(pose.back_project(&K, pu, pv, 1.5), 0.1);
    let frame = render_ideal(pose, &[sphere], &[], None);
    let dist = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    let radius = 0.001;
    let rep = dist
        .repulsion(&frame, &PointOfInterest::new(p, radius))
        .unwrap();
    // with d_o = d_p: D = (((o_x − c_x) − (p_x − c_x)) d_p/f_x, ((o_y − c_y) − (p_y − c_y)) d_p/f_y, 0);
    // the nearest pixel centre to (320.3, 240.2) is (320, 240)
    let dx = ((320.0 - K.cx) * d_p / K.fx) - ((pu - K.cx) * d_p / K.fx);
    let dy = ((240.0 - K.cy) * d_p / K.fy) - ((pv - K.cy) * d_p / K.fy);
    let expected = (dx * dx + dy * dy).sqrt();
    assert!(
        (rep.center_distance - expected).abs() < 1e-12,
        "{} vs {expected}",
        rep.center_distance
    );
    assert!((expected - 2.5 * (0.3f64.hypot(0.2)) / 525.0).abs() < 1e-12);
    assert!((rep.min_distance - (expected - radius)).abs() < 1e-12);
    let o_min = rep.obstacle_point.unwrap();
    assert!((o_min - pose.back_project(&K, 320.0, 240.0, d_p)).norm() < 1e-12);
    // every sphere pixel moved to 2.5 m lies within ρ of P
    let sphere_pixels = frame.iter().filter(|&&d| d > 0).count();
    assert_eq!(rep.pixels_considered, sphere_pixels);
    // while the Cartesian distance to the sphere is about 0.9 m: conservative
    assert!(analytic(&sphere, &p) > 0.89);
    // the surface the camera saw is its front half: its silhouette, about
    // 1.5 − r²/1.5 m deep and r wide, is the nearest of it to P (1.012 m),
    // more than the sphere's hidden back (0.9 m)
    let silhouette = (1.0f64 + 0.1 * 0.1 / 1.5).hypot(0.1) - radius;
    assert!(
        (rep.surface_distance - silhouette).abs() < 3e-3,
        "{} {silhouette}",
        rep.surface_distance
    );
    assert!(rep.surface_distance > analytic(&sphere, &p) - radius);
    // the obstacle behind P instead (nothing in front): the plain distance
    let behind = Capsule::sphere(pose.back_project(&K, pu, pv, 2.8), 0.1);
    let frame = render_ideal(pose, &[behind], &[], None);
    let rep = dist
        .repulsion(&frame, &PointOfInterest::new(p, 0.0))
        .unwrap();
    assert!(
        (rep.center_distance - 0.2).abs() < 1e-3,
        "{}",
        rep.center_distance
    );
    // nothing hidden: the surface seen is the nearest obstacle point
    assert_eq!(rep.surface_distance, rep.min_distance);
}

/// The clearance from `poi`'s sphere to the nearest valid pixel of the
/// whole image (intrinsics `k`), each at its own depth \[m\].
fn brute_force_surface(
    k: &Intrinsics,
    frame: &[u16],
    pose: &CameraPose,
    poi: &PointOfInterest,
) -> f64 {
    let mut best = f64::INFINITY;
    for v in 0..k.height as usize {
        for u in 0..k.width as usize {
            let raw = frame[v * k.width as usize + u];
            if raw != 0 {
                let o = pose.back_project(k, u as f64, v as f64, f64::from(raw) * 1e-3);
                best = best.min((o - poi.position).norm());
            }
        }
    }
    (best - poi.radius).max(0.0)
}

/// The scan's surface seen (`rep`) against the whole image's nearest
/// pixel `all` \[m\] (of `what`): never nearer, and that pixel when it lies
/// within 10 cm (the scan's window holds it); whether it did.
fn surface_is_the_nearest_pixel(rep: &Repulsion, all: f64, what: &str) -> bool {
    assert!(
        rep.surface_distance >= all - 1e-9,
        "{what}: {} {all}",
        rep.surface_distance
    );
    let near = all < 0.1;
    if near {
        assert!(
            (rep.surface_distance - all).abs() < 1e-9,
            "{what}: {} {all}",
            rep.surface_distance
        );
    }
    near
}

#[test]
fn repulsion_points_away_from_the_obstacle() {
    let pose = front_camera();
    let obstacle = Capsule::new(Point3::new(2.0, 0.0, 0.7), Point3::new(2.0, 0.0, 1.3), 0.1);
    let frame = render_ideal(pose, &[obstacle], &[], None);
    let dist = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    // straight in front: by symmetry the push is towards the camera (−x)
    let rep = dist
        .repulsion(
            &frame,
            &PointOfInterest::new(Point3::new(1.75, 0.0, 1.0), 0.0),
        )
        .unwrap();
    let dir = rep.v_call.normalize();
    assert!(dir.x < -0.99, "{dir}");
    assert!((rep.v_call.norm() - params().magnitude(0.15)).abs() < 2e-3 * params().v_max);
    // in front and to the side: away from the nearest point, and from the axis
    for p in [
        Point3::new(1.75, 0.15, 1.1),
        Point3::new(1.8, -0.12, 0.75),
        Point3::new(1.85, 0.0, 1.5),
    ] {
        let rep = dist
            .repulsion(&frame, &PointOfInterest::new(p, 0.0))
            .unwrap();
        let away = (p - obstacle.closest_axis_point(&p)).normalize();
        let dir = rep.v_call.normalize();
        assert!(dir.dot(&away) > 0.8, "P = {p}: push {dir}, away {away}");
        let from_nearest = (p - rep.obstacle_point.unwrap()).normalize();
        assert!(dir.dot(&from_nearest) > 0.5);
    }
    // the magnitude grows as P approaches
    let mut last = 0.0;
    for x in [1.55, 1.65, 1.75, 1.85] {
        let v = dist
            .repulsion(&frame, &PointOfInterest::new(Point3::new(x, 0.0, 1.0), 0.0))
            .unwrap()
            .v_call
            .norm();
        assert!(v > last);
        last = v;
    }
}

#[test]
fn nothing_in_range_gives_no_repulsion() {
    let pose = front_camera();
    let dist = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    let empty = vec![0u16; K.pixel_count()];
    let poi = PointOfInterest::new(Point3::new(2.0, 0.0, 1.0), 0.05);
    assert_eq!(dist.repulsion(&empty, &poi).unwrap(), Repulsion::NONE);
    // an obstacle 0.6 m away (> ρ + radius)
    let far = Capsule::sphere(Point3::new(2.0, 0.65, 1.0), 0.05);
    let frame = render_ideal(pose, &[far], &[], None);
    let rep = dist.repulsion(&frame, &poi).unwrap();
    assert_eq!(rep, Repulsion::NONE);
    assert_eq!(rep.min_distance, f64::INFINITY);
    // a point far outside the field of view
    let outside = PointOfInterest::new(Point3::new(2.0, 5.0, 1.0), 0.05);
    assert!(dist.window(&outside).is_none());
    assert_eq!(dist.repulsion(&frame, &outside).unwrap(), Repulsion::NONE);
}

/// The rules of REFERENCE §3 written out over the whole image, in pixel form.
fn brute_force(
    frame: &[u16],
    pose: &CameraPose,
    prm: &RepulsionParams,
    poi: &PointOfInterest,
    scale: f64,
) -> (f64, usize, Vector3<f64>, f64) {
    let p = pose.to_camera(&poi.position);
    let d_p = p.z;
    let (p_x, p_y) = (K.fx * p.x / p.z + K.cx, K.fy * p.y / p.z + K.cy);
    let reach = prm.rho + poi.radius;
    let (mut best, mut count, mut sum) = (f64::INFINITY, 0, Vector3::zeros());
    let mut weights = 0.0;
    for o_y in 0..K.height as usize {
        for o_x in 0..K.width as usize {
            let raw = frame[o_y * K.width as usize + o_x];
            if raw == 0 {
                continue;
            }
            let mut d_o = f64::from(raw) * scale;
            if d_o > d_p + reach {
                continue;
            }
            if d_o < d_p {
                d_o = d_p;
            }
            let (ox, oy) = (o_x as f64, o_y as f64);
            let d = Vector3::new(
                (ox - K.cx) * d_o / K.fx - (p_x - K.cx) * d_p / K.fx,
                (oy - K.cy) * d_o / K.fy - (p_y - K.cy) * d_p / K.fy,
                d_o - d_p,
            );
            let n = d.norm();
            if n > reach {
                continue;
            }
            count += 1;
            best = best.min(n);
            if n > 0.0 {
                let w = prm.magnitude((n - poi.radius).max(0.0));
                sum -= d / n * w;
                weights += w;
            }
        }
    }
    let v = if count > 0 && sum.norm() > 0.0 {
        pose.vector_to_base(&(sum.normalize() * prm.magnitude((best - poi.radius).max(0.0))))
    } else {
        Vector3::zeros()
    };
    // how much larger the contributions are than their sum: the factor by
    // which their rounding grows in the sum's direction
    let spread = if sum.norm() > 0.0 {
        (weights / sum.norm()).max(1.0)
    } else {
        1.0
    };
    (best, count, v, spread)
}

#[test]
fn windowed_computation_equals_a_brute_force_scan_of_the_whole_image() {
    // the window loses no pixel, wherever P projects (image centre, borders,
    // outside the image, near the camera)
    let pose = CameraPose::paper_default();
    let scene = common::scene();
    let mut renderer = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let mut frame = vec![0u16; K.pixel_count()];
    renderer
        .render(&scene.all, &scene.boxes, scene.floor_z, &mut frame)
        .unwrap();
    SelfFilter::new(K, pose, SelfFilterParams::default())
        .unwrap()
        .apply(&scene.robot, &mut frame)
        .unwrap();
    let prm = params();
    let dist = DepthSpaceDistance::new(K, pose, prm, 0.001).unwrap();
    let mut rng = SmallRng::seed_from_u64(3);
    let mut points: Vec<PointOfInterest> = common::lwr_points_of_interest(&common::Q_REACH)
        .into_iter()
        .map(|(p, r)| PointOfInterest::new(p, r))
        .collect();
    for _ in 0..40 {
        // random pixels (some outside the image) at random depths
        let u = rng.gen_range(-80.0..720.0);
        let v = rng.gen_range(-60.0..540.0);
        let d = rng.gen_range(0.2..4.0);
        let r = if rng.gen_bool(0.5) {
            0.0
        } else {
            rng.gen_range(0.0..0.08)
        };
        points.push(PointOfInterest::new(pose.back_project(&K, u, v, d), r));
    }
    let (mut nonempty, mut near) = (0, 0);
    for poi in &points {
        let rep = dist.repulsion(&frame, poi).unwrap();
        let (best, count, v, spread) = brute_force(&frame, &pose, &prm, poi, 0.001);
        assert_eq!(rep.pixels_considered, count, "P = {}", poi.position);
        if count > 0 {
            nonempty += 1;
            // same rules, same pixels; only the floating-point evaluation
            // differs (each pixel's weight in single precision: 1e-7 of
            // it, grown by how much the contributions cancel in their sum)
            assert!((rep.center_distance - best).abs() < 1e-12);
            let err = (rep.v_call - v).norm();
            assert!(err < 1e-6 * prm.v_max * spread, "{err} (spread {spread})");
            // the surface seen: never nearer than the whole image's nearest
            // pixel, and that pixel when it is near (the window holds it)
            let all = brute_force_surface(&K, &frame, &pose, poi);
            near += usize::from(surface_is_the_nearest_pixel(&rep, all, "synthetic"));
        }
    }
    assert!(nonempty > 20);
    assert!(near > 3, "{near}");
}

/// The surface seen on the real Kinect v1 frames of
/// `../shared/data/kinect-person/` (a person at 0.7-2 m, the background
/// removed; the nominal intrinsics f = 580 px, c = (320, 240)): at points
/// around the person, the scan's nearest surface is never nearer than the
/// whole frame's nearest pixel, and is that pixel when it is near.
#[test]
fn the_surface_seen_on_real_kinect_frames_is_the_nearest_pixel() {
    let k = Intrinsics::KINECT_NOMINAL;
    let pose = CameraPose::paper_default();
    let dist = DepthSpaceDistance::new(k, pose, params(), 0.001).unwrap();
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/kinect-person");
    let mut rng = SmallRng::seed_from_u64(11);
    let (mut frames, mut near) = (0, 0);
    for name in [
        "depth-data-1028894671",
        "depth-data-1064898470",
        "depth-data-1166565565",
    ] {
        let bytes = std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let frame: Vec<u16> = bytes
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        assert_eq!(frame.len(), k.pixel_count(), "{name}");
        frames += 1;
        let valid: Vec<usize> = (0..frame.len()).filter(|&i| frame[i] != 0).collect();
        assert!(valid.len() > 10_000, "{name}: {} pixels", valid.len());
        for _ in 0..15 {
            // beside a pixel of the person: off its surface by up to 15 cm
            let i = valid[rng.gen_range(0..valid.len())];
            let (u, v) = ((i % 640) as f64, (i / 640) as f64);
            let o = pose.back_project(&k, u, v, f64::from(frame[i]) * 1e-3);
            let off = Vector3::new(
                rng.gen_range(-0.15..0.15),
                rng.gen_range(-0.15..0.15),
                rng.gen_range(-0.15..0.15),
            );
            let poi = PointOfInterest::new(o + off, rng.gen_range(0.0..0.06));
            let rep = dist.repulsion(&frame, &poi).unwrap();
            let all = brute_force_surface(&k, &frame, &pose, &poi);
            near += usize::from(surface_is_the_nearest_pixel(&rep, all, name));
        }
    }
    assert_eq!(frames, 3);
    assert!(near > 20, "{near}");
}

#[test]
fn depth_scale_and_batch_calls_agree() {
    let pose = CameraPose::paper_default();
    let scene = common::scene();
    let frame = render_ideal(pose, &scene.human, &scene.boxes, scene.floor_z);
    // the same scene in TUM units (1/5000 m): identical geometry
    let tum: Vec<u16> = frame
        .iter()
        .map(|&d| (u32::from(d) * 5).min(65535) as u16)
        .collect();
    let mm = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    let fifth = DepthSpaceDistance::new(K, pose, params(), 0.0002).unwrap();
    let points: Vec<PointOfInterest> = common::lwr_points_of_interest(&common::Q_REACH)
        .into_iter()
        .map(|(p, r)| PointOfInterest::new(p, r))
        .collect();
    let mut batch = vec![Repulsion::NONE; points.len()];
    mm.repulsions(&frame, &points, &mut batch).unwrap();
    for (poi, b) in points.iter().zip(&batch) {
        let single = mm.repulsion(&frame, poi).unwrap();
        assert_eq!(&single, b);
        let t = fifth.repulsion(&tum, poi).unwrap();
        assert_eq!(t.pixels_considered, single.pixels_considered);
        assert!((t.center_distance - single.center_distance).abs() < 1e-9);
    }
    let mut short = vec![Repulsion::NONE; 2];
    assert!(matches!(
        mm.repulsions(&frame, &points, &mut short),
        Err(DepthError::Count { .. })
    ));
}

#[test]
fn bad_input_is_an_error() {
    let dist = DepthSpaceDistance::new(K, front_camera(), params(), 0.001).unwrap();
    let frame = vec![0u16; K.pixel_count()];
    assert!(matches!(
        dist.repulsion(&frame[1..], &PointOfInterest::new(Point3::origin(), 0.0)),
        Err(DepthError::FrameSize { .. })
    ));
    let points = [
        PointOfInterest::new(Point3::new(1.0, 0.0, 1.0), 0.0),
        PointOfInterest::new(Point3::new(f64::NAN, 0.0, 1.0), 0.0),
    ];
    let mut out = [Repulsion::NONE; 2];
    assert!(matches!(
        dist.repulsions(&frame, &points, &mut out),
        Err(DepthError::PointOfInterest { index: 1 })
    ));
    assert!(dist
        .repulsion(&frame, &PointOfInterest::new(Point3::origin(), -0.1))
        .is_err());
    assert!(DepthSpaceDistance::new(K, front_camera(), params(), 0.0).is_err());
    // points near or behind the camera are fine
    let wall = render_ideal(
        front_camera(),
        &[],
        &[Aabb::new(
            Point3::new(0.7, -3.0, -3.0),
            Point3::new(0.8, 3.0, 3.0),
        )],
        None,
    );
    for x in [0.1, 0.0, -0.2] {
        let rep = dist
            .repulsion(&wall, &PointOfInterest::new(Point3::new(x, 0.0, 1.0), 0.0))
            .unwrap();
        let expected = 0.7 - x;
        if expected <= 0.4 {
            assert!((rep.center_distance - expected).abs() < 1e-3, "x = {x}");
        } else {
            assert_eq!(rep, Repulsion::NONE);
        }
    }
}

#[test]
fn the_window_holds_pixels_a_centred_square_would_miss() {
    // P off to the left of the field of view (camera frame (−2.6, 0, 4)), an
    // obstacle reading at the image's left edge, 0.394 m from P: inside ρ.
    let pose = front_camera();
    let p_cam = Point3::new(-2.6, 0.0, 4.0);
    let (u, v) = (37usize, 240usize);
    let ray = K.ray(u as f64, v as f64);
    // the point of the pixel's ray nearest to P, and its depth
    let depth = p_cam.coords.dot(&ray) / ray.norm_squared();
    let o = ray * (depth * 1000.0).round() / 1000.0;
    let truth = (o - p_cam.coords).norm();
    assert!(truth < 0.4 && depth > p_cam.z);
    let mut frame = vec![0u16; K.pixel_count()];
    frame[v * K.width as usize + u] = (depth * 1000.0).round() as u16;
    let dist = DepthSpaceDistance::new(K, pose, params(), 0.001).unwrap();
    let rep = dist
        .repulsion(&frame, &PointOfInterest::new(pose.to_base(&p_cam), 0.0))
        .unwrap();
    assert_eq!(rep.pixels_considered, 1);
    assert!((rep.center_distance - truth).abs() < 1e-12);
    // REFERENCE's square of half-size ρ f/(d_p − ρ) around p_x ends before column 37
    let p_x = K.fx * p_cam.x / p_cam.z + K.cx;
    assert!(p_x + 0.4 * K.fx / (p_cam.z - 0.4) < u as f64);
}
