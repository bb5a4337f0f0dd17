//! SIGINT and SIGTERM (Ctrl-C, `kill`): a run asked to stop finishes the row it is
//! writing, completes its files, prints its summary marked interrupted and exits with
//! [`EXIT_INTERRUPTED`](crate::error::EXIT_INTERRUPTED). A second signal ends the
//! process at once (exit status 130), for a run that does not come back.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by the signal handlers of [`install`].
static STOP: AtomicBool = AtomicBool::new(false);

/// Installs the handlers of SIGINT and SIGTERM (the binary does, once; library callers
/// and tests in-process do not, and their runs never stop early). An error leaves the
/// signals' default action (the process ends at once).
pub fn install() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::flag;
    for sig in [SIGINT, SIGTERM] {
        // Registered first, so it sees the flag before this signal sets it: the second
        // signal ends the process.
        flag::register_conditional_shutdown(sig, 130, &STOP)?;
        flag::register(sig, &STOP)?;
    }
    Ok(())
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    STOP.load(Ordering::Relaxed)
}
