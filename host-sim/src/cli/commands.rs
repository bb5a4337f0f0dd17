//! The commands that print what host-sim knows without running anything: `host-sim
//! list` and `host-sim analyze`.

use crate::model::analysis;
use crate::model::runfile;
use crate::model::scenarios::{ScenarioId, Source};
use crate::run::converter::start_formula;
use std::io::{self, Write};

/// The text of `host-sim analyze`: for a mechanism, its formula, DOF and groups (the
/// structomatic analysis of [`analysis`]); for the converter, the formula of the mode
/// it starts in. Errors: why no sequence of the library's groups solves it, or why the
/// core refuses the model.
pub fn analyze(source: &Source) -> Result<String, String> {
    let file = source.run_file().map_err(|e| e.to_string())?;
    let mut text = format!("mechanism {}", source.name());
    if let Some(n) = &file.name {
        if n != source.name() {
            text.push_str(&format!(" ({n})"));
        }
    }
    text.push('\n');
    match &file.body {
        runfile::Body::Mechanism(m) => {
            let a = analysis::analyze(m).map_err(|e| e.to_string())?;
            let model = analysis::build_model::<f64>(m, &a).map_err(|e| {
                format!("the sequence was found but the core refuses the model: {e}")
            })?;
            text.push_str(&analysis::report(m, &a, &model));
        }
        runfile::Body::Converter(_) => {
            let c = source
                .converter()
                .ok_or_else(|| "not a converter".to_string())?;
            text.push_str(&format!(
                "formula   {} (the converter's twin: the mode and coordinates change as it runs; host-sim help run)\n",
                start_formula(&c)
            ));
        }
    }
    Ok(text)
}

/// Writes `host-sim list`: one line per scenario with its formula, description and
/// integration settings. A converter scenario's formula is that of its first mode's
/// first coordinate choice (the modes change it as they go: `host-sim help run`).
pub fn list(w: &mut dyn Write) -> io::Result<()> {
    let mut lines = Vec::new();
    for s in ScenarioId::ALL {
        match s.build::<f64>() {
            None => {
                let Some(c) = s.converter() else { continue };
                lines.push((
                    s.name(),
                    start_formula(&c),
                    format!("{}; h = {} s, t_end = {} s", s.description(), c.h, c.t_end),
                ));
            }
            Some(Ok(sc)) => lines.push((
                s.name(),
                sc.model.formula().to_string(),
                format!(
                    "{}; h = {} s, t_end = {} s",
                    s.description(),
                    sc.h,
                    sc.t_end
                ),
            )),
            Some(Err(e)) => lines.push((s.name(), "?".to_string(), format!("cannot build: {e}"))),
        }
    }
    let wn = lines.iter().map(|l| l.0.len()).max().unwrap_or(0);
    let wf = lines.iter().map(|l| l.1.chars().count()).max().unwrap_or(0);
    for (name, formula, desc) in lines {
        writeln!(w, "{name:<wn$}  {formula:<wf$}  {desc}")?;
    }
    Ok(())
}
