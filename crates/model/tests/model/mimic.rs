//! Mimic joints: every term of a model with mimic joints is the reduced one,
//! `Gᵀ (·) G` of the same URDF with its mimic joints free, `G` the constant map
//! from the actuated joints' velocities to all of them (`q_full = G q + offset`).
//! This holds where Pinocchio cannot compare (a leader below its mimic,
//! continuous joints), and on the Panda.

use crate::common::*;
use nalgebra::{DMatrix, DVector, Vector3};
use phri_model::*;

/// The URDF without its `<mimic …/>` tags.
fn without_mimic(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<mimic") {
        out.push_str(&rest[..start]);
        let end = rest[start..].find("/>").expect("self-closing <mimic/>") + start + 2;
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// `G` (full nv × reduced nv) and the offsets, by joint name.
fn projection(reduced: &Model, full: &Model) -> (DMatrix<f64>, DVector<f64>) {
    let mut g = DMatrix::zeros(full.nv(), reduced.nv());
    let mut o = DVector::zeros(full.nv());
    for (f, jf) in full.actuated().iter().enumerate() {
        let r = reduced
            .joints
            .iter()
            .position(|j| j.name == jf.name)
            .expect("same joints");
        match reduced.joints[r].mimic {
            None => g[(f, r)] = 1.0,
            Some(m) => {
                g[(f, m.leader)] = m.multiplier;
                o[f] = m.offset;
            }
        }
    }
    (g, o)
}

fn close(what: &str, ours: &DMatrix<f64>, theirs: &DMatrix<f64>) {
    let err = (ours - theirs).amax() / (1.0 + theirs.amax());
    assert!(
        err < 1e-12,
        "{what}: {err:e}\nours {ours}\nprojected {theirs}"
    );
}

fn col(v: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(v.len(), 1, v.as_slice())
}

fn check(name: &str, text: &str) {
    let reduced = Model::from_urdf_str(text).unwrap();
    let full = Model::from_urdf_str(&without_mimic(text)).unwrap();
    assert!(reduced.nv() < full.nv(), "{name}: no mimic joint");
    assert_eq!(reduced.joints.len(), full.joints.len());
    let (g, o) = projection(&reduced, &full);
    let (mut dr, mut df) = (Data::new(&reduced), Data::new(&full));
    let mut r = rng(21);
    for _ in 0..6 {
        let n = reduced.nv();
        let q = DVector::from_vec(random_vec(&mut r, n, 2.0));
        let qd = DVector::from_vec(random_vec(&mut r, n, 2.0));
        let qdd = DVector::from_vec(random_vec(&mut r, n, 4.0));
        let qf = &g * &q + &o;
        let (qdf, qddf) = (&g * &qd, &g * &qdd);
        let (q, qd, qdd) = (q.as_slice(), qd.as_slice(), qdd.as_slice());
        let (qf, qdf, qddf) = (qf.as_slice(), qdf.as_slice(), qddf.as_slice());
        let gt = g.transpose();
        let m = crba(&reduced, &mut dr, q).unwrap().clone();
        close(
            &format!("{name} M"),
            &m,
            &(&gt * crba(&full, &mut df, qf).unwrap() * &g),
        );
        let c = coriolis_matrix(&reduced, &mut dr, q, qd).unwrap().clone();
        close(
            &format!("{name} C"),
            &c,
            &(&gt * coriolis_matrix(&full, &mut df, qf, qdf).unwrap() * &g),
        );
        let c_qd = col(coriolis_times_qd(&reduced, &mut dr, q, qd).unwrap());
        close(
            &format!("{name} C q̇"),
            &c_qd,
            &(&gt * col(coriolis_times_qd(&full, &mut df, qf, qdf).unwrap())),
        );
        let tau = col(rnea(&reduced, &mut dr, q, qd, qdd).unwrap());
        close(
            &format!("{name} τ"),
            &tau,
            &(&gt * col(rnea(&full, &mut df, qf, qdf, qddf).unwrap())),
        );
        residual_terms(&reduced, &mut dr, q, qd).unwrap();
        residual_terms(&full, &mut df, qf, qdf).unwrap();
        for (what, ours, theirs) in [
            ("p", &dr.p, &df.p),
            ("Cᵀ q̇", &dr.ct_qd, &df.ct_qd),
            ("g", &dr.g, &df.g),
            ("Cᵀ q̇ − g", &dr.residual_bias, &df.residual_bias),
        ] {
            close(&format!("{name} {what}"), &col(ours), &(&gt * col(theirs)));
        }
        let ke = kinetic_energy(&reduced, &mut dr, q, qd).unwrap();
        assert!(
            (ke - kinetic_energy(&full, &mut df, qf, qdf).unwrap()).abs()
                < 1e-12 * (1.0 + ke.abs())
        );
        let pe = potential_energy(&reduced, &mut dr, q).unwrap();
        assert!(
            (pe - potential_energy(&full, &mut df, qf).unwrap()).abs() < 1e-12 * (1.0 + pe.abs())
        );
        // forward dynamics inverts the reduced RNEA
        let tau_v = tau.as_slice().to_vec();
        let back = forward_dynamics(&reduced, &mut dr, q, qd, &tau_v)
            .unwrap()
            .clone();
        close(
            &format!("{name} forward dynamics"),
            &col(&back),
            &DMatrix::from_column_slice(qdd.len(), 1, qdd),
        );
        forward_kinematics(&reduced, &mut dr, q).unwrap();
        forward_kinematics(&full, &mut df, qf).unwrap();
        let (mut jr, mut jf) = (
            Data::jacobian_buffer(&reduced),
            Data::jacobian_buffer(&full),
        );
        let point = Vector3::new(0.03, -0.02, 0.05);
        for f in &reduced.frames {
            let (ir, iff) = (
                reduced.frame_id(&f.name).unwrap(),
                full.frame_id(&f.name).unwrap(),
            );
            let (pr, pf) = (
                frame_placement(&reduced, &dr, ir),
                frame_placement(&full, &df, iff),
            );
            let err = (pr.to_homogeneous() - pf.to_homogeneous()).amax();
            assert!(
                err < 1e-12,
                "{name}: placement of {} differs by {err:e}",
                f.name
            );
            point_jacobian(&reduced, &dr, ir, &point, &mut jr).unwrap();
            point_jacobian(&full, &df, iff, &point, &mut jf).unwrap();
            let jr = DMatrix::from_iterator(6, reduced.nv(), jr.iter().copied());
            let jf = DMatrix::from_iterator(6, full.nv(), jf.iter().copied());
            close(&format!("{name} Jacobian of {}", f.name), &jr, &(jf * &g));
        }
    }
}

#[test]
fn every_term_is_the_projection_of_the_model_with_free_mimic_joints() {
    let panda = std::fs::read_to_string(repo_path("deploy/robots/panda/panda.urdf")).unwrap();
    check("panda", &panda);
    for (seed, n, share) in [(11, 12, 0.4), (3, 9, 0.5), (8, 15, 0.6), (21, 6, 0.9)] {
        check(
            &format!("random tree {seed}"),
            &random_tree_urdf(seed, n, share),
        );
    }
}

#[test]
fn random_mimic_trees_cover_the_cases_pinocchio_refuses() {
    // a leader below its mimic, and continuous leaders or followers
    let (mut below, mut continuous) = (false, false);
    for (seed, n, share) in [(11, 12, 0.4), (3, 9, 0.5), (8, 15, 0.6), (21, 6, 0.9)] {
        let text = random_tree_urdf(seed, n, share);
        let model = Model::from_urdf_str(&text).unwrap();
        for j in model.mimic_joints() {
            let m = j.mimic.unwrap();
            let i = model.joints.iter().position(|k| k.name == j.name).unwrap();
            below |= model.supports(i, m.leader);
            continuous |= [&j.name, &model.joints[m.leader].name]
                .iter()
                .any(|n| text.contains(&format!("name=\"{n}\" type=\"continuous\"")));
        }
    }
    assert!(
        below && continuous,
        "below {below}, continuous {continuous}"
    );
}

#[test]
fn the_panda_has_eight_degrees_of_freedom_and_a_following_finger() {
    let m = panda();
    assert_eq!(m.nv(), 8);
    assert_eq!(m.joints.len(), 9);
    assert_eq!(m.actuated()[7].name, "panda_finger_joint1");
    let finger = &m.mimic_joints()[0];
    assert_eq!(finger.name, "panda_finger_joint2");
    assert_eq!(finger.idx_v, 7);
    assert_eq!(
        finger.mimic,
        Some(Mimic {
            leader: 7,
            multiplier: 1.0,
            offset: 0.0
        })
    );
    // the limits per degree of freedom are the actuated joints'
    let effort: Vec<f64> = m.actuated().iter().map(|j| j.effort).collect();
    assert_eq!(
        effort,
        vec![87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0, 100.0]
    );
    // opening the first finger by 1 cm opens the gap by 2 cm
    let mut d = Data::new(&m);
    let gap = |d: &mut Data, x: f64| {
        forward_kinematics(&m, d, &[0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8, x]).unwrap();
        let l = frame_placement(&m, d, m.frame_id("panda_leftfinger").unwrap()).p;
        let r = frame_placement(&m, d, m.frame_id("panda_rightfinger").unwrap()).p;
        (l - r).norm()
    };
    assert!((gap(&mut d, 0.03) - gap(&mut d, 0.02) - 0.02).abs() < 1e-12);
}
