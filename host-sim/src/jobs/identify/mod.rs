//! `host-sim identify LOG.csv [--clutch-log CLUTCH.csv] [--params BASE.toml] [--fit
//! KEYS] [--max-iters N] --out PARAMS.toml`: the converter's unknown parameters fitted
//! to a bench log ([`fit`](mod@fit)), written as a converter run file: the base file (ccc-s2's
//! without `--params`) with the identified values set at their keys, and in comments
//! each value's uncertainty and bounds and the replay's numbers at the optimum. The
//! file is what `replay --params` and `run` take; the same inputs write the same bytes.

pub mod fit;

pub use fit::{fit, Fit, Identified, Problem};

use crate::error::{report_run_error, write_whole, Fig, RunError, Sci, UsageError};
use crate::model::runfile::{parse_value, run_file_from_value, set_dotted};
use crate::options::IdentifyOptions;
use crate::run::converter::End;
use crate::run::{interrupt, replay};
use std::fmt;
use std::io::Write;

impl fmt::Display for Fit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "identify  {} parameters, Nelder-Mead (argmin): {} iterations ({}), {} replays; \
             cost (sum of squared residuals) {} at the base values, {} identified",
            self.params.len(),
            self.iterations,
            self.termination,
            self.replays,
            Sci(self.cost.0),
            Sci(self.cost.1)
        )?;
        for p in &self.params {
            writeln!(f, "          {}", value_line(p))?;
        }
        writeln!(
            f,
            "          (± the standard uncertainty s·sqrt(diag((JᵀJ)⁻¹)), s = {} over {} residuals)",
            Sci(self.s),
            self.residuals
        )?;
        let r = &self.replay;
        let end = match &r.run.end {
            End::Completed => "to its end".to_string(),
            End::Stopped { error, .. } => format!("stopped at step {}: {error}", r.run.steps + 1),
            End::Interrupted => "interrupted".to_string(),
        };
        writeln!(
            f,
            "replay    {} with the identified values: {} samples, {end}",
            r.log, r.samples
        )?;
        writeln!(f, "crank     {}", r.crank)?;
        write!(f, "shaft     {}", r.shaft)?;
        if let Some(m) = &r.matching {
            write!(f, "\n{}", m.to_string().trim_end())?;
        }
        Ok(())
    }
}

/// `converter.mass = 6.42 ± 0.0012 kg (base 6, bounds 5.4 .. 6.6)`.
fn value_line(p: &Identified) -> String {
    format!(
        "{} = {} ± {} {} (base {}, bounds {} .. {})",
        p.param.key(),
        Sci(p.value),
        Sci(p.sigma),
        p.param.unit(),
        Sci(p.base),
        Sci(p.bounds.0),
        Sci(p.bounds.1)
    )
}

/// The run file of `fit`: `base_text` (a converter run file) with the identified
/// values at their keys, `name` and `description` set, after a comment that gives
/// each value's uncertainty and the replay's numbers. Errors name the key.
pub fn run_file_text(opts: &IdentifyOptions, fit: &Fit) -> Result<String, RunError> {
    let origin = opts.params.name();
    let mut tree =
        parse_value(&opts.base_text, origin).map_err(|e| RunError::Setup(e.to_string()))?;
    let set = |tree: &mut toml::Value, key: &str, v: toml::Value| {
        set_dotted(tree, key, v).map_err(|e| RunError::Setup(format!("{origin}: {e}")))
    };
    for p in &fit.params {
        set(&mut tree, &p.param.key(), toml::Value::Float(p.value))?;
    }
    let log = opts.log.0.display();
    let stem = opts.out.file_stem().map_or_else(
        || "identified".to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    set(&mut tree, "name", toml::Value::String(stem))?;
    set(
        &mut tree,
        "description",
        toml::Value::String(format!(
            "the converter of {origin} with parameters identified from the bench log {log} \
             (host-sim identify)"
        )),
    )?;
    // What replay and run will read: checked before it is written.
    run_file_from_value(tree.clone(), &opts.out.display().to_string())
        .map_err(|e| RunError::Setup(format!("identify: the identified file: {e}")))?;
    let body = toml::to_string(&tree)
        .map_err(|e| RunError::Setup(format!("identify: cannot write the run file: {e}")))?;
    let mut head = format!(
        "# Identified by host-sim identify from the bench log {log}{} on the converter of\n\
         # {origin}: Nelder-Mead (argmin), {} iterations, {} replays; cost (sum of squared\n\
         # residuals: encoder counts, event times in units of {} s) {} -> {}.\n\
         # The identified values (the other keys are {origin}'s), each ± its standard\n\
         # uncertainty s·sqrt(diag((JᵀJ)⁻¹)) (J the residuals' Jacobian at the optimum,\n\
         # s = {} over {} residuals), and the search's bounds:\n",
        opts.clutch.as_ref().map_or(String::new(), |(p, _)| format!(
            " and its clutch log {}",
            p.display()
        )),
        fit.iterations,
        fit.replays,
        Sci(fit::EVENT_SCALE),
        Sci(fit.cost.0),
        Sci(fit.cost.1),
        Sci(fit.s),
        fit.residuals
    );
    for p in &fit.params {
        head.push_str(&format!("#   {}\n", value_line(p)));
    }
    let r = &fit.replay;
    head.push_str(&format!(
        "# Its replay of the log: crank residual RMS {:.3} counts (largest {:+}), shaft {:.3} \
         (largest {:+})",
        r.crank.rms(),
        r.crank.largest.0,
        r.shaft.rms(),
        r.shaft.largest.0
    ));
    if let Some(m) = &r.matching {
        let (machine, twin) = m.counts();
        let same = m.pairs.iter().filter(|p| p.same()).count();
        let worst = m
            .pairs
            .iter()
            .filter(|p| p.same())
            .filter_map(|p| p.dt())
            .fold(0.0_f64, |a, d| a.max(d.abs()));
        head.push_str(&format!(
            ";\n# clutch events: the machine {machine}, the twin {twin}, {same} pairs the same, \
             the largest time difference {} ms",
            Fig(worst * 1e3)
        ));
    }
    head.push_str(".\n\n");
    Ok(head + &body)
}

/// Runs the identification of `opts` and writes its run file; returns the fit.
pub fn run(opts: &IdentifyOptions) -> Result<Fit, RunError> {
    let settings = replay::converter_of(&opts.params)?;
    let params = opts.params.name().to_string();
    let targets = [opts.out.clone()];
    replay::refuse_overwrite(
        &opts.log.0,
        opts.clutch.as_ref().map(|(p, _)| p.as_path()),
        &opts.params,
        &targets,
        "identify",
    )?;
    // A mass or inertia is searched within ±10 % of its base value: of a base of 0
    // that is no range, and its fit (never moved, its σ NaN) would take every other
    // parameter's σ with it.
    for p in &opts.fit {
        let base = p.get(&settings.converter);
        let (lo, hi) = p.bounds(base);
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return Err(RunError::Usage(UsageError(format!(
                "--fit: {}: its value in {params} is {base}, and its search's bounds (±10 % of it) hold nothing else: give it a non-zero value to start from",
                p.key()
            ))));
        }
    }
    let problem = Problem::new(
        &params,
        settings,
        &opts.log.1,
        opts.clutch.as_ref().map(|(_, c)| &**c),
        opts.fit.clone(),
    )
    .in_stages(&opts.stages);
    let fitted = fit(problem, opts.max_iters, opts.quiet)?;
    // A signal after the search (in the last replays, the uncertainty's): those stopped
    // at their start, and their numbers are not the fit's.
    if interrupt::requested() {
        return Err(RunError::Interrupted("identify"));
    }
    let text = run_file_text(opts, &fitted)?;
    write_whole(&opts.out, text.as_bytes())
        .map_err(|e| RunError::write(&opts.out.display().to_string(), e))?;
    Ok(fitted)
}

/// Runs `host-sim identify` with `opts`: the run file, the summary on `stdout` (unless
/// quiet), progress and errors on `stderr`; returns the exit code.
pub fn execute(opts: &IdentifyOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    match run(opts) {
        Ok(fitted) => {
            if !opts.quiet {
                let _ = writeln!(stdout, "{fitted}\nwrote     {}", opts.out.display())
                    .and_then(|_| stdout.flush());
            }
            crate::error::EXIT_OK
        }
        Err(e) => report_run_error(e, stderr),
    }
}
