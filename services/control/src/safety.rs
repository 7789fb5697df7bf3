//! The first question of every period: are the safety inputs fresh? The
//! residual (collision detection, paper Sect. III) and the perception
//! results (avoidance, Sect. V) are judged by their age in measurement time,
//! so that the judgement is deterministic.

use nalgebra::Vector3;
use phri_config::ControlConfig;

use crate::inputs::ControlInput;
use crate::snapshot::snapshot_fields;

/// The safety inputs of one period, judged.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Safety {
    /// a valid residual, no older than `residual_max_age_ms`
    pub residual_fresh: bool,
    /// the fresh residual reports a collision
    pub collision: bool,
    /// the fresh residual reports a contact
    pub contact: bool,
    /// perception results no older than `perception_max_age_ms` (true for a
    /// controller without perception)
    pub perception_fresh: bool,
    /// perception is stale with an obstacle last seen near, or stale for too long
    pub perception_stop: bool,
    /// speed scale of the task: 1, or `slow_scale` while perception is stale
    pub speed_scale: f64,
    /// risk at the end effector `‖V_Call(P_e)‖/V_max ∈ [0, 1]` (0 without fresh perception)
    pub ee_risk: f64,
    /// the end effector's repulsive vector `V_Call(P_e)` [m/s], base frame
    /// (0 without fresh perception; as received, so possibly not finite)
    pub ee_v_call: Vector3<f64>,
}

/// What the judgement remembers between periods, and reports.
#[derive(Clone, Debug)]
pub struct SafetyMonitor {
    /// age of the residual used in the last period \[ns\] (u64::MAX: none)
    pub residual_age_ns: u64,
    /// age of the perception results used in the last period \[ns\] (u64::MAX: none)
    pub perception_age_ns: u64,
    /// smallest obstacle distance of the control points last seen fresh \[m\]
    pub last_min_distance: f64,
    /// largest risk `‖V_Call‖/V_max` over the control points in the last period
    pub risk: f64,
}

snapshot_fields!(SafetyMonitor {
    residual_age_ns,
    perception_age_ns,
    last_min_distance,
    risk
});

impl Default for SafetyMonitor {
    fn default() -> Self {
        SafetyMonitor {
            residual_age_ns: u64::MAX,
            perception_age_ns: u64::MAX,
            last_min_distance: 0.0,
            risk: 0.0,
        }
    }
}

impl SafetyMonitor {
    /// Judge the residual and the perception results of `input` for an
    /// `n`-joint controller.
    pub fn assess(&mut self, input: &ControlInput<'_>, cfg: &ControlConfig, n: usize) -> Safety {
        let (residual_fresh, collision, contact) = match &input.residual {
            Some(r) if r.r.len() == n => {
                self.residual_age_ns = input.state_stamp_ns.saturating_sub(r.state_stamp_ns);
                let fresh =
                    r.valid && (self.residual_age_ns as f64) <= cfg.residual_max_age_ms * 1e6;
                (fresh, fresh && r.collision, fresh && r.contact)
            }
            _ => {
                self.residual_age_ns = u64::MAX;
                (false, false, false)
            }
        };

        // perception: fresh, stale (slow down), or stale with a person last seen near (stop)
        let (perception_fresh, perception_stop) = match &input.perception {
            None => {
                self.perception_age_ns = u64::MAX;
                (true, false)
            }
            Some(v) => {
                self.perception_age_ns = if v.capture_ns == 0 {
                    u64::MAX
                } else {
                    input.state_stamp_ns.saturating_sub(v.capture_ns)
                };
                let age_ms = self.perception_age_ns as f64 * 1e-6;
                let fresh = age_ms <= cfg.perception_max_age_ms;
                if fresh {
                    self.last_min_distance = v
                        .points
                        .iter()
                        .filter(|p| p.active != 0)
                        .map(|p| p.min_distance)
                        .fold(f64::INFINITY, f64::min);
                }
                // blind with a person last seen near: stop at once; blind for long: stop anyway
                let near = self.last_min_distance < cfg.near_distance_m;
                (
                    fresh,
                    !fresh && (near || age_ms > cfg.perception_stop_after_ms),
                )
            }
        };
        let v_max = cfg.avoidance_params.v_max_repulsion.max(1e-9);
        let perception = input.perception.filter(|_| perception_fresh);
        self.risk = perception.map_or(0.0, |v| {
            v.points
                .iter()
                .map(|p| Vector3::from(p.v_call).norm() / v_max)
                .fold(0.0, f64::max)
                .min(1.0)
        });
        let ee_v_call = perception
            .and_then(|v| v.points.first())
            .map_or_else(Vector3::zeros, |p| Vector3::from(p.v_call));
        // NaN.min(1) = 1: a non-finite repulsion is full risk
        let ee_risk = (ee_v_call.norm() / v_max).min(1.0);
        Safety {
            residual_fresh,
            collision,
            contact,
            perception_fresh,
            perception_stop,
            speed_scale: if perception_fresh {
                1.0
            } else {
                cfg.slow_scale.clamp(0.0, 1.0)
            },
            ee_risk,
            ee_v_call,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inputs::{PerceptionView, ResidualView};
    use phri_ipc::PointRepulsion;

    fn cfg() -> ControlConfig {
        phri_config::Config::defaults().control
    }

    fn input<'a>(
        stamp_ms: u64,
        residual: Option<ResidualView<'a>>,
        perception: Option<PerceptionView<'a>>,
    ) -> ControlInput<'a> {
        ControlInput {
            state_stamp_ns: stamp_ms * 1_000_000,
            q: &[],
            residual,
            perception,
            collab: Default::default(),
        }
    }

    #[test]
    fn residual_freshness_is_its_age_in_measurement_time() {
        let cfg = cfg();
        let r = [0.0; 7];
        let view = |stamp_ms: u64, valid, collision| ResidualView {
            state_stamp_ns: stamp_ms * 1_000_000,
            r: &r,
            valid,
            contact: collision,
            collision,
        };
        let mut m = SafetyMonitor::default();
        let s = m.assess(&input(100, Some(view(95, true, true)), None), &cfg, 7);
        assert!(s.residual_fresh && s.collision && s.contact);
        assert_eq!(m.residual_age_ns, 5_000_000);
        // one ms older than residual_max_age_ms (5): stale, and its flags do not count
        let s = m.assess(&input(100, Some(view(94, true, true)), None), &cfg, 7);
        assert!(!s.residual_fresh && !s.collision && !s.contact);
        let s = m.assess(&input(100, Some(view(100, false, false)), None), &cfg, 7);
        assert!(!s.residual_fresh, "not past its warm-up");
        let s = m.assess(&input(100, Some(view(100, true, false)), None), &cfg, 6);
        assert!(!s.residual_fresh, "another robot's residual");
        assert_eq!(m.residual_age_ns, u64::MAX);
        // without perception, perception never stops the arm
        assert!(s.perception_fresh && !s.perception_stop && s.speed_scale == 1.0);
    }

    #[test]
    fn stale_perception_slows_or_stops() {
        let cfg = cfg();
        let near = [PointRepulsion {
            active: 1,
            min_distance: 0.2,
            v_call: [0.0, 0.15, 0.0],
            ..Default::default()
        }];
        let far = [PointRepulsion {
            active: 1,
            min_distance: 0.9,
            ..Default::default()
        }];
        let view = |capture_ms: u64, points| PerceptionView {
            capture_ns: capture_ms * 1_000_000,
            points,
            sources: &[],
        };
        let mut m = SafetyMonitor::default();
        let s = m.assess(&input(1000, None, Some(view(950, &near))), &cfg, 7);
        assert!(s.perception_fresh && !s.perception_stop);
        assert!((s.ee_risk - 0.5).abs() < 1e-12 && (m.risk - 0.5).abs() < 1e-12);
        // stale, a person last seen near: stop at once
        let s = m.assess(&input(1200, None, Some(view(950, &near))), &cfg, 7);
        assert!(!s.perception_fresh && s.perception_stop);
        assert_eq!((s.ee_risk, m.risk), (0.0, 0.0));
        // fresh and far, then stale: slow down
        m.assess(&input(1300, None, Some(view(1250, &far))), &cfg, 7);
        let s = m.assess(&input(1500, None, Some(view(1250, &far))), &cfg, 7);
        assert!(!s.perception_fresh && !s.perception_stop);
        assert_eq!(s.speed_scale, cfg.slow_scale);
        // stale past perception_stop_after_ms: stop whatever was seen
        let s = m.assess(&input(3300, None, Some(view(1250, &far))), &cfg, 7);
        assert!(s.perception_stop);
        // no worker answered yet
        let s = m.assess(&input(10, None, Some(view(0, &far))), &cfg, 7);
        assert!(!s.perception_fresh);
        assert_eq!(m.perception_age_ns, u64::MAX);
    }
}
