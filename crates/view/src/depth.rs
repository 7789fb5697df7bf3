//! A depth frame (`perception/depth`: a [`FrameHeader`] and `width × height`
//! row-major `u16` depths) as viewers show it: its valid pixels
//! back-projected into packed points in the camera's optical frame (+x
//! right, +y down, +z along the optical axis, \[m\]), the camera's pose in the
//! robot's base frame, and the frame's time on phri's clock. Each viewer
//! wraps these in its own message (a Foxglove `PointCloud`, a ROS 2
//! `sensor_msgs/PointCloud2`).

use nalgebra::{Matrix3, Vector3};
use phri_ipc::FrameHeader;

/// Bytes per point: x, y, z as little-endian f32 \[m\], camera optical frame.
pub const POINT_STRIDE: usize = 12;

/// Whether the payload holds the `width × height` depths the header announces
/// (and that number is neither zero nor overflowing).
pub fn complete(h: &FrameHeader, depth: &[u16]) -> bool {
    let n = (h.width as usize).checked_mul(h.height as usize);
    n.is_some_and(|n| n > 0 && depth.len() >= n)
}

/// The frame's valid depths (non-zero), every `k`-th pixel per axis,
/// back-projected through the header's intrinsics (fx, fy, cx, cy \[px\],
/// `depth_scale` [m per unit]) and appended to `out` as packed points
/// ([`POINT_STRIDE`] bytes: x, y, z little-endian f32 \[m\], the camera's
/// optical frame). `false` (nothing appended) when the payload is short, `k`
/// is 0 or the intrinsics are unusable.
pub fn optical_points(h: &FrameHeader, depth: &[u16], k: usize, out: &mut Vec<u8>) -> bool {
    if k == 0 || !complete(h, depth) || !(h.fx > 0.0 && h.fy > 0.0 && h.depth_scale > 0.0) {
        return false;
    }
    let (w, ht) = (h.width as usize, h.height as usize);
    for v in (0..ht).step_by(k) {
        for u in (0..w).step_by(k) {
            let d = depth[v * w + u];
            if d == 0 {
                continue;
            }
            let z = f64::from(d) * h.depth_scale;
            let x = (u as f64 - h.cx) * z / h.fx;
            let y = (v as f64 - h.cy) * z / h.fy;
            for c in [x, y, z] {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
    }
    true
}

/// The camera's pose in the base frame from a frame header: the rotation
/// base ← camera optical frame (the header's row-major `pose_r`) and the
/// optical centre's position in the base frame \[m\].
pub fn camera_pose(h: &FrameHeader) -> (Matrix3<f64>, Vector3<f64>) {
    (
        Matrix3::from_row_slice(&h.pose_r),
        Vector3::new(h.pose_t[0], h.pose_t[1], h.pose_t[2]),
    )
}

/// The frame's time on phri's clock: its capture time, else its publish time
/// [ns, CLOCK_MONOTONIC].
pub fn stamp(h: &FrameHeader) -> u64 {
    if h.capture_wall_ns > 0 {
        h.capture_wall_ns
    } else {
        h.published_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn header() -> FrameHeader {
        let mut h = FrameHeader::zeroed();
        h.width = 4;
        h.height = 2;
        h.fx = 2.0;
        h.fy = 2.0;
        h.cx = 1.5;
        h.cy = 0.5;
        h.depth_scale = 0.001;
        h.pose_r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        h.pose_t = [1.0, 2.0, 3.0];
        h.capture_wall_ns = 5_000_000_007;
        h
    }

    fn floats(b: &[u8]) -> Vec<f32> {
        b.chunks(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    fn points(h: &FrameHeader, d: &[u16], k: usize) -> Option<Vec<f32>> {
        let mut out = Vec::new();
        optical_points(h, d, k, &mut out).then(|| floats(&out))
    }

    #[test]
    fn valid_pixels_become_points_in_the_optical_frame() {
        let h = header();
        // row 0: 1 m at u=0, nothing at u=1, 2 m at u=3; row 1: 0.5 m at u=2
        let d = [1000, 0, 0, 2000, 0, 0, 500, 0];
        let p = points(&h, &d, 1).expect("points");
        assert_eq!(p.len(), 9, "three points");
        // u=0, v=0, z=1: x = (0-1.5)/2, y = (0-0.5)/2
        assert_eq!(&p[..3], &[-0.75, -0.25, 1.0]);
        assert_eq!(&p[3..6], &[1.5, -0.5, 2.0]);
        assert_eq!(&p[6..], &[0.125, 0.125, 0.5]);
        // every other pixel: only (0,0) of the two kept per row is valid
        assert_eq!(points(&h, &d, 2).unwrap().len(), 3);
        // appended: what was in the buffer stays
        let mut out = vec![7u8];
        assert!(optical_points(&h, &d, 1, &mut out));
        assert_eq!((out[0], out.len()), (7, 1 + 3 * POINT_STRIDE));
    }

    #[test]
    fn short_payloads_and_bad_intrinsics_are_refused() {
        let h = header();
        assert!(complete(&h, &[1000; 8]));
        assert!(!complete(&h, &[1000; 7]));
        assert!(!complete(&FrameHeader::zeroed(), &[]), "no pixels");
        assert!(points(&h, &[1000; 7], 1).is_none());
        assert!(points(&h, &[1000; 8], 0).is_none());
        let mut bad = header();
        bad.fx = 0.0;
        let mut out = Vec::new();
        assert!(!optical_points(&bad, &[1000; 8], 1, &mut out));
        assert!(out.is_empty(), "nothing appended");
    }

    #[test]
    fn the_pose_and_the_stamp_come_from_the_header() {
        let mut h = header();
        h.pose_r = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let (r, t) = camera_pose(&h);
        assert_eq!(r[(0, 1)], -1.0, "row-major");
        assert_eq!(r[(1, 0)], 1.0);
        assert_eq!(t, Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(stamp(&h), 5_000_000_007, "the capture time");
        h.capture_wall_ns = 0;
        h.published_ns = 9;
        assert_eq!(stamp(&h), 9, "else the publish time");
    }
}
