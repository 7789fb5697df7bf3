//! The wait at a waypoint. Under the barrier filter the end effector may
//! go round a person beside the path and trail its reference; at the end of
//! the segment the reference waits at the waypoint (the segment ends at
//! rest) for as long as the end effector keeps closing in on it, and the
//! waypoint counts when it arrives. An end effector that has stopped
//! closing in (held off by a person at the waypoint), or that is far from
//! the waypoint when the segment ends, is not waited for.

use crate::snapshot::snapshot_fields;

/// The end effector closes in on the waypoint by at least this between two
/// improvements \[m\].
pub const ARRIVAL_PROGRESS_M: f64 = 0.002;

/// Without such progress for this long, the wait ends \[s\].
pub const ARRIVAL_STALL_S: f64 = 0.2;

/// An end effector farther than this from the waypoint when its segment
/// ends is not waited for (it was led far round, or held off) \[m\].
pub const ARRIVAL_NEAR_M: f64 = 0.15;

/// The wait at the current segment's waypoint.
#[derive(Clone, Debug)]
pub struct Arrival {
    /// time waited at this waypoint \[s\]
    waited_s: f64,
    /// the end effector's closest distance to it so far \[m\]
    best_m: f64,
    /// time since that distance last shrank by [`ARRIVAL_PROGRESS_M`] \[s\]
    since_s: f64,
}

snapshot_fields!(Arrival {
    waited_s,
    best_m,
    since_s
});

impl Default for Arrival {
    fn default() -> Arrival {
        Arrival {
            waited_s: 0.0,
            best_m: f64::INFINITY,
            since_s: 0.0,
        }
    }
}

impl Arrival {
    /// A new segment: nothing waited for yet.
    pub fn reset(&mut self) {
        *self = Arrival::default();
    }

    /// One period `dt` \[s\] at the waypoint with the end effector `distance`
    /// \[m\] from it: whether to go on waiting (at most `limit_s` \[s\] in
    /// all, and only while the end effector closes in). A non-finite
    /// distance is not waited for.
    pub fn wait(&mut self, distance: f64, dt: f64, limit_s: f64) -> bool {
        if !distance.is_finite() || (self.waited_s == 0.0 && distance > ARRIVAL_NEAR_M) {
            return false;
        }
        if distance < self.best_m - ARRIVAL_PROGRESS_M {
            self.best_m = distance;
            self.since_s = 0.0;
        } else {
            self.since_s += dt;
        }
        self.waited_s += dt;
        self.waited_s < limit_s && self.since_s < ARRIVAL_STALL_S
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waits_while_the_end_effector_closes_in_and_no_longer() {
        let dt = 0.001;
        // closing in at 5 cm/s from 10 cm: waited for all the way
        let mut a = Arrival::default();
        let waited = (0..2000)
            .take_while(|k| a.wait(0.10 - 0.05 * *k as f64 * dt, dt, 1.5))
            .count() as f64
            * dt;
        assert!(
            (waited - 1.5).abs() <= 2.0 * dt,
            "the limit ends a closing wait: {waited}"
        );
        // held off at 6 cm: the stall ends the wait after ARRIVAL_STALL_S
        let mut a = Arrival::default();
        let waited = (0..2000).take_while(|_| a.wait(0.06, dt, 2.0)).count() as f64 * dt;
        assert!((waited - ARRIVAL_STALL_S).abs() <= 2.0 * dt, "{waited}");
        // a limit below the stall: the limit
        let mut a = Arrival::default();
        assert_eq!((0..2000).take_while(|_| a.wait(0.06, dt, 0.05)).count(), 49);
        // far from it when the segment ends: not waited for
        let mut a = Arrival::default();
        assert!(!a.wait(ARRIVAL_NEAR_M + 0.01, dt, 2.0));
        // nonsense is not waited for; a reset starts over
        assert!(!a.wait(f64::NAN, dt, 2.0));
        a.reset();
        assert!(a.wait(0.06, dt, 2.0));
    }
}
