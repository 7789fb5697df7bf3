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

/// One actuated joint and the rigid body it moves.
#[derive(Clone, Debug)]
pub struct Joint {
    /// joint name from the URDF
    pub name: String,
    /// URDF link that is this joint's child (the body frame)
    pub child_link: String,
    pub kind: JointKind,
    /// index of the parent joint, `None` when the parent body is the root
    pub parent: Option<usize>,
    /// joint frame in the parent body frame at `q = 0`
    pub placement: Placement,
    /// unit axis, joint frame
    pub axis: Vector3<f64>,
    /// position limits [rad or m]; ±∞ for continuous joints
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

/// Immutable robot model. Joint `i` moves body `i`; parents precede children.
#[derive(Clone, Debug)]
pub struct Model {
    /// robot name from the URDF
    pub name: String,
    /// actuated joints in depth-first order (the order of every joint-space array)
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
/// configuration's check (`phri-config`, at the start posture).
fn moves_mass(joints: &[Joint]) -> Result<(), ModelError> {
    let mut mass: Vec<f64> = joints.iter().map(|j| j.mass).collect();
    let mut inertia: Vec<f64> = joints.iter().map(|j| j.inertia_com.trace()).collect();
    for i in (0..joints.len()).rev() {
        let moves = match joints[i].kind {
            JointKind::Prismatic => mass[i] > 0.0,
            JointKind::Revolute => mass[i] > 0.0 || inertia[i] > 0.0,
        };
        if !moves {
            return Err(ModelError::MovesNoMass {
                joint: joints[i].name.clone(),
            });
        }
        if let Some(p) = joints[i].parent {
            mass[p] += mass[i];
            inertia[p] += inertia[i];
        }
    }
    Ok(())
}

impl Model {
    /// Build from a URDF file (at most [`MAX_URDF_BYTES`]: a larger one is
    /// refused without being read whole).
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<Model, ModelError> {
        use std::io::Read;
        let path = path.as_ref();
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
        let text = String::from_utf8(bytes).map_err(|_| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "not UTF-8 text",
            ))
        })?;
        Self::from_urdf_str_named(&text, &path.display().to_string())
    }

    /// Build from URDF text.
    pub fn from_urdf_str(text: &str) -> Result<Model, ModelError> {
        Self::from_urdf_str_named(text, "<urdf>")
    }

    fn from_urdf_str_named(text: &str, origin: &str) -> Result<Model, ModelError> {
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
        let robot = parsed.map_err(|e| ModelError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        Self::from_urdf(&robot)
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
            if j.mimic.is_some() {
                return Err(ModelError::Mimic {
                    joint: j.name.clone(),
                });
            }
        }
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
        if joints.is_empty() {
            return Err(ModelError::NoActuatedJoint);
        }
        // depth-first order from a stack may interleave subtrees; the algorithms need only parent < child
        debug_assert!(joints
            .iter()
            .enumerate()
            .all(|(i, j)| j.parent.is_none_or(|p| p < i)));
        for (j, p) in joints.iter_mut().zip(props.iter()) {
            let (m, c, i_c) = p.split();
            j.mass = m;
            j.com = c;
            j.inertia_com = i_c;
        }
        moves_mass(&joints)?;
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
            frame_index,
        })
    }

    /// Number of actuated joints (= configuration and velocity dimension).
    #[inline]
    pub fn nv(&self) -> usize {
        self.joints.len()
    }

    /// Index of a link frame by name.
    pub fn frame_id(&self, link: &str) -> Result<usize, ModelError> {
        self.frame_index
            .get(link)
            .copied()
            .ok_or_else(|| ModelError::UnknownLink(link.to_string()))
    }

    /// Actuated joint names, in array order.
    pub fn joint_names(&self) -> Vec<&str> {
        self.joints.iter().map(|j| j.name.as_str()).collect()
    }

    /// Is joint `j` an ancestor of (or equal to) joint `i`?
    #[inline]
    pub fn supports(&self, j: usize, i: usize) -> bool {
        let mut k = Some(i);
        while let Some(x) = k {
            if x == j {
                return true;
            }
            if x < j {
                return false;
            }
            k = self.joints[x].parent;
        }
        false
    }
}
