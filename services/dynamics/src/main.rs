//! `phri-dynamics`: reads `robot/state`, publishes `dynamics/residual` for every state.

use std::process::ExitCode;
use std::time::Duration;

use phri_dynamics::{ResidualConfig, ResidualObserver};
use phri_ipc::*;
use phri_runtime::{now_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-dynamics", body)
}

fn body() -> Result<(), String> {
    let ctx = ServiceContext::from_args("dynamics", &[])?;
    let cfg: ResidualConfig = ctx.section("dynamics")?;
    let model = ctx.robot_model(MAX_DOF)?;
    let n = model.nv();
    let mut observer = ResidualObserver::new(model, &cfg).map_err(|e| e.to_string())?;

    let s = |x: IpcError| x.to_string();
    let node = node(&ctx.name, &ctx.prefix).map_err(s)?;
    let states = subscriber::<JointState>(&node, ROBOT_STATE, DRAIN).map_err(s)?;
    let state_event = listener(&node, ROBOT_STATE).map_err(s)?;
    let residual_pub = publisher::<Residual>(&node, DYNAMICS_RESIDUAL).map_err(s)?;
    let residual_event = notifier(&node, DYNAMICS_RESIDUAL).map_err(s)?;
    ctx.go_realtime();

    let mut msg = Residual::zeroed();
    let mut seq = 0u64;
    let mut bad_samples = 0u64;
    while !ctx.shutdown.requested() {
        // a wake-up without a sample (timeout, signal) just loops
        let _ = state_event.timed_wait(|_| {}, Duration::from_millis(50));
        let mut fresh = false;
        loop {
            let sample = match states.receive() {
                Ok(Some(s)) => s,
                Ok(None) => break,
                Err(e) => return Err(ipc_err(ROBOT_STATE, e).to_string()),
            };
            let s: &JointState = &sample;
            let t0 = now_ns();
            if s.dof as usize != n {
                bad_samples += 1;
                if bad_samples.is_power_of_two() {
                    eprintln!("phri-dynamics: {ROBOT_STATE}: state {} has {} joints, the model {n} ({bad_samples} such samples)", s.seq, s.dof);
                }
                continue;
            }
            let wrench = (s.status & robot_status::FT_VALID != 0).then_some(&s.wrench);
            match observer.step(s.stamp_ns as f64 * 1e-9, &s.q[..n], &s.tau[..n], wrench) {
                Ok(out) => {
                    msg.r[..n].copy_from_slice(out.r);
                    msg.qd[..n].copy_from_slice(out.qd);
                    msg.norm = out.norm;
                    let d = out.detection;
                    msg.flags = (d.contact as u32 * residual_flags::CONTACT)
                        | (d.collision as u32 * residual_flags::COLLISION)
                        | (out.ft_used as u32 * residual_flags::FT_USED)
                        | (out.valid as u32 * residual_flags::VALID);
                    msg.isolated_joint = d.isolated_joint.map_or(-1, |j| j as i32);
                    msg.state_seq = s.seq;
                    msg.state_stamp_ns = s.stamp_ns;
                    msg.dof = n as u32;
                    msg.compute_ns = now_ns() - t0;
                    fresh = true;
                }
                Err(e) => {
                    bad_samples += 1;
                    if bad_samples.is_power_of_two() {
                        eprintln!("phri-dynamics: {ROBOT_STATE}: state {}: {e} ({bad_samples} bad samples)", s.seq);
                    }
                }
            }
        }
        if fresh {
            seq += 1;
            msg.seq = seq;
            msg.stamp_ns = now_ns();
            publish(&residual_pub, DYNAMICS_RESIDUAL, &msg).map_err(s)?;
            let _ = residual_event.notify();
        }
    }
    Ok(())
}
