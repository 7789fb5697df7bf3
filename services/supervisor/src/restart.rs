//! Restart policy with exponential back-off.

/// Per-service restart bookkeeping (times in ns, CLOCK_MONOTONIC).
#[derive(Clone, Debug, Default)]
pub struct RestartPolicy {
    /// restarts so far
    pub restarts: u32,
    quick_failures: u32,
    started_ns: u64,
}

impl RestartPolicy {
    /// The service (re)started at `now_ns`.
    pub fn started(&mut self, now_ns: u64) {
        self.started_ns = now_ns;
    }

    /// The service exited at `now_ns`: when to start it again \[ns\].
    pub fn exited(&mut self, now_ns: u64, min_ms: u64, max_ms: u64, stable_after_s: f64) -> u64 {
        let ran_s = now_ns.saturating_sub(self.started_ns) as f64 * 1e-9;
        if ran_s >= stable_after_s {
            self.quick_failures = 0;
        }
        let delay_ms = min_ms
            .saturating_mul(1u64 << self.quick_failures.min(20))
            .min(max_ms);
        self.quick_failures += 1;
        self.restarts += 1;
        now_ns + delay_ms * 1_000_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backoff_doubles_for_quick_crashes_and_resets_after_a_stable_run() {
        let mut p = RestartPolicy::default();
        let s = 1_000_000_000u64;
        p.started(0);
        assert_eq!(p.exited(s / 10, 50, 400, 5.0), s / 10 + 50_000_000);
        p.started(s);
        assert_eq!(p.exited(s + 1, 50, 400, 5.0), s + 1 + 100_000_000);
        p.started(2 * s);
        assert_eq!(p.exited(2 * s, 50, 400, 5.0), 2 * s + 200_000_000);
        p.started(3 * s);
        assert_eq!(p.exited(3 * s, 50, 400, 5.0), 3 * s + 400_000_000); // capped
        p.started(4 * s);
        assert_eq!(p.exited(10 * s, 50, 400, 5.0), 10 * s + 50_000_000); // ran 6 s: reset
        assert_eq!(p.restarts, 5);
    }
}
