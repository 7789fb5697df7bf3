//! Locked joints: Pinocchio's reduced model, a joint held at its zero.

use crate::error::ModelError;

/// Make the joints `locked` (and the joints that mimic one of them) fixed,
/// at their zero position: their origin stays as the URDF gives it.
pub fn lock_joints(robot: &mut urdf_rs::Robot, locked: &[String]) -> Result<(), ModelError> {
    for name in locked {
        let known = robot
            .joints
            .iter()
            .any(|j| &j.name == name && j.joint_type != urdf_rs::JointType::Fixed);
        if !known {
            return Err(ModelError::UnknownLockedJoint(name.clone()));
        }
    }
    for j in &mut robot.joints {
        let follows_locked = j.mimic.as_ref().is_some_and(|m| locked.contains(&m.joint));
        if locked.contains(&j.name) || follows_locked {
            j.joint_type = urdf_rs::JointType::Fixed;
            j.mimic = None;
        }
    }
    Ok(())
}
