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
        "camera-9:1:2",
        "cameras:1:2",
        "perception:2:1",
        "dynamics:x:2",
        "perception:1",
        "perception:1:2:3",
        "",
    ] {
        let e = bad.parse::<Outage>().unwrap_err().to_string();
        assert!(
            e.contains("perception|dynamics|control|standby|camera|camera-I:FROM:TO"),
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

/// What a collaboration scenario's lock-step run gave.
struct Collab {
    s: phri_cell::CellSummary,
    /// when and why the (first) collaboration ended
    ended_by: Option<(f64, phri_ipc::CollabReason)>,
    /// the smallest distance perception saw (the masked hand excluded) at 8-9.6 s \[m\]
    seen: f64,
    /// touches, switches and F̂'s error, as the report grades them
    fig: common::CollabFigures,
}

/// Run a collaboration scenario in lock-step.
fn collaborate(scenario: &str, seconds: f64) -> Collab {
    collaborate_with(scenario, seconds, &[])
}

/// [`collaborate`] with configuration overrides.
fn collaborate_with(scenario: &str, seconds: f64, sets: &[&str]) -> Collab {
    let mut c = common::cell(scenario, &CellOptions::default(), sets);
    let mut seen = f64::INFINITY;
    let mut fig = common::CollabFigures::default();
    let (s, ended_by) = run_collab(&mut c, seconds, |c| {
        if (8.0..9.6).contains(&now(c)) && c.status.min_distance > 0.0 {
            seen = seen.min(c.status.min_distance);
        }
        fig.observe(c);
    });
    Collab {
        s,
        ended_by,
        seen,
        fig,
    }
}

/// The collaboration's phases of `s` ran approach → contact → follow →
/// contact again, with no reaction and no protective stop (`what` names
/// the run); the index of the first phase after the second contact.
fn assert_touch_follow_touch(s: &phri_cell::CellSummary, what: &str) -> usize {
    let order: Vec<&str> = s.modes.iter().map(|(_, m)| m.as_str()).collect();
    let first = |m: &str, from: usize| order[from..].iter().position(|x| *x == m).map(|i| i + from);
    let a = first("approach", 0).unwrap_or_else(|| panic!("{what}: no approach: {order:?}"));
    let c1 = first("contact", a).unwrap_or_else(|| panic!("{what}: no first contact: {order:?}"));
    let f = first("follow", c1).unwrap_or_else(|| panic!("{what}: no follow: {order:?}"));
    let c2 = first("contact", f).unwrap_or_else(|| panic!("{what}: no second contact: {order:?}"));
    assert!(
        !order.contains(&"reaction"),
        "{what}: a reaction: {order:?}"
    );
    assert!(
        !order.contains(&"protective_stop"),
        "{what}: a stop: {order:?}"
    );
    c2 + 1
}

/// The wrist push (15.5-16.5 s) ended the collaboration of `s` within 0.7
/// s, and nothing was touched unintended (`what` names the run).
fn assert_the_wrist_push_ends_it(
    s: &phri_cell::CellSummary,
    ended_by: Option<(f64, phri_ipc::CollabReason)>,
    what: &str,
) {
    let (t_end, why) = ended_by.unwrap_or_else(|| panic!("{what}: the collaboration never ended"));
    assert_eq!(why, phri_ipc::CollabReason::WristPush, "{what}");
    assert!(
        (15.5..16.2).contains(&t_end),
        "{what}: ended at {t_end:.2} s"
    );
    assert_eq!(s.unintended_contacts, 0, "{what}: {:?}", s.contacts);
}

/// The contact episodes of the person's `part` in `s`.
fn touches<'s>(s: &'s phri_cell::CellSummary, part: &str) -> Vec<&'s phri_cell::ContactEpisode> {
    s.contacts.iter().filter(|c| c.part == part).collect()
}

#[test]
fn collaboration_wave_approach_contact_follow_and_a_wrist_push_ends_it() {
    // deploy/scenarios/collaboration.toml (paper Sect. VII-C, Figs. 8-9)
    let Collab { s, ended_by, .. } = collaborate("collaboration", 22.0);
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
    let after = assert_touch_follow_touch(&s, "collaboration");
    let order: Vec<&str> = s.modes.iter().map(|(_, m)| m.as_str()).collect();
    let r = order[after..]
        .iter()
        .position(|m| *m == "recover")
        .expect("the end")
        + after;
    assert!(order[r..].contains(&"task"), "the task resumes: {order:?}");
    // the wrist push (15.5-16.5 s) ends it, within 0.5 s here; only
    // intended contacts: the right hand on the end effector, the push
    assert_the_wrist_push_ends_it(&s, ended_by, "collaboration");
    let t_end = ended_by.map_or(f64::INFINITY, |(t, _)| t);
    assert!(
        t_end < 16.0,
        "ended at {t_end:.2} s: the push began at 15.5 s"
    );
    let hand = touches(&s, "hand_right");
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
    // the follow's new touch at about contact_speed (below)
    let follow = hand.iter().filter(|c| c.mode == "follow");
    let peak = follow.map(|c| c.peak_force_n).fold(0.0, f64::max);
    assert!(
        peak > 0.0 && peak <= 50.0,
        "the follow's new touch: {peak:.1} N"
    );
}

/// The person tracker on depth instead of the simulation's truth: the same
/// rules (wave, hand to follow, masking) on its skeletons of the rendered
/// frames. The wave is recognised as the right hand's, the arm approaches
/// and touches that hand with its end effector, follows it when it moves
/// away and touches it again, the wrist push ends it, and nothing else is
/// touched, in both collaboration scenarios.
#[test]
fn collaborations_on_the_depth_trackers_skeletons_reach_the_truths_phases() {
    for scenario in ["collaboration", "safe-collaboration"] {
        let truth = collaborate(scenario, 11.0).s;
        let Collab { s, ended_by, .. } =
            collaborate_with(scenario, 17.0, &["skeleton.source=\"depth\""]);
        eprintln!(
            "{scenario}: depth {:?} {:?} ended by {ended_by:?}; truth {:?}",
            s.gesture_requests, s.modes, truth.gesture_requests
        );
        assert_eq!(
            s.gesture_requests.len(),
            1,
            "{scenario}: {:?}",
            s.gesture_requests
        );
        assert_eq!(s.gesture_requests[0].part, "right_hand", "{scenario}");
        let approach = |s: &phri_cell::CellSummary| {
            s.modes
                .iter()
                .find(|(_, m)| m == "approach")
                .map(|(t, _)| *t)
                .expect("an approach")
        };
        let late = approach(&s) - approach(&truth);
        eprintln!("{scenario}: the approach {late:+.2} s from the truth's");
        assert!(late.abs() <= 0.5, "{scenario}: {late:.2} s");
        // approach → contact → follow → contact again, as from the truth
        assert_touch_follow_touch(&s, scenario);
        assert_the_wrist_push_ends_it(&s, ended_by, scenario);
        let hand = touches(&s, "hand_right");
        assert!(
            hand.iter().all(|c| c.link == "lwr_link_7" && c.intended)
                && hand.iter().any(|c| c.t_start_s < 11.0)
                && hand.iter().any(|c| c.t_start_s > 12.0),
            "{scenario}: {hand:?}"
        );
    }
}

/// Under the barrier filter (`[avoidance] law = "cbf"`) each arm reaches the
/// held-out hand past the crossing one, follows it to a second touch, and
/// the wrist push ends it: while a collaboration has a hand, no point keeps
/// its distance to that hand and the body points keep only `margin_m` to
/// the rest of the person. With d_s for every point the Panda's wrist was
/// held off the hand it held out, and its collaborations ended by the
/// collision flag instead (a reflex).
#[test]
fn under_the_barrier_filter_each_arm_touches_the_hand_twice_and_the_wrist_push_ends_it() {
    for robot in ["lwr4", "fr3", "panda"] {
        let arm = format!("robot.name=\"{robot}\"");
        let sets = [arm.as_str(), "avoidance.law=\"cbf\""];
        let Collab { s, ended_by, .. } = collaborate_with("safe-collaboration", 17.0, &sets);
        eprintln!("{robot}: {:?}, ended by {ended_by:?}", s.modes);
        assert_touch_follow_touch(&s, robot);
        assert_the_wrist_push_ends_it(&s, ended_by, robot);
        // the first touch before the hand moves on (11-12 s; the FR3's
        // reaches it at 11.1-11.2 s under either law), the second after
        let hand = touches(&s, "hand_right");
        assert!(
            hand.iter().all(|c| c.intended)
                && hand.iter().any(|c| c.t_start_s < 11.5)
                && hand
                    .iter()
                    .any(|c| c.t_start_s > 12.0 && c.t_start_s < 15.5),
            "{robot}: {hand:?}"
        );
    }
}

/// The robot following a hand that moved away touches it again at about
/// `contact_speed`: near the hand its reference no longer leads the end
/// effector by up to 5 cm, which pulled it in at the feedback's cap on top
/// (56-71 N on the LWR's new touch). Two more script offsets than the
/// collaboration test's (which checks its own), two 7-DOF arms.
#[test]
fn following_a_moved_hand_touches_it_again_gently() {
    for (robot, offset) in [("lwr4", 0.4), ("fr3", -0.2)] {
        let opts = phri_cell::CellOptions {
            human_time_offset_s: offset,
            ..phri_cell::CellOptions::default()
        };
        let set = format!("robot.name=\"{robot}\"");
        let s = common::run("collaboration", 16.0, &opts, &[set.as_str()]);
        let follow: Vec<_> = s
            .contacts
            .iter()
            .filter(|c| c.part == "hand_right" && c.mode == "follow")
            .collect();
        assert!(
            !follow.is_empty(),
            "{robot} {offset}: no new touch: {:?}",
            s.contacts
        );
        let peak = follow.iter().map(|c| c.peak_force_n).fold(0.0, f64::max);
        eprintln!("{robot}, offset {offset}: the follow's new touch peaks at {peak:.1} N");
        // the hold is 25 N; the first touch of the approach peaks at 20-36 N
        assert!(peak <= 50.0, "{robot} {offset}: {peak:.1} N");
    }
}

#[test]
fn safe_collaboration_avoids_the_crossing_hand_and_still_reaches_the_other() {
    // deploy/scenarios/safe-collaboration.toml (paper Sect. VII-D, Figs. 10-11):
    // the left hand crosses the approach at 7.3-8.8 s
    let Collab {
        s,
        ended_by,
        seen,
        fig,
    } = collaborate("safe-collaboration", 22.0);
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
    // the follow touches the moved hand again, as the script does, and F̂
    // keeps within the report's grade (p50 <= 10 %, p95 <= 25 %); the
    // follow's lead shrunk by depth's error at the touch had held the arm
    // 5-10 cm off the hand (one touch, p95 29 %)
    let (p50, p95) = (fig.error_pct(0.5), fig.error_pct(0.95));
    eprintln!(
        "touches {}, switches {}, F̂ error p50 {p50:.1} % p95 {p95:.1} % ({} samples)",
        fig.touches,
        fig.switches,
        fig.errors.len()
    );
    assert_eq!(fig.touches, 2, "{:?}", s.contacts);
    assert!(
        p50 <= 10.0 && p95 <= 25.0,
        "F̂ error p50 {p50:.1} %, p95 {p95:.1} %"
    );
    assert_eq!(
        ended_by.map(|e| e.1),
        Some(phri_ipc::CollabReason::WristPush)
    );
}

/// The robot's links (the collision capsules of the LWR model).
const LINKS: [&str; 7] = [
    "lwr_link_1",
    "lwr_link_2",
    "lwr_link_3",
    "lwr_link_4",
    "lwr_link_5",
    "lwr_link_6",
    "lwr_link_7",
];
/// The robot's elbow: links 3 and 4 (upper arm and elbow).
const ELBOW: [&str; 2] = ["lwr_link_3", "lwr_link_4"];
/// The person's left arm, the non-collaborative part that crosses.
const LEFT_ARM: [&str; 3] = ["hand_left", "forearm_left", "upper_arm_left"];

/// Robot time of the cell \[s\].
fn now(c: &phri_cell::Cell) -> f64 {
    c.time_ns() as f64 * 1e-9
}

/// The right hand touches the end effector's link now (simulator truth).
fn hand_on_link_7(c: &phri_cell::Cell) -> bool {
    c.sim
        .truth()
        .contacts
        .iter()
        .any(|k| k.part == phri_ipc::BodyPart::HandRight && k.link(c.sim.model()) == "lwr_link_7")
}

/// Step `c` for `seconds` in lock-step, calling `each` after every period:
/// the summary and when and why the (first) collaboration ended.
fn run_collab(
    c: &mut phri_cell::Cell,
    seconds: f64,
    mut each: impl FnMut(&phri_cell::Cell),
) -> (
    phri_cell::CellSummary,
    Option<(f64, phri_ipc::CollabReason)>,
) {
    let mut ended_by = None;
    for _ in 0..(seconds * 1000.0).round() as usize {
        c.tick().unwrap();
        each(c);
        let m = c
            .controller
            .collaboration()
            .expect("collaboration enabled")
            .machine();
        if ended_by.is_none() && m.reason() != phri_ipc::CollabReason::None && !m.active() {
            ended_by = Some((now(c), m.reason()));
        }
    }
    (c.summary(), ended_by)
}

/// What a run of `safe-collaboration-elbow` measured.
struct ElbowRun {
    s: phri_cell::CellSummary,
    ended_by: Option<(f64, phri_ipc::CollabReason)>,
    /// closest true surface distance left arm ↔ links 3-4 while the arm
    /// crosses and stays (7.6-11.0 s) \[m\], and when \[s\]
    closest: (f64, f64),
    /// its mean while the arm is held in front of the elbow and the end
    /// effector reaches the right hand (8.4-10.6 s) \[m\]
    mean_held: f64,
    /// the first touch of the right hand on link 7 \[s\] and the left arm's
    /// distance to links 3-4 then \[m\]
    touch: Option<(f64, f64)>,
    /// per period, 8.2-10.6 s: the distance perception reported (the
    /// masked hand excluded) less the true distance left arm ↔ robot \[m\]
    seen_less_true: Vec<f64>,
    /// smallest SNS task scale, 8.2-10.6 s
    task_scale: f64,
}

fn elbow_run(l: &phri_config::Loaded) -> ElbowRun {
    let mut c = common::cell_of(l, &CellOptions::default());
    let (mut closest, mut sum, mut n) = ((f64::INFINITY, 0.0), 0.0, 0usize);
    let mut touch = None;
    let (mut seen_less_true, mut task_scale) = (Vec::new(), 1.0f64);
    let (s, ended_by) = run_collab(&mut c, 23.0, |c| {
        let t = now(c);
        if !(7.6..11.0).contains(&t) {
            return;
        }
        let d = common::parts_to_links(c, &LEFT_ARM, &ELBOW);
        if d < closest.0 {
            closest = (d, t);
        }
        if (8.4..10.6).contains(&t) {
            sum += d;
            n += 1;
        }
        if touch.is_none() && hand_on_link_7(c) {
            touch = Some((t, d));
        }
        if (8.2..10.6).contains(&t) {
            if c.status.min_distance > 0.0 {
                let left = common::parts_to_links(c, &LEFT_ARM, &LINKS);
                seen_less_true.push(c.status.min_distance - left);
            }
            task_scale = task_scale.min(c.status.task_scale);
        }
    });
    ElbowRun {
        s,
        ended_by,
        closest,
        mean_held: sum / n.max(1) as f64,
        touch,
        seen_less_true,
        task_scale,
    }
}

#[test]
fn safe_collaboration_elbow_keeps_the_crossing_arm_off_the_elbow_and_reaches_the_hand() {
    // deploy/scenarios/safe-collaboration-elbow.toml (paper Fig. 12): the
    // left arm crosses in front of the elbow (7.6-8.2 s) and stays (until
    // 10.0 s) while the end effector reaches the right hand
    let l = common::loaded("safe-collaboration-elbow", &[]);
    let r = elbow_run(&l);
    // the same run with the elbow's control points removed (links 3-4, and
    // the forearm's within 12 cm of the elbow: link 5's origin is the elbow
    // joint): no velocity bounds at the elbow, the rest unchanged
    let mut bare = l.clone();
    bare.config.repulsion.points.retain(|p| {
        let near_elbow =
            ELBOW.contains(&p.link.as_str()) || (p.link == "lwr_link_5" && p.xyz[2] <= 0.12);
        !near_elbow
    });
    assert!(bare.config.repulsion.points.len() < l.config.repulsion.points.len());
    let b = elbow_run(&bare);
    let seen_less_true = median(&r.seen_less_true);
    eprintln!(
        "left arm ↔ elbow: closest {:.3} m at {:.2} s, {:.3} m mean while held (without the elbow's points {:.3} m, {:.3} m); \
         right hand reached {:?} (without {:?}); seen − true {:.3} m (median); task scale ≥ {:.2} (without {:.2}); ended by {:?}",
        r.closest.0, r.closest.1, r.mean_held, b.closest.0, b.mean_held, r.touch, b.touch, seen_less_true,
        r.task_scale, b.task_scale, r.ended_by
    );
    eprintln!("modes: {:?}", r.s.modes);
    // untouched: the crossing arm never touched the robot, nothing unintended
    assert_eq!(r.s.unintended_contacts, 0, "{:?}", r.s.contacts);
    assert!(
        !r.s.contacts
            .iter()
            .any(|k| LEFT_ARM.contains(&k.part.as_str()) && k.t_start_s < 16.0),
        "the crossing arm touched the robot: {:?}",
        r.s.contacts
    );
    // not vacuous: the arm came within a few centimetres of the elbow, and
    // perception saw it there (the right hand is masked, the left arm is not)
    assert!(
        r.closest.0 > 0.0 && r.closest.0 < 0.10,
        "the left arm stayed {:.3} m from the elbow",
        r.closest.0
    );
    assert!(r.seen_less_true.len() > 1000);
    assert!(
        seen_less_true.abs() < 0.03,
        "perception saw the crossing arm {seen_less_true:.3} m off its distance (median)"
    );
    // and the elbow's bounds did work: without them the elbow stays nearer
    // to the arm held in front of it
    assert!(
        r.mean_held > b.mean_held + 0.004,
        "the elbow's bounds kept it {:.3} m from the arm, without them {:.3} m",
        r.mean_held,
        b.mean_held
    );
    // the right hand is reached on the end effector while the arm is still
    // in front of the elbow
    let (t_touch, d_touch) = r.touch.expect("the right hand was not reached");
    assert!(
        t_touch < 10.6 && d_touch < 0.15,
        "reached at {t_touch:.2} s with the left arm {d_touch:.3} m from the elbow"
    );
    assert!(r
        .s
        .contacts
        .iter()
        .any(|k| k.part == "hand_right" && k.link == "lwr_link_7" && k.intended));
    // the wrist push (16.5-17.5 s) ends it and the task resumes
    let (t_end, why) = r.ended_by.expect("the collaboration ended");
    assert_eq!(why, phri_ipc::CollabReason::WristPush);
    assert!(
        (16.5..17.2).contains(&t_end),
        "ended at {t_end:.2} s: the push began at 16.5 s"
    );
    let order: Vec<&str> = r.s.modes.iter().map(|(_, m)| m.as_str()).collect();
    let end =
        r.s.modes
            .iter()
            .position(|(t, m)| m == "recover" && *t >= t_end - 0.01)
            .expect("recovery after the end");
    assert!(
        order[end..].contains(&"task"),
        "the task resumes: {order:?}"
    );
    assert!(!order.contains(&"reaction"), "no reaction: {order:?}");
    assert!(!order.contains(&"protective_stop"), "no stop: {order:?}");
}

/// `[collaboration]` overrides that leave the mask out: a 1 mm sphere, no
/// forearm capsule (`mask_radius_m` must be > 0; the hand's surface is 4.5 cm
/// from its joint, so no pixel lies within 1 mm of it). The hand is still
/// refined from the depth pixels around it (`refine_radius_m`).
const NO_MASK: [&str; 2] = [
    "collaboration.mask_radius_m=0.001",
    "collaboration.mask_forearm_m=0",
];

/// What a 12 s run of `collaboration` (wave, approach, contact until the
/// hand moves at 11 s) showed of the mask.
struct MaskRun {
    s: phri_cell::CellSummary,
    ended_by: Option<(f64, phri_ipc::CollabReason)>,
    /// the most pixels masked in a frame
    masked: u32,
    /// the first touch of the right hand on link 7 \[s\]
    touch: Option<f64>,
    /// per period from 8.0 s while the hand is within 25 cm of the robot:
    /// (true distance hand ↔ robot, distance perception reported) \[m\]
    near: Vec<(f64, f64)>,
}

fn mask_run(sets: &[&str]) -> MaskRun {
    let mut c = common::cell("collaboration", &CellOptions::default(), sets);
    let (mut masked, mut touch, mut near) = (0u32, None, Vec::new());
    let (s, ended_by) = run_collab(&mut c, 12.0, |c| {
        let t = now(c);
        if let Some(h) = c.hand.as_ref() {
            masked = masked.max(h.masked_pixels);
        }
        if touch.is_none() && hand_on_link_7(c) {
            touch = Some(t);
        }
        if t >= 8.0 {
            let d = common::parts_to_links(c, &["hand_right"], &LINKS);
            if d < 0.25 && c.status.min_distance > 0.0 {
                near.push((d, c.status.min_distance));
            }
        }
    });
    MaskRun {
        s,
        ended_by,
        masked,
        touch,
        near,
    }
}

#[test]
fn masking_hides_the_collaborative_hand_and_only_it() {
    // with the mask (the default): the hand's pixels are removed while the
    // collaboration is on, the end effector reaches the hand, and perception
    // does not see the hand it touches
    let MaskRun {
        s,
        masked,
        touch,
        near,
        ..
    } = mask_run(&[]);
    let touching: Vec<f64> = near
        .iter()
        .filter(|(d, _)| *d <= 0.0)
        .map(|(_, seen)| *seen)
        .collect();
    let seen_touching = median(&touching);
    // without it: nothing is masked and perception sees the hand
    let u = mask_run(&NO_MASK);
    let worst = u
        .near
        .iter()
        .map(|(d, seen)| seen - d)
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "mask: {masked} px, touched {touch:?}, seen {seen_touching:.3} m (median) while touching; \
         no mask: {} px, touched {:?}, seen at most {worst:.3} m beyond the hand within 0.25 m, ended by {:?}; modes {:?}",
        u.masked, u.touch, u.ended_by, u.s.modes
    );
    assert!(masked > 200, "masked {masked} px");
    let t = touch.expect("with the mask the end effector reaches the hand");
    assert!(t < 10.0, "reached at {t:.2} s");
    assert!(s
        .contacts
        .iter()
        .any(|k| k.part == "hand_right" && k.link == "lwr_link_7" && k.intended));
    assert!(touching.len() > 500, "{} periods touching", touching.len());
    assert!(
        seen_touching > 0.04,
        "the touching hand was seen at {seen_touching:.3} m"
    );
    // a 1 mm sphere around the noisy tracked hand: at most a stray pixel
    assert!(u.masked <= 5, "{} px masked without the mask", u.masked);
    assert!(u.near.len() > 200, "{} periods near", u.near.len());
    assert!(
        worst < 0.03,
        "without the mask perception saw the hand up to {worst:.3} m farther than it was"
    );

    // the other hand is no collaborative part: in `safe-collaboration` the
    // left hand crosses the approach (7.0-9.6 s) while the right hand is
    // masked, and perception still sees it where it is
    // (7.9-8.6 s: the left hand 9-11 cm from the arm, nearer than any other
    // unmasked part; a frame the tracker drops leaves the right hand unmasked,
    // hence the median)
    let mut c = common::cell("safe-collaboration", &CellOptions::default(), &[]);
    let (mut off, mut left, mut active) = (Vec::new(), f64::INFINITY, true);
    run_collab(&mut c, 8.6, |c| {
        if now(c) >= 7.9 {
            active &= c.controller.collaboration().unwrap().machine().active();
            let d = common::parts_to_links(c, &LEFT_ARM, &LINKS);
            left = left.min(d);
            if c.status.min_distance > 0.0 {
                off.push(c.status.min_distance - d);
            }
        }
    });
    let off = median(&off);
    eprintln!("safe-collaboration: the crossing left hand came to {left:.3} m and was seen {off:.3} m off (median)");
    assert!(active, "the mask was on (collaborating) throughout");
    assert!(left < 0.15, "the left hand stayed {left:.3} m away");
    assert!(
        off.abs() < 0.04,
        "the left hand was seen {off:.3} m off its distance (median)"
    );
}

/// The median of `v` (NaN when empty).
fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

#[test]

fn without_the_mask_the_end_effector_stops_short_of_the_hand() {
    // issue 11, item 9: without the mask the collaborative hand is an
    // obstacle like any other: the end effector stops at about the
    // repulsion distance from it and never touches it
    let u = mask_run(&NO_MASK);
    let closest = u.near.iter().map(|(d, _)| *d).fold(f64::INFINITY, f64::min);
    eprintln!(
        "no mask: {} px masked, touched {:?}, closest {closest:.3} m, ended by {:?}, contacts {:?}",
        u.masked, u.touch, u.ended_by, u.s.contacts
    );
    assert!(u.masked <= 5, "{} px masked", u.masked);
    assert_eq!(u.touch, None, "the end effector touched the unmasked hand");
    // where the repulsion (0.29 m/s at 10 cm, 0.25 m/s at 15 cm,
    // `[repulsion.params]`) holds the approach (≤ 0.05 m/s there, plus
    // ≤ 0.1 m/s of position feedback)
    assert!(
        (0.03..0.25).contains(&closest),
        "the end effector stopped {closest:.3} m from the hand"
    );
}

/// What a push on the elbow during the contact of `collaboration` did.
struct ElbowPush {
    s: phri_cell::CellSummary,
    /// the collaboration's phase when the push began
    at_push: Option<phri_ipc::CollabPhase>,
    /// the controller entered `reaction` \[s\]
    reacted: Option<f64>,
    ended_by: Option<(f64, phri_ipc::CollabReason)>,
}

/// `collaboration`, and while the right hand holds the end effector
/// (contact from about 9 s) the left hand pushes link 4 (the elbow), 8 cm
/// from the elbow joint along the link, with `force_n` from 10.0 to 10.6 s,
/// unintended. (Nearer link 4's far end, or with the point off the axis, the
/// pushing arm, which the simulator draws at the reach limit of the person
/// 0.95 m away, also grazes the wrist: another collision.)
fn push_the_elbow(force_n: f64) -> ElbowPush {
    let base = [0.95, 0.0, std::f64::consts::PI];
    let held = Some([0.55, 0.1, 0.35]);
    let l = common::rescript("collaboration", &[], |keyframes| {
        for k in [
            phri_config::Keyframe {
                right_hand: held,
                push: Some(phri_config::Push {
                    link: "lwr_link_4".into(),
                    point: [0.0, -0.08, 0.0],
                    force_n,
                    hand: phri_config::Hand::Left,
                    intended: false,
                }),
                ..common::keyframe(10.0, base)
            },
            phri_config::Keyframe {
                right_hand: held,
                ..common::keyframe(10.6, base)
            },
        ] {
            // between the held-out hand's keyframes at 7 and 11 s
            let at = keyframes.partition_point(|x| x.t < k.t);
            assert!(keyframes[at - 1].right_hand == held && keyframes[at].right_hand == held);
            keyframes.insert(at, k);
        }
    });
    let mut c = common::cell_of(&l, &CellOptions::default());
    let (mut at_push, mut reacted) = (None, None);
    let (s, ended_by) = run_collab(&mut c, 12.0, |c| {
        let t = now(c);
        if at_push.is_none() && t >= 10.0 {
            at_push = Some(c.controller.collaboration().unwrap().phase());
        }
        if reacted.is_none() && t >= 10.0 && c.mode() == phri_ipc::ControlMode::Reaction {
            reacted = Some(t);
        }
    });
    eprintln!(
        "{force_n} N on the elbow: phase when it began {at_push:?}, reaction at {reacted:?}, ended by {ended_by:?}; modes {:?}",
        s.modes
    );
    ElbowPush {
        s,
        at_push,
        reacted,
        ended_by,
    }
}

/// The push on the elbow was detected as a collision: the controller
/// reacted and the collaboration ended as a collision, not as a wrist push,
/// within 0.3 s of the push's onset (ramped over 0.2 s); the push was the
/// only unintended contact.
fn assert_elbow_push_detected(p: &ElbowPush) {
    assert_eq!(
        p.at_push,
        Some(phri_ipc::CollabPhase::Contact),
        "the push began during the contact"
    );
    let (t_end, why) = p.ended_by.expect("the collaboration ended");
    assert_eq!(
        why,
        phri_ipc::CollabReason::Collision,
        "ended at {t_end:.3} s"
    );
    assert!(
        (10.0..10.3).contains(&t_end),
        "ended at {t_end:.3} s: the push began at 10.0 s"
    );
    let t_react = p.reacted.expect("the controller reacted");
    assert!(
        (10.0..10.3).contains(&t_react),
        "reaction at {t_react:.3} s"
    );
    assert_eq!(p.s.unintended_contacts, 1, "{:?}", p.s.contacts);
    assert!(p
        .s
        .contacts
        .iter()
        .any(|k| k.part == "hand_left" && k.link == "lwr_link_4" && !k.intended));
}

/// The push on the elbow the residual tells from a force on the held end
/// effector [N], at the arm's posture in the contact: at 60 N the largest
/// unexplained joint torque was 3.01 Nm against joint 6's 3 Nm threshold
/// with eq. 20 alone (phri before issue 14), 2.49 Nm with the null-space
/// posture of issue 14 (another posture at the contact's start): both
/// scale with the force.
const PUSH_N: f64 = 80.0;

#[test]
fn a_push_on_the_elbow_during_contact_is_a_collision_not_a_wrist_push() {
    // the residual the intended contact does not explain crosses the
    // collision thresholds: the controller reacts and the collaboration ends
    // as a collision (the push on the wrist itself ends it as a wrist push:
    // the collaboration test)
    assert_elbow_push_detected(&push_the_elbow(PUSH_N));
}

#[test]
fn lighter_pushes_on_the_elbow_during_contact_are_never_a_wrist_push() {
    // below ~60 N a push on the elbow during the contact is explained, as far
    // as the collision thresholds see, by the force at the held end effector
    // (F̂ absorbs it): no reaction. It must not end the collaboration as a
    // wrist push either: a force at the wrist centre leaves the elbow's turn
    // about the shoulder-wrist line unexplained (5-9 % of ‖r‖ at 40 N, above
    // `wrist_fit`), which a push on the wrist does not (0.3-1 %)
    for force_n in [40.0, 50.0] {
        let p = push_the_elbow(force_n);
        assert_eq!(p.at_push, Some(phri_ipc::CollabPhase::Contact));
        assert!(
            !p.ended_by
                .is_some_and(|(_, why)| why == phri_ipc::CollabReason::WristPush),
            "{force_n} N on the elbow taken for a wrist push: {:?}",
            p.ended_by
        );
        assert!(
            p.ended_by.is_none()
                || p.ended_by
                    .is_some_and(|(_, why)| why == phri_ipc::CollabReason::Collision),
            "{force_n} N: {:?}",
            p.ended_by
        );
    }
}
