//! The Kinect v1's depth (what libfreenect's `FREENECT_DEPTH_11BIT` and a
//! fakenect recording carry): raw 11-bit disparity ↔ depth in millimetres, with OpenKinect's
//! conversion z \[m\] = 1 / (raw·(−0.0030711016) + 3.3309495161), tabulated
//! once for the 2048 raw values.
//!
//! Quantisation: one raw step is dz ≈ 0.0030711016·z² m (≈ 1.5 mm at
//! 0.7 m, ≈ 12 mm at 2 m, ≈ 31 mm at 3 m). Writing a depth d as the raw
//! whose tabulated depth is nearest ([`Disparity::mm_to_raw`]) and reading
//! it back errs by at most half the depth difference of the two raws whose
//! depths bracket d ([`Disparity::step_mm`]).

/// Pixels of a Kinect v1 depth frame: 640×480.
pub const PIXELS: usize = 640 * 480;

/// Raw value of a pixel without a reading.
pub const RAW_NONE: u16 = 2047;
/// Raw values: 11 bits.
pub const RAW_COUNT: usize = 2048;
/// Slope of the inverse depth [1/(m·raw)] (OpenKinect).
pub const K1: f64 = -0.003_071_101_6;
/// Inverse depth at raw 0 [1/m] (OpenKinect).
pub const K2: f64 = 3.330_949_516_1;
/// The deepest depth kept \[mm\]: the Kinect v1 reads nothing useful beyond
/// 10 m (libfreenect's `FREENECT_DEPTH_MM_MAX_VALUE`); farther raws (up
/// to raw 1084, where the formula's depth runs off to infinity) become 0.
pub const MAX_DEPTH_MM: u16 = 10_000;

/// Depth of raw disparity `raw` \[m\] by the formula (not rounded; may be
/// non-positive or huge past raw 1084).
pub fn raw_to_m(raw: u16) -> f64 {
    1.0 / (raw as f64 * K1 + K2)
}

/// A frame that is not a 640×480 frame of 11-bit values.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum FrameError {
    /// wrong number of pixels in or out
    #[error("a frame of {got} pixels ({expected} expected)")]
    Size {
        /// pixels in the frame given
        got: usize,
        /// pixels of a 640×480 frame
        expected: usize,
    },
    /// a value that is not 11 bits
    #[error("pixel {pixel}: raw value {raw} is not an 11-bit disparity")]
    NotDisparity {
        /// row-major index of the pixel
        pixel: usize,
        /// its value
        raw: u16,
    },
}

/// The raw → millimetre table and its inverse.
#[derive(Clone, Debug)]
pub struct Disparity {
    /// depth of each raw [mm] (0: no reading)
    mm: [u16; RAW_COUNT],
    /// the raws with a reading: 0..valid_raws, depths non-decreasing
    valid_raws: usize,
}

impl Default for Disparity {
    fn default() -> Self {
        Self::new()
    }
}

impl Disparity {
    /// Tabulate the 2048 raws: 2047 → 0, a depth that is not positive or
    /// beyond [`MAX_DEPTH_MM`] → 0, otherwise rounded to the millimetre.
    pub fn new() -> Disparity {
        let mut mm = [0u16; RAW_COUNT];
        let mut valid_raws = 0;
        for raw in 0..RAW_NONE {
            let z = raw_to_m(raw);
            let d = (z * 1000.0).round();
            if z > 0.0 && d.is_finite() && d >= 1.0 && d <= MAX_DEPTH_MM as f64 {
                mm[raw as usize] = d as u16;
                // depth grows with raw until the formula's pole: the valid
                // raws are one prefix
                if valid_raws == raw as usize {
                    valid_raws += 1;
                }
            }
        }
        Disparity { mm, valid_raws }
    }

    /// Depth of raw disparity `raw` \[mm\] (0: no reading; so is a value
    /// outside 11 bits).
    pub fn raw_to_mm(&self, raw: u16) -> u16 {
        self.mm.get(raw as usize).copied().unwrap_or(0)
    }

    /// The nearest and farthest depths a raw can give \[mm\].
    pub fn range_mm(&self) -> (u16, u16) {
        (self.mm[0], self.mm[self.valid_raws - 1])
    }

    /// The raw whose depth is nearest `mm` \[mm\] (ties to the smaller raw);
    /// 0 → [`RAW_NONE`]. A depth outside [`Disparity::range_mm`] gets the
    /// end raw (check the range first to refuse it).
    pub fn mm_to_raw(&self, mm: u16) -> u16 {
        if mm == 0 {
            return RAW_NONE;
        }
        let table = &self.mm[..self.valid_raws];
        // first raw whose depth is ≥ mm
        let above = table.partition_point(|&d| d < mm);
        if above == 0 {
            return 0;
        }
        if above == table.len() {
            return (table.len() - 1) as u16;
        }
        let below = above - 1;
        if mm - table[below] <= table[above] - mm {
            below as u16
        } else {
            above as u16
        }
    }

    /// The depth difference \[mm\] between the two raws whose depths bracket
    /// `mm` (the quantisation there): a depth written with
    /// [`Disparity::mm_to_raw`] reads back within half of it. 0 for 0, and
    /// for a depth outside the range.
    pub fn step_mm(&self, mm: u16) -> u16 {
        let (lo, hi) = self.range_mm();
        if mm == 0 || mm < lo || mm > hi {
            return 0;
        }
        let table = &self.mm[..self.valid_raws];
        let above = table.partition_point(|&d| d < mm);
        if table[above] == mm {
            // read back exactly
            return 0;
        }
        table[above] - table[above - 1]
    }

    /// Convert a raw 640×480 frame into millimetres, into `out` (640×480).
    /// A frame of another size or with a value outside 11 bits is refused
    /// (`out` then holds a partial frame: the caller must not use it).
    pub fn frame_to_mm(&self, raw: &[u16], out: &mut [u16]) -> Result<(), FrameError> {
        for len in [raw.len(), out.len()] {
            if len != PIXELS {
                return Err(FrameError::Size {
                    got: len,
                    expected: PIXELS,
                });
            }
        }
        for (pixel, (o, &r)) in out.iter_mut().zip(raw).enumerate() {
            match self.mm.get(r as usize) {
                Some(&d) => *o = d,
                None => return Err(FrameError::NotDisparity { pixel, raw: r }),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_reading_is_2047_both_ways() {
        let t = Disparity::new();
        assert_eq!(t.raw_to_mm(RAW_NONE), 0);
        assert_eq!(t.mm_to_raw(0), RAW_NONE);
        assert_eq!(t.raw_to_mm(2048), 0);
        assert_eq!(t.raw_to_mm(u16::MAX), 0);
    }

    #[test]
    fn the_table_follows_the_formula() {
        let t = Disparity::new();
        // raw 0: 1/3.3309 m
        assert_eq!(t.raw_to_mm(0), 300);
        // the Kinect's usual working range, a few known points
        for raw in [400u16, 600, 800, 1000] {
            let z = 1.0 / (raw as f64 * -0.0030711016 + 3.3309495161);
            assert_eq!(t.raw_to_mm(raw), (z * 1000.0).round() as u16);
        }
        // past 10 m and past the pole (raw ≥ 1085: negative depths): none
        let (lo, hi) = t.range_mm();
        assert_eq!(lo, 300);
        assert!(hi <= MAX_DEPTH_MM && hi > 9_000, "{hi}");
        for raw in 1053..RAW_NONE {
            assert_eq!(t.raw_to_mm(raw), 0, "raw {raw}");
        }
        assert!(raw_to_m(1085) < 0.0);
        // non-decreasing over the valid raws
        for raw in 1..t.valid_raws {
            assert!(t.mm[raw] >= t.mm[raw - 1]);
        }
    }

    #[test]
    fn millimetres_round_trip_within_half_a_raw_step() {
        let t = Disparity::new();
        let (lo, hi) = t.range_mm();
        let mut worst = 0u32;
        for mm in lo..=hi {
            let back = t.raw_to_mm(t.mm_to_raw(mm));
            let err = (back as i32 - mm as i32).unsigned_abs();
            let step = t.step_mm(mm) as u32;
            // half the bracketing raws' depth difference
            assert!(2 * err <= step, "{mm} mm → {back} mm, step {step} mm");
            // and that step is one raw's depth difference by the formula:
            // 1/z_lo − 1/z_hi = 0.0030711016 /m, so z_hi − z_lo =
            // 0.0030711016·z_lo·z_hi m, with z_lo ≤ mm ≤ z_hi ≤ mm + step
            // (± 1 mm of rounding)
            let (m, s) = (mm as f64, step as f64);
            assert!(
                s <= 0.003_071_101_6 * m * (m + s) / 1000.0 + 1.0,
                "{mm} mm: {step}"
            );
            if mm <= 3000 {
                worst = worst.max(err);
            }
        }
        // up to 3 m: at most ~14 mm off (one raw step there: ~28 mm)
        assert!(worst <= 16, "{worst}");
        // every raw reads back to itself's depth
        for raw in 0..t.valid_raws as u16 {
            let mm = t.raw_to_mm(raw);
            assert_eq!(t.raw_to_mm(t.mm_to_raw(mm)), mm);
        }
        // out of range: the end raws
        assert_eq!(t.mm_to_raw(1), 0);
        assert_eq!(t.raw_to_mm(t.mm_to_raw(u16::MAX)), hi);
    }

    #[test]
    fn a_frame_of_the_wrong_size_or_values_is_refused() {
        let t = Disparity::new();
        let mut out = vec![0u16; PIXELS];
        let raw = vec![RAW_NONE; PIXELS];
        assert_eq!(t.frame_to_mm(&raw, &mut out), Ok(()));
        assert!(out.iter().all(|&d| d == 0));
        assert!(matches!(
            t.frame_to_mm(&raw[..PIXELS - 1], &mut out),
            Err(FrameError::Size { .. })
        ));
        let mut bad = vec![600u16; PIXELS];
        bad[1234] = 4000;
        assert_eq!(
            t.frame_to_mm(&bad, &mut out),
            Err(FrameError::NotDisparity {
                pixel: 1234,
                raw: 4000
            })
        );
    }
}
