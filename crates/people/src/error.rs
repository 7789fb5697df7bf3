//! Typed errors of the tracker: bad configuration or per-call input.

/// What the tracker rejects; it never panics on any frame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrackError {
    /// zero, negative or non-finite intrinsics, or an unusable image size
    #[error("camera intrinsics: {0}")]
    Intrinsics(String),
    /// a configuration value out of its range
    #[error("tracker configuration: {0}")]
    Config(String),
    /// a per-frame buffer of the wrong length
    #[error("{what}: {got} pixels, the {width}x{height} camera needs {expected}")]
    FrameSize {
        /// which buffer, e.g. the depth frame or the ignore mask
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
    /// a time step that is negative or not finite
    #[error("time step {0} s must be finite and >= 0")]
    TimeStep(f64),
}

/// Checks a per-frame buffer's length against the camera's pixel count.
pub(crate) fn check_len(
    what: &'static str,
    width: u32,
    height: u32,
    got: usize,
) -> Result<(), TrackError> {
    let expected = width as usize * height as usize;
    if got == expected {
        Ok(())
    } else {
        Err(TrackError::FrameSize {
            what,
            width,
            height,
            expected,
            got,
        })
    }
}
