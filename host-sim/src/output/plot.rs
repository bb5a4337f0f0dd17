//! The plots of a run: what the thesis plots, from a [`Table`] of the run's CSV
//! columns. A run fills the table as it writes its rows (`host-sim run ... --plot DIR`,
//! through [`super::pictures::Recorder`]); `host-sim plot RUN.csv --out-dir DIR` reads it
//! back from the CSV (its header names the columns). Both draw the same figures.
//!
//! Converter runs (a `mode_code` column): crank angle and speed, motor torque, joint
//! reactions, lever, shaft and rocker speeds, clutch torques, the mode over time,
//! energy. Mechanism runs: coordinates, speeds, driving torques, reactions.

use super::{Cell, Observer, Tables};
use crate::draw::{panels, Color, Figure, Plot, Series, PALETTE};
use crate::error::RunError;
use crate::model::bench::csv_reader;
use std::path::{Path, PathBuf};
use structomat::ccc::Mode;
use structomat::Real;

/// A run's numeric columns by CSV name (a cell that is not a number, such as the mode's
/// name or an empty cell past a mode's DOF, is NaN).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names, in CSV order.
    pub names: Vec<String>,
    /// One vector per column, all of the same length.
    pub columns: Vec<Vec<f64>>,
}

impl Table {
    /// An empty table with these columns.
    pub fn new(names: Vec<String>) -> Table {
        let columns = vec![Vec::new(); names.len()];
        Table { names, columns }
    }

    /// Appends a row (missing cells are NaN, extra ones dropped).
    pub fn push_row(&mut self, row: &[f64]) {
        for (k, c) in self.columns.iter_mut().enumerate() {
            c.push(row.get(k).copied().unwrap_or(f64::NAN));
        }
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// No rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The column `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|k| self.columns[k].as_slice())
    }

    /// Reads a CSV written by `host-sim run` (the `csv` crate's reader): a header,
    /// then rows of the same number of cells. Errors name the line.
    pub fn from_csv(text: &str) -> Result<Table, String> {
        let mut reader = csv_reader(text);
        let mut records = reader.records();
        let line = |r: &::csv::StringRecord| r.position().map_or(0, |p| p.line());
        let header = match records.next() {
            Some(r) => r.map_err(|e| format!("line 1: {e}"))?,
            None => return Err("empty file (no header)".to_string()),
        };
        let names: Vec<String> = header.iter().map(str::to_string).collect();
        if names.first().map(String::as_str) != Some("t") {
            return Err(format!(
                "line 1: the header starts with '{}', not 't' (not a host-sim run CSV)",
                names.first().map_or("", String::as_str)
            ));
        }
        let mut table = Table::new(names);
        let mut row = Vec::new();
        for record in records {
            let record = record.map_err(|e| e.to_string())?;
            row.clear();
            row.extend(record.iter().map(|c| c.parse::<f64>().unwrap_or(f64::NAN)));
            if row.len() != table.names.len() {
                return Err(format!(
                    "line {}: {} cells, the header has {}",
                    line(&record),
                    row.len(),
                    table.names.len()
                ));
            }
            table.push_row(&row);
        }
        Ok(table)
    }
}

impl<T: Real> Observer<T> for Table {
    fn on_start(&mut self, tables: &Tables<'_>) -> Result<(), RunError> {
        *self = Table::new(tables.columns.to_vec());
        Ok(())
    }
    fn on_row(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        let values: Vec<f64> = row.iter().map(Cell::to_f64).collect();
        self.push_row(&values);
        Ok(())
    }
}

/// Figure width, px.
pub const WIDTH: u32 = 1000;
/// Height of one panel, px.
pub const PANEL: u32 = 330;

/// The plots of a run: `(file stem, figure)`; `name` titles them (the scenario or the
/// CSV's stem).
pub fn plots(table: &Table, name: &str) -> Vec<(String, Figure)> {
    if table.column("mode_code").is_some() {
        converter_plots(table, name)
    } else {
        mechanism_plots(table, name)
    }
}

/// A series of column `col` against `t`, with legend `label` (none if the column is
/// missing).
fn series(table: &Table, col: &str, label: &str) -> Option<Series> {
    let t = table.column("t")?;
    let y = table.column(col)?;
    Some(Series::new(label, t.to_vec(), y.to_vec()))
}

fn plot(table: &Table, title: &str, y_label: &str, cols: &[(&str, &str)]) -> Plot {
    let mut p = Plot::new(title, "t, s", y_label);
    p.series = cols
        .iter()
        .filter_map(|(c, l)| series(table, c, l))
        .collect();
    p
}

/// The colours of the modes in the mode plot, by mode code (free, I0, I6, I8, jam, A6,
/// A8, A68, coast): the held-shaft modes in cool colours, the turning ones warm (the
/// coasting shaft, with no lever, a pale one), jam black.
pub const MODE_COLORS: [Color; 9] = [
    Color::rgb(150, 150, 150),
    Color::rgb(86, 180, 233),
    Color::rgb(0, 114, 178),
    Color::rgb(0, 158, 115),
    Color::rgb(0, 0, 0),
    Color::rgb(230, 159, 0),
    Color::rgb(213, 94, 0),
    Color::rgb(204, 121, 167),
    Color::rgb(240, 228, 66),
];

fn converter_plots(table: &Table, name: &str) -> Vec<(String, Figure)> {
    let fig = |title: &str, ps: Vec<Plot>| panels(&format!("{name}: {title}"), &ps, WIDTH, PANEL);
    let mut out = Vec::new();
    out.push((
        "crank".to_string(),
        fig(
            "crank",
            vec![
                plot(
                    table,
                    "Crank angle",
                    "theta1, rad",
                    &[("theta1", "crank angle")],
                ),
                plot(
                    table,
                    "Crank speed",
                    "omega1, rad/s",
                    &[("omega1", "crank speed")],
                ),
            ],
        ),
    ));
    out.push((
        "motor_torque".to_string(),
        fig(
            "motor torque",
            vec![plot(
                table,
                "Motor torque on the crank",
                "torque, N·m",
                &[("motor_torque", "motor torque")],
            )],
        ),
    ));
    out.push((
        "reactions".to_string(),
        fig(
            "joint reactions",
            vec![
                plot(
                    table,
                    "Crank, coupler, rocker, swing link",
                    "|reaction|, N",
                    &[
                        ("R_A", "A"),
                        ("R_B", "B"),
                        ("R_C", "C"),
                        ("R_E", "E"),
                        ("R_F", "F"),
                    ],
                ),
                plot(
                    table,
                    "Diode: rods and levers",
                    "|reaction|, N",
                    &[
                        ("R_D5", "D (rod 5)"),
                        ("R_D7", "D (rod 7)"),
                        ("R_G", "G"),
                        ("R_I", "I"),
                        ("R_H6", "H (lever 6)"),
                        ("R_H8", "H (lever 8)"),
                    ],
                ),
            ],
        ),
    ));
    let mut speeds = plot(
        table,
        "Levers and output shaft",
        "speed, rad/s",
        &[
            ("omega6", "lever 6"),
            ("omega8", "lever 8"),
            ("shaft_speed", "shaft"),
        ],
    );
    // The shaft drawn black on top of the levers.
    if let Some(s) = speeds.series.get_mut(2) {
        s.color = Some(PALETTE[6]);
    }
    out.push((
        "speeds".to_string(),
        fig(
            "speeds",
            vec![
                speeds,
                plot(
                    table,
                    "Rocker",
                    "omega3, rad/s",
                    &[("omega3", "rocker speed")],
                ),
            ],
        ),
    ));
    out.push((
        "clutch_torques".to_string(),
        fig(
            "clutch torques",
            vec![plot(
                table,
                "Torque each clutch delivers to the shaft (+ in the drive direction)",
                "torque, N·m",
                &[("c6", "c6 (lever 6)"), ("c8", "c8 (lever 8)")],
            )],
        ),
    ));
    let mut mode = plot(
        table,
        "Mode (diode state) over time",
        "mode",
        &[("mode_code", "mode")],
    );
    mode.categories = Some(
        Mode::ALL
            .iter()
            .map(|m| {
                (
                    m.name().to_string(),
                    MODE_COLORS[m.code() as usize % MODE_COLORS.len()],
                )
            })
            .collect(),
    );
    out.push(("mode".to_string(), mode_figure(name, mode)));
    // A replay's CSV (`host-sim replay`): the encoders measured against the twin's.
    if table.column("crank_counts").is_some() {
        out.push((
            "encoders".to_string(),
            fig(
                "encoders, measured and twin",
                vec![
                    plot(
                        table,
                        "Crank encoder",
                        "counts",
                        &[("crank_counts", "measured"), ("twin_crank_counts", "twin")],
                    ),
                    plot(
                        table,
                        "Shaft encoder (drive direction positive)",
                        "counts",
                        &[("shaft_counts", "measured"), ("twin_shaft_counts", "twin")],
                    ),
                    plot(
                        table,
                        "Residuals (measured - twin)",
                        "counts",
                        &[("crank_residual", "crank"), ("shaft_residual", "shaft")],
                    ),
                ],
            ),
        ));
    }
    // An observed replay's CSV (`host-sim replay --observer`): what the filter saw and
    // what it named.
    if let Some(observer) = observer_figure(table) {
        out.push(("observer".to_string(), fig("observer", observer)));
    }
    out.push((
        "energy".to_string(),
        fig(
            "energy",
            vec![plot(
                table,
                "Energy and work since t = 0",
                "energy, J",
                &[
                    ("kinetic", "kinetic"),
                    ("potential", "potential"),
                    ("motor_work", "motor work"),
                    ("load_work", "load work"),
                    ("impact_loss", "impact losses"),
                ],
            )],
        ),
    ));
    out
}

/// The diagnostics' columns of an observed replay and their legends.
const DIAGNOSTICS: [(&str, &str); 6] = [
    ("crank_jump", "crank encoder jump"),
    ("shaft_jump", "shaft encoder jump"),
    ("clutch_slip", "clutch slip"),
    ("failed_catch", "failed catch"),
    ("load_bias", "load bias"),
    ("twin_parted", "twin parted"),
];
const _: () = assert!(DIAGNOSTICS.len() == structomat::ccc::Diagnostic::ALL.len());

/// An observed replay's panels (`None` without its columns): the crank's innovation
/// (measured - predicted) beside its residual after the update (measured - corrected
/// twin), the unknown torque on the crank, its bearing's friction and the oscillating
/// mass it estimates, the shaft's innovation since the last mode change, and each
/// diagnostic's count of steps raised so far (a step line that rises where the
/// diagnostic fires).
fn observer_figure(table: &Table) -> Option<Vec<Plot>> {
    let t = table.column("t")?;
    table.column("crank_innovation")?;
    let crank = plot(
        table,
        "Crank: innovation (measured - predicted), residual (measured - corrected twin)",
        "counts",
        &[
            ("crank_innovation", "innovation"),
            ("crank_residual", "residual"),
        ],
    );
    let shaft = plot(
        table,
        "Shaft innovation since the last mode change (measured - twin)",
        "counts",
        &[("shaft_innovation", "shaft")],
    );
    let mut raised = Plot::new("Diagnostics raised (steps so far)", "t, s", "steps");
    for (col, label) in DIAGNOSTICS {
        let Some(flags) = table.column(col) else {
            continue;
        };
        let counts = flags
            .iter()
            .scan(0.0, |n, f| {
                // 1 where raised; the first row (no step yet) is empty, NaN.
                *n += if *f > 0.5 { 1.0 } else { 0.0 };
                Some(*n)
            })
            .collect();
        raised.series.push(Series::new(label, t.to_vec(), counts));
    }
    let mut panels = vec![crank, shaft, raised];
    if table.column("crank_torque_estimate").is_some() {
        panels.insert(
            1,
            plot(
                table,
                "Unknown torque on the crank the filter estimates (added to the motor's)",
                "torque, N·m",
                &[("crank_torque_estimate", "estimate")],
            ),
        );
    }
    // The friction's and the mass's estimates, each before the shaft's panel.
    for (col, label, title, unit) in [
        (
            "crank_friction_estimate",
            "estimate",
            "Viscous friction of the crank's bearing the filter estimates (its torque -c·omega1 added to the motor's)",
            "N·m·s/rad",
        ),
        (
            "oscillating_mass",
            "mass",
            "Oscillating mass the twin carries (the filter's estimate)",
            "kg",
        ),
    ] {
        if table.column(col).is_some() {
            let at = panels.len() - 2;
            panels.insert(at, plot(table, title, unit, &[(col, label)]));
        }
    }
    Some(panels)
}

/// The mode plot: one band row per mode, lower than the line plots.
fn mode_figure(name: &str, mode: Plot) -> Figure {
    panels(&format!("{name}: mode"), &[mode], WIDTH, 300)
}

/// Columns whose names are `prefix` followed by digits and underscores (`q1`,
/// `R2_1`, `R2_1_2`), in CSV order.
fn columns_like<'a>(table: &'a Table, prefix: &str) -> Vec<&'a str> {
    table
        .names
        .iter()
        .filter(|n| {
            n.strip_prefix(prefix).is_some_and(|rest| {
                !rest.is_empty() && rest.chars().all(|c| c.is_ascii_digit() || c == '_')
            })
        })
        .map(String::as_str)
        .collect()
}

fn mechanism_plots(table: &Table, name: &str) -> Vec<(String, Figure)> {
    let fig = |title: &str, ps: Vec<Plot>| panels(&format!("{name}: {title}"), &ps, WIDTH, PANEL);
    let each = |cols: Vec<&str>| -> Vec<(String, String)> {
        cols.iter()
            .map(|c| (c.to_string(), c.to_string()))
            .collect()
    };
    let p = |title: &str, y: &str, cols: Vec<(String, String)>| {
        let refs: Vec<(&str, &str)> = cols.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
        plot(table, title, y, &refs)
    };
    let mut out = Vec::new();
    out.push((
        "coordinates".to_string(),
        fig(
            "generalized coordinates",
            vec![
                p(
                    "Coordinates",
                    "q, rad (R) or m (T)",
                    each(columns_like(table, "q")),
                ),
                p(
                    "Speeds",
                    "qd, rad/s or m/s",
                    each(columns_like(table, "qd")),
                ),
            ],
        ),
    ));
    let mut torques = each(columns_like(table, "motor_torque"));
    torques.extend(each(columns_like(table, "drive_torque")));
    out.push((
        "torques".to_string(),
        fig(
            "driving torques",
            vec![p(
                "Applied (motor_torque) and kinetostatic driving torques (drive_torque)",
                "torque, N·m (force, N)",
                torques,
            )],
        ),
    ));
    let mut reactions = each(columns_like(table, "R"));
    reactions.extend(each(columns_like(table, "N")));
    out.push((
        "reactions".to_string(),
        fig(
            "joint reactions",
            vec![p(
                "Reaction magnitudes (R: revolute |F|, N: prismatic |normal force|)",
                "|reaction|, N",
                reactions,
            )],
        ),
    ));
    out
}

/// Writes each figure as `dir/stem.svg` and `dir/stem.png` (creating `dir`); returns the
/// files written.
pub fn write_plots(
    dir: &Path,
    figures: &[(String, Figure)],
) -> Result<Vec<PathBuf>, crate::draw::DrawError> {
    std::fs::create_dir_all(dir).map_err(|e| crate::draw::DrawError::Write {
        path: dir.display().to_string(),
        error: e.to_string(),
    })?;
    let mut written = Vec::new();
    for (stem, f) in figures {
        for ext in ["svg", "png"] {
            let path = dir.join(format!("{stem}.{ext}"));
            f.write(&path)?;
            written.push(path);
        }
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_and_errors() {
        let t = Table::from_csv("t,mode,q1\n0,I0,1.5\n0.1,A6,\n").unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t.column("q1").map(|c| c[0]), Some(1.5));
        assert!(t.column("q1").unwrap()[1].is_nan());
        assert!(t.column("mode").unwrap()[0].is_nan());
        assert!(Table::from_csv("").is_err());
        assert!(Table::from_csv("x,y\n1,2\n")
            .unwrap_err()
            .contains("line 1"));
        assert!(Table::from_csv("t,y\n1,2\n3\n")
            .unwrap_err()
            .contains("line 3"));
    }

    /// An observed replay's figure: the crank's two series and the torque and friction
    /// estimates as the CSV's columns, each diagnostic's running count of the steps that raised it
    /// (the first row, no step yet, empty), counted here by hand; none without the
    /// observer's columns.
    #[test]
    fn observer_panels_count_the_diagnostics() {
        let csv = "t,crank_residual,crank_innovation,crank_sigma,shaft_innovation,\
crank_jump,shaft_jump,clutch_slip,failed_catch,load_bias,crank_torque_estimate,\
crank_friction_estimate
0,0,,,,,,,,,,
0.001,1,2,0.5,0,0,0,0,0,0,0.25,0.01
0.002,-1,3,0.5,4,0,0,1,0,0,0.5,0.02
0.003,0,0,0.5,0,1,0,1,0,0,-0.5,0.03
";
        let t = Table::from_csv(csv).unwrap();
        let panels = observer_figure(&t).expect("the observer's columns");
        assert_eq!(panels.len(), 5);
        assert_eq!(panels[0].series[0].y[1..], [2.0, 3.0, 0.0]);
        assert_eq!(panels[0].series[1].y, [0.0, 1.0, -1.0, 0.0]);
        assert_eq!(panels[1].series[0].y[1..], [0.25, 0.5, -0.5]);
        assert_eq!(panels[2].series[0].y[1..], [0.01, 0.02, 0.03]);
        let raised = &panels[4].series;
        let names: Vec<&str> = raised.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names[0], "crank encoder jump");
        assert_eq!(raised[0].y, [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(raised[2].y, [0.0, 0.0, 1.0, 2.0]);
        assert_eq!(raised[4].y, [0.0; 4]);
        let plain = Table::from_csv("t,crank_residual\n0,1\n").unwrap();
        assert!(observer_figure(&plain).is_none());
    }

    #[test]
    fn mechanism_columns_by_prefix() {
        let t = Table::new(
            [
                "t",
                "q1",
                "qd1",
                "qdd1",
                "q2",
                "motor_torque1",
                "R1_0",
                "R2_1_2",
                "drive_torque1",
            ]
            .map(String::from)
            .to_vec(),
        );
        assert_eq!(columns_like(&t, "q"), ["q1", "q2"]);
        assert_eq!(columns_like(&t, "qd"), ["qd1"]);
        assert_eq!(columns_like(&t, "R"), ["R1_0", "R2_1_2"]);
    }
}
