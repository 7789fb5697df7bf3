//! The hot standby's rule, as a pure function of what a controller sees:
//! two controllers answer every state, each on a command channel of its own
//! (slot 0 `robot/command`, slot 1 `robot/command/standby`); the robot
//! applies the answer of the one in charge, or the other's in the same
//! period when that one is missing, and says who is in charge in the state
//! (`robot_status::STANDBY_IN_CHARGE`).
//!
//! - The controller in charge publishes its status, collaboration and SSM
//!   messages and its behaviour state ([`phri_ipc::ControlBehaviour`]) after
//!   every step.
//! - The other adopts that behaviour before its next step (the one the
//!   controller in charge left after the previous state), and answers too.
//! - A controller not in charge that has not adopted a behaviour of the last
//!   [`SYNC_STATES`] states (it was stopped, starved, or has just started)
//!   does not command: it would answer from a past of its own. While the
//!   robot is braked nobody is in charge, and anyone may answer (a start,
//!   from the sync mode).

use phri_config::ControlConfig;
use phri_ipc::{residual_flags, robot_status, ControlBehaviour, JointState, Residual, Zeroed};

use crate::{Controller, SnapshotError};

/// A behaviour adopted this many states back at most keeps a standby in sync.
pub const SYNC_STATES: u64 = 2;

/// A standby that rests ([`Standby::may_rest`]) still steps in full one
/// state in this many, so that the robot keeps comparing the two answers
/// (the report's `both_answered` and `max_answer_diff_nm`).
pub const FULL_STEP_EVERY: u64 = 64;

/// Which command slot a controller answers on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// `robot/command`: in charge when the robot starts
    First = 0,
    /// `robot/command/standby`
    Standby = 1,
}

/// What a controller does with one state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Duty {
    /// in charge: publish status, collaboration, SSM and behaviour
    pub in_charge: bool,
    /// publish the command answering this state
    pub command: bool,
}

/// One controller's place beside the other.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Standby {
    slot: Slot,
    /// the state whose behaviour was adopted last (0: none)
    adopted: u64,
}

impl Standby {
    /// A controller answering on `slot`, no behaviour adopted yet.
    pub fn new(slot: Slot) -> Standby {
        Standby { slot, adopted: 0 }
    }

    /// The command slot it answers on.
    pub fn slot(&self) -> Slot {
        self.slot
    }

    /// Is this controller in charge by `state`?
    pub fn in_charge(&self, state: &JointState) -> bool {
        let standby_in_charge = state.status & robot_status::STANDBY_IN_CHARGE != 0;
        standby_in_charge == (self.slot == Slot::Standby)
    }

    /// Before the step of `state`: adopt a peer's behaviour left by the step
    /// of state `behaviour_state_seq`? Only the one of the state before,
    /// and only when not in charge.
    pub fn should_adopt(&self, state: &JointState, behaviour_state_seq: u64) -> bool {
        !self.in_charge(state) && behaviour_state_seq + 1 == state.seq
    }

    /// The peer's behaviour of the state before `state` was adopted.
    pub fn adopted(&mut self, state: &JointState) {
        self.adopted = state.seq;
    }

    /// What to do with `state` after the step; `inputs_fresh`: this
    /// controller's own safety inputs were fresh in it ([`inputs_fresh`]): a
    /// controller just started, without perception results yet, would
    /// answer otherwise than the one in charge.
    pub fn duty(&self, state: &JointState, inputs_fresh: bool) -> Duty {
        let in_charge = self.in_charge(state);
        let braked = state.status & robot_status::BRAKING != 0;
        // (a restarted robot numbers its states from 1 again: a behaviour
        // adopted before is not of this robot's states)
        let in_sync =
            self.adopted > 0 && self.adopted <= state.seq && state.seq - self.adopted < SYNC_STATES;
        Duty {
            in_charge,
            command: in_charge || braked || (in_sync && inputs_fresh),
        }
    }
}

impl Standby {
    /// May this controller rest through `state` (`[control] standby_rests`):
    /// take its inputs, but neither adopt, step nor answer? Only when it is
    /// not in charge, the robot is not braked, the one in charge has
    /// already answered this very state (`peer_answered`: its behaviour
    /// after `state` is here) and the state is not one of every
    /// [`FULL_STEP_EVERY`]. Its answer would not be applied anyway; when the
    /// one in charge has not answered by the time it looks, it steps as
    /// always, adopting the behaviour of the state before, and takes over in
    /// the same period if that answer never comes.
    pub fn may_rest(&self, state: &JointState, peer_answered: bool) -> bool {
        let braked = state.status & robot_status::BRAKING != 0;
        peer_answered
            && !braked
            && !self.in_charge(state)
            && !state.seq.is_multiple_of(FULL_STEP_EVERY)
    }

    /// Before the step of `state`: adopt `behaviour` (the newest the peer
    /// left) when it is the one of the state before and this controller is
    /// not in charge. `Ok(true)`: adopted; a refused one changes nothing.
    pub fn adopt(
        &mut self,
        controller: &mut Controller,
        state: &JointState,
        behaviour: Option<&ControlBehaviour>,
    ) -> Result<bool, SnapshotError> {
        let Some(b) =
            behaviour.filter(|b| b.state_seq > 0 && self.should_adopt(state, b.state_seq))
        else {
            return Ok(false);
        };
        controller.adopt_behaviour(b.snapshot())?;
        self.adopted(state);
        Ok(true)
    }
}

/// `controller`'s behaviour after its step of `state` into `msg`, numbered
/// `seq` (the controller's message numbering) and stamped `stamp_ns`.
pub fn save_behaviour(
    controller: &Controller,
    state: &JointState,
    seq: u64,
    stamp_ns: u64,
    msg: &mut ControlBehaviour,
) -> Result<(), SnapshotError> {
    let len = controller.save_behaviour(&mut msg.bytes)?;
    msg.seq = seq;
    msg.stamp_ns = stamp_ns;
    msg.state_seq = state.seq;
    msg.state_stamp_ns = state.stamp_ns;
    msg.len = len as u32;
    Ok(())
}

/// The torque loop's priority follows the role: the controller in charge
/// runs at the higher of the two controllers' `rt_priority`, the other at
/// the lower, so the answer the robot applies never waits for the other's
/// (a restarted controller, faulting in its first periods, runs below the
/// one in charge), and a standby that took charge keeps it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RolePriority {
    /// SCHED_FIFO priority in charge
    pub in_charge: i32,
    /// SCHED_FIFO priority while not in charge (and before the first state)
    pub standby: i32,
    /// the role of the priority set last (`None`: none set yet)
    role: Option<bool>,
}

impl RolePriority {
    /// From the two controllers' `[services.*] rt_priority`: `None` unless
    /// both run real-time.
    pub fn new(first: i32, standby: i32) -> Option<RolePriority> {
        (first > 0 && standby > 0).then(|| RolePriority {
            in_charge: first.max(standby),
            standby: first.min(standby),
            role: None,
        })
    }

    /// From `config`'s `control` and `control_standby` services.
    pub fn for_cell(config: &phri_config::Config) -> Option<RolePriority> {
        let prio = |s: &str| config.services.get(s).map_or(0, |s| s.rt_priority);
        RolePriority::new(prio("control"), prio("control_standby"))
    }

    /// The priority to move to when the role is now `in_charge` (`None`:
    /// unchanged since the last one set).
    pub fn change(&mut self, in_charge: bool) -> Option<i32> {
        if self.role == Some(in_charge) {
            return None;
        }
        self.role = Some(in_charge);
        Some(match in_charge {
            true => self.in_charge,
            false => self.standby,
        })
    }
}

/// Were `controller`'s safety inputs fresh in its last step: the residual
/// within `[control] residual_max_age_ms` and, with avoidance, perception
/// within `perception_max_age_ms`?
pub fn inputs_fresh(controller: &Controller, cfg: &ControlConfig) -> bool {
    let residual = controller.residual_age_ns() as f64 <= cfg.residual_max_age_ms * 1e6;
    let perception =
        !cfg.avoidance || controller.perception_age_ns() as f64 <= cfg.perception_max_age_ms * 1e6;
    residual && perception
}

/// How far `dynamics/residual` may fall behind the state a controller
/// answers before the one in charge calls the standby's residual
/// (`dynamics/residual/call`): two periods of the robot's clock \[ns\]
/// (it is one behind when the residual service runs after the controller).
pub const RESIDUAL_CALL_BEHIND_NS: u64 = 2_000_000;

/// Does the controller in charge call the standby's residual service for
/// `state`? When the first's newest residual (`first`) is missing, not
/// valid (restarting, warming up) or [`RESIDUAL_CALL_BEHIND_NS`] behind.
pub fn residual_wanted(first: Option<&Residual>, state: &JointState) -> bool {
    first.is_none_or(|r| {
        r.flags & residual_flags::VALID == 0
            || r.state_stamp_ns.saturating_add(RESIDUAL_CALL_BEHIND_NS) < state.stamp_ns
    })
}

/// The residual to act on of the two dynamics services' newest (the first's
/// `dynamics/residual`, the standby's `dynamics/residual/standby`): a valid
/// one before one still warming up, then the one of the newer state, then
/// the first's. Either may be missing (killed, restarting).
pub fn fresher_residual<'a>(
    first: Option<&'a Residual>,
    standby: Option<&'a Residual>,
) -> Option<&'a Residual> {
    // the robot's clock, not the state's number: a restarted robot numbers
    // its states from 1 again, its clock goes on
    let key = |r: &Residual| (r.flags & residual_flags::VALID != 0, r.state_stamp_ns);
    match (first, standby) {
        (Some(a), Some(b)) if key(b) > key(a) => Some(b),
        (Some(a), _) => Some(a),
        (None, b) => b,
    }
}

/// The peer's newest behaviour states, kept until the step they precede:
/// a peer that runs first on the CPU has already published the behaviour
/// of state k when this controller reads state k, and that one is for the
/// step of state k + 1. Two messages, allocated once.
pub struct BehaviourInbox {
    kept: [Box<ControlBehaviour>; 2],
    /// the slot the next message goes into
    next: usize,
}

impl Default for BehaviourInbox {
    fn default() -> Self {
        BehaviourInbox {
            kept: [
                Box::new(ControlBehaviour::zeroed()),
                Box::new(ControlBehaviour::zeroed()),
            ],
            next: 0,
        }
    }
}

impl BehaviourInbox {
    /// Keep `m` in place of the one received before the last (by arrival:
    /// a restarted robot numbers its states from 1 again). Allocates
    /// nothing, and copies the header and the `len` bytes in use only (a
    /// few hundred of the message's 8 KiB: a standby takes every one).
    pub fn push(&mut self, m: &ControlBehaviour) {
        let kept = &mut *self.kept[self.next];
        let used = m.snapshot();
        kept.seq = m.seq;
        kept.stamp_ns = m.stamp_ns;
        kept.state_seq = m.state_seq;
        kept.state_stamp_ns = m.state_stamp_ns;
        kept.len = used.len() as u32;
        kept.bytes[..used.len()].copy_from_slice(used);
        self.next = 1 - self.next;
    }

    /// The behaviour the step of state `seq` left, if kept.
    pub fn after_state(&self, seq: u64) -> Option<&ControlBehaviour> {
        self.kept
            .iter()
            .map(|b| &**b)
            .find(|b| b.state_seq == seq && seq > 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::BEHAVIOUR_BYTES;

    #[test]
    fn the_priority_follows_the_role_with_one_syscall_per_change() {
        let mut p = RolePriority::new(79, 77).unwrap();
        assert_eq!((p.in_charge, p.standby), (79, 77));
        // before the first state: the lower
        assert_eq!(p.change(false), Some(77));
        assert_eq!(p.change(false), None);
        assert_eq!(p.change(true), Some(79));
        assert_eq!(p.change(true), None);
        assert_eq!(p.change(false), Some(77));
        // either order in the configuration; without real time, nothing
        assert_eq!(
            RolePriority::new(70, 75).map(|p| (p.in_charge, p.standby)),
            Some((75, 70))
        );
        assert_eq!(RolePriority::new(0, 77), None);
    }
    use phri_ipc::Zeroed;

    fn state(seq: u64, status: u32) -> JointState {
        JointState {
            seq,
            status,
            ..JointState::zeroed()
        }
    }

    #[test]
    fn the_standby_residual_is_called_when_the_first_is_behind_invalid_or_gone() {
        let at = |stamp_ns: u64| JointState {
            seq: 9,
            stamp_ns,
            ..JointState::zeroed()
        };
        let residual = |state_stamp_ns: u64, flags: u32| Residual {
            state_stamp_ns,
            flags,
            ..Residual::zeroed()
        };
        let ms = 1_000_000;
        let valid = residual_flags::VALID;
        // of this state or the one before: no call
        assert!(!residual_wanted(
            Some(&residual(100 * ms, valid)),
            &at(100 * ms)
        ));
        assert!(!residual_wanted(
            Some(&residual(99 * ms, valid)),
            &at(100 * ms)
        ));
        assert!(!residual_wanted(
            Some(&residual(98 * ms, valid)),
            &at(100 * ms)
        ));
        // more than two periods behind, warming up, or none at all: a call
        assert!(residual_wanted(
            Some(&residual(97 * ms, valid)),
            &at(100 * ms)
        ));
        assert!(residual_wanted(Some(&residual(100 * ms, 0)), &at(100 * ms)));
        assert!(residual_wanted(None, &at(100 * ms)));
        // the bound the configuration checks against
        assert!(RESIDUAL_CALL_BEHIND_NS as f64 / 1e6 + 1.0 <= phri_config::STANDBY_RESIDUAL_LAG_MS);
    }

    #[test]
    fn the_first_slot_is_in_charge_until_the_robot_says_otherwise() {
        let first = Standby::new(Slot::First);
        let standby = Standby::new(Slot::Standby);
        let s = state(5, 0);
        assert!(first.in_charge(&s) && !standby.in_charge(&s));
        let s = state(6, robot_status::STANDBY_IN_CHARGE);
        assert!(!first.in_charge(&s) && standby.in_charge(&s));
        assert_eq!(
            standby.duty(&s, true),
            Duty {
                in_charge: true,
                command: true
            }
        );
    }

    #[test]
    fn a_standby_commands_only_in_sync_with_the_one_in_charge() {
        let mut b = Standby::new(Slot::Standby);
        // just started: not in sync, not commanding
        assert!(!b.duty(&state(10, 0), true).command);
        // the behaviour of the state before is adopted; any other is not
        assert!(!b.should_adopt(&state(10, 0), 8));
        assert!(b.should_adopt(&state(10, 0), 9));
        b.adopted(&state(10, 0));
        assert_eq!(
            b.duty(&state(10, 0), true),
            Duty {
                in_charge: false,
                command: true
            }
        );
        // one state without a behaviour (the one in charge late): still in sync
        assert!(b.duty(&state(11, 0), true).command);
        // two: no longer (a stall, a stop)
        assert!(!b.duty(&state(12, 0), true).command);
        // a restarted robot's states start from 1: not in sync with them
        assert!(!b.duty(&state(1, 0), true).command);
        // in sync, but its own inputs stale (just started): no command
        b.adopted(&state(20, 0));
        assert!(!b.duty(&state(20, 0), false).command);
        assert!(b.duty(&state(20, 0), true).command);
        // in charge it never adopts, and commands
        let s = state(13, robot_status::STANDBY_IN_CHARGE);
        assert!(!b.should_adopt(&s, 12));
        assert!(b.duty(&s, true).command);
    }

    #[test]
    fn the_fresher_valid_residual_is_taken() {
        let r = |seq, valid: bool| Residual {
            state_seq: seq,
            state_stamp_ns: seq * 1_000_000,
            flags: if valid { residual_flags::VALID } else { 0 },
            ..Residual::zeroed()
        };
        let pick = |a: Option<&Residual>, b: Option<&Residual>| {
            fresher_residual(a, b).map(|x| (x.state_seq, x.flags))
        };
        let (a, b) = (r(10, true), r(10, true));
        assert!(std::ptr::eq(
            fresher_residual(Some(&a), Some(&b)).unwrap(),
            &a
        ));
        // the first one killed: its last residual ages, the standby's is newer
        assert_eq!(pick(Some(&r(10, true)), Some(&r(12, true))), Some((12, 8)));
        // a restarted one warming up is not taken over a valid one
        assert_eq!(pick(Some(&r(10, true)), Some(&r(12, false))), Some((10, 8)));
        assert_eq!(pick(None, Some(&r(3, true))), Some((3, 8)));
        assert_eq!(pick(None, None), None);
    }

    #[test]
    fn the_inbox_keeps_the_two_newest_behaviours() {
        let mut inbox = BehaviourInbox::default();
        let b = |seq| ControlBehaviour {
            state_seq: seq,
            ..ControlBehaviour::zeroed()
        };
        assert!(inbox.after_state(0).is_none() && inbox.after_state(1).is_none());
        inbox.push(&b(9));
        inbox.push(&b(10));
        assert_eq!(inbox.after_state(9).map(|m| m.state_seq), Some(9));
        inbox.push(&b(11));
        assert!(inbox.after_state(9).is_none());
        assert!(inbox.after_state(10).is_some() && inbox.after_state(11).is_some());
        // a restarted robot: its states from 1 again
        inbox.push(&b(1));
        inbox.push(&b(2));
        assert!(inbox.after_state(1).is_some() && inbox.after_state(2).is_some());
        inbox.push(&b(3));
        assert!(inbox.after_state(2).is_some() && inbox.after_state(1).is_none());
    }

    #[test]
    fn the_inbox_keeps_each_behaviour_s_header_and_bytes_in_use() {
        let mut inbox = BehaviourInbox::default();
        let b = |seq: u64, len: usize, fill: u8| {
            let mut m = ControlBehaviour {
                seq: 100 + seq,
                stamp_ns: 7 * seq,
                state_seq: seq,
                state_stamp_ns: 11 * seq,
                len: len as u32,
                ..ControlBehaviour::zeroed()
            };
            m.bytes[..len].fill(fill);
            m
        };
        // a long one, then a shorter one into the same slot (two pushes
        // later), then one that claims more than the message holds
        for m in [b(1, 900, 1), b(2, 300, 2), b(3, 120, 3), b(4, 50, 4)] {
            inbox.push(&m);
            let kept = inbox.after_state(m.state_seq).unwrap();
            assert_eq!(
                (kept.seq, kept.stamp_ns, kept.state_stamp_ns),
                (m.seq, m.stamp_ns, m.state_stamp_ns)
            );
            assert_eq!(kept.snapshot(), m.snapshot());
        }
        let mut over = b(5, BEHAVIOUR_BYTES, 5);
        over.len = u32::MAX;
        inbox.push(&over);
        assert_eq!(
            inbox.after_state(5).unwrap().snapshot(),
            &[5; BEHAVIOUR_BYTES][..]
        );
    }

    #[test]
    fn a_standby_rests_only_through_states_the_one_in_charge_answered() {
        let b = Standby::new(Slot::Standby);
        assert!(b.may_rest(&state(10, 0), true));
        // the one in charge has not answered yet: step, ready to take over
        assert!(!b.may_rest(&state(10, 0), false));
        // one state in FULL_STEP_EVERY is stepped: the answers stay compared
        assert!(!b.may_rest(&state(FULL_STEP_EVERY, 0), true));
        assert!(b.may_rest(&state(FULL_STEP_EVERY + 1, 0), true));
        // braked (anyone may answer) or in charge: never
        assert!(!b.may_rest(&state(11, robot_status::BRAKING), true));
        assert!(!b.may_rest(&state(11, robot_status::STANDBY_IN_CHARGE), true));
        // the first slot rests once the standby is in charge
        let first = Standby::new(Slot::First);
        assert!(first.may_rest(&state(11, robot_status::STANDBY_IN_CHARGE), true));
        assert!(!first.may_rest(&state(11, 0), true));
    }

    #[test]
    fn while_the_robot_is_braked_anyone_may_answer() {
        let b = Standby::new(Slot::Standby);
        let d = b.duty(&state(3, robot_status::BRAKING), true);
        assert_eq!(
            d,
            Duty {
                in_charge: false,
                command: true
            }
        );
    }
}
