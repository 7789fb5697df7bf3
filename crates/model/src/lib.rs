//! Robot model and rigid-body dynamics for phri.
//!
//! Shaped like Pinocchio: an immutable [`Model`] built once from a URDF, a
//! preallocated [`Data`] workspace, and algorithms as plain functions over
//! both that allocate nothing. Joint-space arrays follow the order of
//! [`Model::joints`]; Cartesian quantities are in the base frame, SI units.
//!
//! Supported: kinematic trees of revolute, continuous, prismatic and fixed
//! joints with any origins and axes. Floating, planar, spherical and mimic
//! joints are refused with an error naming the joint.

pub mod data;
pub mod dynamics;
pub mod error;
pub mod geometry;
pub mod kinematics;
pub mod model;
pub mod spatial;

pub use data::Data;
pub use dynamics::{
    coriolis_matrix, coriolis_times_qd, coriolis_transpose_times_qd, crba, forward_dynamics,
    gravity, kinetic_energy, momentum, potential_energy, residual_terms, rnea,
};
pub use error::ModelError;
pub use geometry::{parry_shapes, CollisionObject, Shape};
pub use kinematics::{forward_kinematics, frame_placement, point_jacobian};
pub use model::{Frame, Joint, JointKind, Model, Placement};
