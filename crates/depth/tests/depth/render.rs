//! The z-buffer renderer against analytic ray intersections.

use crate::common;

use crate::common::{front_camera, pixel_ray, sphere_trace};
use nalgebra::{Point3, Vector3};
use phri_depth::{
    sigma_z, Aabb, CameraPose, Capsule, DepthError, Intrinsics, RenderOptions, Renderer, LABEL_NONE,
};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

const K: Intrinsics = Intrinsics::KINECT;

fn frame() -> Vec<u16> {
    vec![0; K.pixel_count()]
}

fn ideal(pose: CameraPose) -> Renderer {
    Renderer::new(K, pose, RenderOptions::ideal()).unwrap()
}

fn idx(u: usize, v: usize) -> usize {
    v * K.width as usize + u
}

/// Half a millimetre of rounding plus floating-point slack \[m\].
const MM_ROUNDING: f64 = 0.5e-3 + 1e-9;

#[test]
fn sphere_centre_pixel_depth_is_the_analytic_intersection() {
    let pose = CameraPose::paper_default();
    let mut r = ideal(pose);
    let mut out = frame();
    for (u, v, depth, radius) in [
        (300usize, 200usize, 2.0, 0.1),
        (50, 400, 1.2, 0.05),
        (600, 30, 3.5, 0.3),
    ] {
        let c_cam = K.back_project(u as f64, v as f64, depth);
        let sphere = Capsule::sphere(pose.to_base(&c_cam), radius);
        r.render(&[sphere], &[], None, &mut out).unwrap();
        // along the pixel's ray the entry is |c| − R from the centre of
        // projection; its depth is that distance over the ray's length per
        // metre of depth
        let ray_len = K.ray(u as f64, v as f64).norm();
        let expected = (c_cam.coords.norm() - radius) / ray_len;
        let exact = r.exact_depth()[idx(u, v)];
        assert!((exact - expected).abs() < 1e-9, "{exact} vs {expected}");
        let measured = f64::from(out[idx(u, v)]) / 1000.0;
        assert!(
            (measured - expected).abs() <= MM_ROUNDING,
            "{measured} vs {expected}"
        );
    }
}

#[test]
fn capsule_depths_match_sphere_tracing_on_every_pixel() {
    let pose = CameraPose::paper_default();
    let mut r = ideal(pose);
    let mut out = frame();
    let o = pose.position();
    let mut rng = SmallRng::seed_from_u64(11);
    for case in 0..6 {
        let centre = Point3::new(
            rng.gen_range(-0.3..0.8),
            rng.gen_range(-0.5..0.5),
            rng.gen_range(0.1..0.9),
        );
        let axis = Vector3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        )
        .normalize()
            * rng.gen_range(0.0..0.4);
        // case 0: a capsule along the line of sight
        let axis = if case == 0 {
            (centre - o).normalize() * 0.3
        } else {
            axis
        };
        let c = Capsule::new(centre - axis, centre + axis, rng.gen_range(0.03..0.15));
        r.render(&[c], &[], None, &mut out).unwrap();
        let mut hits = 0;
        for v in (0..480).step_by(2) {
            for u in (0..640).step_by(2) {
                let dir = pixel_ray(&K, &pose, u, v);
                let (traced, closest) = sphere_trace(&o, &dir, &c, 10.0);
                let exact = r.exact_depth()[idx(u, v)];
                match traced {
                    Some(t) => {
                        hits += 1;
                        assert!(
                            (exact - t).abs() < 1e-6,
                            "case {case} pixel ({u}, {v}): rendered {exact}, traced {t}"
                        );
                        assert!((f64::from(out[idx(u, v)]) / 1000.0 - t).abs() <= MM_ROUNDING);
                    }
                    None if exact.is_finite() => {
                        // only a grazing ray may disagree
                        assert!(
                            closest < 1e-6,
                            "case {case} ({u}, {v}): rendered {exact}, trace missed by {closest}"
                        );
                    }
                    None => assert_eq!(out[idx(u, v)], 0),
                }
            }
        }
        assert!(
            hits > 20,
            "case {case}: capsule visible ({hits} sampled pixels)"
        );
    }
}

#[test]
fn pixels_off_the_capsule_read_zero_or_the_floor() {
    let pose = CameraPose::paper_default();
    let o = pose.position();
    let mut r = ideal(pose);
    let mut out = frame();
    let mut labels = frame();
    let c = Capsule::new(Point3::new(0.3, 0.0, 0.2), Point3::new(0.3, 0.0, 0.9), 0.08);
    r.render_labeled(&[c], &[], None, &mut out, &mut labels)
        .unwrap();
    let mut on = 0;
    for i in 0..out.len() {
        if labels[i] == 1 {
            on += 1;
            assert!(out[i] > 0);
        } else {
            assert_eq!(labels[i], LABEL_NONE);
            assert_eq!(out[i], 0, "nothing but the capsule in the scene");
        }
    }
    assert!(on > 1000);

    r.render_labeled(&[c], &[], Some(0.0), &mut out, &mut labels)
        .unwrap();
    let mut floor = 0;
    for v in 0..480 {
        for u in 0..640 {
            let i = idx(u, v);
            let dir = pixel_ray(&K, &pose, u, v);
            let t_floor = (0.0 - o.z) / dir.z;
            match labels[i] {
                1 => {
                    // the capsule is in front of the floor there
                    assert!(t_floor <= 0.0 || r.exact_depth()[i] < t_floor);
                }
                2 => {
                    floor += 1;
                    // relative: rays near the horizon meet the floor far away
                    let e = (r.exact_depth()[i] - t_floor).abs();
                    assert!(e < 1e-9 * t_floor * t_floor, "({u}, {v}): {e} at {t_floor}");
                    if out[i] != 0 {
                        assert!((f64::from(out[i]) / 1000.0 - t_floor).abs() <= MM_ROUNDING);
                    } else {
                        assert!(t_floor > 4.5, "only beyond range");
                    }
                }
                _ => {
                    assert!(
                        t_floor <= 0.0 || !t_floor.is_finite(),
                        "rays up miss the floor"
                    );
                    assert_eq!(out[i], 0);
                }
            }
        }
    }
    assert!(floor > 100_000);
}

#[test]
fn a_near_capsule_hides_a_far_one() {
    let pose = front_camera();
    let near = Capsule::new(Point3::new(1.5, -0.3, 1.0), Point3::new(1.5, 0.3, 1.0), 0.1);
    let far = Capsule::new(Point3::new(3.0, 0.0, 0.6), Point3::new(3.0, 0.0, 1.4), 0.15);
    let mut r = ideal(pose);
    let (mut out_a, mut out_b, mut labels) = (frame(), frame(), frame());
    r.render_labeled(&[near, far], &[], None, &mut out_a, &mut labels)
        .unwrap();
    // the optical axis crosses both: the near one wins
    let centre = idx(319, 239);
    assert_eq!(labels[centre], 1);
    let expected_near = 1.4; // front of the horizontal capsule at x = 1.5, radius 0.1
    assert!((r.exact_depth()[centre] - expected_near).abs() < 1e-3);
    // the far one is still seen above the near one
    let above = pose.project(&K, &Point3::new(3.0, 0.0, 1.3)).unwrap();
    let i = idx(above.px.round() as usize, above.py.round() as usize);
    assert_eq!(labels[i], 2);
    assert!((r.exact_depth()[i] - 2.85).abs() < 0.01);
    // order of the list does not matter
    r.render(&[far, near], &[], None, &mut out_b).unwrap();
    assert_eq!(out_a, out_b);
    // no pixel shows the far capsule where the near one is in front
    let both = out_a
        .iter()
        .zip(&labels)
        .filter(|(_, &l)| l == 2)
        .all(|(&d, _)| f64::from(d) / 1000.0 > 2.8);
    assert!(both);
}

#[test]
fn table_top_and_side_depths_are_analytic() {
    let pose = front_camera();
    let o = pose.position();
    let table = Aabb::new(Point3::new(1.5, -0.5, 0.0), Point3::new(2.5, 0.5, 0.75));
    let mut r = ideal(pose);
    let (mut out, mut labels) = (frame(), frame());
    r.render_labeled(&[], &[table], Some(0.0), &mut out, &mut labels)
        .unwrap();
    let (mut top, mut side) = (0, 0);
    for v in 0..480 {
        for u in 0..640 {
            let i = idx(u, v);
            if labels[i] != 1 {
                continue;
            }
            let dir = pixel_ray(&K, &pose, u, v);
            let t_top = (0.75 - o.z) / dir.z;
            let t_front = (1.5 - o.x) / dir.x;
            let p_top = o + dir * t_top;
            let d = r.exact_depth()[i];
            if (d - t_top).abs() < 1e-9 {
                top += 1;
                let tol = 1e-9;
                assert!(
                    p_top.x > 1.5 - tol && p_top.x < 2.5 + tol && p_top.y.abs() <= 0.5 + tol,
                    "({u}, {v}): top point {p_top}"
                );
            } else {
                assert!((d - t_front).abs() < 1e-9, "pixel ({u}, {v}): {d}");
                side += 1;
            }
            assert!((f64::from(out[i]) / 1000.0 - d).abs() <= MM_ROUNDING);
        }
    }
    assert!(top > 1000 && side > 1000, "top {top}, front face {side}");
}

#[test]
fn capsules_behind_or_around_the_camera_do_not_break_the_frame() {
    let pose = front_camera();
    let mut r = ideal(pose);
    let mut out = frame();
    // entirely behind
    let behind = Capsule::new(
        Point3::new(-1.0, -0.5, 1.0),
        Point3::new(-1.0, 0.5, 1.0),
        0.2,
    );
    r.render(&[behind], &[], None, &mut out).unwrap();
    assert!(out.iter().all(|&d| d == 0));
    // from behind the camera to 2 m in front, beside the optical axis: the
    // part in front is drawn, the part nearer than 0.5 m reads 0
    let through = Capsule::new(
        Point3::new(-1.0, -0.2, 1.0),
        Point3::new(2.0, -0.2, 1.0),
        0.05,
    );
    r.render(&[through], &[], None, &mut out).unwrap();
    let valid = out.iter().filter(|&&d| d > 0).count();
    assert!(valid > 100);
    assert!(out.iter().all(|&d| d == 0 || d >= 500));
    // the camera inside a capsule: everything is blocked
    let around = Capsule::new(Point3::new(-0.5, 0.0, 1.0), Point3::new(0.5, 0.0, 1.0), 0.3);
    r.render(&[around, behind], &[], Some(0.0), &mut out)
        .unwrap();
    assert!(out.iter().all(|&d| d == 0));
    assert!(r.exact_depth().iter().all(|&d| d <= 0.5));
}

#[test]
fn range_limits_give_no_reading() {
    let pose = front_camera();
    let mut r = ideal(pose);
    let mut out = frame();
    for (x, valid) in [(0.45, false), (0.55, true), (4.4, true), (4.6, false)] {
        let wall = Aabb::new(Point3::new(x, -5.0, -5.0), Point3::new(x + 0.1, 5.0, 5.0));
        r.render(&[], &[wall], None, &mut out).unwrap();
        let centre = out[idx(319, 239)];
        if valid {
            assert_eq!(centre, (x * 1000.0).round() as u16);
            assert!(out.iter().all(|&d| d > 0));
        } else {
            assert!(out.iter().all(|&d| d == 0), "wall at {x} m");
        }
    }
}

#[test]
fn noise_follows_the_nguyen_model() {
    let pose = front_camera();
    let wall = Aabb::new(Point3::new(2.5, -5.0, -5.0), Point3::new(2.6, 5.0, 5.0));
    let options = RenderOptions {
        edge_dropout: 0.0,
        seed: 5,
        ..RenderOptions::default()
    };
    let mut r = Renderer::new(K, pose, options).unwrap();
    let mut out = frame();
    r.render(&[], &[wall], None, &mut out).unwrap();
    let n = out.len() as f64;
    let errors = out.iter().map(|&d| f64::from(d) / 1000.0 - 2.5);
    let mean = errors.clone().sum::<f64>() / n;
    let std = (errors.map(|e| (e - mean) * (e - mean)).sum::<f64>() / n).sqrt();
    let sigma = sigma_z(2.5);
    assert!(mean.abs() < 0.1e-3, "bias {mean}");
    // quantization adds 1 mm²/12 of variance, the discrete normal table a little less than 1
    assert!((std / sigma - 1.0).abs() < 0.03, "std {std} vs σ_z {sigma}");
}

#[test]
fn edge_shadows_drop_pixels_at_discontinuities_only() {
    let pose = front_camera();
    let wall = Aabb::new(Point3::new(3.0, -5.0, -5.0), Point3::new(3.1, 5.0, 5.0));
    let ball = Capsule::sphere(Point3::new(1.5, 0.0, 1.0), 0.2);
    let mut exact = frame();
    ideal(pose)
        .render(&[ball], &[wall], None, &mut exact)
        .unwrap();
    let w = K.width as usize;
    let is_edge = |i: usize| {
        let (u, v) = (i % w, i / w);
        let z = f64::from(exact[i]) / 1000.0;
        let jump = 0.05 + 3.0 * sigma_z(z);
        let mut n = vec![];
        if u > 0 {
            n.push(i - 1);
        }
        if u + 1 < w {
            n.push(i + 1);
        }
        if v > 0 {
            n.push(i - w);
        }
        if v + 1 < 480 {
            n.push(i + w);
        }
        n.iter()
            .any(|&j| (f64::from(exact[j]) / 1000.0 - z).abs() > jump)
    };
    let edges: Vec<usize> = (0..exact.len()).filter(|&i| is_edge(i)).collect();
    assert!(edges.len() > 100, "both sides of the silhouette");
    for (p, lo, hi) in [(1.0, 1.0, 1.0), (0.5, 0.4, 0.6), (0.0, 0.0, 0.0)] {
        let options = RenderOptions {
            noise: false,
            edge_dropout: p,
            ..RenderOptions::default()
        };
        let mut r = Renderer::new(K, pose, options).unwrap();
        let mut out = frame();
        r.render(&[ball], &[wall], None, &mut out).unwrap();
        let dropped = edges.iter().filter(|&&i| out[i] == 0).count() as f64 / edges.len() as f64;
        assert!((lo..=hi).contains(&dropped), "p = {p}: dropped {dropped}");
        // everything else is untouched
        for i in 0..out.len() {
            if out[i] != 0 || p == 0.0 {
                assert_eq!(out[i], exact[i]);
            } else {
                assert!(is_edge(i), "pixel {i} dropped but not at an edge");
            }
        }
    }
}

#[test]
fn rendering_is_deterministic_per_seed() {
    let pose = CameraPose::paper_default();
    let s = common::scene();
    let mut a = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let mut b = Renderer::new(K, pose, RenderOptions::default()).unwrap();
    let (mut fa, mut fb, mut fc) = (frame(), frame(), frame());
    a.render(&s.all, &s.boxes, s.floor_z, &mut fa).unwrap();
    b.render(&s.all, &s.boxes, s.floor_z, &mut fb).unwrap();
    assert_eq!(fa, fb);
    // the next frame has fresh noise; reseeding restarts the sequence
    a.render(&s.all, &s.boxes, s.floor_z, &mut fc).unwrap();
    assert_ne!(fa, fc);
    a.reseed(0);
    a.render(&s.all, &s.boxes, s.floor_z, &mut fc).unwrap();
    assert_eq!(fa, fc);
    a.reseed(1);
    a.render(&s.all, &s.boxes, s.floor_z, &mut fc).unwrap();
    assert_ne!(fa, fc);
}

#[test]
fn bad_buffers_and_primitives_are_errors() {
    let mut r = ideal(front_camera());
    let mut small = vec![0u16; 100];
    assert!(matches!(
        r.render(&[], &[], None, &mut small),
        Err(DepthError::FrameSize { got: 100, .. })
    ));
    let mut out = frame();
    let mut labels = vec![0u16; 3];
    assert!(r
        .render_labeled(&[], &[], None, &mut out, &mut labels)
        .is_err());
    let nan = Capsule::new(Point3::new(f64::NAN, 0.0, 0.0), Point3::origin(), 0.1);
    let negative = Capsule::sphere(Point3::new(2.0, 0.0, 1.0), -0.1);
    let ok = Capsule::sphere(Point3::new(2.0, 0.0, 1.0), 0.1);
    assert!(matches!(
        r.render(&[ok, nan], &[], None, &mut out),
        Err(DepthError::Primitive { index: 1, .. })
    ));
    assert!(r.render(&[negative], &[], None, &mut out).is_err());
    let bad_box = Aabb {
        min: Point3::new(1.0, 0.0, 0.0),
        max: Point3::new(0.0, 1.0, 1.0),
    };
    assert!(r.render(&[], &[bad_box], None, &mut out).is_err());
    assert!(r.render(&[], &[], Some(f64::NAN), &mut out).is_err());
    for bad in [
        RenderOptions {
            edge_dropout: 1.5,
            ..RenderOptions::default()
        },
        RenderOptions {
            min_range_m: 5.0,
            ..RenderOptions::default()
        },
        RenderOptions {
            edge_jump_m: -1.0,
            ..RenderOptions::default()
        },
    ] {
        assert!(Renderer::new(K, front_camera(), bad).is_err());
    }
}

/// A renderer keeps the static scene (floor, boxes) between frames and
/// redraws only where the last frame's capsules were: every frame must equal a
/// fresh renderer's, whatever moved, appeared or vanished since, and when the
/// boxes, the floor or the camera change.
#[test]
fn a_frame_leaves_no_trace_in_the_next() {
    let pose = CameraPose::paper_default();
    let s = common::scene();
    let mut kept = ideal(pose);
    let check = |kept: &mut Renderer,
                 pose: CameraPose,
                 caps: &[Capsule],
                 boxes: &[Aabb],
                 floor: Option<f64>| {
        let mut fresh = ideal(pose);
        let (mut a, mut b) = (frame(), frame());
        let (mut la, mut lb) = (frame(), frame());
        kept.render_labeled(caps, boxes, floor, &mut a, &mut la)
            .unwrap();
        fresh
            .render_labeled(caps, boxes, floor, &mut b, &mut lb)
            .unwrap();
        assert_eq!(a, b);
        assert_eq!(la, lb);
        assert_eq!(kept.exact_depth(), fresh.exact_depth());
    };
    // the scene, then everything moved 0.2 m sideways, then the person gone
    check(&mut kept, pose, &s.all, &s.boxes, s.floor_z);
    let moved: Vec<Capsule> = s
        .all
        .iter()
        .map(|c| {
            Capsule::new(
                c.a + Vector3::new(0.0, 0.2, 0.0),
                c.b + Vector3::new(0.0, 0.2, 0.0),
                c.radius,
            )
        })
        .collect();
    check(&mut kept, pose, &moved, &s.boxes, s.floor_z);
    check(&mut kept, pose, &s.robot, &s.boxes, s.floor_z);
    // no boxes, no floor, another floor, and back
    check(&mut kept, pose, &s.all, &[], s.floor_z);
    check(&mut kept, pose, &s.all, &s.boxes, None);
    check(&mut kept, pose, &s.all, &s.boxes, Some(-0.5));
    check(&mut kept, pose, &s.all, &s.boxes, s.floor_z);
    // more capsules than the last frame had (labels of the boxes shift)
    let mut more = s.all.clone();
    more.extend(moved.iter().copied());
    check(&mut kept, pose, &more, &s.boxes, s.floor_z);
    // the camera moved
    let other = front_camera();
    kept.set_pose(other);
    check(&mut kept, other, &s.all, &s.boxes, s.floor_z);
}
