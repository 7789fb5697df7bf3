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
use std::time::Duration;

use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;

use crate::error::IpcError;
use crate::messages::{FrameHeader, Zeroed};
use crate::qos::Qos;

/// A publish-subscribe channel of payload `P` with user header `H`.
/// Messages are `Channel<T>`; depth frames are [`FrameChannel`].
pub struct Channel<P: ?Sized + 'static, H: 'static = ()> {
    /// service name (`robot/state`): what flows, from whom
    pub name: &'static str,
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
type Factory<P, H> = PortFactory<ipc::Service, P, H>;
type RawListener = iceoryx2::port::listener::Listener<ipc::Service>;
type RawNotifier = iceoryx2::port::notifier::Notifier<ipc::Service>;

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

    fn service_name(&self) -> Result<ServiceName, IpcError> {
        self.name
            .try_into()
            .map_err(|e| IpcError::open(self.name, e))
    }

    fn event(
        &self,
        node: &IpcNode,
    ) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, IpcError> {
        if !self.wakes {
            return Err(IpcError::NoEvent { channel: self.name });
        }
        node.service_builder(&self.service_name()?)
            .event()
            .max_notifiers(4)
            .max_listeners(16)
            .open_or_create()
            .map_err(|e| IpcError::open(self.name, e))
    }

    /// A listener woken by every new sample (channels that wake only).
    pub fn listener(&self, node: &IpcNode) -> Result<Listener, IpcError> {
        let port = self
            .event(node)?
            .listener_builder()
            .create()
            .map_err(|e| IpcError::port(self.name, e))?;
        Ok(Listener {
            port,
            channel: self.name,
        })
    }

    /// A notifier that announces new samples (channels that wake only).
    pub fn notifier(&self, node: &IpcNode) -> Result<Notifier, IpcError> {
        let port = self
            .event(node)?
            .notifier_builder()
            .create()
            .map_err(|e| IpcError::port(self.name, e))?;
        Ok(Notifier { port })
    }

    fn notifier_if_wakes(&self, node: &IpcNode) -> Result<Option<Notifier>, IpcError> {
        if self.wakes {
            self.notifier(node).map(Some)
        } else {
            Ok(None)
        }
    }

    fn listener_if_wakes(&self, node: &IpcNode) -> Result<Option<Listener>, IpcError> {
        if self.wakes {
            self.listener(node).map(Some)
        } else {
            Ok(None)
        }
    }
}

impl<P: Debug + ZeroCopySend + IceoryxSend + ?Sized, H: Debug + ZeroCopySend> Channel<P, H> {
    fn builder(
        &self,
        node: &IpcNode,
    ) -> Result<iceoryx2::service::builder::publish_subscribe::Builder<P, H, ipc::Service>, IpcError>
    {
        let q = &self.qos;
        Ok(node
            .service_builder(&self.service_name()?)
            .publish_subscribe::<P>()
            .user_header::<H>()
            .max_publishers(q.max_publishers)
            .max_subscribers(q.max_subscribers)
            .subscriber_max_buffer_size(q.subscriber_max_buffer)
            .history_size(q.history)
            .enable_safe_overflow(true))
    }
}

/// Opening a channel's service: iceoryx2 has one implementation for sized
/// payloads and one for slices, with the same shape.
macro_rules! opening {
    ($(impl[$($g:tt)*] $payload:ty, $header:ty;)+) => {$(
        impl<$($g)*> Channel<$payload, $header> {
            fn open_or_create(&self, node: &IpcNode) -> Result<Factory<$payload, $header>, IpcError> {
                self.builder(node)?
                    .open_or_create()
                    .map_err(|e| IpcError::open(self.name, e))
            }

            /// The channel's service if it exists, for tools that watch a cell and must
            /// never create one: `Ok(None)` while it does not exist (yet), and while
            /// it is half there: being removed by its last user (a service that just
            /// exited) or not finished by its creator.
            fn open_existing(&self, node: &IpcNode) -> Result<Option<Factory<$payload, $header>>, IpcError> {
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

            /// `None` while the channel does not exist; else the process id of
            /// each of its publishers (who commands, who publishes).
            pub fn publisher_pids(&self, node: &IpcNode) -> Result<Option<Vec<i32>>, IpcError> {
                use iceoryx2::service::port_factory::PortFactory as _;
                Ok(self.open_existing(node)?.map(|f| {
                    let mut pids = Vec::new();
                    f.dynamic_config().list_publishers(|p| {
                        if let Ok(pid) = p.node_id.pid::<ipc::Service>() {
                            pids.push(pid.value());
                        }
                        iceoryx2::prelude::CallbackProgression::Continue
                    });
                    pids
                }))
            }

            /// `None` while the channel does not exist; else how many publishers
            /// and subscribers it has now.
            pub fn ports(&self, node: &IpcNode) -> Result<Option<(usize, usize)>, IpcError> {
                use iceoryx2::service::port_factory::PortFactory as _;
                Ok(self.open_existing(node)?.map(|f| {
                    let d = f.dynamic_config();
                    (d.number_of_publishers(), d.number_of_subscribers())
                }))
            }
        }
    )+};
}

opening! {
    impl[T: Message] T, ();
    impl[] [u16], FrameHeader;
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

type RawPub<T> = iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>;
type RawSub<T> = iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>;

impl<T: Message> Channel<T> {
    /// Publish on this channel: refused when it already has as many publishers as
    /// its QoS allows (one for every command and state channel).
    pub fn publisher(&self, node: &IpcNode) -> Result<Publisher<T>, IpcError> {
        let port = self
            .open_or_create(node)?
            .publisher_builder()
            .create()
            .map_err(|e| IpcError::publisher(self.name, self.qos.max_publishers, e))?;
        Ok(Publisher {
            port,
            notifier: self.notifier_if_wakes(node)?,
            channel: self.name,
        })
    }

    /// Subscribe (creating the channel if needed); the subscriber polls. A
    /// listener that nobody waits on still receives every wake-up, so only a
    /// reader that waits for new samples asks for one ([`Channel::waking_subscriber`]).
    pub fn subscriber(&self, node: &IpcNode, queue: Queue) -> Result<Subscriber<T>, IpcError> {
        self.subscribe(self.open_or_create(node)?, None, queue)
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
        self.subscribe(self.open_or_create(node)?, Some(node), queue)
    }

    /// Subscribe only if the channel exists, for tools that watch a cell:
    /// `Ok(None)` otherwise. The subscriber polls, as [`Channel::subscriber`].
    pub fn subscriber_if_exists(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<Option<Subscriber<T>>, IpcError> {
        match self.open_existing(node)? {
            Some(f) => self.subscribe(f, None, queue).map(Some),
            None => Ok(None),
        }
    }

    fn subscribe(
        &self,
        factory: Factory<T, ()>,
        wake_on: Option<&IpcNode>,
        queue: Queue,
    ) -> Result<Subscriber<T>, IpcError> {
        let port = factory
            .subscriber_builder()
            .buffer_size(queue.depth(&self.qos))
            .create()
            .map_err(|e| IpcError::port(self.name, e))?;
        let listener = match wake_on {
            Some(node) => self.listener_if_wakes(node)?,
            None => None,
        };
        Ok(Subscriber {
            port,
            listener,
            channel: self.name,
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
    port: RawPub<T>,
    notifier: Option<Notifier>,
    channel: &'static str,
}

impl<T: Message> Publisher<T> {
    /// Copy `value` into a loaned sample, send it and wake the readers.
    pub fn publish(&self, value: &T) -> Result<(), IpcError> {
        let sample = self
            .port
            .loan_uninit()
            .map_err(|e| IpcError::send(self.channel, e))?;
        sample
            .write_payload(*value)
            .send()
            .map_err(|e| IpcError::send(self.channel, e))?;
        if let Some(n) = &self.notifier {
            n.notify();
        }
        Ok(())
    }

    pub fn channel(&self) -> &'static str {
        self.channel
    }

    /// Connect the readers that appeared since the last send, without
    /// sending: a publisher that sends only now and then (a hot standby's,
    /// until it takes charge) keeps its connections made, so its first
    /// sends cost a real-time loop no more than the others. A failed
    /// connection is retried at the next send.
    pub fn update_connections(&self) {
        use iceoryx2::port::update_connections::UpdateConnections;
        let _ = self.port.update_connections();
    }
}

/// Subscriber of one channel.
pub struct Subscriber<T: Message> {
    port: RawSub<T>,
    listener: Option<Listener>,
    channel: &'static str,
}

impl<T: Message> Subscriber<T> {
    /// The next queued sample, copied out.
    pub fn receive(&self) -> Result<Option<T>, IpcError> {
        Ok(self
            .port
            .receive()
            .map_err(|e| IpcError::receive(self.channel, e))?
            .map(|s| *s))
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
        Ok(self
            .port
            .receive()
            .map_err(|e| IpcError::receive(self.channel, e))?
            .map(|s| (sender_pid(s.header()), *s)))
    }

    /// Hand every queued sample to `f` with the process id of its sender
    /// (0: unknown), oldest first; returns how many. The sender's pid is
    /// read from the sample's header (iceoryx2's node id encodes it):
    /// nothing is allocated or looked up.
    pub fn drain_from(&self, mut f: impl FnMut(i32, &T)) -> Result<usize, IpcError> {
        let mut n = 0;
        while let Some(s) = self
            .port
            .receive()
            .map_err(|e| IpcError::receive(self.channel, e))?
        {
            f(sender_pid(s.header()), &s);
            n += 1;
        }
        Ok(n)
    }

    /// Hand every queued sample to `f`, oldest first; returns how many.
    pub fn drain(&self, mut f: impl FnMut(&T)) -> Result<usize, IpcError> {
        let mut n = 0;
        while let Some(s) = self
            .port
            .receive()
            .map_err(|e| IpcError::receive(self.channel, e))?
        {
            f(&s);
            n += 1;
        }
        Ok(n)
    }

    /// Block until a new sample is announced or `timeout` passes (channels that
    /// wake; zero: consume the pending announcements without blocking); a
    /// channel that does not wake just sleeps `timeout`.
    pub fn wait(&self, timeout: Duration) -> Result<(), IpcError> {
        match &self.listener {
            Some(l) => l.wait(timeout),
            None => {
                std::thread::sleep(timeout);
                Ok(())
            }
        }
    }

    pub fn channel(&self) -> &'static str {
        self.channel
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
        if timeout.is_zero() {
            self.port.try_wait(|_| f())
        } else {
            self.port.timed_wait(|_| f(), timeout)
        }
        .map(|_| ())
        .map_err(|e| IpcError::receive(self.channel, e))
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

type RawFramePub = iceoryx2::port::publisher::Publisher<ipc::Service, [u16], FrameHeader>;
type RawFrameSub = iceoryx2::port::subscriber::Subscriber<ipc::Service, [u16], FrameHeader>;
/// A received frame: header and depths, in shared memory (no copy).
pub type FrameSample = iceoryx2::sample::Sample<ipc::Service, [u16], FrameHeader>;
/// A loaned frame being written in shared memory.
pub type FrameSampleMut = iceoryx2::sample_mut::SampleMut<ipc::Service, [u16], FrameHeader>;

impl FrameChannel {
    /// Publish frames of up to `max_pixels` depths.
    pub fn frame_publisher(
        &self,
        node: &IpcNode,
        max_pixels: usize,
    ) -> Result<FramePublisher, IpcError> {
        let port = self
            .open_or_create(node)?
            .publisher_builder()
            .initial_max_slice_len(max_pixels)
            .create()
            .map_err(|e| IpcError::publisher(self.name, self.qos.max_publishers, e))?;
        Ok(FramePublisher {
            port,
            notifier: self.notifier_if_wakes(node)?,
            channel: self.name,
        })
    }

    /// Subscribe to frames, polling (see [`Channel::subscriber`]).
    pub fn frame_subscriber(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<FrameSubscriber, IpcError> {
        self.frame_subscribe(self.open_or_create(node)?, None, queue)
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
        self.frame_subscribe(self.open_or_create(node)?, Some(node), queue)
    }

    /// Subscribe only if the channel exists, for tools: `Ok(None)` otherwise.
    /// Polls (no listener), as [`Channel::subscriber`].
    pub fn frame_subscriber_if_exists(
        &self,
        node: &IpcNode,
        queue: Queue,
    ) -> Result<Option<FrameSubscriber>, IpcError> {
        match self.open_existing(node)? {
            Some(f) => self.frame_subscribe(f, None, queue).map(Some),
            None => Ok(None),
        }
    }

    fn frame_subscribe(
        &self,
        factory: Factory<[u16], FrameHeader>,
        wake_on: Option<&IpcNode>,
        queue: Queue,
    ) -> Result<FrameSubscriber, IpcError> {
        let port = factory
            .subscriber_builder()
            .buffer_size(queue.depth(&self.qos))
            .create()
            .map_err(|e| IpcError::port(self.name, e))?;
        let listener = match wake_on {
            Some(node) => self.listener_if_wakes(node)?,
            None => None,
        };
        Ok(FrameSubscriber {
            port,
            listener,
            channel: self.name,
        })
    }
}

/// Publisher of depth frames: loan a frame, write it in place, send it.
pub struct FramePublisher {
    port: RawFramePub,
    notifier: Option<Notifier>,
    channel: &'static str,
}

impl FramePublisher {
    /// A frame of `pixels` depths in shared memory, zeroed, header zeroed.
    pub fn loan(&self, pixels: usize) -> Result<FrameSampleMut, IpcError> {
        let mut s = self
            .port
            .loan_slice(pixels)
            .map_err(|e| IpcError::send(self.channel, e))?;
        *s.user_header_mut() = FrameHeader::zeroed();
        Ok(s)
    }

    /// Send a loaned frame and wake the readers.
    pub fn send(&self, sample: FrameSampleMut) -> Result<(), IpcError> {
        sample.send().map_err(|e| IpcError::send(self.channel, e))?;
        if let Some(n) = &self.notifier {
            n.notify();
        }
        Ok(())
    }

    pub fn channel(&self) -> &'static str {
        self.channel
    }
}

/// Subscriber of depth frames.
pub struct FrameSubscriber {
    port: RawFrameSub,
    listener: Option<Listener>,
    channel: &'static str,
}

impl FrameSubscriber {
    /// The next queued frame.
    pub fn receive(&self) -> Result<Option<FrameSample>, IpcError> {
        self.port
            .receive()
            .map_err(|e| IpcError::receive(self.channel, e))
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
        match &self.listener {
            Some(l) => l.wait(timeout),
            None => {
                std::thread::sleep(timeout);
                Ok(())
            }
        }
    }

    pub fn channel(&self) -> &'static str {
        self.channel
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
        .filter_map(|s| s.listener.as_ref())
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
