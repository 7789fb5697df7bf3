//! JSON views of the messages, for the tools that print, record and replay
//! channels (`phri-monitor`, `phri-record`, `phri-replay`).
//!
//! The fields and their encoding come from the messages' serde derives (the
//! helpers of [`phri_ipc::json`]: non-finite floats as `null`, flags as
//! booleans, modes by name, ...). Here, the arrays each message lists in
//! [`Message::COUNTED`] are cut to their count (`q` to `dof`, `contacts` to
//! `n_contacts`, ...) and padded back with zeros when reading. Depth frames
//! are summarised ([`frame_json`]).

#![deny(missing_docs)]

use phri_ipc::{FrameHeader, Message};
use serde_json::{json, Map, Value};

/// A JSON value that is not the view of a message.
#[derive(Debug, thiserror::Error)]
pub enum JsonError {
    /// the value is not a JSON object
    #[error("{message}: not a JSON object")]
    NotAnObject {
        /// the message type's name, e.g. `JointState`
        message: &'static str,
    },
    /// a field of the wrong kind, or a value the message's decoder refused
    #[error("{message}: field '{field}': {detail}")]
    Field {
        /// the message type's name, e.g. `JointState`
        message: &'static str,
        /// the field's name
        field: String,
        /// what is wrong with its value
        detail: String,
    },
    /// the decoder refused the object and no single field could be blamed
    /// (e.g. a field missing)
    #[error("{message}: {source}")]
    Decode {
        /// the message type's name, e.g. `JointState`
        message: &'static str,
        /// the decoder's error
        #[source]
        source: serde_json::Error,
    },
}

/// The message type's name (`JointState`), for errors.
fn message_name<T>() -> &'static str {
    let full = std::any::type_name::<T>();
    full.rsplit("::").next().unwrap_or(full)
}

/// Every field, arrays whole.
fn full_view<T: Message>(m: &T) -> Map<String, Value> {
    match serde_json::to_value(m) {
        Ok(Value::Object(o)) => o,
        // the derives write a struct, with infallible helpers
        other => unreachable!("{} serialized as {other:?}", message_name::<T>()),
    }
}

/// The JSON view of a message: its fields by name, counted arrays cut to their count.
pub fn to_json<T: Message>(m: &T) -> Value {
    let mut v = full_view(m);
    for (count, arrays) in T::COUNTED {
        let n = v.get(*count).and_then(Value::as_u64).unwrap_or(0);
        let n = usize::try_from(n).unwrap_or(usize::MAX);
        for a in *arrays {
            if let Some(Value::Array(xs)) = v.get_mut(*a) {
                xs.truncate(n);
            }
        }
    }
    Value::Object(v)
}

/// A message back from its JSON view ([`to_json`]): counted arrays are
/// padded with zeros, a count larger than its arrays' entries is cut to them,
/// `null` floats become NaN (+inf for distances).
pub fn from_json<T: Message>(v: &Value) -> Result<T, JsonError> {
    let message = message_name::<T>();
    let mut obj = v
        .as_object()
        .ok_or(JsonError::NotAnObject { message })?
        .clone();
    let mut zero: Option<Map<String, Value>> = None;
    for (count, arrays) in T::COUNTED {
        let mut given = usize::MAX;
        for a in *arrays {
            match obj.get_mut(*a) {
                Some(Value::Array(xs)) => {
                    given = given.min(xs.len());
                    let zero = zero.get_or_insert_with(|| full_view(&T::zeroed()));
                    if let Some(Value::Array(z)) = zero.get(*a) {
                        if xs.len() < z.len() {
                            xs.extend_from_slice(&z[xs.len()..]);
                        }
                    }
                }
                Some(other) => {
                    return Err(JsonError::Field {
                        message,
                        field: a.to_string(),
                        detail: format!("expected an array, got {other}"),
                    })
                }
                // reported as missing by the decoder
                None => {}
            }
        }
        if let Some(c) = obj.get_mut(*count) {
            if c.as_u64().is_some_and(|n| n > given as u64) {
                *c = json!(given);
            }
        }
    }
    let obj = Value::Object(obj);
    T::deserialize(&obj).map_err(|source| {
        blame::<T>(&obj, &source.to_string()).unwrap_or(JsonError::Decode { message, source })
    })
}

/// The field whose value the decoder refused: the first one that, replaced
/// by a zeroed message's, lets the message decode (serde's errors do not
/// always name the field).
fn blame<T: Message>(obj: &Value, detail: &str) -> Option<JsonError> {
    let Value::Object(fields) = obj else {
        return None;
    };
    for (k, z) in full_view(&T::zeroed()) {
        if fields.get(&k).is_none_or(|x| *x == z) {
            continue;
        }
        let mut fixed = fields.clone();
        fixed.insert(k.clone(), z);
        if T::deserialize(&Value::Object(fixed)).is_ok() {
            return Some(JsonError::Field {
                message: message_name::<T>(),
                field: k,
                detail: detail.to_string(),
            });
        }
    }
    None
}

/// Summary of a depth frame: seq, size, valid pixels, depth range, latency.
pub fn frame_json(h: &FrameHeader, d: &[u16]) -> Value {
    let (mut valid, mut mn, mut mx) = (0usize, u16::MAX, 0u16);
    for &x in d.iter().filter(|&&x| x > 0) {
        valid += 1;
        mn = mn.min(x);
        mx = mx.max(x);
    }
    json!({
        "seq": h.seq, "width": h.width, "height": h.height, "pixels": d.len(),
        "bytes": d.len() * 2 + std::mem::size_of::<FrameHeader>(),
        "valid_pixels": valid, "removed_pixels": h.removed_pixels,
        "min_depth_mm": if valid > 0 { json!(mn) } else { Value::Null },
        "max_depth_mm": if valid > 0 { json!(mx) } else { Value::Null },
        "capture_to_published_ms": h.published_ns.saturating_sub(h.capture_wall_ns) as f64 * 1e-6,
    })
}
