//! The robot's collision geometry as capsules at a joint state.

use nalgebra::Point3;
use phri_depth::Capsule;
use phri_model::{Data, Model};

/// Capsules of every collision object at the configuration last passed to
/// `forward_kinematics`, into `out` [m, base frame], each radius grown by
/// `margin` \[m\]. The shape-to-capsule rule is the model's one
/// ([`phri_model::Shape::capsule`]), so the camera, the self-filter and the
/// simulator's contacts see the same robot.
pub fn robot_capsules(model: &Model, data: &Data, margin: f64, out: &mut Vec<Capsule>) {
    out.clear();
    for c in &model.collisions {
        let (a, b, radius) = c.capsule_segment(data);
        out.push(Capsule::new(
            Point3::from(a),
            Point3::from(b),
            radius + margin,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_model::Shape;

    #[test]
    fn capsules_follow_the_model_rule_and_the_default_robot_is_all_capsules() {
        let model = phri_config::Loaded::defaults().model().unwrap();
        // the default robot has only capsules: the rule changes nothing for it
        assert!(model
            .collisions
            .iter()
            .all(|c| matches!(c.shape, Shape::Capsule { .. })));
        let mut data = Data::new(&model);
        phri_model::forward_kinematics(&model, &mut data, &[0.3; 7]).unwrap();
        let mut caps = Vec::new();
        robot_capsules(&model, &data, 0.01, &mut caps);
        assert_eq!(caps.len(), model.collisions.len());
        for (c, obj) in caps.iter().zip(&model.collisions) {
            let Shape::Capsule {
                radius,
                half_length,
            } = obj.shape
            else {
                unreachable!()
            };
            assert!((c.radius - radius - 0.01).abs() < 1e-12);
            assert!(((c.b - c.a).norm() - 2.0 * half_length).abs() < 1e-12);
            let centre = obj.pose(&data).p;
            assert!((nalgebra::center(&c.a, &c.b).coords - centre).norm() < 1e-12);
        }
    }
}
