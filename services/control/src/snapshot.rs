//! The controller's behaviour state as bytes, for a hot standby: the
//! controller in charge saves it after each step
//! ([`crate::Controller::save_behaviour`]), the standby adopts it before its
//! next one ([`crate::Controller::adopt_behaviour`]) and, stepping the same
//! states, commands what the primary would have (bumpless transfer).
//!
//! The kit allocates nothing: a [`Writer`] over a caller's `&mut [u8]`, a
//! [`Reader`] over `&[u8]`, little-endian, `f64` as its bits (a round trip is
//! bit-exact). Neither panics: the writer counts the bytes a layout needs
//! beyond its buffer, the reader records where the bytes ran short or made
//! no sense, and the top level turns both into a [`SnapshotError`]. A reader
//! is either applying or a dry run ([`Reader::dry_run`]), which reads and
//! validates everything and writes nothing, so that an adoption checks the
//! whole snapshot before it changes anything.
//!
//! The layout is fixed for a configuration: an `Option` is a tag byte and
//! always its payload (the default's when `None`), a `Vec` its length and
//! elements (its length must match the receiver's), so that the byte length
//! and a fingerprint of the sizes the configuration sets (joints, control
//! points, collaboration, speed and separation monitoring, waypoints, the
//! path history's room) in the header refuse another configuration's
//! snapshot before anything is read. Settings that change no size (gains,
//! limits, waypoints' positions) are not checked: the peer is assumed to
//! run the same configuration file.
//!
//! # What is in it
//!
//! Everything carried from one period to the next that shapes later
//! commands (or the controller's reports): the mode, the controller's
//! time, the last state stamp, the recover timer, the segment a
//! collaboration waits for, the null-space posture, the counters, the
//! velocity estimator (its last `q` and filtered `q̇`), the safety monitor,
//! the resolver (filtered repulsion per control point, the behind-the-hand
//! hysteresis, the task scale, the speed and separation monitor's
//! sightings, speeds and timers, its counters, the path's pace the barrier
//! filter let through and the filter's warm start), the joint reference, the
//! path history's entry count, the task (path time, ramp, segment,
//! approach, counts), the reaction (start time, retreat progress), the
//! collaboration (the phase machine, hand and other-hand filters and
//! sightings, the desired end effector, gaps, contact point, wrist timer,
//! collision and re-arm state, the last answer, back-off), the restart
//! hold and this period's hold.
//!
//! # What is left out, and why
//!
//! - The path history's entries (seconds of joint references, far larger
//!   than the rest): each controller records its own from the same states;
//!   only the peer's entry count travels, and the adopter keeps its newest
//!   `min(peer's, own)` entries. A standby adopting every period records the
//!   primary's entries from its first adoption on; a standby that adopted
//!   once, or started less than a retreat's span ago, retreats along its own
//!   (shorter) record.
//! - Configuration: gains, limits, paths, the model, copies of `[control]`,
//!   `[collaboration]`, `[ssm]`.
//! - What every period recomputes before reading it: the model terms, the
//!   kinematics caches, the end effector, the acceleration and torque, the
//!   SNS and body-task buffers (the solver keeps nothing from one solve to
//!   the next), CLIK's velocity, the force estimate and the force
//!   estimator's kinematics cache. The model terms keep their last good
//!   value when a model call fails: after such a failure right after an
//!   adoption the standby holds its own last good value.
//! - The body task's count of rows dropped for lack of room (reported
//!   nowhere in the controller's messages, shapes no command).

use nalgebra::Vector3;
use phri_ipc::{CollabPart, CollabPhase, CollabReason, ControlMode, HriRequest, MAX_DOF};

/// Room for a behaviour snapshot: the bytes of `control/behaviour`
/// ([`phri_ipc::ControlBehaviour`]). The default configurations
/// (collaboration and speed and separation monitoring on) need 2788 bytes
/// for the LWR-IV (16 control points) and 2460 for the FR3 (12); each
/// control point takes 82 bytes, each joint 56.
pub const BEHAVIOUR_BYTES: usize = phri_ipc::BEHAVIOUR_BYTES;

/// `"PHRB"` little-endian: a behaviour snapshot.
const MAGIC: u32 = u32::from_le_bytes(*b"PHRB");

/// The layout's version: changes whenever a field is added, removed or moved.
pub const VERSION: u32 = 2;

/// The header: magic, version, total length, joints (u32 each), fingerprint (u64) \[bytes\].
pub const HEADER_BYTES: usize = 24;

/// Why a snapshot could not be saved or adopted. An adoption that fails
/// changes nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SnapshotError {
    /// the buffer is too small for the behaviour state
    #[error("behaviour snapshot: needs {need} bytes, the buffer holds {have}")]
    BufferTooSmall {
        /// bytes the behaviour state needs
        need: usize,
        /// bytes the buffer holds
        have: usize,
    },
    /// fewer bytes than the header (or, after it, its length) announces
    #[error("behaviour snapshot: {have} bytes, {need} expected")]
    Truncated {
        /// bytes expected: the header's, or the length it announces
        need: usize,
        /// bytes given
        have: usize,
    },
    /// not a behaviour snapshot
    #[error("behaviour snapshot: bad magic {got:#010x}")]
    Magic {
        /// the first four bytes, little-endian
        got: u32,
    },
    /// another layout version
    #[error("behaviour snapshot: version {got}, this controller reads version {expected}")]
    Version {
        /// the version this controller reads ([`VERSION`])
        expected: u32,
        /// the snapshot's version
        got: u32,
    },
    /// a controller of another robot
    #[error("behaviour snapshot: from a controller of {got} joints, this one has {expected}")]
    Dof {
        /// this controller's joints
        expected: u32,
        /// the snapshot's joints
        got: u32,
    },
    /// a controller of another configuration (control points, collaboration, …)
    #[error(
        "behaviour snapshot: another configuration's layout ({got_bytes} bytes, \
         fingerprint {got:#018x}; this controller's: {expected_bytes} bytes, {expected:#018x})"
    )]
    Layout {
        /// this controller's fingerprint of its configuration's sizes
        expected: u64,
        /// the snapshot's fingerprint
        got: u64,
        /// this controller's snapshot length \[bytes\]
        expected_bytes: usize,
        /// the snapshot's length, as its header says \[bytes\]
        got_bytes: usize,
    },
    /// a value that makes no sense (an unknown enum value or tag, a length
    /// or index that does not fit), at this byte offset
    #[error("behaviour snapshot: malformed at byte {at}")]
    Malformed {
        /// byte offset of the value at fault, from the snapshot's start
        at: usize,
    },
}

/// Writes little-endian values into a caller's buffer. Past its end it
/// writes nothing and only counts: [`Writer::len`] is what the layout needs.
pub struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl<'a> Writer<'a> {
    /// A writer at the start of `buf`.
    pub fn new(buf: &'a mut [u8]) -> Writer<'a> {
        Writer { buf, pos: 0 }
    }

    /// Append `b` as it is (past the buffer's end: only counted).
    pub fn bytes(&mut self, b: &[u8]) {
        let end = self.pos + b.len();
        if let Some(dst) = self.buf.get_mut(self.pos..end) {
            dst.copy_from_slice(b);
        }
        self.pos = end;
    }

    /// Append a byte.
    pub fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }

    /// Append a `u32`, little-endian.
    pub fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }

    /// Append a `u64`, little-endian.
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }

    /// Append an `f64` as its bits (a `u64`).
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }

    /// Append a `bool` as a byte 0 or 1.
    pub fn bool(&mut self, v: bool) {
        self.u8(u8::from(v));
    }

    /// Bytes written, or needed when more than the buffer holds.
    pub fn len(&self) -> usize {
        self.pos
    }

    /// Nothing written yet.
    pub fn is_empty(&self) -> bool {
        self.pos == 0
    }

    /// The layout did not fit the buffer.
    pub fn overflowed(&self) -> bool {
        self.pos > self.buf.len()
    }
}

/// Reads little-endian values. Short of bytes, or on a value that makes no
/// sense ([`Reader::fail`]), it records where and reads zeros from then on.
/// A dry run ([`Reader::dry_run`]) stores nothing: see [`Reader::store`].
pub struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    /// where the last value read began
    at: usize,
    fault: Option<usize>,
    apply: bool,
}

impl<'a> Reader<'a> {
    /// A reader that loads what it reads.
    pub fn new(buf: &'a [u8]) -> Reader<'a> {
        Reader {
            buf,
            pos: 0,
            at: 0,
            fault: None,
            apply: true,
        }
    }

    /// A reader that validates what it reads and stores nothing.
    pub fn dry_run(buf: &'a [u8]) -> Reader<'a> {
        Reader {
            apply: false,
            ..Reader::new(buf)
        }
    }

    /// Loads store what they read: not a dry run, and no fault so far.
    pub fn applying(&self) -> bool {
        self.apply && self.fault.is_none()
    }

    /// `*dst = v` when [`Reader::applying`]; the one way a load changes its receiver.
    pub fn store<T>(&self, dst: &mut T, v: T) {
        if self.applying() {
            *dst = v;
        }
    }

    /// The value just read makes no sense: a fault where it began.
    pub fn fail(&mut self) {
        self.fault.get_or_insert(self.at);
    }

    /// Where the first fault was (byte offset of the value), if any.
    pub fn fault(&self) -> Option<usize> {
        self.fault
    }

    /// Bytes read so far.
    pub fn position(&self) -> usize {
        self.pos
    }

    /// Bytes not read.
    pub fn remaining(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
    }

    fn take<const N: usize>(&mut self) -> [u8; N] {
        if self.fault.is_some() {
            return [0; N];
        }
        self.at = self.pos;
        match self.buf.get(self.pos..self.pos + N) {
            Some(b) => {
                self.pos += N;
                let mut out = [0; N];
                out.copy_from_slice(b);
                out
            }
            None => {
                self.fail();
                [0; N]
            }
        }
    }

    /// The next byte (0 once short of bytes or after a fault).
    pub fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }

    /// The next `u32`, little-endian (0 once short of bytes or after a fault).
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }

    /// The next `u64`, little-endian (0 once short of bytes or after a fault).
    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }

    /// The next `f64`, from its bits.
    pub fn f64(&mut self) -> f64 {
        f64::from_bits(self.u64())
    }

    /// A byte 0 or 1 (anything else is a fault).
    pub fn bool(&mut self) -> bool {
        match self.u8() {
            0 => false,
            1 => true,
            _ => {
                self.fail();
                false
            }
        }
    }

    /// A `u64` that fits a `usize` (else a fault).
    pub fn usize(&mut self) -> usize {
        let v = self.u64();
        usize::try_from(v).unwrap_or_else(|_| {
            self.fail();
            0
        })
    }

    /// The end of reading a snapshot's beginning: no fault so far.
    pub fn finish_prefix(&self, offset: usize) -> Result<(), SnapshotError> {
        match self.fault {
            Some(at) => Err(SnapshotError::Malformed { at: offset + at }),
            None => Ok(()),
        }
    }

    /// The end of a load: no fault, and every byte read.
    fn finish(&self, offset: usize) -> Result<(), SnapshotError> {
        match (self.fault, self.remaining()) {
            (Some(at), _) => Err(SnapshotError::Malformed { at: offset + at }),
            (None, 0) => Ok(()),
            (None, _) => Err(SnapshotError::Malformed {
                at: offset + self.pos,
            }),
        }
    }
}

/// State that is saved into and loaded from a snapshot, in a layout fixed
/// by the receiver's configuration. `load` changes `self` only through
/// [`Reader::store`] (or after checking [`Reader::applying`]).
pub trait Snapshot {
    /// Append this state to `w`.
    fn save(&self, w: &mut Writer<'_>);
    /// Read this state from `r`, in the layout [`Snapshot::save`] writes.
    fn load(&mut self, r: &mut Reader<'_>);
}

/// `impl Snapshot` for a struct from the list of its state fields, in order
/// (the others, configuration and per-period buffers, are not saved).
/// Invoke it in the struct's module: private fields are fine there.
macro_rules! snapshot_fields {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        impl $crate::snapshot::Snapshot for $ty {
            fn save(&self, w: &mut $crate::snapshot::Writer<'_>) {
                $( $crate::snapshot::Snapshot::save(&self.$field, w); )*
            }
            fn load(&mut self, r: &mut $crate::snapshot::Reader<'_>) {
                $( $crate::snapshot::Snapshot::load(&mut self.$field, r); )*
            }
        }
    };
}
pub(crate) use snapshot_fields;

macro_rules! snapshot_scalars {
    ($($ty:ty => $put:ident, $get:ident;)*) => {
        $(
            impl Snapshot for $ty {
                fn save(&self, w: &mut Writer<'_>) {
                    w.$put(*self);
                }
                fn load(&mut self, r: &mut Reader<'_>) {
                    let v = r.$get();
                    r.store(self, v);
                }
            }
        )*
    };
}

snapshot_scalars! {
    f64 => f64, f64;
    u64 => u64, u64;
    u32 => u32, u32;
    u8 => u8, u8;
    bool => bool, bool;
}

/// As a `u64`.
impl Snapshot for usize {
    fn save(&self, w: &mut Writer<'_>) {
        w.u64(*self as u64);
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        let v = r.usize();
        r.store(self, v);
    }
}

/// The wire enums of `phri_ipc`, by their `u32` values (an unknown value is a fault).
macro_rules! snapshot_wire_enums {
    ($($ty:ty),*) => {
        $(
            impl Snapshot for $ty {
                fn save(&self, w: &mut Writer<'_>) {
                    w.u32(u32::from(*self));
                }
                fn load(&mut self, r: &mut Reader<'_>) {
                    match <$ty>::try_from(r.u32()) {
                        Ok(v) => r.store(self, v),
                        Err(_) => r.fail(),
                    }
                }
            }
        )*
    };
}

snapshot_wire_enums!(ControlMode, CollabPhase, CollabReason, CollabPart);

impl Snapshot for Vector3<f64> {
    fn save(&self, w: &mut Writer<'_>) {
        for x in self.iter() {
            w.f64(*x);
        }
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        for x in self.iter_mut() {
            x.load(r);
        }
    }
}

impl<T: Snapshot, const N: usize> Snapshot for [T; N] {
    fn save(&self, w: &mut Writer<'_>) {
        for x in self {
            x.save(w);
        }
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        for x in self.iter_mut() {
            x.load(r);
        }
    }
}

/// The length, then the elements, loaded into the receiver's elements: a
/// length other than the receiver's is a fault (a `Vec` never grows here).
impl<T: Snapshot> Snapshot for Vec<T> {
    fn save(&self, w: &mut Writer<'_>) {
        w.u64(self.len() as u64);
        for x in self {
            x.save(w);
        }
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        if r.u64() != self.len() as u64 {
            r.fail();
            return;
        }
        for x in self.iter_mut() {
            x.load(r);
        }
    }
}

/// A tag byte (0: `None`, 1: `Some`), then always a payload (the default's
/// for `None`), so that the layout does not depend on the value. `T` is
/// plain data: its default allocates nothing.
impl<T: Snapshot + Default> Snapshot for Option<T> {
    fn save(&self, w: &mut Writer<'_>) {
        w.bool(self.is_some());
        match self {
            Some(v) => v.save(w),
            None => T::default().save(w),
        }
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        let some = r.bool();
        let mut v = T::default();
        v.load(r);
        r.store(self, some.then_some(v));
    }
}

impl<A: Snapshot, B: Snapshot> Snapshot for (A, B) {
    fn save(&self, w: &mut Writer<'_>) {
        self.0.save(w);
        self.1.save(w);
    }
    fn load(&mut self, r: &mut Reader<'_>) {
        self.0.load(r);
        self.1.load(r);
    }
}

snapshot_fields!(HriRequest {
    seq,
    stamp_ns,
    utterance_end_ns,
    source,
    kind,
    part,
    person,
    confidence,
    score,
    text
});

/// A slice of `n` values as a `Vec<f64>` of that length would be saved.
pub(crate) fn save_slice(w: &mut Writer<'_>, v: &[f64]) {
    w.u64(v.len() as u64);
    for x in v {
        w.f64(*x);
    }
}

/// `n ≤ MAX_DOF` values saved by [`save_slice`], onto the stack (a fault if
/// the length is not `n`).
pub(crate) fn load_joints(r: &mut Reader<'_>, n: usize) -> [f64; MAX_DOF] {
    let mut out = [0.0; MAX_DOF];
    if r.u64() != n as u64 || n > MAX_DOF {
        r.fail();
        return out;
    }
    for x in out[..n].iter_mut() {
        *x = r.f64();
    }
    out
}

/// What the header of a controller's snapshot says: its joints, its byte
/// length, and a fingerprint of the configuration's sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    pub dof: u32,
    pub bytes: usize,
    pub fingerprint: u64,
}

impl Layout {
    /// A header's place, before the length is known (a counting pass).
    pub const BLANK: Layout = Layout {
        dof: 0,
        bytes: 0,
        fingerprint: 0,
    };
}

/// FNV-1a over the values' little-endian bytes.
pub(crate) fn fingerprint(values: &[u64]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for b in v.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// The header of a snapshot of `layout`.
pub(crate) fn write_header(w: &mut Writer<'_>, layout: &Layout) {
    w.u32(MAGIC);
    w.u32(VERSION);
    w.u32(u32::try_from(layout.bytes).unwrap_or(u32::MAX));
    w.u32(layout.dof);
    w.u64(layout.fingerprint);
}

/// The header of `bytes` checked for its magic, version and `dof` joints:
/// the snapshot's length and fingerprint as it states them.
fn stated_layout(bytes: &[u8], dof: u32) -> Result<(usize, u64), SnapshotError> {
    if bytes.len() < HEADER_BYTES {
        return Err(SnapshotError::Truncated {
            need: HEADER_BYTES,
            have: bytes.len(),
        });
    }
    let mut r = Reader::new(&bytes[..HEADER_BYTES]);
    let (magic, version, len, got, fp) = (r.u32(), r.u32(), r.u32(), r.u32(), r.u64());
    if magic != MAGIC {
        return Err(SnapshotError::Magic { got: magic });
    }
    if version != VERSION {
        return Err(SnapshotError::Version {
            expected: VERSION,
            got: version,
        });
    }
    if got != dof {
        return Err(SnapshotError::Dof { expected: dof, got });
    }
    Ok((len as usize, fp))
}

/// Check `bytes`' header against the receiver's `own` layout: the
/// snapshot's body, `bytes[HEADER_BYTES..own.bytes]` (trailing bytes, e.g.
/// of a fixed-size message array, are ignored).
pub(crate) fn check_header<'b>(bytes: &'b [u8], own: &Layout) -> Result<&'b [u8], SnapshotError> {
    let (len, fp) = stated_layout(bytes, own.dof)?;
    if len != own.bytes || fp != own.fingerprint {
        return Err(SnapshotError::Layout {
            expected: own.fingerprint,
            got: fp,
            expected_bytes: own.bytes,
            got_bytes: len,
        });
    }
    body_within(bytes, len)
}

/// The body of a snapshot of `dof` joints whatever its layout (its length
/// as its header states it): for what every layout begins with.
pub(crate) fn any_body(bytes: &[u8], dof: u32) -> Result<&[u8], SnapshotError> {
    let (len, _) = stated_layout(bytes, dof)?;
    body_within(bytes, len)
}

/// `bytes[HEADER_BYTES..len]`, if `bytes` holds that much.
fn body_within(bytes: &[u8], len: usize) -> Result<&[u8], SnapshotError> {
    if bytes.len() < len || len < HEADER_BYTES {
        return Err(SnapshotError::Truncated {
            need: len.max(HEADER_BYTES),
            have: bytes.len(),
        });
    }
    Ok(&bytes[HEADER_BYTES..len])
}

/// Load `body` into `state` by `load`: a dry run over all of it first, so
/// that a fault anywhere leaves `state` as it was; then the loading pass.
pub(crate) fn load_checked<S: ?Sized>(
    state: &mut S,
    body: &[u8],
    load: impl Fn(&mut S, &mut Reader<'_>),
) -> Result<(), SnapshotError> {
    let mut dry = Reader::dry_run(body);
    load(state, &mut dry);
    dry.finish(HEADER_BYTES)?;
    let mut r = Reader::new(body);
    load(state, &mut r);
    r.finish(HEADER_BYTES)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, PartialEq)]
    struct Plain {
        x: f64,
        n: usize,
        flag: bool,
        at: Option<(Vector3<f64>, u64)>,
        mode: ControlMode,
    }
    snapshot_fields!(Plain {
        x,
        n,
        flag,
        at,
        mode
    });

    impl Default for Plain {
        fn default() -> Plain {
            Plain {
                x: 0.0,
                n: 0,
                flag: false,
                at: None,
                mode: ControlMode::Sync,
            }
        }
    }

    fn saved<T: Snapshot>(v: &T) -> Vec<u8> {
        let mut w = Writer::new(&mut []);
        v.save(&mut w);
        let mut buf = vec![0; w.len()];
        let mut w = Writer::new(&mut buf);
        v.save(&mut w);
        assert!(!w.overflowed());
        buf
    }

    #[test]
    fn round_trips_are_bit_exact_and_the_layout_is_fixed() {
        let a = Plain {
            x: -0.0f64.next_down(),
            n: 7,
            flag: true,
            at: Some((Vector3::new(f64::MIN_POSITIVE, -1e300, 0.1), u64::MAX)),
            mode: ControlMode::BackOff,
        };
        let b = Plain::default();
        let (bytes_a, bytes_b) = (saved(&a), saved(&b));
        assert_eq!(bytes_a.len(), bytes_b.len(), "None takes the room of Some");
        let mut c = Plain::default();
        let mut r = Reader::new(&bytes_a);
        c.load(&mut r);
        assert_eq!(r.finish(0), Ok(()));
        assert_eq!(c.x.to_bits(), a.x.to_bits());
        assert_eq!(c, a);
        // and back to None
        let mut r = Reader::new(&bytes_b);
        c.load(&mut r);
        assert_eq!(c, b);
    }

    #[test]
    fn a_dry_run_validates_and_stores_nothing() {
        let a = Plain {
            x: 3.0,
            mode: ControlMode::Task,
            ..Default::default()
        };
        let mut bytes = saved(&a);
        let mut c = Plain::default();
        let mut dry = Reader::dry_run(&bytes);
        c.load(&mut dry);
        assert_eq!(dry.finish(0), Ok(()));
        assert_eq!(c, Plain::default());
        // an unknown mode: a fault where it was read
        let at = bytes.len() - 4;
        bytes[at..].copy_from_slice(&99u32.to_le_bytes());
        let mut r = Reader::new(&bytes);
        c.load(&mut r);
        assert_eq!(r.finish(0), Err(SnapshotError::Malformed { at }));
        // short of bytes
        let mut r = Reader::new(&bytes[..5]);
        c.load(&mut r);
        assert_eq!(r.fault(), Some(0));
        // a bad tag
        bytes[8 + 8 + 1] = 2;
        let mut r = Reader::dry_run(&bytes);
        c.load(&mut r);
        assert_eq!(r.fault(), Some(8 + 8 + 1));
    }

    #[test]
    fn a_vec_keeps_its_length_and_a_writer_counts_past_its_end() {
        let v = vec![1.0, 2.0, 3.0];
        let bytes = saved(&v);
        assert_eq!(bytes.len(), 8 + 3 * 8);
        let mut w = vec![0.0; 2];
        let mut r = Reader::new(&bytes);
        w.load(&mut r);
        assert!(r.fault().is_some() && w == [0.0, 0.0]);
        let mut buf = [0u8; 10];
        let mut wr = Writer::new(&mut buf);
        v.save(&mut wr);
        assert!(wr.overflowed() && wr.len() == 32);
    }
}
