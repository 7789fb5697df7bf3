//! A moving URDF joint as a [`Joint`]: its kind, unit axis and limits,
//! checked; its mass, its place in the arrays and its leader come later.

use nalgebra::{Matrix3, Vector3};

use super::checked::{finite, finite3};
use crate::error::ModelError;
use crate::model::{Joint, JointKind, Placement};

/// The joint `j` (revolute, continuous or prismatic) moving a new body,
/// child of body `parent` (`None`: the root), its frame at `q = 0` placed
/// at `placement` in the parent body's frame. Massless, its own column
/// (`idx_v` 0, set when the joints are ordered), no leader yet.
pub(super) fn moving_joint(
    j: &urdf_rs::Joint,
    parent: Option<usize>,
    placement: Placement,
) -> Result<Joint, ModelError> {
    let el = format!("joint '{}'", j.name);
    let axis = unit_axis(j, &el)?;
    let (kind, continuous) = match j.joint_type {
        urdf_rs::JointType::Prismatic => (JointKind::Prismatic, false),
        urdf_rs::JointType::Continuous => (JointKind::Revolute, true),
        _ => (JointKind::Revolute, false),
    };
    let (lower, upper) = position_limits(j, continuous, &el)?;
    let lim = &j.limit;
    // a continuous joint may have no <limit> (urdf-rs then reads effort =
    // velocity = 0): unlimited
    let no_limit = continuous && lim.effort == 0.0 && lim.velocity == 0.0;
    Ok(Joint {
        name: j.name.clone(),
        child_link: j.child.link.clone(),
        kind,
        parent,
        idx_v: 0,
        mimic: None,
        placement,
        axis,
        lower,
        upper,
        velocity: rate_limit(j, lim.velocity, no_limit, &el, "limit velocity")?,
        effort: rate_limit(j, lim.effort, no_limit, &el, "limit effort")?,
        mass: 0.0,
        com: Vector3::zeros(),
        inertia_com: Matrix3::zeros(),
    })
}

/// The joint's axis normalised, refusing a zero one.
fn unit_axis(j: &urdf_rs::Joint, el: &str) -> Result<Vector3<f64>, ModelError> {
    let axis = finite3(&j.axis.xyz.0, el, "axis")?;
    let norm = axis.norm();
    if norm < 1e-12 {
        return Err(ModelError::ZeroAxis {
            joint: j.name.clone(),
        });
    }
    Ok(axis / norm)
}

/// (lower, upper) [rad or m]: ±∞ for a continuous joint, else the URDF's,
/// refusing lower above upper.
fn position_limits(
    j: &urdf_rs::Joint,
    continuous: bool,
    el: &str,
) -> Result<(f64, f64), ModelError> {
    let (lower, upper) = if continuous {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        (
            finite(j.limit.lower, el, "limit lower")?,
            finite(j.limit.upper, el, "limit upper")?,
        )
    };
    if lower > upper {
        return Err(ModelError::Limits {
            joint: j.name.clone(),
            lower,
            upper,
        });
    }
    Ok((lower, upper))
}

/// A velocity or effort limit `x`: positive (0 or less is a typo that would
/// remove the clamp), or ∞ when the joint has no limit at all.
fn rate_limit(
    j: &urdf_rs::Joint,
    x: f64,
    no_limit: bool,
    el: &str,
    field: &'static str,
) -> Result<f64, ModelError> {
    let x = finite(x, el, field)?;
    if no_limit {
        Ok(f64::INFINITY)
    } else if x > 0.0 {
        Ok(x)
    } else {
        Err(ModelError::LimitNotPositive {
            joint: j.name.clone(),
            field,
            value: x,
        })
    }
}
