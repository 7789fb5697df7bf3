//! Speed and separation monitoring (ISO/TS 15066 5.5.4, `[ssm]`) in
//! lock-step: a person walking straight at the working arm finds it
//! stopped, which it is not without the monitor; beside a person who only
//! reaches in, the task keeps its pace.

mod common;

use phri_cell::CellOptions;

fn at(offset: f64) -> CellOptions {
    CellOptions {
        human_time_offset_s: offset,
        ..CellOptions::default()
    }
}

/// `walk-in` on `robot` at `offset` with `[ssm] enabled = ssm`: the end
/// effector's speed when the person arrives [m/s], and the run.
fn walk_in(robot: &str, offset: f64, ssm: bool) -> (f64, phri_cell::CellSummary) {
    // the person stops at 3.45 s of their script (1.6 m/s from 2 s)
    walk_at("walk-in", 3.45, 9.0, robot, offset, ssm)
}

/// `scenario` (a person who arrives at `arrival` \[s\] of their script)
/// for `seconds` on `robot` at `offset` with `[ssm] enabled = ssm`: the end
/// effector's speed when the person arrives [m/s], and the run.
fn walk_at(
    scenario: &str,
    arrival: f64,
    seconds: f64,
    robot: &str,
    offset: f64,
    ssm: bool,
) -> (f64, phri_cell::CellSummary) {
    let arm = format!("robot.name=\"{robot}\"");
    let on = format!("ssm.enabled={ssm}");
    let mut c = common::cell(scenario, &at(offset), &[arm.as_str(), on.as_str()]);
    let arrival = arrival - offset;
    let (mut before, mut speed) = (None, f64::NAN);
    for k in 1..=(seconds * 1000.0).round() as usize {
        c.tick().unwrap();
        let t = k as f64 * 0.001;
        if (t - (arrival - 0.01)).abs() < 5e-4 {
            before = Some(c.controller.ee());
        }
        if (t - arrival).abs() < 5e-4 {
            speed = before.map_or(f64::NAN, |b| (c.controller.ee() - b).norm() / 0.01);
        }
    }
    (speed, c.summary())
}

#[test]
fn a_person_walking_in_finds_the_arm_stopped() {
    for robot in ["lwr4", "fr3"] {
        for offset in [-1.0, 0.0, 1.0] {
            let (speed, s) = walk_in(robot, offset, true);
            eprintln!(
                "{robot} {offset}: the end effector at {speed:.3} m/s when the person arrived; closest {:.3} m, monitor limiting {:.1} s, {} violations",
                s.min_distance_m, s.ssm_limited_s, s.ssm_violations
            );
            assert!(speed < 0.01, "{robot} {offset}: {speed:.3} m/s");
            assert!(s.contacts.is_empty(), "{robot} {offset}: {:?}", s.contacts);
            assert!(s.ssm_limited_s > 0.0);
            // never moving on toward the person inside S_p past the stop time
            let iso = &s.iso_ts_15066;
            assert!(iso.ssm_enabled);
            assert_eq!(
                iso.ssm_violations, 0,
                "{robot} {offset}: at {:?} s",
                iso.ssm_violation_times_s
            );
        }
        // not vacuous: without the monitor the arm works on as the person arrives
        let (speed, _) = walk_in(robot, 0.0, false);
        assert!(speed > 0.05, "{robot} without the monitor: {speed:.3} m/s");
    }
}

#[test]
fn a_head_at_the_paths_height_is_never_touched() {
    // deploy/scenarios/head-height.toml: the arm mounted at head height; the
    // person walks at it from 4 s and stands with the face 12 cm in front of
    // P2 from 5.55 s. ISO/TS 15066 allows no transient contact of the face
    for robot in ["lwr4", "fr3"] {
        for offset in [-1.0, 0.0, 1.0] {
            let (speed, s) = walk_at("head-height", 5.55, 10.0, robot, offset, true);
            let iso = &s.iso_ts_15066;
            eprintln!(
                "{robot} {offset}: the end effector at {speed:.3} m/s when the head arrived; closest {:.3} m, monitor limiting {:.1} s, {} violations",
                s.min_distance_m, iso.ssm_limited_s, iso.ssm_violations
            );
            assert!(s.contacts.is_empty(), "{robot} {offset}: {:?}", s.contacts);
            assert!(iso.contacts.is_empty() && iso.over_limit == 0);
            assert_eq!(iso.ssm_violations, 0, "{robot} {offset}");
            // not vacuous: the person came near enough for the monitor to bound the arm
            assert!(iso.ssm_limited_s > 0.0, "{robot} {offset}");
        }
    }
}

#[test]
fn beside_a_person_who_reaches_in_the_monitor_keeps_the_pace() {
    // one visit of `coexistence` (30 s) at two phases of the cycle, the
    // waypoints summed (one run's count moves by one with the repulsion's
    // last bits). `phri-lockstep --scenario coexistence --duration 30
    // --sweep -8,6,2 --set ssm.enabled=B`: 70-71 waypoints with the monitor,
    // 71-74 without
    let (mut with, mut without) = (0, 0);
    for offset in [0.0, -4.0] {
        let on = common::run("coexistence", 30.0, &at(offset), &["ssm.enabled=true"]);
        let off = common::run("coexistence", 30.0, &at(offset), &["ssm.enabled=false"]);
        eprintln!(
            "offset {offset}: {} waypoints with the monitor, {} without; closest {:.3} / {:.3} m; limiting {:.1} s",
            on.waypoints, off.waypoints, on.min_distance_m, off.min_distance_m, on.ssm_limited_s
        );
        assert_eq!(on.unintended_contacts, 0, "{:?}", on.contacts);
        // not vacuous: the monitor bounded the arm while the hand was in
        assert!(on.ssm_limited_s > 0.5, "{}", on.ssm_limited_s);
        (with, without) = (with + on.waypoints, without + off.waypoints);
    }
    assert!(with * 10 >= without * 9, "{with} of {without}");
}
