//! `phri-control`: answers every `robot/state` with a `robot/command` (the only
//! publisher that channel accepts) and a `control/status`.

use std::process::ExitCode;
use std::time::Duration;

use phri_control::{ControlConfig, ControlInput, Controller, PerceptionView, ResidualView};
use serde::Deserialize;

/// What the controller needs of `[repulsion]`: the workers and their control points.
#[derive(Deserialize, Default)]
#[serde(default)]
struct RepulsionSection {
    workers: u32,
    points: Vec<PointSection>,
}

#[derive(Deserialize, Default)]
struct PointSection {
    link: String,
    xyz: [f64; 3],
}
use phri_ipc::*;
use phri_runtime::{now_ns, ServiceContext};

fn main() -> ExitCode {
    phri_runtime::service::run("phri-control", body)
}

fn body() -> Result<(), String> {
    let ctx = ServiceContext::from_args("control", &[])?;
    let cfg: ControlConfig = ctx.section("control")?;
    let model = ctx.robot_model(MAX_DOF)?;
    let n = model.nv();
    let avoidance = cfg.avoidance;
    let rep: RepulsionSection = ctx.section("repulsion")?;
    if avoidance && (rep.workers == 0 || rep.points.is_empty()) {
        return Err(format!(
            "{}: [control] avoidance needs [repulsion] workers and points",
            ctx.config_path.display()
        ));
    }
    let mut controller = Controller::new(model, cfg).map_err(|e| e.to_string())?;
    let points: Vec<(String, [f64; 3])> =
        rep.points.iter().map(|p| (p.link.clone(), p.xyz)).collect();
    controller
        .set_control_points(&points)
        .map_err(|e| e.to_string())?;
    let s = |x: IpcError| x.to_string();
    let node = node(&ctx.name, &ctx.prefix).map_err(s)?;
    let states = subscriber::<JointState>(&node, ROBOT_STATE, LATEST).map_err(s)?;
    let state_event = listener(&node, ROBOT_STATE).map_err(s)?;
    let residuals = subscriber::<Residual>(&node, DYNAMICS_RESIDUAL, LATEST).map_err(s)?;
    // a second controller fails here: the command channel accepts exactly one publisher
    let commands = publisher::<TorqueCommand>(&node, ROBOT_COMMAND)
        .map_err(|x| format!("{x} (another process already commands the robot?)"))?;
    let command_event = notifier(&node, ROBOT_COMMAND).map_err(s)?;
    let status_pub = publisher::<ControlStatus>(&node, CONTROL_STATUS).map_err(s)?;
    let repulsion = subscriber::<RepulsionResult>(&node, PERCEPTION_REPULSION, DRAIN).map_err(s)?;
    // newest result per control point, and the capture time of each worker's newest result
    let mut point_results = vec![PointRepulsion::default(); points.len()];
    let mut worker_capture = vec![0u64; rep.workers.max(1) as usize];
    ctx.go_realtime();

    let mut residual = Residual::zeroed();
    let mut have_residual = false;
    let mut cmd = TorqueCommand::zeroed();
    let mut status = ControlStatus::zeroed();
    let mut seq = 0u64;
    while !ctx.shutdown.requested() {
        let _ = state_event.timed_wait(|_| {}, Duration::from_millis(50));
        let Some(state) = latest(&states, ROBOT_STATE).map_err(s)? else {
            continue;
        };
        let t0 = now_ns();
        if let Some(r) = latest(&residuals, DYNAMICS_RESIDUAL).map_err(s)? {
            if r.dof as usize == n {
                residual = r;
                have_residual = true;
            }
        }
        if state.dof as usize != n {
            eprintln!(
                "phri-control: {ROBOT_STATE}: state {} has {} joints, the model {n}",
                state.seq, state.dof
            );
            continue;
        }
        let view = have_residual.then(|| ResidualView {
            state_stamp_ns: residual.state_stamp_ns,
            r: &residual.r[..n],
            valid: residual.flags & residual_flags::VALID != 0,
            contact: residual.flags & residual_flags::CONTACT != 0,
            collision: residual.flags & residual_flags::COLLISION != 0,
        });
        while let Some(r) = repulsion
            .receive()
            .map_err(|x| ipc_err(PERCEPTION_REPULSION, x).to_string())?
        {
            if let Some(c) = worker_capture.get_mut(r.worker as usize) {
                *c = (*c).max(r.capture_ns);
            }
            for p in r
                .points
                .iter()
                .take((r.n_points as usize).min(MAX_POINTS_PER_WORKER))
            {
                if let Some(slot) = point_results.get_mut(p.point as usize) {
                    *slot = *p;
                }
            }
        }
        let perception = avoidance.then(|| PerceptionView {
            capture_ns: worker_capture.iter().copied().min().unwrap_or(0),
            points: &point_results,
        });
        let out = controller.step(&ControlInput {
            state_stamp_ns: state.stamp_ns,
            q: &state.q[..n],
            residual: view,
            perception,
        });
        seq += 1;
        cmd.seq = seq;
        cmd.state_seq = state.seq;
        cmd.state_stamp_ns = state.stamp_ns;
        cmd.dof = n as u32;
        cmd.mode = out.mode;
        cmd.tau[..n].copy_from_slice(out.tau);
        cmd.stamp_ns = now_ns();
        publish(&commands, ROBOT_COMMAND, &cmd).map_err(s)?;
        let _ = command_event.notify();

        status.seq = seq;
        status.stamp_ns = cmd.stamp_ns;
        status.state_seq = state.seq;
        status.state_stamp_ns = state.stamp_ns;
        status.mode = controller.mode();
        status.reaction = controller.reaction().index();
        status.waypoints_reached = controller.waypoints_reached;
        status.detections = controller.detections;
        status.protective_stops = controller.protective_stops;
        status.resumes = controller.resumes;
        status.residual_age_ns = controller.residual_age_ns();
        status.q_ref[..n].copy_from_slice(controller.q_ref());
        let ee = controller.ee();
        status.ee = [ee.x, ee.y, ee.z];
        status.compute_ns = now_ns() - t0;
        status.wake_latency_ns = t0.saturating_sub(state.published_ns);
        status.perception_age_ns = controller.perception_age_ns();
        status.min_distance = controller.last_min_distance();
        status.risk = controller.risk;
        status.task_scale = controller.task_scale;
        publish(&status_pub, CONTROL_STATUS, &status).map_err(s)?;
    }
    Ok(())
}
