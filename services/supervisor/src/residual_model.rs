//! What the momentum residual should read, from the simulator's true
//! external torque: each joint's τ_ext through the observer's own response,
//! `K/(s + K)` behind the velocity estimate's `a/(s + a)`
//! ([`ResidualConfig::step_response`]), held between samples. A contact
//! whose model residual never reaches the collision threshold (a graze of a
//! few milliseconds) is one no observer of this bandwidth can flag; one
//! whose model crosses it must be flagged soon after.

use phri_config::ResidualConfig;

/// The model residual, joint by joint, over the truth's samples.
#[derive(Clone, Debug)]
pub struct ResidualModel {
    /// observer gain K_I per joint [1/s]
    gains: Vec<f64>,
    /// velocity-estimate bandwidth a = 2π f_c [1/s]
    a: f64,
    /// collision threshold per joint [Nm]
    thresholds: Vec<f64>,
    /// threshold on ‖r‖ [Nm]
    norm_threshold: f64,
    /// τ_ext through the velocity estimate's low-pass [Nm]
    x1: Vec<f64>,
    /// model residual [Nm]
    r: Vec<f64>,
    /// τ_ext of the last sample, held until the next [Nm]
    held: Vec<f64>,
    /// time of the last sample [s]
    t: Option<f64>,
}

/// A gap in the truth longer than this restarts the model [s].
const MAX_GAP_S: f64 = 0.1;

impl ResidualModel {
    /// The model of `dynamics`' observer with per-joint `gains` [1/s] and
    /// collision `thresholds` \[Nm\] (one per joint).
    pub fn new(dynamics: &ResidualConfig, gains: Vec<f64>, thresholds: Vec<f64>) -> ResidualModel {
        let n = gains.len().min(thresholds.len());
        ResidualModel {
            gains,
            a: 2.0 * std::f64::consts::PI * dynamics.velocity_cutoff_hz,
            thresholds,
            norm_threshold: dynamics.collision_norm_threshold,
            x1: vec![0.0; n],
            r: vec![0.0; n],
            held: vec![0.0; n],
            t: None,
        }
    }

    /// A truth sample at `t` \[s\] with the true external torques `tau_ext`
    /// \[Nm\]: the model moves on under the torque held since the last sample,
    /// then holds this one. Returns the model residual's distance to
    /// detection: the largest of |r_i| / θ_i and ‖r‖ / θ_norm (1 is the
    /// threshold).
    pub fn step(&mut self, t: f64, tau_ext: &[f64]) -> f64 {
        let dt = self.t.map_or(0.0, |t0| t - t0);
        if !(0.0..=MAX_GAP_S).contains(&dt) {
            self.x1.fill(0.0);
            self.r.fill(0.0);
        } else if dt > 0.0 {
            let (a, ea) = (self.a, (-self.a * dt).exp());
            for i in 0..self.r.len() {
                // exact for the held input u: x1 = u + c e^{−a t}, ṙ = K (x1 − r)
                let (u, k) = (self.held[i], self.gains[i]);
                let c = self.x1[i] - u;
                let ek = (-k * dt).exp();
                let r0 = self.r[i] - u;
                self.r[i] = u + if (k - a).abs() < 1e-9 * k.max(a) {
                    (r0 + k * c * dt) * ek
                } else {
                    let d = k * c / (k - a);
                    d * ea + (r0 - d) * ek
                };
                self.x1[i] = u + c * ea;
            }
        }
        self.t = Some(t);
        for (h, v) in self.held.iter_mut().zip(tau_ext) {
            *h = *v;
        }
        self.ratio()
    }

    /// Where the model residual stands against the thresholds (1: at one).
    pub fn ratio(&self) -> f64 {
        let joints = self
            .r
            .iter()
            .zip(&self.thresholds)
            .filter(|(_, th)| **th > 0.0)
            .fold(0.0f64, |m, (r, th)| m.max(r.abs() / th));
        let norm = self.r.iter().map(|r| r * r).sum::<f64>().sqrt();
        match self.norm_threshold > 0.0 {
            true => joints.max(norm / self.norm_threshold),
            false => joints,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> (ResidualModel, ResidualConfig) {
        let d = phri_config::Config::defaults().dynamics;
        (ResidualModel::new(&d, vec![100.0; 7], vec![10.0; 7]), d)
    }

    #[test]
    fn a_held_step_follows_the_observers_step_response() {
        let (mut m, d) = model();
        let mut tau = [0.0; 7];
        m.step(0.0, &tau);
        tau[3] = 5.0; // half the threshold
        m.step(0.001, &tau);
        for k in 2..=40 {
            let t = k as f64 * 1e-3;
            let ratio = m.step(t, &tau);
            // the step began at 1 ms: the model is the step response since
            let want = 5.0 * d.step_response(100.0, t - 0.001) / 10.0;
            assert!(
                (ratio - want).abs() < 0.01 * want.max(0.01),
                "{t}: {ratio} vs {want}"
            );
        }
    }

    #[test]
    fn a_short_bump_stays_below_the_threshold_a_long_push_crosses_it() {
        let (mut m, _) = model();
        // twice the threshold for 3 ms: the observer cannot see it
        let peak = (0..60)
            .map(|k| {
                let tau = [if (5..8).contains(&k) { 20.0 } else { 0.0 }; 7];
                m.step(k as f64 * 1e-3, &tau)
            })
            .fold(0.0, f64::max);
        assert!(peak < 1.0, "{peak}");
        // the same for 30 ms crosses
        let (mut m, _) = model();
        let peak = (0..60)
            .map(|k| {
                let tau = [if (5..35).contains(&k) { 20.0 } else { 0.0 }; 7];
                m.step(k as f64 * 1e-3, &tau)
            })
            .fold(0.0, f64::max);
        assert!(peak > 1.0, "{peak}");
    }

    #[test]
    fn a_gap_restarts_the_model() {
        let (mut m, _) = model();
        for k in 0..100 {
            m.step(k as f64 * 1e-3, &[30.0; 7]);
        }
        assert!(m.ratio() > 1.0);
        assert_eq!(m.step(5.0, &[0.0; 7]), 0.0);
    }
}
