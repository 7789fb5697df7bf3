//! Speed and separation monitoring (ISO/TS 15066 clause 5.5.4) from depth
//! space: for every control point and its closest obstacle point, the
//! largest speed toward it that keeps the clearance `d` at least the
//! protective separation distance
//! `S_p = v_h (T_r + T_s) + v_r T_r + S_s + C + Z_d + Z_r` (`S_s = k v_r`):
//! `v_r ≤ (d − v_h (T_r + T_s) − C − Z_d − Z_r) / (T_r + k)`. The avoidance
//! stage bounds each point's approach by it, as eq. 20 bounds it by the risk
//! ([`crate::avoidance::Avoidance::limit_approach`]).
//!
//! The person's speed `v_h` toward a point is ISO 13855's, or measured:
//! frame to frame, how much faster the point's clearance closes than the
//! point itself moves toward its obstacle; a rise counts at once, a fall
//! at most `human_speed_decay`.

use nalgebra::Vector3;
use phri_config::{HumanSpeed, SsmConfig};
use phri_iso15066::{protective_separation_distance, SsmTerms};

use crate::inputs::PerceptionView;
use crate::snapshot::snapshot_fields;

/// A measured approach above this is no person's [m/s] (depth's outliers).
const HUMAN_SPEED_MAX: f64 = 3.0;

/// Frames further apart than this give no speed [s].
const MAX_FRAME_GAP_S: f64 = 0.2;

/// One control point's last sighting.
#[derive(Clone, Copy, Debug, Default)]
struct Sample {
    capture_ns: u64,
    /// clearance [m]
    d: f64,
    /// the control point [m], base frame
    position: Vector3<f64>,
}

/// The monitor's state: per control point, the person's speed toward it.
#[derive(Clone, Debug)]
pub struct SsmMonitor {
    cfg: SsmConfig,
    /// per control point, its last sighting by each camera (point-major:
    /// `k × cameras + camera`), so that a rate is measured between two
    /// frames of one camera
    last: Vec<Option<Sample>>,
    /// cameras whose sightings are kept apart (1 or more)
    cameras: usize,
    /// per control point, the person's measured speed toward it [m/s]
    v_h: Vec<f64>,
    /// per control point, how long it has been approaching its obstacle
    /// inside the protective separation distance [s]
    inside_s: Vec<f64>,
    /// ... inside the standard's protective separation distance
    /// ([`SsmMonitor::separation_standard`]) [s]
    inside_standard_s: Vec<f64>,
    /// capture time of the last frame observed [ns]
    frame_ns: u64,
}

snapshot_fields!(Sample {
    capture_ns,
    d,
    position
});

// per control point (lengths fixed by the configuration), and the last frame
snapshot_fields!(SsmMonitor {
    last,
    v_h,
    inside_s,
    inside_standard_s,
    frame_ns
});

impl SsmMonitor {
    /// For `points` control points seen by one camera.
    pub fn new(cfg: &SsmConfig, points: usize) -> SsmMonitor {
        SsmMonitor::with_cameras(cfg, points, 1)
    }

    /// For `points` control points seen by `cameras` cameras.
    pub fn with_cameras(cfg: &SsmConfig, points: usize, cameras: usize) -> SsmMonitor {
        let cameras = cameras.max(1);
        SsmMonitor {
            cfg: cfg.clone(),
            last: vec![None; points * cameras],
            cameras,
            v_h: vec![0.0; points],
            inside_s: vec![0.0; points],
            inside_standard_s: vec![0.0; points],
            frame_ns: 0,
        }
    }

    /// Cameras whose sightings it keeps apart.
    pub fn cameras(&self) -> usize {
        self.cameras
    }

    /// Its configuration.
    pub fn config(&self) -> &SsmConfig {
        &self.cfg
    }

    /// The standard's terms that do not depend on the speeds, perception
    /// acted on `t_r` \[s\] after its capture.
    fn terms(&self, t_r: f64) -> SsmTerms {
        SsmTerms {
            t_r,
            t_s: self.cfg.stop_time_s,
            c: self.cfg.intrusion_m,
            z_d: self.cfg.sensor_uncertainty_m,
            z_r: self.cfg.robot_uncertainty_m,
        }
    }

    /// A frame's results (nothing when `view`'s capture time did not move
    /// on): the person's speed toward each point that sees an obstacle.
    /// Allocates nothing.
    pub fn observe(&mut self, view: &PerceptionView<'_>) {
        let t = view.capture_ns;
        if t == 0 || t <= self.frame_ns {
            return;
        }
        let since = (t - self.frame_ns) as f64 * 1e-9;
        self.frame_ns = t;
        let fall = self.cfg.human_speed_decay * since.min(1.0);
        for (k, p) in view.points.iter().enumerate() {
            let Some(v_h) = self.v_h.get_mut(k) else {
                break;
            };
            *v_h = (*v_h - fall).max(0.0);
            // with several cameras, the point's own camera and capture: a
            // rate between two cameras' views is their disagreement, not
            // the person's motion (up to the 3 m/s cap from a few mm apart
            // in time)
            let (camera, t_k) = match view.sources.get(k) {
                Some(s) => (s.camera, s.capture_ns),
                None => (0, t),
            };
            if camera >= self.cameras {
                continue;
            }
            let Some(last) = self.last.get_mut(k * self.cameras + camera) else {
                break;
            };
            let position = Vector3::from(p.position);
            let obstacle = Vector3::from(p.obstacle);
            let usable = p.active != 0
                && p.min_distance.is_finite()
                && position
                    .iter()
                    .chain(obstacle.iter())
                    .all(|x| x.is_finite());
            if !usable {
                *last = None;
                continue;
            }
            if let Some(s) = *last {
                if t_k <= s.capture_ns {
                    // this camera's sighting of the point is not newer
                    continue;
                }
                let dt = (t_k - s.capture_ns) as f64 * 1e-9;
                let away = position - obstacle;
                if dt <= MAX_FRAME_GAP_S && away.norm() > 1e-6 {
                    let closing = (s.d - p.min_distance) / dt;
                    let own = -(position - s.position).dot(&away.normalize()) / dt;
                    let measured = (closing - own).clamp(0.0, HUMAN_SPEED_MAX);
                    *v_h = v_h.max(measured);
                }
            }
            *last = Some(Sample {
                capture_ns: t_k,
                d: p.min_distance,
                position,
            });
        }
    }

    /// Point `k` is (`inside`) or is not approaching its obstacle inside
    /// its protective separation distance for another `dt` \[s\]: for how
    /// long it has been \[s\].
    pub fn approaching_inside(&mut self, k: usize, inside: bool, dt: f64) -> f64 {
        let Some(b) = self.inside_s.get_mut(k) else {
            return 0.0;
        };
        *b = match inside {
            true => *b + dt,
            false => 0.0,
        };
        *b
    }

    /// As [`SsmMonitor::approaching_inside`], inside the standard's protective
    /// separation distance ([`SsmMonitor::separation_standard`]).
    pub fn approaching_inside_standard(&mut self, k: usize, inside: bool, dt: f64) -> f64 {
        let Some(b) = self.inside_standard_s.get_mut(k) else {
            return 0.0;
        };
        *b = match inside {
            true => *b + dt,
            false => 0.0,
        };
        *b
    }

    /// The person's measured approach toward control point `k` \[m/s\]
    /// (none when `[ssm] human_speed` is ISO 13855's, which measures nothing).
    pub fn measured_speed(&self, k: usize) -> Option<f64> {
        match self.cfg.human_speed {
            HumanSpeed::Measured => self.v_h.get(k).copied(),
            HumanSpeed::Iso13855 => None,
        }
    }

    /// The person's speed toward point `k` at clearance `d` \[m\] \[m/s\].
    pub fn human_speed(&self, k: usize, d: f64) -> f64 {
        match self.cfg.human_speed {
            HumanSpeed::Measured => self.v_h.get(k).copied().unwrap_or(HUMAN_SPEED_MAX),
            HumanSpeed::Iso13855 => phri_iso15066::human_speed(d),
        }
    }

    /// The largest speed \[m/s\] at which point `k`, `d` \[m\] clear of its
    /// obstacle, may move toward it, with perception `t_r` \[s\] old: 0 where
    /// even a standing robot is too near (or `d` is no number).
    pub fn allowed_speed(&self, k: usize, d: f64, t_r: f64) -> f64 {
        let terms = self.terms(t_r);
        let v_h = self.human_speed(k, d);
        // S_p at v_r = 0
        let standing = protective_separation_distance(v_h, 0.0, 0.0, &terms);
        let per_speed = t_r + self.cfg.stop_distance_per_speed_s;
        let v = (d - standing) / per_speed.max(1e-6);
        if v.is_nan() {
            0.0
        } else {
            v.max(0.0)
        }
    }

    /// The protective separation distance \[m\] of point `k` at clearance
    /// `d`, moving toward its obstacle at `v_r` \[m/s\], perception `t_r` \[s\] old.
    pub fn separation(&self, k: usize, d: f64, v_r: f64, t_r: f64) -> f64 {
        let s_s = self.cfg.stop_distance_per_speed_s * v_r.max(0.0);
        protective_separation_distance(self.human_speed(k, d), v_r, s_s, &self.terms(t_r))
    }
}

impl SsmMonitor {
    /// The standard's own protective separation distance \[m\] at clearance
    /// `d`, the point moving toward its obstacle at `v_r` \[m/s\],
    /// perception `t_r` \[s\] old: ISO 13855's human speed (2.0 m/s within
    /// 0.5 m, 1.6 m/s beyond) whatever `human_speed` configures, the other
    /// terms as configured.
    pub fn separation_standard(&self, d: f64, v_r: f64, t_r: f64) -> f64 {
        let s_s = self.cfg.stop_distance_per_speed_s * v_r.max(0.0);
        let v_h = phri_iso15066::human_speed(d);
        protective_separation_distance(v_h, v_r, s_s, &self.terms(t_r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::PointRepulsion;

    fn cfg(human_speed: HumanSpeed) -> SsmConfig {
        SsmConfig {
            enabled: true,
            human_speed,
            stop_time_s: 0.05,
            stop_distance_per_speed_s: 0.02,
            intrusion_m: 0.0,
            sensor_uncertainty_m: 0.02,
            robot_uncertainty_m: 0.005,
            human_speed_decay: 2.0,
        }
    }

    /// A point at `x` on the x axis, `d` clear of an obstacle ahead of it (+x).
    fn point(d: f64, x: f64) -> PointRepulsion {
        PointRepulsion {
            active: 1,
            min_distance: d,
            position: [x, 0.0, 0.0],
            obstacle: [x + d, 0.0, 0.0],
            ..Default::default()
        }
    }

    #[test]
    fn the_allowed_speed_keeps_the_protective_separation() {
        let m = SsmMonitor::new(&cfg(HumanSpeed::Iso13855), 1);
        // 0.4 m clear, perception 40 ms old, reaching speed 2 m/s:
        // S_p(0) = 2·0.09 + 0.025 = 0.205 m; v ≤ (0.4 − 0.205)/(0.04 + 0.02) = 3.25 m/s
        let v = m.allowed_speed(0, 0.4, 0.04);
        assert!((v - 3.25).abs() < 1e-9, "{v}");
        // moving at that speed the clearance is exactly S_p
        assert!((m.separation(0, 0.4, v, 0.04) - 0.4).abs() < 1e-9);
        // at 0.2 m (inside S_p of a standing robot) nothing toward the person
        assert_eq!(m.allowed_speed(0, 0.2, 0.04), 0.0);
        assert_eq!(m.allowed_speed(0, f64::NAN, 0.04), 0.0);
    }

    /// With a person measured standing, the configured S_p is the
    /// standard's less v_h (T_r + T_s): 2.0 m/s within 0.5 m, 1.6 beyond.
    #[test]
    fn the_standard_s_separation_takes_iso_13855_s_speed_whatever_is_configured() {
        let m = SsmMonitor::new(&cfg(HumanSpeed::Measured), 1);
        // T_r 40 ms, T_s 50 ms, Z 0.025 m, v_r 0.5 m/s (S_s 0.01 m)
        let configured = m.separation(0, 0.3, 0.5, 0.04);
        assert!((configured - (0.5 * 0.04 + 0.01 + 0.025)).abs() < 1e-12);
        let standard = m.separation_standard(0.3, 0.5, 0.04);
        assert!(
            (standard - (configured + 2.0 * 0.09)).abs() < 1e-12,
            "{standard}"
        );
        let far = m.separation_standard(0.8, 0.5, 0.04);
        assert!((far - (configured + 1.6 * 0.09)).abs() < 1e-12, "{far}");
        let mut m = m;
        assert_eq!(m.approaching_inside_standard(0, true, 0.001), 0.001);
        assert_eq!(m.approaching_inside_standard(0, false, 0.001), 0.0);
        assert_eq!(m.approaching_inside_standard(3, true, 0.001), 0.0);
    }

    /// Two cameras phase-shifted by 16 ms see a person standing still at
    /// different clearances (each a bound from its own view), and the
    /// fused point alternates between them: no speed. The same person
    /// walking in at 1 m/s, seen by both: 1 m/s.
    #[test]
    fn the_speed_is_measured_over_one_camera_s_frames() {
        use crate::inputs::PointSource;
        let mut m = SsmMonitor::with_cameras(&cfg(HumanSpeed::Measured), 1, 2);
        let at = |camera: usize, ms: u64| PointSource {
            camera,
            capture_ns: ms * 1_000_000,
        };
        // (camera, capture [ms], clearance [m]) in the order fused
        let still = [
            (0, 1000, 0.30),
            (1, 1016, 0.20),
            (0, 1033, 0.30),
            (1, 1050, 0.20),
        ];
        for (camera, ms, d) in still {
            let (pts, src) = ([point(d, 0.5)], [at(camera, ms)]);
            m.observe(&PerceptionView {
                capture_ns: ms * 1_000_000,
                points: &pts,
                sources: &src,
            });
        }
        assert_eq!(m.human_speed(0, 0.2), 0.0, "a disagreement is no motion");
        // taken as one stream, 10 cm in 16 ms would be the 3 m/s cap
        let mut one = SsmMonitor::new(&cfg(HumanSpeed::Measured), 1);
        for (_, ms, d) in still {
            let pts = [point(d, 0.5)];
            one.observe(&PerceptionView {
                capture_ns: ms * 1_000_000,
                points: &pts,
                sources: &[],
            });
        }
        assert_eq!(one.human_speed(0, 0.2), HUMAN_SPEED_MAX);
        // walking in: each camera's clearance shrinks 1 m/s × its frame gap
        let mut m = SsmMonitor::with_cameras(&cfg(HumanSpeed::Measured), 1, 2);
        for (camera, ms, d0) in [
            (0, 2000, 0.60),
            (1, 2016, 0.50),
            (0, 2033, 0.60),
            (1, 2050, 0.50),
        ] {
            let d = d0 - (ms - 2000) as f64 * 1e-3 * 1.0;
            let (pts, src) = ([point(d, 0.5)], [at(camera, ms)]);
            m.observe(&PerceptionView {
                capture_ns: ms * 1_000_000,
                points: &pts,
                sources: &src,
            });
        }
        let v = m.human_speed(0, 0.45);
        assert!((v - 1.0).abs() < 0.05, "{v}");
    }

    #[test]
    fn a_person_walking_in_is_measured_and_forgotten_slowly() {
        let mut m = SsmMonitor::new(&cfg(HumanSpeed::Measured), 1);
        let mut pts = [point(0.40, 0.5)];
        fn view(points: &[PointRepulsion], t_ms: u64) -> PerceptionView<'_> {
            PerceptionView {
                capture_ns: t_ms * 1_000_000,
                points,
                sources: &[],
            }
        }
        m.observe(&view(&pts, 1000));
        assert_eq!(m.human_speed(0, 0.4), 0.0);
        // 50 ms later 8 cm nearer, the point still: 1.6 m/s toward it
        pts[0] = point(0.32, 0.5);
        m.observe(&view(&pts, 1050));
        assert!((m.human_speed(0, 0.32) - 1.6).abs() < 1e-9);
        // the same frame again changes nothing
        m.observe(&view(&pts, 1050));
        assert!((m.human_speed(0, 0.32) - 1.6).abs() < 1e-9);
        // the point itself moved 2 cm toward the obstacle while the clearance
        // closed 2 cm: the person stood still; the 1.6 m/s falls by 2 m/s² × 50 ms
        pts[0] = point(0.30, 0.52);
        m.observe(&view(&pts, 1100));
        assert!((m.human_speed(0, 0.30) - 1.5).abs() < 1e-9);
        // approaching inside S_p: timed while it lasts, from 0 again after
        assert_eq!(m.approaching_inside(0, true, 0.001), 0.001);
        assert!((m.approaching_inside(0, true, 0.001) - 0.002).abs() < 1e-12);
        assert_eq!(m.approaching_inside(0, false, 0.001), 0.0);
        assert_eq!(m.approaching_inside(0, true, 0.001), 0.001);
        assert_eq!(m.approaching_inside(7, true, 0.001), 0.0, "no such point");
        // ISO 13855's speed instead: 2.0 m/s within 0.5 m
        let iso = SsmMonitor::new(&cfg(HumanSpeed::Iso13855), 1);
        assert_eq!(iso.human_speed(0, 0.3), 2.0);
    }
}
