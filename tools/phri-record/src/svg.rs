//! A small SVG writer for the figures: the primitives of [`crate::plot::Figure`]
//! (lines, dashed lines, polylines, filled rectangles, text) as SVG elements,
//! the text as `<text>` in the embedded font ([`crate::text::FONT_TTF`],
//! declared with `@font-face` as a data URL), so a browser draws the same
//! letters, at the same widths, as the PNG.
//!
//! Coordinates are the canvas's pixels (x right, y down, pixel `(i, j)`
//! covering `[i, i+1] × [j, j+1]`): a one-pixel line through pixels is drawn
//! through their centres (`+0.5`).

use std::fmt::Write as _;

use crate::plot::Rgb;
use crate::text::{Anchor, FONT_FAMILY, FONT_TTF};

/// An SVG document being written.
pub struct Svg {
    w: usize,
    h: usize,
    body: String,
}

fn colour(c: Rgb) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// A coordinate with at most 2 decimals, without trailing zeros.
fn num(v: f64) -> String {
    let s = format!("{:.2}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// `s` escaped for XML text and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

impl Svg {
    /// An empty `w` × `h` \[px\] document with a white background.
    pub fn new(w: usize, h: usize) -> Svg {
        let mut body = String::new();
        let _ = writeln!(body, r##"<rect width="{w}" height="{h}" fill="#ffffff"/>"##);
        Svg { w, h, body }
    }

    /// A one-pixel line through the pixels (x0, y0) and (x1, y1), both drawn.
    pub fn line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb) {
        let _ = writeln!(
            self.body,
            r##"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-linecap="square"/>"##,
            x0 as f64 + 0.5,
            y0 as f64 + 0.5,
            x1 as f64 + 0.5,
            y1 as f64 + 0.5,
            colour(c)
        );
    }

    /// A horizontal or vertical dashed line over the pixels from (x0, y0) to
    /// (x1, y1): `on` pixels drawn, `off` not, starting at (x0, y0).
    // a drawing primitive: two end points, a colour and the dash pattern, as `line` plus the pattern
    #[allow(clippy::too_many_arguments)]
    pub fn dashed(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb, on: u32, off: u32) {
        // from the first pixel's edge to the last one's far edge, along the line
        let (ax, ay, bx, by) = if y0 == y1 {
            let (l, r) = (x0.min(x1), x0.max(x1));
            (l as f64, y0 as f64 + 0.5, r as f64 + 1.0, y0 as f64 + 0.5)
        } else {
            let (t, b) = (y0.min(y1), y0.max(y1));
            (x0 as f64 + 0.5, t as f64, x0 as f64 + 0.5, b as f64 + 1.0)
        };
        let _ = writeln!(
            self.body,
            r##"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-dasharray="{on} {off}"/>"##,
            num(ax),
            num(ay),
            num(bx),
            num(by),
            colour(c)
        );
    }

    /// A one-pixel polyline through points in pixel coordinates (the centre
    /// of pixel (i, j) is (i, j)); a single point is one pixel.
    pub fn polyline(&mut self, pts: &[(f64, f64)], c: Rgb) {
        match pts {
            [] => {}
            [(x, y)] => self.rect(x.round() as i64, y.round() as i64, 1, 1, c),
            _ => {
                self.body.push_str(r##"<polyline fill="none" stroke=""##);
                self.body.push_str(&colour(c));
                self.body
                    .push_str(r##"" stroke-linejoin="round" stroke-linecap="round" points=""##);
                for (i, (x, y)) in pts.iter().enumerate() {
                    if i > 0 {
                        self.body.push(' ');
                    }
                    let _ = write!(self.body, "{},{}", num(x + 0.5), num(y + 0.5));
                }
                self.body.push_str("\"/>\n");
            }
        }
    }

    /// A filled rectangle over `w` × `h` pixels from pixel (x, y).
    pub fn rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        let _ = writeln!(
            self.body,
            r##"<rect x="{x}" y="{y}" width="{w}" height="{h}" fill="{}"/>"##,
            colour(c)
        );
    }

    /// Text in the embedded font at `size` [px, em], its baseline at `y`,
    /// anchored at `x`.
    pub fn text(&mut self, x: f64, y: f64, s: &str, c: Rgb, size: f64, anchor: Anchor) {
        let _ = writeln!(
            self.body,
            r##"<text x="{}" y="{}" font-size="{}" fill="{}" text-anchor="{}">{}</text>"##,
            num(x),
            num(y),
            num(size),
            colour(c),
            anchor.svg(),
            escape(s)
        );
    }

    /// The whole document.
    pub fn finish(&self) -> String {
        let (w, h) = (self.w, self.h);
        let mut out = String::with_capacity(self.body.len() + FONT_TTF.len() * 4 / 3 + 1024);
        out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let _ = writeln!(
            out,
            r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="'{FONT_FAMILY}', sans-serif">"##
        );
        let _ = writeln!(
            out,
            "<style>@font-face {{ font-family: '{FONT_FAMILY}'; src: url(data:font/ttf;base64,{}) format('truetype'); }}</style>",
            base64(FONT_TTF)
        );
        out.push_str(&self.body);
        out.push_str("</svg>\n");
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
        assert_eq!(base64(&[0xff, 0xfe, 0x00]), "//4A");
    }

    #[test]
    fn text_is_escaped_and_numbers_are_short() {
        assert_eq!(escape("a<b & \"c\"'"), "a&lt;b &amp; &quot;c&quot;&apos;");
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-0.001), "0");
        assert_eq!(num(2.25), "2.25");
        assert_eq!(num(2.0001), "2");
        assert_eq!(num(12.5), "12.5");
    }

    #[test]
    fn a_document_has_its_size_font_and_elements() {
        let mut s = Svg::new(40, 30);
        s.line(1, 2, 10, 2, [0, 0, 0]);
        s.dashed(0, 5, 9, 5, [200, 200, 200], 1, 3);
        s.polyline(&[(1.0, 1.0), (2.25, 3.0)], [31, 119, 180]);
        s.text(20.0, 15.0, "x [m] <", [0, 0, 0], 16.0, Anchor::Middle);
        let doc = s.finish();
        assert!(doc.starts_with("<?xml"));
        assert!(doc.contains(r##"width="40" height="30" viewBox="0 0 40 30""##));
        assert!(doc.contains(r##"<line x1="1.5" y1="2.5" x2="10.5" y2="2.5" stroke="#000000""##));
        assert!(doc.contains(
            r##"x1="0" y1="5.5" x2="10" y2="5.5" stroke="#c8c8c8" stroke-dasharray="1 3""##
        ));
        assert!(doc.contains(r##"points="1.5,1.5 2.75,3.5""##));
        assert!(doc.contains(r##"text-anchor="middle">x [m] &lt;</text>"##));
        assert!(doc.contains(&base64(&FONT_TTF[..300])[..400]));
        assert!(doc.trim_end().ends_with("</svg>"));
    }
}
