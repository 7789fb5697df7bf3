//! `reaction`: a collision was detected; the configured strategy of the
//! paper's portfolio (Sect. IV, Fig. 2) runs at once:
//!
//! - `reflex` (eq. 9): `τ = M (K_R r − D_R q̇) + C q̇ + g − r`, the arm
//!   yields along the external torque;
//! - `admittance` (eq. 13): `q̇_r = K_Q r`, tracked by the joint loop;
//! - `stop`: hold where the collision was detected;
//! - `float`: `τ = g − D q̇`, zero gravity with light damping;
//! - `retreat`: back along the path just travelled, with a time law that
//!   ramps the backward speed up and down (one history entry per control period).
//!
//! It lasts at least `reaction_min_s`, a retreat until it is back
//! `retreat_path_s` of path time, and then until the contact is gone.

use phri_config::ControlConfig;
use phri_ipc::Reaction;

use crate::history::PathHistory;
use crate::limits::Limits;
use crate::modes::Behaviour;
use crate::reference::{JointReference, TrackingGains};
use crate::snapshot::snapshot_fields;
use crate::terms::DynamicsTerms;

/// The retreat's walk back through the history. Positions in the history
/// are counted in entries, one per control period.
#[derive(Clone, Debug)]
pub struct Retreat {
    /// control period: the time between two history entries \[s\]
    period_s: f64,
    /// history entries per second [1/s] (`1 / period_s`)
    entries_per_s: f64,
    /// how far back along the path [s of path time]
    path_s: f64,
    /// the time law's ramp \[s\]
    ramp_s: f64,
    /// entries walked back so far
    u: f64,
    /// entries to walk back
    total: f64,
}

snapshot_fields!(Retreat { u, total });

impl Retreat {
    /// A retreat of `path_s` [s of path time] with a time law ramping over
    /// `ramp_s` \[s\], for a history of one entry per `period_s` \[s\].
    pub fn new(path_s: f64, ramp_s: f64, period_s: f64) -> Retreat {
        Retreat {
            period_s,
            entries_per_s: 1.0 / period_s,
            path_s,
            ramp_s,
            u: 0.0,
            total: 0.0,
        }
    }

    /// Start walking back through the `available` entries of the history.
    pub fn start(&mut self, available: usize) {
        self.u = 0.0;
        self.total = (self.path_s / self.period_s).min((available.max(1) - 1) as f64);
    }

    /// Less than half an entry left to walk.
    pub fn done(&self) -> bool {
        self.total - self.u < 0.5
    }

    /// One period of `dt` \[s\], `elapsed_s` \[s\] after the reaction began:
    /// `q_ref` \[rad\] moves back through `history`; returns the path time
    /// \[s\] it reached (`None` with an empty history: `q_ref` stays).
    ///
    /// Time law: the backward speed σ (1: path time runs back at ṡ = −1)
    /// ramps up over `ramp_s`, and down over the last half ramp.
    pub fn step(
        &mut self,
        elapsed_s: f64,
        dt: f64,
        history: &PathHistory,
        q_ref: &mut [f64],
    ) -> Option<f64> {
        let ramp = self.ramp_s.max(1e-3);
        let left_s = (self.total - self.u) * self.period_s;
        let sigma = (elapsed_s / ramp)
            .min(1.0)
            .min(left_s / (0.5 * ramp))
            .max(0.05);
        self.u = (self.u + sigma * dt * self.entries_per_s).min(self.total);
        history.at(self.u, q_ref)
    }
}

/// The reaction's strategy, gains and progress.
#[derive(Clone, Debug)]
pub struct ReactionState {
    strategy: Reaction,
    /// K_R of eq. 9
    reflex_gain: f64,
    /// D_R of eq. 9 [1/s]
    reflex_damping: f64,
    /// K_Q of eq. 13 [rad/(N m s)]
    admittance_gain: f64,
    /// joint damping while floating [Nm s/rad]
    float_damping: f64,
    /// least time spent reacting \[s\]
    min_s: f64,
    /// when the reaction began [s, controller time]
    t0: f64,
    retreat: Retreat,
}

snapshot_fields!(ReactionState { t0, retreat });

/// What one period of the reaction reads and writes.
pub struct ReactionIo<'a> {
    /// measured joint positions \[rad\] and estimated velocities [rad/s]
    pub q: &'a [f64],
    /// estimated joint velocities \[rad/s\]
    pub qd: &'a [f64],
    /// the period \[s\] and the controller's time \[s\]
    pub dt: f64,
    /// the controller's time \[s\]
    pub t: f64,
    /// the residual r \[Nm\] (`None`: vanished; the reaction holds)
    pub residual: Option<&'a [f64]>,
    /// the joint reference (the admittance and the retreat move it)
    pub reference: &'a mut JointReference,
    /// the joint limits (the admittance's reference stays inside)
    pub limits: &'a Limits,
    /// the path history the retreat walks back
    pub history: &'a PathHistory,
    /// the model terms (floating replaces the bias by `g − D q̇`)
    pub terms: &'a mut DynamicsTerms,
    /// the joint tracking gains
    pub gains: TrackingGains,
    /// the acceleration for the torque law [rad/s²]
    pub accel: &'a mut [f64],
}

impl ReactionState {
    /// The strategy and gains of `[control]`, for a controller with period `period_s` \[s\].
    pub fn new(cfg: &ControlConfig, period_s: f64) -> ReactionState {
        ReactionState {
            strategy: cfg.reaction,
            reflex_gain: cfg.reflex_gain,
            reflex_damping: cfg.reflex_damping,
            admittance_gain: cfg.admittance_gain,
            float_damping: cfg.float_damping,
            min_s: cfg.reaction_min_s,
            t0: 0.0,
            retreat: Retreat::new(cfg.retreat_path_s, cfg.retreat_ramp_s, period_s),
        }
    }

    /// The configured strategy (`[control] reaction`).
    pub fn strategy(&self) -> Reaction {
        self.strategy
    }

    /// Begin at time `t` \[s\], with `history_available` entries to retreat through.
    pub fn enter(&mut self, t: f64, history_available: usize) {
        self.t0 = t;
        self.retreat.start(history_available);
    }

    /// At time `t` \[s\]: the least time has passed and a retreat is over.
    pub fn done(&self, t: f64) -> bool {
        t - self.t0 >= self.min_s && (self.strategy != Reaction::Retreat || self.retreat.done())
    }

    /// One period. Returns the behaviour and, for the retreat, the path time reached \[s\].
    pub fn step(&mut self, io: ReactionIo<'_>) -> (Behaviour, Option<f64>) {
        let n = io.q.len();
        let g = io.gains;
        let (q, qd, dt) = (io.q, io.qd, io.dt);
        let joint = Behaviour::Joint { minus_r: false };
        match (self.strategy, io.residual) {
            (Reaction::Reflex, Some(r)) => {
                // eq. 9: a = K_R r − D_R q̇; the torque law subtracts r
                for i in 0..n {
                    io.accel[i] = self.reflex_gain * r[i] - self.reflex_damping * qd[i];
                }
                (Behaviour::Joint { minus_r: true }, None)
            }
            (Reaction::Admittance, Some(r)) => {
                // eq. 13: q̇_r = K_Q r, integrated and tracked
                let rf = io.reference;
                for i in 0..n {
                    rf.qd_ref[i] = self.admittance_gain * r[i];
                    rf.q_ref[i] += rf.qd_ref[i] * dt;
                }
                io.limits.clamp_position(&mut rf.q_ref);
                for i in 0..n {
                    io.accel[i] = g.kp * (rf.q_ref[i] - q[i]) + g.kd * (rf.qd_ref[i] - qd[i]);
                }
                (joint, None)
            }
            (Reaction::Float, _) => {
                // τ = g − D q̇: no inertial term
                for i in 0..n {
                    io.accel[i] = 0.0;
                    io.terms.bias[i] = io.terms.gravity[i] - self.float_damping * qd[i];
                }
                (joint, None)
            }
            (Reaction::Retreat, _) => {
                let rf = io.reference;
                let mut prev = [0.0; phri_ipc::MAX_DOF];
                prev[..n].copy_from_slice(&rf.q_ref);
                let s = self
                    .retreat
                    .step(io.t - self.t0, dt, io.history, &mut rf.q_ref);
                for i in 0..n {
                    rf.qd_ref[i] = if dt > 0.0 {
                        (rf.q_ref[i] - prev[i]) / dt
                    } else {
                        0.0
                    };
                    io.accel[i] = g.kp * (rf.q_ref[i] - q[i]) + g.kd * (rf.qd_ref[i] - qd[i]);
                }
                (joint, s)
            }
            // stop, or a strategy whose residual vanished: hold where detected
            _ => {
                io.reference.hold(q, qd, g, io.accel);
                (joint, None)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A task that moved along a path with path time running at ṡ = 1 for
    /// `seconds`, one history entry per `period_s`, q_ref = [s, −s]; then a
    /// retreat to its end. Returns the path time reached, when 90 % of the
    /// way back was reached \[s\] and the largest backward path speed [s/s].
    fn retreat_after(seconds: f64, period_s: f64) -> (f64, f64, f64) {
        let entries = (seconds / period_s).round() as usize;
        let mut h = PathHistory::for_span(2, 0.6 + 0.5, period_s);
        for k in 0..=entries {
            let s = k as f64 * period_s;
            h.push(s, &[s, -s]);
        }
        let mut r = Retreat::new(0.6, 0.1, period_s);
        r.start(h.available());
        let mut q = [0.0; 2];
        let (mut t, mut s_prev, mut s, mut max_speed) = (0.0, seconds, seconds, 0.0f64);
        let mut t90 = None;
        while !r.done() {
            t += period_s;
            s = r.step(t, period_s, &h, &mut q).unwrap();
            assert_eq!(
                q,
                [s, -s],
                "the reference is the history's at the path time reached"
            );
            max_speed = max_speed.max((s_prev - s) / period_s);
            s_prev = s;
            if seconds - s >= 0.9 * 0.6 && t90.is_none() {
                t90 = Some(t);
            }
            assert!(t < 5.0, "the retreat never ends");
        }
        (s, t90.unwrap_or(t), max_speed)
    }

    #[test]
    fn retreat_walks_back_the_same_path_time_whatever_the_period() {
        let (s1, t1, v1) = retreat_after(2.0, 0.001);
        assert!((s1 - 1.4).abs() <= 0.0005 + 1e-9, "1 ms: back to {s1}");
        for period in [0.002, 0.0025, 0.004] {
            let (s, t, v) = retreat_after(2.0, period);
            // the same path time, to the half entry at which a retreat is done
            assert!(
                (s - s1).abs() <= 0.5 * (period + 0.001) + 1e-9,
                "{period} s: back to {s}, 1 ms: {s1}"
            );
            // the time law is in seconds: 90 % of the way at the same time
            // (to two periods), at the same top speed
            assert!(
                (t - t1).abs() <= 2.0 * period,
                "{period} s: {t} s, 1 ms: {t1} s"
            );
            assert!(
                (v - 1.0).abs() < 1e-6 && (v1 - 1.0).abs() < 1e-6,
                "{v} {v1}"
            );
        }
    }

    #[test]
    fn a_short_history_limits_the_retreat() {
        // only 0.2 s travelled: back to the start of the history, not beyond
        let (s, _, _) = retreat_after(0.2, 0.002);
        assert!(s.abs() <= 0.5 * 0.002 + 1e-12, "{s}");
    }
}
