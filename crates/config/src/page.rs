//! The guide's key reference, `docs/configuration-keys.md`, rendered from
//! this crate's own definitions: each key's default from the defaults every
//! configuration is merged over ([`crate::defaults_table`]: `deploy/phri.toml`
//! and the default arm's robot file) or, for a key neither file gives, from
//! its section's serde default; its safe range from
//! [`crate::ranges::SAFETY_RANGES`]; its unit and description from
//! [`crate::keys::KEY_DOCS`]. `tests/page.rs` fails when the committed page
//! differs from [`render`]; [`REGENERATE`] rewrites it.

use std::collections::BTreeSet;

use toml::{Table, Value};

use crate::keys::{KeyDoc, KEY_DOCS, SERVICE_PREFIX};
use crate::ranges::{Range, SAFETY_RANGES};
use crate::robot::{CapsuleConfig, RobotSection, DEFAULT_ROBOT, DEFAULT_ROBOT_FILE};
use crate::supervisor::ServiceSpec;

/// The page, relative to the workspace's root.
pub const PAGE_PATH: &str = "docs/configuration-keys.md";

/// The command that rewrites the page (from the workspace's root).
pub const REGENERATE: &str =
    "cargo run --release -p phri-config --example config-page > docs/configuration-keys.md";

/// One row of the page: a key, its default, unit, safe range and description.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// dotted key (`services.NAME.key` for every service's)
    pub key: String,
    /// the default as TOML (`0.4`, `"lwr4"`), or a note (`none`, `per entry`)
    pub default: String,
    /// the default comes from the default arm's robot file
    pub from_robot_file: bool,
    /// its unit ("" for a count, a flag, a name or a dimensionless number)
    pub unit: &'static str,
    /// `[lo, hi]` or `(lo, hi]` without the unit; "" for none
    pub range: String,
    /// what it sets, in one line
    pub text: &'static str,
}

/// `key`'s section: the key without its last part.
fn section(key: &str) -> &str {
    key.rsplit_once('.').map_or(key, |(s, _)| s)
}

/// The value at dotted `key` in `table`: through tables, and into the first
/// entry of a list of tables (`repulsion.points.radius`); the second item
/// says whether a list of tables was crossed.
fn lookup<'t>(table: &'t Table, key: &str) -> Option<(&'t Value, bool)> {
    let mut parts = key.split('.');
    let mut at = table.get(parts.next()?)?;
    let mut in_list = false;
    for part in parts {
        if let Value::Array(list) = at {
            in_list = true;
            at = list.first()?;
        }
        at = at.as_table()?.get(part)?;
    }
    Some((at, in_list))
}

/// The list of tables `key` is an entry key of (`repulsion.points` for
/// `repulsion.points.radius`), if it is one.
fn list_of<'t>(table: &'t Table, key: &str) -> Option<&'t Vec<Value>> {
    match lookup(table, section(key)) {
        Some((Value::Array(list), _)) => Some(list),
        _ => None,
    }
}

/// The key without a serde default in `[robot]` (the robot file gives it).
const ROBOT_REQUIRED: &str = "urdf";
/// The key without a serde default in a service's entry.
const SERVICE_REQUIRED: &str = "binary";

/// The serde defaults of the sections whose keys the files may leave out:
/// `[robot]` (`name`, `file`, `armature`, `capsules`, `locked_joints`) and a
/// service's entry (`restart`, `start_delay_ms`, …; `None` fields absent),
/// each typed from its required key alone, which is then marked `required`.
fn serde_defaults() -> Table {
    let required = || Value::String(REQUIRED.into());
    let mut out = Table::new();
    let robot: Option<RobotSection> = toml::from_str(&format!("{ROBOT_REQUIRED} = \"\"")).ok();
    if let Some(mut t) = robot.and_then(|r| Table::try_from(r).ok()) {
        t.insert(ROBOT_REQUIRED.into(), required());
        out.insert("robot".into(), Value::Table(t));
    }
    let spec: Option<ServiceSpec> = toml::from_str(&format!("{SERVICE_REQUIRED} = \"\"")).ok();
    if let Some(mut t) = spec.and_then(|s| Table::try_from(s).ok()) {
        t.insert(SERVICE_REQUIRED.into(), required());
        let mut services = Table::new();
        services.insert("NAME".into(), Value::Table(t));
        out.insert("services".into(), Value::Table(services));
    }
    out
}

/// The default shown for a key that has none.
const REQUIRED: &str = "required";

/// Every key the typed configuration takes beyond the files' (those of
/// [`serde_defaults`], a service's optional ones, a capsule's), collapsed
/// as the page names them.
fn code_keys() -> BTreeSet<String> {
    let mut keys = collapsed_keys(&serde_defaults());
    for k in ["heartbeat", "heartbeat_timeout_ms", "cpu_budget"] {
        keys.insert(format!("{SERVICE_PREFIX}{k}"));
    }
    // a control point's law: absent from every file's point but one
    keys.insert("repulsion.points.law".into());
    let capsule = CapsuleConfig {
        link: String::new(),
        a: [0.0; 3],
        b: [0.0; 3],
        radius: 0.0,
    };
    if let Ok(t) = Table::try_from(capsule) {
        // the list (empty by default) is documented by its entries' keys
        keys.remove("robot.capsules");
        keys.extend(t.keys().map(|k| format!("robot.capsules.{k}")));
    }
    keys
}

/// The leaf keys of `table`, dotted: a list of tables' entry keys once
/// (`repulsion.points.radius`), every service's keys as `services.NAME.key`.
pub fn collapsed_keys(table: &Table) -> BTreeSet<String> {
    fn walk(v: &Value, name: String, out: &mut BTreeSet<String>) {
        match v {
            Value::Table(t) => {
                for (k, x) in t {
                    walk(x, format!("{name}.{k}"), out);
                }
            }
            Value::Array(list) if list.first().is_some_and(Value::is_table) => {
                for x in list {
                    walk(x, name.clone(), out);
                }
            }
            _ => {
                out.insert(name);
            }
        }
    }
    let mut out = BTreeSet::new();
    for (k, v) in table {
        match (k.as_str(), v) {
            ("services", Value::Table(services)) => {
                for spec in services.values() {
                    walk(spec, "services.NAME".into(), &mut out);
                }
            }
            _ => walk(v, k.clone(), &mut out),
        }
    }
    out
}

/// The keys the page must document: every key of the defaults (both
/// files) and of the sections' serde defaults.
pub fn expected_keys() -> BTreeSet<String> {
    let mut keys = collapsed_keys(&crate::defaults_table());
    keys.extend(code_keys());
    keys
}

/// `key`'s safe range, if it has one (`services.heartbeat_timeout_ms` is
/// every service's).
pub fn range_of(key: &str) -> Option<&'static Range> {
    let plain = key.replacen(".NAME.", ".", 1);
    SAFETY_RANGES.iter().find(|r| r.key == plain)
}

/// A range as `[lo, hi]` (`(lo, hi]` with its lower end excluded).
fn range_text(r: &Range) -> String {
    let text = r.text();
    text.strip_suffix(r.unit)
        .unwrap_or(&text)
        .trim_end()
        .to_string()
}

/// A TOML value on one line.
fn show(v: &Value) -> String {
    match v {
        Value::Array(a) if a.is_empty() => "[]".into(),
        v => v.to_string(),
    }
}

/// The row of `doc`, its default looked up in `defaults`, then `serde`.
fn row(doc: &KeyDoc, defaults: &Table, robot: &Table, serde: &Table) -> Row {
    let key = doc.key;
    let found = lookup(defaults, key).or_else(|| lookup(serde, key));
    let default = match (
        list_of(defaults, key).or_else(|| list_of(serde, key)),
        found,
    ) {
        (Some(list), _) if list.is_empty() => "none".to_string(),
        (Some(list), _) => format!("per entry ({} entries)", list.len()),
        (None, Some((Value::String(v), _))) if v == REQUIRED => REQUIRED.to_string(),
        (None, Some((v, _))) => format!("`{}`", show(v)),
        (None, None) => "none".to_string(),
    };
    Row {
        key: key.to_string(),
        default,
        from_robot_file: lookup(robot, key).is_some(),
        unit: doc.unit,
        range: range_of(key).map(range_text).unwrap_or_default(),
        text: doc.text,
    }
}

/// Every row, in [`KEY_DOCS`]'s order.
pub fn rows() -> Vec<Row> {
    let defaults = crate::defaults_table();
    let robot: Table = DEFAULT_ROBOT_FILE.parse().unwrap_or_default();
    let serde = serde_defaults();
    KEY_DOCS
        .iter()
        .map(|d| row(d, &defaults, &robot, &serde))
        .collect()
}

/// `s` inside a Markdown table cell.
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The default roster: each service of the defaults with its settings, in start order.
fn roster(out: &mut String) {
    let defaults = crate::defaults_table();
    let Some(Value::Table(services)) = defaults.get("services") else {
        return;
    };
    let mut specs: Vec<(&String, ServiceSpec)> = services
        .iter()
        .filter_map(|(name, v)| {
            let spec: ServiceSpec = v.clone().try_into().ok()?;
            Some((name, spec))
        })
        .collect();
    specs.sort_by_key(|(name, s)| (s.order, (*name).clone()));
    out.push_str(
        "\nThe default roster, in start order (`--set services.NAME.key=value` changes one):\n\n\
         | service | binary | args | order | rt_priority | cpus | cpu_budget | heartbeat | heartbeat_timeout_ms | depends_on | enabled |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let list = |v: &[String]| v.join(" ");
    let opt = |v: Option<String>| v.unwrap_or_else(|| "—".into());
    for (name, s) in specs {
        let cpus: Vec<String> = s.cpus.iter().map(|c| c.to_string()).collect();
        out.push_str(&format!(
            "| `{name}` | `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            s.binary,
            cell(&list(&s.args)),
            s.order,
            s.rt_priority,
            list(&cpus),
            opt(s.cpu_budget.map(|b| b.to_string())),
            opt(s.heartbeat.clone()),
            opt(s.heartbeat_timeout_ms.map(|t| t.to_string())),
            list(&s.depends_on),
            s.enabled,
        ));
    }
}

/// The page: one table per section.
pub fn render() -> String {
    let mut out = format!(
        "<!-- generated from crates/config (src/keys.rs, src/ranges.rs, deploy/phri.toml, \
         deploy/robots/{DEFAULT_ROBOT}/robot.toml): do not edit; regenerate with\n     \
         {REGENERATE} -->\n\n\
         # Configuration keys\n\n\
         Every key of `deploy/phri.toml` and of the arms' robot files, with its default, \
         unit and safe range ([Configuration](configuration.md): where a value comes from, \
         how it is checked). A default marked † is the default arm's \
         (`deploy/robots/{DEFAULT_ROBOT}/robot.toml`); another arm's robot file gives its own. \
         A value outside its safe range (\"(\": that end excluded) is refused at start, naming \
         the key, the value and the range. Per arm, from its model: \
         `dynamics.contact_threshold` and `collision_threshold` at most each joint's URDF \
         effort limit, every `control.waypoints` entry within the arm's reach. \
         `[[camera]]` entries take the keys of `[camera]`; `[skeleton.tracker]`, the depth \
         tracker's settings, has its defaults in `crates/people/src/config.rs`.\n\n\
         This page is generated from the configuration crate (`crates/config/src/keys.rs` \
         for units and descriptions); `cargo test -p phri-config --test page` fails when it \
         and the code disagree.\n"
    );
    let rows = rows();
    let defaults = crate::defaults_table();
    let serde = serde_defaults();
    // the roster follows the keys of [services.NAME]
    let services = SERVICE_PREFIX.trim_end_matches('.');
    let mut current = "";
    for r in &rows {
        let sect = section(&r.key);
        if sect != current {
            if current == services {
                roster(&mut out);
            }
            current = sect;
            let listed = list_of(&defaults, &r.key)
                .or_else(|| list_of(&serde, &r.key))
                .is_some();
            let heading = match listed {
                true => format!("[[{sect}]]"),
                false => format!("[{sect}]"),
            };
            out.push_str(&format!(
                "\n## `{heading}`\n\n| key | default | unit | safe range | what it sets |\n| --- | --- | --- | --- | --- |\n"
            ));
        }
        let leaf = r.key.rsplit('.').next().unwrap_or(&r.key);
        out.push_str(&format!(
            "| `{leaf}` | {}{} | {} | {} | {} |\n",
            cell(&r.default),
            if r.from_robot_file { " †" } else { "" },
            r.unit,
            r.range,
            cell(r.text),
        ));
    }
    if current == services {
        roster(&mut out);
    }
    out
}

/// The dotted keys a rendered page lists: each table's rows under its
/// section heading (`## \`[repulsion.params]\``).
pub fn page_keys(page: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut sect = None;
    for line in page.lines() {
        if let Some(h) = line.strip_prefix("## `[") {
            sect = Some(
                h.trim_start_matches('[')
                    .trim_end_matches([']', '`'])
                    .to_string(),
            );
            continue;
        }
        if line.starts_with("The default roster") {
            sect = None;
        }
        let (Some(s), Some(rest)) = (&sect, line.strip_prefix("| `")) else {
            continue;
        };
        if let Some((leaf, _)) = rest.split_once('`') {
            out.insert(format!("{s}.{leaf}"));
        }
    }
    out
}
