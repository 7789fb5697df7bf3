//! Collaboration (paper Sect. VI): the modes `approach`, `contact` and
//! `follow`. Each period [`Collaboration::observe`] answers the requests,
//! finds the collaborative hand in the newest skeleton, estimates the
//! contact force from the residual (eqs. 21-22) where the hand meets the
//! robot (the collaborative robot part, or the wrist when the hand is
//! nearer the wrist's surface), checks what the intended contact does not
//! explain against the collision thresholds, looks for a push on the wrist
//! by another part than the collaborative hand, and steps the phase machine
//! ([`crate::collab`]). [`Collaboration::reference`] is the
//! Cartesian reference of the end effector in the phase, which the
//! avoidance stage resolves under SNS with every other obstacle.
//!
//! - approach / follow: the robot point moves toward the filtered hand until
//!   the surfaces touch (aiming `reach_into_m` into the modelled hand, which
//!   depth places only to centimetres), at `approach_speed` far from it and
//!   `contact_speed` within `slow_down_m`, relative to a hand that comes
//!   toward it (the robot backs away from a faster one). The hand is carried
//!   forward by its velocity over the filter's lag, and the gap is to the
//!   nearest of the robot part and the wrist's collision objects;
//! - contact: admittance on the estimated force: the end effector yields
//!   along F̂ at `admittance` [m/(N s)], so the person pushes it around,
//!   and keeps pressing the hand with `contact_hold_n`;
//! - back off: after F̂ passed the force limit, the end effector moves
//!   `back_off_m` along the force the person applied, at `approach_speed`.

use nalgebra::Vector3;
use phri_config::{CollaborationConfig, Config, OnRequest};
use phri_estimation::{ContactPoint, ForceEstimate, ForceEstimator};
use phri_ipc::{
    CollabPart, CollabPhase, HandObservation, HriRequest, RequestKind, Skeleton, SkeletonJoint,
    Zeroed, MAX_DOF, MAX_PEOPLE,
};
use phri_model::{Model, Placement};

use crate::collab::{Answer, CollabMachine, Observation, RobotState};
use crate::error::ControlError;
use crate::inputs::PerceptionView;
use crate::modes::CartesianRef;
use crate::resolve::AT_THE_HAND_M;
use crate::snapshot::{snapshot_fields, Reader, Snapshot, Writer};

/// A skeleton older than this is no sighting of the hand \[s\].
const MAX_SKELETON_AGE_S: f64 = 0.2;
/// Pseudoinverse damping of the force estimate \[m\].
const FORCE_DAMPING: f64 = 1e-3;
/// A person seen in depth this near the wrist's control point confirms a
/// wrist push \[m\] (the collaborative hand is masked: only another part can be).
const WRIST_SEEN_M: f64 = 0.08;
/// The desired end effector stays this close to the measured one \[m\]:
/// blocked by avoidance or by the hand, the reference waits instead of winding up.
const MAX_LEAD_M: f64 = 0.05;
/// ... and at the hand, following it \[m\]: the lead falls
/// linearly to this over `slow_down_m`, so that the end effector touches at
/// about `contact_speed`.
const MIN_NEAR_LEAD_M: f64 = 0.003;
/// A control point's obstacle this near \[m\] touches the robot (depth's
/// noise is a few millimetres at the cell's range), unless it lies within
/// [`AT_THE_HAND_M`] of the collaborative hand (the hand itself, where the
/// mask left its edge).
const OTHER_TOUCH_M: f64 = 0.02;
/// The other hand this near the robot part's surface \[m\] and closing in
/// holds the approach and backs the robot away from it.
const OTHER_HAND_NEAR_M: f64 = 0.3;
/// ... closing in faster than this \[m/s\]: the repulsion's V_max (0.3 m/s,
/// `[repulsion] v_max`), as fast as the avoidance alone moves a robot point
/// away.
const OTHER_CLOSING_MIN: f64 = 0.3;
/// A hand closing in slower than this is still \[m/s\] (the refined hand's
/// velocity jitters by up to 0.09 m/s in depth's noise).
const CLOSING_MIN: f64 = 0.1;

/// The person's hand other than `part` (`None` for none).
fn other_hand(part: CollabPart) -> CollabPart {
    match part {
        CollabPart::RightHand => CollabPart::LeftHand,
        CollabPart::LeftHand => CollabPart::RightHand,
        CollabPart::None => CollabPart::None,
    }
}

/// A hand's velocity \[m/s\], base frame, after a sighting `to` (position
/// \[m\], capture \[ns\]) that follows `from`: `v` low-passed like the
/// position (time constant `tau_s` \[s\]) toward the velocity between them;
/// `None` when they are not in order or further apart than a skeleton's
/// life, which says nothing of the motion.
fn sighted_velocity(
    v: Vector3<f64>,
    (x0, t0): (Vector3<f64>, u64),
    (x, t): (Vector3<f64>, u64),
    tau_s: f64,
) -> Option<Vector3<f64>> {
    let gap_s = t.saturating_sub(t0) as f64 * 1e-9;
    (gap_s > 0.0 && gap_s <= MAX_SKELETON_AGE_S).then(|| {
        let a = 1.0 - (-gap_s / tau_s.max(1e-3)).exp();
        v + ((x - x0) / gap_s - v) * a
    })
}

/// The collaboration's inputs of one period.
#[derive(Clone, Copy, Debug, Default)]
pub struct CollabInput<'a> {
    /// requests that arrived since the last period (`hri/request`)
    pub requests: &'a [HriRequest],
    /// the newest skeleton (`perception/skeleton`)
    pub skeleton: Option<&'a Skeleton>,
    /// the newest refined hand (`perception/hand`), preferred when fresh
    pub hand: Option<&'a HandObservation>,
}

/// The last request answered, for `collab/state`.
#[derive(Clone, Copy, Debug)]
pub struct Answered {
    /// the request
    pub request: HriRequest,
    /// the answer it got
    pub answer: Answer,
}

snapshot_fields!(Answered { request, answer });

impl Default for Answered {
    fn default() -> Answered {
        Answered {
            request: HriRequest::zeroed(),
            answer: Answer::default(),
        }
    }
}

/// The collaboration layer's state.
pub struct Collaboration {
    cfg: CollaborationConfig,
    /// the end effector's speed toward the collaborative hand at most
    /// [m/s]: Annex A's transient-contact speed of the hand against the
    /// robot's effective mass (eq. A.5: half its moving mass)
    hand_speed_limit: f64,
    machine: CollabMachine,
    forces: ForceEstimator,
    contact: ContactPoint,
    /// the frame whose origin is the wrist centre
    wrist_frame: usize,
    /// the repulsion control point on the wrist link (`[[repulsion.points]]`), if any
    wrist_point: Option<usize>,
    /// the model's collision objects of the robot part's and the wrist's
    /// links: the gap to the hand is to the nearest of them too (the wrist
    /// may meet a hand coming from its side first)
    near_objects: Vec<usize>,
    /// the model's collision objects of the wrist's link: a hand nearer to
    /// them than to the robot part meets the robot there
    wrist_objects: Vec<usize>,
    /// F̂'s contact point is on the wrist (the hand nearer the wrist's
    /// surface than the robot part's), not on the robot part
    contact_on_wrist: bool,
    /// the frame of F̂'s contact point (the robot part's or the wrist's)
    contact_frame: usize,
    /// the axis point of the touched capsule nearest the hand \[m\], base
    /// frame (the robot part's: [`Collaboration::robot_point`], or the wrist's)
    contact_axis: Vector3<f64>,
    /// joint collision thresholds of the detector \[Nm\]
    collision_threshold: [f64; MAX_DOF],
    n: usize,
    /// the hand the approach follows \[m\], base frame: the low-passed
    /// sightings carried forward by the filter's lag and the sighting's age
    hand: Option<Vector3<f64>>,
    /// the sightings low-passed \[m\], base frame (they trail a moving hand
    /// by `hand_filter_s` × its speed)
    hand_lp: Option<Vector3<f64>>,
    /// the newest sighting: position \[m\], capture time \[ns, robot clock\]
    sighting: Option<(Vector3<f64>, u64)>,
    /// the hand's velocity from its sightings, low-passed \[m/s\], base frame
    hand_velocity: Vector3<f64>,
    /// the person's other hand: its newest sighting (position \[m\],
    /// capture \[ns\]) and its velocity from the sightings, low-passed
    /// \[m/s\], base frame (a hand that may cross the approach)
    other: Option<(Vector3<f64>, u64)>,
    other_velocity: Vector3<f64>,
    /// this period: the other hand near the robot part and closing in
    /// (see [`Collaboration::other_closing`])
    other_closing: Option<(Vector3<f64>, f64)>,
    /// the hand was seen in this period
    hand_seen: bool,
    /// desired end-effector position \[m\], base frame
    x_d: Vector3<f64>,
    /// the robot part's axis point nearest the hand \[m\], base frame, at
    /// the measured joints (the capsule's centre while no hand is known)
    robot_point: Vector3<f64>,
    estimate: Option<ForceEstimate>,
    /// surface gap robot point ↔ hand \[m\]
    gap: f64,
    /// surface gap hand ↔ the nearest of the robot part and the wrist's
    /// collision objects \[m\]: the approach slows down by it
    near_gap: f64,
    wrist_since: Option<f64>,
    /// the residual had the pattern of a wrist push in the last period
    /// (confirmed by a part or not)
    wrist_pattern: bool,
    collision: bool,
    /// after a collaboration: full detection re-arms once the residual was
    /// quiet for `rearm_quiet_s` (None: armed)
    rearm: Option<Option<f64>>,
    last_answer: Option<Answered>,
    /// backing off after a force limit
    back_off: Option<BackOff>,
    /// the phase of the last reference
    ref_phase: CollabPhase,
    /// the camera tracks people (`[skeleton] enabled`): a restarted
    /// controller can judge where the hands are
    sees_hands: bool,
}

/// Backing off after a force limit: along the force the person applied.
#[derive(Clone, Copy, Debug, Default)]
struct BackOff {
    /// unit direction \[-\], base frame
    dir: Vector3<f64>,
    /// the robot part's link origin when it began \[m\], base frame
    from: Vector3<f64>,
    /// the end effector when it began \[m\], base frame (set by the first reference)
    ee: Option<Vector3<f64>>,
}

snapshot_fields!(BackOff { dir, from, ee });

/// The phase machine and what the layer carries from one period to the
/// next. Not saved: the configuration and what comes from it, and the force
/// estimate and the estimator's kinematics, which every period recomputes
/// (from `q` and `r`) before reading them. The frame of F̂'s contact point
/// follows from whether it is on the wrist.
impl Snapshot for Collaboration {
    fn save(&self, w: &mut Writer<'_>) {
        self.machine.save(w);
        self.contact_on_wrist.save(w);
        self.contact_axis.save(w);
        self.hand.save(w);
        self.hand_lp.save(w);
        self.sighting.save(w);
        self.hand_velocity.save(w);
        self.other.save(w);
        self.other_velocity.save(w);
        self.other_closing.save(w);
        self.hand_seen.save(w);
        self.x_d.save(w);
        self.robot_point.save(w);
        self.gap.save(w);
        self.near_gap.save(w);
        self.wrist_since.save(w);
        self.wrist_pattern.save(w);
        self.collision.save(w);
        self.rearm.save(w);
        self.last_answer.save(w);
        self.back_off.save(w);
        self.ref_phase.save(w);
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        self.machine.load(r);
        self.contact_on_wrist.load(r);
        let frame = match self.contact_on_wrist {
            true => self.wrist_frame,
            false => self.contact.frame,
        };
        r.store(&mut self.contact_frame, frame);
        self.contact_axis.load(r);
        self.hand.load(r);
        self.hand_lp.load(r);
        self.sighting.load(r);
        self.hand_velocity.load(r);
        self.other.load(r);
        self.other_velocity.load(r);
        self.other_closing.load(r);
        self.hand_seen.load(r);
        self.x_d.load(r);
        self.robot_point.load(r);
        self.gap.load(r);
        self.near_gap.load(r);
        self.wrist_since.load(r);
        self.wrist_pattern.load(r);
        self.collision.load(r);
        self.rearm.load(r);
        self.last_answer.load(r);
        self.back_off.load(r);
        self.ref_phase.load(r);
    }
}

impl Collaboration {
    /// The layer of `[collaboration]`, with the detector's thresholds of `[dynamics]`.
    pub fn new(model: &Model, cfg: &Config) -> Result<Collaboration, ControlError> {
        let c = &cfg.collaboration;
        let n = model.nv();
        let frame = model
            .frame_id(&c.robot_link)
            .map_err(|_| ControlError::UnknownLink {
                key: "collaboration.robot_link".into(),
                link: c.robot_link.clone(),
            })?;
        let wrist_frame = model
            .frame_id(&c.wrist_link)
            .map_err(|_| ControlError::UnknownLink {
                key: "collaboration.wrist_link".into(),
                link: c.wrist_link.clone(),
            })?;
        let thresholds = cfg
            .dynamics
            .collision_threshold
            .resolve(n, "dynamics.collision_threshold")?;
        let mut collision_threshold = [f64::INFINITY; MAX_DOF];
        for (t, v) in collision_threshold.iter_mut().zip(&thresholds) {
            *t = *v;
        }
        let m_r = phri_iso15066::robot_effective_mass(model.moving_mass(), 0.0);
        Ok(Collaboration {
            hand_speed_limit: phri_iso15066::transient_speed_limit(
                phri_iso15066::BodyRegion::HandAndFingers,
                m_r,
            ),
            machine: CollabMachine::new(c),
            forces: ForceEstimator::new(model.clone(), FORCE_DAMPING),
            contact: ContactPoint {
                frame,
                point: Vector3::from(c.robot_point),
            },
            wrist_frame,
            near_objects: model
                .collisions
                .iter()
                .enumerate()
                .filter(|(_, o)| o.link == c.robot_link || o.link == c.wrist_link)
                .map(|(i, _)| i)
                .collect(),
            wrist_objects: model
                .collisions
                .iter()
                .enumerate()
                .filter(|(_, o)| o.link == c.wrist_link)
                .map(|(i, _)| i)
                .collect(),
            contact_on_wrist: false,
            contact_frame: frame,
            contact_axis: Vector3::zeros(),
            wrist_point: cfg
                .repulsion
                .points
                .iter()
                .position(|p| p.link == c.wrist_link),
            collision_threshold,
            n,
            hand: None,
            hand_lp: None,
            sighting: None,
            hand_velocity: Vector3::zeros(),
            other: None,
            other_velocity: Vector3::zeros(),
            other_closing: None,
            hand_seen: false,
            x_d: Vector3::zeros(),
            robot_point: Vector3::zeros(),
            estimate: None,
            gap: f64::INFINITY,
            near_gap: f64::INFINITY,
            wrist_since: None,
            wrist_pattern: false,
            collision: false,
            rearm: None,
            last_answer: None,
            back_off: None,
            ref_phase: CollabPhase::Idle,
            sees_hands: cfg.skeleton.enabled,
            cfg: c.clone(),
        })
    }

    /// The collaboration's phase.
    pub fn phase(&self) -> CollabPhase {
        self.machine.phase()
    }

    /// The camera tracks people (`[skeleton] enabled`): hands can be judged.
    pub fn sees_hands(&self) -> bool {
        self.sees_hands
    }

    /// A request lets the task's segment in progress end before the
    /// approach (`on_request = "complete"`).
    pub fn completes_segment(&self) -> bool {
        self.cfg.on_request == OnRequest::Complete
    }

    /// Hand the force estimator the kinematics at `q` the controller
    /// computed this period (its workspace of the same model).
    pub fn share_kinematics(&mut self, data: &phri_model::Data, q: &[f64]) {
        self.forces.share_kinematics(data, q);
    }

    /// The phase machine.
    pub fn machine(&self) -> &CollabMachine {
        &self.machine
    }

    /// The collaborative robot part's frame (`collaboration.robot_link`).
    pub fn robot_frame(&self) -> usize {
        self.contact.frame
    }

    /// The frame of F̂'s contact point: the robot part's, or the wrist's
    /// while the hand is nearer the wrist's surface.
    pub fn contact_frame(&self) -> usize {
        self.contact_frame
    }

    /// F̂ is estimated on the wrist (the hand nearer the wrist's surface
    /// than the robot part's).
    pub fn contact_on_wrist(&self) -> bool {
        self.contact_on_wrist
    }

    /// The last force estimate (while collaborating).
    pub fn estimate(&self) -> Option<&ForceEstimate> {
        self.estimate.as_ref()
    }

    /// Surface gap between the robot part and the hand \[m\] (∞: no hand).
    pub fn gap_m(&self) -> f64 {
        self.gap
    }

    /// Surface gap between the hand and the nearer of the robot part and the
    /// wrist \[m\] (∞: no hand): what the phases' contact and release use.
    pub fn near_gap_m(&self) -> f64 {
        self.near_gap
    }

    /// The collaborative robot part's axis point nearest the hand \[m\],
    /// base frame, at the measured joints.
    pub fn robot_point(&self) -> Vector3<f64> {
        self.robot_point
    }

    /// The desired end-effector position \[m\], base frame.
    pub fn x_d(&self) -> Vector3<f64> {
        self.x_d
    }

    /// The filtered hand \[m\], base frame.
    pub fn hand(&self) -> Option<Vector3<f64>> {
        self.hand
    }

    /// The collaborative hand's velocity from its sightings, low-passed
    /// \[m/s\], base frame (zero while no hand is followed).
    pub fn hand_velocity(&self) -> Vector3<f64> {
        self.hand_velocity
    }

    /// Capture time of the newest sighting of the hand [ns, robot clock].
    pub fn hand_capture_ns(&self) -> Option<u64> {
        self.sighting.map(|(_, t)| t)
    }

    /// The last request answered (`None`: none yet).
    pub fn last_answer(&self) -> Option<&Answered> {
        self.last_answer.as_ref()
    }

    /// The residual the intended contact does not explain crosses a collision threshold.
    pub fn collision(&self) -> bool {
        self.collision
    }

    /// The residual had the pattern of a wrist push in the last period (a
    /// force through the wrist centre), whoever applied it.
    pub fn wrist_pattern(&self) -> bool {
        self.wrist_pattern
    }

    /// Full detection is not yet re-armed after a collaboration.
    pub fn rearming(&self) -> bool {
        self.rearm.is_some()
    }

    /// A `stop` request was accepted (reading clears it).
    pub fn take_stop(&mut self) -> bool {
        self.machine.take_stop()
    }

    /// The hand of `part` of `person` (`u32::MAX`: the first tracked person)
    /// in `sk`: position and confidence.
    fn find_hand(sk: &Skeleton, part: CollabPart, person: u32) -> Option<([f64; 3], f64, u32)> {
        let joint = part.joint()? as usize;
        let n = (sk.n_people as usize).min(MAX_PEOPLE);
        sk.people[..n]
            .iter()
            .filter(|p| p.tracked != 0 && (person == u32::MAX || p.id == person))
            .map(|p| (p.joints[joint], p.confidence[joint], p.id))
            .find(|(x, c, _)| x.iter().all(|v| v.is_finite()) && c.is_finite())
    }

    /// One period's observation: requests, hand, force, wrist, phase.
    #[allow(clippy::too_many_arguments)]
    pub fn observe(
        &mut self,
        t: f64,
        dt: f64,
        stamp_ns: u64,
        q: &[f64],
        residual: Option<&[f64]>,
        robot: RobotState,
        stale: bool,
        input: &CollabInput<'_>,
        perception: Option<&PerceptionView<'_>>,
    ) -> CollabPhase {
        let fresh_skeleton = input.skeleton.filter(|sk| {
            stamp_ns.saturating_sub(sk.capture_ns) as f64 * 1e-9 <= MAX_SKELETON_AGE_S
        });
        self.answer_requests(t, robot, input.requests, fresh_skeleton);
        self.observe_hand(dt, stamp_ns, input.hand, fresh_skeleton);
        self.observe_other_hand(fresh_skeleton);
        let force_n = self.estimate_force(q, residual);
        // the wrist push: a force through the wrist centre, a person seen in
        // depth at the wrist's control point
        let wrist_seen = self
            .wrist_point
            .and_then(|i| perception?.points.get(i))
            .is_some_and(|p| p.active != 0 && p.min_distance <= WRIST_SEEN_M);
        self.wrist_pattern = false;
        let wrist_push =
            self.machine.active() && self.wrist_push(t, q, residual, fresh_skeleton, wrist_seen);
        // the gap and the phase
        (self.gap, self.near_gap) = match self.hand {
            Some(h) => {
                let part = (h - self.robot_point).norm() - self.cfg.robot_radius_m;
                let near = self.surface_distance(&h).min(part);
                (part - self.cfg.hand_radius_m, near - self.cfg.hand_radius_m)
            }
            None => (f64::INFINITY, f64::INFINITY),
        };
        let origin = self.forces.frame_origin(self.contact.frame);
        let backed_off = self
            .back_off
            .is_some_and(|b| (origin - b.from).dot(&b.dir) >= 0.9 * self.cfg.back_off_m);
        let other_touch = self.other_touch(perception);
        self.other_closing = self.other_closing(stamp_ns);
        let was = self.machine.active();
        let phase = self.machine.step(&Observation {
            t,
            hand_seen: self.hand_seen,
            gap_m: self.near_gap,
            force_n,
            wrist_push,
            collision: self.collision,
            other_touch,
            stale,
            backed_off,
        });
        self.update_back_off(phase, origin);
        if was && !self.machine.active() {
            self.rearm = Some(None);
            self.forget_hand();
        }
        self.update_rearm(t, residual);
        phase
    }

    /// The period's requests, stops first: a stop anywhere among them is
    /// acted on, and what follows it finds the robot stopped; each judged
    /// with the named hand's confidence in the newest skeleton.
    fn answer_requests(
        &mut self,
        t: f64,
        robot: RobotState,
        requests: &[HriRequest],
        fresh_skeleton: Option<&Skeleton>,
    ) {
        let is_stop = |r: &&HriRequest| r.kind == RequestKind::Stop as u32;
        let stops = requests.iter().filter(is_stop);
        let others = requests.iter().filter(|r| !is_stop(r));
        let mut robot = robot;
        let mut stopped = None;
        for r in stops.chain(others) {
            let part = CollabPart::try_from(r.part).unwrap_or(CollabPart::None);
            let part = if part == CollabPart::None {
                self.machine.part()
            } else {
                part
            };
            let conf = fresh_skeleton
                .and_then(|sk| Self::find_hand(sk, part, r.person))
                .map_or(0.0, |(_, c, _)| c);
            let was_active = self.machine.active();
            let answer = self.machine.request(r, robot, conf, t);
            if answer.accepted && !was_active && self.machine.active() {
                self.forget_hand();
            }
            let answered = Answered {
                request: *r,
                answer,
            };
            if is_stop(&r) && answer.accepted {
                robot = RobotState::Stopped;
                stopped.get_or_insert(answered);
            }
            self.last_answer = Some(answered);
        }
        // the period's answer collab/state tells is its stop, if it had one
        if let Some(a) = stopped {
            self.last_answer = Some(a);
        }
    }

    /// The collaborative hand while collaborating: its sighting (the
    /// refined `hand`, else the skeleton's), velocity, low-pass and where it
    /// is now ([`Collaboration::hand`]).
    fn observe_hand(
        &mut self,
        dt: f64,
        stamp_ns: u64,
        hand: Option<&HandObservation>,
        fresh_skeleton: Option<&Skeleton>,
    ) {
        self.hand_seen = false;
        if self.machine.active() {
            let refined = hand.filter(|h| {
                h.refined != 0
                    && h.part == self.machine.part() as u32
                    && stamp_ns.saturating_sub(h.capture_ns) as f64 * 1e-9 <= MAX_SKELETON_AGE_S
                    && h.position.iter().all(|v| v.is_finite())
            });
            let seen = match refined {
                Some(h) => Some((h.position, h.confidence, h.capture_ns)),
                None => fresh_skeleton.and_then(|sk| {
                    Self::find_hand(sk, self.machine.part(), self.machine.person())
                        .map(|(x, c, _)| (x, c, sk.capture_ns))
                }),
            };
            if let Some((x, c, capture)) = seen {
                let new = self.sighting.is_none_or(|(_, t0)| capture > t0);
                if c >= self.cfg.min_hand_confidence && new {
                    let x = Vector3::from(x);
                    let tau = self.cfg.hand_filter_s;
                    if let Some(v) = self.sighting.and_then(|from| {
                        sighted_velocity(self.hand_velocity, from, (x, capture), tau)
                    }) {
                        self.hand_velocity = v;
                    }
                    self.sighting = Some((x, capture));
                    self.hand_seen = true;
                }
            }
            if let Some((x, capture)) = self.sighting {
                let tau = self.cfg.hand_filter_s.max(1e-3);
                let alpha = 1.0 - (-dt / tau).exp();
                let lp = match self.hand_lp {
                    Some(h) => h + (x - h) * alpha,
                    None => x,
                };
                self.hand_lp = Some(lp);
                // where the hand is now while approaching and following:
                // the low-pass trails it by τ·v, the sighting is `age` old
                // (in contact its motion is the push, the admittance's)
                let age = (stamp_ns.saturating_sub(capture) as f64 * 1e-9).min(MAX_SKELETON_AGE_S);
                self.hand = Some(match self.machine.phase() {
                    CollabPhase::Approach | CollabPhase::Follow => {
                        lp + self.hand_velocity * (tau + age)
                    }
                    _ => lp,
                });
            }
        }
    }

    /// The other hand while collaborating, tracked, and how fast it moves
    /// (after a gap longer than a skeleton's life, as if still).
    fn observe_other_hand(&mut self, fresh_skeleton: Option<&Skeleton>) {
        if self.machine.active() {
            let seen = fresh_skeleton.and_then(|sk| {
                Self::find_hand(sk, other_hand(self.machine.part()), self.machine.person())
                    .filter(|(_, c, _)| *c >= self.cfg.min_hand_confidence)
                    .map(|(x, _, _)| (Vector3::from(x), sk.capture_ns))
            });
            if let Some(now) = seen.filter(|(_, t)| self.other.is_none_or(|(_, t0)| *t > t0)) {
                if let Some(from) = self.other {
                    self.other_velocity =
                        sighted_velocity(self.other_velocity, from, now, self.cfg.hand_filter_s)
                            .unwrap_or_else(Vector3::zeros);
                }
                self.other = Some(now);
            }
        }
    }

    /// The force at the robot point from the residual, what it leaves
    /// unexplained (a collision elsewhere), only while collaborating (idle,
    /// nothing reads them): the force's magnitude \[N\] (0 without a residual).
    fn estimate_force(&mut self, q: &[f64], residual: Option<&[f64]>) -> f64 {
        let zero = [0.0; MAX_DOF];
        let r = residual
            .filter(|r| r.len() == self.n)
            .unwrap_or(&zero[..self.n]);
        self.estimate = match self.machine.active() {
            true => {
                let contact = self.contact_point(q);
                self.forces
                    .estimate(q, r, std::slice::from_ref(&contact))
                    .ok()
                    .copied()
            }
            false => None,
        };
        let force_n = match &self.estimate {
            Some(e) if residual.is_some() => e.forces[0].norm(),
            _ => 0.0,
        };
        self.collision = self.machine.active()
            && residual.is_some()
            && self.estimate.as_ref().is_some_and(|e| {
                e.left[..self.n.min(e.left.len())]
                    .iter()
                    .zip(&self.collision_threshold)
                    .any(|(u, th)| u.abs() > *th)
            });
        force_n
    }

    /// Another part of the person at the robot: a control point's obstacle
    /// (the collaborative hand is masked from depth) within `OTHER_TOUCH_M`
    /// and not at the hand (what the mask left of its edge).
    fn other_touch(&self, perception: Option<&PerceptionView<'_>>) -> bool {
        perception.is_some_and(|v| {
            v.points.iter().any(|p| {
                let o = Vector3::from(p.obstacle);
                p.active != 0
                    && p.min_distance <= OTHER_TOUCH_M
                    && o.iter().all(|x| x.is_finite())
                    && self.hand.is_none_or(|h| (o - h).norm() > AT_THE_HAND_M)
            })
        })
    }

    /// Backing off (`phase`): its direction, set on entry (away from the
    /// person: along the force they apply, else from their hand) and the
    /// contact frame's `origin` \[m\] it starts from; otherwise none.
    fn update_back_off(&mut self, phase: CollabPhase, origin: Vector3<f64>) {
        self.back_off = match phase {
            CollabPhase::BackOff => Some(self.back_off.unwrap_or_else(|| {
                // the force the person applies points away from them
                let f = self.estimate.map_or(Vector3::zeros(), |e| e.forces[0]);
                let away = match (f.norm() > 1e-3, self.hand) {
                    (true, _) => f,
                    (false, Some(h)) => self.robot_point - h,
                    (false, None) => Vector3::zeros(),
                };
                BackOff {
                    dir: away.try_normalize(1e-9).unwrap_or_else(Vector3::zeros),
                    from: origin,
                    ee: None,
                }
            })),
            _ => None,
        };
    }

    /// `h` \[m\] (base frame) in the robot part's link frame (`pose`: that
    /// link's placement), and the point of the part's capsule axis
    /// (`robot_point ± robot_half_length_m ẑ`) nearest it, link frame.
    fn part_axis(&self, pose: &Placement, h: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let (centre, half) = (self.contact.point, self.cfg.robot_half_length_m);
        let local = pose.r.transpose() * (h - pose.p);
        let z = Vector3::z();
        (
            local,
            centre + z * (local - centre).dot(&z).clamp(-half, half),
        )
    }

    /// Where the hand meets the robot at joints `q`: on the robot part's
    /// capsule `robot_point ± robot_half_length_m ẑ` (link frame), the surface
    /// point toward the hand seen in depth (the capsule's tip along ẑ while no
    /// hand is known); or, when the hand is nearer the surface of the wrist's
    /// collision capsules, the wrist's surface point toward it (in the wrist
    /// link's frame). Sets [`Collaboration::robot_point`] to the robot part's
    /// axis point nearest the hand, and which of the two F̂ is estimated on.
    fn contact_point(&mut self, q: &[f64]) -> ContactPoint {
        self.contact_on_wrist = false;
        self.contact_frame = self.contact.frame;
        let Ok(pose) = self.forces.placement(q, self.contact.frame) else {
            return self.contact;
        };
        let (centre, half, radius) = (
            self.contact.point,
            self.cfg.robot_half_length_m,
            self.cfg.robot_radius_m,
        );
        let z = Vector3::z();
        let (axis, normal, part_distance) = match self.hand {
            Some(h) => {
                let (local, axis) = self.part_axis(&pose, &h);
                let d = local - axis;
                let normal = match d.norm() > 1e-9 {
                    true => d / d.norm(),
                    false => z,
                };
                (axis, normal, d.norm() - radius)
            }
            None => (centre + z * half, z, f64::INFINITY),
        };
        self.robot_point = pose.apply(&axis);
        self.contact_axis = self.robot_point;
        if let Some((point, axis)) = self
            .hand
            .and_then(|h| self.wrist_contact(&h, part_distance))
        {
            self.contact_on_wrist = true;
            self.contact_axis = axis;
            self.contact_frame = self.wrist_frame;
            return ContactPoint {
                frame: self.wrist_frame,
                point,
            };
        }
        ContactPoint {
            frame: self.contact.frame,
            point: axis + normal * radius,
        }
    }

    /// The wrist's surface point toward the hand `h` \[m\] (base frame), in
    /// the wrist link's frame, and the capsule's axis point nearest `h`
    /// \[m\], base frame, when `h` is nearer the surface of the wrist's
    /// collision capsules than `part_distance` \[m\] (the robot part's
    /// surface), at the joints of the last kinematics.
    fn wrist_contact(
        &self,
        h: &Vector3<f64>,
        part_distance: f64,
    ) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let (model, data) = (self.forces.model(), self.forces.data());
        let (axis, distance, radius) = self
            .wrist_objects
            .iter()
            .filter_map(|&i| model.collisions.get(i))
            .map(|o| {
                let (a, b, radius) = o.capsule_segment(data);
                let ab = b - a;
                let len2 = ab.norm_squared();
                let t = match len2 > 1e-12 {
                    true => ((h - a).dot(&ab) / len2).clamp(0.0, 1.0),
                    false => 0.0,
                };
                let axis = a + ab * t;
                (axis, (h - axis).norm() - radius, radius)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        if !(distance < part_distance) {
            return None;
        }
        let normal = (h - axis).try_normalize(1e-9)?;
        let surface = axis + normal * radius;
        let wrist = phri_model::frame_placement(model, data, self.wrist_frame);
        Some((wrist.r.transpose() * (surface - wrist.p), axis))
    }

    /// The controller restarted at `t`: its predecessor's collaboration is
    /// over (`controller_restart`), and the collision flag waits for the
    /// residual to decay (a hand may still press on the robot).
    pub fn restarted(&mut self, t: f64) {
        self.machine.restarted(t);
        self.forget_hand();
        self.rearm = Some(None);
    }

    /// The smallest surface gap \[m\] between a hand of anyone tracked in
    /// `sk` and the robot part (its capsule) or the wrist's collision
    /// objects at joints `q` (∞: no hand tracked); `None` without a skeleton
    /// fresh at `stamp_ns` \[ns, robot clock\] or when the model refuses `q`.
    /// A hand of any confidence counts: one on the robot is partly hidden.
    pub fn nearest_hand_gap(
        &mut self,
        q: &[f64],
        stamp_ns: u64,
        sk: Option<&Skeleton>,
    ) -> Option<f64> {
        let sk = sk.filter(|sk| {
            stamp_ns.saturating_sub(sk.capture_ns) as f64 * 1e-9 <= MAX_SKELETON_AGE_S
        })?;
        let pose = self.forces.placement(q, self.contact.frame).ok()?;
        let n = (sk.n_people as usize).min(MAX_PEOPLE);
        let hands = [
            SkeletonJoint::LeftHand as usize,
            SkeletonJoint::RightHand as usize,
        ];
        let mut gap = f64::INFINITY;
        for p in sk.people[..n].iter().filter(|p| p.tracked != 0) {
            for &j in &hands {
                // an unseen hand of a tracked person (confidence 0, e.g.
                // hidden behind the robot it touches) is judged where the
                // tracker last placed it: never as gone
                let Some(x) = p.joints.get(j) else {
                    continue;
                };
                if !x.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let h = Vector3::from(*x);
                let (local, axis) = self.part_axis(&pose, &h);
                let part = (local - axis).norm() - self.cfg.robot_radius_m;
                gap = gap.min(part.min(self.surface_distance(&h)) - self.cfg.hand_radius_m);
            }
        }
        Some(gap)
    }

    /// A collaboration begins or ends: nothing of the hand carries over.
    fn forget_hand(&mut self) {
        self.hand = None;
        self.hand_lp = None;
        self.sighting = None;
        self.hand_velocity = Vector3::zeros();
        self.other = None;
        self.other_velocity = Vector3::zeros();
        self.other_closing = None;
    }

    /// The other hand, seen within a skeleton's life of `stamp_ns`, near the
    /// robot part and closing in on it faster than [`OTHER_CLOSING_MIN`]:
    /// the direction away from it (unit, base frame) and its closing speed
    /// \[m/s\], capped at the approach speed.
    fn other_closing(&self, stamp_ns: u64) -> Option<(Vector3<f64>, f64)> {
        let (x, capture) = self.other?;
        if stamp_ns.saturating_sub(capture) as f64 * 1e-9 > MAX_SKELETON_AGE_S {
            return None;
        }
        let from = self.robot_point - x;
        let d = from.norm();
        let gap = d - self.cfg.robot_radius_m - self.cfg.hand_radius_m;
        if d < 1e-6 || gap > OTHER_HAND_NEAR_M {
            return None;
        }
        let away = from / d;
        let closing = self.other_velocity.dot(&away);
        (closing > OTHER_CLOSING_MIN).then(|| (away, closing.min(self.cfg.approach_speed)))
    }

    /// The distance \[m\] from `x` (base frame) to the surface of the
    /// robot part's and the wrist's collision objects (their capsules), at
    /// the joints of the last kinematics (∞: none).
    fn surface_distance(&self, x: &Vector3<f64>) -> f64 {
        let (model, data) = (self.forces.model(), self.forces.data());
        self.near_objects
            .iter()
            .filter_map(|&i| model.collisions.get(i))
            .map(|o| o.capsule_distance(data, x))
            .fold(f64::INFINITY, f64::min)
    }

    fn update_rearm(&mut self, t: f64, residual: Option<&[f64]>) {
        let Some(quiet_since) = self.rearm.as_mut() else {
            return;
        };
        let quiet = residual.is_some_and(|r| {
            r.iter()
                .zip(&self.collision_threshold)
                .all(|(x, th)| x.abs() < 0.5 * th)
        });
        match (quiet, *quiet_since) {
            (false, _) => *quiet_since = None,
            (true, None) => *quiet_since = Some(t),
            (true, Some(t0)) if t - t0 >= self.cfg.rearm_quiet_s => self.rearm = None,
            _ => {}
        }
    }

    /// `‖r₅..₇‖ ≤ wrist_ratio ‖r₁..₄‖`, `‖r₁..₄‖ ≥ wrist_min_nm`, a force
    /// at the wrist centre leaving at most `wrist_fit ‖r‖` unexplained, for
    /// `wrist_hold_s`, with a human part other than the collaborative arm
    /// seen within `wrist_confirm_m` of the wrist (in the skeleton; or in
    /// depth at the wrist's control point, unless the collaborative hand
    /// rests on the wrist). The collaborative hand's own force on the wrist
    /// is a contact, not a push.
    fn wrist_push(
        &mut self,
        t: f64,
        q: &[f64],
        residual: Option<&[f64]>,
        sk: Option<&Skeleton>,
        seen_in_depth: bool,
    ) -> bool {
        self.wrist_pattern = false;
        let (Some(r), Some(_)) = (residual, self.estimate.as_ref()) else {
            self.wrist_since = None;
            return false;
        };
        if r.len() < 7 {
            return false;
        }
        let proximal = r[..4].iter().map(|x| x * x).sum::<f64>().sqrt();
        let distal = r[4..].iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut pattern =
            proximal >= self.cfg.wrist_min_nm && distal <= self.cfg.wrist_ratio * proximal;
        if pattern {
            // a force at the wrist centre explains it (a push on the elbow
            // side of the arm leaves the elbow's turn about the shoulder-wrist
            // line unexplained)
            let wrist = ContactPoint {
                frame: self.wrist_frame,
                point: Vector3::zeros(),
            };
            let norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            pattern = self
                .forces
                .estimate(q, r, std::slice::from_ref(&wrist))
                .is_ok_and(|e| e.unexplained <= self.cfg.wrist_fit * norm);
        }
        self.wrist_pattern = pattern;
        let wrist = self.wrist_centre();
        // the collaborative hand near the wrist (resting on it, or holding
        // the end effector beside it): the wrist's force may be its own, and
        // depth near the wrist may be its arm; only another part seen in the
        // skeleton then confirms a push
        let hand_at_wrist = self
            .hand
            .is_some_and(|h| (h - wrist).norm() <= self.cfg.wrist_confirm_m);
        // the collaborative arm (its hand, its elbow) never confirms: its
        // force is the collaboration's
        let part = self.machine.part();
        let elbow = match part {
            CollabPart::RightHand => Some(SkeletonJoint::RightElbow),
            CollabPart::LeftHand => Some(SkeletonJoint::LeftElbow),
            CollabPart::None => None,
        };
        let own = |i: usize| {
            part.joint().is_some_and(|j| j as usize == i) || elbow.is_some_and(|j| j as usize == i)
        };
        let confirmed = (seen_in_depth && !hand_at_wrist)
            || sk.is_some_and(|sk| {
                let n = (sk.n_people as usize).min(MAX_PEOPLE);
                sk.people[..n].iter().filter(|p| p.tracked != 0).any(|p| {
                    p.joints
                        .iter()
                        .zip(&p.confidence)
                        .enumerate()
                        .any(|(i, (j, c))| {
                            *c >= self.cfg.min_hand_confidence
                                && !own(i)
                                && (Vector3::from(*j) - wrist).norm() <= self.cfg.wrist_confirm_m
                        })
                })
            });
        if pattern && confirmed {
            let since = *self.wrist_since.get_or_insert(t);
            t - since >= self.cfg.wrist_hold_s
        } else {
            self.wrist_since = None;
            false
        }
    }

    /// Entering a collaboration mode from another mode: the reference starts
    /// at the measured end effector `ee` \[m\].
    pub fn enter(&mut self, ee: Vector3<f64>) {
        self.x_d = ee;
    }

    /// The end effector's Cartesian reference in the phase (`ee`: the
    /// measured end effector \[m\], `dt` \[s\], `speed_scale` of the safety judgement).
    pub fn reference(&mut self, ee: Vector3<f64>, dt: f64, speed_scale: f64) -> CartesianRef {
        // the end effector's point relative to the collaborative robot point
        // (aiming the wrist instead when the hand is nearer it reached a hand
        // held out to the wrist, but pressed the wrist into a hand the end
        // effector also touched: contacts that would not release)
        let offset = ee - self.robot_point;
        let mut velocity = Vector3::zeros();
        let phase = self.machine.phase();
        // following, the gap as far as it exceeds the one seen at the last
        // press (depth placed the touching hand that far off the surface,
        // and places it so still): the new touch at about `contact_speed`
        // instead of 2-3 times it
        let gap = self.near_gap - self.machine.follow_touch_gap().unwrap_or(0.0).max(0.0);
        if phase == CollabPhase::Contact && self.ref_phase != CollabPhase::Contact {
            // the touch: the approach's lead (up to `MAX_LEAD_M` where the
            // hand stopped the arm) would press on as a spring; the
            // admittance builds the contact force from `touch_lead_m`
            let lead = self.x_d - ee;
            let cap = self.cfg.touch_lead_m;
            if lead.norm() > cap {
                self.x_d = ee + lead * (cap / lead.norm());
            }
        }
        self.ref_phase = phase;
        match phase {
            CollabPhase::Approach | CollabPhase::Follow if self.other_closing.is_some() => {
                // the other hand closes in on the robot part: away from it
                // at its speed, and no approach (the repulsion alone is
                // slower than a hand thrust across the arm)
                if let Some((away, speed)) = self.other_closing {
                    velocity = away * speed;
                    self.x_d += velocity * dt;
                }
            }
            CollabPhase::Approach | CollabPhase::Follow => {
                velocity = self.toward_hand(offset, gap, dt, speed_scale);
            }
            CollabPhase::Contact => velocity = self.admittance(dt),
            CollabPhase::BackOff => velocity = self.backing_off(ee, dt, speed_scale),
            CollabPhase::Idle => self.x_d = ee,
        }
        // following, near the hand the lead shrinks with the gap: a
        // reference that ran ahead while the hand moved away would otherwise
        // pull the end effector into it at the feedback's cap on top of
        // `contact_speed` (the new touch at 0.14 m/s: 60-71 N on the hand).
        // The first approach keeps its lead: the arm comes from afar, and
        // near a hand held out beside the body the lead is what carries
        // the end effector through the body points' repulsion to the touch.
        // The lead shrinks with the gap as depth gives it, not by the
        // touch's depth error as the speed does: that gap reaches 0 with the
        // hand still cm away, where a lead of a few mm no longer carried
        // the end effector through the body's repulsion (safe-collaboration:
        // the follow held 5-10 cm off the moved hand and never touched it)
        let max_lead = match phase {
            CollabPhase::Follow => {
                let near = (self.near_gap.max(0.0) / self.cfg.slow_down_m).min(1.0);
                MIN_NEAR_LEAD_M + (MAX_LEAD_M - MIN_NEAR_LEAD_M) * near
            }
            _ => MAX_LEAD_M,
        };
        let lead = self.x_d - ee;
        if lead.norm() > max_lead {
            self.x_d = ee + lead * (max_lead / lead.norm());
        }
        CartesianRef {
            x_d: self.x_d,
            xd_d: velocity,
            speed_scale,
            path_time: None,
            // backing off, the hand is an obstacle like any other
            collab_hand: self.hand.filter(|_| self.back_off.is_none()),
            collab_touching: self.machine.phase() == CollabPhase::Contact,
            collab_point: match (self.contact_on_wrist, self.wrist_point) {
                (true, Some(i)) => i,
                _ => 0,
            },
            collab_speed_limit: match self.back_off.is_none() {
                true => self.hand_speed_limit,
                false => f64::INFINITY,
            },
        }
    }

    /// Approaching or following: the reference toward the hand, a reach
    /// short of it (`offset`: the end effector from the robot point \[m\]), at
    /// the approach speed far off and `contact_speed` relative to the hand
    /// within `slow_down_m` of `gap` \[m\]; its velocity \[m/s\].
    fn toward_hand(
        &mut self,
        offset: Vector3<f64>,
        gap: f64,
        dt: f64,
        speed_scale: f64,
    ) -> Vector3<f64> {
        let c = &self.cfg;
        let mut velocity = Vector3::zeros();
        if let Some(h) = self.hand {
            let to = h - self.robot_point;
            if to.norm() > 1e-6 {
                let reach = c.robot_radius_m + c.hand_radius_m - c.reach_into_m;
                let target = h - to.normalize() * reach + offset;
                let near = (gap.max(0.0) / c.slow_down_m).min(1.0);
                // within `slow_down_m`, the hand's own speed toward
                // the robot point is taken from the robot's, which
                // backs away from a hand coming faster, so that they
                // meet at `contact_speed` relative; the safety
                // judgement's scale slows the approach, never the
                // backing away
                let closing = -self.hand_velocity.dot(&(to / to.norm()));
                let closing = match closing > CLOSING_MIN && self.near_gap < c.slow_down_m {
                    true => closing,
                    false => 0.0,
                };
                let speed = c.contact_speed + (c.approach_speed - c.contact_speed) * near - closing;
                let speed = match speed >= 0.0 {
                    true => {
                        speed.min(c.approach_speed).min(self.hand_speed_limit)
                            * speed_scale.clamp(0.0, 1.0)
                    }
                    false => speed.max(-c.approach_speed.max(closing)),
                };
                let delta = target - self.x_d;
                let d = delta.norm();
                if d > 1e-9 {
                    velocity = delta / d * speed;
                    self.x_d += delta / d * (speed * dt).min(d);
                }
            }
        }
        velocity
    }

    /// In contact, the admittance: yield along the force the person
    /// applies, keep pressing the hand with `contact_hold_n`; its velocity
    /// \[m/s\] (none without an observable force).
    fn admittance(&mut self, dt: f64) -> Vector3<f64> {
        let c = &self.cfg;
        let mut velocity = Vector3::zeros();
        // admittance: yield along the force the person applies,
        // keep pressing the hand with `contact_hold_n`
        if let Some(e) = self.estimate.as_ref().filter(|e| e.observable[0]) {
            // against the force where it is felt (its direction is the
            // contact's normal), toward the hand seen in depth before
            let f = e.forces[0];
            let to = match f.norm() >= 0.5 * c.contact_force_n {
                true => -f,
                false => self
                    .hand
                    .map_or(Vector3::zeros(), |h| h - self.contact_axis),
            };
            let hold = match to.norm() > 1e-6 {
                true => to / to.norm() * c.contact_hold_n,
                false => Vector3::zeros(),
            };
            // F̂ is where the hand is (the robot part or the wrist):
            // the end effector's translation moves either alike
            velocity = (e.forces[0] + hold) * c.admittance;
            let v = velocity.norm();
            if v > c.approach_speed {
                velocity *= c.approach_speed / v;
            }
            self.x_d += velocity * dt;
        }
        velocity
    }

    /// Backing off: away along the force, `back_off_m` from where the end
    /// effector `ee` \[m\] was, at the approach speed; its velocity \[m/s\].
    fn backing_off(&mut self, ee: Vector3<f64>, dt: f64, speed_scale: f64) -> Vector3<f64> {
        let c = &self.cfg;
        let mut velocity = Vector3::zeros();
        // away along the force, `back_off_m`, at the approach speed
        if let Some(b) = self.back_off.as_mut() {
            let from = *b.ee.get_or_insert(ee);
            let target = from + b.dir * c.back_off_m;
            let delta = target - self.x_d;
            let d = delta.norm();
            let speed = c.approach_speed * speed_scale.clamp(0.0, 1.0);
            if d > 1e-9 {
                velocity = delta / d * speed;
                self.x_d += delta / d * (speed * dt).min(d);
            }
        }
        velocity
    }

    /// The wrist centre \[m\], base frame: the origin of `wrist_link`.
    pub fn wrist_centre(&self) -> Vector3<f64> {
        self.forces.frame_origin(self.wrist_frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hands_velocity_comes_from_sightings_in_order_within_a_skeletons_life() {
        let at = |x: f64, t_ms: u64| (Vector3::new(x, 0.0, 0.0), t_ms * 1_000_000);
        // a hand at 0.6 m/s, seen every 33 ms: the low-pass reaches its speed
        let mut v = Vector3::zeros();
        for k in 0..30 {
            let (from, to) = (
                at(0.0198 * k as f64, 33 * k),
                at(0.0198 * (k + 1) as f64, 33 * (k + 1)),
            );
            v = sighted_velocity(v, from, to, 0.1).unwrap();
        }
        assert!((v.x - 0.6).abs() < 1e-3 && v.y == 0.0, "{v}");
        // the first step is the filter's share of it: 1 − e^(−33/100)
        let first = sighted_velocity(Vector3::zeros(), at(0.0, 0), at(0.0198, 33), 0.1).unwrap();
        assert!((first.x - 0.6 * (1.0 - (-0.33f64).exp())).abs() < 1e-9);
        // out of order, the same capture, or a gap longer than a skeleton's life: nothing
        assert!(sighted_velocity(v, at(0.0, 50), at(0.1, 20), 0.1).is_none());
        assert!(sighted_velocity(v, at(0.0, 50), at(0.1, 50), 0.1).is_none());
        assert!(sighted_velocity(v, at(0.0, 0), at(0.1, 250), 0.1).is_none());
        assert_eq!(other_hand(CollabPart::LeftHand), CollabPart::RightHand);
        assert_eq!(other_hand(CollabPart::RightHand), CollabPart::LeftHand);
        assert_eq!(other_hand(CollabPart::None), CollabPart::None);
    }
}
