//! Z-buffer depth renderer of capsules, axis-aligned boxes and a floor plane,
//! with a Kinect v1-like sensor model (range limits, axial noise, millimetre
//! quantization, dropped pixels at depth discontinuities).
//!
//! Every pixel is an exact ray cast through the pixel centre: capsules are
//! intersected analytically, and only over the pixels of their projected
//! bounding rectangle. The static scene (floor, boxes) is kept between frames
//! and restored only where the last frame's capsules drew. The output is a
//! `width × height` row-major image of `u16` depths in millimetres, 0 = no
//! reading (the Kinect driver convention).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::camera::{CameraPose, Intrinsics};
use crate::error::{check_frame, DepthError};
use crate::lanes::{self, by_lanes, min, Lanes, RUN};
use crate::noise::{draws, normal_index, pixel_bits, sigma_z, NormalSource, TABLE_SIZE};
use crate::shapes::{camera_box_bounds, Aabb, Capsule, CapsulePixels, PixelRect, RayCapsule};

/// Surfaces nearer than this \[m\] block the view but give no reading.
pub(crate) const NEAR_M: f64 = 1e-3;

/// Plain maximum (one instruction): `b` if either is NaN.
#[inline(always)]
fn max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// Label of a pixel that sees no surface (see [`Renderer::render_labeled`]).
pub const LABEL_NONE: u16 = 0;

/// Sensor model of the renderer.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderOptions {
    /// add Gaussian axial noise `σ_z(z) = 0.0012 + 0.0019 (z − 0.4)²` m
    pub noise: bool,
    /// seed of the noise and drop-out sequence (deterministic per seed)
    pub seed: u64,
    /// nearest valid depth \[m\]; nearer surfaces read 0
    pub min_range_m: f64,
    /// farthest valid depth \[m\]; farther surfaces read 0
    pub max_range_m: f64,
    /// constant part of the depth jump \[m\] that marks a discontinuity
    pub edge_jump_m: f64,
    /// noise-proportional part of the jump, in multiples of `σ_z(z)`
    pub edge_jump_sigmas: f64,
    /// probability in \[0, 1\] that a pixel at a discontinuity reads 0 (edge shadow)
    pub edge_dropout: f64,
}

impl Default for RenderOptions {
    /// Kinect v1: noise on, range 0.5-4.5 m, edges over 0.05 m + 3σ dropped
    /// with probability 0.5, seed 0.
    fn default() -> Self {
        Self {
            noise: true,
            seed: 0,
            min_range_m: 0.5,
            max_range_m: 4.5,
            edge_jump_m: 0.05,
            edge_jump_sigmas: 3.0,
            edge_dropout: 0.5,
        }
    }
}

impl RenderOptions {
    /// Noise-free, no edge drop-out: depths are the exact ray intersections,
    /// rounded to the millimetre (range limits still apply).
    pub fn ideal() -> Self {
        Self {
            noise: false,
            edge_dropout: 0.0,
            ..Self::default()
        }
    }

    /// Checks ranges and probabilities.
    pub fn validate(&self) -> Result<(), DepthError> {
        let bad = |reason: String| {
            Err(DepthError::Parameter {
                what: "render options",
                reason,
            })
        };
        if !(self.min_range_m.is_finite()
            && self.max_range_m.is_finite()
            && self.min_range_m > 0.0
            && self.min_range_m < self.max_range_m
            && self.max_range_m <= 65.535)
        {
            return bad(format!(
                "range [{}, {}] m must satisfy 0 < min < max <= 65.535",
                self.min_range_m, self.max_range_m
            ));
        }
        if !(self.edge_jump_m.is_finite()
            && self.edge_jump_m >= 0.0
            && self.edge_jump_sigmas.is_finite()
            && self.edge_jump_sigmas >= 0.0)
        {
            return bad(format!(
                "edge jump {} m + {} σ must be finite and >= 0",
                self.edge_jump_m, self.edge_jump_sigmas
            ));
        }
        if !(0.0..=1.0).contains(&self.edge_dropout) {
            return bad(format!(
                "edge drop-out probability {} must lie in [0, 1]",
                self.edge_dropout
            ));
        }
        Ok(())
    }
}

/// A z-buffer depth renderer with preallocated buffers for one camera.
#[derive(Debug, Clone)]
pub struct Renderer {
    intrinsics: Intrinsics,
    pose: CameraPose,
    options: RenderOptions,
    /// `(u − c_x)/f_x` per column
    xn: Vec<f64>,
    /// `(v − c_y)/f_y` per row
    yn: Vec<f64>,
    /// exact depth per pixel \[m\], `INFINITY` = no surface
    zbuf: Vec<f64>,
    labels: Vec<u16>,
    normals: NormalSource,
    /// the vector width of the sensor model's pass on this CPU
    lanes: Lanes,
    /// the static scene (floor and boxes) of the last render, kept so that a
    /// frame redraws only what moved (see [`Background`])
    background: Background,
    /// one row's random bits and normal draws (the sensor pass's scratch)
    row: SenseRow,
}

/// One row's [`pixel_bits`] and the normal draw of each, filled by the
/// sensor pass before its arithmetic (which then runs in lanes).
#[derive(Debug, Clone)]
struct SenseRow {
    bits: Vec<u32>,
    noise: Vec<f64>,
}

/// The z-buffer and labels of the floor and the boxes alone, and the pixel
/// rectangles the capsules of the last render drew over them: the next
/// render restores those rectangles instead of redrawing the whole frame
/// (the camera, floor and boxes rarely change; the people and the arm do).
#[derive(Debug, Clone)]
struct Background {
    /// what it was drawn from: pose, floor height, boxes, label of the first box
    pose: Option<CameraPose>,
    floor_z: Option<u64>,
    boxes: Vec<Aabb>,
    first_box_label: u16,
    zbuf: Vec<f64>,
    labels: Vec<u16>,
    /// rectangles drawn over it since ...
    dirty: Vec<PixelRect>,
    /// ... unless more than `dirty` holds were: then the whole frame
    all_dirty: bool,
}

impl Renderer {
    /// A renderer for `intrinsics` at `pose`; allocates every buffer once.
    pub fn new(
        intrinsics: Intrinsics,
        pose: CameraPose,
        options: RenderOptions,
    ) -> Result<Self, DepthError> {
        intrinsics.validate()?;
        options.validate()?;
        let n = intrinsics.pixel_count();
        Ok(Self {
            intrinsics,
            pose,
            options,
            xn: intrinsics.column_factors(),
            yn: intrinsics.row_factors(),
            zbuf: vec![f64::INFINITY; n],
            labels: vec![LABEL_NONE; n],
            normals: NormalSource::new(options.seed),
            lanes: Lanes::detect(),
            background: Background {
                pose: None,
                floor_z: None,
                boxes: Vec::new(),
                first_box_label: 0,
                zbuf: vec![f64::INFINITY; n],
                labels: vec![LABEL_NONE; n],
                dirty: Vec::with_capacity(64),
                all_dirty: false,
            },
            row: SenseRow {
                bits: vec![0; intrinsics.width as usize],
                noise: vec![0.0; intrinsics.width as usize],
            },
        })
    }

    /// Camera intrinsics.
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }

    /// Camera pose.
    pub fn pose(&self) -> &CameraPose {
        &self.pose
    }

    /// Moves the camera.
    pub fn set_pose(&mut self, pose: CameraPose) {
        self.pose = pose;
    }

    /// Sensor model.
    pub fn options(&self) -> &RenderOptions {
        &self.options
    }

    /// Restarts the noise and drop-out sequence from `seed`.
    pub fn reseed(&mut self, seed: u64) {
        self.options.seed = seed;
        self.normals.reseed(seed);
    }

    /// Exact (noise-free, unquantized, no range limit) depth \[m\] of every
    /// pixel of the last render, row-major; `f64::INFINITY` where no surface is seen.
    pub fn exact_depth(&self) -> &[f64] {
        &self.zbuf
    }

    /// Renders `capsules` and `boxes` (base frame) and, if given, the floor plane
    /// `z = floor_z` \[m\] into `out` (`width × height` row-major, millimetres,
    /// 0 = no reading). The floor and boxes are drawn once and kept while they
    /// and the camera stay the same; a frame restores them only where the last
    /// frame's capsules were. Allocates nothing once it has seen as many
    /// capsules and boxes.
    ///
    /// Errors if `out` has the wrong size or a primitive is not finite (or has a
    /// negative radius, or `min > max`).
    pub fn render(
        &mut self,
        capsules: &[Capsule],
        boxes: &[Aabb],
        floor_z: Option<f64>,
        out: &mut [u16],
    ) -> Result<(), DepthError> {
        check_frame(
            "depth output",
            self.intrinsics.width,
            self.intrinsics.height,
            out.len(),
        )?;
        self.rasterize(capsules, boxes, floor_z)?;
        self.sense(out);
        Ok(())
    }

    /// [`Renderer::render`], also writing which primitive each pixel sees into
    /// `labels`: [`LABEL_NONE`] (0) for nothing, `1 + i` for `capsules[i]`,
    /// `1 + capsules.len() + j` for `boxes[j]`, `1 + capsules.len() + boxes.len()`
    /// for the floor. Labels describe the geometry: a pixel whose reading was
    /// dropped (range, edge shadow) keeps the label of the surface it sees.
    pub fn render_labeled(
        &mut self,
        capsules: &[Capsule],
        boxes: &[Aabb],
        floor_z: Option<f64>,
        out: &mut [u16],
        labels: &mut [u16],
    ) -> Result<(), DepthError> {
        let (w, h) = (self.intrinsics.width, self.intrinsics.height);
        check_frame("depth output", w, h, out.len())?;
        check_frame("label output", w, h, labels.len())?;
        if capsules.len() + boxes.len() + 1 > usize::from(u16::MAX) {
            return Err(DepthError::Parameter {
                what: "render_labeled",
                reason: format!(
                    "{} primitives do not fit 16-bit labels",
                    capsules.len() + boxes.len() + 1
                ),
            });
        }
        self.rasterize(capsules, boxes, floor_z)?;
        self.sense(out);
        labels.copy_from_slice(&self.labels);
        Ok(())
    }

    /// Fills the exact z-buffer and the labels.
    fn rasterize(
        &mut self,
        capsules: &[Capsule],
        boxes: &[Aabb],
        floor_z: Option<f64>,
    ) -> Result<(), DepthError> {
        for (index, c) in capsules.iter().enumerate() {
            if !c.is_valid() {
                return Err(DepthError::Primitive {
                    what: "capsule",
                    index,
                    reason: "endpoints and radius must be finite, radius >= 0",
                });
            }
        }
        for (index, b) in boxes.iter().enumerate() {
            if !b.is_valid() {
                return Err(DepthError::Primitive {
                    what: "box",
                    index,
                    reason: "corners must be finite with min <= max",
                });
            }
        }
        if let Some(fz) = floor_z {
            if !fz.is_finite() {
                return Err(DepthError::Parameter {
                    what: "floor",
                    reason: format!("height {fz} m is not finite"),
                });
            }
        }
        // the static scene (the floor, or nothing, then the boxes) from the
        // background, redrawn only when it changed; then the capsules
        let first_box_label = u16::try_from(1 + capsules.len()).unwrap_or(u16::MAX);
        let bg = &self.background;
        let same = bg.pose == Some(self.pose)
            && bg.floor_z == floor_z.map(f64::to_bits)
            && bg.first_box_label == first_box_label
            && bg.boxes.as_slice() == boxes;
        if same {
            self.restore_background();
        } else {
            let floor_label = u16::try_from(1 + capsules.len() + boxes.len()).unwrap_or(u16::MAX);
            self.clear_with_floor(floor_z, floor_label);
            let mut label = first_box_label;
            for b in boxes {
                self.rasterize_box(b, label);
                label = label.wrapping_add(1);
            }
            let bg = &mut self.background;
            bg.zbuf.copy_from_slice(&self.zbuf);
            bg.labels.copy_from_slice(&self.labels);
            bg.pose = Some(self.pose);
            bg.floor_z = floor_z.map(f64::to_bits);
            bg.first_box_label = first_box_label;
            bg.boxes.clear();
            bg.boxes.extend_from_slice(boxes);
            bg.dirty.clear();
            bg.all_dirty = false;
            if bg.dirty.capacity() < capsules.len() {
                bg.dirty.reserve(capsules.len());
            }
        }
        let mut label = 1u16;
        for c in capsules {
            if let Some(rect) = self.rasterize_capsule(c, label) {
                let bg = &mut self.background;
                // never grows past its capacity (no allocation): beyond it
                // the next frame restores everything
                if bg.dirty.len() < bg.dirty.capacity() {
                    bg.dirty.push(rect);
                } else {
                    bg.all_dirty = true;
                }
            }
            label = label.wrapping_add(1);
        }
        Ok(())
    }

    /// Puts the background back where the last render's capsules drew.
    fn restore_background(&mut self) {
        let w = self.intrinsics.width as usize;
        let bg = &mut self.background;
        if bg.all_dirty {
            self.zbuf.copy_from_slice(&bg.zbuf);
            self.labels.copy_from_slice(&bg.labels);
        } else {
            for r in &bg.dirty {
                for v in r.v0..=r.v1 {
                    let span = v * w + r.u0..=v * w + r.u1;
                    self.zbuf[span.clone()].copy_from_slice(&bg.zbuf[span.clone()]);
                    self.labels[span.clone()].copy_from_slice(&bg.labels[span]);
                }
            }
        }
        bg.dirty.clear();
        bg.all_dirty = false;
    }

    /// Draws `capsule` into the z-buffer; the pixel rectangle it covered.
    fn rasterize_capsule(&mut self, capsule: &Capsule, label: u16) -> Option<PixelRect> {
        let rc = RayCapsule::new(capsule, &self.pose, 0.0);
        let rect = rc.pixel_rect(&self.intrinsics, NEAR_M)?;
        let draw = Draw {
            at: CapsulePixels::new(&rc, &rect, &self.xn, &self.yn),
            z_min: rc.depth_range().0,
            label,
            fx: self.intrinsics.fx,
            cx: self.intrinsics.cx,
        };
        draw_capsule(self.lanes, &draw, &mut self.zbuf, &mut self.labels);
        Some(rect)
    }

    fn rasterize_box(&mut self, aabb: &Aabb, label: u16) {
        let corners = aabb.corners().map(|c| self.pose.to_camera(&c).coords);
        let lo = corners
            .iter()
            .fold(Vector3::repeat(f64::INFINITY), |m, c| m.inf(c));
        let hi = corners
            .iter()
            .fold(Vector3::repeat(f64::NEG_INFINITY), |m, c| m.sup(c));
        let rect = if lo.z >= NEAR_M {
            // all corners in front: the image of the box is the hull of theirs
            let mut b = [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            for c in &corners {
                let pu = self.intrinsics.fx * c.x / c.z + self.intrinsics.cx;
                let pv = self.intrinsics.fy * c.y / c.z + self.intrinsics.cy;
                b = [b[0].min(pu), b[1].max(pu), b[2].min(pv), b[3].max(pv)];
            }
            PixelRect::from_bounds(&self.intrinsics, b[0], b[1], b[2], b[3])
        } else {
            camera_box_bounds(&self.intrinsics, &lo, &hi, NEAR_M)
                .and_then(|b| PixelRect::from_bounds(&self.intrinsics, b[0], b[1], b[2], b[3]))
        };
        let Some(rect) = rect else {
            return;
        };
        let origin = self.pose.position();
        let lo_rel = aabb.min - origin;
        let hi_rel = aabb.max - origin;
        let r = self.pose.rotation();
        let (c0, c1, c2) = (
            r.matrix().column(0).into_owned(),
            r.matrix().column(1).into_owned(),
            r.matrix().column(2).into_owned(),
        );
        let w = self.intrinsics.width as usize;
        for v in rect.v0..=rect.v1 {
            let y = self.yn[v];
            let row_dir = c1 * y + c2;
            for u in rect.u0..=rect.u1 {
                let i = v * w + u;
                // branch-free slab test; a zero direction component gives
                // infinite slab parameters (NaN for a ray exactly in a face
                // plane: `min`/`max` then keep the infinite one, a grazing miss)
                let dir = c0 * self.xn[u] + row_dir;
                let inv = Vector3::new(1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z);
                let t1 = lo_rel.component_mul(&inv);
                let t2 = hi_rel.component_mul(&inv);
                let t_in = max(max(min(t1.x, t2.x), min(t1.y, t2.y)), min(t1.z, t2.z));
                let t_out = min(min(max(t1.x, t2.x), max(t1.y, t2.y)), max(t1.z, t2.z));
                if !(t_in <= t_out) {
                    continue;
                }
                let t = if t_in > NEAR_M {
                    t_in
                } else if t_out > NEAR_M {
                    NEAR_M
                } else {
                    continue;
                };
                if t < self.zbuf[i] {
                    self.zbuf[i] = t;
                    self.labels[i] = label;
                }
            }
        }
    }

    /// Initialises the z-buffer with the floor plane `z = floor_z` (base
    /// frame) or, without a floor, with "no surface".
    fn clear_with_floor(&mut self, floor_z: Option<f64>, label: u16) {
        let Some(floor_z) = floor_z else {
            self.zbuf.fill(f64::INFINITY);
            self.labels.fill(LABEL_NONE);
            return;
        };
        let origin = self.pose.position();
        let m = *self.pose.rotation().matrix();
        // base-frame z component of the ray t (x, y, 1) is t (m20 x + m21 y + m22)
        let height = floor_z - origin.z;
        let w = self.intrinsics.width as usize;
        for (v, &y) in self.yn.iter().enumerate() {
            let row_dz = m[(2, 1)] * y + m[(2, 2)];
            let zrow = &mut self.zbuf[v * w..(v + 1) * w];
            let lrow = &mut self.labels[v * w..(v + 1) * w];
            for ((z, l), &x) in zrow.iter_mut().zip(lrow.iter_mut()).zip(&self.xn) {
                let t = height / (m[(2, 0)] * x + row_dz);
                // t is ±inf or NaN for rays parallel to the floor: rejected here
                let hit = t > NEAR_M && t.is_finite();
                *z = if hit { t } else { f64::INFINITY };
                *l = if hit { label } else { LABEL_NONE };
            }
        }
    }

    /// Turns the exact z-buffer into sensor readings.
    fn sense(&mut self, out: &mut [u16]) {
        let key = self.normals.frame_key();
        let s = Sense {
            options: self.options,
            table: self.normals.table(),
            key,
            width: self.intrinsics.width as usize,
            height: self.intrinsics.height as usize,
        };
        sense_frame(self.lanes, &s, &self.zbuf, out, &mut self.row);
    }
}

/// One capsule to draw over its pixel rectangle.
struct Draw<'a> {
    at: CapsulePixels<'a>,
    /// the capsule's nearest depth \[m\]: a pixel already nearer is kept
    z_min: f64,
    label: u16,
    /// the intrinsics' focal length and principal point along x \[px\]
    fx: f64,
    cx: f64,
}

by_lanes! {
    /// Draws one capsule into the z-buffer and the labels.
    fn draw_capsule(d: &Draw<'_>, zbuf: &mut [f64], labels: &mut [u16]) -> () = draw_any;
}

/// [`draw_capsule`] over each row's candidate columns ([`RayCapsule::columns`])
/// in runs of [`RUN`] pixels: a run that [`settle_run`] settles in lanes is
/// drawn from its depths; the others pixel by pixel ([`visible_entry`]).
#[inline(always)]
fn draw_any(d: &Draw<'_>, zbuf: &mut [f64], labels: &mut [u16]) {
    let p = &d.at;
    let cols = p.xn.len();
    for v in p.v0..=p.v1 {
        let y = p.yn[v];
        let span = p.rc.columns(y, d.fx, d.cx, p.u0, cols);
        let start = v * p.width + p.u0;
        let zrow = &mut zbuf[start..start + cols];
        let lrow = &mut labels[start..start + cols];
        for c in span.clone().step_by(RUN) {
            let n = RUN.min(span.end - c);
            let xs: [f64; RUN] = lanes::load(&p.xn[..span.end], c);
            let zs: [f64; RUN] = lanes::load(&zrow[..span.end], c);
            let mut t = [0.0f64; RUN];
            let mut drawn = [false; RUN];
            match settle_run(p.rc, &xs, &zs, n, y, d.z_min, &mut t, &mut drawn) {
                Run::Missed => continue,
                Run::Settled => {}
                Run::Scalar => {
                    for i in 0..n {
                        let e = (zs[i] > d.z_min).then(|| visible_entry(p.rc, xs[i], y));
                        (t[i], drawn[i]) = e.flatten().map_or((0.0, false), |e| (e, true));
                    }
                }
            }
            for i in 0..n {
                if drawn[i] & (t[i] < zs[i]) {
                    zrow[c + i] = t[i];
                    lrow[c + i] = d.label;
                }
            }
        }
    }
}

/// What [`settle_run`] made of a run of pixels.
enum Run {
    /// every ray is hidden or misses the capsule
    Missed,
    /// per ray, the depth it enters the capsule at and whether it is drawn
    /// there (in front of the near plane, not hidden behind the capsule's
    /// nearest depth; not yet compared with the z-buffer), written out
    Settled,
    /// some ray runs along the axis or enters behind the near plane: the
    /// scalar rule ([`visible_entry`])
    Scalar,
}

/// The first `n` rays `t (xs[i], y, 1)` of a run, over the depths `zs`
/// already drawn, in lanes: settled when every ray is hidden behind
/// `z_min` (the capsule's nearest depth), misses the capsule or enters it
/// in front of the near plane through its cylinder (most of its image) or,
/// in a second pass, an end sphere. Settled, each ray's depth and whether
/// it is drawn there go to `t` and `hit`.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // a run's inputs and its two outputs, in lanes
fn settle_run(
    rc: &RayCapsule,
    xs: &[f64; RUN],
    zs: &[f64; RUN],
    n: usize,
    y: f64,
    z_min: f64,
    t: &mut [f64; RUN],
    hit: &mut [bool; RUN],
) -> Run {
    let mut open = [false; RUN];
    // per lane: decided by the first pass (`open`: beyond an end, not yet)
    let mut done = [false; RUN];
    let mut missed = true;
    for i in 0..RUN {
        let e = rc.cylinder_entry(xs[i], y);
        let hidden = (i >= n) | (zs[i] <= z_min);
        t[i] = e.t;
        hit[i] = !hidden & e.hit;
        open[i] = !hidden & e.beyond_end;
        done[i] = hidden | e.miss | (e.hit & (e.t > NEAR_M));
        missed &= hidden | e.miss;
    }
    if missed {
        return Run::Missed;
    }
    if !done.iter().all(|&d| d) && open.iter().any(|&o| o) {
        for i in 0..RUN {
            let e = rc.end_entry(xs[i], y, t[i]);
            done[i] |= open[i] & (e.miss | (e.hit & (e.t > NEAR_M)));
            t[i] = if open[i] { e.t } else { t[i] };
            hit[i] |= open[i] & e.hit;
        }
    }
    match done.iter().all(|&d| d) {
        true => Run::Settled,
        false => Run::Scalar,
    }
}

/// The depth at which the ray `t (x, y, 1)` shows the capsule `rc`: its
/// entry, or the near plane where the capsule reaches behind it (and on
/// past it); `None` when the ray misses or the capsule lies wholly behind
/// the near plane along it.
#[inline(always)]
fn visible_entry(rc: &RayCapsule, x: f64, y: f64) -> Option<f64> {
    let t = rc.entry(x, y)?;
    if t > NEAR_M {
        return Some(t);
    }
    // the capsule reaches behind the near plane: blocks the view
    match rc.interval(x, y) {
        Some((_, t_out)) if t_out > NEAR_M => Some(NEAR_M),
        _ => None,
    }
}

/// The sensor model of one frame ([`Renderer`]'s `sense`).
struct Sense<'a> {
    options: RenderOptions,
    /// the normal quantiles the noise draws from
    table: &'a [f32; TABLE_SIZE],
    /// this frame's key of [`pixel_bits`]
    key: u32,
    width: usize,
    height: usize,
}

/// One pixel's reading \[mm\] (0: none) of exact depth `z` \[m\] with the
/// exact depths `near` of its four neighbours (left, right, up, down; a
/// missing one is `z` itself) and the random `bits` of [`pixel_bits`]: range limits, a drop-out with
/// probability `edge_dropout` where a neighbour jumps by more than
/// `edge_jump_m + edge_jump_sigmas σ_z`, axial noise `σ_z(z) N(0, 1)`,
/// rounded half up to the millimetre.
#[cfg(test)]
fn sensed(s: &Sense<'_>, z: f64, near: [f64; 4], bits: u32) -> u16 {
    sensed_with(s, z, near, bits, noise_of(s, bits))
}

/// The standard normal draw of `bits` (0 without noise).
#[inline(always)]
fn noise_of(s: &Sense<'_>, bits: u32) -> f64 {
    if s.options.noise {
        f64::from(s.table[normal_index(bits)])
    } else {
        0.0
    }
}

/// One pixel's reading (the rule of `sensed`) with the normal draw `noise` of `bits` already looked up.
/// Branch-free: it vectorises (the table's lookup, a gather, does not).
#[inline(always)]
fn sensed_with(s: &Sense<'_>, z: f64, near: [f64; 4], bits: u32, noise: f64) -> u16 {
    let o = &s.options;
    let valid = (z >= o.min_range_m) & (z <= o.max_range_m);
    let sigma = sigma_z(z);
    let jump = o.edge_jump_m + o.edge_jump_sigmas * sigma;
    // a neighbour without surface (infinite) is a discontinuity
    let largest = near.iter().fold(0.0f64, |m, &n| m.max((n - z).abs()));
    let dropped = (largest > jump) & draws(bits, o.edge_dropout);
    // round half up (positive values: truncation after + 0.5); the integer
    // read from the bits of `2^52 +` it, which converts in lanes (a cast
    // went element by element)
    let mm = ((z + sigma * noise) * 1000.0 + 0.5)
        .clamp(1.0, 65535.0)
        .floor();
    let mm = (mm + 4_503_599_627_370_496.0).to_bits() as u16;
    if valid & !dropped {
        mm
    } else {
        0
    }
}

by_lanes! {
    /// The sensor model over the whole frame: `zbuf` exact depths \[m\]
    /// into `out` \[mm\]; `row` is scratch of the frame's width.
    fn sense_frame(s: &Sense<'_>, zbuf: &[f64], out: &mut [u16], row: &mut SenseRow) -> () = sense_any;
}

/// Row by row, in three passes: the random bits (a hash, in lanes), their
/// normal draws (a table lookup, element by element), then the sensor
/// model of the row's inner pixels over plain slices (in lanes), and its
/// two end pixels with their neighbours clamped into the row.
#[inline(always)]
fn sense_any(s: &Sense<'_>, zbuf: &[f64], out: &mut [u16], scratch: &mut SenseRow) {
    let (w, h) = (s.width, s.height);
    if w == 0 {
        return;
    }
    let bits = &mut scratch.bits[..w];
    let noise = &mut scratch.noise[..w];
    for v in 0..h {
        let row = &zbuf[v * w..(v + 1) * w];
        // a missing neighbour row is replaced by the row itself: no jump
        let up = if v > 0 {
            &zbuf[(v - 1) * w..v * w]
        } else {
            row
        };
        let down = if v + 1 < h {
            &zbuf[(v + 1) * w..(v + 2) * w]
        } else {
            row
        };
        let out_row = &mut out[v * w..(v + 1) * w];
        let first = (v * w) as u32;
        for (u, b) in bits.iter_mut().enumerate() {
            *b = pixel_bits(s.key, first + u as u32);
        }
        for (n, &b) in noise.iter_mut().zip(bits.iter()) {
            *n = noise_of(s, b);
        }
        if w >= 3 {
            let n = w - 2;
            let (z, left, right) = (&row[1..w - 1], &row[..n], &row[2..]);
            let (a, b) = (&up[1..w - 1], &down[1..w - 1]);
            let (bi, no, o) = (&bits[1..w - 1], &noise[1..w - 1], &mut out_row[1..w - 1]);
            for i in 0..n {
                let near = [left[i], right[i], a[i], b[i]];
                o[i] = sensed_with(s, z[i], near, bi[i], no[i]);
            }
        }
        for u in [0, w - 1] {
            let near = [
                row[u.saturating_sub(1)],
                row[(u + 1).min(w - 1)],
                up[u],
                down[u],
            ];
            out_row[u] = sensed_with(s, row[u], near, bits[u], noise[u]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every compilation of the capsule pass draws as the rule written out
    /// pixel by pixel ([`RayCapsule::entry`], the near plane), for capsules
    /// of every orientation, seen end on, reaching behind the near plane
    /// or behind the camera, over a z-buffer that already holds surfaces.
    #[test]
    fn every_vector_width_draws_capsules_as_the_rule() {
        let k = Intrinsics::default();
        let pose = CameraPose::paper_default();
        let (w, h) = (k.width as usize, k.height as usize);
        let (xn, yn) = (k.column_factors(), k.row_factors());
        let mut lcg = crate::lanes::test_sequence(3);
        let mut uniform =
            move |lo: f64, hi: f64| lo + (hi - lo) * ((lcg() >> 11) as f64 / (1u64 << 53) as f64);
        let eye = pose.position();
        let (mut drawn, mut checked) = (0usize, 0usize);
        for case in 0..60 {
            let a =
                nalgebra::Point3::new(uniform(-1.0, 1.5), uniform(-1.2, 1.2), uniform(0.0, 1.8));
            let b = match case % 6 {
                // end on: the axis through the camera
                0 => a + (a - eye).normalize() * uniform(0.1, 0.5),
                // reaching the camera
                1 => eye + (a - eye) * 0.02,
                _ => a + Vector3::new(uniform(-0.6, 0.6), uniform(-0.6, 0.6), uniform(-0.6, 0.6)),
            };
            let capsule = Capsule::new(a, b, uniform(0.01, 0.2));
            let rc = RayCapsule::new(&capsule, &pose, 0.0);
            let Some(rect) = rc.pixel_rect(&k, NEAR_M) else {
                continue;
            };
            let z0: Vec<f64> = (0..w * h)
                .map(|i| match i % 7 {
                    0 => 0.8 + (i % 13) as f64 * 0.1,
                    1 => -1.0,
                    _ => f64::INFINITY,
                })
                .collect();
            let (z_min, _) = rc.depth_range();
            let mut rule = z0.clone();
            let mut rule_labels = vec![0u16; w * h];
            for v in rect.v0..=rect.v1 {
                for u in rect.u0..=rect.u1 {
                    let i = v * w + u;
                    if rule[i] <= z_min {
                        continue;
                    }
                    let t = match rc.entry(xn[u], yn[v]) {
                        Some(t) if t > NEAR_M => t,
                        Some(_) => match rc.interval(xn[u], yn[v]) {
                            Some((_, t_out)) if t_out > NEAR_M => NEAR_M,
                            _ => continue,
                        },
                        None => continue,
                    };
                    if t < rule[i] {
                        rule[i] = t;
                        rule_labels[i] = 9;
                        drawn += 1;
                    }
                }
            }
            let draw = Draw {
                at: CapsulePixels::new(&rc, &rect, &xn, &yn),
                z_min,
                label: 9,
                fx: k.fx,
                cx: k.cx,
            };
            for lanes in Lanes::available() {
                let mut z = z0.clone();
                let mut labels = vec![0u16; w * h];
                draw_capsule(lanes, &draw, &mut z, &mut labels);
                for i in 0..w * h {
                    assert!(
                        z[i].to_bits() == rule[i].to_bits() && labels[i] == rule_labels[i],
                        "case {case}, {lanes:?}, pixel {i}: {} against {}",
                        z[i],
                        rule[i]
                    );
                }
                checked += 1;
            }
        }
        assert!(
            drawn > 100_000 && checked > 50,
            "{drawn} drawn, {checked} checked"
        );
    }

    /// Every compilation of the sensor pass reads as the rule written out
    /// pixel by pixel (side neighbours clamped into the row, rows into the
    /// frame), on a frame with steps, holes, out-of-range depths and
    /// borders, with and without noise.
    #[test]
    fn every_vector_width_senses_as_the_rule() {
        let (w, h) = (77usize, 13usize);
        let mut lcg = crate::lanes::test_sequence(99);
        let mut next = move || (lcg() >> 33) as u32;
        let zbuf: Vec<f64> = (0..w * h)
            .map(|i| match next() % 12 {
                0 => f64::INFINITY,
                1 => 0.3,
                2 => 5.0,
                3 => 0.5 + f64::from(next() % 4000) * 1e-3,
                _ => 1.2 + (i % w) as f64 * 1e-3 + if (i / w) % 5 == 0 { 0.2 } else { 0.0 },
            })
            .collect();
        let normals = NormalSource::new(5);
        for options in [RenderOptions::default(), RenderOptions::ideal()] {
            let s = Sense {
                options,
                table: normals.table(),
                key: 0xdead_beef,
                width: w,
                height: h,
            };
            let mut rule = vec![0u16; w * h];
            for v in 0..h {
                for u in 0..w {
                    let at = |uu: usize, vv: usize| zbuf[vv * w + uu];
                    let near = [
                        at(u.saturating_sub(1), v),
                        at((u + 1).min(w - 1), v),
                        at(u, v.saturating_sub(1)),
                        at(u, (v + 1).min(h - 1)),
                    ];
                    let bits = pixel_bits(s.key, (v * w + u) as u32);
                    rule[v * w + u] = sensed(&s, zbuf[v * w + u], near, bits);
                }
            }
            let read = rule.iter().filter(|&&r| r != 0).count();
            assert!(read > w * h / 4 && read < w * h, "{read}");
            for lanes in Lanes::available() {
                let mut out = vec![7u16; w * h];
                let mut row = SenseRow {
                    bits: vec![0; w],
                    noise: vec![0.0; w],
                };
                sense_frame(lanes, &s, &zbuf, &mut out, &mut row);
                assert_eq!(out, rule, "{lanes:?}");
            }
        }
    }
}
