//! The learned background: per-pixel mean depth of frames without a person.
//! Foreground = clearly nearer than the background, by a margin that grows
//! with the depth noise σ_z(z) ∝ z² (REFERENCE §6).

use crate::error::{check_len, TrackError};

/// Per-pixel background depth, learned from frames the caller knows to be
/// empty of people. Allocated once; learning and lookups allocate nothing.
#[derive(Debug, Clone)]
pub struct Background {
    width: u32,
    height: u32,
    /// sum of the valid readings \[m\]
    sum: Vec<f32>,
    /// number of valid readings
    count: Vec<u16>,
    frames: u32,
}

impl Background {
    /// An empty model for a `width × height` camera.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![0.0; n],
            count: vec![0; n],
            frames: 0,
        }
    }

    /// Frames learned so far.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Forgets everything learned.
    pub fn clear(&mut self) {
        self.sum.fill(0.0);
        self.count.fill(0);
        self.frames = 0;
    }

    /// Adds one frame without people (`depth` raw units × `scale_m` = metres,
    /// 0 = no reading) to the per-pixel means.
    pub fn learn(&mut self, depth: &[u16], scale_m: f64) -> Result<(), TrackError> {
        check_len("background frame", self.width, self.height, depth.len())?;
        let s = scale_m as f32;
        for ((sum, count), &d) in self.sum.iter_mut().zip(self.count.iter_mut()).zip(depth) {
            if d != 0 && *count < u16::MAX {
                *sum += f32::from(d) * s;
                *count += 1;
            }
        }
        self.frames = self.frames.saturating_add(1);
        Ok(())
    }

    /// Mean background depth of pixel `index` \[m\], `None` where nothing was seen.
    #[inline]
    pub fn depth_m(&self, index: usize) -> Option<f32> {
        match self.count.get(index) {
            Some(&c) if c > 0 => Some(self.sum[index] / f32::from(c)),
            _ => None,
        }
    }
}
