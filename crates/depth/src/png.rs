//! 16-bit grayscale PNG depth images (the Kinect driver and dataset convention,
//! e.g. TUM RGB-D), read into millimetre frames.
//!
//! A PNG sample value `s` means `s · scale` metres; the frame holds
//! `round(s · scale · 1000)` millimetres. Samples 0 stay 0 (no reading); depths
//! beyond 65.535 m (not representable) also become 0. Decoding never panics on
//! corrupt input: every failure is a [`DepthPngError`] naming the file.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use ::png::{BitDepth, ColorType, Decoder, Encoder, Limits};

use crate::error::DepthPngError;

/// Scale of Kinect driver (OpenNI/libfreenect registered) depth PNGs: 1 mm per unit.
pub const MILLIMETRE_SCALE_M: f64 = 0.001;
/// Scale of TUM RGB-D benchmark depth PNGs: 1/5000 m per unit.
pub const TUM_SCALE_M: f64 = 1.0 / 5000.0;

const MEMORY: &str = "<memory>";

/// Reads the 16-bit grayscale PNG at `path`, which must be `width × height`,
/// with `scale_m` metres per sample unit, into a row-major millimetre frame.
pub fn read_depth_png(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    scale_m: f64,
) -> Result<Vec<u16>, DepthPngError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| DepthPngError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode(path, &bytes, width, height, scale_m)
}

/// [`read_depth_png`] on PNG bytes in memory (errors name `<memory>`).
pub fn decode_depth_png(
    bytes: &[u8],
    width: u32,
    height: u32,
    scale_m: f64,
) -> Result<Vec<u16>, DepthPngError> {
    decode(Path::new(MEMORY), bytes, width, height, scale_m)
}

fn decode(
    path: &Path,
    bytes: &[u8],
    width: u32,
    height: u32,
    scale_m: f64,
) -> Result<Vec<u16>, DepthPngError> {
    let p = || path.to_path_buf();
    if !(scale_m.is_finite() && scale_m > 0.0) {
        return Err(DepthPngError::Scale {
            path: p(),
            scale: scale_m,
        });
    }
    let decode_err = |e: ::png::DecodingError| DepthPngError::Decode {
        path: p(),
        message: e.to_string(),
    };
    // the decoder may buffer the image plus a few rows: bound what it allocates
    let expected_bytes = width as usize * height as usize * 2;
    let limits = Limits {
        bytes: expected_bytes.saturating_mul(2).saturating_add(1 << 20),
    };
    let mut decoder = Decoder::new_with_limits(Cursor::new(bytes), limits);
    let info = decoder.read_header_info().map_err(decode_err)?;
    if info.width != width || info.height != height {
        return Err(DepthPngError::Size {
            path: p(),
            width: info.width,
            height: info.height,
            expected_width: width,
            expected_height: height,
        });
    }
    if info.color_type != ColorType::Grayscale {
        return Err(DepthPngError::Color {
            path: p(),
            color: format!("{:?}", info.color_type),
        });
    }
    if info.bit_depth != BitDepth::Sixteen {
        return Err(DepthPngError::BitDepth {
            path: p(),
            bits: info.bit_depth as u8,
        });
    }
    let mut reader = decoder.read_info().map_err(decode_err)?;
    let mut buf = vec![0u8; expected_bytes];
    let frame = reader.next_frame(&mut buf).map_err(decode_err)?;
    let data = buf
        .get(..frame.buffer_size())
        .filter(|d| d.len() == expected_bytes)
        .ok_or_else(|| DepthPngError::Decode {
            path: p(),
            message: format!(
                "decoded {} bytes, a {width}x{height} 16-bit image has {expected_bytes}",
                frame.buffer_size()
            ),
        })?;
    let to_mm = scale_m * 1000.0;
    let identity = to_mm == 1.0;
    Ok(data
        .chunks_exact(2)
        .map(|s| {
            let raw = u16::from_be_bytes([s[0], s[1]]);
            if identity {
                raw
            } else {
                let mm = (f64::from(raw) * to_mm).round();
                if mm <= 65535.0 {
                    mm as u16
                } else {
                    0
                }
            }
        })
        .collect())
}

/// Writes a `width × height` row-major millimetre frame as a 16-bit grayscale
/// PNG (1 mm per unit, [`MILLIMETRE_SCALE_M`]).
pub fn write_depth_png(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    depth_mm: &[u16],
) -> Result<(), DepthPngError> {
    let path = path.as_ref();
    let bytes = encode(path, width, height, depth_mm)?;
    std::fs::write(path, bytes).map_err(|source| DepthPngError::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// [`write_depth_png`] into PNG bytes in memory.
pub fn encode_depth_png(
    width: u32,
    height: u32,
    depth_mm: &[u16],
) -> Result<Vec<u8>, DepthPngError> {
    encode(Path::new(MEMORY), width, height, depth_mm)
}

fn encode(
    path: &Path,
    width: u32,
    height: u32,
    depth_mm: &[u16],
) -> Result<Vec<u8>, DepthPngError> {
    let p = || -> PathBuf { path.to_path_buf() };
    if depth_mm.len() != width as usize * height as usize || width == 0 || height == 0 {
        return Err(DepthPngError::Buffer {
            path: p(),
            width,
            height,
            got: depth_mm.len(),
        });
    }
    let encode_err = |e: ::png::EncodingError| DepthPngError::Encode {
        path: p(),
        message: e.to_string(),
    };
    let mut out = Vec::with_capacity(depth_mm.len() + 1024);
    {
        let mut encoder = Encoder::new(&mut out, width, height);
        encoder.set_color(ColorType::Grayscale);
        encoder.set_depth(BitDepth::Sixteen);
        let mut writer = encoder.write_header().map_err(encode_err)?;
        let data: Vec<u8> = depth_mm.iter().flat_map(|v| v.to_be_bytes()).collect();
        writer.write_image_data(&data).map_err(encode_err)?;
        writer.finish().map_err(encode_err)?;
    }
    Ok(out)
}
