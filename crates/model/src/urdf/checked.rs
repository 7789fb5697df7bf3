//! The URDF's numbers, checked finite where they are read.

use nalgebra::Vector3;

use crate::error::ModelError;
use crate::model::Placement;
use crate::spatial::rpy_to_matrix;

/// `x`, or [`ModelError::NotFinite`] naming `element` and `field`.
pub(super) fn finite(x: f64, element: &str, field: &str) -> Result<f64, ModelError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ModelError::NotFinite {
            element: element.to_string(),
            field: field.to_string(),
        })
    }
}

/// `v` as a vector, or [`ModelError::NotFinite`] naming `element` and `field`.
pub(super) fn finite3(
    v: &[f64; 3],
    element: &str,
    field: &str,
) -> Result<Vector3<f64>, ModelError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vector3::new(v[0], v[1], v[2]))
    } else {
        Err(ModelError::NotFinite {
            element: element.to_string(),
            field: field.to_string(),
        })
    }
}

/// An `<origin xyz rpy>` as a placement: translation [m], rotation from
/// roll, pitch, yaw [rad] (fixed axes x, y, z).
pub(super) fn pose(p: &urdf_rs::Pose, element: &str) -> Result<Placement, ModelError> {
    let xyz = finite3(&p.xyz.0, element, "origin xyz")?;
    let rpy = finite3(&p.rpy.0, element, "origin rpy")?;
    Ok(Placement {
        r: rpy_to_matrix(rpy.x, rpy.y, rpy.z),
        p: xyz,
    })
}
