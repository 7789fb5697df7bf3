//! `phri-sim`: the simulated robot behind the same channels a real robot
//! adapter uses. Every 1 ms (absolute deadlines) it applies the newest
//! command, integrates the arm, publishes `robot/state` (positions and applied
//! torque only) and, for evaluation, `sim/truth`; `robot/stats` at 10 Hz.
//!
//! Like a real torque-controlled arm it protects itself: a command that did
//! not answer the previous state is a missed deadline and the last command is
//! reused; more than 20 in a row engage the brakes until commands return.

use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use phri_ipc::*;
use phri_runtime::{now_ns, sleep_until_ns, ServiceContext};
use phri_sim::snapshot::{self, SharedArm};
use phri_sim::{BodyPart, Scenario, SimConfig, Simulator};

/// Consecutive missing commands the robot tolerates before braking (as Franka's FCI).
const MAX_MISSED: u32 = 20;
/// Period of `robot/stats` [cycles].
const STATS_EVERY: u64 = 100;
/// When this process itself woke late (the simulated world paused with it),
/// the controller gets this much more to answer before the cycle counts as missed [ns].
const LATE_CYCLE_GRACE_NS: u64 = 500_000;
/// how often the arm's positions are saved for a restarted simulator
const SNAPSHOT_PERIOD: Duration = Duration::from_millis(20);

fn main() -> ExitCode {
    phri_runtime::service::run("phri-sim", body)
}

fn body() -> Result<(), String> {
    let ctx = ServiceContext::from_args("sim", &[])?;
    let cfg: SimConfig = ctx.section("sim")?;
    let model = ctx.robot_model(MAX_DOF)?;
    let n = model.nv();
    let scenario_file = ctx
        .config
        .get("scenario")
        .and_then(|s| s.get("file"))
        .and_then(|f| f.as_str())
        .map(str::to_string);
    let scenario = match &scenario_file {
        Some(f) => Scenario::from_file(f).map_err(|e| e.to_string())?,
        None => Scenario::from_str("name = \"free-motion\"").map_err(|e| e.to_string())?,
    };
    let period_ns = (cfg.dt_s * 1e9).round() as u64;
    let mut sim =
        Simulator::from_scenario(model, cfg, &scenario, None).map_err(|e| e.to_string())?;
    // restarted inside a running cell: the world went on without us, so the
    // person continues where the cell's clock is, and the arm stands, at rest,
    // where it was when this process's predecessor last saved it
    let snapshot_path = phri_runtime::service::run_dir().map(|d| d.join(snapshot::FILE_NAME));
    if let Some(start) = phri_runtime::service::cell_start_ns() {
        let behind_s = now_ns().saturating_sub(start) as f64 * 1e-9;
        if behind_s > 1.0 {
            eprintln!(
                "phri-sim: the cell started {behind_s:.1} s ago: the scenario continues from there"
            );
        }
        sim.set_human_time_offset(behind_s);
        if let Some(path) = &snapshot_path {
            match snapshot::load_fresh(path, n, start, now_ns()) {
                Ok(Some(s)) => match sim.reset_state(&s.q) {
                    Ok(()) => eprintln!(
                        "phri-sim: the arm continues from its state of {:.0} ms ago ({})",
                        now_ns().saturating_sub(s.stamp_ns) as f64 * 1e-6,
                        path.display()
                    ),
                    Err(e) => eprintln!(
                        "phri-sim: {}: {e}; the arm starts at its initial position",
                        path.display()
                    ),
                },
                Ok(None) => {}
                Err(e) => eprintln!("phri-sim: {e}; the arm starts at its initial position"),
            }
        }
    }

    let s = |x: IpcError| x.to_string();
    let node = node(&ctx.name, &ctx.prefix).map_err(s)?;
    let state_pub = publisher::<JointState>(&node, ROBOT_STATE)
        .map_err(|x| format!("{x} (is another robot running with this prefix?)"))?;
    let state_event = notifier(&node, ROBOT_STATE).map_err(s)?;
    let truth_pub = publisher::<Truth>(&node, SIM_TRUTH).map_err(s)?;
    let stats_pub = publisher::<RobotStats>(&node, ROBOT_STATS).map_err(s)?;
    let world_pub = publisher::<WorldState>(&node, SIM_WORLD).map_err(s)?;
    let commands = subscriber::<TorqueCommand>(&node, ROBOT_COMMAND, LATEST).map_err(s)?;
    // the arm's positions for a successor, saved by a thread at normal
    // priority (started before this one turns real-time)
    let shared_arm = Arc::new(SharedArm::new(n));
    let saver_thread = snapshot_path.map(|path| {
        let arm = Arc::clone(&shared_arm);
        let shutdown = ctx.shutdown.clone();
        std::thread::spawn(move || {
            let mut reported = false;
            while !shutdown.requested() {
                std::thread::sleep(SNAPSHOT_PERIOD);
                if let Some(s) = arm.load() {
                    if let Err(e) = snapshot::save(&path, &s) {
                        if !reported {
                            eprintln!("phri-sim: cannot save the arm's state: {e}");
                            reported = true;
                        }
                    }
                }
            }
        })
    });
    ctx.go_realtime();

    // a second thread wakes on command events and notes when they arrive, so
    // that latency is measured at receipt, not at the next tick
    let last_command_event = Arc::new(AtomicU64::new(0));
    let listener_thread = {
        let stamp = Arc::clone(&last_command_event);
        let shutdown = ctx.shutdown.clone();
        let (name, prefix) = (format!("{}-listener", ctx.name), ctx.prefix.clone());
        std::thread::spawn(move || -> Result<(), String> {
            let node = phri_ipc::node(&name, &prefix).map_err(|x| x.to_string())?;
            let events = listener(&node, ROBOT_COMMAND).map_err(|x| x.to_string())?;
            while !shutdown.requested() {
                let _ = events.timed_wait(
                    |_| stamp.store(now_ns(), Ordering::Release),
                    Duration::from_millis(50),
                );
            }
            Ok(())
        })
    };

    let mut state = JointState::zeroed();
    state.dof = n as u32;
    let mut truth = Truth::zeroed();
    truth.dof = n as u32;
    let mut world = WorldState::zeroed();
    world.dof = n as u32;
    let mut stats = RobotStats::zeroed();
    let mut tau_cmd = vec![0.0; n];
    let mut command_seq = 0u64;
    let mut consecutive_missed = MAX_MISSED + 1; // braked until a controller answers
    let mut misses = MissLog::default();
    let mut braking = true;
    let mut loop_established = false;

    // a state's stamp is its measurement time on the robot's clock: exactly one
    // period after the previous one (the simulated arm advanced one period),
    // even when this process was late; the return value is when it was published
    let publish_state = |sim: &Simulator,
                         state: &mut JointState,
                         truth: &mut Truth,
                         world: &mut WorldState,
                         seq: u64,
                         stamp_ns: u64,
                         status: u32,
                         command_seq: u64,
                         missed: u32|
     -> Result<u64, String> {
        let m = sim.measurement();
        state.seq = seq;
        state.q[..n].copy_from_slice(&m.q);
        state.tau[..n].copy_from_slice(&m.tau_applied);
        state.status = status
            | if m.wrench.is_some() {
                robot_status::FT_VALID
            } else {
                0
            };
        state.wrench = m.wrench.unwrap_or([0.0; 6]);
        state.command_seq = command_seq;
        state.missed_commands = missed;
        state.stamp_ns = stamp_ns;
        let published = now_ns();
        state.published_ns = published;
        publish(&state_pub, ROBOT_STATE, state).map_err(|x| x.to_string())?;
        let _ = state_event.notify();
        let t = sim.truth();
        shared_arm.store(&t.q, published);
        truth.seq = seq;
        truth.stamp_ns = state.stamp_ns;
        truth.state_seq = seq;
        truth.tau_ext[..n].copy_from_slice(&t.tau_ext);
        truth.q[..n].copy_from_slice(&t.q);
        truth.qd[..n].copy_from_slice(&t.qd);
        truth.min_distance = t.min_distance;
        truth.n_contacts = t.contacts.len().min(MAX_CONTACTS) as u32;
        for (dst, c) in truth.contacts.iter_mut().zip(&t.contacts) {
            dst.robot_object = c.collision as i32;
            dst.human_part = BodyPart::ALL
                .iter()
                .position(|p| *p == c.part)
                .map_or(-1, |i| i as i32);
            dst.intended = c.intended as u32;
            dst.force = [c.force.x, c.force.y, c.force.z];
            dst.point = [c.point.x, c.point.y, c.point.z];
            dst.depth = c.depth;
        }
        publish(&truth_pub, SIM_TRUTH, truth).map_err(|x| x.to_string())?;
        // the world the simulated camera renders
        phri_sim::world::fill_world(sim, seq, stamp_ns, world);
        publish(&world_pub, SIM_WORLD, world).map_err(|x| x.to_string())?;
        Ok(published)
    };

    // the initial state: the arm at rest, brakes on
    let mut seq = 1u64;
    sim.step(&tau_cmd, true);
    let mut tick = now_ns();
    let epoch = tick;
    let mut state_pub_ns = publish_state(
        &sim,
        &mut state,
        &mut truth,
        &mut world,
        seq,
        epoch,
        robot_status::BRAKING,
        0,
        consecutive_missed,
    )?;
    while !ctx.shutdown.requested() {
        tick += period_ns;
        sleep_until_ns(tick);
        let woke = now_ns();
        let late = woke > tick + period_ns / 2;
        if late {
            // this process was late: slip the schedule rather than run cycles
            // back to back (the controller gets a full period for every state)
            stats.overruns += 1;
            tick = woke;
        }
        // did the command answering the last state arrive in time?
        let mut fresh = false;
        let mut newest = latest(&commands, ROBOT_COMMAND).map_err(s)?;
        if late && newest.is_none_or(|c| c.state_seq != seq) {
            // the machine stalled us and maybe the controller too: in simulated
            // time the cycle is not over yet, give the answer a little longer
            let until = woke + LATE_CYCLE_GRACE_NS;
            while now_ns() < until {
                sleep_until_ns(now_ns() + 50_000);
                if let Some(c) = latest(&commands, ROBOT_COMMAND).map_err(s)? {
                    let answered = c.state_seq == seq;
                    newest = Some(c);
                    if answered {
                        break;
                    }
                }
            }
        }
        if let Some(cmd) = newest {
            if cmd.dof as usize == n && cmd.tau[..n].iter().all(|t| t.is_finite()) {
                if cmd.state_seq == seq {
                    fresh = true;
                    let ev = last_command_event.load(Ordering::Acquire);
                    let received = if ev >= cmd.stamp_ns { ev } else { cmd.stamp_ns };
                    let latency = received.saturating_sub(state_pub_ns);
                    stats.latency_hist[((latency / 1000) as usize).min(LATENCY_BINS - 1)] += 1;
                    stats.latency_max_ns = stats.latency_max_ns.max(latency);
                }
                // a late answer to an older state is still the newest torque: reuse it
                tau_cmd.copy_from_slice(&cmd.tau[..n]);
                command_seq = cmd.seq;
            }
        }
        if fresh {
            consecutive_missed = 0;
            loop_established = true;
            misses.end();
        } else {
            consecutive_missed = consecutive_missed.saturating_add(1);
            if loop_established {
                stats.missed_deadlines += 1;
                let since_pub = now_ns().saturating_sub(state_pub_ns);
                misses.miss(
                    stats.missed_deadlines,
                    stats.cycles,
                    since_pub / 1000,
                    woke.saturating_sub(tick) / 1000,
                );
            }
        }
        let brake = consecutive_missed > MAX_MISSED;
        if brake && !braking {
            stats.brake_events += 1;
            eprintln!("phri-sim: {consecutive_missed} commands missing: brakes engaged");
        }
        braking = brake;
        if brake {
            stats.braked_cycles += 1;
        }
        sim.step(&tau_cmd, brake);
        stats.cycles += 1;
        seq += 1;
        let status = if brake { robot_status::BRAKING } else { 0 }
            | if fresh {
                robot_status::COMMAND_FRESH
            } else {
                0
            };
        state_pub_ns = publish_state(
            &sim,
            &mut state,
            &mut truth,
            &mut world,
            seq,
            epoch + (seq - 1) * period_ns,
            status,
            command_seq,
            consecutive_missed,
        )?;
        if stats.cycles % STATS_EVERY == 0 {
            stats.seq += 1;
            stats.stamp_ns = now_ns();
            publish(&stats_pub, ROBOT_STATS, &stats).map_err(s)?;
        }
    }
    // last word on the statistics
    stats.seq += 1;
    stats.stamp_ns = now_ns();
    let _ = publish(&stats_pub, ROBOT_STATS, &stats);
    ctx.shutdown.request();
    let _ = listener_thread.join();
    if let Some(t) = saver_thread {
        let _ = t.join();
    }
    Ok(())
}

/// Missed deadlines logged as runs: one line per run of consecutive misses,
/// when it ends (`missed deadlines A-B at cycles C-D`), so that every miss is
/// placed in time; after 2000 lines only runs of 2^k-th misses are logged.
#[derive(Default)]
struct MissLog {
    /// (first miss number, its cycle, µs since the state was published, µs woke late)
    first: Option<(u64, u64, u64, u64)>,
    last: (u64, u64),
    lines: u64,
}

impl MissLog {
    fn miss(&mut self, n: u64, cycle: u64, since_pub_us: u64, late_us: u64) {
        if self.first.is_none() {
            self.first = Some((n, cycle, since_pub_us, late_us));
        }
        self.last = (n, cycle);
    }

    fn end(&mut self) {
        let Some((n0, c0, since, late)) = self.first.take() else {
            return;
        };
        let (n1, c1) = self.last;
        self.lines += 1;
        if self.lines <= 2000 || n1.is_power_of_two() {
            eprintln!("phri-sim: missed deadlines {n0}-{n1} at cycles {c0}-{c1} (first: state published {since} µs before, cycle woke {late} µs late)");
        }
    }
}

impl Drop for MissLog {
    fn drop(&mut self) {
        self.end();
    }
}
