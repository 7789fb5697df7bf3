//! The picture as shapes: each node of the [`CellGraph`] a box with its
//! words, each edge an arrow along its route with its channels for label.
//! Text widths are estimated (monospace: 0.6 em a character; the sans
//! font is given the same, more than most sans fonts take), which is what
//! the tests check fitting and overlaps with.

use super::graph::CellGraph;
use super::layout::{self, Label, Rect};

/// The fonts of the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Font {
    /// a box's binary: bold monospace
    Title,
    /// a box's words: sans
    Body,
    /// channel names inside a box: monospace
    Note,
    /// an arrow's channels: monospace
    Label,
    /// the legend and the footer: sans
    Small,
}

impl Font {
    /// Its size \[px\].
    pub fn size(self) -> f64 {
        match self {
            Font::Title => 12.5,
            Font::Body => 11.0,
            Font::Note => 10.0,
            Font::Label => 10.5,
            Font::Small => 11.0,
        }
    }

    /// The estimated width of `text` \[px\].
    pub fn width(self, text: &str) -> f64 {
        text.chars().count() as f64 * 0.6 * self.size()
    }
}

/// One line of text, centred on `x`, its baseline at `y` \[px\].
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// the line's centre, horizontally \[px\]
    pub x: f64,
    /// its baseline \[px\]
    pub y: f64,
    /// the words
    pub text: String,
    /// its font
    pub font: Font,
}

impl Line {
    /// The box the line takes \[px\].
    pub fn bounds(&self) -> Rect {
        let s = self.font.size();
        Rect::new(
            self.x - self.font.width(&self.text) / 2.0,
            self.y - 0.8 * s,
            self.font.width(&self.text),
            s,
        )
    }
}

/// How a box is coloured: by the CPU its processes are pinned to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shade {
    /// CPU 1: the torque loop
    Loop,
    /// CPU 0: perception and people
    Perception,
    /// not pinned
    Free,
}

/// A process's box.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxShape {
    /// where \[px\]
    pub rect: Rect,
    /// its colour
    pub shade: Shade,
    /// the roster's services in it (a tooltip)
    pub tooltip: String,
    /// its text: the binaries, the place's words, the channels of note
    pub lines: Vec<Line>,
}

/// An arrow's label: its channels, one line each or all on one.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelShape {
    /// the box it covers (turned: the turned box) \[px\]
    pub rect: Rect,
    /// its lines of text: the channels, all on one line or one a line
    pub lines: Vec<String>,
    /// runs up a vertical segment
    pub turned: bool,
}

/// An arrow from a publisher's box to a reader's.
#[derive(Clone, Debug, PartialEq)]
pub struct Arrow {
    /// the publisher's place (its slot)
    pub from: String,
    /// the reader's place (its slot)
    pub to: String,
    /// the channels the one publishes and the other reads
    pub channels: Vec<&'static str>,
    /// the polyline \[px\], from the publisher's box to the reader's
    pub points: Vec<(f64, f64)>,
    /// its label (`None`: the route's label is [`Label::Shared`], or names a
    /// segment the route does not have)
    pub label: Option<LabelShape>,
    /// the layout has a route for it (else: straight, centre to centre)
    pub routed: bool,
    /// the route's label is [`Label::Shared`]
    pub shared: bool,
}

/// The whole picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// width \[px\]
    pub width: f64,
    /// height \[px\]
    pub height: f64,
    /// one per node of the [`CellGraph`], in its order
    pub boxes: Vec<BoxShape>,
    /// one per edge of the [`CellGraph`], in its order
    pub arrows: Vec<Arrow>,
    /// the legend and the footer
    pub texts: Vec<Line>,
    /// the legend's swatches
    pub swatches: Vec<(Rect, Shade)>,
}

/// Line spacing inside boxes and labels [px].
const LEADING: f64 = 13.0;
/// Inner margin of a box \[px\].
pub const PAD: f64 = 8.0;

/// `words` joined by ", " into lines of at most `width` px in `font`.
fn wrap(prefix: &str, words: &[&str], font: Font, width: f64) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = prefix.to_string();
    for (i, w) in words.iter().enumerate() {
        let sep = if i + 1 < words.len() { "," } else { "" };
        let candidate = match line.is_empty() || line.ends_with(' ') {
            true => format!("{line}{w}{sep}"),
            false => format!("{line} {w}{sep}"),
        };
        if font.width(&candidate) > width && !line.trim().is_empty() && line != prefix {
            lines.push(line);
            line = format!("{w}{sep}");
        } else {
            line = candidate;
        }
    }
    if !line.trim().is_empty() {
        lines.push(line);
    }
    lines
}

/// The box of node `i`.
fn box_of(graph: &CellGraph, i: usize) -> BoxShape {
    let node = &graph.nodes[i];
    let r = node.place.rect;
    let cx = r.x + r.w / 2.0;
    let binaries: Vec<&str> = node.members.iter().map(|m| m.binary.as_str()).collect();
    let title = match binaries.iter().all(|b| *b == binaries[0]) && binaries.len() > 1 {
        true => format!("{} ×{}", binaries[0], binaries.len()),
        false => binaries.join(" + "),
    };
    let inner = r.w - 2.0 * PAD;
    let mut texts: Vec<(String, Font)> = vec![(title, Font::Title)];
    texts.extend(node.place.what.lines().map(|l| (l.to_string(), Font::Body)));
    let within = graph.within(i);
    if !within.is_empty() {
        texts.push(("between the two:".into(), Font::Note));
        texts.extend(within.iter().map(|c| (c.to_string(), Font::Note)));
    }
    let supervised = phri_ipc::ports::SUPERVISED.reads;
    let to_all: Vec<&str> = node
        .publishes
        .iter()
        .copied()
        .filter(|c| supervised.contains(c))
        .collect();
    if !to_all.is_empty() {
        let mut words = to_all.clone();
        let last = words.len() - 1;
        let tail = format!("{} → every service", words[last]);
        words[last] = &tail;
        texts.extend(
            wrap("", &words, Font::Note, inner)
                .into_iter()
                .map(|l| (l, Font::Note)),
        );
    }
    if node.place.observer {
        let reads: Vec<&str> = node.reads.clone();
        texts.extend(
            wrap("reads: ", &reads, Font::Note, inner)
                .into_iter()
                .map(|l| (l, Font::Note)),
        );
    } else {
        for (c, by) in graph.from_outside(i) {
            texts.push((format!("reads {c}"), Font::Note));
            if !by.is_empty() {
                texts.push((format!("from {}", by.join(", ")), Font::Note));
            }
        }
    }
    let mut y = r.y + 18.0;
    let mut lines = Vec::new();
    for (k, (text, font)) in texts.into_iter().enumerate() {
        lines.push(Line {
            x: cx,
            y,
            text,
            font,
        });
        y += if k == 0 { 15.0 } else { LEADING };
    }
    let tooltip = node
        .members
        .iter()
        .map(|m| match m.name.as_str() {
            layout::SUPERVISOR => m.binary.clone(),
            n => format!("[services.{n}] {}", m.binary),
        })
        .collect::<Vec<_>>()
        .join("\n");
    BoxShape {
        rect: r,
        shade: match (node.cpus.contains(&1), node.cpus.contains(&0)) {
            (true, _) => Shade::Loop,
            (false, true) => Shade::Perception,
            _ => Shade::Free,
        },
        tooltip,
        lines,
    }
}

/// The label of `channels` on segment `a`–`b`.
fn label_on(channels: &[&str], a: (f64, f64), b: (f64, f64), turned: bool) -> LabelShape {
    let (cx, cy) = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
    let length = (b.0 - a.0).abs().max((b.1 - a.1).abs());
    let one = channels.join(", ");
    let horizontal = (b.1 - a.1).abs() < 0.5;
    let lines: Vec<String> =
        match (horizontal || turned) && Font::Label.width(&one) + 24.0 <= length {
            true => vec![one],
            false => channels.iter().map(|c| c.to_string()).collect(),
        };
    let w = lines
        .iter()
        .map(|l| Font::Label.width(l))
        .fold(0.0, f64::max)
        + 8.0;
    let h = lines.len() as f64 * LEADING + 3.0;
    let rect = match turned {
        true => Rect::centred(cx, cy, h, w),
        false => Rect::centred(cx, cy, w, h),
    };
    LabelShape {
        rect,
        lines,
        turned,
    }
}

/// The legend (a swatch and words per shade) and the footer.
fn legend(scene: &mut Scene) {
    let y = layout::HEIGHT - 40.0;
    let mut x = layout::PLACES[0].rect.x;
    for (shade, words) in [
        (Shade::Loop, "CPU 1: the torque loop (SCHED_FIFO)"),
        (Shade::Perception, "CPU 0: perception and people"),
        (Shade::Free, "not pinned"),
    ] {
        scene
            .swatches
            .push((Rect::new(x, y - 9.0, 12.0, 12.0), shade));
        let w = Font::Small.width(words);
        scene.texts.push(Line {
            x: x + 18.0 + w / 2.0,
            y: y + 1.0,
            text: words.into(),
            font: Font::Small,
        });
        x += 18.0 + w + 24.0;
    }
    let footer = "Drawn from the code by `phri-supervisor --draw-cell docs/cell.svg`: the roster of deploy/phri.toml, the ports of ipc-schema/src/ports.rs";
    scene.texts.push(Line {
        x: layout::WIDTH / 2.0,
        y: layout::HEIGHT - 14.0,
        text: footer.into(),
        font: Font::Small,
    });
}

impl Scene {
    /// The picture of `graph`.
    pub fn new(graph: &CellGraph) -> Scene {
        let mut scene = Scene {
            width: layout::WIDTH,
            height: layout::HEIGHT,
            boxes: (0..graph.nodes.len()).map(|i| box_of(graph, i)).collect(),
            arrows: Vec::new(),
            texts: Vec::new(),
            swatches: Vec::new(),
        };
        for e in &graph.edges {
            let (a, b) = (&graph.nodes[e.from].place, &graph.nodes[e.to].place);
            let arrow = match layout::route_of(a.slot, b.slot)
                .filter(|_| !a.slot.is_empty() && !b.slot.is_empty())
            {
                Some(r) => {
                    let label = match r.label {
                        Label::On(k) | Label::Turned(k) if k + 1 < r.points.len() => {
                            Some(label_on(
                                &e.channels,
                                r.points[k],
                                r.points[k + 1],
                                matches!(r.label, Label::Turned(_)),
                            ))
                        }
                        _ => None,
                    };
                    Arrow {
                        from: a.slot.into(),
                        to: b.slot.into(),
                        channels: e.channels.clone(),
                        points: r.points.to_vec(),
                        label,
                        routed: true,
                        shared: r.label == Label::Shared,
                    }
                }
                None => {
                    let centre = |r: &Rect| (r.x + r.w / 2.0, r.y + r.h / 2.0);
                    let (p, q) = (centre(&a.rect), centre(&b.rect));
                    Arrow {
                        from: a.slot.into(),
                        to: b.slot.into(),
                        channels: e.channels.clone(),
                        points: vec![p, q],
                        label: Some(label_on(&e.channels, p, q, false)),
                        routed: false,
                        shared: false,
                    }
                }
            };
            scene.arrows.push(arrow);
        }
        legend(&mut scene);
        scene
    }
}
