//! Joint velocity from encoder positions: backward difference through a
//! first-order low-pass (the paper measures positions only).

/// Filtered finite-difference velocity estimator, preallocated.
#[derive(Clone, Debug)]
pub struct VelocityEstimator {
    cutoff_hz: f64,
    last_q: Vec<f64>,
    qd: Vec<f64>,
    primed: bool,
}

impl VelocityEstimator {
    /// An estimator for `n` joints, its low-pass cut off at `cutoff_hz` \[Hz\],
    /// at rest until it has seen positions.
    pub fn new(n: usize, cutoff_hz: f64) -> Self {
        VelocityEstimator {
            cutoff_hz,
            last_q: vec![0.0; n],
            qd: vec![0.0; n],
            primed: false,
        }
    }

    /// The filter's state: the last positions \[rad\], the estimate
    /// \[rad/s\], and whether it has seen positions yet.
    pub fn state(&self) -> (&[f64], &[f64], bool) {
        (&self.last_q, &self.qd, self.primed)
    }

    /// Take over another estimator's state ([`VelocityEstimator::state`]) of
    /// the same joints: `false` (nothing changed) for another length.
    pub fn set_state(&mut self, last_q: &[f64], qd: &[f64], primed: bool) -> bool {
        if last_q.len() != self.last_q.len() || qd.len() != self.qd.len() {
            return false;
        }
        self.last_q.copy_from_slice(last_q);
        self.qd.copy_from_slice(qd);
        self.primed = primed;
        true
    }

    /// Forget the history (next update starts from rest).
    pub fn reset(&mut self) {
        self.primed = false;
        self.qd.fill(0.0);
    }

    /// Feed positions `q` \[rad\] taken `dt` \[s\] after the previous ones; returns q̇ [rad/s].
    pub fn update(&mut self, q: &[f64], dt: f64) -> &[f64] {
        if !self.primed || dt <= 0.0 {
            self.last_q.copy_from_slice(q);
            self.primed = true;
            return &self.qd;
        }
        let alpha = self.smoothing(dt);
        for i in 0..q.len() {
            let raw = (q[i] - self.last_q[i]) / dt;
            self.qd[i] = alpha * self.qd[i] + (1.0 - alpha) * raw;
            self.last_q[i] = q[i];
        }
        &self.qd
    }

    /// The low-pass's weight of the old estimate for a step of `dt` \[s\]:
    /// `v ← α v + (1 − α) raw`.
    pub fn smoothing(&self, dt: f64) -> f64 {
        (-2.0 * std::f64::consts::PI * self.cutoff_hz * dt.max(0.0)).exp()
    }

    /// The current estimate q̇ \[rad/s\].
    pub fn velocity(&self) -> &[f64] {
        &self.qd
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracks_a_constant_velocity() {
        let mut e = VelocityEstimator::new(2, 50.0);
        for k in 0..500 {
            let t = k as f64 * 1e-3;
            e.update(&[0.3 * t, -1.2 * t], 1e-3);
        }
        assert!((e.velocity()[0] - 0.3).abs() < 1e-9);
        assert!((e.velocity()[1] + 1.2).abs() < 1e-9);
    }
}
