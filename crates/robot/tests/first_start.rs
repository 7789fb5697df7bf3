//! The first start of a link with a hot standby: slot 0 (`control`) is in
//! charge at the start however early the standby answers; the arm stays
//! braked until slot 0 answers, and only a slot 0 silent for
//! [`RobotLink::FIRST_START_WAIT_NS`] lets the standby start it.

use phri_ipc::{robot_status, TorqueCommand, Zeroed};
use phri_robot::{CycleTiming, LinkOutput, RobotLink};

const DOF: usize = 7;
const PERIOD_NS: u64 = 1_000_000;

fn command(seq: u64, state_seq: u64, tau: f64) -> TorqueCommand {
    let mut c = TorqueCommand::zeroed();
    c.seq = seq;
    c.state_seq = state_seq;
    c.dof = DOF as u32;
    c.tau[..DOF].fill(tau);
    c
}

fn cycle2(
    link: &mut RobotLink,
    first: Option<&TorqueCommand>,
    standby: Option<&TorqueCommand>,
    seq: u64,
) -> LinkOutput {
    let timing = CycleTiming {
        state_published_ns: seq * PERIOD_NS,
        command_event_ns: 0,
        now_ns: (seq + 1) * PERIOD_NS,
        behind_schedule_ns: 0,
        standby_asked: false,
    };
    link.cycle_slots([first, standby], seq, &timing)
}

/// The standby answers the first 40 states before `control` does (it
/// started sooner): the arm stays braked, nobody takes charge; `control`'s
/// first answer starts the arm with `control` in charge, and the standby's
/// answers are compared, not applied.
#[test]
fn a_standby_that_answers_first_does_not_take_charge_of_the_start() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    for seq in 1..=40 {
        let b = command(seq, seq, 2.0);
        let out = cycle2(&mut link, None, Some(&b), seq);
        assert!(out.brake && !out.fresh, "state {seq}: {out:?}");
        assert_eq!(out.in_charge, 0);
        assert_eq!(out.status & robot_status::STANDBY_IN_CHARGE, 0);
        assert_eq!(out.torque(), &[0.0; DOF]);
    }
    // no missed deadlines before the loop was ever established
    assert_eq!(link.stats().missed_deadlines, 0);
    for seq in 41..=50 {
        let a = command(seq, seq, 1.0);
        let b = command(seq + 1000, seq, 2.0);
        let out = cycle2(&mut link, Some(&a), Some(&b), seq);
        assert!(out.fresh && !out.brake && out.in_charge == 0 && !out.takeover);
        assert_eq!(out.torque(), &[1.0; DOF]);
    }
    assert_eq!(link.commanders().takeovers, 0);
    assert_eq!(link.commanders().periods, [10, 0]);
    // once the loop runs, a missing answer of `control` is the standby's to
    // give in the same period, as ever
    let b = command(2000, 51, 2.0);
    let out = cycle2(&mut link, None, Some(&b), 51);
    assert!(out.fresh && out.takeover && out.in_charge == 1);
    assert_eq!(out.torque(), &[2.0; DOF]);
}

/// `control` never answers: the arm stays braked for the start's wait,
/// then the standby starts it (a start from the brakes, not a takeover).
#[test]
fn a_first_controller_that_never_answers_leaves_the_start_to_the_standby_after_the_wait() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let wait = RobotLink::FIRST_START_WAIT_NS / PERIOD_NS;
    let mut started = None;
    for seq in 1..=wait + 10 {
        let b = command(seq, seq, 2.0);
        let out = cycle2(&mut link, None, Some(&b), seq);
        if out.fresh {
            started.get_or_insert(seq);
            assert!(!out.brake && out.in_charge == 1 && !out.takeover);
        } else {
            assert!(out.brake, "state {seq}");
        }
    }
    let started = started.expect("the standby started the arm");
    assert!(
        (wait..=wait + 2).contains(&started),
        "started at state {started}, waited {wait}"
    );
    assert_eq!(link.commanders().takeovers, 0);
}

/// Nobody answers: braked throughout, whatever the wait.
#[test]
fn nobody_answering_keeps_the_arm_braked() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let wait = RobotLink::FIRST_START_WAIT_NS / PERIOD_NS;
    for seq in 1..=wait + 100 {
        let out = cycle2(&mut link, None, None, seq);
        assert!(out.brake && !out.fresh, "state {seq}");
    }
}
