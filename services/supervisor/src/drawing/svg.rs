//! A [`Scene`] as SVG text: plain elements (rect, polyline, text), no
//! script, no external reference; the same scene gives the same bytes.

use std::fmt::Write;

use super::scene::{Font, Scene, Shade};

const MONO: &str = "ui-monospace, SFMono-Regular, Menlo, Consolas, 'DejaVu Sans Mono', monospace";
const SANS: &str = "-apple-system, 'Segoe UI', Helvetica, Arial, 'DejaVu Sans', sans-serif";

/// A coordinate: whole numbers without decimals, else one decimal.
fn n(v: f64) -> String {
    let r = (v * 10.0).round() / 10.0;
    if r.fract() == 0.0 {
        format!("{}", r as i64)
    } else {
        format!("{r:.1}")
    }
}

/// `text` escaped for XML character data and attribute values.
pub fn escape(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            '\'' => s.push_str("&apos;"),
            c => s.push(c),
        }
    }
    s
}

fn colours(shade: Shade) -> (&'static str, &'static str) {
    match shade {
        Shade::Loop => ("#fdebd3", "#c7862f"),
        Shade::Perception => ("#e1ecf9", "#4d7fbf"),
        Shade::Free => ("#f2f2f2", "#8a8a8a"),
    }
}

/// The font attributes of `font`.
fn font_attrs(font: Font) -> String {
    let (family, weight, fill) = match font {
        Font::Title => ("mono", "bold", "#1a1a1a"),
        Font::Body => ("sans", "normal", "#444444"),
        Font::Note => ("mono", "normal", "#333333"),
        Font::Label => ("mono", "normal", "#1a1a1a"),
        Font::Small => ("sans", "normal", "#555555"),
    };
    let weight = match weight {
        "bold" => " font-weight=\"bold\"",
        _ => "",
    };
    format!(
        "class=\"{family}\" font-size=\"{}\"{weight} fill=\"{fill}\"",
        n(font.size())
    )
}

impl Scene {
    /// The picture as an SVG document (ends with a newline).
    pub fn to_svg(&self) -> String {
        let mut s = String::new();
        let (w, h) = (n(self.width), n(self.height));
        let _ = writeln!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {w} {h}\" width=\"{w}\" height=\"{h}\" role=\"img\" aria-labelledby=\"title\">"
        );
        let _ = writeln!(
            s,
            "<title id=\"title\">The phri cell: its processes and the channels between them</title>"
        );
        let _ = writeln!(
            s,
            "<style>.mono {{ font-family: {MONO}; }} .sans {{ font-family: {SANS}; }}</style>"
        );
        let _ = writeln!(
            s,
            "<defs><marker id=\"head\" viewBox=\"0 0 10 10\" refX=\"10\" refY=\"5\" markerWidth=\"7\" markerHeight=\"7\" orient=\"auto\"><path d=\"M0,0 L10,5 L0,10 z\" fill=\"#555555\"/></marker></defs>"
        );
        let _ = writeln!(
            s,
            "<rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" fill=\"#ffffff\"/>"
        );
        s.push_str("<g id=\"arrows\" fill=\"none\" stroke=\"#555555\" stroke-width=\"1.3\">\n");
        for a in &self.arrows {
            let points: Vec<String> = a
                .points
                .iter()
                .map(|(x, y)| format!("{},{}", n(*x), n(*y)))
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" marker-end=\"url(#head)\"><title>{} → {}: {}</title></polyline>",
                points.join(" "),
                escape(&a.from),
                escape(&a.to),
                escape(&a.channels.join(", "))
            );
        }
        s.push_str("</g>\n<g id=\"processes\">\n");
        for b in &self.boxes {
            let (fill, stroke) = colours(b.shade);
            let r = b.rect;
            let _ = writeln!(
                s,
                "<g><title>{}</title><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" rx=\"6\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"1.5\"/>",
                escape(&b.tooltip),
                n(r.x),
                n(r.y),
                n(r.w),
                n(r.h)
            );
            for l in &b.lines {
                let _ = writeln!(
                    s,
                    "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" {}>{}</text>",
                    n(l.x),
                    n(l.y),
                    font_attrs(l.font),
                    escape(&l.text)
                );
            }
            s.push_str("</g>\n");
        }
        s.push_str("</g>\n<g id=\"channels\">\n");
        for a in &self.arrows {
            let Some(label) = &a.label else { continue };
            let r = label.rect;
            let (cx, cy) = (r.x + r.w / 2.0, r.y + r.h / 2.0);
            let _ = writeln!(
                s,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" rx=\"3\" fill=\"#ffffff\" fill-opacity=\"0.92\"/>",
                n(r.x),
                n(r.y),
                n(r.w),
                n(r.h)
            );
            let turn = match label.turned {
                true => format!(" transform=\"rotate(-90 {} {})\"", n(cx), n(cy)),
                false => String::new(),
            };
            let count = label.lines.len() as f64;
            for (k, line) in label.lines.iter().enumerate() {
                // lines centred on the label's centre, baselines 13 px apart
                let y = cy + (k as f64 - (count - 1.0) / 2.0) * 13.0 + 3.5;
                let _ = writeln!(
                    s,
                    "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\"{turn} {}>{}</text>",
                    n(cx),
                    n(y),
                    font_attrs(Font::Label),
                    escape(line)
                );
            }
        }
        s.push_str("</g>\n<g id=\"legend\">\n");
        for (r, shade) in &self.swatches {
            let (fill, stroke) = colours(*shade);
            let _ = writeln!(
                s,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" rx=\"2\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"1.5\"/>",
                n(r.x),
                n(r.y),
                n(r.w),
                n(r.h)
            );
        }
        for l in &self.texts {
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" {}>{}</text>",
                n(l.x),
                n(l.y),
                font_attrs(l.font),
                escape(&l.text)
            );
        }
        s.push_str("</g>\n</svg>\n");
        s
    }
}
