//! The robot's collision geometry as capsules at a joint state.

use nalgebra::{Point3, Vector3};
use phri_depth::Capsule;
use phri_model::{Data, Model, Shape};

/// Capsules of every collision object at the configuration last passed to
/// `forward_kinematics` (other shapes by their bounding sphere), into `out`.
pub fn robot_capsules(model: &Model, data: &Data, margin: f64, out: &mut Vec<Capsule>) {
    out.clear();
    for c in &model.collisions {
        let pose = c.pose(data);
        let (h, r) = match c.shape {
            Shape::Capsule {
                radius,
                half_length,
            }
            | Shape::Cylinder {
                radius,
                half_length,
            } => (half_length, radius),
            other => (0.0, other.bounding_radius()),
        };
        let a = pose.apply(&Vector3::new(0.0, 0.0, -h));
        let b = pose.apply(&Vector3::new(0.0, 0.0, h));
        out.push(Capsule::new(Point3::from(a), Point3::from(b), r + margin));
    }
}
