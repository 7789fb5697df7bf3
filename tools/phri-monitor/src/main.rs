//! `phri-monitor echo CHANNEL --prefix P [--count N]`: attaches read-only (a
//! subscriber, never a publisher) to a live channel and prints its samples
//! (frames summarised, not dumped).

use std::process::ExitCode;
use std::time::Duration;

use phri_ipc::*;
use phri_runtime::{now_ns, Args, Shutdown};

const USAGE: &str = "usage: phri-monitor echo CHANNEL --prefix PREFIX [--count N] [--every N]";

fn main() -> ExitCode {
    phri_runtime::service::run("phri-monitor", body)
}

fn body() -> Result<(), String> {
    let mut argv = std::env::args().skip(1);
    let cmd = argv.next().ok_or(USAGE)?;
    if cmd != "echo" {
        return Err(format!("unknown command '{cmd}'\n{USAGE}"));
    }
    let channel = argv.next().ok_or(USAGE)?;
    let args = Args::parse(argv, &["--prefix", "--count", "--every"], &[])?;
    let prefix = args
        .get("--prefix")
        .ok_or("--prefix is required (the cell's iceoryx2 prefix, see deploy/up --prefix)")?;
    let count = args.parse_value::<u64>("--count")?.unwrap_or(u64::MAX);
    let every = args.parse_value::<u64>("--every")?.unwrap_or(1).max(1);
    let shutdown = Shutdown::install().map_err(|e| e.to_string())?;
    let node =
        node(&format!("monitor{}", std::process::id()), prefix).map_err(|e| e.to_string())?;
    let mut printed = 0u64;
    let mut seen = 0u64;
    let mut emit = |line: String| -> bool {
        seen += 1;
        if seen % every == 0 {
            println!("{line}");
            printed += 1;
        }
        printed < count
    };
    macro_rules! echo {
        ($t:ty) => {{
            let sub = subscriber::<$t>(&node, &channel, DRAIN).map_err(|e| e.to_string())?;
            'outer: while !shutdown.requested() {
                std::thread::sleep(Duration::from_millis(5));
                while let Some(m) = sub
                    .receive()
                    .map_err(|e| ipc_err(&channel, e).to_string())?
                {
                    if !emit(format!("{:?}", *m)) {
                        break 'outer;
                    }
                }
            }
        }};
    }
    match channel.as_str() {
        ROBOT_STATE => echo!(JointState),
        ROBOT_COMMAND => echo!(TorqueCommand),
        ROBOT_STATS => echo!(RobotStats),
        SIM_TRUTH => echo!(Truth),
        DYNAMICS_RESIDUAL => echo!(Residual),
        CONTROL_STATUS => echo!(ControlStatus),
        SUPERVISOR_HEALTH => echo!(Health),
        SIM_WORLD => echo!(WorldState),
        PERCEPTION_REPULSION => echo!(RepulsionResult),
        CAMERA_DEPTH | PERCEPTION_DEPTH => {
            let sub = frame_subscriber(&node, &channel).map_err(|e| e.to_string())?;
            while !shutdown.requested() {
                std::thread::sleep(Duration::from_millis(5));
                let mut stop = false;
                while let Some(f) = sub
                    .receive()
                    .map_err(|e| ipc_err(&channel, e).to_string())?
                {
                    let h = f.user_header();
                    let d = f.payload();
                    let valid: Vec<u16> = d.iter().copied().filter(|&x| x > 0).collect();
                    let (mn, mx) = (
                        valid.iter().min().copied().unwrap_or(0),
                        valid.iter().max().copied().unwrap_or(0),
                    );
                    let line = format!(
                        "frame {} {}x{} valid {} ({:.1} %) depth {}..{} mm removed {} capture→published {:.2} ms age {:.1} ms",
                        h.seq,
                        h.width,
                        h.height,
                        valid.len(),
                        100.0 * valid.len() as f64 / d.len().max(1) as f64,
                        mn,
                        mx,
                        h.removed_pixels,
                        h.published_ns.saturating_sub(h.capture_wall_ns) as f64 * 1e-6,
                        now_ns().saturating_sub(h.capture_wall_ns) as f64 * 1e-6
                    );
                    if !emit(line) {
                        stop = true;
                        break;
                    }
                }
                if stop {
                    break;
                }
            }
        }
        other => {
            return Err(format!(
                "unknown channel '{other}'; channels: {}",
                ALL.join(", ")
            ))
        }
    }
    Ok(())
}
