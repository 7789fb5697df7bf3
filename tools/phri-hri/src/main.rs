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

use std::process::ExitCode;
use std::time::{Duration, Instant};

use phri_ipc::{
    CollabPart, CollabPhase, CollabReason, CollabState, HriRequest, IpcNode, Queue, RequestKind,
    RequestSource, Zeroed, COLLAB_STATE, HRI_REQUEST, REQUEST_TEXT,
};
use phri_runtime::now_ns;

const USAGE: &str = "usage: phri-hri [--prefix P] request KIND [PART] [--person ID] [--text T] [--wait SECONDS] [--json]
       phri-hri [--prefix P] watch [--once] [--seconds S] [--json]
  request KIND [PART]  ask the robot: begin|follow right_hand|left_hand, end, stop
                       (begin/follow without PART: the part last used)
    --person ID        the tracker's id of the person asking (default: whoever shows the part)
    --text T           what was asked, for the report (default: the command)
    --wait SECONDS     wait this long for the controller's answer on collab/state (default 1)
  watch                print the collaboration state when it changes (Ctrl-C ends)
    --once             print the current state once and exit
    --seconds S        end after S seconds
  --prefix P           the cell's iceoryx2 prefix (default: $PHRI_PREFIX, else phri_)
  --json               JSON instead of text lines
exit status: 0 done (accepted), 1 usage, 2 no cell or no answer, 3 refused";

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
}

struct Args {
    prefix: String,
    json: bool,
    command: Command,
}

/// One clear line for a bad command line.
struct Usage(String);

fn number<T: std::str::FromStr>(flag: &str, v: Option<&String>) -> Result<T, Usage> {
    let v = v.ok_or_else(|| Usage(format!("{flag}: a value is missing")))?;
    v.parse()
        .map_err(|_| Usage(format!("{flag}: '{v}' is not a valid number")))
}

fn seconds(flag: &str, v: Option<&String>) -> Result<f64, Usage> {
    let s: f64 = number(flag, v)?;
    if !(0.0..=86_400.0).contains(&s) {
        return Err(Usage(format!("{flag}: {s} is not between 0 and 86400 s")));
    }
    Ok(s)
}

fn parse(argv: &[String]) -> Result<Args, Usage> {
    let mut prefix = None;
    let mut json = false;
    let mut positional = Vec::new();
    let (mut person, mut text, mut wait_s) = (u32::MAX, None, 1.0);
    let (mut once, mut secs) = (false, None);
    let mut it = argv.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--prefix" => {
                prefix = Some(
                    it.next()
                        .ok_or_else(|| Usage("--prefix: a value is missing".into()))?
                        .clone(),
                )
            }
            "--json" => json = true,
            "--person" => person = number("--person", it.next())?,
            "--text" => {
                text = Some(
                    it.next()
                        .ok_or_else(|| Usage("--text: a value is missing".into()))?
                        .clone(),
                )
            }
            "--wait" => wait_s = seconds("--wait", it.next())?,
            "--once" => once = true,
            "--seconds" => secs = Some(seconds("--seconds", it.next())?),
            s if s.starts_with("--") => return Err(Usage(format!("{s}: unknown flag"))),
            s => positional.push(s.to_string()),
        }
    }
    let prefix = phri_runtime::prefix_or_default(prefix.as_deref());
    let command = match positional.first().map(String::as_str) {
        Some("request") => {
            let kind = positional.get(1).ok_or_else(|| {
                Usage("request: KIND is missing (begin, follow, end, stop)".into())
            })?;
            let kind = RequestKind::from_name(kind).map_err(|e| Usage(e.to_string()))?;
            let part = match positional.get(2) {
                Some(p) => CollabPart::from_name(p).map_err(|e| Usage(e.to_string()))?,
                None => CollabPart::None,
            };
            if positional.len() > 3 {
                return Err(Usage(format!("request: unexpected '{}'", positional[3])));
            }
            if matches!(kind, RequestKind::End | RequestKind::Stop) && part != CollabPart::None {
                return Err(Usage(format!("request {}: takes no part", kind.name())));
            }
            let text = text.unwrap_or_else(|| positional[1..].join(" "));
            if text.len() >= REQUEST_TEXT {
                return Err(Usage(format!("--text: at most {} bytes", REQUEST_TEXT - 1)));
            }
            Command::Request {
                kind,
                part,
                person,
                text,
                wait_s,
            }
        }
        Some("watch") => {
            if positional.len() > 1 {
                return Err(Usage(format!("watch: unexpected '{}'", positional[1])));
            }
            Command::Watch {
                once,
                seconds: secs,
            }
        }
        Some(other) => return Err(Usage(format!("{other}: unknown command (request, watch)"))),
        None => return Err(Usage("a command is missing (request, watch)".into())),
    };
    Ok(Args {
        prefix,
        json,
        command,
    })
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
        } => {
            let states = COLLAB_STATE
                .subscriber_if_exists(&node, Queue::Latest)
                .map_err(|e| e.to_string())?;
            let Some(states) = states else {
                return Err(format!(
                    "{}: not sent: {} does not exist, no controller would answer (is the cell of prefix {} running?)",
                    HRI_REQUEST.name, COLLAB_STATE.name, args.prefix
                ));
            };
            let publisher = HRI_REQUEST.publisher(&node).map_err(|e| e.to_string())?;
            let r = request(kind, part, person, &text);
            publisher.publish(&r).map_err(|e| e.to_string())?;
            let t0 = Instant::now();
            while t0.elapsed().as_secs_f64() < wait_s {
                if let Some(s) = states.latest().map_err(|e| e.to_string())? {
                    if s.request_source == RequestSource::Cli as u32 && s.request_seq == r.seq {
                        print(&s, args.json);
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
        Command::Watch { once, seconds } => {
            let t0 = Instant::now();
            let over = |t0: Instant| seconds.is_some_and(|s| t0.elapsed().as_secs_f64() >= s);
            // the controller may not have started yet
            let states = loop {
                if let Some(s) = COLLAB_STATE
                    .subscriber_if_exists(&node, Queue::Latest)
                    .map_err(|e| e.to_string())?
                {
                    break s;
                }
                if once || over(t0) {
                    return Err(format!(
                        "{} does not exist (is the cell of prefix {} running?)",
                        COLLAB_STATE.name, args.prefix
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
                    let forces_due =
                        s.n_forces > 0 && last_forces.elapsed() >= Duration::from_millis(200);
                    if last != Some(key) || forces_due || once {
                        print(&s, args.json);
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
    }
}

fn main() -> ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    if argv.iter().any(|a| a == "--help" || a == "-h") {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    let args = match parse(&argv) {
        Ok(a) => a,
        Err(Usage(e)) => {
            eprintln!("phri-hri: {e}\n{USAGE}");
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
