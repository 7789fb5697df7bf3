//! Body parts from a person's geodesic extrema and the body's geometry.
//!
//! - head: the extremum above the body's centre nearest its vertical axis; the
//!   joint is the mean of the surface within `head_cap_m` of it (the top of the
//!   head is the extremum, its centre is lower);
//! - feet: extrema far below the head near the body's lowest point, not cut by the image's border;
//! - hands: the first two other extrema (in AGEX order, the farthest first) at
//!   least `hand_min_from_head_m` (geodesic) from the head, at most
//!   `hand_max_below_head_m` below it (not a leg) and not on the same arm; the joint is the mean of the surface within `hand_cap_m` of the tip;
//! - neck: on the geodesic path from the head to the centre, `neck_from_head_m` from the head;
//! - shoulders: the outermost surface points `shoulder_below_head_m` below the
//!   top of the head, at most `shoulder_max_lateral_m` to the side of the neck;
//! - elbows: on the geodesic path from the hand back to its shoulder, where it
//!   bends most (midway along a straight arm);
//! - torso, hips, knees: placed from the neck along the body's vertical axis
//!   (`up`) by a standing adult's proportions, seen only where the body's surface is.
//!
//! Left and right are the person's own, for a person facing the camera: the
//! person's left is on the image's right (+x of the camera frame). A person
//! seen from behind is reported mirrored (depth alone cannot tell front from back).
//!
//! Surface joints are moved `*_inset_m` along the view ray, behind the surface
//! toward the body part's axis. Positions in the camera frame \[m\].

use crate::config::TrackerConfig;
use crate::geodesic::{Extremum, Geodesic, MAX_EXTREMA, NONE};
use crate::grid::Grid;
use crate::segment::{Component, Segmenter};
use crate::Joint;
use crate::JOINTS;

/// Joints and confidences of one person in one frame, camera frame \[m\];
/// confidence 0: not found (the position is then a guess).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawSkeleton {
    /// joint positions in [`Joint`] order \[m\]
    pub joints: [[f64; 3]; JOINTS],
    /// confidence of each joint in \[0, 1\]
    pub confidence: [f64; JOINTS],
    /// the body's centroid \[m\]
    pub centroid: [f64; 3],
}

impl Default for RawSkeleton {
    fn default() -> Self {
        Self {
            joints: [[0.0; 3]; JOINTS],
            confidence: [0.0; JOINTS],
            centroid: [0.0; 3],
        }
    }
}

/// Vertical-axis body proportions below the neck \[m\] (a standing adult).
const NECK_TO_TORSO_M: f64 = 0.2;
const NECK_TO_HIP_M: f64 = 0.45;
const HIP_HALF_WIDTH_M: f64 = 0.1;
const HIP_TO_KNEE_M: f64 = 0.4;
/// An arm whose path from the hand to the shoulder is shorter than this,
/// straight, is seen end on: its elbow is a guess \[m\] (a forearm raised
/// beside the head measures ~0.15).
const MIN_ARM_PATH_M: f32 = 0.12;
/// An arm whose path from hand to shoulder bends less than this is straight \[m\].
const STRAIGHT_ARM_M: f64 = 0.05;
/// An elbow lies at most this far from its shoulder (an upper arm and a margin) \[m\].
const ELBOW_FROM_SHOULDER_M: f64 = 0.36;
/// An elbow lies this far from the hand along the surface \[m\].
const MIN_FOREARM_M: f32 = 0.12;
const MAX_FOREARM_M: f32 = 0.45;
/// two hands closer than this (geodesic) lie on one arm \[m\]
const SAME_ARM_M: f32 = 0.35;

#[inline]
fn add(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}
#[inline]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
/// Distance of `p` from the segment `a`-`b` \[m\].
fn segment_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    norm(sub(p, add(a, ab, t)))
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `p` moved `inset` metres farther along its view ray.
fn inset(p: [f64; 3], inset: f64) -> [f64; 3] {
    let n = norm(p);
    if n > 1e-9 {
        add(p, p, inset / n)
    } else {
        p
    }
}

/// Everything the labelling reads.
pub struct Body<'a> {
    /// the tracker's settings
    pub cfg: &'a TrackerConfig,
    /// this frame's samples
    pub grid: &'a Grid,
    /// this frame's components, the person's among them
    pub seg: &'a Segmenter,
    /// the person's component
    pub comp: &'a Component,
    /// the person's index in `seg.components`
    pub person: usize,
    /// unit up and across vectors, camera frame
    pub up: [f64; 3],
    /// unit across vector (camera x made perpendicular to `up`), camera frame
    pub side: [f64; 3],
}

impl Body<'_> {
    /// Confidence `c` if camera-frame point `p` lies on this body's surface
    /// (its cell belongs to the body, within 0.3 m in depth), else 0.
    fn seen(&self, p: [f64; 3], c: f64) -> f64 {
        match self.grid.cell_of(p) {
            Some(cell)
                if self.seg.owner_of_cell(cell) == Some(self.person)
                    && (f64::from(self.grid.pts[cell][2]) - p[2]).abs() < 0.3 =>
            {
                c
            }
            _ => 0.0,
        }
    }
}

/// Labels the extrema of `geo` (built for `body.comp`) as a skeleton: the
/// head first (the geodesic distances from it then find the rest), the
/// neck and shoulders below it, the feet and hands among the extrema, the
/// arms' elbows along the hands' paths, the torso, hips and knees by the
/// body's proportions.
pub fn label(body: &Body, geo: &mut Geodesic) -> RawSkeleton {
    let cfg = body.cfg;
    let (up, side) = (body.up, body.side);
    let c = body.comp.centroid;
    let mut s = RawSkeleton {
        centroid: c,
        ..RawSkeleton::default()
    };
    // guesses for everything, confidence 0
    for j in s.joints.iter_mut() {
        *j = c;
    }
    s.joints[Joint::Torso as usize] = c;
    s.confidence[Joint::Torso as usize] = 0.3;
    if geo.is_empty() {
        return s;
    }

    // the extrema, copied (the searches below reuse the graph's buffers)
    let mut ex = [Extremum {
        node: NONE,
        dist: 0.0,
    }; MAX_EXTREMA];
    let n_ex = geo.extrema.len().min(MAX_EXTREMA);
    ex[..n_ex].copy_from_slice(&geo.extrema[..n_ex]);
    let ex = &ex[..n_ex];

    let Some(head_node) = find_head(body, geo, ex) else {
        return s;
    };
    geo.from_head(head_node);
    let head_top_h = dot(geo.point(head_node), up);
    let (head_mean, _) = geo.cap_mean(head_node, cfg.head_cap_m as f32);
    s.joints[Joint::Head as usize] = inset(head_mean, cfg.head_inset_m);
    s.confidence[Joint::Head as usize] =
        if body.grid.on_border(geo.cells[head_node as usize] as usize) {
            0.5
        } else {
            1.0
        };

    // --- neck: along the path from the head to the centre ---
    let mut v = head_node;
    while geo.pred0[v as usize] != NONE && geo.head[v as usize] < cfg.neck_from_head_m as f32 {
        v = geo.pred0[v as usize];
    }
    let neck_surface = geo.point(v);
    let neck = inset(neck_surface, cfg.body_inset_m);
    s.joints[Joint::Neck as usize] = neck;
    s.confidence[Joint::Neck as usize] = 0.8;

    let shoulder_nodes = place_shoulders(body, geo, &mut s, neck_surface, head_top_h);
    let feet = feet_among(body, geo, ex, head_node, head_top_h);
    let hands = hands_among(cfg, geo, ex, head_node, &feet, head_top_h, up);
    let (left, right) = left_and_right(geo, hands, neck_surface, side);
    for (k, (hand, hj, ej, sj)) in [
        (left, Joint::LeftHand, Joint::LeftElbow, Joint::LeftShoulder),
        (
            right,
            Joint::RightHand,
            Joint::RightElbow,
            Joint::RightShoulder,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        place_arm(body, geo, &mut s, hand, (hj, ej, sj), shoulder_nodes[k]);
    }
    let feet = left_and_right(geo, feet, neck_surface, side);
    place_torso_and_legs(body, geo, &mut s, neck, feet);
    s
}

/// The head among the extrema `ex` and the body's highest point near its
/// axis (the top of the head may be nearer the centre than the extrema of
/// raised arms and of a body cut by the image's border): above the centre,
/// nearest the vertical axis, a protrusion.
fn find_head(body: &Body, geo: &Geodesic, ex: &[Extremum]) -> Option<u32> {
    let cfg = body.cfg;
    let (up, side, c) = (body.up, body.side, body.comp.centroid);
    let n_ex = ex.len();
    let mut cands = [NONE; MAX_EXTREMA + 1];
    for (k, e) in ex.iter().enumerate() {
        cands[k] = e.node;
    }
    let mut top = (f64::NEG_INFINITY, NONE);
    for n in 0..geo.len() {
        let d = sub(geo.point(n as u32), c);
        let h = dot(d, up);
        if h > top.0 && dot(d, side).abs() <= cfg.head_max_lateral_m {
            top = (h, n as u32);
        }
    }
    cands[n_ex] = top.1;
    let cands = &cands[..=n_ex];
    let mut tried = [false; MAX_EXTREMA + 1];
    loop {
        let mut best: Option<(usize, f64)> = None;
        for (k, &node) in cands.iter().enumerate() {
            if tried[k] || node == NONE {
                continue;
            }
            let d = sub(geo.point(node), c);
            let h = dot(d, up);
            if h < cfg.head_min_above_m {
                continue;
            }
            let lateral = (dot(d, d) - h * h).max(0.0).sqrt();
            if lateral > cfg.head_max_lateral_m {
                continue;
            }
            if best.is_none_or(|(_, l)| lateral < l) {
                best = Some((k, lateral));
            }
        }
        let (k, _) = best?;
        tried[k] = true;
        if is_protrusion(geo, cands[k], up, side) {
            return Some(cands[k]);
        }
    }
}

/// The shoulders into `s`: the outermost surface points at the shoulders'
/// height (below the head's top at `head_top_h` \[m\] along up), either
/// side of the neck's surface point; a side not found is guessed, with
/// confidence 0. Their nodes (left, right; [`NONE`]: guessed).
fn place_shoulders(
    body: &Body,
    geo: &Geodesic,
    s: &mut RawSkeleton,
    neck_surface: [f64; 3],
    head_top_h: f64,
) -> [u32; 2] {
    let cfg = body.cfg;
    let (up, side) = (body.up, body.side);
    let neck = s.joints[Joint::Neck as usize];
    let cell_m = f64::from(body.grid.cell_m(neck_surface[2] as f32));
    let band = (1.5 * cell_m).max(0.03);
    let shoulder_h = head_top_h - cfg.shoulder_below_head_m;
    let mut best_l: Option<(u32, f64)> = None;
    let mut best_r: Option<(u32, f64)> = None;
    for n in 0..geo.len() {
        let p = geo.point(n as u32);
        if (dot(p, up) - shoulder_h).abs() > band {
            continue;
        }
        let l = dot(sub(p, neck_surface), side);
        if l.abs() > cfg.shoulder_max_lateral_m {
            continue;
        }
        if l > 0.0 && best_l.is_none_or(|(_, b)| l > b) {
            best_l = Some((n as u32, l));
        }
        if l < 0.0 && best_r.is_none_or(|(_, b)| l < b) {
            best_r = Some((n as u32, l));
        }
    }
    let down = [-up[0], -up[1], -up[2]];
    let mut shoulder_nodes = [NONE; 2];
    for (k, (best, sign, joint)) in [
        (best_l, 1.0, Joint::LeftShoulder),
        (best_r, -1.0, Joint::RightShoulder),
    ]
    .into_iter()
    .enumerate()
    {
        match best {
            Some((n, _)) => {
                s.joints[joint as usize] = inset(geo.point(n), cfg.body_inset_m);
                s.confidence[joint as usize] = 0.8;
                shoulder_nodes[k] = n;
            }
            None => {
                s.joints[joint as usize] = add(add(neck, side, 0.18 * sign), down, 0.05);
                s.confidence[joint as usize] = 0.0;
            }
        }
    }
    shoulder_nodes
}

/// Up to two feet among the extrema `ex`: far enough below the head's top
/// (at `head_top_h` \[m\] along up), near the body's bottom, not on the
/// image's border ([`NONE`]: no foot).
fn feet_among(
    body: &Body,
    geo: &Geodesic,
    ex: &[Extremum],
    head_node: u32,
    head_top_h: f64,
) -> [u32; 2] {
    let mut feet = [NONE; 2];
    let mut n_feet = 0;
    for e in ex {
        if e.node == head_node || n_feet == 2 {
            continue;
        }
        let h = dot(geo.point(e.node), body.up);
        if head_top_h - h >= body.cfg.foot_min_below_head_m
            && h - body.comp.bottom_m <= 0.3
            && !body.grid.on_border(geo.cells[e.node as usize] as usize)
        {
            feet[n_feet] = e.node;
            n_feet += 1;
        }
    }
    feet
}

/// Up to two hands among the extrema `ex` that are neither the head nor a
/// foot: far enough from the head along the body, not too far below it,
/// and not a second point of the first hand's arm ([`NONE`]: no hand).
fn hands_among(
    cfg: &TrackerConfig,
    geo: &mut Geodesic,
    ex: &[Extremum],
    head_node: u32,
    feet: &[u32; 2],
    head_top_h: f64,
    up: [f64; 3],
) -> [u32; 2] {
    let mut hands = [NONE; 2];
    let mut n_hands = 0;
    for e in ex {
        if n_hands == 2 {
            break;
        }
        if e.node == head_node || feet.contains(&e.node) {
            continue;
        }
        if geo.head[e.node as usize] < cfg.hand_min_from_head_m as f32
            || head_top_h - dot(geo.point(e.node), up) > cfg.hand_max_below_head_m
        {
            continue;
        }
        if n_hands == 1 {
            // not a second point of the first hand's arm
            geo.cap_mean(hands[0], SAME_ARM_M);
            if geo.scratch[e.node as usize] <= SAME_ARM_M {
                continue;
            }
        }
        hands[n_hands] = e.node;
        n_hands += 1;
    }
    hands
}

/// The person's own (left, right) of two nodes (either [`NONE`]): left is
/// the larger coordinate across from the neck's surface point (the person
/// faces the camera); a single node goes to the side it lies on.
fn left_and_right(
    geo: &Geodesic,
    nodes: [u32; 2],
    neck_surface: [f64; 3],
    side: [f64; 3],
) -> (u32, u32) {
    let lat = |n: u32| dot(sub(geo.point(n), neck_surface), side);
    match nodes {
        [NONE, _] => (NONE, NONE),
        [a, NONE] if lat(a) >= 0.0 => (a, NONE),
        [a, NONE] => (NONE, a),
        [a, b] if lat(a) >= lat(b) => (a, b),
        [a, b] => (b, a),
    }
}

/// One arm into `s`: its hand at `hand` ([`NONE`]: unseen, hanging along
/// the body), its elbow where the path from the hand to the shoulder
/// (surface node `shoulder_node`, [`NONE`]: guessed) bends most, or midway
/// along it when it hardly bends (a straight arm). `(hj, ej, sj)`: the
/// hand's, the elbow's and the shoulder's joints.
fn place_arm(
    body: &Body,
    geo: &mut Geodesic,
    s: &mut RawSkeleton,
    hand: u32,
    (hj, ej, sj): (Joint, Joint, Joint),
    shoulder_node: u32,
) {
    let cfg = body.cfg;
    let up = body.up;
    let down = [-up[0], -up[1], -up[2]];
    let shoulder = s.joints[sj as usize];
    if hand == NONE {
        // hanging along the body, unseen
        s.joints[ej as usize] = add(shoulder, down, 0.3);
        s.joints[hj as usize] = add(shoulder, down, 0.6);
        return;
    }
    let (mean, _) = geo.cap_mean(hand, cfg.hand_cap_m as f32);
    s.joints[hj as usize] = inset(mean, cfg.hand_inset_m);
    s.confidence[hj as usize] = if body.grid.on_border(geo.cells[hand as usize] as usize) {
        0.4
    } else {
        1.0
    };
    // elbow: where the path from the hand to the shoulder bends most
    // (the farthest from the straight line between them); midway
    // along the path when it hardly bends (a straight arm)
    let shoulder_surface = if shoulder_node != NONE {
        geo.point(shoulder_node)
    } else {
        shoulder
    };
    let tip = geo.point(hand);
    let d_hand = geo.dist0[hand as usize];
    let mut stop = hand;
    let (mut elbow, mut bend) = (NONE, 0.0);
    while geo.pred0[stop as usize] != NONE {
        let p = geo.point(stop);
        // an elbow is on the arm: an upper arm from the shoulder, a
        // forearm from the hand
        let along = d_hand - geo.dist0[stop as usize];
        let on_arm = norm(sub(p, shoulder_surface)) <= ELBOW_FROM_SHOULDER_M
            && (MIN_FOREARM_M..=MAX_FOREARM_M).contains(&along);
        let off = segment_dist(p, tip, shoulder_surface);
        if on_arm && off > bend {
            (elbow, bend) = (stop, off);
        }
        if norm(sub(p, shoulder_surface)) < 0.08 {
            break;
        }
        stop = geo.pred0[stop as usize];
    }
    let path = d_hand - geo.dist0[stop as usize];
    let bent = bend >= STRAIGHT_ARM_M;
    if !bent {
        let half = 0.5 * path;
        elbow = hand;
        while geo.pred0[elbow as usize] != NONE && d_hand - geo.dist0[elbow as usize] < half {
            elbow = geo.pred0[elbow as usize];
        }
    }
    s.joints[ej as usize] = inset(geo.point(elbow), cfg.body_inset_m);
    s.confidence[ej as usize] = if path > MIN_ARM_PATH_M || bent {
        0.6
    } else {
        0.2
    };
}

/// The torso, hips, knees and feet into `s` by the body's proportions below
/// the neck at `neck` \[m, camera frame\]; a foot seen (`feet`: the
/// person's left and right nodes, [`NONE`]: unseen) places its knee midway.
fn place_torso_and_legs(
    body: &Body,
    geo: &mut Geodesic,
    s: &mut RawSkeleton,
    neck: [f64; 3],
    (foot_l, foot_r): (u32, u32),
) {
    let cfg = body.cfg;
    let (up, side) = (body.up, body.side);
    let down = [-up[0], -up[1], -up[2]];
    let torso = add(neck, down, NECK_TO_TORSO_M);
    s.joints[Joint::Torso as usize] = torso;
    s.confidence[Joint::Torso as usize] = body.seen(torso, 0.8).max(0.3);
    let hip_mid = add(neck, down, NECK_TO_HIP_M);
    for (sign, foot, hj, kj, fj) in [
        (
            1.0,
            foot_l,
            Joint::LeftHip,
            Joint::LeftKnee,
            Joint::LeftFoot,
        ),
        (
            -1.0,
            foot_r,
            Joint::RightHip,
            Joint::RightKnee,
            Joint::RightFoot,
        ),
    ] {
        let hip = add(hip_mid, side, HIP_HALF_WIDTH_M * sign);
        s.joints[hj as usize] = hip;
        s.confidence[hj as usize] = body.seen(hip, 0.5);
        if foot != NONE {
            let (mean, _) = geo.cap_mean(foot, cfg.hand_cap_m as f32);
            let f = inset(mean, cfg.hand_inset_m);
            s.joints[fj as usize] = f;
            s.confidence[fj as usize] = 0.8;
            let knee = add(hip, sub(f, hip), 0.5);
            s.joints[kj as usize] = knee;
            s.confidence[kj as usize] = body.seen(knee, 0.5).max(0.2);
        } else {
            let knee = add(hip, down, HIP_TO_KNEE_M);
            s.joints[kj as usize] = knee;
            s.confidence[kj as usize] = body.seen(knee, 0.3);
            s.joints[fj as usize] = add(knee, down, HIP_TO_KNEE_M);
            s.confidence[fj as usize] = 0.0;
        }
    }
}

/// Lateral band beside a head's top where the shoulders are \[m\] ...
const SHOULDER_BAND_M: [f64; 2] = [0.17, 0.26];
/// ... and where, for a body seen in profile (nothing in the band above),
/// the chest or the back are \[m\].
const PROFILE_BAND_M: [f64; 2] = [0.11, 0.17];
/// The shoulders are at least this far below the top of the head \[m\].
const HEAD_ABOVE_SHOULDERS_M: f64 = 0.12;

/// Whether the extremum `top` stands out like a head: on at least one side of
/// it (0.17-0.26 m across: the shoulders; 0.11-0.17 m in profile, when the
/// body has nothing that far out) the body's surface is at least 0.12 m
/// lower, and on no side is it level with the top (a box's corner, a flat
/// edge: level or no surface).
fn is_protrusion(geo: &Geodesic, top: u32, up: [f64; 3], side: [f64; 3]) -> bool {
    let t = geo.point(top);
    let th = dot(t, up);
    // highest point per side, in the shoulder band and in the profile band
    let mut shoulders = [f64::NEG_INFINITY; 2];
    let mut profile = [f64::NEG_INFINITY; 2];
    for n in 0..geo.len() {
        let p = geo.point(n as u32);
        let l = dot(sub(p, t), side);
        let a = l.abs();
        let k = usize::from(l > 0.0);
        if (SHOULDER_BAND_M[0]..=SHOULDER_BAND_M[1]).contains(&a) {
            shoulders[k] = shoulders[k].max(dot(p, up));
        } else if (PROFILE_BAND_M[0]..SHOULDER_BAND_M[0]).contains(&a) {
            profile[k] = profile[k].max(dot(p, up));
        }
    }
    let lower = |h: f64| h.is_finite() && th - h >= HEAD_ABOVE_SHOULDERS_M;
    let level = |h: f64| h.is_finite() && (th - h).abs() < 0.05;
    let band = if shoulders.iter().any(|h| h.is_finite()) {
        shoulders
    } else {
        profile
    };
    (lower(band[0]) || lower(band[1])) && !level(band[0]) && !level(band[1])
}
