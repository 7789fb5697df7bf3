//! The downsampled surface: one depth sample per `step × step` cell of the
//! image, back-projected to the camera frame (x right, y down, z forward, metres).

use phri_depth::Intrinsics;

use crate::background::Background;

/// Per-frame samples on a regular grid of cells. Allocated once.
#[derive(Debug, Clone)]
pub struct Grid {
    /// cells per row
    pub gw: usize,
    /// cells per column
    pub gh: usize,
    /// cell size \[px\]
    pub step: u32,
    /// the sampled point of each cell, camera frame \[m\] (meaningful where `valid`)
    pub pts: Vec<[f32; 3]>,
    /// the cell has a reading in range, not masked, and (with a background) in the foreground
    pub valid: Vec<bool>,
    /// image width \[px\]
    width: usize,
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
}

/// What a frame's sampling needs besides the frame.
#[derive(Clone, Copy)]
pub struct SampleParams<'a> {
    /// metres per depth unit
    pub scale_m: f64,
    /// nearest and farthest reading kept \[m\]
    pub min_m: f64,
    /// farthest reading kept \[m\]
    pub max_m: f64,
    /// pixels to ignore (the robot's own), row-major, `true` = ignore
    pub ignore: Option<&'a [bool]>,
    /// learned background and its margin `m + k σ_z`
    pub background: Option<&'a Background>,
    /// the margin's constant part `m` \[m\]
    pub bg_margin_m: f64,
    /// the margin's noise part `k`, in depth-noise deviations σ_z
    pub bg_margin_sigmas: f64,
}

impl Grid {
    /// A grid of `step`-pixel cells over the camera's image.
    pub fn new(intrinsics: &Intrinsics, step: u32) -> Self {
        let step = step.max(1);
        let gw = (intrinsics.width / step).max(1) as usize;
        let gh = (intrinsics.height / step).max(1) as usize;
        Self {
            gw,
            gh,
            step,
            pts: vec![[0.0; 3]; gw * gh],
            valid: vec![false; gw * gh],
            width: intrinsics.width as usize,
            fx: intrinsics.fx as f32,
            fy: intrinsics.fy as f32,
            cx: intrinsics.cx as f32,
            cy: intrinsics.cy as f32,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.gw * self.gh
    }

    /// Whether the grid has no cells (never: at least one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Width of a cell at depth `z` \[m\].
    #[inline]
    pub fn cell_m(&self, z: f32) -> f32 {
        self.step as f32 * z / self.fx
    }

    /// Area a cell's sample stands for at depth `z` \[m²\].
    #[inline]
    pub fn cell_area_m2(&self, z: f32) -> f32 {
        let s = self.step as f32 * z;
        s * s / (self.fx * self.fy)
    }

    /// Pixel coordinates of the centre of cell `(i, j)`.
    #[inline]
    pub fn cell_pixel(&self, i: usize, j: usize) -> (usize, usize) {
        let h = (self.step / 2) as usize;
        (i * self.step as usize + h, j * self.step as usize + h)
    }

    /// The cell under a camera-frame point, if it projects into the grid.
    pub fn cell_of(&self, p: [f64; 3]) -> Option<usize> {
        if !(p[2] > 1e-6) || !p[0].is_finite() || !p[1].is_finite() {
            return None;
        }
        let u = f64::from(self.fx) * p[0] / p[2] + f64::from(self.cx);
        let v = f64::from(self.fy) * p[1] / p[2] + f64::from(self.cy);
        let s = f64::from(self.step);
        let (i, j) = ((u / s).floor(), (v / s).floor());
        if i < 0.0 || j < 0.0 || i >= self.gw as f64 || j >= self.gh as f64 {
            return None;
        }
        Some(j as usize * self.gw + i as usize)
    }

    /// Whether cell `c` lies on the grid's border (its surface may go on out of view).
    #[inline]
    pub fn on_border(&self, c: usize) -> bool {
        let (i, j) = (c % self.gw, c / self.gw);
        i == 0 || j == 0 || i + 1 == self.gw || j + 1 == self.gh
    }

    /// Samples `depth` (row-major, the camera's size, checked by the caller):
    /// per cell its centre pixel, or if that has no usable reading the first
    /// usable of four pixels around it.
    pub fn sample(&mut self, depth: &[u16], p: &SampleParams) {
        let step = self.step as usize;
        let h = step / 2;
        let q = (step / 4).max(1);
        let offsets: [(isize, isize); 5] = [
            (0, 0),
            (-(q as isize), -(q as isize)),
            (q as isize, q as isize),
            (q as isize, -(q as isize)),
            (-(q as isize), q as isize),
        ];
        let scale = p.scale_m as f32;
        let (min_m, max_m) = (p.min_m as f32, p.max_m as f32);
        let rows = depth.len() / self.width.max(1);
        for j in 0..self.gh {
            for i in 0..self.gw {
                let c = j * self.gw + i;
                self.valid[c] = false;
                let (u0, v0) = (i * step + h, j * step + h);
                for (k, &(du, dv)) in offsets.iter().enumerate() {
                    if k > 0 && step < 2 {
                        break;
                    }
                    let u = u0 as isize + du;
                    let v = v0 as isize + dv;
                    if u < 0 || v < 0 || u as usize >= self.width || v as usize >= rows {
                        continue;
                    }
                    let (u, v) = (u as usize, v as usize);
                    let idx = v * self.width + u;
                    let raw = depth[idx];
                    if raw == 0 {
                        continue;
                    }
                    if p.ignore
                        .is_some_and(|m| m.get(idx).copied().unwrap_or(false))
                    {
                        continue;
                    }
                    let z = f32::from(raw) * scale;
                    if !(z >= min_m && z <= max_m) {
                        continue;
                    }
                    // a background reading is no person: this cell is empty
                    if let Some(bg) = p.background.and_then(|b| b.depth_m(idx)) {
                        let margin =
                            p.bg_margin_m + p.bg_margin_sigmas * phri_depth::sigma_z(f64::from(bg));
                        if f64::from(z) > f64::from(bg) - margin {
                            break;
                        }
                    }
                    self.pts[c] = [
                        (u as f32 - self.cx) * z / self.fx,
                        (v as f32 - self.cy) * z / self.fy,
                        z,
                    ];
                    self.valid[c] = true;
                    break;
                }
            }
        }
    }
}
