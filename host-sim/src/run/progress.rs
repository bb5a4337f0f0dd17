//! A long run's progress on a terminal: a line redrawn in place on `stderr` (`\r`),
//! twice a second, when `stderr` is a terminal; nothing otherwise (a log file, a pipe,
//! the tests).

use crate::error::Sci;
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Wall time between two redraws.
const EVERY: Duration = Duration::from_millis(500);

/// The progress line of one run.
pub struct Progress {
    /// The run's end time, s.
    t_end: f64,
    /// When to draw next; `None`: silent.
    next: Option<Instant>,
    /// Whether a line was drawn (and must be cleared at the end).
    drawn: bool,
}

impl Progress {
    /// The progress of a run to `t_end` (s): drawn when `stderr` is a terminal and
    /// `quiet` is not set.
    pub fn new(t_end: f64, quiet: bool) -> Progress {
        let on = !quiet && std::io::stderr().is_terminal();
        Progress {
            t_end,
            next: on.then(|| Instant::now() + EVERY),
            drawn: false,
        }
    }

    /// Draws the line for simulated time `t` (s) when it is time to.
    pub fn tick(&mut self, t: f64) {
        let Some(next) = self.next else { return };
        let now = Instant::now();
        if now < next {
            return;
        }
        self.next = Some(now + EVERY);
        let percent = 100.0 * t / self.t_end;
        let _ = write!(
            std::io::stderr(),
            "\rhost-sim: t = {} s of {} s ({percent:.0} %)   ",
            Sci(t),
            Sci(self.t_end)
        );
        self.drawn = true;
    }

    /// Clears the line, if one was drawn.
    pub fn finish(&mut self) {
        if self.drawn {
            let _ = write!(std::io::stderr(), "\r{:60}\r", "");
            self.drawn = false;
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}
