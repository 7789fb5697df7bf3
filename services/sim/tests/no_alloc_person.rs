//! Stepping through the person's actions (a wave, a raised foot, a scripted
//! push on a link) allocates nothing: counted with a global allocator (this
//! test thread's own allocations).

mod common;

use common::counting::{allocations, Counting};

use phri_config::{Scenario, SimConfig};
use phri_sim::Simulator;

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn stepping_through_waves_feet_and_pushes_does_not_allocate() {
    let model = common::model();
    let q = common::ik(&model, common::P2);
    let sc = Scenario::from_str(
        "name = \"actions\"\n[human]\ncollaborative_parts = [\"hand_right\"]\nrepeat_s = 4.0\n\
         [[human.keyframe]]\nt = 0.0\nbase = [0.95, 0.0, 3.141592653589793]\n\
         wave = { hand = \"left\", frequency_hz = 2.0, amplitude_m = 0.3 }\nright_foot = [0.8, 0.1, -0.5]\n\
         [[human.keyframe]]\nt = 1.0\nbase = [0.95, 0.0, 3.141592653589793]\n\
         push = { link = \"lwr_link_7\", point = [0.0, 0.0, 0.04], force_n = 40.0, part = \"right_hand\" }\n\
         [[human.keyframe]]\nt = 3.0\nbase = [0.95, 0.0, 3.141592653589793]\n",
    )
    .expect("scenario");
    let cfg = SimConfig {
        q0: q.clone(),
        ft_sensor: true,
        ..common::sim_config()
    };
    let mut sim = Simulator::from_scenario(model.clone(), cfg, &sc, Some(1)).expect("sim");
    let mut data = phri_model::Data::new(&model);
    let g = phri_model::gravity(&model, &mut data, &q)
        .expect("g")
        .as_slice()
        .to_vec();
    let mut pushed = 0usize;
    let start = allocations();
    for k in 0..9_000 {
        if k % 50 == 0 {
            sim.reset_state(&q).expect("pose");
        }
        sim.step(&g, k % 3000 > 2700);
        pushed += sim.truth().contacts.iter().filter(|c| c.intended).count();
    }
    let allocated = allocations() - start;
    assert!(pushed > 3000, "the run pushed ({pushed} contact steps)");
    assert_eq!(allocated, 0, "step allocated {allocated} times");
}
