//! The pictures of `host-sim run ... --plot DIR --animate FILE`: a [`Recorder`] the run
//! feeds as it goes (the CSV rows into a [`Table`] for the plots, the states at frame
//! times into [`Frames`]), and [`write`], which draws them when the run is over.

use crate::animate::Frames;
use crate::cli::RunOptions;
use crate::columns::Layout;
use crate::plot::Table;
use crate::run::RunError;
use std::path::PathBuf;
use structomat::ccc::Twin;
use structomat::{Real, Simulation};

/// What a run records for its pictures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recorder {
    /// The CSV's columns, filled at every written row (`--plot`).
    pub table: Option<Table>,
    /// The animation's frames (`--animate`).
    pub frames: Option<Frames>,
}

impl Recorder {
    /// The recorder `opts` asks for (`None` without `--plot` and `--animate`).
    pub fn for_options(opts: &RunOptions) -> Option<Recorder> {
        if opts.plot.is_none() && opts.animate.is_empty() {
            return None;
        }
        Some(Recorder {
            table: opts.plot.as_ref().map(|_| Table::default()),
            frames: (!opts.animate.is_empty())
                .then(|| Frames::new(opts.scenario.name(), opts.fps, opts.slow)),
        })
    }

    /// A converter row, as [`crate::ccc::write_row`] writes it (the mode's name and
    /// the coordinates' name, which are not numbers, and cells past the mode's DOF are
    /// NaN).
    pub fn converter_row<T: Real>(&mut self, twin: &Twin<T>) {
        let Some(table) = self.table.as_mut() else {
            return;
        };
        if table.names.is_empty() {
            *table = Table::new(crate::ccc::columns());
        }
        let mode = twin.mode();
        let mut row = vec![twin.time().to_f64(), f64::NAN, mode.code() as f64, f64::NAN];
        for v in [twin.q(), twin.qd()] {
            for j in 0..2 {
                row.push(v.get(j).map_or(f64::NAN, |x| x.to_f64()));
            }
        }
        row.extend((1..=8).map(|p| twin.link(p).theta.to_f64()));
        row.extend((1..=8).map(|p| twin.link(p).omega.to_f64()));
        let [c6, c8] = twin.clutch_torques();
        row.extend(
            [
                twin.shaft_speed(),
                twin.shaft_angle(),
                c6,
                c8,
                twin.motor_torque(),
            ]
            .map(|x| x.to_f64()),
        );
        row.extend(twin.joint_reactions().iter().map(|r| r.norm().to_f64()));
        let a = twin.audit();
        row.extend(
            [
                a.kinetic,
                a.potential,
                a.motor_work,
                a.load_work,
                a.impact_loss,
                a.residual(),
            ]
            .map(|x| x.to_f64()),
        );
        table.push_row(&row);
    }

    /// A converter state (at t = 0 and after every step): the animation's frames.
    pub fn converter_state<T: Real>(&mut self, twin: &Twin<T>) {
        if let Some(f) = self.frames.as_mut() {
            f.converter(twin);
        }
    }

    /// A mechanism row, as [`Layout::write_row`] writes it.
    pub fn mechanism_row<T: Real>(&mut self, layout: &Layout, sim: &Simulation<T>) {
        let Some(table) = self.table.as_mut() else {
            return;
        };
        if table.names.is_empty() {
            *table = Table::new(layout.names.clone());
        }
        let row: Vec<f64> = layout
            .columns
            .iter()
            .map(|c| Layout::value(*c, sim).to_f64())
            .collect();
        table.push_row(&row);
    }

    /// A mechanism state (at t = 0 and after every step).
    pub fn mechanism_state<T: Real>(&mut self, sim: &Simulation<T>) {
        if let Some(f) = self.frames.as_mut() {
            f.mechanism(sim);
        }
    }
}

/// Draws what `rec` recorded as `opts` asks: the plots into `--plot DIR`, each
/// `--animate FILE`. Returns the files written.
pub fn write(opts: &RunOptions, rec: &Recorder) -> Result<Vec<PathBuf>, RunError> {
    let err = |e: crate::draw::DrawError| RunError::Setup(format!("pictures: {e}"));
    let mut written = Vec::new();
    if let (Some(dir), Some(table)) = (&opts.plot, &rec.table) {
        let figures = crate::plot::plots(table, opts.scenario.name());
        written.extend(crate::plot::write_plots(dir, &figures).map_err(err)?);
    }
    if let Some(frames) = &rec.frames {
        for path in &opts.animate {
            crate::animate::write(frames, path).map_err(err)?;
            written.push(path.clone());
        }
    }
    Ok(written)
}

/// Checks `opts`'s pictures before the run, so that a bad option does not cost a run:
/// the frame count (at most [`crate::animate::MAX_FRAMES`]: exit code 2), the plot
/// directory (created) and the animation files (created empty) can be written (else
/// exit code 1).
pub fn check(opts: &RunOptions) -> Result<(), RunError> {
    if !opts.animate.is_empty() {
        let steps = crate::run::Steps::check(opts)?;
        let frames = (steps.t_end * opts.fps as f64 * opts.slow).floor() + 1.0;
        if frames > crate::animate::MAX_FRAMES as f64 {
            return Err(RunError::Usage(crate::cli::UsageError(format!(
                "--animate: {frames} frames ({} s at --fps {} --slow {}) is more than {}; lower --fps, --slow or --t-end",
                steps.t_end,
                opts.fps,
                opts.slow,
                crate::animate::MAX_FRAMES
            ))));
        }
    }
    if let Some(dir) = &opts.plot {
        std::fs::create_dir_all(dir).map_err(|error| RunError::Write {
            target: dir.display().to_string(),
            error,
        })?;
    }
    for path in &opts.animate {
        std::fs::File::create(path).map_err(|error| RunError::Write {
            target: path.display().to_string(),
            error,
        })?;
    }
    Ok(())
}

/// `host-sim plot RUN.csv --out-dir DIR`: the plots of a CSV that `host-sim run`
/// wrote, titled with the CSV's stem; returns the exit code (1 when the CSV cannot be
/// read or the plots cannot be written).
pub fn plot_csv(
    opts: &crate::cli::PlotOptions,
    stdout: &mut dyn std::io::Write,
    stderr: &mut dyn std::io::Write,
) -> u8 {
    let csv = opts.csv.display();
    let text = match std::fs::read_to_string(&opts.csv) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: cannot read {csv}: {e}");
            return crate::EXIT_FAILURE;
        }
    };
    let table = match Table::from_csv(&text) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {csv}: {e}");
            return crate::EXIT_FAILURE;
        }
    };
    let name = opts
        .csv
        .file_stem()
        .map_or_else(|| "run".to_string(), |s| s.to_string_lossy().into_owned());
    let figures = crate::plot::plots(&table, &name);
    match crate::plot::write_plots(&opts.out_dir, &figures) {
        Ok(files) => {
            let _ = writeln!(
                stdout,
                "plots     {} files in {} ({} rows of {csv})",
                files.len(),
                opts.out_dir.display(),
                table.len()
            );
            crate::EXIT_OK
        }
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}");
            crate::EXIT_FAILURE
        }
    }
}
