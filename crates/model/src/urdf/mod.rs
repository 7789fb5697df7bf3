//! Building a [`Model`] from a URDF, one concern per file: the text read
//! and parsed within bounds ([`read`]), the links and joints as one tree
//! ([`tree`]), the walk that merges links into bodies ([`bodies`]) with each
//! moving joint's kind, axis and limits ([`joint`]), mass ([`inertial`]) and
//! collision shapes ([`collision`]), then the mimic joints after the
//! actuated ones ([`mimic`]). Every number is checked finite where it is read
//! ([`checked`]); [`lock_joints`] reduces a URDF before the build.

mod bodies;
mod checked;
mod collision;
mod inertial;
mod joint;
mod lock;
mod mimic;
mod read;
mod tree;

use std::path::Path;

use nalgebra::Vector3;

use crate::error::ModelError;
use crate::model::Model;
use bodies::Bodies;
use tree::Tree;

pub use lock::lock_joints;

impl Model {
    /// Build from a URDF file (at most [`crate::MAX_URDF_BYTES`]: a larger
    /// one is refused without being read whole).
    pub fn from_urdf_file(path: impl AsRef<Path>) -> Result<Model, ModelError> {
        Self::from_urdf_file_locked(path, &[])
    }

    /// Build from URDF text.
    pub fn from_urdf_str(text: &str) -> Result<Model, ModelError> {
        Self::from_urdf(&read::parse(text, "<urdf>")?)
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
        let text = read::read_urdf(path)?;
        let mut robot = read::parse(&text, &path.display().to_string())?;
        lock_joints(&mut robot, locked)?;
        Self::from_urdf(&robot)
    }

    /// [`Model::from_urdf_file_locked`] from URDF text.
    pub fn from_urdf_str_locked(text: &str, locked: &[String]) -> Result<Model, ModelError> {
        let mut robot = read::parse(text, "<urdf>")?;
        lock_joints(&mut robot, locked)?;
        Self::from_urdf(&robot)
    }

    /// Build from a parsed URDF: the tree checked, its links merged into
    /// bodies, the actuated joints first. Gravity is −9.81 m/s² along the
    /// base's z, the armature zero.
    pub fn from_urdf(robot: &urdf_rs::Robot) -> Result<Model, ModelError> {
        let tree = Tree::new(robot)?;
        let mimic_of = mimic::mimics(robot)?;
        let root = tree.root(robot)?;
        let mut bodies = Bodies::walk(robot, &tree, root)?;
        let (nv, order) = mimic::actuated_first(&mut bodies, &mimic_of)?;
        inertial::moves_mass(&bodies.joints, &order, nv)?;
        let frame_index = bodies
            .frames
            .iter()
            .enumerate()
            .map(|(i, f)| (f.name.clone(), i))
            .collect();
        Ok(Model {
            name: robot.name.clone(),
            joints: bodies.joints,
            frames: bodies.frames,
            collisions: bodies.collisions,
            skipped_meshes: bodies.skipped_meshes,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            root_mass: bodies.root_mass,
            armature: vec![0.0; nv],
            nv,
            order,
            frame_index,
        })
    }
}
