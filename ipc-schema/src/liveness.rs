//! Liveness through iceoryx2's own means: every supervised service beats on
//! an event service of its own, `liveness/<service>`, which the supervisor
//! creates with the events iceoryx2 emits when a notifier ends (`ENDED`)
//! or is found dead with its node (`DEAD`, iceoryx2's node liveness). A
//! watcher waits on all it watches in one WaitSet ([`Vigil`]), each
//! attached with its deadline (the service's `heartbeat_timeout_ms`): it is
//! woken by a beat, by a death, or when a service has been silent for its
//! deadline, and otherwise sleeps; nothing is polled. (The deadline lives
//! on the WaitSet, not on the event service: iceoryx2 would warn of a
//! missed service deadline each time it tells of a dead notifier, which
//! is silent by then.) The supervisor beats on `liveness/supervisor` each time it
//! publishes `supervisor/health`, which the services' dead-man watches the
//! same way.
//!
//! A beat carries no data: what a service says (health, pids) stays on its
//! channels, where the senders are checked. A stranger's beats can only
//! wake a watcher early, never keep a silent service alive in the
//! supervisor's eyes for long: see [`Vigil::wait`]'s tick.

use std::time::Duration;

use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::EventOpenError;
use iceoryx2::service::port_factory::event::PortFactory;
use iceoryx2::waitset::{WaitSet, WaitSetGuard};

use crate::error::IpcError;
use crate::IpcNode;

type RawListener = iceoryx2::port::listener::Listener<ipc::Service>;
type RawNotifier = iceoryx2::port::notifier::Notifier<ipc::Service>;

/// The event service a service beats on: `liveness/<service>`.
pub fn liveness_name(service: &str) -> String {
    format!("liveness/{service}")
}

/// The supervisor's own liveness service name (its `supervisor/health` beats).
pub const SUPERVISOR: &str = "supervisor";

/// A beat: the service's loop ran.
pub const BEAT: EventId = EventId::new(1);
/// Emitted by iceoryx2 when a notifier is dropped: its service ended.
pub const ENDED: EventId = EventId::new(2);
/// Emitted by iceoryx2 when a notifier's node is found dead (its process
/// died) and cleaned up, by whichever process cleans up dead nodes.
pub const DEAD: EventId = EventId::new(3);

/// How many beats fit in a deadline: a service beats every
/// `deadline / BEATS_PER_DEADLINE` (or each loop, if its loop is slower).
pub const BEATS_PER_DEADLINE: u32 = 4;

/// What a watcher learned of one watched service.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pulse {
    /// it beat
    Beat,
    /// its notifier was dropped: it ended
    Ended,
    /// its notifier's node was found dead
    Dead,
}

fn err(service: &str, e: impl std::fmt::Debug) -> IpcError {
    IpcError::Liveness {
        service: service.to_string(),
        detail: format!("{e:?}"),
    }
}

fn service_name(service: &str) -> Result<ServiceName, IpcError> {
    liveness_name(service)
        .as_str()
        .try_into()
        .map_err(|e| err(service, e))
}

/// The one builder of every liveness service (opening and creating
/// processes must agree on these).
fn builder(
    node: &IpcNode,
    service: &str,
) -> Result<iceoryx2::service::builder::event::Builder<ipc::Service>, IpcError> {
    Ok(node
        .service_builder(&service_name(service)?)
        .event()
        .max_notifiers(4)
        .max_listeners(48)
        .max_nodes(64)
        .notifier_dropped_event(ENDED)
        .notifier_dead_event(DEAD))
}

/// A liveness service watched for silence beyond `deadline`.
pub struct Watched {
    port: RawListener,
    service: String,
    deadline: Duration,
}

impl Watched {
    /// Watch `service` for silence beyond `deadline`, creating its liveness
    /// service if it does not exist (the supervisor, before it starts the service).
    pub fn create(node: &IpcNode, service: &str, deadline: Duration) -> Result<Watched, IpcError> {
        let factory = builder(node, service)?
            .open_or_create()
            .map_err(|e| err(service, e))?;
        Watched::listen(&factory, service, deadline)
    }

    /// Watch `service` for silence beyond `deadline`, if its liveness
    /// service exists (`Ok(None)`: not supervised).
    pub fn open(
        node: &IpcNode,
        service: &str,
        deadline: Duration,
    ) -> Result<Option<Watched>, IpcError> {
        match builder(node, service)?.open() {
            Ok(factory) => Watched::listen(&factory, service, deadline).map(Some),
            Err(EventOpenError::DoesNotExist) => Ok(None),
            Err(e) => Err(err(service, e)),
        }
    }

    fn listen(
        factory: &PortFactory<ipc::Service>,
        service: &str,
        deadline: Duration,
    ) -> Result<Watched, IpcError> {
        let port = factory
            .listener_builder()
            .create()
            .map_err(|e| err(service, e))?;
        Ok(Watched {
            port,
            service: service.to_string(),
            deadline,
        })
    }

    /// The watched service's name.
    pub fn service(&self) -> &str {
        &self.service
    }

    /// Silence longer than this is missing the deadline.
    pub fn deadline(&self) -> Duration {
        self.deadline
    }

    /// Hand each kind of pulse pending to `f`, once (iceoryx2 counts
    /// repeated events of a kind as one); none pending: returns at once.
    pub fn take(&self, mut f: impl FnMut(Pulse)) -> Result<(), IpcError> {
        self.port
            .try_wait(|a| {
                f(if a.id == ENDED {
                    Pulse::Ended
                } else if a.id == DEAD {
                    Pulse::Dead
                } else {
                    Pulse::Beat
                })
            })
            .map(|_| ())
            .map_err(|e| err(&self.service, e))
    }
}

/// A service's beats on its liveness service, at most one per interval.
/// Beating allocates nothing; a beat is one notification (a syscall), so a
/// 1 kHz loop calls [`Beat::beat`] every period and beats every few dozen.
pub struct Beat {
    port: Option<RawNotifier>,
    interval_ns: u64,
    last_ns: u64,
}

impl Beat {
    /// Beats on `service`'s liveness service, every `deadline` /
    /// [`BEATS_PER_DEADLINE`] (its watcher's deadline); a service nobody
    /// watches (no liveness service: not supervised) gets a beat that does
    /// nothing.
    pub fn open(node: &IpcNode, service: &str, deadline: Duration) -> Result<Beat, IpcError> {
        match builder(node, service)?.open() {
            Ok(f) => Beat::notify_on(&f, service, deadline / BEATS_PER_DEADLINE),
            Err(EventOpenError::DoesNotExist) => Ok(Beat::none()),
            Err(e) => Err(err(service, e)),
        }
    }

    /// Beats on `service`'s liveness service, creating it if it does not
    /// exist (the supervisor's own, which the services watch; it beats with
    /// [`Beat::now`]).
    pub fn create(node: &IpcNode, service: &str) -> Result<Beat, IpcError> {
        let factory = builder(node, service)?
            .open_or_create()
            .map_err(|e| err(service, e))?;
        Beat::notify_on(&factory, service, Duration::ZERO)
    }

    fn notify_on(
        factory: &PortFactory<ipc::Service>,
        service: &str,
        interval: Duration,
    ) -> Result<Beat, IpcError> {
        let port = factory
            .notifier_builder()
            .default_event_id(BEAT)
            .create()
            .map_err(|e| err(service, e))?;
        Ok(Beat {
            port: Some(port),
            interval_ns: interval.as_nanos() as u64,
            last_ns: 0,
        })
    }

    /// A beat that does nothing (an unsupervised service).
    pub fn none() -> Beat {
        Beat {
            port: None,
            interval_ns: u64::MAX,
            last_ns: 0,
        }
    }

    /// The loop ran at `now_ns` [ns, CLOCK_MONOTONIC; the clock's time,
    /// not a loop's schedule, which falls behind when the loop is late]:
    /// beat if the last beat is an interval old.
    pub fn beat(&mut self, now_ns: u64) {
        if now_ns.saturating_sub(self.last_ns) >= self.interval_ns {
            self.now(now_ns);
        }
    }

    /// Beat now, whatever the interval (the supervisor, on each health).
    pub fn now(&mut self, now_ns: u64) {
        if let Some(p) = &self.port {
            self.last_ns = now_ns;
            // a failed wake-up is not the service's error: its watcher
            // hears the next beat, or its deadline says it
            let _ = p.notify();
        }
    }
}

/// What woke a [`Vigil`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wake {
    /// the tick (every `tick` of [`Vigil::new`])
    Tick,
    /// watched service `i` has pulses to take ([`Watched::take`])
    Pulse(usize),
    /// watched service `i` was silent for its deadline
    Missed(usize),
}

/// One WaitSet over every watched service (each with its deadline) and a
/// tick; it lives as long as the watching loop, so each deadline runs from
/// that service's last pulse.
pub struct Vigil<'w> {
    waitset: &'w WaitSet<ipc::Service>,
    tick: WaitSetGuard<'w, 'static, ipc::Service>,
    guards: Vec<WaitSetGuard<'w, 'w, ipc::Service>>,
}

/// The WaitSet a [`Vigil`] borrows (create it first, in the watching loop's scope).
pub fn waitset() -> Result<WaitSet<ipc::Service>, IpcError> {
    WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| err("waitset", e))
}

impl<'w> Vigil<'w> {
    /// Watch `watched` on `waitset`, each with its deadline, and tick every `tick`.
    pub fn new(
        waitset: &'w WaitSet<ipc::Service>,
        watched: &'w [Watched],
        tick: Duration,
    ) -> Result<Vigil<'w>, IpcError> {
        let tick = waitset.attach_interval(tick).map_err(|e| err("tick", e))?;
        let mut guards = Vec::with_capacity(watched.len());
        for w in watched {
            guards.push(
                waitset
                    .attach_deadline(&w.port, w.deadline)
                    .map_err(|e| err(&w.service, e))?,
            );
        }
        Ok(Vigil {
            waitset,
            tick,
            guards,
        })
    }

    /// Sleep until something wakes it (at the latest the next tick, or
    /// `timeout`), then hand `f` what did, each once. A signal also ends the
    /// wait (`f` is then not called).
    pub fn wait(&self, timeout: Duration, mut f: impl FnMut(Wake)) -> Result<(), IpcError> {
        self.waitset
            .wait_and_process_once_with_timeout(
                |id| {
                    if id.has_event_from(&self.tick) {
                        f(Wake::Tick);
                    }
                    for (i, g) in self.guards.iter().enumerate() {
                        if id.has_event_from(g) {
                            f(Wake::Pulse(i));
                        } else if id.has_missed_deadline(g) {
                            f(Wake::Missed(i));
                        }
                    }
                    CallbackProgression::Continue
                },
                timeout,
            )
            .map(|_| ())
            .map_err(|e| err("waitset", e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [ns] since the first call (beats only compare times)
    fn now() -> u64 {
        static T0: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
        T0.get_or_init(std::time::Instant::now).elapsed().as_nanos() as u64 + 1_000_000_000
    }

    fn prefix(tag: &str) -> String {
        format!("lv{}{tag}_", std::process::id())
    }

    /// A beat wakes the watcher; silence beyond the deadline is reported
    /// once the deadline has passed, not before; a dropped notifier is ENDED.
    #[test]
    fn beats_wake_silence_misses_the_deadline_and_an_end_is_told() {
        let p = prefix("a");
        let node = crate::node("watcher", &p).unwrap();
        let deadline = Duration::from_millis(60);
        let watched = vec![Watched::create(&node, "svc", deadline).unwrap()];
        let ws = waitset().unwrap();
        let vigil = Vigil::new(&ws, &watched, Duration::from_secs(10)).unwrap();
        let other = crate::node("service", &p).unwrap();
        let mut beat = Beat::open(&other, "svc", deadline).unwrap();
        assert_eq!(beat.interval_ns, 15_000_000);

        // one wait: what woke the vigil, and the pulses taken
        let wake_once = || {
            let mut woke = Vec::new();
            vigil
                .wait(Duration::from_secs(1), |w| woke.push(w))
                .unwrap();
            let mut pulses = Vec::new();
            watched[0].take(|p| pulses.push(p)).unwrap();
            (woke, pulses)
        };
        beat.beat(now());
        assert_eq!(wake_once(), (vec![Wake::Pulse(0)], vec![Pulse::Beat]));

        // silent from here: woken by the deadline, not before it
        let t0 = now();
        let mut woke = Vec::new();
        while woke.is_empty() {
            vigil
                .wait(Duration::from_secs(1), |w| woke.push(w))
                .unwrap();
        }
        let waited = now() - t0;
        assert_eq!(woke, vec![Wake::Missed(0)]);
        assert!((55_000_000..200_000_000).contains(&waited), "{waited} ns");

        // the service ends: its notifier's drop is told
        drop(beat);
        assert_eq!(wake_once(), (vec![Wake::Pulse(0)], vec![Pulse::Ended]));
    }

    /// Unsupervised (no liveness service), a beat does nothing and an
    /// opened watch is `None`.
    #[test]
    fn without_a_liveness_service_beats_do_nothing() {
        let p = prefix("b");
        let node = crate::node("alone", &p).unwrap();
        let mut beat = Beat::open(&node, "svc", Duration::from_millis(10)).unwrap();
        assert!(beat.port.is_none());
        beat.beat(now());
        assert!(Watched::open(&node, "svc", Duration::from_millis(10))
            .unwrap()
            .is_none());
    }
}
