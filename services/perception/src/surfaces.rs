//! The surfaces every camera saw near a worker's control points, shared by
//! the worker's answers for each camera (one process serves them all).
//!
//! Depth space counts what a camera cannot see as occupied, except the
//! space the robot hides from it: the self-filter removes the robot's
//! pixels, so a person behind the arm reads as free to that camera, and
//! the controller's fusion (the largest bound over the cameras) would take
//! that camera's word. What any camera saw is really there, so the nearest
//! surface over all the cameras bounds the true clearance from above: each
//! answer is capped by it ([`phri_depth::capped_by_surface`]), and
//! the controller's largest capped bound is the nearest observed surface
//! over all cameras against the largest shadow bound.

use phri_depth::SeenSurface;
use phri_ipc::MAX_POINTS_PER_WORKER;

/// Per camera: the capture time of its last answered frame and, per point
/// the worker owns (in its order), the nearest surface that frame showed
/// (`None`: none near).
#[derive(Debug, Clone)]
pub struct SeenSurfaces {
    cameras: Vec<(u64, [Option<SeenSurface>; MAX_POINTS_PER_WORKER])>,
    /// how far apart two cameras' frames may be captured for one's surfaces
    /// to cap the other's answer \[ns\]
    max_apart_ns: u64,
}

impl SeenSurfaces {
    /// For `cameras` cameras; a camera's surfaces count for another's frame
    /// captured at most `max_apart_ns` before or after its own.
    pub fn new(cameras: usize, max_apart_ns: u64) -> SeenSurfaces {
        SeenSurfaces {
            cameras: vec![(0, [None; MAX_POINTS_PER_WORKER]); cameras],
            max_apart_ns,
        }
    }

    /// For the cameras of `config`: frames captured within 1.5 frame
    /// periods of the slowest camera of each other share their surfaces
    /// (cameras that run free are at most one period apart; a hand at
    /// 1.6 m/s moves 8 cm in 50 ms), and never more than `[control]
    /// perception_max_age_ms` (older perception is stale anyway).
    pub fn for_cell(config: &phri_config::Config) -> SeenSurfaces {
        let period_s = config
            .cameras
            .iter()
            .map(|c| 1.0 / c.rate_hz)
            .fold(0.0, f64::max);
        let stale_s = config.control.perception_max_age_ms * 1e-3;
        let apart_s = (1.5 * period_s).min(stale_s).max(0.0);
        SeenSurfaces::new(config.cameras.len(), (apart_s * 1e9) as u64)
    }

    /// Records the nearest surface camera `camera` saw from the worker's
    /// point `slot` in its frame captured at `capture_ns` \[ns, robot
    /// clock\] (`None`: none near; a NaN clearance counts as touching).
    /// Out-of-range cameras or slots are ignored.
    pub fn record(
        &mut self,
        camera: usize,
        capture_ns: u64,
        slot: usize,
        surface: Option<SeenSurface>,
    ) {
        if let Some((t, s)) = self.cameras.get_mut(camera) {
            if let Some(c) = s.get_mut(slot) {
                *t = capture_ns;
                *c = surface.map(|mut s| {
                    if s.clearance.is_nan() {
                        s.clearance = 0.0;
                    }
                    s
                });
            }
        }
    }

    /// The nearest surface any camera saw from point `slot`, over the
    /// cameras whose last frame was captured within the bound of
    /// `capture_ns`; `None` when none saw one.
    pub fn nearest(&self, slot: usize, capture_ns: u64) -> Option<SeenSurface> {
        self.cameras
            .iter()
            .filter(|(t, _)| *t > 0 && t.abs_diff(capture_ns) <= self.max_apart_ns)
            .filter_map(|(_, s)| s.get(slot).copied().flatten())
            .fold(None, |best: Option<SeenSurface>, s| match best {
                Some(b) if b.clearance <= s.clearance => Some(b),
                _ => Some(s),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn at(clearance: f64) -> Option<SeenSurface> {
        Some(SeenSurface {
            clearance,
            point: Point3::new(clearance, 0.0, 0.0),
        })
    }

    fn nearest(s: &SeenSurfaces, slot: usize, t: u64) -> Option<f64> {
        s.nearest(slot, t).map(|s| s.clearance)
    }

    #[test]
    fn the_nearest_fresh_surface_of_any_camera() {
        let mut s = SeenSurfaces::new(2, 100);
        assert_eq!(nearest(&s, 0, 1000), None);
        s.record(0, 1000, 0, at(0.3));
        s.record(1, 950, 0, at(0.1));
        s.record(1, 950, 1, at(0.5));
        assert_eq!(nearest(&s, 0, 1000), Some(0.1));
        assert_eq!(s.nearest(0, 1000).unwrap().point.x, 0.1);
        assert_eq!(nearest(&s, 1, 1000), Some(0.5));
        // camera 1's frame too far apart: camera 0's own only
        assert_eq!(nearest(&s, 0, 1051), Some(0.3));
        // nothing recorded for slot 2
        assert_eq!(nearest(&s, 2, 1000), None);
        // NaN counts as touching; out of range is ignored
        s.record(0, 1000, 2, at(f64::NAN));
        s.record(5, 1000, 0, at(0.0));
        s.record(0, 1000, MAX_POINTS_PER_WORKER, at(0.0));
        assert_eq!(nearest(&s, 2, 1000), Some(0.0));
        assert_eq!(nearest(&s, 0, 1000), Some(0.1));
        // a camera that saw nothing near no longer caps
        s.record(1, 1000, 0, None);
        assert_eq!(nearest(&s, 0, 1000), Some(0.3));
    }
}
