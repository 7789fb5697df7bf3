//! Serde helpers for the messages' JSON view: the `#[serde(with = ...)]`
//! attributes of [`crate::messages`] point here. This is what the tools print
//! (`phri-monitor echo --json`) and record (`phri-record`), and what
//! `phri-replay` reads back, so it is part of the tools' contract:
//!
//! - floats: a non-finite value is `null` (JSON has no inf/NaN); `null` reads
//!   back as NaN ([`finite`], [`finite_array`]), or as +inf for distances
//!   ([`distance`]: no obstacle, no human)
//! - `u32` flags are booleans ([`flag`]); modes and kinds are their names
//!   ([`control_mode`], [`depth_fault_kind`]); an age of `u64::MAX` ("none") is
//!   `null` ([`opt_ns`]); a zero-padded name is a string ([`c_string`])
//! - the latency histogram is summarised, with its non-empty bins ([`latency_hist`])
//!
//! Arrays that hold only as many valid entries as a count field says (joint
//! arrays by `dof`, contacts by `n_contacts`, ...) are serialized whole here;
//! each message lists them in [`crate::Message::COUNTED`] and the tools cut
//! them (and pad them back when reading). Serde only: the JSON encoder is the
//! tools' (`phri-ipc-json`).

use std::fmt;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::ser::Serializer;
use serde::{Deserialize, Serialize};

/// `(count field, [array fields])`: the arrays hold `count` valid entries.
pub type Counted = (&'static str, &'static [&'static str]);

/// A float; non-finite as `null`, `null` read back as NaN.
pub mod finite {
    use super::*;

    /// Write `x`; `null` when it is not finite.
    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        x.is_finite().then_some(*x).serialize(s)
    }

    /// Read a number; `null` as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// A distance; non-finite as `null`, `null` read back as +inf (nothing there).
pub mod distance {
    use super::*;

    pub use super::finite::serialize;

    /// Read a number; `null` as +inf.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}

/// `[f64; N]`; each non-finite entry as `null` (read back as NaN). Reading
/// accepts up to `N` entries; the rest stay 0.
pub mod finite_array {
    use super::*;

    /// Write every entry; `null` for one that is not finite.
    pub fn serialize<S: Serializer, const N: usize>(a: &[f64; N], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(a.iter().map(|x| x.is_finite().then_some(*x)))
    }

    /// Read up to `N` numbers or `null`s (NaN); the entries not given stay 0,
    /// more than `N` is an error.
    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[f64; N], D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for V<N> {
            type Value = [f64; N];
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "an array of at most {N} numbers or nulls")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[f64; N], A::Error> {
                let mut out = [0.0; N];
                let mut n = 0;
                while let Some(x) = seq.next_element::<Option<f64>>()? {
                    if n == N {
                        return Err(de::Error::invalid_length(n + 1, &self));
                    }
                    out[n] = x.unwrap_or(f64::NAN);
                    n += 1;
                }
                Ok(out)
            }
        }
        d.deserialize_seq(V::<N>)
    }
}

/// A `u32` flag (1: set) as a boolean.
pub mod flag {
    use super::*;

    /// Write `true` for any non-zero value.
    pub fn serialize<S: Serializer>(v: &u32, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bool(*v != 0)
    }

    /// Read a boolean as 1 or 0.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
        Ok(bool::deserialize(d)? as u32)
    }
}

/// An age \[ns\] whose `u64::MAX` means "none": that is `null`.
pub mod opt_ns {
    use super::*;

    /// Write the age; `null` for `u64::MAX`.
    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        (*v != u64::MAX).then_some(*v).serialize(s)
    }

    /// Read an age; `null` as `u64::MAX`.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        Ok(Option::<u64>::deserialize(d)?.unwrap_or(u64::MAX))
    }
}

/// A wire enum's `u32` by name: an unknown value is written `"unknown"`, and
/// an unknown name is an error when reading.
macro_rules! by_name {
    ($(#[$meta:meta])* $module:ident, $enum:ident) => {
        $(#[$meta])*
        pub mod $module {
            use super::*;
            use crate::enums::$enum;

            /// Write the name of the value (`"unknown"` for one the enum lacks).
            pub fn serialize<S: Serializer>(v: &u32, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str($enum::name_of(*v))
            }

            /// Read a name as its wire value; an unknown name is an error.
            pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
                let name = String::deserialize(d)?;
                $enum::from_name(&name)
                    .map(u32::from)
                    .map_err(de::Error::custom)
            }
        }
    };
}

by_name!(
    /// [`crate::ControlMode`] as its name (`"task"`).
    control_mode,
    ControlMode
);
by_name!(
    /// [`crate::DepthFaultKind`] as its name (`"delay"`).
    depth_fault_kind,
    DepthFaultKind
);
by_name!(
    /// [`crate::RequestSource`] as its name (`"gesture"`).
    request_source,
    RequestSource
);
by_name!(
    /// [`crate::RequestKind`] as its name (`"follow"`).
    request_kind,
    RequestKind
);
by_name!(
    /// [`crate::CollabPart`] as its name (`"right_hand"`).
    collab_part,
    CollabPart
);
by_name!(
    /// [`crate::CollabPhase`] as its name (`"approach"`).
    collab_phase,
    CollabPhase
);
by_name!(
    /// [`crate::CollabReason`] as its name (`"wrist_push"`).
    collab_reason,
    CollabReason
);
by_name!(
    /// [`crate::ContactPhase`] as its name (`"begin"`).
    contact_phase,
    ContactPhase
);

by_name!(
    /// [`crate::VoiceIntent`] as its name (`"follow_left_hand"`).
    voice_intent,
    VoiceIntent
);
by_name!(
    /// [`crate::VoiceVerdict`] as its name (`"low_score"`).
    voice_verdict,
    VoiceVerdict
);

/// An `[i16; N]` (audio samples) as an array of numbers.
pub mod i16_array {
    use super::*;

    /// Write every sample as a number.
    pub fn serialize<S: Serializer, const N: usize>(a: &[i16; N], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(a.iter())
    }

    /// Read up to `N` samples; the samples not given stay 0, more than `N` is
    /// an error.
    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[i16; N], D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for V<N> {
            type Value = [i16; N];
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "an array of at most {N} 16-bit samples")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[i16; N], A::Error> {
                let mut out = [0; N];
                let mut n = 0;
                while let Some(x) = seq.next_element::<i16>()? {
                    if n == N {
                        return Err(de::Error::invalid_length(n + 1, &self));
                    }
                    out[n] = x;
                    n += 1;
                }
                Ok(out)
            }
        }
        d.deserialize_seq(V::<N>)
    }
}

/// The text of a zero-padded UTF-8 field (`"?"` when not UTF-8).
pub fn c_str<const N: usize>(b: &[u8; N]) -> String {
    c_str_ref(b).to_string()
}

/// The text of a zero-padded UTF-8 field, borrowed (`?` when not UTF-8).
pub fn c_str_ref<const N: usize>(b: &[u8; N]) -> &str {
    let end = b.iter().position(|&c| c == 0).unwrap_or(N);
    std::str::from_utf8(&b[..end]).unwrap_or("?")
}

/// `text` as a zero-padded UTF-8 field: cut on a character boundary so that
/// at least one NUL ends it (the inverse of [`c_str`]).
pub fn to_c_str<const N: usize>(text: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut n = text.len().min(N.saturating_sub(1));
    while !text.is_char_boundary(n) {
        n -= 1;
    }
    out[..n].copy_from_slice(&text.as_bytes()[..n]);
    out
}

/// A zero-padded UTF-8 name (`[u8; N]`) as a string (`"?"` when not UTF-8).
pub mod c_string {
    use super::*;

    /// Write the text up to its first NUL (`"?"` when not UTF-8).
    pub fn serialize<S: Serializer, const N: usize>(b: &[u8; N], s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(super::c_str_ref(b))
    }

    /// Read a string of at most `N` bytes, zero padded; a longer one is an
    /// error.
    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[u8; N], D::Error> {
        let text = String::deserialize(d)?;
        if text.len() > N {
            return Err(de::Error::custom(format_args!(
                "name '{text}' is longer than {N} bytes"
            )));
        }
        let mut out = [0u8; N];
        out[..text.len()].copy_from_slice(text.as_bytes());
        Ok(out)
    }
}

/// The latency histogram (`[u32; N]`, 1 µs bins): its total, its non-empty
/// range and, losslessly, its non-empty bins:
/// `{"bin_us": 1, "count": 12, "first_bin": 3, "last_bin": 9, "bins": [[3, 10], [9, 2]]}`
/// (`first_bin`/`last_bin` `null` when empty).
pub mod latency_hist {
    use super::*;
    use serde::ser::SerializeStruct;

    struct Bins<'a>(&'a [u32]);

    impl Serialize for Bins<'_> {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            s.collect_seq(
                self.0
                    .iter()
                    .enumerate()
                    .filter(|(_, &c)| c > 0)
                    .map(|(bin, &c)| (bin, c)),
            )
        }
    }

    /// Write the summary: `bin_us`, `count`, `first_bin`, `last_bin` and the
    /// non-empty `bins` as `[bin, count]` pairs.
    pub fn serialize<S: Serializer, const N: usize>(h: &[u32; N], s: S) -> Result<S::Ok, S::Error> {
        let count: u64 = h.iter().map(|&c| u64::from(c)).sum();
        let mut st = s.serialize_struct("LatencyHist", 5)?;
        st.serialize_field("bin_us", &1)?;
        st.serialize_field("count", &count)?;
        st.serialize_field("first_bin", &h.iter().position(|&c| c > 0))?;
        st.serialize_field("last_bin", &h.iter().rposition(|&c| c > 0))?;
        st.serialize_field("bins", &Bins(h))?;
        st.end()
    }

    #[derive(Deserialize)]
    struct Sparse {
        count: u64,
        bins: Vec<(usize, u32)>,
    }

    /// Read the non-empty bins back (the others 0); a bin past `N` − 1, or a
    /// `count` that is not the bins' total, is an error.
    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[u32; N], D::Error> {
        let sparse = Sparse::deserialize(d)?;
        let mut out = [0u32; N];
        for &(bin, c) in &sparse.bins {
            let slot = out.get_mut(bin).ok_or_else(|| {
                de::Error::custom(format_args!("latency bin {bin}: at most {}", N - 1))
            })?;
            *slot = c;
        }
        let total: u64 = out.iter().map(|&c| u64::from(c)).sum();
        if total != sparse.count {
            return Err(de::Error::custom(format_args!(
                "latency bins hold {total} samples, 'count' says {}",
                sparse.count
            )));
        }
        Ok(out)
    }
}

/// An array of zero bytes (the default of a byte blob left out of JSON).
pub fn zero_bytes<const N: usize>() -> [u8; N] {
    [0; N]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_fields_are_cut_on_a_character_boundary_and_end_in_a_nul() {
        let t: [u8; 64] = to_c_str(&"é".repeat(40));
        assert_eq!(c_str(&t), "é".repeat(31));
        assert_eq!(t[62..], [0, 0]);
        let t: [u8; 8] = to_c_str("stop");
        assert_eq!(c_str(&t), "stop");
        let t: [u8; 4] = to_c_str("abcdef");
        assert_eq!(c_str(&t), "abc");
    }
}
