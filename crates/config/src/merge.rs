//! Merging tables: the defaults, the configuration file, a scenario's
//! `[config]` and `--set section.key=value` overrides, in that order.

use toml::{Table, Value};

use crate::error::ConfigError;

/// Deep-merge `over` into `base` (tables merge key by key; anything else,
/// arrays included, is replaced). Over a table, an array of tables (e.g.
/// `[[camera]]` over the defaults' `[camera]`) becomes that array with each
/// entry over the table; a table over an array of tables (`--set
/// camera.rate_hz=15`) merges into every entry.
pub fn merge(base: &mut Table, over: &Table) {
    let tables = |a: &[Value]| !a.is_empty() && a.iter().all(Value::is_table);
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(Value::Table(b)), Value::Table(o)) => merge(b, o),
            (Some(Value::Table(b)), Value::Array(o)) if tables(o) => {
                let entries = o
                    .iter()
                    .filter_map(Value::as_table)
                    .map(|e| {
                        let mut t = b.clone();
                        merge(&mut t, e);
                        Value::Table(t)
                    })
                    .collect();
                base.insert(k.clone(), Value::Array(entries));
            }
            (Some(Value::Array(b)), Value::Table(o)) if tables(b) => {
                for e in b.iter_mut().filter_map(Value::as_table_mut) {
                    merge(e, o);
                }
            }
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// Apply one `section.key=value` (any depth; the value is TOML, or a bare
/// string), or `section=[{…}, …]`: a whole list of tables (`camera=[{
/// azimuth_rad = 0.6 }, { azimuth_rad = -0.6 }]`, as `[[camera]]` entries).
pub fn apply_set(table: &mut Table, set: &str) -> Result<(), ConfigError> {
    let (path, value) = set
        .split_once('=')
        .ok_or_else(|| ConfigError::Override(set.to_string()))?;
    let keys: Vec<&str> = path.trim().split('.').collect();
    let value = value.trim();
    let parsed: Value = format!("v = {value}")
        .parse::<Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| Value::String(value.to_string()));
    let list_of_tables =
        matches!(&parsed, Value::Array(a) if !a.is_empty() && a.iter().all(Value::is_table));
    let refuse = |reason: String| ConfigError::SetValue {
        set: set.to_string(),
        reason,
    };
    if keys.iter().any(|k| k.is_empty()) {
        return Err(refuse(format!(
            "'{}' has an empty key: expected section.key=value",
            path.trim()
        )));
    }
    if keys.len() < 2 && !list_of_tables {
        let what = match &parsed {
            Value::Array(a) if a.is_empty() => "an empty list".to_string(),
            Value::Array(_) => "a list whose entries are not all tables".to_string(),
            Value::Table(_) => "a table".to_string(),
            v => a_type(v),
        };
        return Err(refuse(format!(
            "[{}] is a whole section, and {value} is {what}: give one of its keys \
             ({}.KEY=VALUE) or a list of at least one table ({}=[{{…}}, …], as [[{}]] entries)",
            keys[0], keys[0], keys[0], keys[0]
        )));
    }
    let mut cur = table;
    for (i, k) in keys[..keys.len() - 1].iter().enumerate() {
        let entry = cur
            .entry(k.to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        cur = match entry {
            Value::Table(t) => t,
            v => {
                return Err(refuse(format!(
                    "{} is {} ({v}), not a table with keys",
                    keys[..=i].join("."),
                    a_type(v)
                )))
            }
        };
    }
    cur.insert(keys[keys.len() - 1].to_string(), parsed);
    Ok(())
}

/// `a string`, `an integer`: a value's type, for messages.
fn a_type(v: &Value) -> String {
    let t = v.type_str();
    let article = match t.starts_with(['a', 'e', 'i', 'o', 'u']) {
        true => "an",
        false => "a",
    };
    format!("{article} {t}")
}

/// The `--set` of `sets` (the last one) that gave `key` (`section.key`,
/// a table above it or a key below it), as the flag a user typed: an error
/// about that key names the flag, not the file it was merged over.
pub fn set_giving(sets: &[&str], key: &str) -> Option<String> {
    sets.iter().rev().find_map(|s| {
        let k = s.split_once('=').map_or(*s, |(k, _)| k).trim();
        let hit = k == key
            || key.strip_prefix(k).is_some_and(|r| r.starts_with('.'))
            || k.strip_prefix(key).is_some_and(|r| r.starts_with('.'));
        hit.then(|| format!("--set {s}"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_overrides_typed_values_and_creates_sections() {
        let mut t: Table = "[control]\nreaction = \"reflex\"\nk = 1.0\n"
            .parse()
            .unwrap();
        apply_set(&mut t, "control.reaction=stop").unwrap();
        apply_set(&mut t, "control.k=2.5").unwrap();
        apply_set(&mut t, "sim.q0=[0.0, 1.0]").unwrap();
        assert_eq!(t["control"]["reaction"].as_str(), Some("stop"));
        assert_eq!(t["control"]["k"].as_float(), Some(2.5));
        assert_eq!(t["sim"]["q0"].as_array().map(|a| a.len()), Some(2));
        assert_eq!(
            apply_set(&mut t, "nokey").unwrap_err().to_string(),
            "--set 'nokey': expected section.key=value"
        );
        assert_eq!(
            apply_set(&mut t, "control.reaction.x=1").unwrap_err().to_string(),
            "--set 'control.reaction.x=1': control.reaction is a string (\"stop\"), not a table with keys"
        );
        // a whole section: says what is wrong with the value
        let e = apply_set(&mut t, "camera=[]").unwrap_err().to_string();
        assert_eq!(
            e,
            "--set 'camera=[]': [camera] is a whole section, and [] is an empty list: give one of its keys \
             (camera.KEY=VALUE) or a list of at least one table (camera=[{…}, …], as [[camera]] entries)"
        );
        let e = apply_set(&mut t, "camera=3").unwrap_err().to_string();
        assert!(e.contains("3 is an integer"), "{e}");
        let e = apply_set(&mut t, "control..kp=3").unwrap_err().to_string();
        assert!(e.contains("empty key"), "{e}");
    }

    #[test]
    fn merge_is_deep() {
        let mut a: Table = "[s]\nx = 1\ny = 2\n".parse().unwrap();
        let b: Table = "[s]\ny = 3\n".parse().unwrap();
        merge(&mut a, &b);
        assert_eq!(a["s"]["x"].as_integer(), Some(1));
        assert_eq!(a["s"]["y"].as_integer(), Some(3));
    }
}
