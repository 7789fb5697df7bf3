//! The last step before the robot: position, velocity and torque limits of the model.

use phri_model::Model;

/// Joint limits, with stiffness of the virtual end stops.
#[derive(Clone, Debug)]
pub struct Limits {
    /// lower position limit per joint \[rad\]
    pub lower: Vec<f64>,
    /// upper position limit per joint \[rad\]
    pub upper: Vec<f64>,
    /// velocity limit per joint \[rad/s\]
    pub velocity: Vec<f64>,
    /// torque limit per joint \[Nm\]
    pub effort: Vec<f64>,
    /// keep this far inside the position limits \[rad\]
    pub margin: f64,
}

/// What the limiter had to do in one step (bit per joint).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LimitActivity {
    /// joints pushed back by the virtual end stops
    pub position: u32,
    /// joints braked for exceeding their velocity limit
    pub velocity: u32,
    /// joints whose torque was clamped to their limit
    pub torque: u32,
    /// the command was not finite and was replaced
    pub non_finite: bool,
}

impl Limits {
    /// The limits of the model's actuated joints, keeping `margin` \[rad\] inside
    /// the position limits.
    pub fn from_model(model: &Model, margin: f64) -> Limits {
        Limits {
            lower: model.actuated().iter().map(|j| j.lower).collect(),
            upper: model.actuated().iter().map(|j| j.upper).collect(),
            velocity: model.actuated().iter().map(|j| j.velocity).collect(),
            effort: model.actuated().iter().map(|j| j.effort).collect(),
            margin,
        }
    }

    /// Clamp a joint reference inside the limits less the margin.
    pub fn clamp_position(&self, q: &mut [f64]) {
        for (i, x) in q.iter_mut().enumerate() {
            let (lo, hi) = (self.lower[i] + self.margin, self.upper[i] - self.margin);
            if lo < hi {
                *x = x.clamp(lo, hi);
            }
        }
    }

    /// Enforce the limits on `tau` for a robot at `q` moving at `qd`, with
    /// joint-space inertia diagonal `m_diag` scaling the virtual end stops;
    /// `fallback` replaces a non-finite command (e.g. gravity torque).
    pub fn apply(
        &self,
        q: &[f64],
        qd: &[f64],
        m_diag: &[f64],
        fallback: &[f64],
        tau: &mut [f64],
    ) -> LimitActivity {
        let mut act = LimitActivity::default();
        if tau.iter().any(|t| !t.is_finite()) {
            act.non_finite = true;
            for (t, f) in tau.iter_mut().zip(fallback) {
                *t = if f.is_finite() { *f } else { 0.0 };
            }
        }
        const K_STOP: f64 = 400.0; // [1/s²]
        const D_STOP: f64 = 40.0; // [1/s]
        const K_VEL: f64 = 50.0; // [1/s]
        for i in 0..tau.len() {
            let (lo, hi) = (
                self.lower[i] + 0.5 * self.margin,
                self.upper[i] - 0.5 * self.margin,
            );
            // virtual end stops: push back inside, damping only motion outwards
            if q[i] > hi {
                tau[i] += m_diag[i] * (K_STOP * (hi - q[i]) - D_STOP * qd[i].max(0.0));
                act.position |= 1 << i;
            } else if q[i] < lo {
                tau[i] += m_diag[i] * (K_STOP * (lo - q[i]) - D_STOP * qd[i].min(0.0));
                act.position |= 1 << i;
            }
            // velocity: brake the excess
            let v = self.velocity[i];
            if qd[i].abs() > v {
                tau[i] -= m_diag[i] * K_VEL * (qd[i] - v.copysign(qd[i]));
                act.velocity |= 1 << i;
            }
            let e = self.effort[i];
            if tau[i].abs() > e {
                tau[i] = e.copysign(tau[i]);
                act.torque |= 1 << i;
            }
        }
        act
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> Limits {
        Limits {
            lower: vec![-1.0; 2],
            upper: vec![1.0; 2],
            velocity: vec![2.0; 2],
            effort: vec![10.0; 2],
            margin: 0.1,
        }
    }

    #[test]
    fn torque_is_clamped_and_nan_replaced() {
        let l = limits();
        let mut tau = [50.0, -50.0];
        let a = l.apply(&[0.0; 2], &[0.0; 2], &[1.0; 2], &[0.0; 2], &mut tau);
        assert_eq!(tau, [10.0, -10.0]);
        assert_eq!(a.torque, 0b11);
        let mut tau = [f64::NAN, 1.0];
        let a = l.apply(&[0.0; 2], &[0.0; 2], &[1.0; 2], &[3.0, 4.0], &mut tau);
        assert!(a.non_finite);
        assert_eq!(tau, [3.0, 4.0]);
    }

    #[test]
    fn end_stops_push_inwards_and_overspeed_is_braked() {
        let l = limits();
        let mut tau = [0.0, 0.0];
        l.apply(
            &[0.99, -0.99],
            &[0.5, -0.5],
            &[0.01; 2],
            &[0.0; 2],
            &mut tau,
        );
        assert!(tau[0] < 0.0 && tau[1] > 0.0);
        let mut tau = [0.0, 0.0];
        l.apply(&[0.0, 0.0], &[3.0, -3.0], &[0.1; 2], &[0.0; 2], &mut tau);
        assert!(tau[0] < 0.0 && tau[1] > 0.0);
        let mut q = [5.0, -5.0];
        l.clamp_position(&mut q);
        assert_eq!(q, [0.9, -0.9]);
    }
}
