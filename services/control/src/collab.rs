//! The collaboration's phases (paper Sect. VI) as a pure machine: requests
//! in, the phase, the collaborative part and the reason of every change out.
//! The controller feeds it what it measured in the period ([`Observation`])
//! and runs the behaviour of the phase it returns; nothing here moves the arm.
//!
//! | from | to | when |
//! | --- | --- | --- |
//! | idle | approach | a `begin`/`follow` request for a well-tracked hand, the robot neither reacting nor stopped |
//! | approach | contact | surface gap ≤ `contact_gap_m`, or ‖F̂‖ ≥ `contact_force_n` within [`TOUCHING_GAP_M`], or within [`FORCE_TOUCH_GAP_M`] for [`FORCE_TOUCH_S`] |
//! | contact | follow | the hand `follow_gap_m` farther than where it last pressed (‖F̂‖ ≥ `contact_force_n`) and ‖F̂‖ below `release_force_n`, both for `release_s` without a break |
//! | follow | contact | as approach → contact |
//! | approach, contact, follow | back off | ‖F̂‖ above the force limit |
//! | back off | idle | backed off `back_off_m` (or given up after [`BACK_OFF_MAX_S`]) |
//! | any | idle | a wrist push, an `end`/`stop` request, the hand unseen for `hand_lost_s` (not backing off), a collision elsewhere, a stale safety input |
//!
//! Contact holds by hysteresis: it begins on an overlap or a force and ends
//! only when the hand has gone, farther and without force, for a while. A
//! held hand's contact bounces apart for tens of milliseconds (on touching,
//! as the person presses) and depth places the hand only to centimetres:
//! neither is the hand moving away, and neither ends the contact.

use phri_config::CollaborationConfig;
use phri_ipc::{CollabPart, CollabPhase, CollabReason, HriRequest, RequestKind};

use crate::snapshot::snapshot_fields;

/// A force counts as the touch only with the hand's surface this near \[m\]:
/// depth places the hand to a few centimetres, and the residual of an arm
/// approaching at `approach_speed` reads 4-5 N by itself (the FR3's, 22 cm
/// from the hand on the depth trackers, was taken for a touch that never
/// came, and the contact phase held there).
pub const FORCE_TOUCH_GAP_M: f64 = 0.1;

/// Least time in contact before the hand counts as moved away \[s\]: a
/// contact is a touch, not one noisy sample.
const MIN_CONTACT_S: f64 = 0.3;

/// Depth places a touching hand this near the surface \[m\]: a force with
/// the hand nearer counts as the touch at once.
pub const TOUCHING_GAP_M: f64 = 0.06;

/// A force with the hand farther than [`TOUCHING_GAP_M`] (but within
/// [`FORCE_TOUCH_GAP_M`]) counts as the touch once it has lasted this long
/// \[s\]: an arm braking near a hand that depth places 10 cm off for a
/// moment (a hand moving, seen by a camera that sees its edge) reads a few
/// newtons for a few milliseconds; a hand that is touched keeps pressing.
pub const FORCE_TOUCH_S: f64 = 0.03;

/// Backing off ends after this long even when the arm could not get as far
/// as `back_off_m` (blocked by avoidance or a joint limit) \[s\].
pub const BACK_OFF_MAX_S: f64 = 2.0;

/// What the controller measured in this period.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Observation {
    /// controller time \[s\]
    pub t: f64,
    /// the collaborative hand was seen in this period (a fresh observation)
    pub hand_seen: bool,
    /// surface gap between the robot and the hand \[m\]: to the nearer of
    /// the collaborative robot part and the wrist (centre distance less both
    /// radii; negative: they overlap)
    pub gap_m: f64,
    /// ‖F̂‖ at the collaborative contact \[N\]
    pub force_n: f64,
    /// the residual has the pattern of a push on the wrist, confirmed by a
    /// human part other than the collaborative hand seen near the wrist, for
    /// `wrist_hold_s`
    pub wrist_push: bool,
    /// the residual the intended contact does not explain crosses the
    /// collision thresholds
    pub collision: bool,
    /// another part of the person (the collaborative hand is masked from
    /// depth) is seen touching the robot: a force is then no touch of the
    /// hand
    pub other_touch: bool,
    /// a safety input (residual, perception) is stale
    pub stale: bool,
    /// backing off: the end effector got `back_off_m` away
    pub backed_off: bool,
}

/// Where the rest of the robot stands when a request arrives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RobotState {
    /// the task (or holding): a collaboration may start
    Available,
    /// reacting to a collision or recovering from it
    Reacting,
    /// a protective stop: a safety input is stale
    Stopped,
}

/// The answer to one request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Answer {
    /// the request was accepted
    pub accepted: bool,
    /// why it was refused, or what the accepted request did
    pub reason: CollabReason,
}

/// The machine's state.
#[derive(Clone, Debug)]
pub struct CollabMachine {
    cfg: CollaborationConfig,
    phase: CollabPhase,
    reason: CollabReason,
    part: CollabPart,
    /// the part of the last collaboration, for `begin` without a part
    last_part: CollabPart,
    person: u32,
    /// last time the hand was seen \[s\]
    hand_seen_t: f64,
    /// the phase changed at \[s\]
    since: f64,
    /// in contact: the hand has been away and the force low since \[s\]
    apart_since: Option<f64>,
    /// in contact: the gap seen while the force last said the hand touches
    /// \[m\] (depth places a touching hand 0-6 cm off the surface, by the
    /// view): the hand has gone `follow_gap_m` beyond it
    touch_gap: Option<f64>,
    /// following: the gap seen while the hand last pressed \[m\] (depth's
    /// error of the hand then, which mostly persists into the follow)
    follow_touch_gap: Option<f64>,
    /// a `stop` request asked for a protective stop
    stop_requested: bool,
    /// a force near the hand has said it touches since \[s\] ([`FORCE_TOUCH_S`])
    force_touch_since: Option<f64>,
}

snapshot_fields!(Answer { accepted, reason });

impl Default for Answer {
    fn default() -> Answer {
        Answer {
            accepted: false,
            reason: CollabReason::None,
        }
    }
}

// the configuration is not state
snapshot_fields!(CollabMachine {
    phase,
    reason,
    part,
    last_part,
    person,
    hand_seen_t,
    since,
    apart_since,
    touch_gap,
    follow_touch_gap,
    stop_requested,
    force_touch_since
});

impl CollabMachine {
    /// An idle machine with the `[collaboration]` settings `cfg`.
    pub fn new(cfg: &CollaborationConfig) -> CollabMachine {
        CollabMachine {
            cfg: cfg.clone(),
            phase: CollabPhase::Idle,
            reason: CollabReason::None,
            part: CollabPart::None,
            last_part: CollabPart::None,
            person: u32::MAX,
            hand_seen_t: 0.0,
            since: 0.0,
            apart_since: None,
            touch_gap: None,
            follow_touch_gap: None,
            stop_requested: false,
            force_touch_since: None,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> CollabPhase {
        self.phase
    }

    /// Following: the gap depth gave while the hand last pressed \[m\]
    /// (`None`: not following, or no force was felt at the touch).
    pub fn follow_touch_gap(&self) -> Option<f64> {
        self.follow_touch_gap
            .filter(|_| self.phase == CollabPhase::Follow)
    }

    /// `[collaboration]`.
    pub fn config(&self) -> &CollaborationConfig {
        &self.cfg
    }

    /// Why the phase last changed.
    pub fn reason(&self) -> CollabReason {
        self.reason
    }

    /// The collaborative human part (`None` while idle).
    pub fn part(&self) -> CollabPart {
        self.part
    }

    /// The tracker's id of the collaborating person (`u32::MAX`: whoever shows the part).
    pub fn person(&self) -> u32 {
        self.person
    }

    /// Collaborating: approach, contact, follow or backing off.
    pub fn active(&self) -> bool {
        self.phase != CollabPhase::Idle
    }

    /// Time in the current phase \[s\] at controller time `t`.
    pub fn in_phase_s(&self, t: f64) -> f64 {
        (t - self.since).max(0.0)
    }

    /// A `stop` request was accepted since the last call (the controller
    /// enters its protective stop); reading clears it.
    pub fn take_stop(&mut self) -> bool {
        std::mem::take(&mut self.stop_requested)
    }

    /// The largest ‖F̂‖ allowed on the collaborative part \[N\]: the configured
    /// fraction of its body region's ISO/TS 15066 quasi-static limit (a hand).
    pub fn force_limit_n(&self) -> f64 {
        self.cfg.force_limit_fraction * self.cfg.iso_hand_n
    }

    fn enter(&mut self, phase: CollabPhase, reason: CollabReason, t: f64) {
        if phase == CollabPhase::Idle && self.part != CollabPart::None {
            self.last_part = self.part;
            self.part = CollabPart::None;
            self.person = u32::MAX;
        }
        self.follow_touch_gap = match phase {
            CollabPhase::Follow => self.touch_gap.or(self.follow_touch_gap),
            CollabPhase::Contact => self.follow_touch_gap,
            _ => None,
        };
        self.phase = phase;
        self.reason = reason;
        self.since = t;
        self.apart_since = None;
        self.touch_gap = None;
    }

    /// The controller restarted at `t`: whatever collaboration its
    /// predecessor ran is over (`controller_restart`); nothing of it carries over.
    pub fn restarted(&mut self, t: f64) {
        self.enter(CollabPhase::Idle, CollabReason::ControllerRestart, t);
    }

    /// Answer `req` at controller time `t`; `hand_confidence` is the
    /// tracker's confidence of the hand the request names (or of the last
    /// part for `begin` without one), 0 when not tracked.
    pub fn request(
        &mut self,
        req: &HriRequest,
        robot: RobotState,
        hand_confidence: f64,
        t: f64,
    ) -> Answer {
        let refuse = |reason| Answer {
            accepted: false,
            reason,
        };
        let Ok(kind) = RequestKind::try_from(req.kind) else {
            return refuse(CollabReason::None);
        };
        let named = CollabPart::try_from(req.part).unwrap_or(CollabPart::None);
        match kind {
            // the supervisor's (a cell its dead-man stopped), not the controller's
            RequestKind::Resume => refuse(CollabReason::None),
            RequestKind::Stop => {
                if self.active() {
                    self.enter(CollabPhase::Idle, CollabReason::StopRequest, t);
                }
                self.stop_requested = true;
                Answer {
                    accepted: true,
                    reason: CollabReason::StopRequest,
                }
            }
            RequestKind::End => {
                if !self.active() {
                    return refuse(CollabReason::NotCollaborating);
                }
                self.enter(CollabPhase::Idle, CollabReason::EndRequest, t);
                Answer {
                    accepted: true,
                    reason: CollabReason::EndRequest,
                }
            }
            RequestKind::Begin | RequestKind::Follow => {
                let part = match named {
                    CollabPart::None if self.active() => self.part,
                    CollabPart::None => self.last_part,
                    p => p,
                };
                if part == CollabPart::None {
                    return refuse(CollabReason::NoPart);
                }
                match robot {
                    RobotState::Reacting => return refuse(CollabReason::Reacting),
                    RobotState::Stopped => return refuse(CollabReason::ProtectiveStop),
                    RobotState::Available => {}
                }
                if !(hand_confidence >= self.cfg.min_hand_confidence) {
                    return refuse(CollabReason::HandNotTracked);
                }
                self.part = part;
                self.person = req.person;
                self.hand_seen_t = t;
                if !self.active() {
                    self.enter(CollabPhase::Approach, CollabReason::Accepted, t);
                }
                Answer {
                    accepted: true,
                    reason: CollabReason::Accepted,
                }
            }
        }
    }

    /// One period: the phase to run, after the changes `obs` calls for.
    pub fn step(&mut self, obs: &Observation) -> CollabPhase {
        if !self.active() {
            return self.phase;
        }
        if obs.hand_seen {
            self.hand_seen_t = obs.t;
        }
        // the ends, most severe first
        let backing_off = self.phase == CollabPhase::BackOff;
        let end = if obs.stale {
            Some(CollabReason::Stale)
        } else if obs.collision {
            Some(CollabReason::Collision)
        } else if backing_off {
            (obs.backed_off || self.in_phase_s(obs.t) >= BACK_OFF_MAX_S)
                .then_some(CollabReason::ForceLimit)
        } else if obs.force_n > self.force_limit_n() {
            // stop, and back off before the collaboration ends
            self.enter(CollabPhase::BackOff, CollabReason::ForceLimit, obs.t);
            return self.phase;
        } else if obs.wrist_push {
            Some(CollabReason::WristPush)
        } else if obs.t - self.hand_seen_t > self.cfg.hand_lost_s {
            Some(CollabReason::HandLost)
        } else {
            None
        };
        if let Some(reason) = end {
            self.enter(CollabPhase::Idle, reason, obs.t);
            return self.phase;
        }
        // a force alone is no contact far from the hand (the residual of a
        // moving arm is never quite zero), nor while another part of the
        // person touches the robot (a hand crossing the approach: pressing
        // it with the contact's hold would crush it)
        let pressed = obs.force_n >= self.cfg.contact_force_n
            && obs.gap_m <= FORCE_TOUCH_GAP_M.min(self.cfg.slow_down_m)
            && !obs.other_touch;
        self.force_touch_since = match pressed {
            true => self.force_touch_since.or(Some(obs.t)),
            false => None,
        };
        let pressing = pressed
            && (obs.gap_m <= TOUCHING_GAP_M
                || self
                    .force_touch_since
                    .is_some_and(|t0| obs.t - t0 >= FORCE_TOUCH_S - 1e-9));
        let touching = obs.gap_m <= self.cfg.contact_gap_m || pressing;
        match self.phase {
            CollabPhase::Approach | CollabPhase::Follow if touching => {
                self.enter(CollabPhase::Contact, CollabReason::ContactMade, obs.t)
            }
            CollabPhase::Contact => {
                if obs.force_n >= self.cfg.contact_force_n && obs.gap_m.is_finite() {
                    self.touch_gap = Some(obs.gap_m);
                }
                // the hand has gone: away from where it touched and without
                // force, for `release_s`
                let touched_at = self.touch_gap.unwrap_or(0.0).max(0.0);
                let apart = obs.gap_m > touched_at + self.cfg.follow_gap_m
                    && obs.force_n < self.cfg.release_force_n;
                let since = match apart {
                    true => *self.apart_since.get_or_insert(obs.t),
                    false => {
                        self.apart_since = None;
                        obs.t
                    }
                };
                if apart
                    && obs.t - since >= self.cfg.release_s
                    && obs.t - self.since >= MIN_CONTACT_S
                {
                    self.enter(CollabPhase::Follow, CollabReason::HandMovedAway, obs.t)
                }
            }
            _ => {}
        }
        self.phase
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::Config;
    use phri_ipc::{RequestSource, Zeroed};

    fn req(kind: RequestKind, part: CollabPart) -> HriRequest {
        let mut r = HriRequest::zeroed();
        r.source = RequestSource::Cli as u32;
        r.kind = kind as u32;
        r.part = part as u32;
        r.person = 1;
        r
    }

    fn machine() -> CollabMachine {
        CollabMachine::new(&Config::defaults().collaboration)
    }

    /// A machine that accepted `follow left_hand` at 0.5 s: approaching.
    fn approaching_left_hand() -> CollabMachine {
        let mut m = machine();
        let a = m.request(
            &req(RequestKind::Follow, CollabPart::LeftHand),
            RobotState::Available,
            0.9,
            0.5,
        );
        assert!(a.accepted && m.phase() == CollabPhase::Approach);
        m
    }

    #[test]
    fn a_force_while_another_part_touches_the_robot_is_no_contact() {
        let mut m = approaching_left_hand();
        let mut obs = seen(1.0, 0.1, 10.0);
        obs.other_touch = true;
        assert_eq!(m.step(&obs), CollabPhase::Approach);
        // the hand itself at the surface still is
        obs.gap_m = m.cfg.contact_gap_m;
        assert_eq!(m.step(&obs), CollabPhase::Contact);
        // and the same force with nothing else at the robot
        let mut m = approaching_left_hand();
        assert_eq!(press(&mut m, 1.0, 0.1, 10.0), CollabPhase::Contact);
    }

    /// The hand pressed `force_n` at `gap_m` from `t` for [`FORCE_TOUCH_S`],
    /// a step every millisecond: the phase after it.
    fn press(m: &mut CollabMachine, t: f64, gap_m: f64, force_n: f64) -> CollabPhase {
        let steps = (FORCE_TOUCH_S * 1e3).round() as usize;
        for k in 0..steps {
            let phase = m.step(&seen(t + k as f64 * 1e-3, gap_m, force_n));
            assert_ne!(phase, CollabPhase::Contact, "a touch after {k} ms");
        }
        m.step(&seen(t + steps as f64 * 1e-3, gap_m, force_n))
    }

    #[test]
    fn a_force_near_the_hand_for_a_moment_is_no_touch() {
        // an arm braking near a hand depth places 9 cm off for a moment
        let mut m = approaching_left_hand();
        let mut t = 1.0;
        for k in 0..195 {
            t += 1e-3;
            // 5 ms of every 20 over contact_force_n, the last of them at 1 N
            let force = if k % 20 < 15 { 1.0 } else { 6.0 };
            assert_eq!(m.step(&seen(t, 0.09, force)), CollabPhase::Approach);
        }
        // the hand pressed: a touch once the force has lasted
        assert_eq!(press(&mut m, t + 1e-3, 0.09, 6.0), CollabPhase::Contact);
        // a force with the hand where depth places a touching one: at once
        let mut m = approaching_left_hand();
        assert_eq!(
            m.step(&seen(1.0, TOUCHING_GAP_M, 6.0)),
            CollabPhase::Contact
        );
        // the surfaces overlapping are a touch at once, force or not
        let mut m = approaching_left_hand();
        let gap = m.cfg.contact_gap_m;
        assert_eq!(m.step(&seen(1.0, gap, 0.0)), CollabPhase::Contact);
    }

    fn seen(t: f64, gap_m: f64, force_n: f64) -> Observation {
        Observation {
            t,
            hand_seen: true,
            gap_m,
            force_n,
            ..Default::default()
        }
    }

    #[test]
    fn requests_are_accepted_only_for_a_tracked_hand_of_an_available_robot() {
        let mut m = machine();
        let follow = req(RequestKind::Follow, CollabPart::RightHand);
        for (robot, conf, reason) in [
            (RobotState::Reacting, 1.0, CollabReason::Reacting),
            (RobotState::Stopped, 1.0, CollabReason::ProtectiveStop),
            (RobotState::Available, 0.2, CollabReason::HandNotTracked),
            (
                RobotState::Available,
                f64::NAN,
                CollabReason::HandNotTracked,
            ),
        ] {
            let a = m.request(&follow, robot, conf, 0.0);
            assert_eq!((a.accepted, a.reason), (false, reason));
            assert_eq!(m.phase(), CollabPhase::Idle);
        }
        // nothing to end, no part to begin with
        assert_eq!(
            m.request(
                &req(RequestKind::End, CollabPart::None),
                RobotState::Available,
                1.0,
                0.0
            )
            .reason,
            CollabReason::NotCollaborating
        );
        assert_eq!(
            m.request(
                &req(RequestKind::Begin, CollabPart::None),
                RobotState::Available,
                1.0,
                0.0
            )
            .reason,
            CollabReason::NoPart
        );
        // an unknown kind on the wire is refused, never guessed
        let mut bad = follow;
        bad.kind = 99;
        assert!(!m.request(&bad, RobotState::Available, 1.0, 0.0).accepted);
        let a = m.request(&follow, RobotState::Available, 0.9, 1.0);
        assert!(a.accepted);
        assert_eq!(
            (m.phase(), m.part(), m.person()),
            (CollabPhase::Approach, CollabPart::RightHand, 1)
        );
    }

    #[test]
    fn approach_contact_follow_contact_and_the_ends() {
        let mut m = machine();
        let gap = m.cfg.contact_gap_m;
        m.request(
            &req(RequestKind::Follow, CollabPart::RightHand),
            RobotState::Available,
            0.9,
            0.0,
        );
        assert_eq!(m.step(&seen(0.1, 0.3, 0.0)), CollabPhase::Approach);
        assert_eq!(m.step(&seen(0.2, gap - 0.005, 0.0)), CollabPhase::Contact);
        assert_eq!(m.reason(), CollabReason::ContactMade);
        // pushed around in contact: still contact
        assert_eq!(m.step(&seen(0.3, 0.03, 20.0)), CollabPhase::Contact);
        // the hand moves away: away and without force for `release_s`
        // (after a touch of at least MIN_CONTACT_S)
        let release = m.cfg.release_s;
        let t0 = 0.2 + MIN_CONTACT_S;
        assert_eq!(m.step(&seen(t0, 0.2, 0.0)), CollabPhase::Contact);
        assert_eq!(
            m.step(&seen(t0 + release * 0.9, 0.2, 0.0)),
            CollabPhase::Contact
        );
        assert_eq!(m.step(&seen(t0 + release, 0.2, 0.0)), CollabPhase::Follow);
        assert_eq!(m.reason(), CollabReason::HandMovedAway);
        // a force is contact near the hand, not far from it
        let t1 = t0 + release + 0.05;
        assert_eq!(m.step(&seen(t1, 0.4, 10.0)), CollabPhase::Follow);
        assert_eq!(m.step(&seen(t1 + 0.05, 0.05, 10.0)), CollabPhase::Contact);
        // the wrist push ends it; `begin` without a part resumes with the last one
        let push = Observation {
            wrist_push: true,
            ..seen(t1 + 0.1, 0.0, 5.0)
        };
        assert_eq!(m.step(&push), CollabPhase::Idle);
        assert_eq!(
            (m.reason(), m.part()),
            (CollabReason::WristPush, CollabPart::None)
        );
        let a = m.request(
            &req(RequestKind::Begin, CollabPart::None),
            RobotState::Available,
            0.9,
            t1 + 0.5,
        );
        assert!(a.accepted);
        assert_eq!(m.part(), CollabPart::RightHand);
    }

    #[test]
    fn a_held_hand_stays_in_contact_through_bounces_and_depth_errors() {
        let mut m = approaching_left_hand();
        let c = m.cfg.clone();
        // touched: depth sees the pressing hand 4 cm off the surface
        assert_eq!(m.step(&seen(1.0, 0.04, 30.0)), CollabPhase::Contact);
        let mut t = 1.0;
        for k in 0..3000 {
            t += 1e-3;
            // the contact bounces apart 40 ms in every 100 ms (F̂ drops to
            // 0), depth's gap wanders ±1.5 cm about where the hand pressed
            let bounce = k % 100 < 40;
            let gap = 0.04 + 0.015 * ((k as f64) * 0.37).sin();
            let force = if bounce { 0.0 } else { 20.0 };
            assert_eq!(
                m.step(&seen(t, gap, force)),
                CollabPhase::Contact,
                "t {t:.3}"
            );
        }
        // apart without a break for less than release_s: still contact
        let from = t;
        while t < from + c.release_s * 0.9 {
            t += 1e-3;
            assert_eq!(
                m.step(&seen(t, 0.04 + c.follow_gap_m + 0.01, 0.0)),
                CollabPhase::Contact
            );
        }
        // a force again resets the release; then the hand goes for release_s
        assert_eq!(m.step(&seen(t, 0.04, 10.0)), CollabPhase::Contact);
        let from = t;
        while m.phase() == CollabPhase::Contact {
            t += 1e-3;
            m.step(&seen(t, 0.04 + c.follow_gap_m + 0.01, 0.0));
            assert!(t < from + c.release_s + 0.01, "never released");
        }
        assert!(t >= from + c.release_s - 1e-9);
        assert_eq!(
            (m.phase(), m.reason()),
            (CollabPhase::Follow, CollabReason::HandMovedAway)
        );
    }

    #[test]
    fn every_end_has_its_reason_and_the_most_severe_wins() {
        let limit = machine().force_limit_n();
        let lost = machine().cfg.hand_lost_s;
        for (obs, reason) in [
            (
                Observation {
                    stale: true,
                    collision: true,
                    ..seen(1.0, 0.0, 0.0)
                },
                CollabReason::Stale,
            ),
            (
                Observation {
                    collision: true,
                    wrist_push: true,
                    ..seen(1.0, 0.0, 0.0)
                },
                CollabReason::Collision,
            ),
            (
                Observation {
                    t: 0.5 + lost + 0.01,
                    hand_seen: false,
                    gap_m: 0.2,
                    ..Default::default()
                },
                CollabReason::HandLost,
            ),
        ] {
            let mut m = approaching_left_hand();
            assert_eq!(m.step(&obs), CollabPhase::Idle, "{obs:?}");
            assert_eq!(m.reason(), reason, "{obs:?}");
        }
        // a force above the limit: back off first, then idle; the hand
        // lost meanwhile changes nothing, a collision still ends it
        for (then, after, reason) in [
            (
                Observation {
                    backed_off: true,
                    ..seen(1.2, 0.05, 0.0)
                },
                CollabPhase::Idle,
                CollabReason::ForceLimit,
            ),
            (
                seen(1.2, 0.05, 0.0),
                CollabPhase::BackOff,
                CollabReason::ForceLimit,
            ),
            (
                Observation {
                    t: 1.0 + lost + 0.5,
                    gap_m: 0.1,
                    ..Default::default()
                },
                CollabPhase::BackOff,
                CollabReason::ForceLimit,
            ),
            (
                seen(1.0 + BACK_OFF_MAX_S, 0.1, 0.0),
                CollabPhase::Idle,
                CollabReason::ForceLimit,
            ),
            (
                Observation {
                    collision: true,
                    ..seen(1.1, 0.05, 0.0)
                },
                CollabPhase::Idle,
                CollabReason::Collision,
            ),
        ] {
            let mut m = approaching_left_hand();
            assert_eq!(m.step(&seen(1.0, 0.0, limit * 1.01)), CollabPhase::BackOff);
            assert_eq!(m.reason(), CollabReason::ForceLimit);
            assert_eq!(m.step(&then), after, "{then:?}");
            assert_eq!(m.reason(), reason, "{then:?}");
        }
        // the hand unseen for less than hand_lost_s: still approaching
        let mut m = approaching_left_hand();
        let unseen = Observation {
            t: 0.5 + lost * 0.9,
            gap_m: 0.2,
            ..Default::default()
        };
        assert_eq!(m.step(&unseen), CollabPhase::Approach);
        // end and stop requests
        let a = m.request(
            &req(RequestKind::End, CollabPart::None),
            RobotState::Available,
            0.0,
            1.0,
        );
        assert!(
            a.accepted && m.phase() == CollabPhase::Idle && m.reason() == CollabReason::EndRequest
        );
        assert!(!m.take_stop());
        m.request(
            &req(RequestKind::Stop, CollabPart::None),
            RobotState::Available,
            0.0,
            1.1,
        );
        assert!(m.take_stop() && !m.take_stop());
    }
}
