//! A depth frame as Foxglove shows it: a `foxglove.PointCloud` in the base
//! frame (the camera's points, posed by the camera's pose in the frame
//! header) and a `foxglove.RawImage` (`16UC1`, millimetres), both downsampled
//! by `k` per axis (the top-left pixel of each block). The back-projection
//! itself is `phri-view`'s (`phri_view::depth`), shared with phri-ros2.

use foxglove::bytes::Bytes;
use foxglove::messages::{
    packed_element_field::NumericType, PackedElementField, PointCloud, RawImage,
};
use phri_ipc::FrameHeader;

use crate::geometry::{pose, rotation, timestamp};
use crate::{BASE_FRAME, CAMERA_FRAME};

use phri_view::depth::{camera_pose, complete, optical_points, stamp, POINT_STRIDE};

/// The frame's valid depths (non-zero) as points, every `k`-th pixel per
/// axis; the cloud's pose is the camera's, so the points stay in the optical
/// frame and the cloud sits in [`BASE_FRAME`]. `None` when the payload is
/// short, `k` is 0 or the intrinsics are unusable.
pub fn point_cloud(h: &FrameHeader, depth: &[u16], k: usize) -> Option<PointCloud> {
    let (w, ht) = (h.width as usize, h.height as usize);
    let mut data = Vec::with_capacity((w / k.max(1) + 1) * (ht / k.max(1) + 1) * POINT_STRIDE);
    if !optical_points(h, depth, k, &mut data) {
        return None;
    }
    let (r, t) = camera_pose(h);
    let field = |name: &str, offset: u32| PackedElementField {
        name: name.to_string(),
        offset,
        r#type: NumericType::Float32 as i32,
    };
    Some(PointCloud {
        timestamp: Some(timestamp(stamp(h))),
        frame_id: BASE_FRAME.to_string(),
        pose: Some(pose(&t, &rotation(&r))),
        point_stride: POINT_STRIDE as u32,
        fields: vec![field("x", 0), field("y", 4), field("z", 8)],
        data: Bytes::from(data),
    })
}

/// The frame as a `16UC1` image (millimetres, little endian, 0 = no
/// reading) in [`CAMERA_FRAME`], every `k`-th pixel per axis. `None` when the
/// payload is short or `k` is 0.
pub fn image(h: &FrameHeader, depth: &[u16], k: usize) -> Option<RawImage> {
    if k == 0 || !complete(h, depth) {
        return None;
    }
    let (w, ht) = (h.width as usize, h.height as usize);
    let (dw, dh) = (w.div_ceil(k), ht.div_ceil(k));
    let mut data = Vec::with_capacity(dw * dh * 2);
    for v in (0..ht).step_by(k) {
        for u in (0..w).step_by(k) {
            data.extend_from_slice(&depth[v * w + u].to_le_bytes());
        }
    }
    Some(RawImage {
        timestamp: Some(timestamp(stamp(h))),
        frame_id: CAMERA_FRAME.to_string(),
        width: dw as u32,
        height: dh as u32,
        encoding: "16UC1".to_string(),
        step: (dw * 2) as u32,
        data: Bytes::from(data),
    })
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

    #[test]
    fn valid_pixels_become_points_in_the_optical_frame() {
        let h = header();
        // row 0: 1 m at u=0, nothing at u=1, 2 m at u=3; row 1: 0.5 m at u=2
        let d = [1000, 0, 0, 2000, 0, 0, 500, 0];
        let c = point_cloud(&h, &d, 1).expect("a cloud");
        assert_eq!(c.frame_id, BASE_FRAME);
        assert_eq!(c.point_stride, 12);
        let p = floats(&c.data);
        assert_eq!(p.len(), 9, "three points");
        // u=0, v=0, z=1: x = (0-1.5)/2, y = (0-0.5)/2
        assert_eq!(&p[..3], &[-0.75, -0.25, 1.0]);
        assert_eq!(&p[3..6], &[1.5, -0.5, 2.0]);
        assert_eq!(&p[6..], &[0.125, 0.125, 0.5]);
        let origin = c.pose.unwrap().position.unwrap();
        assert_eq!((origin.x, origin.y, origin.z), (1.0, 2.0, 3.0));
        assert_eq!(c.timestamp.unwrap().sec(), 5);
        // every other pixel: only (0,0) of the two kept per row is valid
        let c2 = point_cloud(&h, &d, 2).unwrap();
        assert_eq!(floats(&c2.data).len(), 3);
    }

    #[test]
    fn the_image_keeps_millimetres_little_endian() {
        let h = header();
        let d = [0x0102, 1, 2, 3, 4, 5, 6, 0xa0b0];
        let im = image(&h, &d, 1).unwrap();
        assert_eq!((im.width, im.height, im.step), (4, 2, 8));
        assert_eq!(&im.data[..2], &[0x02, 0x01]);
        assert_eq!(&im.data[14..], &[0xb0, 0xa0]);
        let half = image(&h, &d, 2).unwrap();
        assert_eq!((half.width, half.height), (2, 1));
        assert_eq!(half.data.len(), 4);
        assert_eq!(half.frame_id, CAMERA_FRAME);
    }

    #[test]
    fn short_payloads_are_refused() {
        let h = header();
        assert!(point_cloud(&h, &[1000; 7], 1).is_none());
        assert!(image(&h, &[1000; 7], 1).is_none());
        assert!(image(&h, &[1000; 8], 0).is_none());
        let mut bad = header();
        bad.fx = 0.0;
        assert!(point_cloud(&bad, &[1000; 8], 1).is_none());
    }
}
