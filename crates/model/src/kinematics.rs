//! Forward kinematics and Jacobians.

use nalgebra::{Matrix6xX, Vector3};

use crate::data::Data;
use crate::error::{check_len, ModelError};
use crate::model::{JointKind, Model, Placement};
use crate::spatial::{axis_angle, Inertia, Motion};

/// Body placements and base-frame motion subspaces for configuration `q`
/// (one value per actuated joint; mimic joints follow their leaders).
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), ModelError> {
    check_len("q", model.nv(), q.len())?;
    fk_pass(model, data, q);
    Ok(())
}

/// FK without the length check (callers have checked).
#[inline]
pub(crate) fn fk_pass(model: &Model, data: &mut Data, q: &[f64]) {
    for &i in model.order() {
        let j = &model.joints[i];
        let qi = model.joint_position(i, q);
        let parent = data.body_placement(j.parent);
        let joint_frame = parent.compose(&j.placement);
        let axis = joint_frame.r * j.axis;
        let s = match j.kind {
            JointKind::Revolute => {
                data.body[i] = Placement {
                    r: joint_frame.r * axis_angle(&j.axis, qi),
                    p: joint_frame.p,
                };
                Motion::new(axis, joint_frame.p.cross(&axis))
            }
            JointKind::Prismatic => {
                data.body[i] = Placement {
                    r: joint_frame.r,
                    p: joint_frame.p + axis * qi,
                };
                Motion::new(Vector3::zeros(), axis)
            }
        };
        // a mimic joint moves `multiplier` times as fast as its leader
        data.s[i] = match j.mimic {
            None => s,
            Some(m) => s.scale(m.multiplier),
        };
    }
}

/// Body spatial inertias in the base frame (after [`fk_pass`]).
#[inline]
pub(crate) fn inertia_pass(model: &Model, data: &mut Data) {
    for (i, j) in model.joints.iter().enumerate() {
        let b = &data.body[i];
        let c = b.apply(&j.com);
        let i_c = b.r * j.inertia_com * b.r.transpose();
        data.inertia[i] = Inertia::from_com(j.mass, &c, &i_c);
    }
}

/// Body velocities and `Ṡ` (after [`fk_pass`]).
#[inline]
pub(crate) fn velocity_pass(model: &Model, data: &mut Data, qd: &[f64]) {
    for &i in model.order() {
        let j = &model.joints[i];
        let vp = match j.parent {
            Some(p) => data.v[p],
            None => Motion::ZERO,
        };
        data.v[i] = vp + data.s[i].scale(qd[j.idx_v]);
        data.s_dot[i] = data.v[i].cross_motion(&data.s[i]);
    }
}

/// Placement of link frame `frame` in the base frame (after [`forward_kinematics`]).
pub fn frame_placement(model: &Model, data: &Data, frame: usize) -> Placement {
    let f = &model.frames[frame];
    data.body_placement(f.body).compose(&f.placement)
}

/// Geometric Jacobian (6×n, linear rows then angular rows, base-frame axes)
/// of the point `point` \[m\] fixed in link frame `frame`, after
/// [`forward_kinematics`]. Columns of joints that do not move the link are
/// zero; a mimic joint that moves it adds its motion to its leader's column.
pub fn point_jacobian(
    model: &Model,
    data: &Data,
    frame: usize,
    point: &Vector3<f64>,
    out: &mut Matrix6xX<f64>,
) -> Result<(), ModelError> {
    check_len("jacobian columns", model.nv(), out.ncols())?;
    let f = model
        .frames
        .get(frame)
        .ok_or_else(|| ModelError::UnknownLink(format!("#{frame}")))?;
    out.fill(0.0);
    let p = data
        .body_placement(f.body)
        .compose(&f.placement)
        .apply(point);
    let mut k = f.body;
    while let Some(j) = k {
        let s = &data.s[j];
        let col = model.joints[j].idx_v;
        let lin = s.velocity_at(&p);
        for a in 0..3 {
            out[(a, col)] += lin[a];
            out[(3 + a, col)] += s.w[a];
        }
        k = model.joints[j].parent;
    }
    Ok(())
}
