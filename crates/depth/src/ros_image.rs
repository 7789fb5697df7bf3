//! ROS 2 depth images (REP 118) into phri's depth frames: a
//! `sensor_msgs/Image` payload of encoding `16UC1` (millimetres, 0 = no
//! reading; alias `mono16`) or `32FC1` (metres; NaN, ±inf and ≤ 0 = no
//! reading), of any size up to [`MAX_WIDTH`]×[`MAX_HEIGHT`], little- or
//! big-endian, resampled to the channel's [`OUT_WIDTH`]×[`OUT_HEIGHT`]
//! millimetres, and its `sensor_msgs/CameraInfo` intrinsics scaled to match.
//!
//! Resampling never thins an obstacle: each output pixel takes the nearest
//! valid reading (the smallest non-zero depth) among the input pixels of its
//! footprint, the input pixels its area covers. Output pixel `u` spans input
//! columns `[u·W/640, (u+1)·W/640)` (pixel edges), so its footprint is the
//! columns `floor(u·W/640) .. ceil((u+1)·W/640)`: every input pixel lies in
//! at least one footprint, at any scale, integral or not, up or down. The
//! intrinsics follow the same geometry with pixel centres at integer
//! coordinates: `f' = f·s`, `c' = (c + 0.5)·s − 0.5`, `s = 640/W` (resp.
//! `480/H`).
//!
//! [`Resampler::decode_into`] writes straight into a caller's frame of
//! 640·480 depths and allocates nothing: its row buffers are made once.

use crate::Intrinsics;

/// The output's width \[px\] (the `camera/depth` channel's).
pub const OUT_WIDTH: u32 = 640;
/// The output's height \[px\].
pub const OUT_HEIGHT: u32 = 480;
/// The widest input accepted \[px\].
pub const MAX_WIDTH: u32 = 1280;
/// The tallest input accepted \[px\].
pub const MAX_HEIGHT: u32 = 800;

/// The depth encodings accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthEncoding {
    /// `16UC1` or `mono16`: millimetres, 0 = no reading
    Mm16,
    /// `32FC1`: metres, NaN, ±inf or ≤ 0 = no reading
    M32,
}

impl DepthEncoding {
    /// The encoding of a ROS image's `encoding` field, if accepted.
    pub fn parse(encoding: &str) -> Option<DepthEncoding> {
        match encoding {
            "16UC1" | "mono16" => Some(DepthEncoding::Mm16),
            "32FC1" => Some(DepthEncoding::M32),
            _ => None,
        }
    }

    /// Bytes per pixel.
    pub fn bytes(self) -> usize {
        match self {
            DepthEncoding::Mm16 => 2,
            DepthEncoding::M32 => 4,
        }
    }
}

/// What is wrong with an image or a camera info.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RosImageError {
    /// an encoding that is not a depth image phri takes
    #[error("encoding '{0}' refused (16UC1, mono16 or 32FC1)")]
    Encoding(String),
    /// zero or beyond the largest size
    #[error("size {width}×{height} outside 1×1..={MAX_WIDTH}×{MAX_HEIGHT}")]
    Size {
        /// the image's width \[px\] (or 640 for an output of the wrong length)
        width: u32,
        /// the image's height \[px\] (or the output's length / 640)
        height: u32,
    },
    /// a row shorter than its pixels
    #[error("step {step} < width {width} × {bytes} bytes")]
    Step {
        /// the image's bytes per row
        step: u32,
        /// the image's width \[px\]
        width: u32,
        /// bytes per pixel of its encoding
        bytes: usize,
    },
    /// fewer bytes than step × height
    #[error("{len} bytes of data < step {step} × height {height}")]
    Data {
        /// bytes of data given
        len: usize,
        /// the image's bytes per row
        step: u32,
        /// the image's height \[px\]
        height: u32,
    },
    /// a camera info that gives no usable intrinsics
    #[error("camera info: {0}")]
    Info(String),
}

/// A `sensor_msgs/Image` as received: its fields, the data borrowed.
#[derive(Clone, Copy, Debug)]
pub struct ImageView<'a> {
    /// image width \[px\]
    pub width: u32,
    /// image height \[px\]
    pub height: u32,
    /// the `encoding` field, e.g. `16UC1` (see [`DepthEncoding::parse`])
    pub encoding: &'a str,
    /// `is_bigendian` ≠ 0: the samples are big-endian
    pub is_bigendian: u8,
    /// bytes per row
    pub step: u32,
    /// the pixels, row by row, `step` bytes a row
    pub data: &'a [u8],
}

/// An image's checked layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// image width \[px\], 1 to [`MAX_WIDTH`]
    pub width: u32,
    /// image height \[px\], 1 to [`MAX_HEIGHT`]
    pub height: u32,
    /// the sample format
    pub encoding: DepthEncoding,
    /// the samples are big-endian
    pub big_endian: bool,
    /// bytes per row, at least `width` × the encoding's bytes per pixel
    pub step: usize,
}

/// The checks of an image: its encoding, its size, its step, its data's length.
pub fn check(img: &ImageView<'_>) -> Result<Layout, RosImageError> {
    let encoding = DepthEncoding::parse(img.encoding)
        .ok_or_else(|| RosImageError::Encoding(shown(img.encoding)))?;
    if img.width == 0 || img.height == 0 || img.width > MAX_WIDTH || img.height > MAX_HEIGHT {
        return Err(RosImageError::Size {
            width: img.width,
            height: img.height,
        });
    }
    let bytes = encoding.bytes();
    if (img.step as usize) < img.width as usize * bytes {
        return Err(RosImageError::Step {
            step: img.step,
            width: img.width,
            bytes,
        });
    }
    if img.data.len() < img.step as usize * img.height as usize {
        return Err(RosImageError::Data {
            len: img.data.len(),
            step: img.step,
            height: img.height,
        });
    }
    Ok(Layout {
        width: img.width,
        height: img.height,
        encoding,
        big_endian: img.is_bigendian != 0,
        step: img.step as usize,
    })
}

/// A text from the wire, fit for one log line: at most 32 characters, no
/// control characters.
fn shown(s: &str) -> String {
    let mut out: String = s
        .chars()
        .take(32)
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if s.chars().count() > 32 {
        out.push('…');
    }
    out
}

/// The intrinsics of a `sensor_msgs/CameraInfo`: its `K` (row-major 3×3:
/// fx = K\[0\], cx = K\[2\], fy = K\[4\], cy = K\[5\]) for an image of
/// `width`×`height`. Refused: a focal length zero, negative or not finite,
/// a centre not finite or outside the image, a size out of range.
pub fn camera_info_intrinsics(
    width: u32,
    height: u32,
    k: &[f64; 9],
) -> Result<Intrinsics, RosImageError> {
    if width == 0 || height == 0 || width > MAX_WIDTH || height > MAX_HEIGHT {
        return Err(RosImageError::Info(format!(
            "size {width}×{height} outside 1×1..={MAX_WIDTH}×{MAX_HEIGHT}"
        )));
    }
    let (fx, cx, fy, cy) = (k[0], k[2], k[4], k[5]);
    if !(fx.is_finite() && fx > 0.0 && fy.is_finite() && fy > 0.0) {
        return Err(RosImageError::Info(format!(
            "focal lengths fx = {fx}, fy = {fy} not positive and finite"
        )));
    }
    let inside = |c: f64, n: u32| c.is_finite() && c >= 0.0 && c <= f64::from(n);
    if !(inside(cx, width) && inside(cy, height)) {
        return Err(RosImageError::Info(format!(
            "centre ({cx}, {cy}) outside the {width}×{height} image"
        )));
    }
    Ok(Intrinsics {
        width,
        height,
        fx,
        fy,
        cx,
        cy,
    })
}

/// Intrinsics `k` of an input image, scaled to the 640×480 output.
pub fn scale_intrinsics(k: &Intrinsics) -> Intrinsics {
    let sx = f64::from(OUT_WIDTH) / f64::from(k.width);
    let sy = f64::from(OUT_HEIGHT) / f64::from(k.height);
    Intrinsics {
        width: OUT_WIDTH,
        height: OUT_HEIGHT,
        fx: k.fx * sx,
        fy: k.fy * sy,
        cx: (k.cx + 0.5) * sx - 0.5,
        cy: (k.cy + 0.5) * sy - 0.5,
    }
}

/// The input indices `[start, end)` output index `i` of `out` covers
/// among `n` inputs: `floor(i·n/out) .. ceil((i+1)·n/out)`.
pub fn footprint(i: u32, n: u32, out: u32) -> (u32, u32) {
    let (i, n, out) = (u64::from(i), u64::from(n), u64::from(out));
    let start = i * n / out;
    let end = ((i + 1) * n).div_ceil(out);
    (start as u32, end.min(n) as u32)
}

/// A `32FC1` sample \[m\] in millimetres: 0 for no reading (NaN, ±inf, ≤ 0,
/// or beyond 65.535 m), at least 1 for a reading.
#[inline]
pub fn metres_to_mm(m: f32) -> u16 {
    // NaN and ≤ 0: no reading
    if !(m > 0.0) {
        return 0;
    }
    // rounded half up (positive: as `round`, without its libm call)
    let mm = f64::from(m) * 1000.0 + 0.5;
    // +inf too
    if mm >= 65536.0 {
        return 0;
    }
    (mm as u16).max(1)
}

/// The resampler: the footprints of one input size and the row buffers,
/// made once; then each frame is decoded with no allocation.
#[derive(Clone, Debug)]
pub struct Resampler {
    /// the input size the footprints are for
    size: (u32, u32),
    /// per output column, its input columns
    cols: Vec<(u32, u32)>,
    /// per output row, its input rows
    rows: Vec<(u32, u32)>,
    /// one input row's depths minus 1 (wrapping: no reading is u16::MAX)
    row: Vec<u16>,
    /// one input row's minima over each output column's footprint, minus 1
    hmin: Vec<u16>,
    /// one output row's minima, minus 1 (wrapping)
    acc: Vec<u16>,
}

impl Default for Resampler {
    fn default() -> Self {
        Resampler::new()
    }
}

impl Resampler {
    /// Buffers for any input up to [`MAX_WIDTH`]×[`MAX_HEIGHT`].
    pub fn new() -> Resampler {
        Resampler {
            size: (0, 0),
            cols: Vec::with_capacity(OUT_WIDTH as usize),
            rows: Vec::with_capacity(OUT_HEIGHT as usize),
            row: vec![0; MAX_WIDTH as usize],
            hmin: vec![0; OUT_WIDTH as usize],
            acc: vec![0; OUT_WIDTH as usize],
        }
    }

    fn footprints(&mut self, width: u32, height: u32) {
        if self.size == (width, height) {
            return;
        }
        self.size = (width, height);
        self.cols.clear();
        self.cols
            .extend((0..OUT_WIDTH).map(|u| footprint(u, width, OUT_WIDTH)));
        self.rows.clear();
        self.rows
            .extend((0..OUT_HEIGHT).map(|v| footprint(v, height, OUT_HEIGHT)));
    }

    /// Decode `img` into `out` (640·480 millimetres, row-major, 0 = no
    /// reading): each output pixel the nearest valid reading of its
    /// footprint. Checks the image first ([`check`]); `out` of another
    /// length is refused as a size error.
    pub fn decode_into(
        &mut self,
        img: &ImageView<'_>,
        out: &mut [u16],
    ) -> Result<(), RosImageError> {
        let layout = check(img)?;
        if out.len() != (OUT_WIDTH * OUT_HEIGHT) as usize {
            return Err(RosImageError::Size {
                width: OUT_WIDTH,
                height: (out.len() / OUT_WIDTH as usize) as u32,
            });
        }
        self.footprints(layout.width, layout.height);
        match (layout.encoding, layout.big_endian) {
            (DepthEncoding::Mm16, false) => {
                self.resample(&layout, img.data, out, |b| u16::from_le_bytes([b[0], b[1]]))
            }
            (DepthEncoding::Mm16, true) => {
                self.resample(&layout, img.data, out, |b| u16::from_be_bytes([b[0], b[1]]))
            }
            (DepthEncoding::M32, false) => self.resample(&layout, img.data, out, |b| {
                metres_to_mm(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            }),
            (DepthEncoding::M32, true) => self.resample(&layout, img.data, out, |b| {
                metres_to_mm(f32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            }),
        }
        Ok(())
    }

    fn resample(
        &mut self,
        layout: &Layout,
        data: &[u8],
        out: &mut [u16],
        sample: impl Fn(&[u8]) -> u16,
    ) {
        let w = layout.width as usize;
        let bytes = layout.encoding.bytes();
        // the input row whose horizontal minima `hmin` holds: footprints
        // advance monotonically, so a row shared by two output rows (a
        // non-integral scale, an upscale) is decoded once
        let mut cached: Option<usize> = None;
        for (v, out_row) in out.chunks_exact_mut(OUT_WIDTH as usize).enumerate() {
            let (y0, y1) = self.rows[v];
            self.acc.fill(u16::MAX);
            for y in y0 as usize..y1 as usize {
                if cached != Some(y) {
                    cached = Some(y);
                    let line = &data[y * layout.step..y * layout.step + w * bytes];
                    self.horizontal(line, bytes, &sample);
                }
                for (a, &m) in self.acc.iter_mut().zip(self.hmin.iter()) {
                    *a = (*a).min(m);
                }
            }
            for (o, &a) in out_row.iter_mut().zip(self.acc.iter()) {
                *o = a.wrapping_add(1);
            }
        }
    }

    /// One input row's minima over each output column's footprint, as
    /// depth − 1 wrapping (no reading, 0, is the largest key), in `hmin`.
    fn horizontal(&mut self, line: &[u8], bytes: usize, sample: &impl Fn(&[u8]) -> u16) {
        let key = |b: &[u8]| sample(b).wrapping_sub(1);
        let w = line.len() / bytes;
        if w == OUT_WIDTH as usize {
            for (h, b) in self.hmin.iter_mut().zip(line.chunks_exact(bytes)) {
                *h = key(b);
            }
        } else if w == 2 * OUT_WIDTH as usize {
            for (h, b) in self.hmin.iter_mut().zip(line.chunks_exact(2 * bytes)) {
                let (l, r) = b.split_at(bytes);
                *h = key(l).min(key(r));
            }
        } else {
            let row = &mut self.row[..w];
            for (r, b) in row.iter_mut().zip(line.chunks_exact(bytes)) {
                *r = key(b);
            }
            for (h, &(x0, x1)) in self.hmin.iter_mut().zip(self.cols.iter()) {
                *h = row[x0 as usize..x1 as usize]
                    .iter()
                    .copied()
                    .min()
                    .unwrap_or(u16::MAX);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    const N: usize = (OUT_WIDTH * OUT_HEIGHT) as usize;

    /// A 640×480 frame with a pattern of readings and holes.
    fn pattern() -> Vec<u16> {
        (0..N)
            .map(|i| {
                let (x, y) = (i % 640, i / 640);
                if (x * 7 + y * 3) % 11 == 0 {
                    0
                } else {
                    (500 + (x * 13 + y * 29) % 3000) as u16
                }
            })
            .collect()
    }

    fn mm16(width: u32, height: u32, d: &[u16], big: bool) -> Vec<u8> {
        assert_eq!(d.len(), (width * height) as usize);
        d.iter()
            .flat_map(|v| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            })
            .collect()
    }

    fn m32(d: &[f32], big: bool) -> Vec<u8> {
        d.iter()
            .flat_map(|v| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            })
            .collect()
    }

    fn view<'a>(w: u32, h: u32, enc: &'a str, bytes: u32, data: &'a [u8]) -> ImageView<'a> {
        ImageView {
            width: w,
            height: h,
            encoding: enc,
            is_bigendian: 0,
            step: w * bytes,
            data,
        }
    }

    #[test]
    fn equal_frames_at_640x480_in_both_encodings_and_byte_orders() {
        let src = pattern();
        let mut r = Resampler::new();
        let mut out = vec![7u16; N];
        for big in [false, true] {
            for enc in ["16UC1", "mono16"] {
                let data = mm16(640, 480, &src, big);
                let mut v = view(640, 480, enc, 2, &data);
                v.is_bigendian = u8::from(big);
                r.decode_into(&v, &mut out).unwrap();
                assert!(out == src, "{enc} big {big}");
            }
            // metres, no reading as NaN, inf, 0 or negative
            let f: Vec<f32> = src
                .iter()
                .enumerate()
                .map(|(i, &d)| match (d, i % 4) {
                    (0, 0) => f32::NAN,
                    (0, 1) => f32::INFINITY,
                    (0, 2) => -1.0,
                    (0, _) => 0.0,
                    (d, _) => f32::from(d) / 1000.0,
                })
                .collect();
            let data = m32(&f, big);
            let mut v = view(640, 480, "32FC1", 4, &data);
            v.is_bigendian = u8::from(big);
            out.fill(7);
            r.decode_into(&v, &mut out).unwrap();
            assert!(out == src, "32FC1 big {big}");
        }
        // a row padded beyond its pixels (step > width · 2)
        let mut data = Vec::new();
        for row in src.chunks(640) {
            data.extend(row.iter().flat_map(|v| v.to_le_bytes()));
            data.extend([0xAB; 6]);
        }
        let v = ImageView {
            step: 640 * 2 + 6,
            ..view(640, 480, "16UC1", 2, &data)
        };
        r.decode_into(&v, &mut out).unwrap();
        assert!(out == src);
    }

    /// The nearest valid reading of output pixel (u, v)'s footprint in a
    /// `w`×`h` input, straight from the definition.
    fn reference(src: &[u16], w: u32, h: u32, u: u32, v: u32) -> u16 {
        let x0 = (f64::from(u) * f64::from(w) / 640.0).floor() as u32;
        let x1 = (f64::from(u + 1) * f64::from(w) / 640.0).ceil() as u32;
        let y0 = (f64::from(v) * f64::from(h) / 480.0).floor() as u32;
        let y1 = (f64::from(v + 1) * f64::from(h) / 480.0).ceil() as u32;
        let mut best = 0u16;
        for y in y0..y1.min(h) {
            for x in x0..x1.min(w) {
                let d = src[(y * w + x) as usize];
                if d > 0 && (best == 0 || d < best) {
                    best = d;
                }
            }
        }
        best
    }

    #[test]
    fn at_1280x720_no_output_is_farther_than_the_nearest_input_of_its_footprint() {
        let (w, h) = (1280u32, 720u32);
        let src: Vec<u16> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (x * 5 + y * 7) % 13 < 3 {
                    0
                } else {
                    (400 + (x * 31 + y * 17) % 4000) as u16
                }
            })
            .collect();
        let data = mm16(w, h, &src, false);
        let mut out = vec![0u16; N];
        Resampler::new()
            .decode_into(&view(w, h, "16UC1", 2, &data), &mut out)
            .unwrap();
        for v in 0..480 {
            for u in 0..640 {
                assert_eq!(out[(v * 640 + u) as usize], reference(&src, w, h, u, v));
            }
        }
        // a footprint of 2 columns × 1.5 rows: rows overlap, every input row seen
        assert_eq!(footprint(0, 720, 480), (0, 2));
        assert_eq!(footprint(1, 720, 480), (1, 3));
        assert_eq!(footprint(479, 720, 480), (718, 720));
    }

    #[test]
    fn a_one_pixel_wide_pole_at_1280x720_still_appears() {
        let (w, h) = (1280u32, 720u32);
        for col in [0u32, 1, 639, 640, 641, 1279] {
            // a wall at 3 m, a pole of one pixel at 0.9 m, 32FC1 with NaN holes
            let f: Vec<f32> = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    if x == col {
                        0.9
                    } else if (x + y) % 3 == 0 {
                        f32::NAN
                    } else {
                        3.0
                    }
                })
                .collect();
            let data = m32(&f, false);
            let mut out = vec![0u16; N];
            Resampler::new()
                .decode_into(&view(w, h, "32FC1", 4, &data), &mut out)
                .unwrap();
            let u = col / 2;
            for v in 0..480 {
                assert_eq!(out[(v * 640 + u) as usize], 900, "pole at column {col}");
            }
            assert_eq!(out.iter().filter(|&&d| d == 900).count(), 480);
            assert!(out.iter().all(|&d| d == 900 || d == 3000));
        }
    }

    #[test]
    fn a_non_integral_downscale_and_an_upscale_cover_every_input_pixel() {
        for (w, h) in [
            (848u32, 480u32),
            (1280, 800),
            (320, 240),
            (424, 240),
            (1, 1),
            (641, 479),
        ] {
            let src: Vec<u16> = (0..w * h)
                .map(|i| {
                    if i % 3 == 0 {
                        0
                    } else {
                        (1000 + i % 977) as u16
                    }
                })
                .collect();
            let data = mm16(w, h, &src, false);
            let mut out = vec![0u16; N];
            Resampler::new()
                .decode_into(&view(w, h, "16UC1", 2, &data), &mut out)
                .unwrap();
            for v in (0..480).step_by(7) {
                for u in (0..640).step_by(5) {
                    assert_eq!(
                        out[(v * 640 + u) as usize],
                        reference(&src, w, h, u, v),
                        "{w}×{h} at ({u}, {v})"
                    );
                }
            }
            // every input column and row lies in some footprint
            let mut seen = vec![false; w as usize];
            for u in 0..640 {
                let (a, b) = footprint(u, w, 640);
                assert!(a < b);
                seen[a as usize..b as usize].fill(true);
            }
            assert!(seen.iter().all(|&s| s), "{w}×{h}");
        }
    }

    #[test]
    fn the_intrinsics_of_a_resampled_frame_map_a_point_to_the_same_pixel() {
        // an upsampled frame: 320×240 of f 290, c (159.75, 119.75)
        let k_in = camera_info_intrinsics(
            320,
            240,
            &[290.0, 0.0, 159.75, 0.0, 290.0, 119.75, 0.0, 0.0, 1.0],
        )
        .unwrap();
        let k = scale_intrinsics(&k_in);
        assert_eq!((k.width, k.height, k.fx, k.fy), (640, 480, 580.0, 580.0));
        assert!((k.cx - 320.0).abs() < 1e-12 && (k.cy - 240.0).abs() < 1e-12);
        for p in [
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(0.31, -0.2, 1.7),
            Point3::new(-0.5, 0.4, 2.2),
        ] {
            let a = k_in.project(&p).unwrap();
            let b = k.project(&p).unwrap();
            // pixel (i, j) of the input covers output pixels 2i, 2i+1: the
            // point's input pixel holds its output pixel
            let (i, j) = ((a.px + 0.5).floor() as u32, (a.py + 0.5).floor() as u32);
            let (u, v) = ((b.px + 0.5).floor() as u32, (b.py + 0.5).floor() as u32);
            let (x0, x1) = footprint(u, 320, 640);
            let (y0, y1) = footprint(v, 240, 480);
            assert!((x0..x1).contains(&i) && (y0..y1).contains(&j), "{p:?}");
            // and the continuous coordinates map by (c + 0.5)·s − 0.5
            assert!(((a.px + 0.5) * 2.0 - 0.5 - b.px).abs() < 1e-9);
            assert!(((a.py + 0.5) * 2.0 - 0.5 - b.py).abs() < 1e-9);
        }
        // 1280×720: the Kinect's 580/(320, 240) stretched, back to itself
        let k = scale_intrinsics(
            &camera_info_intrinsics(
                1280,
                720,
                &[1160.0, 0.0, 640.5, 0.0, 870.0, 360.25, 0.0, 0.0, 1.0],
            )
            .unwrap(),
        );
        assert!((k.fx - 580.0).abs() < 1e-9 && (k.fy - 580.0).abs() < 1e-9);
        assert!((k.cx - 320.0).abs() < 1e-9 && (k.cy - 240.0).abs() < 1e-9);
    }

    #[test]
    fn every_fault_is_refused_with_its_reason() {
        let data = vec![0u8; 640 * 480 * 4];
        let mut r = Resampler::new();
        let mut out = vec![0u16; N];
        let e = r
            .decode_into(&view(640, 480, "rgb8", 3, &data), &mut out)
            .unwrap_err();
        assert_eq!(e, RosImageError::Encoding("rgb8".into()));
        assert!(e.to_string().contains("rgb8"), "{e}");
        let bad = view(640, 480, "16UC1", 2, &data);
        let e = check(&ImageView { step: 1279, ..bad }).unwrap_err();
        assert!(matches!(e, RosImageError::Step { step: 1279, .. }), "{e}");
        let e = check(&ImageView {
            data: &data[..640 * 479 * 2],
            ..bad
        })
        .unwrap_err();
        assert!(matches!(e, RosImageError::Data { .. }), "{e}");
        let e = check(&ImageView {
            step: 640 * 4,
            data: &data[..640 * 4 * 480 - 1],
            ..bad
        })
        .unwrap_err();
        assert!(matches!(e, RosImageError::Data { .. }), "{e}");
        for (w, h) in [(0, 480), (640, 0), (1281, 720), (1280, 801)] {
            let e = check(&ImageView {
                width: w,
                height: h,
                step: w * 2,
                ..bad
            })
            .unwrap_err();
            assert!(matches!(e, RosImageError::Size { .. }), "{w}×{h}: {e}");
        }
        // a 32FC1 row is 4 bytes a pixel
        let e = check(&view(640, 480, "32FC1", 2, &data)).unwrap_err();
        assert!(matches!(e, RosImageError::Step { bytes: 4, .. }), "{e}");
        // an output of the wrong length
        assert!(r.decode_into(&bad, &mut out[..100]).is_err());
        // a control character in an encoding is not logged as such
        let e = check(&view(640, 480, "x\ny", 2, &data)).unwrap_err();
        assert!(!e.to_string().contains('\n'));

        let k = |fx: f64, fy: f64, cx: f64, cy: f64| [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0];
        for bad in [
            k(0.0, 580.0, 320.0, 240.0),
            k(580.0, -1.0, 320.0, 240.0),
            k(f64::NAN, 580.0, 320.0, 240.0),
            k(580.0, f64::INFINITY, 320.0, 240.0),
            k(580.0, 580.0, -3.0, 240.0),
            k(580.0, 580.0, 320.0, 481.0),
            k(580.0, 580.0, f64::NAN, 240.0),
        ] {
            let e = camera_info_intrinsics(640, 480, &bad).unwrap_err();
            assert!(matches!(e, RosImageError::Info(_)), "{bad:?}: {e}");
        }
        assert!(camera_info_intrinsics(0, 480, &k(580.0, 580.0, 0.0, 0.0)).is_err());
        assert!(camera_info_intrinsics(640, 480, &k(580.0, 580.0, 320.0, 240.0)).is_ok());
    }

    #[test]
    fn metres_become_millimetres_and_non_depths_no_reading() {
        assert_eq!(metres_to_mm(0.8886), 889);
        assert_eq!(metres_to_mm(0.0001), 1);
        assert_eq!(metres_to_mm(65.6), 0);
        for x in [0.0, -0.0, -2.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(metres_to_mm(x), 0, "{x}");
        }
        for mm in 1..=u16::MAX {
            assert_eq!(metres_to_mm(f32::from(mm) / 1000.0), mm);
        }
    }
}
