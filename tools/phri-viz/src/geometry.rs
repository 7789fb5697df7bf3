//! Foxglove primitives from phri's geometry: poses, colours, timestamps, and
//! the shapes Foxglove lacks (a capsule is a cylinder and two spheres; an
//! arrow is posed along its +x axis). Positions in \[m\], base frame.

use foxglove::messages::{
    ArrowPrimitive, Color, CylinderPrimitive, LinePrimitive, Point3, Pose, Quaternion,
    SpherePrimitive, Timestamp, Vector3 as FgVector3,
};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// A timestamp from nanoseconds on phri's clock (CLOCK_MONOTONIC).
pub fn timestamp(ns: u64) -> Timestamp {
    let sec = u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX);
    Timestamp::new(sec, (ns % 1_000_000_000) as u32)
}

/// An RGBA colour, each channel in [0, 1].
pub const fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

/// A Foxglove vector.
pub fn vec3(v: &Vector3<f64>) -> FgVector3 {
    FgVector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// A Foxglove point.
pub fn point3(v: &Vector3<f64>) -> Point3 {
    Point3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// A Foxglove quaternion.
pub fn quaternion(q: &UnitQuaternion<f64>) -> Quaternion {
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

/// The quaternion of a rotation matrix (re-orthonormalised first: a matrix
/// read from a message may carry rounding).
pub fn rotation(r: &Matrix3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(r))
}

/// A pose at `p` with orientation `q`.
pub fn pose(p: &Vector3<f64>, q: &UnitQuaternion<f64>) -> Pose {
    Pose {
        position: Some(vec3(p)),
        orientation: Some(quaternion(q)),
    }
}

/// The rotation taking `from` (a unit axis) onto the direction of `to`;
/// identity when `to` is (nearly) zero, a half turn when they are opposite.
pub fn rotation_between(from: &Vector3<f64>, to: &Vector3<f64>) -> UnitQuaternion<f64> {
    let n = to.norm();
    if !(n > 1e-12) {
        return UnitQuaternion::identity();
    }
    UnitQuaternion::rotation_between(from, &(to / n)).unwrap_or_else(|| {
        // opposite: half a turn about any axis perpendicular to `from`
        let axis = if from.x.abs() < 0.9 {
            from.cross(&Vector3::x())
        } else {
            from.cross(&Vector3::y())
        };
        UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), std::f64::consts::PI)
    })
}

/// A sphere of `radius` \[m\] centred at `c`.
pub fn sphere(c: &Vector3<f64>, radius: f64, color: Color) -> SpherePrimitive {
    let d = 2.0 * radius;
    SpherePrimitive {
        pose: Some(pose(c, &UnitQuaternion::identity())),
        size: Some(FgVector3 { x: d, y: d, z: d }),
        color: Some(color),
    }
}

/// A capsule (segment `a`–`b` swept by `radius` \[m\]) as Foxglove draws it:
/// a cylinder between the end centres (none when they coincide) and a sphere
/// at each end.
pub fn capsule(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    radius: f64,
    color: Color,
) -> (Option<CylinderPrimitive>, [SpherePrimitive; 2]) {
    let axis = b - a;
    let len = axis.norm();
    let d = 2.0 * radius;
    let cylinder = (len > 1e-9).then(|| CylinderPrimitive {
        pose: Some(pose(
            &((a + b) * 0.5),
            &rotation_between(&Vector3::z(), &axis),
        )),
        size: Some(FgVector3 { x: d, y: d, z: len }),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: Some(color),
    });
    (
        cylinder,
        [sphere(a, radius, color), sphere(b, radius, color)],
    )
}

/// An arrow from `tail` along `v` \[m\] (its length is ‖v‖), `diameter` \[m\]
/// thick; `None` when `v` is (nearly) zero.
pub fn arrow(
    tail: &Vector3<f64>,
    v: &Vector3<f64>,
    diameter: f64,
    color: Color,
) -> Option<ArrowPrimitive> {
    let len = v.norm();
    if !(len > 1e-6) {
        return None;
    }
    let head = (0.25 * len).min(3.0 * diameter).max(0.0);
    Some(ArrowPrimitive {
        pose: Some(pose(tail, &rotation_between(&Vector3::x(), v))),
        shaft_length: len - head,
        shaft_diameter: diameter,
        head_length: head,
        head_diameter: 2.0 * diameter,
        color: Some(color),
    })
}

/// Line segments `(a, b)` drawn `thickness` \[m\] thick (a LINE_LIST).
pub fn segments(
    pairs: &[(Vector3<f64>, Vector3<f64>)],
    thickness: f64,
    color: Color,
) -> LinePrimitive {
    LinePrimitive {
        r#type: foxglove::messages::line_primitive::Type::LineList as i32,
        pose: Some(pose(&Vector3::zeros(), &UnitQuaternion::identity())),
        thickness,
        scale_invariant: false,
        points: pairs
            .iter()
            .flat_map(|(a, b)| [point3(a), point3(b)])
            .collect(),
        color: Some(color),
        colors: Vec::new(),
        indices: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(p: &Pose) -> UnitQuaternion<f64> {
        let o = p.orientation.expect("orientation");
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(o.w, o.x, o.y, o.z))
    }

    #[test]
    fn a_capsule_is_a_cylinder_between_two_spheres() {
        let a = Vector3::new(0.0, 0.0, 0.0);
        let b = Vector3::new(0.3, 0.0, 0.0);
        let (cyl, [s0, s1]) = capsule(&a, &b, 0.05, rgba(1.0, 0.0, 0.0, 1.0));
        let cyl = cyl.expect("a cylinder");
        let size = cyl.size.expect("size");
        assert!((size.z - 0.3).abs() < 1e-12 && (size.x - 0.1).abs() < 1e-12);
        let p = cyl.pose.expect("pose");
        let c = p.position.expect("position");
        assert!((c.x - 0.15).abs() < 1e-12 && c.y.abs() < 1e-12);
        // the cylinder's z axis lies along a → b
        let z = q(&p) * Vector3::z();
        assert!((z - Vector3::x()).norm() < 1e-9, "{z}");
        assert_eq!(s0.pose.unwrap().position.unwrap().x, 0.0);
        assert_eq!(s1.pose.unwrap().position.unwrap().x, 0.3);
        assert_eq!(s1.size.unwrap().x, 0.1);
        // a sphere-only capsule has no cylinder
        assert!(capsule(&a, &a, 0.05, rgba(1.0, 0.0, 0.0, 1.0)).0.is_none());
    }

    #[test]
    fn arrows_point_along_their_vector_with_its_length() {
        let v = Vector3::new(0.0, 0.0, -0.4);
        let a = arrow(
            &Vector3::new(1.0, 2.0, 3.0),
            &v,
            0.01,
            rgba(0.0, 0.0, 1.0, 1.0),
        )
        .unwrap();
        assert!((a.shaft_length + a.head_length - 0.4).abs() < 1e-12);
        let x = q(&a.pose.unwrap()) * Vector3::x();
        assert!((x - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-9, "{x}");
        assert!(arrow(
            &Vector3::zeros(),
            &Vector3::zeros(),
            0.01,
            rgba(0.0, 0.0, 1.0, 1.0)
        )
        .is_none());
        // opposite to the +x axis: a half turn, not a NaN
        let back = arrow(
            &Vector3::zeros(),
            &Vector3::new(-1.0, 0.0, 0.0),
            0.01,
            rgba(0.0, 0.0, 1.0, 1.0),
        )
        .unwrap();
        let x = q(&back.pose.unwrap()) * Vector3::x();
        assert!((x + Vector3::x()).norm() < 1e-9, "{x}");
    }

    #[test]
    fn timestamps_split_seconds_and_nanoseconds() {
        let t = timestamp(12_000_000_345);
        assert_eq!((t.sec(), t.nsec()), (12, 345));
    }
}
