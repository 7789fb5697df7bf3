//! 16-bit depth PNGs: round trips, scales and corrupt input.

use phri_depth::png::{MILLIMETRE_SCALE_M, TUM_SCALE_M};
use phri_depth::{
    decode_depth_png, encode_depth_png, read_depth_png, write_depth_png, DepthPngError,
};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("phri-depth-{}-{name}", std::process::id()))
}

fn pattern(w: u32, h: u32) -> Vec<u16> {
    (0..w * h).map(|i| (i * 7919 % 65536) as u16).collect()
}

/// A PNG of any colour type and bit depth, written with the png crate directly.
fn png_bytes(
    w: u32,
    h: u32,
    color: ::png::ColorType,
    depth: ::png::BitDepth,
    data: &[u8],
) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut e = ::png::Encoder::new(&mut out, w, h);
        e.set_color(color);
        e.set_depth(depth);
        let mut wr = e.write_header().unwrap();
        wr.write_image_data(data).unwrap();
        wr.finish().unwrap();
    }
    out
}

#[test]
fn round_trip_through_a_file() {
    let (w, h) = (640, 480);
    let frame = pattern(w, h);
    let path = tmp("round_trip.png");
    write_depth_png(&path, w, h, &frame).unwrap();
    let back = read_depth_png(&path, w, h, MILLIMETRE_SCALE_M).unwrap();
    assert_eq!(back, frame);
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn tum_scale_converts_to_millimetres() {
    // TUM RGB-D: 5000 units per metre
    let raw: Vec<u16> = vec![0, 5000, 5002, 5003, 12_500, 65_535];
    let bytes = encode_depth_png(3, 2, &raw).unwrap();
    let mm = decode_depth_png(&bytes, 3, 2, TUM_SCALE_M).unwrap();
    // 5002/5 = 1000.4 → 1000, 5003/5 = 1000.6 → 1001, 65535/5 = 13107
    assert_eq!(mm, vec![0, 1000, 1000, 1001, 2500, 13_107]);
    // a scale that would exceed 65.535 m gives no reading, not a wrapped value
    let mm = decode_depth_png(&bytes, 3, 2, 0.002).unwrap();
    assert_eq!(mm, vec![0, 10_000, 10_004, 10_006, 25_000, 0]);
    assert!(matches!(
        decode_depth_png(&bytes, 3, 2, 0.0),
        Err(DepthPngError::Scale { .. })
    ));
    assert!(decode_depth_png(&bytes, 3, 2, f64::NAN).is_err());
}

#[test]
fn wrong_size_is_refused_naming_the_file() {
    let path = tmp("small.png");
    write_depth_png(&path, 4, 3, &pattern(4, 3)).unwrap();
    let err = read_depth_png(&path, 640, 480, MILLIMETRE_SCALE_M).unwrap_err();
    assert!(matches!(
        err,
        DepthPngError::Size {
            width: 4,
            height: 3,
            expected_width: 640,
            expected_height: 480,
            ..
        }
    ));
    let text = err.to_string();
    assert!(
        text.contains("small.png") && text.contains("4x3") && text.contains("640x480"),
        "{text}"
    );
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn eight_bit_and_colour_images_are_refused() {
    let gray8 = png_bytes(
        4,
        2,
        ::png::ColorType::Grayscale,
        ::png::BitDepth::Eight,
        &[7; 8],
    );
    let err = decode_depth_png(&gray8, 4, 2, MILLIMETRE_SCALE_M).unwrap_err();
    assert!(
        matches!(err, DepthPngError::BitDepth { bits: 8, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("16-bit"));
    let rgb16 = png_bytes(
        4,
        2,
        ::png::ColorType::Rgb,
        ::png::BitDepth::Sixteen,
        &[1; 48],
    );
    let err = decode_depth_png(&rgb16, 4, 2, MILLIMETRE_SCALE_M).unwrap_err();
    assert!(matches!(err, DepthPngError::Color { .. }), "{err}");
    assert!(err.to_string().contains("grayscale"));
    let ga16 = png_bytes(
        4,
        2,
        ::png::ColorType::GrayscaleAlpha,
        ::png::BitDepth::Sixteen,
        &[1; 32],
    );
    assert!(matches!(
        decode_depth_png(&ga16, 4, 2, MILLIMETRE_SCALE_M),
        Err(DepthPngError::Color { .. })
    ));
}

#[test]
fn corrupt_files_are_errors_not_panics() {
    let frame = pattern(64, 48);
    let good = encode_depth_png(64, 48, &frame).unwrap();
    assert_eq!(
        decode_depth_png(&good, 64, 48, MILLIMETRE_SCALE_M).unwrap(),
        frame
    );
    // every truncation
    for len in 0..good.len() - 1 {
        let r = decode_depth_png(&good[..len], 64, 48, MILLIMETRE_SCALE_M);
        // a file cut inside its final chunks may still hold the whole image
        if let Ok(img) = r {
            assert_eq!(img, frame, "truncated at {len}");
            assert!(
                len > good.len() - 20,
                "truncated at {len} of {}",
                good.len()
            );
        }
    }
    // garbage, and garbage behind a valid signature
    let mut state = 0x1234_5678u32;
    let mut noise = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state >> 24) as u8
    };
    for n in [1, 8, 100, 5000] {
        let junk: Vec<u8> = (0..n).map(|_| noise()).collect();
        assert!(decode_depth_png(&junk, 64, 48, MILLIMETRE_SCALE_M).is_err());
        let mut signed = good[..8].to_vec();
        signed.extend_from_slice(&junk);
        assert!(decode_depth_png(&signed, 64, 48, MILLIMETRE_SCALE_M).is_err());
    }
    // flipped bytes (CRC or zlib errors, or a header that no longer matches)
    for i in (8..good.len()).step_by(7) {
        let mut bad = good.clone();
        bad[i] ^= 0x5a;
        let _ = decode_depth_png(&bad, 64, 48, MILLIMETRE_SCALE_M);
    }
    // a header announcing a huge image is refused before any allocation
    let huge = encode_depth_png(1, 1, &[1]).unwrap();
    assert!(matches!(
        decode_depth_png(&huge, 640, 480, MILLIMETRE_SCALE_M),
        Err(DepthPngError::Size { .. })
    ));
}

#[test]
fn io_and_buffer_errors_name_the_file() {
    let missing = tmp("does-not-exist.png");
    let err = read_depth_png(&missing, 640, 480, MILLIMETRE_SCALE_M).unwrap_err();
    assert!(matches!(err, DepthPngError::Io { .. }));
    assert!(err.to_string().contains("does-not-exist.png"));
    let garbage = tmp("garbage.png");
    std::fs::write(&garbage, b"not a png at all").unwrap();
    let err = read_depth_png(&garbage, 640, 480, MILLIMETRE_SCALE_M).unwrap_err();
    assert!(matches!(err, DepthPngError::Decode { .. }));
    assert!(err.to_string().contains("garbage.png"), "{err}");
    std::fs::remove_file(&garbage).unwrap();
    let err = write_depth_png(tmp("short.png"), 640, 480, &[0; 10]).unwrap_err();
    assert!(matches!(err, DepthPngError::Buffer { got: 10, .. }));
    let err = write_depth_png("/nonexistent-dir/x.png", 1, 1, &[0]).unwrap_err();
    assert!(matches!(err, DepthPngError::Write { .. }));
    assert!(err.to_string().contains("/nonexistent-dir/x.png"));
}

/// A file holding `head`, then grown (sparse) to `len` bytes.
fn sized_file(name: &str, head: &[u8], len: u64) -> PathBuf {
    let path = tmp(name);
    std::fs::write(&path, head).unwrap();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&path)
        .unwrap()
        .set_len(len)
        .unwrap();
    path
}

#[test]
fn a_huge_file_is_refused_without_being_read() {
    let (w, h) = (640, 480);
    assert_eq!(
        phri_depth::png::max_png_bytes(w, h),
        2 * 614_400 + (1 << 20)
    );
    // a valid 640×480 16-bit header in front of 128 MB: the header is right,
    // the size is not (it spun ingestion at real-time priority)
    let good = encode_depth_png(w, h, &pattern(w, h)).unwrap();
    let path = sized_file("huge.png", &good[..64], 128 << 20);
    let err = read_depth_png(&path, w, h, MILLIMETRE_SCALE_M).unwrap_err();
    assert!(
        matches!(err, DepthPngError::TooLarge { bytes, .. } if bytes == 128 << 20),
        "{err}"
    );
    assert!(err.to_string().contains("huge.png"), "{err}");
    // just under the bound, it is read (and refused as a PNG: the rest is zeros)
    let max = phri_depth::png::max_png_bytes(w, h);
    std::fs::remove_file(&path).unwrap();
    let path = sized_file("just_under.png", &good[..64], max);
    assert!(matches!(
        read_depth_png(&path, w, h, MILLIMETRE_SCALE_M),
        Err(DepthPngError::Decode { .. })
    ));
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn the_header_is_checked_before_the_image_data_is_read() {
    let (w, h) = (640, 480);
    // headers of the wrong size, bit depth or colour, in front of 2 MB of
    // image data that would take milliseconds to inflate: refused by the header
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (
            encode_depth_png(320, 240, &pattern(320, 240)).unwrap(),
            "320x240",
        ),
        (
            png_bytes(
                w,
                h,
                ::png::ColorType::Grayscale,
                ::png::BitDepth::Eight,
                &vec![3; (w * h) as usize],
            ),
            "8-bit",
        ),
        (
            png_bytes(
                w,
                h,
                ::png::ColorType::Rgb,
                ::png::BitDepth::Sixteen,
                &vec![3; (w * h * 6) as usize],
            ),
            "Rgb",
        ),
    ];
    for (i, (bytes, needle)) in cases.iter().enumerate() {
        let path = tmp(&format!("header{i}.png"));
        std::fs::write(&path, bytes).unwrap();
        let err = read_depth_png(&path, w, h, MILLIMETRE_SCALE_M).unwrap_err();
        assert!(err.to_string().contains(needle), "{err}");
        // the same verdict from the first 33 bytes alone
        let from_header =
            phri_depth::png::check_header(&path, &bytes[..phri_depth::png::HEADER_BYTES], w, h)
                .unwrap_err();
        assert_eq!(from_header.to_string(), err.to_string());
        std::fs::remove_file(&path).unwrap();
    }
    let good = encode_depth_png(w, h, &pattern(w, h)).unwrap();
    phri_depth::png::check_header(std::path::Path::new("x"), &good, w, h).unwrap();
    // interlaced: byte 28 of the header (the CRC no longer matters: refused first)
    let mut interlaced = good[..33].to_vec();
    interlaced[28] = 1;
    assert!(
        phri_depth::png::check_header(std::path::Path::new("x"), &interlaced, w, h)
            .unwrap_err()
            .to_string()
            .contains("interlaced")
    );
}

#[test]
fn directories_devices_and_absurd_sizes_are_refused() {
    let dir = tmp("a-dir.png");
    std::fs::create_dir_all(&dir).unwrap();
    for path in [dir.as_path(), std::path::Path::new("/dev/zero")] {
        let err = read_depth_png(path, 640, 480, MILLIMETRE_SCALE_M).unwrap_err();
        assert!(matches!(err, DepthPngError::NotAFile { .. }), "{err}");
        assert!(err.to_string().contains(&path.display().to_string()));
    }
    std::fs::remove_dir_all(&dir).unwrap();
    for (w, h) in [(0, 480), (640, 0), (65_536, 65_536)] {
        let err = read_depth_png("/dev/zero", w, h, MILLIMETRE_SCALE_M).unwrap_err();
        assert!(matches!(err, DepthPngError::Dimensions { .. }), "{err}");
        assert!(matches!(
            decode_depth_png(&[0; 64], w, h, MILLIMETRE_SCALE_M),
            Err(DepthPngError::Dimensions { .. })
        ));
    }
}
