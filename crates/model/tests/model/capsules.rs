//! Capsules added to a link (a robot file's, for a URDF with mesh
//! collisions only): the segment rides on the link wherever the joints put it.

use crate::common;

use nalgebra::Vector3;
use phri_model::{forward_kinematics, frame_placement, Data, Shape};

#[test]
fn an_added_capsule_rides_on_its_link() {
    let mut model = common::lwr4();
    let before = model.collisions.len();
    let (a, b) = (
        Vector3::new(0.01, 0.08, -0.06),
        Vector3::new(-0.02, 0.05, -0.2),
    );
    model.add_capsule("lwr_link_5", &a, &b, 0.055).unwrap();
    // a degenerate segment is a sphere; one along −z is turned, not mirrored
    model
        .add_capsule("lwr_link_3", &Vector3::zeros(), &Vector3::zeros(), 0.05)
        .unwrap();
    let (c, d) = (Vector3::new(0.0, 0.0, 0.1), Vector3::new(0.0, 0.0, -0.1));
    model.add_capsule("lwr_link_4", &c, &d, 0.07).unwrap();
    assert_eq!(model.collisions.len(), before + 3);
    let mut data = Data::new(&model);
    for q in [[0.0; 7], [0.3, -0.7, 1.1, 1.4, -0.9, 0.6, 2.0]] {
        forward_kinematics(&model, &mut data, &q).unwrap();
        for (k, link, a, b) in [
            (before, "lwr_link_5", a, b),
            (before + 2, "lwr_link_4", c, d),
        ] {
            let o = &model.collisions[k];
            let (p, r, radius) = o.capsule_segment(&data);
            let f = frame_placement(&model, &data, model.frame_id(link).unwrap());
            let (fa, fb) = (f.apply(&a), f.apply(&b));
            let ends = ((p - fa).norm() + (r - fb).norm()).min((p - fb).norm() + (r - fa).norm());
            assert!(ends < 1e-12, "{link} at {q:?}: ends off by {ends}");
            assert!(radius > 0.05);
        }
        let sphere = &model.collisions[before + 1];
        assert!(matches!(sphere.shape, Shape::Capsule { half_length, .. } if half_length == 0.0));
    }
    // an unknown link and a bad radius are refused
    assert!(model.add_capsule("no_link", &a, &b, 0.05).is_err());
    assert!(model.add_capsule("lwr_link_5", &a, &b, 0.0).is_err());
    assert!(model
        .add_capsule("lwr_link_5", &Vector3::new(f64::NAN, 0.0, 0.0), &b, 0.05)
        .is_err());
}
