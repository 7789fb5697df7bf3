//! The paper's hierarchy of behaviours, one module per mode, and the one
//! pure function that chooses the mode of each period ([`next_mode`]).
//!
//! | mode | behaviour |
//! | --- | --- |
//! | [`sync`] | after a (re)start: hold where the arm is until the safety inputs are fresh |
//! | [`task`] | the Cartesian task; `slow` is the task under stale perception |
//! | [`reaction`] | the configured reaction to a detected collision (eqs. 9, 13, stop, float, retreat) |
//! | [`protective_stop`] | hold while a safety input is stale |
//! | [`recover`] | hold (evading under perception) until the residual stays quiet, then resume |
//! | [`restart_hold`] | a restarted controller: `protective_stop` while a tracked hand is at the robot |
//! | [`collaborate`] | `approach` the collaborative hand, `contact` (admittance on F̂), `follow` it (paper Sect. VI), `back_off` after a force limit |
//!
//! A behaviour writes the joint reference and either an acceleration for the
//! torque law or a Cartesian reference of the end effector, which the
//! avoidance stage resolves (SNS under perception, CLIK without).

pub mod arrival;
pub mod collaborate;
pub mod protective_stop;
pub mod reaction;
pub mod recover;
pub mod restart_hold;
pub mod sync;
pub mod task;

use nalgebra::Vector3;
use phri_ipc::{CollabPhase, ControlMode};

pub use restart_hold::Hold;

/// What the transition of one period looks at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Conditions {
    /// a valid residual, fresh enough
    pub residual_fresh: bool,
    /// the fresh residual reports a collision (detection, paper Sect. III)
    pub collision: bool,
    /// the fresh residual reports a contact
    pub contact: bool,
    /// perception fresh (or none configured)
    pub perception_fresh: bool,
    /// perception stale with an obstacle last seen near, or stale for too long
    pub perception_stop: bool,
    /// the reaction lasted its least time and its retreat (if any) is over
    pub reaction_done: bool,
    /// recovering: the residual stayed quiet for `resume_quiet_s` and `resume` is on
    pub may_resume: bool,
    /// the collaboration's phase (`None`: no collaboration)
    pub collab: Option<CollabPhase>,
    /// the task's segment in progress is done, or need not be (`on_request = "abort"`)
    pub segment_done: bool,
    /// collaborating: the residual the intended contact does not explain is a collision
    pub collab_collision: bool,
    /// a collaboration just ended: the collision flag waits for the residual to decay
    pub rearming: bool,
    /// a `stop` request
    pub stop_requested: bool,
    /// a restarted controller's hold: a hand at the robot, or not yet judged
    pub restart: Hold,
}

/// The mode of this period, from the mode of the last one.
///
/// - `sync` waits for fresh inputs (residual and perception), then starts the task;
///   a restarted controller also waits for its first judgement of the hands
///   and, with a hand at the robot, holds in a protective stop until it left;
/// - in every other mode a stale residual, or perception that asks for it,
///   is a protective stop;
/// - from the protective stop, fresh inputs lead to `recover`;
/// - a collision during the task or while recovering starts the reaction;
/// - the task runs as `task` with fresh perception and `slow` without;
/// - a finished reaction without contact recovers;
/// - recovering, a quiet residual resumes the task;
/// - an accepted request turns the task into the collaboration's phase
///   (approach, contact, follow, back off), at once or once the segment in
///   progress is done (`on_request`); collaborating, only what the intended
///   contact does not explain is a collision; when the collaboration ends the
///   arm recovers, with the collision flag waiting until the residual decays;
/// - a `stop` request is a protective stop.
pub fn next_mode(mode: ControlMode, c: &Conditions) -> ControlMode {
    use ControlMode::*;
    match mode {
        Sync if c.residual_fresh && c.perception_fresh => match c.restart {
            Hold::Clear => Task,
            Hold::Judging => Sync,
            Hold::HandNear => ProtectiveStop,
        },
        Sync => Sync,
        _ if !c.residual_fresh || c.perception_stop || c.stop_requested => ProtectiveStop,
        ProtectiveStop if c.restart != Hold::Clear => ProtectiveStop,
        ProtectiveStop => Recover,
        Task | Slow if c.collision => Reaction,
        Task | Slow if c.collab.is_some() && c.segment_done => collab_mode(c.collab),
        Task | Slow if c.perception_fresh => Task,
        Task | Slow => Slow,
        Approach | Contact | Follow | BackOff if c.collab_collision => Reaction,
        Approach | Contact | Follow | BackOff if c.collab.is_none() => Recover,
        Approach | Contact | Follow | BackOff => collab_mode(c.collab),
        Reaction if c.reaction_done && !c.contact => Recover,
        Reaction => Reaction,
        Recover if c.collision && !c.rearming => Reaction,
        Recover if c.may_resume && !c.contact => Task,
        Recover => Recover,
    }
}

/// The mode of a collaboration phase.
fn collab_mode(phase: Option<CollabPhase>) -> ControlMode {
    match phase {
        Some(CollabPhase::Contact) => ControlMode::Contact,
        Some(CollabPhase::Follow) => ControlMode::Follow,
        Some(CollabPhase::BackOff) => ControlMode::BackOff,
        _ => ControlMode::Approach,
    }
}

/// A Cartesian reference of the end effector, for the avoidance stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CartesianRef {
    /// desired position \[m\], base frame
    pub x_d: Vector3<f64>,
    /// desired velocity [m/s], base frame
    pub xd_d: Vector3<f64>,
    /// scale of the joint velocity bounds (slower while perception is stale)
    pub speed_scale: f64,
    /// the task's path time \[s\], to record in the retreat's history (`None`: not the task)
    pub path_time: Option<f64>,
    /// collaborating: the hand the end effector goes to \[m\], base frame;
    /// obstacles behind it (seen from the end effector) do not repel the end
    /// effector, everything nearer does, and every other control point avoids all
    pub collab_hand: Option<Vector3<f64>>,
    /// collaborating in contact with that hand: what lies about as deep as
    /// the hand is the hand (and its mask's edge), not an obstacle
    pub collab_touching: bool,
    /// the control point (index into `[[repulsion.points]]`) where the robot
    /// meets that hand: 0, the end effector, or the wrist's while the hand is
    /// nearer the wrist (then obstacles behind the hand, seen from the
    /// wrist, do not repel the wrist either)
    pub collab_point: usize,
    /// collaborating: the end effector's speed toward that hand is bounded
    /// by this [m/s] (ISO/TS 15066 Annex A's transient-contact speed for
    /// the hand; ∞: no bound)
    pub collab_speed_limit: f64,
}

/// What a behaviour leaves for the rest of the period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Behaviour {
    /// resolve this reference into the joint reference (SNS or CLIK), then track it
    Cartesian(CartesianRef),
    /// the acceleration is written; the torque law adds the bias and, for
    /// the reflex (eq. 9), subtracts the residual
    Joint {
        /// the torque law subtracts the residual (the reflex, eq. 9)
        minus_r: bool,
    },
}

#[cfg(test)]
mod tests {
    use super::*;
    use ControlMode::*;

    const FRESH: Conditions = Conditions {
        residual_fresh: true,
        collision: false,
        contact: false,
        perception_fresh: true,
        perception_stop: false,
        reaction_done: false,
        may_resume: false,
        collab: None,
        segment_done: true,
        collab_collision: false,
        rearming: false,
        stop_requested: false,
        restart: Hold::Clear,
    };

    /// `fresh` with the named conditions changed.
    fn with(changes: &[&str]) -> Conditions {
        let mut c = FRESH;
        for ch in changes {
            match *ch {
                "stale" => c.residual_fresh = false,
                "collision" => {
                    c.collision = true;
                    c.contact = true
                }
                "contact" => c.contact = true,
                "blind" => c.perception_fresh = false,
                "blind-stop" => {
                    c.perception_fresh = false;
                    c.perception_stop = true
                }
                "done" => c.reaction_done = true,
                "quiet" => c.may_resume = true,
                "approach" => c.collab = Some(CollabPhase::Approach),
                "touch" => c.collab = Some(CollabPhase::Contact),
                "follow" => c.collab = Some(CollabPhase::Follow),
                "back-off" => c.collab = Some(CollabPhase::BackOff),
                "mid-segment" => c.segment_done = false,
                "unexplained" => c.collab_collision = true,
                "rearming" => c.rearming = true,
                "stop" => c.stop_requested = true,
                "restart-judging" => c.restart = Hold::Judging,
                "restart-hand-near" => c.restart = Hold::HandNear,
                other => panic!("unknown condition {other}"),
            }
        }
        c
    }

    #[test]
    fn transition_table() {
        #[rustfmt::skip]
        let table: &[(ControlMode, &[&str], ControlMode)] = &[
            // sync waits for every input, and never stops (it holds already)
            (Sync, &[], Task),
            (Sync, &["stale"], Sync),
            (Sync, &["blind"], Sync),
            (Sync, &["blind-stop"], Sync),
            (Sync, &["collision"], Task),
            // stale safety inputs stop every other mode
            (Task, &["stale"], ProtectiveStop),
            (Slow, &["stale"], ProtectiveStop),
            (Reaction, &["stale"], ProtectiveStop),
            (Recover, &["stale"], ProtectiveStop),
            (ProtectiveStop, &["stale"], ProtectiveStop),
            (Task, &["blind-stop"], ProtectiveStop),
            (Reaction, &["blind-stop", "done"], ProtectiveStop),
            (Task, &["stale", "collision"], ProtectiveStop),
            (ProtectiveStop, &["blind-stop"], ProtectiveStop),
            // fresh again: recover first, never straight back to the task
            (ProtectiveStop, &[], Recover),
            (ProtectiveStop, &["collision"], Recover),
            (ProtectiveStop, &["blind"], Recover),
            // a restarted controller: judge the hands first; hold while one is at the robot
            (Sync, &["restart-judging"], Sync),
            (Sync, &["restart-hand-near"], ProtectiveStop),
            (Sync, &["restart-hand-near", "stale"], Sync),
            (ProtectiveStop, &["restart-hand-near"], ProtectiveStop),
            (ProtectiveStop, &["restart-judging"], ProtectiveStop),
            // the task, slowed while perception is stale
            (Task, &[], Task),
            (Task, &["blind"], Slow),
            (Slow, &["blind"], Slow),
            (Slow, &[], Task),
            (Task, &["contact"], Task),
            // detection: the reaction at once
            (Task, &["collision"], Reaction),
            (Slow, &["collision", "blind"], Reaction),
            (Recover, &["collision"], Reaction),
            (Recover, &["collision", "quiet"], Reaction),
            // the reaction ends when done and out of contact
            (Reaction, &[], Reaction),
            (Reaction, &["done", "contact"], Reaction),
            (Reaction, &["done"], Recover),
            (Reaction, &["done", "blind"], Recover),
            (Reaction, &["collision"], Reaction),
            // resume after a quiet residual
            (Recover, &[], Recover),
            (Recover, &["contact"], Recover),
            (Recover, &["quiet"], Task),
            (Recover, &["quiet", "blind"], Task),
            // collaboration: an accepted request turns the task into its phase
            (Task, &["approach"], Approach),
            (Slow, &["approach", "blind"], Approach),
            // on_request = "complete": the segment in progress ends first
            (Task, &["approach", "mid-segment"], Task),
            (Slow, &["approach", "mid-segment", "blind"], Slow),
            (Task, &["approach", "mid-segment", "collision"], Reaction),
            (Task, &["approach", "collision"], Reaction),
            (Approach, &["touch"], Contact),
            (Contact, &["follow"], Follow),
            (Follow, &["touch"], Contact),
            // a force limit: back off, then recover; a collision still reacts
            (Contact, &["back-off"], BackOff),
            (Approach, &["back-off"], BackOff),
            (BackOff, &["back-off"], BackOff),
            (BackOff, &[], Recover),
            (BackOff, &["back-off", "unexplained"], Reaction),
            (BackOff, &["back-off", "stale"], ProtectiveStop),
            // collaborating, the intended contact is no collision ...
            (Contact, &["touch", "collision"], Contact),
            // ... what it does not explain is
            (Contact, &["touch", "unexplained"], Reaction),
            (Approach, &["approach", "unexplained"], Reaction),
            // stale inputs and stop requests stop it
            (Contact, &["touch", "stale"], ProtectiveStop),
            (Follow, &["follow", "blind-stop"], ProtectiveStop),
            (Approach, &["approach", "stop"], ProtectiveStop),
            (Task, &["stop"], ProtectiveStop),
            // it ends into recover, where detection re-arms once the residual decayed
            (Contact, &["collision"], Recover),
            (Follow, &[], Recover),
            (Recover, &["collision", "rearming"], Recover),
            (Recover, &["collision", "rearming", "quiet"], Recover),
            (Recover, &["quiet", "rearming"], Task),
            // a request elsewhere changes nothing
            (Reaction, &["approach"], Reaction),
            (Recover, &["approach"], Recover),
            (ProtectiveStop, &["approach"], Recover),
        ];
        for (from, conditions, to) in table {
            assert_eq!(
                next_mode(*from, &with(conditions)),
                *to,
                "{from} with {conditions:?}"
            );
        }
    }

    #[test]
    fn every_mode_stops_on_a_stale_residual_but_sync() {
        for &m in ControlMode::ALL {
            let next = next_mode(m, &with(&["stale"]));
            let expected = if m == Sync { Sync } else { ProtectiveStop };
            assert_eq!(next, expected, "{m}");
        }
    }
}
