//! SIGINT and SIGTERM (Ctrl-C, `kill`): a run asked to stop finishes the row it is
//! writing, completes its files, prints its summary marked interrupted and exits with
//! [`EXIT_INTERRUPTED`](crate::error::EXIT_INTERRUPTED). A second signal ends the
//! process at once (exit status 130), for a run that does not come back.
//!
//! A library caller that has signals of its own (the Python package: the interpreter
//! owns SIGINT) installs no handler but a hook for its thread ([`with_hook`]): the
//! runners ask [`requested`] before every step, and the hook answers for that thread.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};

/// A thread's own answer to "stop?" ([`with_hook`]).
type Hook = Box<dyn FnMut() -> bool>;

thread_local! {
    /// The hook of the run under way on this thread, if its caller set one.
    static HOOK: RefCell<Option<Hook>> = const { RefCell::new(None) };
}

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

/// Whether a stop was asked for: by a signal ([`install`]), or by this thread's hook
/// ([`with_hook`]).
pub fn requested() -> bool {
    STOP.load(Ordering::Relaxed)
        || HOOK.with(|h| {
            // A hook that asks `requested` itself finds the cell borrowed: no stop.
            h.try_borrow_mut()
                .ok()
                .and_then(|mut h| h.as_mut().map(|f| f()))
                .unwrap_or(false)
        })
}

/// Runs `f` on this thread with `hook` answering [`requested`] (every step of a run
/// asks it, so a hook that does real work, as taking a lock, should rate-limit
/// itself); the thread's former hook is back when `f` returns or unwinds.
pub fn with_hook<R>(hook: impl FnMut() -> bool + 'static, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Hook>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let former = self.0.take();
            HOOK.with(|h| {
                if let Ok(mut h) = h.try_borrow_mut() {
                    *h = former;
                }
            });
        }
    }
    let former = HOOK.with(|h| h.replace(Some(Box::new(hook))));
    let _restore = Restore(former);
    f()
}
