//! Distances fused across several depth cameras.
//!
//! Each camera's depth-space distance ([`crate::DepthSpaceDistance`]) takes
//! whatever it cannot see behind an obstacle as occupied (eq. 15's rule), so
//! it is a lower bound of the true distance, but only over the space the
//! camera watches. What lies outside its view (beside the image, nearer
//! than its nearest or farther than its farthest reading) it reports as
//! free: a camera that cannot see the hand would call it far away. Here
//! that space counts as occupied too: a camera's bound is the smaller of its
//! depth-space distance (which looks no farther than ρ) and the point's
//! clearance from the boundary of the camera's view
//! ([`CameraView::clearance`]). Every such bound is a lower
//! bound of the truth, so the largest of them is one as well, and the
//! tightest the cameras give: the fused distance ([`fuse`]). Its repulsion
//! is the repulsive vector of the camera that gives it, at the magnitude of
//! the fused distance (eq. 16).
//!
//! One space escapes that rule: what the robot hides from a camera. Its
//! pixels are removed before the scan, so a person behind the arm reads as
//! free to that camera, whose bound can then exceed the truth. What any
//! camera saw is really there, so the nearest surface seen over all the
//! cameras ([`Repulsion::surface_distance`]) bounds the truth from above:
//! each camera's bound is capped by it ([`capped_by_surface`]) before the
//! largest is taken, which makes the fused distance the nearest observed
//! surface over all cameras against the largest shadow bound.
//!
//! Frames: base frame of the robot, metres. Nothing here allocates.

use nalgebra::{Point3, Vector3};

use crate::camera::{CameraPose, Intrinsics};
use crate::distance::{PointOfInterest, Repulsion, RepulsionParams};
use crate::error::DepthError;

/// The space one camera watches: the pyramid of its image between its
/// nearest and farthest readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraView {
    pose: CameraPose,
    /// nearest depth a pixel reads \[m\]
    near: f64,
    /// farthest depth a pixel reads \[m\]
    far: f64,
    /// unit inward normals of the four side planes (through the optical
    /// centre), camera frame: left, right, top, bottom
    sides: [Vector3<f64>; 4],
}

impl CameraView {
    /// The view of a camera with `intrinsics` at `pose` whose pixels read
    /// depths in `[min_range_m, max_range_m]` (beyond: no reading). The
    /// image's edges are its outer pixel borders (u = −½ and width − ½).
    pub fn new(
        intrinsics: &Intrinsics,
        pose: CameraPose,
        min_range_m: f64,
        max_range_m: f64,
    ) -> Result<Self, DepthError> {
        intrinsics.validate()?;
        if !(min_range_m.is_finite() && max_range_m.is_finite())
            || min_range_m < 0.0
            || max_range_m <= min_range_m
        {
            return Err(DepthError::Parameter {
                what: "camera view",
                reason: format!(
                    "range {min_range_m}..{max_range_m} m: need 0 <= min < max, both finite"
                ),
            });
        }
        let k = intrinsics;
        // x/z at the left and right image borders, y/z at the top and bottom
        let left = (-0.5 - k.cx) / k.fx;
        let right = (f64::from(k.width) - 0.5 - k.cx) / k.fx;
        let top = (-0.5 - k.cy) / k.fy;
        let bottom = (f64::from(k.height) - 0.5 - k.cy) / k.fy;
        // inside: x ≥ left z, x ≤ right z, y ≥ top z, y ≤ bottom z
        let sides = [
            Vector3::new(1.0, 0.0, -left).normalize(),
            Vector3::new(-1.0, 0.0, right).normalize(),
            Vector3::new(0.0, 1.0, -top).normalize(),
            Vector3::new(0.0, -1.0, bottom).normalize(),
        ];
        Ok(Self {
            pose,
            near: min_range_m,
            far: max_range_m,
            sides,
        })
    }

    /// The camera's pose.
    pub fn pose(&self) -> &CameraPose {
        &self.pose
    }

    /// Moves the camera.
    pub fn set_pose(&mut self, pose: CameraPose) {
        self.pose = pose;
    }

    /// How far `p` (base frame \[m\]) is from the space the camera does not
    /// watch \[m\]: the distance to the nearest face of its view (the view is
    /// convex, so that is the distance to its boundary), 0 outside it.
    pub fn clearance(&self, p: &Point3<f64>) -> f64 {
        let c = self.pose.to_camera(p);
        if !c.iter().all(|x| x.is_finite()) {
            return 0.0;
        }
        let faces = [c.z - self.near, self.far - c.z];
        let sides = self.sides.iter().map(|n| n.dot(&c.coords));
        faces
            .into_iter()
            .chain(sides)
            .fold(f64::INFINITY, f64::min)
            .max(0.0)
    }

    /// One camera's lower bound of `point`'s clearance \[m\]: its depth-space
    /// distance `repulsion.min_distance`, which looks no farther than the
    /// scan's reach `rho` (nothing seen: clearance ρ, no more), and no
    /// farther than the space it does not watch.
    pub fn bound(&self, point: &PointOfInterest, repulsion: &Repulsion, rho: f64) -> f64 {
        let unwatched = (self.clearance(&point.position) - point.radius).max(0.0);
        repulsion.min_distance.min(rho).min(unwatched)
    }
}

/// The nearest surface any camera saw from a point of interest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenSurface {
    /// clearance from the point's sphere to it \[m\]
    pub clearance: f64,
    /// the surface point, base frame \[m\]
    pub point: Point3<f64>,
}

/// One camera's `bound` \[m\] of `at` and its `repulsion`, capped by
/// `surface`, the nearest surface any fresh camera saw from the point (what
/// the robot hid from this camera another may have seen). When the cap
/// binds, the answer is that surface's: its distance, the obstacle point
/// and a repulsion pointing away from it at eq. 16's magnitude. Since
/// `max_c min(b_c, s) = min(max_c b_c, s)`, capping every camera's bound
/// and then fusing ([`fuse`]) gives the nearest surface against the largest
/// bound. A NaN bound counts as 0.
pub fn capped_by_surface(
    bound: f64,
    repulsion: &Repulsion,
    at: &PointOfInterest,
    surface: Option<SeenSurface>,
    params: &RepulsionParams,
) -> (f64, Repulsion) {
    let bound = if bound.is_nan() { 0.0 } else { bound };
    let Some(s) = surface.filter(|s| s.clearance < bound) else {
        return (bound, *repulsion);
    };
    let away = at.position - s.point;
    let norm = away.norm();
    let v_call = match norm > 0.0 && norm.is_finite() {
        true => away * (params.magnitude(s.clearance) / norm),
        false => Vector3::zeros(),
    };
    let capped = Repulsion {
        v_call,
        min_distance: s.clearance,
        center_distance: s.clearance + at.radius,
        obstacle_point: Some(s.point),
        pixels_considered: repulsion.pixels_considered,
        surface_distance: s.clearance,
        surface_point: Some(s.point),
    };
    (s.clearance, capped)
}

/// The fused answer for one point of interest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fused {
    /// repulsion of the camera that gave the distance, with its distance
    /// and magnitude set to the fused ones (eq. 16)
    pub repulsion: Repulsion,
    /// that camera, by its place in the input; `None` without any camera
    pub camera: Option<usize>,
}

impl Fused {
    /// No camera to answer: the point is in unwatched space (distance 0).
    pub const BLIND: Fused = Fused {
        repulsion: Repulsion {
            v_call: Vector3::new(0.0, 0.0, 0.0),
            min_distance: 0.0,
            center_distance: 0.0,
            obstacle_point: None,
            pixels_considered: 0,
            surface_distance: f64::INFINITY,
            surface_point: None,
        },
        camera: None,
    };
}

/// The fused distance of one point from its per-camera answers `(bound,
/// repulsion)` (cameras gone stale are left out by the caller): the largest
/// bound, with the repulsive vector of the camera that gives it rescaled to
/// `params.magnitude` of that distance. A camera's vector points away from
/// what it saw; when the bound comes from its unwatched space instead, the
/// vector still points away from what it saw, or is zero when it saw nothing.
/// Ties go to the first camera. [`Fused::BLIND`] without cameras.
pub fn fuse<'a>(
    answers: impl IntoIterator<Item = (f64, &'a Repulsion)>,
    params: &RepulsionParams,
) -> Fused {
    let mut best: Option<(usize, f64, &Repulsion)> = None;
    for (i, (bound, r)) in answers.into_iter().enumerate() {
        let bound = if bound.is_nan() { 0.0 } else { bound };
        if best.is_none_or(|(_, b, _)| bound > b) {
            best = Some((i, bound, r));
        }
    }
    let Some((camera, distance, r)) = best else {
        return Fused::BLIND;
    };
    let mut repulsion = *r;
    let norm = r.v_call.norm();
    repulsion.v_call = if norm > 0.0 && distance.is_finite() {
        r.v_call * (params.magnitude(distance) / norm)
    } else {
        Vector3::zeros()
    };
    let radius = (r.center_distance - r.min_distance).max(0.0);
    repulsion.min_distance = distance;
    if distance < r.min_distance {
        // the view's boundary, not what the camera saw, bounds the point
        repulsion.center_distance = distance + radius;
    }
    Fused {
        repulsion,
        camera: Some(camera),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> CameraView {
        // at 1 m height looking along base +x
        let pose = CameraPose::look_at(
            &Point3::new(0.0, 0.0, 1.0),
            &Point3::new(1.0, 0.0, 1.0),
            &Vector3::z(),
        )
        .unwrap();
        CameraView::new(&Intrinsics::KINECT, pose, 0.5, 4.5).unwrap()
    }

    #[test]
    fn clearance_is_the_distance_to_the_nearest_face_and_zero_outside() {
        let v = view();
        // on the optical axis: the near and far faces at 0.5 and 4.5 m
        assert!((v.clearance(&Point3::new(0.7, 0.0, 1.0)) - 0.2).abs() < 1e-9);
        assert!((v.clearance(&Point3::new(4.4, 0.0, 1.0)) - 0.1).abs() < 1e-9);
        // behind the camera, nearer than its range, beside or beyond the view
        for p in [
            Point3::new(-1.0, 0.0, 1.0),
            Point3::new(0.3, 0.0, 1.0),
            Point3::new(1.0, 5.0, 1.0),
            Point3::new(6.0, 0.0, 1.0),
        ] {
            assert_eq!(v.clearance(&p), 0.0, "{p}");
        }
        // halfway across, the side faces bound it: the ball of that radius
        // stays inside, a point just past it in the face's direction is out
        let p = Point3::new(2.0, 0.3, 1.2);
        let c = v.clearance(&p);
        assert!(c > 0.0 && c < 0.9, "{c}");
        let k = Intrinsics::KINECT;
        let inside = |q: &Point3<f64>| {
            v.pose().project(&k, q).is_some_and(|px| {
                px.px >= -0.5
                    && px.px <= f64::from(k.width) - 0.5
                    && px.py >= -0.5
                    && px.py <= f64::from(k.height) - 0.5
                    && px.depth >= 0.5
                    && px.depth <= 4.5
            })
        };
        let mut outside_at_c = 0;
        for i in 0..40 {
            for j in 0..20 {
                let (az, el) = (i as f64 * 0.157, (j as f64 + 0.5) * 0.157 - 1.57);
                let dir = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
                assert!(inside(&(p + dir * (c * 0.999))), "{dir}");
                if !inside(&(p + dir * (c * 1.05))) {
                    outside_at_c += 1;
                }
            }
        }
        assert!(
            outside_at_c > 0,
            "no direction leaves the view just past the clearance"
        );
    }

    #[test]
    fn a_camera_that_saw_nothing_bounds_by_what_it_does_not_watch() {
        let v = view();
        let point = PointOfInterest::new(Point3::new(0.7, 0.0, 1.0), 0.05);
        // nothing seen near: the near face 0.2 m away, less the radius
        assert!((v.bound(&point, &Repulsion::NONE, 0.4) - 0.15).abs() < 1e-9);
        // nothing seen within the scan's reach, deep in the view: ρ
        let deep = PointOfInterest::new(Point3::new(2.0, 0.0, 1.0), 0.05);
        assert_eq!(v.bound(&deep, &Repulsion::NONE, 0.4), 0.4);
        // an obstacle seen nearer than that bounds it
        let seen = Repulsion {
            min_distance: 0.1,
            center_distance: 0.15,
            ..Repulsion::NONE
        };
        assert_eq!(v.bound(&point, &seen, 0.4), 0.1);
    }

    #[test]
    fn a_surface_nearer_than_the_bound_caps_it_and_gives_the_direction() {
        let params = RepulsionParams::default();
        let at = PointOfInterest::new(Point3::new(1.0, 0.0, 1.0), 0.05);
        let seen = Repulsion {
            v_call: Vector3::new(0.0, 0.1, 0.0),
            min_distance: 0.2,
            center_distance: 0.25,
            obstacle_point: Some(Point3::new(1.0, -0.25, 1.0)),
            pixels_considered: 7,
            surface_distance: 0.2,
            surface_point: Some(Point3::new(1.0, -0.25, 1.0)),
        };
        // another camera saw a surface 0.1 m away along +x
        let nearer = SeenSurface {
            clearance: 0.1,
            point: Point3::new(1.15, 0.0, 1.0),
        };
        let (bound, r) = capped_by_surface(0.2, &seen, &at, Some(nearer), &params);
        assert_eq!(bound, 0.1);
        assert_eq!(r.min_distance, 0.1);
        assert!((r.center_distance - 0.15).abs() < 1e-12);
        assert_eq!(r.obstacle_point, Some(nearer.point));
        assert!((r.v_call.norm() - params.magnitude(0.1)).abs() < 1e-12);
        assert!(r.v_call.x < 0.0 && r.v_call.y.abs() < 1e-12);
        // a farther surface (or none) leaves the answer as it was
        let farther = SeenSurface {
            clearance: 0.3,
            ..nearer
        };
        assert_eq!(
            capped_by_surface(0.2, &seen, &at, Some(farther), &params),
            (0.2, seen)
        );
        assert_eq!(
            capped_by_surface(0.2, &seen, &at, None, &params),
            (0.2, seen)
        );
        // a NaN bound counts as touching: nothing caps it further
        assert_eq!(
            capped_by_surface(f64::NAN, &seen, &at, Some(nearer), &params).0,
            0.0
        );
    }

    #[test]
    fn the_largest_bound_wins_with_its_cameras_direction_at_its_magnitude() {
        let params = RepulsionParams::default();
        let a = Repulsion {
            v_call: Vector3::new(0.0, 0.2, 0.0),
            min_distance: 0.05,
            center_distance: 0.1,
            obstacle_point: Some(Point3::new(0.0, -0.1, 0.0)),
            pixels_considered: 10,
            surface_distance: 0.3,
            surface_point: None,
        };
        let b = Repulsion {
            v_call: Vector3::new(-0.1, 0.0, 0.0),
            min_distance: 0.2,
            center_distance: 0.25,
            obstacle_point: Some(Point3::new(0.25, 0.0, 0.0)),
            pixels_considered: 5,
            surface_distance: 0.2,
            surface_point: None,
        };
        // b's view bounds it at 0.15: still more than a's 0.05
        let f = fuse([(0.05, &a), (0.15, &b)], &params);
        assert_eq!(f.camera, Some(1));
        assert_eq!(f.repulsion.min_distance, 0.15);
        assert!((f.repulsion.center_distance - 0.2).abs() < 1e-12);
        let v = f.repulsion.v_call;
        assert!((v.norm() - params.magnitude(0.15)).abs() < 1e-12);
        assert!(v.x < 0.0 && v.y.abs() < 1e-12);
        // a camera that saw nothing bounds without a direction
        let f = fuse([(0.05, &a), (0.3, &Repulsion::NONE)], &params);
        assert_eq!((f.camera, f.repulsion.min_distance), (Some(1), 0.3));
        assert_eq!(f.repulsion.v_call, Vector3::zeros());
        // every camera free: ∞, no vector; none at all: blind
        let f = fuse([(f64::INFINITY, &Repulsion::NONE)], &params);
        assert_eq!(f.repulsion.min_distance, f64::INFINITY);
        assert_eq!(f.repulsion.v_call, Vector3::zeros());
        assert_eq!(fuse([], &params), Fused::BLIND);
    }

    #[test]
    fn a_nan_bound_counts_as_no_clearance() {
        let params = RepulsionParams::default();
        let f = fuse([(f64::NAN, &Repulsion::NONE)], &params);
        assert_eq!(f.repulsion.min_distance, 0.0);
        assert!(view().clearance(&Point3::new(f64::NAN, 0.0, 1.0)) == 0.0);
    }
}
