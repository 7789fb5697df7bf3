//! Masking the collaborative part (paper Fig. 5): while a collaboration is
//! on, the depth pixels whose 3-D point lies within a sphere around the
//! collaborative hand, or a short capsule from it toward the elbow, are
//! removed from the frame the repulsion workers see, so that the hand the
//! robot is asked to touch is no obstacle. Every other pixel, the other hand
//! included, stays.
//!
//! The same pixels refine the hand: the tracker's hand is noisy (a few
//! centimetres), the depth pixels around it are not. The refined hand is the
//! centre of the 3-D points within `refine_radius_m` of the tracked hand,
//! pushed back along the mean viewing ray by two thirds of the hand's radius
//! (the camera sees only the near side of the hand).
//!
//! Only the image window the region projects into is visited.

use std::cell::Cell;

use nalgebra::{Point3, Vector3};
use phri_config::CollaborationConfig;
use phri_depth::{CameraPose, Intrinsics};
use phri_ipc::{
    CollabPart, CollabPhase, CollabState, FrameHeader, HandObservation, Skeleton, SkeletonJoint,
    Zeroed,
};

/// The region to remove, base frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandMask {
    /// the tracked hand \[m\]
    pub hand: [f64; 3],
    /// the tracked elbow of the same arm \[m\] (`None`: the sphere alone)
    pub elbow: Option<[f64; 3]>,
    /// radius of the sphere and the capsule \[m\]
    pub radius_m: f64,
    /// length of the capsule from the hand toward the elbow \[m\]
    pub forearm_m: f64,
    /// the hand is refined from the points within this of the tracked hand \[m\]
    pub refine_radius_m: f64,
    /// radius of the hand \[m\]
    pub hand_radius_m: f64,
}

/// What [`apply`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Masked {
    /// pixels removed
    pub pixels: u32,
    /// the hand refined from the depth points around it \[m\], base frame
    /// (`None`: too few points)
    pub refined: Option<[f64; 3]>,
}

/// Fewest points that refine the hand.
const MIN_REFINE_POINTS: usize = 10;

/// Distance from `p` to the segment `a`–`b`.
fn to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * s)).norm()
}

/// An image window: columns `u0..=u1`, rows `v0..=v1` \[px\].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Window {
    u0: usize,
    v0: usize,
    u1: usize,
    v1: usize,
}

/// The image window that every sphere of `spheres` (centre \[m\], base
/// frame; radius \[m\]) projects into, clipped to the image (`None`: none
/// is in front of the camera).
fn window(k: &Intrinsics, pose: &CameraPose, spheres: &[(Vector3<f64>, f64)]) -> Option<Window> {
    let mut w = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for &(p, r) in spheres {
        let Some(px) = pose.project(k, &Point3::from(p)) else {
            continue;
        };
        let grow = k.fx * r / (px.depth - r).max(0.1);
        w = [
            w[0].min(px.px - grow),
            w[1].min(px.py - grow),
            w[2].max(px.px + grow),
            w[3].max(px.py + grow),
        ];
    }
    w[0].is_finite().then(|| Window {
        u0: w[0].floor().max(0.0) as usize,
        v0: w[1].floor().max(0.0) as usize,
        u1: (w[2].ceil().max(0.0) as usize).min((k.width as usize).saturating_sub(1)),
        v1: (w[3].ceil().max(0.0) as usize).min((k.height as usize).saturating_sub(1)),
    })
}

/// Each pixel of `win` with a reading: its 3-D point \[m\], base frame,
/// and its depth \[mm\] (a cell: the removal clears it).
fn for_each_point(
    k: &Intrinsics,
    pose: &CameraPose,
    depth: &[Cell<u16>],
    win: Window,
    mut f: impl FnMut(Vector3<f64>, &Cell<u16>),
) {
    let w = k.width as usize;
    for v in win.v0..=win.v1 {
        for u in win.u0..=win.u1 {
            let Some(d) = depth.get(v * w + u).filter(|d| d.get() != 0) else {
                continue;
            };
            let p = pose
                .back_project(k, u as f64, v as f64, d.get() as f64 * 1e-3)
                .coords;
            f(p, d);
        }
    }
}

/// The hand refined from the points of `depth` within
/// `refine_radius_m` of the tracked hand of `mask`: their centre, pushed
/// back along their mean viewing ray by two thirds of the hand's radius
/// (`None`: too few points).
fn refine(
    k: &Intrinsics,
    pose: &CameraPose,
    mask: &HandMask,
    depth: &[Cell<u16>],
) -> Option<[f64; 3]> {
    let hand = Vector3::from(mask.hand);
    let win = window(k, pose, &[(hand, mask.refine_radius_m)])?;
    let camera = pose.position().coords;
    let (mut sum, mut rays, mut count) = (Vector3::zeros(), Vector3::zeros(), 0usize);
    for_each_point(k, pose, depth, win, |p, _| {
        if (p - hand).norm() <= mask.refine_radius_m {
            sum += p;
            rays += (p - camera).normalize();
            count += 1;
        }
    });
    (count >= MIN_REFINE_POINTS).then(|| {
        let centre = sum / count as f64 + rays.normalize() * (mask.hand_radius_m * 2.0 / 3.0);
        [centre.x, centre.y, centre.z]
    })
}

/// Remove the region of `mask` from `depth` (millimetres, row-major, the
/// camera `k` at `pose`), and refine the hand from what was there. The
/// region is the sphere around the tracked hand and the capsule from it
/// toward the elbow, and the sphere around the refined hand too: a
/// tracker centimetres off (the simulated one's hand errs by up to 9 cm
/// along the view) left the hand's near side, the side the robot comes
/// to, in the frame, where it repelled the approach it was asked for.
pub fn apply(k: &Intrinsics, pose: &CameraPose, mask: &HandMask, depth: &mut [u16]) -> Masked {
    let (w, h) = (k.width as usize, k.height as usize);
    let hand = Vector3::from(mask.hand);
    if depth.len() < w * h || !hand.iter().all(|x| x.is_finite()) || !(mask.radius_m > 0.0) {
        return Masked::default();
    }
    let tip = match mask.elbow {
        Some(e) if e.iter().all(|x| x.is_finite()) => {
            let to = Vector3::from(e) - hand;
            if to.norm() > 1e-6 {
                hand + to * (mask.forearm_m.max(0.0) / to.norm()).min(1.0)
            } else {
                hand
            }
        }
        _ => hand,
    };
    let depth = Cell::from_mut(depth).as_slice_of_cells();
    let refined = refine(k, pose, mask, depth);
    let r = mask.radius_m;
    // the refined hand's sphere (none: the tracked hand's again)
    let near = refined.map_or(hand, Vector3::from);
    let Some(win) = window(k, pose, &[(hand, r), (tip, r), (near, r)]) else {
        return Masked { pixels: 0, refined };
    };
    let mut removed = 0u32;
    for_each_point(k, pose, depth, win, |p, d| {
        if to_segment(&p, &hand, &tip) <= r || (p - near).norm() <= r {
            d.set(0);
            removed += 1;
        }
    });
    Masked {
        pixels: removed,
        refined,
    }
}

/// The region ingestion removes around the collaborative `part` of the
/// first tracked person in `sk` (`None`: the part is not tracked).
pub fn hand_mask(sk: &Skeleton, part: CollabPart, cfg: &CollaborationConfig) -> Option<HandMask> {
    let (hand, elbow) = match part {
        CollabPart::RightHand => (SkeletonJoint::RightHand, SkeletonJoint::RightElbow),
        CollabPart::LeftHand => (SkeletonJoint::LeftHand, SkeletonJoint::LeftElbow),
        CollabPart::None => return None,
    };
    let n = (sk.n_people as usize).min(sk.people.len());
    let p = sk.people[..n].iter().find(|p| p.tracked != 0)?;
    let h = p.joints[hand as usize];
    if !h.iter().all(|x| x.is_finite()) {
        return None;
    }
    let e = p.joints[elbow as usize];
    Some(HandMask {
        hand: h,
        elbow: e.iter().all(|x| x.is_finite()).then_some(e),
        radius_m: cfg.mask_radius_m,
        forearm_m: cfg.mask_forearm_m,
        refine_radius_m: cfg.refine_radius_m,
        hand_radius_m: cfg.hand_radius_m,
    })
}

/// A tracker that loses the person for a frame (a dropout) must not unmask
/// the collaborative hand for that frame, or the hand the robot holds would
/// repel it: the last mask is kept this long \[ns\].
pub const MASK_HOLD_NS: u64 = 300_000_000;

/// The mask of each frame while collaborating: the tracked hand's, or
/// through a dropout the last one for up to [`MASK_HOLD_NS`].
#[derive(Clone, Copy, Debug, Default)]
pub struct MaskHold {
    last: Option<(HandMask, u64)>,
}

impl MaskHold {
    /// The mask for the frame captured at `capture_ns` \[ns\]: `part`
    /// (`None`: no collaboration, which forgets the last mask) in `sk`.
    pub fn mask(
        &mut self,
        sk: Option<&Skeleton>,
        part: Option<CollabPart>,
        cfg: &CollaborationConfig,
        capture_ns: u64,
    ) -> Option<HandMask> {
        let Some(part) = part else {
            self.last = None;
            return None;
        };
        match sk.and_then(|sk| hand_mask(sk, part, cfg)) {
            Some(m) => {
                self.last = Some((m, capture_ns));
                Some(m)
            }
            None => self
                .last
                .filter(|(_, t)| capture_ns.saturating_sub(*t) <= MASK_HOLD_NS)
                .map(|(m, _)| m),
        }
    }
}

/// A `collab/state` older than this no longer masks its hand \[ns\]: the
/// controller publishes one every period (1 ms), so this is a controller
/// stopped, killed or stalled, and its collaboration is over for safety.
pub const COLLAB_STATE_MAX_AGE_NS: u64 = 50_000_000;

/// The part to mask at `now_ns` \[ns, CLOCK_MONOTONIC\]: the collaborative
/// part of the newest `collab/state` while a collaboration is on and that
/// state is fresh. A controller that died mid-contact leaves its last state
/// behind; once stale, the hand it named is an obstacle again, for the
/// restarted controller as for any other.
pub fn collaborating_part(state: Option<&CollabState>, now_ns: u64) -> Option<CollabPart> {
    state
        .filter(|s| s.phase != CollabPhase::Idle as u32)
        .filter(|s| now_ns.saturating_sub(s.stamp_ns) <= COLLAB_STATE_MAX_AGE_NS)
        .filter(|s| s.stamp_ns <= now_ns.saturating_add(COLLAB_STATE_MAX_AGE_NS))
        .and_then(|s| CollabPart::try_from(s.human_part).ok())
}

/// The `perception/hand` message of a masked frame.
pub fn hand_observation(
    header: &FrameHeader,
    part: CollabPart,
    mask: &HandMask,
    masked: &Masked,
    published_ns: u64,
) -> HandObservation {
    let mut h = HandObservation::zeroed();
    h.seq = header.seq;
    h.capture_ns = header.capture_ns;
    h.published_ns = published_ns;
    h.part = part as u32;
    h.person = u32::MAX;
    h.refined = masked.refined.is_some() as u32;
    h.masked_pixels = masked.pixels;
    h.tracked = mask.hand;
    h.position = masked.refined.unwrap_or(mask.hand);
    // refined from depth: certain; otherwise the controller uses the skeleton
    h.confidence = if masked.refined.is_some() { 1.0 } else { 0.0 };
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stale_collaboration_state_masks_nothing() {
        let mut st = CollabState::zeroed();
        st.phase = CollabPhase::Contact as u32;
        st.human_part = CollabPart::RightHand as u32;
        st.stamp_ns = 1_000_000_000;
        let fresh = st.stamp_ns + 10_000_000;
        assert_eq!(
            collaborating_part(Some(&st), fresh),
            Some(CollabPart::RightHand)
        );
        // its controller stopped: 60 ms without a state
        assert_eq!(
            collaborating_part(Some(&st), st.stamp_ns + 60_000_000),
            None
        );
        // idle, absent, or stamped far in the future: nothing
        let mut idle = st;
        idle.phase = CollabPhase::Idle as u32;
        assert_eq!(collaborating_part(Some(&idle), fresh), None);
        assert_eq!(collaborating_part(None, fresh), None);
        assert_eq!(collaborating_part(Some(&st), 0), None);
    }
    use phri_depth::{Capsule, RenderOptions, Renderer};

    fn scene(capsules: &[Capsule]) -> (Intrinsics, CameraPose, Vec<u16>) {
        let k = Intrinsics::KINECT;
        let pose = CameraPose::paper_default();
        let opts = RenderOptions {
            noise: false,
            edge_dropout: 0.0,
            ..RenderOptions::default()
        };
        let mut r = Renderer::new(k, pose, opts).unwrap();
        let mut out = vec![0; k.pixel_count()];
        r.render(capsules, &[], None, &mut out).unwrap();
        (k, pose, out)
    }

    #[test]
    fn the_hand_goes_the_other_hand_stays_and_the_hand_is_refined() {
        let right = [0.6, 0.3, 0.3];
        let left = [0.6, -0.3, 0.3];
        let ball = |c: [f64; 3]| Capsule::new(Point3::from(c), Point3::from(c), 0.045);
        let (k, pose, mut depth) = scene(&[ball(right), ball(left)]);
        let before = depth.iter().filter(|&&d| d > 0).count();
        // the tracker is 3 cm off
        let mask = HandMask {
            hand: [0.62, 0.32, 0.31],
            elbow: None,
            radius_m: 0.12,
            forearm_m: 0.0,
            refine_radius_m: 0.12,
            hand_radius_m: 0.045,
        };
        let m = apply(&k, &pose, &mask, &mut depth);
        let after = depth.iter().filter(|&&d| d > 0).count();
        assert!(m.pixels > 50, "{m:?}");
        assert_eq!(before - after, m.pixels as usize);
        // only the left hand is left, every pixel of it
        let (_, _, only_left) = scene(&[ball(left)]);
        assert_eq!(depth, only_left);
        let r = Vector3::from(m.refined.expect("refined"));
        assert!(
            (r - Vector3::from(right)).norm() < 0.015,
            "refined {r} vs {right:?}"
        );
    }

    #[test]
    fn a_tracker_far_off_still_leaves_nothing_of_the_hand() {
        // the tracked hand 9 cm beyond the hand along the camera's view,
        // and 3 cm aside: the hand's near side lies outside the tracked
        // sphere, inside the refined one
        let right = Vector3::new(0.6, 0.3, 0.3);
        let ball = |c: Vector3<f64>| Capsule::new(Point3::from(c), Point3::from(c), 0.045);
        let (k, pose, mut depth) = scene(&[ball(right)]);
        let view = (right - pose.position().coords).normalize();
        let aside = view.cross(&Vector3::z()).normalize();
        let tracked = right + view * 0.09 + aside * 0.03;
        let mask = HandMask {
            hand: [tracked.x, tracked.y, tracked.z],
            elbow: None,
            radius_m: 0.12,
            forearm_m: 0.0,
            refine_radius_m: 0.12,
            hand_radius_m: 0.045,
        };
        // the tracked sphere alone would leave some of the hand
        let mut outside = 0;
        let all = window(&k, &pose, &[(right, 0.05)]).unwrap();
        let cells = depth.iter().copied().map(Cell::new).collect::<Vec<_>>();
        for_each_point(&k, &pose, &cells, all, |p, _| {
            outside += usize::from((p - tracked).norm() > 0.12);
        });
        assert!(outside > 20, "{outside} pixels outside the tracked sphere");
        let m = apply(&k, &pose, &mask, &mut depth);
        assert!(depth.iter().all(|&d| d == 0), "{m:?}");
        let r = Vector3::from(m.refined.expect("refined"));
        assert!((r - right).norm() < 0.06, "refined {r} vs {right}");
    }

    #[test]
    fn a_tracker_dropout_keeps_the_last_mask_for_a_while() {
        let cfg = phri_config::Config::defaults().collaboration;
        let mut sk = Skeleton::zeroed();
        sk.n_people = 1;
        sk.people[0].tracked = 1;
        sk.people[0].joints[SkeletonJoint::RightHand as usize] = [0.5, 0.1, 0.3];
        sk.people[0].joints[SkeletonJoint::RightElbow as usize] = [0.7, 0.1, 0.2];
        let mut lost = sk;
        lost.people[0].tracked = 0;
        let right = Some(CollabPart::RightHand);
        let mut hold = MaskHold::default();
        let ms = 1_000_000u64;
        let m = hold
            .mask(Some(&sk), right, &cfg, 1000 * ms)
            .expect("tracked");
        assert_eq!(m.hand, [0.5, 0.1, 0.3]);
        // a dropout: the last mask, until MASK_HOLD_NS has passed
        assert_eq!(hold.mask(Some(&lost), right, &cfg, 1033 * ms), Some(m));
        assert_eq!(
            hold.mask(None, right, &cfg, 1000 * ms + MASK_HOLD_NS),
            Some(m)
        );
        assert_eq!(
            hold.mask(Some(&lost), right, &cfg, 1001 * ms + MASK_HOLD_NS),
            None
        );
        // no collaboration: nothing masked, and nothing held for the next
        assert!(hold.mask(Some(&sk), right, &cfg, 2000 * ms).is_some());
        assert_eq!(hold.mask(Some(&sk), None, &cfg, 2033 * ms), None);
        assert_eq!(hold.mask(Some(&lost), right, &cfg, 2066 * ms), None);
    }
}
