//! The command line (clap's derive API): the commands and their arguments, and
//! [`main_with`], which runs a command line through the layers below.

pub mod commands;
pub mod help;

use crate::error::{report_write, UsageError, EXIT_FAILURE, EXIT_OK, EXIT_USAGE, HINT};
use crate::jobs::{batch, design, identify, sweep};
use crate::model::scenarios::Source;
use crate::options::args::{
    AnalyzeArgs, BatchArgs, DesignArgs, FmuArgs, IdentifyArgs, PlotArgs, ReplayArgs, RunArgs,
    SweepArgs,
};
use crate::options::{
    BatchOptions, DesignOptions, FmuOptions, IdentifyOptions, PlotOptions, ReplayOptions,
    RunOptions, SweepOptions,
};
use crate::output::pictures;
use crate::run;
use clap::error::ErrorKind;
use clap::{ColorChoice, Parser, Subcommand};
use std::ffi::OsString;
use std::io::Write;

/// `host-sim`'s command line.
#[derive(Parser, Debug)]
#[command(
    name = "host-sim",
    version,
    about = "Simulate the structomat core's mechanisms and the Constantinesco converter",
    long_about = help::ABOUT_LONG,
    after_long_help = help::TOP,
    color = ColorChoice::Never,
    term_width = 88,
    subcommand_required = true,
    arg_required_else_help = false
)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: CliCommand,
}

/// The commands, as clap parses them.
#[derive(Subcommand, Debug)]
pub enum CliCommand {
    /// List the built-in scenarios and their formulas
    List,
    /// Simulate a scenario or a run file and write CSV (options override the file's
    /// values)
    #[command(after_long_help = help::RUN)]
    Run(RunArgs),
    /// Replay a bench log on the converter's twin: the encoder residuals and, with the
    /// machine's clutch log, its events paired with the twin's
    #[command(after_long_help = help::REPLAY)]
    Replay(ReplayArgs),
    /// Fit the converter's unknown parameters to a bench log (its open-loop replay's
    /// encoder and clutch-event errors) and write them as a converter run file
    #[command(after_long_help = help::IDENTIFY)]
    Identify(IdentifyArgs),
    /// Find and print the structomatic formula, the DOF and each group with its links
    /// and joints
    Analyze(AnalyzeArgs),
    /// Run the runs listed in a batch file, N at a time
    #[command(after_long_help = help::BATCH)]
    Batch(BatchArgs),
    /// Run a grid of variants of a run (a sweep file) and write a table and heat-maps
    #[command(after_long_help = help::SWEEP)]
    Sweep(SweepArgs),
    /// Search a converter design (a design file): the best run file, every design's
    /// table, the convergence, the front over loads and the winner's run
    #[command(after_long_help = help::DESIGN)]
    Design(DesignArgs),
    /// Plot a CSV that host-sim run wrote (as run --plot)
    Plot(PlotArgs),
    /// Package the converter's twin as an FMI 2.0 Co-Simulation FMU (the converter
    /// options of run give its start values)
    #[command(after_long_help = help::FMU)]
    Fmu(FmuArgs),
}

/// A parsed and checked command line.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// `host-sim list`.
    List,
    /// `host-sim run <scenario> [options]`.
    Run(RunOptions),
    /// `host-sim replay LOG.csv [--params FILE.toml] [--observer] [--clutch-log FILE] --out FILE`.
    Replay(ReplayOptions),
    /// `host-sim identify LOG.csv [--clutch-log FILE] [--params FILE.toml] --out FILE`.
    Identify(IdentifyOptions),
    /// `host-sim analyze FILE.toml|<scenario>`.
    Analyze(Source),
    /// `host-sim batch FILE --out-dir DIR [--threads N] [--quiet]`.
    Batch(BatchOptions),
    /// `host-sim plot RUN.csv --out-dir DIR`.
    Plot(PlotOptions),
    /// `host-sim sweep FILE --out-dir DIR [options]`.
    Sweep(SweepOptions),
    /// `host-sim design FILE --out-dir DIR [options]`.
    Design(DesignOptions),
    /// `host-sim fmu [SCENARIO|FILE.toml] --out FILE.fmu [options]`.
    Fmu(FmuOptions),
}

/// Why a command line does not give a command.
#[derive(Debug)]
pub enum ParseError {
    /// clap's: help or the version asked for (printed on stdout, exit code 0), or a
    /// bad command line (unknown, misspelled, repeated or missing arguments: stderr,
    /// exit code 2).
    Clap(clap::Error),
    /// A value that does not check: stderr, exit code 2.
    Usage(UsageError),
}

/// Parses the arguments after the program name and checks their values.
pub fn parse_args<I, S>(args: I) -> Result<Command, ParseError>
where
    I: IntoIterator<Item = S>,
    S: Into<OsString>,
{
    let argv = std::iter::once(OsString::from("host-sim")).chain(args.into_iter().map(Into::into));
    let cli = Cli::try_parse_from(argv).map_err(ParseError::Clap)?;
    let checked = match cli.command {
        CliCommand::List => Ok(Command::List),
        CliCommand::Run(a) => a.options().map(Command::Run),
        CliCommand::Replay(a) => a.options().map(Command::Replay),
        CliCommand::Identify(a) => a.options().map(Command::Identify),
        CliCommand::Analyze(a) => a.source().map(Command::Analyze),
        CliCommand::Batch(a) => a.options().map(Command::Batch),
        CliCommand::Sweep(a) => a.options().map(Command::Sweep),
        CliCommand::Design(a) => a.options().map(Command::Design),
        CliCommand::Plot(a) => a.options().map(Command::Plot),
        CliCommand::Fmu(a) => a.options().map(Command::Fmu),
    };
    checked.map_err(ParseError::Usage)
}

/// Runs the command line `args` (without the program name), writing to `stdout` and
/// `stderr`; returns the exit code. Never panics on user input.
pub fn main_with<I, S>(args: I, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8
where
    I: IntoIterator<Item = S>,
    S: Into<OsString>,
{
    let print =
        |w: &mut dyn Write, text: &str| w.write_all(text.as_bytes()).and_then(|_| w.flush());
    match parse_args(args) {
        Ok(Command::List) => match commands::list(stdout).and_then(|_| stdout.flush()) {
            Ok(()) => EXIT_OK,
            Err(e) => report_write(stderr, "stdout", &e),
        },
        Ok(Command::Run(opts)) => run::execute(&opts, stdout, stderr),
        Ok(Command::Replay(opts)) => run::replay::execute(&opts, stdout, stderr),
        Ok(Command::Identify(opts)) => identify::execute(&opts, stdout, stderr),
        Ok(Command::Analyze(source)) => match commands::analyze(&source) {
            Ok(text) => match print(stdout, &text) {
                Ok(()) => EXIT_OK,
                Err(e) => report_write(stderr, "stdout", &e),
            },
            Err(e) => {
                let _ = writeln!(stderr, "host-sim: analyze {}: {e}", source.name());
                EXIT_FAILURE
            }
        },
        Ok(Command::Batch(opts)) => batch::execute(&opts, stdout, stderr),
        Ok(Command::Plot(opts)) => pictures::plot_csv(&opts, stdout, stderr),
        Ok(Command::Sweep(opts)) => sweep::execute(&opts, stdout, stderr),
        Ok(Command::Design(opts)) => design::execute(&opts, stdout, stderr),
        Ok(Command::Fmu(opts)) => run::fmu::execute(&opts, stdout, stderr),
        Err(ParseError::Clap(e)) => {
            let text = e.render().to_string();
            match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => match print(stdout, &text) {
                    Ok(()) => EXIT_OK,
                    Err(e) => report_write(stderr, "stdout", &e),
                },
                _ => {
                    let _ = print(stderr, &text);
                    EXIT_USAGE
                }
            }
        }
        Err(ParseError::Usage(e)) => {
            let _ = writeln!(stderr, "host-sim: {e}\n{HINT}");
            EXIT_USAGE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::model::scenarios::ScenarioId;
    use crate::options::Output;

    /// The command, or the error's message (clap's without its usage lines).
    fn parse(args: &[&str]) -> Result<Command, UsageError> {
        parse_args(args.iter().copied()).map_err(|e| match e {
            ParseError::Clap(e) => UsageError(crate::options::args::one_line(&e)),
            ParseError::Usage(e) => e,
        })
    }

    // `--f64` overrides a run file's `f32 = true`, `--f32` a file's default; both at
    // once are an error.
    #[test]
    fn precision_over_the_file() {
        let dir = std::env::temp_dir().join(format!("host-sim-cli-f64-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("single.toml");
        let text = ScenarioId::FiveBar
            .file_text()
            .replace("f32 = false", "f32 = true");
        assert!(text.contains("f32 = true"));
        std::fs::write(&path, text).unwrap();
        let file = path.to_str().unwrap();
        let f32_of = |extra: &[&str]| match parse(&[&["run", file][..], extra].concat()) {
            Ok(Command::Run(o)) => Ok(o.f32),
            Ok(other) => panic!("{other:?}"),
            Err(e) => Err(e.0),
        };
        assert_eq!(f32_of(&[]), Ok(true));
        assert_eq!(f32_of(&["--f64"]), Ok(false));
        assert!(f32_of(&["--f32", "--f32"])
            .unwrap_err()
            .contains("'--f32' cannot be used multiple times"));
        assert!(f32_of(&["--f32", "--f64"])
            .unwrap_err()
            .contains("'--f32' cannot be used with '--f64'"));
        let builtin = |extra: &[&str]| match parse(&[&["run", "five-bar"][..], extra].concat()) {
            Ok(Command::Run(o)) => o.f32,
            other => panic!("{other:?}"),
        };
        assert!(!builtin(&[]) && builtin(&["--f32"]) && !builtin(&["--f64"]));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn run_options_in_any_order() {
        let c = parse(&[
            "run",
            "--h=0.002",
            "five-bar",
            "--every",
            "5",
            "--out",
            "x.csv",
            "--f32",
            "--quiet",
        ]);
        let mut want = RunOptions::new(ScenarioId::FiveBar);
        want.h = Some(0.002);
        want.every = 5;
        want.out = Output::File("x.csv".into());
        want.f32 = true;
        want.quiet = true;
        assert_eq!(c, Ok(Command::Run(want)));
    }

    #[test]
    fn negative_value_is_a_value_not_an_option() {
        let e = parse(&["run", "five-bar", "--h", "-1"]).unwrap_err();
        assert!(e.0.starts_with("--h: -1 is not positive"), "{e}");
        let e = parse(&["run", "five-bar", "--t-end", "inf"]).unwrap_err();
        assert!(e.0.contains("--t-end") && e.0.contains("not finite"), "{e}");
        let e = parse(&["run", "five-bar", "--t-end", "NaN"]).unwrap_err();
        assert!(e.0.contains("--t-end"), "{e}");
    }

    #[test]
    fn errors_name_the_argument() {
        for (args, needle) in [
            (&["run"][..], "not provided:; <SCENARIO|FILE.toml>"),
            (&["run", "four-bar"][..], "'four-bar'"),
            (
                &["run", "five-bar", "--h"][..],
                "value is required for '--h <SECONDS>'",
            ),
            (&["run", "five-bar", "--every", "-3"][..], "--every"),
            (&["run", "five-bar", "--every", "1.5"][..], "--every"),
            (&["run", "five-bar", "--frob"][..], "'--frob'"),
            (&["run", "five-bar", "--quiet=1"][..], "--quiet"),
            (&["run", "five-bar", "slider-crank"][..], "'slider-crank'"),
            (&["run", "five-bar", "--out", ""][..], "--out"),
            (&["list", "x"][..], "'x'"),
            (&["walk"][..], "'walk'"),
            (&[][..], "requires a subcommand"),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {e}");
        }
    }

    #[test]
    fn converter_options() {
        let c = parse(&["run", "--ccw", "ccc-s2", "--load=0", "--motor", "-3.5"]);
        let mut want = RunOptions::new(ScenarioId::CccS2);
        want.ccw = true;
        want.load = Some(0.0);
        want.motor = Some(-3.5);
        assert_eq!(c, Ok(Command::Run(want)));
        // -0 is a load of 0.
        let Ok(Command::Run(o)) = parse(&["run", "ccc-s2", "--load", "-0"]) else {
            panic!("--load -0")
        };
        assert!(o.load.is_some_and(|l| l == 0.0 && l.is_sign_positive()));
        // S1 takes a motor override.
        let mut want = RunOptions::new(ScenarioId::CccS1);
        want.motor = Some(6.0);
        assert_eq!(
            parse(&["run", "ccc-s1", "--motor", "6"]),
            Ok(Command::Run(want))
        );
        for (args, needle) in [
            (
                &["run", "ccc-s2", "--load", "-1"][..],
                "--load: -1 is negative",
            ),
            (&["run", "ccc-s2", "--motor", "inf"][..], "--motor"),
            (
                &["run", "five-bar", "--ccw"][..],
                "--ccw: only for the converter",
            ),
            (&["run", "ccc-s1", "--load", "1"][..], "--load: ccc-s1"),
            (&["run", "ccc-s1", "--ccw"][..], "--ccw: ccc-s1"),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {e}");
        }
    }

    #[test]
    fn batch_options() {
        let c = parse(&[
            "batch",
            "--threads=3",
            "b.batch",
            "--out-dir",
            "out",
            "--quiet",
        ]);
        assert_eq!(
            c,
            Ok(Command::Batch(BatchOptions {
                file: "b.batch".into(),
                out_dir: "out".into(),
                threads: 3,
                quiet: true,
            }))
        );
        let Ok(Command::Batch(b)) = parse(&["batch", "b", "--out-dir=o"]) else {
            panic!("batch b --out-dir=o")
        };
        assert_eq!(b.threads, 2, "default threads");
        for (args, needle) in [
            (&["batch", "--out-dir", "o"][..], "not provided:; <FILE>"),
            (&["batch", "b"][..], "not provided:; --out-dir <DIR>"),
            (&["batch", "b", "--out-dir", ""][..], "--out-dir: empty"),
            (
                &["batch", "b", "--out-dir"][..],
                "value is required for '--out-dir <DIR>'",
            ),
            (
                &["batch", "b", "--out-dir", "o", "--threads", "0"][..],
                "--threads: 0",
            ),
            (
                &["batch", "b", "--out-dir", "o", "--threads", "x"][..],
                "'x'",
            ),
            (
                &["batch", "b", "--out-dir", "o", "--threads", "257"][..],
                "257",
            ),
            (&["batch", "b", "c", "--out-dir", "o"][..], "'c'"),
            (
                &["batch", "b", "--out-dir", "o", "--t-end", "1"][..],
                "'--t-end'",
            ),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {e}");
        }
    }

    // Help for the program and for each command, wherever -h or --help stands; the
    // version.
    #[test]
    fn help_anywhere() {
        let kind = |args: &[&str]| match parse_args(args.iter().copied()) {
            Err(ParseError::Clap(e)) => Some(e.kind()),
            _ => None,
        };
        for args in [
            &["help"][..],
            &["-h"],
            &["--help"],
            &["help", "batch"],
            &["run", "--help"],
            &["run", "five-bar", "-h"],
            &["batch", "--help"],
        ] {
            assert_eq!(kind(args), Some(ErrorKind::DisplayHelp), "{args:?}");
        }
        assert_eq!(kind(&["--version"]), Some(ErrorKind::DisplayVersion));
    }
}
