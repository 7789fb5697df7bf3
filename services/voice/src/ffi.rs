//! The part of pocketsphinx 5prealpha's C API that phri uses, loaded at run
//! time from Debian's `libpocketsphinx3` (`libpocketsphinx.so.3`, with
//! `libsphinxbase.so.3`): nothing is needed to build phri, and a machine
//! without the library gets one clear error naming the package. (The
//! `pocketsphinx` crate binds an older API: `ps_start_utt` and `ps_get_hyp`
//! changed signature.)

use std::ffi::{c_char, c_void};

use libloading::Library;

use crate::error::VoiceError;

/// The Debian packages that provide the recogniser and its model.
pub const PACKAGES: &str = "libpocketsphinx-dev pocketsphinx-en-us";

/// `cmd_ln_t *`, `ps_decoder_t *`, `ps_seg_t *`: opaque.
pub type Ptr = *mut c_void;

/// The functions, resolved once; the libraries stay loaded while this lives.
pub struct Api {
    /// `ps_args()`: the decoder's argument definitions, for `cmd_ln_parse_r`
    pub ps_args: unsafe extern "C" fn() -> *const c_void,
    /// `cmd_ln_parse_r(inout, defn, argc, argv, strict)`: a configuration from
    /// command-line arguments (null: refused)
    pub cmd_ln_parse_r: unsafe extern "C" fn(Ptr, *const c_void, i32, *mut *mut c_char, i32) -> Ptr,
    /// `cmd_ln_free_r(config)`: release a configuration
    pub cmd_ln_free_r: unsafe extern "C" fn(Ptr) -> i32,
    /// `ps_init(config)`: a decoder (null: failed)
    pub ps_init: unsafe extern "C" fn(Ptr) -> Ptr,
    /// `ps_free(ps)`: release a decoder
    pub ps_free: unsafe extern "C" fn(Ptr) -> i32,
    /// `ps_add_word(ps, word, phones, update)`: add a word to the dictionary
    pub ps_add_word: unsafe extern "C" fn(Ptr, *const c_char, *const c_char, i32) -> i32,
    /// `ps_set_jsgf_string(ps, name, jsgf)`: a JSGF grammar as the search `name`
    pub ps_set_jsgf_string: unsafe extern "C" fn(Ptr, *const c_char, *const c_char) -> i32,
    /// `ps_set_search(ps, name)`: make the search `name` the active one
    pub ps_set_search: unsafe extern "C" fn(Ptr, *const c_char) -> i32,
    /// `ps_start_utt(ps)`: begin an utterance
    pub ps_start_utt: unsafe extern "C" fn(Ptr) -> i32,
    /// `ps_process_raw(ps, data, n_samples, no_search, full_utt)`: decode 16-bit
    /// samples
    pub ps_process_raw: unsafe extern "C" fn(Ptr, *const i16, usize, i32, i32) -> i32,
    /// `ps_end_utt(ps)`: end the utterance
    pub ps_end_utt: unsafe extern "C" fn(Ptr) -> i32,
    /// `ps_get_hyp(ps, out_best_score)`: the best hypothesis's words (null: none)
    pub ps_get_hyp: unsafe extern "C" fn(Ptr, *mut i32) -> *const c_char,
    /// `ps_seg_iter(ps)`: an iterator over the best hypothesis's word segments
    /// (null: none)
    pub ps_seg_iter: unsafe extern "C" fn(Ptr) -> Ptr,
    /// `ps_seg_next(seg)`: the next segment (null at the end, the iterator freed)
    pub ps_seg_next: unsafe extern "C" fn(Ptr) -> Ptr,
    /// `ps_seg_word(seg)`: the segment's word
    pub ps_seg_word: unsafe extern "C" fn(Ptr) -> *const c_char,
    /// `ps_seg_frames(seg, out_sf, out_ef)`: the segment's first and last frame
    pub ps_seg_frames: unsafe extern "C" fn(Ptr, *mut i32, *mut i32),
    /// `ps_seg_prob(seg, out_ascr, out_lscr, out_lback)`: the segment's acoustic
    /// and language scores and back-off; returns its posterior probability
    pub ps_seg_prob: unsafe extern "C" fn(Ptr, *mut i32, *mut i32, *mut i32) -> i32,
    _sphinxbase: Library,
    _pocketsphinx: Library,
}

fn open(name: &'static str) -> Result<Library, VoiceError> {
    // SAFETY: loading a shared library runs its initialisers; these are
    // Debian's sphinxbase/pocketsphinx, which only set up static tables
    unsafe { Library::new(name) }.map_err(|e| VoiceError::Library {
        name,
        message: e.to_string(),
    })
}

macro_rules! resolve {
    ($lib:expr, $name:ident) => {{
        // SAFETY: the type is the C prototype of 5prealpha's header
        // (pocketsphinx.h, ps_search.h, cmd_ln.h), checked by this crate's tests
        let s = unsafe { $lib.get(concat!(stringify!($name), "\0").as_bytes()) }.map_err(|e| {
            VoiceError::Library {
                name: stringify!($name),
                message: e.to_string(),
            }
        })?;
        *s
    }};
}

impl Api {
    /// Load the libraries and resolve every function.
    pub fn load() -> Result<Api, VoiceError> {
        let sb = open("libsphinxbase.so.3")?;
        let ps = open("libpocketsphinx.so.3")?;
        Ok(Api {
            ps_args: resolve!(ps, ps_args),
            cmd_ln_parse_r: resolve!(sb, cmd_ln_parse_r),
            cmd_ln_free_r: resolve!(sb, cmd_ln_free_r),
            ps_init: resolve!(ps, ps_init),
            ps_free: resolve!(ps, ps_free),
            ps_add_word: resolve!(ps, ps_add_word),
            ps_set_jsgf_string: resolve!(ps, ps_set_jsgf_string),
            ps_set_search: resolve!(ps, ps_set_search),
            ps_start_utt: resolve!(ps, ps_start_utt),
            ps_process_raw: resolve!(ps, ps_process_raw),
            ps_end_utt: resolve!(ps, ps_end_utt),
            ps_get_hyp: resolve!(ps, ps_get_hyp),
            ps_seg_iter: resolve!(ps, ps_seg_iter),
            ps_seg_next: resolve!(ps, ps_seg_next),
            ps_seg_word: resolve!(ps, ps_seg_word),
            ps_seg_frames: resolve!(ps, ps_seg_frames),
            ps_seg_prob: resolve!(ps, ps_seg_prob),
            _sphinxbase: sb,
            _pocketsphinx: ps,
        })
    }
}
