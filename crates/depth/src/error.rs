//! Typed errors: configuration and per-call input checks ([`DepthError`]) and
//! depth-image files ([`DepthPngError`]).

use std::path::PathBuf;

/// Invalid camera or algorithm parameters, or per-call input that does not fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DepthError {
    /// invalid [`crate::Intrinsics`]: image size, focal lengths or principal point
    #[error("camera intrinsics: {0}")]
    Intrinsics(String),
    /// a [`crate::CameraPose`] that cannot be built (e.g. `look_at` with eye on target)
    #[error("camera pose: {0}")]
    Pose(String),
    /// an algorithm's parameters out of range
    #[error("{what}: {reason}")]
    Parameter {
        /// whose parameters, e.g. `repulsion parameters` or `render options`
        what: &'static str,
        /// what is wrong with them
        reason: String,
    },
    /// a per-frame buffer whose length is not the camera's `width × height`
    #[error("{what}: buffer has {got} pixels, the {width}x{height} camera needs {expected}")]
    FrameSize {
        /// which buffer, e.g. `depth output`
        what: &'static str,
        /// the camera's image width \[px\]
        width: u32,
        /// the camera's image height \[px\]
        height: u32,
        /// pixels needed, `width × height`
        expected: usize,
        /// pixels the buffer has
        got: usize,
    },
    /// a capsule or box to render or filter that is not finite or not well formed
    #[error("{what} {index}: {reason}")]
    Primitive {
        /// the kind of primitive, e.g. `capsule`, `box` or `robot capsule`
        what: &'static str,
        /// its index in the slice given
        index: usize,
        /// what is wrong with it
        reason: &'static str,
    },
    /// a point of interest with a non-finite position or radius, or a negative radius
    #[error(
        "point of interest {index}: position or radius is not finite, or the radius is negative"
    )]
    PointOfInterest {
        /// its index in the slice given
        index: usize,
    },
    /// an output slice whose length is not the number of points of interest
    #[error("{what}: {got} entries for {expected} points of interest")]
    Count {
        /// which slice, e.g. `repulsion output`
        what: &'static str,
        /// entries needed: one per point of interest
        expected: usize,
        /// entries the slice has
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
    /// the file could not be opened, inspected or read
    #[error("{path}: cannot read: {source}")]
    Io {
        /// the file
        path: PathBuf,
        /// the operating system's error
        source: std::io::Error,
    },
    /// the file could not be written
    #[error("{path}: cannot write: {source}")]
    Write {
        /// the file
        path: PathBuf,
        /// the operating system's error
        source: std::io::Error,
    },
    /// not a PNG, a corrupt one, an interlaced one, or one that decodes short
    #[error("{path}: not a valid PNG: {message}")]
    Decode {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// what the header check or the decoder found
        message: String,
    },
    /// the encoder failed
    #[error("{path}: cannot encode PNG: {message}")]
    Encode {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the encoder's message
        message: String,
    },
    /// the image's size is not the one asked for
    #[error("{path}: image is {width}x{height}, expected {expected_width}x{expected_height}")]
    Size {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the image's width \[px\]
        width: u32,
        /// the image's height \[px\]
        height: u32,
        /// the width asked for \[px\]
        expected_width: u32,
        /// the height asked for \[px\]
        expected_height: u32,
    },
    /// samples of another bit depth than 16
    #[error("{path}: {bits}-bit samples; a depth image must have 16-bit samples")]
    BitDepth {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the image's bits per sample
        bits: u8,
    },
    /// not single-channel grayscale
    #[error("{path}: colour type {color}; a depth image must be single-channel grayscale")]
    Color {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the image's colour type, e.g. `Rgb`
        color: String,
    },
    /// a file larger than [`crate::png::max_png_bytes`] for its size; not read
    #[error(
        "{path}: {bytes} bytes, more than the {max} a depth image of this size may have; not read"
    )]
    TooLarge {
        /// the file
        path: PathBuf,
        /// its size \[bytes\]
        bytes: u64,
        /// the size allowed \[bytes\], [`crate::png::max_png_bytes`]
        max: u64,
    },
    /// a size asked for with no pixel or more than [`crate::png::MAX_PIXELS`]
    #[error("{path}: a {width}x{height} image was asked for; depth images have 1 to {max} pixels")]
    Dimensions {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the width asked for \[px\]
        width: u32,
        /// the height asked for \[px\]
        height: u32,
        /// the most pixels allowed, [`crate::png::MAX_PIXELS`]
        max: u64,
    },
    /// a directory, pipe or device rather than a regular file
    #[error("{path}: not a regular file")]
    NotAFile {
        /// the path
        path: PathBuf,
    },
    /// a depth scale that is not positive and finite
    #[error("{path}: depth scale {scale} m per unit is not a positive finite number")]
    Scale {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the scale given \[m per sample unit\]
        scale: f64,
    },
    /// a frame to write whose length is not `width × height`, or of zero size
    #[error("{path}: {got} pixels given for a {width}x{height} image")]
    Buffer {
        /// the file (`"<memory>"` for in-memory data)
        path: PathBuf,
        /// the width given \[px\]
        width: u32,
        /// the height given \[px\]
        height: u32,
        /// pixels in the frame given
        got: usize,
    },
}
