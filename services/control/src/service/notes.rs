//! What the 1 kHz loop logs, through a thread at normal priority
//! (`phri_runtime::log::Deferred`): posted, never formatted, in the loop.

use crate::{InputError, SnapshotError};

/// One event of the loop worth a log line.
#[derive(Debug)]
pub enum Note {
    /// a refused input: the error and how many so far
    Refused {
        /// why it was refused
        error: InputError,
        /// inputs refused so far
        count: u64,
    },
    /// a peer's behaviour state refused: the error and how many so far
    Behaviour {
        /// why it was refused
        error: SnapshotError,
        /// behaviour states refused so far
        count: u64,
    },
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Note::Refused { error, count } => write!(f, "{error} ({count} inputs refused)"),
            Note::Behaviour { error, count } => write!(
                f,
                "the other controller's behaviour state refused: {error} ({count} so far)"
            ),
        }
    }
}

/// Counts an event and says whether to log it: the 1st, 2nd, 4th, 8th, …
pub fn count_and_log(count: &mut u64) -> bool {
    *count += 1;
    count.is_power_of_two()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logs_at_powers_of_two() {
        let mut count = 0;
        let logged: Vec<u64> = (1..=20).filter(|_| count_and_log(&mut count)).collect();
        assert_eq!(logged, [1, 2, 4, 8, 16]);
    }

    #[test]
    fn a_refused_input_says_how_many() {
        let note = Note::Refused {
            error: InputError::Dof {
                channel: "robot/state",
                seq: 3,
                expected: 7,
                got: 6,
            },
            count: 4,
        };
        assert!(note.to_string().ends_with(" (4 inputs refused)"), "{note}");
    }
}
