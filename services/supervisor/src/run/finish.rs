//! The end of a run: a start that failed stops what it started; otherwise
//! what arrived last is read, the services are stopped in order, the report
//! is built, written and summed up in one line.

use phri_runtime::now_ns;

use super::driver::Driver;
use super::ipc;
use super::report_file::ReportFile;
use crate::cpu::CpuReport;
use crate::evaluation::Evaluation;
use crate::process::cpu_time_ns;
use crate::report::Report;
use crate::supervision::{Action, Ending, Event, Supervision};
use crate::{Plan, SupervisorError};

/// End the run `sup` supervised through `driver`: stop the cell, clean up,
/// write the report (to `report_file`); the error says why the run failed
/// or was degraded.
pub fn finish(
    driver: Driver,
    sup: &mut Supervision,
    plan: &Plan,
    mut report_file: Option<ReportFile>,
) -> Result<(), SupervisorError> {
    let Driver {
        node,
        mut ports,
        mut cell,
        mut evaluation,
        publishers,
        prefix,
        ..
    } = driver;
    drop(publishers);
    let stop_reason = match sup.ending() {
        Ending::StartFailed(reason) => {
            tracing::warn!("{reason}: stopping everything started");
            cell.stop(sup.roster());
            ipc::close(node, Some(ports), &prefix);
            cell.remove_state();
            return Err(SupervisorError::StartFailed(reason));
        }
        Ending::Stopped(reason) => reason,
    };
    let end = now_ns();
    let services = sup.roster().reports();
    // drain what arrived in the last period before stopping anything
    ports.read_last(&mut evaluation);
    // each service's CPU over the run, sampled once more before the stop
    let now = now_ns();
    let mut none = Vec::new();
    for index in 0..sup.roster().len() {
        let cpu_ns = sup.roster().get(index).pid.and_then(cpu_time_ns);
        sup.step(now, Event::CpuTime { index, cpu_ns }, &mut none);
    }
    let cpu = sup.cpu().report(sup.roster());
    let ours: Vec<u32> = (0..sup.roster().len())
        .filter_map(|i| sup.roster().get(i).pid)
        .collect();
    evaluation.eval.on_stop(now_ns());
    cell.stop(sup.roster());
    ports.read_after_stop(&mut evaluation);
    judge_last_strangers(sup, &mut evaluation, &ours);
    let own_cpu_ns = cpu_time_ns(std::process::id());
    let mut report = evaluation.report(plan, end, services, cpu, sup.realtime().report());
    report.supervisor_cpu = own_cpu_ns.map(|ns| CpuReport::of_run(ns, report.duration_s));
    ipc::close(node, Some(ports), &prefix);
    cell.remove_state();
    if let Some(file) = report_file.as_mut() {
        let json = serde_json::to_string_pretty(&report).map_err(|e| SupervisorError::Report {
            path: file.path().to_path_buf(),
            source: std::io::Error::other(e),
        })?;
        file.write(&json)?;
    }
    summary(&report);
    match stop_reason {
        Some(reason) => Err(SupervisorError::Degraded(reason)),
        None => Ok(()),
    }
}

/// The strangers the robot named only in what it said as it stopped (a
/// command refused in its last `robot/commanders`, read after the rounds
/// ended), judged as a round judges them: an intruder event and a degraded
/// line each, never left out of the report. `ours`: the pids of the
/// services this supervisor ran before it stopped them.
/// Returns the supervision's actions, each applied to the report.
fn judge_last_strangers(
    sup: &mut Supervision,
    evaluation: &mut Evaluation,
    ours: &[u32],
) -> Vec<Action> {
    let late = evaluation
        .boxes
        .intruders(|pid| !ours.contains(&(pid as u32)));
    let mut out = Vec::new();
    for reason in late {
        sup.step(now_ns(), Event::RobotIntruder(reason), &mut out);
    }
    for action in &out {
        if let Action::Warn(line) = action {
            tracing::warn!("{line}");
        }
        evaluation.apply(action);
    }
    out
}

/// The run in one line.
fn summary(report: &Report) {
    let intended = report.contacts.iter().filter(|c| c.intended).count();
    tracing::info!(
        "{} done after {:.1} s: {} cycles, {} missed deadlines, latency p99 {:.0} µs, {} unintended contacts, {} intended touches, {} false detections; {}",
        report.scenario,
        report.duration_s,
        report.torque_loop.cycles,
        report.torque_loop.missed_deadlines,
        report.torque_loop.latency_us.p99,
        report.contacts.len() - intended,
        report.collaboration.contacts_intended,
        report.false_detections,
        report.summary
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervision::Setup;
    use phri_ipc::{CommanderStats, Zeroed};

    /// The default cell's plan, supervised from t = 0.
    fn cell() -> (Plan, Supervision) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let plan = Plan::load(&root.join("deploy/phri.toml"), None, &[], None).unwrap();
        let sup = Supervision::new(Setup::unscheduled(
            plan.loaded.config.supervisor.clone(),
            plan.services.clone(),
        ));
        (plan, sup)
    }

    #[test]
    fn a_stranger_named_only_as_the_robot_stopped_is_an_intruder_in_the_report() {
        let (plan, mut sup) = cell();
        let mut evaluation = Evaluation::new(&plan, 0);
        // the robot's last robot/commanders, read after the services stopped
        let mut c = CommanderStats::zeroed();
        c.seq = 40;
        c.refused_stranger = [1, 0];
        c.stranger_pid = 4242;
        evaluation.boxes.on_commanders(&c);
        let out = judge_last_strangers(&mut sup, &mut evaluation, &[77, 78]);
        let recorded = out.iter().any(|a| {
            matches!(a, Action::Record { kind: "intruder", service, detail, .. }
                if service == "robot" && detail.contains("pid 4242"))
        });
        assert!(recorded, "{out:?}");
        assert!(
            out.iter().any(|a| matches!(a, Action::Degrade(_))),
            "{out:?}"
        );
        // judged once over the run
        assert!(judge_last_strangers(&mut sup, &mut evaluation, &[77, 78]).is_empty());
        // one of the supervisor's own services, whose pid the robot learned
        // late, is no intruder
        let mut c = CommanderStats::zeroed();
        c.seq = 41;
        c.refused_stranger = [2, 0];
        c.stranger_pid = 77;
        evaluation.boxes.on_commanders(&c);
        assert!(judge_last_strangers(&mut sup, &mut evaluation, &[77, 78]).is_empty());
    }
}
