//! The avoidance stage: a behaviour's Cartesian reference of the end
//! effector becomes the joint reference. Under perception (paper Sect. V)
//! the end effector's repulsive vector adds to its task velocity (eq. 19),
//! every other control point shapes the joint velocity bounds (eq. 20) and
//! SNS solves the task within them and the joint-limit bounds, and (with
//! `body_avoidance = "null_space"`) each body point moves away from its
//! obstacle in the task's null space; without perception, CLIK with a
//! null-space posture.

use nalgebra::{DMatrix, DVectorView, Matrix6xX, Vector3};
use phri_config::{BodyAvoidance, ControlConfig, PointConfig};
use phri_ipc::MAX_DOF;
use phri_model::{Data, Model};

use crate::avoidance::Avoidance;
use crate::cbf::{CbfCounters, CbfFilter, WarmStart};
use crate::clik::{Clik, ClikGains};
use crate::drives::DriveCaps;
use crate::error::ControlError;
use crate::inputs::PerceptionView;
use crate::modes::CartesianRef;
use crate::reference::JointReference;
use crate::slew;
use crate::snapshot::{snapshot_fields, Reader, Snapshot, Writer};
use crate::ssm::SsmMonitor;

/// A point whose allowed approach is above this needs no bound [m/s] (no
/// joint moves a point that fast).
const SSM_UNBOUNDED_M_S: f64 = 5.0;

/// A point approaching its obstacle slower than this is not moving toward
/// it, for counting violations [m/s].
const SSM_MOVING_M_S: f64 = 0.01;

/// The time constant of the path's pace under the barrier filter \[s\].
const PATH_SCALE_FILTER_S: f64 = 0.05;

/// A nominal end-effector progress along the path below this sets no pace
/// [m/s].
const LET_THROUGH_MIN_M_S: f64 = 1e-3;

/// What speed and separation monitoring did, counted over the run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SsmCounters {
    /// periods in which it bounded some control point's approach
    pub limited_periods: u64,
    /// periods in which some control point had been moving toward its
    /// obstacle (faster than 1 cm/s) with its clearance below the
    /// protective separation distance for longer than the stop takes (T_s:
    /// the standard's S_p grants the stop that time)
    pub violation_periods: u64,
    /// violations: runs of such periods
    pub violations: u64,
    /// violations judged against the standard's own protective separation
    /// distance: ISO 13855's human speed (2.0 m/s within 0.5 m, 1.6 m/s
    /// beyond) in place of the configured one, the same other terms
    pub violations_standard: u64,
}

/// What speed and separation monitoring saw in the last period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsmPeriod {
    /// it bounded some control point's approach
    pub limiting: bool,
    /// a violation (see [`SsmCounters::violation_periods`])
    pub violating: bool,
    /// a violation of the standard's S_p (see [`SsmCounters::violations_standard`])
    pub violating_standard: bool,
    /// some control point approached its obstacle inside the protective
    /// separation distance of a standing robot: the reference dropped to
    /// the bounded solution at once (a stop of the approach), not at the
    /// reference's slew limit
    pub stopping: bool,
    /// the smallest clearance less the protective separation distance
    /// over the control points \[m\] (+∞: none monitored)
    pub min_margin_m: f64,
    /// the largest person's speed toward a control point used [m/s]
    pub human_speed_m_s: f64,
    /// T_r: the age of the perception acted on \[s\] (NaN: not monitoring)
    pub reaction_s: f64,
}

impl Default for SsmPeriod {
    fn default() -> SsmPeriod {
        SsmPeriod {
            limiting: false,
            violating: false,
            violating_standard: false,
            stopping: false,
            min_margin_m: f64::INFINITY,
            human_speed_m_s: 0.0,
            reaction_s: f64::NAN,
        }
    }
}

snapshot_fields!(SsmCounters {
    limited_periods,
    violation_periods,
    violations,
    violations_standard
});

snapshot_fields!(SsmPeriod {
    limiting,
    violating,
    violating_standard,
    stopping,
    min_margin_m,
    human_speed_m_s,
    reaction_s
});

/// What the resolver carries from one period to the next: per control
/// point the filtered repulsion and the behind-the-hand hysteresis, the
/// task scale, speed and separation monitoring (the monitor, when
/// configured, after a byte saying it is), the perception ages d_s
/// holds, the path's pace the barrier filter let through and (after a
/// byte saying it runs) the filter's warm start. CLIK, SNS, the body task
/// and the Jacobians keep nothing between periods.
impl Snapshot for Resolver {
    fn save(&self, w: &mut Writer<'_>) {
        self.v_call_filtered.save(w);
        self.behind_before.save(w);
        self.task_scale.save(w);
        w.bool(self.ssm.is_some());
        if let Some(m) = &self.ssm {
            m.save(w);
        }
        self.ssm_counters.save(w);
        self.ssm_period.save(w);
        self.ssm_was_violating.save(w);
        self.ssm_was_violating_standard.save(w);
        self.age_hold.save(w);
        self.path_scale.save(w);
        self.cbf.as_ref().map(CbfFilter::warm_start).save(w);
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        self.v_call_filtered.load(r);
        self.behind_before.load(r);
        self.task_scale.load(r);
        if r.bool() != self.ssm.is_some() {
            r.fail();
        }
        if let Some(m) = self.ssm.as_mut() {
            m.load(r);
        }
        self.ssm_counters.load(r);
        self.ssm_period.load(r);
        self.ssm_was_violating.load(r);
        self.ssm_was_violating_standard.load(r);
        self.age_hold.load(r);
        self.path_scale.load(r);
        // as an Option's layout; the tag is read here so that a dry run
        // checks it too
        if r.bool() != self.cbf.is_some() {
            r.fail();
        }
        let mut warm = WarmStart::default();
        warm.load(r);
        if let (Some(f), true) = (self.cbf.as_mut(), r.applying()) {
            f.adopt_warm_start(&warm);
        }
    }
}

/// While collaborating, d_s's perception age is the largest of this long's
/// two last spans \[s\]: at 30 Hz, the age just before a frame.
pub const AGE_HOLD_S: f64 = 0.05;

/// The largest perception ages of the current span and the one before.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct AgeHold {
    /// the current span's largest age \[s\]
    now: f64,
    /// the span before's \[s\]
    before: f64,
    /// time into the current span \[s\]
    since_s: f64,
}

snapshot_fields!(AgeHold {
    now,
    before,
    since_s
});

impl AgeHold {
    /// Take in `age_s` \[s\], `dt` \[s\] after the last: the largest age of
    /// the current span and the one before (a non-finite age starts over
    /// and is returned as it is).
    fn push(&mut self, age_s: f64, dt: f64) -> f64 {
        if !age_s.is_finite() {
            *self = AgeHold::default();
            return age_s;
        }
        self.since_s += dt.max(0.0);
        if self.since_s >= AGE_HOLD_S {
            self.before = self.now;
            self.now = 0.0;
            self.since_s = 0.0;
        }
        self.now = self.now.max(age_s);
        self.now.max(self.before)
    }
}

/// Failures met while resolving, counted (each leaves the fail-safe it always had).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Faults {
    /// model calls refused (kinematics, Jacobians)
    pub model: u64,
    /// avoidance or SNS refusals (dimensions, inconsistent bounds, non-finite values)
    pub avoidance: u64,
}

/// CLIK, the avoidance with its SNS solver, and the control points,
/// preallocated for one robot.
pub struct Resolver {
    clik: Clik,
    avoidance: Avoidance,
    /// control points: (link frame, point in it \[m\]); 0 is the end effector
    points: Vec<(usize, Vector3<f64>)>,
    jac_ee: Matrix6xX<f64>,
    jac_point: Matrix6xX<f64>,
    /// low-passed repulsive vectors per control point [m/s], base frame
    v_call_filtered: Vec<Vector3<f64>>,
    /// per control point: its obstacle lay behind the collaborative hand in
    /// the last period (the test then keeps it there for
    /// [`BEHIND_HYSTERESIS_M`] more: depth's noise flipped it frame by frame)
    behind_before: Vec<bool>,
    /// task scale of the last SNS solution
    task_scale: f64,
    /// speed and separation monitoring (`None`: `[ssm] enabled = false`)
    ssm: Option<SsmMonitor>,
    ssm_counters: SsmCounters,
    ssm_period: SsmPeriod,
    /// the last period monitored was a violation (a new one counts once)
    ssm_was_violating: bool,
    /// ... of the standard's S_p
    ssm_was_violating_standard: bool,
    /// the control-barrier filter (`None`: the paper's law)
    cbf: Option<CbfFilter>,
    /// each joint's acceleration cap from its drive (under the filter)
    drives: DriveCaps,
    /// d_s's perception age \[s\] (capture → command)
    perception_age_s: f64,
    /// the largest perception ages of the last two spans of [`AGE_HOLD_S`]
    age_hold: AgeHold,
    /// the share of the task's end-effector progress along the path the
    /// filter let through, low-passed, 0-1 (1 under the paper's law)
    path_scale: f64,
}

impl Resolver {
    /// For the end effector `ee_frame` of `model`.
    pub fn new(model: &Model, ee_frame: usize, cfg: &ControlConfig) -> Resolver {
        Resolver {
            clik: Clik::new(model, ee_frame),
            avoidance: {
                let mut a = Avoidance::new(model, cfg.avoidance_params);
                if cfg.body_avoidance == BodyAvoidance::NullSpace {
                    a.set_body_task(Some(cfg.body_repulsion_gain));
                }
                a
            },
            points: Vec::new(),
            jac_ee: Data::jacobian_buffer(model),
            jac_point: Data::jacobian_buffer(model),
            v_call_filtered: Vec::new(),
            behind_before: Vec::new(),
            task_scale: 1.0,
            ssm: None,
            ssm_counters: SsmCounters::default(),
            ssm_period: SsmPeriod::default(),
            ssm_was_violating: false,
            ssm_was_violating_standard: false,
            cbf: None,
            drives: DriveCaps::new(model),
            perception_age_s: 0.0,
            age_hold: AgeHold::default(),
            path_scale: 1.0,
        }
    }

    /// The avoidance law of `[avoidance]`: the paper's (eqs. 19-20, the
    /// default) or the control-barrier filter ([`crate::cbf`]).
    pub fn set_law(&mut self, cfg: &phri_config::AvoidanceConfig) -> Result<(), ControlError> {
        self.cbf = match cfg.law {
            phri_config::AvoidanceLaw::Paper => None,
            phri_config::AvoidanceLaw::Cbf => Some(CbfFilter::new(self.avoidance.n(), cfg)?),
        };
        Ok(())
    }

    /// The control-barrier filter is the law.
    pub fn cbf_law(&self) -> bool {
        self.cbf.is_some()
    }

    /// The drives' acceleration caps at the measured state (joint-space
    /// inertia `m` \[kg m²\], bias `C q̇ + g` \[Nm\]), for the barrier
    /// filter's reference ([`crate::drives`]); nothing under the paper's
    /// law, which does not read them.
    pub fn set_drives(&mut self, m: &DMatrix<f64>, bias: &[f64]) {
        if self.cbf.is_some() {
            self.drives.update(m, bias);
        }
    }

    /// What the control-barrier filter did so far (zeros under the paper's law).
    pub fn cbf_counters(&self) -> CbfCounters {
        self.cbf.as_ref().map(|f| f.counters()).unwrap_or_default()
    }

    /// The perception results' age this period \[s\], `dt` \[s\] after the
    /// last; `collaborating`: a collaboration's reference (approach,
    /// contact, follow). d_s takes the age itself, which grows by a frame
    /// period between frames and falls back at each, except while
    /// collaborating: then the largest age of the last [`AGE_HOLD_S`] to
    /// 2 × [`AGE_HOLD_S`]. A d_s rising and falling with the frames 30
    /// times a second (5 cm at 1.6 m/s) made the barrier push and release
    /// as often next to the person, and the end effector bounced on the
    /// hand it held (45-104 contact episodes where the person makes 2, F̂
    /// 40 % off).
    pub fn set_perception_age(&mut self, age_s: f64, dt: f64, collaborating: bool) {
        let held = self.age_hold.push(age_s, dt);
        self.perception_age_s = match collaborating {
            true => held,
            false => age_s,
        };
    }

    /// The share of the task's end-effector progress along the path the
    /// filter let through (low-passed), 0-1: the path's time slows by it
    /// under the filter (1 under the paper's law, whose path slows by its
    /// own rule).
    pub fn path_scale(&self) -> f64 {
        self.path_scale
    }

    /// The control points of the repulsion workers, in their configured
    /// order (the first is the end effector); an unknown link names its key.
    pub fn set_control_points(
        &mut self,
        model: &Model,
        points: &[PointConfig],
    ) -> Result<(), ControlError> {
        self.points = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let f = model
                    .frame_id(&p.link)
                    .map_err(|_| ControlError::UnknownLink {
                        key: format!("repulsion.points[{i}].link"),
                        link: p.link.clone(),
                    })?;
                Ok((f, Vector3::from(p.xyz)))
            })
            .collect::<Result<_, ControlError>>()?;
        self.v_call_filtered = vec![Vector3::zeros(); points.len()];
        self.behind_before = vec![false; points.len()];
        if let Some(m) = self.ssm.as_mut() {
            *m = SsmMonitor::with_cameras(m.config(), points.len(), m.cameras());
        }
        Ok(())
    }

    /// Speed and separation monitoring after `[ssm]` (`None`: off), with
    /// `cameras` cameras' results.
    pub fn set_ssm(&mut self, cfg: Option<&phri_config::SsmConfig>, cameras: usize) {
        self.ssm = cfg.map(|c| SsmMonitor::with_cameras(c, self.points.len(), cameras));
    }

    /// What speed and separation monitoring did so far.
    pub fn ssm_counters(&self) -> SsmCounters {
        self.ssm_counters
    }

    /// What speed and separation monitoring saw in the last period.
    pub fn ssm_period(&self) -> SsmPeriod {
        self.ssm_period
    }

    /// A period without the avoidance stage (a joint-space behaviour): the
    /// monitor saw nothing.
    pub fn skip_ssm_period(&mut self) {
        self.ssm_period = SsmPeriod::default();
        self.ssm_was_violating = false;
        self.ssm_was_violating_standard = false;
    }

    /// Speed and separation monitoring is configured.
    pub fn ssm_enabled(&self) -> bool {
        self.ssm.is_some()
    }

    /// The number of control points.
    pub fn control_points(&self) -> usize {
        self.points.len()
    }

    /// The end effector's frame (its origin is the task point).
    pub fn ee_frame(&self) -> usize {
        self.clik.frame()
    }

    /// Task scale of the last SNS solution (1 without perception).
    pub fn task_scale(&self) -> f64 {
        self.task_scale
    }

    /// Without perception: CLIK moves `q_ref` after `c`, writes `qd_ref`.
    #[allow(clippy::too_many_arguments)]
    pub fn clik(
        &mut self,
        model: &Model,
        data: &mut Data,
        reference: &mut JointReference,
        c: &CartesianRef,
        dt: f64,
        cfg: &ControlConfig,
        posture: &[f64],
        vmax: &[f64],
    ) -> Faults {
        let gains = ClikGains {
            clik: cfg.clik_gain,
            posture: cfg.posture_gain,
            damping: cfg.damping,
        };
        let step = self.clik.step(
            model,
            data,
            &mut reference.q_ref,
            &c.x_d,
            &c.xd_d,
            dt,
            gains,
            posture,
            vmax,
        );
        let model_errors = u64::from(step.is_err());
        self.path_scale = 1.0;
        reference.qd_ref.copy_from_slice(self.clik.velocity());
        Faults {
            model: model_errors,
            avoidance: 0,
        }
    }

    /// The task under avoidance (paper Sect. V): the end effector's repulsive
    /// velocity adds to its task velocity (eq. 19); every other control point
    /// shapes the joint velocity bounds (eq. 20); SNS solves the task within
    /// them and the joint-limit bounds. Moves `q_ref`, writes `qd_ref`.
    /// `perception`: fresh results (`None`: stale, no repulsion); `posture`:
    /// the body task's lowest level (empty: none). `ssm`: speed and
    /// separation monitoring applies this period, with the results this
    /// old \[s\] (`T_r`: capture → this command).
    #[allow(clippy::too_many_arguments)]
    pub fn avoid(
        &mut self,
        model: &Model,
        data: &mut Data,
        reference: &mut JointReference,
        c: &CartesianRef,
        dt: f64,
        cfg: &ControlConfig,
        posture: &[f64],
        perception: Option<PerceptionView<'_>>,
        ssm: Option<f64>,
    ) -> Faults {
        let mut faults = Faults::default();
        let x = match self.begin_avoidance((model, data), reference, c, cfg, posture) {
            Ok(x) => x,
            Err(f) => {
                reference.qd_ref.fill(0.0);
                return f;
            }
        };
        let mut v_ee = Vector3::zeros();
        // the end effector's clearance to its obstacle [m] (∞: none seen)
        let mut ee_clearance = f64::INFINITY;
        let alpha = repulsion_gain(cfg, dt);
        let was_violating = self.begin_ssm_period(ssm);
        let d_s = self.begin_filter();
        let period = &mut self.ssm_period;
        if let Some(v) = perception {
            if let Some(m) = self.ssm.as_mut() {
                m.observe(&v);
            }
            // the monitor measures the person's approach speeds in every
            // period; its separation applies only when `ssm` says so
            let mut monitor = self.ssm.as_mut();
            for (k, &(frame, xyz)) in self.points.iter().enumerate() {
                let Some(p) = v.points.get(k) else { break };
                let behind_the_hand = masked_by_hand(c, k, p, &mut self.behind_before);
                let target = if p.active == 0 || behind_the_hand {
                    Vector3::zeros()
                } else {
                    Vector3::from(p.v_call)
                };
                if k == 0 && p.active != 0 && !behind_the_hand && !p.min_distance.is_nan() {
                    ee_clearance = p.min_distance;
                }
                // the person's measured approach toward the point [m/s]
                let measured = monitor.as_deref().and_then(|m| m.measured_speed(k));
                // the point's result may come from an older camera than the
                // view's newest: its own age is T_r
                let older_s = v.point_older_s(k);
                // speed and separation monitoring: the point approaches its
                // obstacle no faster than the separation allows
                let bound = monitor
                    .as_deref_mut()
                    .zip(ssm.map(|t_r| t_r + older_s))
                    .filter(|_| p.active != 0)
                    .and_then(|(m, t_r)| approach_bound(m, k, p, t_r, period).map(|b| (m, t_r, b)));
                // under the filter, the point carries a barrier row
                let barrier = self.cbf.is_some() && p.active != 0 && !behind_the_hand;
                // the point's Jacobian, once, for its rows and its bound (a
                // refusal counted: then neither)
                let jacs = (&self.jac_ee, &mut self.jac_point);
                let needed = barrier || bound.is_some();
                let jac = jacobian_once(needed, (model, data), (k, frame, xyz), jacs, &mut faults);
                // the barrier row (which replaces eq. 19's and eq. 20's
                // repulsion), and the separation's bound as a row of its own
                let row = match (self.cbf.as_mut(), jac) {
                    (Some(filter), Some(j)) if barrier => {
                        let ages = (d_s, older_s);
                        let speeds = (measured, ssm.is_some(), bound.as_ref().map(|b| b.2 .0));
                        barrier_row(filter, c, (k, j), p, ages, speeds)
                    }
                    _ => Row::None,
                };
                let (inside, inside_standard) = match (bound, jac) {
                    (Some((m, t_r, bound)), Some(j)) => {
                        let a = Approach {
                            k,
                            p,
                            t_r,
                            qd_ref: &reference.qd_ref,
                        };
                        let limits = (&mut self.avoidance, &mut *period, &mut faults);
                        separate(m, &a, j, (bound, row), limits)
                    }
                    _ => (false, false),
                };
                // a violation: approaching inside S_p for longer than the
                // stop takes (S_p grants it T_s)
                if let Some(m) = monitor.as_deref_mut().filter(|_| ssm.is_some()) {
                    time_inside(m, k, (inside, inside_standard), dt, period);
                }
                let Some(f) = self.v_call_filtered.get_mut(k) else {
                    break;
                };
                *f += (target - *f) * alpha;
                let v_call = *f;
                if self.cbf.is_some() {
                    continue;
                }
                if v_call.norm() < 1e-6 {
                    continue;
                }
                if k == 0 {
                    v_ee = v_call;
                } else {
                    let into = (&mut self.jac_point, &mut self.avoidance);
                    add_body_point((model, data), (frame, xyz), v_call, into, &mut faults);
                }
            }
        }
        self.count_ssm_period(was_violating);
        faults.avoidance += self.resolve_task(reference, c, cfg, (x, v_ee, ee_clearance), dt);
        faults
    }

    /// The period's kinematics at `reference.q_ref` (the end effector's
    /// Jacobian) and the avoidance's bounds begun, with the body task and
    /// `posture` as `c` allows; the end effector's position \[m\], base
    /// frame, or the fault that stops the period.
    fn begin_avoidance(
        &mut self,
        (model, data): (&Model, &mut Data),
        reference: &JointReference,
        c: &CartesianRef,
        cfg: &ControlConfig,
        posture: &[f64],
    ) -> Result<Vector3<f64>, Faults> {
        let ee = self.clik.frame();
        let kinematics =
            phri_model::forward_kinematics(model, data, &reference.q_ref).and_then(|_| {
                phri_model::point_jacobian(model, data, ee, &Vector3::zeros(), &mut self.jac_ee)
            });
        if kinematics.is_err() {
            return Err(Faults {
                model: 1,
                avoidance: 0,
            });
        }
        // the body points move away in the task's null space, except while
        // collaborating (the hand's arm would roll the wrist into the hand);
        // the posture below them, except in contact with the hand (the arm
        // yields to it in its null space)
        self.avoidance
            .pause_body_task(c.collab_hand.is_some(), c.collab_touching);
        if self.avoidance.begin(&reference.q_ref).is_err() {
            return Err(Faults {
                model: 0,
                avoidance: 1,
            });
        }
        self.avoidance
            .set_posture(posture, &reference.q_ref, cfg.posture_gain);
        Ok(phri_model::frame_placement(model, data, ee).p)
    }

    /// A new period of the barrier filter (no rows): the distance its
    /// barriers keep at this perception's age, d_s \[m\] (0: no filter).
    fn begin_filter(&mut self) -> f64 {
        let age = self.perception_age_s;
        self.cbf.as_mut().map_or(0.0, |f| {
            f.begin();
            f.config().safe_distance_m(age)
        })
    }

    /// A new period of speed and separation monitoring (`ssm`: the
    /// results' age \[s\] when it applies); whether the period before was a
    /// violation (phri's, the standard's).
    fn begin_ssm_period(&mut self, ssm: Option<f64>) -> (bool, bool) {
        self.ssm_period = SsmPeriod {
            reaction_s: ssm.filter(|_| self.ssm.is_some()).unwrap_or(f64::NAN),
            ..SsmPeriod::default()
        };
        (self.ssm_was_violating, self.ssm_was_violating_standard)
    }

    /// The period's speed and separation monitoring into the run's
    /// counters (`was_violating`…: the period before's, so that a
    /// violation counts once).
    fn count_ssm_period(&mut self, (was_violating, was_violating_standard): (bool, bool)) {
        let period = self.ssm_period;
        self.ssm_counters.limited_periods += u64::from(period.limiting);
        self.ssm_counters.violation_periods += u64::from(period.violating);
        self.ssm_counters.violations += u64::from(period.violating && !was_violating);
        self.ssm_was_violating = period.violating;
        self.ssm_counters.violations_standard +=
            u64::from(period.violating_standard && !was_violating_standard);
        self.ssm_was_violating_standard = period.violating_standard;
    }

    /// The task resolved under the avoidance's bounds (SNS): the end
    /// effector's task velocity (the path's, with position feedback capped
    /// toward its obstacle and toward the collaborative hand) plus its
    /// repulsion `v_ee` \[m/s\], at `x` \[m\] with `ee_clearance` \[m\] to its
    /// obstacle; `qd_ref` slew-limited toward the solution, `q_ref`
    /// integrated over `dt` \[s\]. The avoidance faults (1: SNS failed, the
    /// reference braked).
    fn resolve_task(
        &mut self,
        reference: &mut JointReference,
        c: &CartesianRef,
        cfg: &ControlConfig,
        (x, v_ee, ee_clearance): (Vector3<f64>, Vector3<f64>, f64),
        dt: f64,
    ) -> u64 {
        let mut failed = 0;
        // position feedback: toward the end effector's obstacle capped below
        // the repulsion's V_max; the task's elsewhere faster (to rejoin its
        // path), the collaboration's at the cautious cap everywhere (it
        // approaches, follows and backs off from a person's hand)
        let task = c.path_time.is_some();
        let fb = cap_feedback(
            (c.x_d - x) * cfg.clik_gain,
            &v_ee,
            FeedbackCaps {
                toward: cfg.feedback_max_speed,
                free: if task {
                    cfg.feedback_free_speed
                } else {
                    cfg.feedback_max_speed
                },
                clearance: ee_clearance,
                approach_clearance: cfg.approach_clearance_m,
                approach_gain: if task { cfg.approach_gain } else { 0.0 },
            },
        );
        let xdot_task = limit_toward_hand(c, &x, c.xd_d + fb, &v_ee);
        // slew-limited towards the SNS solution (which stays within the bounds
        // it was computed for; the limit only delays reaching it), except
        // when the separation monitor stops an approach: then at once, as
        // the protective stop holds (no feed-forward of the step)
        let dv = match self.ssm_period.stopping {
            true => f64::INFINITY,
            // the filter's answer lags the reference no more than a slew
            // the barrier can live with: a hand at 1 m/s braked against
            false => match self.cbf.as_ref() {
                Some(f) => f.config().accel_limit * dt,
                None => cfg.reference_accel_limit * dt,
            },
        };
        // under the filter, with a jerk limit: (its slew, its jerk)
        let jerk = match (self.cbf.as_ref(), self.ssm_period.stopping) {
            (Some(f), false) if f.config().jerk_limit > 0.0 => {
                Some((f.config().accel_limit, f.config().jerk_limit))
            }
            _ => None,
        };
        // under the filter, each joint no faster than its drive gives it
        let mut caps = [f64::INFINITY; MAX_DOF];
        if self.cbf.is_some() && !self.ssm_period.stopping {
            for (i, cap) in caps.iter_mut().enumerate() {
                *cap = self.drives.cap(i);
            }
        }
        let solved = self
            .avoidance
            .solve(&self.jac_ee, &xdot_task, &v_ee, c.speed_scale)
            .map_err(|_| ())
            .and_then(|out| {
                self.task_scale = out.scale;
                match self.cbf.as_mut() {
                    None => Ok(out.qd),
                    Some(f) => {
                        let qd = f
                            .solve(&self.jac_ee, out.qd, (out.qd_min, out.qd_max))
                            .map_err(|_| ())?;
                        // low-passed: the path's pace follows the filter's
                        // braking, not its period-to-period changes
                        let r = let_through(&self.jac_ee, &c.xd_d, out.qd, qd);
                        self.path_scale +=
                            (r - self.path_scale) * (dt / PATH_SCALE_FILTER_S).min(1.0);
                        Ok(qd)
                    }
                }
            });
        match solved {
            Ok(qd) => {
                let r = &mut *reference;
                match jerk {
                    Some(limits) => {
                        let v = r.qd_ref.iter_mut().zip(r.qdd_ref.iter_mut());
                        for ((v, a), (&target, &cap)) in v.zip(qd.iter().zip(&caps)) {
                            slew::slew_jerk(v, a, target, (limits.0.min(cap), limits.1), dt);
                        }
                    }
                    None => {
                        for (v, (&target, &cap)) in r.qd_ref.iter_mut().zip(qd.iter().zip(&caps)) {
                            slew::slew(v, target, dv.min(cap * dt));
                        }
                    }
                }
                if self.ssm_period.stopping {
                    reference.qd_ref_prev.copy_from_slice(&reference.qd_ref);
                }
            }
            Err(()) => {
                failed = 1;
                self.task_scale = 0.0;
                self.path_scale = 0.0;
                for r in reference.qd_ref.iter_mut() {
                    *r -= r.clamp(-dv, dv);
                }
            }
        }
        for (q, v) in reference.q_ref.iter_mut().zip(&reference.qd_ref) {
            *q += v * dt;
        }
        failed
    }
}

/// The distance \[m\] the barrier keeps control point `k` from its
/// obstacle under `c`: `d_s`, except for the body points while a
/// collaboration has a hand (approach, contact, follow), which keep only
/// `margin_m` \[m\]: the person stands within reach on purpose, the
/// perception's age charged at ISO 13855's speed (5-7 cm more) held the
/// wrist and the forearm off the hand and off the arm it is held out on,
/// and the end effector, which carries the approach, keeps its `d_s` to
/// all but the hand. Under the paper's law the body points do not repel
/// at all while collaborating; speed and separation monitoring still
/// watches over every point.
fn collaborating_distance(c: &CartesianRef, k: usize, d_s: f64, margin_m: f64) -> f64 {
    match c.collab_hand.is_some() && k != 0 && k != c.collab_point {
        true => margin_m.min(d_s),
        false => d_s,
    }
}

/// What became of a control point's barrier row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Row {
    /// no separation's row: no filter, an inactive point or one behind or
    /// at the collaborative hand, no Jacobian, rows the filter could not
    /// take, or a point inside its `d_s` (the separation shapes the joint
    /// velocity bounds instead)
    None,
    /// a barrier row, and speed and separation monitoring's where it
    /// applies; `separation`: the separation's is the tighter
    Added { separation: bool },
}

/// Control point `k`'s barrier row in `filter` (Jacobian `j`; none for an
/// obstacle at the collaborative hand), `d_s` \[m\] for the view's age and the point's
/// result `older_s` \[s\] older (fused from an older camera: its age),
/// the person's approach `measured` \[m/s\] charged as [`barrier_speed`]
/// says (`separating`: outside a collaboration), the point's approach at
/// most `allowed` \[m/s\] (speed and separation monitoring's; none: not
/// monitored) as a row of its own while the point is clear of `d_s`.
fn barrier_row(
    filter: &mut CbfFilter,
    c: &CartesianRef,
    (k, j): (usize, &Matrix6xX<f64>),
    p: &phri_ipc::PointRepulsion,
    (d_s, older_s): (f64, f64),
    (measured, separating, allowed): (Option<f64>, bool, Option<f64>),
) -> Row {
    if c.collab_hand.is_some_and(|h| at_the_hand(&h, p)) {
        return Row::None;
    }
    let cfg = filter.config();
    let d_s = d_s + cfg.human_speed_m_s * older_s;
    let d_s = collaborating_distance(c, k, d_s, cfg.margin_m);
    let v_h = barrier_speed(
        measured,
        separating,
        c.collab_touching,
        cfg.collaboration_speed_m_s,
    );
    let away = away_from_obstacle(p);
    if !filter.add_point(k, j, &away, p.min_distance, d_s, v_h.unwrap_or(0.0)) {
        return Row::None;
    }
    match allowed {
        None => Row::Added { separation: false },
        // inside d_s the barrier pushes the point out, with slack where it
        // cannot: there the separation shapes the joint velocity bounds
        // (a row let the slack's trade swing the rest of the arm at full
        // speed, a hand in link 2's shadow beside the FR3's elbow: a swing
        // the residual took for a collision)
        Some(_) if p.min_distance < d_s => Row::None,
        // the separation's own row, without slack; none: its bounds
        Some(v) => filter
            .bound_approach(k, v)
            .map_or(Row::None, |tighter| Row::Added {
                separation: tighter,
            }),
    }
}

/// The person's approach speed toward a control point that its barrier
/// row charges \[m/s\] (`None`: none), of the one `measured`: all of it
/// while the separation is monitored (`separating`: outside a
/// collaboration); during a collaboration's approach and follow, at most
/// `collaboration_m_s` (another hand thrust at the arm is braked against
/// before it arrives; the hand thrust faster is a push on purpose, the
/// wrist push at 3 m/s, which the arm would flee as fast); none in contact.
fn barrier_speed(
    measured: Option<f64>,
    separating: bool,
    touching: bool,
    collaboration_m_s: f64,
) -> Option<f64> {
    match (separating, touching) {
        (true, _) => measured,
        (false, false) => measured.map(|v| v.min(collaboration_m_s)),
        (false, true) => None,
    }
}

/// The share of the nominal end effector's progress along the path's
/// direction `along` [m/s] (at `qd_nom`) that the filtered `qd` keeps,
/// 0-1: 1 when the path is at rest or the nominal makes no progress along
/// it (an end effector trailing its reference from aside or ahead: the time
/// law goes on, and the reference leads it away from what held it).
fn let_through(jac_ee: &Matrix6xX<f64>, along: &Vector3<f64>, qd_nom: &[f64], qd: &[f64]) -> f64 {
    // the linear rows times the joint velocities: a Vector3 on the stack
    let v = |qd: &[f64]| -> Vector3<f64> {
        jac_ee.fixed_rows::<3>(0) * DVectorView::from_slice(qd, qd.len())
    };
    let Some(u) = along.try_normalize(1e-9) else {
        return 1.0;
    };
    let (nom, got) = (v(qd_nom).dot(&u), v(qd).dot(&u));
    match nom > LET_THROUGH_MIN_M_S {
        true => (got / nom).clamp(0.0, 1.0),
        false => 1.0,
    }
}

/// Whether control point `k`'s obstacle (result `p`) is the collaborative
/// hand of `c`: for the end effector and the collaboration's point, while
/// it stays behind the hand (with hysteresis: `behind_before`); touching,
/// for every point, what lies at the hand. Then the point repels nothing.
fn masked_by_hand(
    c: &CartesianRef,
    k: usize,
    p: &phri_ipc::PointRepulsion,
    behind_before: &mut [bool],
) -> bool {
    let was_behind = behind_before.get(k).copied().unwrap_or(false);
    let margin = match c.collab_touching {
        true => BEHIND_MARGIN_CONTACT_M,
        false => BEHIND_MARGIN_M,
    };
    let behind_the_hand = (k == 0 || k == c.collab_point)
        && c.collab_hand
            .is_some_and(|h| still_behind(&h, p, margin, was_behind));
    if let Some(b) = behind_before.get_mut(k) {
        *b = behind_the_hand && p.active != 0;
    }
    // touching, what lies at the hand is the hand (for every point)
    behind_the_hand || (c.collab_touching && c.collab_hand.is_some_and(|h| at_the_hand(&h, p)))
}

/// A violation of the period: control point `k` approaching inside the
/// protective separation (`inside`: phri's, the standard's) for longer
/// than the stop takes (S_p grants it T_s) at this period of `dt` \[s\].
fn time_inside(
    m: &mut SsmMonitor,
    k: usize,
    (inside, inside_standard): (bool, bool),
    dt: f64,
    period: &mut SsmPeriod,
) {
    let for_s = m.approaching_inside(k, inside, dt);
    period.violating |= for_s > m.config().stop_time_s;
    let for_s = m.approaching_inside_standard(k, inside_standard, dt);
    period.violating_standard |= for_s > m.config().stop_time_s;
}

/// Body point `xyz` \[m\] of link frame `frame` repelled at `v_call`
/// \[m/s\]: its rows in the avoidance's joint velocity bounds (eq. 20),
/// its Jacobian computed into `jac`; refusals counted in `faults`.
fn add_body_point(
    (model, data): (&Model, &mut Data),
    (frame, xyz): (usize, Vector3<f64>),
    v_call: Vector3<f64>,
    (jac, avoidance): (&mut Matrix6xX<f64>, &mut Avoidance),
    faults: &mut Faults,
) {
    if phri_model::point_jacobian(model, data, frame, &xyz, jac).is_err() {
        faults.model += 1;
    } else if avoidance.add_point(jac, v_call).is_err() {
        faults.avoidance += 1;
    }
}

/// Control point `k`'s Jacobian (at `xyz` \[m\] of link frame `frame`):
/// the end effector's `jac_ee` for point 0, else computed into `jac_point`;
/// none when the model refused it.
fn point_jac<'j>(
    (model, data): (&Model, &mut Data),
    (k, frame, xyz): (usize, usize, Vector3<f64>),
    (jac_ee, jac_point): (&'j Matrix6xX<f64>, &'j mut Matrix6xX<f64>),
) -> Option<&'j Matrix6xX<f64>> {
    match k {
        0 => Some(jac_ee),
        _ => match phri_model::point_jacobian(model, data, frame, &xyz, &mut *jac_point) {
            Ok(_) => Some(jac_point),
            Err(_) => None,
        },
    }
}

/// The repulsions' low-pass gain over a period of `dt` \[s\] (1: unfiltered).
fn repulsion_gain(cfg: &ControlConfig, dt: f64) -> f64 {
    match cfg.repulsion_filter_s > 0.0 {
        true => 1.0 - (-dt / cfg.repulsion_filter_s).exp(),
        false => 1.0,
    }
}

/// [`point_jac`] when `needed` (else none), a refusal counted in `faults`.
fn jacobian_once<'j>(
    needed: bool,
    (model, data): (&Model, &mut Data),
    at: (usize, usize, Vector3<f64>),
    jacs: (&'j Matrix6xX<f64>, &'j mut Matrix6xX<f64>),
    faults: &mut Faults,
) -> Option<&'j Matrix6xX<f64>> {
    if !needed {
        return None;
    }
    let j = point_jac((model, data), at, jacs);
    faults.model += u64::from(j.is_none());
    j
}

/// One control point's approach to its obstacle under speed and separation
/// monitoring.
struct Approach<'a> {
    /// the point's index (0: the end effector)
    k: usize,
    /// its repulsion result: distance, direction, activity
    p: &'a phri_ipc::PointRepulsion,
    /// the results' age \[s\] (`T_r`: capture → this command)
    t_r: f64,
    /// the joint velocity reference of the last period \[rad/s\]
    qd_ref: &'a [f64],
}

/// Speed and separation monitoring of control point `k` (repulsion
/// result `p`, `t_r` \[s\] old): the human's speed into `period`; the
/// speed the separation allows toward its obstacle \[m/s\] and the
/// direction away from it, none when nothing bounds it.
fn approach_bound(
    m: &mut SsmMonitor,
    k: usize,
    p: &phri_ipc::PointRepulsion,
    t_r: f64,
    period: &mut SsmPeriod,
) -> Option<(f64, Vector3<f64>)> {
    let allowed = m.allowed_speed(k, p.min_distance, t_r);
    period.human_speed_m_s = period.human_speed_m_s.max(m.human_speed(k, p.min_distance));
    let away = away_from_obstacle(p);
    (allowed < SSM_UNBOUNDED_M_S && away != Vector3::zeros()).then_some((allowed, away))
}

/// The approach of a bounded control point (`j`: its Jacobian, `allowed`
/// \[m/s\] toward its obstacle, `away` from it) limited to what the
/// separation allows (as a row of the filter when `row` says it carries
/// one, else in the avoidance's joint velocity bounds), the period's margin and
/// flags into `period`; whether it approaches inside the protective
/// separation (phri's, and the standard's).
fn separate(
    m: &mut SsmMonitor,
    a: &Approach<'_>,
    j: &Matrix6xX<f64>,
    ((allowed, away), row): ((f64, Vector3<f64>), Row),
    (avoidance, period, faults): (&mut Avoidance, &mut SsmPeriod, &mut Faults),
) -> (bool, bool) {
    let (k, p, t_r) = (a.k, a.p, a.t_r);
    // the point's speed toward its obstacle at last period's reference
    let v_r = -along(j, &away, a.qd_ref);
    let margin = p.min_distance - m.separation(k, p.min_distance, v_r, t_r);
    period.min_margin_m = period.min_margin_m.min(margin);
    let moving = v_r > SSM_MOVING_M_S;
    let inside = moving && margin < 0.0;
    let standard = m.separation_standard(p.min_distance, v_r, t_r);
    let inside_standard = moving && p.min_distance < standard;
    period.stopping |= moving && allowed <= 0.0;
    match row {
        // the filter's row bounds the approach itself
        Row::Added { separation } => period.limiting |= separation,
        // eq. 20's way: the joint velocity bounds shaped
        Row::None => match avoidance.limit_approach(j, &away, allowed) {
            Ok(f) => period.limiting |= f > 0.0,
            Err(_) => faults.avoidance += 1,
        },
    }
    (inside, inside_standard)
}

/// Power and force limiting: the end effector's velocity `task + v_ee`
/// [m/s] (the task's and the repulsion's, eq. 19) toward the collaborative
/// hand of `c` at most its `collab_speed_limit` (Annex A's transient speed):
/// the task's part cut along the hand's direction from the end effector at
/// `x` \[m\]. SNS scales the task, never turns it, so the resolved end
/// effector approaches no faster.
fn limit_toward_hand(
    c: &CartesianRef,
    x: &Vector3<f64>,
    task: Vector3<f64>,
    v_ee: &Vector3<f64>,
) -> Vector3<f64> {
    let Some(h) = c.collab_hand.filter(|_| c.collab_speed_limit.is_finite()) else {
        return task;
    };
    let Some(u) = (h - x).try_normalize(1e-9) else {
        return task;
    };
    let toward = (task + v_ee).dot(&u);
    match toward > c.collab_speed_limit {
        true => task - u * (toward - c.collab_speed_limit),
        false => task,
    }
}

/// The caps of [`cap_feedback`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedbackCaps {
    /// toward the obstacle, once `‖V_Call‖ ≥ toward` [m/s]
    pub toward: f64,
    /// the whole feedback [m/s]
    pub free: f64,
    /// the end effector's clearance to its obstacle \[m\] (∞: none)
    pub clearance: f64,
    /// the net approach may go on down to this clearance \[m\] ...
    pub approach_clearance: f64,
    /// ... at `gain × (clearance − approach_clearance)` [1/s] (0: never)
    pub approach_gain: f64,
}

/// The end effector's position feedback `fb` [m/s], capped (`v_call`: its
/// repulsive vector, base frame [m/s]):
/// - the whole at `free`, so that an end effector pushed off its path by
///   an obstacle rejoins the path once past it rather than trailing it;
/// - its component toward the obstacle (against `v_call`) at the larger of
///   1. `free` with no repulsion, down to `toward` once `‖v_call‖ ≥ toward`
///      (where feedback and repulsion balance, `‖v_call‖ = toward` below
///      the repulsion's `V_max`, the repulsion wins), and
///   2. `‖v_call‖ + gain (clearance − approach_clearance)`: the feedback
///      may beat the repulsion by a net approach speed that falls linearly
///      with the clearance and ends at `approach_clearance` (speed and
///      separation: a path through a person's reach is followed up to that
///      clearance, slowly near it, never nearer).
///
/// A non-finite `v_call` caps the whole at `toward`.
pub fn cap_feedback(fb: Vector3<f64>, v_call: &Vector3<f64>, caps: FeedbackCaps) -> Vector3<f64> {
    let FeedbackCaps { toward, free, .. } = caps;
    let free = free.max(toward);
    let norm = v_call.norm();
    let mut out = fb;
    if norm > 1e-9 && norm.is_finite() {
        let u = v_call / norm;
        let along = fb.dot(&u);
        let repelled = free - (free - toward) * (norm / toward.max(1e-9)).min(1.0);
        let margin = caps.clearance - caps.approach_clearance;
        let approach = if caps.approach_gain > 0.0 && margin > 0.0 {
            norm + caps.approach_gain * margin
        } else {
            0.0
        };
        let cap = repelled.max(approach).min(free);
        if along < -cap {
            out += u * (-cap - along);
        }
    } else if !norm.is_finite() {
        // no usable direction: the cautious cap everywhere
        if out.norm() > toward {
            out *= toward / out.norm();
        }
        return out;
    }
    if out.norm() > free {
        out *= free / out.norm();
    }
    out
}

/// Margin by which an obstacle must lie beyond the collaborative hand's
/// centre to be "behind" it \[m\]: less than the hand's radius, so that the
/// hand's own near surface, were it not masked, still repels the end effector.
const BEHIND_MARGIN_M: f64 = 0.02;
/// The margin while the end effector touches the hand \[m\]: more than the
/// hand's radius; what lies about as deep as the hand then is the hand
/// itself (where the tracker misplaced the mask) and the mask's edge, and
/// its repulsion would only shake the contact.
const BEHIND_MARGIN_CONTACT_M: f64 = 0.05;

/// An obstacle found behind the collaborative hand stays behind it until
/// it comes this much nearer than the margin \[m\] (depth's noise of a few
/// centimetres flipped a body just behind the hand in and out, each flip a
/// step of the end effector's repulsion that shook a held contact).
const BEHIND_HYSTERESIS_M: f64 = 0.03;

/// While touching the collaborative hand, an obstacle this near the hand's
/// centre as the controller sees it \[m\] is the hand itself or its mask's
/// edge (the hand's radius 4.5 cm, depth's error of the centre 3-5 cm).
pub(crate) const AT_THE_HAND_M: f64 = 0.10;

/// Unit vector from `p`'s closest obstacle point to the control point (base
/// frame); touching (no direction between them), away along its repulsion;
/// 0 when neither gives one.
fn away_from_obstacle(p: &phri_ipc::PointRepulsion) -> Vector3<f64> {
    let away = Vector3::from(p.position) - Vector3::from(p.obstacle);
    match away.norm() > 1e-9 && away.iter().all(|x| x.is_finite()) {
        true => away.normalize(),
        false => Vector3::from(p.v_call)
            .try_normalize(1e-12)
            .unwrap_or_default(),
    }
}

/// The speed \[m/s\] along unit `u` of the point whose Jacobian is `jac`
/// (its first three rows linear), at joint velocities `qd` \[rad/s\].
fn along(jac: &Matrix6xX<f64>, u: &Vector3<f64>, qd: &[f64]) -> f64 {
    qd.iter()
        .enumerate()
        .map(|(col, v)| (u.x * jac[(0, col)] + u.y * jac[(1, col)] + u.z * jac[(2, col)]) * v)
        .sum()
}

/// The obstacle of `p` is the collaborative hand `h` itself ([`AT_THE_HAND_M`]):
/// touching, no point repels it; under the barrier filter, no point keeps
/// its distance to it while a collaboration has the hand (the wrist and
/// the last links reach a hand held out beside the end effector).
fn at_the_hand(h: &Vector3<f64>, p: &phri_ipc::PointRepulsion) -> bool {
    let o = Vector3::from(p.obstacle);
    o.iter().all(|v| v.is_finite()) && (o - h).norm() <= AT_THE_HAND_M
}

/// [`behind`], with [`BEHIND_HYSTERESIS_M`] more margin for an obstacle
/// that lay behind the hand in the last period (`was`).
fn still_behind(h: &Vector3<f64>, p: &phri_ipc::PointRepulsion, margin: f64, was: bool) -> bool {
    let more = if was { BEHIND_HYSTERESIS_M } else { 0.0 };
    behind(h, p, margin + more)
}

/// The obstacle of `p` lies behind the collaborative hand `h` as seen from
/// the control point: farther along the direction to the hand than the hand,
/// less a margin (the person's body behind the hand the robot is asked to
/// touch; a hand crossing in between is nearer and still repels).
fn behind(h: &Vector3<f64>, p: &phri_ipc::PointRepulsion, margin: f64) -> bool {
    let (o, x) = (Vector3::from(p.obstacle), Vector3::from(p.position));
    let to_hand = h - x;
    let d = to_hand.norm();
    if d < 1e-6 || !o.iter().chain(x.iter()).all(|v| v.is_finite()) {
        return false;
    }
    (o - x).dot(&to_hand) / d >= d - margin
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_collaboration_charges_the_approach_up_to_its_cap_and_none_in_contact() {
        assert_eq!(barrier_speed(Some(3.0), true, false, 1.0), Some(3.0));
        assert_eq!(barrier_speed(Some(3.0), false, false, 1.0), Some(1.0));
        assert_eq!(barrier_speed(Some(0.4), false, false, 1.0), Some(0.4));
        assert_eq!(barrier_speed(Some(3.0), false, true, 1.0), None);
        assert_eq!(barrier_speed(None, true, false, 1.0), None);
    }

    #[test]
    fn the_pace_is_the_progress_along_the_path_the_filter_let_through() {
        // three joints moving the end effector along x, y and z
        let mut jac = Matrix6xX::zeros(3);
        jac.fixed_view_mut::<3, 3>(0, 0).fill_with_identity();
        let x = Vector3::x();
        // along the path: half of it let through, none, or backwards
        assert!((let_through(&jac, &x, &[0.2, 0.0, 0.0], &[0.1, 0.05, 0.0]) - 0.5).abs() < 1e-12);
        assert_eq!(
            let_through(&jac, &x, &[0.2, 0.0, 0.0], &[0.0, 0.1, 0.0]),
            0.0
        );
        assert_eq!(
            let_through(&jac, &x, &[0.2, 0.0, 0.0], &[-0.1, 0.0, 0.0]),
            0.0
        );
        // more progress than asked: the full pace, no more
        assert_eq!(
            let_through(&jac, &x, &[0.2, 0.0, 0.0], &[0.3, 0.0, 0.0]),
            1.0
        );
        // trailing the reference from aside (the nominal makes no progress
        // along the path) and held there: the path goes on
        assert_eq!(
            let_through(&jac, &x, &[0.0, 0.2, 0.0], &[0.0, 0.0, 0.0]),
            1.0
        );
        // the path at rest: the full pace
        assert_eq!(
            let_through(&jac, &Vector3::zeros(), &[0.2, 0.0, 0.0], &[0.0; 3]),
            1.0
        );
    }

    #[test]
    fn the_held_age_is_the_frames_largest_and_follows_a_faster_camera() {
        let mut h = AgeHold::default();
        // 30 Hz frames 6.5 ms after capture: the age runs 6.5-39.8 ms
        let age = |t_ms: u64, period_ms: f64| 6.5e-3 + (t_ms as f64 % period_ms) * 1e-3;
        let mut held = Vec::new();
        for t in 0..1000u64 {
            held.push(h.push(age(t, 33.3), 1e-3));
        }
        // after the first 100 ms, steady at the age just before a frame
        let (lo, hi) = held[100..]
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(lo > 0.0385 && hi < 0.0399, "{lo} {hi}");
        // a camera at 60 Hz: within 100 ms the held age is its own
        for t in 0..100u64 {
            h.push(age(t, 16.7), 1e-3);
        }
        let now = h.push(age(100, 16.7), 1e-3);
        assert!(now < 0.0235, "{now}");
        // a non-finite age passes through and starts over
        assert!(h.push(f64::NAN, 1e-3).is_nan());
        assert_eq!(h, AgeHold::default());
    }

    /// The LWR-IV at a bent pose: the end effector's speed toward a hand
    /// 0.4 m ahead of it along +y under a collaboration's reference that
    /// wants 2 m/s toward it, after 0.3 s, bounded by `limit` [m/s].
    fn approach_toward_a_hand(limit: f64) -> f64 {
        let model = Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        let cfg = phri_config::Config::defaults().control;
        let ee = model.frame_id("lwr_link_7").unwrap();
        let mut r = Resolver::new(&model, ee, &cfg);
        let mut data = Data::new(&model);
        let mut reference = JointReference::new(7);
        reference
            .q_ref
            .copy_from_slice(&[0.0, 0.6, 0.0, -1.4, 0.0, 0.8, 0.0]);
        phri_model::forward_kinematics(&model, &mut data, &reference.q_ref).unwrap();
        let x0 = phri_model::frame_placement(&model, &data, ee).p;
        let toward = Vector3::new(0.0, 1.0, 0.0);
        let hand = x0 + toward * 0.4;
        let mut approach = 0.0;
        let mut jac = Data::jacobian_buffer(&model);
        for _ in 0..300 {
            phri_model::forward_kinematics(&model, &mut data, &reference.q_ref).unwrap();
            let x = phri_model::frame_placement(&model, &data, ee).p;
            let c = CartesianRef {
                x_d: x + toward * 0.05,
                xd_d: toward * 2.0,
                speed_scale: 1.0,
                path_time: None,
                collab_hand: Some(hand),
                collab_touching: false,
                collab_point: 0,
                collab_speed_limit: limit,
            };
            let view = PerceptionView {
                capture_ns: 1,
                points: &[],
                sources: &[],
            };
            let f = r.avoid(
                &model,
                &mut data,
                &mut reference,
                &c,
                0.001,
                &cfg,
                &[],
                Some(view),
                None,
            );
            assert_eq!(f, Faults::default());
            phri_model::point_jacobian(&model, &data, ee, &Vector3::zeros(), &mut jac).unwrap();
            approach = along(&jac, &toward, &reference.qd_ref);
        }
        approach
    }

    #[test]
    fn the_end_effector_meets_the_collaborative_hand_no_faster_than_annex_a_allows() {
        let free = approach_toward_a_hand(f64::INFINITY);
        let bounded = approach_toward_a_hand(0.3);
        // not vacuous: unbounded, the reference carries it in faster
        assert!(free > 0.5, "{free}");
        assert!(bounded <= 0.3 + 1e-6 && bounded > 0.2, "{bounded}");
    }

    fn caps(clearance: f64, approach_gain: f64) -> FeedbackCaps {
        FeedbackCaps {
            toward: 0.1,
            free: 0.5,
            clearance,
            approach_clearance: 0.08,
            approach_gain,
        }
    }

    #[test]
    fn feedback_toward_the_obstacle_loses_to_a_strong_repulsion() {
        // the obstacle lies in −x: the repulsion points +x
        let toward = Vector3::new(-3.0, 0.0, 0.0);
        let side = Vector3::new(0.0, 3.0, 0.0);
        // no repulsion: the whole cap
        let fb = cap_feedback(toward, &Vector3::zeros(), caps(f64::INFINITY, 0.0));
        assert!((fb.norm() - 0.5).abs() < 1e-12);
        // a strong repulsion (≥ toward): 0.1 m/s toward it, less than ‖V_Call‖
        let v = Vector3::new(0.25, 0.0, 0.0);
        let fb = cap_feedback(toward, &v, caps(0.1, 0.0));
        assert!((fb.x + 0.1).abs() < 1e-12);
        // a weak one: the cap falls linearly from 0.5 to 0.1 as ‖V_Call‖ grows to 0.1
        let fb = cap_feedback(toward, &Vector3::new(0.05, 0.0, 0.0), caps(0.3, 0.0));
        assert!((fb.x + 0.3).abs() < 1e-12);
        // beside the obstacle: not capped below the whole cap
        let fb = cap_feedback(side, &v, caps(0.1, 0.0));
        assert!((fb - Vector3::new(0.0, 0.5, 0.0)).norm() < 1e-12);
        // toward and beside: only the part toward it is cut
        let fb = cap_feedback(Vector3::new(-0.2, 0.2, 0.0), &v, caps(0.1, 0.0));
        assert!((fb - Vector3::new(-0.1, 0.2, 0.0)).norm() < 1e-12);
        // a malformed repulsion: the cautious cap everywhere
        let nan = Vector3::new(f64::NAN, 0.0, 0.0);
        assert!((cap_feedback(side, &nan, caps(0.1, 0.0)).norm() - 0.1).abs() < 1e-12);
    }

    #[test]
    fn a_body_just_behind_the_hand_stays_behind_it_through_depths_noise() {
        // the control point at the origin, the hand 0.2 m along x; the
        // boundary of the contact margin lies at x = 0.15
        let h = Vector3::new(0.2, 0.0, 0.0);
        let at = |x: f64| phri_ipc::PointRepulsion {
            position: [0.0; 3],
            obstacle: [x, 0.05, 0.0],
            active: 1,
            ..Default::default()
        };
        let m = BEHIND_MARGIN_CONTACT_M;
        // depth's noise moves the body ±1.5 cm about the boundary
        let xs = [0.16, 0.14, 0.165, 0.136, 0.158, 0.137];
        let mut was = still_behind(&h, &at(xs[0]), m, false);
        let (mut flips_held, mut flips_bare) = (0, 0);
        for w in xs.windows(2) {
            let before = was;
            was = still_behind(&h, &at(w[1]), m, before);
            flips_held += (was != before) as u32;
            flips_bare += (behind(&h, &at(w[1]), m) != behind(&h, &at(w[0]), m)) as u32;
        }
        assert!(behind(&h, &at(xs[0]), m), "it starts behind");
        assert_eq!(flips_held, 0, "held behind through the noise");
        assert_eq!(flips_bare, 5, "without the hysteresis it flips each frame");
        // a part that comes clearly nearer than the hand repels again
        assert!(!still_behind(&h, &at(0.10), m, true));
        assert!(!still_behind(&h, &at(0.05), m, true));
    }

    #[test]
    fn the_approach_beats_the_repulsion_only_down_to_its_clearance() {
        let toward = Vector3::new(-3.0, 0.0, 0.0);
        let v = Vector3::new(0.25, 0.0, 0.0);
        // 0.13 m: ‖V_Call‖ + 2 (0.13 − 0.08) = 0.35 m/s, a net approach of 0.1 m/s
        let fb = cap_feedback(toward, &v, caps(0.13, 2.0));
        assert!((fb.x + 0.35).abs() < 1e-12);
        assert!((-fb.x - v.x - 0.1).abs() < 1e-12);
        // at the clearance and nearer: the repulsion wins again
        for d in [0.08, 0.05, 0.0] {
            let fb = cap_feedback(toward, &v, caps(d, 2.0));
            assert!((fb.x + 0.1).abs() < 1e-12, "{d}: {fb:?}");
        }
        // never beyond the whole cap
        let fb = cap_feedback(toward, &v, caps(0.4, 2.0));
        assert!((fb.x + 0.5).abs() < 1e-12);
    }
}
