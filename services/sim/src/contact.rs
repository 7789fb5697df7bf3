//! Capsule–capsule distance and the compliant contact law.
//!
//! A capsule is a segment `a`–`b` swept by a sphere of radius `r`. The
//! distance between two capsules is the distance between their segments minus
//! both radii; it is negative when they overlap, and its magnitude is then the
//! penetration depth along the line of the segments' closest points.
//!
//! Contact law: a penetration `δ > 0` of a human capsule into a robot capsule
//! gives a force on the robot `F = max(0, k δ + d δ̇) n` along the unit normal
//! `n` that pushes the robot out of the human, with `k` the body part's spring
//! constant and `d` a small damping; it acts at the point of the robot
//! capsule's surface that is deepest in the human. The clamp keeps the
//! contact from pulling (no adhesion while the bodies separate). The spring
//! constant of each body region is [`stiffness_n_per_m`].

use nalgebra::Vector3;
use phri_ipc::BodyPart;

/// Closest points of two segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentClosest {
    /// parameter of the closest point on the first segment, in `[0, 1]`
    pub s: f64,
    /// parameter of the closest point on the second segment, in `[0, 1]`
    pub t: f64,
    /// closest point on the first segment \[m\]
    pub p: Vector3<f64>,
    /// closest point on the second segment \[m\]
    pub q: Vector3<f64>,
}

/// Squared length below which a segment is treated as a point [m²].
const DEGENERATE: f64 = 1e-24;

/// Closest points between segments `p1`–`q1` and `p2`–`q2` (Ericson,
/// Real-Time Collision Detection, 5.1.9). Degenerate segments (points) and
/// parallel segments are handled: for parallel segments the first segment's
/// parameter is fixed at 0 and the other clamped, which still gives a pair of
/// closest points at the exact minimum distance.
pub fn closest_points_segments(
    p1: &Vector3<f64>,
    q1: &Vector3<f64>,
    p2: &Vector3<f64>,
    q2: &Vector3<f64>,
) -> SegmentClosest {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let (s, t) = if a <= DEGENERATE && e <= DEGENERATE {
        (0.0, 0.0)
    } else if a <= DEGENERATE {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= DEGENERATE {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            // parallel (denom ≈ 0, relative to a e): any s works, take 0
            let mut s = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    SegmentClosest {
        s,
        t,
        p: p1 + d1 * s,
        q: p2 + d2 * t,
    }
}

/// Signed distance between two capsules and where it is attained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CapsuleDistance {
    /// surface distance \[m\]: segment distance minus both radii; negative when
    /// the capsules overlap (then `-distance` is the penetration depth)
    pub distance: f64,
    /// point of capsule A's surface towards B \[m\] (inside B when overlapping)
    pub point_a: Vector3<f64>,
    /// point of capsule B's surface towards A \[m\] (inside A when overlapping)
    pub point_b: Vector3<f64>,
    /// unit normal from A towards B (from A's closest axis point to B's)
    pub normal: Vector3<f64>,
}

/// Distance between capsule A (`a0`–`a1`, radius `ra`) and capsule B
/// (`b0`–`b1`, radius `rb`) \[m\]. When the axes intersect the normal is taken
/// perpendicular to A's axis (and to B's when possible), so it is always a
/// unit vector.
pub fn capsule_distance(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    ra: f64,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
    rb: f64,
) -> CapsuleDistance {
    let c = closest_points_segments(a0, a1, b0, b1);
    let d = c.q - c.p;
    let len = d.norm();
    let normal = if len > 1e-12 {
        d / len
    } else {
        fallback_normal(&(a1 - a0), &(b1 - b0))
    };
    CapsuleDistance {
        distance: len - ra - rb,
        point_a: c.p + normal * ra,
        point_b: c.q - normal * rb,
        normal,
    }
}

/// A unit vector perpendicular to both directions if they span a plane, else
/// perpendicular to the first (or any unit vector for points).
fn fallback_normal(da: &Vector3<f64>, db: &Vector3<f64>) -> Vector3<f64> {
    let n = da.cross(db);
    let nn = n.norm();
    if nn > 1e-12 {
        return n / nn;
    }
    let dir = if da.norm_squared() > DEGENERATE {
        *da
    } else {
        *db
    };
    if dir.norm_squared() <= DEGENERATE {
        return Vector3::z();
    }
    // the coordinate axis least aligned with dir, made perpendicular
    let axis = if dir.x.abs() <= dir.y.abs() && dir.x.abs() <= dir.z.abs() {
        Vector3::x()
    } else if dir.y.abs() <= dir.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    dir.cross(&axis).normalize()
}

/// Magnitude of the contact force \[N\] for penetration `depth` \[m\] (> 0 when
/// penetrating), its rate `depth_rate` [m/s], stiffness `k` [N/m] and damping
/// `d` [N·s/m]: `max(0, k δ + d δ̇)`, zero without penetration.
#[inline]
pub fn contact_force_magnitude(depth: f64, depth_rate: f64, k: f64, d: f64) -> f64 {
    if depth <= 0.0 {
        0.0
    } else {
        (k * depth + d * depth_rate).max(0.0)
    }
}

/// Contact spring constant [N/m] of a body region, after the effective
/// spring constants of ISO/TS 15066 Table A.2 (N/mm × 1000): hand 75,
/// forearm 40, upper arm 30, head 150, chest 25, abdomen/pelvis 10,
/// thigh 50, lower leg 60.
pub fn stiffness_n_per_m(part: BodyPart) -> f64 {
    let n_per_mm = match part {
        BodyPart::Head => 150.0,
        BodyPart::Torso => 25.0,
        BodyPart::Pelvis => 10.0,
        BodyPart::UpperArmLeft | BodyPart::UpperArmRight => 30.0,
        BodyPart::ForearmLeft | BodyPart::ForearmRight => 40.0,
        BodyPart::HandLeft | BodyPart::HandRight => 75.0,
        BodyPart::ThighLeft | BodyPart::ThighRight => 50.0,
        BodyPart::ShinLeft | BodyPart::ShinRight => 60.0,
    };
    n_per_mm * 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_segments() {
        let c = capsule_distance(
            &Vector3::new(-1.0, 0.0, 0.0),
            &Vector3::new(1.0, 0.0, 0.0),
            0.1,
            &Vector3::new(0.0, -1.0, 0.5),
            &Vector3::new(0.0, 1.0, 0.5),
            0.2,
        );
        assert!((c.distance - 0.2).abs() < 1e-15);
        assert!((c.normal - Vector3::z()).norm() < 1e-15);
        assert!((c.point_a - Vector3::new(0.0, 0.0, 0.1)).norm() < 1e-15);
        assert!((c.point_b - Vector3::new(0.0, 0.0, 0.3)).norm() < 1e-15);
    }

    #[test]
    fn parallel_and_degenerate() {
        // parallel, overlapping in extent
        let c = capsule_distance(
            &Vector3::new(0.0, 0.0, 0.0),
            &Vector3::new(1.0, 0.0, 0.0),
            0.0,
            &Vector3::new(0.5, 1.0, 0.0),
            &Vector3::new(2.0, 1.0, 0.0),
            0.0,
        );
        assert!((c.distance - 1.0).abs() < 1e-15);
        // parallel, disjoint in extent
        let c = capsule_distance(
            &Vector3::new(0.0, 0.0, 0.0),
            &Vector3::new(1.0, 0.0, 0.0),
            0.0,
            &Vector3::new(2.0, 1.0, 0.0),
            &Vector3::new(3.0, 1.0, 0.0),
            0.0,
        );
        assert!((c.distance - 2f64.sqrt()).abs() < 1e-15);
        // point against segment, point against point
        let o = Vector3::zeros();
        let c = capsule_distance(
            &o,
            &o,
            0.1,
            &Vector3::new(-1.0, 2.0, 0.0),
            &Vector3::new(1.0, 2.0, 0.0),
            0.1,
        );
        assert!((c.distance - 1.8).abs() < 1e-15);
        let c = capsule_distance(&o, &o, 0.1, &o, &o, 0.1);
        assert!((c.distance + 0.2).abs() < 1e-15);
        assert!((c.normal.norm() - 1.0).abs() < 1e-15);
        // intersecting axes: unit normal, depth = sum of radii
        let c = capsule_distance(
            &Vector3::new(-1.0, 0.0, 0.0),
            &Vector3::new(1.0, 0.0, 0.0),
            0.1,
            &Vector3::new(0.0, -1.0, 0.0),
            &Vector3::new(0.0, 1.0, 0.0),
            0.1,
        );
        assert!((c.distance + 0.2).abs() < 1e-15);
        assert!((c.normal.norm() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn force_law() {
        assert_eq!(contact_force_magnitude(-0.01, 1.0, 1e4, 100.0), 0.0);
        assert!((contact_force_magnitude(0.01, 0.0, 1e4, 100.0) - 100.0).abs() < 1e-12);
        assert_eq!(contact_force_magnitude(0.001, -1.0, 1e4, 100.0), 0.0);
    }
}
