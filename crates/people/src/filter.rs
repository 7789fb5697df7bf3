//! The one-euro filter (Casiez, Roussel, Vogel, CHI 2012) of a 3-D point:
//! a low-pass whose cut-off rises with the point's speed (little lag when it
//! moves, little jitter when it rests), restarted by a jump (a re-detection).

use std::f64::consts::TAU;

/// Parameters of a [`OneEuro`] filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneEuroParams {
    /// cut-off at rest \[Hz\]
    pub min_cutoff_hz: f64,
    /// cut-off growth per m/s
    pub beta: f64,
    /// cut-off of the speed estimate \[Hz\]
    pub d_cutoff_hz: f64,
    /// a jump farther than this restarts the filter \[m\]
    pub snap_m: f64,
}

/// State of one filtered point \[m\], \[m/s\].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OneEuro {
    x: [f64; 3],
    dx: [f64; 3],
    init: bool,
}

/// Smoothing factor of a first-order low-pass at `cutoff` \[Hz\] over `dt` \[s\].
#[inline]
fn alpha(cutoff: f64, dt: f64) -> f64 {
    let tau = 1.0 / (TAU * cutoff);
    1.0 / (1.0 + tau / dt)
}

impl OneEuro {
    /// Forgets the state.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// The last output \[m\].
    pub fn value(&self) -> [f64; 3] {
        self.x
    }

    /// Filters measurement `p` \[m\] taken `dt` \[s\] after the last one.
    pub fn update(&mut self, p: [f64; 3], dt: f64, k: &OneEuroParams) -> [f64; 3] {
        let jump =
            ((p[0] - self.x[0]).powi(2) + (p[1] - self.x[1]).powi(2) + (p[2] - self.x[2]).powi(2))
                .sqrt();
        if !self.init || !(dt > 0.0) || !(jump <= k.snap_m) {
            self.x = p;
            self.dx = [0.0; 3];
            self.init = true;
            return p;
        }
        let ad = alpha(k.d_cutoff_hz, dt);
        let mut speed2 = 0.0;
        for i in 0..3 {
            let raw = (p[i] - self.x[i]) / dt;
            self.dx[i] += ad * (raw - self.dx[i]);
            speed2 += self.dx[i] * self.dx[i];
        }
        let a = alpha(k.min_cutoff_hz + k.beta * speed2.sqrt(), dt);
        for i in 0..3 {
            self.x[i] += a * (p[i] - self.x[i]);
        }
        self.x
    }
}
