//! Agreement with Pinocchio 4.1 on states stored by
//! `tests/reference/compare_pinocchio.py --write-fixture` (the default robot,
//! a tree with prismatic and continuous joints, and the Panda with its mimic
//! finger joint, loaded by Pinocchio with `mimic=True`):
//!
//! ```sh
//! python3 tests/reference/compare_pinocchio.py \
//!     --write-fixture crates/model/tests/data/pinocchio_reference.json \
//!     deploy/robots/kuka_lwr4.urdf@10 crates/model/tests/data/tree_prismatic.urdf@10 \
//!     deploy/robots/panda/panda.urdf@20
//! ```

use crate::common::repo_path;
use nalgebra::Vector3;
use phri_model::*;

fn rel_err(ours: &[f64], theirs: &[f64]) -> f64 {
    assert_eq!(ours.len(), theirs.len());
    let diff = ours
        .iter()
        .zip(theirs)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let scale = theirs.iter().map(|b| b.abs()).fold(1e-12, f64::max);
    diff / scale
}

fn flat(v: &serde_json::Value) -> Vec<f64> {
    match v {
        serde_json::Value::Array(a) => a.iter().flat_map(flat).collect(),
        serde_json::Value::Number(n) => vec![n.as_f64().unwrap()],
        _ => panic!("fixture: unexpected value"),
    }
}

fn row_major(m: &nalgebra::DMatrix<f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
        .collect()
}

#[test]
fn agrees_with_pinocchio_to_1e_9() {
    let text = std::fs::read_to_string(repo_path(
        "crates/model/tests/data/pinocchio_reference.json",
    ))
    .unwrap();
    let fixture: serde_json::Value = serde_json::from_str(&text).unwrap();
    let cases = fixture["cases"].as_array().unwrap();
    assert!(cases.len() >= 20);
    let panda = cases
        .iter()
        .filter(|c| c["urdf"] == "deploy/robots/panda/panda.urdf")
        .count();
    assert!(panda >= 20, "{panda} Panda states");
    let mut worst: f64 = 0.0;
    for case in cases {
        let model = Model::from_urdf_file(repo_path(case["urdf"].as_str().unwrap())).unwrap();
        let names: Vec<&str> = case["joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        assert_eq!(names, model.joint_names(), "joint order");
        let (q, qd, qdd) = (flat(&case["q"]), flat(&case["qd"]), flat(&case["qdd"]));
        let mut d = Data::new(&model);
        let mut check_against = |what: &str, ours: Vec<f64>, theirs: &serde_json::Value| {
            let e = rel_err(&ours, &flat(theirs));
            assert!(
                e < 1e-9,
                "{}: {what} differs from Pinocchio by {e:e}",
                case["urdf"]
            );
            worst = worst.max(e);
        };
        let mut check = |what: &str, ours: Vec<f64>| check_against(what, ours, &case[what]);
        check("M", row_major(crba(&model, &mut d, &q).unwrap()));
        check(
            "C",
            row_major(coriolis_matrix(&model, &mut d, &q, &qd).unwrap()),
        );
        check(
            "C_qd",
            coriolis_times_qd(&model, &mut d, &q, &qd)
                .unwrap()
                .as_slice()
                .to_vec(),
        );
        residual_terms(&model, &mut d, &q, &qd).unwrap();
        check("Ct_qd", d.ct_qd.as_slice().to_vec());
        check("g", d.g.as_slice().to_vec());
        check(
            "tau",
            rnea(&model, &mut d, &q, &qd, &qdd)
                .unwrap()
                .as_slice()
                .to_vec(),
        );
        forward_kinematics(&model, &mut d, &q).unwrap();
        let fk = case["fk"].as_object().unwrap();
        assert_eq!(fk.len(), model.frames.len());
        for (link, placement) in fk {
            let ours = frame_placement(&model, &d, model.frame_id(link).unwrap()).to_homogeneous();
            let ours = (0..4).flat_map(|i| (0..4).map(move |j| ours[(i, j)]));
            check_against(&format!("placement of {link}"), ours.collect(), placement);
        }
        let frame = model
            .frame_id(case["point_link"].as_str().unwrap())
            .unwrap();
        let p = flat(&case["point"]);
        let mut j = Data::jacobian_buffer(&model);
        point_jacobian(&model, &d, frame, &Vector3::new(p[0], p[1], p[2]), &mut j).unwrap();
        let jm = nalgebra::DMatrix::from_iterator(6, model.nv(), j.iter().copied());
        check_against("jacobian", row_major(&jm), &case["jacobian"]);
    }
    eprintln!("worst relative difference from Pinocchio: {worst:e}");
}
