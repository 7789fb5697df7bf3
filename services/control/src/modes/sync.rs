//! `sync`: after a (re)start the controller has no reference of its own. It
//! holds the arm where it was first measured (the first command does not
//! jump to an old one) until the residual and perception are fresh; then the
//! task approaches its path from there.

use crate::modes::Behaviour;
use crate::reference::{JointReference, TrackingGains};

/// One period of waiting: in the first period (`first` — no time has passed
/// since the start) take the measured `q` as the hold, then hold it.
pub fn step(
    reference: &mut JointReference,
    q: &[f64],
    qd: &[f64],
    first: bool,
    gains: TrackingGains,
    accel: &mut [f64],
) -> Behaviour {
    if first {
        reference.hold_here(q);
    }
    reference.hold(q, qd, gains, accel);
    Behaviour::Joint { minus_r: false }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_where_the_arm_was_first_measured() {
        let gains = TrackingGains {
            kp: 400.0,
            kd: 40.0,
        };
        let mut r = JointReference::new(2);
        let mut a = [0.0; 2];
        step(&mut r, &[0.5, -0.2], &[0.0; 2], true, gains, &mut a);
        assert_eq!(a, [0.0, 0.0], "at rest where measured: no acceleration");
        // later periods: the hold stays where the arm first was
        step(&mut r, &[0.6, -0.2], &[1.0, 0.0], false, gains, &mut a);
        assert_eq!(r.q_hold, [0.5, -0.2]);
        assert!((a[0] - (400.0 * -0.1 - 40.0)).abs() < 1e-9 && a[1] == 0.0);
    }
}
