//! The whole cell in lock-step on the deployed configuration: avoidance keeps
//! the person untouched wherever in the robot's cycle they arrive, and while
//! perception or the residual is briefly down.

mod common;

use common::run;
use phri_cell::{CellOptions, Down, Outage};

#[test]
fn coexistence_is_contact_free_wherever_the_person_meets_the_cycle() {
    // the task cycle lasts 4 s: meet it at four phases
    for offset in [0.0, -1.0, -2.0, -3.0] {
        let opts = CellOptions {
            human_time_offset_s: offset,
            ..CellOptions::default()
        };
        let s = run("coexistence", 30.0, &opts, &[]);
        eprintln!(
            "offset {offset}: closest {:.3} m, {} waypoints, {} frames",
            s.min_distance_m, s.waypoints, s.frames
        );
        assert_eq!(
            s.unintended_contacts, 0,
            "offset {offset}: {:?}",
            s.contacts
        );
        assert!(s.frames > 850, "the camera ran: {} frames", s.frames);
        assert!(
            s.min_distance_m < 0.3,
            "the person came near: {}",
            s.min_distance_m
        );
        assert!(
            s.waypoints >= 2,
            "the task went on: {} waypoints",
            s.waypoints
        );
    }
}

#[test]
fn without_avoidance_the_same_cell_hits_the_person() {
    // the scenario is a real test: the same run with avoidance off has contacts
    let s = run(
        "coexistence",
        30.0,
        &CellOptions::default(),
        &["control.avoidance=false"],
    );
    assert!(s.unintended_contacts >= 2, "{:?}", s.contacts);
    assert_eq!(s.frames, 0, "no perception without avoidance");
}

#[test]
fn outages_while_the_person_steps_in_stop_the_arm_without_contact() {
    // a 1 s outage of perception or of the residual as the person steps in (8.5-11 s)
    for (service, from_s) in [
        (Down::Perception, 8.5),
        (Down::Dynamics, 9.5),
        (Down::Perception, 10.5),
    ] {
        let opts = CellOptions {
            human_time_offset_s: -1.0,
            outages: vec![Outage {
                service,
                from_s,
                to_s: from_s + 1.0,
            }],
            ..CellOptions::default()
        };
        let s = run("coexistence", 16.0, &opts, &[]);
        eprintln!(
            "{service:?} down at {from_s} s: closest {:.3} m, stopped {:.2} s",
            s.min_distance_m, s.protective_stop_s
        );
        assert!(
            s.protective_stop_s > 0.5,
            "{service:?}: no protective stop ({} s)",
            s.protective_stop_s
        );
        assert_eq!(
            s.unintended_contacts, 0,
            "{service:?} at {from_s}: {:?}",
            s.contacts
        );
    }
}

#[test]
fn malformed_outages_are_refused_with_the_format() {
    for bad in [
        "camera:1:2",
        "perception:2:1",
        "dynamics:x:2",
        "perception:1",
        "perception:1:2:3",
        "",
    ] {
        let e = bad.parse::<Outage>().unwrap_err().to_string();
        assert!(
            e.contains("perception|dynamics|control:FROM:TO"),
            "{bad}: {e}"
        );
    }
    let o: Outage = "dynamics:1.5:2.5".parse().unwrap();
    assert_eq!(o.service, Down::Dynamics);
    assert_eq!((o.from_s, o.to_s), (1.5, 2.5));
    assert_eq!(
        "control:0:1".parse::<Outage>().unwrap().service,
        Down::Control
    );
}
