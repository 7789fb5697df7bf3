//! A solve allocates nothing once the workspace exists: a counting global
//! allocator (per thread, so the test harness's other threads do not count).

mod common;

use common::sequence::Sequence;
use common::{random_feasible, Qp};
use phri_qp::{solve, Settings, Start, Workspace};
use rand::rngs::SmallRng;
use rand::SeedableRng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(|a| a.get())
}

#[test]
fn solves_allocate_nothing() {
    let mut rng = SmallRng::seed_from_u64(9);
    // every problem built before counting
    let seq = Sequence::new(&mut rng, 7, 32);
    let sequence: Vec<Qp> = (0..500).map(|k| seq.at(k)).collect();
    let mut random: Vec<Qp> = (0..200)
        .map(|i| random_feasible(&mut rng, 7, [4, 16, 32][i % 3]))
        .collect();
    for qp in random.iter_mut().step_by(2) {
        qp.bounds = Some((vec![-2.0; 7], vec![2.0; 7]));
    }
    let mut infeasible = random_feasible(&mut rng, 7, 4);
    infeasible.c.extend([
        1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    infeasible.d.extend([-1.0, -1.0]);
    let bad = Qp {
        g: vec![f64::NAN; 7],
        ..random[0].clone()
    };
    let mut ws = Workspace::new(7, 34, Settings::default()).expect("workspace");
    let mut tight = Workspace::new(
        7,
        34,
        Settings {
            max_iterations: 1,
            ..Settings::default()
        },
    )
    .expect("workspace");

    let before = allocations();
    let mut solved = 0;
    for qp in &sequence {
        solved += solve(&mut ws, &qp.problem(), Start::Warm).is_ok() as usize;
    }
    for qp in &random {
        solved += solve(&mut ws, &qp.problem(), Start::Cold).is_ok() as usize;
        solved += solve(&mut ws, &qp.problem(), Start::Warm).is_ok() as usize;
        let _ = solve(&mut tight, &qp.problem(), Start::Cold);
    }
    let e1 = solve(&mut ws, &infeasible.problem(), Start::Cold).is_err();
    let e2 = solve(&mut ws, &bad.problem(), Start::Cold).is_err();
    let after = allocations();

    assert_eq!(solved, 900);
    assert!(e1 && e2);
    assert_eq!(after - before, 0, "allocations during solves");
}
