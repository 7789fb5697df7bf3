//! The `phri-model` binary: JSON on success, one line on stderr and exit 2 on bad input.

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
        (vec!["inspect", &urdf], "--q is required"),
        (
            vec!["inspect", &urdf, "--q", q7, "--bogus", "1"],
            "unknown argument",
        ),
        (vec!["frobnicate"], "unknown command"),
        (vec![], "usage"),
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
        assert!(err.starts_with("phri-model: "));
    }
}
