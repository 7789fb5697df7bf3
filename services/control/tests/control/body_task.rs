//! The body points' repulsion as a task below the end effector's (issue 14)
//! on the KUKA LWR-IV model: the end effector's velocity is exactly what
//! SNS gave it, the body point moves away from its obstacle, the bounds
//! hold, on random postures and repulsions.

use nalgebra::{Matrix6xX, Vector3};
use phri_config::Config;
use phri_control::avoidance::Avoidance;
use phri_model::{Data, Model};

fn lwr4() -> Model {
    Model::from_urdf_file(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/robots/kuka_lwr4.urdf"
    ))
    .unwrap()
}

/// splitmix64
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// SNS alone, with the body task, the end effector's and the point's
/// Jacobians, and the bounds.
struct Solved {
    alone: Vec<f64>,
    with: Vec<f64>,
    je: Matrix6xX<f64>,
    jp: Matrix6xX<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

/// One cycle with one body point: (SNS alone, with the body task).
fn solve(
    model: &Model,
    q: &[f64],
    point: (usize, Vector3<f64>),
    v_call: Vector3<f64>,
    xdot: Vector3<f64>,
) -> Solved {
    let mut data = Data::new(model);
    phri_model::forward_kinematics(model, &mut data, q).unwrap();
    let ee = model.frame_id("lwr_flange").unwrap();
    let mut je = Data::jacobian_buffer(model);
    let mut jp = Data::jacobian_buffer(model);
    phri_model::point_jacobian(model, &data, ee, &Vector3::zeros(), &mut je).unwrap();
    phri_model::point_jacobian(model, &data, point.0, &point.1, &mut jp).unwrap();
    let params = Config::defaults().control.avoidance_params;
    let mut out = Vec::new();
    let mut bounds = (Vec::new(), Vec::new());
    for body in [None, Some(1.0)] {
        let mut a = Avoidance::new(model, params);
        a.set_body_task(body);
        a.begin(q).unwrap();
        a.add_point(&jp, v_call).unwrap();
        let r = a.solve(&je, &xdot, &Vector3::zeros(), 1.0).unwrap();
        out.push(r.qd.to_vec());
        bounds = (r.qd_min.to_vec(), r.qd_max.to_vec());
    }
    let with = out.pop().unwrap();
    let alone = out.pop().unwrap();
    Solved {
        alone,
        with,
        je,
        jp,
        lo: bounds.0,
        hi: bounds.1,
    }
}

fn lin(j: &Matrix6xX<f64>, qd: &[f64]) -> Vector3<f64> {
    let mut v = Vector3::zeros();
    for (c, x) in qd.iter().enumerate() {
        for r in 0..3 {
            v[r] += j[(r, c)] * x;
        }
    }
    v
}

#[test]
fn the_elbow_moves_away_and_the_end_effector_does_not_notice() {
    let model = lwr4();
    let elbow = (model.frame_id("lwr_link_4").unwrap(), Vector3::zeros());
    let q = [0.0, -0.4, 0.0, 1.8, 0.0, -0.6, 0.0];
    // a hand approaching the elbow from +y, the end effector moving along +y
    let v_call = Vector3::new(0.0, -0.15, 0.0);
    let xdot = Vector3::new(0.0, 0.2, 0.0);
    let Solved {
        alone,
        with,
        je,
        jp,
        lo,
        hi,
    } = solve(&model, &q, elbow, v_call, xdot);
    let u = v_call.normalize();
    let away_alone = u.dot(&lin(&jp, &alone));
    let away_with = u.dot(&lin(&jp, &with));
    eprintln!("elbow away: {away_alone:.4} m/s alone, {away_with:.4} m/s with the body task");
    assert!(away_with > away_alone + 0.05, "{away_with} vs {away_alone}");
    assert!((lin(&je, &with) - lin(&je, &alone)).norm() < 1e-9);
    for j in 0..7 {
        assert!(
            lo[j] - 1e-12 <= with[j] && with[j] <= hi[j] + 1e-12,
            "joint {j}"
        );
    }
}

#[test]
fn on_random_problems_the_task_is_kept_and_no_point_comes_closer() {
    let model = lwr4();
    let links: Vec<usize> = ["lwr_link_3", "lwr_link_4", "lwr_link_5", "lwr_link_6"]
        .iter()
        .map(|l| model.frame_id(l).unwrap())
        .collect();
    let mut rng = Rng(14);
    let (mut moved, mut total) = (0, 0);
    for _ in 0..500 {
        let q: Vec<f64> = model
            .actuated()
            .iter()
            .map(|j| rng.uniform(0.8 * j.lower, 0.8 * j.upper))
            .collect();
        let link = links[(rng.uniform(0.0, 4.0) as usize).min(3)];
        let point = (link, Vector3::new(0.0, 0.0, rng.uniform(0.0, 0.3)));
        let dir = Vector3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let v_call = dir.normalize() * rng.uniform(0.01, 0.3);
        let xdot = Vector3::new(
            rng.uniform(-0.3, 0.3),
            rng.uniform(-0.3, 0.3),
            rng.uniform(-0.3, 0.3),
        );
        let Solved {
            alone,
            with,
            je,
            jp,
            lo,
            hi,
        } = solve(&model, &q, point, v_call, xdot);
        // the end effector's velocity is SNS's (exactly up to round-off)
        let d = (lin(&je, &with) - lin(&je, &alone)).norm();
        assert!(d < 1e-9, "end effector changed by {d}");
        for j in 0..7 {
            assert!(
                lo[j] - 1e-12 <= with[j] && with[j] <= hi[j] + 1e-12,
                "joint {j}"
            );
        }
        // the point does not come closer than SNS alone would bring it
        let u = v_call.normalize();
        let (a, w) = (u.dot(&lin(&jp, &alone)), u.dot(&lin(&jp, &with)));
        assert!(w >= a - 1e-9, "point closer: {w} vs {a}");
        total += 1;
        moved += usize::from(w > a + 1e-3);
    }
    eprintln!("the body task moved the point away in {moved} of {total} problems");
    assert!(moved > total / 2, "{moved} of {total}");
}
