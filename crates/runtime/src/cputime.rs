//! The CPU time a process has used, from `/proc` (the supervisor's budget
//! and starvation judgements, the monitor's live view).

/// CPU time `pid` has used so far, all its threads \[ns\]: from each thread's
/// `schedstat` (nanoseconds), else from `stat`'s utime + stime (clock
/// ticks). `None`: no such process (or `/proc` unreadable).
pub fn cpu_time_ns(pid: u32) -> Option<u64> {
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
    }

    #[test]
    fn steal_is_read_and_never_runs_backwards() {
        let a = steal_ns().expect("/proc/stat");
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert!(steal_ns().unwrap() >= a);
    }
}
