//! The control box's own figures and errors, as `robot/box` carries them:
//! FCI's command success rate while phri controls the arm, and every error
//! of the box (a motion it aborted) with its time.

use phri_ipc::{BoxStatus, Zeroed, MAX_DOF};

use crate::cycle::JOINTS;

/// The box's own torques of a state, kept for comparison with phri's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BoxTorques {
    /// its joint torque sensors \[Nm\] (FCI's `tau_J`)
    pub tau_j: [f64; JOINTS],
    /// its external torque estimate \[Nm\] (FCI's `tau_ext_hat_filtered`)
    pub tau_ext_hat: [f64; JOINTS],
}

/// An error of the control box: the motion it aborted, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("control box: {names}")]
pub struct BoxError {
    /// the box's error names (libfranka's, e.g. `communication_constraints_violation`),
    /// comma separated, or its message when it named none
    pub names: String,
}

impl BoxError {
    /// From the error names the box set (`names`) and its message.
    pub fn new(names: &[&str], message: &str) -> BoxError {
        let names = match names.is_empty() {
            true => message
                .lines()
                .next()
                .unwrap_or("motion aborted")
                .to_owned(),
            false => names.join(", "),
        };
        BoxError { names }
    }
}

/// What the adapter refused so far: state datagrams its FCI client dropped
/// (another sender's, malformed, a stale or far-ahead message id) and
/// states it did not act on (positions not finite, or moved faster than
/// the joints can).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Refused {
    /// state datagrams from another address or port than the box's
    pub foreign: u64,
    /// state datagrams of the wrong size, or not parsable
    pub malformed: u64,
    /// state datagrams whose message id is not above the newest accepted one
    /// (a duplicate or a replay)
    pub stale_id: u64,
    /// state datagrams whose message id is further ahead than the time since
    /// allows
    pub id_ahead: u64,
    /// states with a joint position that is not finite ([`crate::StateGuard`])
    pub non_finite: u64,
    /// states whose joints moved faster than their velocity limits allow
    /// ([`crate::StateGuard`])
    pub too_fast: u64,
}

impl Refused {
    /// Everything refused.
    pub fn total(&self) -> u64 {
        self.foreign
            + self.malformed
            + self.stale_id
            + self.id_ahead
            + self.non_finite
            + self.too_fast
    }
}

/// The figures of `robot/box`, kept across torque controls.
pub struct BoxLog {
    msg: BoxStatus,
}

impl Default for BoxLog {
    fn default() -> Self {
        let mut msg = BoxStatus::zeroed();
        msg.success_min = 1.0;
        BoxLog { msg }
    }
}

impl BoxLog {
    /// States between two messages (10 Hz at FCI's 1 kHz).
    pub const EVERY: u64 = 100;

    /// A state read from the box (with its own torques, `box_torques`): `controlled` while phri's torque control
    /// runs, with FCI's `control_command_success_rate` (in (0, 1\]; 0 says
    /// no control loop runs yet, as in the first states of a torque control,
    /// and a value outside is refused: neither is counted). True every [`BoxLog::EVERY`] states: time
    /// to publish. Allocates nothing.
    pub fn on_state(
        &mut self,
        controlled: bool,
        success_rate: f64,
        box_torques: &BoxTorques,
    ) -> bool {
        self.msg.states += 1;
        let n = box_torques.tau_j.len().min(MAX_DOF);
        self.msg.dof = n as u32;
        self.msg.tau_j[..n].copy_from_slice(&box_torques.tau_j[..n]);
        self.msg.tau_ext_hat[..n].copy_from_slice(&box_torques.tau_ext_hat[..n]);
        if controlled && success_rate > 0.0 && success_rate <= 1.0 {
            self.msg.controlled += 1;
            self.msg.success_sum += success_rate;
            self.msg.success_min = self.msg.success_min.min(success_rate);
        }
        self.msg.states.is_multiple_of(Self::EVERY)
    }

    /// The box aborted the motion at `now_ns` \[ns, CLOCK_MONOTONIC\].
    pub fn on_error(&mut self, now_ns: u64, error: &BoxError) {
        self.msg.errors += 1;
        self.msg.last_error_ns = now_ns;
        self.msg.last_error = phri_ipc::json::to_c_str(&error.names);
    }

    /// What was refused so far (cumulative counts).
    pub fn set_refused(&mut self, r: &Refused) {
        let m = &mut self.msg;
        m.refused_foreign = r.foreign;
        m.refused_malformed = r.malformed;
        m.refused_stale_id = r.stale_id;
        m.refused_id_ahead = r.id_ahead;
        m.refused_non_finite = r.non_finite;
        m.refused_too_fast = r.too_fast;
    }

    /// The adapter ran the box's automatic error recovery.
    pub fn on_recovery(&mut self) {
        self.msg.recoveries += 1;
    }

    /// Mean success rate while controlled (1 before any state).
    pub fn success_rate(&self) -> f64 {
        match self.msg.controlled {
            0 => 1.0,
            n => self.msg.success_sum / n as f64,
        }
    }

    /// The message, stamped `stamp_ns`.
    pub fn message(&mut self, stamp_ns: u64) -> &BoxStatus {
        self.msg.seq += 1;
        self.msg.stamp_ns = stamp_ns;
        &self.msg
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::BOX_ERROR_TEXT;

    #[test]
    fn the_rate_counts_only_controlled_states_and_errors_keep_their_names_and_time() {
        let mut log = BoxLog::default();
        assert_eq!(log.success_rate(), 1.0);
        let mut due = 0;
        let t = BoxTorques::default();
        for _ in 0..10 {
            due += usize::from(log.on_state(false, 0.0, &t)); // braked: no commands, on purpose
        }
        for k in 0..100 {
            due += usize::from(log.on_state(true, if k < 90 { 1.0 } else { 0.95 }, &t));
        }
        due += usize::from(log.on_state(true, f64::NAN, &t));
        let newest = BoxTorques {
            tau_j: [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0],
            tau_ext_hat: [0.5; JOINTS],
        };
        due += usize::from(log.on_state(true, 0.0, &newest)); // the box's loop not armed yet
        assert_eq!(due, 1, "one message per 100 states");
        assert!((log.success_rate() - 0.995).abs() < 1e-12);
        let e = BoxError::new(
            &[
                "communication_constraints_violation",
                "joint_velocity_violation",
            ],
            "Motion aborted by reflex!",
        );
        log.on_error(42_000, &e);
        log.on_recovery();
        let m = *log.message(50_000);
        assert_eq!((m.states, m.controlled), (112, 100));
        assert_eq!(m.success_min, 0.95);
        // the box's own torques of the newest state, for comparison
        assert_eq!(m.dof, 7);
        assert_eq!(m.tau_j[..7], newest.tau_j);
        assert_eq!(m.tau_ext_hat[..7], [0.5; 7]);
        assert_eq!((m.errors, m.recoveries, m.last_error_ns), (1, 1, 42_000));
        assert_eq!(
            m.last_error_str(),
            "communication_constraints_violation, joint_velocity_violation"
        );
        assert_eq!(
            BoxError::new(&[], "libfranka: Move command aborted\nmore").names,
            "libfranka: Move command aborted"
        );
    }

    #[test]
    fn a_long_error_is_cut_on_a_character() {
        let mut log = BoxLog::default();
        let long = "é".repeat(BOX_ERROR_TEXT);
        log.on_error(1, &BoxError::new(&[], &long));
        let m = *log.message(2);
        assert!(m.last_error_str().len() <= BOX_ERROR_TEXT);
        assert!(m.last_error_str().chars().all(|c| c == 'é'));
    }
}
