//! How well each arm's control points stand for its links: an obstacle a
//! few centimetres from a link is seen by the points (each a sphere,
//! `|o − c| − r`) no farther than it truly is from the arm's collision
//! capsules, or only a little farther. A point set that leaves part of a
//! link out (a capsule's end cap beyond its sphere) lets an arm that keeps
//! its distance at the points come nearer than that at the link, whatever
//! the avoidance law.
//!
//! `cargo test --release -p phri-cell --test cell coverage -- --nocapture`
//! prints each arm's worst excess per link.

use crate::common::{loaded, Uniform};
use nalgebra::Vector3;
use phri_model::{forward_kinematics, frame_placement, Data};

/// Per link that carries a control point: the most by which the points see
/// an obstacle farther than it is from the arm \[m\], over obstacles placed
/// `clearance` \[m\] from that link's capsule all round (its sides and its
/// end caps) in 40 postures, where that link is the arm's nearest; and
/// where that obstacle was \[m\], link frame.
fn worst_excess(robot: &str, law: &str, clearance: f64) -> Vec<(String, f64, Vector3<f64>)> {
    let arm = format!("robot.name=\"{robot}\"");
    let law_set = format!("avoidance.law=\"{law}\"");
    let l = loaded("coexistence", &[arm.as_str(), law_set.as_str()]);
    let model = l.model().unwrap();
    let mut data = Data::new(&model);
    let points: Vec<(usize, Vector3<f64>, f64)> = l
        .config
        .repulsion
        .points
        .iter()
        .map(|p| {
            let frame = model.frame_id(&p.link).unwrap();
            (frame, Vector3::from(p.xyz), p.radius)
        })
        .collect();
    // the links that carry a point, each with its worst excess so far and
    // where it was
    let mut links: Vec<String> = l
        .config
        .repulsion
        .points
        .iter()
        .map(|p| p.link.clone())
        .collect();
    links.sort();
    links.dedup();
    let mut worst: Vec<(String, f64, Vector3<f64>)> = links
        .into_iter()
        .map(|k| (k, 0.0, Vector3::zeros()))
        .collect();
    let n = model.nv();
    let mut rng = Uniform(0x9e37_79b9_7f4a_7c15);
    for posture in 0..40 {
        let q: Vec<f64> = if posture == 0 {
            l.config.control.posture.clone()
        } else {
            model.joints[..n]
                .iter()
                .map(|j| j.lower + (j.upper - j.lower) * rng.next())
                .collect()
        };
        forward_kinematics(&model, &mut data, &q).unwrap();
        let centres: Vec<(Vector3<f64>, f64)> = points
            .iter()
            .map(|(f, xyz, r)| (frame_placement(&model, &data, *f).apply(xyz), *r))
            .collect();
        for object in &model.collisions {
            let Some(slot) = worst.iter().position(|(k, ..)| *k == object.link) else {
                continue;
            };
            let (a, b, radius) = object.capsule_segment(&data);
            for _ in 0..400 {
                // a point of the axis, then out along any direction: on the
                // capsule's surface at the ends too
                let x = a + (b - a) * rng.next();
                let o = x + rng.direction() * (radius + clearance);
                let (nearest, truth) = model
                    .collisions
                    .iter()
                    .map(|c| (&c.link, c.capsule_distance(&data, &o)))
                    .fold(
                        (&object.link, f64::INFINITY),
                        |m, c| {
                            if c.1 < m.1 {
                                c
                            } else {
                                m
                            }
                        },
                    );
                if *nearest != object.link || truth < 0.5 * clearance {
                    continue;
                }
                let seen = centres
                    .iter()
                    .map(|(c, r)| (o - c).norm() - r)
                    .fold(f64::INFINITY, f64::min);
                if seen - truth > worst[slot].1 {
                    // where, in the link's frame
                    let body = data.body_placement(object.body);
                    worst[slot].1 = seen - truth;
                    worst[slot].2 = body.r.transpose() * (o - body.p);
                }
            }
        }
    }
    worst
}

/// The most by which an arm's points may see an obstacle 5-10 cm from a
/// link farther than it is under the barrier filter \[m\]: the waist
/// between two spheres of 7 cm radius 10 cm apart along a link is 1.0 cm at
/// 5 cm (the LWR-IV's upper arm and elbow: 1.2 cm).
const TOLERANCE_M: f64 = 0.015;

#[test]
fn the_control_points_stand_for_every_link_they_are_on() {
    let mut failures = Vec::new();
    for robot in ["lwr4", "fr3", "panda"] {
        for law in ["paper", "cbf"] {
            for clearance in [0.05, 0.10] {
                for (link, excess, at) in worst_excess(robot, law, clearance) {
                    eprintln!(
                        "{robot} {law}, {:.0} cm: {link} seen up to {:.1} cm farther (at [{:.3}, {:.3}, {:.3}] m, link frame)",
                        clearance * 100.0,
                        excess * 100.0,
                        at.x,
                        at.y,
                        at.z
                    );
                    // the paper's law keeps the paper's points (printed,
                    // BENCHMARKS): link 6's ends on every arm 3 cm, the
                    // FR3's and the Panda's link 7 8 cm, link 2's ends 5 cm
                    if law == "cbf" && excess > TOLERANCE_M {
                        failures.push(format!(
                            "{robot} {law} {link} at {clearance} m: {excess:.3} m"
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
