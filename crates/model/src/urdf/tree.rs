//! The URDF's links and joints as one tree: unique names, every joint
//! between two known links, every link the child of at most one joint.

use std::collections::{HashMap, HashSet};

use crate::error::ModelError;

/// Which joints leave and enter each link (indices into the URDF's `links`
/// and `joints`).
pub(super) struct Tree<'a> {
    /// link index by name
    pub link_index: HashMap<&'a str, usize>,
    /// per link, the joints whose parent it is, in file order
    pub children: Vec<Vec<usize>>,
    /// per link, the joint whose child it is; `None` for a root
    pub parent_joint: Vec<Option<usize>>,
}

impl<'a> Tree<'a> {
    /// The tree of `robot`, refusing two links or two joints of one name, a
    /// joint naming an unknown link, a link with two parents and a joint
    /// kind phri does not model (floating, planar, spherical), in the URDF's
    /// joint order.
    pub fn new(robot: &'a urdf_rs::Robot) -> Result<Tree<'a>, ModelError> {
        let link_index = unique_links(robot)?;
        unique_joints(robot)?;
        let mut tree = Tree {
            link_index,
            children: vec![Vec::new(); robot.links.len()],
            parent_joint: vec![None; robot.links.len()],
        };
        for (ji, j) in robot.joints.iter().enumerate() {
            let p = tree.link(j, &j.parent.link)?;
            let c = tree.link(j, &j.child.link)?;
            if tree.parent_joint[c].is_some() {
                return Err(ModelError::SeveralParents {
                    link: j.child.link.clone(),
                });
            }
            tree.parent_joint[c] = Some(ji);
            tree.children[p].push(ji);
            supported(j)?;
        }
        Ok(tree)
    }

    /// The one link that is no joint's child.
    pub fn root(&self, robot: &urdf_rs::Robot) -> Result<usize, ModelError> {
        let roots: Vec<usize> = (0..self.parent_joint.len())
            .filter(|&i| self.parent_joint[i].is_none())
            .collect();
        match roots.as_slice() {
            [] => Err(ModelError::NoRoot),
            [r] => Ok(*r),
            _ => Err(ModelError::SeveralRoots {
                roots: roots.iter().map(|&i| robot.links[i].name.clone()).collect(),
            }),
        }
    }

    /// The index of `link`, which joint `j` names.
    fn link(&self, j: &urdf_rs::Joint, link: &str) -> Result<usize, ModelError> {
        self.link_index
            .get(link)
            .copied()
            .ok_or_else(|| ModelError::MissingLink {
                joint: j.name.clone(),
                link: link.to_string(),
            })
    }
}

/// Link index by name, refusing a name given twice.
fn unique_links(robot: &urdf_rs::Robot) -> Result<HashMap<&str, usize>, ModelError> {
    let mut link_index = HashMap::with_capacity(robot.links.len());
    for (i, l) in robot.links.iter().enumerate() {
        if link_index.insert(l.name.as_str(), i).is_some() {
            return Err(ModelError::DuplicateName {
                element: "link",
                name: l.name.clone(),
            });
        }
    }
    Ok(link_index)
}

/// Refuses a joint name given twice.
fn unique_joints(robot: &urdf_rs::Robot) -> Result<(), ModelError> {
    let mut joint_names: HashSet<&str> = HashSet::with_capacity(robot.joints.len());
    for j in &robot.joints {
        if !joint_names.insert(j.name.as_str()) {
            return Err(ModelError::DuplicateName {
                element: "joint",
                name: j.name.clone(),
            });
        }
    }
    Ok(())
}

/// Refuses a joint kind other than revolute, continuous, prismatic, fixed.
fn supported(j: &urdf_rs::Joint) -> Result<(), ModelError> {
    match j.joint_type {
        urdf_rs::JointType::Revolute
        | urdf_rs::JointType::Continuous
        | urdf_rs::JointType::Prismatic
        | urdf_rs::JointType::Fixed => Ok(()),
        ref other => Err(ModelError::UnsupportedJoint {
            joint: j.name.clone(),
            kind: format!("{other:?}").to_lowercase(),
        }),
    }
}
