//! What the drives can follow. Under the barrier filter each joint's
//! reference accelerates no faster than [`FEED_FORWARD_SHARE`] of the
//! torque its effort limit leaves beyond the bias it already carries can
//! give it alone: `share · (τ_max,i − |C q̇ + g|_i) / M_ii` at the measured
//! state, below `[avoidance] accel_limit`. Without it an escape at `accel_limit`
//! asked 2-2.5 times the Panda's shoulder torques in a stretched posture;
//! clamped at the last step, the arm left its reference, and its elbow ran
//! 8 cm-rad ahead of it into its end stop (the stop's jolt a false
//! collision).

use nalgebra::DMatrix;
use phri_model::Model;

/// The share of the torque each joint's effort limit leaves beyond its
/// bias that its reference's acceleration may take under the barrier
/// filter; the rest is left to the tracking feedback and to the coupling
/// between the joints.
pub const FEED_FORWARD_SHARE: f64 = 0.85;

/// The least acceleration cap \[rad/s²\]: a joint whose bias alone takes
/// its share still turns back.
pub const MIN_ACCEL: f64 = 1.0;

/// Each joint's acceleration cap from its drive, preallocated.
#[derive(Clone, Debug)]
pub struct DriveCaps {
    /// each joint's effort limit \[Nm\] (∞: none)
    effort: Vec<f64>,
    /// the caps of the last [`DriveCaps::update`] \[rad/s²\]
    caps: Vec<f64>,
}

impl DriveCaps {
    /// The drives of `model`'s actuated joints; no cap until the first update.
    pub fn new(model: &Model) -> DriveCaps {
        let n = model.actuated().len();
        DriveCaps {
            effort: model.actuated().iter().map(|j| j.effort.abs()).collect(),
            caps: vec![f64::INFINITY; n],
        }
    }

    /// The caps at the measured state: joint-space inertia `m` \[kg m²\],
    /// bias torque `bias` = `C q̇ + g` \[Nm\]. A joint without an effort
    /// limit is uncapped; a non-finite or non-positive inertia, or a
    /// non-finite bias, caps it at [`MIN_ACCEL`].
    pub fn update(&mut self, m: &DMatrix<f64>, bias: &[f64]) {
        let n = self
            .caps
            .len()
            .min(bias.len())
            .min(m.nrows())
            .min(m.ncols());
        for i in 0..n {
            let m_ii = m[(i, i)];
            let room = FEED_FORWARD_SHARE * (self.effort[i] - bias[i].abs());
            let inertia = m_ii.is_finite() && m_ii > 0.0;
            self.caps[i] = if inertia && room.is_finite() {
                (room / m_ii).max(MIN_ACCEL)
            } else if inertia && room == f64::INFINITY {
                f64::INFINITY
            } else {
                MIN_ACCEL
            };
        }
    }

    /// Joint `i`'s acceleration cap \[rad/s²\] (∞: none).
    pub fn cap(&self, i: usize) -> f64 {
        self.caps.get(i).copied().unwrap_or(f64::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_joint_accelerates_no_faster_than_its_drive_less_its_bias_gives_it() {
        let model = Model::from_urdf_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        ))
        .unwrap();
        let n = model.actuated().len();
        let effort: Vec<f64> = model.actuated().iter().map(|j| j.effort).collect();
        let mut d = DriveCaps::new(&model);
        assert!(
            (0..n).all(|i| d.cap(i).is_infinite()),
            "no cap before the first update"
        );
        let mut m = DMatrix::identity(n, n) * 2.0;
        m[(1, 1)] = 4.0;
        let mut bias = vec![0.0; n];
        bias[1] = -10.0;
        // the bias as large as the joint's limit: it still turns back
        bias[2] = -effort[2];
        d.update(&m, &bias);
        assert!((d.cap(0) - FEED_FORWARD_SHARE * effort[0] / 2.0).abs() < 1e-12);
        assert!((d.cap(1) - FEED_FORWARD_SHARE * (effort[1] - 10.0) / 4.0).abs() < 1e-12);
        assert_eq!(d.cap(2), MIN_ACCEL);
        // a broken inertia caps at the least, never at ∞ or NaN
        m[(3, 3)] = f64::NAN;
        d.update(&m, &bias);
        assert_eq!(d.cap(3), MIN_ACCEL);
        assert!(d.cap(n).is_infinite(), "no such joint");
    }
}
