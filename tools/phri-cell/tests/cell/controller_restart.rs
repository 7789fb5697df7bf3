//! A controller restarted mid-contact ends the collaboration safely, in
//! lock-step: the new controller (a new process: nothing of its
//! predecessor's collaboration survives) ends it with `controller_restart`,
//! holds in a protective stop while the hand is at the robot, and resumes
//! its task only once the hand has gone. Checked with the right hand held
//! at the end effector and leaving (`collaboration`), and with the left hand
//! resting on the wrist for the rest of the run (`voice-collaboration`).

use crate::common;

use phri_cell::{Cell, CellOptions};
use phri_config::{Keyframe, Loaded};
use phri_control::Controller;
use phri_ipc::{CollabPhase, CollabReason, ControlMode};

/// The robot's links the collaborative hand meets: the end effector's and the wrist's.
const LINKS: [&str; 2] = ["lwr_link_7", "lwr_link_6"];

/// What happened after the restart.
struct AfterRestart {
    /// the restarted controller's collaboration: its phase and why
    phase: CollabPhase,
    reason: CollabReason,
    /// periods in `task` or `slow` while the hand was within 5 cm of the robot
    task_near_hand: usize,
    /// the hand's true distance to the robot when the restart happened \[m\]
    distance_at_restart: f64,
    /// the first time \[s\] the task ran again, and the hand's distance then \[m\]
    resumed: Option<(f64, f64)>,
    protective_stops: u64,
    unintended: usize,
}

/// Run `l` until the collaboration has been in contact for 0.5 s, restart
/// the controller, run until `until_s` \[s\] with `hand` (a body part name).
fn restart_in_contact(l: &Loaded, hand: &str, until_s: f64) -> AfterRestart {
    let mut c = common::cell_of(l, &CellOptions::default());
    let mut contact_since = None;
    while c.time_ns() < 14_000_000_000 {
        c.tick().unwrap();
        let t = c.time_ns() as f64 * 1e-9;
        let phase = c.controller.collaboration().unwrap().machine().phase();
        if phase == CollabPhase::Contact && t - *contact_since.get_or_insert(t) >= 0.5 {
            break;
        }
    }
    assert!(contact_since.is_some(), "no contact by 14 s");
    let distance_at_restart = common::parts_to_links(&c, &[hand], &LINKS);
    let mut controller = Controller::from_config(l.model().unwrap(), &l.config).unwrap();
    controller.restarted();
    c.restart_controller(controller);
    let mut r = AfterRestart {
        phase: CollabPhase::Idle,
        reason: CollabReason::None,
        task_near_hand: 0,
        distance_at_restart,
        resumed: None,
        protective_stops: 0,
        unintended: 0,
    };
    while (c.time_ns() as f64) < until_s * 1e9 {
        c.tick().unwrap();
        let d = common::parts_to_links(&c, &[hand], &LINKS);
        let tasking = matches!(c.mode(), ControlMode::Task | ControlMode::Slow);

        if tasking && d < 0.05 {
            r.task_near_hand += 1;
        }
        if tasking && r.resumed.is_none() {
            r.resumed = Some((c.time_ns() as f64 * 1e-9, d));
        }
    }
    let m = c.controller.collaboration().unwrap().machine();
    (r.phase, r.reason) = (m.phase(), m.reason());
    r.protective_stops = c.controller.counters().protective_stops;
    r.unintended = summary_unintended(&c);
    r
}

fn summary_unintended(c: &Cell) -> usize {
    c.summary().unintended_contacts
}

fn report(name: &str, r: &AfterRestart) {
    eprintln!(
        "{name}: hand {:.3} m from the robot at the restart; phase {:?} ({:?}); {} protective stop(s); \
         task near the hand {} ms; resumed {:?}; {} unintended contact(s)",
        r.distance_at_restart,
        r.phase,
        r.reason,
        r.protective_stops,
        r.task_near_hand,
        r.resumed,
        r.unintended
    );
}

/// Print the run; the hand was at the robot when the controller restarted,
/// and the new controller ended the collaboration for the restart.
fn ended_by_the_restart_in_contact(name: &str, r: &AfterRestart) {
    report(name, r);
    assert!(
        r.distance_at_restart < 0.02,
        "the hand was not at the robot"
    );
    assert_eq!(
        (r.phase, r.reason),
        (CollabPhase::Idle, CollabReason::ControllerRestart)
    );
}

#[test]
fn a_controller_restarted_with_the_hand_at_the_end_effector_holds_until_it_left() {
    // the right hand held out 7-11 s, moved 11-12 s to a new place 5 cm
    // from the held arm, held there; lowered at 15.5 s (the left hand
    // pushes the wrist 15.5-16.5 s)
    let l = common::loaded("collaboration", &[]);
    let r = restart_in_contact(&l, "hand_right", 19.0);
    ended_by_the_restart_in_contact("collaboration", &r);
    assert_eq!(
        r.protective_stops, 1,
        "the restarted controller did not hold"
    );
    assert_eq!(
        r.task_near_hand, 0,
        "task motion with the hand at the robot"
    );
    let (t, d) = r
        .resumed
        .expect("the task never resumed after the hand left");
    assert!(
        t > 15.5 && d > 0.1,
        "resumed at {t:.2} s, the hand {d:.3} m away"
    );
    assert_eq!(r.unintended, 0);
}

#[test]
fn a_controller_restarted_with_a_hand_resting_on_the_wrist_keeps_holding() {
    // voice-collaboration: "follow the left hand", the left hand held out
    // from 10.5 s and held there to the end
    let mut l = common::rescript("voice-collaboration", &[], |keyframes| {
        keyframes.retain(|k| k.t <= 10.5);
        let last = keyframes.last().cloned().unwrap();
        keyframes.push(Keyframe { t: 20.0, ..last });
    });
    l.scenario.voice.retain(|v| v.t < 10.0);
    let r = restart_in_contact(&l, "hand_left", 19.0);
    ended_by_the_restart_in_contact("voice-collaboration", &r);
    assert_eq!(r.protective_stops, 1);
    assert_eq!(
        r.resumed, None,
        "the task resumed with the hand on the robot"
    );
}

#[test]
fn a_controller_restarted_far_from_any_hand_resumes_at_once() {
    // restarted in the approach's first second: the hand is far, nothing holds
    let l = common::loaded("collaboration", &[]);
    let mut c = common::cell_of(&l, &CellOptions::default());
    while c.controller.collaboration().unwrap().machine().phase() != CollabPhase::Approach {
        c.tick().unwrap();
        assert!(c.time_ns() < 10_000_000_000, "no approach by 10 s");
    }
    let d = common::parts_to_links(&c, &["hand_right", "hand_left"], &LINKS);
    let mut controller = Controller::from_config(l.model().unwrap(), &l.config).unwrap();
    controller.restarted();
    c.restart_controller(controller);
    let t0 = c.time_ns();
    while !matches!(c.mode(), ControlMode::Task | ControlMode::Slow) {
        c.tick().unwrap();
        assert!(
            c.time_ns() - t0 < 1_000_000_000,
            "still {:?} after 1 s",
            c.mode()
        );
    }
    let waited = (c.time_ns() - t0) as f64 * 1e-9;
    eprintln!("hands {d:.3} m from the robot at the restart: task again after {waited:.3} s");
    assert!(d > 0.1);
    assert_eq!(c.controller.counters().protective_stops, 0);
    let m = c.controller.collaboration().unwrap().machine();
    assert_eq!(m.reason(), CollabReason::ControllerRestart);
}
