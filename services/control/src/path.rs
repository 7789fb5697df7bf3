//! The task's geometry: a cyclic Cartesian path of minimum-jerk segments
//! through waypoints, parametrised by path time, and the straight
//! minimum-jerk approach that (re)joins it.

use nalgebra::Vector3;

use crate::snapshot::snapshot_fields;

/// Minimum-jerk blend `p(u) = 10u³ − 15u⁴ + 6u⁵` and its derivative, u ∈ [0, 1].
#[inline]
pub fn min_jerk(u: f64) -> (f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (
        u3 * (10.0 - 15.0 * u + 6.0 * u2),
        30.0 * u2 * (1.0 - 2.0 * u + u2),
    )
}

/// Cyclic path through waypoints, parametrised by path time `s` \[s\].
#[derive(Clone, Debug)]
pub struct Path {
    /// end-effector waypoints \[m\], base frame; the last leads back to the first
    pub waypoints: Vec<Vector3<f64>>,
    /// duration of each segment \[s\]
    pub segment_time: f64,
}

impl Path {
    /// One full cycle \[s\].
    pub fn period(&self) -> f64 {
        self.segment_time * self.waypoints.len() as f64
    }

    /// Index of the waypoint the segment at `s` ends in.
    pub fn target_index(&self, s: f64) -> usize {
        let k = (s.rem_euclid(self.period()) / self.segment_time).floor() as usize;
        (k + 1) % self.waypoints.len()
    }

    /// Unit direction of the segment at `s` (from its waypoint to the next;
    /// zero for coinciding waypoints).
    pub fn direction(&self, s: f64) -> Vector3<f64> {
        let n = self.waypoints.len();
        let s = s.rem_euclid(self.period());
        let k = ((s / self.segment_time).floor() as usize).min(n - 1);
        unit(self.waypoints[(k + 1) % n] - self.waypoints[k])
    }

    /// Position \[m\] and its derivative with respect to path time [m/s] at `s`.
    pub fn sample(&self, s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let n = self.waypoints.len();
        let s = s.rem_euclid(self.period());
        let k = ((s / self.segment_time).floor() as usize).min(n - 1);
        let u = (s - k as f64 * self.segment_time) / self.segment_time;
        let (a, b) = (self.waypoints[k], self.waypoints[(k + 1) % n]);
        let (p, dp) = min_jerk(u);
        (a + (b - a) * p, (b - a) * (dp / self.segment_time))
    }
}

/// `v / ‖v‖`, or zero for a (nearly) zero or non-finite `v`.
fn unit(v: Vector3<f64>) -> Vector3<f64> {
    let n = v.norm();
    if n > 1e-12 && n.is_finite() {
        v / n
    } else {
        Vector3::zeros()
    }
}

/// A straight minimum-jerk move of the end effector from `from` to `to`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Approach {
    /// start \[m\], base frame
    pub from: Vector3<f64>,
    /// end \[m\], base frame
    pub to: Vector3<f64>,
    /// duration of the move \[s\]
    pub duration: f64,
    /// time since the start \[s\] (at most `duration`)
    pub t: f64,
}

snapshot_fields!(Approach {
    from,
    to,
    duration,
    t
});

impl Approach {
    /// From `from` to `to` at a peak speed of `speed` \[m/s\], lasting at least 0.5 s.
    pub fn new(from: Vector3<f64>, to: Vector3<f64>, speed: f64) -> Approach {
        // a minimum-jerk move peaks at 1.875× its mean speed
        let duration = ((to - from).norm() * 1.875 / speed.max(1e-3)).max(0.5);
        Approach::lasting(from, to, duration)
    }

    /// From `from` to `to` in `duration` \[s\].
    pub fn lasting(from: Vector3<f64>, to: Vector3<f64>, duration: f64) -> Approach {
        Approach {
            from,
            to,
            duration,
            t: 0.0,
        }
    }

    /// The move has reached `to`.
    pub fn done(&self) -> bool {
        self.t >= self.duration
    }

    /// Unit direction of the move (zero for a move of no length).
    pub fn direction(&self) -> Vector3<f64> {
        unit(self.to - self.from)
    }

    /// Advance by `dt`; returns position and velocity.
    pub fn step(&mut self, dt: f64) -> (Vector3<f64>, Vector3<f64>) {
        self.t = (self.t + dt).min(self.duration);
        let (p, dp) = min_jerk(self.t / self.duration);
        (
            self.from + (self.to - self.from) * p,
            (self.to - self.from) * (dp / self.duration),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_jerk_is_smooth_at_the_ends() {
        assert_eq!(min_jerk(0.0), (0.0, 0.0));
        let (p, dp) = min_jerk(1.0);
        assert!((p - 1.0).abs() < 1e-15 && dp.abs() < 1e-12);
        // derivative matches finite differences
        let h = 1e-6;
        let u = 0.37;
        assert!(((min_jerk(u + h).0 - min_jerk(u - h).0) / (2.0 * h) - min_jerk(u).1).abs() < 1e-8);
    }

    #[test]
    fn path_is_continuous_and_cyclic() {
        let p = Path {
            waypoints: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
            ],
            segment_time: 1.0,
        };
        for k in 0..300 {
            let s = k as f64 * 0.01;
            let (a, _) = p.sample(s);
            let (b, _) = p.sample(s + 1e-6);
            assert!((a - b).norm() < 1e-4);
        }
        assert!((p.sample(1.0).0 - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        assert!((p.sample(3.0).0 - p.sample(0.0).0).norm() < 1e-12);
        assert_eq!(p.target_index(0.5), 1);
        assert_eq!(p.target_index(2.5), 0);
    }
}
