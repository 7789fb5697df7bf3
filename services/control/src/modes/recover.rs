//! `recover`: the reaction is over, or a stale input is fresh again. The
//! arm holds until the residual stays quiet for `resume_quiet_s`, then the
//! task resumes. With someone in view it holds the end effector where it
//! stopped but keeps evading (eqs. 19-20) instead of standing in their way;
//! with nothing near the repulsion is zero and that is a plain hold.

use nalgebra::Vector3;

use crate::modes::{Behaviour, CartesianRef};
use crate::reference::{JointReference, TrackingGains};

/// Enter: hold the measured `q` \[rad\], and the end effector at `ee` \[m\], base frame.
pub fn enter(reference: &mut JointReference, q: &[f64], ee: Vector3<f64>) {
    reference.hold_here(q);
    reference.x_hold = ee;
}

/// One period: with fresh perception (`evading`) hold the end effector
/// through the avoidance; otherwise hold the joints.
pub fn step(
    reference: &JointReference,
    q: &[f64],
    qd: &[f64],
    evading: bool,
    gains: TrackingGains,
    accel: &mut [f64],
) -> Behaviour {
    if evading {
        return Behaviour::Cartesian(CartesianRef {
            x_d: reference.x_hold,
            xd_d: Vector3::zeros(),
            speed_scale: 1.0,
            path_time: None,
            collab_hand: None,
            collab_touching: false,
            collab_point: 0,
            collab_speed_limit: f64::INFINITY,
        });
    }
    reference.hold(q, qd, gains, accel);
    Behaviour::Joint { minus_r: false }
}
