//! The hot standby in lock-step: a second controller answers every state
//! (with `[control] standby_rests`, only those the one in charge has not
//! answered when it looks) and adopts the behaviour of the one in charge,
//! so that stopping, killing or restarting either controller costs the arm nothing. The
//! measure is physical: the arm's true joint trajectory with the fault is
//! the trajectory without it, and the robot link missed no deadline.

mod common;

use common::{cell, loaded};
use phri_cell::{Cell, CellOptions, CellSummary, Down, Outage};
use phri_control::standby::FULL_STEP_EVERY;
use phri_control::Controller;
use phri_ipc::ControlMode;

fn standby_opts(outages: &[(Down, f64, f64)]) -> CellOptions {
    CellOptions {
        standby: true,
        outages: outages
            .iter()
            .map(|&(service, from_s, to_s)| Outage {
                service,
                from_s,
                to_s,
            })
            .collect(),
        ..CellOptions::default()
    }
}

/// One run: the true joint positions every period, the largest change of
/// the applied torque from one period to the next \[Nm\], the summary.
struct Run {
    q: Vec<Vec<f64>>,
    max_step_nm: f64,
    summary: CellSummary,
    cell: Cell,
}

/// Run `scenario` for `seconds`; `at` is called before each period with the
/// cell and the robot time \[s\] (restarts).
fn run(
    scenario: &str,
    sets: &[&str],
    seconds: f64,
    opts: &CellOptions,
    mut at: impl FnMut(&mut Cell, f64),
) -> Run {
    let mut c = cell(scenario, opts, sets);
    let mut q = Vec::new();
    let mut last: Option<Vec<f64>> = None;
    let mut max_step_nm = 0.0f64;
    for k in 0..(seconds * 1000.0).round() as usize {
        at(&mut c, k as f64 * 1e-3);
        c.tick().unwrap();
        q.push(c.sim.truth().q.clone());
        let tau = c.link_output().torque().to_vec();
        if let (Some(l), false) = (&last, c.link_output().brake) {
            for (a, b) in tau.iter().zip(l) {
                max_step_nm = max_step_nm.max((a - b).abs());
            }
        }
        last = Some(tau);
    }
    Run {
        q,
        max_step_nm,
        summary: c.summary(),
        cell: c,
    }
}

/// The largest joint difference between two runs' trajectories \[rad\].
fn largest_gap(a: &Run, b: &Run) -> f64 {
    a.q.iter()
        .zip(&b.q)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Bumpless: both controllers answered alike, a takeover stepped the
/// torque no more than a period of `reference` did, and the arm moved as in
/// `reference`, the run without the fault.
fn assert_bumpless(reference: &Run, faulted: &Run, robot: &str) {
    let s = faulted.summary.standby.clone().expect("the standby ran");
    assert!(
        s.max_answer_diff_nm <= 1e-9,
        "{robot}: {}",
        s.max_answer_diff_nm
    );
    assert!(s.max_takeover_diff_nm <= reference.max_step_nm, "{robot}");
    let gap = largest_gap(reference, faulted);
    assert!(
        gap < 1e-9,
        "{robot}: the arm moved as without the fault ({gap:e} rad)"
    );
}

fn fresh_controller(scenario: &str, sets: &[&str]) -> Controller {
    let l = loaded(scenario, sets);
    Controller::from_config(l.model().unwrap(), &l.config).unwrap()
}

#[test]
fn a_retreat_just_after_a_takeover_walks_the_path_back_as_without_the_fault() {
    // the person strikes the arm at 5.6 s; the first controller stops at
    // 5.4 s: the standby, resting through the states answered before (or
    // stepping every state), takes over and retreats along the path's
    // history, which it kept from the behaviours it received
    for rests in ["control.standby_rests=true", "control.standby_rests=false"] {
        let sets = [
            "control.avoidance=false",
            "control.reaction=\"retreat\"",
            rests,
        ];
        let reference = run("collision", &sets, 7.5, &standby_opts(&[]), |_, _| {});
        let outages = [(Down::Control, 5.4, 6.5)];
        let faulted = run("collision", &sets, 7.5, &standby_opts(&outages), |_, _| {});
        let s = faulted.summary.standby.clone().expect("the standby ran");
        assert_eq!(s.takeovers, 1, "{rests}");
        assert_eq!(s.missed_deadlines, 0, "{rests}");
        assert!(
            faulted.summary.detections > 0,
            "{rests}: the strike was detected"
        );
        let gap = largest_gap(&reference, &faulted);
        assert!(
            gap < 1e-9,
            "{rests}: the arm moved as without the fault ({gap:e} rad)"
        );
    }
}

#[test]
fn a_stopped_controller_costs_the_arm_nothing_on_either_arm() {
    // the standby resting through the states the one in charge answers
    // and stepping every state (the default)
    for (robot, rests) in [
        ("robot.name=lwr4", "control.standby_rests=true"),
        ("robot.name=fr3", "control.standby_rests=true"),
        ("robot.name=lwr4", "control.standby_rests=false"),
    ] {
        let sets = [robot, rests];
        let robot = format!("{robot} {rests}");
        let reference = run("coexistence", &sets, 7.0, &standby_opts(&[]), |_, _| {});
        // the first controller stops for 0.5 s (SIGSTOP), the standby stops for 0.3 s later
        let outages = [(Down::Control, 3.0, 3.5), (Down::Standby, 5.0, 5.3)];
        let faulted = run(
            "coexistence",
            &sets,
            7.0,
            &standby_opts(&outages),
            |_, _| {},
        );
        let s = faulted.summary.standby.clone().expect("the standby ran");
        println!(
            "{robot}: {s:?}, largest torque step of the run {:.3} Nm",
            reference.max_step_nm
        );
        assert_eq!(s.missed_deadlines, 0, "{robot}: no deadline missed");
        assert_eq!(s.takeovers, 2, "{robot}: the standby, then the first again");
        assert_eq!(
            faulted.summary.braked_s, 0.001,
            "{robot}: braked only before the start"
        );
        assert_bumpless(&reference, &faulted, &robot);
        // the stopped one rejoined as the standby: both answered after it
        // woke, every state or (resting) one in FULL_STEP_EVERY
        let both = 6000 - 500 - 300 - 100;
        let both = match rests.ends_with("true") {
            true => both / FULL_STEP_EVERY - 2,
            false => both,
        };
        assert!(s.both_answered > both, "{robot}: {}", s.both_answered);
        if rests.ends_with("true") {
            // and rested through the rest
            assert!(
                s.both_answered < 2 * both + 100,
                "{robot}: {}",
                s.both_answered
            );
        }
        assert_eq!(faulted.cell.mode(), ControlMode::Task);
        assert!(faulted.summary.waypoints >= 1);
    }
}

#[test]
fn a_restarted_controller_commands_only_after_it_resynced() {
    let sets: [&str; 0] = [];
    let reference = run("coexistence", &sets, 6.0, &standby_opts(&[]), |_, _| {});
    // the first controller dies at 2.0 s and its successor starts at 2.2 s; at
    // 4.0 s the standby (in charge since 2.0 s) dies and restarts at 4.3 s
    let outages = [(Down::Control, 2.0, 2.2), (Down::Standby, 4.0, 4.3)];
    let mut restarts = [(2.2, false), (4.3, true)].into_iter().peekable();
    let faulted = run(
        "coexistence",
        &sets,
        6.0,
        &standby_opts(&outages),
        |c, t| {
            if let Some(&(at, standby)) = restarts.peek() {
                if t >= at {
                    restarts.next();
                    let fresh = fresh_controller("coexistence", &sets);
                    match standby {
                        false => c.restart_controller(fresh),
                        true => c.restart_standby(fresh),
                    }
                }
            }
        },
    );
    let s = faulted.summary.standby.clone().unwrap();
    println!("{s:?}");
    assert_eq!((s.missed_deadlines, s.takeovers), (0, 2));
    let gap = largest_gap(&reference, &faulted);
    assert!(
        gap < 1e-9,
        "the arm moved as without the restarts ({gap:e} rad)"
    );
}

#[test]
fn both_controllers_down_still_brake_and_the_cell_resumes() {
    let outages = [(Down::Control, 3.0, 3.5), (Down::Standby, 3.0, 3.5)];
    let r = run("coexistence", &[], 8.0, &standby_opts(&outages), |_, _| {});
    let s = r.summary.standby.clone().unwrap();
    println!("{s:?}, braked {:.3} s", r.summary.braked_s);
    assert_eq!(s.takeovers, 0, "nobody to take over");
    assert!(s.missed_deadlines >= 480, "{}", s.missed_deadlines);
    assert!(
        r.summary.braked_s > 0.45,
        "the brakes held the arm: {}",
        r.summary.braked_s
    );
    assert_eq!(r.cell.mode(), ControlMode::Task, "resumed");
    // without the standby, one controller stopped is the same brake
    let alone = CellOptions {
        outages: standby_opts(&outages[..1]).outages,
        ..CellOptions::default()
    };
    let a = run("coexistence", &[], 8.0, &alone, |_, _| {});
    assert!(a.summary.braked_s > 0.45 && a.summary.standby.is_none());
}

#[test]
fn a_takeover_in_contact_with_the_hand_is_the_collaboration_without_it() {
    let sets: [&str; 0] = [];
    let seconds = 14.0;
    let reference = run(
        "collaboration",
        &sets,
        seconds,
        &standby_opts(&[]),
        |_, _| {},
    );
    let contact = reference
        .summary
        .modes
        .iter()
        .find(|(_, m)| m == "contact")
        .map(|(t, _)| *t)
        .expect("the reference touches the hand");
    let outages = [(Down::Control, contact + 0.1, contact + 0.6)];
    let faulted = run(
        "collaboration",
        &sets,
        seconds,
        &standby_opts(&outages),
        |_, _| {},
    );
    let s = faulted.summary.standby.clone().unwrap();
    println!("contact at {contact:.3} s: {s:?}");
    assert_eq!((s.missed_deadlines, s.takeovers), (0, 1));
    let gap = largest_gap(&reference, &faulted);
    assert!(
        gap < 1e-9,
        "the collaboration went on as without the stop ({gap:e} rad)"
    );
    let peak = |r: &Run| {
        r.summary
            .contacts
            .iter()
            .filter(|c| c.intended)
            .map(|c| c.peak_force_n)
            .fold(0.0, f64::max)
    };
    assert!(peak(&reference) > 0.0);
    assert_eq!(peak(&faulted), peak(&reference));
}

#[test]
fn a_takeover_while_the_barrier_filter_holds_the_arm_is_bumpless() {
    // under the barrier filter the hand holds the arm short of its second
    // waypoint from about 10.5 s (`coexistence`): the first controller stops
    // at 12 s, inside the hold, where the path's pace is the filter's, and
    // the standby, resting through the states before, takes over with the
    // pace and the solver's warm start it adopted
    for robot in ["robot.name=lwr4", "robot.name=panda"] {
        let sets = [robot, "avoidance.law=\"cbf\""];
        let seconds = 14.0;
        let reference = run("coexistence", &sets, seconds, &standby_opts(&[]), |_, _| {});
        let r = reference.summary.standby.clone().unwrap();
        assert!(
            r.max_answer_diff_nm <= 1e-9,
            "{robot}: both controllers answer alike ({} Nm)",
            r.max_answer_diff_nm
        );
        let outages = [(Down::Control, 12.0, 12.5)];
        let faulted = run(
            "coexistence",
            &sets,
            seconds,
            &standby_opts(&outages),
            |_, _| {},
        );
        let s = faulted.summary.standby.clone().unwrap();
        println!(
            "{robot}: {s:?}, largest torque step of the run {:.3} Nm",
            reference.max_step_nm
        );
        assert_eq!((s.missed_deadlines, s.takeovers), (0, 1), "{robot}");
        assert_bumpless(&reference, &faulted, robot);
    }
}
