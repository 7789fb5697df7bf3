//! A streaming low-pass resampler: Kaiser-windowed sinc, polyphase, for
//! any pair of rates (a capture device's own rate to `audio/mic`'s 16 kHz).
//!
//! Output sample `o` is the band-limited input at input time
//! `o · in_rate / out_rate` (input samples since the stream's first): the
//! filter is centred, so the output is late by half the filter (its
//! latency, [`Resampler::latency_in`]) but never shifted in time; a
//! capture time maps through the rates alone. Before the first input the
//! stream is taken as silence.
//!
//! The cutoff is 0.45 × the lower of the two rates (90 % of its Nyquist
//! frequency), 24 zero crossings of the sinc each side, Kaiser β = 8
//! (stopband about −80 dB): going down to 16 kHz, content above 8 kHz is
//! removed, not folded into the speech band. The ratio is exact (reduced
//! by the rates' greatest common divisor); rates whose reduced ratio has
//! more than [`MAX_PHASES`] phases use the nearest of that many filter
//! phases (a timing error below 1/2048 of an input sample).
//!
//! Pure and allocation-free after [`Resampler::new`] (the history grows
//! once if a block longer than the one sized for arrives).

/// Filter phases kept at most (the table is phases × taps coefficients).
pub const MAX_PHASES: u64 = 1024;
/// Zero crossings of the windowed sinc on each side.
const ZERO_CROSSINGS: f64 = 24.0;
/// Cutoff as a fraction of the lower rate's Nyquist frequency.
const ROLLOFF: f64 = 0.9;
/// Kaiser window shape (about 80 dB of stopband attenuation).
const KAISER_BETA: f64 = 8.0;

/// Streaming sample-rate converter (mono).
#[derive(Clone, Debug)]
pub struct Resampler {
    in_rate: u32,
    out_rate: u32,
    /// reduced ratio: output `o` sits at input time `o · step_num / step_den`
    step_num: u64,
    step_den: u64,
    /// phases of the coefficient table
    phases: u64,
    /// taps per output sample (even)
    taps: usize,
    /// `phases` rows of `taps` coefficients; row p is the filter for a
    /// fractional position p / phases
    table: Vec<f32>,
    /// input history; `hist[0]` is absolute index `base` (absolute index
    /// `taps / 2` is the first real sample: silence before it)
    hist: Vec<f32>,
    base: u64,
    /// the next output's input position: integer part (absolute index of
    /// the real sample at or before it) and remainder over `step_den`
    pos_int: u64,
    pos_rem: u64,
    /// same rate: the input is the output
    bypass: bool,
}

/// Zeroth-order modified Bessel function of the first kind (series).
fn bessel_i0(x: f64) -> f64 {
    let mut sum = 1.0;
    let mut term = 1.0;
    let q = x * x / 4.0;
    for k in 1..64 {
        term *= q / (k as f64 * k as f64);
        sum += term;
        if term < sum * 1e-17 {
            break;
        }
    }
    sum
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

impl Resampler {
    /// A converter from `in_rate` to `out_rate` \[Hz\] (both > 0, else the
    /// input passes through unchanged), sized for input blocks of up to
    /// `max_block` samples.
    pub fn new(in_rate: u32, out_rate: u32, max_block: usize) -> Resampler {
        let bypass = in_rate == out_rate || in_rate == 0 || out_rate == 0;
        let (step_num, step_den) = if bypass {
            (1, 1)
        } else {
            let g = gcd(in_rate as u64, out_rate as u64);
            (in_rate as u64 / g, out_rate as u64 / g)
        };
        // the cutoff in cycles per input sample, and the half-width of the
        // window in input samples
        let fc = if bypass {
            0.5
        } else {
            0.5 * ROLLOFF * (out_rate as f64 / in_rate as f64).min(1.0)
        };
        let half = if bypass {
            1
        } else {
            (ZERO_CROSSINGS / (2.0 * fc)).ceil() as usize
        };
        let taps = 2 * half;
        let phases = step_den.min(MAX_PHASES);
        let mut table = Vec::new();
        if !bypass {
            table.reserve_exact(phases as usize * taps);
            let width = half as f64;
            for p in 0..phases {
                let frac = p as f64 / phases as f64;
                let row = table.len();
                // tap j multiplies input (i0 + j + 1 - half) for an output at i0 + frac
                for j in 0..taps {
                    let t = frac - (j as f64 + 1.0 - half as f64);
                    let x = 2.0 * fc * t;
                    let sinc = if x.abs() < 1e-12 {
                        1.0
                    } else {
                        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
                    };
                    let r = t / width;
                    let w = if r.abs() >= 1.0 {
                        0.0
                    } else {
                        bessel_i0(KAISER_BETA * (1.0 - r * r).sqrt()) / bessel_i0(KAISER_BETA)
                    };
                    table.push((2.0 * fc * sinc * w) as f32);
                }
                // unit gain at DC in every phase
                let sum: f32 = table[row..].iter().sum();
                if sum.abs() > 1e-6 {
                    for c in &mut table[row..] {
                        *c /= sum;
                    }
                }
            }
        }
        let mut hist = Vec::with_capacity(2 * taps + max_block + 1);
        hist.resize(half, 0.0);
        Resampler {
            in_rate,
            out_rate,
            step_num,
            step_den,
            phases,
            taps,
            table,
            hist,
            base: 0,
            pos_int: half as u64,
            pos_rem: 0,
            bypass,
        }
    }

    /// The input rate \[Hz\].
    pub fn in_rate(&self) -> u32 {
        self.in_rate
    }

    /// The output rate \[Hz\].
    pub fn out_rate(&self) -> u32 {
        self.out_rate
    }

    /// How far the output lags the input it represents [input samples]:
    /// an output is produced once this many samples after its time have arrived.
    pub fn latency_in(&self) -> usize {
        if self.bypass {
            0
        } else {
            self.taps / 2
        }
    }

    /// Feed `input`; `out` receives every output sample that the input so
    /// far completes, in order.
    pub fn push(&mut self, input: &[f32], mut out: impl FnMut(f32)) {
        if self.bypass {
            input.iter().for_each(|&x| out(x));
            return;
        }
        self.hist.extend_from_slice(input);
        let half = (self.taps / 2) as u64;
        let end = self.base + self.hist.len() as u64;
        let whole = self.step_num / self.step_den;
        let part = self.step_num % self.step_den;
        // output at pos_int + pos_rem/den needs inputs pos_int + 1 - half ..= pos_int + half
        while self.pos_int + half < end {
            // the nearest table phase (exact when the table has every phase)
            let scaled = self.pos_rem * self.phases;
            let mut p = (scaled + self.step_den / 2) / self.step_den;
            let mut i0 = self.pos_int;
            if p == self.phases {
                p = 0;
                i0 += 1;
            }
            if i0 + half < end {
                let first = (i0 + 1 - half - self.base) as usize;
                let row = &self.table[p as usize * self.taps..(p as usize + 1) * self.taps];
                let x = &self.hist[first..first + self.taps];
                let y: f32 = row.iter().zip(x).map(|(c, s)| c * s).sum();
                out(y);
            } else {
                // rounded up to the next sample, whose last tap has not arrived
                break;
            }
            self.pos_int += whole;
            self.pos_rem += part;
            if self.pos_rem >= self.step_den {
                self.pos_rem -= self.step_den;
                self.pos_int += 1;
            }
        }
        // drop what no later output needs
        let keep_from = (self.pos_int + 1).saturating_sub(half);
        if keep_from > self.base {
            let n = ((keep_from - self.base) as usize).min(self.hist.len());
            self.hist.drain(..n);
            self.base += n as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Amplitude and phase of `x` at `f` Hz (a rate of `rate`), by correlation.
    fn tone(x: &[f32], f: f64, rate: f64) -> f64 {
        let (mut s, mut c) = (0.0, 0.0);
        for (n, &v) in x.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f * n as f64 / rate;
            s += v as f64 * w.sin();
            c += v as f64 * w.cos();
        }
        2.0 * (s * s + c * c).sqrt() / x.len() as f64
    }

    fn rms(x: &[f32]) -> f64 {
        (x.iter().map(|&v| (v as f64).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
    }

    /// `seconds` of a sine of `f` Hz and amplitude `a` at `rate`, resampled
    /// to 16 kHz in blocks of `block`.
    fn run(rate: u32, f: f64, a: f64, seconds: f64, block: usize) -> Vec<f32> {
        let n = (rate as f64 * seconds) as usize;
        let x: Vec<f32> = (0..n)
            .map(|i| (a * (2.0 * std::f64::consts::PI * f * i as f64 / rate as f64).sin()) as f32)
            .collect();
        let mut r = Resampler::new(rate, 16_000, block);
        let mut y = Vec::new();
        for b in x.chunks(block) {
            r.push(b, |v| y.push(v));
        }
        y
    }

    #[test]
    fn a_1khz_tone_comes_out_at_1khz_with_its_amplitude() {
        for rate in [44_100, 48_000, 8_000, 22_050, 11_025, 96_000] {
            let y = run(rate, 1000.0, 10_000.0, 1.0, 441);
            // as many outputs as the time covered, less the filter's latency
            assert!(
                (y.len() as i64 - 16_000).abs() < 200,
                "{rate}: {} outputs",
                y.len()
            );
            // skip the filter's start-up from silence
            let steady = &y[200..y.len() - 10];
            let a = tone(steady, 1000.0, 16_000.0);
            assert!((a / 10_000.0 - 1.0).abs() < 0.005, "{rate}: amplitude {a}");
            // all of it is the 1 kHz tone: no other frequency, no distortion
            let rest = rms(steady) - a / 2f64.sqrt();
            assert!(rest.abs() < 20.0, "{rate}: {rest}");
            // other frequencies: little
            for f in [500.0, 2000.0, 3000.0] {
                assert!(tone(steady, f, 16_000.0) < 10.0, "{rate}: {f} Hz");
            }
        }
    }

    #[test]
    fn output_sample_o_is_the_input_at_its_time() {
        // a sine read at output index o must be the input's value at o · in/out
        let y = run(44_100, 440.0, 1.0, 0.5, 100);
        for o in [500usize, 1234, 3000, 7000] {
            let t = o as f64 / 16_000.0;
            let want = (2.0 * std::f64::consts::PI * 440.0 * t).sin();
            assert!(
                (y[o] as f64 - want).abs() < 1e-3,
                "o {o}: {} vs {want}",
                y[o]
            );
        }
    }

    #[test]
    fn content_above_8khz_is_removed_not_folded() {
        for rate in [44_100, 48_000, 32_000] {
            for f in [8_500.0, 10_000.0, 12_000.0, 15_000.0] {
                if f >= rate as f64 / 2.0 {
                    continue;
                }
                let y = run(rate, f, 10_000.0, 0.5, 512);
                let steady = &y[200..y.len() - 10];
                let r = rms(steady);
                // −60 dB relative to the tone's RMS (7071)
                assert!(r < 7.1, "{rate}: {f} Hz leaves RMS {r}");
            }
        }
    }

    #[test]
    fn the_block_size_does_not_change_the_output() {
        let a = run(44_100, 1234.0, 3000.0, 0.3, 1);
        let b = run(44_100, 1234.0, 3000.0, 0.3, 882);
        let c = run(44_100, 1234.0, 3000.0, 0.3, 13_230);
        assert_eq!(a.len(), b.len());
        assert_eq!(b.len(), c.len());
        assert!(a.iter().zip(&b).all(|(x, y)| x == y));
        assert!(b.iter().zip(&c).all(|(x, y)| x == y));
    }

    #[test]
    fn the_same_rate_passes_through_and_odd_rates_work() {
        let y = run(16_000, 1000.0, 1000.0, 0.1, 320);
        assert_eq!(y.len(), 1600);
        assert!(
            (y[17] as f64 - 1000.0 * (2.0 * std::f64::consts::PI * 17.0 / 16.0).sin()).abs() < 1e-3
        );
        // 44 056 Hz: 16 000 / gcd = 2000 phases, more than the table keeps
        let y = run(44_056, 1000.0, 10_000.0, 1.0, 441);
        let a = tone(&y[200..y.len() - 10], 1000.0, 16_000.0);
        assert!((a / 10_000.0 - 1.0).abs() < 0.005, "amplitude {a}");
    }

    #[test]
    fn the_history_stays_bounded() {
        let mut r = Resampler::new(48_000, 16_000, 960);
        let cap = r.hist.capacity();
        let block = vec![0.5f32; 960];
        for _ in 0..1000 {
            r.push(&block, |_| {});
        }
        assert_eq!(r.hist.capacity(), cap, "no reallocation");
        assert!(r.hist.len() <= r.taps + 960);
    }
}
