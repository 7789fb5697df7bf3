//! The `phri-model` binary: JSON on success, one line on stderr and exit 2 on
//! bad input (the command line is clap's, through `phri_runtime::cli`).

use std::process::Command;

fn repo(rel: &str) -> String {
    format!("{}/../../{rel}", env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_phri-model"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn inspect_prints_every_key() {
    let urdf = repo("deploy/robots/kuka_lwr4.urdf");
    let (code, out, err) = run(&[
        "inspect",
        &urdf,
        "--q",
        "0.1,0.2,0.3,0.4,0.5,0.6,0.7",
        "--qd",
        "1,0,0,0,0,0,1",
        "--point",
        "lwr_flange:0,0,0.1",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in [
        "joints", "M", "C", "C_qd", "Ct_qd", "g", "tau", "fk", "jacobian",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["joints"].as_array().unwrap().len(), 7);
    assert_eq!(v["jacobian"].as_array().unwrap().len(), 6);
    assert_eq!(v["fk"]["lwr_flange"].as_array().unwrap().len(), 4);
    // without --qd/--qdd, tau is gravity
    let (_, out, _) = run(&["inspect", &urdf, "--q", "0,0.5,0,0,0,0,0"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["tau"], v["g"]);
}

#[test]
fn bench_prints_every_figure() {
    let (code, out, err) = run(&[
        "bench",
        &repo("deploy/robots/kuka_lwr4.urdf"),
        "--samples",
        "5",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in [
        "fk_ns",
        "jacobian_ns",
        "crba_ns",
        "rnea_ns",
        "gravity_ns",
        "coriolis_ns",
        "residual_terms_ns",
    ] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key}");
    }
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let dir = std::env::temp_dir().join(format!("phri-model-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad_xml = dir.join("bad.urdf");
    std::fs::write(&bad_xml, "<robot name=\"x\"><link name=").unwrap();
    let urdf = repo("deploy/robots/kuka_lwr4.urdf");
    let q7 = "0,0,0,0,0,0,0";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["inspect", "/no/such/file.urdf", "--q", q7],
            "/no/such/file.urdf",
        ),
        (
            vec!["inspect", bad_xml.to_str().unwrap(), "--q", q7],
            "malformed URDF",
        ),
        (vec!["inspect", &urdf, "--q", "0,0,0"], "expected 7"),
        (
            vec!["inspect", &urdf, "--q", "0,0,0,NaN,0,0,0"],
            "not a finite number",
        ),
        (
            vec!["inspect", &urdf, "--q", "0,0,0,abc,0,0,0"],
            "not a number",
        ),
        (
            vec!["inspect", &urdf, "--q", q7, "--point", "nolink:0,0,0"],
            "nolink",
        ),
        (
            vec!["inspect", &urdf, "--q", q7, "--point", "lwr_flange:0,0"],
            "3 coordinates",
        ),
        (vec!["inspect", &urdf], "--q"),
        (vec!["inspect", &urdf, "--q", q7, "--bogus", "1"], "--bogus"),
        (vec!["inspect", &urdf, "--q", q7, "--q", q7], "--q"),
        (vec!["inspect", "--q", q7], "ROBOT.urdf"),
        (vec!["frobnicate"], "frobnicate"),
        (vec!["completions", "tcsh"], "tcsh"),
    ];
    for (args, needle) in cases {
        let (code, out, err) = run(&args);
        assert_eq!(code, 2, "{args:?}");
        assert!(out.is_empty(), "{args:?}: stdout {out}");
        assert!(
            err.contains(needle),
            "{args:?}: stderr '{err}' lacks '{needle}'"
        );
        assert!(!err.contains("panicked"), "{args:?}");
        assert!(err.starts_with("phri-model: "), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
    // no command at all: the usage on stderr, exit 2
    let (code, out, err) = run(&[]);
    assert_eq!(code, 2);
    assert!(out.is_empty(), "stdout {out}");
    assert!(
        err.contains("Usage: phri-model") && err.contains("inspect"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn flags_take_negative_values_and_the_equals_form() {
    let urdf = repo("deploy/robots/kuka_lwr4.urdf");
    let (code, out, err) = run(&[
        "inspect",
        &urdf,
        "--q=-0.1,-0.2,0.3,-0.4,0.5,-0.6,0.7",
        "--qd",
        "-1,0,0,0,0,0,-1",
        "--point=lwr_flange:-0.1,0,0.1",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["jacobian"].as_array().unwrap().len(), 6);
    let (code, out, err) = run(&["bench", &urdf, "--samples=3"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["samples"], 3);
}

#[test]
fn help_version_and_completions() {
    let (code, out, _) = run(&["--help"]);
    assert_eq!(code, 0);
    for sub in ["inspect", "bench", "completions"] {
        assert!(out.contains(sub), "{out}");
    }
    let (code, out, _) = run(&["inspect", "--help"]);
    assert_eq!(code, 0);
    for flag in ["--q", "--qd", "--qdd", "--point"] {
        assert!(out.contains(flag), "{out}");
    }
    let (code, out, _) = run(&["bench", "--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("--samples"), "{out}");
    let (code, out, _) = run(&["--version"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("phri-model "), "{out}");
    for shell in ["bash", "zsh", "fish"] {
        let (code, out, err) = run(&["completions", shell]);
        assert_eq!(code, 0, "{shell}: {err}");
        assert!(
            out.contains("phri-model") && out.contains("inspect"),
            "{shell}"
        );
        // fish spells flags `-l samples`
        assert!(out.contains("samples"), "{shell}");
    }
}

#[test]
fn the_panda_loads_with_its_mimic_finger() {
    let urdf = repo("deploy/robots/panda/panda.urdf");
    // 7 arm joints and one finger; the second finger follows the first
    let q8 = "0.1,-0.3,0.2,-2.0,0.1,1.6,0.7,0.03";
    let (code, out, err) = run(&[
        "inspect",
        &urdf,
        "--q",
        q8,
        "--point",
        "panda_rightfinger:0,0,0.05",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let joints: Vec<&str> = v["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j.as_str().unwrap())
        .collect();
    assert_eq!(joints.len(), 8);
    assert_eq!(joints[7], "panda_finger_joint1");
    assert_eq!(
        v["mimic_joints"],
        serde_json::json!([{
            "joint": "panda_finger_joint2",
            "leader": "panda_finger_joint1",
            "multiplier": 1.0,
            "offset": 0.0
        }])
    );
    assert_eq!(v["M"].as_array().unwrap().len(), 8);
    assert_eq!(v["jacobian"][0].as_array().unwrap().len(), 8);
    // the fingers sit 2 × 0.03 m apart (the mimic opens by as much as its leader)
    let fk = |link: &str, row: usize| v["fk"][link][row][3].as_f64().unwrap();
    let gap = ((0..3)
        .map(|r| (fk("panda_leftfinger", r) - fk("panda_rightfinger", r)).powi(2))
        .sum::<f64>())
    .sqrt();
    assert!((gap - 0.06).abs() < 1e-12, "finger gap {gap}");
    // a ninth value (the mimic's own) is refused
    refused(
        &["inspect", &urdf, "--q", &format!("{q8},0.03")],
        "expected 8",
    );
    // the default robot has no mimic joints
    let (_, out, _) = run(&[
        "inspect",
        &repo("deploy/robots/kuka_lwr4.urdf"),
        "--q",
        "0,0,0,0,0,0,0",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["mimic_joints"], serde_json::json!([]));
}

/// One line on stderr, exit 2, nothing on stdout, no panic or abort.
fn refused(args: &[&str], needle: &str) {
    let (code, out, err) = run(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert!(out.is_empty(), "{args:?}: stdout {out}");
    assert!(err.starts_with("phri-model: "), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: '{err}' lacks '{needle}'");
}

#[test]
fn sample_counts_are_bounded_before_anything_is_allocated() {
    let urdf = repo("deploy/robots/kuka_lwr4.urdf");
    let t = std::time::Instant::now();
    // a billion samples aborted on a 48 GB allocation
    refused(
        &["bench", &urdf, "--samples", "1000000000"],
        "more than 100000",
    );
    refused(
        &["bench", &urdf, "--samples", "99999999999999999999999"],
        "not a positive integer",
    );
    refused(
        &["bench", &urdf, "--samples", "0"],
        "not a positive integer",
    );
    assert!(t.elapsed().as_secs() < 10);
}

#[test]
fn non_finite_results_are_refused_not_printed_as_null() {
    let urdf = repo("deploy/robots/kuka_lwr4.urdf");
    // finite inputs whose products overflow: C q̇ ~ 1e600
    refused(
        &[
            "inspect",
            &urdf,
            "--q",
            "0,0,0,0,0,0,0",
            "--qd",
            "1e300,1e300,1e300,1e300,1e300,1e300,1e300",
        ],
        "non-finite",
    );
    // a robot whose numbers overflow
    let dir = std::env::temp_dir().join(format!("phri-model-cli-nf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(&urdf)
        .unwrap()
        .replace("<mass value=\"0.3\"/>", "<mass value=\"1e308\"/>");
    let heavy = dir.join("heavy.urdf");
    std::fs::write(&heavy, text).unwrap();
    refused(
        &[
            "inspect",
            heavy.to_str().unwrap(),
            "--q",
            "0,0.5,0,0.5,0,0.5,0",
            "--qd",
            "1,1,1,1,1,1,1",
        ],
        "non-finite",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malicious_robot_descriptions_are_refused_in_one_line() {
    let dir = std::env::temp_dir().join(format!("phri-model-cli-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let q7 = "0,0,0,0,0,0,0";
    // 100 000 nested elements overflowed the parser's stack (abort)
    let deep = dir.join("deep.urdf");
    std::fs::write(
        &deep,
        format!("<robot name=\"r\">{}</robot>", "<link>".repeat(100_000)),
    )
    .unwrap();
    refused(
        &["inspect", deep.to_str().unwrap(), "--q", q7],
        "nested deeper",
    );
    refused(&["bench", deep.to_str().unwrap()], "nested deeper");
    // an effort limit of 0 removed the torque clamp
    let text = std::fs::read_to_string(repo("deploy/robots/kuka_lwr4.urdf")).unwrap();
    let zero = dir.join("zero_effort.urdf");
    std::fs::write(&zero, text.replacen("effort=\"176\"", "effort=\"0\"", 1)).unwrap();
    refused(
        &["inspect", zero.to_str().unwrap(), "--q", q7],
        "lwr_joint_1",
    );
    let _ = std::fs::remove_dir_all(&dir);
}
