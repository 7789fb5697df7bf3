//! The controller refuses what it cannot act on: a malformed joint state
//! (non-finite, wrong length) gives a finite hold torque, never a panic; a
//! configuration it cannot run is an error at construction.

use phri_config::Config;
use phri_control::{ControlConfig, ControlInput, Controller, ControllerParams, Reaction};
use phri_model::Model;

const PARAMS: ControllerParams = ControllerParams { period_s: 0.001 };

fn lwr4() -> Model {
    Model::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/robots/kuka_lwr4.urdf"
    ))
    .unwrap()
}

fn control_config(reaction: Reaction) -> ControlConfig {
    ControlConfig {
        reaction,
        ..Config::defaults().control
    }
}

#[test]
fn malformed_state_never_panics() {
    let mut c = Controller::new(lwr4(), control_config(Reaction::Reflex), PARAMS).unwrap();
    let out = c.step(&ControlInput {
        state_stamp_ns: 1,
        q: &[f64::NAN; 7],
        residual: None,
        perception: None,
        collab: Default::default(),
    });
    assert!(out.tau.iter().all(|t| t.is_finite()));
    let out = c.step(&ControlInput {
        state_stamp_ns: 2,
        q: &[0.0; 3],
        residual: None,
        perception: None,
        collab: Default::default(),
    });
    assert_eq!(out.tau.len(), 7);
    let bad = ControlConfig {
        waypoints: vec![[0.0; 3]],
        ..control_config(Reaction::Reflex)
    };
    assert!(Controller::new(lwr4(), bad, PARAMS).is_err());
    let bad = ControlConfig {
        ee_link: "nope".into(),
        ..control_config(Reaction::Reflex)
    };
    assert!(Controller::new(lwr4(), bad, PARAMS).is_err());
}
