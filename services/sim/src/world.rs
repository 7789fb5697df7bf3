//! The hybrid cell's simulator: a robot outside (behind `phri-franka`)
//! publishes `robot/state`, and the simulator only follows it. Each period
//! [`WorldFollower::step`] puts the simulated arm where the newest state
//! says (velocity from consecutive states), moves the person and finds the
//! contacts ([`Simulator::follow`]): what the simulated camera renders and
//! the evaluation reads, with the arm the real one.

use phri_ipc::JointState;

use crate::sim::Simulator;

/// States further apart than this say nothing of the velocity \[ns\].
const MAX_GAP_NS: u64 = 50_000_000;

/// The arm's last state and velocity, preallocated.
#[derive(Clone, Debug)]
pub struct WorldFollower {
    /// the newest state's positions \[rad\], its seq and stamp \[ns, robot clock\]
    q: Vec<f64>,
    last: Option<(u64, u64)>,
    /// velocity between the two newest states [rad/s]
    qd: Vec<f64>,
    /// states refused for a joint count other than the model's
    refused: u64,
}

impl WorldFollower {
    /// For the arm of `q0.len()` joints, at `q0` \[rad\] until the first state.
    pub fn new(q0: &[f64]) -> WorldFollower {
        WorldFollower {
            q: q0.to_vec(),
            last: None,
            qd: vec![0.0; q0.len()],
            refused: 0,
        }
    }

    /// One period: `state`, the newest `robot/state` (None or the same as
    /// before: the arm stays, the person moves on).
    pub fn step(&mut self, sim: &mut Simulator, state: Option<&JointState>) {
        let n = self.q.len();
        if let Some(s) = state.filter(|s| self.last.is_none_or(|(seq, _)| s.seq != seq)) {
            let fits = s.dof as usize == n && s.q[..n.min(s.q.len())].iter().all(|x| x.is_finite());
            if !fits {
                self.refused += 1;
            } else {
                let gap = self.last.map(|(_, t)| s.stamp_ns.saturating_sub(t));
                for i in 0..n {
                    self.qd[i] = match gap {
                        Some(g) if g > 0 && g <= MAX_GAP_NS => {
                            (s.q[i] - self.q[i]) / (g as f64 * 1e-9)
                        }
                        _ => 0.0,
                    };
                    self.q[i] = s.q[i];
                }
                self.last = Some((s.seq, s.stamp_ns));
            }
        }
        sim.follow(&self.q, &self.qd);
    }

    /// States refused (a joint count other than the model's, a non-finite position).
    pub fn refused(&self) -> u64 {
        self.refused
    }

    /// The newest state's seq and stamp \[ns, robot clock\] (None: none yet).
    pub fn last(&self) -> Option<(u64, u64)> {
        self.last
    }
}
