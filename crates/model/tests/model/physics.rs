//! Physical identities every dynamics term must satisfy, on the default robot,
//! a generated tree with prismatic joints and random trees.

use crate::common::*;
use nalgebra::{DMatrix, DVector, Vector3};
use phri_model::*;

const STATES: usize = 8;

#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    for (name, model) in models() {
        let mut d = Data::new(&model);
        let mut r = rng(1);
        for _ in 0..STATES {
            let q = random_vec(&mut r, model.nv(), 3.0);
            let m = crba(&model, &mut d, &q).unwrap().clone();
            assert!(
                (&m - m.transpose()).amax() < 1e-12,
                "{name}: M not symmetric"
            );
            let eig = m.symmetric_eigenvalues();
            assert!(
                eig.min() > 0.0,
                "{name}: M not positive definite, eigenvalues {eig}"
            );
        }
    }
}

#[test]
fn mdot_minus_2c_is_skew_and_c_qd_matches_rnea() {
    for (name, model) in models() {
        let n = model.nv();
        let mut d = Data::new(&model);
        let mut r = rng(2);
        for _ in 0..STATES {
            let q = random_vec(&mut r, n, 3.0);
            let qd = random_vec(&mut r, n, 2.0);
            let c = coriolis_matrix(&model, &mut d, &q, &qd).unwrap().clone();
            // Ṁ by central differences along q̇
            let h = 1e-6;
            let mp = crba(&model, &mut d, &axpy(&q, h, &qd)).unwrap().clone();
            let mm = crba(&model, &mut d, &axpy(&q, -h, &qd)).unwrap().clone();
            let mdot = (mp - mm) / (2.0 * h);
            let n2c = &mdot - &c * 2.0;
            let skew_err = (&n2c + n2c.transpose()).amax();
            assert!(
                skew_err < 1e-6 * (1.0 + mdot.amax()),
                "{name}: Ṁ − 2C not skew ({skew_err})"
            );
            let qdv = DVector::from_column_slice(&qd);
            let c_qd = coriolis_times_qd(&model, &mut d, &q, &qd).unwrap().clone();
            assert!(
                (&c * &qdv - &c_qd).amax() < 1e-10 * (1.0 + c_qd.amax()),
                "{name}: C q̇ ≠ RNEA bias"
            );
            residual_terms(&model, &mut d, &q, &qd).unwrap();
            assert!(
                (c.transpose() * &qdv - &d.ct_qd).amax() < 1e-10 * (1.0 + d.ct_qd.amax()),
                "{name}: Cᵀ q̇ (O(n)) ≠ Cᵀ q̇ (matrix)"
            );
            // Cᵀ q̇ = Ṁ q̇ − C q̇
            assert!(
                (&mdot * &qdv - &c_qd - &d.ct_qd).amax() < 1e-6 * (1.0 + d.ct_qd.amax()),
                "{name}: Cᵀq̇ ≠ Ṁq̇ − Cq̇"
            );
        }
    }
}

#[test]
fn rnea_equals_m_qdd_plus_c_qd_plus_g_and_forward_dynamics_inverts_it() {
    for (name, model) in models() {
        let n = model.nv();
        let mut d = Data::new(&model);
        let mut r = rng(3);
        for _ in 0..STATES {
            let q = random_vec(&mut r, n, 3.0);
            let qd = random_vec(&mut r, n, 2.0);
            let qdd = random_vec(&mut r, n, 5.0);
            let tau = rnea(&model, &mut d, &q, &qd, &qdd).unwrap().clone();
            let m = crba(&model, &mut d, &q).unwrap().clone();
            let c_qd = coriolis_times_qd(&model, &mut d, &q, &qd).unwrap().clone();
            let g = gravity(&model, &mut d, &q).unwrap().clone();
            let rhs = &m * DVector::from_column_slice(&qdd) + c_qd + &g;
            assert!(
                (&tau - &rhs).amax() < 1e-10 * (1.0 + tau.amax()),
                "{name}: RNEA ≠ Mq̈ + Cq̇ + g"
            );
            // gravity from RNEA at rest
            let zero = vec![0.0; n];
            let g_rnea = rnea(&model, &mut d, &q, &zero, &zero).unwrap().clone();
            assert!(
                (&g_rnea - &g).amax() < 1e-10 * (1.0 + g.amax()),
                "{name}: g (O(n)) ≠ RNEA at rest"
            );
            residual_terms(&model, &mut d, &q, &qd).unwrap();
            assert!(
                (&d.g - &g).amax() < 1e-12 * (1.0 + g.amax()),
                "{name}: residual g ≠ g"
            );
            let p = &m * DVector::from_column_slice(&qd);
            assert!(
                (&d.p - &p).amax() < 1e-10 * (1.0 + p.amax()),
                "{name}: p ≠ M q̇"
            );
            assert!((&d.residual_bias - (&d.ct_qd - &d.g)).amax() == 0.0);
            let back = forward_dynamics(&model, &mut d, &q, &qd, tau.as_slice())
                .unwrap()
                .clone();
            assert!(
                (back - DVector::from_column_slice(&qdd)).amax() < 1e-8,
                "{name}: FD does not invert RNEA"
            );
        }
    }
}

#[test]
fn all_terms_in_one_pass_equal_each_term_alone() {
    for (name, model) in models() {
        let n = model.nv();
        let (mut one, mut each) = (Data::new(&model), Data::new(&model));
        let mut r = rng(7);
        for _ in 0..STATES {
            let q = random_vec(&mut r, n, 3.0);
            let qd = random_vec(&mut r, n, 2.0);
            all_terms(&model, &mut one, &q, &qd).unwrap();
            let m = crba(&model, &mut each, &q).unwrap().clone();
            let g = gravity(&model, &mut each, &q).unwrap().clone();
            let bias = rnea(&model, &mut each, &q, &qd, &vec![0.0; n])
                .unwrap()
                .clone();
            let scale = 1.0 + bias.amax() + m.amax();
            assert!((&one.m - &m).amax() < 1e-12 * scale, "{name}: M");
            assert!((&one.g - &g).amax() < 1e-12 * scale, "{name}: g");
            assert!((&one.tau - &bias).amax() < 1e-12 * scale, "{name}: C q̇ + g");
            // the placements are those of forward kinematics at q
            forward_kinematics(&model, &mut each, &q).unwrap();
            for f in 0..model.frames.len() {
                let (a, b) = (
                    frame_placement(&model, &one, f),
                    frame_placement(&model, &each, f),
                );
                assert!(
                    (a.p - b.p).norm() < 1e-14 && (a.r - b.r).amax() < 1e-14,
                    "{name}: frame {f}"
                );
            }
        }
        // a state of the wrong length is refused, naming it
        assert!(all_terms(&model, &mut one, &vec![0.0; n + 1], &vec![0.0; n]).is_err());
        assert!(all_terms(&model, &mut one, &vec![0.0; n], &vec![0.0; n + 1]).is_err());
    }
}

#[test]
fn jacobians_match_finite_differences_of_forward_kinematics() {
    for (name, model) in models() {
        let n = model.nv();
        let mut d = Data::new(&model);
        let mut j = Data::jacobian_buffer(&model);
        let mut r = rng(4);
        for frame in 0..model.frames.len() {
            let q = random_vec(&mut r, n, 3.0);
            let point = Vector3::from_column_slice(&random_vec(&mut r, 3, 0.2));
            forward_kinematics(&model, &mut d, &q).unwrap();
            point_jacobian(&model, &d, frame, &point, &mut j).unwrap();
            let h = 1e-6;
            for k in 0..n {
                let mut e = vec![0.0; n];
                e[k] = 1.0;
                forward_kinematics(&model, &mut d, &axpy(&q, h, &e)).unwrap();
                let tp = frame_placement(&model, &d, frame);
                forward_kinematics(&model, &mut d, &axpy(&q, -h, &e)).unwrap();
                let tm = frame_placement(&model, &d, frame);
                let lin = (tp.apply(&point) - tm.apply(&point)) / (2.0 * h);
                // angular: vee(Ṙ Rᵀ)
                let rdot = (tp.r - tm.r) / (2.0 * h);
                let w = rdot * ((tp.r + tm.r) * 0.5).transpose();
                let ang = Vector3::new(
                    w[(2, 1)] - w[(1, 2)],
                    w[(0, 2)] - w[(2, 0)],
                    w[(1, 0)] - w[(0, 1)],
                ) * 0.5;
                let col = j.column(k);
                assert!(
                    (col.fixed_rows::<3>(0) - lin).amax() < 1e-7,
                    "{name}: frame {frame} joint {k} linear column"
                );
                assert!(
                    (col.fixed_rows::<3>(3) - ang).amax() < 1e-7,
                    "{name}: frame {frame} joint {k} angular column"
                );
            }
        }
    }
}

#[test]
fn gravity_is_the_gradient_of_potential_energy() {
    for (name, model) in models() {
        let n = model.nv();
        let mut d = Data::new(&model);
        let mut r = rng(5);
        for _ in 0..STATES {
            let q = random_vec(&mut r, n, 3.0);
            let g = gravity(&model, &mut d, &q).unwrap().clone();
            let h = 1e-6;
            for k in 0..n {
                let mut e = vec![0.0; n];
                e[k] = 1.0;
                let du = (potential_energy(&model, &mut d, &axpy(&q, h, &e)).unwrap()
                    - potential_energy(&model, &mut d, &axpy(&q, -h, &e)).unwrap())
                    / (2.0 * h);
                assert!(
                    (du - g[k]).abs() < 1e-6 * (1.0 + g.amax()),
                    "{name}: ∂U/∂q{k} = {du} but g = {}",
                    g[k]
                );
            }
        }
    }
}

/// RK4 step of the torque-free system.
fn rk4(model: &Model, d: &mut Data, q: &mut [f64], qd: &mut [f64], dt: f64) {
    let n = q.len();
    let zero = vec![0.0; n];
    let f = |d: &mut Data, q: &[f64], qd: &[f64]| -> (Vec<f64>, Vec<f64>) {
        (
            qd.to_vec(),
            forward_dynamics(model, d, q, qd, &zero)
                .unwrap()
                .as_slice()
                .to_vec(),
        )
    };
    let (k1q, k1v) = f(d, q, qd);
    let (k2q, k2v) = f(d, &axpy(q, dt / 2.0, &k1q), &axpy(qd, dt / 2.0, &k1v));
    let (k3q, k3v) = f(d, &axpy(q, dt / 2.0, &k2q), &axpy(qd, dt / 2.0, &k2v));
    let (k4q, k4v) = f(d, &axpy(q, dt, &k3q), &axpy(qd, dt, &k3v));
    for i in 0..n {
        q[i] += dt / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i]);
        qd[i] += dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
    }
}

#[test]
fn energy_is_conserved_without_torque() {
    for (name, model) in [
        ("lwr4", lwr4()),
        ("tree", tree()),
        ("panda", panda()),
        ("mimic9", random_mimic_tree(3, 9, 0.5)),
    ] {
        let n = model.nv();
        let mut d = Data::new(&model);
        let mut r = rng(6);
        let mut q = random_vec(&mut r, n, 1.5);
        let mut qd = random_vec(&mut r, n, 1.0);
        let energy = |d: &mut Data, q: &[f64], qd: &[f64]| {
            kinetic_energy(&model, d, q, qd).unwrap() + potential_energy(&model, d, q).unwrap()
        };
        let e0 = energy(&mut d, &q, &qd);
        let ke0 = kinetic_energy(&model, &mut d, &q, &qd).unwrap();
        let mut worst: f64 = 0.0;
        for _ in 0..2000 {
            rk4(&model, &mut d, &mut q, &mut qd, 2e-4);
            worst = worst.max((energy(&mut d, &q, &qd) - e0).abs());
        }
        // 0.4 s of free motion: drift below 1e-6 of the energy scale
        let scale = ke0.abs() + model.joints.iter().map(|j| j.mass).sum::<f64>() * 9.81;
        assert!(
            worst < 1e-6 * scale,
            "{name}: energy drift {worst} J (scale {scale})"
        );
    }
}

#[test]
fn kinetic_energy_matches_mass_matrix() {
    let model = lwr4();
    let mut d = Data::new(&model);
    let mut r = rng(7);
    let q = random_vec(&mut r, 7, 2.0);
    let qd = random_vec(&mut r, 7, 2.0);
    let m: DMatrix<f64> = crba(&model, &mut d, &q).unwrap().clone();
    let v = DVector::from_column_slice(&qd);
    let ke = kinetic_energy(&model, &mut d, &q, &qd).unwrap();
    assert!((ke - 0.5 * v.dot(&(&m * &v))).abs() < 1e-12);
}

#[test]
fn default_robot_matches_the_dh_table() {
    // straight up at q = 0: flange at 0.3105 + 0.40 + 0.39 + 0.078 m
    let model = lwr4();
    let mut d = Data::new(&model);
    forward_kinematics(&model, &mut d, &[0.0; 7]).unwrap();
    let flange = frame_placement(&model, &d, model.frame_id("lwr_flange").unwrap());
    assert!((flange.p - Vector3::new(0.0, 0.0, 1.1785)).norm() < 1e-12);
    // elbow at 90°: the wrist swings sideways by the forearm length
    let mut q = [0.0; 7];
    q[3] = std::f64::consts::FRAC_PI_2;
    forward_kinematics(&model, &mut d, &q).unwrap();
    let flange = frame_placement(&model, &d, model.frame_id("lwr_flange").unwrap());
    assert!((flange.p.z - 0.7105).abs() < 1e-12, "flange {:?}", flange.p);
    assert!(((flange.p.x.powi(2) + flange.p.y.powi(2)).sqrt() - 0.468).abs() < 1e-12);
    assert_eq!(model.nv(), 7);
    let deg = std::f64::consts::PI / 180.0;
    assert!((model.joints[1].upper - 120.0 * deg).abs() < 1e-12);
    assert!((model.joints[4].velocity - 204.0 * deg).abs() < 1e-12);
    assert_eq!(model.joints[5].effort, 38.0);
    // one capsule per moving link plus the base
    assert_eq!(model.collisions.len(), 8);
    assert!(model
        .collisions
        .iter()
        .all(|c| matches!(c.shape, Shape::Capsule { .. })));
}

#[test]
fn collision_shapes_convert_to_parry_with_urdf_axes() {
    let model = tree();
    let mut d = Data::new(&model);
    let q = vec![0.3; model.nv()];
    forward_kinematics(&model, &mut d, &q).unwrap();
    assert!(!model.collisions.is_empty());
    for c in &model.collisions {
        let (shape, iso) = c.parry(&d);
        let pose = c.pose(&d);
        // the point at the end of the shape's own z extent lies on the surface
        let z = match c.shape {
            Shape::Capsule {
                radius,
                half_length,
            } => radius + half_length,
            Shape::Cylinder { half_length, .. } => half_length,
            Shape::Sphere { radius } => radius,
            Shape::Box { half_extents } => half_extents.z,
        };
        let p = pose.apply(&Vector3::new(0.0, 0.0, z));
        let dist = shape.distance_to_point(&iso, &p.into(), true);
        assert!(
            dist.abs() < 1e-9,
            "{}: {:?} surface point at distance {dist}",
            c.link,
            c.shape
        );
        let outside = pose.apply(&Vector3::new(0.0, 0.0, z + 0.01));
        assert!((shape.distance_to_point(&iso, &outside.into(), true) - 0.01).abs() < 1e-9);
    }
}

/// `capsule_distance` is parry3d's signed point distance to the LWR's
/// collision capsules, at random joints and points inside and outside.
#[test]
fn capsule_distance_matches_parry_on_the_default_robot() {
    let model = lwr4();
    let mut d = Data::new(&model);
    let mut r = rng(5);
    for _ in 0..STATES {
        let q = random_vec(&mut r, model.nv(), 2.0);
        forward_kinematics(&model, &mut d, &q).unwrap();
        for c in &model.collisions {
            let Shape::Capsule { .. } = c.shape else {
                continue;
            };
            let (shape, iso) = c.parry(&d);
            let centre = c.pose(&d).apply(&Vector3::zeros());
            for _ in 0..20 {
                let x = centre + Vector3::from_vec(random_vec(&mut r, 3, 0.3));
                let ours = c.capsule_distance(&d, &x);
                let theirs = shape.distance_to_point(&iso, &x.into(), false);
                let theirs = if shape.contains_point(&iso, &x.into()) {
                    -shape
                        .project_point(&iso, &x.into(), false)
                        .point
                        .coords
                        .metric_distance(&x)
                } else {
                    theirs
                };
                assert!(
                    (ours - theirs).abs() < 1e-9,
                    "{}: {ours} vs {theirs}",
                    c.link
                );
            }
        }
    }
}
