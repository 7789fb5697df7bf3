//! Capsule distance against parry3d-f64 on random capsules.
//!
//! parry has an exact segment–segment routine (Ericson's, like ours) and
//! iterative (GJK/EPA) capsule queries. The segment distance, which fixes the
//! capsule distance (`segment distance − ra − rb`), must agree to 1e-9 m, and
//! it is also checked against a ternary search (the distance is convex in the
//! first segment's parameter). The iterative capsule queries stop at their own
//! tolerance (median difference ~5e-9 m, 90th percentile ~1e-6 m, largest
//! ~1.4e-5 m, where the ternary search confirms our value), so they are
//! checked to 1e-4 m with a median below 1e-8 m; overlaps are compared where
//! they are shallow (the contact regime), since EPA drifts by 0.1 mm in deep
//! overlaps and by millimetres for end-to-end collinear axes.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::query;
use parry3d_f64::shape::{Capsule, Segment};
use phri_sim::{capsule_distance, closest_points_segments};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

fn random_point(rng: &mut SmallRng, scale: f64) -> Vector3<f64> {
    Vector3::new(
        rng.gen_range(-scale..scale),
        rng.gen_range(-scale..scale),
        rng.gen_range(-scale..scale),
    )
}

/// A capsule as parry sees it: a z-aligned capsule of half length |b − a|/2 placed by an isometry.
fn parry_capsule(a: &Vector3<f64>, b: &Vector3<f64>, r: f64) -> (Capsule, Isometry3<f64>) {
    let d = b - a;
    let rot = UnitQuaternion::rotation_between(&Vector3::z(), &d).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    (
        Capsule::new_z(d.norm() * 0.5, r),
        Isometry3::from_parts(Translation3::from((a + b) * 0.5), rot),
    )
}

/// Random capsule pairs; every tenth pair parallel, every tenth a sphere
/// (zero-length axis), every tenth collinear.
/// Capsule A (`a0`, `a1`, radius) and capsule B (`b0`, `b1`, radius).
type Pair = (
    Vector3<f64>,
    Vector3<f64>,
    f64,
    Vector3<f64>,
    Vector3<f64>,
    f64,
);

fn cases(n: usize) -> Vec<Pair> {
    let mut rng = SmallRng::seed_from_u64(7);
    (0..n)
        .map(|i| {
            let a0 = random_point(&mut rng, 0.5);
            let mut a1 = a0 + random_point(&mut rng, 0.3);
            let mut b0 = random_point(&mut rng, 0.5);
            let mut b1 = b0 + random_point(&mut rng, 0.3);
            match i % 10 {
                0 => b1 = b0 + (a1 - a0) * rng.gen_range(-2.0..2.0),
                1 => a1 = a0,
                2 => {
                    b0 = a0 + (a1 - a0) * rng.gen_range(-1.5..2.5);
                    b1 = a0 + (a1 - a0) * rng.gen_range(-1.5..2.5);
                }
                _ => {}
            }
            (
                a0,
                a1,
                rng.gen_range(0.01..0.15),
                b0,
                b1,
                rng.gen_range(0.01..0.15),
            )
        })
        .collect()
}

/// Minimum over `s` of the distance from `a0 + s (a1 − a0)` to the segment `b0`–`b1`, by ternary search.
fn ternary_distance(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> f64 {
    let point_segment = |p: &Vector3<f64>| {
        let d = b1 - b0;
        let t = if d.norm_squared() > 0.0 {
            ((p - b0).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (b0 + d * t)).norm()
    };
    let at = |s: f64| point_segment(&(a0 + (a1 - a0) * s));
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..200 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if at(m1) <= at(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    at(0.5 * (lo + hi)).min(at(0.0)).min(at(1.0))
}

#[test]
fn segment_distance_matches_parry_to_1e_9() {
    for (i, (a0, a1, ra, b0, b1, rb)) in cases(20_000).into_iter().enumerate() {
        let (pa0, pa1, pb0, pb1) = (
            Point3::from(a0),
            Point3::from(a1),
            Point3::from(b0),
            Point3::from(b1),
        );
        let (la, lb) = query::details::closest_points_segment_segment_with_locations_nD(
            (&pa0, &pa1),
            (&pb0, &pb1),
        );
        let d_parry =
            (Segment::new(pb0, pb1).point_at(&lb) - Segment::new(pa0, pa1).point_at(&la)).norm();
        let seg = closest_points_segments(&a0, &a1, &b0, &b1);
        if i % 10 < 5 {
            let brute = ternary_distance(&a0, &a1, &b0, &b1);
            assert!(
                ((seg.q - seg.p).norm() - brute).abs() < 1e-9,
                "case {i}: {} vs ternary search {brute}",
                (seg.q - seg.p).norm()
            );
        }
        assert!((0.0..=1.0).contains(&seg.s) && (0.0..=1.0).contains(&seg.t));
        let ours = capsule_distance(&a0, &a1, ra, &b0, &b1, rb);
        assert!(
            (ours.distance - (d_parry - ra - rb)).abs() < 1e-9,
            "case {i}: {} vs parry {}",
            ours.distance,
            d_parry - ra - rb
        );
        assert!((ours.normal.norm() - 1.0).abs() < 1e-12);
        // the surface points lie on the capsules, along the normal
        assert!(((ours.point_b - ours.point_a).dot(&ours.normal) - ours.distance).abs() < 1e-12);
    }
}

#[test]
fn capsule_distance_and_depth_match_parry_queries() {
    let (mut separated, mut overlapping, mut exact) = (0, 0, 0);
    let mut errs = Vec::with_capacity(60_000);
    for (i, (a0, a1, ra, b0, b1, rb)) in cases(60_000).into_iter().enumerate() {
        let ours = capsule_distance(&a0, &a1, ra, &b0, &b1, rb);
        let (ca, ia) = parry_capsule(&a0, &a1, ra);
        let (cb, ib) = parry_capsule(&b0, &b1, rb);
        if ours.distance > 0.0 {
            let d = query::distance(&ia, &ca, &ib, &cb).expect("capsule distance is supported");
            assert!(
                (d - ours.distance).abs() < 1e-4,
                "case {i}: distance {} vs parry {d}",
                ours.distance
            );
            exact += usize::from((d - ours.distance).abs() < 1e-9);
            errs.push((d - ours.distance).abs());
            separated += 1;
        } else if -ours.distance < 0.5 * ra.min(rb) && i % 10 != 2 {
            // shallow overlap, the contact regime (EPA is undefined when the
            // axes intersect, drifts by 0.1 mm in deep overlaps and by
            // millimetres for end-to-end collinear axes, where the exact depth
            // is ra + rb − gap)
            let c = query::contact(&ia, &ca, &ib, &cb, 0.0)
                .expect("capsule contact is supported")
                .expect("parry sees the overlap");
            assert!(
                (c.dist - ours.distance).abs() < 1e-4,
                "case {i}: depth {} vs parry {}",
                ours.distance,
                c.dist
            );
            exact += usize::from((c.dist - ours.distance).abs() < 1e-9);
            errs.push((c.dist - ours.distance).abs());
            assert!(
                (c.normal1.into_inner() - ours.normal).norm() < 1e-3,
                "case {i}: normal"
            );
            // parallel axes have a continuum of closest points
            if i % 10 != 0 {
                assert!(
                    (Vector3::from(c.point1.coords) - ours.point_a).norm() < 1e-4,
                    "case {i}: point on A"
                );
            }
            overlapping += 1;
        }
    }
    assert!(
        separated > 20_000 && overlapping > 500,
        "{separated} separated, {overlapping} overlapping"
    );
    let compared = separated + overlapping;
    errs.sort_by(f64::total_cmp);
    let median = errs[errs.len() / 2];
    println!("{compared} pairs compared, {exact} within 1e-9 m, median difference {median:e} m, largest {:e} m", errs[errs.len() - 1]);
    assert!(median < 1e-8, "median difference {median:e} m");
}
