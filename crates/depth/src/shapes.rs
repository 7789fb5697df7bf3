//! Scene primitives (capsules, axis-aligned boxes) and their exact
//! intersection with camera rays.
//!
//! A camera ray through a pixel is `t · (x_n, y_n, 1)` in the camera frame, with
//! `x_n = (p_x − c_x)/f_x`, `y_n = (p_y − c_y)/f_y`; because the direction's z
//! component is 1, the ray parameter `t` *is* the depth of the point it reaches.

use std::ops::Range;

use nalgebra::{Point3, Vector3};

use crate::camera::{CameraPose, Intrinsics};

/// A capsule: every point within `radius` of the segment `a`–`b`.
/// Endpoints in the base frame \[m\], radius \[m\]. `a == b` is a sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// first axis endpoint, base frame \[m\]
    pub a: Point3<f64>,
    /// second axis endpoint, base frame \[m\]
    pub b: Point3<f64>,
    /// radius \[m\], ≥ 0
    pub radius: f64,
}

impl Capsule {
    /// A capsule around the segment `a`–`b` (base frame, metres).
    pub fn new(a: Point3<f64>, b: Point3<f64>, radius: f64) -> Self {
        Self { a, b, radius }
    }

    /// A sphere of `radius` \[m\] around `center` (base frame).
    pub fn sphere(center: Point3<f64>, radius: f64) -> Self {
        Self {
            a: center,
            b: center,
            radius,
        }
    }

    /// The same capsule with its radius grown by `margin` \[m\].
    pub fn inflated(&self, margin: f64) -> Self {
        Self {
            radius: self.radius + margin,
            ..*self
        }
    }

    /// `true` if the endpoints are finite and the radius finite and ≥ 0.
    pub fn is_valid(&self) -> bool {
        self.a.iter().chain(self.b.iter()).all(|c| c.is_finite())
            && self.radius.is_finite()
            && self.radius >= 0.0
    }

    /// The point of the axis segment closest to `p`.
    pub fn closest_axis_point(&self, p: &Point3<f64>) -> Point3<f64> {
        let ab = self.b - self.a;
        let len2 = ab.norm_squared();
        if len2 <= 0.0 {
            return self.a;
        }
        let s = ((p - self.a).dot(&ab) / len2).clamp(0.0, 1.0);
        self.a + ab * s
    }

    /// Signed distance \[m\] from `p` to the capsule surface (negative inside).
    pub fn distance_to_point(&self, p: &Point3<f64>) -> f64 {
        (p - self.closest_axis_point(p)).norm() - self.radius
    }
}

/// An axis-aligned box in the base frame \[m\] (a table, a shelf, a wall).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// smallest corner, base frame \[m\]
    pub min: Point3<f64>,
    /// largest corner, base frame \[m\]
    pub max: Point3<f64>,
}

impl Aabb {
    /// The box between two opposite corners (in any order), base frame \[m\].
    pub fn new(corner1: Point3<f64>, corner2: Point3<f64>) -> Self {
        Self {
            min: corner1.inf(&corner2),
            max: corner1.sup(&corner2),
        }
    }

    /// `true` if the corners are finite and `min <= max` on every axis.
    pub fn is_valid(&self) -> bool {
        self.min
            .iter()
            .chain(self.max.iter())
            .all(|c| c.is_finite())
            && (0..3).all(|i| self.min[i] <= self.max[i])
    }

    /// The 8 corners.
    pub fn corners(&self) -> [Point3<f64>; 8] {
        let (l, h) = (self.min, self.max);
        [
            Point3::new(l.x, l.y, l.z),
            Point3::new(h.x, l.y, l.z),
            Point3::new(l.x, h.y, l.z),
            Point3::new(h.x, h.y, l.z),
            Point3::new(l.x, l.y, h.z),
            Point3::new(h.x, l.y, h.z),
            Point3::new(l.x, h.y, h.z),
            Point3::new(h.x, h.y, h.z),
        ]
    }

    /// Entry and exit parameters `[t_in, t_out]` of the line `o + t d` through the
    /// box (slab method), or `None` if it misses. `t` may be negative.
    pub fn ray_interval(&self, o: &Point3<f64>, d: &Vector3<f64>) -> Option<(f64, f64)> {
        let mut t_in = f64::NEG_INFINITY;
        let mut t_out = f64::INFINITY;
        for i in 0..3 {
            if d[i] == 0.0 {
                if o[i] < self.min[i] || o[i] > self.max[i] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d[i];
            let t1 = (self.min[i] - o[i]) * inv;
            let t2 = (self.max[i] - o[i]) * inv;
            let (lo, hi) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
            t_in = t_in.max(lo);
            t_out = t_out.min(hi);
            if t_in > t_out {
                return None;
            }
        }
        Some((t_in, t_out))
    }
}

/// An inclusive rectangle of pixels: columns `u0..=u1`, rows `v0..=v1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PixelRect {
    pub u0: usize,
    pub u1: usize,
    pub v0: usize,
    pub v1: usize,
}

impl PixelRect {
    /// The pixels whose centres lie in `[pu_min, pu_max] × [pv_min, pv_max]`
    /// (pixel coordinates), clamped to the image; `None` if none does.
    pub fn from_bounds(
        intrinsics: &Intrinsics,
        pu_min: f64,
        pu_max: f64,
        pv_min: f64,
        pv_max: f64,
    ) -> Option<Self> {
        let w = f64::from(intrinsics.width - 1);
        let h = f64::from(intrinsics.height - 1);
        // NaN bounds fail these comparisons and give None
        if !(pu_max >= 0.0 && pu_min <= w && pv_max >= 0.0 && pv_min <= h) {
            return None;
        }
        let u0 = pu_min.ceil().clamp(0.0, w);
        let u1 = pu_max.floor().clamp(0.0, w);
        let v0 = pv_min.ceil().clamp(0.0, h);
        let v1 = pv_max.floor().clamp(0.0, h);
        if u0 > u1 || v0 > v1 {
            return None;
        }
        Some(Self {
            u0: u0 as usize,
            u1: u1 as usize,
            v0: v0 as usize,
            v1: v1 as usize,
        })
    }
}

/// Pixel-coordinate bounds `[pu_min, pu_max, pv_min, pv_max]` (not clamped to
/// the image) of every point of the camera-frame box `[lo, hi]` with depth ≥
/// `near` (> 0); `None` if the box lies entirely nearer than `near`. Exact
/// bounds of `x/z`, `y/z` over the clipped box, reached at its corners.
pub(crate) fn camera_box_bounds(
    intrinsics: &Intrinsics,
    lo: &Vector3<f64>,
    hi: &Vector3<f64>,
    near: f64,
) -> Option<[f64; 4]> {
    if hi.z < near {
        return None;
    }
    let z_lo = lo.z.max(near);
    let z_hi = hi.z;
    let x_min = (lo.x / z_lo).min(lo.x / z_hi);
    let x_max = (hi.x / z_lo).max(hi.x / z_hi);
    let y_min = (lo.y / z_lo).min(lo.y / z_hi);
    let y_max = (hi.y / z_lo).max(hi.y / z_hi);
    Some([
        intrinsics.fx * x_min + intrinsics.cx,
        intrinsics.fx * x_max + intrinsics.cx,
        intrinsics.fy * y_min + intrinsics.cy,
        intrinsics.fy * y_max + intrinsics.cy,
    ])
}

/// Pixels that may see any point of the camera-frame box `[lo, hi]` with depth
/// ≥ `near` (> 0), clamped to the image.
pub(crate) fn camera_box_rect(
    intrinsics: &Intrinsics,
    lo: &Vector3<f64>,
    hi: &Vector3<f64>,
    near: f64,
) -> Option<PixelRect> {
    let [u0, u1, v0, v1] = camera_box_bounds(intrinsics, lo, hi, near)?;
    PixelRect::from_bounds(intrinsics, u0, u1, v0, v1)
}

/// A capsule over its pixel rectangle in a frame `width` pixels wide: rows
/// `v0..=v1`, columns from `u0` on, as many as `xn` (their ray factors
/// `(u − c_x)/f_x`); `yn` every row's factor. What a per-pixel pass over
/// one capsule reads.
pub(crate) struct CapsulePixels<'a> {
    pub rc: &'a RayCapsule,
    pub xn: &'a [f64],
    pub yn: &'a [f64],
    pub width: usize,
    pub u0: usize,
    pub v0: usize,
    pub v1: usize,
}

impl<'a> CapsulePixels<'a> {
    /// `rc` over `rect` of a frame whose columns' and rows' ray factors are
    /// `xn` and `yn` (the whole frame's).
    pub fn new(rc: &'a RayCapsule, rect: &PixelRect, xn: &'a [f64], yn: &'a [f64]) -> Self {
        CapsulePixels {
            rc,
            xn: &xn[rect.u0..=rect.u1],
            yn,
            width: xn.len(),
            u0: rect.u0,
            v0: rect.v0,
            v1: rect.v1,
        }
    }
}

/// A ray's entry into a capsule as [`RayCapsule::cylinder_entry`] and
/// [`RayCapsule::end_entry`] find it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    /// depth of the entry \[m\] (when `hit`)
    pub t: f64,
    /// the ray enters the capsule at `t`
    pub hit: bool,
    /// the ray misses the capsule
    pub miss: bool,
    /// the ray meets the infinite cylinder beyond an end of the capsule
    /// ([`RayCapsule::end_entry`] tells)
    pub beyond_end: bool,
}

/// A capsule in the camera frame, prepared for rays through the optical centre.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RayCapsule {
    a: Vector3<f64>,
    b: Vector3<f64>,
    r: f64,
    ba: Vector3<f64>,
    /// `‖b − a‖²`
    k: f64,
    /// `a · (b − a)`
    aba: f64,
    /// constant term of the infinite-cylinder quadratic: `k a·a − aba² − r² k`
    cyl_c: f64,
    /// `a·a − r²`, `b·b − r²`
    sa_c: f64,
    sb_c: f64,
}

/// Roots of `q t² − 2 m t + c = 0` (the ray–sphere form) as `(t0, t1)`, t0 ≤ t1.
#[inline(always)]
fn sphere_roots(q: f64, m: f64, c: f64) -> Option<(f64, f64)> {
    let disc = m * m - q * c;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    Some(((m - s) / q, (m + s) / q))
}

/// [`sphere_roots`] without branches, its interval joined to `[lo, hi]`.
#[inline(always)]
fn sphere_lanes(q: f64, m: f64, c: f64, lo: &mut f64, hi: &mut f64) {
    let disc = m * m - q * c;
    let s = disc.sqrt();
    let hit = !(disc < 0.0);
    *lo = if hit { lo.min((m - s) / q) } else { *lo };
    *hi = if hit { hi.max((m + s) / q) } else { *hi };
}

impl RayCapsule {
    /// `capsule` (base frame) seen from `pose`, radius grown by `margin` \[m\].
    pub fn new(capsule: &Capsule, pose: &CameraPose, margin: f64) -> Self {
        let a = pose.to_camera(&capsule.a).coords;
        let b = pose.to_camera(&capsule.b).coords;
        let r = capsule.radius + margin;
        let ba = b - a;
        let k = ba.norm_squared();
        let aba = a.dot(&ba);
        let r2 = r * r;
        Self {
            a,
            b,
            r,
            ba,
            k,
            aba,
            cyl_c: k * a.norm_squared() - aba * aba - r2 * k,
            sa_c: a.norm_squared() - r2,
            sb_c: b.norm_squared() - r2,
        }
    }

    /// Smallest and largest camera-frame depth of the capsule \[m\].
    pub fn depth_range(&self) -> (f64, f64) {
        (
            self.a.z.min(self.b.z) - self.r,
            self.a.z.max(self.b.z) + self.r,
        )
    }

    /// Pixels whose rays may hit the capsule in front of `near` \[m\] (> 0).
    pub fn pixel_rect(&self, intrinsics: &Intrinsics, near: f64) -> Option<PixelRect> {
        let rv = Vector3::repeat(self.r);
        let (a_lo, a_hi) = (self.a - rv, self.a + rv);
        let (b_lo, b_hi) = (self.b - rv, self.b + rv);
        if a_lo.z >= near && b_lo.z >= near {
            // both end spheres in front: the capsule lies in the convex hull of
            // the two end boxes, and a point of that hull projects between the
            // projections of the two box points it combines
            let [a0, a1, a2, a3] = camera_box_bounds(intrinsics, &a_lo, &a_hi, near)?;
            let [b0, b1, b2, b3] = camera_box_bounds(intrinsics, &b_lo, &b_hi, near)?;
            PixelRect::from_bounds(intrinsics, a0.min(b0), a1.max(b1), a2.min(b2), a3.max(b3))
        } else {
            // partly behind the near plane: bound the whole capsule by one box
            camera_box_rect(intrinsics, &a_lo.inf(&b_lo), &a_hi.sup(&b_hi), near)
        }
    }

    #[inline(always)]
    fn sphere_a(&self, q: f64, x: f64, y: f64) -> Option<(f64, f64)> {
        sphere_roots(q, self.a.x * x + self.a.y * y + self.a.z, self.sa_c)
    }

    #[inline(always)]
    fn sphere_b(&self, q: f64, x: f64, y: f64) -> Option<(f64, f64)> {
        sphere_roots(q, self.b.x * x + self.b.y * y + self.b.z, self.sb_c)
    }

    /// The ray factors `x` of the row `y` whose rays `t (x, y, 1)` may enter
    /// the capsule, as `[lo, hi]`: outside it [`RayCapsule::entry`] is `None`
    /// (the ray misses the infinite cylinder). `(−∞, ∞)` when the row is not
    /// bounded this way (a sphere, a camera inside the cylinder, a row
    /// whose misses are not one interval's complement); `lo > hi` when
    /// every ray of the row misses. Along a row, the cylinder's
    /// discriminant of [`RayCapsule::entry`] is a quadratic in `x`; its
    /// roots are exact but for rounding (the caller widens the interval).
    pub fn row_candidates(&self, y: f64) -> (f64, f64) {
        const ALL: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);
        if !(self.k > 0.0 && self.cyl_c > 0.0) {
            return ALL;
        }
        // bard = p1 x + p0, ard = r1 x + r0, half_b = m1 x + m0,
        // qa = k q − bard² = e2 x² + e1 x + e0 with q = x² + y² + 1
        let (p1, p0) = (self.ba.x, self.ba.y * y + self.ba.z);
        let (r1, r0) = (self.a.x, self.a.y * y + self.a.z);
        let (m1, m0) = (-self.k * r1 + self.aba * p1, -self.k * r0 + self.aba * p0);
        let (e2, e1, e0) = (
            self.k - p1 * p1,
            -2.0 * p1 * p0,
            self.k * (y * y + 1.0) - p0 * p0,
        );
        // h = half_b² − qa cyl_c = a x² + b x + c
        let a = m1 * m1 - self.cyl_c * e2;
        let b = 2.0 * m1 * m0 - self.cyl_c * e1;
        let c = m0 * m0 - self.cyl_c * e0;
        if !(a < 0.0) {
            return ALL;
        }
        let disc = b * b - 4.0 * a * c;
        if disc < -1e-9 * (b * b + (4.0 * a * c).abs()) {
            return (f64::INFINITY, f64::NEG_INFINITY);
        }
        // a < 0: h ≥ 0 between the roots (the stable pair of formulas)
        let s = disc.max(0.0).sqrt();
        let q = -0.5 * (b + s.copysign(b));
        let (x1, x2) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
        (x1.min(x2), x1.max(x2))
    }

    /// The columns of row `y` whose rays may enter the capsule, as offsets
    /// into the `cols` columns from `u0` on ([`RayCapsule::row_candidates`],
    /// widened by two pixels for rounding; `fx`, `cx` the intrinsics'
    /// focal length and principal point along x \[px\]); empty when none may.
    pub fn columns(&self, y: f64, fx: f64, cx: f64, u0: usize, cols: usize) -> Range<usize> {
        let (lo, hi) = self.row_candidates(y);
        if lo > hi {
            return 0..0;
        }
        let n = cols as f64;
        let first = (lo * fx + cx).floor() - 2.0 - u0 as f64;
        let last = (hi * fx + cx).ceil() + 2.0 - u0 as f64;
        // ±∞ clamp to the columns; NaN never arises from finite roots
        let start = first.clamp(0.0, n) as usize;
        let end = (last + 1.0).clamp(0.0, n) as usize;
        start..end.max(start)
    }

    /// [`RayCapsule::entry`]'s first step for the ray `t (x, y, 1)`, of the
    /// same arithmetic without branches, so that a run of pixels
    /// vectorises: its entry `t` into the infinite cylinder; `hit` when
    /// that is the capsule's entry (`entry` is `Some(t)`), `miss` when the
    /// ray misses the cylinder (`entry` is `None`), `beyond_end` when it
    /// meets the cylinder beyond an end ([`RayCapsule::end_entry`] tells);
    /// none of them: the ray runs along the axis, or the capsule is a
    /// sphere (`entry` tells).
    #[inline(always)]
    pub fn cylinder_entry(&self, x: f64, y: f64) -> Entry {
        let q = x * x + y * y + 1.0;
        let bard = self.ba.x * x + self.ba.y * y + self.ba.z;
        let ard = self.a.x * x + self.a.y * y + self.a.z;
        let qa = self.k * q - bard * bard;
        let slanted = (self.k > 0.0) & (qa > 1e-12 * self.k * q);
        let half_b = -self.k * ard + bard * self.aba;
        let h = half_b * half_b - qa * self.cyl_c;
        let t = (-half_b - h.sqrt()) / qa;
        let s = t * bard - self.aba;
        let meets = slanted & (h >= 0.0);
        let body = (s >= 0.0) & (s <= self.k);
        Entry {
            t,
            hit: meets & body,
            miss: slanted & (h < 0.0),
            beyond_end: meets & !body,
        }
    }

    /// [`RayCapsule::entry`]'s second step, without branches: for a slanted
    /// ray that meets the infinite cylinder beyond an end (`beyond_end` of
    /// [`RayCapsule::cylinder_entry`], whose `t` is `cylinder_t`), its
    /// entry into that end's sphere, or a miss.
    #[inline(always)]
    pub fn end_entry(&self, x: f64, y: f64, cylinder_t: f64) -> Entry {
        let q = x * x + y * y + 1.0;
        let bard = self.ba.x * x + self.ba.y * y + self.ba.z;
        let s = cylinder_t * bard - self.aba;
        let before = s < 0.0;
        let ma = self.a.x * x + self.a.y * y + self.a.z;
        let mb = self.b.x * x + self.b.y * y + self.b.z;
        let m = if before { ma } else { mb };
        let c = if before { self.sa_c } else { self.sb_c };
        let disc = m * m - q * c;
        let hit = !(disc < 0.0);
        Entry {
            t: (m - disc.sqrt()) / q,
            hit,
            miss: !hit,
            beyond_end: false,
        }
    }

    /// Depth where the ray `t (x, y, 1)` enters the capsule (may be ≤ 0 when
    /// the capsule reaches behind the camera), or `None` if it misses.
    /// Branching: a missed ray costs no square root (the renderer's scalar
    /// rule; [`RayCapsule::cylinder_entry`] and [`RayCapsule::end_entry`]
    /// are its branch-free steps, of the same arithmetic, checked bit for
    /// bit against it by the renderer's tests).
    #[inline(always)]
    pub fn entry(&self, x: f64, y: f64) -> Option<f64> {
        let q = x * x + y * y + 1.0;
        if self.k > 0.0 {
            let bard = self.ba.x * x + self.ba.y * y + self.ba.z;
            let ard = self.a.x * x + self.a.y * y + self.a.z;
            let qa = self.k * q - bard * bard;
            if qa > 1e-12 * self.k * q {
                let half_b = -self.k * ard + bard * self.aba;
                let h = half_b * half_b - qa * self.cyl_c;
                if h < 0.0 {
                    // misses the infinite cylinder, which holds the capsule
                    return None;
                }
                let t = (-half_b - h.sqrt()) / qa;
                let s = t * bard - self.aba;
                if s >= 0.0 && s <= self.k {
                    return Some(t);
                }
                // the ray enters the infinite cylinder beyond an end: the
                // capsule's first point is on that end's sphere (or none)
                let roots = if s < 0.0 {
                    self.sphere_a(q, x, y)
                } else {
                    self.sphere_b(q, x, y)
                };
                return roots.map(|(t0, _)| t0);
            }
            if self.cyl_c > 0.0 {
                // parallel to the axis and outside the infinite cylinder
                return None;
            }
            // parallel to the axis inside the cylinder: the nearer end sphere
            return match (self.sphere_a(q, x, y), self.sphere_b(q, x, y)) {
                (Some((ta, _)), Some((tb, _))) => Some(ta.min(tb)),
                (Some((ta, _)), None) => Some(ta),
                (None, Some((tb, _))) => Some(tb),
                (None, None) => None,
            };
        }
        self.sphere_a(q, x, y).map(|(t0, _)| t0)
    }

    /// [`RayCapsule::interval`] written without branches, so that a run of
    /// pixels vectorises: `(t_in, t_out)` of the same arithmetic when the ray
    /// hits, `t_in > t_out` (or NaN) when it misses.
    #[inline(always)]
    pub fn interval_lanes(&self, x: f64, y: f64) -> (f64, f64) {
        let q = x * x + y * y + 1.0;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let ma = self.a.x * x + self.a.y * y + self.a.z;
        sphere_lanes(q, ma, self.sa_c, &mut lo, &mut hi);
        // a sphere (k = 0) has no second end and no cylinder: both are
        // computed all the same and left out by a select, not a branch (the
        // branch kept a run of pixels from vectorising)
        let capsule = self.k > 0.0;
        let mb = self.b.x * x + self.b.y * y + self.b.z;
        let (mut lo_b, mut hi_b) = (lo, hi);
        sphere_lanes(q, mb, self.sb_c, &mut lo_b, &mut hi_b);
        // the finite cylinder: the infinite one within the slab
        let bard = self.ba.x * x + self.ba.y * y + self.ba.z;
        let ard = self.a.x * x + self.a.y * y + self.a.z;
        let qa = self.k * q - bard * bard;
        let slanted = qa > 1e-12 * self.k * q;
        let half_b = -self.k * ard + bard * self.aba;
        let h = half_b * half_b - qa * self.cyl_c;
        let sh = h.sqrt();
        let (c0, c1) = if slanted {
            ((-half_b - sh) / qa, (-half_b + sh) / qa)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        };
        let cyl = if slanted {
            !(h < 0.0)
        } else {
            self.cyl_c <= 0.0
        };
        // slab 0 ≤ (t rd − a)·(b − a) ≤ k
        let crossing = bard.abs() > 1e-300;
        let t0 = self.aba / bard;
        let t1 = (self.k + self.aba) / bard;
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        let (s0, s1) = if crossing {
            (near, far)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        };
        let slab = crossing | ((-self.aba >= 0.0) & (-self.aba <= self.k));
        let l = c0.max(s0);
        let u = c1.min(s1);
        let hit = capsule & cyl & slab & (l <= u);
        lo = if capsule { lo_b } else { lo };
        hi = if capsule { hi_b } else { hi };
        lo = if hit { lo.min(l) } else { lo };
        hi = if hit { hi.max(u) } else { hi };
        (lo, hi)
    }

    /// Entry and exit depths `[t_in, t_out]` of the ray `t (x, y, 1)` through the
    /// capsule (it is convex, so the union of the pieces' intervals is one
    /// interval), or `None` if it misses.
    #[inline]
    pub fn interval(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let q = x * x + y * y + 1.0;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut add = |iv: Option<(f64, f64)>| {
            if let Some((t0, t1)) = iv {
                lo = lo.min(t0);
                hi = hi.max(t1);
            }
        };
        add(self.sphere_a(q, x, y));
        if self.k > 0.0 {
            add(self.sphere_b(q, x, y));
            add(self.cylinder_interval(q, x, y));
        }
        if lo <= hi {
            Some((lo, hi))
        } else {
            None
        }
    }

    /// Interval of the ray inside the finite cylinder (the capsule minus its caps).
    #[inline(always)]
    fn cylinder_interval(&self, q: f64, x: f64, y: f64) -> Option<(f64, f64)> {
        let bard = self.ba.x * x + self.ba.y * y + self.ba.z;
        let ard = self.a.x * x + self.a.y * y + self.a.z;
        let qa = self.k * q - bard * bard;
        // interval of the infinite cylinder
        let (c0, c1) = if qa > 1e-12 * self.k * q {
            let half_b = -self.k * ard + bard * self.aba;
            let h = half_b * half_b - qa * self.cyl_c;
            if h < 0.0 {
                return None;
            }
            let s = h.sqrt();
            ((-half_b - s) / qa, (-half_b + s) / qa)
        } else if self.cyl_c <= 0.0 {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            return None;
        };
        // slab 0 ≤ (t rd − a)·(b − a) ≤ k
        let (s0, s1) = if bard.abs() > 1e-300 {
            let t0 = self.aba / bard;
            let t1 = (self.k + self.aba) / bard;
            if t0 <= t1 {
                (t0, t1)
            } else {
                (t1, t0)
            }
        } else if -self.aba >= 0.0 && -self.aba <= self.k {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            return None;
        };
        let lo = c0.max(s0);
        let hi = c1.min(s1);
        if lo <= hi {
            Some((lo, hi))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CameraPose, Intrinsics};
    use nalgebra::Point3;

    /// Every ray that enters a capsule lies within its row's candidates, for
    /// capsules of every orientation around and in front of the camera.
    #[test]
    fn every_entering_ray_is_a_row_candidate() {
        let k = Intrinsics::default();
        let pose = CameraPose::paper_default();
        let (xn, yn) = (k.column_factors(), k.row_factors());
        let mut lcg = crate::lanes::test_sequence(7);
        let mut uniform =
            move |lo: f64, hi: f64| lo + (hi - lo) * ((lcg() >> 11) as f64 / (1u64 << 53) as f64);
        let (mut hits, mut pruned, mut bounded) = (0usize, 0usize, 0usize);
        for _ in 0..300 {
            let a = Point3::new(uniform(-1.0, 1.5), uniform(-1.2, 1.2), uniform(0.0, 1.8));
            let b = a + nalgebra::Vector3::new(
                uniform(-0.6, 0.6),
                uniform(-0.6, 0.6),
                uniform(-0.6, 0.6),
            );
            let capsule = Capsule::new(a, b, uniform(0.01, 0.15));
            let rc = RayCapsule::new(&capsule, &pose, 0.0);
            for (v, &y) in yn.iter().enumerate().step_by(3) {
                let (lo, hi) = rc.row_candidates(y);
                bounded += usize::from(lo.is_finite() || lo > hi);
                for &x in xn.iter().step_by(2) {
                    let inside = x >= lo && x <= hi;
                    if rc.entry(x, y).is_some() {
                        hits += 1;
                        assert!(inside, "row {v}: x {x} outside [{lo}, {hi}]");
                    } else if !inside {
                        pruned += 1;
                    }
                }
            }
        }
        assert!(
            hits > 10_000 && pruned > hits,
            "{hits} hits, {pruned} pruned"
        );
        assert!(bounded > 0);
    }
}
