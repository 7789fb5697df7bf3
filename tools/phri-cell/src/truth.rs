//! Perfect perception, for measuring what the avoidance does when no camera
//! hides anything: every control point's distance, closest point and
//! repulsive vector (eq. 16) from the simulated person's body itself.

use nalgebra::Vector3;
use phri_depth::RepulsionParams;
use phri_ipc::RepulsionResult;
use phri_sim::{closest_points_segments, HumanCapsule};

/// Rewrite `result`'s points with the truth: for each control point (its
/// position as the worker saw it, its link radius from `radii`), the
/// clearance to the closest body capsule, capped at ρ; the capsule's surface
/// point as the obstacle; `v(d)` of eq. 16 away from it. A point with
/// nothing within ρ is inactive, as in depth space.
pub fn rewrite(
    result: &mut RepulsionResult,
    body: &[HumanCapsule],
    radii: &[f64],
    params: &RepulsionParams,
) {
    let n = (result.n_points as usize).min(result.points.len());
    for p in &mut result.points[..n] {
        let at = Vector3::from(p.position);
        let radius = radii.get(p.point as usize).copied().unwrap_or(0.0);
        let closest = body
            .iter()
            .map(|c| {
                let axis = closest_points_segments(&c.a, &c.b, &at, &at).p;
                let away = at - axis;
                let len = away.norm();
                let dir = if len > 1e-9 { away / len } else { Vector3::z() };
                (
                    (len - c.radius - radius).max(0.0),
                    axis + dir * c.radius,
                    dir,
                )
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match closest {
            Some((d, surface, dir)) if d < params.rho => {
                p.active = 1;
                p.min_distance = d;
                p.obstacle = surface.into();
                p.v_call = (dir * params.magnitude(d)).into();
            }
            _ => {
                p.active = 0;
                p.min_distance = params.rho;
                p.obstacle = [0.0; 3];
                p.v_call = [0.0; 3];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::BodyPart;
    use phri_ipc::Zeroed;

    #[test]
    fn the_truth_is_the_clearance_to_the_closest_capsule() {
        let params = RepulsionParams::default();
        let hand = HumanCapsule {
            part: BodyPart::ALL[0],
            a: Vector3::new(0.5, 0.0, 0.4),
            b: Vector3::new(0.6, 0.0, 0.4),
            radius: 0.05,
        };
        let mut r = RepulsionResult::zeroed();
        r.n_points = 2;
        r.points[0].point = 0;
        r.points[0].position = [0.55, 0.0, 0.6]; // 0.2 above the axis
        r.points[1].point = 1;
        r.points[1].position = [0.55, 0.0, 1.6]; // beyond ρ
        rewrite(&mut r, &[hand], &[0.05, 0.05], &params);
        let p = &r.points[0];
        assert_eq!(p.active, 1);
        assert!((p.min_distance - 0.10).abs() < 1e-12, "{}", p.min_distance);
        assert!((Vector3::from(p.obstacle) - Vector3::new(0.55, 0.0, 0.45)).norm() < 1e-12);
        // eq. 16's magnitude, pointing away from the hand (+z)
        assert!((p.v_call[2] - params.magnitude(0.10)).abs() < 1e-12);
        assert!(p.v_call[0].abs() < 1e-12 && p.v_call[1].abs() < 1e-12);
        assert_eq!(r.points[1].active, 0);
        assert_eq!(r.points[1].min_distance, params.rho);
    }
}
