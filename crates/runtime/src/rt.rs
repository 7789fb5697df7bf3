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
/// Returns a description of what could not be done (without SCHED_FIFO the
/// process runs under the normal scheduler), never fails hard.
pub fn make_realtime(priority: i32) -> Result<(), RtError> {
    if priority <= 0 {
        return Err(RtError::NoPriority);
    }
    // SAFETY: plain syscall with a valid flag.
    let locked = unsafe { libc::mlockall(libc::MCL_CURRENT) };
    let lock_error = std::io::Error::last_os_error();
    fifo(priority)?;
    if locked != 0 {
        return Err(RtError::Lock(lock_error));
    }
    Ok(())
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
/// not locked: the thread does not run a control loop.
pub fn make_watchdog(priority: i32) -> Result<(), RtError> {
    if priority <= 0 {
        return Err(RtError::NoPriority);
    }
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
