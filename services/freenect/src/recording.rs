//! fakenect recordings written from millimetre frames, for running the
//! service (or any libfreenect program) without a Kinect:
//! `fakenect DIR PROGRAM ARGS`.
//!
//! The format, as Debian's 0.5.3 fakenect reads it (`fakenect/fakenect.c`:
//! `sscanf(line, "%c-%lf-%u-%*s", …)` on each line of `INDEX.txt`):
//! - `DIR/INDEX.txt`: file names, one a line, played in order;
//! - a depth file `d-CURRENTTIME-TIMESTAMP.pgm`: CURRENTTIME the recording
//!   host's time \[s\] as a float (fakenect sleeps the difference between
//!   consecutive lines' times; it skips the first sleep while the previous
//!   time is 0, so times start at 1 s here), TIMESTAMP the device's 32-bit
//!   timestamp [60 MHz ticks] handed to the depth callback;
//! - its content: the line `P5 640 480 65535\n`, then 640×480 little-endian
//!   `u16` raw 11-bit disparity (fakenect skips the first line and copies
//!   the depth mode's 614400 bytes).
//!
//! At the end of `INDEX.txt` Debian's 0.5.3 fakenect does not loop: each
//! later event processing prints `Warning: No more lines in [DIR]` on
//! stdout and returns −1 (found by running it; newer upstream versions loop
//! by default).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::disparity::Disparity;
use crate::timestamps::TICK_HZ;
use crate::PIXELS;

/// The depth file's header line.
pub const PGM_HEADER: &[u8] = b"P5 640 480 65535\n";
/// CURRENTTIME of the first frame \[s\] (not 0: see the module's notes).
pub const START_TIME_S: f64 = 1.0;

/// A recording that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// a frame of the wrong size
    #[error("frame {frame}: {got} pixels ({expected} expected)")]
    Size {
        /// index of the frame
        frame: usize,
        /// its pixels
        got: usize,
        /// pixels of a frame (640×480)
        expected: usize,
    },
    /// a depth no raw disparity reads as
    #[error("frame {frame}, pixel {pixel}: {mm} mm is outside the Kinect's {lo}..={hi} mm")]
    OutOfRange {
        /// index of the frame
        frame: usize,
        /// index of the pixel in the frame, row-major
        pixel: usize,
        /// its depth \[mm\]
        mm: u16,
        /// the smallest depth a disparity reads as \[mm\]
        lo: u16,
        /// the largest depth a disparity reads as \[mm\]
        hi: u16,
    },
    /// a rate that is not a positive finite number of frames per second
    #[error("a frame rate of {0} Hz")]
    Rate(f64),
    /// the file system
    #[error("{path}: {source}")]
    Io {
        /// the file or directory
        path: PathBuf,
        /// the system's error
        source: std::io::Error,
    },
}

/// A depth file's name: `d-CURRENTTIME-TIMESTAMP.pgm` (time \[s\], 6
/// decimals, as libfreenect's recorder writes it; timestamp \[ticks\]).
pub fn depth_file_name(time_s: f64, timestamp: u32) -> String {
    format!("d-{time_s:.6}-{timestamp}.pgm")
}

/// A depth file's content from a millimetre frame (0: no reading).
pub fn depth_file(table: &Disparity, frame: usize, mm: &[u16]) -> Result<Vec<u8>, RecordingError> {
    if mm.len() != PIXELS {
        return Err(RecordingError::Size {
            frame,
            got: mm.len(),
            expected: PIXELS,
        });
    }
    let (lo, hi) = table.range_mm();
    let mut out = Vec::with_capacity(PGM_HEADER.len() + 2 * PIXELS);
    out.extend_from_slice(PGM_HEADER);
    for (pixel, &d) in mm.iter().enumerate() {
        if d != 0 && !(lo..=hi).contains(&d) {
            return Err(RecordingError::OutOfRange {
                frame,
                pixel,
                mm: d,
                lo,
                hi,
            });
        }
        out.extend_from_slice(&table.mm_to_raw(d).to_le_bytes());
    }
    Ok(out)
}

/// Write `frames` (640×480 depths \[mm\], 0: no reading) as a fakenect
/// recording into `dir` (created if missing), played at `rate_hz`, device
/// timestamps from `first_timestamp` \[ticks\] on (wrapping). Returns the
/// file names, in `INDEX.txt`'s order.
pub fn write_recording<F: AsRef<[u16]>>(
    dir: &Path,
    frames: &[F],
    rate_hz: f64,
    first_timestamp: u32,
) -> Result<Vec<String>, RecordingError> {
    if !(rate_hz > 0.0 && rate_hz.is_finite()) {
        return Err(RecordingError::Rate(rate_hz));
    }
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| RecordingError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let table = Disparity::new();
    let ticks_per_frame = (TICK_HZ as f64 / rate_hz).round() as u64;
    let mut names = Vec::with_capacity(frames.len());
    for (i, frame) in frames.iter().enumerate() {
        let time = START_TIME_S + i as f64 / rate_hz;
        let ts = (first_timestamp as u64).wrapping_add(i as u64 * ticks_per_frame) as u32;
        let name = depth_file_name(time, ts);
        let content = depth_file(&table, i, frame.as_ref())?;
        let path = dir.join(&name);
        std::fs::write(&path, content).map_err(io(&path))?;
        names.push(name);
    }
    let index = dir.join("INDEX.txt");
    let mut f = std::fs::File::create(&index).map_err(io(&index))?;
    for n in &names {
        writeln!(f, "{n}").map_err(io(&index))?;
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_fakenects_pattern() {
        assert_eq!(depth_file_name(1.0, 0), "d-1.000000-0.pgm");
        assert_eq!(
            depth_file_name(1.033333333, u32::MAX),
            "d-1.033333-4294967295.pgm"
        );
    }

    #[test]
    fn a_recording_has_its_index_and_raw_frames() {
        let dir = std::env::temp_dir().join(format!("phri-freenect-rec-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut a = vec![0u16; PIXELS];
        a[7] = 1000;
        let b = vec![1500u16; PIXELS];
        let names = write_recording(&dir, &[a, b], 30.0, u32::MAX - 1_000_000).unwrap();
        assert_eq!(
            names,
            ["d-1.000000-4293967295.pgm", "d-1.033333-999999.pgm"]
        );
        let index = std::fs::read_to_string(dir.join("INDEX.txt")).unwrap();
        assert_eq!(index, format!("{}\n{}\n", names[0], names[1]));
        let data = std::fs::read(dir.join(&names[0])).unwrap();
        assert_eq!(data.len(), PGM_HEADER.len() + 2 * PIXELS);
        assert!(data.starts_with(PGM_HEADER));
        let raw = |i: usize| {
            let o = PGM_HEADER.len() + 2 * i;
            u16::from_le_bytes([data[o], data[o + 1]])
        };
        let t = Disparity::new();
        assert_eq!(raw(0), 2047);
        assert_eq!(raw(7), t.mm_to_raw(1000));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn depths_out_of_range_or_frames_of_the_wrong_size_are_refused() {
        let t = Disparity::new();
        let mut f = vec![0u16; PIXELS];
        f[3] = 100;
        assert!(matches!(
            depth_file(&t, 2, &f),
            Err(RecordingError::OutOfRange {
                frame: 2,
                pixel: 3,
                ..
            })
        ));
        assert!(matches!(
            depth_file(&t, 0, &f[1..]),
            Err(RecordingError::Size { .. })
        ));
    }
}
