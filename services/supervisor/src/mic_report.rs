//! The report's `voice.mic`: which microphone the cell heard through and
//! what it lost (`audio/mic/status`).

use phri_ipc::MicStatus;
use serde::Serialize;

/// `voice` in the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VoiceReport {
    /// the microphone (`voice.mic`)
    pub mic: MicReport,
}

/// `voice.mic` in the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MicReport {
    /// `sim` (the stand-in of `[audio]`) or `alsa`
    pub source: String,
    /// the ALSA capture device (`[mic] device`; the stand-in's: `sim`)
    pub device: String,
    /// the device's own rate \[Hz\] (0: no status arrived)
    pub device_rate_hz: u32,
    /// `audio/mic` chunks published (20 ms each)
    pub chunks: u64,
    /// capture overruns: sound lost because the device's buffer overflowed
    pub overruns: u64,
}

/// The microphone's figures so far, summed over its process's restarts.
#[derive(Clone, Debug, Default)]
pub struct MicEval {
    report: MicReport,
    latest: MicStatus,
    /// chunks and overruns of the processes before the newest
    before: (u64, u64),
}

impl MicEval {
    /// The microphone as configured.
    pub fn new(source: &str, device: &str) -> MicEval {
        MicEval {
            report: MicReport {
                source: source.to_string(),
                device: device.to_string(),
                ..MicReport::default()
            },
            ..MicEval::default()
        }
    }

    /// `phri-mic` said what it did.
    pub fn on_status(&mut self, m: &MicStatus) {
        if m.seq < self.latest.seq || m.chunks < self.latest.chunks {
            self.before.0 += self.latest.chunks;
            self.before.1 += self.latest.overruns;
        }
        self.latest = *m;
    }

    /// `voice` in the report: the chunks and overruns of every process so far.
    pub fn report(&self) -> VoiceReport {
        VoiceReport {
            mic: MicReport {
                device_rate_hz: self.latest.device_rate_hz,
                chunks: self.before.0 + self.latest.chunks,
                overruns: self.before.1 + self.latest.overruns,
                ..self.report.clone()
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_restarted_microphone_s_counts_add_up() {
        let mut e = MicEval::new("alsa", "hw:1,0");
        let st = |seq, chunks, overruns| MicStatus {
            seq,
            chunks,
            overruns,
            device_rate_hz: 48_000,
            source: 1,
            ..MicStatus::default()
        };
        e.on_status(&st(1, 50, 0));
        e.on_status(&st(2, 100, 2));
        e.on_status(&st(1, 10, 1)); // restarted
        let r = e.report().mic;
        assert_eq!((r.chunks, r.overruns, r.device_rate_hz), (110, 3, 48_000));
        assert_eq!((r.source.as_str(), r.device.as_str()), ("alsa", "hw:1,0"));
    }
}
