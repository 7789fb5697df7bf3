//! The walk down the URDF tree that merges links into rigid bodies: one
//! body per moving joint (links behind fixed joints ride on their parent's),
//! with its mass, the frames of its links and their collision geometry.

use super::checked::pose;
use super::collision::link_collisions;
use super::inertial::{link_inertial, MassProps};
use super::joint::moving_joint;
use super::tree::Tree;
use crate::error::ModelError;
use crate::geometry::CollisionObject;
use crate::model::{Frame, Joint, Placement};

/// The bodies in depth-first preorder (children in file order): body `b`
/// is moved by `joints[b]`. Body indices are those of this order until the
/// joints are reordered (actuated first).
pub(super) struct Bodies {
    /// one per moving joint, its body's mass properties set, `idx_v` and
    /// `mimic` not yet
    pub joints: Vec<Joint>,
    /// the URDF joint index of each body
    pub urdf_joint: Vec<usize>,
    /// every link, with the body it rides on
    pub frames: Vec<Frame>,
    /// link collision geometry
    pub collisions: Vec<CollisionObject>,
    /// links whose mesh collisions were skipped
    pub skipped_meshes: Vec<String>,
    /// mass rigidly attached to the root [kg]
    pub root_mass: f64,
}

/// A link still to visit.
struct Pending {
    /// URDF link index
    link: usize,
    /// the URDF joint leading to it when that joint moves
    via: Option<usize>,
    /// the body its parent link rides on (`None`: the root)
    parent_body: Option<usize>,
    /// its placement in that body (for a moving joint: the joint frame at q = 0)
    placement: Placement,
}

impl Bodies {
    /// Walks `robot` from the root of `tree`, refusing a link reached twice
    /// or never (only a cycle does either).
    pub fn walk(robot: &urdf_rs::Robot, tree: &Tree, root: usize) -> Result<Bodies, ModelError> {
        let mut bodies = Bodies {
            joints: Vec::new(),
            urdf_joint: Vec::new(),
            frames: Vec::new(),
            collisions: Vec::new(),
            skipped_meshes: Vec::new(),
            root_mass: 0.0,
        };
        let mut props: Vec<MassProps> = Vec::new();
        let mut root_props = MassProps::ZERO;
        let mut stack = vec![Pending {
            link: root,
            via: None,
            parent_body: None,
            placement: Placement::IDENTITY,
        }];
        let mut visited = 0usize;
        while let Some(next) = stack.pop() {
            visited += 1;
            if visited > robot.links.len() {
                return Err(ModelError::NoRoot);
            }
            let (body, in_body) = match next.via {
                None => (next.parent_body, next.placement),
                Some(ji) => {
                    let joint = moving_joint(&robot.joints[ji], next.parent_body, next.placement)?;
                    bodies.joints.push(joint);
                    bodies.urdf_joint.push(ji);
                    props.push(MassProps::ZERO);
                    (Some(bodies.joints.len() - 1), Placement::IDENTITY)
                }
            };
            let link = &robot.links[next.link];
            bodies.link(link, body, in_body, &mut props, &mut root_props)?;
            // children in reverse so that the first child is popped first
            for &ji in tree.children[next.link].iter().rev() {
                let j = &robot.joints[ji];
                let origin = pose(&j.origin, &format!("joint '{}'", j.name))?;
                let actuated = j.joint_type != urdf_rs::JointType::Fixed;
                stack.push(Pending {
                    link: tree.link_index[j.child.link.as_str()],
                    via: actuated.then_some(ji),
                    parent_body: body,
                    placement: in_body.compose(&origin),
                });
            }
        }
        if visited != robot.links.len() {
            // links not reachable from the root can only sit on a cycle
            return Err(ModelError::NoRoot);
        }
        for (j, p) in bodies.joints.iter_mut().zip(props.iter()) {
            (j.mass, j.com, j.inertia_com) = p.split();
        }
        bodies.root_mass = root_props.m;
        Ok(bodies)
    }

    /// Adds `link`, riding on `body` at `in_body`: its frame, its mass (to
    /// `props` of its body, or the root's) and its collision geometry.
    fn link(
        &mut self,
        link: &urdf_rs::Link,
        body: Option<usize>,
        in_body: Placement,
        props: &mut [MassProps],
        root_props: &mut MassProps,
    ) -> Result<(), ModelError> {
        self.frames.push(Frame {
            name: link.name.clone(),
            body,
            placement: in_body,
        });
        if let Some((m, c, i_c)) = link_inertial(link, &in_body)? {
            match body {
                Some(b) => props[b].add(m, &c, &i_c),
                None => root_props.add(m, &c, &i_c),
            }
        }
        link_collisions(
            link,
            body,
            &in_body,
            &mut self.collisions,
            &mut self.skipped_meshes,
        )
    }
}
