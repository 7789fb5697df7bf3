//! Several depth cameras in the lock-step cell: `deploy/two-cameras.toml`
//! (the paper's camera and its mirror) loads as two cameras, and the cell
//! runs both, their distances fused, through the person's first pass of
//! `coexistence` with no contact.

mod common;

use phri_cell::CellOptions;
use phri_config::Loaded;

#[test]
fn the_mirrored_pair_keeps_the_person_clear_in_lock_step() {
    let file = common::deploy().with_file_name("two-cameras.toml");
    let l = Loaded::load(&file, Some("coexistence"), &[]).unwrap();
    assert_eq!(l.config.cameras.len(), 2);
    assert_eq!(l.config.cameras[1].azimuth_rad, -0.6);
    let mut c = common::cell_of(&l, &CellOptions::default());
    for _ in 0..20_000 {
        c.tick().unwrap();
    }
    let s = c.summary();
    assert_eq!(s.unintended_contacts, 0, "{:?}", s.contacts);
    assert!(s.min_distance_m > 0.03, "closest {} m", s.min_distance_m);
    assert!(s.waypoints >= 2, "waypoints {}", s.waypoints);
    assert!(s.frames > 550, "frames {}", s.frames);
}

/// The mirrored collaboration (the left hand waves and is held out): the
/// paper's one camera never sees the wave; with the mirrored pair a joint
/// either camera sees is seen, the wave starts the collaboration, the robot
/// touches the left hand and the push on the wrist ends it.
#[test]
fn the_mirrored_wave_is_seen_by_two_cameras_and_not_by_one() {
    let one = Loaded::load(&common::deploy(), Some("collaboration-mirrored"), &[]).unwrap();
    let mut c = common::cell_of(&one, &CellOptions::default());
    for _ in 0..8_000 {
        c.tick().unwrap();
    }
    assert!(
        c.summary().gesture_requests.is_empty(),
        "one camera saw the left hand wave"
    );
    let file = common::deploy().with_file_name("two-cameras.toml");
    let two = Loaded::load(&file, Some("collaboration-mirrored"), &[]).unwrap();
    let mut c = common::cell_of(&two, &CellOptions::default());
    for _ in 0..20_000 {
        c.tick().unwrap();
    }
    let s = c.summary();
    let waves: Vec<&str> = s.gesture_requests.iter().map(|g| g.part.as_str()).collect();
    assert!(!waves.is_empty(), "no wave recognised");
    assert!(waves.iter().all(|p| p.contains("left")), "{waves:?}");
    let modes: Vec<&str> = s.modes.iter().map(|m| m.1.as_str()).collect();
    assert!(
        modes.contains(&"approach") && modes.contains(&"contact"),
        "{modes:?}"
    );
    assert!(
        s.contacts
            .iter()
            .any(|k| k.intended && k.part.contains("left")),
        "the left hand was never touched: {:?}",
        s.contacts
    );
    assert_eq!(s.unintended_contacts, 0, "{:?}", s.contacts);
    // the push on the wrist ends it: the task again
    assert_eq!(modes.last(), Some(&"task"), "{modes:?}");
}

/// `safe-collaboration` with the mirrored pair: the robot, no longer held
/// back by the crossing arm hiding the hand it approaches, is struck by the
/// crossing left hand (a person's hand at 0.6 m/s, faster than the
/// repulsion's 0.3 m/s). Its force at the robot must never be taken for
/// the touch of the collaborative right hand: depth sees another part at
/// the robot, so no contact phase begins (before, one did, and its hold
/// pressed the left hand with 170 N), and no contact with it happens in one.
#[test]
fn a_hand_striking_the_arm_is_never_taken_for_the_collaborative_touch() {
    let file = common::deploy().with_file_name("two-cameras.toml");
    let l = Loaded::load(&file, Some("safe-collaboration"), &[]).unwrap();
    let mut c = common::cell_of(&l, &CellOptions::default());
    for _ in 0..9_000 {
        c.tick().unwrap();
    }
    let s = c.summary();
    let strikes: Vec<_> = s.contacts.iter().filter(|k| !k.intended).collect();
    // not vacuous: the left hand does strike the arm here
    assert!(
        strikes.iter().any(|k| k.part == "hand_left"),
        "{:?}",
        s.contacts
    );
    assert!(
        strikes.iter().all(|k| k.mode != "contact"),
        "a strike in a contact phase: {strikes:?}"
    );
    let modes: Vec<&str> = s.modes.iter().map(|m| m.1.as_str()).collect();
    assert!(!modes.contains(&"contact"), "{modes:?}");
}
