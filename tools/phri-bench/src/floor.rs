//! The machine's floor: how late a thread at the torque loop's priority, on
//! its CPU, wakes for a periodic deadline (what `cyclictest` measures),
//! counted the way the robot's loop counts its overruns (a wake-up more
//! than half a period late, after which the schedule slips to it). Run
//! beside a cell, it tells the part of the loop's tail that is the
//! machine's (a virtual machine's host, the kernel) from phri's own.

use phri_runtime::{now_ns, sleep_until_ns};
use serde_json::{json, Value};

/// Wake-up latency bins \[µs\]: 1 µs each, the last holds everything above.
const BINS: usize = 20_000;

/// What a floor thread measured.
#[derive(Clone, Debug)]
pub struct Floor {
    period_ns: u64,
    /// wake-ups per latency \[µs\]
    hist: Vec<u64>,
    /// wake-ups more than half a period late
    late: u64,
    max_ns: u64,
    /// the thread ran under SCHED_FIFO at the priority asked, on the CPU asked
    realtime: Result<(), String>,
}

impl Floor {
    /// Wake-ups counted.
    pub fn wakeups(&self) -> u64 {
        self.hist.iter().sum()
    }

    /// The latency \[µs\] under which a share `q` of the wake-ups fell.
    fn percentile(&self, q: f64) -> Option<f64> {
        let n = self.wakeups();
        if n == 0 {
            return None;
        }
        let rank = ((q * n as f64).ceil() as u64).clamp(1, n);
        let mut seen = 0;
        for (us, &c) in self.hist.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return Some(us as f64);
            }
        }
        None
    }

    /// As JSON: wake-ups, those over half a period late and their share,
    /// latency p50/p99/max \[µs\], and whether the thread got its priority.
    pub fn to_json(&self) -> Value {
        let n = self.wakeups();
        json!({
            "period_us": self.period_ns as f64 / 1e3,
            "wakeups": n,
            "late_over_half_period": self.late,
            "late_share": if n > 0 { self.late as f64 / n as f64 } else { 0.0 },
            "latency_us": {
                "p50": self.percentile(0.5),
                "p99": self.percentile(0.99),
                "max": self.max_ns as f64 / 1e3,
            },
            "realtime": match &self.realtime {
                Ok(()) => Value::Null,
                Err(e) => Value::String(e.clone()),
            },
        })
    }
}

/// Run the calling thread on `cpu` (`None`: any) under SCHED_FIFO at
/// `priority` (0: the normal scheduler), waking every `period_ns` until
/// `until_ns` \[CLOCK_MONOTONIC\], counting from `from_ns` on.
pub fn measure(
    cpu: Option<usize>,
    priority: i32,
    period_ns: u64,
    from_ns: u64,
    until_ns: u64,
) -> Floor {
    let mut realtime = Ok(());
    if let Some(c) = cpu {
        // SAFETY: a zeroed cpu_set_t is a valid empty set; CPU_SET on it and
        // sched_setaffinity on the calling thread with its size.
        let rc = unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(c, &mut set);
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set)
        };
        if rc != 0 {
            realtime = Err(format!("CPU {c}: {}", std::io::Error::last_os_error()));
        }
    }
    if priority > 0 {
        if let Err(e) = phri_runtime::rt::make_realtime(priority) {
            realtime = Err(e.to_string());
        }
    }
    let period_ns = period_ns.max(1);
    let mut hist = vec![0u64; BINS];
    let (mut late, mut max_ns) = (0u64, 0u64);
    let mut deadline = now_ns() + period_ns;
    while deadline < until_ns {
        sleep_until_ns(deadline);
        let woke = now_ns();
        let lateness = woke.saturating_sub(deadline);
        if deadline >= from_ns {
            hist[((lateness / 1000) as usize).min(BINS - 1)] += 1;
            max_ns = max_ns.max(lateness);
            if lateness > period_ns / 2 {
                late += 1;
            }
        }
        // as the robot's loop: a wake-up more than half a period late slips the schedule
        deadline = if lateness > period_ns / 2 {
            woke
        } else {
            deadline
        } + period_ns;
    }
    phri_runtime::rt::make_normal();
    Floor {
        period_ns,
        hist,
        late,
        max_ns,
        realtime,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_and_the_late_share_come_from_the_histogram() {
        let mut f = Floor {
            period_ns: 1_000_000,
            hist: vec![0; BINS],
            late: 2,
            max_ns: 900_000,
            realtime: Ok(()),
        };
        f.hist[10] = 97;
        f.hist[600] = 2;
        f.hist[900] = 1;
        let j = f.to_json();
        assert_eq!(j["wakeups"], 100);
        assert_eq!(j["latency_us"]["p50"], 10.0);
        assert_eq!(j["latency_us"]["p99"], 600.0);
        assert_eq!(j["latency_us"]["max"], 900.0);
        assert_eq!(j["late_share"], 0.02);
        assert_eq!(j["realtime"], Value::Null);
    }

    #[test]
    fn a_run_wakes_at_most_once_a_period_and_counts_what_it_measured() {
        let start = now_ns();
        let f = measure(None, 0, 1_000_000, start, start + 50_000_000);
        assert!((1..=50).contains(&f.wakeups()), "{}", f.wakeups());
        assert!(f.late <= f.wakeups());
    }
}
