//! The Foxglove layout in `deploy/foxglove/` names only topics phri-viz
//! serves, and only fields its status message has.

use std::path::Path;

use serde_json::Value;

fn strings<'a>(v: &'a Value, out: &mut Vec<&'a str>) {
    match v {
        Value::String(s) => out.push(s),
        Value::Array(a) => a.iter().for_each(|x| strings(x, out)),
        Value::Object(m) => {
            for (k, x) in m {
                out.push(k);
                strings(x, out);
            }
        }
        _ => {}
    }
}

#[test]
fn the_layout_names_served_topics_and_status_fields() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/foxglove/phri-layout.json");
    let text = std::fs::read_to_string(&path).expect("the layout");
    let layout: Value = serde_json::from_str(&text).expect("JSON");
    let panels = layout["configById"].as_object().expect("configById");
    for kind in ["3D!", "Image!", "Plot!", "Indicator!", "StateTransitions!"] {
        assert!(panels.keys().any(|k| k.starts_with(kind)), "a {kind} panel");
    }
    // every panel in the tree is configured
    let mut tree = Vec::new();
    strings(&layout["layout"], &mut tree);
    for id in tree.iter().filter(|s| s.contains('!')) {
        assert!(panels.contains_key(*id), "{id} has no configuration");
    }
    let status_fields = phri_viz::status::Status::json_schema();
    let mut all = Vec::new();
    strings(&layout["configById"], &mut all);
    let mut used = std::collections::BTreeSet::new();
    for s in all.iter().filter(|s| s.starts_with("/viz/")) {
        let (topic, field) = s.split_once('.').unwrap_or((s, ""));
        assert!(phri_viz::TOPICS.contains(&topic), "{s}: no such topic");
        used.insert(topic);
        if topic == phri_viz::topics::STATUS && !field.is_empty() {
            let name = field.split('[').next().unwrap_or(field);
            assert!(
                status_fields["properties"].get(name).is_some(),
                "{s}: the status has no field '{name}'"
            );
        }
    }
    // everything served is shown somewhere
    for t in phri_viz::TOPICS {
        assert!(used.contains(t), "{t} is in no panel");
    }
}
