//! One FCI period of the adapter, pure: the robot's state and phri's newest
//! command in, the torque for the control box out. Allocates nothing.

use phri_ipc::TorqueCommand;
use phri_model::{Data, Model};
use phri_robot::{CommandGate, CycleTiming, LinkError, LinkOutput, RobotLink};

/// Largest change of a commanded joint torque the control box accepts
/// \[Nm/s\] (libfranka's `kMaxTorqueRate`).
pub const MAX_TORQUE_RATE_NM_PER_S: f64 = 1000.0;

/// FCI's joints.
pub const JOINTS: usize = 7;

/// Why an [`FciCycle`] could not be built, or refused a state.
#[derive(Debug, thiserror::Error)]
pub enum CycleError {
    /// the robot model has another number of joints than [`JOINTS`]
    #[error("the robot model has {0} joints; a Franka arm has 7")]
    Joints(usize),
    /// the protocol's bookkeeping could not be set up
    #[error(transparent)]
    Link(#[from] LinkError),
    /// the control period \[s\] is not a positive finite number
    #[error("the control period must be positive, not {0} s")]
    Period(f64),
    /// the model's gravity could not be computed
    #[error("robot model: {0}")]
    Model(#[from] phri_model::ModelError),
}

/// What to send to the control box in this period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FciTorque {
    /// joint torque without gravity \[Nm\], effort-limited and rate-limited
    pub tau: [f64; JOINTS],
    /// the protocol's brakes: end the torque control (the box stops the arm
    /// by its own rule) until a controller answers again
    pub brake: bool,
}

/// The adapter's period: the model's gravity, its effort limits and the
/// protocol's decisions.
pub struct FciCycle {
    model: Model,
    data: Data,
    link: RobotLink,
    /// effort limits of the model \[Nm\]
    effort: [f64; JOINTS],
    /// largest torque step per period \[Nm\]
    max_step: f64,
    /// the torque sent last \[Nm\], without gravity
    last: [f64; JOINTS],
}

impl FciCycle {
    /// A cycle for `model` (the arm's, from its URDF) at `period_s` (FCI: 1 ms).
    pub fn new(model: Model, period_s: f64) -> Result<FciCycle, CycleError> {
        if model.nv() != JOINTS {
            return Err(CycleError::Joints(model.nv()));
        }
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(CycleError::Period(period_s));
        }
        let mut effort = [f64::INFINITY; JOINTS];
        for (e, j) in effort
            .iter_mut()
            .zip(model.joints.iter().filter(|j| j.mimic.is_none()))
        {
            *e = j.effort;
        }
        Ok(FciCycle {
            data: Data::new(&model),
            link: RobotLink::new(JOINTS, (period_s * 1e9) as u64)?,
            effort,
            max_step: MAX_TORQUE_RATE_NM_PER_S * period_s,
            last: [0.0; JOINTS],
            model,
        })
    }

    /// The arm's model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The protocol's bookkeeping.
    pub fn link(&self) -> &RobotLink {
        &self.link
    }

    /// Take commands only from the senders `gate` admits ([`RobotLink::set_gate`]).
    pub fn set_gate(&mut self, gate: CommandGate) {
        self.link.set_gate(gate);
    }

    /// Take the newest admitted command of each slot ([`RobotLink::poll`]);
    /// true when one answers state `state_seq`.
    pub fn poll(
        &mut self,
        channels: [&phri_ipc::Subscriber<TorqueCommand>; phri_robot::SLOTS],
        newest: &mut [Option<TorqueCommand>; phri_robot::SLOTS],
        state_seq: u64,
    ) -> Result<bool, phri_ipc::IpcError> {
        self.link.poll(channels, newest, state_seq)
    }

    /// The torque sent last, without gravity \[Nm\]: what the box is sent
    /// again for a state the adapter refused.
    pub fn held(&self) -> [f64; JOINTS] {
        self.last
    }

    /// `robot/stats` now (`stamp_ns` on this machine's clock).
    pub fn stats_message(&mut self, stamp_ns: u64) -> &phri_ipc::RobotStats {
        self.link.stats_message(stamp_ns)
    }

    /// `robot/commanders` now (`stamp_ns` on this machine's clock).
    pub fn commanders_message(&mut self, stamp_ns: u64) -> &phri_ipc::CommanderStats {
        self.link.commanders_message(stamp_ns)
    }

    /// Gravity `g(q)` of the model \[Nm\].
    pub fn gravity(&mut self, q: &[f64; JOINTS]) -> Result<[f64; JOINTS], CycleError> {
        let g = phri_model::gravity(&self.model, &mut self.data, q)?;
        let mut out = [0.0; JOINTS];
        out.copy_from_slice(g.as_slice());
        Ok(out)
    }

    /// A new torque control started (the first, or after brakes): the box
    /// starts from zero torque, so does the rate limit.
    pub fn restart(&mut self) {
        self.last = [0.0; JOINTS];
    }

    /// The torque the arm's motors apply as phri's residual counts it, at
    /// joints `q` \[rad\]: the last torque sent plus the box's gravity
    /// compensation (phri's model's g(q), the one subtracted) \[Nm\]. What
    /// `robot/state` carries, as phri-sim's applied torque: a box's own
    /// τ_J is its sensors' (franka-sim reports the commanded torque without
    /// gravity).
    pub fn applied(&mut self, q: &[f64; JOINTS]) -> Result<[f64; JOINTS], CycleError> {
        let g = self.gravity(q)?;
        Ok(std::array::from_fn(|k| self.last[k] + g[k]))
    }

    /// One period: `newest` is phri's newest command, `state_seq` the state
    /// it should answer, `q` the measured joints \[rad\]. The torque for the
    /// box is phri's, clipped to the model's effort limits, less gravity
    /// (itself within the limits, as the box checks what it is sent),
    /// changed by at most the box's rate from the last one sent; under the
    /// protocol's brakes it decays to zero at that rate.
    pub fn step(
        &mut self,
        newest: Option<&TorqueCommand>,
        state_seq: u64,
        timing: &CycleTiming,
        q: &[f64; JOINTS],
    ) -> Result<(LinkOutput, FciTorque), CycleError> {
        self.step_slots([newest, None], state_seq, timing, q)
    }

    /// [`FciCycle::step`] with a hot standby: `newest[s]` is command slot
    /// `s`'s newest command (`RobotLink::cycle_slots`).
    pub fn step_slots(
        &mut self,
        newest: [Option<&TorqueCommand>; phri_robot::SLOTS],
        state_seq: u64,
        timing: &CycleTiming,
        q: &[f64; JOINTS],
    ) -> Result<(LinkOutput, FciTorque), CycleError> {
        let out = self.link.cycle_slots(newest, state_seq, timing);
        let g = self.gravity(q)?;
        let mut tau = [0.0; JOINTS];
        for k in 0..JOINTS {
            let wanted = match out.brake {
                true => 0.0,
                // the motors' total within the effort limit, and the part
                // the box is sent too (the box checks its tau_J_d range)
                false => (out.tau[k].clamp(-self.effort[k], self.effort[k]) - g[k])
                    .clamp(-self.effort[k], self.effort[k]),
            };
            tau[k] = wanted.clamp(self.last[k] - self.max_step, self.last[k] + self.max_step);
        }
        self.last = tau;
        Ok((
            out,
            FciTorque {
                tau,
                brake: out.brake,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn cycle() -> FciCycle {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        );
        let model = Model::from_urdf_file(urdf).expect("the LWR's URDF");
        FciCycle::new(model, 1e-3).expect("7 joints")
    }

    fn command(seq: u64, tau: [f64; JOINTS]) -> TorqueCommand {
        let mut c = TorqueCommand::zeroed();
        c.seq = seq;
        c.state_seq = seq;
        c.dof = JOINTS as u32;
        c.tau[..JOINTS].copy_from_slice(&tau);
        c
    }

    fn timing(seq: u64) -> CycleTiming {
        CycleTiming {
            state_published_ns: seq * 1_000_000,
            command_event_ns: seq * 1_000_000 + 100_000,
            now_ns: seq * 1_000_000 + 100_000,
            behind_schedule_ns: 0,
            standby_asked: false,
        }
    }

    const Q: [f64; JOINTS] = [0.1, 0.5, -0.2, -1.2, 0.3, 0.8, 0.0];

    #[test]
    fn the_box_gets_the_command_less_gravity_at_its_torque_rate() {
        let mut c = cycle();
        let g = c.gravity(&Q).unwrap();
        let u = [0.5, -0.4, 0.3, 0.2, -0.1, 0.05, 0.0];
        let mut tau = [0.0; JOINTS];
        for k in 0..JOINTS {
            tau[k] = g[k] + u[k];
        }
        // the first period: at most 1 Nm (1000 Nm/s × 1 ms) from zero
        let (_, first) = c.step(Some(&command(1, tau)), 1, &timing(1), &Q).unwrap();
        for k in 0..JOINTS {
            assert!(first.tau[k].abs() <= 1.0 + 1e-12, "{first:?}");
        }
        // within a few periods exactly the command less gravity
        let mut last = first;
        for seq in 2..=60 {
            last = c
                .step(Some(&command(seq, tau)), seq, &timing(seq), &Q)
                .unwrap()
                .1;
        }
        for k in 0..JOINTS {
            assert!((last.tau[k] - u[k]).abs() < 1e-9, "joint {k}: {last:?}");
        }
        assert!(!last.brake);
    }

    #[test]
    fn a_command_beyond_the_effort_limit_is_clipped_before_gravity_comes_off() {
        for sign in [1.0, -1.0] {
            let mut c = cycle();
            let g = c.gravity(&Q).unwrap();
            let effort = c.effort;
            let mut last = None;
            for seq in 1..=400 {
                let out = c.step(
                    Some(&command(seq, [sign * 1e6; JOINTS])),
                    seq,
                    &timing(seq),
                    &Q,
                );
                last = Some(out.unwrap().1);
            }
            let last = last.unwrap();
            for k in 0..JOINTS {
                let e = effort[k];
                assert!(
                    (last.tau[k] - (sign * e - g[k]).clamp(-e, e)).abs() < 1e-9,
                    "joint {k}: {last:?}"
                );
                // what the box is sent and what the motors give, both within
                assert!(last.tau[k].abs() <= e + 1e-9);
                assert!((last.tau[k] + g[k]).abs() <= e + 1e-9);
            }
        }
    }

    #[test]
    fn without_commands_the_brakes_come_and_the_torque_fades_at_the_box_rate() {
        let mut c = cycle();
        let g = c.gravity(&Q).unwrap();
        let mut tau = g;
        tau[1] += 5.0;
        for seq in 1..=20 {
            c.step(Some(&command(seq, tau)), seq, &timing(seq), &Q)
                .unwrap();
        }
        let mut outs = Vec::new();
        for seq in 21..=50 {
            outs.push(c.step(None, seq, &timing(seq), &Q).unwrap().1);
        }
        // 20 misses are tolerated (the last torque reused), the 21st brakes
        assert!(outs[..20]
            .iter()
            .all(|o| !o.brake && (o.tau[1] - 5.0).abs() < 1e-9));
        assert!(outs[20..].iter().all(|o| o.brake));
        assert!((outs[20].tau[1] - 4.0).abs() < 1e-9 && outs[25].tau[1].abs() < 1e-12);
    }

    #[test]
    fn only_a_seven_joint_arm_and_a_positive_period() {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../deploy/robots/kuka_lwr4.urdf"
        );
        let model = Model::from_urdf_file(urdf).unwrap();
        assert!(matches!(
            FciCycle::new(model, 0.0),
            Err(CycleError::Period(_))
        ));
    }
}
