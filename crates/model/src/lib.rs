//! Robot model and rigid-body dynamics for phri.
//!
//! Shaped like Pinocchio: an immutable [`Model`] built once from a URDF, a
//! preallocated [`Data`] workspace, and algorithms as plain functions over
//! both that allocate nothing. Joint-space arrays follow the order of
//! [`Model::joints`]; Cartesian quantities are in the base frame, SI units.
//!
//! Supported: kinematic trees of revolute, continuous, prismatic and fixed
//! joints with any origins and axes. Floating, planar and spherical joints
//! are refused with an error naming the joint.
//!
//! Mimic joints (URDF `<mimic>`, e.g. the Panda's second finger) follow their
//! leader as in Pinocchio (`buildModelFromUrdf(…, mimic=True)`):
//! `q = multiplier · q_leader + offset`, no degree of freedom of their own, so
//! `nv` counts the actuated joints only and every term (`M`, `C`, `g`, RNEA,
//! Jacobians) is the reduced one, `Gᵀ (·) G` of the model with the mimic joint
//! free, `G` the constant map from the actuated to all joint velocities: the
//! mimic's motion adds `multiplier × its own axis` to its leader's column.
//! Refused, naming the joint: an unknown leader, a fixed leader, a leader that
//! is a mimic itself (chains and self-reference, refused by Pinocchio too), a
//! multiplier or offset that is not finite. Unlike Pinocchio, continuous
//! joints may lead or mimic (phri's configuration is an angle, not cos/sin)
//! and a leader may sit below its mimic in the tree. A `<mimic>` on a fixed
//! joint is ignored, as Pinocchio does.
//!
//! Refused as well, each naming the culprit: effort or velocity limits ≤ 0
//! (a revolute or prismatic joint must give both; a continuous joint without
//! `<limit>` is unlimited — urdf-rs reads it as effort = velocity = 0, so
//! exactly that pair means "no limit" on a continuous joint), two links or
//! two joints of one name, a joint that moves no mass or inertia (singular
//! `M` at every configuration), XML nested deeper than [`MAX_XML_DEPTH`]
//! (checked before parsing: the parser recurses), a file larger than
//! [`MAX_URDF_BYTES`].

#![deny(missing_docs)]

pub mod cholesky;
pub mod data;
pub mod dynamics;
pub mod error;
pub mod geometry;
pub mod kinematics;
pub mod model;
pub mod spatial;
mod urdf;
mod xml_depth;

pub use cholesky::{cholesky_factor, cholesky_solve, NotPositiveDefinite};
pub use data::Data;
pub use dynamics::{
    all_terms, coriolis_matrix, coriolis_times_qd, coriolis_transpose_times_qd, crba,
    forward_dynamics, gravity, kinetic_energy, momentum, potential_energy, residual_terms, rnea,
};
pub use error::{check_len, LengthError, ModelError};
pub use geometry::{parry_shapes, CollisionObject, Shape};
pub use kinematics::{forward_kinematics, frame_placement, point_jacobian};
pub use model::{lock_joints, Frame, Joint, JointKind, Mimic, Model, Placement, MAX_URDF_BYTES};
pub use xml_depth::MAX_XML_DEPTH;
