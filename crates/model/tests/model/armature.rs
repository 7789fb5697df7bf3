//! Rotor inertia (armature): every algorithm sees the same `M + diag(a)`.

use crate::common;

use phri_model::{crba, forward_dynamics, momentum, rnea, Data};

#[test]
fn armature_enters_m_rnea_momentum_and_forward_dynamics_alike() {
    let mut rng = common::rng(7);
    for (name, mut model) in common::models() {
        let n = model.nv();
        let q = common::random_vec(&mut rng, n, 1.0);
        let qd = common::random_vec(&mut rng, n, 1.0);
        let qdd = common::random_vec(&mut rng, n, 2.0);
        let mut data = Data::new(&model);
        let m0 = crba(&model, &mut data, &q).unwrap().clone();
        let a: Vec<f64> = (0..n).map(|k| 0.05 + 0.01 * k as f64).collect();
        model.set_armature(&a).unwrap();
        let mut data = Data::new(&model);
        let m = crba(&model, &mut data, &q).unwrap().clone();
        for r in 0..n {
            for c in 0..n {
                let want = m0[(r, c)] + if r == c { a[r] } else { 0.0 };
                assert!((m[(r, c)] - want).abs() < 1e-12, "{name}: M[{r},{c}]");
            }
        }
        // RNEA(q̈) − RNEA(0) = M q̈; p = M q̇; forward dynamics inverts RNEA
        let tau = rnea(&model, &mut data, &q, &qd, &qdd).unwrap().clone();
        let bias = rnea(&model, &mut data, &q, &qd, &vec![0.0; n])
            .unwrap()
            .clone();
        let p = momentum(&model, &mut data, &q, &qd).unwrap().clone();
        for r in 0..n {
            let mq: f64 = (0..n).map(|c| m[(r, c)] * qdd[c]).sum();
            assert!((tau[r] - bias[r] - mq).abs() < 1e-9, "{name}: RNEA row {r}");
            let mv: f64 = (0..n).map(|c| m[(r, c)] * qd[c]).sum();
            assert!((p[r] - mv).abs() < 1e-9, "{name}: momentum row {r}");
        }
        let back = forward_dynamics(&model, &mut data, &q, &qd, tau.as_slice()).unwrap();
        for r in 0..n {
            assert!((back[r] - qdd[r]).abs() < 1e-8, "{name}: q̈ row {r}");
        }
    }
    // a length or a value that cannot be an inertia is refused
    let mut model = common::lwr4();
    assert!(model.set_armature(&[0.1; 3]).is_err());
    assert!(model.set_armature(&[-0.1; 7]).is_err());
    assert!(model.set_armature(&[f64::NAN; 7]).is_err());
}
