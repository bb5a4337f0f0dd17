//! The pictures of `host-sim run ... --plot DIR --animate FILE`: a [`Recorder`], the observer
//! a run feeds as it goes (the CSV rows into a [`Table`] for the plots, the states at frame
//! times into [`Frames`]), and [`write()`], which draws them when the run is over.

use super::animate::{self, Frames};
use super::plot::{self, Table};
use super::{Cell, Observer, State, Tables};
use crate::error::{RunError, UsageError, EXIT_FAILURE, EXIT_OK};
use crate::options::{PlotOptions, RunOptions, Steps, MAX_FRAMES};
use std::path::{Path, PathBuf};
use structomat::Real;

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
}

impl<T: Real> Observer<T> for Recorder {
    fn on_start(&mut self, tables: &Tables<'_>) -> Result<(), RunError> {
        if let Some(t) = self.table.as_mut() {
            Observer::<T>::on_start(t, tables)?;
        }
        Ok(())
    }
    fn on_state(&mut self, state: State<'_, T>) {
        if let Some(f) = self.frames.as_mut() {
            f.on_state(state);
        }
    }
    fn on_row(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        if let Some(t) = self.table.as_mut() {
            t.on_row(row)?;
        }
        Ok(())
    }
}

/// Draws what `rec` recorded as `opts` asks: the plots into `--plot DIR`, each
/// `--animate FILE`. Returns the files written.
pub fn write(opts: &RunOptions, rec: &Recorder) -> Result<Vec<PathBuf>, RunError> {
    let err = |e: crate::draw::DrawError| RunError::Setup(format!("pictures: {e}"));
    let mut written = Vec::new();
    if let (Some(dir), Some(table)) = (&opts.plot, &rec.table) {
        let figures = plot::plots(table, opts.scenario.name());
        written.extend(plot::write_plots(dir, &figures).map_err(err)?);
    }
    if let Some(frames) = &rec.frames {
        for path in &opts.animate {
            animate::write(frames, path).map_err(err)?;
            written.push(path.clone());
        }
    }
    Ok(written)
}

/// Checks `opts`'s pictures before the run, so that a bad option does not cost a run:
/// the frame count (at most [`MAX_FRAMES`]: exit code 2), the plot directory and the
/// animation files can be made (a folder to hold them exists, else exit code 1). Nothing
/// is created: the pictures of a run that fails are not written at all.
pub fn check(opts: &RunOptions) -> Result<(), RunError> {
    if !opts.animate.is_empty() {
        let steps = Steps::check(opts)?;
        let frames = (steps.t_end * opts.fps as f64 * opts.slow).floor() + 1.0;
        if frames > MAX_FRAMES as f64 {
            return Err(RunError::Usage(UsageError(format!(
                "--animate: {frames} frames ({} s at --fps {} --slow {}) is more than {}; lower --fps, --slow or --t-end",
                steps.t_end,
                opts.fps,
                opts.slow,
                MAX_FRAMES
            ))));
        }
    }
    let refuse = |path: &Path, why: &str| RunError::Write {
        target: path.display().to_string(),
        error: std::io::Error::other(why.to_string()),
    };
    if let Some(dir) = &opts.plot {
        if dir.exists() && !dir.is_dir() {
            return Err(refuse(dir, "--plot: it is a file, not a folder"));
        }
        // The folder is made when the plots are written: its nearest existing ancestor
        // must be a folder.
        if !dir
            .ancestors()
            .skip(1)
            .find(|a| a.exists())
            .is_none_or(Path::is_dir)
        {
            return Err(refuse(dir, "--plot: a file stands where a folder must be"));
        }
    }
    for path in &opts.animate {
        if path.is_dir() {
            return Err(refuse(path, "--animate: it is a folder, not a file"));
        }
        if !folder_of(path).is_dir() {
            return Err(refuse(path, "--animate: no such folder"));
        }
    }
    Ok(())
}

/// The folder that holds `path` (`.` for a bare file name).
pub fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// `host-sim plot RUN.csv --out-dir DIR`: the plots of a CSV that `host-sim run`
/// wrote, titled with the CSV's stem; returns the exit code (1 when the CSV cannot be
/// read or the plots cannot be written).
pub fn plot_csv(
    opts: &PlotOptions,
    stdout: &mut dyn std::io::Write,
    stderr: &mut dyn std::io::Write,
) -> u8 {
    let csv = opts.csv.display();
    let text = match std::fs::read_to_string(&opts.csv) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: cannot read {csv}: {e}");
            return EXIT_FAILURE;
        }
    };
    let table = match Table::from_csv(&text) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {csv}: {e}");
            return EXIT_FAILURE;
        }
    };
    let name = opts
        .csv
        .file_stem()
        .map_or_else(|| "run".to_string(), |s| s.to_string_lossy().into_owned());
    let figures = plot::plots(&table, &name);
    match plot::write_plots(&opts.out_dir, &figures) {
        Ok(files) => {
            let _ = writeln!(
                stdout,
                "plots     {} files in {} ({} rows of {csv})",
                files.len(),
                opts.out_dir.display(),
                table.len()
            );
            EXIT_OK
        }
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}");
            EXIT_FAILURE
        }
    }
}
