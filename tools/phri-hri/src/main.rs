//! `phri-hri`: collaboration requests from a command line or a script, and
//! the collaboration state as the controller runs it.
//!
//! `request` publishes one `HriRequest` (source `cli`) on `hri/request` and
//! waits for the controller's answer on `collab/state` (the request's
//! sequence number is its send time, unique per sender). `watch` prints the
//! collaboration phase, the last request's answer and the estimated contact
//! forces whenever one of them changes.
//!
//! Exit status: 0 done (request accepted), 1 usage, 2 the cell cannot be
//! reached or did not answer, 3 the request was refused (the reason is printed).
//! `phri-hri completions bash|zsh|fish` prints a shell completion script.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use phri_ipc::{
    CollabPart, CollabPhase, CollabReason, CollabState, HriRequest, IpcNode, Queue, RequestKind,
    RequestSource, Zeroed, COLLAB_STATE, HRI_REQUEST, REQUEST_TEXT,
};
use phri_runtime::now_ns;

const BIN: &str = "phri-hri";

/// Examples and exit statuses, after the flags in `--help`.
const AFTER_HELP: &str = "Examples:
  phri-hri request follow right_hand
  phri-hri request end
  phri-hri watch --once --json

Exit status: 0 done (accepted), 1 usage, 2 no cell or no answer, 3 refused";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Collaboration requests from the command line (hri/request) and the collaboration state (collab/state)",
    after_help = AFTER_HELP,
    args_override_self = true
)]
struct Cli {
    /// The cell's iceoryx2 prefix [default: phri_]
    #[arg(long, value_name = "P", env = phri_runtime::PREFIX_ENV, global = true)]
    prefix: Option<String>,
    /// JSON instead of text lines
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Ask the robot: begin|follow right_hand|left_hand, end, stop; wait for the controller's answer
    Request {
        /// What is asked (begin/follow without PART: the part last used)
        #[arg(value_name = "KIND", value_parser = kind_parser())]
        kind: RequestKind,
        /// The collaborative part to begin or follow
        #[arg(value_name = "PART", value_parser = part_parser())]
        part: Option<CollabPart>,
        /// The tracker's id of the person asking (default: whoever shows the part)
        #[arg(long, value_name = "ID")]
        person: Option<u32>,
        /// What was asked, for the report (default: the command)
        #[arg(long, value_name = "T")]
        text: Option<String>,
        /// How long to wait for the controller's answer on collab/state \[s\]
        #[arg(
            long,
            value_name = "SECONDS",
            default_value_t = 1.0,
            allow_negative_numbers = true,
            value_parser = seconds
        )]
        wait: f64,
    },
    /// Resume a cell its dead-man stopped (no supervisor was heard): the
    /// supervisor starts its services again; waits until every one runs
    Resume {
        /// How long to wait for every service to run again \[s\]
        #[arg(
            long,
            value_name = "SECONDS",
            default_value_t = 10.0,
            allow_negative_numbers = true,
            value_parser = seconds
        )]
        wait: f64,
    },
    /// Print the collaboration state when it changes (Ctrl-C ends)
    Watch {
        /// Print the current state once and exit
        #[arg(long)]
        once: bool,
        /// End after this long \[s\]
        #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = seconds)]
        seconds: Option<f64>,
    },
    /// Print a shell completion script to stdout (bash, zsh, fish, elvish or powershell)
    Completions {
        /// Shell to write the script for
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

fn kind_parser() -> impl TypedValueParser<Value = RequestKind> {
    PossibleValuesParser::new(RequestKind::ALL.iter().map(|k| k.name()))
        .try_map(|s| RequestKind::from_name(&s))
}

fn part_parser() -> impl TypedValueParser<Value = CollabPart> {
    PossibleValuesParser::new(CollabPart::ALL.iter().map(|p| p.name()))
        .try_map(|s| CollabPart::from_name(&s))
}

/// A duration between 0 and one day \[s\].
fn seconds(v: &str) -> Result<f64, String> {
    let s: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("'{v}' is not a valid number"))?;
    if !(0.0..=86_400.0).contains(&s) {
        return Err(format!("{s} is not between 0 and 86400 s"));
    }
    Ok(s)
}

enum Command {
    Request {
        kind: RequestKind,
        part: CollabPart,
        person: u32,
        text: String,
        wait_s: f64,
    },
    Watch {
        once: bool,
        seconds: Option<f64>,
    },
    Resume {
        wait_s: f64,
    },
}

struct Args {
    prefix: String,
    json: bool,
    command: Command,
}

/// What the command line asks for.
enum Parsed {
    Run(Args),
    Completions(clap_complete::Shell),
}

/// Parse `argv` (the first is the program name): `--help`/`--version` print
/// and exit 0 here, no command prints the help and exits 1; `Err` is the one
/// line of a bad command line (exit 1).
fn parse(argv: impl IntoIterator<Item = std::ffi::OsString>) -> Result<Parsed, String> {
    let cli = Cli::command()
        .name(BIN)
        .bin_name(BIN)
        .try_get_matches_from(argv)
        .and_then(|mut m| Cli::from_arg_matches_mut(&mut m))
        .map_err(|e| match e.kind() {
            clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                e.exit()
            }
            // no command at all: the help on stderr, exit 1 (usage)
            clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                let _ = e.print();
                std::process::exit(1)
            }
            _ => phri_runtime::cli::one_line(&e),
        })?;
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let command = match cli.command {
        Cmd::Completions { shell } => return Ok(Parsed::Completions(shell)),
        Cmd::Request {
            kind,
            part,
            person,
            text,
            wait,
        } => {
            // the default text: the command as typed
            let typed = match part {
                None => kind.name().to_string(),
                Some(p) => format!("{} {}", kind.name(), p.name()),
            };
            let part = part.unwrap_or(CollabPart::None);
            if kind == RequestKind::Resume {
                return Err(
                    "request resume: the supervisor's, not the controller's: use 'phri-hri resume'"
                        .into(),
                );
            }
            if matches!(kind, RequestKind::End | RequestKind::Stop) && part != CollabPart::None {
                return Err(format!("request {}: takes no part", kind.name()));
            }
            let text = text.unwrap_or(typed);
            if text.len() >= REQUEST_TEXT {
                return Err(format!("--text: at most {} bytes", REQUEST_TEXT - 1));
            }
            Command::Request {
                kind,
                part,
                person: person.unwrap_or(u32::MAX),
                text,
                wait_s: wait,
            }
        }
        Cmd::Watch { once, seconds } => Command::Watch { once, seconds },
        Cmd::Resume { wait } => Command::Resume { wait_s: wait },
    };
    Ok(Parsed::Run(Args {
        prefix,
        json: cli.json,
        command,
    }))
}

/// The request as sent: source `cli`, sequence number = send time.
fn request(kind: RequestKind, part: CollabPart, person: u32, text: &str) -> HriRequest {
    let mut r = HriRequest::zeroed();
    let now = now_ns();
    r.seq = now;
    r.stamp_ns = now;
    r.source = RequestSource::Cli as u32;
    r.kind = kind as u32;
    r.part = part as u32;
    r.person = person;
    r.confidence = 1.0;
    r.text = phri_ipc::json::to_c_str(text);
    r
}

/// One text line of a collaboration state.
fn line(s: &CollabState) -> String {
    let mut out = format!(
        "phase {} ({}), part {}",
        CollabPhase::name_of(s.phase),
        CollabReason::name_of(s.reason),
        CollabPart::name_of(s.human_part)
    );
    if s.request_source != 0 {
        out.push_str(&format!(
            "; last request {} {} from {}: {} ({})",
            RequestKind::name_of(s.request_kind),
            CollabPart::name_of(s.request_part),
            RequestSource::name_of(s.request_source),
            if s.request_accepted != 0 {
                "accepted"
            } else {
                "refused"
            },
            CollabReason::name_of(s.request_reason)
        ));
    }
    let n = (s.n_forces as usize).min(s.forces.len());
    for f in &s.forces[..n] {
        let norm = f.force.iter().map(|x| x * x).sum::<f64>().sqrt();
        out.push_str(&format!(
            "; F̂ {:.1} N [{:.1}, {:.1}, {:.1}]{}",
            norm,
            f.force[0],
            f.force[1],
            f.force[2],
            if f.observable != 0 {
                ""
            } else {
                " (not observable)"
            }
        ));
    }
    out
}

fn print(s: &CollabState, json: bool) {
    if json {
        println!("{}", phri_ipc_json::to_json(s));
    } else {
        println!("{}", line(s));
    }
}

fn node(prefix: &str) -> Result<IpcNode, String> {
    phri_ipc::node(&format!("phri-hri-{}", std::process::id()), prefix)
        .map_err(|e| format!("prefix {prefix}: {e}"))
}

fn run(args: Args) -> Result<ExitCode, String> {
    let node = node(&args.prefix)?;
    match args.command {
        Command::Request {
            kind,
            part,
            person,
            text,
            wait_s,
        } => send(
            &node,
            &args.prefix,
            args.json,
            request(kind, part, person, &text),
            wait_s,
        ),
        Command::Resume { wait_s } => resume(&node, &args.prefix, wait_s),
        Command::Watch { once, seconds } => watch(&node, &args.prefix, args.json, once, seconds),
    }
}

/// Send request `r` on hri/request and wait up to `wait_s` \[s\] for the
/// controller's answer on collab/state: exit 0 accepted, 3 refused.
fn send(
    node: &IpcNode,
    prefix: &str,
    json: bool,
    r: HriRequest,
    wait_s: f64,
) -> Result<ExitCode, String> {
    let states = COLLAB_STATE
        .subscriber_if_exists(node, Queue::Latest)
        .map_err(|e| e.to_string())?;
    let Some(states) = states else {
        return Err(format!(
            "{}: not sent: {} does not exist, no controller would answer (is the cell of prefix {} running?)",
            HRI_REQUEST.name, COLLAB_STATE.name, prefix
        ));
    };
    let publisher = HRI_REQUEST.publisher(node).map_err(|e| e.to_string())?;
    publisher.publish(&r).map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < wait_s {
        if let Some(s) = states.latest().map_err(|e| e.to_string())? {
            if s.request_source == RequestSource::Cli as u32 && s.request_seq == r.seq {
                print(&s, json);
                return Ok(if s.request_accepted != 0 {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::from(3)
                });
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    Err(format!(
        "{}: no answer to the request on {} within {wait_s} s",
        HRI_REQUEST.name, COLLAB_STATE.name
    ))
}

/// Ask the supervisor to resume the cell after a protective stop that
/// needs it, and wait up to `wait_s` \[s\] for every service to run again.
fn resume(node: &IpcNode, prefix: &str, wait_s: f64) -> Result<ExitCode, String> {
    // the supervisor's channel, found within the wait (a supervisor
    // just back from a stall may still be cleaning up its dead
    // services: on a loaded machine that took over 2 s)
    let t0 = Instant::now();
    let health = loop {
        let found = phri_ipc::SUPERVISOR_HEALTH.subscriber_if_exists(node, Queue::Latest);
        match found {
            Ok(Some(h)) => break h,
            _ if t0.elapsed().as_secs_f64() < wait_s.min(5.0) => {
                std::thread::sleep(Duration::from_millis(50));
            }
            Ok(None) => {
                return Err(format!(
                    "{}: not sent: no supervisor runs the cell of prefix {}",
                    HRI_REQUEST.name, prefix
                ))
            }
            Err(e) => return Err(e.to_string()),
        }
    };
    let publisher = HRI_REQUEST.publisher(node).map_err(|e| e.to_string())?;
    publisher
        .publish(&request(
            RequestKind::Resume,
            CollabPart::None,
            u32::MAX,
            "resume",
        ))
        .map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < wait_s {
        if let Some(h) = health.latest().map_err(|e| e.to_string())? {
            let n = (h.count as usize).min(h.services.len());
            if n > 0 && h.services[..n].iter().all(|s| s.alive != 0) {
                println!("resumed: {n} services run");
                return Ok(ExitCode::SUCCESS);
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Err(format!(
        "{}: the services did not all run again within {wait_s} s",
        phri_ipc::SUPERVISOR_HEALTH.name
    ))
}

/// Print collab/state's changes (forces at most 5 times a second) until
/// `seconds` \[s\] passed (forever: `None`); `once`: the newest state only.
fn watch(
    node: &IpcNode,
    prefix: &str,
    json: bool,
    once: bool,
    seconds: Option<f64>,
) -> Result<ExitCode, String> {
    let t0 = Instant::now();
    let over = |t0: Instant| seconds.is_some_and(|s| t0.elapsed().as_secs_f64() >= s);
    // the controller may not have started yet
    let states = loop {
        if let Some(s) = COLLAB_STATE
            .subscriber_if_exists(node, Queue::Latest)
            .map_err(|e| e.to_string())?
        {
            break s;
        }
        if once || over(t0) {
            return Err(format!(
                "{} does not exist (is the cell of prefix {} running?)",
                COLLAB_STATE.name, prefix
            ));
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let mut last: Option<(u32, u32, u32, u64, bool)> = None;
    let mut last_forces = Instant::now();
    loop {
        if let Some(s) = states.latest().map_err(|e| e.to_string())? {
            let key = (
                s.phase,
                s.reason,
                s.human_part,
                s.request_seq,
                s.request_accepted != 0,
            );
            // forces change every cycle: at most 5 lines a second for them
            let forces_due = s.n_forces > 0 && last_forces.elapsed() >= Duration::from_millis(200);
            if last != Some(key) || forces_due || once {
                print(&s, json);
                last = Some(key);
                last_forces = Instant::now();
            }
            if once {
                return Ok(ExitCode::SUCCESS);
            }
        } else if once && t0.elapsed() > Duration::from_secs(1) {
            return Err(format!(
                "{}: no state within 1 s (is the controller running?)",
                COLLAB_STATE.name
            ));
        }
        if over(t0) {
            return Ok(ExitCode::SUCCESS);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn main() -> ExitCode {
    let args = match parse(std::env::args_os()) {
        Ok(Parsed::Run(a)) => a,
        Ok(Parsed::Completions(shell)) => {
            phri_runtime::cli::completions::<Cli>(BIN, shell);
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("{BIN}: {e}");
            return ExitCode::from(1);
        }
    };
    let prefix = args.prefix.clone();
    match run(args) {
        Ok(code) => code,
        Err(e) => {
            // no cell there: take back the node counter our node left
            // (nothing is removed while any node of the prefix lives)
            let _ = phri_ipc::remove_leftovers(&prefix);
            eprintln!("phri-hri: {e}");
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
