//! A sweep's results: the outcome of each variant, the table's columns, the heat-map
//! grids a metric makes over two axes.

use super::*;

/// A heat-map to draw: a numeric table column over two numeric axes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HeatSpec {
    /// The table column.
    pub metric: Metric,
    /// The axis across (index into the sweep's axes).
    pub x: usize,
    /// The axis up, or `None` for a sweep of one axis (a single row).
    pub y: Option<usize>,
}

/// The outcomes of a variant that a heat-map can show: the numeric columns of
/// `sweep.csv` (described in `host-sim help sweep`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// First breakaway, s: the first event that starts the held shaft.
    FirstBreakaway,
    /// Work done against the load, J.
    LoadWork,
    /// Mean power delivered to the load over the run, W.
    LoadPower,
    /// Motor work, J.
    MotorWork,
    /// Shaft angle turned, rad (CCW positive).
    ShaftAngle,
    /// Energy lost in plastic impacts, J.
    ImpactLoss,
    /// Mode-change events.
    Events,
    /// Coordinate switches.
    Switches,
    /// Time of the last good state, s (where a run that failed stopped).
    Time,
}

impl Metric {
    /// Every metric, in table order.
    pub const ALL: [Metric; 9] = [
        Metric::Time,
        Metric::FirstBreakaway,
        Metric::Events,
        Metric::Switches,
        Metric::ShaftAngle,
        Metric::MotorWork,
        Metric::LoadWork,
        Metric::LoadPower,
        Metric::ImpactLoss,
    ];

    /// Its column name.
    pub fn name(self) -> &'static str {
        match self {
            Metric::FirstBreakaway => "first_breakaway",
            Metric::LoadWork => "load_work",
            Metric::LoadPower => "load_power",
            Metric::MotorWork => "motor_work",
            Metric::ShaftAngle => "shaft_angle",
            Metric::ImpactLoss => "impact_loss",
            Metric::Events => "events",
            Metric::Switches => "switches",
            Metric::Time => "time",
        }
    }

    /// What it is, with its unit (a heat-map's colour-bar label).
    pub fn describe(self) -> &'static str {
        match self {
            Metric::FirstBreakaway => "first breakaway, s",
            Metric::LoadWork => "work against the load, J",
            Metric::LoadPower => "mean power to the load, W",
            Metric::MotorWork => "motor work, J",
            Metric::ShaftAngle => "shaft angle turned, rad",
            Metric::ImpactLoss => "impact losses, J",
            Metric::Events => "mode changes",
            Metric::Switches => "coordinate switches",
            Metric::Time => "time reached, s",
        }
    }

    /// The metric of a column name.
    pub fn from_name(name: &str) -> Option<Metric> {
        Metric::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The names, for messages.
    pub fn names() -> String {
        Metric::ALL.map(Metric::name).join(", ")
    }
}

/// What a variant's run gave, in the table's terms (`None`: does not apply, or the run
/// did not get that far).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcome {
    /// The exit status the run alone gives.
    pub exit: u8,
    /// How it ended: `completed`, `singularity`, `failed` or `error`.
    pub end: &'static str,
    /// Steps completed.
    pub steps: Option<u64>,
    /// The metrics, in [`Metric::ALL`] order.
    pub metrics: [Option<f64>; Metric::ALL.len()],
    /// The error of a run that did not complete.
    pub message: Option<String>,
}

impl Outcome {
    /// The value of `m`.
    pub fn get(&self, m: Metric) -> Option<f64> {
        let k = Metric::ALL.iter().position(|x| *x == m)?;
        self.metrics.get(k).copied().flatten()
    }
}

impl From<&batch::Outcome> for Outcome {
    /// The table's view of a run's outcome (the same exit status, end and message as
    /// `host-sim batch` gives it).
    fn from(o: &batch::Outcome) -> Self {
        let mut metrics = [None; Metric::ALL.len()];
        let mut put = |m: Metric, v: f64| {
            if let Some(k) = Metric::ALL.iter().position(|x| *x == m) {
                metrics[k] = Some(v);
            }
        };
        let steps = match o {
            batch::Outcome::Mechanism(Ok(s)) => {
                put(Metric::Time, s.time);
                Some(s.steps)
            }
            batch::Outcome::Mechanism(Err(
                RunError::Step { steps, .. } | RunError::Integrator { steps, .. },
            )) => Some(*steps),
            batch::Outcome::Converter(Ok(s)) => {
                let a = &s.audit;
                put(Metric::Time, s.time);
                if let Some((t, _)) = s.first_breakaway {
                    put(Metric::FirstBreakaway, t);
                }
                put(Metric::Events, s.event_count() as f64);
                put(Metric::Switches, s.switches as f64);
                put(Metric::ShaftAngle, s.shaft_angle);
                put(Metric::MotorWork, a.motor_work);
                put(Metric::LoadWork, a.load_work);
                if s.time > 0.0 {
                    put(Metric::LoadPower, a.load_work / s.time);
                }
                put(Metric::ImpactLoss, a.impact_loss);
                Some(s.steps)
            }
            batch::Outcome::Mechanism(Err(_)) | batch::Outcome::Converter(Err(_)) => None,
        };
        Outcome {
            exit: o.exit_code(),
            end: o.end(),
            steps,
            metrics,
            message: o.message(),
        }
    }
}

/// Writes `sweep.csv`: the header (`job`, the axes' keys, `exit`, `end`, `steps`, the
/// metrics in [`Metric::ALL`] order, `message`), then one row per variant in grid
/// order. Numbers in shortest round-trip form; no wall times, so the table depends on
/// nothing but the runs.
pub fn write_table(
    w: &mut dyn Write,
    sweep: &Sweep,
    variants: &[Vec<usize>],
    outcomes: &[Outcome],
) -> io::Result<()> {
    let mut header: Vec<&str> = vec!["job"];
    header.extend(sweep.axes.iter().map(|a| a.key.as_str()));
    header.extend(["exit", "end", "steps"]);
    header.extend(Metric::ALL.map(Metric::name));
    header.push("message");
    writeln!(
        w,
        "{}",
        header.iter().map(|h| cell(h)).collect::<Vec<_>>().join(",")
    )?;
    for (job, (idx, o)) in variants.iter().zip(outcomes).enumerate() {
        let mut row = vec![job.to_string()];
        for (a, &i) in sweep.axes.iter().zip(idx) {
            row.push(cell(&a.values.get(i).map(show).unwrap_or_default()).into_owned());
        }
        row.push(o.exit.to_string());
        row.push(o.end.to_string());
        row.push(o.steps.map(|s| s.to_string()).unwrap_or_default());
        for m in o.metrics {
            row.push(m.map(|v| v.to_string()).unwrap_or_default());
        }
        row.push(cell(o.message.as_deref().unwrap_or("")).into_owned());
        writeln!(w, "{}", row.join(","))?;
    }
    Ok(())
}

/// One heat-map's data: `spec.metric` over the x and y axes, for one combination of
/// the values of the other axes.
#[derive(Clone, Debug, PartialEq)]
pub struct HeatGrid {
    /// The other axes' values, `key = value, ...` (empty when there are none).
    pub fixed: String,
    /// The x axis's values.
    pub x: Vec<f64>,
    /// The y axis's values (one row, `[0.0]`, without a y axis).
    pub y: Vec<f64>,
    /// Row-major `z[iy * x.len() + ix]`; `None` where the run gave no value.
    pub z: Vec<Option<f64>>,
}

/// The heat-maps of `spec`: one per combination of the other axes' values, in grid
/// order. `variants[k]` (the axis indices, as [`Sweep::variants`] gives them) had
/// `outcomes[k]`.
pub fn heat_grids(
    sweep: &Sweep,
    spec: &HeatSpec,
    variants: &[Vec<usize>],
    outcomes: &[Outcome],
) -> Vec<HeatGrid> {
    let axis_numbers = |k: usize| {
        sweep
            .axes
            .get(k)
            .and_then(Axis::numbers)
            .unwrap_or_default()
    };
    let x = axis_numbers(spec.x);
    let y = spec.y.map_or_else(|| vec![0.0], axis_numbers);
    let others: Vec<usize> = (0..sweep.axes.len())
        .filter(|&k| k != spec.x && Some(k) != spec.y)
        .collect();
    let mut grids: Vec<(Vec<usize>, HeatGrid)> = Vec::new();
    for (idx, o) in variants.iter().zip(outcomes) {
        let key: Vec<usize> = others
            .iter()
            .map(|&k| idx.get(k).copied().unwrap_or(0))
            .collect();
        let g = match grids.iter().position(|(k, _)| *k == key) {
            Some(p) => &mut grids[p].1,
            None => {
                let fixed = others
                    .iter()
                    .zip(&key)
                    .map(|(&a, &i)| {
                        let axis = &sweep.axes[a];
                        format!(
                            "{} = {}",
                            axis.key,
                            axis.values.get(i).map(show).unwrap_or_default()
                        )
                    })
                    .collect::<Vec<_>>()
                    .join(", ");
                grids.push((
                    key,
                    HeatGrid {
                        fixed,
                        x: x.clone(),
                        y: y.clone(),
                        z: vec![None; x.len() * y.len()],
                    },
                ));
                &mut grids.last_mut().expect("just pushed").1
            }
        };
        let ix = idx.get(spec.x).copied().unwrap_or(0);
        let iy = spec.y.and_then(|k| idx.get(k).copied()).unwrap_or(0);
        if let Some(cell) = g.z.get_mut(iy * g.x.len() + ix) {
            *cell = o.get(spec.metric);
        }
    }
    grids.into_iter().map(|(_, g)| g).collect()
}
