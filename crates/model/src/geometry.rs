//! Link collision geometry as primitives, convertible to parry3d shapes.

use nalgebra::{Isometry3, Matrix3, Vector3};
use parry3d_f64::shape::SharedShape;

use crate::data::Data;
use crate::model::{Model, Placement};

/// A collision primitive in its own frame. Capsules and cylinders lie along
/// their frame's z axis, as in URDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// segment from `−half_length ẑ` to `+half_length ẑ` swept by a sphere \[m\]
    Capsule {
        /// radius of the swept sphere \[m\]
        radius: f64,
        /// half the segment's length \[m\]
        half_length: f64,
    },
    /// cylinder along z \[m\]
    Cylinder {
        /// radius \[m\]
        radius: f64,
        /// half the length along z \[m\]
        half_length: f64,
    },
    /// sphere \[m\]
    Sphere {
        /// radius \[m\]
        radius: f64,
    },
    /// box with half side lengths \[m\]
    Box {
        /// half the side lengths along x, y, z \[m\]
        half_extents: Vector3<f64>,
    },
}

/// One collision primitive rigidly attached to a body.
#[derive(Clone, Debug)]
pub struct CollisionObject {
    /// URDF link the geometry belongs to
    pub link: String,
    /// body (joint index) it rides on, `None` for the root
    pub body: Option<usize>,
    /// shape frame in the body frame
    pub placement: Placement,
    /// the primitive, in the shape frame
    pub shape: Shape,
}

impl Shape {
    /// The parry3d shape, in parry's convention (cylinders along y), and the
    /// rotation to put in front of it so that it lies along z as in URDF.
    pub fn to_parry(&self) -> (SharedShape, Isometry3<f64>) {
        let id = Isometry3::identity();
        match *self {
            Shape::Capsule {
                radius,
                half_length,
            } => (SharedShape::capsule_z(half_length, radius), id),
            Shape::Sphere { radius } => (SharedShape::ball(radius), id),
            Shape::Box { half_extents } => (
                SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z),
                id,
            ),
            // parry's cylinder is along y: rotate +90° about x to map y onto z
            Shape::Cylinder {
                radius,
                half_length,
            } => (
                SharedShape::cylinder(half_length, radius),
                Isometry3::rotation(Vector3::x() * std::f64::consts::FRAC_PI_2),
            ),
        }
    }

    /// The capsule that stands in for this shape wherever phri needs capsules
    /// (the simulator's contacts, the camera's robot pixels, the self-filter):
    /// capsules and spheres exactly; a cylinder by the capsule of the same
    /// radius and axis; a box by the capsule along its longest axis whose
    /// radius covers its cross-section. Each contains the shape, and for a box
    /// no capsule along that axis with a shorter segment or a smaller radius
    /// does (the corners sit on it). Returns `(radius, half_length, R)` \[m\]:
    /// the capsule's segment is `R (0, 0, ±half_length)` in the shape frame.
    pub fn capsule(&self) -> (f64, f64, Matrix3<f64>) {
        let id = Matrix3::identity();
        match *self {
            Shape::Capsule {
                radius,
                half_length,
            }
            | Shape::Cylinder {
                radius,
                half_length,
            } => (radius, half_length, id),
            Shape::Sphere { radius } => (radius, 0.0, id),
            Shape::Box { half_extents: e } => {
                // a permutation putting the longest axis on z
                let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
                if e.z >= e.x && e.z >= e.y {
                    (e.x.hypot(e.y), e.z, id)
                } else if e.x >= e.y {
                    (e.y.hypot(e.z), e.x, Matrix3::from_columns(&[y, z, x]))
                } else {
                    (e.z.hypot(e.x), e.y, Matrix3::from_columns(&[z, x, y]))
                }
            }
        }
    }

    /// Radius of the smallest sphere around the shape's origin that holds it \[m\].
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Shape::Capsule {
                radius,
                half_length,
            } => radius + half_length,
            Shape::Cylinder {
                radius,
                half_length,
            } => (radius * radius + half_length * half_length).sqrt(),
            Shape::Sphere { radius } => radius,
            Shape::Box { half_extents } => half_extents.norm(),
        }
    }
}

impl CollisionObject {
    /// Pose of the shape frame in the base frame, from the body placements in `data`
    /// (after [`crate::forward_kinematics`]).
    pub fn pose(&self, data: &Data) -> Placement {
        data.body_placement(self.body).compose(&self.placement)
    }

    /// The capsule of [`Shape::capsule`] posed in the base frame (after
    /// [`crate::forward_kinematics`]): its axis endpoints `(a, b)` \[m\] and
    /// radius \[m\].
    pub fn capsule_segment(&self, data: &Data) -> (Vector3<f64>, Vector3<f64>, f64) {
        let pose = self.pose(data);
        let (radius, half_length, rot) = self.shape.capsule();
        let axis = rot * Vector3::new(0.0, 0.0, half_length);
        (pose.apply(&-axis), pose.apply(&axis), radius)
    }

    /// Signed distance \[m\] from `x` (base frame) to the surface of the
    /// capsule of [`CollisionObject::capsule_segment`] (negative inside).
    pub fn capsule_distance(&self, data: &Data, x: &Vector3<f64>) -> f64 {
        let (a, b, radius) = self.capsule_segment(data);
        let ab = b - a;
        let len2 = ab.norm_squared();
        let t = match len2 > 1e-12 {
            true => ((x - a).dot(&ab) / len2).clamp(0.0, 1.0),
            false => 0.0,
        };
        (x - (a + ab * t)).norm() - radius
    }

    /// The parry3d shape and its base-frame pose (after [`crate::forward_kinematics`]).
    pub fn parry(&self, data: &Data) -> (SharedShape, Isometry3<f64>) {
        let (shape, local) = self.shape.to_parry();
        (shape, self.pose(data).to_isometry() * local)
    }
}

/// Every collision object of the model as parry3d shapes with base-frame poses.
pub fn parry_shapes(model: &Model, data: &Data) -> Vec<(String, SharedShape, Isometry3<f64>)> {
    model
        .collisions
        .iter()
        .map(|c| {
            let (s, iso) = c.parry(data);
            (c.link.clone(), s, iso)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// distance from `p` to the capsule `(r, h, R)` minus its radius
    fn outside(p: Vector3<f64>, (r, h, rot): (f64, f64, Matrix3<f64>)) -> f64 {
        let local = rot.transpose() * p;
        let z = local.z.clamp(-h, h);
        (local - Vector3::new(0.0, 0.0, z)).norm() - r
    }

    #[test]
    fn the_capsule_of_a_shape_contains_it_and_is_tight_for_boxes() {
        for e in [
            Vector3::new(0.1, 0.2, 0.5),
            Vector3::new(0.5, 0.1, 0.2),
            Vector3::new(0.2, 0.5, 0.1),
            Vector3::new(0.3, 0.3, 0.3),
        ] {
            let b = Shape::Box { half_extents: e };
            let c = b.capsule();
            let mut touching = 0;
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    for sz in [-1.0, 1.0] {
                        let corner = Vector3::new(sx * e.x, sy * e.y, sz * e.z);
                        let d = outside(corner, c);
                        assert!(d <= 1e-12, "corner {corner:?} of {e:?} outside by {d}");
                        if d > -1e-12 {
                            touching += 1;
                        }
                    }
                }
            }
            assert_eq!(touching, 8, "every corner of {e:?} lies on its capsule");
            // the axis is the box's longest
            assert!((c.1 - e.max()).abs() < 1e-15);
        }
        let cyl = Shape::Cylinder {
            radius: 0.07,
            half_length: 0.2,
        };
        let c = cyl.capsule();
        for (x, z) in [(0.07, 0.2), (0.0, -0.2), (0.07, -0.2)] {
            assert!(outside(Vector3::new(x, 0.0, z), c) <= 1e-12);
        }
        assert_eq!(Shape::Sphere { radius: 0.1 }.capsule().1, 0.0);
    }
}
