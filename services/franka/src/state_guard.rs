//! What a state of the control box must look like before phri acts on it:
//! finite joint positions that moved no faster than the joints can. The box
//! numbers one state per millisecond (`message_id`, FCI's clock); between
//! two states `n` ids apart a joint moves at most its velocity limit (the
//! robot model's) times `n` ms, with a margin. A state that does not is
//! refused: never published on `robot/state`, never answered with a new
//! torque. Allocates nothing.

use crate::cycle::JOINTS;

/// How much faster than its velocity limit a joint may seem to move between
/// two states (measurement noise, a limit rounded in the URDF) [-].
pub const VELOCITY_MARGIN: f64 = 1.25;

/// Movement any joint may show between two states whatever its limit
/// (encoder noise) \[rad\].
pub const POSITION_SLACK_RAD: f64 = 1e-4;

/// Why a state was refused.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum StateRefusal {
    /// a joint position is NaN or infinite
    #[error("joint {joint}: position not finite")]
    NonFinite { joint: usize },
    /// a joint moved further than its velocity limit allows in the time
    /// the message ids say passed
    #[error(
        "joint {joint}: moved {moved_rad:.4} rad in {periods} ms, at most {allowed_rad:.4} allowed"
    )]
    TooFast {
        joint: usize,
        moved_rad: f64,
        allowed_rad: f64,
        periods: u64,
    },
}

/// The check, and what it refused so far.
#[derive(Clone, Debug)]
pub struct StateGuard {
    /// velocity limit per joint \[rad/s\] (the model's; infinite: unknown)
    velocity: [f64; JOINTS],
    /// the box's period \[s\]
    period_s: f64,
    /// the newest accepted state: its positions \[rad\] and message id
    last: Option<([f64; JOINTS], u64)>,
    /// states refused as not finite
    pub non_finite: u64,
    /// states refused as too fast
    pub too_fast: u64,
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

    /// Judge state `message_id` with joint positions `q` \[rad\]; an
    /// accepted one becomes the reference, a refused one is counted. The
    /// first state of a session is judged only for finiteness.
    pub fn check(&mut self, q: &[f64; JOINTS], message_id: u64) -> Result<(), StateRefusal> {
        if let Some(joint) = q.iter().position(|x| !x.is_finite()) {
            self.non_finite += 1;
            return Err(StateRefusal::NonFinite { joint });
        }
        if let Some((q0, id0)) = &self.last {
            // an id not above the reference: at most one period (the box's
            // client takes only newer ones; this is the guard's own floor)
            let periods = message_id.saturating_sub(*id0).max(1);
            let dt = periods as f64 * self.period_s;
            for k in 0..JOINTS {
                let moved = (q[k] - q0[k]).abs();
                let allowed = self.velocity[k] * dt * VELOCITY_MARGIN + POSITION_SLACK_RAD;
                if moved > allowed {
                    self.too_fast += 1;
                    return Err(StateRefusal::TooFast {
                        joint: k,
                        moved_rad: moved,
                        allowed_rad: allowed,
                        periods,
                    });
                }
            }
        }
        self.last = Some((*q, message_id));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const Q: [f64; JOINTS] = [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8];
    /// the FR3's limits \[rad/s\]
    const V: [f64; JOINTS] = [2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26];

    #[test]
    fn a_state_ahead_of_what_the_joint_can_do_is_refused_and_the_reference_kept() {
        let mut g = StateGuard::new(V, 1e-3);
        assert_eq!(g.check(&Q, 10), Ok(()));
        // at the limit for one period: taken
        let mut q = Q;
        q[0] += 2.62e-3;
        assert_eq!(g.check(&q, 11), Ok(()));
        // 0.3 rad ahead in one period: refused
        let mut forged = q;
        forged[3] += 0.3;
        assert!(matches!(
            g.check(&forged, 12),
            Err(StateRefusal::TooFast {
                joint: 3,
                periods: 1,
                ..
            })
        ));
        // the next genuine state is judged against the last accepted one
        assert_eq!(g.check(&q, 12), Ok(()));
        // after a gap of 200 ms, 0.3 rad is possible (2.62 rad/s × 0.2 s)
        let mut later = q;
        later[3] += 0.3;
        assert_eq!(g.check(&later, 212), Ok(()));
        assert_eq!((g.too_fast, g.non_finite), (1, 0));
    }

    #[test]
    fn non_finite_positions_are_refused_even_first() {
        let mut g = StateGuard::new(V, 1e-3);
        let mut q = Q;
        q[5] = f64::NAN;
        assert_eq!(g.check(&q, 1), Err(StateRefusal::NonFinite { joint: 5 }));
        q[5] = f64::INFINITY;
        assert!(g.check(&q, 2).is_err());
        assert_eq!(g.check(&Q, 3), Ok(()));
        assert_eq!(g.non_finite, 2);
        // a reset takes any finite state as the new reference
        g.reset();
        let mut far = Q;
        far[0] = 1.0;
        assert_eq!(g.check(&far, 4), Ok(()));
    }

    #[test]
    fn a_duplicate_id_may_not_move_more_than_one_period() {
        let mut g = StateGuard::new(V, 1e-3);
        g.check(&Q, 5).unwrap();
        let mut q = Q;
        q[1] += 0.01;
        assert!(g.check(&q, 5).is_err());
        assert!(g.check(&q, 3).is_err());
    }

    #[test]
    fn an_unknown_limit_is_not_checked() {
        let mut v = V;
        v[6] = 0.0;
        let mut g = StateGuard::new(v, 1e-3);
        g.check(&Q, 1).unwrap();
        let mut q = Q;
        q[6] += 1.0;
        assert_eq!(g.check(&q, 2), Ok(()));
    }
}
