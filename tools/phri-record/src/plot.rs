//! A minimal line plotter: an RGB buffer, Bresenham lines, axes with tick
//! marks, labels and a legend ([`crate::text`]), PNG output with the `png` crate.

use crate::text;

pub type Rgb = [u8; 3];
pub const WHITE: Rgb = [255, 255, 255];
pub const BLACK: Rgb = [0, 0, 0];
pub const GREY: Rgb = [200, 200, 200];
pub const BLUE: Rgb = [31, 119, 180];
pub const RED: Rgb = [214, 39, 40];
pub const ORANGE: Rgb = [255, 127, 14];

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

    pub fn get(&self, x: usize, y: usize) -> Rgb {
        let i = (y * self.w + x) * 3;
        [self.px[i], self.px[i + 1], self.px[i + 2]]
    }

    /// Bresenham line from (x0, y0) to (x1, y1), pixel coordinates.
    pub fn line(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: Rgb) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut e) = (x0, y0, dx + dy);
        loop {
            self.set(x, y, c);
            if x == x1 && y == y1 {
                break;
            }
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

    /// Write as an 8-bit RGB PNG.
    pub fn save_png(&self, path: &std::path::Path) -> Result<(), PngError> {
        let f = std::fs::File::create(path).map_err(|source| PngError::Create {
            path: path.to_path_buf(),
            source,
        })?;
        let encoding = |source| PngError::Encode {
            path: path.to_path_buf(),
            source,
        };
        let mut enc = png::Encoder::new(std::io::BufWriter::new(f), self.w as u32, self.h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(encoding)?;
        wr.write_image_data(&self.px).map_err(encoding)?;
        wr.finish().map_err(encoding)
    }
}

/// A PNG that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PngError {
    #[error("cannot create '{}': {source}", path.display())]
    Create {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: {source}", path.display())]
    Encode {
        path: std::path::PathBuf,
        #[source]
        source: png::EncodingError,
    },
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
    pub fn new(c: &Canvas, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> Axes {
        Axes {
            x0,
            x1,
            y0,
            y1,
            left: 90,
            top: 80,
            right: c.w as i64 - 30,
            bottom: c.h as i64 - 64,
        }
    }

    pub fn px(&self, x: f64) -> i64 {
        let f = (x - self.x0) / (self.x1 - self.x0);
        self.left + (f * (self.right - self.left) as f64).round() as i64
    }

    pub fn py(&self, y: f64) -> i64 {
        let f = (y - self.y0) / (self.y1 - self.y0);
        self.bottom - (f * (self.bottom - self.top) as f64).round() as i64
    }

    /// Frame, grid lines and tick marks at "nice" steps.
    pub fn draw(&self, c: &mut Canvas) {
        for x in ticks(self.x0, self.x1).1 {
            let p = self.px(x);
            for y in (self.top..self.bottom).step_by(4) {
                c.set(p, y, GREY);
            }
            c.line(p, self.bottom, p, self.bottom + 6, BLACK);
        }
        for y in ticks(self.y0, self.y1).1 {
            let p = self.py(y);
            for x in (self.left..self.right).step_by(4) {
                c.set(x, p, GREY);
            }
            c.line(self.left - 6, p, self.left, p, BLACK);
        }
        c.line(self.left, self.top, self.right, self.top, BLACK);
        c.line(self.left, self.bottom, self.right, self.bottom, BLACK);
        c.line(self.left, self.top, self.left, self.bottom, BLACK);
        c.line(self.right, self.top, self.right, self.bottom, BLACK);
    }

    /// Tick values, the title (above the plot), the x label (below, centred)
    /// and the y label (above the y axis), in black at text scale 2.
    pub fn label(&self, c: &mut Canvas, title: &str, xlabel: &str, ylabel: &str) {
        const S: i64 = 2;
        let (sx, xs) = ticks(self.x0, self.x1);
        for x in xs {
            let t = text::tick_label(x, sx);
            text::draw(
                c,
                self.px(x) - text::width(&t, S) / 2,
                self.bottom + 10,
                &t,
                BLACK,
                S,
            );
        }
        let (sy, ys) = ticks(self.y0, self.y1);
        for y in ys {
            let t = text::tick_label(y, sy);
            let h = text::height(S);
            text::draw(
                c,
                self.left - 10 - text::width(&t, S),
                self.py(y) - h / 2,
                &t,
                BLACK,
                S,
            );
        }
        let h = text::height(S);
        let xl = (self.left + self.right - text::width(xlabel, S)) / 2;
        text::draw(c, xl, self.bottom + 20 + h, xlabel, BLACK, S);
        text::draw(c, self.left - 40, self.top - 12 - h, ylabel, BLACK, S);
        text::draw(c, self.left - 40, self.top - 24 - 2 * h, title, BLACK, S);
    }

    /// A legend in the top right corner above the plot: a short line in each
    /// colour, then its label.
    pub fn legend(&self, c: &mut Canvas, items: &[(Rgb, &str)]) {
        const S: i64 = 2;
        let h = text::height(S);
        let mut y = 8;
        for (col, label) in items {
            let x = self.right - text::width(label, S);
            for dy in -1..=1 {
                c.line(x - 30, y + h / 2 + dy, x - 8, y + h / 2 + dy, *col);
            }
            text::draw(c, x, y, label, BLACK, S);
            y += h + 5;
        }
    }

    /// Polyline through the points; a non-finite point breaks the line.
    pub fn polyline(&self, c: &mut Canvas, pts: &[(f64, f64)], col: Rgb) {
        let mut prev: Option<(i64, i64)> = None;
        for &(x, y) in pts {
            if !(x.is_finite() && y.is_finite()) {
                prev = None;
                continue;
            }
            let p = (self.px(x), self.py(y));
            match prev {
                Some(q) if q != p => c.line(q.0, q.1, p.0, p.1, col),
                None => c.set(p.0, p.1, col),
                _ => {}
            }
            prev = Some(p);
        }
    }

    /// Dashed horizontal line at `y`.
    pub fn hline(&self, c: &mut Canvas, y: f64, col: Rgb) {
        let p = self.py(y);
        let mut x = self.left;
        while x < self.right {
            c.line(x, p, (x + 6).min(self.right), p, col);
            x += 12;
        }
    }

    /// Vertical line at `x`.
    pub fn vline(&self, c: &mut Canvas, x: f64, col: Rgb) {
        let p = self.px(x);
        c.line(p, self.top, p, self.bottom, col);
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
        let c = Canvas::new(200, 100);
        let a = Axes::new(&c, (0.0, 1.0), (-1.0, 1.0));
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
