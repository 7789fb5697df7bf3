//! Every malformed or unsupported input is refused with a typed error naming the culprit.

use crate::common;

use phri_model::*;

const LINK: &str = "<link name=\"a\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link>";

fn robot(body: &str) -> Result<Model, ModelError> {
    Model::from_urdf_str(&format!(
        "<robot name=\"r\"><link name=\"base\"/>{LINK}{body}</robot>"
    ))
}

fn joint(kind: &str, extra: &str) -> String {
    format!("<joint name=\"j\" type=\"{kind}\"><parent link=\"base\"/><child link=\"a\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>{extra}</joint>")
}

#[test]
fn floating_planar_spherical_joints_are_refused_by_name() {
    for kind in ["floating", "planar", "spherical"] {
        match robot(&joint(kind, "")) {
            Err(ModelError::UnsupportedJoint { joint, kind: k }) => {
                assert_eq!(joint, "j");
                assert_eq!(k, kind);
            }
            other => panic!("{kind}: {other:?}"),
        }
    }
}

/// The leader `j` (base → a) and a mimic joint `m` (a → b, revolute) whose `<mimic>` is `mimic`.
fn with_mimic(mimic: &str) -> Result<Model, ModelError> {
    let b = LINK.replace("name=\"a\"", "name=\"b\"");
    robot(&format!("{}{b}<joint name=\"m\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"1 0 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>{mimic}</joint>", joint("revolute", "")))
}

#[test]
fn mimic_joints_follow_their_leader_without_a_degree_of_freedom() {
    let m = with_mimic("<mimic joint=\"j\" multiplier=\"-2\" offset=\"0.5\"/>").unwrap();
    assert_eq!(m.nv(), 1);
    assert_eq!(m.joints.len(), 2);
    assert_eq!(m.joint_names(), vec!["j"]);
    let f = &m.mimic_joints()[0];
    assert_eq!(f.name, "m");
    assert_eq!(f.idx_v, 0);
    assert_eq!(
        f.mimic,
        Some(Mimic {
            leader: 0,
            multiplier: -2.0,
            offset: 0.5
        })
    );
    assert_eq!(m.joint_position(1, &[0.25]), 0.0);
    // multiplier 1 and offset 0 when omitted
    let m = with_mimic("<mimic joint=\"j\"/>").unwrap();
    let f = m.mimic_joints()[0].mimic.unwrap();
    assert_eq!((f.multiplier, f.offset), (1.0, 0.0));
    // a <mimic> on a fixed joint is ignored (Pinocchio does the same)
    let fixed = format!(
        "{}{}<joint name=\"m\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/><mimic joint=\"nowhere\"/></joint>",
        joint("revolute", ""),
        LINK.replace("name=\"a\"", "name=\"b\"")
    );
    let m = robot(&fixed).unwrap();
    assert_eq!((m.nv(), m.joints.len()), (1, 1));
}

#[test]
fn malformed_mimic_joints_are_refused_by_name() {
    match with_mimic("<mimic joint=\"nope\"/>") {
        Err(e @ ModelError::MimicUnknownLeader { .. }) => {
            assert!(e.to_string().contains("'m' mimics 'nope'"), "{e}")
        }
        other => panic!("unknown leader: {other:?}"),
    }
    // following itself, or a leader that follows another joint: Pinocchio refuses chains
    assert!(matches!(
        with_mimic("<mimic joint=\"m\"/>"),
        Err(ModelError::MimicChain { joint, leader }) if joint == "m" && leader == "m"
    ));
    let c = LINK.replace("name=\"a\"", "name=\"c\"");
    let chain = format!(
        "{c}<joint name=\"n\" type=\"revolute\"><parent link=\"a\"/><child link=\"c\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"m\"/></joint>"
    );
    let b = LINK.replace("name=\"a\"", "name=\"b\"");
    let two = robot(&format!("{}{b}<joint name=\"m\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"j\"/></joint>{chain}", joint("revolute", "")));
    assert!(
        matches!(&two, Err(ModelError::MimicChain { joint, leader }) if joint == "n" && leader == "m"),
        "{two:?}"
    );
    // two joints that follow each other: a cycle, refused as a chain
    let b = LINK.replace("name=\"a\"", "name=\"b\"");
    let cycle = robot(&format!("{}{b}<joint name=\"m\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"j\"/></joint>", joint("revolute", "<mimic joint=\"m\"/>")));
    assert!(
        matches!(&cycle, Err(ModelError::MimicChain { .. })),
        "{cycle:?}"
    );
    // a fixed leader
    let c = LINK.replace("name=\"a\"", "name=\"c\"");
    let fixed_leader = robot(&format!("{}{c}<joint name=\"f\" type=\"fixed\"><parent link=\"a\"/><child link=\"c\"/></joint><link name=\"b\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link><joint name=\"m\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"f\"/></joint>", joint("revolute", "")));
    match fixed_leader {
        Err(e @ ModelError::MimicLeaderFixed { .. }) => {
            assert!(e.to_string().contains("'m' mimics 'f'"), "{e}")
        }
        other => panic!("fixed leader: {other:?}"),
    }
    for (attr, value) in [
        ("multiplier", "nan"),
        ("multiplier", "inf"),
        ("offset", "-inf"),
        ("offset", "NaN"),
    ] {
        match with_mimic(&format!("<mimic joint=\"j\" {attr}=\"{value}\"/>")) {
            Err(ModelError::NotFinite { element, field }) => {
                assert!(element.contains("'m'"), "{element}");
                assert_eq!(field, attr);
            }
            other => panic!("{attr}={value}: {other:?}"),
        }
    }
    // a mimic joint keeps the checks of its own limits
    let zero = with_mimic("<mimic joint=\"j\"/>").map(|_| ());
    assert!(zero.is_ok());
    let b = LINK.replace("name=\"a\"", "name=\"b\"");
    let bad = robot(&format!("{}{b}<joint name=\"m\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"1\"/><mimic joint=\"j\"/></joint>", joint("revolute", "")));
    assert!(
        matches!(&bad, Err(ModelError::LimitNotPositive { joint, .. }) if joint == "m"),
        "{bad:?}"
    );
}

#[test]
fn a_leader_whose_only_mimic_moves_nothing_is_refused() {
    // the leader carries no mass itself, its mimic carries the mass with multiplier 0
    let text = format!(
        "<robot name=\"r\"><link name=\"base\"/><link name=\"a\"/>{}<joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint><joint name=\"m\" type=\"revolute\"><parent link=\"base\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"j\" multiplier=\"{{k}}\"/></joint></robot>",
        LINK.replace("name=\"a\"", "name=\"b\"")
    );
    let zero = Model::from_urdf_str(&text.replace("{k}", "0"));
    assert!(
        matches!(&zero, Err(ModelError::MovesNoMass { joint }) if joint == "j"),
        "{zero:?}"
    );
    // with a non-zero multiplier the mimic's body gives the leader's column its inertia
    let m = Model::from_urdf_str(&text.replace("{k}", "0.5")).unwrap();
    let mut d = Data::new(&m);
    let mm = crba(&m, &mut d, &[0.3]).unwrap();
    assert!((mm[(0, 0)] - 0.25).abs() < 1e-12, "{mm}");
}

#[test]
fn structural_errors() {
    let missing = "<joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"nope\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
    assert!(matches!(robot(missing), Err(ModelError::MissingLink { link, .. }) if link == "nope"));
    // two roots: "a" is nobody's child
    assert!(matches!(robot(""), Err(ModelError::SeveralRoots { .. })));
    // a cycle: base -> a -> base
    let cycle = format!(
        "{}<joint name=\"k\" type=\"fixed\"><parent link=\"a\"/><child link=\"base\"/></joint>",
        joint("revolute", "")
    );
    assert!(matches!(robot(&cycle), Err(ModelError::NoRoot)));
    let two_parents = format!(
        "{}<joint name=\"k\" type=\"fixed\"><parent link=\"base\"/><child link=\"a\"/></joint>",
        joint("revolute", "")
    );
    assert!(matches!(robot(&two_parents), Err(ModelError::SeveralParents { link }) if link == "a"));
    assert!(matches!(
        robot(&joint("fixed", "")),
        Err(ModelError::NoActuatedJoint)
    ));
}

#[test]
fn bad_values_are_refused() {
    let zero_axis = joint("revolute", "").replace("0 0 1", "0 0 0");
    assert!(matches!(robot(&zero_axis), Err(ModelError::ZeroAxis { joint }) if joint == "j"));
    let nan = joint("revolute", "<origin xyz=\"0 NaN 0\"/>");
    assert!(
        matches!(robot(&nan), Err(ModelError::NotFinite { element, .. }) if element.contains("'j'"))
    );
    let limits =
        joint("revolute", "").replace("lower=\"-1\" upper=\"1\"", "lower=\"1\" upper=\"-1\"");
    assert!(matches!(robot(&limits), Err(ModelError::Limits { .. })));
    let neg_mass = format!(
        "<robot name=\"r\"><link name=\"base\"/>{}{}</robot>",
        LINK.replace("value=\"1\"", "value=\"-1\""),
        joint("revolute", "")
    );
    assert!(
        matches!(Model::from_urdf_str(&neg_mass), Err(ModelError::Inertia { link, .. }) if link == "a")
    );
}

#[test]
fn malformed_xml_and_missing_files() {
    assert!(matches!(
        Model::from_urdf_str("<robot name=\"r\"><link name="),
        Err(ModelError::Parse { .. })
    ));
    assert!(matches!(
        Model::from_urdf_str("not xml at all"),
        Err(ModelError::Parse { .. })
    ));
    assert!(matches!(
        Model::from_urdf_str(""),
        Err(ModelError::Parse { .. })
    ));
    match Model::from_urdf_file("/nonexistent/robot.urdf") {
        Err(e @ ModelError::Io { .. }) => {
            assert!(e.to_string().contains("/nonexistent/robot.urdf"))
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn wrong_lengths_and_unknown_links() {
    let model = common::lwr4();
    let mut d = Data::new(&model);
    assert!(matches!(
        crba(&model, &mut d, &[0.0; 6]),
        Err(ModelError::Dimension(LengthError {
            what: "q",
            expected: 7,
            got: 6
        }))
    ));
    assert!(matches!(
        rnea(&model, &mut d, &[0.0; 7], &[0.0; 7], &[0.0; 8]),
        Err(ModelError::Dimension(LengthError { what: "qdd", .. }))
    ));
    assert!(matches!(
        residual_terms(&model, &mut d, &[0.0; 7], &[0.0; 3]),
        Err(ModelError::Dimension(LengthError { what: "qd", .. }))
    ));
    assert!(matches!(
        forward_dynamics(&model, &mut d, &[0.0; 7], &[0.0; 7], &[0.0; 2]),
        Err(ModelError::Dimension(LengthError { what: "tau", .. }))
    ));
    assert!(
        matches!(model.frame_id("no_such_link"), Err(ModelError::UnknownLink(l)) if l == "no_such_link")
    );
    let mut j = nalgebra::Matrix6xX::zeros(3);
    assert!(point_jacobian(&model, &d, 0, &nalgebra::Vector3::zeros(), &mut j).is_err());
}

#[test]
fn continuous_joints_have_no_position_limits_and_meshes_are_skipped() {
    let body = joint("continuous", "").replace(
        "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
        "",
    );
    let m = Model::from_urdf_str(&format!("<robot name=\"r\"><link name=\"base\"><collision><geometry><mesh filename=\"x.stl\"/></geometry></collision></link>{LINK}{body}</robot>")).unwrap();
    assert_eq!(m.joints[0].lower, f64::NEG_INFINITY);
    assert_eq!(m.joints[0].velocity, f64::INFINITY);
    assert_eq!(m.skipped_meshes, vec!["base".to_string()]);
}

#[test]
fn effort_or_velocity_limits_at_or_below_zero_are_refused_by_joint() {
    for (field, value) in [
        ("effort", "0"),
        ("effort", "-5"),
        ("velocity", "0"),
        ("velocity", "-1"),
    ] {
        for kind in ["revolute", "prismatic", "continuous"] {
            let body =
                joint(kind, "").replace(&format!("{field}=\"1\""), &format!("{field}=\"{value}\""));
            match robot(&body) {
                Err(e @ ModelError::LimitNotPositive { .. }) => {
                    let ModelError::LimitNotPositive {
                        joint, field: f, ..
                    } = &e
                    else {
                        unreachable!()
                    };
                    assert_eq!(joint, "j");
                    assert!(f.contains(field), "{e}");
                    assert!(e.to_string().contains("'j'"), "{e}");
                }
                other => panic!("{kind} {field}={value}: {other:?}"),
            }
        }
    }
    // effort omitted from <limit> (urdf-rs reads 0): refused as well
    let body = joint("revolute", "").replace(" effort=\"1\"", "");
    assert!(matches!(
        robot(&body),
        Err(ModelError::LimitNotPositive { field, .. }) if field.contains("effort")
    ));
    // a revolute joint without <limit> has neither limit: refused
    let body = joint("revolute", "").replace(
        "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
        "",
    );
    assert!(matches!(
        robot(&body),
        Err(ModelError::LimitNotPositive { .. })
    ));
    // positive limits are kept as given
    let m = robot(&joint("revolute", "")).unwrap();
    assert_eq!((m.joints[0].effort, m.joints[0].velocity), (1.0, 1.0));
}

#[test]
fn duplicate_joint_or_link_names_are_refused() {
    let two_joints = format!(
        "{}<link name=\"b\">{}</link><joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
        joint("revolute", ""),
        &LINK["<link name=\"a\">".len()..LINK.len() - "</link>".len()]
    );
    match robot(&two_joints) {
        Err(e @ ModelError::DuplicateName { .. }) => {
            assert!(e.to_string().contains("joints are named 'j'"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    let two_links = format!("{LINK}{}", joint("revolute", ""));
    match robot(&two_links) {
        Err(e @ ModelError::DuplicateName { .. }) => {
            assert!(e.to_string().contains("links are named 'a'"), "{e}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_joint_that_moves_no_mass_is_refused_by_name() {
    // "a" carries nothing: no inertial, no child
    let massless = "<robot name=\"r\"><link name=\"base\"/><link name=\"a\"/><joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>";
    match Model::from_urdf_str(massless) {
        Err(e @ ModelError::MovesNoMass { .. }) => {
            assert!(e.to_string().contains("joint 'j'"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // a massless link is fine when the joint carries mass further out
    let carried = format!("<robot name=\"r\"><link name=\"base\"/><link name=\"a\"/>{}<joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint><joint name=\"k\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/><origin xyz=\"0.1 0 0\"/></joint></robot>", LINK.replace("name=\"a\"", "name=\"b\""));
    assert!(
        Model::from_urdf_str(&carried).is_ok(),
        "{:?}",
        Model::from_urdf_str(&carried)
    );
    // a link with inertia but no mass is no body (the model keeps no inertia
    // without mass): the joint that carries only it moves nothing
    for kind in ["prismatic", "revolute"] {
        let inertia_only = format!(
            "<robot name=\"r\"><link name=\"base\"/>{}{}</robot>",
            LINK.replace("value=\"1\"", "value=\"0\""),
            joint(kind, "")
        );
        assert!(
            matches!(
                Model::from_urdf_str(&inertia_only),
                Err(ModelError::MovesNoMass { ref joint }) if joint == "j"
            ),
            "{kind}"
        );
    }
}

#[test]
fn deep_nesting_and_huge_files_are_refused_before_parsing() {
    // 100 000 levels overflowed the parser's stack (the process aborted)
    let deep = format!(
        "<robot name=\"r\"><link name=\"base\">{}</link></robot>",
        "<x>".repeat(100_000)
    );
    match Model::from_urdf_str(&deep) {
        Err(e @ ModelError::TooDeep { .. }) => {
            assert!(e.to_string().contains("nested deeper than 64"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // within the bound, the parser has its say as before
    let nested_ok = format!(
        "<robot name=\"r\"><link name=\"base\">{}{}</link></robot>",
        "<x>".repeat(MAX_XML_DEPTH - 2),
        "</x>".repeat(MAX_XML_DEPTH - 2)
    );
    assert!(!matches!(
        Model::from_urdf_str(&nested_ok),
        Err(ModelError::TooDeep { .. })
    ));
    let dir = std::env::temp_dir().join(format!("phri-model-refused-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("deep.urdf");
    std::fs::write(&path, &deep).unwrap();
    match Model::from_urdf_file(&path) {
        Err(e @ ModelError::TooDeep { .. }) => {
            assert!(e.to_string().contains("deep.urdf"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    let huge = dir.join("huge.urdf");
    let f = std::fs::File::create(&huge).unwrap();
    f.set_len(MAX_URDF_BYTES + 1).unwrap();
    match Model::from_urdf_file(&huge) {
        Err(e @ ModelError::TooLarge { .. }) => {
            assert!(e.to_string().contains("huge.urdf"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}
