//! Depth frames as `foxglove.RawImage` (JSON encoding), so that Foxglove's
//! Image and 3D panels show a recording's depth images without a plugin.
//! Schema: <https://docs.foxglove.dev/docs/visualization/message-schemas/raw-image/>;
//! JSON bytes are base64 strings with `"contentEncoding": "base64"`.

use serde_json::{json, Value};

/// Schema name Foxglove recognises for raw images in JSON encoding.
pub const RAW_IMAGE: &str = "foxglove.RawImage";
/// `frame_id` of the depth images: the camera's optical frame
/// (+x right, +y down, +z along the optical axis).
pub const CAMERA_FRAME: &str = "camera";

/// Topic of the image view of a frame channel: `camera/depth` → `camera/depth/image`.
pub fn image_topic(frame_channel: &str) -> String {
    format!("{frame_channel}/image")
}

/// The JSON schema of `foxglove.RawImage` (the subset of fields Foxglove reads).
pub fn raw_image_schema() -> Vec<u8> {
    let time = json!({
        "type": "object",
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
        }
    });
    let schema = json!({
        "title": RAW_IMAGE,
        "type": "object",
        "properties": {
            "timestamp": time,
            "frame_id": {"type": "string"},
            "width": {"type": "integer", "minimum": 0},
            "height": {"type": "integer", "minimum": 0},
            "encoding": {"type": "string"},
            "step": {"type": "integer", "minimum": 0},
            "data": {"type": "string", "contentEncoding": "base64"}
        }
    });
    serde_json::to_vec(&schema).unwrap_or_default()
}

/// A `foxglove.RawImage` message of a depth image: `16UC1` little endian,
/// millimetres (0 = no reading), `width × height` pixels row-major.
/// `stamp_ns` is the capture time [ns, CLOCK_MONOTONIC].
pub fn raw_image_16uc1(stamp_ns: u64, width: usize, height: usize, mm: &[u16]) -> Value {
    let mut bytes = Vec::with_capacity(mm.len() * 2);
    for &d in mm {
        bytes.extend_from_slice(&d.to_le_bytes());
    }
    json!({
        "timestamp": {"sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000},
        "frame_id": CAMERA_FRAME,
        "width": width,
        "height": height,
        "encoding": "16UC1",
        "step": width * 2,
        "data": base64(&bytes),
    })
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            if i <= c.len() {
                s.push(B64[(n >> shift) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (raw, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(raw.as_bytes()), enc, "{raw:?}");
        }
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    #[test]
    fn image_has_little_endian_rows() {
        let v = raw_image_16uc1(3_000_000_001, 2, 1, &[0x0102, 0xa0b0]);
        assert_eq!(v["timestamp"]["sec"], 3);
        assert_eq!(v["timestamp"]["nsec"], 1);
        assert_eq!(v["step"], 4);
        assert_eq!(v["encoding"], "16UC1");
        assert_eq!(v["data"], base64(&[0x02, 0x01, 0xb0, 0xa0]));
    }
}
