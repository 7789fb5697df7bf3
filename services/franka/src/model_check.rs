//! The arm phri was configured for against the arm the control box says it
//! is (FCI v10 serves its URDF, `GetRobotModel`): the cell must not drive
//! one arm with another's model (gravity, limits, the controller's
//! kinematics would all be wrong).

use phri_model::Model;

/// Relative tolerance of a compared number (the URDFs print 4-6 digits).
const TOLERANCE: f64 = 1e-6;

/// The first difference between the configured model and the robot's, in
/// words naming the joint and the quantity (`None`: the same arm).
pub fn first_difference(configured: &Model, robot: &Model) -> Option<String> {
    if configured.nv() != robot.nv() {
        return Some(format!(
            "the configured URDF has {} joints, the robot {}",
            configured.nv(),
            robot.nv()
        ));
    }
    for (a, b) in configured.joints.iter().zip(&robot.joints) {
        if a.name != b.name {
            return Some(format!("joint {}: the robot's is named {}", a.name, b.name));
        }
        let numbers = [
            ("lower limit", a.lower, b.lower),
            ("upper limit", a.upper, b.upper),
            ("velocity limit", a.velocity, b.velocity),
            ("effort limit", a.effort, b.effort),
            ("mass", a.mass, b.mass),
        ];
        for (what, x, y) in numbers {
            let same = x == y || (x - y).abs() <= TOLERANCE * x.abs().max(y.abs()).max(1.0);
            if !same {
                return Some(format!(
                    "joint {}: {what} {x} in the configured URDF, {y} on the robot",
                    a.name
                ));
            }
        }
        let placement = (a.placement.p - b.placement.p).norm();
        if placement > TOLERANCE {
            return Some(format!(
                "joint {}: its origin differs by {placement:.6} m",
                a.name
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lwr() -> Model {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        );
        Model::from_urdf_file(urdf).unwrap()
    }

    #[test]
    fn the_same_arm_passes_and_the_first_difference_is_named() {
        let a = lwr();
        assert_eq!(first_difference(&a, &a), None);
        let mut b = lwr();
        b.joints[3].effort += 10.0;
        b.joints[5].mass *= 2.0;
        let d = first_difference(&a, &b).unwrap();
        assert!(
            d.contains(&a.joints[3].name) && d.contains("effort limit"),
            "{d}"
        );
        let mut c = lwr();
        c.joints[0].name = "fr3_joint1".into();
        assert!(first_difference(&a, &c).unwrap().contains("fr3_joint1"));
    }
}
