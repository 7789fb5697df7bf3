//! The robot side of the 1 kHz protocol runs in the lock-step cell as in the
//! robot process: a dead controller's last command is reused for 20 periods,
//! then the brakes hold the arm; a controller that comes back releases them
//! and re-syncs.

use crate::common;

use phri_cell::{CellOptions, Down, Outage};
use phri_ipc::{robot_status, ControlMode};

#[test]
fn the_cell_brakes_when_the_controller_is_down_and_recovers_when_it_returns() {
    let opts = CellOptions {
        perception: false,
        outages: vec![Outage {
            service: Down::Control,
            from_s: 5.0,
            to_s: 6.0,
        }],
        ..CellOptions::default()
    };
    let mut cell = common::cell("free-motion", &opts, &[]);
    // before: a fresh command every period, no brakes
    for _ in 0..4990 {
        cell.tick().unwrap();
    }
    assert!(!cell.link_output().brake && cell.link_output().fresh);
    assert_eq!(cell.controller.mode(), ControlMode::Task);
    let moving = cell
        .sim
        .state()
        .1
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max);
    assert!(
        moving > 0.05,
        "the arm moves before the outage ({moving} rad/s)"
    );
    // the controller dies at 5 s: 20 periods on its last command, then the brakes
    let mut first_brake = None;
    for k in 0..1000 {
        cell.tick().unwrap();
        let out = *cell.link_output();
        if out.brake && first_brake.is_none() {
            first_brake = Some(k);
            assert_eq!(out.missed, 21);
            assert_ne!(
                cell.state.status & robot_status::BRAKING,
                0,
                "the state says so"
            );
        }
        if let Some(k0) = first_brake {
            assert!(
                out.brake,
                "released at {k} without a controller (braked at {k0})"
            );
        } else if k > 10 {
            // the last command, reused
            assert!(!out.fresh && out.missed <= 20, "{out:?}");
        }
    }
    let k0 = first_brake.expect("the robot never braked without its controller");
    // the outage starts with the state of 5.000 s (the 10th period here); the
    // robot answers 21 missing commands with the brakes
    assert_eq!(k0, 9 + 21, "braked after {k0} periods");
    // braked for the rest of the outage: the arm comes to rest
    let speed = cell
        .sim
        .state()
        .1
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max);
    assert!(speed < 1e-3, "still moving at {speed} rad/s while braked");
    // the controller is back: brakes released, the task resumes
    for _ in 0..4000 {
        cell.tick().unwrap();
    }
    assert!(!cell.link_output().brake && cell.link_output().fresh);
    assert_eq!(cell.controller.mode(), ControlMode::Task);
    let s = cell.summary();
    assert!(
        (0.97..=0.99).contains(&s.braked_s),
        "braked {} s",
        s.braked_s
    );
    assert_eq!(s.false_detections, 0);
}
