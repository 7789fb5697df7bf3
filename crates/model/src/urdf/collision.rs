//! A link's `<collision>` elements as primitive shapes in its body's frame.

use super::checked::{finite, finite3, pose};
use crate::error::ModelError;
use crate::geometry::{CollisionObject, Shape};
use crate::model::Placement;

/// Appends the collision geometry of `link` (riding on `body`, its frame at
/// `in_body` in the body's frame) to `collisions`; a mesh, which has no
/// primitive, adds the link's name to `skipped_meshes` instead. Refuses a
/// size or origin that is not finite.
pub(super) fn link_collisions(
    link: &urdf_rs::Link,
    body: Option<usize>,
    in_body: &Placement,
    collisions: &mut Vec<CollisionObject>,
    skipped_meshes: &mut Vec<String>,
) -> Result<(), ModelError> {
    for (ci, col) in link.collision.iter().enumerate() {
        let el = format!("link '{}' collision {}", link.name, ci);
        let placement = in_body.compose(&pose(&col.origin, &el)?);
        match shape(&col.geometry, &el)? {
            Some(shape) => collisions.push(CollisionObject {
                link: link.name.clone(),
                body,
                placement,
                shape,
            }),
            None => skipped_meshes.push(link.name.clone()),
        }
    }
    Ok(())
}

/// The primitive of a URDF geometry (sizes [m]); `None` for a mesh.
fn shape(geometry: &urdf_rs::Geometry, el: &str) -> Result<Option<Shape>, ModelError> {
    Ok(match geometry {
        urdf_rs::Geometry::Box { size } => Some(Shape::Box {
            half_extents: finite3(&size.0, el, "size")? * 0.5,
        }),
        urdf_rs::Geometry::Cylinder { radius, length } => Some(Shape::Cylinder {
            radius: finite(*radius, el, "radius")?,
            half_length: finite(*length, el, "length")? * 0.5,
        }),
        urdf_rs::Geometry::Capsule { radius, length } => Some(Shape::Capsule {
            radius: finite(*radius, el, "radius")?,
            half_length: finite(*length, el, "length")? * 0.5,
        }),
        urdf_rs::Geometry::Sphere { radius } => Some(Shape::Sphere {
            radius: finite(*radius, el, "radius")?,
        }),
        urdf_rs::Geometry::Mesh { .. } => None,
    })
}
