//! Several depth cameras in the lock-step cell: `deploy/two-cameras.toml`
//! (the paper's camera and its mirror) loads as two cameras, and the cell
//! runs both, their distances fused, through the person's first pass of
//! `coexistence` with no contact.

mod common;

use phri_cell::CellOptions;
use phri_config::Loaded;

#[test]
fn the_mirrored_pair_keeps_the_person_clear_in_lock_step() {
    let file = common::deploy().with_file_name("two-cameras.toml");
    let l = Loaded::load(&file, Some("coexistence"), &[]).unwrap();
    assert_eq!(l.config.cameras.len(), 2);
    assert_eq!(l.config.cameras[1].azimuth_rad, -0.6);
    let mut c = common::cell_of(&l, &CellOptions::default());
    for _ in 0..20_000 {
        c.tick().unwrap();
    }
    let s = c.summary();
    assert_eq!(s.unintended_contacts, 0, "{:?}", s.contacts);
    assert!(s.min_distance_m > 0.03, "closest {} m", s.min_distance_m);
    assert!(s.waypoints >= 2, "waypoints {}", s.waypoints);
    assert!(s.frames > 550, "frames {}", s.frames);
}
