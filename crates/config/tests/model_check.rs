//! The configuration's check against the robot: a joint that moves no mass at
//! the start posture (singular `M`) is refused, naming the joint, before any
//! service runs with it.

use std::path::{Path, PathBuf};

use phri_config::Loaded;

fn deploy() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy")
}

/// The default robot with link 7's inertia zeroed: its mass sits on joint 7's
/// axis, so joint 7 moves nothing (the model accepts it: it has mass).
fn robot_with_a_point_mass_wrist(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(deploy().join("robots/kuka_lwr4.urdf")).unwrap();
    let link7 =
        "<inertia ixx=\"0.00021\" ixy=\"0\" ixz=\"0\" iyy=\"0.00021\" iyz=\"0\" izz=\"0.00024\"/>";
    assert!(
        text.contains(link7),
        "the default robot changed: update this test"
    );
    let text = text.replace(
        link7,
        "<inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/>",
    );
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("point_mass_wrist.urdf");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_joint_that_moves_no_mass_at_the_start_posture_is_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("phri-config-model-{}", std::process::id()));
    let urdf = robot_with_a_point_mass_wrist(&dir);
    // the model alone accepts it (the joint carries mass, on its axis)
    let model = phri_model::Model::from_urdf_file(&urdf).unwrap();
    let set = format!("robot.urdf=\"{}\"", urdf.display());
    let loaded = Loaded::load(&deploy().join("phri.toml"), None, &[&set]).unwrap();
    let e = loaded
        .config
        .check_model(&model)
        .expect_err("singular M refused");
    assert_eq!(e.key, "robot.urdf");
    assert!(e.reason.contains("'lwr_joint_7'"), "{e}");
    // what the supervisor and every service call: one line naming file, key and joint
    let e = loaded.model().unwrap_err().to_string();
    assert!(
        e.contains("robot.urdf")
            && e.contains("lwr_joint_7")
            && e.contains("sim.q0")
            && e.contains("point_mass_wrist.urdf"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
    // the default robot passes at its start posture
    Loaded::defaults().model().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
