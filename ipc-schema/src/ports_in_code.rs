//! Keeps [`crate::ports::PORTS`] honest: reads the sources of every binary
//! it lists and compares the channels they open (`X.publisher(`,
//! `X.subscriber(`, `X.latest_reader(`, …) with the entry's, both ways.
//! A receiver that is a variable (`command_channel.publisher(`) is resolved
//! by [`ALIASES`]; an unknown one fails the test, naming the place.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::channels::*;
use crate::ports::SUPERVISED;

/// The files whose code opens each binary's ports, from the workspace root
/// (a path ending in `/`: every `.rs` file under that folder).
const FILES: &[(&str, &[&str])] = &[
    ("phri-sim", &["services/sim/src/main.rs"]),
    ("phri-franka", &["services/franka/src/main.rs"]),
    ("phri-dynamics", &["services/dynamics/src/main.rs"]),
    (
        "phri-control",
        &[
            "services/control/src/main.rs",
            "services/control/src/service/",
        ],
    ),
    (
        "phri-camera",
        &[
            "services/perception/src/bin/camera.rs",
            "services/perception/src/live.rs",
        ],
    ),
    (
        "phri-freenect",
        &[
            "services/freenect/src/main.rs",
            "services/perception/src/live.rs",
        ],
    ),
    (
        "phri-camera-ros2",
        &[
            "services/ros2/src/camera/main.rs",
            "services/ros2/src/camera.rs",
            "services/perception/src/live.rs",
        ],
    ),
    (
        "phri-perception",
        &["services/perception/src/bin/ingest.rs"],
    ),
    ("phri-tracker", &["services/perception/src/bin/tracker.rs"]),
    (
        "phri-repulsion",
        &["services/perception/src/bin/repulsion.rs"],
    ),
    ("phri-gesture", &["services/gesture/src/main.rs"]),
    ("phri-mic", &["services/voice/src/bin/mic.rs"]),
    ("phri-voice", &["services/voice/src/main.rs"]),
    ("phri-ros2", &["services/ros2/src/main.rs"]),
    (
        "phri-supervisor",
        &[
            "services/supervisor/src/main.rs",
            "services/supervisor/src/run/",
        ],
    ),
    ("phri-fault", &["tools/phri-fault/src/main.rs"]),
    ("phri-hri", &["tools/phri-hri/src/main.rs"]),
];

/// The file of the dead-man thread every supervised service runs ([`SUPERVISED`]).
const RUNTIME: &str = "crates/runtime/src/service.rs";

/// Variables that hold a channel: (file, variable, the channels it may be).
const ALIASES: &[(&str, &str, &[&str])] = &[
    (
        "services/control/src/service/channels.rs",
        "command_channel",
        &[ROBOT_COMMAND.name, ROBOT_COMMAND_STANDBY.name],
    ),
    (
        "services/control/src/service/channels.rs",
        "own_behaviour",
        &[CONTROL_BEHAVIOUR.name, CONTROL_STANDBY_BEHAVIOUR.name],
    ),
    (
        "services/control/src/service/channels.rs",
        "peer_behaviour",
        &[CONTROL_BEHAVIOUR.name, CONTROL_STANDBY_BEHAVIOUR.name],
    ),
    (
        "services/dynamics/src/main.rs",
        "channel",
        &[DYNAMICS_RESIDUAL.name, DYNAMICS_RESIDUAL_STANDBY.name],
    ),
    (
        "services/perception/src/live.rs",
        "channel",
        &[CAMERA_DEPTH.name],
    ),
];

/// The methods that open a port, and whether the port publishes.
const OPENERS: &[(&str, bool)] = &[
    ("publisher", true),
    ("frame_publisher", true),
    ("subscriber", false),
    ("waking_subscriber", false),
    ("subscriber_if_exists", false),
    ("latest_reader", false),
    ("frame_subscriber", false),
    ("waking_frame_subscriber", false),
    ("frame_subscriber_if_exists", false),
];

macro_rules! constants {
    ($($c:ident),* $(,)?) => {
        &[$((stringify!($c), $c.name)),*]
    };
}

/// Every channel constant by its identifier.
const CONSTANTS: &[(&str, &str)] = constants![
    ROBOT_STATE,
    ROBOT_STATE_STANDBY,
    DYNAMICS_RESIDUAL_CALL,
    ROBOT_COMMAND,
    ROBOT_COMMAND_STANDBY,
    ROBOT_COMMANDERS,
    ROBOT_STATS,
    ROBOT_BOX,
    CAMERA_STATUS,
    AUDIO_MIC_STATUS,
    ROS2_REQUESTS,
    SIM_TRUTH,
    DYNAMICS_RESIDUAL,
    DYNAMICS_RESIDUAL_STANDBY,
    CONTROL_STATUS,
    CONTROL_BEHAVIOUR,
    CONTROL_STANDBY_BEHAVIOUR,
    SUPERVISOR_HEALTH,
    SUPERVISOR_HEALTH_MORE,
    SIM_WORLD,
    CAMERA_DEPTH,
    PERCEPTION_DEPTH,
    PERCEPTION_REPULSION,
    SIM_CONTACTS,
    PERCEPTION_SKELETON,
    PERCEPTION_HAND,
    HRI_REQUEST,
    COLLAB_STATE,
    CONTROL_SSM,
    CONTROL_BARRIER,
    AUDIO_MIC,
    VOICE_UTTERANCE,
    INPUT_AUDIT,
    FAULT_DEPTH,
];

/// A camera's channels as fields of [`CameraChannels`], by the first camera's names.
const CAMERA_FIELDS: &[(&str, &str)] = &[
    ("depth", CAMERA_DEPTH.name),
    ("perception", PERCEPTION_DEPTH.name),
    ("repulsion", PERCEPTION_REPULSION.name),
    ("skeleton", PERCEPTION_SKELETON.name),
    ("hand", PERCEPTION_HAND.name),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The code of `text` without comments, whitespace around `.` removed (a
/// chain over several lines reads as one) and other whitespace runs as one
/// space, with the line each character came from.
fn code(text: &str) -> (Vec<char>, Vec<usize>) {
    let mut chars: Vec<(char, usize)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split("//").next().unwrap_or("");
        chars.extend(line.chars().map(|c| (c, n + 1)));
        chars.push((' ', n + 1));
    }
    let mut out: Vec<(char, usize)> = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let (c, n) = chars[i];
        if c.is_whitespace() {
            let mut j = i;
            while j < chars.len() && chars[j].0.is_whitespace() {
                j += 1;
            }
            let next_dot = chars.get(j).is_some_and(|(c, _)| *c == '.');
            let prev_dot = out.last().is_some_and(|(c, _)| *c == '.');
            if !next_dot && !prev_dot {
                out.push((' ', n));
            }
            i = j;
        } else {
            out.push((c, n));
            i += 1;
        }
    }
    out.into_iter().unzip()
}

/// A port one file opens: the channel, whether it publishes, and where.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Opened {
    channel: &'static str,
    publishes: bool,
    line: usize,
}

/// Every port `file` opens (every channel an alias may be).
fn opened_in(file: &str) -> Result<Vec<Opened>, String> {
    let text = std::fs::read_to_string(root().join(file)).map_err(|e| format!("{file}: {e}"))?;
    let (chars, lines) = code(&text);
    let s: String = chars.iter().collect();
    let mut found = Vec::new();
    for (method, publishes) in OPENERS {
        let pattern = format!(".{method}(");
        let mut from = 0;
        while let Some(at) = s[from..].find(&pattern) {
            let dot = from + at;
            from = dot + pattern.len();
            let start = s[..dot]
                .rfind(|c: char| !(c.is_alphanumeric() || c == '_' || c == '.' || c == ':'))
                .map_or(0, |i| i + 1);
            let receiver = &s[start..dot];
            let line = lines[s[..dot].chars().count()];
            let last = receiver.rsplit(['.', ':']).next().unwrap_or(receiver);
            let channels: Vec<&'static str> =
                if let Some((_, c)) = CONSTANTS.iter().find(|(id, _)| *id == last) {
                    vec![*c]
                } else if let Some((_, c)) = CAMERA_FIELDS
                    .iter()
                    .find(|(f, _)| *f == last && receiver.contains('.'))
                {
                    vec![*c]
                } else if let Some((_, _, c)) = ALIASES
                    .iter()
                    .find(|(f, v, _)| *f == file && *v == receiver)
                {
                    c.to_vec()
                } else {
                    return Err(format!(
                        "{file}:{line}: `{receiver}.{method}(`: which channel is `{receiver}`? \
                         Add it to ALIASES in ipc-schema/src/ports_in_code.rs"
                    ));
                };
            found.extend(channels.into_iter().map(|channel| Opened {
                channel,
                publishes: *publishes,
                line,
            }));
        }
    }
    if s.contains(".watch_inputs()") {
        found.push(Opened {
            channel: INPUT_AUDIT.name,
            publishes: true,
            line: 0,
        });
    }
    found.sort();
    Ok(found)
}

fn set<'a>(names: impl IntoIterator<Item = &'a &'static str>) -> BTreeSet<&'static str> {
    names.into_iter().copied().collect()
}

#[test]
fn every_channel_constant_is_known_to_the_scan() {
    let known = set(CONSTANTS.iter().map(|(_, c)| c));
    assert_eq!(
        known,
        set(ALL),
        "CONSTANTS must list every channel of channels::ALL"
    );
}

#[test]
fn each_binary_opens_exactly_the_channels_its_entry_lists() {
    let mut wrong = Vec::new();
    for (binary, files) in FILES {
        let mut opened: Vec<Opened> = Vec::new();
        for f in expand(files) {
            opened.extend(opened_in(&f).unwrap_or_else(|e| panic!("{e}")));
        }
        let entries: Vec<_> = crate::ports::of(binary).collect();
        assert!(!entries.is_empty(), "{binary}: no entry in ports::PORTS");
        for publishes in [true, false] {
            let code: BTreeSet<&str> = opened
                .iter()
                .filter(|o| o.publishes == publishes)
                .map(|o| o.channel)
                .collect();
            let listed: BTreeSet<&str> = entries
                .iter()
                .flat_map(|p| match publishes {
                    true => p.publishes,
                    false => p.reads,
                })
                .copied()
                .collect();
            let verb = if publishes { "publishes" } else { "reads" };
            for c in code.difference(&listed) {
                let at: Vec<String> = opened
                    .iter()
                    .filter(|o| o.channel == *c && o.publishes == publishes)
                    .map(|o| o.line.to_string())
                    .collect();
                wrong.push(format!(
                    "{binary} {verb} {c} (line {} of {files:?}) but ports::PORTS does not say so",
                    at.join(", ")
                ));
            }
            for c in listed.difference(&code) {
                wrong.push(format!(
                    "ports::PORTS says {binary} {verb} {c}, but its code ({files:?}) never opens it"
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn every_supervised_service_reads_the_health_and_may_audit() {
    let opened = opened_in(RUNTIME).unwrap_or_else(|e| panic!("{e}"));
    let reads = set(opened.iter().filter(|o| !o.publishes).map(|o| &o.channel));
    let publishes = set(opened.iter().filter(|o| o.publishes).map(|o| &o.channel));
    assert_eq!(reads, set(SUPERVISED.reads));
    assert_eq!(publishes, set([&INPUT_AUDIT.name]));
}

/// Every `.rs` file under `dir`, recursively, sorted.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `files` with each folder replaced by its `.rs` files, from the workspace root.
fn expand(files: &[&str]) -> Vec<String> {
    let root = root();
    let mut out = Vec::new();
    for f in files {
        if f.ends_with('/') {
            let mut found = Vec::new();
            rust_files(&root.join(f), &mut found);
            out.extend(found.iter().map(|p| relative(&root, p)));
        } else {
            out.push(f.to_string());
        }
    }
    out
}

fn relative(root: &Path, path: &Path) -> String {
    path.strip_prefix(root)
        .unwrap_or(path)
        .to_string_lossy()
        .to_string()
}

#[test]
fn no_service_file_opens_ports_unlisted() {
    // a new file of a service that opens a channel must be one of FILES
    let claimed: BTreeSet<String> = FILES
        .iter()
        .flat_map(|(_, f)| expand(f))
        .chain([RUNTIME.to_string()])
        .collect();
    let root = root();
    let mut files = Vec::new();
    for dir in ["services", "crates/runtime/src"] {
        rust_files(&root.join(dir), &mut files);
    }
    let mut unclaimed = Vec::new();
    for path in files {
        let rel = relative(&root, &path);
        if claimed.contains(&rel) || rel.contains("/tests/") || rel.contains("/benches/") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let (chars, _) = code(&text);
        let s: String = chars.iter().collect();
        if OPENERS.iter().any(|(m, _)| {
            let p = format!(".{m}(&");
            s.contains(&p) || s.contains(&format!(".{m}(node"))
        }) {
            unclaimed.push(rel);
        }
    }
    assert!(
        unclaimed.is_empty(),
        "these files open channels but belong to no binary of ports_in_code::FILES: {unclaimed:?}"
    );
}
