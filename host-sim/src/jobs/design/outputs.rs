//! The files of a design search: `designs.csv` (every design at every point),
//! `best.toml` (the winner as a run file), the convergence plot, the front over loads.

use super::evaluate::{Evaluation, VIOLATIONS};
use super::file::{Design, Objective};
use super::search::Outcome;
use crate::draw::plot::{Plot, Series};
use crate::jobs::batch::cell;
use std::io::{self, Write};
use std::path::Path;

/// `designs.csv`'s header: `search` (the load of a front's search, or `main`),
/// `generation`, `member`, `point`, the free keys, then per point the evaluation.
pub fn header(d: &Design) -> Vec<String> {
    let mut h: Vec<String> = ["search", "generation", "member", "point"]
        .map(String::from)
        .to_vec();
    h.extend(d.free.iter().map(|f| f.key.clone()));
    h.extend(
        [
            "load",
            "motor",
            "horizon",
            "ended",
            "time",
            "min_margin",
            "jam_at",
            "first_breakaway",
            "mean_power",
            "efficiency",
            "half_efficiency",
            "motor_work",
            "load_work",
            "shaft_angle",
        ]
        .map(String::from),
    );
    h.extend(VIOLATIONS.iter().map(|v| format!("v_{v}")));
    h.extend(["violation", "objective", "feasible", "message"].map(String::from));
    h
}

fn num(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        v.to_string()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

/// Load work over motor work over the last half of the horizon.
pub fn half_efficiency(e: &Evaluation) -> f64 {
    if e.half_work.0 > 0.0 {
        e.half_work.1 / e.half_work.0
    } else {
        f64::NAN
    }
}

/// Writes the rows of one search (`search`: its name in the first column); with
/// `header`, the header first. Numbers in shortest round-trip form.
pub fn write_rows(
    w: &mut dyn Write,
    d: &Design,
    search: &str,
    out: &Outcome,
    with_header: bool,
) -> io::Result<()> {
    if with_header {
        let h = header(d);
        writeln!(
            w,
            "{}",
            h.iter().map(|c| cell(c)).collect::<Vec<_>>().join(",")
        )?;
    }
    for r in &out.rows {
        for (j, (e, p)) in r.evals.iter().zip(&d.points).enumerate() {
            let mut row = vec![
                search.to_string(),
                r.generation.to_string(),
                r.member.to_string(),
                (j + 1).to_string(),
            ];
            row.extend(r.x.iter().map(|v| v.to_string()));
            row.push(num(p.load));
            row.push(opt(p.motor));
            row.push(num(p.horizon));
            row.push(e.ended.name().to_string());
            row.push(num(e.time));
            row.push(num(e.min_margin));
            row.push(opt(e.jam_at));
            row.push(opt(e.first_breakaway));
            row.push(num(e.mean_power));
            row.push(num(e.efficiency()));
            row.push(num(half_efficiency(e)));
            row.push(num(e.motor_work));
            row.push(num(e.load_work));
            row.push(num(e.shaft_angle));
            row.extend(e.violations(&d.constraints).iter().map(|v| v.to_string()));
            row.push(r.score.violation.to_string());
            row.push(num(r.score.objective));
            row.push(r.score.is_feasible().to_string());
            row.push(cell(e.message.as_deref().unwrap_or("")).into_owned());
            writeln!(w, "{}", row.join(","))?;
        }
    }
    Ok(())
}

/// The objective in the user's terms (mean power, W; first breakaway, s) from the
/// minimised value.
pub fn shown(d: &Design, objective: f64) -> f64 {
    match d.objective {
        Objective::MeanPower => -objective,
        Objective::FirstBreakaway => objective,
    }
}

/// The objective's description with its unit.
pub fn describe(d: &Design) -> &'static str {
    match d.objective {
        Objective::MeanPower => "mean power to the load, W",
        Objective::FirstBreakaway => "first breakaway, s",
    }
}

/// The convergence plot: the best feasible objective after each generation (for the
/// mean power: over the last half of the horizon), and the share of feasible designs
/// in each generation.
pub fn convergence(d: &Design, out: &Outcome, title: &str) -> Vec<Plot> {
    let gens: Vec<f64> = (0..out.history.len()).map(|g| g as f64).collect();
    let best: Vec<f64> = out
        .history
        .iter()
        .map(|&k| {
            let r = &out.rows[k];
            if r.score.is_feasible() {
                shown(d, r.score.objective)
            } else {
                f64::NAN
            }
        })
        .collect();
    let share: Vec<f64> = (0..out.history.len())
        .map(|g| {
            let gen: Vec<_> = out.rows.iter().filter(|r| r.generation == g).collect();
            let ok = gen.iter().filter(|r| r.score.is_feasible()).count();
            100.0 * ok as f64 / gen.len().max(1) as f64
        })
        .collect();
    vec![
        Plot::new(title, "generation", describe(d)).with(Series::new(
            "best feasible design",
            gens.clone(),
            best,
        )),
        Plot::new(
            "feasible designs per generation",
            "generation",
            "feasible, %",
        )
        .with(Series::new("feasible", gens, share)),
    ]
}

/// `best.toml`: the winner's run-file tree at the first point, with a comment that
/// says where it came from.
pub fn best_toml(d: &Design, out: &Outcome) -> Option<String> {
    let best = out.best_row()?;
    let point = d.points.first()?;
    let mut tree = d.tree(&best.x, point).ok()?;
    tree.insert(
        "name".into(),
        toml::Value::String("design-best".to_string()),
    );
    let e = best.evals.first()?;
    let what = if best.score.is_feasible() {
        format!(
            "feasible: {} {}, min diode margin {:.4} m",
            describe(d),
            shown(d, best.score.objective),
            e.min_margin
        )
    } else {
        format!(
            "INFEASIBLE (no design met the constraints): total violation {}",
            best.score.violation
        )
    };
    tree.insert(
        "description".into(),
        toml::Value::String(format!(
            "the best of {} designs of {} ({what})",
            out.rows.len(),
            d.origin
        )),
    );
    let body = toml::to_string(&tree).ok()?;
    Some(format!(
        "# Written by host-sim design {}: generation {}, member {}.\n# {}\n# {what}\n{body}",
        d.origin,
        best.generation,
        best.member,
        d.describe(&best.x)
    ))
}

/// One search of a front: its load and its result.
pub struct FrontPoint {
    /// The load, N·m.
    pub load: f64,
    /// The best feasible objective (user terms), if one was found.
    pub best: Option<f64>,
    /// The base design's objective at that load, if feasible.
    pub base: Option<f64>,
    /// The best design's free values.
    pub x: Vec<f64>,
    /// The smallest violation when none was feasible.
    pub violation: f64,
}

/// `front.csv`.
pub fn write_front(w: &mut dyn Write, d: &Design, front: &[FrontPoint]) -> io::Result<()> {
    let mut h = vec![
        "load".to_string(),
        "best".into(),
        "base".into(),
        "violation".into(),
    ];
    h.extend(d.free.iter().map(|f| f.key.clone()));
    writeln!(
        w,
        "{}",
        h.iter().map(|c| cell(c)).collect::<Vec<_>>().join(",")
    )?;
    for f in front {
        let mut row = vec![
            num(f.load),
            opt(f.best),
            opt(f.base),
            f.violation.to_string(),
        ];
        row.extend(f.x.iter().map(|v| v.to_string()));
        writeln!(w, "{}", row.join(","))?;
    }
    Ok(())
}

/// The front's plot: the best feasible objective over the load, and the base's.
pub fn front_plot(d: &Design, front: &[FrontPoint]) -> Plot {
    let loads: Vec<f64> = front.iter().map(|f| f.load).collect();
    let pick = |g: fn(&FrontPoint) -> Option<f64>| -> Vec<f64> {
        front.iter().map(|f| g(f).unwrap_or(f64::NAN)).collect()
    };
    let mut base = Series::new("base geometry", loads.clone(), pick(|f| f.base));
    base.dashed = true;
    let none: Vec<String> = front
        .iter()
        .filter(|f| f.best.is_none())
        .map(|f| f.load.to_string())
        .collect();
    let mut title = format!("the best design per load ({}, one search each)", d.base);
    if !none.is_empty() {
        title.push_str(&format!("; none feasible at {} N·m", none.join(", ")));
    }
    Plot::new(title, "load T_r, N·m", describe(d))
        .with(Series::new("best design found", loads, pick(|f| f.best)))
        .with(base)
}

/// Writes a figure as `stem.svg` and `stem.png` in `dir`.
pub fn write_figure(dir: &Path, stem: &str, fig: &crate::draw::Figure) -> Result<(), String> {
    for ext in ["svg", "png"] {
        fig.write(&dir.join(format!("{stem}.{ext}")))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}
