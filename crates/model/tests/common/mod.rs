//! Shared helpers for the model tests: robots, random states, finite differences.
#![allow(dead_code)]

use phri_model::Model;
use rand::{Rng, SeedableRng};

pub fn repo_path(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

pub fn lwr4() -> Model {
    Model::from_urdf_file(repo_path("deploy/robots/kuka_lwr4.urdf")).expect("default robot loads")
}

/// The Panda with its fingers (`panda_finger_joint2` a mimic of `panda_finger_joint1`).
pub fn panda() -> Model {
    Model::from_urdf_file(repo_path("deploy/robots/panda/panda.urdf")).expect("the Panda loads")
}

pub fn tree() -> Model {
    Model::from_urdf_file(repo_path("crates/model/tests/data/tree_prismatic.urdf"))
        .expect("tree loads")
}

/// A random tree of `n` joints (revolute, prismatic, continuous and fixed ones
/// in between), random origins, axes and inertias.
pub fn random_tree(seed: u64, n: usize) -> Model {
    Model::from_urdf_str(&random_tree_urdf(seed, n, 0.0)).expect("random tree loads")
}

/// [`random_tree`] where about `mimic_share` of the moving joints (never
/// `j1`) follow another, actuated one anywhere in the tree (above, below or
/// on another branch) with a random multiplier (±0.3…2) and offset. The tree
/// is the same as without mimic joints.
pub fn random_mimic_tree(seed: u64, n: usize, mimic_share: f64) -> Model {
    Model::from_urdf_str(&random_tree_urdf(seed, n, mimic_share)).expect("random mimic tree loads")
}

/// The URDF text of [`random_mimic_tree`] (`mimic_share = 0`: [`random_tree`]).
pub fn random_tree_urdf(seed: u64, n: usize, mimic_share: f64) -> String {
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed);
    let mut s = String::from("<robot name=\"random\"><link name=\"l0\"/>");
    // (kind, text without `</joint>`) per joint; the mimic tags go in afterwards
    let mut joints: Vec<(&str, String)> = Vec::new();
    let v3 = |rng: &mut rand::rngs::SmallRng, a: f64| {
        format!(
            "{} {} {}",
            rng.gen_range(-a..a),
            rng.gen_range(-a..a),
            rng.gen_range(-a..a)
        )
    };
    for i in 1..=n {
        let parent = if i > 2 && rng.gen_bool(0.3) {
            rng.gen_range(0..i - 1)
        } else {
            i - 1
        };
        let kind = ["revolute", "prismatic", "continuous", "fixed"]
            [if i == 1 { 0 } else { rng.gen_range(0..4) }];
        let (a, b, c) = (
            rng.gen_range(0.01..0.1),
            rng.gen_range(0.01..0.1),
            rng.gen_range(0.01..0.1),
        );
        s += &format!(
            "<link name=\"l{i}\"><inertial><origin xyz=\"{}\" rpy=\"{}\"/><mass value=\"{}\"/><inertia ixx=\"{}\" ixy=\"0\" ixz=\"0\" iyy=\"{}\" iyz=\"0\" izz=\"{}\"/></inertial></link>",
            v3(&mut rng, 0.1),
            v3(&mut rng, 3.0),
            rng.gen_range(0.2..3.0),
            b + c,
            a + c,
            a + b
        );
        joints.push((kind, format!(
            "<joint name=\"j{i}\" type=\"{kind}\"><parent link=\"l{parent}\"/><child link=\"l{i}\"/><origin xyz=\"{}\" rpy=\"{}\"/><axis xyz=\"{}\"/><limit lower=\"-3\" upper=\"3\" effort=\"10\" velocity=\"1\"/>",
            v3(&mut rng, 0.3),
            v3(&mut rng, 3.0),
            v3(&mut rng, 1.0)
        )));
    }
    if mimic_share > 0.0 {
        // a generator of its own: the tree stays the one without mimic joints
        let mut m = rand::rngs::SmallRng::seed_from_u64(seed ^ 0x006d_696d_6963);
        let follows: Vec<bool> = joints
            .iter()
            .enumerate()
            .map(|(k, (kind, _))| k > 0 && *kind != "fixed" && m.gen_bool(mimic_share))
            .collect();
        let leaders: Vec<usize> = (0..joints.len())
            .filter(|&k| joints[k].0 != "fixed" && !follows[k])
            .collect();
        for k in 0..joints.len() {
            if follows[k] {
                let leader = leaders[m.gen_range(0..leaders.len())] + 1;
                let sign = if m.gen_bool(0.5) { -1.0 } else { 1.0 };
                let multiplier = sign * m.gen_range(0.3..2.0);
                let offset = m.gen_range(-0.5..0.5);
                joints[k].1 += &format!(
                    "<mimic joint=\"j{leader}\" multiplier=\"{multiplier}\" offset=\"{offset}\"/>"
                );
            }
        }
    }
    for (_, j) in joints {
        s += &j;
        s += "</joint>";
    }
    s += "</robot>";
    s
}

pub fn random_vec(rng: &mut impl Rng, n: usize, a: f64) -> Vec<f64> {
    (0..n).map(|_| rng.gen_range(-a..a)).collect()
}

pub fn rng(seed: u64) -> rand::rngs::SmallRng {
    rand::rngs::SmallRng::seed_from_u64(seed)
}

/// Every model the identities are checked on.
pub fn models() -> Vec<(&'static str, Model)> {
    vec![
        ("lwr4", lwr4()),
        ("tree", tree()),
        ("random12", random_tree(11, 12)),
        ("random5", random_tree(5, 5)),
        ("panda", panda()),
        ("mimic12", random_mimic_tree(11, 12, 0.4)),
        ("mimic9", random_mimic_tree(3, 9, 0.5)),
    ]
}

pub fn axpy(x: &[f64], a: f64, d: &[f64]) -> Vec<f64> {
    x.iter().zip(d).map(|(x, d)| x + a * d).collect()
}
