//! Isolated flying pixels: depth readings that agree with none of their
//! neighbours. A real surface seen by a Kinect-class camera gives every pixel
//! neighbours at nearly its depth (they differ by the sensor noise and by the
//! surface's slope across one pixel); a flying pixel (multipath, a glint, a
//! corrupt sample) floats alone in front of or behind them. Left in the
//! frame, one flying pixel near the robot is an obstacle to the repulsion
//! (eqs. 15-18): the arm evades nothing, slows or stops, and the disturbance
//! can look like a collision. [`FlyingPixels`] removes every reading with
//! fewer than [`MIN_SUPPORT`] of its 8 neighbours within the tolerance of its
//! depth, which keeps surfaces, their edges and corners.

use crate::camera::Intrinsics;
use crate::error::{check_frame, DepthError};
use crate::lanes::{by_lanes, load, store, Lanes};
use crate::noise::sigma_z;

/// Neighbours (of 8) that must agree with a reading for it to stay: 2 keeps
/// a surface's corner (3 neighbours on it) and a one-pixel-wide line but its
/// two end pixels, and removes a lone pixel and a lone pair.
pub const MIN_SUPPORT: u32 = 2;

/// Standard deviations of the difference of two neighbours' noise allowed.
pub const NOISE_SIGMAS: f64 = 3.0;

/// Steepest surface whose neighbouring pixels still support each other \[rad\]
/// (75° from facing the camera): the depth step across one pixel is
/// `z / f · tan(75°)`. Steeper surfaces are barely measured by a
/// structured-light camera anyway.
pub const MAX_INCIDENCE_RAD: f64 = 75.0 * std::f64::consts::PI / 180.0;

/// Depth bucket of the tolerance table: `depth_mm >> BUCKET_BITS`.
const BUCKET_BITS: u32 = 4;
const BUCKETS: usize = (u16::MAX as usize >> BUCKET_BITS) + 1;

/// What [`FlyingPixels::filter`] did to a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Filtered {
    /// readings removed as isolated flying pixels
    pub removed: usize,
    /// readings left (pixels of the output other than 0)
    pub valid: usize,
}

impl Filtered {
    /// Count one pixel: its reading `z` and what the filter left of it `o`.
    #[inline]
    fn count(&mut self, o: u16, z: u16) {
        self.removed += usize::from(o == 0 && z != 0);
        self.valid += usize::from(o != 0);
    }
}

/// The flying-pixel filter of one camera: a tolerance per depth, computed once.
#[derive(Clone, Debug)]
pub struct FlyingPixels {
    width: u32,
    height: u32,
    /// largest depth difference \[mm\] between neighbours on one surface, per
    /// 16 mm bucket of depth (a fixed-size table: a `u16 >> 4` indexes it
    /// without a bounds check)
    tolerance_mm: Box<[u16; BUCKETS]>,
    /// the vector width this CPU runs
    lanes: Lanes,
}

impl FlyingPixels {
    /// The filter for frames of camera `k`. Two neighbours at depth `z` \[m\]
    /// agree when they differ by at most
    /// `NOISE_SIGMAS · √2 · σ_z(z) + z / f · tan(MAX_INCIDENCE_RAD) + 1 mm`
    /// (σ_z: [`sigma_z`], the camera's axial noise; f: the larger focal
    /// length; 1 mm: the quantization). At 1 m that is 15 mm, at 2 m 40 mm,
    /// at 4 m 140 mm. Allocates its table (8 KiB) here.
    pub fn new(k: &Intrinsics) -> Result<FlyingPixels, DepthError> {
        k.validate()?;
        let f = k.fx.max(k.fy);
        let slope = MAX_INCIDENCE_RAD.tan() / f;
        let mut tolerance_mm = Box::new([0u16; BUCKETS]);
        for (b, t) in tolerance_mm.iter_mut().enumerate() {
            *t = {
                // the bucket's deepest depth: never stricter than the formula
                let z = (((b << BUCKET_BITS) + (1 << BUCKET_BITS) - 1) as f64) * 1e-3;
                let tol = NOISE_SIGMAS * std::f64::consts::SQRT_2 * sigma_z(z) + z * slope + 1e-3;
                // below the bucket's shallowest depth, and within what a u16
                // holds above its deepest, so that no reading (0) ever agrees
                // (`n + tol − z` wraps around neither end)
                let shallowest = (b << BUCKET_BITS).max(1) as f64 - 1.0;
                let headroom =
                    f64::from(u16::MAX) - (((b << BUCKET_BITS) + (1 << BUCKET_BITS) - 1) as f64);
                (tol * 1e3)
                    .ceil()
                    .min(shallowest)
                    .min(headroom)
                    .min(f64::from(u16::MAX / 2)) as u16
            };
        }
        Ok(FlyingPixels {
            width: k.width,
            height: k.height,
            tolerance_mm,
            lanes: Lanes::detect(),
        })
    }

    /// Largest difference \[mm\] between two neighbours at `depth_mm` that still agree.
    #[inline]
    pub fn tolerance_mm(&self, depth_mm: u16) -> u16 {
        self.tolerance_mm[(depth_mm >> BUCKET_BITS) as usize]
    }

    /// Copy `input` (a `width × height` row-major frame \[mm\], 0 = no
    /// reading) into `out` without its isolated flying pixels (set to 0);
    /// returns how many were removed. Allocates nothing; one pass, each pixel
    /// compared with its left and right neighbours, and with the rows above
    /// and below only when those two do not both agree.
    pub fn apply(&self, input: &[u16], out: &mut [u16]) -> Result<usize, DepthError> {
        self.filter(input, out).map(|f| f.removed)
    }

    /// [`FlyingPixels::apply`], also counting the readings left in `out` (in
    /// the same pass: no second pass over the frame to count them).
    pub fn filter(&self, input: &[u16], out: &mut [u16]) -> Result<Filtered, DepthError> {
        let (w, h) = (self.width as usize, self.height as usize);
        check_frame("flying-pixel input", self.width, self.height, input.len())?;
        check_frame("flying-pixel output", self.width, self.height, out.len())?;
        let mut f = Filtered::default();
        for y in 0..h {
            let out_row = &mut out[y * w..(y + 1) * w];
            if y == 0 || y + 1 == h || w < 3 {
                for (x, o) in out_row.iter_mut().enumerate() {
                    *o = self.keep_at_border(input, w, h, x, y);
                    f.count(*o, input[y * w + x]);
                }
                continue;
            }
            let up = &input[(y - 1) * w..y * w];
            let row = &input[y * w..(y + 1) * w];
            let down = &input[(y + 1) * w..(y + 2) * w];
            out_row[0] = self.keep_at_border(input, w, h, 0, y);
            out_row[w - 1] = self.keep_at_border(input, w, h, w - 1, y);
            f.count(out_row[0], row[0]);
            f.count(out_row[w - 1], row[w - 1]);
            let (removed, kept) = self.interior(up, row, down, &mut out_row[1..w - 1]);
            f.removed += removed;
            f.valid += kept;
        }
        Ok(f)
    }

    /// The interior pixels `1..w − 1` of a row (`up`, `row`, `down`: the three
    /// rows, full width) into `out` (`w − 2` pixels); returns how many it
    /// removed and how many readings it kept. A reading stays when at least
    /// [`MIN_SUPPORT`] of its 8 neighbours agree with it, counted branch-free
    /// over runs of pixels, so that it vectorises ([`Lanes`]): the same
    /// decisions as counting the two row neighbours first and the six others
    /// only when needed.
    fn interior(&self, up: &[u16], row: &[u16], down: &[u16], out: &mut [u16]) -> (usize, usize) {
        interior(self.lanes, &self.tolerance_mm, up, row, down, out)
    }

    /// The depths `n` \[mm\] that agree with `z`: `n + shift ≤ span` in
    /// wrapping 16-bit arithmetic (`shift = tol − z`, `span = 2 tol`).
    #[inline]
    fn window(&self, z: u16) -> (u16, u16) {
        let tol = self.tolerance_mm(z);
        (tol.wrapping_sub(z), 2 * tol)
    }

    /// The filtered value of pixel (x, y) where some neighbours lie outside the image.
    fn keep_at_border(&self, input: &[u16], w: usize, h: usize, x: usize, y: usize) -> u16 {
        let z = input[y * w + x];
        if z == 0 {
            return 0;
        }
        let (shift, span) = self.window(z);
        let mut support = 0u32;
        for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
            for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                if (nx, ny) != (x, y) && input[ny * w + nx].wrapping_add(shift) <= span {
                    support += 1;
                }
            }
        }
        if support >= MIN_SUPPORT {
            z
        } else {
            0
        }
    }
}

/// Pixels per run of [`interior_any`].
const RUN: usize = 32;

by_lanes! {
    fn interior(
        tolerance_mm: &[u16; BUCKETS],
        up: &[u16],
        row: &[u16],
        down: &[u16],
        out: &mut [u16],
    ) -> (usize, usize) = interior_any;
}

/// See [`FlyingPixels::interior`].
#[inline(always)]
fn interior_any(
    tolerance_mm: &[u16; BUCKETS],
    up: &[u16],
    row: &[u16],
    down: &[u16],
    out: &mut [u16],
) -> (usize, usize) {
    let n = out.len();
    let (mut removed, mut valid) = (0usize, 0usize);
    let mut x = 0;
    while x < n {
        let len = RUN.min(n - x);
        // the run's pixels and their 8 neighbours: out[x + i] is pixel
        // x + i + 1 of the row, its neighbours columns x + i ..= x + i + 2
        // (a short last run is padded with no reading)
        let take =
            |src: &[u16], off: usize| -> [u16; RUN] { load(&src[x + off..x + off + len], 0) };
        let z = take(row, 1);
        let nb = [
            take(row, 0),
            take(row, 2),
            take(up, 0),
            take(up, 1),
            take(up, 2),
            take(down, 0),
            take(down, 1),
            take(down, 2),
        ];
        let mut tol = [0u16; RUN];
        for i in 0..RUN {
            tol[i] = tolerance_mm[(z[i] >> BUCKET_BITS) as usize];
        }
        let mut kept = [0u16; RUN];
        let (mut gone, mut left) = (0u16, 0u16);
        for i in 0..RUN {
            let shift = tol[i].wrapping_sub(z[i]);
            let span = 2 * tol[i];
            let mut support = 0u16;
            for n in &nb {
                support += u16::from(n[i].wrapping_add(shift) <= span);
            }
            let keep = (z[i] != 0) & (support >= MIN_SUPPORT as u16);
            kept[i] = if keep { z[i] } else { 0 };
            gone += u16::from((z[i] != 0) & !keep);
            left += u16::from(keep);
        }
        store(out, x, &kept);
        removed += usize::from(gone);
        valid += usize::from(left);
        x += len;
    }
    (removed, valid)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filter(w: u32, h: u32) -> FlyingPixels {
        let k = Intrinsics {
            width: w,
            height: h,
            ..Intrinsics::KINECT
        };
        FlyingPixels::new(&k).unwrap()
    }

    /// The rule written out pixel by pixel: a reading stays when at least
    /// MIN_SUPPORT of its (up to 8) neighbours in the image agree with it.
    fn reference(f: &FlyingPixels, w: usize, h: usize, input: &[u16]) -> (Vec<u16>, usize) {
        let mut out = vec![0u16; w * h];
        let mut removed = 0;
        for y in 0..h {
            for x in 0..w {
                let z = input[y * w + x];
                if z == 0 {
                    continue;
                }
                let tol = i32::from(f.tolerance_mm(z));
                let mut support = 0;
                for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                    for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                        let n = i32::from(input[ny * w + nx]);
                        if (nx, ny) != (x, y) && n != 0 && (n - i32::from(z)).abs() <= tol {
                            support += 1;
                        }
                    }
                }
                if support >= MIN_SUPPORT {
                    out[y * w + x] = z;
                } else {
                    removed += 1;
                }
            }
        }
        (out, removed)
    }

    /// Every vector width this CPU runs removes exactly the pixels of the
    /// rule, on noisy surfaces with holes, steps, spikes and the far range
    /// (widths around the run length, so that short runs are met).
    #[test]
    fn every_vector_width_removes_what_the_rule_says() {
        let mut lcg = crate::lanes::test_sequence(99);
        let mut next = move || (lcg() >> 33) as u32;
        let mut removed_any = 0;
        for (w, h) in [(3u32, 3u32), (33, 5), (34, 7), (640, 24), (65, 4)] {
            let mut f = filter(w, h);
            let (wu, hu) = (w as usize, h as usize);
            let input: Vec<u16> = (0..wu * hu)
                .map(|i| match next() % 20 {
                    0 => 0,
                    1 => (next() % 65536) as u16,
                    2 => 400 + (next() % 4000) as u16,
                    3 => 65535,
                    _ => (1500 + (i % wu) as u32 * 2 + (next() % 30)) as u16,
                })
                .collect();
            let (want, want_removed) = reference(&f, wu, hu, &input);
            removed_any += want_removed;
            for lanes in Lanes::available() {
                f.lanes = lanes;
                let mut out = vec![7u16; wu * hu];
                let got = f.filter(&input, &mut out).unwrap();
                assert_eq!(out, want, "{w}x{h} {lanes:?}");
                assert_eq!(got.removed, want_removed, "{w}x{h} {lanes:?}");
                let left = want.iter().filter(|&&d| d != 0).count();
                assert_eq!(got.valid, left, "{w}x{h} {lanes:?}");
            }
        }
        assert!(removed_any > 50, "{removed_any}");
    }

    #[test]
    fn the_tolerance_follows_the_sensor_noise_and_the_slope() {
        let f = filter(640, 480);
        for (mm, lo, hi) in [(1000, 12, 20), (2000, 35, 45), (4000, 130, 150)] {
            let t = f.tolerance_mm(mm);
            assert!((lo..=hi).contains(&t), "{mm} mm: {t}");
        }
        assert!(f.tolerance_mm(30000) >= f.tolerance_mm(4000));
        // no reading (0) ever agrees: the tolerance stays within 1 .. z and
        // within what a u16 holds above z
        for z in 1..=u16::MAX {
            let t = u32::from(f.tolerance_mm(z));
            assert!(t < u32::from(z) && u32::from(z) + t <= 65535, "{z}: {t}");
        }
    }

    #[test]
    fn lone_pixels_and_pairs_go_lines_corners_and_surfaces_stay() {
        let (w, h) = (8u32, 6u32);
        let f = filter(w, h);
        let mut input = vec![0u16; (w * h) as usize];
        let at = |x: usize, y: usize| y * w as usize + x;
        // a 3×3 patch at 1.5 m in the top-left corner
        for y in 0..3 {
            for x in 0..3 {
                input[at(x, y)] = 1500;
            }
        }
        // a lone pixel, a lone pair, a diagonal line of 3 pixels
        input[at(6, 0)] = 2000;
        input[at(5, 4)] = 900;
        input[at(6, 4)] = 905;
        input[at(2, 5)] = 3000;
        input[at(3, 4)] = 3010;
        input[at(4, 3)] = 3020;
        // a pixel far in front of the patch, inside it
        input[at(1, 1)] = 700;
        let mut out = vec![7u16; input.len()];
        let removed = f.apply(&input, &mut out).unwrap();
        let kept: Vec<(usize, usize)> = (0..h as usize)
            .flat_map(|y| (0..w as usize).map(move |x| (x, y)))
            .filter(|&(x, y)| out[at(x, y)] != 0)
            .collect();
        // the patch minus its flying centre; the line's middle (2 neighbours) and
        // its ends (1 each: a 3-pixel line is too short to keep its ends)
        let mut expected: Vec<(usize, usize)> = (0..3)
            .flat_map(|y| (0..3).map(move |x| (x, y)))
            .filter(|&p| p != (1, 1))
            .collect();
        expected.push((3, 4));
        expected.sort_by_key(|&(x, y)| (y, x));
        assert_eq!(kept, expected);
        assert_eq!(removed, 1 + 2 + 2 + 1);
        for &(x, y) in &kept {
            assert_eq!(out[at(x, y)], input[at(x, y)], "kept as it was");
        }
        // wrong sizes are refused
        assert!(f.apply(&input[1..], &mut out).is_err());
        assert!(f.apply(&input, &mut out[1..]).is_err());
    }
}
