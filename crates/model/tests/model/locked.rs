//! Locked joints (Pinocchio's reduced model): the Panda with its fingers
//! held at zero is the full Panda at finger position zero, restricted to the
//! arm: the same M block, the same gravity, the same RNEA torques at zero
//! finger motion.

use crate::common::*;
use phri_model::*;

fn locked_panda(locked: &[&str]) -> Result<Model, ModelError> {
    let names: Vec<String> = locked.iter().map(|s| s.to_string()).collect();
    Model::from_urdf_file_locked(
        repo_path("deploy/robots/panda/panda_collision.urdf"),
        &names,
    )
}

#[test]
fn the_panda_with_its_fingers_locked_is_the_full_panda_at_closed_fingers() {
    let arm = locked_panda(&["panda_finger_joint1"]).unwrap();
    let full = locked_panda(&[]).unwrap();
    assert_eq!((arm.nv(), full.nv()), (7, 8));
    // the mimic follower went with its leader; the fingers still weigh on the flange
    assert!(arm.joints.iter().all(|j| j.mimic.is_none()));
    assert_eq!(arm.collisions.len(), full.collisions.len());
    let mut rng = rng(7);
    let (mut da, mut df) = (Data::new(&arm), Data::new(&full));
    for _ in 0..20 {
        let q = random_vec(&mut rng, 7, 1.5);
        let qd = random_vec(&mut rng, 7, 1.0);
        let qdd = random_vec(&mut rng, 7, 2.0);
        let pad = |v: &[f64]| {
            let mut x = v.to_vec();
            x.push(0.0);
            x
        };
        let ma = crba(&arm, &mut da, &q).unwrap().clone();
        let mf = crba(&full, &mut df, &pad(&q)).unwrap().clone();
        assert!((ma - mf.view((0, 0), (7, 7))).abs().max() < 1e-12);
        let ga = gravity(&arm, &mut da, &q).unwrap().clone();
        let gf = gravity(&full, &mut df, &pad(&q)).unwrap().clone();
        assert!((ga - gf.rows(0, 7)).abs().max() < 1e-12);
        let ta = rnea(&arm, &mut da, &q, &qd, &qdd).unwrap().clone();
        let tf = rnea(&full, &mut df, &pad(&q), &pad(&qd), &pad(&qdd))
            .unwrap()
            .clone();
        assert!((ta - tf.rows(0, 7)).abs().max() < 1e-10);
    }
}

#[test]
fn a_joint_to_lock_that_is_not_there_or_does_not_move_is_named() {
    for name in ["panda_finger_joint9", "panda_joint8"] {
        let e = locked_panda(&[name]).unwrap_err();
        assert!(
            matches!(&e, ModelError::UnknownLockedJoint(n) if n == name),
            "{e}"
        );
        assert!(e.to_string().contains(name));
    }
}
