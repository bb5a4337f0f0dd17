//! The core's diagnostic records (mode changes, coordinate switches, refused
//! candidates), behind the cargo feature `log` (off by default).
//!
//! With the feature, `debug!`, `info!` and `warn!` forward to the `log` crate's
//! macros of the same names (a logger installed by the application receives them;
//! with none, each costs a load and a compare). Without it they expand to a branch
//! that is never taken: the arguments are still type-checked by `format_args!`, but no
//! formatting code, string or `log` dependency is linked into the firmware (smoltcp
//! gates its logging the same way).

// A build uses the levels its callers name, not necessarily all three.
#![allow(unused_macros)]

/// A record at `log`'s level `$level` (`debug`, `info`, `warn`): with the feature
/// `log`, that macro of the `log` crate.
#[cfg(feature = "log")]
macro_rules! record {
    ($level:ident, $($arg:tt)+) => { ::log::$level!($($arg)+) };
}

/// A record, type-checked and never formatted (no feature `log`): the branch is
/// constant-false, so the arguments compile and nothing of them is linked.
#[cfg(not(feature = "log"))]
macro_rules! record {
    ($level:ident, $($arg:tt)+) => {
        if false {
            let _ = ::core::format_args!($($arg)+);
        }
    };
}

/// A debug-level record (details of event location and of the mode choice).
macro_rules! debug {
    ($($arg:tt)+) => { $crate::trace::record!(debug, $($arg)+) };
}

/// An info-level record (mode changes, coordinate switches).
macro_rules! info {
    ($($arg:tt)+) => { $crate::trace::record!(info, $($arg)+) };
}

/// A warning record (no consistent mode: the least violating one taken).
macro_rules! warn_ {
    ($($arg:tt)+) => { $crate::trace::record!(warn, $($arg)+) };
}

// `warn` is also a built-in attribute: the macro is defined as `warn_` and exported
// under its name, which a path (`trace::warn!`) reaches without ambiguity.
#[allow(unused_imports)]
pub(crate) use {debug, info, record, warn_ as warn};

#[cfg(test)]
mod tests {
    /// The records compile with inline and positional arguments, as the twin writes
    /// them, and evaluate to `()`: a record is a statement, whatever the feature.
    #[test]
    fn records_take_format_arguments() {
        let time = 0.25f64;
        let mode = "I6";
        let () = super::debug!("t = {time:.6} s: {} -> {mode}", 1);
        let () = super::info!("t = {time:.6} s: mode {mode}");
        let () = super::warn!("{:?}", [time; 2]);
    }
}
