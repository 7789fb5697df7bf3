//! Link collision geometry as primitives, convertible to parry3d shapes.

use nalgebra::{Isometry3, Vector3};
use parry3d_f64::shape::SharedShape;

use crate::data::Data;
use crate::model::{Model, Placement};

/// A collision primitive in its own frame. Capsules and cylinders lie along
/// their frame's z axis, as in URDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// segment from `−half_length ẑ` to `+half_length ẑ` swept by a sphere [m]
    Capsule { radius: f64, half_length: f64 },
    /// cylinder along z [m]
    Cylinder { radius: f64, half_length: f64 },
    /// sphere [m]
    Sphere { radius: f64 },
    /// box with half side lengths [m]
    Box { half_extents: Vector3<f64> },
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

    /// Radius of the smallest sphere around the shape's origin that holds it [m].
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
