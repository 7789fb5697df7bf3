//! Judging a command sample's sender and form (`RobotLink::admit`, what
//! `RobotLink::poll` does per sample on the 1 kHz path) and deciding the
//! period allocate nothing: counted with a global allocator (per thread:
//! the test harness's other threads do not count).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use phri_ipc::{OwnerTable, ServiceRole, TorqueCommand, Zeroed};
use phri_robot::{CommandGate, CycleTiming, RobotLink};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// Allocations and reallocations of this thread so far.
fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn judging_senders_and_deciding_allocate_nothing() {
    let role = |name: &str| ServiceRole {
        name: name.into(),
        binary: "phri-control".into(),
        worker: None,
    };
    let roles = ["sim", "dynamics", "control", "control_standby"].map(role);
    let owners = std::sync::Arc::new(OwnerTable::new(roles.to_vec(), true));
    owners.set_pid("control", 100);
    owners.set_pid("control_standby", 200);
    let mut link = RobotLink::new(7, 1_000_000).expect("link");
    link.set_gate(CommandGate::new(owners));
    let mut c = TorqueCommand::zeroed();
    c.dof = 7;
    let start = allocations();
    let (mut taken, mut refused) = (0u32, 0u32);
    for seq in 1..=5_000u64 {
        c.seq = seq;
        c.state_seq = seq;
        c.tau[3] = if seq % 97 == 0 { f64::NAN } else { 1.0 };
        let pid = match seq % 5 {
            0 => 4242,
            1 => 200,
            _ => 100,
        };
        let slot = usize::from(pid == 200);
        let ok = link.admit(slot, pid, &c);
        taken += u32::from(ok);
        refused += u32::from(!ok);
        let newest = ok.then_some(&c);
        let timing = CycleTiming {
            state_published_ns: seq * 1_000_000,
            command_event_ns: 0,
            now_ns: seq * 1_000_000 + 100_000,
            behind_schedule_ns: 0,
            standby_asked: false,
        };
        let out = link.cycle_slots(
            [newest.filter(|_| slot == 0), newest.filter(|_| slot == 1)],
            seq,
            &timing,
        );
        if out.publish_stats || out.refused {
            link.commanders_message(seq);
        }
    }
    let allocations = allocations() - start;
    assert_eq!(allocations, 0, "{allocations} allocations in 5000 periods");
    assert!(
        taken > 3_000 && refused > 1_000,
        "{taken} taken, {refused} refused"
    );
    assert_eq!(link.commanders().stranger_pid, 4242);
}
