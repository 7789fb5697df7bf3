//! What the multi-process test files share.

use std::io::Write;
use std::sync::Once;

/// Print every test's panic message straight to the process's standard
/// error as well, where the supervisors' own lines go: the harness keeps a
/// failing test's message for its summary at the end, which a CI log cut
/// to its first part never shows.
pub fn loud_panics() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let thread = std::thread::current();
            let _ = writeln!(
                std::io::stderr().lock(),
                "test {} failed: {info}",
                thread.name().unwrap_or("?")
            );
            previous(info);
        }));
    });
}
