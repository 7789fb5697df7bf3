//! What the configuration trusts and refuses: files another user could
//! have written, values outside their safe ranges (with the arm's model),
//! safety functions switched off (and by what), and errors that name the
//! part at fault (a truncated robot file, a URDF of 100 000 links, `--set
//! camera=[]`).

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

use phri_config::{ConfigError, Loaded, Origin};

fn deploy() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy")
}

/// A fresh directory of ours (0755) under the temporary directory.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-config-safety-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o755)).unwrap();
    d
}

fn load(path: &Path, scenario: Option<&str>, sets: &[&str]) -> Result<Loaded, ConfigError> {
    let l = Loaded::load(path, scenario, sets)?;
    l.model()?;
    Ok(l)
}

/// A copy of the arm `name`'s robot directory in `dir/robots/`, and a
/// configuration file beside it choosing that arm.
fn arm_copy(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    let robot_dir = dir.join("robots").join(name);
    std::fs::create_dir_all(&robot_dir).unwrap();
    for e in std::fs::read_dir(deploy().join("robots").join(name)).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), robot_dir.join(e.file_name())).unwrap();
    }
    let config = dir.join("cell.toml");
    std::fs::write(&config, format!("[robot]\nname = \"{name}\"\n")).unwrap();
    (config, robot_dir.join("robot.toml"))
}

#[test]
fn every_deployed_configuration_scenario_and_arm_is_within_the_safe_ranges() {
    let mut scenarios: Vec<String> = std::fs::read_dir(deploy().join("scenarios"))
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "toml").then(|| p.file_stem()?.to_str().map(String::from))?
        })
        .collect();
    scenarios.sort();
    assert!(scenarios.len() > 5, "{scenarios:?}");
    for robot in ["lwr4", "fr3", "panda"] {
        let set = format!("robot.name={robot}");
        for s in &scenarios {
            load(&deploy().join("phri.toml"), Some(s), &[&set])
                .unwrap_or_else(|e| panic!("{s} on {robot}: {e}"));
        }
    }
    for file in ["phri.toml", "two-cameras.toml", "points-8.toml"] {
        let l = load(&deploy().join(file), None, &[]).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(l.safety_off().is_empty(), "{file}: {:?}", l.safety_off());
    }
}

#[test]
fn a_safety_function_switched_off_is_listed_with_what_switched_it_off() {
    let phri = deploy().join("phri.toml");
    let l = load(&phri, None, &["control.avoidance=false"]).unwrap();
    let off = l.safety_off();
    assert_eq!(off.len(), 1, "{off:?}");
    assert_eq!(off[0].function, "collision avoidance");
    assert_eq!(
        off[0].origin,
        Origin::Set("--set control.avoidance=false".into())
    );
    assert_eq!(
        off[0].to_string(),
        "collision avoidance switched off (control.avoidance by --set control.avoidance=false)"
    );
    // from a file, from a scenario's [config]
    let d = scratch("off");
    let file = d.join("cell.toml");
    std::fs::write(
        &file,
        "[ssm]\nenabled = false\n[services.dynamics]\nenabled = false\n",
    )
    .unwrap();
    let l = load(&file, None, &[]).unwrap();
    let off: Vec<String> = l.safety_off().iter().map(|o| o.to_string()).collect();
    assert_eq!(
        off,
        [
            format!(
                "speed and separation monitoring switched off (ssm.enabled by {})",
                file.display()
            ),
            format!(
                "collision detection (the residual) switched off (services.dynamics.enabled by {})",
                file.display()
            ),
        ]
    );
    let scen = d.join("no-ssm.toml");
    std::fs::write(
        &scen,
        "name = \"no-ssm\"\nduration_s = 3.0\n[config.ssm]\nenabled = false\n",
    )
    .unwrap();
    let l = load(&phri, Some(scen.to_str().unwrap()), &[]).unwrap();
    let off = l.safety_off();
    assert!(
        matches!(&off[..], [o] if matches!(&o.origin, Origin::Scenario(p) if p.ends_with("no-ssm.toml"))),
        "{off:?}"
    );
    // the standby's residual is not the detection
    let l = load(&phri, None, &["control.standby=false"]).unwrap();
    assert!(l.safety_off().is_empty(), "{:?}", l.safety_off());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn values_outside_their_safe_range_are_refused_naming_what_gave_them() {
    let phri = deploy().join("phri.toml");
    let err = |sets: &[&str]| load(&phri, None, sets).unwrap_err().to_string();
    let e = err(&["perception.self_filter.margin_m=3"]);
    assert!(
        e.starts_with("--set perception.self_filter.margin_m=3: perception.self_filter.margin_m: 3 is outside its safe range [0, 0.1] m"),
        "{e}"
    );
    load(&phri, None, &["perception.self_filter.margin_m=0.1"]).unwrap();
    // from the arm's model: a threshold above the joint's torque limit
    let e = err(&["dynamics.collision_threshold=[8.0, 8.0, 6.0, 6.0, 4.0, 3.0, 500.0]"]);
    assert!(
        e.contains("dynamics.collision_threshold[6]: 500 is outside its safe range (0, ")
            && e.contains("Nm: joint '"),
        "{e}"
    );
    let e = err(&["dynamics.collision_norm_threshold=1000"]);
    assert!(
        e.contains(
            "dynamics.collision_norm_threshold: 1000 is outside its safe range (0, 308.0] Nm"
        ),
        "{e}"
    );
    let e = err(&["dynamics.contact_threshold=1000"]);
    assert!(
        e.contains("dynamics.contact_threshold: 1000 is outside its safe range"),
        "{e}"
    );
    // a standby residual that steps too many states at once
    let e = err(&["dynamics.standby_wake_ms=30", "control.standby=false"]);
    assert!(
        e.contains("dynamics.standby_wake_ms: 30 is outside its safe range [0, 25] ms"),
        "{e}"
    );
    // a residual bound the standby's residual cannot meet once called
    let e = err(&["control.residual_max_age_ms=3"]);
    assert!(
        e.contains("control.residual_max_age_ms") && e.contains("more than 3 ms"),
        "{e}"
    );
    load(
        &phri,
        None,
        &["control.residual_max_age_ms=3", "control.standby=false"],
    )
    .unwrap();
    // a waypoint beyond the arm's reach
    let e = err(&["control.waypoints=[[0.45, -0.35, 0.45], [3.0, 0.0, 0.3]]"]);
    assert!(
        e.contains("control.waypoints[1]: [3, 0, 0.3] is 3.015 m from the base, outside the arm's reach (0, "),
        "{e}"
    );
    // a capsule larger than a link
    let d = scratch("capsule");
    let (config, _) = arm_copy(&d, "fr3");
    let e = load(&config, None, &["robot.capsules=[{ link = \"fr3_link7\", a = [0.0, 0.0, 0.0], b = [0.0, 0.0, 0.1], radius = 0.31 }]"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("robot.capsules[0].radius: 0.31 is outside its safe range [0, 0.3] m"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn files_another_user_could_write_and_fifos_are_refused_in_one_line() {
    let d = scratch("trust");
    let (config, robot) = arm_copy(&d, "fr3");
    load(&config, None, &[]).unwrap();
    // the robot file writable by others
    std::fs::set_permissions(&robot, std::fs::Permissions::from_mode(0o666)).unwrap();
    let e = load(&config, None, &[]).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("{}: owned by uid", robot.display()))
            && e.contains("mode 0666, writable by other users: refused"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
    std::fs::set_permissions(&robot, std::fs::Permissions::from_mode(0o644)).unwrap();
    // the URDF another user's (root can make one)
    let urdf = robot.with_file_name("fr3.urdf");
    if phri_config::trust::euid() == 0 {
        std::os::unix::fs::chown(&urdf, Some(65534), None).unwrap();
        let e = load(&config, None, &[]).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{}: owned by uid 65534", urdf.display())),
            "{e}"
        );
        std::os::unix::fs::chown(&urdf, Some(0), None).unwrap();
    }
    // a directory above the configuration that others can write
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o777)).unwrap();
    let e = load(&config, None, &[]).unwrap_err().to_string();
    assert!(
        e.contains(&format!("directory {} above it is owned", d.display()))
            && e.contains("mode 0777"),
        "{e}"
    );
    std::fs::set_permissions(&d, std::fs::Permissions::from_mode(0o755)).unwrap();
    // a FIFO: refused at once, not waited on
    let fifo = d.join("fifo.toml");
    let c = std::ffi::CString::new(fifo.display().to_string()).unwrap();
    // SAFETY: a valid C string
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let e = Loaded::load(&fifo, None, &[]).unwrap_err().to_string();
    assert_eq!(
        e,
        format!("{}: is a FIFO, not a regular file: refused", fifo.display())
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_truncated_robot_file_is_named_not_the_configuration() {
    let d = scratch("truncated");
    let (config, robot) = arm_copy(&d, "fr3");
    let text = std::fs::read_to_string(&robot).unwrap();
    // cut at a line's end: keys missing
    let lines: Vec<&str> = text.lines().collect();
    for keep in [5, 20, 60] {
        std::fs::write(&robot, lines[..keep].join("\n")).unwrap();
        let e = load(&config, None, &[]).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{}: ", robot.canonicalize().unwrap().display()))
                && e.contains("missing field")
                && e.contains("must give it"),
            "{keep}: {e}"
        );
    }
    // cut in the middle of a key
    std::fs::write(&robot, &text[..text.find("b =").unwrap() + 3]).unwrap();
    let e = load(&config, None, &[]).unwrap_err().to_string();
    assert!(
        e.contains("robot.toml: line ") && e.contains("cut short"),
        "{e}"
    );
    // the built-in configuration file's name is no part of it
    assert!(!e.contains("phri.toml") && !e.contains("cell.toml"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_urdf_of_100000_links_is_refused_naming_it_and_the_limit() {
    let d = scratch("forest");
    let (config, robot) = arm_copy(&d, "fr3");
    let urdf = robot.with_file_name("fr3.urdf");
    let mut text = std::fs::read_to_string(&urdf).unwrap();
    let links = 100_000 + text.matches("<link ").count();
    let end = text.rfind("</robot>").unwrap();
    let extra: String = (0..100_000)
        .map(|i| format!("<link name=\"x{i}\"/>\n"))
        .collect();
    text.insert_str(end, &extra);
    std::fs::write(&urdf, text).unwrap();
    let t0 = std::time::Instant::now();
    let e = load(&config, None, &[]).unwrap_err().to_string();
    assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
    assert!(
        e.contains(&format!(
            "robot.urdf: {}: {links} links",
            urdf.canonicalize().unwrap().display()
        )) && e.contains("at most 256 links"),
        "{e}"
    );
    assert!(
        e.starts_with(&robot.canonicalize().unwrap().display().to_string()),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_set_of_a_whole_section_says_what_is_wrong_with_its_value() {
    let e = Loaded::load(&deploy().join("phri.toml"), None, &["camera=[]"])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("--set 'camera=[]': [camera] is a whole section, and [] is an empty list"),
        "{e}"
    );
    assert!(!e.contains("expected section.key=value"), "{e}");
}
