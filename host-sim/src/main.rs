//! `host-sim`: parses the command line, runs it through the library, exits with its
//! code (0 success, 1 run failure, 2 bad arguments, 130 interrupted).

use std::io::{self, BufWriter, Write};
use std::process::ExitCode;

fn main() -> ExitCode {
    // Without the handlers, Ctrl-C ends the run as before: at once, files cut short.
    let _ = host_sim::run::interrupt::install();
    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut err = io::stderr().lock();
    let code = host_sim::main_with(std::env::args_os().skip(1), &mut out, &mut err);
    let _ = out.flush();
    ExitCode::from(code)
}
