//! Vector lanes for the per-pixel passes: [`by_lanes!`] compiles a pass for
//! the x86-64 baseline, AVX2 + FMA and AVX-512 and calls the one the CPU
//! runs ([`Lanes::detect`]); the flying-pixel filter and the self-filter use
//! it, and so does the distance scan here.
//!
//! The distance scan's in-range work (eqs. 15-17) on a run of [`RUN`]
//! pixels at once, written as branch-free lanes that the compiler turns into
//! vector instructions: the occlusion rule, `‖D‖²`, the region test and every
//! pixel's weight `v(‖D‖ − r)/‖D‖` with an exponential of its own ([`exp32`],
//! fused multiply-adds where the compilation has them), where the scalar
//! code called the C library's once per pixel. The weights are computed in
//! single precision (eight lanes per AVX2 register; the crowded frame below
//! 5.3 → 3.4 ms measured back to back on a slower day of the same machine),
//! everything that decides which pixels count and which is nearest in double
//! precision. Each lane keeps its own
//! count and its row's smallest distances with a vector minimum, never a
//! conditional store; the row that holds the smallest, then its pixel, are
//! found once per row and once per point ([`Sums::end_row`], [`find`]).
//! A conditional store per lane (a masked store, and the next run's load
//! that waited for it) had been half of the scan's time: the timing test's
//! 8 points on a crowded frame (every pixel in front of every point, AVX2,
//! an AMD EPYC virtual machine) 7.0 → 3.8 ms a frame, the human + robot
//! scene 1.21 → 0.65 ms. Each lane also keeps the nearest pixel at its own
//! depth (the surface seen, for the fusion of several cameras).

use nalgebra::Vector3;

/// Pixels per run (the distance scan's and the renderer's capsule pass).
pub(crate) const RUN: usize = 16;

/// `a b + c` in single precision: fused with `FMA`.
#[inline(always)]
fn fma32<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `e^x` in single precision for a finite `x`, within 2 ulp of the exact
/// value on `[−87, 88]` (checked against `f64::exp` in the tests), `x`
/// beyond clamped, so that it never overflows to infinity; branch-free: it
/// vectorises.
/// `FMA`: each step of the series as one fused multiply-add (for a
/// compilation with FMA instructions: without them it is a library call).
#[inline(always)]
fn exp32<const FMA: bool>(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    // ln 2 split so that k·LN2_HI is exact for |k| < 2^8
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    // 1.5·2^23: adding it rounds to an integer held in the low mantissa bits
    const SHIFT: f32 = 12_582_912.0;
    let x = x.clamp(-87.0, 88.0);
    let t = x * LOG2E + SHIFT;
    let k = t - SHIFT;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    // Taylor series to r^7: truncation below 6e-9 relative on |r| ≤ ln2/2
    let mut p = 1.0 / 5_040.0;
    p = fma32::<FMA>(p, r, 1.0 / 720.0);
    p = fma32::<FMA>(p, r, 1.0 / 120.0);
    p = fma32::<FMA>(p, r, 1.0 / 24.0);
    p = fma32::<FMA>(p, r, 1.0 / 6.0);
    p = fma32::<FMA>(p, r, 0.5);
    p = fma32::<FMA>(p, r, 1.0);
    p = fma32::<FMA>(p, r, 1.0);
    let k_bits = t.to_bits().wrapping_sub(SHIFT.to_bits());
    let two_k = f32::from_bits(k_bits.wrapping_add(127) << 23);
    p * two_k
}

/// What the scan of one point of interest needs, fixed for its window.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Point {
    /// the point in camera coordinates \[m\]
    pub x: f64,
    pub y: f64,
    pub d_p: f64,
    /// `d_p + ρ + r` \[m\]: pixels deeper are out of range
    pub d_far: f64,
    /// `(ρ + r)²` \[m²\]
    pub reach2: f64,
    /// link radius `r` \[m\]
    pub radius: f64,
    /// metres per depth unit
    pub scale: f64,
    /// eq. (16): `V_max`, `2/ρ` and `α`
    pub v_max: f64,
    pub two_over_rho: f64,
    pub alpha: f64,
}

/// Running sums of one point's scan, per lane (a lane holds every
/// `RUN`-th pixel of a row: no horizontal step per run), and what the scan
/// found.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sums {
    /// Σ of `−D k` per lane (eq. 17's sum before its direction is taken)
    pub x: [f64; RUN],
    pub y: [f64; RUN],
    pub z: [f64; RUN],
    /// pixels in the region
    count: [u64; RUN],
    /// the row's smallest `‖D‖²` per lane (∞: none in the region)
    row_low: [f64; RUN],
    /// the row's smallest squared distance per lane to a pixel at its own
    /// depth (no occlusion rule) \[m²\]
    row_surface: [f64; RUN],
    /// the smallest `‖D‖²` and the first row that holds it
    low: f64,
    low_row: usize,
    /// the nearest surface seen \[m²\] and the first row that holds it
    surface: f64,
    surface_row: usize,
    /// what the scan found, once it is done
    found: Nearest,
}

/// What a scan found: eq. (17)'s pixel count, the nearest pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Nearest {
    /// pixels in the region
    pub count: usize,
    /// the smallest `‖D‖²` (∞: no pixel)
    pub best2: f64,
    /// the first pixel of the scan order (row by row) at `best2`: its
    /// column, row and depth `d_o` \[m\]
    pub best: (usize, usize, f64),
    /// the smallest squared distance to a valid pixel taken at its own depth
    /// (the nearest surface the camera saw) \[m²\] (∞: no pixel)
    pub surface2: f64,
    /// that pixel (the first of the scan order at `surface2`): column, row
    pub surface: (usize, usize),
}

impl Sums {
    pub fn new() -> Self {
        Sums {
            x: [0.0; RUN],
            y: [0.0; RUN],
            z: [0.0; RUN],
            count: [0; RUN],
            row_low: [f64::INFINITY; RUN],
            row_surface: [f64::INFINITY; RUN],
            low: f64::INFINITY,
            low_row: 0,
            surface: f64::INFINITY,
            surface_row: 0,
            found: Nearest {
                count: 0,
                best2: f64::INFINITY,
                best: (0, 0, 0.0),
                surface2: f64::INFINITY,
                surface: (0, 0),
            },
        }
    }

    /// The sum of eq. (17), camera frame.
    pub fn total(&self) -> Vector3<f64> {
        Vector3::new(
            self.x.iter().sum(),
            self.y.iter().sum(),
            self.z.iter().sum(),
        )
    }

    /// The count and the nearest pixel over every lane: the smallest
    /// `‖D‖²`, at a tie the first of the scan order (row, then column).
    pub fn nearest(&self) -> Nearest {
        self.found
    }

    /// The end of row `v`: its lanes' smallest values against the scan's.
    #[inline(always)]
    fn end_row(&mut self, v: usize) {
        let low = self.row_low.iter().fold(f64::INFINITY, |m, &x| min(m, x));
        if low < self.low {
            self.low = low;
            self.low_row = v;
        }
        let surface = self
            .row_surface
            .iter()
            .fold(f64::INFINITY, |m, &x| min(m, x));
        if surface < self.surface {
            self.surface = surface;
            self.surface_row = v;
        }
        self.row_low = [f64::INFINITY; RUN];
        self.row_surface = [f64::INFINITY; RUN];
    }
}

/// Plain minimum (one instruction): `b` if either is NaN.
#[inline(always)]
pub(crate) fn min(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

/// One pixel of a point's scan: depth `d` \[m\] (0: no reading, `raw` its
/// raw value), column factor `x`, row factor `y`. Returns `‖D‖²` with the
/// occlusion rule, the depth used `d_o`, `D`, whether the pixel is in the
/// region, and its squared distance at its own depth (∞ without a reading).
#[inline(always)]
fn pixel(p: &Point, raw: u16, x: f64, y: f64) -> (f64, f64, [f64; 3], bool, f64) {
    let d = f64::from(raw) * p.scale;
    // occlusion: worst case at P's depth
    let d_used = if d < p.d_p { p.d_p } else { d };
    let ex = x * d_used - p.x;
    let ey = y * d_used - p.y;
    let ez = d_used - p.d_p;
    let m = ex * ex + ey * ey + ez * ez;
    // the surface as seen: the pixel at its own depth
    let (sx, sy, sz) = (x * d - p.x, y * d - p.y, d - p.d_p);
    let seen = sx * sx + sy * sy + sz * sz;
    let seen = if raw != 0 { seen } else { f64::INFINITY };
    let ins = (raw != 0) & (d <= p.d_far) & (m <= p.reach2);
    (m, d_used, [ex, ey, ez], ins, seen)
}

/// One full run: depths `raw` (units), column factors `xs` (`(u − c_x)/f_x`),
/// row factor `y`. Each lane keeps the row's smallest values with a
/// minimum, never a conditional store (a masked store, and the load of the
/// next run that waited for it, were most of the scan's time); the row and
/// then the pixel that holds them are found once, at the end
/// ([`Sums::end_row`], [`find`]).
#[inline(always)]
fn run<const FMA: bool>(p: &Point, raw: &[u16; RUN], xs: &[f64; RUN], y: f64, s: &mut Sums) {
    let mut n2 = [0.0f64; RUN];
    let mut dx = [0.0f64; RUN];
    let mut dy = [0.0f64; RUN];
    let mut dz = [0.0f64; RUN];
    let mut inside = [false; RUN];
    let mut any = false;
    for i in 0..RUN {
        let (m, _, [ex, ey, ez], ins, seen) = pixel(p, raw[i], xs[i], y);
        s.row_surface[i] = min(seen, s.row_surface[i]);
        s.row_low[i] = min(if ins { m } else { f64::INFINITY }, s.row_low[i]);
        s.count[i] += u64::from(ins);
        any |= ins;
        inside[i] = ins;
        n2[i] = m;
        dx[i] = ex;
        dy[i] = ey;
        dz[i] = ez;
    }
    if !any {
        return;
    }
    // each pixel's weight of eq. (16) in single precision (half the vector
    // work of its square root, exponential and division; the weights sum
    // to a direction, 1e-7 relative); the distances, the region and the
    // nearest pixel stay in double precision
    let mut k = [0.0f32; RUN];
    for i in 0..RUN {
        let n = (n2[i] as f32).sqrt();
        let clearance = (n - p.radius as f32).max(0.0);
        let e = exp32::<FMA>((clearance * p.two_over_rho as f32 - 1.0) * p.alpha as f32);
        let w = p.v_max as f32 / ((1.0 + e) * n);
        k[i] = if inside[i] & (n2[i] > 0.0) { w } else { 0.0 };
    }
    for i in 0..RUN {
        let k = f64::from(k[i]);
        s.x[i] -= k * dx[i];
        s.y[i] -= k * dy[i];
        s.z[i] -= k * dz[i];
    }
}

/// `$vis fn $name(lanes: Lanes, args…) -> T`: calls `$body(args…)` as
/// compiled for the width `lanes` names (the body is `#[inline(always)]`,
/// so each compilation inlines it with that width's instructions). With
/// `= $body::<FMA>`, the body takes `const FMA: bool`: `true` where the
/// compilation has fused multiply-add (AVX2 + FMA, AVX-512).
macro_rules! by_lanes {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty = $body:ident;) => {
        $crate::lanes::by_lanes! {
            @ $(#[$meta])* $vis fn $name($($arg: $ty),*) -> $ret = ($body) ($body) ($body)
        }
    };
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty = $body:ident::<FMA>;) => {
        $crate::lanes::by_lanes! {
            @ $(#[$meta])* $vis fn $name($($arg: $ty),*) -> $ret
                = ($body::<false>) ($body::<true>) ($body::<true>)
        }
    };
    (@ $(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),*) -> $ret:ty
        = ($($base:tt)+) ($($wide:tt)+) ($($widest:tt)+)) => {
        $(#[$meta])*
        $vis fn $name(lanes: $crate::lanes::Lanes, $($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,fma")]
            unsafe fn avx2($($arg: $ty),*) -> $ret {
                $($wide)+($($arg),*)
            }
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f,avx512bw,avx2,fma")]
            unsafe fn avx512($($arg: $ty),*) -> $ret {
                $($widest)+($($arg),*)
            }
            match lanes {
                $crate::lanes::Lanes::Baseline => $($base)+($($arg),*),
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `Lanes::Avx2` is only made when the CPU has AVX2 and FMA
                $crate::lanes::Lanes::Avx2 => unsafe { avx2($($arg),*) },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `Lanes::Avx512` is only made when the CPU has AVX-512 F and BW
                $crate::lanes::Lanes::Avx512 => unsafe { avx512($($arg),*) },
            }
        }
    };
}
pub(crate) use by_lanes;

/// Which compilation of the scan a machine runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Lanes {
    /// the x86-64 baseline (SSE2), or any other architecture
    Baseline,
    /// AVX2 and FMA, detected at run time
    #[cfg(target_arch = "x86_64")]
    Avx2,
    /// AVX-512 (F and BW), detected at run time
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Lanes {
    /// Every compilation, narrowest first.
    const ALL: &'static [Lanes] = &[
        Lanes::Baseline,
        #[cfg(target_arch = "x86_64")]
        Lanes::Avx2,
        #[cfg(target_arch = "x86_64")]
        Lanes::Avx512,
    ];

    /// Whether this CPU has the instructions of `self`.
    fn runs_here(self) -> bool {
        match self {
            Lanes::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Lanes::Avx2 => {
                std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Lanes::Avx512 => {
                std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx512bw")
            }
        }
    }

    /// The widest this CPU runs.
    pub fn detect() -> Lanes {
        Self::ALL
            .iter()
            .rev()
            .copied()
            .find(|l| l.runs_here())
            .unwrap_or(Lanes::Baseline)
    }

    /// Every compilation this CPU can run (the tests compare them).
    #[cfg(test)]
    pub fn available() -> Vec<Lanes> {
        Self::ALL
            .iter()
            .copied()
            .filter(|l| l.runs_here())
            .collect()
    }
}

/// The `N` values of `src` from `at` on, padded with `T::default()` where
/// `src` ends first: a run of pixels as a fixed-size array (a full run is
/// copied at a length known to the compiler, without a call).
#[inline(always)]
pub(crate) fn load<T: Copy + Default, const N: usize>(src: &[T], at: usize) -> [T; N] {
    let mut a = [T::default(); N];
    let len = N.min(src.len().saturating_sub(at));
    if len == N {
        a.copy_from_slice(&src[at..at + N]);
    } else {
        a[..len].copy_from_slice(&src[at..at + len]);
    }
    a
}

/// Writes the first `dst.len() − at` (at most `N`) values of `run` to
/// `dst[at..]`: the inverse of [`load`].
#[inline(always)]
pub(crate) fn store<T: Copy, const N: usize>(dst: &mut [T], at: usize, run: &[T; N]) {
    let len = N.min(dst.len().saturating_sub(at));
    if len == N {
        dst[at..at + N].copy_from_slice(run);
    } else {
        dst[at..at + len].copy_from_slice(&run[..len]);
    }
}

/// A point's pixel window in a frame `width` pixels wide: rows `v0..=v1`,
/// columns from `u0` on, as many as `xs` (their factors `(u − c_x)/f_x`);
/// `yn` every row's factor; `raw_far` the smallest raw value beyond range.
pub(crate) struct Window<'a> {
    pub frame: &'a [u16],
    pub width: usize,
    pub u0: usize,
    pub v0: usize,
    pub v1: usize,
    pub xs: &'a [f64],
    pub yn: &'a [f64],
    pub raw_far: u16,
}

by_lanes! {
    /// The whole window's scan with `lanes`.
    pub(crate) fn scan(p: &Point, w: &Window<'_>, s: &mut Sums) -> () = scan_any::<FMA>;
}

impl Window<'_> {
    /// Row `v`'s pixels of the window.
    #[inline(always)]
    fn row(&self, v: usize) -> &[u16] {
        let at = v * self.width + self.u0;
        &self.frame[at..at + self.xs.len()]
    }

    /// The runs of row `v` that the scan visits: their first column in the
    /// window and their depths. A run all invalid or beyond range by more
    /// than a unit is skipped whole: most of a window's background (a short
    /// last run is padded with no reading, which is skipped too).
    #[inline(always)]
    fn runs(&self, v: usize) -> impl Iterator<Item = (usize, [u16; RUN])> + '_ {
        let row = self.row(v);
        (0..row.len()).step_by(RUN).filter_map(move |c| {
            let raw: [u16; RUN] = load(row, c);
            let nearest = raw.iter().fold(u16::MAX, |m, &r| m.min(r.wrapping_sub(1)));
            (nearest < self.raw_far).then_some((c, raw))
        })
    }
}

#[inline(always)]
fn scan_any<const FMA: bool>(p: &Point, w: &Window<'_>, sums: &mut Sums) {
    // the sums as a local, which the compiler keeps in registers where it can
    let mut acc = *sums;
    let s = &mut acc;
    for v in w.v0..=w.v1 {
        let y = w.yn[v];
        for (c, raw) in w.runs(v) {
            run::<FMA>(p, &raw, &load(w.xs, c), y, s);
        }
        s.end_row(v);
    }
    acc.found = find(p, w, &acc);
    *sums = acc;
}

/// The pixels that hold a scan's smallest values, each the first of its row
/// at that value (the rows were found by [`Sums::end_row`], the first at
/// their value), by the same arithmetic as the scan's ([`pixel`]).
#[inline(always)]
fn find(p: &Point, w: &Window<'_>, s: &Sums) -> Nearest {
    let mut n = Nearest {
        count: s.count.iter().sum::<u64>() as usize,
        best2: s.low,
        best: (0, 0, 0.0),
        surface2: s.surface,
        surface: (0, 0),
    };
    // the first pixel of row `v` (of the runs the scan visited) that `hit`
    // takes: its column and what `hit` returned
    let first = |v: usize, hit: &dyn Fn(u16, f64, f64) -> Option<f64>| {
        let y = w.yn[v];
        w.runs(v).find_map(|(c, raw)| {
            let xs: [f64; RUN] = load(w.xs, c);
            (0..RUN).find_map(|i| hit(raw[i], xs[i], y).map(|d| (w.u0 + c + i, d)))
        })
    };
    if s.low.is_finite() {
        let v = s.low_row;
        let at = first(v, &|raw, x, y| {
            let (m, d_used, _, ins, _) = pixel(p, raw, x, y);
            (ins & (m == s.low)).then_some(d_used)
        });
        if let Some((u, d)) = at {
            n.best = (u, v, d);
        }
    }
    if s.surface.is_finite() {
        let v = s.surface_row;
        let at = first(v, &|raw, x, y| {
            (pixel(p, raw, x, y).4 == s.surface).then_some(0.0)
        });
        if let Some((u, _)) = at {
            n.surface = (u, v);
        }
    }
    n
}

/// A deterministic sequence for the tests' scenes: the states of Knuth's
/// MMIX linear congruential generator from `seed` (use the high bits).
#[cfg(test)]
pub(crate) fn test_sequence(seed: u64) -> impl FnMut() -> u64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point at camera coordinates `(x, y, d_p)` \[m\] with link radius
    /// `radius` \[m\], the paper's repulsion (ρ 0.4 m, V_max 0.21 m/s, α 6),
    /// depths in millimetres.
    fn point(x: f64, y: f64, d_p: f64, radius: f64) -> Point {
        let reach = 0.4 + radius;
        Point {
            x,
            y,
            d_p,
            d_far: d_p + reach,
            reach2: reach * reach,
            radius,
            scale: 0.001,
            v_max: 0.21,
            two_over_rho: 2.0 / 0.4,
            alpha: 6.0,
        }
    }

    /// Every compilation this CPU runs gives the same scan: the same pixels,
    /// the same nearest one, the same sum but for rounding.
    #[test]
    fn every_vector_width_scans_alike() {
        let all = Lanes::available();
        let (width, height) = (101usize, 37usize);
        // a deterministic scene: a slanted surface with holes, steps and spikes
        let mut lcg = test_sequence(12_345);
        let mut next = move || (lcg() >> 33) as u32;
        let frame: Vec<u16> = (0..width * height)
            .map(|i| match next() % 10 {
                0 => 0,
                1 => 400 + (next() % 3000) as u16,
                _ => 1500 + (i % width) as u16 * 3 + (i / width) as u16 * 5,
            })
            .collect();
        let xs: Vec<f64> = (0..width).map(|u| (u as f64 - 50.0) / 80.0).collect();
        let yn: Vec<f64> = (0..height).map(|v| (v as f64 - 18.0) / 80.0).collect();
        let mut seen = 0;
        for (px, py, d_p, radius) in [
            (0.0, 0.0, 1.8, 0.0),
            (0.1, -0.05, 1.6, 0.07),
            (-0.2, 0.1, 2.2, 0.03),
        ] {
            let reach = 0.4 + radius;
            let p = point(px, py, d_p, radius);
            let window = Window {
                frame: &frame,
                width,
                u0: 3,
                v0: 1,
                v1: 35,
                xs: &xs[3..=97],
                yn: &yn,
                raw_far: ((d_p + reach) / 0.001 + 1.0).floor() as u16 + 1,
            };
            let sums: Vec<Sums> = all
                .iter()
                .map(|&l| {
                    let mut s = Sums::new();
                    scan(l, &p, &window, &mut s);
                    s
                })
                .collect();
            let count = sums[0].nearest().count;
            assert!(count > 100, "{count}");
            seen += count;
            for s in &sums[1..] {
                assert_eq!(s.nearest(), sums[0].nearest());
                // the weights are single precision: fused or not, they
                // round alike to about 1e-7
                let (a, b) = (s.total(), sums[0].total());
                assert!((a - b).norm() <= 1e-6 * b.norm(), "{a} {b}");
            }
        }
        assert!(seen > 0 && !all.is_empty());
    }

    /// The nearest pixel and the nearest surface are the first of the scan
    /// order (row, then column) at their value, as a pixel-by-pixel scan
    /// finds them, also where pixels tie (a flat wall seen square on, the
    /// point halfway between two columns and two rows) and where the tie
    /// spans two runs.
    #[test]
    fn ties_go_to_the_first_pixel_of_the_scan_order() {
        let (width, height) = (64usize, 9usize);
        let xs: Vec<f64> = (0..width).map(|u| (u as f64 - 31.5) / 64.0).collect();
        let yn: Vec<f64> = (0..height).map(|v| (v as f64 - 4.5) / 64.0).collect();
        for (depth, d_p, px) in [(2000u16, 1.8, 0.0), (1700, 1.8, 0.0), (2000, 1.8, 0.25)] {
            let frame = vec![depth; width * height];
            let reach = 0.4;
            let p = point(px, 0.0, d_p, 0.0);
            let window = Window {
                frame: &frame,
                width,
                u0: 0,
                v0: 0,
                v1: height - 1,
                xs: &xs,
                yn: &yn,
                raw_far: ((d_p + reach) / 0.001 + 1.0).floor() as u16 + 1,
            };
            // pixel by pixel, row by row: the first strictly smaller wins
            let (mut best, mut at, mut surface, mut surface_at) =
                (f64::INFINITY, (0, 0, 0.0), f64::INFINITY, (0, 0));
            for v in 0..height {
                for u in 0..width {
                    let (m, d_used, _, ins, seen) = pixel(&p, frame[v * width + u], xs[u], yn[v]);
                    if ins && m < best {
                        (best, at) = (m, (u, v, d_used));
                    }
                    if seen < surface {
                        (surface, surface_at) = (seen, (u, v));
                    }
                }
            }
            for l in Lanes::available() {
                let mut s = Sums::new();
                scan(l, &p, &window, &mut s);
                let n = s.nearest();
                assert_eq!((n.best2, n.best), (best, at), "{l:?} {depth} {px}");
                assert_eq!((n.surface2, n.surface), (surface, surface_at), "{l:?}");
            }
        }
    }

    /// The single-precision exponential against the double one, rounded:
    /// within 2 ulp of `f32` over its whole range, exact at 0, clamped.
    #[test]
    fn exp32_is_within_two_ulp_of_the_rounded_exact_value() {
        let ulps32 = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs();
        let mut worst = 0;
        let mut x = -87.0f32;
        while x <= 88.0 {
            let want = f64::from(x).exp() as f32;
            for e in [exp32::<false>(x), exp32::<true>(x)] {
                worst = worst.max(ulps32(e, want));
            }
            x += 0.000_37;
        }
        assert!(worst <= 2, "{worst} ulp");
        assert_eq!(exp32::<false>(0.0), 1.0);
        assert_eq!(exp32::<true>(0.0), 1.0);
        assert!(exp32::<false>(1e6).is_finite() && exp32::<false>(1e6) > 1e38);
        assert!(exp32::<false>(-1e6) > 0.0);
    }
}
