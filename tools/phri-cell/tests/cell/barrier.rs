//! The control-barrier safety filter (`[avoidance] law = "cbf"`) in
//! lock-step on the deployed configuration, camera and perception as
//! deployed: beside a person it touches no one and keeps more of the task
//! than the paper's law, which brakes every point near a person whether it
//! approaches or not.

use crate::common::run;
use phri_cell::CellOptions;

const CBF: &str = "avoidance.law=\"cbf\"";

fn at(offset: f64) -> CellOptions {
    CellOptions {
        human_time_offset_s: offset,
        ..CellOptions::default()
    }
}

/// `coexistence` for `seconds` under both laws with `opts`: the filter
/// touches no one, the person came near (not vacuous) and no nearer than
/// 3 cm; (the filter's waypoints, the paper's).
fn both_laws(opts: &CellOptions, seconds: f64) -> (u64, u64) {
    let offset = opts.human_time_offset_s;
    let cbf = run("coexistence", seconds, opts, &[CBF]);
    let paper = run("coexistence", seconds, opts, &[]);
    eprintln!(
        "offset {offset}: cbf {} waypoints, closest {:.3} m; paper {} waypoints, closest {:.3} m",
        cbf.waypoints, cbf.min_distance_m, paper.waypoints, paper.min_distance_m
    );
    assert_eq!(
        cbf.unintended_contacts, 0,
        "offset {offset}: {:?}",
        cbf.contacts
    );
    assert!(
        cbf.min_distance_m < 0.15,
        "offset {offset}: the person stayed {:.3} m away",
        cbf.min_distance_m
    );
    assert!(
        cbf.min_distance_m >= 0.03,
        "offset {offset}: closest {:.3} m",
        cbf.min_distance_m
    );
    (cbf.waypoints, paper.waypoints)
}

#[test]
fn beside_a_person_seen_by_the_camera_the_barrier_filter_touches_no_one() {
    for offset in [0.0, -2.0] {
        let (cbf, paper) = both_laws(&at(offset), 30.0);
        assert!(
            cbf >= paper,
            "offset {offset}: cbf {cbf} waypoints, paper {paper}"
        );
    }
}

#[test]
fn with_perception_that_hides_nothing_the_barrier_filter_keeps_more_of_the_task_than_the_paper_s_law(
) {
    // `phri-lockstep --scenario coexistence --duration 60 --truth-perception
    // --sweep -8,2,2`: the paper's 17-22 waypoints on the default arm, the
    // filter's 22-24 (free motion: 41)
    for offset in [0.0, -4.0] {
        let opts = CellOptions {
            truth_perception: true,
            ..at(offset)
        };
        let (cbf, paper) = both_laws(&opts, 60.0);
        assert!(
            cbf > paper,
            "offset {offset}: cbf {cbf} waypoints, paper {paper}"
        );
    }
}

#[test]
fn a_hand_moving_into_the_elbow_is_evaded_under_the_barrier_filter() {
    let mut closest = f64::INFINITY;
    for offset in [-4.0, -2.0, 0.0] {
        let s = run("elbow", 28.0, &at(offset), &[CBF]);
        eprintln!(
            "elbow, offset {offset}: closest {:.3} m, {} waypoints",
            s.min_distance_m, s.waypoints
        );
        assert_eq!(
            s.unintended_contacts, 0,
            "offset {offset}: {:?}",
            s.contacts
        );
        assert!(s.waypoints >= 5, "the task went on: {}", s.waypoints);
        closest = closest.min(s.min_distance_m);
    }
    assert!(closest < 0.12, "the person stayed {closest:.3} m away");
}
