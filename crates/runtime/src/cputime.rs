//! The CPU time a process has used, from `/proc` (the supervisor's budget
//! and starvation judgements, the monitor's live view).

/// CPU time `pid` has used so far, all its threads \[ns\]: the process's
/// CPU-time clock (`clock_getcpuclockid`, one system call: the supervisor
/// samples every service 50 times a second), else the sum of each thread's
/// `schedstat` (nanoseconds, the same count), else `stat`'s utime + stime
/// (clock ticks). `None`: no such process (or `/proc` unreadable).
pub fn cpu_time_ns(pid: u32) -> Option<u64> {
    clock_ns(pid).or_else(|| proc_time_ns(pid))
}

/// `pid`'s CPU-time clock \[ns\]; `None` when the kernel gives none.
fn clock_ns(pid: u32) -> Option<u64> {
    let pid = libc::pid_t::try_from(pid).ok().filter(|&p| p > 0)?;
    let mut clock: libc::clockid_t = 0;
    // SAFETY: `clock` is a valid place for the clock's id
    if unsafe { libc::clock_getcpuclockid(pid, &mut clock) } != 0 {
        return None;
    }
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid place for the time
    if unsafe { libc::clock_gettime(clock, &mut t) } != 0 {
        return None;
    }
    let secs = u64::try_from(t.tv_sec).ok()?;
    let nanos = u64::try_from(t.tv_nsec).ok()?;
    Some(secs.saturating_mul(1_000_000_000).saturating_add(nanos))
}

/// CPU time of `pid` from `/proc` \[ns\] ([`cpu_time_ns`]'s second and third ways).
fn proc_time_ns(pid: u32) -> Option<u64> {
    if let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) {
        let mut total = 0u64;
        let mut any = false;
        for t in tasks.flatten() {
            let Ok(text) = std::fs::read_to_string(t.path().join("schedstat")) else {
                continue;
            };
            if let Some(ns) = text
                .split_whitespace()
                .next()
                .and_then(|f| f.parse::<u64>().ok())
            {
                total = total.saturating_add(ns);
                any = true;
            }
        }
        if any {
            return Some(total);
        }
    }
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // after the parenthesised command name (which may hold spaces and
    // parentheses): fields 14 and 15 of stat(5), utime and stime
    let (_, rest) = stat.rsplit_once(')')?;
    let mut f = rest.split_whitespace().skip(11);
    let utime: u64 = f.next()?.parse().ok()?;
    let stime: u64 = f.next()?.parse().ok()?;
    // SAFETY: sysconf has no preconditions
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as u64;
    Some((utime + stime).saturating_mul(1_000_000_000 / hz))
}

/// Time a hypervisor has taken from this machine so far, per CPU on average
/// \[ns\] (`steal` of `/proc/stat`, in clock ticks): a process's CPU time
/// leaves it out, so a share of a CPU judged on a virtual machine is judged
/// against what the machine had. `None`: `/proc/stat` unreadable.
pub fn steal_ns() -> Option<u64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let mut lines = stat.lines();
    // "cpu user nice system idle iowait irq softirq steal …": all CPUs
    let steal: u64 = lines.next()?.split_whitespace().nth(8)?.parse().ok()?;
    let cpus = lines.take_while(|l| l.starts_with("cpu")).count().max(1) as u64;
    // SAFETY: sysconf has no preconditions
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as u64;
    Some(steal.saturating_mul(1_000_000_000 / hz) / cpus)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_has_used_some_cpu_and_a_missing_one_none() {
        let mine = cpu_time_ns(std::process::id()).unwrap();
        // busy for 0.1 s of wall clock: several scheduler ticks account it
        let start = std::time::Instant::now();
        let mut x = 0u64;
        while start.elapsed() < std::time::Duration::from_millis(100) {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        assert!(cpu_time_ns(std::process::id()).unwrap() > mine);
        assert_eq!(cpu_time_ns(u32::MAX - 1), None);
        assert_eq!(cpu_time_ns(0), None);
    }

    #[test]
    fn the_clock_counts_every_thread_and_never_less_than_proc() {
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::sync::Arc;
        let me = std::process::id();
        let before = clock_ns(me).unwrap();
        // a second thread busy until it used 50 ms of its own CPU time
        let done = Arc::new(AtomicBool::new(false));
        let busy = {
            let done = Arc::clone(&done);
            std::thread::spawn(move || {
                let mut t = libc::timespec {
                    tv_sec: 0,
                    tv_nsec: 0,
                };
                let mut x = 0u64;
                while t.tv_sec == 0 && t.tv_nsec < 50_000_000 {
                    x = std::hint::black_box(x.wrapping_add(1));
                    // SAFETY: `t` is a valid place for the time
                    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
                }
                done.store(true, Ordering::Release);
                // alive while the others read (/proc counts live threads only)
                std::thread::sleep(std::time::Duration::from_millis(200));
            })
        };
        while !done.load(Ordering::Acquire) {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let (a, b) = (proc_time_ns(me).unwrap(), clock_ns(me).unwrap());
        busy.join().unwrap();
        assert!(b - before >= 50_000_000, "{before} → {b} ns");
        // /proc sums the live threads (to a scheduler tick where it falls
        // back to `stat`); the clock counts ended ones too, read after it
        assert!(a <= b + 10_000_000, "/proc {a} ns, clock {b} ns");
    }

    #[test]
    fn steal_is_read_and_never_runs_backwards() {
        let a = steal_ns().expect("/proc/stat");
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert!(steal_ns().unwrap() >= a);
    }
}
