//! 16-bit grayscale PNG depth images (the Kinect driver and dataset convention,
//! e.g. TUM RGB-D), read into millimetre frames.
//!
//! A PNG sample value `s` means `s · scale` metres; the frame holds
//! `round(s · scale · 1000)` millimetres. Samples 0 stay 0 (no reading); depths
//! beyond 65.535 m (not representable) also become 0. Decoding never panics on
//! corrupt input: every failure is a [`DepthPngError`] naming the file.
//!
//! Reading a file is bounded before it costs anything: a file larger than
//! [`max_png_bytes`] (or not a regular file) is refused without being read,
//! and the PNG header (signature, `IHDR`: size, bit depth, colour type) is
//! checked from the first [`HEADER_BYTES`] before the image data is read.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use ::png::{BitDepth, ColorType, Decoder, Encoder, Limits};

use crate::error::DepthPngError;

/// Scale of Kinect driver (OpenNI/libfreenect registered) depth PNGs: 1 mm per unit.
pub const MILLIMETRE_SCALE_M: f64 = 0.001;
/// Scale of TUM RGB-D benchmark depth PNGs: 1/5000 m per unit.
pub const TUM_SCALE_M: f64 = 1.0 / 5000.0;

const MEMORY: &str = "<memory>";

/// Largest image accepted \[pixels\]: 4096 × 4096, far beyond a depth camera
/// (640×480 Kinect class, 1280×720 at most), so that no header makes the
/// reader allocate more than 32 MiB.
pub const MAX_PIXELS: u64 = 4096 * 4096;

/// Bytes of a PNG's start that hold everything [`check_header`] needs: the
/// 8-byte signature and the whole `IHDR` chunk (length, type, 13 bytes, CRC).
pub const HEADER_BYTES: usize = 33;

/// PNG signature.
const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// Largest file accepted for a `width × height` 16-bit image \[bytes\]: the raw
/// samples twice over (an incompressible image stored by zlib grows by a few
/// per mille; filter bytes add one per row) plus 1 MiB of ancillary chunks.
/// 640×480: 2.2 MB.
pub fn max_png_bytes(width: u32, height: u32) -> u64 {
    let raw = u64::from(width) * u64::from(height) * 2;
    raw * 2 + (1 << 20)
}

/// Check a PNG header (its first [`HEADER_BYTES`] or more): the signature,
/// `IHDR` first, `width × height`, 16-bit samples, single-channel grayscale,
/// not interlaced. Errors name `path`.
pub fn check_header(
    path: &Path,
    head: &[u8],
    width: u32,
    height: u32,
) -> Result<(), DepthPngError> {
    let p = || path.to_path_buf();
    let decode_err = |message: &str| DepthPngError::Decode {
        path: p(),
        message: message.to_string(),
    };
    if head.len() < HEADER_BYTES || head[..8] != SIGNATURE {
        return Err(decode_err("no PNG signature"));
    }
    if head[8..12] != [0, 0, 0, 13] || &head[12..16] != b"IHDR" {
        return Err(decode_err("the first chunk is not a 13-byte IHDR"));
    }
    let be32 = |i: usize| u32::from_be_bytes([head[i], head[i + 1], head[i + 2], head[i + 3]]);
    let (w, h) = (be32(16), be32(20));
    if w != width || h != height {
        return Err(DepthPngError::Size {
            path: p(),
            width: w,
            height: h,
            expected_width: width,
            expected_height: height,
        });
    }
    let (bits, color, interlace) = (head[24], head[25], head[28]);
    if color != 0 {
        let color = match color {
            2 => "Rgb".to_string(),
            3 => "Indexed".to_string(),
            4 => "GrayscaleAlpha".to_string(),
            6 => "Rgba".to_string(),
            c => format!("unknown ({c})"),
        };
        return Err(DepthPngError::Color { path: p(), color });
    }
    if bits != 16 {
        return Err(DepthPngError::BitDepth { path: p(), bits });
    }
    if interlace != 0 {
        return Err(decode_err("interlaced (a depth image is not)"));
    }
    Ok(())
}

/// Reads the 16-bit grayscale PNG at `path`, which must be `width × height`
/// (at most [`MAX_PIXELS`]), with `scale_m` metres per sample unit, into a
/// row-major millimetre frame. A file that is not a regular file or is larger
/// than [`max_png_bytes`] is refused without being read; the header is checked
/// ([`check_header`]) before the rest is read.
pub fn read_depth_png(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    scale_m: f64,
) -> Result<Vec<u16>, DepthPngError> {
    use std::io::Read;
    let path = path.as_ref();
    let io = |source| DepthPngError::Io {
        path: path.to_path_buf(),
        source,
    };
    check_pixels(path, width, height)?;
    // a directory, pipe or device is no image (a pipe would block the reader)
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(DepthPngError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    let max = max_png_bytes(width, height);
    if meta.len() > max {
        return Err(DepthPngError::TooLarge {
            path: path.to_path_buf(),
            bytes: meta.len(),
            max,
        });
    }
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(meta.len().min(max) as usize);
    // the header first: a wrong image costs 33 bytes
    (&mut file)
        .take(HEADER_BYTES as u64)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    check_header(path, &bytes, width, height)?;
    // the rest, bounded even if the file grew since its size was read
    file.take(max - HEADER_BYTES as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > max {
        return Err(DepthPngError::TooLarge {
            path: path.to_path_buf(),
            bytes: bytes.len() as u64,
            max,
        });
    }
    decode(path, &bytes, width, height, scale_m)
}

fn check_pixels(path: &Path, width: u32, height: u32) -> Result<(), DepthPngError> {
    let pixels = u64::from(width) * u64::from(height);
    if pixels == 0 || pixels > MAX_PIXELS {
        return Err(DepthPngError::Dimensions {
            path: path.to_path_buf(),
            width,
            height,
            max: MAX_PIXELS,
        });
    }
    Ok(())
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
    check_pixels(path, width, height)?;
    check_header(path, bytes, width, height)?;
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
