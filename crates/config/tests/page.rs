//! The guide's key reference (`docs/configuration-keys.md`) is what the
//! crate renders from its own definitions, and it and the code list the same
//! keys: every key of `deploy/phri.toml` and of the default arm's robot file
//! has a unit and a description (`src/keys.rs`), every entry there names a
//! key the configuration takes, every safe range's key is on the page.
//! `PHRI_BLESS=1` rewrites the page instead of failing.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use phri_config::keys::KEY_DOCS;
use phri_config::page::{self, PAGE_PATH, REGENERATE};
use phri_config::ranges::SAFETY_RANGES;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn the_committed_page_is_the_rendered_one() {
    let path = root().join(PAGE_PATH);
    let rendered = page::render();
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed == rendered {
        return;
    }
    if std::env::var_os("PHRI_BLESS").is_some_and(|v| v == "1") {
        std::fs::write(&path, &rendered).unwrap();
        return;
    }
    let first = committed
        .lines()
        .zip(rendered.lines())
        .position(|(a, b)| a != b)
        .unwrap_or_else(|| committed.lines().count().min(rendered.lines().count()));
    panic!(
        "{PAGE_PATH} is not what the configuration crate renders (first difference at line {}):\n  \
         committed: {:?}\n  rendered:  {:?}\nregenerate it from the workspace's root with\n  {REGENERATE}\n\
         (or PHRI_BLESS=1 cargo test --release -p phri-config --test page)",
        first + 1,
        committed.lines().nth(first).unwrap_or("<end of file>"),
        rendered.lines().nth(first).unwrap_or("<end of file>"),
    );
}

/// Every key of the defaults has an entry in `src/keys.rs`, and every entry a key.
#[test]
fn every_key_has_an_entry_and_every_entry_a_key() {
    let expected = page::expected_keys();
    let documented: BTreeSet<String> = KEY_DOCS.iter().map(|d| d.key.to_string()).collect();
    let missing: Vec<_> = expected.difference(&documented).collect();
    assert!(
        missing.is_empty(),
        "keys of deploy/phri.toml (or the default robot file, or the code) without an entry in crates/config/src/keys.rs: {missing:?}"
    );
    let unknown: Vec<_> = documented.difference(&expected).collect();
    assert!(
        unknown.is_empty(),
        "entries of crates/config/src/keys.rs that name no key of the configuration: {unknown:?}"
    );
    assert_eq!(
        documented.len(),
        KEY_DOCS.len(),
        "a key listed twice in keys.rs"
    );
}

/// What `deploy/phri.toml` itself lists is on the committed page, and the
/// page lists nothing the files and the code do not.
#[test]
fn the_page_lists_every_key_of_deploy_phri_toml_and_no_other() {
    let text = std::fs::read_to_string(root().join(PAGE_PATH)).unwrap_or_default();
    let on_page = page::page_keys(&text);
    let file: toml::Table = phri_config::DEFAULTS.parse().unwrap();
    let in_file = page::collapsed_keys(&file);
    let absent: Vec<_> = in_file.difference(&on_page).collect();
    assert!(
        absent.is_empty(),
        "keys of deploy/phri.toml missing from {PAGE_PATH}: {absent:?} (regenerate: {REGENERATE})"
    );
    let expected = page::expected_keys();
    let extra: Vec<_> = on_page.difference(&expected).collect();
    assert!(
        extra.is_empty(),
        "{PAGE_PATH} lists keys the configuration does not take: {extra:?} (regenerate: {REGENERATE})"
    );
    assert_eq!(
        on_page, expected,
        "{PAGE_PATH}: regenerate it with {REGENERATE}"
    );
}

/// Every safe range's key is on the page, with the range's own unit.
#[test]
fn every_range_is_on_the_page_with_its_unit() {
    let rows = page::rows();
    for range in SAFETY_RANGES {
        let row = rows
            .iter()
            .find(|r| page::range_of(&r.key).is_some_and(|x| x.key == range.key))
            .unwrap_or_else(|| panic!("no row of the page has the range of {}", range.key));
        assert_eq!(
            row.unit, range.unit,
            "{}: unit {:?} in keys.rs, {:?} in ranges.rs",
            row.key, row.unit, range.unit
        );
        assert!(!row.range.is_empty(), "{}", row.key);
    }
}
