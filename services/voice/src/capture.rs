//! A real microphone: ALSA capture (`phri-mic --source alsa`) cut into
//! `audio/mic` chunks, 16 kHz mono 16-bit, 20 ms, each with the
//! CLOCK_MONOTONIC time of its first sample.
//!
//! The device is opened by name (`arecord -L` lists them) and asked for
//! one channel (else the fewest it has, downmixed), S16_LE (else S32_LE or
//! FLOAT_LE, converted; any other format is refused, naming it) and
//! 16 kHz (else its nearest rate, converted by [`crate::resample`]).
//! Capture times: the read's completion time less the frames still in
//! the device's buffer (`snd_pcm_delay`). A device that delivers faster
//! than real time (ALSA's `file` plugin over `null`: a recording) is paced
//! to the wall clock rather than read as fast as it goes.
//!
//! An overrun (the device's buffer overflowed: `EPIPE` from a read) is
//! counted and the stream restarted (`snd_pcm_prepare`); any other error (a
//! device unplugged: `ENODEV`) ends the capture with [`CaptureError::Device`].

use alsa::pcm::{Access, Format, HwParams, PCM};
use alsa::{Direction, ValueOr};
use phri_ipc::{AUDIO_CHUNK_SAMPLES, AUDIO_RATE_HZ};

use crate::resample::Resampler;

/// Why the microphone could not be opened or read. One line each, naming the device.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// the device could not be opened
    #[error("ALSA capture device \"{device}\": cannot open it ({message}); `arecord -L` lists the devices")]
    Open {
        /// the device's ALSA name
        device: String,
        /// ALSA's error
        message: String,
    },
    /// the device offers none of the sample formats taken
    #[error("ALSA capture device \"{device}\": sample format {format} not supported (phri-mic takes S16_LE, S32_LE or FLOAT_LE)")]
    Format {
        /// the device's ALSA name
        device: String,
        /// the first other format it offers (`(none known)`: none phri-mic can name)
        format: String,
    },
    /// a hardware parameter could not be set
    #[error("ALSA capture device \"{device}\": cannot set {what} ({message})")]
    Params {
        /// the device's ALSA name
        device: String,
        /// the parameter, e.g. `the rate`
        what: &'static str,
        /// ALSA's error, or why the value is refused
        message: String,
    },
    /// a read failed, other than by an overrun (the device unplugged): the
    /// capture ends
    #[error("ALSA capture device \"{device}\": {message}; capture ended")]
    Device {
        /// the device's ALSA name
        device: String,
        /// ALSA's error
        message: String,
    },
}

/// The sample formats taken, best first.
const FORMATS: [Format; 3] = [Format::S16LE, Format::S32LE, Format::FloatLE];

/// Formats named in a refusal (the first the device offers).
const OTHER_FORMATS: [Format; 19] = [
    Format::U8,
    Format::S8,
    Format::S16BE,
    Format::U16LE,
    Format::U16BE,
    Format::S24LE,
    Format::S24BE,
    Format::S243LE,
    Format::S243BE,
    Format::S32BE,
    Format::U32LE,
    Format::FloatBE,
    Format::Float64LE,
    Format::Float64BE,
    Format::MuLaw,
    Format::ALaw,
    Format::ImaAdPCM,
    Format::U24LE,
    Format::IEC958SubframeLE,
];

/// Which of `FORMATS` the device gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleFormat {
    /// signed 16-bit little-endian (`S16_LE`)
    S16,
    /// signed 32-bit little-endian (`S32_LE`)
    S32,
    /// 32-bit float little-endian (`FLOAT_LE`)
    F32,
}

impl SampleFormat {
    /// The first format of `offered` (best first) that phri-mic takes.
    pub fn choose(offered: impl Fn(Format) -> bool) -> Option<SampleFormat> {
        FORMATS.iter().position(|&f| offered(f)).map(|i| match i {
            0 => SampleFormat::S16,
            1 => SampleFormat::S32,
            _ => SampleFormat::F32,
        })
    }

    /// ALSA's name of the format, e.g. `S16_LE`.
    pub fn name(self) -> &'static str {
        match self {
            SampleFormat::S16 => "S16_LE",
            SampleFormat::S32 => "S32_LE",
            SampleFormat::F32 => "FLOAT_LE",
        }
    }
}

/// Interleaved frames of `channels` → mono on the 16-bit scale (the
/// channels' mean), appended to `out`.
pub fn downmix<T: Copy>(
    frames: &[T],
    channels: usize,
    scale: impl Fn(T) -> f32,
    out: &mut Vec<f32>,
) {
    let channels = channels.max(1);
    let k = 1.0 / channels as f32;
    for f in frames.chunks_exact(channels) {
        out.push(f.iter().map(|&s| scale(s)).sum::<f32>() * k);
    }
}

/// Capture times of a stream of blocks: measured from the read's
/// completion, or, for a device running ahead of the wall clock, the
/// stream's own time (and how long to wait for it).
#[derive(Clone, Debug, Default)]
pub struct StreamClock {
    /// (device frame, its capture time [ns]) of the last block
    anchor: Option<(u64, u64)>,
}

/// A read up to this much later than the stream's own clock puts its block
/// is a reader held up (a loaded machine), not a device that fell behind:
/// the stream's clock stays \[ns\].
const LATE_READ_NS: f64 = 100e6;
/// The stream's clock follows such late reads by this fraction of their
/// lateness (a device slower than the wall clock is tracked, 100 ppm to
/// within 64 µs; a read 8 ms late moves the time by 0.25 ms).
const LATE_READ_SLEW: f64 = 1.0 / 32.0;

/// Frames at `rate` as nanoseconds.
fn frames_ns(frames: f64, rate: u32) -> f64 {
    frames * 1e9 / rate.max(1) as f64
}

impl StreamClock {
    /// Forget the time (the stream restarted after an overrun).
    pub fn reset(&mut self) {
        self.anchor = None;
    }

    /// A block of `frames` frames starting at device frame `first` was read
    /// at `done_ns` with `delay` frames still buffered: the capture time of
    /// its first frame, and when the block's end is due if the device ran
    /// ahead of the wall clock by more than `slack_ns` (wait until then). A
    /// read that comes late by up to 100 ms, or early by up to `slack_ns`,
    /// keeps the stream's own time, moved by 1/32 of the difference; beyond
    /// either, the time is measured afresh.
    pub fn block(
        &mut self,
        first: u64,
        frames: u64,
        rate: u32,
        done_ns: u64,
        delay: i64,
        slack_ns: u64,
    ) -> (u64, Option<u64>) {
        let behind = frames_ns(frames as f64 + delay.max(0) as f64, rate);
        let measured = (done_ns as f64 - behind).max(0.0) as u64;
        if let Some((f0, t0)) = self.anchor {
            // where the stream's own clock puts this block
            let nominal = t0 as f64 + frames_ns(first as f64 - f0 as f64, rate);
            let end = nominal + frames_ns(frames as f64, rate);
            if end > (done_ns + slack_ns) as f64 && nominal >= measured as f64 {
                let nominal = nominal as u64;
                self.anchor = Some((first, nominal));
                return (nominal, Some(end as u64));
            }
            // late < 0: the block's data was there before the stream's
            // clock put it (a paced recording read after a late wake-up, or
            // a device a little faster than the wall clock)
            let late = measured as f64 - nominal;
            if (-(slack_ns as f64)..=LATE_READ_NS).contains(&late) {
                let t = (nominal + late * LATE_READ_SLEW) as u64;
                self.anchor = Some((first, t));
                return (t, None);
            }
        }
        self.anchor = Some((first, measured));
        (measured, None)
    }

    /// The capture time of device frame `frame` (fractional), by the last block's anchor.
    pub fn time_of(&self, frame: f64, rate: u32) -> u64 {
        match self.anchor {
            Some((f0, t0)) => (t0 as f64 + frames_ns(frame - f0 as f64, rate)).max(0.0) as u64,
            None => 0,
        }
    }
}

/// The device's read buffer, in its format.
enum Buffer {
    S16(Vec<i16>),
    S32(Vec<i32>),
    F32(Vec<f32>),
}

/// An open ALSA capture stream, read as `audio/mic` chunks.
pub struct Capture {
    pcm: PCM,
    device: String,
    format: SampleFormat,
    channels: u32,
    rate: u32,
    buf: Buffer,
    mono: Vec<f32>,
    resampler: Resampler,
    /// 16 kHz samples made and not yet handed out
    out: Vec<i16>,
    /// device frames read since the start
    frames_in: u64,
    /// 16 kHz samples handed out since the start
    frames_out: u64,
    clock: StreamClock,
    /// capture overruns (sound lost)
    pub overruns: u64,
}

impl Capture {
    /// Open `device` for capture at 16 kHz (or the nearest rate it has).
    pub fn open(device: &str) -> Result<Capture, CaptureError> {
        Capture::open_at(device, AUDIO_RATE_HZ)
    }

    /// Open `device`, asking it for `rate` \[Hz\] (the nearest it has); the
    /// chunks are 16 kHz whatever the device's rate.
    pub fn open_at(device: &str, rate: u32) -> Result<Capture, CaptureError> {
        let dev = || device.to_string();
        let open = |e: alsa::Error| CaptureError::Open {
            device: dev(),
            message: e.to_string(),
        };
        let params = |what: &'static str| {
            move |e: alsa::Error| CaptureError::Params {
                device: device.to_string(),
                what,
                message: e.to_string(),
            }
        };
        // non-blocking: a read waits at most WAIT_MS (the caller's heartbeat)
        let pcm = PCM::new(device, Direction::Capture, true).map_err(open)?;
        let (format, channels, rate, block) = {
            let hwp = HwParams::any(&pcm).map_err(params("the hardware parameters"))?;
            hwp.set_access(Access::RWInterleaved)
                .map_err(params("interleaved access"))?;
            let Some(format) = SampleFormat::choose(|f| hwp.test_format(f).is_ok()) else {
                let format = OTHER_FORMATS
                    .iter()
                    .find(|&&f| hwp.test_format(f).is_ok())
                    .map_or_else(|| "(none known)".to_string(), |f| f.to_string());
                return Err(CaptureError::Format {
                    device: dev(),
                    format,
                });
            };
            hwp.set_format(FORMATS[format as usize])
                .map_err(params("the sample format"))?;
            let channels = hwp.set_channels_near(1).map_err(params("the channels"))?;
            // the device's own rate, not ALSA's conversion (`plughw:` still converts)
            let _ = hwp.set_rate_resample(false);
            let rate = hwp
                .set_rate_near(rate.max(1), ValueOr::Nearest)
                .map_err(params("the rate"))?;
            // 20 ms periods in a 200 ms buffer
            let period = (rate as i64 / 50).max(1);
            let _ = hwp.set_period_size_near(period, ValueOr::Nearest);
            let _ = hwp.set_buffer_size_near(period * 10);
            pcm.hw_params(&hwp)
                .map_err(params("the hardware parameters"))?;
            let period = hwp.get_period_size().unwrap_or(period).clamp(1, 1 << 16);
            (format, channels.max(1), rate, period as usize)
        };
        if rate == 0 {
            return Err(CaptureError::Params {
                device: dev(),
                what: "the rate",
                message: "the device reports 0 Hz".into(),
            });
        }
        let samples = block * channels as usize;
        let buf = match format {
            SampleFormat::S16 => Buffer::S16(vec![0; samples]),
            SampleFormat::S32 => Buffer::S32(vec![0; samples]),
            SampleFormat::F32 => Buffer::F32(vec![0.0; samples]),
        };
        let max_out = block * AUDIO_RATE_HZ as usize / rate as usize + 2;
        pcm.prepare().map_err(params("the stream (prepare)"))?;
        Ok(Capture {
            pcm,
            device: device.to_string(),
            format,
            channels,
            rate,
            buf,
            mono: Vec::with_capacity(block),
            resampler: Resampler::new(rate, AUDIO_RATE_HZ, block),
            out: Vec::with_capacity(AUDIO_CHUNK_SAMPLES + max_out + 1),
            frames_in: 0,
            frames_out: 0,
            clock: StreamClock::default(),
            overruns: 0,
        })
    }

    /// The device's own rate \[Hz\].
    pub fn device_rate(&self) -> u32 {
        self.rate
    }

    /// The channels the device delivers (downmixed to mono).
    pub fn channels(&self) -> u32 {
        self.channels
    }

    /// The sample format the device delivers.
    pub fn format(&self) -> SampleFormat {
        self.format
    }

    /// The device's ALSA name, as opened.
    pub fn device(&self) -> &str {
        &self.device
    }

    fn fail(&self, e: alsa::Error) -> CaptureError {
        CaptureError::Device {
            device: self.device.clone(),
            message: e.to_string(),
        }
    }

    /// Fill `chunk` with the next 20 ms at 16 kHz and return its first
    /// sample's capture time [ns, CLOCK_MONOTONIC]; `None` when the device
    /// had nothing within `wait_ms` (call again: the caller's heartbeat).
    pub fn next_chunk(
        &mut self,
        chunk: &mut [i16; AUDIO_CHUNK_SAMPLES],
        wait_ms: u32,
    ) -> Result<Option<u64>, CaptureError> {
        while self.out.len() < AUDIO_CHUNK_SAMPLES {
            if !self.read_block(wait_ms)? {
                return Ok(None);
            }
        }
        chunk.copy_from_slice(&self.out[..AUDIO_CHUNK_SAMPLES]);
        self.out.drain(..AUDIO_CHUNK_SAMPLES);
        // the chunk's first sample, on the device's frame scale
        let frame = self.frames_out as f64 * self.rate as f64 / AUDIO_RATE_HZ as f64;
        self.frames_out += AUDIO_CHUNK_SAMPLES as u64;
        Ok(Some(self.clock.time_of(frame, self.rate)))
    }

    /// Read one block into the 16 kHz output; false: nothing came in time.
    fn read_block(&mut self, wait_ms: u32) -> Result<bool, CaptureError> {
        let channels = self.channels as usize;
        let got = loop {
            let r = match &mut self.buf {
                Buffer::S16(b) => self.pcm.io_i16().and_then(|io| io.readi(b)),
                Buffer::S32(b) => self.pcm.io_i32().and_then(|io| io.readi(b)),
                Buffer::F32(b) => self.pcm.io_f32().and_then(|io| io.readi(b)),
            };
            match r {
                Ok(0) => {}
                Ok(n) => break n,
                Err(e) if e.errno() == libc_errno::EAGAIN => {}
                Err(e) if e.errno() == libc_errno::EINTR => continue,
                Err(e) if e.errno() == libc_errno::EPIPE => {
                    // overrun: sound lost; start again
                    self.overruns += 1;
                    self.clock.reset();
                    self.pcm.prepare().map_err(|e| self.fail(e))?;
                    continue;
                }
                Err(e) if e.errno() == libc_errno::ESTRPIPE => {
                    // suspended (the machine slept): resume, else restart
                    if self.pcm.resume().is_err() {
                        self.pcm.prepare().map_err(|e| self.fail(e))?;
                    }
                    self.clock.reset();
                    continue;
                }
                Err(e) => return Err(self.fail(e)),
            }
            // nothing buffered yet: wait for the device (at most wait_ms)
            match self.pcm.wait(Some(wait_ms)) {
                Ok(true) => continue,
                Ok(false) => return Ok(false),
                Err(e) if e.errno() == libc_errno::EPIPE || e.errno() == libc_errno::EINTR => {
                    continue
                }
                Err(e) => return Err(self.fail(e)),
            }
        };
        let done = phri_runtime::now_ns();
        let delay = self.pcm.delay().unwrap_or(0);
        let first = self.frames_in;
        self.frames_in += got as u64;
        // a device faster than real time (a recording) is paced: never spin
        let (_, due) = self
            .clock
            .block(first, got as u64, self.rate, done, delay, 5_000_000);
        if let Some(due) = due {
            phri_runtime::sleep_until_ns(due);
        }
        self.mono.clear();
        let n = got * channels;
        match &self.buf {
            Buffer::S16(b) => downmix(&b[..n], channels, |s| s as f32, &mut self.mono),
            Buffer::S32(b) => downmix(&b[..n], channels, |s| s as f32 / 65536.0, &mut self.mono),
            Buffer::F32(b) => downmix(
                &b[..n],
                channels,
                |s| if s.is_finite() { s * 32768.0 } else { 0.0 },
                &mut self.mono,
            ),
        }
        let out = &mut self.out;
        self.resampler.push(&self.mono, |y| {
            out.push(y.round().clamp(-32768.0, 32767.0) as i16)
        });
        Ok(true)
    }
}

/// The errno values ALSA's reads return (Linux).
mod libc_errno {
    pub const EINTR: i32 = 4;
    pub const EAGAIN: i32 = 11;
    pub const EPIPE: i32 = 32;
    pub const ESTRPIPE: i32 = 86;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_taken_best_first_and_others_refused() {
        assert_eq!(SampleFormat::choose(|_| true), Some(SampleFormat::S16));
        assert_eq!(
            SampleFormat::choose(|f| f == Format::FloatLE || f == Format::S32LE),
            Some(SampleFormat::S32)
        );
        assert_eq!(
            SampleFormat::choose(|f| f == Format::FloatLE),
            Some(SampleFormat::F32)
        );
        assert_eq!(SampleFormat::choose(|f| f == Format::U8), None);
        let e = CaptureError::Format {
            device: "hw:1,0".into(),
            format: Format::S243LE.to_string(),
        };
        let s = e.to_string();
        assert!(
            s.contains("\"hw:1,0\"") && s.contains("S24_3LE") && !s.contains('\n'),
            "{s}"
        );
    }

    #[test]
    fn channels_are_averaged_to_mono() {
        let mut out = Vec::new();
        downmix(&[100i16, 300, -50, 50, 7, 9], 2, |s| s as f32, &mut out);
        assert_eq!(out, [200.0, 0.0, 8.0]);
        out.clear();
        downmix(&[65536i32 * 1000], 1, |s| s as f32 / 65536.0, &mut out);
        assert_eq!(out, [1000.0]);
    }

    #[test]
    fn a_real_time_device_is_timed_by_its_reads_a_fast_one_is_paced() {
        let rate = 16_000;
        let mut c = StreamClock::default();
        // real time: 320 frames every 20 ms, 160 still buffered at each read
        let (t, wait) = c.block(0, 320, rate, 1_000_000_000, 160, 5_000_000);
        assert_eq!((t, wait), (1_000_000_000 - 30_000_000, None));
        let (t, wait) = c.block(320, 320, rate, 1_020_000_000, 160, 5_000_000);
        assert_eq!((t, wait), (1_000_000_000 - 10_000_000, None));
        // a recording: reads return at once, nothing buffered
        let mut c = StreamClock::default();
        let (t0, _) = c.block(0, 320, rate, 1_000_000_000, 0, 5_000_000);
        assert_eq!(t0, 980_000_000);
        let (t1, wait) = c.block(320, 320, rate, 1_000_001_000, 0, 5_000_000);
        assert_eq!(t1, 1_000_000_000);
        assert_eq!(wait, Some(1_020_000_000));
        // the frame times follow the anchor
        assert_eq!(c.time_of(480.0, rate), 1_010_000_000);
        // a reader held up 8 ms: the stream's time, all but 1/32 of it
        let (t2, wait) = c.block(640, 320, rate, 1_048_000_000, 0, 5_000_000);
        assert_eq!((t2, wait), (1_020_250_000, None));
        // a paced recording's reader that woke 15 ms after the block's end
        // was due: the block is 5 ms "early" against the stream's time,
        // which keeps all but 1/32 of it (no step back)
        let (t2b, wait) = c.block(960, 320, rate, 1_055_250_000, 0, 5_000_000);
        assert_eq!((t2b, wait), (1_040_250_000 - 156_250, None));
        // held up past 100 ms: measured afresh
        let (t3, _) = c.block(960, 320, rate, 1_200_000_000, 0, 5_000_000);
        assert_eq!(t3, 1_180_000_000);
        // an overrun starts the clock over from the reads
        c.reset();
        let (t, wait) = c.block(640, 320, rate, 5_000_000_000, 0, 5_000_000);
        assert_eq!((t, wait), (4_980_000_000, None));
    }
}
