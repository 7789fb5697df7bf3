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
        // walking up, lingering and leaving is no wave
        assert!(
            s.gesture_requests.is_empty(),
            "offset {offset}: false requests {:?}",
            s.gesture_requests
        );
    }
}

#[test]
fn reaching_into_the_robot_is_no_wave() {
    // the person of `collision` walks in, reaches twice, steps back, leaves
    for offset in [0.0, -2.0] {
        let opts = CellOptions {
            human_time_offset_s: offset,
            ..CellOptions::default()
        };
        let s = run("collision", 16.0, &opts, &[]);
        assert!(s.frames > 450, "the camera ran: {} frames", s.frames);
        assert!(
            s.gesture_requests.is_empty(),
            "offset {offset}: false requests {:?}",
            s.gesture_requests
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

#[test]
fn a_wave_of_the_simulated_person_is_recognised_on_the_simulated_tracker() {
    // deploy/scenarios/wave.toml: the right hand waves from t = 3 s (raised
    // over 0.5 s) at 2 Hz, 12 cm, until 6 s, then is held out and lowered;
    // 4 reversals (`[gesture] reversals`) take 1.5 half periods after it is up
    let s = run("wave", 12.0, &CellOptions::default(), &[]);
    eprintln!("requests: {:?}", s.gesture_requests);
    assert_eq!(s.gesture_requests.len(), 1, "{:?}", s.gesture_requests);
    let w = &s.gesture_requests[0];
    assert_eq!(w.part, "right_hand");
    assert!(
        w.t_s > 3.0 && w.t_s <= 4.8,
        "recognised {:.2} s after the wave began at 3 s",
        w.t_s - 3.0
    );
    // the left hand never waved, the held-out hand is no wave
    assert!(w.onset_s >= 3.0, "{w:?}");
}

/// Run a collaboration scenario in lock-step: the summary and when and why
/// the (first) collaboration ended.
fn collaborate(
    scenario: &str,
    seconds: f64,
) -> (
    phri_cell::CellSummary,
    Option<(f64, phri_ipc::CollabReason)>,
    f64,
) {
    let mut c = common::cell(scenario, &CellOptions::default(), &[]);
    let mut ended_by = None;
    // the smallest distance perception saw (the masked hand excluded) at 8-9.6 s
    let mut seen = f64::INFINITY;
    for _ in 0..(seconds * 1000.0) as usize {
        c.tick().unwrap();
        let t = c.time_ns() as f64 * 1e-9;
        if (8.0..9.6).contains(&t) && c.status.min_distance > 0.0 {
            seen = seen.min(c.status.min_distance);
        }
        let m = c
            .controller
            .collaboration()
            .expect("collaboration enabled")
            .machine();
        if ended_by.is_none() && m.reason() != phri_ipc::CollabReason::None && !m.active() {
            ended_by = Some((c.time_ns() as f64 * 1e-9, m.reason()));
        }
    }
    (c.summary(), ended_by, seen)
}

#[test]
fn collaboration_wave_approach_contact_follow_and_a_wrist_push_ends_it() {
    // deploy/scenarios/collaboration.toml (paper Sect. VII-C, Figs. 8-9)
    let (s, ended_by, _) = collaborate("collaboration", 22.0);
    eprintln!("modes: {:?}", s.modes);
    eprintln!("requests: {:?}, ended by {ended_by:?}", s.gesture_requests);
    // the wave (from 3.0 s) is recognised and the approach starts within 2 s
    assert_eq!(s.gesture_requests.len(), 1, "{:?}", s.gesture_requests);
    let approach = s
        .modes
        .iter()
        .find(|(_, m)| m == "approach")
        .expect("an approach");
    assert!(
        approach.0 - 3.0 <= 2.0,
        "approach {:.2} s after the wave",
        approach.0 - 3.0
    );
    // approach → contact → follow → contact again, then recover and the task
    let order: Vec<&str> = s.modes.iter().map(|(_, m)| m.as_str()).collect();
    let first = |m: &str, from: usize| order[from..].iter().position(|x| *x == m).map(|i| i + from);
    let a = first("approach", 0).unwrap();
    let c1 = first("contact", a).expect("a first contact");
    let f = first("follow", c1).expect("a follow");
    let c2 = first("contact", f).expect("a contact after the follow");
    let r = first("recover", c2).expect("the end");
    assert!(first("task", r).is_some(), "the task resumes: {order:?}");
    assert!(!order.contains(&"reaction"), "no reaction: {order:?}");
    assert!(!order.contains(&"protective_stop"), "no stop: {order:?}");
    // the wrist push (15.5-16.5 s) ends it
    let (t_end, why) = ended_by.expect("the collaboration ended");
    assert_eq!(why, phri_ipc::CollabReason::WristPush);
    assert!(
        (15.5..16.0).contains(&t_end),
        "ended at {t_end:.2} s: the push began at 15.5 s"
    );
    // only intended contacts: the right hand on the end effector, the push
    assert_eq!(s.unintended_contacts, 0, "{:?}", s.contacts);
    let hand: Vec<_> = s
        .contacts
        .iter()
        .filter(|c| c.part == "hand_right")
        .collect();
    assert!(
        hand.iter().any(|c| c.t_start_s < 11.0),
        "first contact: {hand:?}"
    );
    assert!(
        hand.iter().any(|c| c.t_start_s > 12.0),
        "second contact: {hand:?}"
    );
    assert!(hand.iter().all(|c| c.link == "lwr_link_7" && c.intended));
    let peak = hand.iter().map(|c| c.peak_force_n).fold(0.0, f64::max);
    assert!(peak <= 70.0, "peak intended force {peak:.1} N");
}

#[test]
fn safe_collaboration_avoids_the_crossing_hand_and_still_reaches_the_other() {
    // deploy/scenarios/safe-collaboration.toml (paper Sect. VII-D, Figs. 10-11):
    // the left hand crosses the approach at 7.3-8.8 s
    let (s, ended_by, seen) = collaborate("safe-collaboration", 22.0);
    eprintln!(
        "modes: {:?}, ended by {ended_by:?}, closest seen {seen:.3} m",
        s.modes
    );
    // the crossing hand came close: avoidance had work to do
    assert!(seen < 0.15, "the crossing hand stayed {seen:.3} m away");
    assert_eq!(s.unintended_contacts, 0, "{:?}", s.contacts);
    assert!(
        !s.contacts
            .iter()
            .any(|c| c.part == "hand_left" && c.t_start_s < 15.0),
        "the crossing hand was touched: {:?}",
        s.contacts
    );
    let reached: Vec<_> = s
        .contacts
        .iter()
        .filter(|c| c.part == "hand_right" && c.link == "lwr_link_7")
        .collect();
    assert!(
        !reached.is_empty(),
        "the collaborative hand was not reached"
    );
    assert!(s.modes.iter().any(|(_, m)| m == "contact"));
    assert_eq!(
        ended_by.map(|e| e.1),
        Some(phri_ipc::CollabReason::WristPush)
    );
}
