//! The hot standby in lock-step: a second controller answers every state
//! on command slot 1 (`robot/command/standby`), as `phri-control --standby`
//! does. Each period the one in charge steps; the other adopts the
//! behaviour the controller in charge left after the state before (the rule
//! of [`phri_control::standby`]) and steps too, or rests through a state
//! the one in charge answers (`[control] standby_rests`); the robot link
//! applies the answer of the one in charge, or the other's in the same
//! period.

use phri_control::standby::{inputs_fresh, save_behaviour, Slot, Standby};
use phri_control::Controller;
use phri_ipc::{ControlBehaviour, JointState, TorqueCommand, Zeroed};

/// The hot standby's controller (slot 1; slot 0 is the cell's `controller`)
/// and both slots' places.
pub(crate) struct Pair {
    pub standby: Controller,
    pub slots: Slots,
}

impl Pair {
    pub fn new(standby: Controller, control: phri_config::ControlConfig) -> Pair {
        Pair {
            standby,
            slots: Slots::new(control),
        }
    }

    /// The slot in charge by `state`.
    pub fn in_charge(&self, state: &JointState) -> usize {
        usize::from(!self.slots.roles[0].in_charge(state))
    }
}

/// Both command slots' places.
pub(crate) struct Slots {
    pub roles: [Standby; 2],
    /// each slot's newest command (kept while it is down)
    pub commands: [Option<TorqueCommand>; 2],
    /// each slot's behaviour after its last step in charge (state 0: none)
    pub behaviours: [Box<ControlBehaviour>; 2],
    /// adoptions refused (a layout mismatch): none expected
    pub refused: u64,
    /// `[control]` as the controllers run it (their inputs' staleness bounds)
    pub control: phri_config::ControlConfig,
}

impl Slots {
    fn new(control: phri_config::ControlConfig) -> Slots {
        Slots {
            control,
            roles: [Standby::new(Slot::First), Standby::new(Slot::Standby)],
            commands: [None, None],
            behaviours: [
                Box::new(ControlBehaviour::zeroed()),
                Box::new(ControlBehaviour::zeroed()),
            ],
            refused: 0,
        }
    }

    /// Slot `slot`'s controller was replaced by a new one: not in sync, no
    /// command nor behaviour of its own yet.
    pub fn restarted(&mut self, slot: usize) {
        let kind = [Slot::First, Slot::Standby][slot];
        self.roles[slot] = Standby::new(kind);
        self.commands[slot] = None;
        self.behaviours[slot].state_seq = 0;
    }

    /// Does slot `slot` rest through `state` (`[control] standby_rests`,
    /// [`Standby::may_rest`])? `up`: which slots run; the one in charge,
    /// when it runs, answers the state before the other looks.
    pub fn rests(&self, slot: usize, state: &JointState, up: [bool; 2]) -> bool {
        let peer = 1 - slot;
        let peer_answers = up[peer] && self.roles[peer].in_charge(state);
        self.control.standby_rests && self.roles[slot].may_rest(state, peer_answers)
    }

    /// Before slot `slot`'s step of `state`: adopt the other slot's behaviour
    /// of the state before, if it left one and `slot` is not in charge.
    pub fn adopt(&mut self, slot: usize, controller: &mut Controller, state: &JointState) {
        let peer = &self.behaviours[1 - slot];
        if self.roles[slot]
            .adopt(controller, state, Some(peer))
            .is_err()
        {
            self.refused += 1;
        }
    }

    /// After the period of `state`: slot `slot`, not in charge, follows the
    /// path history of the behaviour the other left after this state, if
    /// it left one ([`Controller::follow_behaviour`]).
    pub fn follow(&mut self, slot: usize, controller: &mut Controller, state: &JointState) {
        let b = &self.behaviours[1 - slot];
        if b.state_seq != state.seq || state.seq == 0 {
            return;
        }
        if controller.follow_behaviour(b.snapshot()).is_err() {
            self.refused += 1;
        }
    }

    /// After slot `slot`'s step of `state`, answered by `cmd`: keep the
    /// command if it is to be sent, the behaviour if in charge.
    pub fn answered(
        &mut self,
        slot: usize,
        controller: &Controller,
        state: &JointState,
        cmd: TorqueCommand,
    ) {
        let duty = self.roles[slot].duty(state, inputs_fresh(controller, &self.control));
        if duty.command {
            self.commands[slot] = Some(cmd);
        }
        if duty.in_charge {
            let b = &mut self.behaviours[slot];
            if save_behaviour(controller, state, cmd.seq, state.stamp_ns, b).is_err() {
                b.state_seq = 0;
            }
        }
    }
}
