//! The command recogniser: pocketsphinx in grammar (JSGF) mode with the
//! command grammar compiled in, and a score for what it heard.
//!
//! A closed grammar always answers with its nearest command, so every
//! hypothesis is scored: the same audio is decoded again through a free
//! loop of the model's phones, and the score is the command path's acoustic
//! log-likelihood minus the phone loop's, per 10 ms frame. Speech that is a
//! command fits the command about as well as (or better than, the loop pays
//! for every phone it inserts) any phone string; other speech forced onto a
//! command fits it worse. A score is in pocketsphinx's log units (base
//! 1.0001, scaled down by 2^10).

use std::ffi::{CStr, CString};
use std::path::Path;

use phri_config::VoiceConfig;
use phri_ipc::VoiceIntent;

use crate::error::VoiceError;
use crate::ffi::{Api, Ptr};

/// The commands (paper Sect. VI-A; "begin", not "start": the model hears
/// "start collaboration" as "stop", REFERENCE §4).
pub const GRAMMAR: &str = "#JSGF V1.0;\ngrammar phri;\npublic <command> = follow [the] (right | left) hand | begin collaboration | end collaboration | stop;\n";

/// The en-us model's phones (the phone loop's words are these, one each).
const PHONES: [&str; 39] = [
    "AA", "AE", "AH", "AO", "AW", "AY", "B", "CH", "D", "DH", "EH", "ER", "EY", "F", "G", "HH",
    "IH", "IY", "JH", "K", "L", "M", "N", "NG", "OW", "OY", "P", "R", "S", "SH", "T", "TH", "UH",
    "UW", "V", "W", "Y", "Z", "ZH",
];

const COMMANDS: &CStr = c"commands";
const PHONE_LOOP: &CStr = c"phones";

/// What one utterance decoded to.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// the words (empty: the grammar matched nothing)
    pub text: String,
    /// the command the words name ([`intent_of`])
    pub intent: VoiceIntent,
    /// command vs phone loop, acoustic log-likelihood per frame (0 when nothing matched)
    pub score: f64,
    /// 10 ms frames of the command's path
    pub frames: u32,
}

/// The command a hypothesis names.
pub fn intent_of(text: &str) -> VoiceIntent {
    let words: Vec<&str> = text.split_whitespace().collect();
    match words.as_slice() {
        ["follow", .., "right", "hand"] => VoiceIntent::FollowRightHand,
        ["follow", .., "left", "hand"] => VoiceIntent::FollowLeftHand,
        ["begin", "collaboration"] => VoiceIntent::Begin,
        ["end", "collaboration"] => VoiceIntent::End,
        ["stop"] => VoiceIntent::Stop,
        _ => VoiceIntent::None,
    }
}

/// One pocketsphinx decoder with the two searches.
pub struct Recognizer {
    api: Api,
    ps: Ptr,
    /// the audio with a ±1 LSB dither (digital silence breaks the front end's
    /// log energies), seeded per utterance: the same audio, the same answer
    dithered: Vec<i16>,
}

struct Path_ {
    acoustic: i64,
    frames: u32,
    words: Vec<String>,
}

impl Recognizer {
    /// Load pocketsphinx and the model named in `cfg`.
    pub fn new(cfg: &VoiceConfig) -> Result<Recognizer, VoiceError> {
        for (path, what) in [
            (&cfg.acoustic_model, "acoustic model"),
            (&cfg.dictionary, "dictionary"),
        ] {
            if !Path::new(path).exists() {
                return Err(VoiceError::Model {
                    path: path.into(),
                    what,
                });
            }
        }
        let api = Api::load()?;
        let args: Vec<CString> = [
            "-hmm",
            cfg.acoustic_model.as_str(),
            "-dict",
            cfg.dictionary.as_str(),
            "-samprate",
            "16000",
            "-logfn",
            "/dev/null",
        ]
        .iter()
        .map(|a| {
            CString::new(*a).map_err(|_| VoiceError::Decoder(format!("argument '{a}' holds a NUL")))
        })
        .collect::<Result<_, _>>()?;
        let mut argv: Vec<*mut std::ffi::c_char> =
            args.iter().map(|a| a.as_ptr() as *mut _).collect();
        // SAFETY: argv holds argc valid C strings that outlive the call (it copies them)
        let config = unsafe {
            (api.cmd_ln_parse_r)(
                std::ptr::null_mut(),
                (api.ps_args)(),
                argv.len() as i32,
                argv.as_mut_ptr(),
                1,
            )
        };
        if config.is_null() {
            return Err(VoiceError::Decoder(
                "the decoder's arguments were refused".into(),
            ));
        }
        // SAFETY: config is a valid cmd_ln_t; ps_init takes its own reference
        let ps = unsafe { (api.ps_init)(config) };
        // SAFETY: drop our reference (the decoder holds one)
        unsafe { (api.cmd_ln_free_r)(config) };
        if ps.is_null() {
            return Err(VoiceError::Decoder(format!(
                "cannot initialise with the model {}",
                cfg.acoustic_model
            )));
        }
        let r = Recognizer {
            api,
            ps,
            dithered: Vec::with_capacity(16_000 * 8),
        };
        r.searches()?;
        Ok(r)
    }

    fn searches(&self) -> Result<(), VoiceError> {
        let mut words = Vec::with_capacity(PHONES.len());
        for (i, p) in PHONES.iter().enumerate() {
            let word = CString::new(format!("phone_{}", p.to_lowercase())).expect("no NUL");
            let phone = CString::new(*p).expect("no NUL");
            let update = (i + 1 == PHONES.len()) as i32;
            // SAFETY: valid decoder and C strings
            if unsafe { (self.api.ps_add_word)(self.ps, word.as_ptr(), phone.as_ptr(), update) } < 0
            {
                return Err(VoiceError::Decoder(format!(
                    "cannot add the phone word for {p}"
                )));
            }
            words.push(word.into_string().expect("ASCII"));
        }
        let phone_loop = format!(
            "#JSGF V1.0;\ngrammar phones;\npublic <loop> = <phone>+;\n<phone> = {};\n",
            words.join(" | ")
        );
        for (name, g) in [(COMMANDS, GRAMMAR.to_string()), (PHONE_LOOP, phone_loop)] {
            let g = CString::new(g).expect("no NUL");
            // SAFETY: valid decoder and C strings
            if unsafe { (self.api.ps_set_jsgf_string)(self.ps, name.as_ptr(), g.as_ptr()) } < 0 {
                return Err(VoiceError::Decoder(format!(
                    "the grammar '{}' was refused",
                    name.to_string_lossy()
                )));
            }
        }
        Ok(())
    }

    /// Decode one utterance (16 kHz mono) and score it.
    pub fn decode(&mut self, audio: &[i16]) -> Result<Decoded, VoiceError> {
        self.dithered.clear();
        let mut x: u32 = 0x9E37_79B9;
        self.dithered.extend(audio.iter().map(|&s| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            s.saturating_add((x % 3) as i16 - 1)
        }));
        let command = self.run(COMMANDS)?;
        let text = command.words.join(" ");
        let intent = intent_of(&text);
        if intent == VoiceIntent::None || command.frames == 0 {
            return Ok(Decoded {
                text: String::new(),
                intent: VoiceIntent::None,
                score: 0.0,
                frames: 0,
            });
        }
        let phones = self.run(PHONE_LOOP)?;
        let score = (command.acoustic - phones.acoustic) as f64 / command.frames as f64;
        Ok(Decoded {
            text,
            intent,
            score,
            frames: command.frames,
        })
    }

    fn run(&mut self, search: &CStr) -> Result<Path_, VoiceError> {
        let api = &self.api;
        let ps = self.ps;
        let fail = |what: &str| VoiceError::Decoder(format!("{what} failed"));
        // SAFETY: valid decoder; the audio buffer outlives the calls
        unsafe {
            if (api.ps_set_search)(ps, search.as_ptr()) < 0 {
                return Err(fail("selecting the search"));
            }
            if (api.ps_start_utt)(ps) < 0 {
                return Err(fail("starting the utterance"));
            }
            if (api.ps_process_raw)(ps, self.dithered.as_ptr(), self.dithered.len(), 0, 1) < 0 {
                (api.ps_end_utt)(ps);
                return Err(fail("processing the audio"));
            }
            if (api.ps_end_utt)(ps) < 0 {
                return Err(fail("ending the utterance"));
            }
        }
        let mut path = Path_ {
            acoustic: 0,
            frames: 0,
            words: Vec::new(),
        };
        let mut best = 0i32;
        // SAFETY: valid decoder after an utterance
        let hyp = unsafe { (api.ps_get_hyp)(ps, &mut best) };
        if hyp.is_null() {
            return Ok(path);
        }
        // SAFETY: the iterator is walked to its end (ps_seg_next frees it there)
        unsafe {
            let mut seg = (api.ps_seg_iter)(ps);
            while !seg.is_null() {
                let (mut ascr, mut lscr, mut lback) = (0i32, 0i32, 0i32);
                (api.ps_seg_prob)(seg, &mut ascr, &mut lscr, &mut lback);
                let (mut sf, mut ef) = (0i32, 0i32);
                (api.ps_seg_frames)(seg, &mut sf, &mut ef);
                let w = (api.ps_seg_word)(seg);
                let word = if w.is_null() {
                    String::new()
                } else {
                    CStr::from_ptr(w).to_string_lossy().into_owned()
                };
                path.acoustic += ascr as i64;
                path.frames += (ef - sf + 1).max(0) as u32;
                // fillers and silences are part of the path, not words
                // ... and "the(2)" is the second pronunciation of "the"
                if !word.is_empty() && !word.starts_with('<') && !word.starts_with('[') {
                    let base = word.split('(').next().unwrap_or(&word);
                    if !base.is_empty() {
                        path.words.push(base.to_string());
                    }
                }
                seg = (api.ps_seg_next)(seg);
            }
        }
        Ok(path)
    }
}

impl Drop for Recognizer {
    fn drop(&mut self) {
        // SAFETY: the decoder was created by ps_init and is freed once
        unsafe { (self.api.ps_free)(self.ps) };
    }
}
