//! A minimal line plotter with two outputs of one drawing: a [`Figure`]
//! takes lines, dashed lines, polylines, rectangles and text (in pixel
//! coordinates) and draws each both into an RGB [`Canvas`] (PNG with the
//! `png` crate; Bresenham lines, text anti-aliased from the embedded font,
//! [`crate::text`]) and into an SVG document ([`crate::svg`]); [`Axes`] put
//! frames, ticks, labels and legends on it.
//!
//! Why this and not `plotters`: the figures, their layout and their tests
//! stay as they are; both formats come from the same calls, so they cannot
//! drift apart; the only new dependency for drawing is `ab_glyph` (no
//! `image`, no font discovery: `plotters` without a font feature panics on
//! the first label and with system fonts fails on machines that have none).

use std::path::{Path, PathBuf};

use crate::svg::Svg;
use crate::text::{self, Anchor};

pub type Rgb = [u8; 3];
pub const WHITE: Rgb = [255, 255, 255];
pub const BLACK: Rgb = [0, 0, 0];
pub const GREY: Rgb = [200, 200, 200];
pub const BLUE: Rgb = [31, 119, 180];
pub const RED: Rgb = [214, 39, 40];
pub const ORANGE: Rgb = [255, 127, 14];

/// Font sizes [px, em]: tick values, axis labels and legend, title.
pub const TICK_SIZE: f64 = 14.0;
pub const LABEL_SIZE: f64 = 16.0;
pub const TITLE_SIZE: f64 = 18.0;

/// An RGB image.
pub struct Canvas {
    pub w: usize,
    pub h: usize,
    pub px: Vec<u8>,
}

impl Canvas {
    pub fn new(w: usize, h: usize) -> Canvas {
        Canvas {
            w,
            h,
            px: vec![255; w * h * 3],
        }
    }

    pub fn set(&mut self, x: i64, y: i64, c: Rgb) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = (y as usize * self.w + x as usize) * 3;
            self.px[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Blend the pixel (x, y) towards `c` by `alpha` (0: unchanged, 1: `c`).
    pub fn blend(&mut self, x: i64, y: i64, c: Rgb, alpha: f32) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let a = alpha.clamp(0.0, 1.0);
            let i = (y as usize * self.w + x as usize) * 3;
            for (k, p) in self.px[i..i + 3].iter_mut().enumerate() {
                *p = (*p as f32 + (c[k] as f32 - *p as f32) * a).round() as u8;
            }
        }
    }

    pub fn get(&self, x: usize, y: usize) -> Rgb {
        let i = (y * self.w + x) * 3;
        [self.px[i], self.px[i + 1], self.px[i + 2]]
    }

    /// Bresenham line from (x0, y0) to (x1, y1), pixel coordinates; every
    /// pixel `keep` accepts (by its index along the line) is drawn.
    fn line_where(
        &mut self,
        x0: i64,
        y0: i64,
        x1: i64,
        y1: i64,
        c: Rgb,
        keep: impl Fn(u64) -> bool,
    ) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut e) = (x0, y0, dx + dy);
        let mut i = 0u64;
        loop {
            if keep(i) {
                self.set(x, y, c);
            }
            if x == x1 && y == y1 {
                break;
            }
            i += 1;
            let e2 = 2 * e;
            if e2 >= dy {
                e += dy;
                x += sx;
            }
            if e2 <= dx {
                e += dx;
                y += sy;
            }
        }
    }

    /// Bresenham line from (x0, y0) to (x1, y1), pixel coordinates.
    pub fn line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb) {
        self.line_where(x0, y0, x1, y1, c, |_| true);
    }

    /// Encode as an 8-bit RGB PNG.
    pub fn png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut buf = Vec::new();
        let mut enc = png::Encoder::new(&mut buf, self.w as u32, self.h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header()?;
        wr.write_image_data(&self.px)?;
        wr.finish()?;
        Ok(buf)
    }

    /// Write as an 8-bit RGB PNG.
    pub fn save_png(&self, path: &Path) -> Result<(), FigureError> {
        let buf = self.png().map_err(|source| FigureError::Encode {
            path: path.to_path_buf(),
            source,
        })?;
        write(path, &buf)
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), FigureError> {
    std::fs::write(path, bytes).map_err(|source| FigureError::Create {
        path: path.to_path_buf(),
        source,
    })
}

/// A figure that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("cannot write '{}': {source}", path.display())]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: {source}", path.display())]
    Encode {
        path: PathBuf,
        #[source]
        source: png::EncodingError,
    },
}

/// Which files a figure is written as.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// `NAME.png` only
    Png,
    /// `NAME.svg` only
    Svg,
    /// `NAME.png` and `NAME.svg`
    Both,
}

/// One drawing, kept as an RGB canvas and as an SVG document at once:
/// every primitive goes to both, in the same order.
pub struct Figure {
    pub canvas: Canvas,
    svg: Svg,
}

impl Figure {
    /// A white `w` × `h` \[px\] figure.
    pub fn new(w: usize, h: usize) -> Figure {
        Figure {
            canvas: Canvas::new(w, h),
            svg: Svg::new(w, h),
        }
    }

    pub fn w(&self) -> usize {
        self.canvas.w
    }

    pub fn h(&self) -> usize {
        self.canvas.h
    }

    /// A one-pixel line through the pixels (x0, y0) and (x1, y1).
    pub fn line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb) {
        self.canvas.line(x0, y0, x1, y1, c);
        self.svg.line(x0, y0, x1, y1, c);
    }

    /// A horizontal or vertical dashed line over the pixels from (x0, y0)
    /// to (x1, y1): `on` pixels drawn, then `off` not, from (x0, y0) on.
    // a drawing primitive: two end points, a colour and the dash pattern, as `line` plus the pattern
    #[allow(clippy::too_many_arguments)]
    pub fn dashed(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb, on: u32, off: u32) {
        let period = (on + off).max(1) as u64;
        let (x0, x1) = (x0.min(x1), x0.max(x1));
        let (y0, y1) = (y0.min(y1), y0.max(y1));
        self.canvas
            .line_where(x0, y0, x1, y1, c, |i| i % period < on as u64);
        self.svg.dashed(x0, y0, x1, y1, c, on, off);
    }

    /// A filled rectangle over `w` × `h` pixels from pixel (x, y).
    pub fn rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        for py in y..y + h {
            for px in x..x + w {
                self.canvas.set(px, py, c);
            }
        }
        self.svg.rect(x, y, w, h, c);
    }

    /// A polyline through points in pixel coordinates (pixel (i, j) at
    /// (i, j)); the canvas rounds them to pixels and joins them with
    /// Bresenham lines, the SVG keeps them exact; points that round to the
    /// pixel of the one before are left out of both.
    pub fn polyline(&mut self, pts: &[(f64, f64)], c: Rgb) {
        let mut kept: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
        let mut prev: Option<(i64, i64)> = None;
        for &(x, y) in pts {
            let p = (x.round() as i64, y.round() as i64);
            match prev {
                Some(q) if q == p => continue,
                Some(q) => self.canvas.line(q.0, q.1, p.0, p.1, c),
                None => self.canvas.set(p.0, p.1, c),
            }
            prev = Some(p);
            kept.push((x, y));
        }
        self.svg.polyline(&kept, c);
    }

    /// Text at `size` [px, em], its baseline at `y`, anchored at `x`.
    pub fn text(&mut self, x: f64, y: f64, s: &str, c: Rgb, size: f64, anchor: Anchor) {
        text::draw(&mut self.canvas, x, y, s, c, size, anchor);
        self.svg.text(x, y, s, c, size, anchor);
    }

    /// The figure as an SVG document.
    pub fn svg(&self) -> String {
        self.svg.finish()
    }

    /// Write `DIR/NAME.png`, `DIR/NAME.svg` or both; the paths written.
    pub fn save(
        &self,
        dir: &Path,
        name: &str,
        format: Format,
    ) -> Result<Vec<PathBuf>, FigureError> {
        let mut written = Vec::new();
        if matches!(format, Format::Png | Format::Both) {
            let path = dir.join(format!("{name}.png"));
            self.canvas.save_png(&path)?;
            written.push(path);
        }
        if matches!(format, Format::Svg | Format::Both) {
            let path = dir.join(format!("{name}.svg"));
            write(&path, self.svg().as_bytes())?;
            written.push(path);
        }
        Ok(written)
    }
}

/// A plot area mapping data coordinates into a canvas with margins.
pub struct Axes {
    pub x0: f64,
    pub x1: f64,
    pub y0: f64,
    pub y1: f64,
    /// pixel box: left, top, right, bottom
    pub left: i64,
    pub top: i64,
    pub right: i64,
    pub bottom: i64,
}

/// "Nice" tick step for a span (1, 2 or 5 × 10^k, about 5–10 ticks).
pub fn tick_step(span: f64) -> f64 {
    if !(span > 0.0 && span.is_finite()) {
        return 1.0;
    }
    let raw = span / 8.0;
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    p * if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// The tick step of `[lo, hi]` and the tick values in it (multiples of the step).
pub fn ticks(lo: f64, hi: f64) -> (f64, impl Iterator<Item = f64>) {
    let step = tick_step(hi - lo);
    let first = (lo / step).ceil();
    let last = if hi.is_finite() {
        (hi / step).floor()
    } else {
        first - 1.0
    };
    let count = (last - first + 1.0).clamp(0.0, 1000.0) as usize;
    (step, (0..count).map(move |i| (first + i as f64) * step))
}

/// Data range with a 5 % pad (a unit range around a constant).
pub fn range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if !lo.is_finite() {
        return None;
    }
    if hi - lo < 1e-12 {
        return Some((lo - 0.5, hi + 0.5));
    }
    let pad = (hi - lo) * 0.05;
    Some((lo - pad, hi + pad))
}

impl Axes {
    /// Axes over the figure with room for labels: 90 px left, 80 px top
    /// (title, y label, legend), 30 px right, 64 px bottom (ticks, x label).
    pub fn new(f: &Figure, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> Axes {
        Axes {
            x0,
            x1,
            y0,
            y1,
            left: 90,
            top: 80,
            right: f.w() as i64 - 30,
            bottom: f.h() as i64 - 64,
        }
    }

    /// Pixel column of `x` [px, exact].
    pub fn fx(&self, x: f64) -> f64 {
        let f = (x - self.x0) / (self.x1 - self.x0);
        self.left as f64 + f * (self.right - self.left) as f64
    }

    /// Pixel row of `y` [px, exact].
    pub fn fy(&self, y: f64) -> f64 {
        let f = (y - self.y0) / (self.y1 - self.y0);
        self.bottom as f64 - f * (self.bottom - self.top) as f64
    }

    /// Pixel column of `x`.
    pub fn px(&self, x: f64) -> i64 {
        let f = (x - self.x0) / (self.x1 - self.x0);
        self.left + (f * (self.right - self.left) as f64).round() as i64
    }

    /// Pixel row of `y`.
    pub fn py(&self, y: f64) -> i64 {
        let f = (y - self.y0) / (self.y1 - self.y0);
        self.bottom - (f * (self.bottom - self.top) as f64).round() as i64
    }

    /// Frame, dotted grid lines and tick marks at "nice" steps.
    pub fn draw(&self, f: &mut Figure) {
        for x in ticks(self.x0, self.x1).1 {
            let p = self.px(x);
            f.dashed(p, self.top, p, self.bottom - 1, GREY, 1, 3);
            f.line(p, self.bottom, p, self.bottom + 6, BLACK);
        }
        for y in ticks(self.y0, self.y1).1 {
            let p = self.py(y);
            f.dashed(self.left, p, self.right - 1, p, GREY, 1, 3);
            f.line(self.left - 6, p, self.left, p, BLACK);
        }
        f.line(self.left, self.top, self.right, self.top, BLACK);
        f.line(self.left, self.bottom, self.right, self.bottom, BLACK);
        f.line(self.left, self.top, self.left, self.bottom, BLACK);
        f.line(self.right, self.top, self.right, self.bottom, BLACK);
    }

    /// Tick values, the title (top left), the x label (below, centred)
    /// and the y label (above the y axis), in black.
    pub fn label(&self, f: &mut Figure, title: &str, xlabel: &str, ylabel: &str) {
        let cap = text::cap_height(TICK_SIZE);
        let (sx, xs) = ticks(self.x0, self.x1);
        for x in xs {
            let t = text::tick_label(x, sx);
            let base = (self.bottom + 10) as f64 + cap;
            f.text(
                self.px(x) as f64 + 0.5,
                base,
                &t,
                BLACK,
                TICK_SIZE,
                Anchor::Middle,
            );
        }
        let (sy, ys) = ticks(self.y0, self.y1);
        for y in ys {
            let t = text::tick_label(y, sy);
            let base = self.py(y) as f64 + 0.5 + cap / 2.0;
            f.text(
                (self.left - 10) as f64,
                base,
                &t,
                BLACK,
                TICK_SIZE,
                Anchor::End,
            );
        }
        let xl = (self.left + self.right) as f64 / 2.0;
        let base = (self.bottom + 22) as f64 + cap + text::cap_height(LABEL_SIZE);
        f.text(xl, base, xlabel, BLACK, LABEL_SIZE, Anchor::Middle);
        let x = (self.left - 40) as f64;
        f.text(
            x,
            (self.top - 14) as f64,
            ylabel,
            BLACK,
            LABEL_SIZE,
            Anchor::Start,
        );
        f.text(
            x,
            (self.top - 48) as f64,
            title,
            BLACK,
            TITLE_SIZE,
            Anchor::Start,
        );
    }

    /// A legend in the top right corner above the plot: a short thick line
    /// in each colour, then its label (right-aligned to the plot's edge).
    pub fn legend(&self, f: &mut Figure, items: &[(Rgb, &str)]) {
        let cap = text::cap_height(LABEL_SIZE);
        let mut base = 8.0 + cap;
        for (col, label) in items {
            let x = self.right as f64 - text::width(label, LABEL_SIZE);
            let mid = (base - cap / 2.0).round() as i64;
            f.rect(x.round() as i64 - 30, mid - 1, 23, 3, *col);
            f.text(
                self.right as f64,
                base,
                label,
                BLACK,
                LABEL_SIZE,
                Anchor::End,
            );
            base += (LABEL_SIZE * 1.25).round();
        }
    }

    /// Polyline through the points (data coordinates); a non-finite point
    /// breaks the line.
    pub fn polyline(&self, f: &mut Figure, pts: &[(f64, f64)], col: Rgb) {
        let mut run: Vec<(f64, f64)> = Vec::new();
        for &(x, y) in pts {
            if !(x.is_finite() && y.is_finite()) {
                f.polyline(&run, col);
                run.clear();
                continue;
            }
            run.push((self.fx(x), self.fy(y)));
        }
        f.polyline(&run, col);
    }

    /// Dashed horizontal line at `y`.
    pub fn hline(&self, f: &mut Figure, y: f64, col: Rgb) {
        let p = self.py(y);
        f.dashed(self.left, p, self.right, p, col, 7, 5);
    }

    /// Vertical line at `x`.
    pub fn vline(&self, f: &mut Figure, x: f64, col: Rgb) {
        let p = self.px(x);
        f.line(p, self.top, p, self.bottom, col);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_hits_both_ends_and_diagonal() {
        let mut c = Canvas::new(10, 10);
        c.line(1, 1, 8, 8, BLACK);
        for i in 1..=8 {
            assert_eq!(c.get(i, i), BLACK);
        }
        assert_eq!(c.get(0, 0), WHITE);
        c.line(9, 0, 0, 3, RED);
        assert_eq!(c.get(9, 0), RED);
        assert_eq!(c.get(0, 3), RED);
    }

    #[test]
    fn axes_map_corners() {
        let f = Figure::new(200, 100);
        let a = Axes::new(&f, (0.0, 1.0), (-1.0, 1.0));
        assert_eq!(a.px(0.0), a.left);
        assert_eq!(a.px(1.0), a.right);
        assert_eq!(a.py(-1.0), a.bottom);
        assert_eq!(a.py(1.0), a.top);
        assert_eq!(tick_step(10.0), 1.0);
        let (step, t) = ticks(-0.25, 1.0);
        assert_eq!(step, 0.2);
        let t: Vec<f64> = t.collect();
        assert_eq!(t.len(), 7);
        assert!(
            (t[0] + 0.2).abs() < 1e-12 && (t[6] - 1.0).abs() < 1e-12,
            "{t:?}"
        );
    }
}
