//! The body's surface as a graph and its accumulative geodesic extrema (AGEX,
//! Plagemann et al. ICRA 2010): nodes are a person's grid cells, edges join
//! 8-neighbours of one surface (the segmentation's depth-continuity rule),
//! weighted by their 3-D distance \[m\]. Dijkstra from the body's centre gives
//! the farthest point, the first extremum; each extremum found becomes a source
//! too and the next extremum is the point farthest from all of them. Head,
//! hands and feet are among the first extrema.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::grid::Grid;
use crate::segment::{JoinRule, Segmenter, BRIDGE_CELLS, NEIGHBOURS};

/// No node / no predecessor.
pub const NONE: u32 = u32::MAX;

/// Edge slots per node: 8 neighbours and 2 bridges.
const SLOTS: usize = 10;

/// Most extrema per person.
pub const MAX_EXTREMA: usize = 16;

/// A weighted edge of the surface graph.
#[derive(Debug, Clone, Copy)]
pub struct Edge {
    /// target node
    pub to: u32,
    /// 3-D distance \[m\]
    pub w: f32,
}

const NO_EDGE: Edge = Edge { to: NONE, w: 0.0 };

/// An accumulative geodesic extremum.
#[derive(Debug, Clone, Copy)]
pub struct Extremum {
    /// its node
    pub node: u32,
    /// its geodesic distance from the centre and the extrema before it when found \[m\]
    pub dist: f32,
}

/// The graph of one person and the distances over it; allocated once for the
/// whole grid, reused for every person of every frame.
#[derive(Debug, Clone)]
pub struct Geodesic {
    /// per grid cell: its node in the current person (meaningful only for its cells)
    local: Vec<u32>,
    /// per node: its grid cell
    pub cells: Vec<u32>,
    /// per node: its point, camera frame \[m\]
    pub pts: Vec<[f32; 3]>,
    adj: Vec<[Edge; SLOTS]>,
    /// per node: distance from the centre \[m\] and the predecessor toward it
    pub dist0: Vec<f32>,
    /// per node: the next node on its shortest path to the centre ([`NONE`] at the
    /// centre and where unreached)
    pub pred0: Vec<u32>,
    /// per node: distance from the centre and every extremum \[m\]
    pub agex: Vec<f32>,
    /// per node: distance from the head's extremum \[m\] (after [`Geodesic::from_head`])
    pub head: Vec<f32>,
    /// per node: distance of the last bounded search \[m\]
    pub scratch: Vec<f32>,
    heap: BinaryHeap<Reverse<u64>>,
    /// the node nearest the component's centroid
    pub centre: u32,
    /// the extrema in the order found
    pub extrema: Vec<Extremum>,
}

impl Geodesic {
    /// Room for a grid of `n_cells` cells.
    pub fn new(n_cells: usize) -> Self {
        Self {
            local: vec![NONE; n_cells],
            cells: Vec::with_capacity(n_cells),
            pts: Vec::with_capacity(n_cells),
            adj: Vec::with_capacity(n_cells),
            dist0: Vec::with_capacity(n_cells),
            pred0: Vec::with_capacity(n_cells),
            agex: Vec::with_capacity(n_cells),
            head: Vec::with_capacity(n_cells),
            scratch: Vec::with_capacity(n_cells),
            // lazy deletion: at most one push per directed edge and the source
            heap: BinaryHeap::with_capacity(SLOTS * n_cells + 8),
            centre: NONE,
            extrema: Vec::with_capacity(MAX_EXTREMA),
        }
    }

    /// Number of nodes of the current person.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether the current person has no nodes.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Builds the graph of person `person` (an index into `seg.components`:
    /// its component and the parts given to it, see [`Segmenter::owner`]) and
    /// finds up to `k` extrema at least `min_m` (geodesic) from the centre and
    /// each other. A part joins its body by bridge edges across the gap or the
    /// depth jump between them.
    pub fn build(
        &mut self,
        grid: &Grid,
        seg: &Segmenter,
        person: usize,
        rule: &JoinRule,
        k: usize,
        min_m: f32,
    ) {
        self.cells.clear();
        self.pts.clear();
        self.adj.clear();
        self.extrema.clear();
        self.centre = NONE;
        self.gather(grid, seg, person);
        self.connect(grid, seg, rule);
        self.bridge(grid, seg, person);
        if self.cells.is_empty() {
            return;
        }
        self.search_from_centre(seg.components[person].centroid);
        self.find_extrema(k, min_m);
    }

    /// The cells of person `person`: its component's and its parts'.
    fn gather(&mut self, grid: &Grid, seg: &Segmenter, person: usize) {
        for (m, part) in seg.components.iter().enumerate() {
            if seg.owner[m] != person as u32 {
                continue;
            }
            for &c in &seg.order[part.start..part.end] {
                self.local[c as usize] = self.cells.len() as u32;
                self.cells.push(c);
                self.pts.push(grid.pts[c as usize]);
            }
        }
    }

    /// Edges between neighbouring cells of the same component that `rule`
    /// joins (their depths continuous), weighted by their distance \[m\].
    fn connect(&mut self, grid: &Grid, seg: &Segmenter, rule: &JoinRule) {
        let (gw, gh) = (grid.gw as isize, grid.gh as isize);
        for &c in &self.cells {
            let c = c as usize;
            let p = grid.pts[c];
            let label = seg.labels[c];
            let (i, j) = ((c % grid.gw) as isize, (c / grid.gw) as isize);
            let mut edges = [NO_EDGE; SLOTS];
            for (e, (di, dj)) in NEIGHBOURS.iter().enumerate() {
                let (ni, nj) = (i + di, j + dj);
                if ni < 0 || nj < 0 || ni >= gw || nj >= gh {
                    continue;
                }
                let nc = (nj * gw + ni) as usize;
                if seg.labels[nc] != label {
                    continue;
                }
                let q = grid.pts[nc];
                if !rule.joins(p[2], q[2]) {
                    continue;
                }
                edges[e] = Edge {
                    to: self.local[nc],
                    w: dist(p, q),
                };
            }
            self.adj.push(edges);
        }
    }

    /// Bridges: from each cell of a part to the nearest cell of another
    /// component of person `person`'s group, within [`BRIDGE_CELLS`].
    fn bridge(&mut self, grid: &Grid, seg: &Segmenter, person: usize) {
        let comp = seg.components[person];
        let (gw, gh) = (grid.gw as isize, grid.gh as isize);
        for v in 0..self.cells.len() {
            let c = self.cells[v] as usize;
            let label = seg.labels[c];
            if label == comp.label {
                continue;
            }
            let p = grid.pts[c];
            let (i, j) = ((c % grid.gw) as isize, (c / grid.gw) as isize);
            let mut best = (f32::INFINITY, NONE);
            for dj in -BRIDGE_CELLS..=BRIDGE_CELLS {
                for di in -BRIDGE_CELLS..=BRIDGE_CELLS {
                    let (ni, nj) = (i + di, j + dj);
                    if ni < 0 || nj < 0 || ni >= gw || nj >= gh {
                        continue;
                    }
                    let nc = (nj * gw + ni) as usize;
                    let l = seg.labels[nc];
                    if l == label || seg.owner_of_cell(nc) != Some(person) {
                        continue;
                    }
                    let q = grid.pts[nc];
                    let d = dist(p, q);
                    if d < best.0 {
                        best = (d, self.local[nc]);
                    }
                }
            }
            if best.1 == NONE {
                continue;
            }
            let (a, b) = (v, best.1 as usize);
            let free_a = (8..SLOTS).find(|&s| self.adj[a][s].to == NONE);
            let free_b = (8..SLOTS).find(|&s| self.adj[b][s].to == NONE);
            if let (Some(sa), Some(sb)) = (free_a, free_b) {
                self.adj[a][sa] = Edge {
                    to: b as u32,
                    w: best.0,
                };
                self.adj[b][sb] = Edge {
                    to: a as u32,
                    w: best.0,
                };
            }
        }
    }

    /// The centre (the node nearest `centroid`, camera frame \[m\]) and the
    /// geodesic distances and paths from it ([`Geodesic::dist0`],
    /// [`Geodesic::pred0`]).
    fn search_from_centre(&mut self, centroid: [f64; 3]) {
        let n = self.cells.len();
        let cen = [centroid[0] as f32, centroid[1] as f32, centroid[2] as f32];
        let mut best = (f32::INFINITY, 0u32);
        for (k, &p) in self.pts.iter().enumerate() {
            let d = dist(p, cen);
            if d < best.0 {
                best = (d, k as u32);
            }
        }
        self.centre = best.1;
        self.dist0.clear();
        self.dist0.resize(n, f32::INFINITY);
        self.pred0.clear();
        self.pred0.resize(n, NONE);
        dijkstra(
            &self.adj,
            &mut self.dist0,
            Some(&mut self.pred0),
            &mut self.heap,
            self.centre,
            f32::INFINITY,
        );
    }

    /// Up to `k` extrema, each the node farthest from the centre and the
    /// extrema before it, while at least `min_m` \[m\] away.
    fn find_extrema(&mut self, k: usize, min_m: f32) {
        self.agex.clear();
        self.agex.extend_from_slice(&self.dist0);
        for _ in 0..k.min(MAX_EXTREMA) {
            let mut far = (0.0f32, NONE);
            for (v, &d) in self.agex.iter().enumerate() {
                if d.is_finite() && d > far.0 {
                    far = (d, v as u32);
                }
            }
            if far.1 == NONE || far.0 < min_m {
                break;
            }
            self.extrema.push(Extremum {
                node: far.1,
                dist: far.0,
            });
            // the new source only lowers distances: an incremental search
            dijkstra(
                &self.adj,
                &mut self.agex,
                None,
                &mut self.heap,
                far.1,
                f32::INFINITY,
            );
        }
    }

    /// Distances from node `head` over the whole graph into [`Geodesic::head`].
    pub fn from_head(&mut self, head: u32) {
        self.head.clear();
        self.head.resize(self.cells.len(), f32::INFINITY);
        if (head as usize) < self.cells.len() {
            dijkstra(
                &self.adj,
                &mut self.head,
                None,
                &mut self.heap,
                head,
                f32::INFINITY,
            );
        }
    }

    /// Mean point \[m\] of the surface within geodesic distance `radius` of
    /// `node`, and the number of nodes averaged.
    pub fn cap_mean(&mut self, node: u32, radius: f32) -> ([f64; 3], usize) {
        self.scratch.clear();
        self.scratch.resize(self.cells.len(), f32::INFINITY);
        if node as usize >= self.cells.len() {
            return ([0.0; 3], 0);
        }
        dijkstra(
            &self.adj,
            &mut self.scratch,
            None,
            &mut self.heap,
            node,
            radius,
        );
        let mut s = [0.0f64; 3];
        let mut n = 0usize;
        for (v, &d) in self.scratch.iter().enumerate() {
            if d <= radius {
                let p = self.pts[v];
                for k in 0..3 {
                    s[k] += f64::from(p[k]);
                }
                n += 1;
            }
        }
        if n > 0 {
            for c in &mut s {
                *c /= n as f64;
            }
        }
        (s, n)
    }

    /// Point of node `v` \[m\] in f64.
    pub fn point(&self, v: u32) -> [f64; 3] {
        let p = self.pts[v as usize];
        [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
    }
}

/// Euclidean distance \[m\].
#[inline]
pub fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    let (x, y, z) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    (x * x + y * y + z * z).sqrt()
}

/// Dijkstra from `source` over `adj`, lowering `dist` in place (a fresh search
/// when `dist` is all infinite, an incremental one otherwise); records
/// predecessors if given; nodes farther than `bound` are not expanded.
fn dijkstra(
    adj: &[[Edge; SLOTS]],
    dist: &mut [f32],
    mut pred: Option<&mut [u32]>,
    heap: &mut BinaryHeap<Reverse<u64>>,
    source: u32,
    bound: f32,
) {
    heap.clear();
    dist[source as usize] = 0.0;
    if let Some(p) = pred.as_deref_mut() {
        p[source as usize] = NONE;
    }
    // non-negative f32 order as their bit patterns: one u64 key per entry
    heap.push(Reverse(u64::from(source)));
    while let Some(Reverse(key)) = heap.pop() {
        let v = (key & 0xFFFF_FFFF) as usize;
        let d = f32::from_bits((key >> 32) as u32);
        if d > dist[v] {
            continue;
        }
        if d > bound {
            break;
        }
        for e in &adj[v] {
            if e.to == NONE {
                continue;
            }
            let nd = d + e.w;
            let t = e.to as usize;
            if nd < dist[t] {
                dist[t] = nd;
                if let Some(p) = pred.as_deref_mut() {
                    p[t] = v as u32;
                }
                // lazy deletion can exceed one push per edge only with equal
                // keys; never grow past the preallocated room
                if heap.len() < heap.capacity() {
                    heap.push(Reverse((u64::from(nd.to_bits()) << 32) | e.to as u64));
                }
            }
        }
    }
}
