//! Logs of every phri process: `tracing` with levels, timestamps and
//! `RUST_LOG` filters, written to stderr by a background thread (a
//! non-blocking writer: a slow terminal or pipe never stalls the caller).
//!
//! A real-time thread must not format or write a line at all: it posts a
//! small `Copy` event to a [`Deferred`] mailbox (no allocation, no lock, no
//! formatting), and a thread at normal priority turns it into a log line.

use std::fmt::Display;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use tracing_appender::non_blocking::WorkerGuard;
use tracing_subscriber::fmt::format::{self, FormatEvent, FormatFields};
use tracing_subscriber::fmt::time::{FormatTime, SystemTime};
use tracing_subscriber::fmt::FmtContext;
use tracing_subscriber::registry::LookupSpan;
use tracing_subscriber::EnvFilter;

/// Filter when `RUST_LOG` is unset or empty: everything at `info` and
/// above, but DDS's own chatter (RustDDS, ros2-client: sockets, locators)
/// from `warn` up.
pub const DEFAULT_FILTER: &str = "info,rustdds=warn,ros2_client=warn";

/// Keeps the log writer alive: dropping it flushes the lines still queued.
/// Hold it in `main` (or the service body) until the process ends.
#[must_use = "dropping the guard stops the log writer"]
pub struct LogGuard {
    _worker: Option<WorkerGuard>,
}

/// Install the process's subscriber: `RUST_LOG` (e.g. `warn`,
/// `phri_sim=debug`) else [`DEFAULT_FILTER`]; lines carry an RFC 3339
/// timestamp, the level and the binary's name; colours only on a terminal.
/// A second call (a test installing twice) keeps the first subscriber.
pub fn init(bin: &'static str) -> LogGuard {
    let filter = std::env::var("RUST_LOG")
        .ok()
        .filter(|f| !f.trim().is_empty())
        .and_then(|f| EnvFilter::try_new(f).ok())
        .unwrap_or_else(|| EnvFilter::new(DEFAULT_FILTER));
    let (writer, guard) = tracing_appender::non_blocking(std::io::stderr());
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let installed = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(writer)
        .with_ansi(ansi)
        .event_format(Line { bin })
        .try_init()
        .is_ok();
    if installed {
        tracing::debug!(pid = std::process::id(), "logging");
    }
    LogGuard {
        _worker: installed.then_some(guard),
    }
}

/// One log line: `2026-11-23T22:37:54.123456Z  WARN phri-sim: message k=v`
/// (the services share the supervisor's stderr: every line names its
/// binary, and the service when another name than the binary's, as the
/// repulsion workers: `phri-repulsion/repulsion1`).
struct Line {
    bin: &'static str,
}

/// The service's name as the supervisor knows it, once known ([`set_service`]).
static SERVICE: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Name this process's log lines after service `name` too (when the binary's
/// own name, `phri-<name>`, does not already say it).
pub fn set_service(name: &str) {
    let _ = SERVICE.set(name.to_string());
}

impl<S, N> FormatEvent<S, N> for Line
where
    S: tracing::Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &FmtContext<'_, S, N>,
        mut writer: format::Writer<'_>,
        event: &tracing::Event<'_>,
    ) -> std::fmt::Result {
        SystemTime.format_time(&mut writer)?;
        write!(writer, " {:>5} {}", event.metadata().level(), self.bin)?;
        if let Some(s) = SERVICE.get() {
            if self.bin.strip_prefix("phri-") != Some(s.as_str()) {
                write!(writer, "/{s}")?;
            }
        }
        write!(writer, ": ")?;
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

/// The real-time side of a deferred log: [`Deferred::post`] never blocks,
/// allocates, locks or formats; a full mailbox drops the event and counts it.
pub struct Deferred<T> {
    tx: SyncSender<T>,
    dropped: Arc<AtomicU64>,
}

impl<T: Send + 'static> Deferred<T> {
    /// Post `event` for the logging thread. The mailbox is a bounded channel
    /// read only by polling (`try_recv`): no receiver ever waits on it, so a
    /// post takes no lock that a lower-priority thread could hold.
    pub fn post(&self, event: T) {
        if self.tx.try_send(event).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// A mailbox of `capacity` events and the thread (normal priority; start it
/// before the caller turns real-time) that logs each with `log` every
/// `poll`, until `running` turns false and the mailbox is drained.
pub fn deferred<T: Send + 'static>(
    capacity: usize,
    poll: Duration,
    running: impl Fn() -> bool + Send + 'static,
    log: impl Fn(T) + Send + 'static,
) -> (Deferred<T>, JoinHandle<()>) {
    let (tx, rx) = sync_channel(capacity.max(1));
    let dropped = Arc::new(AtomicU64::new(0));
    let seen = Arc::clone(&dropped);
    let thread = std::thread::spawn(move || drain(rx, poll, running, log, seen));
    (Deferred { tx, dropped }, thread)
}

fn drain<T>(
    rx: Receiver<T>,
    poll: Duration,
    running: impl Fn() -> bool,
    log: impl Fn(T),
    dropped: Arc<AtomicU64>,
) {
    let mut reported = 0;
    loop {
        let alive = running();
        loop {
            match rx.try_recv() {
                Ok(e) => log(e),
                Err(TryRecvError::Empty) => break,
                // every sender is gone: the real-time loop ended
                Err(TryRecvError::Disconnected) => {
                    report_dropped(&dropped, &mut reported);
                    return;
                }
            }
        }
        report_dropped(&dropped, &mut reported);
        if !alive {
            return;
        }
        std::thread::sleep(poll);
    }
}

fn report_dropped(dropped: &AtomicU64, reported: &mut u64) {
    let now = dropped.load(Ordering::Relaxed);
    if now > *reported {
        tracing::warn!("{} log events dropped (mailbox full)", now - *reported);
        *reported = now;
    }
}

/// Log `event` at `warn` (the common case of a deferred event).
pub fn warn<T: Display>(event: T) {
    tracing::warn!("{event}");
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn deferred_events_arrive_in_order_and_overflow_is_counted() {
        let got = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&got);
        let (tx, thread) = deferred(
            4,
            Duration::from_millis(1),
            || true,
            move |e: u32| sink.lock().unwrap().push(e),
        );
        for k in 0..3 {
            tx.post(k);
        }
        // a burst beyond the capacity before the thread drains: some are dropped
        for k in 3..1000 {
            tx.post(k);
        }
        let dropped = tx.dropped.load(Ordering::Relaxed);
        drop(tx);
        thread.join().unwrap();
        let got = got.lock().unwrap();
        assert_eq!(got.len() as u64 + dropped, 1000);
        assert!(got.windows(2).all(|w| w[0] < w[1]), "in order");
        assert_eq!(&got[..3], &[0, 1, 2]);
    }
}
