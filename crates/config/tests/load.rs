//! Loading: the defaults are valid, precedence is defaults < file < scenario
//! < --set, and every refusal names its key.

use std::path::{Path, PathBuf};

use phri_config::{Config, ConfigError, Loaded, PerJoint};

fn deploy() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/phri.toml")
}

fn load(sets: &[&str]) -> Result<Loaded, ConfigError> {
    Loaded::load(&deploy(), None, sets)
}

fn err(sets: &[&str]) -> String {
    load(sets).unwrap_err().to_string()
}

#[test]
fn the_defaults_are_a_valid_configuration_for_the_default_robot() {
    let d = Loaded::defaults();
    d.config.validate().unwrap();
    let model = d.model().unwrap();
    assert_eq!(model.nv(), 7);
    assert_eq!(Config::defaults(), d.config);
    // one value in one place: V_max of the avoidance is the repulsion's
    assert_eq!(
        d.config.control.avoidance_params.v_max_repulsion,
        d.config.repulsion.params.v_max
    );
    let l = load(&[]).unwrap();
    assert_eq!(l.config.control, d.config.control);
    assert!(l.urdf().is_absolute() && l.urdf().is_file());
}

#[test]
fn a_file_needs_only_the_keys_it_changes() {
    let l = Loaded::load_text("[control]\nkp = 123.0\n", &deploy(), None, &[]).unwrap();
    assert_eq!(l.config.control.kp, 123.0);
    assert_eq!(l.config.control.kd, Config::defaults().control.kd);
    l.model().unwrap();
}

#[test]
fn precedence_is_file_then_scenario_then_set() {
    // the elbow scenario sets no control key; collision's [config] is empty too,
    // so write a scenario of our own
    let dir = std::env::temp_dir().join(format!("phri-config-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scen = dir.join("s.toml");
    std::fs::write(
        &scen,
        "name = \"s\"\nduration_s = 3.0\n[config]\ncontrol = { kp = 111.0, kd = 22.0 }\n",
    )
    .unwrap();
    let s = scen.to_str().unwrap();
    let l = Loaded::load(&deploy(), Some(s), &["control.kd=33"]).unwrap();
    assert_eq!(
        l.config.control.kp, 111.0,
        "the scenario overrides the file"
    );
    assert_eq!(l.config.control.kd, 33.0, "--set overrides the scenario");
    assert_eq!(l.scenario.name, "s");
    assert_eq!(l.config.scenario.name, "s");
    // the merged table, written and loaded again (as a service does), is the same
    // configuration and does not merge the scenario's [config] a second time
    let merged = dir.join("merged.toml");
    std::fs::write(&merged, l.to_toml()).unwrap();
    let again = Loaded::load(&merged, None, &[]).unwrap();
    assert_eq!(again.config, l.config);
    assert_eq!(again.scenario.name, "s");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn scenarios_are_found_by_name_beside_the_configuration() {
    let l = Loaded::load(&deploy(), Some("collision"), &[]).unwrap();
    assert_eq!(l.scenario.name, "collision");
    assert!(l.scenario.human.is_some());
    let e = Loaded::load(&deploy(), Some("no-such-scenario"), &[]).unwrap_err();
    assert!(e.to_string().contains("no-such-scenario"), "{e}");
    // a misspelling is answered with the scenarios there are
    let e = Loaded::load(&deploy(), Some("colision"), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("known: ") && e.contains("collision") && e.contains("coexistence"),
        "{e}"
    );
}

/// An error about a key a `--set` gave names that flag, as typed; one about
/// a key of the file names the file.
#[test]
fn errors_name_the_set_that_gave_the_key() {
    let e = err(&["control.kv=12"]);
    assert!(e.starts_with("--set control.kv=12: control.kv"), "{e}");
    let e = err(&["control.avoidance=true", "control.kp=-1"]);
    assert!(e.starts_with("--set control.kp=-1: "), "{e}");
    let e = err(&["contrl.kp=1"]);
    assert!(
        e.starts_with("--set contrl.kp=1: unknown section [contrl]"),
        "{e}"
    );
    // the same key from the file: the file is named
    let e = Loaded::load_text("[control]\nkp = -1.0\n", &deploy(), None, &["control.kd=3"])
        .unwrap_err()
        .to_string();
    assert!(e.starts_with(&deploy().display().to_string()), "{e}");
}

#[test]
fn unknown_sections_and_keys_are_refused_by_name() {
    let e = err(&["nonsense.x=1"]);
    assert!(e.contains("unknown section [nonsense]"), "{e}");
    let e = err(&["control.kpp=1"]);
    assert!(
        e.contains("control.kpp") && e.contains("unknown field"),
        "{e}"
    );
    let e = err(&["control.avoidance_params.v_max_repulsion=0.2"]);
    assert!(e.contains("v_max_repulsion"), "{e}");
}

#[test]
fn wrong_types_and_values_name_their_key() {
    let e = err(&["control.kp=abc"]);
    assert!(e.contains("control.kp"), "{e}");
    let e = err(&["control.reaction=explode"]);
    assert!(
        e.contains("control.reaction") && e.contains("explode"),
        "{e}"
    );
    let e = err(&["control.kp=-1"]);
    assert!(e.contains("control.kp") && e.contains("positive"), "{e}");
    let e = err(&["control.kp=nan"]);
    assert!(e.contains("control.kp"), "{e}");
    let e = err(&["camera.rate_hz=1e12"]);
    assert!(e.contains("camera.rate_hz"), "{e}");
    let e = err(&["perception.png_rate_hz=1e12"]);
    assert!(e.contains("perception.png_rate_hz"), "{e}");
    let e = err(&["repulsion.workers=0"]);
    assert!(e.contains("repulsion.workers"), "{e}");
    let e = err(&["services.control.heartbeat=\"control/nothing\""]);
    assert!(e.contains("services.control.heartbeat"), "{e}");
    let e = err(&["record.compression=gzip"]);
    assert!(e.contains("record.compression"), "{e}");
}

#[test]
fn per_joint_settings_are_one_number_or_one_value_per_joint() {
    let l = load(&["dynamics.gain=[100, 100, 100, 100, 100, 100, 50]"]).unwrap();
    l.model().unwrap();
    let l = load(&["dynamics.gain=[100, 50]"]).unwrap();
    let e = l.model().unwrap_err().to_string();
    assert!(e.contains("dynamics.gain") && e.contains("7 joints"), "{e}");
    let e = err(&["sim.viscous_friction=-1"]);
    assert!(e.contains("sim.viscous_friction"), "{e}");
    assert_eq!(
        PerJoint::All(2.0).resolve(3, "k").unwrap(),
        vec![2.0, 2.0, 2.0]
    );
}

#[test]
fn the_model_check_names_links_and_lengths() {
    let e = model_err(&["control.ee_link=nowhere"]);
    assert!(
        e.contains("control.ee_link") && e.contains("nowhere"),
        "{e}"
    );
    let e = load(&[
        "repulsion.points=[{name = \"p\", link = \"nolink\", xyz = [0.0, 0.0, 0.0], radius = 0.1}]",
    ])
    .unwrap()
    .model()
    .unwrap_err()
    .to_string();
    assert!(e.contains("repulsion.points[0].link"), "{e}");
    let e = load(&["sim.q0=[0.0, 1.0]"])
        .unwrap()
        .model()
        .unwrap_err()
        .to_string();
    assert!(e.contains("sim.q0"), "{e}");
}

#[test]
fn syntax_errors_name_the_file() {
    let e = Loaded::load_text("[control\nkp = 1", &deploy(), None, &[]).unwrap_err();
    assert!(e.to_string().contains("phri.toml"), "{e}");
    let e = Loaded::load(Path::new("/nonexistent/phri.toml"), None, &[]).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/phri.toml"), "{e}");
}

/// `deploy/points-8.toml` (issue 14's comparison): merged over the
/// defaults, the first 8 of the default 16 control points, 2 per worker;
/// everything else stays the default.
#[test]
fn the_eight_point_comparison_keeps_the_first_eight_points() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/points-8.toml");
    let l = Loaded::load(&file, None, &[]).unwrap();
    let r = &l.config.repulsion;
    let d = Config::defaults();
    assert_eq!(d.repulsion.points.len(), 16);
    assert!((0..4).all(|w| d.repulsion.points_of(w).len() == 4));
    let model = l.model().unwrap();
    assert!(d
        .repulsion
        .points
        .iter()
        .all(|p| model.frame_id(&p.link).is_ok()));
    assert_eq!(r.points.len(), 8);
    assert_eq!(r.workers, 4);
    assert!((0..4).all(|w| r.points_of(w).len() == 2));
    assert_eq!(r.points[..], d.repulsion.points[..8]);
    assert_eq!(l.config.control, d.control);
}

/// Values that would make a service allocate without bound or overflow its
/// clocks are refused up front, naming the key and the range.
#[test]
fn values_that_would_exhaust_memory_or_overflow_time_are_refused() {
    let e = err(&["voice.hangover_s=1e9"]);
    assert!(
        e.contains("voice.hangover_s") && e.contains("[0.01, 5]"),
        "{e}"
    );
    let e = err(&["sim.dt_s=1e-9"]);
    assert!(
        e.contains("sim.dt_s") && e.contains("[0.0001, 0.01]"),
        "{e}"
    );
    let e = err(&["voice.skeleton_max_age_ms=1e300"]);
    assert!(e.contains("voice.skeleton_max_age_ms"), "{e}");
}

#[test]
fn the_arm_comes_from_its_robot_file() {
    // the default: the LWR-IV, from robots/lwr4/robot.toml
    let lwr = load(&[]).unwrap();
    assert_eq!(lwr.config.robot.name, "lwr4");
    assert!(lwr.config.robot.file.ends_with("robots/lwr4/robot.toml"));
    assert_eq!(lwr.config.control.ee_link, "lwr_flange");
    // --robot fr3: everything the cell knows of the arm changes with it
    let fr3 = load(&["robot.name=fr3"]).unwrap();
    let c = &fr3.config;
    assert!(
        fr3.urdf().ends_with("robots/fr3/fr3.urdf"),
        "{:?}",
        fr3.urdf()
    );
    assert_eq!(c.control.ee_link, "link8");
    assert_eq!(c.collaboration.robot_link, "link7");
    assert_eq!(c.collaboration.wrist_link, "link6");
    assert_eq!(c.sim.q0[3], -2.356);
    assert!(c
        .repulsion
        .points
        .iter()
        .all(|p| p.link.starts_with("link")));
    let model = fr3.model().unwrap();
    assert_eq!(model.nv(), 7);
    // its URDF's collisions are meshes: the capsules are the robot file's
    assert_eq!(model.collisions.len(), c.robot.capsules.len());
    assert!(model.collisions.len() >= 10);
    // the rest is the configuration's, and a --set still wins over the robot file
    assert_eq!(c.control.kp, lwr.config.control.kp);
    let kp = load(&[
        "robot.name=fr3",
        "control.posture=[0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8]",
    ])
    .unwrap();
    assert_eq!(kp.config.control.posture[1], -0.5);
    // the merged table the supervisor hands its services loads the same, wherever it is written
    let dir = tempdir("merged");
    let merged = dir.join("cell.toml");
    std::fs::write(&merged, fr3.to_toml()).unwrap();
    let again = Loaded::load(&merged, None, &[]).unwrap();
    assert_eq!(again.config, fr3.config);
    // --robot panda: its URDF has the hand's fingers; the robot file locks
    // them, so the arm's model has its 7 joints (and the collision model of
    // its URDF, no capsules of the file)
    let panda = load(&["robot.name=panda"]).unwrap();
    let model = panda.model().unwrap();
    assert_eq!(model.nv(), 7);
    assert!(panda.config.robot.capsules.is_empty());
    assert!(model.collisions.len() >= 30);
    assert_eq!(panda.config.control.ee_link, "panda_link8");
    let e = model_err(&[
        "robot.name=panda",
        "robot.locked_joints=[\"panda_fingers\"]",
    ]);
    assert!(e.contains("panda_fingers"), "{e}");
}

/// The configuration loads, its model does not: why.
fn model_err(sets: &[&str]) -> String {
    load(sets).unwrap().model().unwrap_err().to_string()
}

#[test]
fn an_unknown_arm_and_a_wrong_link_in_a_robot_file_are_refused_by_name() {
    let e = err(&["robot.name=ur5"]);
    assert!(
        e.contains("--set robot.name=ur5") && e.contains("'ur5'") && e.contains("fr3, lwr4, panda"),
        "{e}"
    );
    let e = err(&["robot.name=../lwr4"]);
    assert!(e.contains("robot.name") && e.contains("known"), "{e}");
    // a robot file beside the configuration, with a link its URDF lacks
    let dir = tempdir("robot-file");
    std::fs::create_dir_all(dir.join("robots/arm")).unwrap();
    let lwr = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/robots");
    let text = std::fs::read_to_string(lwr.join("lwr4/robot.toml"))
        .unwrap()
        .replace(
            "urdf = \"../kuka_lwr4.urdf\"",
            &format!("urdf = \"{}\"", lwr.join("kuka_lwr4.urdf").display()),
        )
        .replace("wrist_link = \"lwr_link_6\"", "wrist_link = \"lwr_link_9\"");
    let robot = dir.join("robots/arm/robot.toml");
    std::fs::write(&robot, text).unwrap();
    let config = dir.join("cell.toml");
    std::fs::write(&config, "[robot]\nname = \"arm\"\n").unwrap();
    let l = Loaded::load(&config, None, &[]).unwrap();
    assert_eq!(
        l.config.robot.file,
        robot.canonicalize().unwrap().display().to_string()
    );
    let e = l.model().unwrap_err().to_string();
    assert!(
        e.contains("robots/arm/robot.toml")
            && e.contains("collaboration.wrist_link")
            && e.contains("lwr_link_9"),
        "{e}"
    );
    // a capsule on a link the URDF lacks, likewise
    let capsule = "\n[[robot.capsules]]\nlink = \"nowhere\"\na = [0.0, 0.0, 0.0]\nb = [0.0, 0.0, 0.1]\nradius = 0.05\n";
    let text = std::fs::read_to_string(&robot).unwrap();
    let text = text.replace("wrist_link = \"lwr_link_9\"", "wrist_link = \"lwr_link_6\"");
    let text = text.replace("[sim]", &format!("{capsule}\n[sim]"));
    std::fs::write(&robot, text).unwrap();
    let e = Loaded::load(&config, None, &[])
        .unwrap()
        .model()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("robot.capsules[0].link") && e.contains("nowhere"),
        "{e}"
    );
}

/// A fresh directory of this test's own.
fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phri-config-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_push_on_the_wrist_by_role_lands_on_each_arms_wrist() {
    for (sets, wrist) in [(&[][..], "lwr_link_6"), (&["robot.name=fr3"][..], "link6")] {
        let l = Loaded::load(&deploy(), Some("collaboration"), sets).unwrap();
        let pushes: Vec<&str> = l
            .scenario
            .human
            .as_ref()
            .unwrap()
            .keyframes()
            .iter()
            .filter_map(|k| k.push.as_ref().map(|p| p.link.as_str()))
            .collect();
        assert_eq!(pushes, [wrist], "{sets:?}");
    }
}

#[test]
fn several_cameras_are_listed_as_camera_entries_over_the_defaults() {
    // one camera: [camera], as every configuration so far
    let one = load(&[]).unwrap().config;
    assert_eq!(one.cameras, vec![one.camera.clone()]);
    // two: each entry names what differs from [camera]'s defaults
    let text = "[[camera]]\nazimuth_rad = 0.6\n\n[[camera]]\nazimuth_rad = -0.6\nrate_hz = 15.0\n";
    let two = Loaded::load_text(text, &deploy(), None, &[])
        .unwrap()
        .config;
    assert_eq!(two.cameras.len(), 2);
    assert_eq!(two.camera, two.cameras[0]);
    assert_eq!(two.cameras[1].azimuth_rad, -0.6);
    assert_eq!(two.cameras[1].rate_hz, 15.0);
    assert_eq!(two.cameras[0].rate_hz, one.camera.rate_hz);
    assert_eq!(two.cameras[1].intrinsics, one.camera.intrinsics);
    // a --set of a camera key sets it on every camera
    let set = Loaded::load_text(text, &deploy(), None, &["camera.latency_ms=5"])
        .unwrap()
        .config;
    assert!(set.cameras.iter().all(|c| c.latency_ms == 5.0));
    assert_eq!(set.cameras[1].rate_hz, 15.0);
    // or the whole list on the command line
    let l = load(&["camera=[{azimuth_rad=0.6},{azimuth_rad=-0.6}]"])
        .unwrap()
        .config;
    assert_eq!(l.cameras.len(), 2);
    assert_eq!(l.cameras[1].azimuth_rad, -0.6);
    assert!(err(&["camera=3"]).contains("camera=3"));
    // a bad entry is named by its place
    let bad = "[[camera]]\nazimuth_rad = 0.6\n\n[[camera]]\nrate_hz = -1.0\n";
    let e = Loaded::load_text(bad, &deploy(), None, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("camera[1].rate_hz"), "{e}");
    let e = Loaded::load_text("[[camera]]\nfocus = 1\n", &deploy(), None, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("camera[0]") || e.contains("focus"), "{e}");
    let e = Loaded::load_text("camera = []\n", &deploy(), None, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("camera"), "{e}");
}

#[test]
fn each_further_camera_gets_its_own_camera_and_ingestion_services() {
    let text = "[[camera]]\nazimuth_rad = 0.6\n\n[[camera]]\nazimuth_rad = -0.6\n";
    let loaded = Loaded::load_text(text, &deploy(), None, &[]).unwrap();
    let s = &loaded.config.services;
    let camera = &s["camera-1"];
    assert_eq!(camera.binary, "phri-camera");
    assert_eq!(camera.args, ["--camera", "1"]);
    assert_eq!(camera.heartbeat.as_deref(), Some("camera/1/depth"));
    assert_eq!(camera.cpus, s["camera"].cpus);
    let ingest = &s["perception-1"];
    assert_eq!(ingest.binary, "phri-perception");
    assert_eq!(ingest.args, ["--camera", "1"]);
    assert_eq!(ingest.heartbeat.as_deref(), Some("perception/1/depth"));
    assert_eq!(ingest.depends_on, ["camera-1"]);
    // the workers serve every camera: none derived
    assert!(!s
        .keys()
        .any(|k| k.starts_with("repulsion") && k.contains('-')));
    assert!(!s.contains_key("camera-2"));
    // the merged copy the services read derives nothing twice
    let again = Loaded::load_text(&loaded.to_toml(), &deploy(), None, &[]).unwrap();
    assert_eq!(&again.config.services, s);
    // a dropped camera service drops its copies' start too
    let off = Loaded::load_text(text, &deploy(), None, &["services.camera.enabled=false"])
        .unwrap()
        .config;
    assert!(!off.services["camera-1"].enabled);
    // five cameras: more than the channels
    let five = "[[camera]]\n".repeat(5);
    let e = Loaded::load_text(&five, &deploy(), None, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("at most 4"), "{e}");
    // four cameras fit the roster (at most MAX_ROSTER services; the
    // supervisor's health lists the first 16); past it, refused by count
    let four = "[[camera]]\n".repeat(4);
    let l = Loaded::load_text(&four, &deploy(), None, &[]).unwrap();
    let enabled = l.config.services.values().filter(|s| s.enabled).count();
    assert!(
        enabled > 16 && enabled <= phri_config::MAX_ROSTER,
        "{enabled}"
    );
    let extra: Vec<String> = (0..=phri_config::MAX_ROSTER - enabled)
        .flat_map(|i| [format!("services.extra{i}.binary=\"phri-gesture\"")])
        .collect();
    let extra: Vec<&str> = extra.iter().map(|s| s.as_str()).collect();
    let e = Loaded::load_text(&four, &deploy(), None, &extra)
        .unwrap_err()
        .to_string();
    let got = format!("got {}", phri_config::MAX_ROSTER + 1);
    assert!(e.contains("services") && e.contains(&got), "{e}");
}

#[test]
fn a_cameras_tracker_runs_only_where_its_skeletons_come_from_depth() {
    let tracker = |l: &Loaded, name: &str| l.config.services.get(name).map(|s| s.enabled);
    // the simulated camera's stand-in tracker by default: no phri-tracker
    let l = load(&[]).unwrap();
    assert_eq!(
        l.config.skeleton_source(0),
        phri_config::SkeletonSource::Sim
    );
    assert_eq!(tracker(&l, "tracker"), Some(false));
    // depth for every camera, the second camera's derived tracker too
    let two = deploy().with_file_name("two-cameras.toml");
    let l = Loaded::load(&two, None, &["skeleton.source=\"depth\""]).unwrap();
    assert_eq!(tracker(&l, "tracker"), Some(true));
    assert_eq!(tracker(&l, "tracker-1"), Some(true));
    assert!(l.config.services["tracker-1"]
        .args
        .windows(2)
        .any(|w| w == ["--camera", "1"]));
    // a camera that is not simulated always tracks on depth
    let l = load(&["camera.source=\"replay\"", "camera.replay_dir=\"/tmp\""]).unwrap();
    assert_eq!(
        l.config.skeleton_source(0),
        phri_config::SkeletonSource::Depth
    );
    assert_eq!(tracker(&l, "tracker"), Some(true));
    // the tracker's own settings are checked by name
    let e = err(&["skeleton.tracker.grid_step_px=0"]);
    assert!(e.contains("skeleton.tracker"), "{e}");
    let e = err(&["skeleton.facing=\"left\""]);
    assert!(e.contains("skeleton.facing") || e.contains("facing"), "{e}");
}

/// A service's CPU budget is a share of one core: the default roster's sum
/// to at most 1.5 cores of 2, and a budget outside (0, 1] is refused by key.
#[test]
fn cpu_budgets_are_shares_of_a_core_within_the_machine() {
    let l = Loaded::load(&deploy(), None, &[]).unwrap();
    let enabled: Vec<_> = l
        .config
        .services
        .iter()
        .filter(|(_, s)| s.enabled)
        .collect();
    let sum: f64 = enabled.iter().filter_map(|(_, s)| s.cpu_budget).sum();
    assert!(
        enabled.iter().all(|(_, s)| s.cpu_budget.is_some()),
        "every default service has a budget"
    );
    assert!(sum <= 1.5, "{sum} cores");
    for bad in ["0", "1.5", "-0.1"] {
        let set = format!("services.sim.cpu_budget={bad}");
        let e = Loaded::load(&deploy(), None, &[set.as_str()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("services.sim.cpu_budget"), "{e}");
    }
}

#[test]
fn a_control_point_of_one_law_exists_only_under_that_law() {
    let names = |sets: &[&str]| -> Vec<String> {
        let l = load(sets).unwrap_or_else(|e| panic!("{e}"));
        l.config.validate().unwrap();
        l.config
            .repulsion
            .points
            .into_iter()
            .map(|p| p.name)
            .collect()
    };
    // the capsules' ends both Franka arms' paper points leave out
    const FRANKA_ENDS: &[&str] = &[
        "shoulder_end_a",
        "shoulder_end_b",
        "forearm_end_a",
        "forearm_end_b",
        "wrist_end_a",
        "wrist_end_b",
    ];
    // each arm's points at the capsules' ends serve the barrier filter only
    // (the coverage test in phri-cell's `cell`): the paper's points come
    // first, in the same order under both laws
    for (arm, only_cbf) in [
        ("robot.name=lwr4", &["wrist_end_a", "wrist_end_b"][..]),
        (
            "robot.name=fr3",
            &[FRANKA_ENDS, &["link7_low", "flange_side"]].concat()[..],
        ),
        (
            "robot.name=panda",
            &[&["link7_low"], FRANKA_ENDS].concat()[..],
        ),
    ] {
        let paper = names(&[arm]);
        let cbf = names(&[arm, "avoidance.law=cbf"]);
        assert!(
            !paper.iter().any(|n| only_cbf.contains(&n.as_str())),
            "{arm}: {paper:?}"
        );
        assert_eq!(paper[..], cbf[..paper.len()], "{arm}");
        assert_eq!(cbf[paper.len()..], only_cbf[..], "{arm}");
    }
    // a law that is none is refused, naming the key
    let text = "[[repulsion.points]]\nname = \"p\"\nlink = \"lwr_link_7\"\n\
                xyz = [0.0, 0.0, 0.0]\nradius = 0.1\nlaw = \"fast\"\n";
    let e = Loaded::load_text(text, &deploy(), None, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("repulsion.points") && e.contains("fast"), "{e}");
}
