//! Typed channels: each channel is one constant that carries its name, its
//! message type, its quality of service and whether a new sample wakes its
//! readers, so that a process cannot pair a name with the wrong type.
//!
//! ```no_run
//! use phri_ipc::{node, Queue, ROBOT_STATE};
//! let node = node("example", "phri_").unwrap();
//! let states = ROBOT_STATE.subscriber(&node, Queue::Latest).unwrap();
//! if let Some(s) = states.latest().unwrap() {
//!     println!("q = {:?}", &s.q[..s.dof as usize]);
//! }
//! ```

use std::fmt::Debug;
use std::marker::PhantomData;
use std::mem::{size_of, MaybeUninit};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::marker::{CustomHeaderMarker, CustomPayloadMarker};
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use iceoryx2::service::static_config::message_type_details::{TypeDetail, TypeVariant};

use crate::error::IpcError;
use crate::messages::{FrameHeader, Zeroed};
use crate::qos::{Qos, DELIVERY_WAIT};

/// A publish-subscribe channel of payload `P` with user header `H`.
/// Messages are `Channel<T>`; depth frames are [`FrameChannel`].
pub struct Channel<P: ?Sized + 'static, H: 'static = ()> {
    /// service name (`robot/state`): what flows, from whom
    pub name: &'static str,
    /// publishers and subscribers allowed, queue depths, history, overflow
    pub qos: Qos,
    /// a new sample is announced on the event service of the same name
    pub wakes: bool,
    _types: PhantomData<fn() -> (*const P, H)>,
}

impl<P: ?Sized, H> Clone for Channel<P, H> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<P: ?Sized, H> Copy for Channel<P, H> {}

impl<P: ?Sized, H> Debug for Channel<P, H> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Channel({})", self.name)
    }
}

/// Depth frames: `[u16]` millimetres with a [`FrameHeader`].
pub type FrameChannel = Channel<[u16], FrameHeader>;

/// How many samples a subscriber keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Queue {
    /// the newest sample only (control: an old value is worth nothing)
    Latest,
    /// every sample since the last read, as deep as the channel allows (evaluation, recording)
    Drain,
    /// this many (capped by the channel's QoS)
    Depth(usize),
}

/// Deepest queue [`Queue::Drain`] asks for.
pub const DRAIN_DEPTH: usize = 256;

impl Queue {
    fn depth(self, qos: &Qos) -> usize {
        let want = match self {
            Queue::Latest => 1,
            Queue::Drain => DRAIN_DEPTH,
            Queue::Depth(n) => n,
        };
        want.clamp(1, qos.subscriber_max_buffer.max(1))
    }
}

/// The node type of this project.
pub type IpcNode = Node<ipc::Service>;
type RawListener = iceoryx2::port::listener::Listener<ipc::Service>;
type RawNotifier = iceoryx2::port::notifier::Notifier<ipc::Service>;

// Every channel's ports are iceoryx2's ports of opaque bytes: the payload a
// byte slice, the user header opaque. The channel's own types are written
// into the service's static config exactly as a typed port writes them (the
// type's name, size and alignment: [`Layout`]), so outside clients (`iox2`,
// the Python binding, a typed Rust port) see and match the same service.
// iceoryx2's code is generic over the payload and header: opened this way it
// is compiled once, in this crate, instead of once per message type in
// every binary that uses it. The typed API below copies a message in and out
// (a few hundred bytes); depth frames stay zero-copy.
type Bytes = [CustomPayloadMarker];
type Opaque = CustomHeaderMarker;
type Factory = PortFactory<ipc::Service, Bytes, Opaque>;
type RawPub = iceoryx2::port::publisher::Publisher<ipc::Service, Bytes, Opaque>;
type RawSub = iceoryx2::port::subscriber::Subscriber<ipc::Service, Bytes, Opaque>;
type RawSample = iceoryx2::sample::Sample<ipc::Service, Bytes, Opaque>;
type RawSampleMut = iceoryx2::sample_mut::SampleMut<ipc::Service, Bytes, Opaque>;

/// What a channel's service records of its types: the payload's and the
/// user header's type details, as a typed iceoryx2 port would record them.
#[derive(Clone, Copy, Debug)]
struct Layout {
    payload: TypeDetail,
    header: TypeDetail,
}

impl Layout {
    /// One message of `T` per sample, no user header (`Channel<T>`).
    fn message<T: ZeroCopySend>() -> Layout {
        Layout {
            payload: TypeDetail::new::<T>(TypeVariant::FixedSize),
            header: TypeDetail::new::<()>(TypeVariant::FixedSize),
        }
    }

    /// A slice of `T` per sample with a user header `H` (depth frames).
    fn slice<T: ZeroCopySend, H: ZeroCopySend>() -> Layout {
        Layout {
            payload: TypeDetail::new::<T>(TypeVariant::Dynamic),
            header: TypeDetail::new::<H>(TypeVariant::FixedSize),
        }
    }
}

/// A channel's name, QoS and types: everything that opens its service.
#[derive(Clone, Copy)]
struct Spec<'a> {
    name: &'static str,
    qos: &'a Qos,
    layout: Layout,
}

impl Spec<'_> {
    fn builder(
        &self,
        node: &IpcNode,
    ) -> Result<
        iceoryx2::service::builder::publish_subscribe::Builder<Bytes, Opaque, ipc::Service>,
        IpcError,
    > {
        let name: ServiceName = self
            .name
            .try_into()
            .map_err(|e| IpcError::open(self.name, e))?;
        let q = self.qos;
        let builder = node
            .service_builder(&name)
            .publish_subscribe::<Bytes>()
            .user_header::<Opaque>();
        // SAFETY: the details are those of the types this crate reads and
        // writes through the ports (Layout::message, Layout::slice), so the
        // chunks iceoryx2 lays out fit them
        let builder = unsafe {
            builder
                .__internal_set_payload_type_details(&self.layout.payload)
                .__internal_set_user_header_type_details(&self.layout.header)
        };
        Ok(builder
            .max_publishers(q.max_publishers)
            .max_subscribers(q.max_subscribers)
            .subscriber_max_buffer_size(q.subscriber_max_buffer)
            .history_size(q.history)
            .enable_safe_overflow(q.overflow))
    }

    fn open_or_create(&self, node: &IpcNode) -> Result<Factory, IpcError> {
        self.builder(node)?
            .open_or_create()
            .map_err(|e| IpcError::open(self.name, e))
    }

    /// The service if it exists: `Ok(None)` while it does not exist (yet),
    /// and while it is half there: being removed by its last user (a service
    /// that just exited) or not finished by its creator.
    fn open_existing(&self, node: &IpcNode) -> Result<Option<Factory>, IpcError> {
        match self.builder(node)?.open() {
            Ok(f) => Ok(Some(f)),
            Err(
                PublishSubscribeOpenError::DoesNotExist
                | PublishSubscribeOpenError::IsMarkedForDestruction
                | PublishSubscribeOpenError::HangsInCreation,
            ) => Ok(None),
            Err(e) => Err(IpcError::open(self.name, e)),
        }
    }

    fn publisher_pids(&self, node: &IpcNode) -> Result<Option<Vec<i32>>, IpcError> {
        Ok(self.open_existing(node)?.as_ref().map(publisher_pids_of))
    }

    fn publisher_watch(&self) -> PublisherWatch {
        PublisherWatch {
            name: self.name,
            qos: *self.qos,
            layout: self.layout,
            factory: None,
        }
    }

    fn ports(&self, node: &IpcNode) -> Result<Option<(usize, usize)>, IpcError> {
        use iceoryx2::service::port_factory::PortFactory as _;
        Ok(self.open_existing(node)?.map(|f| {
            let d = f.dynamic_config();
            (d.number_of_publishers(), d.number_of_subscribers())
        }))
    }

    /// A publisher of up to `max_elements` payload elements per sample.
    fn publisher(
        &self,
        node: &IpcNode,
        wakes: bool,
        max_elements: usize,
    ) -> Result<Sender, IpcError> {
        let factory = self.open_or_create(node)?;
        let builder = factory
            .publisher_builder()
            .initial_max_slice_len(max_elements);
        // a channel that does not overflow: wait for a full reader, then
        // leave it out of this sample and count it
        let undelivered = (!self.qos.overflow).then(|| Arc::new(AtomicU64::new(0)));
        let builder = match &undelivered {
            Some(count) => {
                let count = Arc::clone(count);
                builder.set_backpressure_handler(move |info: &BackpressureInfo| {
                    if info.elapsed_time < DELIVERY_WAIT {
                        BackpressureAction::Retry
                    } else {
                        count.fetch_add(1, Ordering::Relaxed);
                        BackpressureAction::DiscardData
                    }
                })
            }
            None => builder,
        };
        let port = builder
            .create()
            .map_err(|e| IpcError::publisher(self.name, self.qos.max_publishers, e))?;
        let notifier = if wakes {
            Some(notifier_of(node, self.name)?)
        } else {
            None
        };
        Ok(Sender {
            port,
            notifier,
            channel: self.name,
            undelivered,
        })
    }

    fn subscribe(
        &self,
        factory: Factory,
        wake_on: Option<&IpcNode>,
        queue: Queue,
    ) -> Result<Receiver, IpcError> {
        let port = factory
            .subscriber_builder()
            .buffer_size(queue.depth(self.qos))
            .create()
            .map_err(|e| IpcError::port(self.name, e))?;
        let listener = match wake_on {
            Some(node) => Some(listener_of(node, self.name)?),
            None => None,
        };
        Ok(Receiver {
            port,
            listener,
            channel: self.name,
        })
    }
}

fn event_of(
    node: &IpcNode,
    channel: &'static str,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, IpcError> {
    let name: ServiceName = channel.try_into().map_err(|e| IpcError::open(channel, e))?;
    node.service_builder(&name)
        .event()
        .max_notifiers(4)
        .max_listeners(16)
        .open_or_create()
        .map_err(|e| IpcError::open(channel, e))
}

fn listener_of(node: &IpcNode, channel: &'static str) -> Result<Listener, IpcError> {
    let port = event_of(node, channel)?
        .listener_builder()
        .create()
        .map_err(|e| IpcError::port(channel, e))?;
    Ok(Listener { port, channel })
}

fn notifier_of(node: &IpcNode, channel: &'static str) -> Result<Notifier, IpcError> {
    let port = event_of(node, channel)?
        .notifier_builder()
        .create()
        .map_err(|e| IpcError::port(channel, e))?;
    Ok(Notifier { port })
}

/// The sending end of any channel: a byte publisher and its wake-ups.
struct Sender {
    port: RawPub,
    notifier: Option<Notifier>,
    channel: &'static str,
    /// a channel that does not overflow: how often a reader was left out
    /// of a sample after [`DELIVERY_WAIT`]
    undelivered: Option<Arc<AtomicU64>>,
}

impl Sender {
    /// Copy the first `head` of `len` bytes from `src` into a loaned sample
    /// of one element (of `len` bytes; past `head` it keeps what an
    /// earlier sample left in that memory), send it and wake the readers.
    ///
    /// # Safety
    /// `src` is valid for reads of `head.min(len)` bytes.
    unsafe fn send_copy(&self, src: *const u8, len: usize, head: usize) -> Result<(), IpcError> {
        // SAFETY: one element of a fixed-size payload
        let mut sample = unsafe { self.port.loan_custom_payload(1) }
            .map_err(|e| IpcError::send(self.channel, e))?;
        let dst = sample.payload_mut();
        if dst.len() != len {
            return Err(IpcError::send(
                self.channel,
                format!("a sample holds {} bytes, the message {len}", dst.len()),
            ));
        }
        // SAFETY: dst holds len bytes (checked), src is readable (the caller)
        // and the sample's memory is not the caller's. Past `head` the bytes
        // are shared memory of earlier samples (or the zeros it was made
        // with): this process never reads them
        let sample = unsafe {
            std::ptr::copy_nonoverlapping(src, dst.as_mut_ptr().cast::<u8>(), head.min(len));
            sample.assume_init()
        };
        sample.send().map_err(|e| IpcError::send(self.channel, e))?;
        self.notify();
        Ok(())
    }

    fn notify(&self) {
        if let Some(n) = &self.notifier {
            n.notify();
        }
    }

    fn update_connections(&self) {
        use iceoryx2::port::update_connections::UpdateConnections;
        let _ = self.port.update_connections();
    }
}

/// The receiving end of any channel: a byte subscriber and its listener.
struct Receiver {
    port: RawSub,
    listener: Option<Listener>,
    channel: &'static str,
}

impl Receiver {
    fn receive(&self) -> Result<Option<RawSample>, IpcError> {
        self.port
            .receive()
            .map_err(|e| IpcError::receive(self.channel, e))
    }

    /// Copy the next sample's payload (`len` bytes) to `dst`; the process id
    /// of its sender (0: not decodable), `None` when nothing is queued.
    ///
    /// # Safety
    /// `dst` is valid for writes of `len` bytes.
    unsafe fn receive_copy(&self, dst: *mut u8, len: usize) -> Result<Option<i32>, IpcError> {
        let mut from = None;
        self.receive_with(len, |pid, bytes| {
            // SAFETY: both hold len bytes (checked; the caller) and do not overlap
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), dst, len) };
            from = Some(pid);
        })?;
        Ok(from)
    }

    /// Hand the next sample's payload (`len` bytes, checked) to `f` in
    /// place, with the process id of its sender; `false` when nothing is
    /// queued. The sample is released when `f` returns.
    fn receive_with(&self, len: usize, f: impl FnOnce(i32, &[u8])) -> Result<bool, IpcError> {
        let Some(s) = self.receive()? else {
            return Ok(false);
        };
        let src = s.payload();
        if src.len() != len {
            return Err(IpcError::receive(
                self.channel,
                format!("a sample of {} bytes, the message has {len}", src.len()),
            ));
        }
        // SAFETY: the payload holds `len` bytes (checked), alive while `s` is
        let bytes = unsafe { std::slice::from_raw_parts(src.as_ptr().cast::<u8>(), len) };
        f(sender_pid(s.header()), bytes);
        Ok(true)
    }

    fn wait(&self, timeout: Duration) -> Result<(), IpcError> {
        match &self.listener {
            Some(l) => l.wait(timeout),
            None => {
                std::thread::sleep(timeout);
                Ok(())
            }
        }
    }
}

impl<P: ?Sized, H> Channel<P, H> {
    /// A channel; the constants in [`crate::channels`] are the only ones a cell uses.
    pub const fn new(name: &'static str, qos: Qos, wakes: bool) -> Self {
        Channel {
            name,
            qos,
            wakes,
            _types: PhantomData,
        }
    }

    /// A listener woken by every new sample (channels that wake only).
    pub fn listener(&self, node: &IpcNode) -> Result<Listener, IpcError> {
        if !self.wakes {
            return Err(IpcError::NoEvent { channel: self.name });
        }
        listener_of(node, self.name)
    }

    /// A notifier that announces new samples (channels that wake only).
    pub fn notifier(&self, node: &IpcNode) -> Result<Notifier, IpcError> {
        if !self.wakes {
            return Err(IpcError::NoEvent { channel: self.name });
        }
        notifier_of(node, self.name)
    }
}

/// What every channel's service offers, whatever it carries.
macro_rules! opening {
    ($(impl[$($g:tt)*] $payload:ty, $header:ty => $layout:expr;)+) => {$(
        impl<$($g)*> Channel<$payload, $header> {
            fn spec(&self) -> Spec<'_> {
                Spec {
                    name: self.name,
                    qos: &self.qos,
                    layout: $layout,
                }
            }

            /// `None` while the channel does not exist; else the process id of
            /// each of its publishers (who commands, who publishes).
            pub fn publisher_pids(&self, node: &IpcNode) -> Result<Option<Vec<i32>>, IpcError> {
                self.spec().publisher_pids(node)
            }

            /// A watch over who publishes on this channel, for asking often.
            pub fn publisher_watch(&self) -> PublisherWatch {
                self.spec().publisher_watch()
            }

            /// `None` while the channel does not exist; else how many publishers
            /// and subscribers it has now.
            pub fn ports(&self, node: &IpcNode) -> Result<Option<(usize, usize)>, IpcError> {
                self.spec().ports(node)
            }
        }
    )+};
}

opening! {
    impl[T: Message] T, () => Layout::message::<T>();
    impl[] [u16], FrameHeader => Layout::slice::<u16, FrameHeader>();
}

/// The process id of each publisher of an open service.
fn publisher_pids_of(f: &Factory) -> Vec<i32> {
    use iceoryx2::service::port_factory::PortFactory as _;
    let mut pids = Vec::new();
    f.dynamic_config().list_publishers(|p| {
        if let Ok(pid) = p.node_id.pid::<ipc::Service>() {
            pids.push(pid.value());
        }
        CallbackProgression::Continue
    });
    pids
}

/// Who publishes on one channel, asked again and again (a supervisor's
/// watch): the channel's service is opened once, when it first exists, and
/// kept open, so each question reads its publisher list only (opening a
/// service reads its files and maps its memory, milliseconds each time).
pub struct PublisherWatch {
    name: &'static str,
    qos: Qos,
    layout: Layout,
    factory: Option<Factory>,
}

impl PublisherWatch {
    /// The channel's name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// `None` while the channel does not exist; else the process id of each
    /// of its publishers now.
    pub fn publisher_pids(&mut self, node: &IpcNode) -> Result<Option<Vec<i32>>, IpcError> {
        if self.factory.is_none() {
            let spec = Spec {
                name: self.name,
                qos: &self.qos,
                layout: self.layout,
            };
            self.factory = spec.open_existing(node)?;
        }
        Ok(self.factory.as_ref().map(publisher_pids_of))
    }
}

/// A message type: plain data with a sequence number, and a JSON view for
/// tools (serde, with the helpers of [`crate::json`]).
pub trait Message:
    Debug
    + ZeroCopySend
    + IceoryxSend
    + Copy
    + Zeroed
    + serde::Serialize
    + serde::de::DeserializeOwned
    + 'static
{
    /// Arrays that hold only as many valid entries as a count field says
    /// (joint arrays by `dof`, contacts by `n_contacts`, ...), by JSON field
    /// name: a JSON view shows only those entries.
    const COUNTED: &'static [crate::json::Counted] = &[];
    /// sequence number (per publisher)
    fn seq(&self) -> u64;
    /// independent sequence streams on one channel (one per publisher)
    fn stream(&self) -> u64 {
        0
    }
    /// publish time [ns, CLOCK_MONOTONIC] when the message carries one
    fn published_ns(&self) -> Option<u64>;
}

/// The process id of the node that sent a sample (0: not decodable).
fn sender_pid(h: &iceoryx2::service::header::publish_subscribe::Header) -> i32 {
    use iceoryx2::service::header::payload_header::PayloadHeader as _;
    h.node_id().pid::<ipc::Service>().map_or(0, |p| p.value())
}

impl<T: Message> Channel<T> {
    /// Publish on this channel: refused when it already has as many publishers as
    /// its QoS allows (one for every command and state channel).
    pub fn publisher(&self, node: &IpcNode) -> Result<Publisher<T>, IpcError> {
        Ok(Publisher {
            raw: self.spec().publisher(node, self.wakes, 1)?,
            _t: PhantomData,
        })
    }

    /// Subscribe (creating the channel if needed); the subscriber polls. A
    /// listener that nobody waits on still receives every wake-up, so only a
    /// reader that waits for new samples asks for one ([`Channel::waking_subscriber`]).
    pub fn subscriber(&self, node: &IpcNode, queue: Queue) -> Result<Subscriber<T>, IpcError> {
        let spec = self.spec();
        self.typed(spec.subscribe(spec.open_or_create(node)?, None, queue)?)
    }

    /// Subscribe with a listener, for a reader that waits for new samples
    /// ([`Subscriber::wait`]); the channel must wake its readers.
    pub fn waking_subscriber(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<Subscriber<T>, IpcError> {
        if !self.wakes {
            return Err(IpcError::NoEvent { channel: self.name });
        }
        let spec = self.spec();
        self.typed(spec.subscribe(spec.open_or_create(node)?, Some(node), queue)?)
    }

    /// Subscribe only if the channel exists, for tools that watch a cell:
    /// `Ok(None)` otherwise. The subscriber polls, as [`Channel::subscriber`].
    pub fn subscriber_if_exists(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<Option<Subscriber<T>>, IpcError> {
        let spec = self.spec();
        match spec.open_existing(node)? {
            Some(f) => self.typed(spec.subscribe(f, None, queue)?).map(Some),
            None => Ok(None),
        }
    }

    fn typed(&self, raw: Receiver) -> Result<Subscriber<T>, IpcError> {
        Ok(Subscriber {
            raw,
            _t: PhantomData,
        })
    }

    /// A latest-value reader: keeps the newest sample it has seen.
    pub fn latest_reader(&self, node: &IpcNode) -> Result<LatestReader<T>, IpcError> {
        Ok(LatestReader {
            sub: self.subscriber(node, Queue::Latest)?,
            value: None,
        })
    }
}

/// Publisher of one channel; announces each sample when the channel wakes its readers.
pub struct Publisher<T: Message> {
    raw: Sender,
    _t: PhantomData<fn(T)>,
}

impl<T: Message> Publisher<T> {
    /// Copy `value` into a loaned sample, send it and wake the readers.
    pub fn publish(&self, value: &T) -> Result<(), IpcError> {
        // SAFETY: value is a T of size_of::<T>() bytes
        unsafe {
            self.raw.send_copy(
                (value as *const T).cast::<u8>(),
                size_of::<T>(),
                size_of::<T>(),
            )
        }
    }

    /// Publish the first `head` bytes of `value` only (all of it when
    /// `head` says more), for a message whose tail past them is unused,
    /// e.g. [`crate::ControlBehaviour`]'s `bytes` past its `len`: readers
    /// find there what an earlier sample left.
    pub fn publish_head(&self, value: &T, head: usize) -> Result<(), IpcError> {
        // SAFETY: value is a T of size_of::<T>() bytes, at least the head read
        unsafe {
            self.raw
                .send_copy((value as *const T).cast::<u8>(), size_of::<T>(), head)
        }
    }

    /// The name of the channel it publishes on.
    pub fn channel(&self) -> &'static str {
        self.raw.channel
    }

    /// How often a reader was left out of a sample of this publisher: on a
    /// channel that does not overflow ([`Qos::overflow`]), a reader whose
    /// queue stayed full for [`DELIVERY_WAIT`] (0 on the others, where a
    /// full queue drops its oldest instead).
    pub fn undelivered(&self) -> u64 {
        self.raw
            .undelivered
            .as_ref()
            .map_or(0, |c| c.load(Ordering::Relaxed))
    }

    /// Connect the readers that appeared since the last send, without
    /// sending: a publisher that sends only now and then (a hot standby's,
    /// until it takes charge) keeps its connections made, so its first
    /// sends cost a real-time loop no more than the others. A failed
    /// connection is retried at the next send.
    pub fn update_connections(&self) {
        self.raw.update_connections();
    }
}

/// Subscriber of one channel.
pub struct Subscriber<T: Message> {
    raw: Receiver,
    _t: PhantomData<fn() -> T>,
}

impl<T: Message> Subscriber<T> {
    /// The next queued sample, copied out.
    pub fn receive(&self) -> Result<Option<T>, IpcError> {
        Ok(self.receive_from()?.map(|(_, v)| v))
    }

    /// The newest sample (older queued ones are consumed), or `None`.
    pub fn latest(&self) -> Result<Option<T>, IpcError> {
        let mut out = None;
        while let Some(s) = self.receive()? {
            out = Some(s);
        }
        Ok(out)
    }

    /// The next queued sample and its sender's process id (see
    /// [`Subscriber::drain_from`]), copied out.
    pub fn receive_from(&self) -> Result<Option<(i32, T)>, IpcError> {
        let mut v = MaybeUninit::<T>::uninit();
        // SAFETY: v has room for size_of::<T>() bytes; a message type is
        // plain data, so the bytes a publisher of T wrote are a T
        Ok(unsafe {
            self.raw
                .receive_copy(v.as_mut_ptr().cast::<u8>(), size_of::<T>())?
                .map(|pid| (pid, v.assume_init()))
        })
    }

    /// Hand every queued sample to `f` with the process id of its sender
    /// (0: unknown), oldest first; returns how many. The sender's pid is
    /// read from the sample's header (iceoryx2's node id encodes it):
    /// nothing is allocated or looked up.
    ///
    /// Each sample is read where it lies in shared memory, not copied out
    /// (a hot standby takes every 8 KiB `control/behaviour` of its peer):
    /// iceoryx2 lays a payload out at its type's alignment; one that is not
    /// is copied out first.
    pub fn drain_from(&self, mut f: impl FnMut(i32, &T)) -> Result<usize, IpcError> {
        let mut n = 0;
        let mut each = |pid: i32, bytes: &[u8]| {
            if bytes.as_ptr().align_offset(std::mem::align_of::<T>()) == 0 {
                // SAFETY: `size_of::<T>()` bytes (checked by receive_with),
                // aligned for T (just checked); a message type is plain
                // data, so the bytes a publisher of T wrote are a T
                f(pid, unsafe { &*bytes.as_ptr().cast::<T>() });
            } else {
                let mut v = MaybeUninit::<T>::uninit();
                // SAFETY: as above, copied to an aligned T first
                f(pid, unsafe {
                    std::ptr::copy_nonoverlapping(
                        bytes.as_ptr(),
                        v.as_mut_ptr().cast::<u8>(),
                        bytes.len(),
                    );
                    v.assume_init_ref()
                });
            }
        };
        while self.raw.receive_with(size_of::<T>(), &mut each)? {
            n += 1;
        }
        Ok(n)
    }

    /// Hand every queued sample to `f`, oldest first; returns how many.
    pub fn drain(&self, mut f: impl FnMut(&T)) -> Result<usize, IpcError> {
        self.drain_from(|_, v| f(v))
    }

    /// Block until a new sample is announced or `timeout` passes (channels that
    /// wake; zero: consume the pending announcements without blocking); a
    /// channel that does not wake just sleeps `timeout`.
    pub fn wait(&self, timeout: Duration) -> Result<(), IpcError> {
        self.raw.wait(timeout)
    }

    /// The name of the channel it reads.
    pub fn channel(&self) -> &'static str {
        self.raw.channel
    }
}

/// The newest value of a channel, kept between reads (a controller keeps
/// acting on the last residual until a newer one arrives, and judges its age).
pub struct LatestReader<T: Message> {
    sub: Subscriber<T>,
    value: Option<T>,
}

impl<T: Message> LatestReader<T> {
    /// Take the newest sample if one arrived; `true` when the value changed.
    pub fn update(&mut self) -> Result<bool, IpcError> {
        match self.sub.latest()? {
            Some(v) => {
                self.value = Some(v);
                Ok(true)
            }
            None => Ok(false),
        }
    }

    /// Take the newest of the queued samples that `accept` passes, given its
    /// sender's pid (see [`Subscriber::drain_from`]): a refused sample that
    /// came last does not hide an accepted one before it. `true` when the
    /// value changed.
    pub fn update_from(
        &mut self,
        mut accept: impl FnMut(i32, &T) -> bool,
    ) -> Result<bool, IpcError> {
        let mut changed = false;
        let value = &mut self.value;
        self.sub.drain_from(|pid, v| {
            if accept(pid, v) {
                *value = Some(*v);
                changed = true;
            }
        })?;
        Ok(changed)
    }

    /// Like [`LatestReader::update`], keeping only samples that pass `accept`.
    pub fn update_if(&mut self, accept: impl Fn(&T) -> bool) -> Result<bool, IpcError> {
        match self.sub.latest()? {
            Some(v) if accept(&v) => {
                self.value = Some(v);
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// The newest value seen, if any.
    pub fn get(&self) -> Option<&T> {
        self.value.as_ref()
    }

    /// The subscriber it reads from (polling, [`Queue::Latest`]).
    pub fn subscriber(&self) -> &Subscriber<T> {
        &self.sub
    }
}

/// Wakes on new samples of one channel.
pub struct Listener {
    port: RawListener,
    channel: &'static str,
}

impl Listener {
    /// Block until an announcement arrives or `timeout` passes (a signal also
    /// ends the wait). Pending announcements are consumed. A zero `timeout`
    /// never blocks: it only consumes what is pending (iceoryx2's own timed
    /// wait takes zero as no timeout at all on its socket-based events).
    pub fn wait(&self, timeout: Duration) -> Result<(), IpcError> {
        self.wait_each(timeout, || {})
    }

    /// Like [`Listener::wait`], calling `f` once per announcement.
    pub fn wait_each(&self, timeout: Duration, mut f: impl FnMut()) -> Result<(), IpcError> {
        if !timeout.is_zero() {
            self.block(timeout);
        }
        self.port
            .try_wait(|_| f())
            .map(|_| ())
            .map_err(|e| IpcError::receive(self.channel, e))
    }

    /// Block until the listener's socket holds an announcement, `timeout`
    /// passes or a signal arrives: one `ppoll`, and the announcements are
    /// then taken without blocking. iceoryx2's own timed wait switches its
    /// socket to blocking and back and sets the socket's timeout at every
    /// wait: seven system calls per wake-up where this makes two (`ppoll`,
    /// `recvfrom`; strace on the residual standby), at 1 kHz in each of the
    /// torque loop's services.
    fn block(&self, timeout: Duration) {
        // SAFETY: the descriptor is only polled, never closed or kept: it
        // stays the listener's, open as long as `self.port`
        let raw = unsafe { self.port.file_descriptor().native_handle() };
        let mut fd = libc::pollfd {
            fd: raw,
            events: libc::POLLIN,
            revents: 0,
        };
        let ts = libc::timespec {
            tv_sec: libc::time_t::try_from(timeout.as_secs()).unwrap_or(libc::time_t::MAX),
            // below 10⁹: fits any c_long
            tv_nsec: timeout.subsec_nanos() as libc::c_long,
        };
        // SAFETY: one valid pollfd, a valid timeout, no signal mask; the
        // outcome (ready, timed out, interrupted) needs no reading: the
        // non-blocking take after it finds what there is
        unsafe { libc::ppoll(&mut fd, 1, &ts, std::ptr::null()) };
    }
}

/// Announces new samples of one channel.
pub struct Notifier {
    port: RawNotifier,
}

impl Notifier {
    /// Wake the channel's listeners. A failed wake-up is not an error for the
    /// publisher: readers also poll on their timeout.
    pub fn notify(&self) {
        let _ = self.port.notify();
    }
}

/// A received frame: header and depths, in shared memory (no copy).
pub struct FrameSample(RawSample);

impl FrameSample {
    /// the frame's header
    pub fn user_header(&self) -> &FrameHeader {
        // SAFETY: the service's user header is a FrameHeader (Layout::slice),
        // written by its publisher
        unsafe { &*(self.0.user_header() as *const Opaque).cast::<FrameHeader>() }
    }

    /// depths \[mm\], row-major
    pub fn payload(&self) -> &[u16] {
        let bytes = self.0.payload();
        // SAFETY: the payload is a slice of u16 (Layout::slice), aligned
        // for it by iceoryx2's chunk layout
        unsafe { std::slice::from_raw_parts(bytes.as_ptr().cast::<u16>(), bytes.len() / 2) }
    }
}

/// A loaned frame being written in shared memory.
pub struct FrameSampleMut(RawSampleMut);

impl FrameSampleMut {
    /// the frame's header
    pub fn user_header(&self) -> &FrameHeader {
        // SAFETY: as FrameSample::user_header; initialised at the loan
        unsafe { &*(self.0.user_header() as *const Opaque).cast::<FrameHeader>() }
    }

    /// the frame's header, to fill in
    pub fn user_header_mut(&mut self) -> &mut FrameHeader {
        // SAFETY: as FrameSampleMut::user_header
        unsafe { &mut *(self.0.user_header_mut() as *mut Opaque).cast::<FrameHeader>() }
    }

    /// depths \[mm\], row-major
    pub fn payload(&self) -> &[u16] {
        let bytes = self.0.payload();
        // SAFETY: as FrameSample::payload; zeroed at the loan
        unsafe { std::slice::from_raw_parts(bytes.as_ptr().cast::<u16>(), bytes.len() / 2) }
    }

    /// depths \[mm\], row-major, to fill in
    pub fn payload_mut(&mut self) -> &mut [u16] {
        let bytes = self.0.payload_mut();
        // SAFETY: as FrameSampleMut::payload
        unsafe { std::slice::from_raw_parts_mut(bytes.as_mut_ptr().cast::<u16>(), bytes.len() / 2) }
    }
}

impl FrameChannel {
    /// Publish frames of up to `max_pixels` depths.
    pub fn frame_publisher(
        &self,
        node: &IpcNode,
        max_pixels: usize,
    ) -> Result<FramePublisher, IpcError> {
        Ok(FramePublisher {
            raw: self.spec().publisher(node, self.wakes, max_pixels)?,
        })
    }

    /// Subscribe to frames, polling (see [`Channel::subscriber`]).
    pub fn frame_subscriber(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<FrameSubscriber, IpcError> {
        let spec = self.spec();
        Ok(FrameSubscriber {
            raw: spec.subscribe(spec.open_or_create(node)?, None, queue)?,
        })
    }

    /// Subscribe to frames with a listener, for a reader that waits for them.
    pub fn waking_frame_subscriber(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<FrameSubscriber, IpcError> {
        if !self.wakes {
            return Err(IpcError::NoEvent { channel: self.name });
        }
        let spec = self.spec();
        Ok(FrameSubscriber {
            raw: spec.subscribe(spec.open_or_create(node)?, Some(node), queue)?,
        })
    }

    /// Subscribe only if the channel exists, for tools: `Ok(None)` otherwise.
    /// Polls (no listener), as [`Channel::subscriber`].
    pub fn frame_subscriber_if_exists(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<Option<FrameSubscriber>, IpcError> {
        let spec = self.spec();
        match spec.open_existing(node)? {
            Some(f) => Ok(Some(FrameSubscriber {
                raw: spec.subscribe(f, None, queue)?,
            })),
            None => Ok(None),
        }
    }
}

/// Publisher of depth frames: loan a frame, write it in place, send it.
pub struct FramePublisher {
    raw: Sender,
}

impl FramePublisher {
    /// A frame of `pixels` depths in shared memory, zeroed, header zeroed.
    pub fn loan(&self, pixels: usize) -> Result<FrameSampleMut, IpcError> {
        let channel = self.raw.channel;
        // SAFETY: a slice payload (Layout::slice): any number of elements
        let mut s = unsafe { self.raw.port.loan_custom_payload(pixels) }
            .map_err(|e| IpcError::send(channel, e))?;
        let bytes = s.payload_mut();
        if bytes.len() != pixels * size_of::<u16>() {
            return Err(IpcError::send(
                channel,
                format!("a frame of {} bytes for {pixels} depths", bytes.len()),
            ));
        }
        // SAFETY: zeroes are valid depths and a valid FrameHeader
        // (FrameHeader::zeroed); the header's memory is the chunk's, laid
        // out for a FrameHeader (Layout::slice)
        let s = unsafe {
            std::ptr::write_bytes(bytes.as_mut_ptr().cast::<u8>(), 0, bytes.len());
            (s.user_header_mut() as *mut Opaque)
                .cast::<FrameHeader>()
                .write(FrameHeader::zeroed());
            s.assume_init()
        };
        Ok(FrameSampleMut(s))
    }

    /// Send a loaned frame and wake the readers.
    pub fn send(&self, sample: FrameSampleMut) -> Result<(), IpcError> {
        sample
            .0
            .send()
            .map_err(|e| IpcError::send(self.raw.channel, e))?;
        self.raw.notify();
        Ok(())
    }

    /// The name of the channel it publishes on.
    pub fn channel(&self) -> &'static str {
        self.raw.channel
    }
}

/// Subscriber of depth frames.
pub struct FrameSubscriber {
    raw: Receiver,
}

impl FrameSubscriber {
    /// The next queued frame.
    pub fn receive(&self) -> Result<Option<FrameSample>, IpcError> {
        Ok(self.raw.receive()?.map(FrameSample))
    }

    /// The newest queued frame (older ones are released).
    pub fn latest(&self) -> Result<Option<FrameSample>, IpcError> {
        let mut out = None;
        while let Some(f) = self.receive()? {
            out = Some(f);
        }
        Ok(out)
    }

    /// Block until a new frame is announced or `timeout` passes.
    pub fn wait(&self, timeout: Duration) -> Result<(), IpcError> {
        self.raw.wait(timeout)
    }

    /// The name of the channel it reads.
    pub fn channel(&self) -> &'static str {
        self.raw.channel
    }
}

/// Block until any of `subscribers` announces a new frame or `timeout`
/// passes (a signal also ends the wait), through one of iceoryx2's
/// WaitSets; pending announcements are consumed. Subscribers without a
/// listener (polling) are not waited on; with none at all, it sleeps
/// `timeout`. For a service that serves several cameras' frames: a camera
/// that stops announcing delays none of the others.
pub fn wait_any(subscribers: &[&FrameSubscriber], timeout: Duration) -> Result<(), IpcError> {
    let listeners: Vec<&Listener> = subscribers
        .iter()
        .filter_map(|s| s.raw.listener.as_ref())
        .collect();
    let Some(first) = listeners.first() else {
        std::thread::sleep(timeout);
        return Ok(());
    };
    if listeners.len() == 1 {
        return first.wait(timeout);
    }
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| IpcError::receive(first.channel, e))?;
    let mut guards = Vec::with_capacity(listeners.len());
    for l in &listeners {
        guards.push(
            waitset
                .attach_notification(&l.port)
                .map_err(|e| IpcError::receive(l.channel, e))?,
        );
    }
    waitset
        .wait_and_process_once_with_timeout(|_| CallbackProgression::Stop, timeout)
        .map_err(|e| IpcError::receive(first.channel, e))?;
    drop(guards);
    for l in &listeners {
        l.port
            .try_wait(|_| {})
            .map_err(|e| IpcError::receive(l.channel, e))?;
    }
    Ok(())
}
