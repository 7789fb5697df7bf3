//! The immutable robot model, built once from a URDF (`crate::urdf`).

use std::collections::HashMap;

use nalgebra::{Matrix3, Vector3};

use crate::error::ModelError;
use crate::geometry::{CollisionObject, Shape};

pub use crate::urdf::lock_joints;

/// Largest URDF file read \[bytes\]: robot descriptions are kilobytes (meshes
/// are separate files), so 16 MiB leaves ample room and bounds what a
/// wrong path (a log, a device) costs.
pub const MAX_URDF_BYTES: u64 = 16 << 20;

/// Kind of an actuated joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// rotation about `axis` \[rad\]; continuous joints are revolute with infinite position limits
    Revolute,
    /// translation along `axis` \[m\]
    Prismatic,
}

/// A rigid placement: rotation and translation of a child frame in its parent frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// rotation, child axes in parent coordinates
    pub r: Matrix3<f64>,
    /// origin of the child frame \[m\], parent frame
    pub p: Vector3<f64>,
}

impl Placement {
    /// the identity: child frame = parent frame
    pub const IDENTITY: Placement = Placement {
        r: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        p: Vector3::new(0.0, 0.0, 0.0),
    };

    /// `self ∘ other`: `other` expressed in `self`'s parent frame.
    #[inline]
    pub fn compose(&self, other: &Placement) -> Placement {
        Placement {
            r: self.r * other.r,
            p: self.p + self.r * other.p,
        }
    }

    /// Transform a point from the child frame to the parent frame.
    #[inline]
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.p + self.r * x
    }

    /// 4×4 homogeneous matrix.
    pub fn to_homogeneous(&self) -> nalgebra::Matrix4<f64> {
        let mut m = nalgebra::Matrix4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.r);
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.p);
        m
    }

    /// As a nalgebra isometry (re-orthonormalised rotation).
    pub fn to_isometry(&self) -> nalgebra::Isometry3<f64> {
        let rot = nalgebra::Rotation3::from_matrix(&self.r);
        nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::from(self.p),
            nalgebra::UnitQuaternion::from_rotation_matrix(&rot),
        )
    }
}

/// How a mimic joint follows its leader (URDF `<mimic>`, as in Pinocchio):
/// `q = multiplier · q_leader + offset`, so `q̇ = multiplier · q̇_leader`. The
/// mimic joint has no degree of freedom of its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mimic {
    /// index of the leader in [`Model::joints`]: an actuated joint (`< nv`)
    pub leader: usize,
    /// [rad/rad, m/m, m/rad or rad/m, after the two joints' kinds]
    pub multiplier: f64,
    /// [rad or m, the mimic joint's unit]
    pub offset: f64,
}

/// One moving joint and the rigid body it moves: an actuated joint (one
/// degree of freedom) or a mimic joint that follows one.
#[derive(Clone, Debug)]
pub struct Joint {
    /// joint name from the URDF
    pub name: String,
    /// URDF link that is this joint's child (the body frame)
    pub child_link: String,
    /// revolute (continuous included) or prismatic
    pub kind: JointKind,
    /// index of the parent joint, `None` when the parent body is the root
    pub parent: Option<usize>,
    /// column of the joint's motion in every joint-space array (Pinocchio's
    /// `idx_v`): its own index for an actuated joint, its leader's for a mimic joint
    pub idx_v: usize,
    /// `Some` for a mimic joint: the leader it follows
    pub mimic: Option<Mimic>,
    /// joint frame in the parent body frame at `q = 0`
    pub placement: Placement,
    /// unit axis, joint frame
    pub axis: Vector3<f64>,
    /// position limits [rad or m]; ±∞ for continuous joints. The limits
    /// (position, velocity, effort) of a mimic joint are the URDF's, checked
    /// like any joint's but enforced by nothing: it has no degree of freedom
    /// (Pinocchio keeps none for it either)
    pub lower: f64,
    /// upper position limit \[rad or m\]; +∞ for continuous joints (see `lower`)
    pub upper: f64,
    /// velocity limit [rad/s or m/s], > 0; ∞ only for a continuous joint
    /// without `<limit>`
    pub velocity: f64,
    /// effort limit [Nm or N], > 0; ∞ only for a continuous joint without `<limit>`
    pub effort: f64,
    /// mass \[kg\], centre of mass \[m\] and inertia about it [kg m²] of the
    /// body (links rigidly attached by fixed joints merged), body frame
    pub mass: f64,
    /// centre of mass of the body \[m\], body frame
    pub com: Vector3<f64>,
    /// rotational inertia of the body about its centre of mass \[kg m²\], body-frame axes
    pub inertia_com: Matrix3<f64>,
}

/// A URDF link as a frame rigidly attached to a body.
#[derive(Clone, Debug)]
pub struct Frame {
    /// link name from the URDF
    pub name: String,
    /// body the link is attached to: the joint index, `None` for the root body
    pub body: Option<usize>,
    /// link frame in that body's frame
    pub placement: Placement,
}

/// Immutable robot model. Joint `i` moves body `i`. The actuated joints
/// come first, in depth-first order: joint `i < nv` is column `i` of every
/// joint-space array. Mimic joints follow, in depth-first order; a parent may
/// then come after its child, so recursions run in [`Model::order`].
#[derive(Clone, Debug)]
pub struct Model {
    /// robot name from the URDF
    pub name: String,
    /// moving joints: the [`Model::nv`] actuated ones, then the mimic ones
    pub joints: Vec<Joint>,
    /// every URDF link, with the body it rides on
    pub frames: Vec<Frame>,
    /// link collision geometry
    pub collisions: Vec<CollisionObject>,
    /// collision meshes that were skipped (not convertible to primitives): link names
    pub skipped_meshes: Vec<String>,
    /// gravity acceleration [m/s²], base frame
    pub gravity: Vector3<f64>,
    /// mass attached rigidly to the root (does not enter the dynamics) \[kg\]
    pub root_mass: f64,
    /// rotor inertia reflected at each actuated joint [kg m² or kg], added
    /// to `M`'s diagonal (zero unless [`Model::set_armature`] gives it: a
    /// URDF has no place for it)
    pub armature: Vec<f64>,
    /// number of actuated joints (= configuration and velocity dimension)
    pub(crate) nv: usize,
    /// every joint index once, parents before children (depth-first preorder)
    pub(crate) order: Vec<usize>,
    pub(crate) frame_index: HashMap<String, usize>,
}

impl Model {
    /// The mass of the moving parts \[kg\]: every body a joint moves (what is
    /// rigidly attached to the root is not).
    pub fn moving_mass(&self) -> f64 {
        self.joints.iter().map(|j| j.mass).sum()
    }

    /// Number of actuated joints (= configuration and velocity dimension;
    /// mimic joints have none of their own, as in Pinocchio).
    #[inline]
    pub fn nv(&self) -> usize {
        self.nv
    }

    /// The actuated joints, in array order: `actuated()[i]` is column `i`
    /// of every joint-space array (limits per degree of freedom come from here).
    #[inline]
    pub fn actuated(&self) -> &[Joint] {
        &self.joints[..self.nv]
    }

    /// The mimic joints (those after the actuated ones in [`Model::joints`]).
    #[inline]
    pub fn mimic_joints(&self) -> &[Joint] {
        &self.joints[self.nv..]
    }

    /// Every joint index once, parents before children: the order of the
    /// forward recursions (backward ones run it reversed).
    #[inline]
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// Position of joint `i` [rad or m] in configuration `q` (one value per
    /// actuated joint): `q[i]`, or `multiplier · q[leader] + offset` for a mimic joint.
    #[inline]
    pub fn joint_position(&self, i: usize, q: &[f64]) -> f64 {
        match self.joints[i].mimic {
            None => q[i],
            Some(m) => m.multiplier * q[m.leader] + m.offset,
        }
    }

    /// Index of a link frame by name.
    pub fn frame_id(&self, link: &str) -> Result<usize, ModelError> {
        self.frame_index
            .get(link)
            .copied()
            .ok_or_else(|| ModelError::UnknownLink(link.to_string()))
    }

    /// The rotor inertia reflected at each actuated joint \[kg m² or kg\]
    /// (a robot file's `armature`): `M` gains it on its diagonal, the
    /// torque of RNEA `armature ⊙ q̈`, the momentum `armature ⊙ q̇`.
    pub fn set_armature(&mut self, armature: &[f64]) -> Result<(), ModelError> {
        crate::check_len("armature", self.nv, armature.len())?;
        if let Some(bad) = armature.iter().find(|a| !(a.is_finite() && **a >= 0.0)) {
            return Err(ModelError::NotFinite {
                element: "armature".into(),
                field: format!("{bad} (must be finite and ≥ 0)"),
            });
        }
        self.armature.copy_from_slice(armature);
        Ok(())
    }

    /// Adds a capsule to link `link`'s collision geometry: the segment
    /// `a`–`b` \[m\] (link frame) swept by a sphere of `radius` \[m\] (a
    /// robot whose URDF has only mesh collisions gets its capsules from its
    /// robot file this way).
    pub fn add_capsule(
        &mut self,
        link: &str,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        radius: f64,
    ) -> Result<(), ModelError> {
        let element = format!("capsule on link '{link}'");
        if !a.iter().chain(b.iter()).all(|x| x.is_finite()) {
            return Err(ModelError::NotFinite {
                element,
                field: "a or b".into(),
            });
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(ModelError::NotFinite {
                element,
                field: "radius (> 0)".into(),
            });
        }
        let frame = &self.frames[self.frame_id(link)?];
        let d = b - a;
        let len = d.norm();
        // z onto the segment's direction
        let r = match len > 1e-9 {
            true => {
                let u = d / len;
                let z = Vector3::z();
                let axis = z.cross(&u);
                let (sin, cos) = (axis.norm(), z.dot(&u));
                match sin > 1e-12 {
                    true => crate::spatial::axis_angle(&(axis / sin), sin.atan2(cos)),
                    false if cos > 0.0 => Matrix3::identity(),
                    false => crate::spatial::axis_angle(&Vector3::x(), std::f64::consts::PI),
                }
            }
            false => Matrix3::identity(),
        };
        let placement = frame.placement.compose(&Placement {
            r,
            p: (a + b) * 0.5,
        });
        self.collisions.push(CollisionObject {
            link: link.to_string(),
            body: frame.body,
            placement,
            shape: Shape::Capsule {
                radius,
                half_length: len * 0.5,
            },
        });
        Ok(())
    }

    /// Actuated joint names, in array order.
    pub fn joint_names(&self) -> Vec<&str> {
        self.actuated().iter().map(|j| j.name.as_str()).collect()
    }

    /// Is joint `j` an ancestor of (or equal to) joint `i`?
    #[inline]
    pub fn supports(&self, j: usize, i: usize) -> bool {
        let mut k = Some(i);
        while let Some(x) = k {
            if x == j {
                return true;
            }
            k = self.joints[x].parent;
        }
        false
    }
}
