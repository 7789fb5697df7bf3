//! Mimic joints: every `<mimic>` checked, and the joints reordered so the
//! actuated ones come first (one column each) and the mimic ones after,
//! each following its leader's column.

use std::collections::HashMap;

use super::bodies::Bodies;
use super::checked::finite;
use crate::error::ModelError;
use crate::model::{Joint, Mimic};

/// A checked `<mimic>`: leader (URDF joint index), multiplier, offset.
pub(super) type UrdfMimic = (usize, f64, f64);

/// Check every `<mimic>` of a moving joint (a fixed joint's is ignored, as
/// Pinocchio does): its leader must exist, move, and not be a mimic joint
/// itself (Pinocchio refuses chains); multiplier (default 1) and offset
/// (default 0) must be finite. Returns per URDF joint `(leader, multiplier,
/// offset)`, the leader as a URDF joint index.
pub(super) fn mimics(robot: &urdf_rs::Robot) -> Result<Vec<Option<UrdfMimic>>, ModelError> {
    let by_name: HashMap<&str, usize> = robot
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| (j.name.as_str(), i))
        .collect();
    let moving = |j: &urdf_rs::Joint| j.joint_type != urdf_rs::JointType::Fixed;
    let mut out = Vec::with_capacity(robot.joints.len());
    for j in &robot.joints {
        let Some(m) = j.mimic.as_ref().filter(|_| moving(j)) else {
            out.push(None);
            continue;
        };
        let el = format!("joint '{}' mimic", j.name);
        let multiplier = finite(m.multiplier.unwrap_or(1.0), &el, "multiplier")?;
        let offset = finite(m.offset.unwrap_or(0.0), &el, "offset")?;
        let leader =
            *by_name
                .get(m.joint.as_str())
                .ok_or_else(|| ModelError::MimicUnknownLeader {
                    joint: j.name.clone(),
                    leader: m.joint.clone(),
                })?;
        let l = &robot.joints[leader];
        if !moving(l) {
            return Err(ModelError::MimicLeaderFixed {
                joint: j.name.clone(),
                leader: l.name.clone(),
            });
        }
        if l.mimic.is_some() {
            return Err(ModelError::MimicChain {
                joint: j.name.clone(),
                leader: l.name.clone(),
            });
        }
        out.push(Some((leader, multiplier, offset)));
    }
    Ok(out)
}

/// Reorders the joints of `bodies` actuated first, mimic after, each in
/// depth-first order (the identity without mimic joints), renumbering the
/// parents, frames and collision objects, and gives every joint its column
/// (`idx_v`) and every mimic joint its leader. Returns `nv`, the number of
/// actuated joints, and the depth-first preorder (parents first) in the new
/// indices; refuses a robot without an actuated joint.
pub(super) fn actuated_first(
    bodies: &mut Bodies,
    mimic_of: &[Option<UrdfMimic>],
) -> Result<(usize, Vec<usize>), ModelError> {
    let n = bodies.joints.len();
    let urdf_joint = &bodies.urdf_joint;
    let is_mimic = |b: usize| mimic_of[urdf_joint[b]].is_some();
    let mut new_index = vec![0usize; n];
    let mut body_of_urdf: HashMap<usize, usize> = HashMap::with_capacity(n);
    let (mut actuated, mut followers) = (0usize, 0usize);
    let nv = (0..n).filter(|&b| !is_mimic(b)).count();
    for b in 0..n {
        new_index[b] = if is_mimic(b) {
            followers += 1;
            nv + followers - 1
        } else {
            actuated += 1;
            actuated - 1
        };
        body_of_urdf.insert(urdf_joint[b], new_index[b]);
    }
    if nv == 0 {
        return Err(ModelError::NoActuatedJoint);
    }
    let mut slots: Vec<Option<Joint>> = (0..n).map(|_| None).collect();
    for (b, mut j) in std::mem::take(&mut bodies.joints).into_iter().enumerate() {
        j.parent = j.parent.map(|p| new_index[p]);
        let i = new_index[b];
        j.idx_v = i;
        if let Some((leader, multiplier, offset)) = mimic_of[bodies.urdf_joint[b]] {
            // the leader moves (checked) and every link was reached: it is a body
            let leader = *body_of_urdf.get(&leader).ok_or(ModelError::NoRoot)?;
            j.idx_v = leader;
            j.mimic = Some(Mimic {
                leader,
                multiplier,
                offset,
            });
        }
        slots[i] = Some(j);
    }
    bodies.joints = slots.into_iter().flatten().collect();
    debug_assert_eq!(bodies.joints.len(), n);
    for f in &mut bodies.frames {
        f.body = f.body.map(|b| new_index[b]);
    }
    for c in &mut bodies.collisions {
        c.body = c.body.map(|b| new_index[b]);
    }
    // depth-first preorder (parents first) in the new indices
    Ok((nv, new_index))
}
