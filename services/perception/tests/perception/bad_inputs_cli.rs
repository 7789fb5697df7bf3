//! Inputs the cell refuses before anything runs, with one line naming the
//! culprit and exit 2: a prefix longer than iceoryx2's names allow (131
//! characters made every service panic deep inside iceoryx2), refused by the
//! supervisor and the services; robot descriptions that made the supervisor
//! abort (100 000 nested elements) or run without a torque clamp (effort 0)
//! or with a singular mass matrix (a joint that moves no mass).

use std::process::Command;

use crate::workspace::{bin, repo};

#[test]
fn a_prefix_too_long_for_iceoryx2_is_one_line_and_exit_2() {
    let head = format!("long{}_", std::process::id());
    let prefix = format!("{head}{}", "p".repeat(131 - head.len()));
    assert_eq!(prefix.len(), 131);
    let run_dir = std::env::temp_dir().join(format!("phri-test-{head}run"));
    let _ = std::fs::remove_dir_all(&run_dir);
    let config = repo().join("deploy/phri.toml");
    let cases: Vec<(&str, Vec<String>)> = vec![
        (
            "phri-supervisor",
            vec![
                "--scenario".into(),
                "free-motion".into(),
                "--duration".into(),
                "2".into(),
                "--run-dir".into(),
                run_dir.display().to_string(),
            ],
        ),
        ("phri-camera", vec![]),
        ("phri-perception", vec![]),
        ("phri-repulsion", vec!["--worker".into(), "0".into()]),
    ];
    for (name, extra) in cases {
        let out = Command::new(bin(name))
            .current_dir(repo())
            .arg("--config")
            .arg(&config)
            .args(["--prefix", &prefix])
            .args(&extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(
            err.starts_with(&format!("{name}: prefix '{prefix}'")) && err.contains("at most 48"),
            "{name}: {err}"
        );
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
    // nothing of the run is left: no process, no shared memory
    let out = Command::new("pgrep").arg("-f").arg(&head).output().unwrap();
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    for dir in ["/tmp/iceoryx2", "/dev/shm"] {
        if let Ok(rd) = std::fs::read_dir(dir) {
            for e in rd.flatten() {
                assert!(!e.file_name().to_string_lossy().starts_with(&head));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&run_dir);
}

#[test]
fn robot_descriptions_the_cell_cannot_run_are_refused_naming_the_culprit() {
    let dir = std::env::temp_dir().join(format!("phri-badurdf-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let lwr = std::fs::read_to_string(repo().join("deploy/robots/kuka_lwr4.urdf")).unwrap();
    let link7 =
        "<inertia ixx=\"0.00021\" ixy=\"0\" ixz=\"0\" iyy=\"0.00021\" iyz=\"0\" izz=\"0.00024\"/>";
    let limit7 = "upper=\"2.9670597283903604\" velocity=\"3.2114058236695664\" effort=\"38\"";
    assert!(lwr.contains(link7) && lwr.contains(limit7));
    let cases = [
        (
            "deep.urdf",
            format!("<robot name=\"r\">{}</robot>", "<link>".repeat(200)),
            &["nested deeper than 64"][..],
        ),
        (
            "no_clamp.urdf",
            lwr.replace(limit7, &limit7.replace("\"38\"", "\"0\"")),
            &["joint 'lwr_joint_7': limit effort is 0"][..],
        ),
        (
            "point_mass_wrist.urdf",
            lwr.replace(
                link7,
                "<inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/>",
            ),
            &["joint 'lwr_joint_7' of", "moves no mass"][..],
        ),
    ];
    let run_dir = dir.join("run");
    for (file, text, needles) in cases {
        let urdf = dir.join(file);
        std::fs::write(&urdf, text).unwrap();
        let prefix = format!("urdf{}_", std::process::id());
        let out = Command::new(bin("phri-supervisor"))
            .current_dir(repo())
            .arg("--config")
            .arg(repo().join("deploy/phri.toml"))
            .arg("--set")
            .arg(format!("robot.urdf=\"{}\"", urdf.display()))
            .args([
                "--scenario",
                "free-motion",
                "--duration",
                "2",
                "--prefix",
                &prefix,
            ])
            .arg("--run-dir")
            .arg(&run_dir)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{file}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{file}: {err}");
        assert!(
            needles.iter().all(|n| err.contains(n)) && err.contains(file),
            "{file}: {err}"
        );
        assert!(
            !run_dir.exists(),
            "{file}: the refused supervisor wrote its run directory"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
