//! The picture of the cell (`phri-supervisor --draw-cell FILE`): its
//! processes as boxes and the channels between them as arrows, drawn from
//! the code: the roster of the run's configuration (the enabled
//! `[services.*]`), what each binary publishes and reads
//! (`phri_ipc::ports`, kept honest by a test that reads the services'
//! sources), and a hand-made layout ([`layout`]). The README shows the
//! default cell's, `docs/cell.svg`; a test here fails when that file is
//! not what the code draws, and says how to redraw it.

pub mod graph;
pub mod layout;
pub mod scene;
pub mod svg;

use std::path::Path;

use crate::error::SupervisorError;
use crate::plan::Plan;

pub use graph::CellGraph;
pub use scene::Scene;

/// The command that redraws `docs/cell.svg` from the repository's root.
pub const REDRAW: &str = "cargo build --release -p phri-supervisor && target/release/phri-supervisor --draw-cell docs/cell.svg";

/// The scene of the cell `plan` runs.
pub fn scene(plan: &Plan) -> Scene {
    Scene::new(&CellGraph::new(&plan.services, &plan.loaded.config))
}

/// The picture of the cell `plan` runs, as an SVG document.
pub fn draw(plan: &Plan) -> String {
    scene(plan).to_svg()
}

/// Draw the cell `plan` runs into `path`.
pub fn write(plan: &Plan, path: &Path) -> Result<(), SupervisorError> {
    std::fs::write(path, draw(plan)).map_err(|source| SupervisorError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::layout::{Label, Rect, PLACES, ROUTES};
    use super::scene::PAD;
    use super::*;
    use std::path::PathBuf;

    fn root() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    fn default_plan() -> Plan {
        Plan::load(&root().join("deploy/phri.toml"), None, &[], None).unwrap()
    }

    #[test]
    fn docs_cell_svg_is_what_the_code_draws() {
        let drawn = draw(&default_plan());
        let path = root().join("docs/cell.svg");
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        if committed != drawn {
            let first = committed
                .lines()
                .zip(drawn.lines())
                .position(|(a, b)| a != b)
                .map_or(committed.lines().count().min(drawn.lines().count()), |i| i);
            panic!(
                "docs/cell.svg is not the picture the code draws (first difference at line {}): \
                 redraw it from the repository's root with\n    {REDRAW}",
                first + 1
            );
        }
    }

    #[test]
    fn the_picture_is_well_formed_and_the_same_every_time() {
        let plan = default_plan();
        let svg = draw(&plan);
        assert_eq!(svg, draw(&plan));
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("not XML: {e}"));
        let root = doc.root_element();
        assert_eq!(root.tag_name().name(), "svg");
        assert_eq!(
            root.tag_name().namespace(),
            Some("http://www.w3.org/2000/svg")
        );
        let count = |tag: &str| doc.descendants().filter(|n| n.has_tag_name(tag)).count();
        let g = CellGraph::new(&plan.services, &plan.loaded.config);
        assert_eq!(count("polyline"), g.edges.len());
        assert!(count("text") > 40);
        // every channel on an arrow is named in the picture
        for e in &g.edges {
            for c in &e.channels {
                assert!(
                    svg.contains(&format!(">{c}<"))
                        || svg.contains(&format!("{c},"))
                        || svg.contains(&format!(" {c}<")),
                    "{c}"
                );
            }
        }
    }

    #[test]
    fn the_default_cell_has_a_place_and_a_route_for_everything() {
        let plan = default_plan();
        let g = CellGraph::new(&plan.services, &plan.loaded.config);
        for n in &g.nodes {
            assert!(
                !n.place.slot.is_empty(),
                "{:?} has no place in drawing/layout.rs PLACES",
                n.members.iter().map(|m| &m.name).collect::<Vec<_>>()
            );
        }
        for (name, _) in &plan.services {
            assert!(
                PLACES.iter().any(|p| p.services.contains(&name.as_str())),
                "[services.{name}] has no place in drawing/layout.rs"
            );
        }
        let s = Scene::new(&g);
        for a in &s.arrows {
            assert!(
                a.routed,
                "{} → {} ({:?}) has no route in drawing/layout.rs ROUTES",
                a.from, a.to, a.channels
            );
        }
        for r in ROUTES {
            assert!(
                s.arrows.iter().any(|a| a.from == r.from && a.to == r.to),
                "ROUTES has {} → {}, but no channel flows so: remove it",
                r.from,
                r.to
            );
        }
        for a in s.arrows.iter().filter(|a| a.shared) {
            // a shared label: another arrow with the same channels starts along the same way, labelled
            let named = s.arrows.iter().any(|b| {
                b.label.is_some()
                    && b.channels == a.channels
                    && b.from == a.from
                    && b.points[..2] == a.points[..2]
            });
            assert!(
                named,
                "{} → {}: its label is shared with no labelled arrow",
                a.from, a.to
            );
        }
    }

    #[test]
    fn nothing_overlaps_and_every_word_fits() {
        let plan = default_plan();
        let s = scene(&plan);
        let canvas = Rect::new(0.0, 0.0, s.width, s.height);
        let inside = |r: &Rect| {
            r.x >= canvas.x
                && r.y >= canvas.y
                && r.right() <= canvas.right()
                && r.bottom() <= canvas.bottom()
        };
        for (i, b) in s.boxes.iter().enumerate() {
            assert!(inside(&b.rect), "box {i} leaves the picture");
            for (j, c) in s.boxes.iter().enumerate().skip(i + 1) {
                assert!(!b.rect.overlaps(&c.rect), "boxes {i} and {j} overlap");
            }
            for l in &b.lines {
                let t = l.bounds();
                assert!(
                    t.x >= b.rect.x + PAD - 0.01
                        && t.right() <= b.rect.right() - PAD + 0.01
                        && t.bottom() <= b.rect.bottom() - 2.0,
                    "{:?} does not fit its box {:?}",
                    l.text,
                    b.rect
                );
            }
        }
        let boxes: Vec<(&str, Rect)> = s
            .boxes
            .iter()
            .zip(CellGraph::new(&plan.services, &plan.loaded.config).nodes)
            .map(|(b, n)| (n.place.slot, b.rect))
            .collect();
        let rect_of = |slot: &str| {
            boxes
                .iter()
                .find(|(s, _)| *s == slot)
                .map(|(_, r)| *r)
                .unwrap()
        };
        for a in &s.arrows {
            let (first, last) = (a.points[0], a.points[a.points.len() - 1]);
            assert!(
                rect_of(&a.from).on_border(first),
                "{} → {} starts off {}'s border",
                a.from,
                a.to,
                a.from
            );
            assert!(
                rect_of(&a.to).on_border(last),
                "{} → {} ends off {}'s border",
                a.from,
                a.to,
                a.to
            );
            for w in a.points.windows(2) {
                for (slot, r) in &boxes {
                    assert!(
                        !r.crossed_by(w[0], w[1], 1.0),
                        "{} → {} runs through {slot}",
                        a.from,
                        a.to
                    );
                }
            }
        }
        let labels: Vec<(String, Rect)> = s
            .arrows
            .iter()
            .filter_map(|a| {
                a.label
                    .as_ref()
                    .map(|l| (format!("{} → {}", a.from, a.to), l.rect))
            })
            .collect();
        for (i, (name, r)) in labels.iter().enumerate() {
            assert!(inside(r), "the label of {name} leaves the picture");
            for (slot, b) in &boxes {
                assert!(!r.overlaps(b), "the label of {name} covers {slot}");
            }
            for (other, q) in labels.iter().skip(i + 1) {
                assert!(!r.overlaps(q), "the labels of {name} and {other} overlap");
            }
            for t in &s.texts {
                assert!(
                    !r.overlaps(&t.bounds()),
                    "the label of {name} covers the legend"
                );
            }
        }
        for t in &s.texts {
            assert!(inside(&t.bounds()), "{:?} leaves the picture", t.text);
            for (slot, b) in &boxes {
                assert!(!t.bounds().overlaps(b), "{:?} covers {slot}", t.text);
            }
        }
        // every route's label sits on a segment of it
        for r in ROUTES {
            if let Label::On(k) | Label::Turned(k) = r.label {
                assert!(
                    k + 1 < r.points.len(),
                    "{} → {}: no segment {k}",
                    r.from,
                    r.to
                );
            }
        }
    }

    #[test]
    fn the_arrows_carry_the_channels_of_the_ports_table() {
        let plan = default_plan();
        let g = CellGraph::new(&plan.services, &plan.loaded.config);
        let edge = |a: &str, b: &str| {
            let (i, j) = (g.index(a).unwrap(), g.index(b).unwrap());
            g.edges
                .iter()
                .find(|e| e.from == i && e.to == j)
                .map(|e| e.channels.clone())
                .unwrap_or_default()
        };
        assert_eq!(
            edge("sim", "control"),
            ["robot/state", "robot/state/standby"]
        );
        assert_eq!(edge("control", "dynamics"), ["dynamics/residual/call"]);
        assert_eq!(
            edge("control", "sim"),
            ["robot/command", "robot/command/standby"]
        );
        assert_eq!(
            edge("dynamics", "control"),
            ["dynamics/residual", "dynamics/residual/standby"]
        );
        assert_eq!(
            edge("camera", "perception"),
            ["camera/depth", "perception/skeleton"]
        );
        assert_eq!(edge("control", "perception"), ["collab/state"]);
        // observers get no arrows; the supervisor reads its report's channels
        let sup = g.index("supervisor").unwrap();
        assert!(g.edges.iter().all(|e| e.to != sup));
        assert!(g.nodes[sup].reads.contains(&"sim/truth"));
        // the hot standby pair talks within its box; the camera's faults come from a tool
        let control = g.index("control").unwrap();
        assert_eq!(
            g.within(control),
            ["control/behaviour", "control/standby/behaviour"]
        );
        let camera = g.index("camera").unwrap();
        assert_eq!(
            g.from_outside(camera),
            [("fault/depth", vec!["phri-fault"])]
        );
        // the simulated camera does not read robot/state; a replayed one does
        assert!(!g.nodes[camera].reads.contains(&"robot/state"));
        let replay = Plan::load(
            &root().join("deploy/phri.toml"),
            None,
            &["camera.source=\"replay\""],
            None,
        );
        if let Ok(p) = replay {
            let g = CellGraph::new(&p.services, &p.loaded.config);
            let camera = g.index("camera").unwrap();
            assert!(g.nodes[camera].reads.contains(&"robot/state"));
        }
    }
}
