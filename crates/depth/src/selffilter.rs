//! Removing the robot's own pixels from a depth frame (REFERENCE §3: the robot
//! sees itself and must not repel itself).
//!
//! Each robot capsule is inflated by a margin. A pixel belongs to the robot if
//! its ray crosses an inflated capsule and its measured depth lies in that
//! capsule's entry/exit depth interval along the ray, widened on both sides by
//! a depth tolerance `tol(d) = depth_tolerance_m + noise_sigmas · σ_z(d)`. Such
//! pixels are set to 0 (no reading). Only pixels inside each capsule's
//! projected bounding rectangle are visited.
//!
//! Why this catches every robot pixel: a surface point of the true capsule lies
//! at least `margin` behind the inflated capsule's entry along any ray (the
//! distance along a ray is at least the distance between the two surfaces), so
//! a reading is kept only if its noise exceeds `margin + tol(d)`.

use serde::{Deserialize, Serialize};

use crate::camera::{CameraPose, Intrinsics};
use crate::error::{check_frame, DepthError};
use crate::lanes::{by_lanes, load, store, Lanes};
use crate::noise::sigma_z;
use crate::render::NEAR_M;
use crate::shapes::{Capsule, CapsulePixels, RayCapsule};

/// Parameters of the self-filter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SelfFilterParams {
    /// radius added to every robot capsule \[m\] (covers model error, joint-state latency)
    pub margin_m: f64,
    /// constant depth tolerance on both ends of the ray interval \[m\]
    pub depth_tolerance_m: f64,
    /// extra depth tolerance in multiples of the sensor noise `σ_z(d)`
    pub noise_sigmas: f64,
    /// metres per unit of the frame (0.001: millimetres)
    pub depth_scale_m: f64,
}

impl Default for SelfFilterParams {
    /// 3 cm margin, 2 cm + 3σ depth tolerance, millimetre frames.
    fn default() -> Self {
        Self {
            margin_m: 0.03,
            depth_tolerance_m: 0.02,
            noise_sigmas: 3.0,
            depth_scale_m: 0.001,
        }
    }
}

impl SelfFilterParams {
    /// Checks that every value is finite and ≥ 0 (scale > 0).
    pub fn validate(&self) -> Result<(), DepthError> {
        let ok = self.margin_m.is_finite()
            && self.margin_m >= 0.0
            && self.depth_tolerance_m.is_finite()
            && self.depth_tolerance_m >= 0.0
            && self.noise_sigmas.is_finite()
            && self.noise_sigmas >= 0.0
            && self.depth_scale_m.is_finite()
            && self.depth_scale_m > 0.0;
        if ok {
            Ok(())
        } else {
            Err(DepthError::Parameter {
                what: "self-filter",
                reason: format!("{self:?}: values must be finite and >= 0, scale > 0"),
            })
        }
    }
}

/// Removes the pixels of the robot's own (inflated) collision capsules from
/// depth frames of one camera.
#[derive(Debug, Clone)]
pub struct SelfFilter {
    intrinsics: Intrinsics,
    pose: CameraPose,
    params: SelfFilterParams,
    xn: Vec<f64>,
    yn: Vec<f64>,
    /// `d ± tol(d)` never decrease over the raw values (they do not for the
    /// sensor's noise at any sane `noise_sigmas`): a capsule's depth range is
    /// then one interval of raw values, tested on the raw depths first
    monotone: bool,
    /// the vector width this CPU runs
    lanes: Lanes,
}

impl SelfFilter {
    /// A filter for `intrinsics` at `pose`; precomputes the per-column and
    /// per-row ray factors.
    pub fn new(
        intrinsics: Intrinsics,
        pose: CameraPose,
        params: SelfFilterParams,
    ) -> Result<Self, DepthError> {
        intrinsics.validate()?;
        params.validate()?;
        Ok(Self {
            intrinsics,
            pose,
            params,
            xn: intrinsics.column_factors(),
            yn: intrinsics.row_factors(),
            monotone: edges_never_decrease(&params),
            lanes: Lanes::detect(),
        })
    }

    /// Parameters.
    pub fn params(&self) -> &SelfFilterParams {
        &self.params
    }

    /// Moves the camera.
    pub fn set_pose(&mut self, pose: CameraPose) {
        self.pose = pose;
    }

    /// Sets to 0 every pixel of `frame` (`width × height`, units of
    /// `depth_scale_m`) that lies on one of `robot_capsules` (base frame, at the
    /// joint state of the frame's time) inflated by the margin, within the depth
    /// tolerance. Returns the number of pixels removed. Allocates nothing.
    pub fn apply(
        &mut self,
        robot_capsules: &[Capsule],
        frame: &mut [u16],
    ) -> Result<usize, DepthError> {
        check_frame(
            "self-filter frame",
            self.intrinsics.width,
            self.intrinsics.height,
            frame.len(),
        )?;
        for (index, c) in robot_capsules.iter().enumerate() {
            if !c.is_valid() {
                return Err(DepthError::Primitive {
                    what: "robot capsule",
                    index,
                    reason: "endpoints and radius must be finite, radius >= 0",
                });
            }
        }
        let p = self.params;
        let mut removed = 0;
        for capsule in robot_capsules {
            let rc = RayCapsule::new(capsule, &self.pose, p.margin_m);
            let Some(rect) = rc.pixel_rect(&self.intrinsics, NEAR_M) else {
                continue;
            };
            let (z_min, z_max) = rc.depth_range();
            let region = Region {
                at: CapsulePixels::new(&rc, &rect, &self.xn, &self.yn),
                params: &p,
                raw: match self.monotone {
                    true => raw_range(&p, z_min, z_max),
                    false => (1, u16::MAX),
                },
            };
            removed += remove(self.lanes, &region, frame);
        }
        Ok(removed)
    }
}

/// Pixels per run of [`remove_any`].
const RUN: usize = 16;

/// One capsule's pixel rectangle, and the filter's parameters.
struct Region<'a> {
    at: CapsulePixels<'a>,
    params: &'a SelfFilterParams,
    /// raw depths (lo ≥ 1, hi) outside which no reading can lie in the
    /// capsule's depth range: a run with none inside is passed over before
    /// any floating-point work
    raw: (u16, u16),
}

/// `tol(d)` of the filter's rule \[m\] for a depth `d` \[m\].
#[inline(always)]
fn tolerance(p: &SelfFilterParams, d: f64) -> f64 {
    p.depth_tolerance_m + p.noise_sigmas * sigma_z(d)
}

/// Whether `d − tol(d)` and `d + tol(d)` never decrease from one raw value to
/// the next over every raw value (checked once per filter: 65 536 values).
fn edges_never_decrease(p: &SelfFilterParams) -> bool {
    let edges = |r: u32| {
        let d = f64::from(r) * p.depth_scale_m;
        let t = tolerance(p, d);
        (d - t, d + t)
    };
    (1..=u32::from(u16::MAX)).all(|r| {
        let (a0, b0) = edges(r - 1);
        let (a1, b1) = edges(r);
        a1 >= a0 && b1 >= b0
    })
}

/// The raw values (lo ≥ 1, hi) outside which a reading cannot lie within
/// `tol` of the depth range `[z_min, z_max]` \[m\] (`d + tol(d) < z_min` or
/// `d − tol(d) > z_max`), for edges that never decrease
/// ([`edges_never_decrease`]); one unit wider on each side than the
/// boundaries found, so that no rounding of the rule's own arithmetic
/// falls outside.
fn raw_range(p: &SelfFilterParams, z_min: f64, z_max: f64) -> (u16, u16) {
    let d = |r: u32| f64::from(r) * p.depth_scale_m;
    // the first raw value whose upper edge reaches z_min
    let (mut a, mut b) = (0u32, u32::from(u16::MAX) + 1);
    while a < b {
        let m = (a + b) / 2;
        if d(m) + tolerance(p, d(m)) < z_min {
            a = m + 1;
        } else {
            b = m;
        }
    }
    let lo = a.saturating_sub(1).max(1);
    // the first raw value whose lower edge passes z_max
    let (mut a, mut b) = (0u32, u32::from(u16::MAX) + 1);
    while a < b {
        let m = (a + b) / 2;
        if d(m) - tolerance(p, d(m)) <= z_max {
            a = m + 1;
        } else {
            b = m;
        }
    }
    let hi = a.min(u32::from(u16::MAX));
    match lo <= hi {
        true => (lo as u16, hi as u16),
        false => (1, 0),
    }
}

by_lanes! {
    fn remove(region: &Region<'_>, frame: &mut [u16]) -> usize = remove_any;
}

/// Removes the pixels of one capsule's rectangle that lie on it, in runs of
/// [`RUN`] pixels without branches (a run none of whose readings lies in
/// the capsule's depth range is passed over): a reading goes when its depth
/// `d` is within `tol(d)` of the capsule's depth range and of its ray's
/// entry/exit interval. Returns how many went.
#[inline(always)]
fn remove_any(region: &Region<'_>, frame: &mut [u16]) -> usize {
    let p = region.params;
    let (z_min, z_max) = region.at.rc.depth_range();
    let cols = region.at.xn.len();
    let mut removed = 0;
    for v in region.at.v0..=region.at.v1 {
        let y = region.at.yn[v];
        let start = v * region.at.width + region.at.u0;
        let row = &mut frame[start..start + cols];
        for c in (0..cols).step_by(RUN) {
            // a short last run is padded with no reading
            let mut raw: [u16; RUN] = load(row, c);
            let (lo, hi) = region.raw;
            let span = hi.wrapping_sub(lo);
            let mut maybe = false;
            for r in raw {
                maybe |= r.wrapping_sub(lo) <= span;
            }
            if !maybe || hi < lo {
                continue;
            }
            let xs: [f64; RUN] = load(region.at.xn, c);
            let mut d = [0.0f64; RUN];
            let mut tol = [0.0f64; RUN];
            let mut near = [false; RUN];
            for i in 0..RUN {
                d[i] = f64::from(raw[i]) * p.depth_scale_m;
                tol[i] = tolerance(p, d[i]);
                near[i] = (raw[i] != 0) & !(d[i] < z_min - tol[i] || d[i] > z_max + tol[i]);
            }
            if near.iter().any(|&n| n) {
                let mut gone = 0usize;
                for i in 0..RUN {
                    let (t_in, t_out) = region.at.rc.interval_lanes(xs[i], y);
                    let on = near[i] & (d[i] >= t_in - tol[i]) & (d[i] <= t_out + tol[i]);
                    raw[i] = if on { 0 } else { raw[i] };
                    gone += usize::from(on);
                }
                store(row, c, &raw);
                removed += gone;
            }
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    /// The rule pixel by pixel, with the ray interval of
    /// [`RayCapsule::interval`] (the branching form).
    fn reference(f: &SelfFilter, capsules: &[Capsule], frame: &mut [u16]) -> usize {
        let p = f.params;
        let w = f.intrinsics.width as usize;
        let mut removed = 0;
        for capsule in capsules {
            let rc = RayCapsule::new(capsule, &f.pose, p.margin_m);
            let (z_min, z_max) = rc.depth_range();
            let Some(rect) = rc.pixel_rect(&f.intrinsics, NEAR_M) else {
                continue;
            };
            for v in rect.v0..=rect.v1 {
                for u in rect.u0..=rect.u1 {
                    let raw = frame[v * w + u];
                    if raw == 0 {
                        continue;
                    }
                    let d = f64::from(raw) * p.depth_scale_m;
                    let tol = p.depth_tolerance_m + p.noise_sigmas * sigma_z(d);
                    if d < z_min - tol || d > z_max + tol {
                        continue;
                    }
                    if let Some((t_in, t_out)) = rc.interval(f.xn[u], f.yn[v]) {
                        if d >= t_in - tol && d <= t_out + tol {
                            frame[v * w + u] = 0;
                            removed += 1;
                        }
                    }
                }
            }
        }
        removed
    }

    /// Every vector width this CPU runs removes exactly the pixels the
    /// branching form does: capsules of every orientation (along the
    /// optical axis, across it, degenerate spheres, partly behind the
    /// camera) over frames of surfaces near and through them.
    #[test]
    fn every_vector_width_removes_what_the_branching_form_does() {
        let k = Intrinsics::default();
        let pose = CameraPose::paper_default();
        let mut f = SelfFilter::new(k, pose, SelfFilterParams::default()).unwrap();
        let mut lcg = crate::lanes::test_sequence(7);
        let mut next = move || (lcg() >> 11) as f64 / (1u64 << 53) as f64;
        let mut total = 0;
        for trial in 0..12 {
            let mut capsules = Vec::new();
            for _ in 0..6 {
                let a = Point3::new(next() * 1.2 - 0.2, next() * 1.2 - 0.6, next() * 1.0);
                let b = match trial % 3 {
                    0 => a,
                    _ => Point3::new(next() * 1.2 - 0.2, next() * 1.2 - 0.6, next() * 1.0),
                };
                capsules.push(Capsule::new(a, b, 0.02 + next() * 0.1));
            }
            // the camera's view of the capsules themselves (depth of the
            // nearest entry) with noise, and random readings elsewhere
            let w = k.width as usize;
            let mut frame = vec![0u16; k.pixel_count()];
            let rcs: Vec<RayCapsule> = capsules
                .iter()
                .map(|c| RayCapsule::new(c, &pose, 0.0))
                .collect();
            for v in 0..k.height as usize {
                for u in 0..w {
                    let entry = rcs
                        .iter()
                        .filter_map(|rc| rc.entry(f.xn[u], f.yn[v]))
                        .filter(|t| *t > 0.0)
                        .fold(f64::INFINITY, f64::min);
                    let raw = if entry.is_finite() && next() < 0.9 {
                        entry * 1000.0 + (next() - 0.5) * 60.0
                    } else if next() < 0.2 {
                        0.0
                    } else {
                        300.0 + next() * 4000.0
                    };
                    frame[v * w + u] = raw.clamp(0.0, 65535.0) as u16;
                }
            }
            let mut want = frame.clone();
            let want_removed = reference(&f, &capsules, &mut want);
            total += want_removed;
            for (lanes, monotone) in Lanes::available()
                .into_iter()
                .flat_map(|l| [(l, true), (l, false)])
            {
                f.lanes = lanes;
                f.monotone = monotone;
                let mut got = frame.clone();
                let removed = f.apply(&capsules, &mut got).unwrap();
                assert_eq!(removed, want_removed, "trial {trial} {lanes:?} {monotone}");
                assert!(got == want, "trial {trial} {lanes:?} {monotone}");
            }
        }
        assert!(total > 10_000, "{total}");
    }

    /// The raw interval a capsule's depth range allows holds every raw value
    /// the rule's depth test lets through, over all 65 536 of them, and
    /// little more; edges that decrease (an absurd noise factor) are found.
    #[test]
    fn the_raw_interval_holds_every_reading_the_depth_test_keeps() {
        let base = SelfFilterParams::default();
        let cases = [
            base,
            SelfFilterParams {
                depth_tolerance_m: 0.0,
                noise_sigmas: 0.0,
                ..base
            },
            SelfFilterParams {
                depth_scale_m: 0.0001,
                ..base
            },
        ];
        let mut lcg = crate::lanes::test_sequence(3);
        let mut next = move || (lcg() >> 11) as f64 / (1u64 << 53) as f64;
        for p in cases {
            assert!(edges_never_decrease(&p), "{p:?}");
            for _ in 0..40 {
                let z_min = next() * 5.0 - 0.5;
                let z_max = z_min + next() * 0.6;
                let (lo, hi) = raw_range(&p, z_min, z_max);
                let near: Vec<u16> = (1..=u16::MAX)
                    .filter(|&r| {
                        let d = f64::from(r) * p.depth_scale_m;
                        let tol = tolerance(&p, d);
                        !(d < z_min - tol || d > z_max + tol)
                    })
                    .collect();
                match (near.first(), near.last()) {
                    (Some(&a), Some(&b)) => {
                        assert!(
                            lo <= a && b <= hi,
                            "{p:?} [{z_min}, {z_max}]: {a}..{b} outside {lo}..{hi}"
                        );
                        assert!(a - lo <= 1 && hi - b <= 1, "{p:?}: {a}..{b} in {lo}..{hi}");
                    }
                    _ => assert!(u32::from(hi) < u32::from(lo) + 2, "none near: {lo}..{hi}"),
                }
            }
        }
        let absurd = SelfFilterParams {
            noise_sigmas: 1000.0,
            ..base
        };
        assert!(!edges_never_decrease(&absurd));
    }
}
