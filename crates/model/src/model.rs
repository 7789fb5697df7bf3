//! The immutable robot model, built once from a URDF.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use crate::error::ModelError;
use crate::geometry::{CollisionObject, Shape};
use crate::spatial::rpy_to_matrix;
use crate::xml_depth::{check_depth, MAX_XML_DEPTH};

/// Largest URDF file read [bytes]: robot descriptions are kilobytes (meshes
/// are separate files), so 16 MiB leaves ample room and bounds what a
/// wrong path (a log, a device) costs.
pub const MAX_URDF_BYTES: u64 = 16 << 20;

/// Kind of an actuated joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// rotation about `axis` [rad]; continuous joints are revolute with infinite position limits
    Revolute,
    /// translation along `axis` [m]
    Prismatic,
}

/// A rigid placement: rotation and translation of a child frame in its parent frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// rotation, child axes in parent coordinates
    pub r: Matrix3<f64>,
    /// origin of the child frame [m], parent frame
    pub p: Vector3<f64>,
}

impl Placement {
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
    pub upper: f64,
    /// velocity limit [rad/s or m/s], > 0; ∞ only for a continuous joint
    /// without `<limit>`
    pub velocity: f64,
    /// effort limit [Nm or N], > 0; ∞ only for a continuous joint without `<limit>`
    pub effort: f64,
    /// mass [kg], centre of mass [m] and inertia about it [kg m²] of the
    /// body (links rigidly attached by fixed joints merged), body frame
    pub mass: f64,
    pub com: Vector3<f64>,
    pub inertia_com: Matrix3<f64>,
}

/// A URDF link as a frame rigidly attached to a body.
#[derive(Clone, Debug)]
pub struct Frame {
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
    /// mass attached rigidly to the root (does not enter the dynamics) [kg]
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

fn finite3(v: &[f64; 3], element: &str, field: &str) -> Result<Vector3<f64>, ModelError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vector3::new(v[0], v[1], v[2]))
    } else {
        Err(ModelError::NotFinite {
            element: element.to_string(),
            field: field.to_string(),
        })
    }
}

fn pose(p: &urdf_rs::Pose, element: &str) -> Result<Placement, ModelError> {
    let xyz = finite3(&p.xyz.0, element, "origin xyz")?;
    let rpy = finite3(&p.rpy.0, element, "origin rpy")?;
    Ok(Placement {
        r: rpy_to_matrix(rpy.x, rpy.y, rpy.z),
        p: xyz,
    })
}

fn finite(x: f64, element: &str, field: &str) -> Result<f64, ModelError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ModelError::NotFinite {
            element: element.to_string(),
            field: field.to_string(),
        })
    }
}

/// Mass properties accumulated in a body frame.
#[derive(Clone, Copy)]
struct MassProps {
    m: f64,
    /// Σ m c
    h: Vector3<f64>,
    /// Σ (I_c + m (|c|² 1 − c cᵀ)), about the body origin
    i_o: Matrix3<f64>,
}

impl MassProps {
    const ZERO: MassProps = MassProps {
        m: 0.0,
        h: Vector3::new(0.0, 0.0, 0.0),
        i_o: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    fn add(&mut self, m: f64, c: &Vector3<f64>, i_c: &Matrix3<f64>) {
        self.m += m;
        self.h += c * m;
        self.i_o += i_c + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * m;
    }

    /// (mass, com, inertia about com)
    fn split(&self) -> (f64, Vector3<f64>, Matrix3<f64>) {
        if self.m <= 0.0 {
            return (0.0, Vector3::zeros(), Matrix3::zeros());
        }
        let c = self.h / self.m;
        let i_c = self.i_o - (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * self.m;
        (self.m, c, i_c)
    }
}

/// Every joint must move some mass, whatever the configuration: a prismatic
/// joint some mass in its subtree, a revolute one some mass or rotational
/// inertia (a body keeps inertia only with mass: [`MassProps::split`]). Otherwise its column of `M` is zero at every `q` (singular `M`:
/// forward dynamics, the residual and the controller's inverse fail).
/// Configuration-dependent singularities (mass only on the axis) are the
/// configuration's check (`phri-config`, at the start posture). An actuated
/// joint moves its own subtree and those of its mimic joints whose multiplier
/// is not zero; the deepest joint that moves nothing is named.
fn moves_mass(joints: &[Joint], order: &[usize], nv: usize) -> Result<(), ModelError> {
    let mut mass: Vec<f64> = joints.iter().map(|j| j.mass).collect();
    let mut inertia: Vec<f64> = joints.iter().map(|j| j.inertia_com.trace()).collect();
    for &i in order.iter().rev() {
        if let Some(p) = joints[i].parent {
            mass[p] += mass[i];
            inertia[p] += inertia[i];
        }
    }
    let mut moves = vec![false; nv];
    for (i, j) in joints.iter().enumerate() {
        let scale = j.mimic.map_or(1.0, |m| m.multiplier);
        let subtree = match j.kind {
            JointKind::Prismatic => mass[i] > 0.0,
            JointKind::Revolute => mass[i] > 0.0 || inertia[i] > 0.0,
        };
        moves[j.idx_v] |= scale != 0.0 && subtree;
    }
    match moves.iter().rposition(|&m| !m) {
        Some(i) => Err(ModelError::MovesNoMass {
            joint: joints[i].name.clone(),
        }),
        None => Ok(()),
    }
}

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

/// A checked `<mimic>`: leader (URDF joint index), multiplier, offset.
type UrdfMimic = (usize, f64, f64);

/// Check every `<mimic>` of a moving joint (a fixed joint's is ignored, as
/// Pinocchio does): its leader must exist, move, and not be a mimic joint
/// itself (Pinocchio refuses chains); multiplier (default 1) and offset
/// (default 0) must be finite. Returns per URDF joint `(leader, multiplier,
/// offset)`, the leader as a URDF joint index.
fn mimics(robot: &urdf_rs::Robot) -> Result<Vec<Option<UrdfMimic>>, ModelError> {
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

impl Model {
    /// Build from a URDF file (at most [`MAX_URDF_BYTES`]: a larger one is
    /// refused without being read whole).
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<Model, ModelError> {
        Self::from_urdf_file_locked(path, &[])
    }

    /// The URDF text of `path` (at most [`MAX_URDF_BYTES`]).
    fn read_urdf(path: &Path) -> Result<String, ModelError> {
        use std::io::Read;
        let io = |source| ModelError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let mut bytes = Vec::new();
        // one byte more than allowed tells a file that is too large (even one
        // whose size the file system does not report, such as a pipe)
        file.take(MAX_URDF_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        if bytes.len() as u64 > MAX_URDF_BYTES {
            return Err(ModelError::TooLarge {
                path: path.to_path_buf(),
                max: MAX_URDF_BYTES,
            });
        }
        String::from_utf8(bytes).map_err(|_| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "not UTF-8 text",
            ))
        })
    }

    /// Build from URDF text.
    pub fn from_urdf_str(text: &str) -> Result<Model, ModelError> {
        Self::from_urdf_str_named(text, "<urdf>")
    }

    /// Build from a URDF file with the joints `locked` held at their zero
    /// (Pinocchio's reduced model): a gripper's fingers, which have a
    /// controller of their own, so the model has the arm's joints only.
    /// Joints that mimic a locked joint are locked with it.
    pub fn from_urdf_file_locked(
        path: impl AsRef<Path>,
        locked: &[String],
    ) -> Result<Model, ModelError> {
        let path = path.as_ref();
        let text = Self::read_urdf(path)?;
        let mut robot = Self::parse(&text, &path.display().to_string())?;
        lock_joints(&mut robot, locked)?;
        Self::from_urdf(&robot)
    }

    /// [`Model::from_urdf_file_locked`] from URDF text.
    pub fn from_urdf_str_locked(text: &str, locked: &[String]) -> Result<Model, ModelError> {
        let mut robot = Self::parse(text, "<urdf>")?;
        lock_joints(&mut robot, locked)?;
        Self::from_urdf(&robot)
    }

    fn from_urdf_str_named(text: &str, origin: &str) -> Result<Model, ModelError> {
        Self::from_urdf(&Self::parse(text, origin)?)
    }

    fn parse(text: &str, origin: &str) -> Result<urdf_rs::Robot, ModelError> {
        // the parser recurses per nesting level: bound the depth before it runs
        check_depth(text, MAX_XML_DEPTH).map_err(|_| ModelError::TooDeep {
            origin: origin.to_string(),
            max: MAX_XML_DEPTH,
        })?;
        // urdf-rs sorts elements with a string pass before parsing; guard against panics deep in it
        let parsed =
            std::panic::catch_unwind(|| urdf_rs::read_from_string(text)).map_err(|_| {
                ModelError::Parse {
                    origin: origin.to_string(),
                    message: "parser failed".into(),
                }
            })?;
        parsed.map_err(|e| ModelError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })
    }

    /// Build from a parsed URDF.
    pub fn from_urdf(robot: &urdf_rs::Robot) -> Result<Model, ModelError> {
        let mut link_index: HashMap<&str, usize> = HashMap::with_capacity(robot.links.len());
        for (i, l) in robot.links.iter().enumerate() {
            if link_index.insert(l.name.as_str(), i).is_some() {
                return Err(ModelError::DuplicateName {
                    element: "link",
                    name: l.name.clone(),
                });
            }
        }
        let mut joint_names: HashSet<&str> = HashSet::with_capacity(robot.joints.len());
        for j in &robot.joints {
            if !joint_names.insert(j.name.as_str()) {
                return Err(ModelError::DuplicateName {
                    element: "joint",
                    name: j.name.clone(),
                });
            }
        }
        // children per link in file order, parent joint per link
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
        let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
        for (ji, j) in robot.joints.iter().enumerate() {
            let p =
                *link_index
                    .get(j.parent.link.as_str())
                    .ok_or_else(|| ModelError::MissingLink {
                        joint: j.name.clone(),
                        link: j.parent.link.clone(),
                    })?;
            let c =
                *link_index
                    .get(j.child.link.as_str())
                    .ok_or_else(|| ModelError::MissingLink {
                        joint: j.name.clone(),
                        link: j.child.link.clone(),
                    })?;
            if parent_joint[c].is_some() {
                return Err(ModelError::SeveralParents {
                    link: j.child.link.clone(),
                });
            }
            parent_joint[c] = Some(ji);
            children[p].push(ji);
            match j.joint_type {
                urdf_rs::JointType::Revolute
                | urdf_rs::JointType::Continuous
                | urdf_rs::JointType::Prismatic
                | urdf_rs::JointType::Fixed => {}
                ref other => {
                    return Err(ModelError::UnsupportedJoint {
                        joint: j.name.clone(),
                        kind: format!("{other:?}").to_lowercase(),
                    });
                }
            }
        }
        let mimic_of = mimics(robot)?;
        let roots: Vec<usize> = (0..robot.links.len())
            .filter(|&i| parent_joint[i].is_none())
            .collect();
        let root = match roots.as_slice() {
            [] => return Err(ModelError::NoRoot),
            [r] => *r,
            _ => {
                return Err(ModelError::SeveralRoots {
                    roots: roots.iter().map(|&i| robot.links[i].name.clone()).collect(),
                })
            }
        };

        let mut joints: Vec<Joint> = Vec::new();
        // URDF joint index of each body, in depth-first order
        let mut urdf_joint: Vec<usize> = Vec::new();
        let mut frames: Vec<Frame> = Vec::new();
        let mut props: Vec<MassProps> = Vec::new();
        let mut root_props = MassProps::ZERO;
        let mut collisions = Vec::new();
        let mut skipped_meshes = Vec::new();

        // depth-first preorder, children in file order. A stack entry is a link, the URDF
        // joint that leads to it when that joint is actuated, the body its parent rides on and
        // its placement in that body (for an actuated joint: the joint frame at q = 0).
        let mut stack: Vec<(usize, Option<usize>, Option<usize>, Placement)> =
            vec![(root, None, None, Placement::IDENTITY)];
        let mut visited = 0usize;
        while let Some((li, via, parent_body, placement)) = stack.pop() {
            visited += 1;
            if visited > robot.links.len() {
                return Err(ModelError::NoRoot);
            }
            let (body, in_body) = match via {
                None => (parent_body, placement),
                Some(ji) => {
                    let j = &robot.joints[ji];
                    let el = format!("joint '{}'", j.name);
                    let axis = finite3(&j.axis.xyz.0, &el, "axis")?;
                    let norm = axis.norm();
                    if norm < 1e-12 {
                        return Err(ModelError::ZeroAxis {
                            joint: j.name.clone(),
                        });
                    }
                    let (kind, continuous) = match j.joint_type {
                        urdf_rs::JointType::Prismatic => (JointKind::Prismatic, false),
                        urdf_rs::JointType::Continuous => (JointKind::Revolute, true),
                        _ => (JointKind::Revolute, false),
                    };
                    let lim = &j.limit;
                    let (lower, upper) = if continuous {
                        (f64::NEG_INFINITY, f64::INFINITY)
                    } else {
                        (
                            finite(lim.lower, &el, "limit lower")?,
                            finite(lim.upper, &el, "limit upper")?,
                        )
                    };
                    if lower > upper {
                        return Err(ModelError::Limits {
                            joint: j.name.clone(),
                            lower,
                            upper,
                        });
                    }
                    // effort and velocity must be positive: 0 or less is a typo
                    // that would remove the clamp. A continuous joint may have no
                    // <limit> (urdf-rs then reads effort = velocity = 0): unlimited.
                    let no_limit = continuous && lim.effort == 0.0 && lim.velocity == 0.0;
                    let positive_or_inf = |x: f64, f: &'static str| -> Result<f64, ModelError> {
                        let x = finite(x, &el, f)?;
                        if no_limit {
                            Ok(f64::INFINITY)
                        } else if x > 0.0 {
                            Ok(x)
                        } else {
                            Err(ModelError::LimitNotPositive {
                                joint: j.name.clone(),
                                field: f,
                                value: x,
                            })
                        }
                    };
                    joints.push(Joint {
                        name: j.name.clone(),
                        child_link: j.child.link.clone(),
                        kind,
                        parent: parent_body,
                        idx_v: 0,
                        mimic: None,
                        placement,
                        axis: axis / norm,
                        lower,
                        upper,
                        velocity: positive_or_inf(lim.velocity, "limit velocity")?,
                        effort: positive_or_inf(lim.effort, "limit effort")?,
                        mass: 0.0,
                        com: Vector3::zeros(),
                        inertia_com: Matrix3::zeros(),
                    });
                    props.push(MassProps::ZERO);
                    urdf_joint.push(ji);
                    (Some(joints.len() - 1), Placement::IDENTITY)
                }
            };
            let link = &robot.links[li];
            frames.push(Frame {
                name: link.name.clone(),
                body,
                placement: in_body,
            });
            // inertial data of this link, into the body frame
            let inertial = &link.inertial;
            let el = format!("link '{}' inertial", link.name);
            let m = finite(inertial.mass.value, &el, "mass")?;
            if m < 0.0 {
                return Err(ModelError::Inertia {
                    link: link.name.clone(),
                    reason: format!("negative mass {m}"),
                });
            }
            let it = &inertial.inertia;
            let vals = [it.ixx, it.ixy, it.ixz, it.iyy, it.iyz, it.izz];
            if vals.iter().any(|v| !v.is_finite()) {
                return Err(ModelError::NotFinite {
                    element: el,
                    field: "inertia".into(),
                });
            }
            let i_local = Matrix3::new(
                it.ixx, it.ixy, it.ixz, it.ixy, it.iyy, it.iyz, it.ixz, it.iyz, it.izz,
            );
            if m > 0.0 || i_local.norm() > 0.0 {
                let eig = i_local.symmetric_eigenvalues();
                if eig.iter().any(|&e| e < -1e-12) {
                    return Err(ModelError::Inertia {
                        link: link.name.clone(),
                        reason: "rotational inertia is not positive semidefinite".into(),
                    });
                }
                let io = in_body.compose(&pose(&inertial.origin, &el)?);
                let c = io.p;
                let i_c = io.r * i_local * io.r.transpose();
                match body {
                    Some(b) => props[b].add(m, &c, &i_c),
                    None => root_props.add(m, &c, &i_c),
                }
            }
            for (ci, col) in link.collision.iter().enumerate() {
                let el = format!("link '{}' collision {}", link.name, ci);
                let place = in_body.compose(&pose(&col.origin, &el)?);
                let shape = match &col.geometry {
                    urdf_rs::Geometry::Box { size } => Some(Shape::Box {
                        half_extents: finite3(&size.0, &el, "size")? * 0.5,
                    }),
                    urdf_rs::Geometry::Cylinder { radius, length } => Some(Shape::Cylinder {
                        radius: finite(*radius, &el, "radius")?,
                        half_length: finite(*length, &el, "length")? * 0.5,
                    }),
                    urdf_rs::Geometry::Capsule { radius, length } => Some(Shape::Capsule {
                        radius: finite(*radius, &el, "radius")?,
                        half_length: finite(*length, &el, "length")? * 0.5,
                    }),
                    urdf_rs::Geometry::Sphere { radius } => Some(Shape::Sphere {
                        radius: finite(*radius, &el, "radius")?,
                    }),
                    urdf_rs::Geometry::Mesh { .. } => None,
                };
                match shape {
                    Some(shape) => collisions.push(CollisionObject {
                        link: link.name.clone(),
                        body,
                        placement: place,
                        shape,
                    }),
                    None => skipped_meshes.push(link.name.clone()),
                }
            }
            // children in reverse so that the first child is popped first
            for &ji in children[li].iter().rev() {
                let j = &robot.joints[ji];
                let origin = pose(&j.origin, &format!("joint '{}'", j.name))?;
                let child = link_index[j.child.link.as_str()];
                let actuated = j.joint_type != urdf_rs::JointType::Fixed;
                stack.push((
                    child,
                    actuated.then_some(ji),
                    body,
                    in_body.compose(&origin),
                ));
            }
        }
        if visited != robot.links.len() {
            // links not reachable from the root can only sit on a cycle
            return Err(ModelError::NoRoot);
        }
        for (j, p) in joints.iter_mut().zip(props.iter()) {
            let (m, c, i_c) = p.split();
            j.mass = m;
            j.com = c;
            j.inertia_com = i_c;
        }
        // actuated joints first, mimic joints after, each in depth-first order
        // (the identity without mimic joints)
        let n = joints.len();
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
        for (b, mut j) in joints.into_iter().enumerate() {
            j.parent = j.parent.map(|p| new_index[p]);
            let i = new_index[b];
            j.idx_v = i;
            if let Some((leader, multiplier, offset)) = mimic_of[urdf_joint[b]] {
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
        let joints: Vec<Joint> = slots.into_iter().flatten().collect();
        debug_assert_eq!(joints.len(), n);
        for f in &mut frames {
            f.body = f.body.map(|b| new_index[b]);
        }
        for c in &mut collisions {
            c.body = c.body.map(|b| new_index[b]);
        }
        // depth-first preorder (parents first) in the new indices
        let order: Vec<usize> = new_index;
        moves_mass(&joints, &order, nv)?;
        let frame_index = frames
            .iter()
            .enumerate()
            .map(|(i, f)| (f.name.clone(), i))
            .collect();
        Ok(Model {
            name: robot.name.clone(),
            joints,
            frames,
            collisions,
            skipped_meshes,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            root_mass: root_props.m,
            armature: vec![0.0; nv],
            nv,
            order,
            frame_index,
        })
    }

    /// The mass of the moving parts [kg]: every body a joint moves (what is
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
