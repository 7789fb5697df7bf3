//! `protective_stop`: a safety input is stale (no fresh valid residual, or
//! blind perception with a person last seen near). Without detection the arm
//! must not move: it holds where it was when the stop began.

use crate::modes::Behaviour;
use crate::reference::{JointReference, TrackingGains};

/// Enter: hold the measured `q` \[rad\].
pub fn enter(reference: &mut JointReference, q: &[f64]) {
    reference.hold_here(q);
}

/// One period: `a = K_P (q_hold − q) − K_D q̇`.
pub fn step(
    reference: &JointReference,
    q: &[f64],
    qd: &[f64],
    gains: TrackingGains,
    accel: &mut [f64],
) -> Behaviour {
    reference.hold(q, qd, gains, accel);
    Behaviour::Joint { minus_r: false }
}
