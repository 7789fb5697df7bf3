//! The controller's period in the cell, in the order of the paper's
//! hierarchy around [`Controller::step`]: the inputs gathered, a lost request
//! acted on, the behaviour of the controller in charge adopted (as the hot
//! standby), the step, then the messages the role asks for.

use phri_ipc::{IpcError, JointState};
use phri_runtime::log::Deferred;

use super::channels::{InputChannels, OutputChannels};
use super::intake::Intake;
use super::notes::{count_and_log, Note};
use super::publish::{Messages, Period};
use crate::standby::{inputs_fresh, BehaviourInbox, Duty, RolePriority, Slot, Standby};
use crate::{ControlConfig, Controller, InputGate, RepulsionInputs, Stamps};

/// The controller, its role beside a hot standby, and the buffers of its
/// inputs and messages: everything the loop keeps from period to period.
pub struct ControlService {
    controller: Controller,
    /// the controller's own configuration (whether its inputs are fresh)
    control: ControlConfig,
    intake: Intake,
    messages: Messages,
    role: Role,
    /// the messages' number, one numbering whoever is in charge
    seq: u64,
    /// refused inputs so far
    refused: u64,
}

/// This controller's place beside the other one.
struct Role {
    standby: Standby,
    /// whether a hot standby runs beside
    with_standby: bool,
    /// the other controller's behaviour states, by the state they answered
    inbox: BehaviourInbox,
    /// the other's behaviour states refused so far
    refused: u64,
    /// with the standby, the loop's priority follows the role (the lower until in charge)
    rank: Option<RolePriority>,
}

impl ControlService {
    /// `controller` in `slot` of a cell as `cfg` describes it (a standby
    /// beside it `with_standby`), `repulsion` its cameras' accumulator,
    /// `rank` the priorities of the role (none: the priority stays).
    pub fn new(
        controller: Controller,
        cfg: &phri_config::Config,
        repulsion: RepulsionInputs,
        slot: Slot,
        with_standby: bool,
        rank: Option<RolePriority>,
    ) -> ControlService {
        let n = controller.model().nv();
        ControlService {
            control: cfg.control.clone(),
            intake: Intake::new(cfg, repulsion, n, with_standby),
            messages: Messages::default(),
            role: Role {
                standby: Standby::new(slot),
                with_standby,
                inbox: BehaviourInbox::default(),
                refused: 0,
                rank,
            },
            controller,
            seq: 0,
            refused: 0,
        }
    }

    /// The priority to start at, as the standby not yet in charge (none:
    /// keep the one given).
    pub fn start_priority(&mut self) -> Option<i32> {
        self.role.rank.as_mut().and_then(|r| r.change(false))
    }

    /// Answers `state` (its loop woke at `woke_ns`): reads `inputs` through
    /// `gate`, steps, publishes on `outputs`; refusals go to `log`.
    pub fn period(
        &mut self,
        inputs: &mut InputChannels,
        outputs: &OutputChannels,
        gate: &InputGate,
        state: &JointState,
        woke_ns: u64,
        log: &Deferred<Note>,
    ) -> Result<(), IpcError> {
        let in_charge = self.role.standby.in_charge(state);
        let gathered = match self.intake.gather(inputs, gate, state, in_charge)? {
            Ok(gathered) => gathered,
            Err(error) => {
                if count_and_log(&mut self.refused) {
                    let count = self.refused;
                    log.post(Note::Refused { error, count });
                }
                return Ok(());
            }
        };
        if self.role.with_standby {
            let follow = (!in_charge).then_some(&mut self.controller);
            self.role.receive(outputs, gate, follow, log)?;
            if self.control.standby_rests && self.role.may_rest(state) {
                // resting is not in charge: a controller stopped in charge
                // and resumed as the standby lowers its priority here too
                self.role.set_priority(false);
                return Ok(());
            }
        }
        if gathered.requests_lost {
            self.controller.requests_lost();
        }
        if self.role.with_standby {
            let seq = &mut self.seq;
            self.role.adopt(&mut self.controller, state, seq, log);
        }
        let call_residual = gathered.residual_late;
        self.controller.step(&gathered.input);
        self.seq += 1;
        let stamps = Stamps {
            woke_ns,
            done_ns: phri_runtime::now_ns(),
        };
        let period = Period {
            seq: self.seq,
            stamps,
            duty: self.role.duty(&self.controller, &self.control, state),
            requests_dropped: self.intake.request_watch.dropped(),
            call_residual,
            with_standby: self.role.with_standby,
        };
        let c = &self.controller;
        self.messages.command(c, state, period, outputs)?;
        self.role.set_priority(period.duty.in_charge);
        self.messages.rest(c, state, period, outputs)
    }
}

impl Role {
    /// The other controller's behaviour states published since the last
    /// period, those of the controller the supervisor started; not in
    /// charge, `follow` keeps the path history of each ([`Controller::follow_behaviour`]).
    fn receive(
        &mut self,
        outputs: &OutputChannels,
        gate: &InputGate,
        mut follow: Option<&mut Controller>,
        log: &Deferred<Note>,
    ) -> Result<(), IpcError> {
        let (inbox, refused) = (&mut self.inbox, &mut self.refused);
        outputs.peer_behaviour.drain_from(|pid, b| {
            if !gate.behaviour(pid) {
                return;
            }
            if let Some(c) = follow.as_deref_mut() {
                if let Err(error) = c.follow_behaviour(b.snapshot()) {
                    if count_and_log(refused) {
                        let count = *refused;
                        log.post(Note::Behaviour { error, count });
                    }
                }
            }
            inbox.push(b);
        })?;
        Ok(())
    }

    /// With the standby, the loop's priority of the role, `in_charge` or
    /// not (one system call per change).
    fn set_priority(&mut self, in_charge: bool) {
        if let Some(p) = self.rank.as_mut().and_then(|r| r.change(in_charge)) {
            // refused: the priority stays (the supervisor's watch reports it)
            let _ = phri_runtime::rt::set_fifo_priority(p);
        }
    }

    /// Rest through `state`: the one in charge has answered it already
    /// ([`Standby::may_rest`]).
    fn may_rest(&self, state: &JointState) -> bool {
        let answered = self.inbox.after_state(state.seq).is_some();
        self.standby.may_rest(state, answered)
    }

    /// The hot standby: the behaviour the one in charge left after the
    /// state before, adopted when this controller is not in charge.
    fn adopt(
        &mut self,
        controller: &mut Controller,
        state: &JointState,
        seq: &mut u64,
        log: &Deferred<Note>,
    ) {
        let before = self.inbox.after_state(state.seq.saturating_sub(1));
        match self.standby.adopt(controller, state, before) {
            // one numbering of the messages, whoever is in charge
            Ok(true) => *seq = before.map_or(*seq, |b| b.seq),
            Ok(false) => {}
            Err(error) => {
                if count_and_log(&mut self.refused) {
                    let count = self.refused;
                    log.post(Note::Behaviour { error, count });
                }
            }
        }
    }

    /// What this controller publishes after stepping `state`: everything
    /// alone, as the role says beside a standby.
    fn duty(&self, controller: &Controller, control: &ControlConfig, state: &JointState) -> Duty {
        match self.with_standby {
            true => self.standby.duty(state, inputs_fresh(controller, control)),
            false => Duty {
                in_charge: true,
                command: true,
            },
        }
    }
}
