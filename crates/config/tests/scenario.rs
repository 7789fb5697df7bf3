//! Scenario files and human scripts: parsing, checks and errors naming the
//! field (moved here from the simulator's tests with the parser).

use phri_config::{HumanScript, Keyframe, Scenario, ScenarioError, ScriptError};
use phri_ipc::BodyPart;

fn scenario_path(name: &str) -> String {
    format!(
        "{}/../../deploy/scenarios/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn shipped_scenarios_load() {
    let free =
        Scenario::from_file(scenario_path("free-motion.toml")).expect("free-motion.toml loads");
    assert_eq!(free.name, "free-motion");
    assert_eq!(free.duration_s, 60.0);
    assert!(free.human.is_none() && free.collaborative_parts.is_empty() && free.config.is_empty());
    let col = Scenario::from_file(scenario_path("collision.toml")).expect("collision.toml loads");
    assert_eq!(col.duration_s, 16.0);
    let human = col.human.expect("collision has a human");
    assert_eq!(human.floor_z(), -0.8);
    assert!(human.end_time() <= 13.0);
}

#[test]
fn optional_fields_and_config_table() {
    let sc = Scenario::from_str(&format!(
        "{HEAD}collaborative_parts = [\"hand_right\", \"forearm_right\"]\n[[human.keyframe]]\nt = 0\nbase = [1, 0, 3]\nleft_hand = [0.5, 0.1, 0.4]\n[config.sim]\nsubsteps = 8\n[config.control]\nreaction = \"stop\"\n"
    ))
    .expect("valid");
    assert_eq!(
        sc.collaborative_parts,
        vec![BodyPart::HandRight, BodyPart::ForearmRight]
    );
    let human = sc.human.expect("human");
    assert_eq!(human.floor_z(), -0.8, "default floor");
    assert_eq!(human.keyframes()[0].left_hand, Some([0.5, 0.1, 0.4]));
    assert_eq!(human.keyframes()[0].right_hand, None);
    let sim = sc
        .config
        .get("sim")
        .and_then(|v| v.as_table())
        .expect("config.sim kept");
    assert_eq!(sim.get("substeps").and_then(|v| v.as_integer()), Some(8));
    assert!(sc.config.contains_key("control"));
}

/// Only `name` is required: no human, the default run length, no overrides.
#[test]
fn minimal_scenario() {
    let sc = Scenario::from_str("name = \"free-motion\"").expect("a name is enough");
    assert_eq!(sc.duration_s, Scenario::DEFAULT_DURATION_S);
    assert!(sc.human.is_none() && sc.description.is_empty() && sc.config.is_empty());
}

fn parse_err(text: &str) -> ScenarioError {
    match Scenario::from_str(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

const HEAD: &str = "name = \"x\"\nduration_s = 5.0\n[human]\n";
const K0: &str = "[[human.keyframe]]\nt = 0.0\nbase = [1.0, 0.0, 0.0]\n";

/// Every malformed input is refused with an error naming the field.
#[test]
fn parse_errors_name_the_field() {
    let cases: Vec<(String, &str)> = vec![
        (format!("{HEAD}[[human.keyframe]]\nt = \"soon\"\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[0].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0]\n"), "human.keyframe[1].base"),
        (format!("{HEAD}{K0}righthand = [1.0, 0.0, 0.0]\n"), "righthand"),
        (format!("{HEAD}[[human.keyframe]]\nt = 0.0\n"), "missing field `base`"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 2.0\nbase = [1.0, 0.0, 0.0]\n[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[2].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 0.0\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[1].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = nan\nbase = [1.0, 0.0, 0.0]\n"), "human.keyframe[1].t"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, inf, 0.0]\n"), "human.keyframe[1].base"),
        (format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\nright_hand = [0.5, nan, 0.3]\n"), "human.keyframe[1].right_hand"),
        (format!("{HEAD}collaborative_parts = [\"tail\"]\n{K0}"), "human.collaborative_parts[0]"),
        (format!("{HEAD}floor_z = inf\n{K0}"), "human.floor_z"),
        (HEAD.to_string(), "human.keyframe"),
        ("name = \"x\"\nduration_s = -1.0\n".to_string(), "duration_s"),
        ("name = \"x\"\nduration_s = 1.0\nspeed = 2\n".to_string(), "speed"),
        ("duration_s = 1.0\n".to_string(), "missing field `name`"),
        ("name = 3\nduration_s = 1.0\n".to_string(), "name"),
        ("name = \"x\"\nduration_s = 1.0\nconfig = 3\n".to_string(), "config"),
        ("name = \"x\"\nduration_s = [1.0\n".to_string(), "<scenario>:"),
    ];
    for (text, field) in cases {
        let e = parse_err(&text).to_string();
        assert!(
            e.contains(field),
            "error for\n{text}\ndoes not name {field}: {e}"
        );
        assert!(e.starts_with("<scenario>:"), "error names the origin: {e}");
    }
    // a structured error carries the line and the field
    match parse_err(&format!(
        "{HEAD}{K0}[[human.keyframe]]\nt = \"x\"\nbase = [1.0, 0.0, 0.0]\n"
    )) {
        ScenarioError::Parse { line, field, .. } => {
            assert_eq!((line, field.as_str()), (8, "human.keyframe[1].t"))
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn file_errors_name_the_file() {
    let e = Scenario::from_file("/nonexistent/phri/scenario.toml").expect_err("missing file");
    assert!(matches!(e, ScenarioError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/phri/scenario.toml"));
    let dir = std::env::temp_dir().join(format!("phri-sim-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        format!("{HEAD}{K0}[[human.keyframe]]\nt = -1.0\nbase = [1.0, 0.0, 0.0]\n"),
    )
    .expect("write");
    let e = Scenario::from_file(&path)
        .expect_err("unsorted")
        .to_string();
    assert!(
        e.contains("bad.toml") && e.contains("human.keyframe[1].t"),
        "{e}"
    );
    // a file past the size bound is refused before it is parsed
    let huge = dir.join("huge.toml");
    let mut text = String::from(HEAD);
    text.push_str(K0);
    while text.len() <= 1 << 20 {
        text.push_str("# padding padding padding padding padding padding padding\n");
    }
    std::fs::write(&huge, text).expect("write");
    let e = Scenario::from_file(&huge)
        .expect_err("too large")
        .to_string();
    assert!(e.contains("huge.toml") && e.contains("larger than"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_script_of_too_many_keyframes_is_refused() {
    let keyframes: Vec<Keyframe> = (0..=HumanScript::MAX_KEYFRAMES)
        .map(|i| Keyframe {
            t: i as f64,
            base: [1.0, 0.0, 0.0],
            ..Default::default()
        })
        .collect();
    let e = HumanScript::new(-0.8, keyframes).expect_err("too many");
    assert_eq!(
        e,
        ScriptError::TooMany {
            count: HumanScript::MAX_KEYFRAMES + 1,
            max: HumanScript::MAX_KEYFRAMES
        }
    );
}

/// Garbage never panics: truncations and byte flips of a valid file.
#[test]
fn malformed_input_never_panics() {
    let text = std::fs::read_to_string(scenario_path("collision.toml")).expect("read");
    let bytes = text.as_bytes();
    let mut state = 12345u64;
    for i in 0..3000 {
        let mut b = bytes[..(i * 7919) % bytes.len()].to_vec();
        for _ in 0..(i % 4) {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            if !b.is_empty() {
                let k = (state >> 33) as usize % b.len();
                b[k] = b"=[]\"#.,0x\n-e"[(state >> 20) as usize % 12];
            }
        }
        let _ = Scenario::from_str(&String::from_utf8_lossy(&b));
    }
}

/// A script is refused with the keyframe and field named.
#[test]
fn refuses_bad_scripts() {
    let k = |t: f64| Keyframe {
        t,
        base: [0.0; 3],
        right_hand: None,
        ..Keyframe::default()
    };
    assert_eq!(HumanScript::new(-0.8, vec![]), Err(ScriptError::NoKeyframe));
    assert!(matches!(
        HumanScript::new(-0.8, vec![k(1.0), k(0.5)]),
        Err(ScriptError::Unsorted { index: 1, .. })
    ));
    assert!(matches!(
        HumanScript::new(-0.8, vec![k(f64::NAN)]),
        Err(ScriptError::NotFinite {
            index: 0,
            field: "t"
        })
    ));
    assert!(matches!(
        HumanScript::new(f64::INFINITY, vec![k(0.0)]),
        Err(ScriptError::FloorZ(_))
    ));
    let two = || HumanScript::new(-0.8, vec![k(0.0), k(10.0)]).unwrap();
    for bad in [5.0, 0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(two().repeating(bad), Err(ScriptError::Repeat { .. })),
            "repeat_s {bad}"
        );
    }
}

/// `wave`, `push` and foot targets are read into the keyframe; a push's
/// `intended` defaults to whether its hand is collaborative.
#[test]
fn wave_push_and_feet_are_read() {
    use phri_config::{Hand, Push, Wave};
    let text = |collab: &str, intended: &str| {
        format!(
            "{HEAD}collaborative_parts = [{collab}]\n{K0}\
             [[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\n\
             wave = {{ hand = \"left\", frequency_hz = 1.5, amplitude_m = 0.12 }}\n\
             push = {{ link = \"lwr_link_7\", point = [0.0, 0.0, 0.04], force_n = 30.0, part = \"right_hand\"{intended} }}\n\
             right_foot = [0.9, 0.1, -0.5]\nleft_foot = [0.9, -0.1, -0.6]\n"
        )
    };
    let sc = Scenario::from_str(&text("", ", intended = true")).expect("valid");
    let human = sc.human.expect("human");
    let k = &human.keyframes()[1];
    assert_eq!(
        k.wave,
        Some(Wave {
            hand: Hand::Left,
            frequency_hz: 1.5,
            amplitude_m: 0.12
        })
    );
    assert_eq!(
        k.push,
        Some(Push {
            link: "lwr_link_7".into(),
            point: [0.0, 0.0, 0.04],
            force_n: 30.0,
            hand: Hand::Right,
            intended: true,
        })
    );
    assert_eq!(k.right_foot, Some([0.9, 0.1, -0.5]));
    assert_eq!(k.left_foot, Some([0.9, -0.1, -0.6]));
    let intended = |collab: &str| {
        let sc = Scenario::from_str(&text(collab, "")).expect("valid");
        let h = sc.human.expect("human");
        h.keyframes()[1].push.as_ref().expect("push").intended
    };
    assert!(
        intended("\"hand_right\""),
        "a collaborative hand pushes on purpose"
    );
    assert!(!intended(""));
    assert!(!intended("\"hand_left\""));
    let sc = Scenario::from_str(&text("\"hand_right\"", ", intended = false")).expect("valid");
    assert!(
        !sc.human.expect("human").keyframes()[1]
            .push
            .as_ref()
            .expect("push")
            .intended
    );
}

/// Bad wave, push and foot values are refused, naming the key.
#[test]
fn bad_wave_push_and_feet_are_refused_by_key() {
    let k1 = |extra: &str| {
        format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\n{extra}\n")
    };
    let wave = |hand: &str, f: &str, a: &str| {
        k1(&format!(
            "wave = {{ hand = \"{hand}\", frequency_hz = {f}, amplitude_m = {a} }}"
        ))
    };
    let push = |link: &str, point: &str, force: &str, part: &str| {
        k1(&format!(
            "push = {{ link = \"{link}\", point = {point}, force_n = {force}, part = \"{part}\" }}"
        ))
    };
    let ok_point = "[0.0, 0.0, 0.04]";
    let cases: Vec<(String, &str)> = vec![
        (wave("up", "1.5", "0.1"), "human.keyframe[1].wave.hand"),
        (wave("right", "0.0", "0.1"), "human.keyframe[1].wave.frequency_hz"),
        (wave("right", "-1.0", "0.1"), "human.keyframe[1].wave.frequency_hz"),
        (wave("right", "5.5", "0.1"), "human.keyframe[1].wave.frequency_hz"),
        (wave("right", "nan", "0.1"), "human.keyframe[1].wave.frequency_hz"),
        (wave("left", "1.0", "0.0"), "human.keyframe[1].wave.amplitude_m"),
        (wave("left", "1.0", "0.6"), "human.keyframe[1].wave.amplitude_m"),
        (wave("left", "1.0", "inf"), "human.keyframe[1].wave.amplitude_m"),
        (k1("wave = { hand = \"left\", frequency_hz = 1.0 }"), "missing field `amplitude_m`"),
        (k1("wave = { hand = \"left\", frequency_hz = 1.0, amplitude_m = 0.1, speed = 2 }"), "speed"),
        (push("", ok_point, "30.0", "right_hand"), "human.keyframe[1].push.link"),
        (push("lwr_link_7", "[0.0, nan, 0.0]", "30.0", "right_hand"), "human.keyframe[1].push.point"),
        (push("lwr_link_7", "[2.0, 0.0, 0.0]", "30.0", "right_hand"), "human.keyframe[1].push.point"),
        (push("lwr_link_7", ok_point, "0.0", "right_hand"), "human.keyframe[1].push.force_n"),
        (push("lwr_link_7", ok_point, "-5.0", "right_hand"), "human.keyframe[1].push.force_n"),
        (push("lwr_link_7", ok_point, "600.0", "right_hand"), "human.keyframe[1].push.force_n"),
        (push("lwr_link_7", ok_point, "30.0", "right_foot"), "human.keyframe[1].push.part"),
        (
            k1("wave = { hand = \"right\", frequency_hz = 1.0, amplitude_m = 0.1 }\npush = { link = \"lwr_link_7\", point = [0.0, 0.0, 0.0], force_n = 10.0, part = \"right_hand\" }"),
            "human.keyframe[1].push.part",
        ),
        (k1("push = { link = \"lwr_link_7\", point = [0.0, 0.0, 0.0], force_n = 10.0 }"), "missing field `part`"),
        (k1("right_foot = [0.9, nan, -0.5]"), "human.keyframe[1].right_foot"),
        (k1("left_foot = [0.9, 0.1]"), "human.keyframe[1].left_foot"),
        (k1("left_foot = [0.9, 0.1, inf]"), "human.keyframe[1].left_foot"),
    ];
    for (text, field) in cases {
        let e = parse_err(&text).to_string();
        assert!(
            e.contains(field),
            "error for\n{text}\ndoes not name {field}: {e}"
        );
        assert!(e.starts_with("<scenario>:"), "error names the origin: {e}");
    }
    // the script's own errors, without a scenario file
    use phri_config::{Hand, Keyframe, Push, Wave};
    let k = Keyframe {
        t: 0.0,
        base: [1.0, 0.0, 0.0],
        wave: Some(Wave {
            hand: Hand::Left,
            frequency_hz: 7.0,
            amplitude_m: 0.1,
        }),
        ..Keyframe::default()
    };
    let e =
        HumanScript::new(-0.8, vec![Keyframe::default(), Keyframe { t: 1.0, ..k }]).unwrap_err();
    assert!(
        matches!(
            e,
            ScriptError::Invalid {
                index: 1,
                field: "wave.frequency_hz",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with("keyframe[1].wave.frequency_hz: 7 Hz"),
        "{e}"
    );
    let k = Keyframe {
        push: Some(Push {
            link: "lwr_link_7".into(),
            point: [0.0; 3],
            force_n: f64::NAN,
            hand: Hand::Right,
            intended: false,
        }),
        ..Keyframe::default()
    };
    let e = HumanScript::new(-0.8, vec![k]).unwrap_err();
    assert!(
        e.to_string().starts_with("keyframe[0].push.force_n:"),
        "{e}"
    );
    let k = Keyframe {
        left_foot: Some([0.0, f64::INFINITY, 0.0]),
        ..Keyframe::default()
    };
    assert_eq!(
        HumanScript::new(-0.8, vec![k]),
        Err(ScriptError::NotFinite {
            index: 0,
            field: "left_foot"
        })
    );
}

/// The shipped `wave.toml` loads: the right hand waves from 3 s to 6 s at
/// 2 Hz, 0.12 m, and is held out at (0.55, 0.1, 0.35) from 7 s to 10 s.
#[test]
fn wave_scenario_loads() {
    use phri_config::{Hand, Wave};
    let sc = Scenario::from_file(scenario_path("wave.toml")).expect("wave.toml loads");
    assert_eq!(sc.name, "wave");
    assert_eq!(sc.duration_s, 12.0);
    assert_eq!(sc.collaborative_parts, vec![BodyPart::HandRight]);
    let h = sc.human.expect("human");
    let waving: Vec<_> = h.keyframes().iter().filter(|k| k.wave.is_some()).collect();
    assert_eq!(waving.len(), 1);
    assert_eq!(waving[0].t, 3.0);
    assert_eq!(
        waving[0].wave,
        Some(Wave {
            hand: Hand::Right,
            frequency_hz: 2.0,
            amplitude_m: 0.12
        })
    );
    let (i, start, end) = h.interval_at(4.0).expect("inside the script");
    assert_eq!((h.keyframes()[i].t, start, end), (3.0, 3.0, 6.0));
    let held: Vec<f64> = h
        .keyframes()
        .iter()
        .filter(|k| k.right_hand == Some([0.55, 0.1, 0.35]))
        .map(|k| k.t)
        .collect();
    assert_eq!(held, vec![7.0, 10.0]);
    assert!(h.end_time() <= 12.0);
}

#[test]
fn a_lean_is_read_and_one_out_of_range_is_refused_by_key() {
    let k1 = |lean: &str| {
        format!("{HEAD}{K0}[[human.keyframe]]\nt = 1.0\nbase = [1.0, 0.0, 0.0]\nlean = {lean}\n")
    };
    let sc = Scenario::from_str(&k1("0.9")).expect("a lean");
    let ks = sc.human.expect("a human").keyframes().to_vec();
    assert_eq!((ks[0].lean, ks[1].lean), (None, Some(0.9)));
    let lean_over = Scenario::from_file(scenario_path("lean-over.toml")).expect("lean-over.toml");
    assert!(lean_over
        .human
        .expect("a person")
        .keyframes()
        .iter()
        .any(|k| k.lean == Some(0.9)));
    for bad in ["1.6", "-0.6", "nan", "inf"] {
        let e = parse_err(&k1(bad)).to_string();
        assert!(e.contains("keyframe[1].lean"), "{bad}: {e}");
    }
    let e = parse_err(&k1("\"deep\"")).to_string();
    assert!(e.contains("lean"), "{e}");
}
