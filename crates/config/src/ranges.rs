//! The safe ranges of every safety-relevant setting, in one place: a value
//! outside its range is refused at start with one line naming the key, the
//! value and the range (`perception.self_filter.margin_m = 3 is outside its
//! safe range [0, 0.1] m: …`). Each range keeps its function meaningful: a
//! self-filter margin of 3 m removes the person with the robot (perception
//! blind: 7 contacts up to 180 N), a stale-input bound of minutes keeps a
//! controller acting on a world long gone. `deploy/phri.toml` gives each
//! range beside its key (`safe: [lo, hi]`, checked by this module's tests).
//!
//! Switching a function off on purpose is not a value out of range:
//! `control.avoidance = false`, `ssm.enabled = false` and a dropped
//! perception or residual service stay possible, and make every report of
//! the run degraded ([`crate::Loaded::safety_off`]).
//!
//! Ranges that depend on the arm are checked with its model
//! ([`check_model`]): detection thresholds at most the joints' torque
//! limits, waypoints within the arm's reach.

use toml::{Table, Value};

use crate::error::Invalid;
use crate::Config;

/// One safe range: `lo` (excluded when `lo_open`) to `hi`, both included otherwise.
#[derive(Clone, Copy, Debug)]
pub struct Range {
    /// dotted key (`perception.self_filter.margin_m`)
    pub key: &'static str,
    /// lower end, in `unit`
    pub lo: f64,
    /// `lo` itself is outside the range
    pub lo_open: bool,
    /// upper end, in `unit` (always included)
    pub hi: f64,
    /// the key's unit ("" for a dimensionless number)
    pub unit: &'static str,
    /// what goes wrong outside it
    pub why: &'static str,
}

impl Range {
    /// `[lo, hi] unit` or `(lo, hi] unit`
    pub fn text(&self) -> String {
        format!(
            "{}{}, {}]{}{}",
            if self.lo_open { "(" } else { "[" },
            self.lo,
            self.hi,
            if self.unit.is_empty() { "" } else { " " },
            self.unit
        )
    }

    fn holds(&self, v: f64) -> bool {
        v.is_finite() && (v > self.lo || (!self.lo_open && v == self.lo)) && v <= self.hi
    }
}

const fn r(key: &'static str, lo: f64, hi: f64, unit: &'static str, why: &'static str) -> Range {
    Range {
        key,
        lo,
        lo_open: false,
        hi,
        unit,
        why,
    }
}

/// A range whose lower end is excluded (`(0, hi]`).
const fn ro(key: &'static str, lo: f64, hi: f64, unit: &'static str, why: &'static str) -> Range {
    Range {
        key,
        lo,
        lo_open: true,
        hi,
        unit,
        why,
    }
}

const STALE: &str = "an input older than 1 s describes a world long gone";

/// ISO/TS 15066 Annex A, Table A.2: the hands' quasi-static limit \[N\].
pub fn iso_hand_limit_n() -> f64 {
    phri_iso15066::BodyRegion::HandAndFingers.quasi_static_n()
}

/// ISO/TS 15066 Annex A, Table A.2: the lower arms' quasi-static limit \[N\].
pub fn iso_lower_arm_limit_n() -> f64 {
    phri_iso15066::BodyRegion::LowerArmAndWrist.quasi_static_n()
}

/// The smallest stopping time `T_s` \[s\] the cell may assume: the arm's
/// measured stop (lock-step: at most 47 ms up to 1.1 m/s, BENCHMARKS.md
/// "How the arm stops"); ISO/TS 15066 5.5.4 takes `T_s` as measured, never
/// less.
pub const MIN_STOP_TIME_S: f64 = 0.047;
/// The smallest `S_s` per speed \[s\] (measured: at most 18 ms × v).
pub const MIN_STOP_DISTANCE_PER_SPEED_S: f64 = 0.018;
/// The smallest `Z_d` \[m\]: the depth sensor's noise at 2 m (6 mm).
pub const MIN_SENSOR_UNCERTAINTY_M: f64 = 0.006;

/// Every safety-relevant setting's safe range. Hand and lower-arm limits
/// are Annex A's ([`iso_hand_limit_n`], [`iso_lower_arm_limit_n`]: 140 and
/// 160 N as transcribed publicly).
pub const SAFETY_RANGES: &[Range] = &[
    // perception: what the controller sees
    ro("perception.max_state_gap_ms", 0.0, 100.0, "ms", "a joint state farther from the capture misplaces the arm's mask by centimetres"),
    ro("perception.max_frame_age_ms", 0.0, 1000.0, "ms", STALE),
    r("perception.self_filter.margin_m", 0.0, 0.1, "m", "a larger margin removes a person's pixels near the arm: perception blind where contact happens"),
    r("perception.self_filter.depth_tolerance_m", 0.0, 0.1, "m", "a larger tolerance removes a hand lying on the arm"),
    r("perception.self_filter.noise_sigmas", 0.0, 5.0, "", "more sigmas of depth noise remove a hand lying on the arm"),
    ro("camera.rate_hz", 0.0, 1000.0, "Hz", "frames per second"),
    ro("camera.max_age_s", 0.0, 1.0, "s", STALE),
    // the repulsion (eq. 16)
    r("repulsion.params.rho", 0.1, 2.0, "m", "below 0.1 m the repulsion begins too close to evade a person; above 2 m it holds the arm away from the whole room"),
    r("repulsion.params.v_max", 0.05, 1.0, "m/s", "below 0.05 m/s the arm cannot evade a walking person; above 1 m/s the evasion is itself a hazard"),
    r("repulsion.params.alpha", 1.0, 20.0, "", "the sigmoid's shape: outside it the repulsion is a step or never full"),
    r("repulsion.points.radius", 0.0, 0.3, "m", "a control sphere larger than an arm's link subtracts distance the person is at"),
    r("robot.capsules.radius", 0.0, 0.3, "m", "a capsule larger than an arm's link masks the person from perception and contacts"),
    // the residual and detection
    r("dynamics.gain", 10.0, 1000.0, "1/s", "a slower observer detects a collision after the arm has pressed on"),
    r("dynamics.velocity_cutoff_hz", 5.0, 500.0, "Hz", "a lower cutoff delays the velocity the residual's model needs: false or late detections"),
    ro("dynamics.max_gap_s", 0.0, 1.0, "s", STALE),
    r("dynamics.warmup_samples", 0.0, 1000.0, "samples", "no detection for longer than 1 s after a (re)start"),
    r("dynamics.standby_wake_ms", 0.0, 25.0, "ms", "the standby residual steps this many periods' states at once, on the torque loop's CPU"),
    // the controller's inputs, reactions and speeds
    r("control.standby_wake_ms", 0.0, 25.0, "ms", "past the 32 behaviours its channel queues, a standby loses the path history a retreat after its takeover walks back"),
    ro("control.residual_max_age_ms", 0.0, 1000.0, "ms", STALE),
    ro("control.perception_max_age_ms", 0.0, 1000.0, "ms", STALE),
    ro("control.perception_stop_after_ms", 0.0, 5000.0, "ms", "stale perception this long stops the arm whatever was seen last"),
    r("control.near_distance_m", 0.1, 2.0, "m", "stale perception with a person this near stops the arm"),
    r("control.slow_scale", 0.0, 0.5, "", "the speed while perception is stale"),
    ro("control.velocity_scale", 0.0, 1.0, "", "the fraction of the joints' velocity limits the reference may use"),
    ro("control.approach_speed", 0.0, 0.5, "m/s", "the end effector's speed (re)joining the path"),
    ro("control.feedback_max_speed", 0.0, 1.0, "m/s", "the feedback toward an obstacle, below repulsion.params.v_max"),
    ro("control.feedback_free_speed", 0.0, 1.5, "m/s", "the end effector rejoining its path"),
    ro("control.reference_accel_limit", 0.0, 100.0, "rad/s²", "the reference's slew under avoidance"),
    r("control.repulsion_filter_s", 0.0, 0.5, "s", "a slower low-pass delays the evasion"),
    r("control.body_repulsion_gain", 0.0, 10.0, "", "the body points' evasion"),
    r("control.approach_clearance_m", 0.02, 1.0, "m", "the end effector's nearest approach along its path"),
    r("control.approach_gain", 0.0, 10.0, "1/s", "the approach toward an obstacle"),
    r("control.reflex_gain", 0.0, 10.0, "", "K_R of eq. 9"),
    r("control.reflex_damping", 0.0, 100.0, "1/s", "D_R of eq. 9"),
    r("control.admittance_gain", 0.0, 1.0, "rad/(Nm s)", "K_Q of eq. 13"),
    r("control.reaction_min_s", 0.0, 5.0, "s", "the reaction's length"),
    r("control.retreat_path_s", 0.0, 5.0, "s", "the retreat's length"),
    r("control.resume_quiet_s", 0.2, 60.0, "s", "resuming sooner after a collision drives into the person again"),
    r("control.position_margin", 0.0, 0.5, "rad", "the margin inside the position limits"),
    ro("control.avoidance_params.accel_limit", 0.0, 100.0, "rad/s²", "the joint-limit bounds' acceleration"),
    r("control.avoidance_params.horizon_s", 0.0, 1.0, "s", "eq. 20's horizon"),
    r("control.avoidance_params.position_margin", 0.0, 0.5, "rad", "the margin of eq. 20's position bounds"),
    // speed and separation monitoring: the terms' minima are the arm's measured stop and the sensor's noise
    ro("avoidance.gamma", 0.0, 20.0, "1/s", "a barrier rate faster than the arm can brake lets a point close in at speed until the last centimetres"),
    r("avoidance.margin_m", 0.02, 0.5, "m", "a clearance below depth's noise and the mask's margins (2 cm) lets the filter keep none"),
    ro("avoidance.accel_limit", 0.0, 100.0, "rad/s²", "the reference's slew under the barrier filter"),
    r("avoidance.human_speed_m_s", 1.6, 2.5, "m/s", "below ISO 13855's 1.6 m/s the perception's latency is charged at less than a walking hand"),
    r("ssm.stop_time_s", MIN_STOP_TIME_S, 1.0, "s", "T_s below the arm's measured stop (47 ms) promises a stop it cannot make"),
    r("ssm.stop_distance_per_speed_s", MIN_STOP_DISTANCE_PER_SPEED_S, 1.0, "s", "S_s below the measured 18 ms × v promises a stop it cannot make"),
    r("ssm.intrusion_m", 0.0, 1.0, "m", "C: ISO 13855's reach distances are at most 0.85 m"),
    r("ssm.sensor_uncertainty_m", MIN_SENSOR_UNCERTAINTY_M, 0.2, "m", "Z_d below the depth noise at 2 m (6 mm) ignores the sensor's error"),
    r("ssm.robot_uncertainty_m", 0.0, 0.1, "m", "Z_r"),
    r("ssm.human_speed_decay", 0.1, 10.0, "m/s²", "a measured approach forgotten faster than a person changes speed"),
    // the collaboration: Annex A's limits
    ro("collaboration.iso_hand_n", 0.0, 140.0, "N", "ISO/TS 15066 Annex A's quasi-static limit of the hands (140 N)"),
    ro("collaboration.iso_lower_arm_n", 0.0, 160.0, "N", "ISO/TS 15066 Annex A's quasi-static limit of the lower arms (160 N)"),
    ro("collaboration.force_limit_fraction", 0.0, 1.0, "", "a fraction of the region's limit"),
    r("collaboration.contact_hold_n", 0.0, 140.0, "N", "pressing the hand harder than Annex A's hand limit"),
    ro("collaboration.contact_force_n", 0.0, 140.0, "N", "a touch counted only above Annex A's hand limit"),
    ro("collaboration.approach_speed", 0.0, 0.5, "m/s", "the approach toward a hand"),
    ro("collaboration.contact_speed", 0.0, 0.25, "m/s", "the speed at the touch"),
    ro("collaboration.admittance", 0.0, 0.01, "m/(N s)", "the contact's admittance"),
    ro("collaboration.hand_lost_s", 0.0, 5.0, "s", "a collaboration with a hand unseen for longer"),
    r("collaboration.restart_clear_m", 0.05, 1.0, "m", "a restarted controller resuming with a hand this near"),
    ro("collaboration.hand_radius_m", 0.0, 0.15, "m", "the hand's radius"),
    ro("collaboration.robot_radius_m", 0.0, 0.3, "m", "the collaborative part's capsule radius"),
    ro("collaboration.mask_radius_m", 0.0, 0.3, "m", "depth masked around the hand: larger blinds perception near the arm"),
    r("collaboration.mask_forearm_m", 0.0, 0.4, "m", "depth masked along the forearm: longer blinds perception near the arm"),
    ro("collaboration.refine_radius_m", 0.0, 0.3, "m", "the pixels the hand is refined from"),
    r("collaboration.back_off_m", 0.0, 0.5, "m", "the back-off after a force limit"),
    r("collaboration.touch_lead_m", 0.0, 0.05, "m", "the reference's lead at the touch: a spring pressing the hand"),
    r("collaboration.reach_into_m", 0.0, 0.1, "m", "how far the approach aims into the hand"),
    r("collaboration.rearm_quiet_s", 0.0, 5.0, "s", "full detection re-armed only after this"),
    // stale inputs of the recognisers; the watchdogs
    ro("gesture.max_age_ms", 0.0, 1000.0, "ms", STALE),
    ro("voice.skeleton_max_age_ms", 0.0, 1000.0, "ms", STALE),
    ro("supervisor.deadman_s", 0.0, 60.0, "s", "a cell whose supervisor died runs on this long"),
    ro("supervisor.heartbeat_timeout_ms", 0.0, 10_000.0, "ms", "a frozen service goes unnoticed this long"),
    ro("services.heartbeat_timeout_ms", 0.0, 10_000.0, "ms", "a frozen service goes unnoticed this long"),
];

/// The values at `key` in `table`: a number, each number of a list, each
/// entry of a list of tables (`repulsion.points.radius`: every point's) or
/// of a table of tables (`services.heartbeat_timeout_ms`: every service's);
/// each with the key that names it (`repulsion.points[3].radius`).
fn values_at(table: &Table, key: &str) -> Vec<(String, f64)> {
    fn walk(v: &Value, rest: &[&str], name: String, out: &mut Vec<(String, f64)>) {
        match (v, rest.split_first()) {
            (Value::Float(x), None) => out.push((name, *x)),
            (Value::Integer(x), None) => out.push((name, *x as f64)),
            (Value::Array(a), None) => {
                for x in a {
                    walk(x, rest, name.clone(), out);
                }
            }
            (Value::Array(a), Some(_)) => {
                for (i, x) in a.iter().enumerate() {
                    walk(x, rest, format!("{name}[{i}]"), out);
                }
            }
            (Value::Table(t), Some((k, tail))) => match t.get(*k) {
                Some(x) => walk(x, tail, format!("{name}.{k}"), out),
                // services.NAME.key: every service's
                None if name == "services" => {
                    for (n, x) in t {
                        if let Some(y) = x.get(*k) {
                            walk(y, tail, format!("{name}.{n}.{k}"), out);
                        }
                    }
                }
                None => {}
            },
            _ => {}
        }
    }
    let parts: Vec<&str> = key.split('.').collect();
    let mut out = Vec::new();
    if let Some((first, rest)) = parts.split_first() {
        if let Some(v) = table.get(*first) {
            walk(v, rest, first.to_string(), &mut out);
        }
    }
    out
}

fn refuse(key: &str, v: f64, range: &Range) -> Invalid {
    Invalid::new(
        key,
        format!(
            "{v} is outside its safe range {}: {}",
            range.text(),
            range.why
        ),
    )
}

/// Every value of [`SAFETY_RANGES`] in `config`, and the relations between
/// them (the feedback toward an obstacle below the repulsion's speed, the
/// stale-perception stop after its staleness bound).
pub fn check(config: &Config) -> Result<(), Invalid> {
    let table = Table::try_from(config).map_err(|e| Invalid::new("<config>", e.to_string()))?;
    for range in SAFETY_RANGES {
        for (key, v) in values_at(&table, range.key) {
            if !range.holds(v) {
                return Err(refuse(&key, v, range));
            }
        }
    }
    let c = &config.control;
    if c.feedback_max_speed > config.repulsion.params.v_max {
        return Err(Invalid::new(
            "control.feedback_max_speed",
            format!(
                "{} is outside its safe range (0, repulsion.params.v_max = {}] m/s: the feedback toward an obstacle would overrun the repulsion",
                c.feedback_max_speed, config.repulsion.params.v_max
            ),
        ));
    }
    let co = &config.collaboration;
    let force_limit = co.force_limit_fraction * co.iso_hand_n;
    if co.contact_hold_n >= force_limit {
        return Err(Invalid::new(
            "collaboration.contact_hold_n",
            format!(
                "{} is outside its safe range [0, force_limit_fraction × iso_hand_n = {force_limit}) N: the hold itself would reach the force limit",
                co.contact_hold_n
            ),
        ));
    }
    if c.perception_stop_after_ms < c.perception_max_age_ms {
        return Err(Invalid::new(
            "control.perception_stop_after_ms",
            format!(
                "{} is outside its safe range [control.perception_max_age_ms = {}, 5000] ms",
                c.perception_stop_after_ms, c.perception_max_age_ms
            ),
        ));
    }
    Ok(())
}

/// The arm's reach from its base \[m\]: the sum of the lengths of its links
/// (each joint's offset from its parent) and of the end effector's offset
/// from its body, an upper bound on how far any of its points gets.
pub fn reach_m(model: &phri_model::Model, ee_link: &str) -> f64 {
    let links: f64 = model.joints.iter().map(|j| j.placement.p.norm()).sum();
    let ee = model
        .frame_id(ee_link)
        .ok()
        .and_then(|i| model.frames.get(i))
        .map_or(0.0, |f| f.placement.p.norm());
    links + ee
}

/// The ranges that depend on the arm: a collision or contact threshold at
/// most its joint's torque limit (higher, the residual never reaches it:
/// detection off), every waypoint within the arm's reach.
pub fn check_model(config: &Config, model: &phri_model::Model) -> Result<(), Invalid> {
    let n = model.nv();
    let limits: Vec<(String, f64)> = model
        .joints
        .iter()
        .filter(|j| j.mimic.is_none())
        .map(|j| (j.name.clone(), j.effort))
        .collect();
    let d = &config.dynamics;
    for (key, list) in [
        ("dynamics.contact_threshold", &d.contact_threshold),
        ("dynamics.collision_threshold", &d.collision_threshold),
    ] {
        let values = list.resolve(n, key)?;
        for (i, (v, (joint, effort))) in values.iter().zip(&limits).enumerate() {
            if !(v.is_finite() && *v > 0.0 && v <= effort) {
                let shown = match list {
                    crate::PerJoint::All(_) => key.to_string(),
                    crate::PerJoint::Each(_) => format!("{key}[{i}]"),
                };
                return Err(Invalid::new(
                    shown,
                    format!(
                        "{v} is outside its safe range (0, {effort}] Nm: joint '{joint}' cannot exert more (its URDF effort limit), so the residual never reaches it: detection off"
                    ),
                ));
            }
        }
    }
    // ‖r‖ above the norm of every joint's limit is never reached either
    let norm = limits.iter().map(|(_, e)| e * e).sum::<f64>().sqrt();
    if !(d.collision_norm_threshold <= norm) {
        return Err(Invalid::new(
            "dynamics.collision_norm_threshold",
            format!(
                "{} is outside its safe range (0, {norm:.1}] Nm: the norm of the joints' URDF effort limits, which the residual never exceeds: detection off",
                d.collision_norm_threshold
            ),
        ));
    }
    let reach = reach_m(model, &config.control.ee_link);
    for (i, w) in config.control.waypoints.iter().enumerate() {
        let dist = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        if dist > reach {
            return Err(Invalid::new(
                format!("control.waypoints[{i}]"),
                format!(
                    "[{}, {}, {}] is {dist:.3} m from the base, outside the arm's reach (0, {reach:.3}] m (the sum of its link lengths)",
                    w[0], w[1], w[2]
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults with `key` set to `v` (in every entry or service it names).
    fn with(key: &str, v: f64) -> Result<(), Invalid> {
        let mut t = Table::try_from(Config::defaults()).unwrap();
        fn set(v: &mut Value, rest: &[&str], x: f64, services: bool) {
            // an integral value as an integer: counts take no float, floats take integers
            let value = |_: &Value| match x.fract() == 0.0 {
                true => Value::Integer(x as i64),
                false => Value::Float(x),
            };
            match (v, rest.split_first()) {
                (Value::Array(a), _) => a.iter_mut().for_each(|e| set(e, rest, x, false)),
                (Value::Table(t), Some((k, []))) if !services => {
                    let old = t.get(*k).cloned().unwrap_or(Value::Float(0.0));
                    t.insert(k.to_string(), value(&old));
                }
                (Value::Table(t), Some((k, tail))) if !services => {
                    if let Some(e) = t.get_mut(*k) {
                        set(e, tail, x, false)
                    }
                }
                (Value::Table(t), _) => t.iter_mut().for_each(|(_, e)| set(e, rest, x, false)),
                _ => {}
            }
        }
        let parts: Vec<&str> = key.split('.').collect();
        let services = parts[0] == "services";
        set(t.get_mut(parts[0]).unwrap(), &parts[1..], v, services);
        let config = Config::from_table(&t, "<test>").unwrap();
        check(&config)
    }

    #[test]
    fn the_defaults_are_within_every_range() {
        check(&Config::defaults()).unwrap();
    }

    #[test]
    fn each_range_refuses_past_its_ends_naming_key_value_and_range_and_takes_its_ends() {
        // relations between keys are tested apart
        let relational = [
            "collaboration.contact_hold_n",
            "collaboration.iso_hand_n",
            "collaboration.force_limit_fraction",
            "control.feedback_max_speed",
            "control.perception_stop_after_ms",
            "repulsion.params.v_max",
        ];
        let defaults = Table::try_from(Config::defaults()).unwrap();
        for range in SAFETY_RANGES {
            // robot.capsules: none on the default arm (tested below)
            if values_at(&defaults, range.key).is_empty() {
                continue;
            }
            let past_hi = range.hi + range.hi.abs().max(1.0) * 0.5;
            let e = with(range.key, past_hi).expect_err(range.key);
            let text = e.to_string();
            assert!(
                text.contains(&format!(
                    "{past_hi} is outside its safe range {}",
                    range.text()
                )),
                "{}: {text}",
                range.key
            );
            let leaf = range.key.rsplit('.').next().unwrap();
            assert!(
                e.key.ends_with(leaf) && e.key.starts_with(range.key.split('.').next().unwrap()),
                "{}: {}",
                range.key,
                e.key
            );
            if !relational.contains(&range.key) {
                with(range.key, range.hi).unwrap_or_else(|e| panic!("{}: {e}", range.key));
            }
            if range.lo_open {
                with(range.key, range.lo).expect_err(range.key);
            } else {
                if !relational.contains(&range.key) {
                    with(range.key, range.lo).unwrap_or_else(|e| panic!("{}: {e}", range.key));
                }
                if range.lo > 0.0 || range.key.ends_with("_m") || range.key.ends_with("_s") {
                    let below = range.lo - range.lo.abs().max(0.01) * 0.5;
                    with(range.key, below).expect_err(range.key);
                }
            }
        }
    }

    #[test]
    fn the_examples_of_the_issue_are_refused() {
        let e = with("perception.self_filter.margin_m", 3.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "perception.self_filter.margin_m: 3 is outside its safe range [0, 0.1] m: a larger margin removes a person's pixels near the arm: perception blind where contact happens"
        );
        with("perception.self_filter.margin_m", 0.1).unwrap();
        let e = with("collaboration.iso_hand_n", 141.0).unwrap_err();
        assert!(
            e.to_string()
                .contains("141 is outside its safe range (0, 140] N"),
            "{e}"
        );
        assert_eq!(iso_hand_limit_n(), 140.0);
        assert_eq!(iso_lower_arm_limit_n(), 160.0);
        let e = with("repulsion.points.radius", 0.31).unwrap_err();
        assert_eq!(e.key, "repulsion.points[0].radius");
        let e = with("services.heartbeat_timeout_ms", 60_000.0).unwrap_err();
        assert!(
            e.key.starts_with("services.") && e.key.ends_with(".heartbeat_timeout_ms"),
            "{}",
            e.key
        );
    }

    #[test]
    fn relations_between_keys() {
        let mut c = Config::defaults();
        c.control.feedback_max_speed = 0.31;
        let e = check(&c).unwrap_err();
        assert!(
            e.to_string().contains("repulsion.params.v_max = 0.3"),
            "{e}"
        );
        c.control.feedback_max_speed = 0.3;
        check(&c).unwrap();
        c.collaboration.contact_hold_n = 70.0;
        let e = check(&c).unwrap_err();
        assert_eq!(e.key, "collaboration.contact_hold_n");
        c.collaboration.contact_hold_n = 69.0;
        check(&c).unwrap();
        c.control.perception_stop_after_ms = 99.0;
        let e = check(&c).unwrap_err();
        assert_eq!(e.key, "control.perception_stop_after_ms");
    }

    /// Every range is documented beside its key in `deploy/phri.toml`.
    #[test]
    fn deploy_phri_toml_gives_every_range() {
        let text = crate::DEFAULTS;
        for range in SAFETY_RANGES {
            let doc = format!("safe: {}", range.text());
            let leaf = range.key.rsplit('.').next().unwrap();
            // beside its key, or (keys of the robot files, of every service) in the notes
            let found = text
                .lines()
                .any(|l| l.trim_start().starts_with(&format!("{leaf} ")) && l.contains(&doc))
                || text.contains(&format!("{leaf} {doc}"));
            assert!(
                found,
                "deploy/phri.toml does not give `{doc}` beside {}",
                range.key
            );
        }
    }
}
