//! The progress bar a sweep (and a design search) redraws on `stderr`.

use std::io::{self, Write};
use std::time::Duration;

/// The progress bar of a sweep: `sweep  [#######.............]  12/40  30%  0:34
/// elapsed  ~1:19 left`. The estimate is the mean time per finished variant times the
/// variants left (variants differ in cost, so it is rough early on).
pub fn progress_bar(done: usize, total: usize, elapsed: Duration) -> String {
    const WIDTH: usize = 24;
    let total = total.max(1);
    let done = done.min(total);
    let filled = WIDTH * done / total;
    let pct = 100 * done / total;
    let mut s = format!(
        "sweep  [{}{}] {done:>w$}/{total} {pct:>3}%  {} elapsed",
        "#".repeat(filled),
        ".".repeat(WIDTH - filled),
        clock(elapsed),
        w = total.to_string().len()
    );
    if done > 0 && done < total {
        let left = elapsed.mul_f64((total - done) as f64 / done as f64);
        s.push_str(&format!("  ~{} left", clock(left)));
    }
    s
}

/// Redraws the progress bar in place: back to the line's start, the line cleared to its
/// end (`\r` and the terminal's erase-in-line `ESC [ K`, so that a shorter line leaves
/// no stale text of a longer one), then `line`; a line break after the last.
pub fn redraw(w: &mut dyn Write, line: &str, last: bool) -> io::Result<()> {
    write!(w, "\r\x1b[K{line}{}", if last { "\n" } else { "" })?;
    w.flush()
}

/// `m:ss`, or `h:mm:ss` from an hour.
fn clock(d: Duration) -> String {
    let s = d.as_secs();
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}
