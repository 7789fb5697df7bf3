//! What a state of the control box must look like before phri acts on it:
//! finite joint positions where the last accepted state said the joints
//! were heading. The box numbers one state per millisecond (`message_id`,
//! FCI's clock). Between two states `n` ids apart a joint is expected at
//! the last accepted position moved on by its measured velocity (`dq`, at
//! most [`VELOCITY_CAP`] times the joint's limit) for `n` ms, and may
//! depart from that by its velocity limit (the robot model's) times `n` ms
//! with a small margin ([`VELOCITY_MARGIN`]). A state that does not is
//! refused: never published on `robot/state`, never answered with a new
//! torque. A forged state 0.3 rad ahead departs 90 times as far as one
//! period allows; an arm flung by a collision (franka-sim's MuJoCo arm
//! pushed by a kilonewton reaches 5 times a joint's limit) moves on with
//! its measured velocity and stays within it. After [`REANCHOR_AFTER`]
//! refused states in a row (none came within the bound: the arm itself
//! moved) the newest finite one is taken as the new reference rather than
//! hiding the arm longer. Allocates nothing.

use crate::cycle::JOINTS;

/// How far beyond its prediction a joint may be, as a share of how far its
/// velocity limit takes it in the same time (a change of velocity, noise) [-].
pub const VELOCITY_MARGIN: f64 = 1.25;

/// The measured velocity a prediction trusts at most, in multiples of the
/// joint's velocity limit (a flung arm; a state's own `dq` cannot open the
/// gate wider) [-].
pub const VELOCITY_CAP: f64 = 10.0;

/// Refused states in a row after which the newest finite one is taken as
/// the reference again (the protocol's tolerance of missing commands: the
/// arm, not a forger, moved).
pub const REANCHOR_AFTER: u32 = 20;

/// Movement any joint may show between two states whatever its limit
/// (encoder noise) \[rad\].
pub const POSITION_SLACK_RAD: f64 = 1e-4;

/// Why a state was refused.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum StateRefusal {
    /// a joint position is NaN or infinite
    #[error("joint {joint}: position not finite")]
    NonFinite {
        /// index of the first such joint
        joint: usize,
    },
    /// a joint is further from where the last accepted state was heading
    /// than its velocity limit allows in the time the message ids say passed
    #[error(
        "joint {joint}: {off_rad:.4} rad from its prediction after {periods} ms, at most {allowed_rad:.4} allowed"
    )]
    TooFast {
        /// index of the first such joint
        joint: usize,
        /// its distance from the predicted position \[rad\]
        off_rad: f64,
        /// the distance allowed \[rad\]
        allowed_rad: f64,
        /// message ids since the last accepted state (at least 1) \[ms\]
        periods: u64,
    },
}

/// The newest accepted state: positions \[rad\], velocities \[rad/s\]
/// (capped), message id.
type Reference = ([f64; JOINTS], [f64; JOINTS], u64);

/// The check, and what it refused so far.
#[derive(Clone, Debug)]
pub struct StateGuard {
    /// velocity limit per joint \[rad/s\] (the model's; infinite: unknown)
    velocity: [f64; JOINTS],
    /// the box's period \[s\]
    period_s: f64,
    last: Option<Reference>,
    /// states refused as not finite
    pub non_finite: u64,
    /// states refused as too far from their prediction
    pub too_fast: u64,
    /// states taken as a new reference after [`REANCHOR_AFTER`] refusals in a row
    pub reanchored: u64,
    /// refusals in a row
    run: u32,
}

impl StateGuard {
    /// A guard for joints with velocity limits `velocity` \[rad/s\] (a
    /// non-positive or non-finite one: unchecked) and the box's period
    /// `period_s` \[s\].
    pub fn new(velocity: [f64; JOINTS], period_s: f64) -> StateGuard {
        StateGuard {
            velocity: velocity.map(|v| {
                if v.is_finite() && v > 0.0 {
                    v
                } else {
                    f64::INFINITY
                }
            }),
            period_s,
            last: None,
            non_finite: 0,
            too_fast: 0,
            reanchored: 0,
            run: 0,
        }
    }

    /// The guard of `model`'s joint velocity limits.
    pub fn for_model(model: &phri_model::Model, period_s: f64) -> StateGuard {
        let mut velocity = [f64::INFINITY; JOINTS];
        for (v, j) in velocity
            .iter_mut()
            .zip(model.joints.iter().filter(|j| j.mimic.is_none()))
        {
            *v = j.velocity;
        }
        StateGuard::new(velocity, period_s)
    }

    /// Forget the reference (a new session with the box: its first state
    /// is taken as it is).
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// Judge state `message_id` with joint positions `q` \[rad\] and
    /// measured velocities `dq` \[rad/s\] (a non-finite one counts as 0);
    /// an accepted one becomes the reference, a refused one is counted. The
    /// first state of a session is judged only for finiteness, and so is
    /// one after [`REANCHOR_AFTER`] refusals in a row.
    pub fn check(
        &mut self,
        q: &[f64; JOINTS],
        dq: &[f64; JOINTS],
        message_id: u64,
    ) -> Result<(), StateRefusal> {
        if let Some(joint) = q.iter().position(|x| !x.is_finite()) {
            self.non_finite += 1;
            self.run = self.run.saturating_add(1);
            return Err(StateRefusal::NonFinite { joint });
        }
        if self.run >= REANCHOR_AFTER && self.last.is_some() {
            self.reanchored += 1;
            self.last = None;
        }
        if let Some((q0, dq0, id0)) = &self.last {
            // an id not above the reference: at most one period (the box's
            // client takes only newer ones; this is the guard's own floor)
            let periods = message_id.saturating_sub(*id0).max(1);
            let dt = periods as f64 * self.period_s;
            for k in 0..JOINTS {
                let off = (q[k] - (q0[k] + dq0[k] * dt)).abs();
                let allowed = self.velocity[k] * dt * VELOCITY_MARGIN + POSITION_SLACK_RAD;
                if off > allowed {
                    self.too_fast += 1;
                    self.run = self.run.saturating_add(1);
                    return Err(StateRefusal::TooFast {
                        joint: k,
                        off_rad: off,
                        allowed_rad: allowed,
                        periods,
                    });
                }
            }
        }
        let cap = |k: usize| self.velocity[k] * VELOCITY_CAP;
        let v = std::array::from_fn(|k| match dq[k].is_finite() {
            true => dq[k].clamp(-cap(k), cap(k)),
            false => 0.0,
        });
        self.last = Some((*q, v, message_id));
        self.run = 0;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const Q: [f64; JOINTS] = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8];
    /// the FR3's limits \[rad/s\]
    const V: [f64; JOINTS] = [2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26];
    const STILL: [f64; JOINTS] = [0.0; JOINTS];

    #[test]
    fn a_state_ahead_of_where_the_joint_was_heading_is_refused_and_the_reference_kept() {
        let mut g = StateGuard::new(V, 1e-3);
        assert_eq!(g.check(&Q, &STILL, 10), Ok(()));
        // at the limit for one period from rest: taken
        let mut q = Q;
        q[0] += 2.62e-3;
        assert_eq!(g.check(&q, &STILL, 11), Ok(()));
        // 0.3 rad ahead in one period: refused
        let mut forged = q;
        forged[3] += 0.3;
        assert!(matches!(
            g.check(&forged, &STILL, 12),
            Err(StateRefusal::TooFast {
                joint: 3,
                periods: 1,
                ..
            })
        ));
        // the next genuine state is judged against the last accepted one
        assert_eq!(g.check(&q, &STILL, 12), Ok(()));
        // after a gap of 100 ms, 0.3 rad is possible (1.25 × 2.62 rad/s × 0.1 s)
        let mut later = q;
        later[3] += 0.3;
        assert_eq!(g.check(&later, &STILL, 112), Ok(()));
        assert_eq!((g.too_fast, g.non_finite, g.reanchored), (1, 0, 0));
    }

    #[test]
    fn an_arm_flung_faster_than_its_limit_is_followed_by_its_measured_velocity() {
        let mut g = StateGuard::new(V, 1e-3);
        // joint 4 at 12 rad/s (4.6 times its limit), accelerating 700 rad/s²
        let (mut q, mut v) = (Q, 12.0);
        let mut dq = STILL;
        dq[3] = v;
        g.check(&q, &dq, 1).unwrap();
        // (to 25 rad/s, within the cap of 26.2)
        for id in 2..20 {
            q[3] += v * 1e-3;
            v += 0.7;
            dq[3] = v;
            assert_eq!(g.check(&q, &dq, id), Ok(()), "state {id}");
        }
        // a forged state claiming to stand still where the arm is not
        let mut forged = q;
        forged[3] -= 0.3;
        assert!(g.check(&forged, &STILL, 20).is_err());
        assert_eq!(g.too_fast, 1);
    }

    #[test]
    fn a_measured_velocity_opens_the_gate_no_wider_than_its_cap() {
        let mut g = StateGuard::new(V, 1e-3);
        let mut dq = STILL;
        dq[0] = 1e6;
        g.check(&Q, &dq, 1).unwrap();
        // predicted at most 10 × 2.62 rad/s × 1 ms = 26 mrad on
        let mut q = Q;
        q[0] += 0.3;
        assert!(g.check(&q, &STILL, 2).is_err());
        q[0] = Q[0] + 0.0262;
        assert_eq!(g.check(&q, &STILL, 2), Ok(()));
    }

    #[test]
    fn an_arm_that_really_jumped_is_taken_again_after_twenty_refusals() {
        let mut g = StateGuard::new(V, 1e-3);
        g.check(&Q, &STILL, 1).unwrap();
        // the arm somewhere else, standing: refused 20 times, then the reference moves
        let mut q = Q;
        q[1] += 0.5;
        for id in 2..=21 {
            assert!(g.check(&q, &STILL, id).is_err(), "state {id}");
        }
        assert_eq!(g.check(&q, &STILL, 22), Ok(()));
        assert_eq!((g.too_fast, g.reanchored), (20, 1));
        // and judged from there
        let mut jump = q;
        jump[1] += 0.3;
        assert!(g.check(&jump, &STILL, 23).is_err());
        assert_eq!(g.check(&q, &STILL, 23), Ok(()));
        // a forged state between genuine ones never builds a run
        for id in 24..100 {
            assert!(g.check(&jump, &STILL, id).is_err());
            assert_eq!(g.check(&q, &STILL, id), Ok(()));
        }
        assert_eq!(g.reanchored, 1);
    }

    #[test]
    fn non_finite_positions_are_refused_even_first() {
        let mut g = StateGuard::new(V, 1e-3);
        let mut q = Q;
        q[5] = f64::NAN;
        assert_eq!(
            g.check(&q, &STILL, 1),
            Err(StateRefusal::NonFinite { joint: 5 })
        );
        q[5] = f64::INFINITY;
        assert!(g.check(&q, &STILL, 2).is_err());
        // a non-finite velocity predicts no motion
        assert_eq!(g.check(&Q, &[f64::NAN; JOINTS], 3), Ok(()));
        assert_eq!(g.non_finite, 2);
        // a reset takes any finite state as the new reference
        g.reset();
        let mut far = Q;
        far[0] = 1.0;
        assert_eq!(g.check(&far, &STILL, 4), Ok(()));
    }

    #[test]
    fn a_duplicate_id_may_not_move_more_than_one_period() {
        let mut g = StateGuard::new(V, 1e-3);
        g.check(&Q, &STILL, 5).unwrap();
        let mut q = Q;
        q[1] += 0.01;
        assert!(g.check(&q, &STILL, 5).is_err());
        assert!(g.check(&q, &STILL, 3).is_err());
    }

    #[test]
    fn an_unknown_limit_is_not_checked() {
        let mut v = V;
        v[6] = 0.0;
        let mut g = StateGuard::new(v, 1e-3);
        g.check(&Q, &STILL, 1).unwrap();
        let mut q = Q;
        q[6] += 1.0;
        assert_eq!(g.check(&q, &STILL, 2), Ok(()));
    }
}
