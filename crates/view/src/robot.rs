//! The robot as viewers show it: its collision capsules and link frames
//! posed by forward kinematics from a joint state, in the robot's base frame
//! \[m\], with the same shape-to-capsule rule as the simulator's contacts and
//! the camera ([`phri_model::Shape::capsule`]).

use nalgebra::Vector3;
use phri_model::{forward_kinematics, Data, Model, ModelError, Placement};

/// One capsule: segment `a`–`b` swept by `radius` \[m\], base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// one end of the segment \[m\], base frame
    pub a: Vector3<f64>,
    /// the other end \[m\], base frame
    pub b: Vector3<f64>,
    /// the radius swept around the segment \[m\]
    pub radius: f64,
}

/// A robot model with its forward-kinematics workspace.
pub struct RobotView {
    model: Model,
    data: Data,
    names: Vec<String>,
    posed: bool,
}

impl RobotView {
    /// A view of `model`, not yet posed ([`RobotView::is_posed`] is false).
    pub fn new(model: Model) -> RobotView {
        let data = Data::new(&model);
        let names = model.joint_names().iter().map(|s| s.to_string()).collect();
        RobotView {
            model,
            data,
            names,
            posed: false,
        }
    }

    /// Joints, in the order of the messages' joint arrays.
    pub fn joint_names(&self) -> &[String] {
        &self.names
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Pose the robot at `q` [rad or m] (exactly one value per joint, finite).
    pub fn pose(&mut self, q: &[f64]) -> Result<(), ModelError> {
        self.posed = false;
        forward_kinematics(&self.model, &mut self.data, q)?;
        self.posed = q.iter().all(|x| x.is_finite());
        Ok(())
    }

    /// Whether the last [`RobotView::pose`] succeeded.
    pub fn is_posed(&self) -> bool {
        self.posed
    }

    /// Every collision object as a capsule at the last pose, with its link's name.
    pub fn capsules(&self) -> impl Iterator<Item = (&str, Capsule)> + '_ {
        self.model.collisions.iter().map(|c| {
            let (a, b, radius) = c.capsule_segment(&self.data);
            (c.link.as_str(), Capsule { a, b, radius })
        })
    }

    /// Each moving link's frame in the base frame at the last pose: `(link,
    /// placement)` (rotation base ← link, the link's origin \[m\]).
    pub fn link_frames(&self) -> impl Iterator<Item = (&str, Placement)> + '_ {
        self.model
            .joints
            .iter()
            .zip(&self.data.body)
            .map(|(j, p)| (j.child_link.as_str(), *p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> RobotView {
        RobotView::new(
            phri_config::Loaded::defaults()
                .model()
                .expect("the default robot"),
        )
    }

    #[test]
    fn capsules_follow_the_joints() {
        let mut r = view();
        let n = r.joint_names().len();
        assert_eq!(n, 7);
        r.pose(&vec![0.0; n]).unwrap();
        let straight: Vec<Capsule> = r.capsules().map(|(_, c)| c).collect();
        assert!(!straight.is_empty());
        // straight up at zero: the topmost capsule end is high above the base
        let top = straight
            .iter()
            .map(|c| c.a.z.max(c.b.z))
            .fold(f64::MIN, f64::max);
        assert!(top > 0.8, "{top}");
        // bending joint 2 (index 1) by 90° brings the arm down and out
        let mut q = vec![0.0; n];
        q[1] = std::f64::consts::FRAC_PI_2;
        r.pose(&q).unwrap();
        let bent: Vec<Capsule> = r.capsules().map(|(_, c)| c).collect();
        let top_bent = bent
            .iter()
            .map(|c| c.a.z.max(c.b.z))
            .fold(f64::MIN, f64::max);
        assert!(top_bent < top - 0.3, "{top_bent} vs {top}");
        // radii do not depend on the pose
        for (s, b) in straight.iter().zip(&bent) {
            assert_eq!(s.radius, b.radius);
        }
        assert_eq!(r.link_frames().count(), n);
    }

    #[test]
    fn a_wrong_joint_count_is_refused() {
        let mut r = view();
        assert!(r.pose(&[0.0; 3]).is_err());
        assert!(!r.is_posed());
        r.pose(&[f64::NAN; 7]).unwrap();
        assert!(!r.is_posed(), "a NaN joint state is not a pose");
    }
}
