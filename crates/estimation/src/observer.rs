//! The momentum residual (paper eq. 5) in discrete time:
//!
//! `r_k = K_I ( p_k − p_0 − Σ_j (τ_j − τ_f,j + (Cᵀq̇ − g)_j + J_eᵀF_m,j + r_{j−1}) Δt_j )`
//!
//! with `p = M(q) q̇`, q̇ estimated from positions, `τ_f` the nominal friction
//! and `J_eᵀF_m` only when a wrist F/T reading is used (eq. 8). `τ_j` is the
//! torque the robot held over the period ending at sample j; the
//! state-dependent terms are averaged over the period (trapezoid); `r` enters
//! explicitly, so each component is a first-order low-pass of τ_ext with
//! bandwidth K_I.

use nalgebra::{Matrix6xX, Vector3};
use phri_config::{Invalid, ResidualConfig};
use phri_model::{check_len, Data, Model};

use crate::detect::{Detection, Detector};
use crate::velocity::VelocityEstimator;

/// Why the observer could not be built or refused a sample.
#[derive(Debug, thiserror::Error)]
pub enum ResidualError {
    /// a `[dynamics]` value out of range or not fitting the model (names the key)
    #[error(transparent)]
    Config(#[from] Invalid),
    /// `q` or `tau` of the wrong length
    #[error(transparent)]
    Dimension(#[from] phri_model::LengthError),
    /// the time, `q` or `tau` holds a NaN or an infinity
    #[error("{0}: not a finite number")]
    NotFinite(&'static str),
    /// a dynamics or kinematics call on the model failed
    #[error(transparent)]
    Model(#[from] phri_model::ModelError),
}

/// Result of one step (borrowed from the observer's buffers).
#[derive(Debug)]
pub struct ResidualOutput<'a> {
    /// residual \[Nm\]
    pub r: &'a [f64],
    /// estimated joint velocity [rad/s]
    pub qd: &'a [f64],
    /// ‖r‖ \[Nm\]
    pub norm: f64,
    /// `r` judged by the detector (all false during warm-up)
    pub detection: Detection,
    /// past warm-up: the residual is meaningful
    pub valid: bool,
    /// the F/T reading entered the integrand
    pub ft_used: bool,
}

/// Residual observer with preallocated buffers; `step` allocates nothing.
pub struct ResidualObserver {
    model: Model,
    data: Data,
    gain: Vec<f64>,
    viscous: Vec<f64>,
    coulomb: Vec<f64>,
    coulomb_velocity: f64,
    use_ft: bool,
    ft_frame: usize,
    jac: Matrix6xX<f64>,
    detector: Detector,
    velocity: VelocityEstimator,
    warmup: u32,
    max_gap_s: f64,
    // state
    samples: u32,
    last_t: Option<f64>,
    p0: Vec<f64>,
    integral: Vec<f64>,
    last_integrand: Vec<f64>,
    /// the integrand through the velocity estimate's low-pass
    forcing: Vec<f64>,
    r: Vec<f64>,
    integrand: Vec<f64>,
}

impl ResidualObserver {
    /// An observer for `model` with `[dynamics]` settings `cfg`: validated,
    /// per-joint values resolved against the model's joint count, the F/T
    /// link looked up.
    pub fn new(model: Model, cfg: &ResidualConfig) -> Result<Self, ResidualError> {
        let n = model.nv();
        cfg.validate()?;
        let gain = cfg.gain.resolve(n, "dynamics.gain")?;
        if gain.iter().any(|&k| k <= 0.0) {
            return Err(Invalid::new("dynamics.gain", "must be positive").into());
        }
        let detector = Detector {
            contact: cfg
                .contact_threshold
                .resolve(n, "dynamics.contact_threshold")?,
            collision: cfg
                .collision_threshold
                .resolve(n, "dynamics.collision_threshold")?,
            norm: cfg.collision_norm_threshold,
        };
        let ft_link = if cfg.ft_link.is_empty() {
            model.actuated()[n - 1].child_link.clone()
        } else {
            cfg.ft_link.clone()
        };
        let ft_frame = model
            .frame_id(&ft_link)
            .map_err(|_| Invalid::new("dynamics.ft_link", format!("unknown link '{ft_link}'")))?;
        Ok(ResidualObserver {
            data: Data::new(&model),
            jac: Data::jacobian_buffer(&model),
            viscous: cfg
                .viscous_friction
                .resolve(n, "dynamics.viscous_friction")?,
            coulomb: cfg
                .coulomb_friction
                .resolve(n, "dynamics.coulomb_friction")?,
            coulomb_velocity: cfg.coulomb_velocity.max(1e-6),
            use_ft: cfg.use_ft_sensor,
            ft_frame,
            detector,
            velocity: VelocityEstimator::new(n, cfg.velocity_cutoff_hz),
            warmup: cfg.warmup_samples.max(2),
            max_gap_s: cfg.max_gap_s,
            samples: 0,
            last_t: None,
            p0: vec![0.0; n],
            integral: vec![0.0; n],
            last_integrand: vec![0.0; n],
            forcing: vec![0.0; n],
            r: vec![0.0; n],
            integrand: vec![0.0; n],
            gain,
            model,
        })
    }

    /// The robot model the observer runs on.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The contact and collision thresholds, from the `[dynamics]` settings.
    pub fn detector(&self) -> &Detector {
        &self.detector
    }

    /// Start over: velocity history, p(0), integral and r.
    pub fn reset(&mut self) {
        self.samples = 0;
        self.last_t = None;
        self.velocity.reset();
        self.integral.fill(0.0);
        self.r.fill(0.0);
    }

    /// One sample: time `t` \[s\], measured positions `q`, the torque `tau`
    /// applied since the previous sample, and an optional wrist wrench
    /// (force, moment; base frame, at the F/T link's origin).
    pub fn step(
        &mut self,
        t: f64,
        q: &[f64],
        tau: &[f64],
        wrench: Option<&[f64; 6]>,
    ) -> Result<ResidualOutput<'_>, ResidualError> {
        let n = self.model.nv();
        check_len("q", n, q.len())?;
        check_len("tau", n, tau.len())?;
        if !t.is_finite() || q.iter().any(|x| !x.is_finite()) {
            return Err(ResidualError::NotFinite("q"));
        }
        if tau.iter().any(|x| !x.is_finite()) {
            return Err(ResidualError::NotFinite("tau"));
        }
        let dt = match self.last_t {
            Some(t0) if t > t0 && t - t0 <= self.max_gap_s => t - t0,
            Some(_) => {
                // clock jump or a long gap: the integral would be meaningless
                self.reset();
                0.0
            }
            None => 0.0,
        };
        self.last_t = Some(t);
        let qd = self.velocity.update(q, dt);
        phri_model::residual_terms(&self.model, &mut self.data, q, qd)?;
        let ft_used = self.use_ft && wrench.is_some();
        if ft_used {
            phri_model::forward_kinematics(&self.model, &mut self.data, q)?;
            phri_model::point_jacobian(
                &self.model,
                &self.data,
                self.ft_frame,
                &Vector3::zeros(),
                &mut self.jac,
            )?;
        }
        for i in 0..n {
            let v = qd[i];
            let friction =
                self.viscous[i] * v + self.coulomb[i] * (v / self.coulomb_velocity).tanh();
            let mut x = self.data.residual_bias[i] - friction;
            if let (true, Some(w)) = (ft_used, wrench) {
                let col = self.jac.column(i);
                x += (0..6).map(|k| col[k] * w[k]).sum::<f64>();
            }
            self.integrand[i] = x;
        }
        self.samples = self.samples.saturating_add(1);
        // the velocity filter needs a few samples before p(0) is meaningful
        // the applied torque is held over the period; the state-dependent
        // terms are averaged; all through the low-pass that made q̇ (and so
        // p), so that the momentum and its integrated rate lag alike
        let alpha = self.velocity.smoothing(dt);
        for i in 0..n {
            let x = tau[i] + 0.5 * (self.integrand[i] + self.last_integrand[i]);
            self.forcing[i] = match self.samples <= self.warmup {
                true => x,
                false => alpha * self.forcing[i] + (1.0 - alpha) * x,
            };
        }
        if self.samples <= self.warmup {
            self.p0.copy_from_slice(self.data.p.as_slice());
            self.integral.fill(0.0);
            self.r.fill(0.0);
        } else {
            for i in 0..n {
                self.integral[i] += dt * (self.forcing[i] + self.r[i]);
                self.r[i] = self.gain[i] * (self.data.p[i] - self.p0[i] - self.integral[i]);
            }
        }
        self.last_integrand.copy_from_slice(&self.integrand);
        let valid = self.samples > self.warmup;
        let detection = if valid {
            self.detector.classify(&self.r)
        } else {
            Detection::default()
        };
        let norm = self.r.iter().map(|x| x * x).sum::<f64>().sqrt();
        Ok(ResidualOutput {
            r: &self.r,
            qd: self.velocity.velocity(),
            norm,
            detection,
            valid,
            ft_used,
        })
    }
}
