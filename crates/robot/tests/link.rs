//! The robot side of the 1 kHz protocol ([`RobotLink`]): fresh and stale
//! commands, the brakes after more than 20 missing, the latency histogram,
//! malformed commands, late cycles and the reports of missed deadlines.

use phri_ipc::{robot_status, TorqueCommand, Zeroed, LATENCY_BINS};
use phri_robot::link::{LATE_CYCLE_GRACE_NS, MAX_MISSED, STATS_EVERY};
use phri_robot::{CycleTiming, LinkError, LinkOutput, RobotLink};

const DOF: usize = 7;
const PERIOD_NS: u64 = 1_000_000;

/// A command `seq` answering state `state_seq`, stamped `stamp_ns`, torque `tau` on every joint.
fn command(seq: u64, state_seq: u64, stamp_ns: u64, tau: f64) -> TorqueCommand {
    let mut c = TorqueCommand::zeroed();
    c.seq = seq;
    c.state_seq = state_seq;
    c.stamp_ns = stamp_ns;
    c.dof = DOF as u32;
    c.tau[..DOF].fill(tau);
    c
}

/// State `seq` published at `seq` ms, the decision 1 ms later, no event stamp.
fn timing(seq: u64) -> CycleTiming {
    CycleTiming {
        state_published_ns: seq * PERIOD_NS,
        command_event_ns: 0,
        now_ns: (seq + 1) * PERIOD_NS,
        behind_schedule_ns: 0,
        standby_asked: false,
    }
}

/// One cycle for state `seq` with command `cmd` (if any).
fn cycle(link: &mut RobotLink, cmd: Option<&TorqueCommand>, seq: u64) -> LinkOutput {
    link.cycle(cmd, seq, &timing(seq))
}

/// A link whose controller has answered state 1 (the loop is established).
fn established() -> RobotLink {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let out = cycle(&mut link, Some(&command(1, 1, PERIOD_NS + 100_000, 2.0)), 1);
    assert!(out.fresh && !out.brake);
    link
}

#[test]
fn the_arm_starts_braked_until_a_controller_answers() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let first = *link.output();
    assert!(first.brake && !first.fresh);
    assert_eq!(first.status, robot_status::BRAKING);
    assert_eq!((first.command_seq, first.missed), (0, MAX_MISSED + 1));
    assert_eq!(first.torque(), &[0.0; DOF]);
    // no controller yet: braked, but no brake event and no missed deadline
    for seq in 1..=50 {
        let out = cycle(&mut link, None, seq);
        assert!(out.brake && !out.brake_engaged);
    }
    assert_eq!(link.stats().brake_events, 0);
    assert_eq!(link.stats().braked_cycles, 50);
    assert_eq!(
        link.stats().missed_deadlines,
        0,
        "no loop yet: nothing to miss"
    );
    assert_eq!(link.stats().cycles, 50);
}

#[test]
fn a_command_answering_the_last_state_is_fresh_and_applied() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let cmd = command(9, 1, PERIOD_NS + 100_000, 3.5);
    let out = cycle(&mut link, Some(&cmd), 1);
    assert!(out.fresh && !out.brake && !out.brake_engaged);
    assert_eq!(out.status, robot_status::COMMAND_FRESH);
    assert_eq!(out.torque(), &[3.5; DOF]);
    assert_eq!((out.command_seq, out.missed), (9, 0));
    assert_eq!(out.tau[DOF..].iter().filter(|t| **t != 0.0).count(), 0);
    assert_eq!(link.stats().missed_deadlines, 0);
    assert_eq!(*link.output(), out);
}

#[test]
fn a_stale_answer_is_reused_but_counts_as_missed() {
    let mut link = established();
    // the controller answers state 1 again while state 2 is out
    let out = cycle(&mut link, Some(&command(2, 1, 2 * PERIOD_NS, -4.0)), 2);
    assert!(!out.fresh && !out.brake);
    assert_eq!(out.status, 0);
    assert_eq!(out.torque(), &[-4.0; DOF], "the newest torque is reused");
    assert_eq!((out.command_seq, out.missed), (2, 1));
    assert_eq!(link.stats().missed_deadlines, 1);
    // nothing at all: the last torque again
    let out = cycle(&mut link, None, 3);
    assert_eq!(out.torque(), &[-4.0; DOF]);
    assert_eq!((out.command_seq, out.missed), (2, 2));
    assert_eq!(link.stats().missed_deadlines, 2);
}

#[test]
fn twenty_misses_keep_going_the_21st_brakes_and_a_fresh_command_releases() {
    let mut link = established();
    let mut seq = 1;
    for k in 1..=MAX_MISSED {
        seq += 1;
        let out = cycle(&mut link, None, seq);
        assert!(!out.brake, "miss {k}: still running");
        assert_eq!(out.missed, k);
        assert_eq!(out.torque(), &[2.0; DOF]);
    }
    seq += 1;
    let out = cycle(&mut link, None, seq);
    assert!(out.brake && out.brake_engaged, "miss 21 brakes");
    assert_eq!(out.status, robot_status::BRAKING);
    assert_eq!(out.missed, MAX_MISSED + 1);
    // braked while misses go on; one brake event
    for _ in 0..9 {
        seq += 1;
        let out = cycle(&mut link, None, seq);
        assert!(out.brake && !out.brake_engaged);
    }
    // a stale command does not release
    seq += 1;
    let out = cycle(&mut link, Some(&command(50, seq - 1, 0, 1.0)), seq);
    assert!(out.brake && !out.fresh);
    // a fresh one does, and reports the run of misses
    seq += 1;
    let out = cycle(
        &mut link,
        Some(&command(51, seq, seq * PERIOD_NS, 1.5)),
        seq,
    );
    assert!(out.fresh && !out.brake);
    assert_eq!(out.status, robot_status::COMMAND_FRESH);
    assert_eq!(out.torque(), &[1.5; DOF]);
    let s = link.stats();
    assert_eq!(s.brake_events, 1);
    assert_eq!(s.braked_cycles, 11, "21st miss, 9 more, the stale answer");
    assert_eq!(s.missed_deadlines, 31);
    assert_eq!(s.cycles, 33);
    let run = out.miss_run.expect("the run of misses ended");
    assert_eq!((run.first, run.last), (1, 31));
    assert_eq!((run.first_cycle, run.last_cycle), (1, 31));
    assert_eq!(
        run.to_string(),
        "missed deadlines 1-31 at cycles 1-31 (first: state published 1000 µs before, cycle woke 0 µs late)"
    );
    // the brakes engage again after another 21
    for k in 1..=MAX_MISSED + 1 {
        seq += 1;
        let out = cycle(&mut link, None, seq);
        assert_eq!(out.brake_engaged, k == MAX_MISSED + 1);
    }
    assert_eq!(link.stats().brake_events, 2);
}

#[test]
fn latency_is_binned_in_microseconds_from_the_state_to_the_receipt() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let published = 5_000_000;
    let at = |link: &mut RobotLink, seq: u64, stamp_ns: u64, event_ns: u64| {
        let t = CycleTiming {
            state_published_ns: published,
            command_event_ns: event_ns,
            now_ns: published + PERIOD_NS,
            behind_schedule_ns: 0,
            standby_asked: false,
        };
        assert!(
            link.cycle(Some(&command(seq, seq, stamp_ns, 0.0)), seq, &t)
                .fresh
        );
    };
    at(&mut link, 1, published + 1_500, 0); // 1.5 µs: bin 1
    at(&mut link, 2, published + 999, 0); // bin 0
    at(&mut link, 3, published + 300, published + 42_700); // the event came later: bin 42
    at(&mut link, 4, published + 80_000, published + 10_000); // the stamp is later: bin 80
    at(&mut link, 5, published + 5_000_000, 0); // 5 ms: the last bin
    at(&mut link, 6, published - 1_000, 0); // stamped before the state: 0
    let s = link.stats();
    let h = &s.latency_hist;
    assert_eq!(
        (h[0], h[1], h[42], h[80], h[LATENCY_BINS - 1]),
        (2, 1, 1, 1, 1)
    );
    assert_eq!(h.iter().map(|x| u64::from(*x)).sum::<u64>(), 6);
    assert_eq!(s.latency_max_ns, 5_000_000);
    // a stale answer is not a latency sample
    let t = CycleTiming {
        state_published_ns: published,
        ..CycleTiming::default()
    };
    link.cycle(Some(&command(7, 5, published, 0.0)), 7, &t);
    assert_eq!(
        link.stats()
            .latency_hist
            .iter()
            .map(|x| u64::from(*x))
            .sum::<u64>(),
        6
    );
}

#[test]
fn malformed_commands_are_never_applied() {
    let mut link = established();
    let mut wrong_dof = command(2, 2, 0, 99.0);
    wrong_dof.dof = 6;
    let mut nan = command(3, 3, 0, 99.0);
    nan.tau[4] = f64::NAN;
    let mut inf = command(4, 4, 0, 99.0);
    inf.tau[0] = f64::INFINITY;
    let mut too_many = command(5, 5, 0, 99.0);
    too_many.dof = 13;
    for (seq, bad) in [(2, wrong_dof), (3, nan), (4, inf), (5, too_many)] {
        assert!(!link.valid(&bad));
        let out = cycle(&mut link, Some(&bad), seq);
        assert!(!out.fresh, "command {seq} is malformed");
        assert_eq!(out.torque(), &[2.0; DOF], "the last valid torque stays");
        assert_eq!(out.command_seq, 1);
    }
    assert_eq!(link.stats().missed_deadlines, 4);
    // malformed commands alone brake the arm like missing ones
    let mut seq = 5;
    let mut braked = false;
    for _ in 0..MAX_MISSED {
        seq += 1;
        braked |= cycle(&mut link, Some(&nan), seq).brake;
    }
    assert!(braked);
}

#[test]
fn a_late_wake_is_an_overrun_slips_the_schedule_and_waits_for_the_answer() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    let deadline = 10 * PERIOD_NS;
    // up to half a period late: on schedule
    let w = link.wake(deadline, deadline + PERIOD_NS / 2);
    assert!(!w.late);
    assert_eq!(w.deadline_ns, deadline);
    assert_eq!(w.behind_schedule_ns(), PERIOD_NS / 2);
    assert_eq!(w.grace_until(None, 9), None, "an on-time cycle decides now");
    assert_eq!(link.stats().overruns, 0);
    // later: an overrun, and the schedule continues from the wake-up
    let woke = deadline + 3 * PERIOD_NS;
    let w = link.wake(deadline, woke);
    assert!(w.late);
    assert_eq!(w.deadline_ns, woke);
    assert_eq!(w.behind_schedule_ns(), 0);
    assert_eq!(link.stats().overruns, 1);
    // the answer gets a grace unless it is already there
    let answer = command(1, 9, 0, 0.0);
    let older = command(1, 8, 0, 0.0);
    assert_eq!(w.grace_until(None, 9), Some(woke + LATE_CYCLE_GRACE_NS));
    assert_eq!(
        w.grace_until(Some(&older), 9),
        Some(woke + LATE_CYCLE_GRACE_NS)
    );
    assert_eq!(w.grace_until(Some(&answer), 9), None);
    assert!(RobotLink::answers(&answer, 9) && !RobotLink::answers(&older, 9));
}

#[test]
fn statistics_are_due_every_100_cycles_and_stamped() {
    let mut link = established();
    let mut due = vec![];
    for seq in 2..=300u64 {
        if cycle(&mut link, Some(&command(seq, seq, 0, 0.0)), seq).publish_stats {
            due.push(link.stats().cycles);
        }
    }
    assert_eq!(due, vec![STATS_EVERY, 2 * STATS_EVERY, 3 * STATS_EVERY]);
    let m = *link.stats_message(123);
    assert_eq!((m.seq, m.stamp_ns, m.cycles), (1, 123, 300));
    assert_eq!(link.stats_message(456).seq, 2);
}

#[test]
fn runs_of_misses_are_placed_in_time_and_an_open_run_is_reported_at_the_end() {
    let mut link = established();
    // state 2 published at 2 ms, the decision 1 ms later, woke 40 µs behind
    let t = CycleTiming {
        behind_schedule_ns: 40_000,
        ..timing(2)
    };
    assert!(link.cycle(None, 2, &t).miss_run.is_none());
    cycle(&mut link, None, 3);
    let run = cycle(&mut link, Some(&command(4, 4, 0, 0.0)), 4)
        .miss_run
        .expect("run ended");
    assert_eq!(
        (run.first, run.last, run.first_cycle, run.last_cycle),
        (1, 2, 1, 2)
    );
    assert_eq!((run.since_published_us, run.behind_schedule_us), (1000, 40));
    assert!(link.finish().is_none(), "no run open");
    cycle(&mut link, None, 5);
    let open = link.finish().expect("the open run");
    assert_eq!((open.first, open.last, open.first_cycle), (3, 3, 4));
    assert!(link.finish().is_none());
}

#[test]
fn state_stamps_advance_one_period_per_state() {
    let link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    assert_eq!(link.state_stamp_ns(7_000, 1), 7_000);
    assert_eq!(link.state_stamp_ns(7_000, 4), 7_000 + 3 * PERIOD_NS);
}

#[test]
fn a_link_needs_joints_and_a_period() {
    assert_eq!(
        RobotLink::new(0, PERIOD_NS).unwrap_err(),
        LinkError::Joints { dof: 0, max: 12 }
    );
    assert!(RobotLink::new(13, PERIOD_NS).is_err());
    assert_eq!(RobotLink::new(7, 0).unwrap_err(), LinkError::Period);
}

/// One cycle for state `seq` with each slot's newest command.
fn cycle2(
    link: &mut RobotLink,
    primary: Option<&TorqueCommand>,
    standby: Option<&TorqueCommand>,
    seq: u64,
) -> LinkOutput {
    link.cycle_slots([primary, standby], seq, &timing(seq))
}

#[test]
fn the_standby_answers_in_the_same_period_the_primary_misses_and_takes_charge() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    // both answer: the primary's torque is applied, the standby's is compared
    for seq in 1..=10 {
        let a = command(seq, seq, 0, 1.0);
        let b = command(seq + 1000, seq, 0, 1.25);
        let out = cycle2(&mut link, Some(&a), Some(&b), seq);
        assert!(out.fresh && out.in_charge == 0 && !out.takeover);
        assert_eq!(out.torque(), &[1.0; DOF]);
        assert_eq!(out.status & robot_status::STANDBY_IN_CHARGE, 0);
    }
    // compared from the second: the first answer released the brakes
    assert_eq!(link.commanders().both_answered, 9);
    assert_eq!(link.commanders().max_answer_diff_nm, 0.25);
    // the primary dies: its last command answers state 10 only
    let dead = command(10, 10, 0, 1.0);
    for seq in 11..=40 {
        let b = command(seq + 1000, seq, 0, 1.5);
        let out = cycle2(&mut link, Some(&dead), Some(&b), seq);
        assert!(out.fresh, "state {seq}: the standby's answer is fresh");
        assert!(!out.brake && out.missed == 0);
        assert_eq!(out.torque(), &[1.5; DOF]);
        assert_eq!(out.in_charge, 1);
        assert_eq!(out.takeover, seq == 11, "one takeover, at the first miss");
        assert_ne!(out.status & robot_status::STANDBY_IN_CHARGE, 0);
    }
    let c = *link.commanders();
    assert_eq!(
        link.stats().missed_deadlines,
        0,
        "a takeover misses nothing"
    );
    assert_eq!((c.takeovers, c.in_charge, c.last_takeover_to), (1, 1, 1));
    assert_eq!(c.last_takeover_state_seq, 11);
    assert_eq!(c.last_takeover_diff_nm, 0.5);
    assert_eq!(c.periods, [10, 30]);
    // the old primary comes back (re-synced) as the standby: the new primary
    // keeps charge while it answers
    for seq in 41..=50 {
        let a = command(seq, seq, 0, 1.0);
        let b = command(seq + 1000, seq, 0, 1.5);
        let out = cycle2(&mut link, Some(&a), Some(&b), seq);
        assert_eq!((out.in_charge, out.torque()), (1, &[1.5; DOF][..]));
    }
    assert_eq!(link.commanders().takeovers, 1);
}

#[test]
fn a_late_primary_is_replaced_and_a_late_standby_changes_nothing() {
    let mut link = established();
    // the standby is late (answers an older state): the primary commands
    let old = command(900, 1, 0, 9.0);
    let out = cycle2(&mut link, Some(&command(2, 2, 0, 2.0)), Some(&old), 2);
    assert_eq!((out.in_charge, out.torque()), (0, &[2.0; DOF][..]));
    assert_eq!(link.commanders().both_answered, 0);
    // the primary is late too: a missed deadline, the primary's newest reused
    let out = cycle2(&mut link, Some(&command(2, 2, 0, 2.0)), Some(&old), 3);
    assert!(!out.fresh && out.in_charge == 0);
    assert_eq!(link.stats().missed_deadlines, 1);
}

#[test]
fn both_controllers_dead_still_brake_and_whichever_answers_first_resumes() {
    let mut link = established();
    for seq in 2..=(2 + MAX_MISSED as u64) {
        let out = cycle2(&mut link, None, None, seq);
        assert_eq!(out.brake, seq == 2 + MAX_MISSED as u64);
    }
    assert_eq!(link.stats().brake_events, 1);
    // the standby's restarted process answers first: it takes charge from
    // the brakes, which is a start, not a takeover
    let seq = 3 + MAX_MISSED as u64;
    let out = cycle2(&mut link, None, Some(&command(5, seq, 0, 3.0)), seq);
    assert!(out.fresh && !out.brake && out.in_charge == 1 && !out.takeover);
    assert_eq!(link.commanders().takeovers, 0);
}

/// The yardstick of a takeover: the largest change of the applied command
/// from one fresh period to the next, takeovers and missed periods left out.
#[test]
fn the_step_of_one_period_is_measured_apart_from_takeovers() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    // a ramp of 0.25 Nm a period from the primary
    for seq in 1..=10 {
        let a = command(seq, seq, 0, 0.25 * seq as f64);
        cycle2(&mut link, Some(&a), None, seq);
    }
    assert_eq!(link.commanders().max_step_nm, 0.25);
    // the standby takes over with a 3 Nm jump: a takeover, not a step
    let b = command(1011, 11, 0, 5.5);
    assert!(cycle2(&mut link, None, Some(&b), 11).takeover);
    assert_eq!(link.commanders().last_takeover_diff_nm, 3.0);
    // a missed period, then a fresh answer 2 Nm away: no period's step either
    cycle2(&mut link, None, None, 12);
    let b = command(1013, 13, 0, 7.5);
    assert!(cycle2(&mut link, None, Some(&b), 13).fresh);
    // the next period's 0.5 Nm is one
    let b = command(1014, 14, 0, 8.0);
    cycle2(&mut link, None, Some(&b), 14);
    assert_eq!(link.commanders().max_step_nm, 0.5);
}

/// The owners of a supervised cell: `control` runs as 100, `control_standby` as 200.
fn supervised_gate() -> phri_robot::CommandGate {
    use phri_ipc::{OwnerTable, ServiceRole};
    let role = |name: &str| ServiceRole {
        name: name.into(),
        binary: "phri-control".into(),
        worker: None,
    };
    let owners = OwnerTable::new(vec![role("control"), role("control_standby")], true);
    owners.set_pid("control", 100);
    owners.set_pid("control_standby", 200);
    phri_robot::CommandGate::new(std::sync::Arc::new(owners))
}

#[test]
fn only_the_slot_s_own_controller_commands_it_and_the_rest_is_counted() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    link.set_gate(supervised_gate());
    let good = command(1, 1, PERIOD_NS, 2.0);
    // the slot's controller: taken
    assert!(link.admit(0, 100, &good));
    assert!(link.admit(1, 200, &good));
    // the other slot's controller, a stranger, an unknown sender: refused
    assert!(!link.admit(0, 200, &good));
    assert!(!link.admit(1, 100, &good));
    assert!(!link.admit(0, 0, &good));
    assert!(!link.admit(0, 4242, &good));
    // the slot's controller, malformed: refused as such
    let mut nan = good;
    nan.tau[3] = f64::NAN;
    assert!(!link.admit(0, 100, &nan));
    let mut wrong = good;
    wrong.dof = 6;
    assert!(!link.admit(1, 200, &wrong));
    let c = *link.commanders();
    assert_eq!(c.refused_stranger, [3, 1]);
    assert_eq!(c.refused_malformed, [1, 1]);
    assert_eq!(c.stranger_pid, 4242);
    // the newest stranger's pid is kept
    assert!(!link.admit(1, 31337, &good));
    assert_eq!(link.commanders().stranger_pid, 31337);
    // the refusals make robot/commanders due (not at every period)
    let out = link.cycle(None, 20, &timing(20));
    assert!(!out.refused, "not before 10 periods");
    for seq in 21..=30 {
        link.cycle(None, seq, &timing(seq));
    }
    let out = link.cycle(None, 31, &timing(31));
    assert!(out.refused);
    link.commanders_message(1);
    let out = link.cycle(None, 32, &timing(32));
    assert!(!out.refused, "published: nothing new refused");
}

#[test]
fn a_controller_restarted_under_a_new_pid_is_taken_from_when_the_supervisor_names_it() {
    use phri_ipc::{OwnerTable, ServiceRole};
    let owners = std::sync::Arc::new(OwnerTable::new(
        vec![ServiceRole {
            name: "control".into(),
            binary: "phri-control".into(),
            worker: None,
        }],
        true,
    ));
    let gate = phri_robot::CommandGate::new(std::sync::Arc::clone(&owners));
    // no health yet: nobody commands (as the controller takes no input)
    assert!(!gate.admits(0, 100));
    owners.set_pid("control", 100);
    assert!(gate.admits(0, 100));
    owners.set_pid("control", 0);
    assert!(!gate.admits(0, 100), "down");
    owners.set_pid("control", 101);
    assert!(gate.admits(0, 101) && !gate.admits(0, 100));
    // no standby configured: nobody on slot 1
    assert!(!gate.admits(1, 101));
}

#[test]
fn without_a_supervisor_every_sender_commands_as_before() {
    let unsupervised = phri_ipc::OwnerTable::new(Vec::new(), false);
    for gate in [
        phri_robot::CommandGate::unchecked(),
        phri_robot::CommandGate::new(std::sync::Arc::new(unsupervised)),
    ] {
        let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
        link.set_gate(gate);
        assert!(link.admit(0, 4242, &command(1, 1, PERIOD_NS, 2.0)));
        assert!(link.admit(1, 0, &command(1, 1, PERIOD_NS, 2.0)));
        assert_eq!(link.commanders().refused_stranger, [0, 0]);
    }
}

/// The resting standby is asked for an answer only when slot 0, in charge
/// of a running loop, has not answered at the deadline; its answer, given
/// after that, is applied (it takes charge) and the period counts as a
/// missed deadline; in charge, it is woken by every state and asked nothing.
#[test]
fn the_standby_is_asked_only_for_the_answer_the_one_in_charge_did_not_give() {
    let mut link = RobotLink::new(DOF, PERIOD_NS).expect("link");
    // braked before the first start: nobody is asked
    assert!(!link.standby_wanted(&[None, None], 1));
    let mut link = {
        let out = link.cycle_slots([Some(&command(1, 1, PERIOD_NS, 2.0)), None], 1, &timing(1));
        assert!(out.fresh && out.in_charge == 0);
        link
    };
    // slot 0 answered in time: the standby rests
    let on_time = [Some(command(2, 2, 2 * PERIOD_NS, 2.5)), None];
    assert!(!link.standby_wanted(&on_time, 2));
    link.cycle_slots([on_time[0].as_ref(), None], 2, &timing(2));
    // slot 0 answered an older state only (late, or gone): asked
    let late = [Some(command(2, 2, 2 * PERIOD_NS, 2.5)), None];
    assert!(link.standby_wanted(&late, 3));
    // a malformed answer is no answer
    let mut bad = command(3, 3, 3 * PERIOD_NS, 2.5);
    bad.tau[0] = f64::NAN;
    assert!(link.standby_wanted(&[Some(bad), None], 3));
    // the standby answers within the grace: applied, in charge, but late
    let standby = command(7, 3, 3 * PERIOD_NS + 1_200_000, 2.6);
    let asked = CycleTiming {
        standby_asked: true,
        ..timing(3)
    };
    let missed_before = link.stats().missed_deadlines;
    let out = link.cycle_slots([late[0].as_ref(), Some(&standby)], 3, &asked);
    assert_eq!(out.torque(), &[2.6; DOF]);
    assert!(!out.fresh && !out.brake && out.takeover && out.in_charge == 1);
    assert_eq!(out.status & robot_status::COMMAND_FRESH, 0);
    assert_ne!(out.status & robot_status::STANDBY_IN_CHARGE, 0);
    assert_eq!(link.stats().missed_deadlines, missed_before + 1);
    assert_eq!(link.commanders().takeovers, 1);
    // in charge now: never asked, whatever slot 0 does; its answers are fresh
    assert!(!link.standby_wanted(&[None, None], 4));
    let next = command(8, 4, 4 * PERIOD_NS + 100_000, 2.7);
    let out = link.cycle_slots([None, Some(&next)], 4, &timing(4));
    assert!(out.fresh && out.in_charge == 1 && !out.takeover);
    assert_eq!(link.stats().missed_deadlines, missed_before + 1);
    // the brakes on (both gone): nobody asked
    for seq in 5..=5 + u64::from(MAX_MISSED) {
        link.cycle_slots([None, None], seq, &timing(seq));
    }
    assert!(link.output().brake);
    assert!(!link.standby_wanted(&[None, None], 30));
}

/// The cycle's wait: none when slot 0 answered in time; the standby asked
/// and 0.5 ms from the deadline when it did not; a late cycle's own grace
/// when that ends later; without a standby, nobody asked.
#[test]
fn the_grace_asks_the_standby_and_waits_the_later_of_the_two() {
    use phri_robot::link::{Wake, STANDBY_GRACE_NS};
    let mut link = established();
    let on_time = Wake {
        woke_ns: 2 * PERIOD_NS,
        deadline_ns: 2 * PERIOD_NS,
        late: false,
    };
    let now = 2 * PERIOD_NS + 10_000;
    let answered = [Some(command(2, 1, PERIOD_NS + 100_000, 2.0)), None];
    let g = link.grace(&on_time, &answered, 1, now);
    assert!(!g.standby_asked && g.until_ns.is_none());
    let missing = [Some(command(1, 0, 100_000, 2.0)), None];
    let g = link.grace(&on_time, &missing, 1, now);
    assert!(g.standby_asked);
    assert_eq!(g.until_ns, Some(now + STANDBY_GRACE_NS));
    // this process woke late: the longer of its grace and the standby's
    let late = Wake {
        woke_ns: 2 * PERIOD_NS + 700_000,
        deadline_ns: 2 * PERIOD_NS + 700_000,
        late: true,
    };
    let g = link.grace(&late, &missing, 1, now);
    assert_eq!(g.until_ns, Some(late.woke_ns + LATE_CYCLE_GRACE_NS));
    // one controller alone: a late cycle's grace only
    link.set_standby(false);
    let g = link.grace(&on_time, &missing, 1, now);
    assert!(!g.standby_asked && g.until_ns.is_none());
    assert!(!link.grace(&late, &missing, 1, now).standby_asked);
}
