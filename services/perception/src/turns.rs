//! Cameras that capture in turn: camera `i` of `N`, each at the same
//! frame period `T`, captures at `k T + i T / N` of the clock, so that the
//! newest of the cell's views is never older than `T / N` (plus the
//! latency), not `T` as when they capture together, and their frames'
//! processing is spread over the period instead of arriving at once.

/// The latest capture time of camera `camera` of `cameras` at or before
/// `now_ns` \[ns\], every `period_ns` \[ns\] on the grid above (0 when
/// there is none yet).
pub fn last_turn_ns(now_ns: u64, period_ns: u64, camera: usize, cameras: usize) -> u64 {
    let period = period_ns.max(1);
    let cameras = cameras.max(1) as u64;
    let phase = period * (camera as u64 % cameras) / cameras;
    match now_ns.checked_sub(phase) {
        Some(since) => phase + since / period * period,
        None => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cameras_take_turns_a_period_over_n_apart() {
        let t = 33_333_333;
        for now in [5 * t + 1, 7 * t + t / 2, 100 * t - 1] {
            let a = last_turn_ns(now, t, 0, 2);
            let b = last_turn_ns(now, t, 1, 2);
            assert!(a <= now && b <= now && now - a < t && now - b < t);
            assert_eq!(a % t, 0);
            assert_eq!(b % t, t / 2);
            // the newest of the two is less than half a period old
            assert!(now - a.max(b) < t / 2 + 1);
        }
        // one camera: the plain grid
        assert_eq!(last_turn_ns(3 * t + 5, t, 0, 1), 3 * t);
        // before the first turn of a late phase
        assert_eq!(last_turn_ns(10, t, 1, 2), 0);
    }
}
