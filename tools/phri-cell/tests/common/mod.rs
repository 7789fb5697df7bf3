//! The deployed configuration and scenarios, for the lock-step tests.

#![allow(dead_code)]

use std::path::PathBuf;

use phri_cell::{Cell, CellOptions, CellSummary};
use phri_config::Loaded;

pub fn deploy() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../deploy/phri.toml"
    ))
}

/// `deploy/phri.toml` with `scenario` and `sets` (`section.key=value`).
pub fn loaded(scenario: &str, sets: &[&str]) -> Loaded {
    Loaded::load(&deploy(), Some(scenario), sets).unwrap()
}

pub fn cell(scenario: &str, opts: &CellOptions, sets: &[&str]) -> Cell {
    let l = loaded(scenario, sets);
    let model = l.model().unwrap();
    Cell::new(&l, model, opts).unwrap()
}

/// Run `scenario` for `seconds` and summarise.
pub fn run(scenario: &str, seconds: f64, opts: &CellOptions, sets: &[&str]) -> CellSummary {
    let mut c = cell(scenario, opts, sets);
    for _ in 0..(seconds * 1000.0).round() as usize {
        c.tick().unwrap();
    }
    c.summary()
}
