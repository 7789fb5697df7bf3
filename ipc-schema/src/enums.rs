//! Enumerations carried as `u32` on the wire: each a `#[repr(u32)]` enum with
//! `TryFrom<u32>` (an unknown value is an error, never a guess) and a stable
//! snake_case name for command lines, configuration and JSON.

use serde::{Deserialize, Serialize};

/// A `u32` on the wire that names no variant of `what`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: unknown value {value}")]
pub struct UnknownValue {
    /// what was read (`"control mode"`)
    pub what: &'static str,
    /// the value received
    pub value: u32,
}

/// A name that names no variant of `what`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: unknown name '{name}' (expected one of: {expected})")]
pub struct UnknownName {
    /// what was named (`"reaction"`)
    pub what: &'static str,
    /// the name given
    pub name: String,
    /// the names accepted, comma separated
    pub expected: String,
}

macro_rules! wire_enum {
    (
        $(#[$meta:meta])*
        $name:ident, $what:literal {
            $( $(#[$vmeta:meta])* $variant:ident = $value:literal => $text:literal, )+
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
        #[serde(rename_all = "snake_case")]
        #[repr(u32)]
        pub enum $name {
            $( $(#[$vmeta])* $variant = $value, )+
        }

        impl $name {
            /// Every variant, in wire order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];

            /// Stable snake_case name.
            pub fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $text,)+
                }
            }

            /// The variant called `name`.
            pub fn from_name(name: &str) -> Result<$name, UnknownName> {
                Self::ALL.iter().copied().find(|v| v.name() == name).ok_or_else(|| UnknownName {
                    what: $what,
                    name: name.to_string(),
                    expected: Self::ALL.iter().map(|v| v.name()).collect::<Vec<_>>().join(", "),
                })
            }

            /// The name of wire value `v`, or `"unknown"`.
            pub fn name_of(v: u32) -> &'static str {
                $name::try_from(v).map_or("unknown", $name::name)
            }
        }

        impl TryFrom<u32> for $name {
            type Error = UnknownValue;
            fn try_from(v: u32) -> Result<$name, UnknownValue> {
                match v {
                    $($value => Ok($name::$variant),)+
                    _ => Err(UnknownValue { what: $what, value: v }),
                }
            }
        }

        impl From<$name> for u32 {
            fn from(v: $name) -> u32 {
                v as u32
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $name {
            type Err = UnknownName;
            fn from_str(s: &str) -> Result<$name, UnknownName> {
                $name::from_name(s)
            }
        }
    };
}

wire_enum! {
    /// The controller's mode ([`crate::TorqueCommand::mode`], [`crate::ControlStatus::mode`]).
    ControlMode, "control mode" {
        /// waiting for the first fresh inputs, re-syncing to the measured state
        Sync = 0 => "sync",
        /// executing the task
        Task = 1 => "task",
        /// reacting to a detected collision
        Reaction = 2 => "reaction",
        /// holding still because a safety input is stale
        ProtectiveStop = 3 => "protective_stop",
        /// reaction over, waiting for the residual to settle before resuming
        Recover = 4 => "recover",
        /// slowed down because perception is stale
        Slow = 5 => "slow",
        /// collaboration: the end effector moves to the collaborative hand
        Approach = 6 => "approach",
        /// collaboration: in contact with the hand, compliant to the estimated force
        Contact = 7 => "contact",
        /// collaboration: the hand moved away, the end effector follows it
        Follow = 8 => "follow",
        /// collaboration: a force limit was passed; the end effector backs off
        BackOff = 9 => "back_off",
    }
}

wire_enum! {
    /// Reaction strategies of the paper's portfolio (Sect. IV, Fig. 2)
    /// ([`crate::ControlStatus::reaction`], `[control] reaction`).
    Reaction, "reaction" {
        /// τ = M (K_R r − D_R q̇) + C q̇ + g − r (eq. 9): the arm yields along τ_ext
        Reflex = 0 => "reflex",
        /// q̇_r = K_Q r (eq. 13) tracked by the joint loop
        Admittance = 1 => "admittance",
        /// freeze the reference where the collision was detected
        Stop = 2 => "stop",
        /// τ = g(q) (+ light damping): zero-gravity
        Float = 3 => "float",
        /// time-scaled retreat back along the path just travelled
        Retreat = 4 => "retreat",
    }
}

wire_enum! {
    /// What the simulated camera does to its next frames ([`crate::DepthFault::kind`]).
    DepthFaultKind, "depth fault" {
        /// flying pixels: 2 % of the pixels get random depths (0.5-4 m)
        Noise = 1 => "noise",
        /// every pixel 0 (no return): a blind frame
        Zeros = 2 => "zeros",
        /// the header's image size disagrees with the payload
        Size = 3 => "size",
        /// capture time one second in the past
        Stale = 4 => "stale",
        /// publish every frame `delay_ms` late for `duration_s`
        Delay = 5 => "delay",
    }
}

wire_enum! {
    /// Who asked ([`crate::HriRequest::source`]).
    RequestSource, "request source" {
        /// a gesture recognised on the skeleton (`phri-gesture`)
        Gesture = 1 => "gesture",
        /// a voice command (`phri-voice`)
        Voice = 2 => "voice",
        /// a command line or script (`phri-hri`)
        Cli = 3 => "cli",
        /// a ROS 2 node, on `/phri/request` (`phri-ros2`)
        Ros2 = 4 => "ros2",
    }
}

wire_enum! {
    /// What is asked ([`crate::HriRequest::kind`]).
    RequestKind, "request kind" {
        /// begin collaborating (with the part named, or the one last used)
        Begin = 1 => "begin",
        /// end the collaboration; the task resumes
        End = 2 => "end",
        /// a protective stop (complements, never replaces, the emergency stop)
        Stop = 3 => "stop",
        /// collaborate with the part named: come to it and follow it
        Follow = 4 => "follow",
        /// the operator resumes a cell its dead-man stopped (for the
        /// supervisor: the controller ignores it)
        Resume = 5 => "resume",
    }
}

wire_enum! {
    /// A collaborative human part ([`crate::HriRequest::part`], [`crate::CollabState::human_part`]).
    CollabPart, "collaborative part" {
        /// none named
        None = 0 => "none",
        /// the right hand
        RightHand = 1 => "right_hand",
        /// the left hand
        LeftHand = 2 => "left_hand",
    }
}

impl CollabPart {
    /// The skeleton joint of the part (`None`: no part).
    pub fn joint(self) -> Option<SkeletonJoint> {
        match self {
            CollabPart::None => None,
            CollabPart::RightHand => Some(SkeletonJoint::RightHand),
            CollabPart::LeftHand => Some(SkeletonJoint::LeftHand),
        }
    }

    /// The body part of the scripted person's capsules.
    pub fn body_part(self) -> Option<BodyPart> {
        match self {
            CollabPart::None => None,
            CollabPart::RightHand => Some(BodyPart::HandRight),
            CollabPart::LeftHand => Some(BodyPart::HandLeft),
        }
    }
}

wire_enum! {
    /// The collaboration's phase ([`crate::CollabState::phase`]).
    CollabPhase, "collaboration phase" {
        /// no collaboration: the task (or a reaction, a stop) runs
        Idle = 0 => "idle",
        /// the end effector moves to the collaborative hand
        Approach = 1 => "approach",
        /// in contact: compliant to the estimated force
        Contact = 2 => "contact",
        /// the hand moved away: the end effector follows it
        Follow = 3 => "follow",
        /// a force limit was passed: the end effector backs off, then idle
        BackOff = 4 => "back_off",
    }
}

wire_enum! {
    /// A voice command ([`crate::Utterance::intent`]): the grammar's commands.
    VoiceIntent, "voice intent" {
        /// no command recognised
        None = 0 => "none",
        /// "follow \[the\] right hand"
        FollowRightHand = 1 => "follow_right_hand",
        /// "follow \[the\] left hand"
        FollowLeftHand = 2 => "follow_left_hand",
        /// "begin collaboration"
        Begin = 3 => "begin",
        /// "end collaboration"
        End = 4 => "end",
        /// "stop": a protective stop
        Stop = 5 => "stop",
    }
}

impl VoiceIntent {
    /// The request the command makes: what and which part (none for `None`).
    pub fn request(self) -> Option<(RequestKind, CollabPart)> {
        match self {
            VoiceIntent::None => None,
            VoiceIntent::FollowRightHand => Some((RequestKind::Follow, CollabPart::RightHand)),
            VoiceIntent::FollowLeftHand => Some((RequestKind::Follow, CollabPart::LeftHand)),
            VoiceIntent::Begin => Some((RequestKind::Begin, CollabPart::None)),
            VoiceIntent::End => Some((RequestKind::End, CollabPart::None)),
            VoiceIntent::Stop => Some((RequestKind::Stop, CollabPart::None)),
        }
    }
}

wire_enum! {
    /// What became of an utterance ([`crate::Utterance::verdict`]).
    VoiceVerdict, "voice verdict" {
        /// a request was published
        Accepted = 1 => "accepted",
        /// refused: the decoder matched no command
        NoMatch = 2 => "no_match",
        /// refused: a command matched, but its score is below `[voice] min_score`
        LowScore = 3 => "low_score",
        /// refused: speech shorter than `[voice] min_utterance_s`
        TooShort = 4 => "too_short",
        /// refused: speech longer than `[voice] max_utterance_s`
        TooLong = 5 => "too_long",
        /// refused: `follow` for a hand the body tracker does not see
        HandNotTracked = 6 => "hand_not_tracked",
        /// refused before decoding: no voicing (noise, a rattle, a clatter),
        /// `[voice] min_voiced_s`
        NotSpeech = 7 => "not_speech",
    }
}

wire_enum! {
    /// Why the collaboration last changed, or why a request was refused
    /// ([`crate::CollabState::reason`], [`crate::CollabState::request_reason`]).
    CollabReason, "collaboration reason" {
        /// none yet: no change of phase, no request answered
        None = 0 => "none",
        /// a request was accepted
        Accepted = 1 => "accepted",
        /// refused: the named hand is not tracked with good confidence
        HandNotTracked = 2 => "hand_not_tracked",
        /// refused: the robot is reacting to a collision
        Reacting = 3 => "reacting",
        /// refused: the robot is in a protective stop (a safety input is stale)
        ProtectiveStop = 4 => "protective_stop",
        /// refused: no part named and none to continue with
        NoPart = 5 => "no_part",
        /// refused: there is no collaboration to end
        NotCollaborating = 6 => "not_collaborating",
        /// the end effector touched the hand
        ContactMade = 7 => "contact_made",
        /// the hand moved away from the end effector
        HandMovedAway = 8 => "hand_moved_away",
        /// ended: a push on the wrist
        WristPush = 9 => "wrist_push",
        /// ended: an `end` request
        EndRequest = 10 => "end_request",
        /// ended: a `stop` request (protective stop)
        StopRequest = 11 => "stop_request",
        /// ended: the hand was not seen for too long
        HandLost = 12 => "hand_lost",
        /// ended: the estimated contact force passed its limit; the arm backs off
        ForceLimit = 13 => "force_limit",
        /// ended: a collision elsewhere was detected (the unexplained residual)
        Collision = 14 => "collision",
        /// ended: a safety input went stale
        Stale = 15 => "stale",
        /// ended: the controller restarted (it crashed or froze); the new
        /// one holds until no hand is at the end effector
        ControllerRestart = 16 => "controller_restart",
    }
}

wire_enum! {
    /// The 15 joints of a tracked person ([`crate::TrackedPerson::joints`]),
    /// in OpenNI/NiTE's order.
    SkeletonJoint, "skeleton joint" {
        /// the head
        Head = 0 => "head",
        /// the neck
        Neck = 1 => "neck",
        /// the torso (centre of the trunk)
        Torso = 2 => "torso",
        /// the left shoulder
        LeftShoulder = 3 => "left_shoulder",
        /// the right shoulder
        RightShoulder = 4 => "right_shoulder",
        /// the left elbow
        LeftElbow = 5 => "left_elbow",
        /// the right elbow
        RightElbow = 6 => "right_elbow",
        /// the left hand
        LeftHand = 7 => "left_hand",
        /// the right hand
        RightHand = 8 => "right_hand",
        /// the left hip
        LeftHip = 9 => "left_hip",
        /// the right hip
        RightHip = 10 => "right_hip",
        /// the left knee
        LeftKnee = 11 => "left_knee",
        /// the right knee
        RightKnee = 12 => "right_knee",
        /// the left foot
        LeftFoot = 13 => "left_foot",
        /// the right foot
        RightFoot = 14 => "right_foot",
    }
}

wire_enum! {
    /// What a [`crate::ContactEvent`] reports of a contact episode.
    ContactPhase, "contact phase" {
        /// the contact began
        Begin = 1 => "begin",
        /// still in contact (sent every 100 ms with the peak so far)
        Update = 2 => "update",
        /// the contact ended (with its peak force)
        End = 3 => "end",
    }
}

wire_enum! {
    /// A human body region, numbered as in [`crate::ContactTruth::human_part`]
    /// and [`crate::WorldCapsule::part`]; names as written in scenario files.
    BodyPart, "body part" {
        /// head
        Head = 0 => "head",
        /// torso
        Torso = 1 => "torso",
        /// pelvis
        Pelvis = 2 => "pelvis",
        /// left upper arm
        UpperArmLeft = 3 => "upper_arm_left",
        /// right upper arm
        UpperArmRight = 4 => "upper_arm_right",
        /// left forearm
        ForearmLeft = 5 => "forearm_left",
        /// right forearm
        ForearmRight = 6 => "forearm_right",
        /// left hand
        HandLeft = 7 => "hand_left",
        /// right hand
        HandRight = 8 => "hand_right",
        /// left thigh
        ThighLeft = 9 => "thigh_left",
        /// right thigh
        ThighRight = 10 => "thigh_right",
        /// left shin
        ShinLeft = 11 => "shin_left",
        /// right shin
        ShinRight = 12 => "shin_right",
    }
}

impl BodyPart {
    /// Name of wire index `i` (−1 or out of range: `"unknown"`).
    pub fn name_of_index(i: i32) -> &'static str {
        u32::try_from(i).map_or("unknown", BodyPart::name_of)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_values_round_trip_and_unknown_values_are_errors() {
        for m in ControlMode::ALL {
            assert_eq!(ControlMode::try_from(*m as u32), Ok(*m));
            assert_eq!(ControlMode::from_name(m.name()), Ok(*m));
        }
        assert!(ControlMode::try_from(99).is_err());
        assert_eq!(ControlMode::name_of(99), "unknown");
        assert_eq!(Reaction::try_from(4), Ok(Reaction::Retreat));
        assert!(Reaction::from_name("explode").is_err());
        assert_eq!(BodyPart::ALL.len(), 13);
        for (i, p) in BodyPart::ALL.iter().enumerate() {
            assert_eq!(*p as usize, i, "body parts are numbered in order");
        }
        assert_eq!(
            DepthFaultKind::from_name("delay"),
            Ok(DepthFaultKind::Delay)
        );
        assert!(DepthFaultKind::try_from(0).is_err());
    }

    #[test]
    fn serde_uses_the_snake_case_names() {
        #[derive(Deserialize)]
        struct T {
            r: Reaction,
        }
        let t: T = toml::from_str("r = \"admittance\"").unwrap();
        assert_eq!(t.r, Reaction::Admittance);
        assert!(toml::from_str::<T>("r = \"explode\"").is_err());
    }
}
