//! The cell's channels: one constant each, carrying the name (what flows,
//! from whom), the message type, the QoS and whether it wakes its readers.
//! Publish-subscribe services and the event services that wake their readers
//! share the name.

use crate::channel::{Channel, FrameChannel, Message};
use crate::messages::*;
use crate::qos::Qos;

/// [`JointState`] from the robot (simulated or real adapter), 1 kHz. Wakes: new state.
pub const ROBOT_STATE: Channel<JointState> = Channel::new("robot/state", Qos::ONE_PUBLISHER, true);
/// [`JointState`] from the robot again, for the hot standby on
/// `robot/command/standby` only when its answer is wanted: every state while
/// it is in charge, and a state the controller in charge has not answered
/// by the robot's next period (the robot waits a grace for it). The
/// standby otherwise rests on a clock of its own (`[control]
/// standby_wake_ms`); a robot adapter that cannot wait republishes every
/// state. Wakes: a state to answer.
pub const ROBOT_STATE_STANDBY: Channel<JointState> =
    Channel::new("robot/state/standby", Qos::ONE_PUBLISHER, true);
/// [`TorqueCommand`] to the robot, one publisher only (the controller). Wakes: new command.
pub const ROBOT_COMMAND: Channel<TorqueCommand> =
    Channel::new("robot/command", Qos::ONE_PUBLISHER, true);
/// [`TorqueCommand`] to the robot from the hot standby controller, one
/// publisher only: applied when the controller in charge misses a period
/// (then the standby is in charge). Wakes: new command.
pub const ROBOT_COMMAND_STANDBY: Channel<TorqueCommand> =
    Channel::new("robot/command/standby", Qos::ONE_PUBLISHER, true);
/// [`CommanderStats`] from the robot adapter: which controller commanded,
/// takeovers, 10 Hz and at every takeover.
pub const ROBOT_COMMANDERS: Channel<CommanderStats> =
    Channel::new("robot/commanders", Qos::SLOW, false);
/// [`RobotStats`] from the robot adapter: loop timing and latency histogram, 10 Hz.
pub const ROBOT_STATS: Channel<RobotStats> = Channel::new("robot/stats", Qos::SLOW, false);
/// [`BoxStatus`] from a real robot's adapter: its control box's own figures
/// and errors, 10 Hz and at every error (none with the simulated arm).
pub const ROBOT_BOX: Channel<BoxStatus> = Channel::new("robot/box", Qos::SLOW, false);
/// [`CameraStatus`] from every camera process (the simulated camera, a
/// Kinect's, a ROS 2 camera's, a replay), 2 Hz: frames and drops by cause.
pub const CAMERA_STATUS: Channel<CameraStatus> = Channel::new(
    "camera/status",
    Qos {
        max_publishers: MAX_CAMERAS,
        ..Qos::SLOW
    },
    false,
);
/// [`MicStatus`] from the microphone (`phri-mic`), 2 Hz: chunks, overruns.
pub const AUDIO_MIC_STATUS: Channel<MicStatus> = Channel::new("audio/mic/status", Qos::SLOW, false);
/// [`BridgeRequests`] from the ROS 2 bridge: what it did with `/phri/request`, 2 Hz.
pub const ROS2_REQUESTS: Channel<BridgeRequests> = Channel::new("ros2/requests", Qos::SLOW, false);
/// [`Truth`]: simulator ground truth for evaluation only, 1 kHz. No controller may read it.
pub const SIM_TRUTH: Channel<Truth> = Channel::new("sim/truth", Qos::ONE_PUBLISHER, false);
/// [`Residual`] from the dynamics service, 1 kHz. Wakes: new residual.
pub const DYNAMICS_RESIDUAL: Channel<Residual> =
    Channel::new("dynamics/residual", Qos::ONE_PUBLISHER, true);
/// [`Residual`] from the hot standby's dynamics service (the same observer
/// over the same states), 1 kHz: the controller takes the fresher of the
/// two. Wakes: new residual.
pub const DYNAMICS_RESIDUAL_STANDBY: Channel<Residual> =
    Channel::new("dynamics/residual/standby", Qos::ONE_PUBLISHER, true);
/// [`JointState`] from the controller in charge, when `dynamics/residual`
/// falls two periods behind the state it answers or is not valid (the
/// residual service killed, restarting, warming up): the standby's
/// residual service, resting on its clock (`[dynamics] standby_wake_ms`),
/// steps the states queued since at once, then each state the call names,
/// until the calls stop. Wakes: a residual wanted.
pub const DYNAMICS_RESIDUAL_CALL: Channel<JointState> =
    Channel::new("dynamics/residual/call", Qos::CONTROLLERS, true);
/// [`ControlStatus`] from the controller in charge, 1 kHz (the standby's
/// publisher waits: two publishers at most).
pub const CONTROL_STATUS: Channel<ControlStatus> =
    Channel::new("control/status", Qos::CONTROLLERS, false);
/// [`ControlBehaviour`] of the controller on `robot/command`, every period
/// while it is in charge: the standby adopts it.
pub const CONTROL_BEHAVIOUR: Channel<ControlBehaviour> =
    Channel::new("control/behaviour", Qos::BEHAVIOUR, false);
/// [`ControlBehaviour`] of the controller on `robot/command/standby`, every
/// period while it is in charge.
pub const CONTROL_STANDBY_BEHAVIOUR: Channel<ControlBehaviour> =
    Channel::new("control/standby/behaviour", Qos::BEHAVIOUR, false);
/// [`Health`] from the supervisor, 10 Hz.
pub const SUPERVISOR_HEALTH: Channel<Health> = Channel::new("supervisor/health", Qos::SLOW, false);
/// [`Health`] of the services past the first [`crate::MAX_SERVICES`] in
/// start order (its `services[0]` is service number `MAX_SERVICES`),
/// published with each `supervisor/health` while the roster holds more.
pub const SUPERVISOR_HEALTH_MORE: Channel<Health> =
    Channel::new("supervisor/health/more", Qos::SLOW, false);
/// [`WorldState`]: the simulated world for the simulated camera, 1 kHz. Simulation only.
pub const SIM_WORLD: Channel<WorldState> = Channel::new("sim/world", Qos::ONE_PUBLISHER, false);
/// Raw depth frames from the camera (`[u16]` with a [`FrameHeader`]), 30 Hz. Wakes: new frame.
pub const CAMERA_DEPTH: FrameChannel = Channel::new("camera/depth", Qos::FRAMES, true);
/// Validated depth frames without the robot's own pixels. Wakes: new frame.
pub const PERCEPTION_DEPTH: FrameChannel = Channel::new("perception/depth", Qos::FRAMES, true);
/// [`RepulsionResult`] from every repulsion worker (one publisher each).
pub const PERCEPTION_REPULSION: Channel<RepulsionResult> =
    Channel::new("perception/repulsion", Qos::WORKERS, false);
/// [`ContactEvent`]s: contact episodes from the simulator's ground truth, for
/// evaluation only (a few per second, deeply queued: no episode is lost).
pub const SIM_CONTACTS: Channel<ContactEvent> = Channel::new("sim/contacts", Qos::EVENTS, false);
/// [`Skeleton`]: the people a body tracker sees, one message per depth
/// frame (same sequence number and capture time), 30 Hz. Wakes: new skeleton.
pub const PERCEPTION_SKELETON: Channel<Skeleton> =
    Channel::new("perception/skeleton", Qos::ONE_PUBLISHER, true);
/// [`HandObservation`]: the collaborative hand refined from depth by
/// ingestion, per frame while a collaboration is on.
pub const PERCEPTION_HAND: Channel<HandObservation> =
    Channel::new("perception/hand", Qos::ONE_PUBLISHER, false);
/// [`HriRequest`]s from people (gesture, voice, command line): several
/// publishers; a full reader makes its publisher wait, never loses its
/// oldest ([`Qos::REQUESTS`]).
pub const HRI_REQUEST: Channel<HriRequest> = Channel::new("hri/request", Qos::REQUESTS, false);
/// [`CollabState`] from the controller in charge, 1 kHz.
pub const COLLAB_STATE: Channel<CollabState> =
    Channel::new("collab/state", Qos::CONTROLLERS, false);
/// [`SsmStatus`] from the controller in charge, 1 kHz: speed and separation monitoring.
pub const CONTROL_SSM: Channel<SsmStatus> = Channel::new("control/ssm", Qos::CONTROLLERS, false);
/// [`BarrierStatus`] from the controller in charge, 1 kHz while the
/// control-barrier filter runs (`[avoidance] law = "cbf"`; nothing under the
/// paper's law): what the filter did.
pub const CONTROL_BARRIER: Channel<BarrierStatus> =
    Channel::new("control/barrier", Qos::CONTROLLERS, false);
/// [`AudioChunk`]s from the microphone (a capture driver, a recording, or
/// the simulated cell's scripted speech), 50 Hz, deeply queued: the
/// recogniser loses no audio while it decodes. Wakes: new chunk.
pub const AUDIO_MIC: Channel<AudioChunk> = Channel::new("audio/mic", Qos::AUDIO, true);
/// [`Utterance`]s from `phri-voice`: every utterance heard, and its verdict.
pub const VOICE_UTTERANCE: Channel<Utterance> = Channel::new("voice/utterance", Qos::EVENTS, false);
/// [`InputAudit`]s: what each reader of the owned channels (controller,
/// residual, voice recogniser) refused, 2 Hz, one publisher per reader.
pub const INPUT_AUDIT: Channel<InputAudit> = Channel::new("audit/inputs", Qos::WORKERS, false);
/// [`DepthFault`] from `phri-fault` to the simulated camera: frames to corrupt or delay (testing only).
pub const FAULT_DEPTH: Channel<DepthFault> = Channel::new("fault/depth", Qos::INJECTION, false);

/// Cameras a cell may have ([[camera]] entries).
pub const MAX_CAMERAS: usize = 4;

/// One camera's channels: the first camera's are the constants above
/// (`camera/depth`, …); camera `i` ≥ 1 has the same channels with its index
/// after the first segment (`camera/1/depth`, `perception/1/depth`,
/// `perception/1/repulsion`, `perception/1/skeleton`, `perception/1/hand`),
/// same types and QoS.
#[derive(Clone, Copy, Debug)]
pub struct CameraChannels {
    /// raw depth frames from camera `i`
    pub depth: FrameChannel,
    /// its validated frames without the robot's pixels
    pub perception: FrameChannel,
    /// the repulsion workers' results on its frames (distances bounded by
    /// what the camera watches when the cell has several)
    pub repulsion: Channel<RepulsionResult>,
    /// its body tracker's skeletons
    pub skeleton: Channel<Skeleton>,
    /// the collaborative hand its ingestion refined from its frames
    pub hand: Channel<HandObservation>,
}

const fn camera_channels(
    depth: &'static str,
    perception: &'static str,
    repulsion: &'static str,
    skeleton: &'static str,
    hand: &'static str,
) -> CameraChannels {
    CameraChannels {
        depth: Channel::new(depth, CAMERA_DEPTH.qos, CAMERA_DEPTH.wakes),
        perception: Channel::new(perception, PERCEPTION_DEPTH.qos, PERCEPTION_DEPTH.wakes),
        repulsion: Channel::new(
            repulsion,
            PERCEPTION_REPULSION.qos,
            PERCEPTION_REPULSION.wakes,
        ),
        skeleton: Channel::new(skeleton, PERCEPTION_SKELETON.qos, PERCEPTION_SKELETON.wakes),
        hand: Channel::new(hand, PERCEPTION_HAND.qos, PERCEPTION_HAND.wakes),
    }
}

/// Every camera's channels, by camera index.
pub const CAMERAS: [CameraChannels; MAX_CAMERAS] = [
    CameraChannels {
        depth: CAMERA_DEPTH,
        perception: PERCEPTION_DEPTH,
        repulsion: PERCEPTION_REPULSION,
        skeleton: PERCEPTION_SKELETON,
        hand: PERCEPTION_HAND,
    },
    camera_channels(
        "camera/1/depth",
        "perception/1/depth",
        "perception/1/repulsion",
        "perception/1/skeleton",
        "perception/1/hand",
    ),
    camera_channels(
        "camera/2/depth",
        "perception/2/depth",
        "perception/2/repulsion",
        "perception/2/skeleton",
        "perception/2/hand",
    ),
    camera_channels(
        "camera/3/depth",
        "perception/3/depth",
        "perception/3/repulsion",
        "perception/3/skeleton",
        "perception/3/hand",
    ),
];

/// The channels of a cell's `n` cameras (at least the first, at most
/// [`MAX_CAMERAS`]).
pub fn cameras(n: usize) -> &'static [CameraChannels] {
    &CAMERAS[..n.clamp(1, MAX_CAMERAS)]
}

/// Camera `i`'s channels; `None` past [`MAX_CAMERAS`].
pub fn camera(i: usize) -> Option<&'static CameraChannels> {
    CAMERAS.get(i)
}

/// The camera whose channel `name` is (0 for the first camera's constants),
/// with the first camera's name of the same channel; `None` for a channel
/// that belongs to no camera.
pub fn camera_of_channel(name: &str) -> Option<(usize, &'static str)> {
    CAMERAS.iter().enumerate().find_map(|(i, c)| {
        [
            (c.depth.name, CAMERA_DEPTH.name),
            (c.perception.name, PERCEPTION_DEPTH.name),
            (c.repulsion.name, PERCEPTION_REPULSION.name),
            (c.skeleton.name, PERCEPTION_SKELETON.name),
            (c.hand.name, PERCEPTION_HAND.name),
        ]
        .into_iter()
        .find(|(n, _)| *n == name)
        .map(|(_, first)| (i, first))
    })
}

/// Camera `camera`'s name of the first camera's channel `first`
/// (`camera/depth` → `camera/1/depth`); any other name unchanged.
pub fn for_camera(first: &str, camera: usize) -> &str {
    let Some(c) = CAMERAS.get(camera) else {
        return first;
    };
    match first {
        n if n == CAMERA_DEPTH.name => c.depth.name,
        n if n == PERCEPTION_DEPTH.name => c.perception.name,
        n if n == PERCEPTION_REPULSION.name => c.repulsion.name,
        n if n == PERCEPTION_SKELETON.name => c.skeleton.name,
        n if n == PERCEPTION_HAND.name => c.hand.name,
        other => other,
    }
}

// The contract, checked when this crate compiles: one commander, one robot,
// a worker pool, no history on frames, wake-ups where readers wait on them.
const _: () = {
    assert!(ROBOT_COMMAND.qos.max_publishers == 1);
    assert!(ROBOT_STATE.qos.max_publishers == 1);
    assert!(PERCEPTION_REPULSION.qos.max_publishers >= 4);
    assert!(CAMERA_DEPTH.qos.history == 0 && PERCEPTION_DEPTH.qos.history == 0);
    assert!(ROBOT_STATE.wakes && ROBOT_COMMAND.wakes && DYNAMICS_RESIDUAL.wakes);
    assert!(ROBOT_STATE_STANDBY.wakes && ROBOT_STATE_STANDBY.qos.max_publishers == 1);
    assert!(CAMERA_DEPTH.wakes && PERCEPTION_DEPTH.wakes && !SIM_TRUTH.wakes);
    assert!(AUDIO_MIC.qos.max_publishers == 1 && AUDIO_MIC.wakes);
    assert!(crate::owners::PUBLISHERS.len() <= crate::messages::AUDIT_CHANNELS);
};

/// Every publish-subscribe channel of the cell, by name, for tools that list or record them.
pub const ALL: &[&str] = &[
    ROBOT_STATE.name,
    ROBOT_COMMAND.name,
    ROBOT_STATS.name,
    SIM_TRUTH.name,
    DYNAMICS_RESIDUAL.name,
    CONTROL_STATUS.name,
    SUPERVISOR_HEALTH.name,
    SUPERVISOR_HEALTH_MORE.name,
    SIM_WORLD.name,
    CAMERA_DEPTH.name,
    PERCEPTION_DEPTH.name,
    PERCEPTION_REPULSION.name,
    FAULT_DEPTH.name,
    SIM_CONTACTS.name,
    PERCEPTION_SKELETON.name,
    HRI_REQUEST.name,
    PERCEPTION_HAND.name,
    COLLAB_STATE.name,
    AUDIO_MIC.name,
    VOICE_UTTERANCE.name,
    INPUT_AUDIT.name,
    ROBOT_BOX.name,
    CONTROL_SSM.name,
    ROBOT_COMMAND_STANDBY.name,
    ROBOT_COMMANDERS.name,
    CONTROL_BEHAVIOUR.name,
    CONTROL_STANDBY_BEHAVIOUR.name,
    DYNAMICS_RESIDUAL_STANDBY.name,
    ROS2_REQUESTS.name,
    CAMERA_STATUS.name,
    AUDIO_MIC_STATUS.name,
    CONTROL_BARRIER.name,
    ROBOT_STATE_STANDBY.name,
    DYNAMICS_RESIDUAL_CALL.name,
];

/// Channels that carry messages only when something happens (a tool injects a
/// fault, a contact, a request, a collaboration, an arm outside the cell, a
/// roster past one health message, the barrier filter chosen, a standby's
/// answer wanted): monitors and tests must not
/// expect traffic on them.
pub const ON_DEMAND: &[&str] = &[
    FAULT_DEPTH.name,
    SIM_CONTACTS.name,
    HRI_REQUEST.name,
    PERCEPTION_HAND.name,
    VOICE_UTTERANCE.name,
    ROBOT_BOX.name,
    ROBOT_COMMAND_STANDBY.name,
    CONTROL_BEHAVIOUR.name,
    CONTROL_STANDBY_BEHAVIOUR.name,
    DYNAMICS_RESIDUAL_STANDBY.name,
    ROS2_REQUESTS.name,
    SUPERVISOR_HEALTH_MORE.name,
    CONTROL_BARRIER.name,
    ROBOT_STATE_STANDBY.name,
    DYNAMICS_RESIDUAL_CALL.name,
];

/// Something done with each channel of the cell, typed: tools that handle
/// every channel (monitor, recorder) implement this instead of matching names.
pub trait ChannelVisitor {
    /// Do it with a channel of messages of type `T`.
    fn message<T: Message>(&mut self, channel: Channel<T>);
    /// Do it with a channel of depth frames.
    fn frames(&mut self, channel: FrameChannel);
}

/// Visit every channel of the cell, in [`ALL`]'s order.
pub fn visit_all(v: &mut impl ChannelVisitor) {
    v.message(ROBOT_STATE);
    v.message(ROBOT_COMMAND);
    v.message(ROBOT_STATS);
    v.message(SIM_TRUTH);
    v.message(DYNAMICS_RESIDUAL);
    v.message(CONTROL_STATUS);
    v.message(SUPERVISOR_HEALTH);
    v.message(SUPERVISOR_HEALTH_MORE);
    v.message(SIM_WORLD);
    v.frames(CAMERA_DEPTH);
    v.frames(PERCEPTION_DEPTH);
    v.message(PERCEPTION_REPULSION);
    v.message(FAULT_DEPTH);
    v.message(SIM_CONTACTS);
    v.message(PERCEPTION_SKELETON);
    v.message(HRI_REQUEST);
    v.message(PERCEPTION_HAND);
    v.message(COLLAB_STATE);
    v.message(AUDIO_MIC);
    v.message(VOICE_UTTERANCE);
    v.message(INPUT_AUDIT);
    v.message(ROBOT_BOX);
    v.message(CONTROL_SSM);
    v.message(ROBOT_COMMAND_STANDBY);
    v.message(ROBOT_COMMANDERS);
    v.message(CONTROL_BEHAVIOUR);
    v.message(CONTROL_STANDBY_BEHAVIOUR);
    v.message(DYNAMICS_RESIDUAL_STANDBY);
    v.message(ROS2_REQUESTS);
    v.message(CAMERA_STATUS);
    v.message(AUDIO_MIC_STATUS);
    v.message(CONTROL_BARRIER);
    v.message(ROBOT_STATE_STANDBY);
    v.message(DYNAMICS_RESIDUAL_CALL);
}

/// The further cameras' channels by name (camera 1 on, in [`CAMERAS`]'s
/// order, each camera's in [`visit_camera`]'s), for tools that take them
/// beside [`ALL`] in a cell of several cameras.
pub const FURTHER_CAMERAS: &[&str] = &[
    CAMERAS[1].depth.name,
    CAMERAS[1].perception.name,
    CAMERAS[1].repulsion.name,
    CAMERAS[1].skeleton.name,
    CAMERAS[1].hand.name,
    CAMERAS[2].depth.name,
    CAMERAS[2].perception.name,
    CAMERAS[2].repulsion.name,
    CAMERAS[2].skeleton.name,
    CAMERAS[2].hand.name,
    CAMERAS[3].depth.name,
    CAMERAS[3].perception.name,
    CAMERAS[3].repulsion.name,
    CAMERAS[3].skeleton.name,
    CAMERAS[3].hand.name,
];

/// Visit camera `i`'s channels: its raw and ingested frames, its repulsion
/// results, its skeletons and its hand; nothing past [`MAX_CAMERAS`].
pub fn visit_camera(i: usize, v: &mut impl ChannelVisitor) {
    if let Some(c) = CAMERAS.get(i) {
        v.frames(c.depth);
        v.frames(c.perception);
        v.message(c.repulsion);
        v.message(c.skeleton);
        v.message(c.hand);
    }
}

/// Visit the channel called `name`, a further camera's included; `false`
/// when the cell has none of that name.
pub fn visit_named(name: &str, v: &mut impl ChannelVisitor) -> bool {
    struct One<'a, V> {
        name: &'a str,
        v: &'a mut V,
        found: bool,
    }
    impl<V: ChannelVisitor> ChannelVisitor for One<'_, V> {
        fn message<T: Message>(&mut self, c: Channel<T>) {
            if !self.found && c.name == self.name {
                self.found = true;
                self.v.message(c);
            }
        }
        fn frames(&mut self, c: FrameChannel) {
            if !self.found && c.name == self.name {
                self.found = true;
                self.v.frames(c);
            }
        }
    }
    let mut one = One {
        name,
        v,
        found: false,
    };
    visit_all(&mut one);
    for i in 1..MAX_CAMERAS {
        visit_camera(i, &mut one);
    }
    one.found
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names a visit gives, in its order.
    struct Names(Vec<&'static str>);

    impl ChannelVisitor for Names {
        fn message<T: Message>(&mut self, c: Channel<T>) {
            self.0.push(c.name);
        }
        fn frames(&mut self, c: FrameChannel) {
            self.0.push(c.name);
        }
    }

    #[test]
    fn further_cameras_channels_are_listed_and_found_by_name() {
        let mut names = Names(Vec::new());
        for i in 1..MAX_CAMERAS {
            visit_camera(i, &mut names);
        }
        assert_eq!(names.0, FURTHER_CAMERAS);
        for name in FURTHER_CAMERAS {
            assert!(visit_named(name, &mut Names(Vec::new())), "{name}");
            assert!(!ALL.contains(name), "{name}");
        }
        let mut first = Names(Vec::new());
        visit_camera(0, &mut first);
        assert!(first.0.iter().all(|n| ALL.contains(n)));
        let mut past = Names(Vec::new());
        visit_camera(MAX_CAMERAS, &mut past);
        assert!(past.0.is_empty());
    }

    #[test]
    fn each_camera_has_its_own_channels_of_the_first_cameras_types() {
        let mut names: Vec<&str> = CAMERAS
            .iter()
            .flat_map(|c| {
                [
                    c.depth.name,
                    c.perception.name,
                    c.repulsion.name,
                    c.skeleton.name,
                ]
            })
            .collect();
        assert_eq!(names.len(), 4 * MAX_CAMERAS);
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 4 * MAX_CAMERAS, "a name used twice");
        assert_eq!(camera(1).unwrap().depth.name, "camera/1/depth");
        assert_eq!(
            camera_of_channel("perception/2/repulsion"),
            Some((2, "perception/repulsion"))
        );
        assert_eq!(
            camera_of_channel("perception/repulsion"),
            Some((0, "perception/repulsion"))
        );
        assert_eq!(camera_of_channel("robot/state"), None);
        assert_eq!(for_camera("camera/depth", 3), "camera/3/depth");
        assert_eq!(for_camera("camera/depth", 0), "camera/depth");
        assert_eq!(for_camera("robot/state", 1), "robot/state");
        assert_eq!(for_camera("camera/depth", 9), "camera/depth");
        assert!(camera(MAX_CAMERAS).is_none());
        assert_eq!(cameras(0).len(), 1);
        assert_eq!(cameras(9).len(), MAX_CAMERAS);
    }

    #[test]
    fn every_channel_is_visited_once_in_order() {
        let mut n = Names(Vec::new());
        visit_all(&mut n);
        assert_eq!(n.0, ALL);
        assert!(visit_named("robot/state", &mut n));
        assert!(!visit_named("robot/nothing", &mut n));
    }
}
