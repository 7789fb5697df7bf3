//! The dynamics service as a pure, deterministic step over messages: a
//! [`JointState`] in, the [`Residual`] message out (momentum residual, paper
//! Sect. III, eqs. 4-8; detection flags; the isolated joint). The estimators
//! themselves live in `phri-estimation`; `main.rs` only wires `robot/state`
//! to `dynamics/residual`, and the lock-step cell calls the same step.

#![deny(missing_docs)]

use std::time::Duration;

use phri_config::ResidualConfig;
use phri_estimation::{ResidualError, ResidualObserver};
use phri_ipc::{residual_flags, robot_status, JointState, Residual, Zeroed};
use phri_model::Model;

/// Why a state produced no residual.
#[derive(Debug, thiserror::Error)]
pub enum DynamicsError {
    /// the robot model has more joints than a message carries
    #[error("the model has {model} joints, the messages carry at most {max}")]
    TooManyJoints {
        /// joints of the model
        model: usize,
        /// most joints a message carries
        max: usize,
    },
    /// a state whose joint count is not the model's
    #[error("state {seq} has {got} joints, the model {model}")]
    Dof {
        /// the state's sequence number
        seq: u64,
        /// joints in the state
        got: u32,
        /// joints of the model
        model: usize,
    },
    /// the observer refused the state (non-finite values) or its configuration
    #[error("state {seq}: {source}")]
    State {
        /// the state's sequence number
        seq: u64,
        /// the observer's error
        #[source]
        source: ResidualError,
    },
    /// the observer could not be built from the model and the `[dynamics]`
    /// settings
    #[error(transparent)]
    Config(#[from] ResidualError),
}

/// How the service waits for robot states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wake {
    /// woken by every state (the service in charge), and by this timeout
    /// at the latest (a loop that checks for shutdown)
    EveryState(Duration),
    /// on its own clock this often, stepping the states queued since, and
    /// at once when the controller in charge calls (the hot standby: one
    /// wake-up in several states while the one in charge answers)
    Every(Duration),
}

/// The longest wait for a state of the service in charge.
pub const STATE_WAIT: Duration = Duration::from_millis(50);

impl Wake {
    /// The service in charge wakes at every state; the hot standby
    /// (`standby`) every `standby_wake_ms` (`[dynamics] standby_wake_ms`),
    /// or at every state as well when that is 0 or not a finite positive
    /// value.
    pub fn of(standby: bool, standby_wake_ms: f64) -> Wake {
        match standby && standby_wake_ms.is_finite() && standby_wake_ms > 0.0 {
            true => Wake::Every(Duration::from_secs_f64(standby_wake_ms.min(1e3) * 1e-3)),
            false => Wake::EveryState(STATE_WAIT),
        }
    }

    /// How long one wait lasts at most.
    pub fn timeout(self) -> Duration {
        match self {
            Wake::EveryState(d) | Wake::Every(d) => d,
        }
    }
}

/// The residual observer and the message it fills; `step` allocates nothing.
pub struct DynamicsStep {
    observer: ResidualObserver,
    msg: Residual,
    n: usize,
}

impl DynamicsStep {
    /// An observer for `model` with `[dynamics]` settings `cfg` (validated here).
    pub fn new(model: Model, cfg: &ResidualConfig) -> Result<DynamicsStep, DynamicsError> {
        let n = model.nv();
        if n > phri_ipc::MAX_DOF {
            return Err(DynamicsError::TooManyJoints {
                model: n,
                max: phri_ipc::MAX_DOF,
            });
        }
        let mut msg = Residual::zeroed();
        msg.dof = n as u32;
        msg.isolated_joint = -1;
        Ok(DynamicsStep {
            observer: ResidualObserver::new(model, cfg)?,
            msg,
            n,
        })
    }

    /// One robot state: its positions \[rad\] at `stamp_ns` [ns, robot clock],
    /// the torque applied over the period that ended there \[Nm\] and, when the
    /// status says `FT_VALID`, the wrist wrench [N, Nm; base frame, at the
    /// F/T link's origin]. Returns the residual message: `r` \[Nm\], the
    /// estimated `qd` [rad/s], ‖r‖, [`residual_flags`], the isolated joint
    /// (−1: none), the state's sequence and stamp. `seq`, `stamp_ns` and
    /// `compute_ns` are those of the last [`DynamicsStep::seal`].
    ///
    /// A state whose torque is not known (`TORQUE_UNKNOWN`: a control box
    /// holds the arm) gives no valid residual and starts the observer over.
    /// A state of the wrong joint count or with non-finite values is refused
    /// and leaves the message as it was.
    pub fn step(&mut self, state: &JointState) -> Result<&Residual, DynamicsError> {
        let n = self.n;
        if state.dof as usize != n {
            return Err(DynamicsError::Dof {
                seq: state.seq,
                got: state.dof,
                model: n,
            });
        }
        if state.status & robot_status::TORQUE_UNKNOWN != 0 {
            // the arm's own box holds it: no residual, and a fresh start
            // (warm-up included) once phri's torque acts again
            self.observer.reset();
            let m = &mut self.msg;
            m.r.fill(0.0);
            m.qd.fill(0.0);
            m.norm = 0.0;
            m.flags = 0;
            m.isolated_joint = -1;
            m.state_seq = state.seq;
            m.state_stamp_ns = state.stamp_ns;
            return Ok(&self.msg);
        }
        let wrench = (state.status & robot_status::FT_VALID != 0).then_some(&state.wrench);
        let out = self
            .observer
            .step(
                state.stamp_ns as f64 * 1e-9,
                &state.q[..n],
                &state.tau[..n],
                wrench,
            )
            .map_err(|source| DynamicsError::State {
                seq: state.seq,
                source,
            })?;
        let m = &mut self.msg;
        m.r[..n].copy_from_slice(out.r);
        m.qd[..n].copy_from_slice(out.qd);
        m.norm = out.norm;
        let d = out.detection;
        m.flags = (d.contact as u32 * residual_flags::CONTACT)
            | (d.collision as u32 * residual_flags::COLLISION)
            | (out.ft_used as u32 * residual_flags::FT_USED)
            | (out.valid as u32 * residual_flags::VALID);
        m.isolated_joint = d.isolated_joint.map_or(-1, |j| j as i32);
        m.state_seq = state.seq;
        m.state_stamp_ns = state.stamp_ns;
        m.dof = n as u32;
        Ok(&self.msg)
    }

    /// Number the residual of the last accepted state for publishing: the
    /// next sequence number, the publish time `stamp_ns` [ns, CLOCK_MONOTONIC]
    /// and the time its step took `compute_ns` \[ns\]. A reader drains every
    /// queued state and publishes the last residual once.
    pub fn seal(&mut self, stamp_ns: u64, compute_ns: u64) -> &Residual {
        self.msg.seq += 1;
        self.msg.stamp_ns = stamp_ns;
        self.msg.compute_ns = compute_ns;
        &self.msg
    }

    /// The message as it stands.
    pub fn message(&self) -> &Residual {
        &self.msg
    }

    /// The residual observer, with its state and settings.
    pub fn observer(&self) -> &ResidualObserver {
        &self.observer
    }

    /// Joints of the model.
    pub fn dof(&self) -> usize {
        self.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_config::Loaded;

    const Q: [f64; 7] = [0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0];

    fn state(seq: u64, tau: &[f64; 7]) -> JointState {
        let mut s = JointState::zeroed();
        s.seq = seq;
        s.stamp_ns = 1_000_000_000 + seq * 1_000_000;
        s.dof = 7;
        s.q[..7].copy_from_slice(&Q);
        s.tau[..7].copy_from_slice(tau);
        s
    }

    /// The default arm's observer, its gravity at `Q` [Nm] and its warm-up samples.
    fn observer() -> (DynamicsStep, [f64; 7], u64) {
        let loaded = Loaded::defaults();
        let model = loaded.model().unwrap();
        let mut d = phri_model::Data::new(&model);
        let g = phri_model::gravity(&model, &mut d, &Q).unwrap();
        let g: [f64; 7] = std::array::from_fn(|i| g[i]);
        let cfg = &loaded.config.dynamics;
        let step = DynamicsStep::new(model, cfg).unwrap();
        (step, g, cfg.warmup_samples as u64)
    }

    #[test]
    fn the_standby_wakes_on_its_clock_and_the_one_in_charge_at_every_state() {
        let ms = Duration::from_millis;
        assert_eq!(Wake::of(true, 2.0), Wake::Every(ms(2)));
        assert_eq!(Wake::of(true, 2.0).timeout(), ms(2));
        assert_eq!(Wake::of(false, 2.0), Wake::EveryState(STATE_WAIT));
        for off in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(Wake::of(true, off), Wake::EveryState(STATE_WAIT), "{off}");
        }
        // the default: the standby wakes every 10 ms
        let cfg = Loaded::defaults().config;
        assert_eq!(
            Wake::of(true, cfg.dynamics.standby_wake_ms),
            Wake::Every(ms(10))
        );
    }

    #[test]
    fn a_state_the_box_holds_gives_no_residual_and_a_fresh_warm_up() {
        let (mut step, g, warm) = observer();
        for seq in 1..=warm + 10 {
            step.step(&state(seq, &g)).unwrap();
        }
        assert_eq!(step.message().flags, residual_flags::VALID);
        // the box holds the arm: the torque reported (none, say) did not act
        let mut seq = warm + 11;
        for _ in 0..100 {
            let mut held = state(seq, &[0.0; 7]);
            held.status = robot_status::BRAKING | robot_status::TORQUE_UNKNOWN;
            let m = *step.step(&held).unwrap();
            assert_eq!(m.flags, 0, "a residual over an unknown torque");
            assert_eq!(m.state_seq, seq);
            seq += 1;
        }
        // phri's torque acts again: a fresh warm-up, then quiet
        for k in 1..=warm + 1 {
            let m = *step.step(&state(seq, &g)).unwrap();
            assert_eq!(m.flags & residual_flags::VALID != 0, k > warm, "sample {k}");
            seq += 1;
        }
        assert!(step.message().norm < 1e-6);
    }

    #[test]
    fn a_state_in_a_residual_out_flags_isolation_and_refusals() {
        let (mut step, g, warm) = observer();
        assert_eq!(step.dof(), 7);
        // the arm held still by gravity compensation: valid after warm-up, quiet
        for seq in 1..=warm {
            let m = step.step(&state(seq, &g)).unwrap();
            assert_eq!(m.flags & residual_flags::VALID, 0, "valid during warm-up");
        }
        let m = *step.step(&state(warm + 1, &g)).unwrap();
        assert_eq!(m.flags, residual_flags::VALID);
        assert_eq!((m.state_seq, m.dof, m.isolated_joint), (warm + 1, 7, -1));
        assert_eq!(m.state_stamp_ns, state(warm + 1, &g).stamp_ns);
        assert!(m.norm < 1e-6, "‖r‖ {}", m.norm);
        // 10 Nm pushing on joint 4 (the motors hold g − τ_ext): contact and
        // collision (threshold 6 Nm there), isolated at joint index 3
        let mut push = g;
        push[3] -= 10.0;
        let mut seq = warm + 2;
        let mut m = m;
        for _ in 0..200 {
            m = *step.step(&state(seq, &push)).unwrap();
            seq += 1;
        }
        assert_eq!(
            m.flags,
            residual_flags::VALID | residual_flags::CONTACT | residual_flags::COLLISION
        );
        assert_eq!(m.isolated_joint, 3);
        assert!((m.r[3] - 10.0).abs() < 1e-3, "r {:?}", &m.r[..7]);
        assert!((m.norm - 10.0).abs() < 1e-3);
        // a wrist reading is used when the robot flags it (use_ft_sensor = true)
        let mut ft = state(seq, &push);
        ft.status = robot_status::FT_VALID;
        assert_ne!(step.step(&ft).unwrap().flags & residual_flags::FT_USED, 0);
        seq += 1;
        // refusals leave the message as it was
        let before = *step.message();
        let mut six = state(seq, &g);
        six.dof = 6;
        assert!(matches!(
            step.step(&six),
            Err(DynamicsError::Dof {
                got: 6,
                model: 7,
                ..
            })
        ));
        let mut nan = state(seq, &g);
        nan.q[2] = f64::NAN;
        let e = step.step(&nan).unwrap_err();
        assert!(matches!(e, DynamicsError::State { .. }), "{e}");
        assert!(e.to_string().contains(&format!("state {seq}")), "{e}");
        assert_eq!(step.message().state_seq, before.state_seq);
        assert_eq!(step.message().r, before.r);
        // sealing numbers the publications
        assert_eq!(step.seal(7, 3).seq, 1);
        let sealed = *step.seal(8, 4);
        assert_eq!((sealed.seq, sealed.stamp_ns, sealed.compute_ns), (2, 8, 4));
    }
}
