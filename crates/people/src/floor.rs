//! The floor plane: given by the caller, or fitted to the downsampled surface
//! by RANSAC (deterministic), then removed before clustering. Camera frame, metres.

use serde::{Deserialize, Serialize};

use crate::error::TrackError;
use crate::grid::Grid;

/// A plane `n · p + d = 0` in the camera frame; `n` is a unit normal pointing
/// up (toward the room), `d` in metres, so `n · p + d` is a point's height above it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    /// unit normal, camera frame, pointing up
    pub normal: [f64; 3],
    /// offset \[m\]
    pub d: f64,
}

impl Plane {
    /// Height of `p` (camera frame \[m\]) above the plane \[m\].
    #[inline]
    pub fn height(&self, p: [f32; 3]) -> f64 {
        self.normal[0] * f64::from(p[0])
            + self.normal[1] * f64::from(p[1])
            + self.normal[2] * f64::from(p[2])
            + self.d
    }
}

/// How the floor is found.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FloorMode {
    /// no floor removal (a learned background, or a recorder, removed it)
    None,
    /// this plane (camera frame)
    Given(Plane),
    /// a plane fitted every frame by RANSAC among the near-horizontal planes
    /// (normal within 45° of up), seeded with the last frame's floor
    #[default]
    Ransac,
}

impl FloorMode {
    pub(crate) fn validate(&self) -> Result<(), TrackError> {
        if let FloorMode::Given(p) = self {
            let n = p.normal.iter().map(|c| c * c).sum::<f64>().sqrt();
            if !(n.is_finite() && (n - 1.0).abs() < 1e-3 && p.d.is_finite()) {
                return Err(TrackError::Config(format!(
                    "floor plane normal {:?} must be a finite unit vector and d = {} finite",
                    p.normal, p.d
                )));
            }
        }
        Ok(())
    }
}

/// RANSAC iterations per frame.
const ITERATIONS: usize = 48;
/// Minimum cosine between a floor normal and up (45°: the up vector may be a
/// guess, an upright camera's, when the camera is pitched).
const MIN_COS_UP: f64 = 0.707;
/// Inlier distance \[m\] (plus 3 σ_z of the point).
const INLIER_M: f64 = 0.03;

/// The RANSAC floor fitter: deterministic, no allocation per frame.
#[derive(Debug, Clone)]
pub struct FloorFit {
    /// indices of the valid grid cells of this frame
    cells: Vec<u32>,
    /// xorshift state, reset every frame (deterministic per frame)
    last: Option<Plane>,
}

impl FloorFit {
    /// Room for `n_cells` grid cells.
    pub fn new(n_cells: usize) -> Self {
        Self {
            cells: Vec::with_capacity(n_cells),
            last: None,
        }
    }

    /// Forgets the last frame's floor.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// The floor found in the last frame, if any.
    pub fn last(&self) -> Option<Plane> {
        self.last
    }

    /// Fits the floor to the valid cells of `grid` (camera frame), `up` the
    /// unit up vector. A plane is a floor when at least 8 % of the valid cells
    /// (and at least 40) lie on it and most valid cells are not below it.
    pub fn fit(&mut self, grid: &Grid, up: [f64; 3]) -> Option<Plane> {
        self.cells.clear();
        for (i, &v) in grid.valid.iter().enumerate() {
            if v {
                self.cells.push(i as u32);
            }
        }
        let n = self.cells.len();
        if n < 40 {
            self.last = None;
            return None;
        }
        // score on every k-th valid cell (at most ~1500 of them)
        let stride = (n / 1500).max(1);
        let score = |p: &Plane| -> (usize, usize) {
            let (mut inliers, mut below) = (0, 0);
            let mut k = 0;
            while k < n {
                let q = grid.pts[self.cells[k] as usize];
                let h = p.height(q);
                let tol = INLIER_M + 3.0 * phri_depth::sigma_z(f64::from(q[2]));
                if h.abs() < tol {
                    inliers += 1;
                } else if h < 0.0 {
                    below += 1;
                }
                k += stride;
            }
            (inliers, below)
        };
        let scored = n.div_ceil(stride);
        let mut best: Option<(Plane, usize)> = None;
        if let Some(p) = self.last {
            let (inl, below) = score(&p);
            if below * 10 < scored {
                best = Some((p, inl));
            }
        }
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15 ^ n as u64;
        let mut next = |m: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as usize
        };
        for _ in 0..ITERATIONS {
            let a = grid.pts[self.cells[next(n)] as usize];
            let b = grid.pts[self.cells[next(n)] as usize];
            let c = grid.pts[self.cells[next(n)] as usize];
            let u = [
                f64::from(b[0] - a[0]),
                f64::from(b[1] - a[1]),
                f64::from(b[2] - a[2]),
            ];
            let v = [
                f64::from(c[0] - a[0]),
                f64::from(c[1] - a[1]),
                f64::from(c[2] - a[2]),
            ];
            let mut nn = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = (nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]).sqrt();
            if !(len > 1e-9) {
                continue;
            }
            for c in &mut nn {
                *c /= len;
            }
            let mut cos = nn[0] * up[0] + nn[1] * up[1] + nn[2] * up[2];
            if cos < 0.0 {
                for c in &mut nn {
                    *c = -*c;
                }
                cos = -cos;
            }
            if cos < MIN_COS_UP {
                continue;
            }
            let d = -(nn[0] * f64::from(a[0]) + nn[1] * f64::from(a[1]) + nn[2] * f64::from(a[2]));
            let p = Plane { normal: nn, d };
            let (inl, below) = score(&p);
            if below * 10 >= scored {
                continue;
            }
            if best.is_none_or(|(_, b)| inl > b) {
                best = Some((p, inl));
            }
        }
        self.last = match best {
            Some((p, inl)) if inl * stride >= 40 && inl * 100 >= scored * 8 => Some(p),
            _ => None,
        };
        self.last
    }
}
