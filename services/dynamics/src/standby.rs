//! The standby residual's pace. The hot standby (`phri-dynamics --standby`)
//! observes every state as the first service does, but does not wake on
//! each: while the first keeps up it reads the states queued since it last
//! looked every [`RESTING`], and steps and publishes each of them; once the
//! first falls behind (killed, stalled, restarting and not yet valid) it
//! looks every [`COVERING`], so the residual the controller then acts on is
//! at most about that old, well inside `[control] residual_max_age_ms`.

use std::time::Duration;

use phri_ipc::{residual_flags, Residual};

/// The standby's pause while the first residual service keeps up: two
/// robot periods at 1 kHz, half the wake-ups of one per state.
pub const RESTING: Duration = Duration::from_micros(2000);

/// The standby's pause while the first residual service is behind.
pub const COVERING: Duration = Duration::from_micros(500);

/// The pause before the standby looks again: `first` is the first
/// service's newest residual (none yet: killed before it published),
/// `newest_state_seq` the newest state the standby has stepped. The first
/// keeps up while its newest valid residual answers that state or the one
/// before.
pub fn pause(first: Option<&Residual>, newest_state_seq: u64) -> Duration {
    let keeps_up = first.is_some_and(|r| {
        r.flags & residual_flags::VALID != 0 && r.state_seq + 1 >= newest_state_seq
    });
    match keeps_up {
        true => RESTING,
        false => COVERING,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use phri_ipc::Zeroed;

    fn first(state_seq: u64, valid: bool) -> Residual {
        Residual {
            state_seq,
            flags: if valid { residual_flags::VALID } else { 0 },
            ..Residual::zeroed()
        }
    }

    #[test]
    fn the_standby_covers_as_soon_as_the_first_residual_falls_behind() {
        // the first has answered the newest state, or the one before
        assert_eq!(pause(Some(&first(100, true)), 100), RESTING);
        assert_eq!(pause(Some(&first(99, true)), 100), RESTING);
        // two states behind (stalled, killed): cover
        assert_eq!(pause(Some(&first(98, true)), 100), COVERING);
        // a restarted first, warming up, or none at all
        assert_eq!(pause(Some(&first(100, false)), 100), COVERING);
        assert_eq!(pause(None, 100), COVERING);
        // covering, the standby's residual is never older than the
        // controller's bound (default residual_max_age_ms = 5 ms) by its pause
        assert!(COVERING < RESTING && RESTING < Duration::from_millis(5));
    }
}
