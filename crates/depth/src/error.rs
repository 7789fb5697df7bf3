//! Typed errors: configuration and per-call input checks ([`DepthError`]) and
//! depth-image files ([`DepthPngError`]).

use std::path::PathBuf;

/// Invalid camera or algorithm parameters, or per-call input that does not fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DepthError {
    #[error("camera intrinsics: {0}")]
    Intrinsics(String),
    #[error("camera pose: {0}")]
    Pose(String),
    #[error("{what}: {reason}")]
    Parameter { what: &'static str, reason: String },
    #[error("{what}: buffer has {got} pixels, the {width}x{height} camera needs {expected}")]
    FrameSize {
        what: &'static str,
        width: u32,
        height: u32,
        expected: usize,
        got: usize,
    },
    #[error("{what} {index}: {reason}")]
    Primitive {
        what: &'static str,
        index: usize,
        reason: &'static str,
    },
    #[error(
        "point of interest {index}: position or radius is not finite, or the radius is negative"
    )]
    PointOfInterest { index: usize },
    #[error("{what}: {got} entries for {expected} points of interest")]
    Count {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}

/// Checks that a per-frame buffer has exactly `width * height` pixels.
pub(crate) fn check_frame(
    what: &'static str,
    width: u32,
    height: u32,
    got: usize,
) -> Result<(), DepthError> {
    let expected = width as usize * height as usize;
    if got == expected {
        Ok(())
    } else {
        Err(DepthError::FrameSize {
            what,
            width,
            height,
            expected,
            got,
        })
    }
}

/// Reading or writing a 16-bit depth PNG failed; every variant names the file
/// (`"<memory>"` for in-memory data).
#[derive(Debug, thiserror::Error)]
pub enum DepthPngError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a valid PNG: {message}")]
    Decode { path: PathBuf, message: String },
    #[error("{path}: cannot encode PNG: {message}")]
    Encode { path: PathBuf, message: String },
    #[error("{path}: image is {width}x{height}, expected {expected_width}x{expected_height}")]
    Size {
        path: PathBuf,
        width: u32,
        height: u32,
        expected_width: u32,
        expected_height: u32,
    },
    #[error("{path}: {bits}-bit samples; a depth image must have 16-bit samples")]
    BitDepth { path: PathBuf, bits: u8 },
    #[error("{path}: colour type {color}; a depth image must be single-channel grayscale")]
    Color { path: PathBuf, color: String },
    #[error(
        "{path}: {bytes} bytes, more than the {max} a depth image of this size may have; not read"
    )]
    TooLarge { path: PathBuf, bytes: u64, max: u64 },
    #[error("{path}: a {width}x{height} image was asked for; depth images have 1 to {max} pixels")]
    Dimensions {
        path: PathBuf,
        width: u32,
        height: u32,
        max: u64,
    },
    #[error("{path}: not a regular file")]
    NotAFile { path: PathBuf },
    #[error("{path}: depth scale {scale} m per unit is not a positive finite number")]
    Scale { path: PathBuf, scale: f64 },
    #[error("{path}: {got} pixels given for a {width}x{height} image")]
    Buffer {
        path: PathBuf,
        width: u32,
        height: u32,
        got: usize,
    },
}
