//! One repulsion worker's results from several cameras, fused point by
//! point ([`phri_depth::fusion`]): each camera's distance is bounded by the
//! space it does not watch, the largest bound wins and brings its camera's
//! repulsive vector, at that distance's magnitude. The result keeps the
//! layout of one camera's ([`RepulsionResult`]), so the controller reads it
//! as it reads one camera's. Allocates nothing.

use nalgebra::{Point3, Vector3};
use phri_config::{CameraConfig, Invalid, RepulsionConfig};
use phri_depth::{fuse, CameraView, PointOfInterest, Repulsion, RepulsionParams};
use phri_ipc::{PointRepulsion, RepulsionResult};

/// The cameras' views and the control points' radii.
#[derive(Debug, Clone)]
pub struct ResultFusion {
    views: Vec<CameraView>,
    /// link radius of each control point [m]
    radii: Vec<f64>,
    params: RepulsionParams,
}

impl ResultFusion {
    /// For `cameras` (their order is the order of the results to fuse) and
    /// the control points of `repulsion`.
    pub fn new(cameras: &[CameraConfig], repulsion: &RepulsionConfig) -> Result<Self, Invalid> {
        let views = cameras
            .iter()
            .enumerate()
            .map(|(i, c)| {
                CameraView::new(
                    &c.intrinsics,
                    c.pose()?,
                    c.render.min_range_m,
                    c.render.max_range_m,
                )
                .map_err(|e| Invalid::new(format!("camera[{i}]"), e.to_string()))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            views,
            radii: repulsion.points.iter().map(|p| p.radius).collect(),
            params: repulsion.params,
        })
    }

    /// Cameras fused.
    pub fn cameras(&self) -> usize {
        self.views.len()
    }

    /// Fuses `results` (one worker's, camera by camera in the order of
    /// [`ResultFusion::new`]; `None` for a camera left out, e.g. stale)
    /// into `out`, which takes the first present result's header. A point
    /// a camera did not answer (another worker layout) leaves that camera
    /// out for it. False when no camera is present (`out` untouched).
    pub fn fuse(&self, results: &[Option<&RepulsionResult>], out: &mut RepulsionResult) -> bool {
        let Some(head) = results.iter().flatten().next() else {
            return false;
        };
        *out = **head;
        let n = (head.n_points as usize).min(head.points.len());
        for (j, slot) in out.points[..n].iter_mut().enumerate() {
            let index = slot.point;
            let Some(&radius) = self.radii.get(index as usize) else {
                continue;
            };
            let answers = results.iter().zip(&self.views).filter_map(|(r, view)| {
                let p = (*r)?.points.get(j).filter(|p| p.point == index)?;
                let point = PointOfInterest::new(Point3::from(p.position), radius);
                let seen = repulsion_of(p, radius);
                Some((view.bound(&point, &seen, self.params.rho), seen, p))
            });
            // the camera whose bound is largest
            let mut best: Option<(f64, Repulsion, &PointRepulsion)> = None;
            for a in answers {
                if best.as_ref().is_none_or(|b| a.0 > b.0) {
                    best = Some(a);
                }
            }
            let Some((bound, seen, p)) = best else {
                continue;
            };
            let fused = fuse([(bound, &seen)], &self.params).repulsion;
            *slot = *p;
            slot.min_distance = fused.min_distance;
            slot.v_call = fused.v_call.into();
        }
        true
    }
}

/// A worker's answer for one point as a [`Repulsion`] (its distance is ρ
/// when nothing was near; nothing was then seen).
fn repulsion_of(p: &PointRepulsion, radius: f64) -> Repulsion {
    match p.active != 0 {
        true => Repulsion {
            v_call: Vector3::from(p.v_call),
            min_distance: p.min_distance,
            center_distance: p.min_distance + radius,
            obstacle_point: Some(Point3::from(p.obstacle)),
            pixels_considered: 1,
        },
        false => Repulsion::NONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn fusion(azimuths: &[f64]) -> (ResultFusion, RepulsionConfig) {
        let cfg = phri_config::Config::defaults();
        let cameras: Vec<CameraConfig> = azimuths
            .iter()
            .map(|&a| {
                let mut c = cfg.camera.clone();
                c.azimuth_rad = a;
                c
            })
            .collect();
        (
            ResultFusion::new(&cameras, &cfg.repulsion).unwrap(),
            cfg.repulsion,
        )
    }

    /// One worker's result with point 0 at `position`, seen at `distance`
    /// (None: nothing near).
    fn result(position: [f64; 3], distance: Option<f64>, v: [f64; 3], rho: f64) -> RepulsionResult {
        let mut r = RepulsionResult::zeroed();
        r.n_points = 1;
        r.points[0].point = 0;
        r.points[0].position = position;
        match distance {
            Some(d) => {
                r.points[0].active = 1;
                r.points[0].min_distance = d;
                r.points[0].v_call = v;
            }
            None => r.points[0].min_distance = rho,
        }
        r
    }

    #[test]
    fn the_camera_that_sees_the_point_clear_gives_its_distance_and_direction() {
        let (f, cfg) = fusion(&[0.6, -0.6]);
        let rho = cfg.params.rho;
        // a point both cameras watch: the first sees the person 2 cm away
        // (in its shadow), the second 25 cm away
        let at = [0.4, 0.0, 0.5];
        let a = result(at, Some(0.02), [0.0, 0.2, 0.0], rho);
        let b = result(at, Some(0.25), [-0.05, 0.0, 0.0], rho);
        let mut out = RepulsionResult::zeroed();
        assert!(f.fuse(&[Some(&a), Some(&b)], &mut out));
        let p = out.points[0];
        assert!((p.min_distance - 0.25).abs() < 1e-12, "{}", p.min_distance);
        let v = Vector3::from(p.v_call);
        assert!((v.norm() - cfg.params.magnitude(0.25)).abs() < 1e-12);
        assert!(v.x < 0.0 && v.y.abs() < 1e-12);
        // the second camera left out (stale): the first's answer
        assert!(f.fuse(&[Some(&a), None], &mut out));
        assert!((out.points[0].min_distance - 0.02).abs() < 1e-12);
        // none: nothing to fuse
        assert!(!f.fuse(&[None, None], &mut out));
    }

    #[test]
    fn a_camera_that_does_not_watch_the_point_bounds_it_at_its_view() {
        let (f, cfg) = fusion(&[0.6]);
        let rho = cfg.params.rho;
        // behind the camera (2 m out at azimuth 0.6, looking at the robot):
        // nothing seen there says nothing
        let behind = [3.0 * 0.6f64.cos(), 3.0 * 0.6f64.sin(), 1.2];
        let free = result(behind, None, [0.0; 3], rho);
        let mut out = RepulsionResult::zeroed();
        assert!(f.fuse(&[Some(&free)], &mut out));
        assert_eq!(out.points[0].min_distance, 0.0);
        // at the robot, well inside the view: nothing near means ρ
        let inside = result([0.3, 0.0, 0.4], None, [0.0; 3], rho);
        assert!(f.fuse(&[Some(&inside)], &mut out));
        assert_eq!(out.points[0].min_distance, rho);
        assert_eq!(out.points[0].v_call, [0.0; 3]);
    }
}
