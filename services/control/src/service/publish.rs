//! One period's messages, written into buffers allocated once and published
//! by the controller in charge (the command by whichever the role says).

use phri_ipc::{
    BarrierStatus, CollabState, ControlBehaviour, ControlStatus, IpcError, JointState, SsmStatus,
    TorqueCommand, Zeroed,
};

use super::channels::OutputChannels;
use crate::standby::{save_behaviour, Duty};
use crate::{
    write_barrier_status, write_collab_state, write_messages, write_ssm_status, Controller, Stamps,
};

/// The buffers of the messages the controller publishes.
pub struct Messages {
    cmd: TorqueCommand,
    status: ControlStatus,
    collab_state: CollabState,
    ssm_status: SsmStatus,
    barrier_status: BarrierStatus,
    /// this controller's behaviour state, for the other one
    behaviour: Box<ControlBehaviour>,
}

impl Default for Messages {
    fn default() -> Messages {
        Messages {
            cmd: TorqueCommand::zeroed(),
            status: ControlStatus::zeroed(),
            collab_state: CollabState::zeroed(),
            ssm_status: SsmStatus::zeroed(),
            barrier_status: BarrierStatus::zeroed(),
            behaviour: Box::new(ControlBehaviour::zeroed()),
        }
    }
}

/// What the messages of a period carry besides the controller's state.
#[derive(Clone, Copy, Debug)]
pub struct Period {
    /// the message number
    pub seq: u64,
    /// when the loop woke and when the step was done [ns, CLOCK_MONOTONIC]
    pub stamps: Stamps,
    /// what this controller publishes
    pub duty: Duty,
    /// the requests this controller may have lost (collab/state's requests_dropped)
    pub requests_dropped: u32,
    /// whether a hot standby runs beside (the behaviour state is published)
    pub with_standby: bool,
    /// in charge, call the standby's residual (`dynamics/residual/call`)
    pub call_residual: bool,
}

impl Messages {
    /// Writes `controller`'s answer to `state` and publishes the command
    /// when `period.duty` asks.
    pub fn command(
        &mut self,
        controller: &Controller,
        state: &JointState,
        period: Period,
        out: &OutputChannels,
    ) -> Result<(), IpcError> {
        write_messages(
            controller,
            state,
            period.seq,
            period.stamps,
            &mut self.cmd,
            &mut self.status,
        );
        if period.duty.command {
            out.commands.publish(&self.cmd)?;
        }
        Ok(())
    }

    /// In charge, publishes the status, the collaboration's and SSM's state,
    /// the barrier filter's (under that law) and (with a standby) the
    /// behaviour state; otherwise keeps the
    /// publishers of the one in charge connected, ready to take charge.
    pub fn rest(
        &mut self,
        controller: &Controller,
        state: &JointState,
        period: Period,
        out: &OutputChannels,
    ) -> Result<(), IpcError> {
        if !period.duty.in_charge {
            // ready to take charge: the publishers of the one in charge connected
            out.status.update_connections();
            out.collab.update_connections();
            out.ssm.update_connections();
            out.barrier.update_connections();
            out.behaviour.update_connections();
            if let Some(call) = &out.residual_call {
                call.update_connections();
            }
            return Ok(());
        }
        if let (true, Some(call)) = (period.call_residual, &out.residual_call) {
            // the first residual is late: the standby's steps the states now
            call.publish(state)?;
        }
        let (seq, now) = (period.seq, phri_runtime::now_ns);
        out.status.publish(&self.status)?;
        write_collab_state(controller, state, seq, now(), &mut self.collab_state);
        self.collab_state.requests_dropped = period.requests_dropped;
        out.collab.publish(&self.collab_state)?;
        write_ssm_status(controller, state, seq, now(), &mut self.ssm_status);
        out.ssm.publish(&self.ssm_status)?;
        if write_barrier_status(controller, state, seq, now(), &mut self.barrier_status) {
            out.barrier.publish(&self.barrier_status)?;
        }
        if period.with_standby
            && save_behaviour(controller, state, seq, now(), &mut self.behaviour).is_ok()
        {
            // the header and the snapshot's few hundred bytes of 8 KiB
            out.behaviour
                .publish_head(&self.behaviour, self.behaviour.used_bytes())?;
        }
        Ok(())
    }
}
