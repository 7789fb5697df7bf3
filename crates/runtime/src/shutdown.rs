//! Shutdown on SIGINT / SIGTERM through signal-hook.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Set once SIGINT or SIGTERM arrived.
#[derive(Clone)]
pub struct Shutdown(Arc<AtomicBool>);

impl Shutdown {
    /// Install the handlers.
    pub fn install() -> Result<Shutdown, std::io::Error> {
        let flag = Arc::new(AtomicBool::new(false));
        for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            signal_hook::flag::register(sig, Arc::clone(&flag))?;
        }
        Ok(Shutdown(flag))
    }

    /// A signal arrived or [`Shutdown::request`] was called.
    #[inline]
    pub fn requested(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Request shutdown as a signal would (for every clone of this handle).
    pub fn request(&self) {
        self.0.store(true, Ordering::Relaxed)
    }
}
