//! Scenarios: a named run of the cell with an optional scripted human and
//! configuration overrides (merged by [`crate::Loaded::load`]), read from TOML.
//!
//! ```toml
//! name = "collision"                 # the only required field
//! description = "a person walks into the moving forearm"   # default ""
//! duration_s = 16.0                  # default run length [s], default 60
//!
//! [human]                            # optional: no table, no human
//! floor_z = -0.8                     # soles' height in the robot base frame [m], default -0.8
//! collaborative_parts = ["hand_right"]   # contacts of these parts (with any robot link) are
//!                                    # intended, all others collisions; default none
//! repeat_s = 30.0                    # optional: the script starts over every 30 s, default: plays once
//!
//! [[human.keyframe]]                 # at least one; strictly increasing t
//! t = 0.0                            # [s]
//! base = [1.2, 0.0, 3.14159]         # floor x, y [m] and heading yaw [rad], base frame
//! right_hand = [0.4, 0.1, 0.5]       # optional hand target [m], base frame; absent: hangs
//! left_hand = [0.4, -0.1, 0.5]       # optional
//! right_foot = [0.9, 0.1, -0.5]      # optional ankle target [m], base frame (a raised leg,
//! left_foot = [0.9, -0.1, -0.5]      #   knee bent forward); absent: stands straight
//! # optional actions, from this keyframe until the next one (the last
//! # keyframe's: until the script ends or starts over):
//! wave = { hand = "right", frequency_hz = 1.5, amplitude_m = 0.12 }
//! #   the hand ("right" | "left") is raised above its elbow and swings along
//! #   the person's left-right axis: frequency in (0, 5] Hz, peak amplitude
//! #   in (0, 0.5] m about the elbow; blends in and out over 0.5 s
//! push = { link = "flange", point = [0.0, 0.0, 0.04], force_n = 30.0, part = "right_hand", intended = true }
//! #   the simulator pushes robot link `link` (a link of the URDF, or a role
//! #   that fits every arm: "wrist", the arm's collaboration.wrist_link;
//! #   "flange", its control.ee_link) at `point` [m] (link frame) with
//! #   force_n in (0, 500] N, horizontal, from the person's base position
//! #   towards the point, ramped over 0.2 s at both ends; the hand `part`
//! #   ("right_hand" | "left_hand") is put on the link there and the force is
//! #   a ground-truth contact of that hand on that link. `intended` defaults
//! #   to whether the hand is one of `collaborative_parts`. The link is checked
//! #   against the robot model when the simulator is built.
//!
//! [config]                           # optional, any tables: overrides for the services,
//! sim = { substeps = 8 }             # kept as an opaque toml::Table
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use phri_ipc::BodyPart;

use crate::human_script::{Hand, HumanScript, Keyframe, Push, ScriptError, Wave};

/// A loaded, checked scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// the scenario's name (`collision`)
    pub name: String,
    /// what happens in it, in a line ("" when the file gives none)
    pub description: String,
    /// default run length \[s\] ([`Scenario::DEFAULT_DURATION_S`] when the file gives none)
    pub duration_s: f64,
    /// the scripted human, if any
    pub human: Option<HumanScript>,
    /// human parts whose contacts are intended (collaboration); empty without a human
    pub collaborative_parts: Vec<BodyPart>,
    /// what the person says, in time order (the simulated microphone plays it)
    pub voice: Vec<VoiceLine>,
    /// configuration overrides, uninterpreted here
    pub config: toml::Table,
}

/// `[[voice]]`: a recording the simulated microphone plays at scenario time `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct VoiceLine {
    /// when the recording starts [s, scenario time]
    pub t: f64,
    /// WAV file (16 kHz mono 16 bit), relative to `deploy/audio/` (the
    /// `audio` directory beside the scenario's directory) unless absolute
    pub wav: String,
}

impl VoiceLine {
    /// The file `wav` names, for a scenario read from `scenario_file`.
    pub fn path(&self, scenario_file: &Path) -> PathBuf {
        let p = Path::new(&self.wav);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        let dir = scenario_file.parent().unwrap_or(Path::new("."));
        dir.join("..").join("audio").join(p)
    }
}

/// Why a scenario could not be loaded. `origin` is the file path (or
/// `<scenario>` for text), `field` a dotted path such as `human.keyframe[2].t`.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// the file could not be read
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// the file
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
    /// TOML syntax, a missing or unknown field or a wrong type, at `line`
    /// (1-based; 0 when unknown) in the table or key `field` (empty when unknown)
    #[error("{origin}:{line}: {}{message}", if field.is_empty() { String::new() } else { format!("{field}: ") })]
    Parse {
        /// the file (`<scenario>` for text)
        origin: String,
        /// the line, 1-based (0: unknown)
        line: usize,
        /// the table or key, dotted ("": unknown)
        field: String,
        /// the parser's message
        message: String,
    },
    /// a well-typed value out of range, or a human script refused
    #[error("{origin}: {field}: {reason}")]
    Invalid {
        /// the file (`<scenario>` for text)
        origin: String,
        /// the key, dotted (`human.keyframe[2].t`)
        field: String,
        /// why the value is refused
        reason: String,
    },
    /// a file another user could have written, or not a regular file
    #[error(transparent)]
    Untrusted(crate::trust::TrustError),
}

impl From<crate::trust::TrustError> for ScenarioError {
    fn from(e: crate::trust::TrustError) -> ScenarioError {
        match e {
            crate::trust::TrustError::Io { path, source } => ScenarioError::Io { path, source },
            e => ScenarioError::Untrusted(e),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default = "default_duration_s")]
    duration_s: f64,
    human: Option<RawHuman>,
    #[serde(default)]
    voice: Vec<RawVoice>,
    #[serde(default)]
    config: toml::Table,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVoice {
    t: f64,
    wav: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHuman {
    #[serde(default = "default_floor_z")]
    floor_z: f64,
    #[serde(default)]
    collaborative_parts: Vec<String>,
    #[serde(default)]
    keyframe: Vec<RawKeyframe>,
    repeat_s: Option<f64>,
}

/// The longest run \[s\] (about 116 days): a longer one would overflow the
/// nanosecond clocks.
pub const MAX_DURATION_S: f64 = 1e7;

fn default_duration_s() -> f64 {
    Scenario::DEFAULT_DURATION_S
}

fn default_floor_z() -> f64 {
    HumanScript::DEFAULT_FLOOR_Z
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKeyframe {
    t: f64,
    base: [f64; 3],
    right_hand: Option<[f64; 3]>,
    left_hand: Option<[f64; 3]>,
    right_foot: Option<[f64; 3]>,
    left_foot: Option<[f64; 3]>,
    lean: Option<f64>,
    wave: Option<RawWave>,
    push: Option<RawPush>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWave {
    hand: String,
    frequency_hz: f64,
    amplitude_m: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPush {
    link: String,
    point: [f64; 3],
    force_n: f64,
    part: String,
    intended: Option<bool>,
}

/// `right` / `left` of a wave.
fn wave_hand(name: &str) -> Option<Hand> {
    match name {
        "right" => Some(Hand::Right),
        "left" => Some(Hand::Left),
        _ => None,
    }
}

/// The pushing hand: `right_hand` / `left_hand` (or its body part name
/// `hand_right` / `hand_left`).
fn push_hand(name: &str) -> Option<Hand> {
    match name {
        "right_hand" | "hand_right" => Some(Hand::Right),
        "left_hand" | "hand_left" => Some(Hand::Left),
        _ => None,
    }
}

impl Scenario {
    /// Run length \[s\] of a scenario that does not give `duration_s`.
    pub const DEFAULT_DURATION_S: f64 = 60.0;

    /// No person, no overrides: the arm alone (`free-motion`), for a cell run without a scenario.
    pub fn free_motion() -> Scenario {
        Scenario {
            name: "free-motion".into(),
            description: String::new(),
            duration_s: Self::DEFAULT_DURATION_S,
            human: None,
            collaborative_parts: Vec::new(),
            voice: Vec::new(),
            config: toml::Table::new(),
        }
    }

    /// Read and check a scenario file; errors name the file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Scenario, ScenarioError> {
        let path = path.as_ref();
        let text = crate::check::read_text(path)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parse and check scenario text (errors name `<scenario>` as the origin).
    #[allow(clippy::should_implement_trait)]
    pub fn from_str(text: &str) -> Result<Scenario, ScenarioError> {
        Self::parse(text, "<scenario>")
    }

    fn parse(text: &str, origin: &str) -> Result<Scenario, ScenarioError> {
        let raw: RawScenario = toml::from_str(text).map_err(|e| {
            // a missing field is reported at the start of its table, not at a key
            let table_only = e.message().starts_with("missing field");
            let (line, field) = match e.span() {
                Some(span) => locate(text, span.start, table_only),
                None => (0, String::new()),
            };
            ScenarioError::Parse {
                origin: origin.to_string(),
                line,
                field,
                message: e.message().trim_end().to_string(),
            }
        })?;
        let invalid = |field: String, reason: String| ScenarioError::Invalid {
            origin: origin.to_string(),
            field,
            reason,
        };
        if !(raw.duration_s.is_finite() && raw.duration_s > 0.0 && raw.duration_s <= MAX_DURATION_S)
        {
            return Err(invalid(
                "duration_s".into(),
                format!(
                    "{} is not a positive number of seconds up to {MAX_DURATION_S}",
                    raw.duration_s
                ),
            ));
        }
        let (human, collaborative_parts) = match raw.human {
            None => (None, Vec::new()),
            Some(h) => {
                let (script, parts) = human_script(h, &invalid)?;
                (Some(script), parts)
            }
        };
        let voice = voice_lines(raw.voice, &invalid)?;
        Ok(Scenario {
            voice,
            name: raw.name,
            description: raw.description,
            duration_s: raw.duration_s,
            human,
            collaborative_parts,
            config: raw.config,
        })
    }
}

/// The scenario's error about `field` for `reason`, named by its origin.
type Invalid<'a> = dyn Fn(String, String) -> ScenarioError + 'a;

/// The person's script and collaborative parts from the file's `[human]`.
fn human_script(
    h: RawHuman,
    invalid: &Invalid<'_>,
) -> Result<(HumanScript, Vec<BodyPart>), ScenarioError> {
    let mut parts = Vec::with_capacity(h.collaborative_parts.len());
    for (i, name) in h.collaborative_parts.iter().enumerate() {
        let part = BodyPart::from_name(name).map_err(|e| {
            invalid(
                format!("human.collaborative_parts[{i}]"),
                format!("unknown body part '{name}' (known: {})", e.expected),
            )
        })?;
        if !parts.contains(&part) {
            parts.push(part);
        }
    }
    let mut keyframes = Vec::with_capacity(h.keyframe.len());
    for (i, k) in h.keyframe.into_iter().enumerate() {
        keyframes.push(keyframe(i, k, &parts, invalid)?);
    }
    let script = HumanScript::new(h.floor_z, keyframes).map_err(|e| match e {
        ScriptError::FloorZ(v) => invalid("human.floor_z".into(), format!("{v} is not a finite number")),
        ScriptError::NoKeyframe => invalid("human.keyframe".into(), "a human needs at least one [[human.keyframe]]".into()),
        ScriptError::TooMany { count, max } => invalid("human.keyframe".into(), format!("{count} keyframes, more than the {max} a script may have")),
        ScriptError::NotFinite { index, field } => invalid(format!("human.keyframe[{index}].{field}"), "not a finite number".into()),
        ScriptError::Unsorted { index, t, previous } => {
            invalid(format!("human.keyframe[{index}].t"), format!("{t} s is not after the previous keyframe's {previous} s (keyframes must be sorted by strictly increasing t)"))
        }
        ScriptError::Repeat { .. } => invalid("human.repeat_s".into(), e.to_string()),
        ScriptError::Invalid { index, field, reason } => invalid(format!("human.keyframe[{index}].{field}"), reason),
    })?;
    let script = match h.repeat_s {
        None => script,
        Some(r) => script
            .repeating(r)
            .map_err(|e| invalid("human.repeat_s".into(), e.to_string()))?,
    };
    Ok((script, parts))
}

/// Keyframe `i` of the script, its wave and push checked (`parts`: the
/// collaborative ones, which a push is meant to touch unless it says).
fn keyframe(
    i: usize,
    k: RawKeyframe,
    parts: &[BodyPart],
    invalid: &Invalid<'_>,
) -> Result<Keyframe, ScenarioError> {
    let wave = match k.wave {
        None => None,
        Some(w) => Some(Wave {
            hand: wave_hand(&w.hand).ok_or_else(|| {
                invalid(
                    format!("human.keyframe[{i}].wave.hand"),
                    format!("'{}' is not \"right\" or \"left\"", w.hand),
                )
            })?,
            frequency_hz: w.frequency_hz,
            amplitude_m: w.amplitude_m,
        }),
    };
    let push = match k.push {
        None => None,
        Some(p) => {
            let hand = push_hand(&p.part).ok_or_else(|| {
                invalid(
                    format!("human.keyframe[{i}].push.part"),
                    format!("'{}' is not \"right_hand\" or \"left_hand\"", p.part),
                )
            })?;
            Some(Push {
                link: p.link,
                point: p.point,
                force_n: p.force_n,
                hand,
                intended: p.intended.unwrap_or(parts.contains(&hand.part())),
            })
        }
    };
    Ok(Keyframe {
        t: k.t,
        base: k.base,
        right_hand: k.right_hand,
        left_hand: k.left_hand,
        right_foot: k.right_foot,
        left_foot: k.left_foot,
        lean: k.lean,
        wave,
        push,
    })
}

/// The voice lines, each at a time ≥ 0 s, in time order, naming a file.
fn voice_lines(raw: Vec<RawVoice>, invalid: &Invalid<'_>) -> Result<Vec<VoiceLine>, ScenarioError> {
    let mut voice = Vec::with_capacity(raw.len());
    for (i, v) in raw.into_iter().enumerate() {
        if !(v.t.is_finite() && v.t >= 0.0) {
            return Err(invalid(
                format!("voice[{i}].t"),
                format!("{} is not a time ≥ 0 s", v.t),
            ));
        }
        if let Some(prev) = voice.last().map(|p: &VoiceLine| p.t) {
            if v.t < prev {
                return Err(invalid(
                    format!("voice[{i}].t"),
                    format!(
                        "{} s is before the previous line's {prev} s (lines must be in time order)",
                        v.t
                    ),
                ));
            }
        }
        if v.wav.trim().is_empty() {
            return Err(invalid(format!("voice[{i}].wav"), "no file named".into()));
        }
        voice.push(VoiceLine { t: v.t, wav: v.wav });
    }
    Ok(voice)
}

/// 1-based line of byte `offset` in `text` and the dotted field there, such as
/// `human.keyframe[2].t` (the key of the nearest `key =` line at or before it,
/// in the table of the nearest header; the table alone when the offset is on
/// a header, or with `table_only`). A best-effort reading of plain TOML for
/// error messages.
pub(crate) fn locate(text: &str, offset: usize, table_only: bool) -> (usize, String) {
    let offset = offset.min(text.len());
    let line_no = text.as_bytes()[..offset]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1;
    let mut table = String::new();
    let mut arrays: Vec<(String, usize)> = Vec::new();
    let mut key: Option<String> = None;
    for line in text.lines().take(line_no) {
        let l = line.trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|r| r.split("]]").next()) {
            let name = name.trim().to_string();
            let count = match arrays.iter_mut().find(|(n, _)| *n == name) {
                Some((_, c)) => {
                    *c += 1;
                    *c
                }
                None => {
                    arrays.push((name.clone(), 1));
                    1
                }
            };
            table = format!("{name}[{}]", count - 1);
            key = None;
        } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.split(']').next()) {
            table = name.trim().to_string();
            key = None;
        } else if let Some((k, _)) = l.split_once('=') {
            let k = k.trim();
            if !k.is_empty()
                && !k.starts_with('#')
                && k.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "_-.\"' ".contains(c))
            {
                key = Some(k.trim_matches('"').to_string());
            }
        }
    }
    let field = match (table.is_empty(), key.filter(|_| !table_only)) {
        (true, Some(k)) => k,
        (false, Some(k)) => format!("{table}.{k}"),
        (_, None) => table,
    };
    (line_no, field)
}
