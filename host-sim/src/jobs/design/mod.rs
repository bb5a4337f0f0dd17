//! `host-sim design FILE --out-dir DIR`: a sweep whose variants an optimizer chooses.
//! A design file ([`file`](mod@file)) names a base converter, free parameters with bounds (any
//! numeric dotted run-file key), operating points, an objective and constraints; a
//! seeded differential evolution ([`evolution`]) asks for a generation of designs, the
//! worker pool evaluates each at every point ([`evaluate`](mod@evaluate): the twin stepped to the
//! horizon with the diode's margin, the jam and the assembly checked at every step),
//! the scores go back in job order ([`search`]), and the files are written from them
//! ([`outputs`]).
//!
//! Determinism: the optimizer draws from its own seeded generator and sees the
//! scores in member order, whatever thread or Dask worker computed them; so the
//! designs, the table and the best design are the same bit for bit on any number of
//! threads. Only the progress lines on `stderr` depend on the finishing order.

pub mod evaluate;
pub mod evolution;
pub mod file;
pub mod outputs;
pub mod search;

use crate::error::{EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, HINT};
use crate::model::runfile;
use crate::model::scenarios::Source;
use crate::options::{DesignOptions, Output, RunOptions};
use crate::run::interrupt;
use evaluate::{evaluate, Ended, Evaluation};
use file::{get_dotted, read_design, Design};
use outputs::{shown, FrontPoint};
use search::Outcome;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::Instant;

/// The progress line of a generation.
pub fn progress_line(d: &Design, generation: usize, out: &Outcome, secs: f64) -> String {
    let gen: Vec<_> = out
        .rows
        .iter()
        .filter(|r| r.generation == generation)
        .collect();
    let ok = gen.iter().filter(|r| r.score.is_feasible()).count();
    let best = match out.best_row() {
        Some(b) if b.score.is_feasible() => format!(
            "best {} = {:.6}",
            d.objective.name(),
            shown(d, b.score.objective)
        ),
        Some(b) => format!(
            "none feasible yet (least violation {:.4})",
            b.score.violation
        ),
        None => "nothing evaluated".into(),
    };
    format!(
        "design    generation {generation}/{}: {} designs, {ok} feasible; {best}; {:.1} s",
        d.search.generations,
        gen.len(),
        secs
    )
}

/// The base design (no free key written) at each point of `d`.
pub fn base_evaluations(d: &Design) -> Vec<Evaluation> {
    d.points.iter().map(|p| evaluate(d, &[], p)).collect()
}

/// The winner at half the step: its evaluations at every point of `d`.
pub fn at_half_step(d: &Design, x: &[f64]) -> Result<Vec<Evaluation>, String> {
    let h = get_dotted(&d.base_tree, "run.h").ok_or("the base has no run.h")?;
    let mut half = d.clone();
    runfile::set_dotted_in(&mut half.base_tree, "run.h", toml::Value::Float(h / 2.0))?;
    Ok(half.points.iter().map(|p| evaluate(&half, x, p)).collect())
}

fn write_file(path: &Path, f: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<(), String> {
    File::create(path)
        .and_then(|file| {
            let mut w = BufWriter::new(file);
            f(&mut w)?;
            w.flush()
        })
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Runs `host-sim design` with `opts`: checks the design file before anything runs
/// (exit status 2, the field named), runs the search (and one per load of a front),
/// writes the files into `out_dir`, runs the winner through `host-sim run`'s pipeline
/// with its plots and animation and checks it at h/2, and prints a summary. Exit
/// status 0 when the files are written (also when no design is feasible: best.toml
/// says so), 1 when a file cannot be written, 130 when interrupted.
pub fn execute(opts: &DesignOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    let origin = opts.file.display().to_string();
    let text = match fs::read_to_string(&opts.file) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: cannot read design file {origin}: {e}");
            return EXIT_FAILURE;
        }
    };
    let d = match read_design(&text, &opts.file) {
        Ok(d) => d,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}\nnothing was run; {HINT}");
            return EXIT_USAGE;
        }
    };
    let out = &opts.out_dir;
    if let Err(e) = fs::create_dir_all(out) {
        let _ = writeln!(stderr, "host-sim: cannot create {}: {e}", out.display());
        return EXIT_FAILURE;
    }
    let threads = opts.threads.or(d.threads).unwrap_or(2);
    let start = Instant::now();
    let quiet = opts.quiet;
    let run_search = |d: &Design, stderr: &mut dyn Write| {
        search::search(
            d,
            threads,
            &mut |g, o| {
                if !quiet {
                    let _ = writeln!(
                        stderr,
                        "{}",
                        progress_line(d, g, o, start.elapsed().as_secs_f64())
                    );
                }
            },
            &mut |_, _| {},
        )
    };
    let main = run_search(&d, stderr);
    let base = base_evaluations(&d);
    let mut front = Vec::new();
    let mut front_runs = Vec::new();
    for &load in &d.front {
        if interrupt::requested() {
            break;
        }
        let mut dl = d.at_load(load);
        // Each load's search starts from the main search's best feasible design.
        dl.start_point = main
            .best_row()
            .filter(|b| b.score.is_feasible())
            .map(|b| b.x.clone());
        if !quiet {
            let _ = writeln!(stderr, "design    front: T_r = {load} N·m");
        }
        let o = run_search(&dl, stderr);
        let b = base_evaluations(&dl);
        let best = o.best_row();
        front.push(FrontPoint {
            load,
            best: best
                .filter(|r| r.score.is_feasible())
                .map(|r| shown(&dl, r.score.objective)),
            base: {
                let s = search::score(&dl, &b);
                s.is_feasible().then(|| shown(&dl, s.objective))
            },
            x: best.map(|r| r.x.clone()).unwrap_or_default(),
            violation: best.map_or(f64::NAN, |r| r.score.violation),
        });
        front_runs.push((dl, o));
    }
    let search_wall = start.elapsed();
    // The files.
    let written = (|| -> Result<Vec<String>, String> {
        let mut files = Vec::new();
        let table = out.join("designs.csv");
        write_file(&table, |w| {
            outputs::write_rows(w, &d, "main", &main, true)?;
            for (dl, o) in &front_runs {
                let name = format!("load {}", dl.points[0].load);
                outputs::write_rows(w, dl, &name, o, false)?;
            }
            Ok(())
        })?;
        files.push(format!("table     {}", table.display()));
        if let Some(text) = outputs::best_toml(&d, &main) {
            let p = out.join("best.toml");
            write_file(&p, |w| w.write_all(text.as_bytes()))?;
            files.push(format!("best      {}", p.display()));
        }
        let title = format!(
            "convergence of the search ({}, {})",
            d.base,
            d.objective.name()
        );
        let fig = crate::draw::panels("", &outputs::convergence(&d, &main, &title), 900, 320);
        outputs::write_figure(out, "convergence", &fig)?;
        files.push(format!(
            "picture   {} (and .png)",
            out.join("convergence.svg").display()
        ));
        if !front.is_empty() {
            let p = out.join("front.csv");
            write_file(&p, |w| outputs::write_front(w, &d, &front))?;
            let fig = outputs::front_plot(&d, &front).figure(900, 420);
            outputs::write_figure(out, "front", &fig)?;
            files.push(format!(
                "front     {} and {} (and .png)",
                p.display(),
                out.join("front.svg").display()
            ));
        }
        Ok(files)
    })();
    let files = match written {
        Ok(f) => f,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}");
            return EXIT_FAILURE;
        }
    };
    // The winner's run and its check at h/2.
    let mut winner_lines = Vec::new();
    let feasible = main.best_row().filter(|b| b.score.is_feasible());
    if main.best_row().is_some() && feasible.is_none() {
        winner_lines.push("winner    not run: no design is feasible".to_string());
    }
    if let (false, Some(best)) = (opts.no_winner || interrupt::requested(), feasible) {
        match winner_run(out) {
            Ok(line) => winner_lines.push(line),
            Err(e) => {
                let _ = writeln!(stderr, "host-sim: the winner's run: {e}");
                return EXIT_FAILURE;
            }
        }
        match at_half_step(&d, &best.x) {
            Ok(half) => {
                let s = search::score(&d, &half);
                let change = if best.score.is_feasible() && s.is_feasible() {
                    format!(
                        ", objective {:.6} ({:+.3} % of h's)",
                        shown(&d, s.objective),
                        100.0 * (s.objective - best.score.objective) / best.score.objective.abs()
                    )
                } else {
                    String::new()
                };
                winner_lines.push(format!(
                    "h/2       the winner at half the step: {}{change}, min margin {:.6} m",
                    if s.is_feasible() {
                        "feasible"
                    } else {
                        "INFEASIBLE"
                    },
                    half.iter()
                        .map(|e| e.min_margin)
                        .fold(f64::INFINITY, f64::min)
                ));
            }
            Err(e) => winner_lines.push(format!("h/2       not checked: {e}")),
        }
    }
    if !quiet {
        let front_designs = front_runs.iter().map(|(_, o)| o.rows.len()).sum();
        let _ = summary(
            stdout,
            &d,
            &main,
            &base,
            threads,
            search_wall.as_secs_f64(),
            &files,
            &winner_lines,
            &front,
            front_designs,
        );
    }
    if interrupt::requested() {
        EXIT_INTERRUPTED
    } else {
        EXIT_OK
    }
}

/// Runs `best.toml` as `host-sim run best.toml --out winner/run.csv --plot
/// winner/plots --animate winner/run.gif` would; its summary's first lines.
fn winner_run(out: &Path) -> Result<String, String> {
    let path = out.join("best.toml");
    let text =
        fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let file =
        runfile::parse_run_file(&text, &path.display().to_string()).map_err(|e| e.to_string())?;
    let dir = out.join("winner");
    fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut opts = RunOptions::from_source(Source::from_file(path.display().to_string(), file));
    opts.out = Output::File(dir.join("run.csv"));
    opts.plot = Some(dir.join("plots"));
    opts.animate = vec![dir.join("run.gif")];
    // A long horizon: every 5th step in the CSV, the animation at 10 frames a second.
    opts.every = 5;
    opts.fps = 10;
    let (mut so, mut se) = (Vec::new(), Vec::new());
    let code = crate::run::execute(&opts, &mut so, &mut se);
    if code != EXIT_OK {
        return Err(format!(
            "exit status {code}: {}",
            String::from_utf8_lossy(&se).trim()
        ));
    }
    Ok(format!(
        "winner    {} (run.csv, its logs, plots/, run.gif)",
        dir.display()
    ))
}

#[allow(clippy::too_many_arguments)]
fn summary(
    w: &mut dyn Write,
    d: &Design,
    main: &Outcome,
    base: &[Evaluation],
    threads: usize,
    wall: f64,
    files: &[String],
    winner: &[String],
    front: &[FrontPoint],
    front_designs: usize,
) -> io::Result<()> {
    let front_part = if front.is_empty() {
        String::new()
    } else {
        format!(
            " and {front_designs} in the front's {} searches",
            front.len()
        )
    };
    writeln!(
        w,
        "design    {} designs of {} ({} free, {} point{}){front_part} on {threads} thread{} in {wall:.1} s",
        main.rows.len(),
        d.base,
        d.free.len(),
        d.points.len(),
        if d.points.len() == 1 { "" } else { "s" },
        if threads == 1 { "" } else { "s" },
    )?;
    match main.best_row() {
        Some(b) if b.score.is_feasible() => {
            writeln!(w, "best      {}", d.describe(&b.x))?;
            for (k, (e, p)) in b.evals.iter().zip(&d.points).enumerate() {
                writeln!(
                    w,
                    "point {}   T_r = {} N·m, {} s: mean power {:.3} W over the last half, efficiency {:.4} (load work / motor work; {:.4} over the last half), min diode margin {:.4} m, {}",
                    k + 1,
                    p.load,
                    p.horizon,
                    e.mean_power,
                    e.efficiency(),
                    outputs::half_efficiency(e),
                    e.min_margin,
                    // With `no_jam = false` a design that jams may win: say when.
                    e.jam_at
                        .map_or_else(|| "no jam".to_string(), |t| format!("jammed at {t:.4} s"))
                )?;
            }
        }
        Some(b) => writeln!(
            w,
            "best      none feasible: the least violation {} at {} ({})",
            b.score.violation,
            d.describe(&b.x),
            b.evals
                .first()
                .and_then(|e| e.message.as_deref())
                .unwrap_or("")
        )?,
        None => writeln!(w, "best      nothing evaluated")?,
    }
    for (k, e) in base.iter().enumerate() {
        let how = match e.ended {
            Ended::Completed => format!(
                "mean power {:.3} W, min margin {:.4} m",
                e.mean_power, e.min_margin
            ),
            _ => format!(
                "{} ({})",
                e.ended.name(),
                e.message.as_deref().unwrap_or("")
            ),
        };
        writeln!(w, "base      point {}: {how}", k + 1)?;
    }
    for f in files.iter().chain(winner) {
        writeln!(w, "{f}")?;
    }
    for f in front {
        writeln!(
            w,
            "front     T_r = {} N·m: best {}, base {}",
            f.load,
            f.best.map_or("none feasible".into(), |v| format!("{v:.3}")),
            f.base.map_or("infeasible".into(), |v| format!("{v:.3}")),
        )?;
    }
    w.flush()
}
