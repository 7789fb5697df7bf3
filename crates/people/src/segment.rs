//! People from a depth frame: connected components of the downsampled surface
//! by depth continuity, each judged a person or not by its size, extent and
//! shape (a plane is a wall, a door or a table). The foreground itself (learned
//! background, floor, ignored pixels) is decided before, in [`crate::grid`] and
//! [`crate::floor`].

use nalgebra::{Matrix3, SymmetricEigen};

use crate::config::TrackerConfig;
use crate::grid::Grid;

/// Components examined per frame (those of at least 4 cells, in scan order).
pub const MAX_COMPONENTS: usize = 256;

/// No component.
pub const NO_LABEL: u32 = u32::MAX;

/// When two neighbouring cells belong to one surface: their depths differ by
/// at most `base + slope · cell(z) + sigmas · σ_z(z)` \[m\] at the nearer depth z.
#[derive(Debug, Clone, Copy)]
pub struct JoinRule {
    base: f32,
    /// `slope · step / f_x`: metres of allowed jump per metre of depth
    per_m: f32,
    sigmas: f32,
}

impl JoinRule {
    /// The rule of `cfg` on `grid`'s cells.
    pub fn new(cfg: &TrackerConfig, grid: &Grid) -> Self {
        Self {
            base: cfg.join_base_m as f32,
            per_m: cfg.join_cell_slope as f32 * grid.cell_m(1.0),
            sigmas: cfg.join_sigmas as f32,
        }
    }

    /// Whether depths `za`, `zb` \[m\] of neighbouring cells join.
    #[inline]
    pub fn joins(&self, za: f32, zb: f32) -> bool {
        let z = za.min(zb);
        let e = z - 0.4;
        let sigma = 0.0012 + 0.0019 * e * e;
        (za - zb).abs() <= self.base + self.per_m * z + self.sigmas * sigma
    }
}

/// One connected component of the surface.
#[derive(Debug, Clone, Copy, Default)]
pub struct Component {
    /// its label in [`Segmenter::labels`]
    pub label: u32,
    /// its cells are `Segmenter::order[start..end]`
    pub start: usize,
    /// one past its last cell in `Segmenter::order`
    pub end: usize,
    /// mean of its points, camera frame \[m\]
    pub centroid: [f64; 3],
    /// visible surface area \[m²\]
    pub area_m2: f64,
    /// extent along up \[m\]
    pub height_m: f64,
    /// extent across (perpendicular to up, camera x made horizontal) \[m\]
    pub width_m: f64,
    /// height along up of its highest and lowest point, relative to the camera \[m\]
    pub top_m: f64,
    /// height along up of its lowest point, relative to the camera \[m\]
    pub bottom_m: f64,
    /// RMS distance of its points from their best plane \[m\]
    pub planar_rms_m: f64,
    /// plausible as a person
    pub person: bool,
}

/// Connected components of the valid cells; allocated once.
#[derive(Debug, Clone)]
pub struct Segmenter {
    /// per cell: its component's label, [`NO_LABEL`] for an invalid cell
    pub labels: Vec<u32>,
    /// cells in breadth-first order, each component contiguous
    pub order: Vec<u32>,
    /// the components of at least 4 cells (at most [`MAX_COMPONENTS`])
    pub components: Vec<Component>,
    /// indices into `components` of the people, largest first
    pub people: Vec<usize>,
    /// per component: the person (component index) it belongs to, [`NO_LABEL`]
    /// for none; a person's own index for a person
    pub owner: Vec<u32>,
    /// per label: its index in `components`, [`NO_LABEL`] if not kept
    label_comp: Vec<u32>,
}

/// Components stored per frame have at least this many cells (a hand at 3 m has ~12).
const MIN_PART_CELLS: usize = 4;
/// A part (a hand or forearm held toward the camera, cut from the body by a
/// depth jump) is at most this large \[m², m\].
const PART_MAX_AREA_M2: f64 = 0.08;
const PART_MAX_EXTENT_M: f64 = 0.7;
/// A part is joined to a body within this many cells in the grid ...
pub const BRIDGE_CELLS: isize = 2;
/// ... that is not nearer than the part by more than this \[m\] (a part far
/// behind a body is something else seen past its edge).
const PART_BEHIND_M: f32 = 0.15;

impl Segmenter {
    /// Room for a grid of `n_cells` cells.
    pub fn new(n_cells: usize) -> Self {
        Self {
            labels: vec![NO_LABEL; n_cells],
            order: Vec::with_capacity(n_cells),
            components: Vec::with_capacity(MAX_COMPONENTS),
            people: Vec::with_capacity(MAX_COMPONENTS),
            owner: Vec::with_capacity(MAX_COMPONENTS),
            label_comp: vec![NO_LABEL; n_cells],
        }
    }

    /// Labels the components of `grid`'s valid cells and judges each;
    /// `up` is the unit up vector in the camera frame.
    pub fn run(&mut self, grid: &Grid, rule: &JoinRule, cfg: &TrackerConfig, up: [f64; 3]) {
        self.labels.fill(NO_LABEL);
        self.order.clear();
        self.components.clear();
        self.people.clear();
        let (gw, gh) = (grid.gw, grid.gh);
        let mut next_label = 0u32;
        for seed in 0..grid.len() {
            if !grid.valid[seed] || self.labels[seed] != NO_LABEL {
                continue;
            }
            let label = next_label;
            next_label += 1;
            let start = self.order.len();
            self.labels[seed] = label;
            self.order.push(seed as u32);
            let mut head = start;
            while head < self.order.len() {
                let c = self.order[head] as usize;
                head += 1;
                let (i, j) = ((c % gw) as isize, (c / gw) as isize);
                let zc = grid.pts[c][2];
                for (di, dj) in NEIGHBOURS {
                    let (ni, nj) = (i + di, j + dj);
                    if ni < 0 || nj < 0 || ni >= gw as isize || nj >= gh as isize {
                        continue;
                    }
                    let n = nj as usize * gw + ni as usize;
                    if grid.valid[n] && self.labels[n] == NO_LABEL && rule.joins(zc, grid.pts[n][2])
                    {
                        self.labels[n] = label;
                        self.order.push(n as u32);
                    }
                }
            }
            let end = self.order.len();
            self.label_comp[label as usize] = NO_LABEL;
            if end - start >= MIN_PART_CELLS && self.components.len() < MAX_COMPONENTS {
                let comp = judge(grid, &self.order[start..end], label, start, end, cfg, up);
                self.label_comp[label as usize] = self.components.len() as u32;
                self.components.push(comp);
            }
        }
        self.attach_parts(grid);
        for (k, c) in self.components.iter().enumerate() {
            if c.person {
                self.people.push(k);
            }
        }
        let comps = &self.components;
        self.people.sort_unstable_by(|&a, &b| {
            comps[b]
                .area_m2
                .total_cmp(&comps[a].area_m2)
                .then(comps[a].start.cmp(&comps[b].start))
        });
    }
}

impl Segmenter {
    /// The person (component index) that cell `cell` belongs to, if any.
    #[inline]
    pub fn owner_of_cell(&self, cell: usize) -> Option<usize> {
        let l = *self.labels.get(cell)?;
        if l == NO_LABEL {
            return None;
        }
        let k = self.label_comp[l as usize];
        if k == NO_LABEL {
            return None;
        }
        let o = self.owner[k as usize];
        (o != NO_LABEL).then_some(o as usize)
    }

    /// Gives the small components within [`BRIDGE_CELLS`] of a person's
    /// surface, in front of it across a depth jump (a hand or forearm toward
    /// the camera) or beside it at about its depth (an arm cut off by an edge
    /// shadow), to that person; repeated so that a hand in front of a forearm
    /// in front of the body joins too.
    fn attach_parts(&mut self, grid: &Grid) {
        self.owner.clear();
        for (k, c) in self.components.iter().enumerate() {
            self.owner.push(if c.person { k as u32 } else { NO_LABEL });
        }
        let (gw, gh) = (grid.gw as isize, grid.gh as isize);
        for _ in 0..3 {
            let mut changed = false;
            for k in 0..self.components.len() {
                let comp = self.components[k];
                if self.owner[k] != NO_LABEL
                    || comp.area_m2 > PART_MAX_AREA_M2
                    || comp.height_m > PART_MAX_EXTENT_M
                    || comp.width_m > PART_MAX_EXTENT_M
                {
                    continue;
                }
                'cells: for &c in &self.order[comp.start..comp.end] {
                    let c = c as usize;
                    let z = grid.pts[c][2];
                    let (i, j) = ((c % grid.gw) as isize, (c / grid.gw) as isize);
                    for dj in -BRIDGE_CELLS..=BRIDGE_CELLS {
                        for di in -BRIDGE_CELLS..=BRIDGE_CELLS {
                            let (ni, nj) = (i + di, j + dj);
                            if ni < 0 || nj < 0 || ni >= gw || nj >= gh {
                                continue;
                            }
                            let n = (nj * gw + ni) as usize;
                            let l = self.labels[n];
                            if l == NO_LABEL || l == comp.label {
                                continue;
                            }
                            let m = self.label_comp[l as usize];
                            if m == NO_LABEL || self.owner[m as usize] == NO_LABEL {
                                continue;
                            }
                            // in front of that body, or beside it at about its depth
                            if grid.pts[n][2] > z - PART_BEHIND_M {
                                self.owner[k] = self.owner[m as usize];
                                changed = true;
                                break 'cells;
                            }
                        }
                    }
                }
            }
            if !changed {
                break;
            }
        }
    }
}

/// The 8 neighbours of a cell.
pub const NEIGHBOURS: [(isize, isize); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// The unit vector across the body: camera x made perpendicular to `up`.
pub fn side_axis(up: [f64; 3]) -> [f64; 3] {
    let d = up[0];
    let s = [1.0 - d * up[0], -d * up[1], -d * up[2]];
    let n = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    if n < 1e-6 {
        // up along the camera's x: take z made perpendicular instead
        return [0.0, 0.0, 1.0];
    }
    [s[0] / n, s[1] / n, s[2] / n]
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f32; 3]) -> f64 {
    a[0] * f64::from(b[0]) + a[1] * f64::from(b[1]) + a[2] * f64::from(b[2])
}

/// Statistics of a component and whether it is a person.
fn judge(
    grid: &Grid,
    cells: &[u32],
    label: u32,
    start: usize,
    end: usize,
    cfg: &TrackerConfig,
    up: [f64; 3],
) -> Component {
    let side = side_axis(up);
    let n = cells.len() as f64;
    let mut mean = [0.0f64; 3];
    let mut area = 0.0f64;
    let (mut top, mut bottom) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut left, mut right) = (f64::INFINITY, f64::NEG_INFINITY);
    for &c in cells {
        let p = grid.pts[c as usize];
        for k in 0..3 {
            mean[k] += f64::from(p[k]);
        }
        area += f64::from(grid.cell_area_m2(p[2]));
        let h = dot(up, p);
        top = top.max(h);
        bottom = bottom.min(h);
        let s = dot(side, p);
        left = left.min(s);
        right = right.max(s);
    }
    for m in &mut mean {
        *m /= n;
    }
    let mut cov = Matrix3::<f64>::zeros();
    for &c in cells {
        let p = grid.pts[c as usize];
        let d = [
            f64::from(p[0]) - mean[0],
            f64::from(p[1]) - mean[1],
            f64::from(p[2]) - mean[2],
        ];
        for r in 0..3 {
            for k in 0..3 {
                cov[(r, k)] += d[r] * d[k];
            }
        }
    }
    cov /= n;
    let eig = SymmetricEigen::new(cov);
    let min_ev = eig.eigenvalues.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let rms = min_ev.max(0.0).sqrt();
    let height = top - bottom;
    let width = right - left;
    let noise = phri_depth::sigma_z(mean[2]);
    let person = cells.len() >= cfg.person_min_cells
        && area >= cfg.person_min_area_m2
        && height >= cfg.person_min_height_m
        && height <= cfg.person_max_height_m
        && width >= cfg.person_min_width_m
        && width <= cfg.person_max_width_m
        && rms > cfg.planar_max_rms_m + 0.5 * noise;
    Component {
        label,
        start,
        end,
        centroid: mean,
        area_m2: area,
        height_m: height,
        width_m: width,
        top_m: top,
        bottom_m: bottom,
        planar_rms_m: rms,
        person,
    }
}
