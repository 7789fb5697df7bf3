//! The model terms of the computed-torque law at the measured state: the
//! joint-space inertia `M(q)` (left in [`phri_model::Data::m`]), gravity
//! `g(q)` and the bias `C(q, q̇) q̇ + g(q)`.

use phri_model::{Data, Model};

/// `g`, `C q̇ + g` and the diagonal of `M`, preallocated.
#[derive(Clone, Debug)]
pub struct DynamicsTerms {
    /// diagonal of `M(q)` [kg m²] (the limits scale their virtual end stops by it)
    pub m_diag: Vec<f64>,
    /// gravity torque `g(q)` \[Nm\]
    pub gravity: Vec<f64>,
    /// bias torque `C(q, q̇) q̇ + g(q)` \[Nm\]
    pub bias: Vec<f64>,
    zeros: Vec<f64>,
}

impl DynamicsTerms {
    pub fn new(n: usize) -> DynamicsTerms {
        DynamicsTerms {
            m_diag: vec![0.0; n],
            gravity: vec![0.0; n],
            bias: vec![0.0; n],
            zeros: vec![0.0; n],
        }
    }

    /// The terms at (`q` \[rad\], `q̇` [rad/s]); `M` lands in `data.m`. Returns
    /// how many model calls failed: a failed call leaves its term as it was
    /// in the previous period (fail-safe: the last good value).
    pub fn update(&mut self, model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) -> u64 {
        let mut errors = 0;
        if phri_model::crba(model, data, q).is_err() {
            errors += 1;
        }
        for i in 0..self.m_diag.len() {
            self.m_diag[i] = data.m[(i, i)];
        }
        match phri_model::gravity(model, data, q) {
            Ok(g) => self.gravity.copy_from_slice(g.as_slice()),
            Err(_) => errors += 1,
        }
        match phri_model::rnea(model, data, q, qd, &self.zeros) {
            Ok(b) => self.bias.copy_from_slice(b.as_slice()),
            Err(_) => errors += 1,
        }
        errors
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refused_model_calls_are_counted_and_keep_the_last_terms() {
        let model = Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        let mut data = Data::new(&model);
        let mut terms = DynamicsTerms::new(7);
        let q = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];
        assert_eq!(terms.update(&model, &mut data, &q, &[0.0; 7]), 0);
        let g = phri_model::gravity(&model, &mut Data::new(&model), &q)
            .unwrap()
            .as_slice()
            .to_vec();
        assert_eq!(terms.gravity, g);
        for i in 0..7 {
            assert!(
                (terms.bias[i] - g[i]).abs() < 1e-12,
                "at rest the bias is gravity"
            );
        }
        assert!(terms.m_diag.iter().all(|m| *m > 0.0));
        // a state the model refuses: three calls fail, the terms stay
        assert_eq!(terms.update(&model, &mut data, &q[..3], &[0.0; 3]), 3);
        assert_eq!(terms.gravity, g);
    }
}
