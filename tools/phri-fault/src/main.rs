//! `phri-fault`: inject process faults into the services of a running cell.
//!
//! The services' pids come from `<run-dir>/state.json`, written by
//! `phri-supervisor` (the run directory: `--run-dir`, or the supervisor's
//! default for `--prefix`); it is re-read before every injection, since a
//! restarted service has a new pid. The file is read only if no other user
//! can have written it, and a pid is signalled only while it is a process of
//! this user whose command line names the cell's prefix and the service, and
//! the supervisor named in the file runs (no stray signal to a recycled pid,
//! to init or to "every process").
//!
//! Exit status: 0 done, 1 usage error, 2 the cell cannot be acted on
//! (state.json missing, garbage or untrusted, service unknown, down or dead).
//! `phri-fault completions bash|zsh|fish` prints a shell completion script.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::{CommandFactory, FromArgMatches, Parser};

use phri_ipc::{DepthFault, DepthFaultKind, IpcNode, Publisher, Zeroed, FAULT_DEPTH};
use phri_runtime::cli::CompletionsCmd;
use phri_supervisor::process::process_matches;
use phri_supervisor::StateJson;

const BIN: &str = "phri-fault";

/// The actions and exit statuses, after the flags in `--help`.
const AFTER_HELP: &str = "Actions:
  kill            SIGKILL
  term            SIGTERM
  freeze SECONDS  SIGSTOP, SIGCONT after SECONDS
  slow PERCENT --for SECONDS
                  SIGSTOP/SIGCONT in 10 ms slices: the process runs PERCENT % of the time
  corrupt KIND [--frames N]
                  (SERVICE camera, the simulated one) corrupt the next N frames (default 30):
                  noise (2 % flying pixels), zeros (blind frame), size (header
                  disagrees with the payload), stale (capture time 1 s back)
  delay MS --for SECONDS
                  (SERVICE camera) publish every frame MS late for SECONDS

Without --every/--random the first injection is immediate, the next 1 s apart.

Exit status: 0 done, 1 usage, 2 state.json missing/garbage/untrusted, service unknown/down, pid dead or not the service's";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Injects process faults (kill, term, freeze, slow) into a running cell's services, and corrupts or delays the simulated camera's depth frames",
    override_usage = "phri-fault [--run-dir DIR | --prefix P] SERVICE ACTION [VALUE] [OPTIONS]\n       phri-fault completions <SHELL>",
    after_help = AFTER_HELP,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    args_override_self = true
)]
struct Cli {
    /// A service of state.json, `random` (any of them) or `random:a,b,...` (one of a set)
    #[arg(value_name = "SERVICE", required = true)]
    service: Option<String>,
    /// What to do to it
    #[arg(value_name = "ACTION", required = true, value_parser = ["kill", "term", "freeze", "slow", "corrupt", "delay"])]
    action: Option<String>,
    /// The action's value: freeze SECONDS, slow PERCENT, corrupt KIND (noise, zeros, size, stale), delay MS
    #[arg(value_name = "VALUE", allow_negative_numbers = true)]
    value: Option<String>,
    /// The cell's run directory [default: the supervisor's default for --prefix]
    #[arg(long, value_name = "DIR")]
    run_dir: Option<PathBuf>,
    /// The cell's iceoryx2 prefix [default: phri_]
    #[arg(long, value_name = "P", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// Injections (0: until --until, state.json disappears or Ctrl-C)
    #[arg(long, value_name = "N", default_value_t = 1)]
    times: u64,
    /// Wait this long before each injection \[s\]
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = non_negative, conflicts_with = "random")]
    every: Option<f64>,
    /// Wait a uniformly random time in [MIN, MAX] before each injection \[s\]
    #[arg(long, value_name = "MIN,MAX", allow_hyphen_values = true, value_parser = min_max)]
    random: Option<(f64, f64)>,
    /// Seed of the random choices [default: from the clock]
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// Inject nothing later than this long after the start \[s\]
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = non_negative)]
    until: Option<f64>,
    /// How long slow and delay last \[s\]
    #[arg(long = "for", value_name = "SECONDS", allow_negative_numbers = true, value_parser = non_negative)]
    for_s: Option<f64>,
    /// Frames corrupt acts on [default: 30]
    #[arg(long, value_name = "N", value_parser = positive_count)]
    frames: Option<u32>,
    /// One JSON object per injection instead of a text line
    #[arg(long)]
    json: bool,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

/// A non-negative, finite number.
fn non_negative(v: &str) -> Result<f64, String> {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err("not a non-negative number".into()),
    }
}

/// `MIN,MAX`, both non-negative, MIN ≤ MAX.
fn min_max(v: &str) -> Result<(f64, f64), String> {
    let (a, b) = v
        .split_once(',')
        .ok_or_else(|| "expected MIN,MAX".to_string())?;
    let (a, b) = (non_negative(a)?, non_negative(b)?);
    if b < a {
        return Err("MIN > MAX".into());
    }
    Ok((a, b))
}

/// A count above 0.
fn positive_count(v: &str) -> Result<u32, String> {
    v.trim()
        .parse::<u32>()
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| "not a positive count".into())
}

/// Parse `argv` (the first is the program name): `--help`/`--version` print
/// and exit 0 here; a usage error is [`Fail::Usage`] (one line, exit 1).
fn parse_cli(argv: impl IntoIterator<Item = std::ffi::OsString>) -> Result<Cli, Fail> {
    Cli::command()
        .name(BIN)
        .bin_name(BIN)
        .try_get_matches_from(argv)
        .and_then(|mut m| Cli::from_arg_matches_mut(&mut m))
        .map_err(|e| match e.kind() {
            clap::error::ErrorKind::DisplayHelp
            | clap::error::ErrorKind::DisplayVersion
            | clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
            _ => Fail::Usage(phri_runtime::cli::one_line(&e)),
        })
}

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

#[derive(Clone, Debug)]
enum Action {
    Kill,
    Term,
    Freeze(f64),
    Slow {
        percent: f64,
        for_s: f64,
    },
    /// a fault message to the simulated camera on `fault/depth`
    Depth {
        kind: DepthFaultKind,
        frames: u32,
        delay_ms: f64,
        for_s: f64,
    },
}

impl Action {
    fn name(&self) -> &'static str {
        match self {
            Action::Kill => "kill",
            Action::Term => "term",
            Action::Freeze(_) => "freeze",
            Action::Slow { .. } => "slow",
            Action::Depth {
                kind: DepthFaultKind::Delay,
                ..
            } => "delay",
            Action::Depth { .. } => "corrupt",
        }
    }
    fn detail(&self) -> String {
        match self {
            Action::Kill => "SIGKILL".into(),
            Action::Term => "SIGTERM".into(),
            Action::Freeze(s) => format!("SIGSTOP for {s} s"),
            Action::Slow { percent, for_s } => format!("{percent} % CPU for {for_s} s"),
            Action::Depth {
                kind: DepthFaultKind::Delay,
                delay_ms,
                for_s,
                ..
            } => format!("frames {delay_ms} ms late for {for_s} s"),
            Action::Depth { kind, frames, .. } => format!("{kind} on {frames} frames"),
        }
    }
}

#[derive(Clone, Debug)]
enum Target {
    One(String),
    Random(Option<Vec<String>>),
}

#[derive(Debug)]
struct Opts {
    run_dir: PathBuf,
    target: Target,
    action: Action,
    times: u64,
    every: Option<f64>,
    random: Option<(f64, f64)>,
    seed: u64,
    until: Option<f64>,
    json: bool,
}

/// Error of the cell (exit 2) or of the command line (exit 1).
enum Fail {
    Usage(String),
    Cell(String),
}

fn parse_f64(flag: &str, v: &str) -> Result<f64, Fail> {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(Fail::Usage(format!(
            "{flag}: not a non-negative number: {v:?}"
        ))),
    }
}

/// The options of a parsed command line (the `completions` subcommand is handled before).
fn options(cli: Cli) -> Result<Opts, Fail> {
    // clap requires both unless a subcommand is given
    let (Some(service), Some(action)) = (cli.service, cli.action) else {
        return Err(Fail::Usage("SERVICE and ACTION are required".into()));
    };
    let target = if service == "random" {
        Target::Random(None)
    } else if let Some(set) = service.strip_prefix("random:") {
        let set: Vec<String> = set
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        if set.is_empty() {
            return Err(Fail::Usage("random: needs at least one service".into()));
        }
        Target::Random(Some(set))
    } else {
        Target::One(service)
    };
    let mut value = cli.value;
    let for_s = cli.for_s;
    let action = match action.as_str() {
        "kill" => Action::Kill,
        "term" => Action::Term,
        "freeze" => {
            let v = value
                .take()
                .ok_or_else(|| Fail::Usage("freeze needs SECONDS".into()))?;
            Action::Freeze(parse_f64("freeze", &v)?)
        }
        "slow" => {
            let v = value
                .take()
                .ok_or_else(|| Fail::Usage("slow needs PERCENT".into()))?;
            let percent = parse_f64("slow", &v)?;
            if percent > 100.0 {
                return Err(Fail::Usage(format!("slow: PERCENT above 100: {v}")));
            }
            let for_s = for_s.ok_or_else(|| Fail::Usage("slow needs --for SECONDS".into()))?;
            Action::Slow { percent, for_s }
        }
        "corrupt" => {
            let v = value.take().ok_or_else(|| {
                Fail::Usage("corrupt needs KIND (noise, zeros, size, stale)".into())
            })?;
            let kind = DepthFaultKind::from_name(&v)
                .ok()
                .filter(|k| *k != DepthFaultKind::Delay)
                .ok_or_else(|| {
                    Fail::Usage(format!(
                        "corrupt: unknown KIND {v:?} (noise, zeros, size, stale)"
                    ))
                })?;
            Action::Depth {
                kind,
                frames: cli.frames.unwrap_or(30),
                delay_ms: 0.0,
                for_s: 0.0,
            }
        }
        "delay" => {
            let v = value
                .take()
                .ok_or_else(|| Fail::Usage("delay needs MS".into()))?;
            let delay_ms = parse_f64("delay", &v)?;
            let for_s = for_s.ok_or_else(|| Fail::Usage("delay needs --for SECONDS".into()))?;
            Action::Depth {
                kind: DepthFaultKind::Delay,
                frames: 0,
                delay_ms,
                for_s,
            }
        }
        a => return Err(Fail::Usage(format!("unknown ACTION {a:?}"))),
    };
    if let Some(extra) = value {
        return Err(Fail::Usage(format!("unexpected argument {extra:?}")));
    }
    if matches!(action, Action::Depth { .. })
        && !matches!(&target, Target::One(name) if name == "camera")
    {
        return Err(Fail::Usage(
            "corrupt and delay act on the simulated camera: SERVICE must be camera".into(),
        ));
    }
    let (times, every, random, until) = (cli.times, cli.every, cli.random, cli.until);
    if times == 0 && until.is_none() && every.is_none() && random.is_none() {
        return Err(Fail::Usage("--times 0 needs --every or --random".into()));
    }
    let run_dir = match cli.run_dir {
        Some(d) => d,
        None => {
            let p =
                phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
            phri_runtime::rundir::default_run_dir(&p)
                .map_err(|e| Fail::Cell(format!("--prefix {p}: {e}")))?
        }
    };
    let seed = cli.seed.unwrap_or_else(|| {
        let t = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        t.as_nanos() as u64 ^ (std::process::id() as u64) << 32
    });
    Ok(Opts {
        run_dir,
        target,
        action,
        times,
        every,
        random,
        seed,
        until,
        json: cli.json,
    })
}

/// SplitMix64: small, seedable, no dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

struct State {
    supervisor_pid: u32,
    prefix: String,
    services: BTreeMap<String, Option<i32>>,
}

/// `<run-dir>/state.json`, if it is there and trusted (a regular file of this
/// user that no one else can write).
fn read_state(run_dir: &Path) -> Result<State, Fail> {
    let path = StateJson::path(run_dir);
    let st = StateJson::read(run_dir)
        .map_err(|e| Fail::Cell(e.to_string()))?
        .ok_or_else(|| {
            Fail::Cell(format!(
                "{}: no such file (is the cell running with this --run-dir?)",
                path.display()
            ))
        })?;
    let services = st
        .services
        .into_iter()
        .map(|(k, s)| {
            let pid = s.pid.filter(|&p| p > 0 && p <= i32::MAX as u32);
            (k, pid.map(|p| p as i32))
        })
        .collect();
    Ok(State {
        supervisor_pid: st.supervisor_pid,
        prefix: st.prefix,
        services,
    })
}

/// `pid` is service `name` of the cell of `prefix`: a live process of this
/// user whose command line says so ([`process_matches`]).
fn is_service(pid: i32, prefix: &str, name: &str) -> bool {
    pid > 1
        && process_matches(
            pid as u32,
            &[format!("--prefix {prefix}"), format!("--name {name}")],
        )
}

fn send(pid: i32, sig: libc::c_int) -> Result<(), String> {
    if pid <= 1 {
        return Err(format!("refusing to signal pid {pid}"));
    }
    // SAFETY: kill(2) on one pid (> 1) checked to be the cell's service ([`is_service`]).
    if unsafe { libc::kill(pid, sig) } == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error().to_string())
    }
}

/// Pick the service and its pid, from a fresh read of state.json.
fn choose(opts: &Opts, rng: &mut Rng) -> Result<(String, i32), Fail> {
    let st = read_state(&opts.run_dir)?;
    // a state of a supervisor that is gone names pids that may be anyone's now
    if !process_matches(st.supervisor_pid, &["phri-supervisor"]) {
        return Err(Fail::Cell(format!(
            "{}: its supervisor (pid {}) is not running: stale state.json?",
            StateJson::path(&opts.run_dir).display(),
            st.supervisor_pid
        )));
    }
    let (name, pid) = match &opts.target {
        Target::One(name) => {
            let pid = st
                .services
                .get(name)
                .ok_or_else(|| {
                    Fail::Cell(format!(
                        "service {name:?} is not in state.json (services: {})",
                        st.services.keys().cloned().collect::<Vec<_>>().join(", ")
                    ))
                })?
                .ok_or_else(|| {
                    Fail::Cell(format!(
                        "service {name} is down (no pid in state.json: restarting?)"
                    ))
                })?;
            (name.clone(), pid)
        }
        Target::Random(set) => {
            if let Some(set) = set {
                if let Some(bad) = set.iter().find(|n| !st.services.contains_key(*n)) {
                    return Err(Fail::Cell(format!(
                        "service {bad:?} is not in state.json (services: {})",
                        st.services.keys().cloned().collect::<Vec<_>>().join(", ")
                    )));
                }
            }
            let up: Vec<(String, i32)> = st
                .services
                .iter()
                .filter(|(n, _)| set.as_ref().is_none_or(|s| s.contains(n)))
                .filter_map(|(n, p)| p.map(|p| (n.clone(), p)))
                .filter(|(n, p)| is_service(*p, &st.prefix, n))
                .collect();
            if up.is_empty() {
                return Err(Fail::Cell("no candidate service is up".into()));
            }
            up[rng.below(up.len())].clone()
        }
    };
    if !is_service(pid, &st.prefix, &name) {
        return Err(Fail::Cell(format!(
            "{name}: pid {pid} is not alive, or not service {name} of the cell {}: stale state.json?",
            st.prefix
        )));
    }
    Ok((name, pid))
}

/// Sleep, waking early on Ctrl-C/SIGTERM. Returns false when interrupted.
fn sleep_s(s: f64) -> bool {
    let end = Instant::now() + Duration::from_secs_f64(s.max(0.0));
    loop {
        if STOP.load(Ordering::SeqCst) {
            return false;
        }
        let now = Instant::now();
        if now >= end {
            return true;
        }
        std::thread::sleep((end - now).min(Duration::from_millis(10)));
    }
}

fn mono_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: valid pointer to a timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn unix_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// When an injection started: since the tool's start, Unix time, CLOCK_MONOTONIC (the supervisor's clock).
struct Stamp(f64, f64, f64);

fn print_injection(opts: &Opts, at: &Stamp, n: u64, service: &str, pid: i32, outcome: &str) {
    let Stamp(t, unix, mono) = *at;
    if opts.json {
        let v = serde_json::json!({
            "n": n, "t_s": t, "unix_s": unix, "mono_s": mono,
            "service": service, "pid": pid, "action": opts.action.name(),
            "detail": opts.action.detail(), "outcome": outcome,
        });
        println!("{v}");
    } else {
        println!(
            "phri-fault: {t:8.3} s  #{n}  {service} (pid {pid})  {}  {}  {outcome}",
            opts.action.name(),
            opts.action.detail()
        );
    }
}

/// Apply the action. SIGSTOPped processes are always continued on the way out.
fn apply(action: &Action, pid: i32) -> Result<String, String> {
    match *action {
        Action::Kill => send(pid, libc::SIGKILL).map(|_| "sent".into()),
        Action::Term => send(pid, libc::SIGTERM).map(|_| "sent".into()),
        Action::Freeze(s) => {
            send(pid, libc::SIGSTOP)?;
            let full = sleep_s(s);
            let cont = send(pid, libc::SIGCONT);
            match (full, cont) {
                (true, Ok(())) => Ok("continued".into()),
                (false, Ok(())) => Ok("interrupted, continued".into()),
                (_, Err(e)) => Ok(format!("gone before SIGCONT ({e})")),
            }
        }
        Action::Depth { .. } => Err("internal: depth faults are sent on fault/depth".into()),
        Action::Slow { percent, for_s } => {
            let slices = (for_s * 100.0).round() as u64;
            let mut acc = 0.0;
            let mut stopped = false;
            let start = Instant::now();
            let mut outcome = "done, continued".to_string();
            for i in 0..slices {
                acc += percent;
                let run = if acc >= 100.0 {
                    acc -= 100.0;
                    true
                } else {
                    false
                };
                if run == stopped {
                    let sig = if run { libc::SIGCONT } else { libc::SIGSTOP };
                    if let Err(e) = send(pid, sig) {
                        outcome =
                            format!("gone after {:.2} s ({e})", start.elapsed().as_secs_f64());
                        return Ok(outcome);
                    }
                    stopped = !run;
                }
                // absolute slice ends: no drift over a long --for
                let end = start + Duration::from_millis(10 * (i + 1));
                let now = Instant::now();
                if end > now && !sleep_s((end - now).as_secs_f64()) {
                    outcome = "interrupted, continued".into();
                    break;
                }
            }
            let _ = send(pid, libc::SIGCONT);
            Ok(outcome)
        }
    }
}

/// The publisher of depth faults, opened on first use with the cell's prefix.
struct FaultPort {
    node: IpcNode,
    publisher: Publisher<DepthFault>,
    seq: u64,
}

impl FaultPort {
    fn open(run_dir: &Path) -> Result<FaultPort, Fail> {
        let prefix = read_state(run_dir)?.prefix;
        let node = phri_ipc::node(&format!("phri-fault-{}", std::process::id()), &prefix)
            .map_err(|e| Fail::Cell(e.to_string()))?;
        let publisher = FAULT_DEPTH.publisher(&node).map_err(|e| {
            Fail::Cell(format!(
                "{e} (another phri-fault injecting into this cell?)"
            ))
        })?;
        Ok(FaultPort {
            node,
            publisher,
            seq: 0,
        })
    }

    fn send(&mut self, action: &Action) -> Result<String, String> {
        let Action::Depth {
            kind,
            frames,
            delay_ms,
            for_s,
        } = *action
        else {
            return Err("internal: not a depth fault".into());
        };
        self.seq += 1;
        let mut f = DepthFault::zeroed();
        f.seq = self.seq;
        f.stamp_ns = (mono_s() * 1e9) as u64;
        f.kind = kind.into();
        f.frames = frames;
        f.delay_ms = delay_ms;
        f.duration_s = for_s;
        let listeners = FAULT_DEPTH
            .ports(&self.node)
            .map_err(|e| e.to_string())?
            .map_or(0, |(_, subscribers)| subscribers);
        if listeners == 0 {
            return Err(format!(
                "{}: no camera listens (is the cell's camera the simulated one?)",
                FAULT_DEPTH.name
            ));
        }
        self.publisher.publish(&f).map_err(|e| e.to_string())?;
        // samples live in the publisher's memory: stay until the camera (which
        // polls once per frame) has surely taken it
        sleep_s(0.3);
        Ok("sent".into())
    }
}

fn run(opts: &Opts) -> Result<(), Fail> {
    let mut rng = Rng(opts.seed);
    let mut port: Option<FaultPort> = None;
    let t0 = Instant::now();
    let mut n = 0u64;
    loop {
        if opts.times != 0 && n >= opts.times {
            return Ok(());
        }
        let wait = if let Some(e) = opts.every {
            e
        } else if let Some((a, b)) = opts.random {
            a + (b - a) * rng.unit()
        } else if n == 0 {
            0.0
        } else {
            1.0
        };
        if let Some(u) = opts.until {
            if t0.elapsed().as_secs_f64() + wait > u {
                // the next injection would fall after --until: sleep out the window and stop
                let _ = sleep_s(u - t0.elapsed().as_secs_f64());
                return Ok(());
            }
        }
        if !sleep_s(wait) {
            return Ok(());
        }
        if opts.times == 0 && !opts.run_dir.join("state.json").exists() {
            // unbounded mode ends with the run: the supervisor removes state.json
            eprintln!(
                "phri-fault: {} gone: the run ended",
                opts.run_dir.join("state.json").display()
            );
            return Ok(());
        }
        let (service, pid) = choose(opts, &mut rng)?;
        n += 1;
        let at = Stamp(t0.elapsed().as_secs_f64(), unix_s(), mono_s());
        let outcome = if let Action::Depth { .. } = opts.action {
            if port.is_none() {
                port = Some(FaultPort::open(&opts.run_dir)?);
            }
            let p = port
                .as_mut()
                .ok_or_else(|| Fail::Cell("no fault port".into()))?;
            p.send(&opts.action)
        } else {
            apply(&opts.action, pid)
        }
        .map_err(|e| Fail::Cell(format!("{service}: pid {pid}: {e}")))?;
        print_injection(opts, &at, n, &service, pid, &outcome);
    }
}

fn main() -> ExitCode {
    let opts = match parse_cli(std::env::args_os()) {
        Ok(Cli {
            completions: Some(CompletionsCmd::Completions { shell }),
            ..
        }) => {
            phri_runtime::cli::completions::<Cli>(BIN, shell);
            return ExitCode::SUCCESS;
        }
        Ok(cli) => options(cli),
        Err(e) => Err(e),
    };
    let opts = match opts {
        Ok(o) => o,
        Err(Fail::Usage(m)) => {
            eprintln!("{BIN}: {m}");
            return ExitCode::from(1);
        }
        Err(Fail::Cell(m)) => {
            eprintln!("{BIN}: {m}");
            return ExitCode::from(2);
        }
    };
    // SAFETY: the handler only stores to an atomic.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
    match run(&opts) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Fail::Usage(m)) => {
            eprintln!("phri-fault: {m}");
            ExitCode::from(1)
        }
        Err(Fail::Cell(m)) => {
            eprintln!("phri-fault: {m}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// clap's own consistency checks (names, conflicts, positionals), which
    /// release builds skip at run time.
    #[test]
    fn the_command_is_consistent() {
        super::Cli::command().debug_assert();
    }
}
