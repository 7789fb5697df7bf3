//! The controller's channels in the cell: what it reads each period and
//! what it publishes, opened in one place.

use std::time::Duration;

use phri_ipc::{BarrierStatus, CollabState, ControlStatus, SsmStatus, TorqueCommand};
use phri_ipc::{
    ControlBehaviour, HandObservation, HriRequest, IpcError, IpcNode, JointState, LatestReader,
    Publisher, Queue, RepulsionResult, Residual, Skeleton, Subscriber, COLLAB_STATE,
    CONTROL_BARRIER, CONTROL_BEHAVIOUR, CONTROL_SSM, CONTROL_STANDBY_BEHAVIOUR, CONTROL_STATUS,
    DYNAMICS_RESIDUAL, DYNAMICS_RESIDUAL_CALL, DYNAMICS_RESIDUAL_STANDBY, HRI_REQUEST,
    ROBOT_COMMAND, ROBOT_COMMAND_STANDBY, ROBOT_STATE, ROBOT_STATE_STANDBY,
};

use crate::standby::Slot;

/// What the controller reads.
pub struct InputChannels {
    /// `robot/state`, waking the loop (not the standby's that rests on its clock)
    pub states: Subscriber<JointState>,
    /// the standby resting on its clock: `robot/state/standby`, waking it
    /// when its answer is wanted, and the clock's period
    /// (`[control] standby_wake_ms`)
    pub standby_states: Option<(Subscriber<JointState>, Duration)>,
    /// `dynamics/residual`
    pub residuals: LatestReader<Residual>,
    /// `dynamics/residual/standby`, with a hot standby (the fresher residual is acted on)
    pub standby_residuals: Option<LatestReader<Residual>>,
    /// every camera's `perception/C/repulsion`
    pub results: Vec<Subscriber<RepulsionResult>>,
    /// `hri/request`
    pub requests: Subscriber<HriRequest>,
    /// every camera's `perception/C/skeleton`
    pub skeletons: Vec<LatestReader<Skeleton>>,
    /// every camera's `perception/C/hand`
    pub hands: Vec<LatestReader<HandObservation>>,
}

/// What the controller publishes, and the behaviour of the other controller.
pub struct OutputChannels {
    /// `robot/command` (`robot/command/standby` as the standby): one publisher only
    pub commands: Publisher<TorqueCommand>,
    /// this controller's behaviour state, for the other one
    pub behaviour: Publisher<ControlBehaviour>,
    /// the other controller's behaviour state
    pub peer_behaviour: Subscriber<ControlBehaviour>,
    /// `control/status`
    pub status: Publisher<ControlStatus>,
    /// `collab/state`
    pub collab: Publisher<CollabState>,
    /// `control/ssm`
    pub ssm: Publisher<SsmStatus>,
    /// `control/barrier` (under `[avoidance] law = "cbf"`)
    pub barrier: Publisher<BarrierStatus>,
    /// `dynamics/residual/call`, with a standby: the first residual is late
    pub residual_call: Option<Publisher<JointState>>,
}

/// How long a loop waits for a state before it beats and looks again.
const STATE_WAIT: Duration = Duration::from_millis(50);

/// Opens the channels of the controller in `slot` on `node`, for `cameras`
/// cameras; the standby's residual only `with_standby`; the standby slot
/// rests on a clock of `standby_wake_ms` \[ms\] (0: woken by every state).
/// A second controller of one slot fails here: the command channel accepts
/// exactly one publisher.
pub fn open(
    node: &IpcNode,
    slot: Slot,
    with_standby: bool,
    cameras: usize,
    standby_wake_ms: f64,
) -> Result<(InputChannels, OutputChannels), IpcError> {
    let (command_channel, own_behaviour, peer_behaviour) = match slot {
        Slot::First => (ROBOT_COMMAND, CONTROL_BEHAVIOUR, CONTROL_STANDBY_BEHAVIOUR),
        Slot::Standby => (
            ROBOT_COMMAND_STANDBY,
            CONTROL_STANDBY_BEHAVIOUR,
            CONTROL_BEHAVIOUR,
        ),
    };
    let on_clock = (slot == Slot::Standby && with_standby && standby_wake_ms > 0.0)
        .then(|| Duration::from_secs_f64(standby_wake_ms.min(1e3) * 1e-3));
    let (states, standby_states) = match on_clock {
        Some(every) => (
            ROBOT_STATE.subscriber(node, Queue::Latest)?,
            Some((
                ROBOT_STATE_STANDBY.waking_subscriber(node, Queue::Latest)?,
                every,
            )),
        ),
        None => (ROBOT_STATE.waking_subscriber(node, Queue::Latest)?, None),
    };
    let residuals = DYNAMICS_RESIDUAL.latest_reader(node)?;
    let standby_residuals = match with_standby {
        true => Some(DYNAMICS_RESIDUAL_STANDBY.latest_reader(node)?),
        false => None,
    };
    let commands = command_channel.publisher(node)?;
    let behaviour = own_behaviour.publisher(node)?;
    let peer_behaviour = peer_behaviour.subscriber(node, Queue::Drain)?;
    let status = CONTROL_STATUS.publisher(node)?;
    let cameras = phri_ipc::cameras(cameras);
    let results = cameras
        .iter()
        .map(|c| c.repulsion.subscriber(node, Queue::Drain))
        .collect::<Result<Vec<_>, _>>()?;
    let requests = HRI_REQUEST.subscriber(node, Queue::Drain)?;
    let skeletons = cameras
        .iter()
        .map(|c| c.skeleton.latest_reader(node))
        .collect::<Result<Vec<_>, _>>()?;
    let hands = cameras
        .iter()
        .map(|c| c.hand.latest_reader(node))
        .collect::<Result<Vec<_>, _>>()?;
    let collab = COLLAB_STATE.publisher(node)?;
    let ssm = CONTROL_SSM.publisher(node)?;
    let barrier = CONTROL_BARRIER.publisher(node)?;
    let residual_call = match with_standby {
        true => Some(DYNAMICS_RESIDUAL_CALL.publisher(node)?),
        false => None,
    };
    let inputs = InputChannels {
        states,
        standby_states,
        residuals,
        standby_residuals,
        results,
        requests,
        skeletons,
        hands,
    };
    let outputs = OutputChannels {
        commands,
        behaviour,
        peer_behaviour,
        status,
        collab,
        ssm,
        barrier,
        residual_call,
    };
    Ok((inputs, outputs))
}

impl InputChannels {
    /// Wait for a state to answer: the next of `robot/state`, or, the
    /// standby resting on its clock, a `robot/state/standby` (the robot
    /// wants its answer) or the clock's tick; the wake-up's samples are
    /// taken (counted by `gate`), the state is `robot/state`'s newest.
    /// An error ends a wait early: one more poll.
    pub fn wait(&self, gate: &crate::InputGate) {
        match &self.standby_states {
            Some((wake, every)) => {
                let _ = wake.wait(*every);
                let _ = wake.drain_from(|pid, _| {
                    gate.state(pid);
                });
            }
            None => {
                let _ = self.states.wait(STATE_WAIT);
            }
        }
    }

    /// The newest `robot/state` queued from the robot `gate` admits, if any.
    pub fn latest_state(&self, gate: &crate::InputGate) -> Result<Option<JointState>, IpcError> {
        let mut latest = None;
        self.states.drain_from(|pid, s| {
            if gate.state(pid) {
                latest = Some(*s);
            }
        })?;
        Ok(latest)
    }
}
