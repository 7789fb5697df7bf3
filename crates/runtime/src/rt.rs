//! Real-time scheduling where the machine permits it.

/// What could not be done to make a process real-time.
#[derive(Debug, thiserror::Error)]
pub enum RtError {
    /// no real-time priority asked for (0 or below): the normal scheduler
    #[error("real-time priority 0: normal scheduler")]
    NoPriority,
    /// the system refused SCHED_FIFO (no permission, no real-time budget)
    #[error("SCHED_FIFO {priority} refused: {source}")]
    Scheduler {
        /// the priority asked for
        priority: i32,
        /// the system's error
        source: std::io::Error,
    },
    /// the system refused to lock the process's memory (`mlockall`)
    #[error("mlockall refused: {0}")]
    Lock(std::io::Error),
}

/// Lock the memory the calling process has mapped so far, then run it under
/// SCHED_FIFO at `priority` (1-99) (call it after creating its ports). The
/// lock comes first: faulting in and locking every page (the binary, the
/// heap, each shared-memory segment) takes milliseconds, which at real-time
/// priority would stall every lower-priority loop on the same CPU (a
/// restarted residual service, the highest on the torque loop's CPU, kept
/// the robot and its controller from running and the robot braked). Not
/// MCL_FUTURE: a real-time loop would then stall while the kernel faults in
/// and locks every shared-memory segment of a publisher that appears later
/// (a restarted perception worker, a monitor), milliseconds per segment.
/// Its descriptor table is sized first ([`reserve_descriptors`]).
/// Returns a description of what could not be done (without SCHED_FIFO the
/// process runs under the normal scheduler), never fails hard.
pub fn make_realtime(priority: i32) -> Result<(), RtError> {
    if priority <= 0 {
        return Err(RtError::NoPriority);
    }
    reserve_descriptors(RESERVED_DESCRIPTORS);
    // SAFETY: plain syscall with a valid flag.
    let locked = unsafe { libc::mlockall(libc::MCL_CURRENT) };
    let lock_error = std::io::Error::last_os_error();
    fifo(priority)?;
    if locked != 0 {
        return Err(RtError::Lock(lock_error));
    }
    Ok(())
}

/// The descriptors a real-time process's table holds room for from its
/// start (fewer if `RLIMIT_NOFILE` allows fewer): 1024 on a default limit.
pub const RESERVED_DESCRIPTORS: u64 = 4096;

/// Grow the calling process's descriptor table now to hold `n` descriptors
/// (at most its `RLIMIT_NOFILE`), so that a real-time loop never grows it.
/// Every shared-memory connection to a new peer opens descriptors inside
/// the loop (iceoryx2 connects lazily, in `send` and `receive`), and the
/// kernel grows a table shared by several threads only after an RCU grace
/// period (`expand_files` → `synchronize_rcu`): 14-16 ms on these 2 cores,
/// seen in ftrace as both controllers blocked in `openat` as their 257th
/// descriptor opened when the ROS 2 bridge's ports appeared (the robot
/// braked after 14 missed commands). The table never shrinks. Returns the
/// table's size as the kernel reports it (`FDSize`, 0 unknown).
pub fn reserve_descriptors(n: u64) -> u64 {
    let highest = libc::c_int::try_from(n.min(descriptor_limit()).saturating_sub(1)).unwrap_or(0);
    if highest > 0 {
        // a descriptor duplicated at `highest` or above makes the kernel
        // grow the table to hold it; closed at once, the table stays
        // SAFETY: plain syscalls on a descriptor this function opened
        unsafe {
            let fd = libc::open(c"/dev/null".as_ptr(), libc::O_RDONLY | libc::O_CLOEXEC);
            if fd >= 0 {
                let high = libc::fcntl(fd, libc::F_DUPFD_CLOEXEC, highest);
                if high >= 0 {
                    libc::close(high);
                }
                libc::close(fd);
            }
        }
    }
    descriptor_table_size()
}

/// The calling process's soft `RLIMIT_NOFILE` (0 when unknown).
pub fn descriptor_limit() -> u64 {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: a valid rlimit to fill in
    match unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) } {
        0 => limit.rlim_cur,
        _ => 0,
    }
}

/// The calling process's descriptor table size (`FDSize` of
/// `/proc/self/status`), 0 when unknown.
pub fn descriptor_table_size() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("FDSize:"))
                .and_then(|v| v.trim().parse().ok())
        })
        .unwrap_or(0)
}

/// Move the calling thread, already under SCHED_FIFO, to `priority`
/// (1-99): one syscall, nothing allocated, for a loop whose role changes
/// its rank (a hot standby taking charge). A thread under the normal
/// scheduler is left there (the machine refused SCHED_FIFO before).
pub fn set_fifo_priority(priority: i32) -> Result<(), RtError> {
    if priority <= 0 {
        return Err(RtError::NoPriority);
    }
    // SAFETY: plain syscall on the calling thread.
    if unsafe { libc::sched_getscheduler(0) } != libc::SCHED_FIFO {
        return Ok(());
    }
    fifo(priority)
}

/// Run the calling thread, a watchdog of real-time services, under
/// SCHED_FIFO at `priority` (1-99) with SCHED_RESET_ON_FORK: processes and
/// threads it starts begin under the normal scheduler (each service sets
/// its own priority). A watchdog below the services it watches can be
/// starved by the one that misbehaves, and then blames nobody. Memory is
/// not locked: the thread does not run a control loop. Its descriptor table
/// is sized first, as a service's ([`reserve_descriptors`]): the watchdog
/// opens pipes and channels as it starts and restarts services.
pub fn make_watchdog(priority: i32) -> Result<(), RtError> {
    if priority <= 0 {
        return Err(RtError::NoPriority);
    }
    reserve_descriptors(RESERVED_DESCRIPTORS);
    let param = libc::sched_param {
        sched_priority: priority.min(99),
    };
    // SAFETY: plain syscall with valid arguments on the calling thread.
    let rc = unsafe {
        libc::sched_setscheduler(0, libc::SCHED_FIFO | libc::SCHED_RESET_ON_FORK, &param)
    };
    if rc != 0 {
        return Err(RtError::Scheduler {
            priority,
            source: std::io::Error::last_os_error(),
        });
    }
    Ok(())
}

/// SCHED_FIFO at `priority` (capped at 99) for the calling thread.
fn fifo(priority: i32) -> Result<(), RtError> {
    let param = libc::sched_param {
        sched_priority: priority.min(99),
    };
    // SAFETY: plain syscall with valid arguments.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        return Err(RtError::Scheduler {
            priority,
            source: std::io::Error::last_os_error(),
        });
    }
    Ok(())
}

/// Return the calling thread to the normal scheduler (SCHED_OTHER), e.g.
/// once its real-time loop has ended: waiting at real-time priority for a
/// normal thread on the same CPU (the log writer's flush at exit) would
/// starve that thread and spin until the wait times out.
pub fn make_normal() {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: plain syscall with valid arguments; failure leaves the policy as it was.
    let _ = unsafe { libc::sched_setscheduler(0, libc::SCHED_OTHER, &param) };
}

/// The calling process's scheduling policy name.
pub fn policy() -> &'static str {
    // SAFETY: plain syscall.
    match unsafe { libc::sched_getscheduler(0) } {
        libc::SCHED_FIFO => "SCHED_FIFO",
        libc::SCHED_RR => "SCHED_RR",
        _ => "SCHED_OTHER",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table holds the reserve afterwards (as the kernel reports it),
    /// and a descriptor opened then lands inside it.
    #[test]
    fn the_descriptor_table_holds_the_reserve() {
        let limit = descriptor_limit();
        assert!(limit > 0, "RLIMIT_NOFILE unknown");
        let want = RESERVED_DESCRIPTORS.min(limit);
        // a thread shares the table, as in every service
        let t = std::thread::spawn(|| ());
        let size = reserve_descriptors(RESERVED_DESCRIPTORS);
        t.join().unwrap();
        assert!(size >= want, "FDSize {size}, reserve {want}");
        let f = std::fs::File::open("/dev/null").unwrap();
        use std::os::fd::AsRawFd;
        assert!((f.as_raw_fd() as u64) < size);
        assert_eq!(descriptor_table_size(), size, "the table stays");
    }
}
