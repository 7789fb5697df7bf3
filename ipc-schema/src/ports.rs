//! Who publishes and who reads each channel: per binary, the channels its
//! code opens, as data. The picture of the cell (`phri-supervisor
//! --draw-cell`) is drawn from this table and the roster; a test of this
//! crate reads every service's sources and fails when a binary opens a
//! channel its entry does not list, or lists one it never opens.
//!
//! A camera's channels are named by the first camera's
//! (`perception/skeleton` stands for `perception/I/skeleton` too). Tools
//! that handle every channel alike (`phri-monitor`, `phri-record`,
//! `phri-viz`, `phri-bench`) are not listed: they read whatever is there.

use crate::channels::*;

/// When a binary opens the ports of one entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum When {
    /// every run of the binary
    Always,
    /// run with this flag among its arguments (`--standby`)
    Flag(&'static str),
    /// run without this flag
    NoFlag(&'static str),
    /// the arm is simulated (`[robot] ip` empty)
    ArmSimulated,
    /// the arm is outside the cell (`[robot] ip` set): the simulator
    /// follows it and simulates the person and the world only
    ArmOutside,
    /// its source is the simulated one (`[camera] source = "sim"`, `[mic]`
    /// and `[audio] source = "sim"`)
    SimulatedSource,
    /// its source is not the simulated one (a replay, a recording)
    OtherSource,
}

/// The channels one binary opens, under one condition.
#[derive(Clone, Copy, Debug)]
pub struct Ports {
    /// the binary (`phri-control`)
    pub binary: &'static str,
    /// when it opens these
    pub when: When,
    /// the channels it publishes
    pub publishes: &'static [&'static str],
    /// the channels it subscribes to
    pub reads: &'static [&'static str],
}

const fn ports(
    binary: &'static str,
    when: When,
    publishes: &'static [&'static str],
    reads: &'static [&'static str],
) -> Ports {
    Ports {
        binary,
        when,
        publishes,
        reads,
    }
}

/// Every supervised service's dead-man thread (phri-runtime) reads the
/// supervisor's health; a service that checks who sent its inputs
/// (`ServiceContext::watch_inputs`) publishes `audit/inputs` from that
/// thread, listed in its own entry.
pub const SUPERVISED: Ports = ports(
    "",
    When::Always,
    &[],
    &[SUPERVISOR_HEALTH.name, SUPERVISOR_HEALTH_MORE.name],
);

/// The channels of every binary of the cell, one or more entries each.
pub const PORTS: &[Ports] = &[
    ports(
        "phri-sim",
        When::Always,
        &[SIM_TRUTH.name, SIM_WORLD.name, SIM_CONTACTS.name],
        &[],
    ),
    ports(
        "phri-sim",
        When::ArmSimulated,
        &[
            ROBOT_STATE.name,
            ROBOT_STATE_STANDBY.name,
            ROBOT_STATS.name,
            ROBOT_COMMANDERS.name,
            INPUT_AUDIT.name,
        ],
        &[ROBOT_COMMAND.name, ROBOT_COMMAND_STANDBY.name],
    ),
    ports("phri-sim", When::ArmOutside, &[], &[ROBOT_STATE.name]),
    ports(
        "phri-franka",
        When::Always,
        &[
            ROBOT_STATE.name,
            ROBOT_STATE_STANDBY.name,
            ROBOT_STATS.name,
            ROBOT_COMMANDERS.name,
            ROBOT_BOX.name,
            INPUT_AUDIT.name,
        ],
        &[ROBOT_COMMAND.name, ROBOT_COMMAND_STANDBY.name],
    ),
    ports(
        "phri-dynamics",
        When::Always,
        &[INPUT_AUDIT.name],
        &[ROBOT_STATE.name],
    ),
    ports(
        "phri-dynamics",
        When::NoFlag("--standby"),
        &[DYNAMICS_RESIDUAL.name],
        &[],
    ),
    ports(
        "phri-dynamics",
        When::Flag("--standby"),
        &[DYNAMICS_RESIDUAL_STANDBY.name],
        &[DYNAMICS_RESIDUAL_CALL.name],
    ),
    ports(
        "phri-control",
        When::Always,
        &[
            CONTROL_STATUS.name,
            COLLAB_STATE.name,
            CONTROL_SSM.name,
            CONTROL_BARRIER.name,
            DYNAMICS_RESIDUAL_CALL.name,
            INPUT_AUDIT.name,
        ],
        &[
            ROBOT_STATE.name,
            DYNAMICS_RESIDUAL.name,
            DYNAMICS_RESIDUAL_STANDBY.name,
            PERCEPTION_REPULSION.name,
            PERCEPTION_SKELETON.name,
            PERCEPTION_HAND.name,
            HRI_REQUEST.name,
        ],
    ),
    ports(
        "phri-control",
        When::NoFlag("--standby"),
        &[ROBOT_COMMAND.name, CONTROL_BEHAVIOUR.name],
        &[CONTROL_STANDBY_BEHAVIOUR.name],
    ),
    ports(
        "phri-control",
        When::Flag("--standby"),
        &[ROBOT_COMMAND_STANDBY.name, CONTROL_STANDBY_BEHAVIOUR.name],
        &[CONTROL_BEHAVIOUR.name, ROBOT_STATE_STANDBY.name],
    ),
    ports(
        "phri-camera",
        When::Always,
        &[CAMERA_DEPTH.name, CAMERA_STATUS.name],
        &[],
    ),
    // the stand-in body tracker from the truth, with [skeleton] source = "sim"
    ports(
        "phri-camera",
        When::SimulatedSource,
        &[PERCEPTION_SKELETON.name],
        &[SIM_WORLD.name, FAULT_DEPTH.name],
    ),
    ports("phri-camera", When::OtherSource, &[], &[ROBOT_STATE.name]),
    ports(
        "phri-freenect",
        When::Always,
        &[CAMERA_DEPTH.name, CAMERA_STATUS.name],
        &[ROBOT_STATE.name],
    ),
    ports(
        "phri-camera-ros2",
        When::Always,
        &[CAMERA_DEPTH.name, CAMERA_STATUS.name],
        &[ROBOT_STATE.name],
    ),
    ports(
        "phri-perception",
        When::Always,
        &[PERCEPTION_DEPTH.name, PERCEPTION_HAND.name],
        &[
            ROBOT_STATE.name,
            CAMERA_DEPTH.name,
            COLLAB_STATE.name,
            PERCEPTION_SKELETON.name,
        ],
    ),
    ports(
        "phri-tracker",
        When::Always,
        &[PERCEPTION_SKELETON.name],
        &[ROBOT_STATE.name, CAMERA_DEPTH.name],
    ),
    ports(
        "phri-repulsion",
        When::Always,
        &[PERCEPTION_REPULSION.name],
        &[PERCEPTION_DEPTH.name],
    ),
    ports(
        "phri-gesture",
        When::Always,
        &[HRI_REQUEST.name],
        &[PERCEPTION_SKELETON.name],
    ),
    ports(
        "phri-mic",
        When::Always,
        &[AUDIO_MIC.name, AUDIO_MIC_STATUS.name],
        &[],
    ),
    ports("phri-mic", When::SimulatedSource, &[], &[SIM_WORLD.name]),
    ports(
        "phri-voice",
        When::Always,
        &[HRI_REQUEST.name, VOICE_UTTERANCE.name, INPUT_AUDIT.name],
        &[AUDIO_MIC.name, PERCEPTION_SKELETON.name],
    ),
    ports(
        "phri-ros2",
        When::Always,
        &[HRI_REQUEST.name, ROS2_REQUESTS.name],
        &[
            ROBOT_STATE.name,
            DYNAMICS_RESIDUAL.name,
            CONTROL_STATUS.name,
            COLLAB_STATE.name,
            PERCEPTION_DEPTH.name,
            PERCEPTION_REPULSION.name,
            PERCEPTION_SKELETON.name,
        ],
    ),
    ports(
        "phri-supervisor",
        When::Always,
        &[SUPERVISOR_HEALTH.name, SUPERVISOR_HEALTH_MORE.name],
        &[
            ROBOT_STATS.name,
            ROBOT_COMMANDERS.name,
            ROBOT_BOX.name,
            SIM_TRUTH.name,
            SIM_CONTACTS.name,
            DYNAMICS_RESIDUAL.name,
            DYNAMICS_RESIDUAL_STANDBY.name,
            CONTROL_STATUS.name,
            CONTROL_SSM.name,
            CONTROL_BARRIER.name,
            COLLAB_STATE.name,
            CAMERA_DEPTH.name,
            CAMERA_STATUS.name,
            PERCEPTION_DEPTH.name,
            PERCEPTION_REPULSION.name,
            PERCEPTION_SKELETON.name,
            HRI_REQUEST.name,
            ROS2_REQUESTS.name,
            AUDIO_MIC_STATUS.name,
            VOICE_UTTERANCE.name,
            INPUT_AUDIT.name,
        ],
    ),
    // tools that publish into the cell
    ports("phri-fault", When::Always, &[FAULT_DEPTH.name], &[]),
    ports(
        "phri-hri",
        When::Always,
        &[HRI_REQUEST.name],
        &[COLLAB_STATE.name, SUPERVISOR_HEALTH.name],
    ),
];

/// The entries of `binary`, in the table's order.
pub fn of(binary: &str) -> impl Iterator<Item = &'static Ports> + '_ {
    PORTS.iter().filter(move |p| p.binary == binary)
}

/// Every channel `binary` may publish (under any condition), in the table's order.
pub fn publishes_any(binary: &str) -> Vec<&'static str> {
    let mut v: Vec<&'static str> = Vec::new();
    for c in of(binary).flat_map(|p| p.publishes) {
        if !v.contains(c) {
            v.push(c);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_is_a_channel_and_every_channel_has_a_publisher() {
        let listed = PORTS
            .iter()
            .chain([&SUPERVISED])
            .flat_map(|p| p.publishes.iter().chain(p.reads));
        for c in listed {
            assert!(ALL.contains(c), "{c} is not in channels::ALL");
        }
        for c in ALL {
            assert!(
                PORTS.iter().any(|p| p.publishes.contains(c)),
                "no binary publishes {c}"
            );
        }
    }

    #[test]
    fn the_owners_are_the_publishers() {
        // every binary allowed to publish an owned channel publishes it here
        for (channel, binaries) in crate::owners::PUBLISHERS {
            for b in *binaries {
                assert!(
                    publishes_any(b).contains(channel),
                    "{b} owns {channel} but does not publish it"
                );
            }
        }
    }
}
