//! Pacing and logging for a source of frames: [`Ticks`], a schedule that
//! never runs late work back to back, and [`RateLimited`], a repeated error
//! logged once a second.

/// The replay's schedule: a tick every `period_ns` [ns, CLOCK_MONOTONIC],
/// anchored at the start. A tick handled late never makes the next ones run
/// back to back: the ticks that passed meanwhile are dropped (counted), and
/// the next tick waits at least as long as the late one worked, so that the
/// replay takes at most half the CPU whatever its rate and its files cost.
#[derive(Clone, Debug)]
pub struct Ticks {
    period_ns: u64,
    next_ns: u64,
    dropped: u64,
}

impl Ticks {
    /// Ticks every `period_ns` (at least 1 ns), the first at `start_ns + period_ns`.
    pub fn new(start_ns: u64, period_ns: u64) -> Ticks {
        let period_ns = period_ns.max(1);
        Ticks {
            period_ns,
            next_ns: start_ns.saturating_add(period_ns),
            dropped: 0,
        }
    }

    /// When the next tick is due \[ns\]: sleep until then.
    pub fn deadline_ns(&self) -> u64 {
        self.next_ns
    }

    /// The tick due at [`Ticks::deadline_ns`] began its work at `woke_ns`
    /// and ended it at `done_ns`: schedule the next one. On time, that is
    /// one period later; otherwise the first tick of the schedule no earlier
    /// than `done_ns + (done_ns − woke_ns)`, the ones before it dropped.
    /// Returns the new deadline.
    pub fn done(&mut self, woke_ns: u64, done_ns: u64) -> u64 {
        let earliest = done_ns.saturating_add(done_ns.saturating_sub(woke_ns));
        let mut next = self.next_ns.saturating_add(self.period_ns);
        if next < earliest {
            let behind = (earliest - next).div_ceil(self.period_ns);
            self.dropped += behind;
            next = next.saturating_add(behind.saturating_mul(self.period_ns));
        }
        self.next_ns = next;
        next
    }

    /// Ticks dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

/// A repeated error logged at most once per `interval_ns`, with how many
/// occurred since the last line (a bad file replayed at 30 Hz is one line a
/// second, not thirty).
#[derive(Clone, Debug)]
pub struct RateLimited {
    interval_ns: u64,
    next_line_ns: Option<u64>,
    count: u64,
}

impl RateLimited {
    /// Once per second.
    pub const SECOND_NS: u64 = 1_000_000_000;

    /// At most one line per `interval_ns` \[ns\]; the first occurrence is logged.
    pub fn new(interval_ns: u64) -> RateLimited {
        RateLimited {
            interval_ns,
            next_line_ns: None,
            count: 0,
        }
    }

    /// One more occurrence at `now_ns` \[ns\]: `Some(n)` when a line is due, `n`
    /// the occurrences it reports (this one and the ones not logged before it).
    pub fn hit(&mut self, now_ns: u64) -> Option<u64> {
        self.count += 1;
        if self.next_line_ns.is_some_and(|t| now_ns < t) {
            return None;
        }
        self.next_line_ns = Some(now_ns.saturating_add(self.interval_ns));
        let n = self.count;
        self.count = 0;
        Some(n)
    }
}
