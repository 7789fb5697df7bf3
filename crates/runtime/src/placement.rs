//! Keeping a process that is not part of the torque loop (a viewer, a
//! bridge: phri-viz, phri-ros2, phri-camera-ros2) off it: the normal
//! scheduler, and the CPUs the 1 kHz services are not pinned to
//! (`[services.*] cpus` of the configuration). Threads started afterwards
//! (a WebSocket server's, DDS's) inherit both.

use std::collections::BTreeSet;

use phri_config::Config;

/// The services of the torque loop (robot, residual, controller).
pub const TORQUE_LOOP: &[&str] = &["sim", "dynamics", "control"];

/// The CPUs the configuration pins the torque loop's enabled services to.
pub fn torque_loop_cpus(config: &Config) -> BTreeSet<usize> {
    TORQUE_LOOP
        .iter()
        .filter_map(|s| config.services.get(*s))
        .filter(|s| s.enabled)
        .flat_map(|s| s.cpus.iter().copied())
        .collect()
}

/// The CPUs of `usable` not in `avoid`; `None` when that leaves none (a
/// one-CPU machine, or a loop pinned everywhere): then nothing is pinned.
pub fn allowed(usable: &[usize], avoid: &BTreeSet<usize>) -> Option<Vec<usize>> {
    let keep: Vec<usize> = usable
        .iter()
        .copied()
        .filter(|c| !avoid.contains(c))
        .collect();
    (!keep.is_empty()).then_some(keep)
}

/// The CPUs this thread may run on now (their indices).
pub fn usable_cpus() -> std::io::Result<Vec<usize>> {
    // SAFETY: a zeroed cpu_set_t is a valid empty set; sched_getaffinity
    // writes at most size_of::<cpu_set_t>() bytes into it.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok((0..libc::CPU_SETSIZE as usize)
            .filter(|&c| libc::CPU_ISSET(c, &set))
            .collect())
    }
}

/// Run this thread (and the threads it starts later) on `cpus` only.
pub fn pin(cpus: &[usize]) -> std::io::Result<()> {
    // SAFETY: as above; CPU_SET is given indices below CPU_SETSIZE only.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        for &c in cpus.iter().filter(|&&c| c < libc::CPU_SETSIZE as usize) {
            libc::CPU_SET(c, &mut set);
        }
        if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// Make sure this thread runs under the normal scheduler (SCHED_OTHER), even
/// when started from a real-time shell.
pub fn normal_scheduler() -> std::io::Result<()> {
    // SAFETY: plain syscalls on this thread with a valid sched_param.
    unsafe {
        if libc::sched_getscheduler(0) == libc::SCHED_OTHER {
            return Ok(());
        }
        let p = libc::sched_param { sched_priority: 0 };
        if libc::sched_setscheduler(0, libc::SCHED_OTHER, &p) != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// Keep off the torque loop's CPUs, under the normal scheduler; before any
/// thread starts, so that the process's later threads inherit it. What
/// cannot be done is logged (a warning), never fatal.
pub fn keep_off_the_loop(config: &Config) {
    if let Err(e) = normal_scheduler() {
        tracing::warn!("cannot switch to the normal scheduler: {e}");
    }
    let avoid = torque_loop_cpus(config);
    let usable = match usable_cpus() {
        Ok(c) => c,
        Err(e) => {
            tracing::warn!("cannot read this process's CPUs: {e}; not pinned");
            return;
        }
    };
    match allowed(&usable, &avoid) {
        Some(cpus) if cpus.len() < usable.len() => match pin(&cpus) {
            Ok(()) => tracing::info!("on CPUs {cpus:?}, off the torque loop's {avoid:?}"),
            Err(e) => tracing::warn!("cannot pin to CPUs {cpus:?}: {e}"),
        },
        Some(cpus) => {
            tracing::info!("on CPUs {cpus:?} (the torque loop is pinned to none of them)")
        }
        None => tracing::warn!(
            "only the torque loop's CPUs {avoid:?} are usable: not pinned (normal scheduler)"
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_cell_keeps_the_loop_on_cpu_1() {
        let cfg = phri_config::Loaded::defaults().config;
        assert_eq!(torque_loop_cpus(&cfg), BTreeSet::from([1]));
        assert_eq!(allowed(&[0, 1], &BTreeSet::from([1])), Some(vec![0]));
        assert_eq!(
            allowed(&[0, 1, 2, 3], &BTreeSet::from([1])),
            Some(vec![0, 2, 3])
        );
        assert_eq!(
            allowed(&[1], &BTreeSet::from([1])),
            None,
            "one CPU: no pinning"
        );
        assert_eq!(allowed(&[0, 1], &BTreeSet::new()), Some(vec![0, 1]));
    }

    #[test]
    fn pinning_a_thread_narrows_its_cpus() {
        // in a thread of its own, so that the test harness keeps its CPUs
        std::thread::spawn(|| {
            let before = usable_cpus().unwrap();
            assert!(!before.is_empty());
            pin(&before[..1]).unwrap();
            assert_eq!(usable_cpus().unwrap(), before[..1].to_vec());
            normal_scheduler().unwrap();
        })
        .join()
        .unwrap();
    }
}
