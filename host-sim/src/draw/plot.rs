//! Line plots: [`Plot`] (series against a shared x, axes with nice ticks, labels with
//! units, a legend, a title), category band plots (a value that takes a few named
//! states over time, as the converter's mode), and [`panels`], plots stacked in one
//! figure. Long series are decimated for drawing: per pixel column the first, lowest,
//! highest and last point, in their order, so spikes stay visible.

use super::ticks::{ticks, Ticks};
use super::{pt, Anchor, Color, Figure, Pt, Shape, Stroke, Text, TextSize, PALETTE};

/// One curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Its legend entry.
    pub name: String,
    /// Abscissae (ascending, as time).
    pub x: Vec<f64>,
    /// Ordinates (non-finite values break the curve).
    pub y: Vec<f64>,
    /// Colour (`None`: the palette's next).
    pub color: Option<Color>,
    /// Drawn dashed (a reference level).
    pub dashed: bool,
}

impl Series {
    /// A solid curve in the palette's next colour.
    pub fn new(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Series {
        Series {
            name: name.into(),
            x,
            y,
            color: None,
            dashed: false,
        }
    }
}

/// One plot (a panel of a figure).
#[derive(Clone, Debug, PartialEq)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label with its unit, e.g. `t, s`.
    pub x_label: String,
    /// y-axis label with its unit.
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
    /// A category plot: the first series's y are indices into these (name, colour),
    /// drawn as bands per run of equal values, the names on the y axis.
    pub categories: Option<Vec<(String, Color)>>,
}

impl Plot {
    /// A line plot.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Plot {
        Plot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            categories: None,
        }
    }
    /// With one more curve.
    pub fn with(mut self, s: Series) -> Plot {
        self.series.push(s);
        self
    }
    /// The plot alone as a figure of `width` x `height` px.
    pub fn figure(&self, width: u32, height: u32) -> Figure {
        panels("", std::slice::from_ref(self), width, height)
    }
}

const TITLE_H: f64 = 34.0;
const TICK: TextSize = TextSize::Small;
const LABEL: TextSize = TextSize::Medium;

/// The plots stacked in one figure `width` px wide, each panel `panel_height` px high,
/// under the figure's `title` (none when empty).
pub fn panels(title: &str, plots: &[Plot], width: u32, panel_height: u32) -> Figure {
    let top = if title.is_empty() { 0.0 } else { TITLE_H };
    let height = top + panel_height as f64 * plots.len() as f64;
    let mut fig = Figure::new(width, height.ceil().max(1.0) as u32);
    if !title.is_empty() {
        let mut t = Text::new(
            pt(width as f64 / 2.0, TITLE_H / 2.0 + 2.0),
            title,
            TextSize::Large,
            Anchor::Middle,
        );
        t.bold = true;
        fig.text(t);
    }
    for (k, p) in plots.iter().enumerate() {
        let y0 = top + panel_height as f64 * k as f64;
        draw_panel(&mut fig, p, 0.0, y0, width as f64, panel_height as f64);
    }
    fig
}

/// Finite min and max of `v` (`None` if none is finite).
fn range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    v.filter(|x| x.is_finite()).fold(None, |r, x| match r {
        None => Some((x, x)),
        Some((a, b)) => Some((a.min(x), b.max(x))),
    })
}

/// The legend: one entry per series, wrapped into rows within `width`; returns the
/// entries' (x, y) relative to the legend's top-left and the rows' count.
fn legend_layout(series: &[Series], width: f64) -> (Vec<(f64, f64)>, usize) {
    let row_h = 20.0;
    let (mut x, mut y, mut rows) = (0.0, row_h / 2.0, 0);
    let mut at = Vec::new();
    for s in series {
        let w = 30.0 + TICK.width(&s.name) + 20.0;
        if x > 0.0 && x + w > width {
            x = 0.0;
            y += row_h;
        }
        if at.is_empty() || x == 0.0 {
            rows += 1;
        }
        at.push((x, y));
        x += w;
    }
    (at, rows)
}

fn draw_panel(fig: &mut Figure, p: &Plot, x0: f64, y0: f64, w: f64, h: f64) {
    let colors: Vec<Color> = p
        .series
        .iter()
        .enumerate()
        .map(|(k, s)| s.color.unwrap_or(PALETTE[k % PALETTE.len()]))
        .collect();
    // Title line.
    let mut cursor = y0 + 8.0;
    if !p.title.is_empty() {
        let mut t = Text::new(pt(x0 + 20.0, cursor + 12.0), &p.title, LABEL, Anchor::Start);
        t.bold = true;
        fig.text(t);
        cursor += 26.0;
    }
    // The y axis: categories or nice ticks.
    let (yt, y_labels): (Ticks, Vec<(f64, String)>) = match &p.categories {
        Some(cats) => {
            let n = cats.len().max(1) as f64;
            let t = Ticks {
                lo: -0.5,
                hi: n - 0.5,
                step: 1.0,
                values: (0..cats.len()).map(|k| k as f64).collect(),
                decimals: 0,
            };
            let labels = cats
                .iter()
                .enumerate()
                .map(|(k, c)| (k as f64, c.0.clone()))
                .collect();
            (t, labels)
        }
        None => {
            let (lo, hi) =
                range(p.series.iter().flat_map(|s| s.y.iter().copied())).unwrap_or((0.0, 1.0));
            let t = ticks(lo, hi, 6);
            let labels = t.values.iter().map(|v| (*v, t.label(*v))).collect();
            (t, labels)
        }
    };
    let label_w = y_labels
        .iter()
        .map(|(_, l)| TICK.width(l))
        .fold(0.0, f64::max);
    let left = x0 + 12.0 + LABEL.height() + 8.0 + label_w + 8.0;
    let right = x0 + w - 24.0;
    // Legend under the title (category plots have none: the names are on the axis).
    let show_legend = p.categories.is_none() && !p.series.is_empty();
    if show_legend {
        let (at, rows) = legend_layout(&p.series, right - left);
        for ((s, c), (lx, ly)) in p.series.iter().zip(&colors).zip(at) {
            let (ex, ey) = (left + lx, cursor + ly);
            let stroke = if s.dashed {
                Stroke::dashed(*c, 2.5, 6.0, 4.0)
            } else {
                Stroke::solid(*c, 2.5)
            };
            fig.line(pt(ex, ey), pt(ex + 24.0, ey), stroke);
            fig.text(Text::new(pt(ex + 30.0, ey), &s.name, TICK, Anchor::Start));
        }
        cursor += 20.0 * rows as f64 + 4.0;
    }
    let top = cursor + 8.0;
    let bottom = y0 + h - (TICK.height() + 6.0 + LABEL.height() + 12.0);
    if bottom - top < 20.0 || right - left < 20.0 {
        return;
    }
    // The x axis: the data's own range, nice ticks inside it.
    let (xlo, xhi) = range(p.series.iter().flat_map(|s| s.x.iter().copied())).unwrap_or((0.0, 1.0));
    let (xlo, xhi) = if xhi > xlo {
        (xlo, xhi)
    } else {
        (xlo - 0.5, xhi + 0.5)
    };
    let xt = ticks(xlo, xhi, 8);
    let sx = |x: f64| left + (x - xlo) / (xhi - xlo) * (right - left);
    let sy = |y: f64| bottom - (y - yt.lo) / (yt.hi - yt.lo) * (bottom - top);
    // Grid and tick labels.
    let grid = Stroke::solid(Color::GRID, 1.0);
    for v in xt
        .values
        .iter()
        .copied()
        .filter(|v| *v >= xlo - 1e-9 * (xhi - xlo) && *v <= xhi + 1e-9 * (xhi - xlo))
    {
        let x = sx(v);
        fig.line(pt(x, top), pt(x, bottom), grid);
        fig.line(
            pt(x, bottom),
            pt(x, bottom + 5.0),
            Stroke::solid(Color::INK, 1.0),
        );
        fig.text(Text::new(
            pt(x, bottom + 6.0 + TICK.height() / 2.0),
            xt.label(v),
            TICK,
            Anchor::Middle,
        ));
    }
    for (v, l) in &y_labels {
        let y = sy(*v);
        fig.line(pt(left, y), pt(right, y), grid);
        fig.line(
            pt(left - 5.0, y),
            pt(left, y),
            Stroke::solid(Color::INK, 1.0),
        );
        fig.text(Text::new(pt(left - 8.0, y), l, TICK, Anchor::End));
    }
    // Axis labels.
    fig.text(Text::new(
        pt((left + right) / 2.0, y0 + h - 6.0 - LABEL.height() / 2.0),
        &p.x_label,
        LABEL,
        Anchor::Middle,
    ));
    let mut yl = Text::new(
        pt(x0 + 12.0 + LABEL.height() / 2.0, (top + bottom) / 2.0),
        &p.y_label,
        LABEL,
        Anchor::Middle,
    );
    yl.vertical = true;
    fig.text(yl);
    // Data.
    match &p.categories {
        Some(cats) => {
            if let Some(s) = p.series.first() {
                draw_bands(fig, s, cats, &sx, &sy);
            }
        }
        None => {
            let pixels = (right - left).max(1.0) as usize;
            for (s, c) in p.series.iter().zip(&colors) {
                let stroke = if s.dashed {
                    Stroke::dashed(*c, 1.5, 8.0, 5.0)
                } else {
                    Stroke::solid(*c, 1.5)
                };
                for run in finite_runs(&s.x, &s.y) {
                    let pts = decimate(run, xlo, xhi, pixels);
                    let points: Vec<Pt> = pts.iter().map(|(x, y)| pt(sx(*x), sy(*y))).collect();
                    if points.len() == 1 {
                        fig.push(Shape::Circle {
                            c: points[0],
                            r: 1.5,
                            fill: Some(*c),
                            stroke: None,
                        });
                    } else {
                        fig.push(Shape::Polyline { points, stroke });
                    }
                }
            }
        }
    }
    // The frame on top of the data.
    fig.rect(
        pt(left, top),
        right - left,
        bottom - top,
        None,
        Some(Stroke::solid(Color::INK, 1.0)),
    );
}

/// The runs of consecutive points where x and y are finite.
fn finite_runs(x: &[f64], y: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for (a, b) in x.iter().zip(y) {
        if a.is_finite() && b.is_finite() {
            cur.push((*a, *b));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// At most four points per pixel column of an axis `pixels` wide over `[lo, hi]`: the
/// first, lowest, highest and last of the column, in their order. Short runs (at most
/// four points per column on average) are kept whole.
pub fn decimate(run: Vec<(f64, f64)>, lo: f64, hi: f64, pixels: usize) -> Vec<(f64, f64)> {
    if run.len() <= 4 * pixels.max(1) || hi <= lo {
        return run;
    }
    let col = |x: f64| (((x - lo) / (hi - lo)) * pixels as f64).floor() as i64;
    let mut out = Vec::with_capacity(4 * pixels);
    let mut start = 0;
    while start < run.len() {
        let c = col(run[start].0);
        let mut end = start + 1;
        while end < run.len() && col(run[end].0) == c {
            end += 1;
        }
        let (mut imin, mut imax) = (start, start);
        for i in start..end {
            if run[i].1 < run[imin].1 {
                imin = i;
            }
            if run[i].1 > run[imax].1 {
                imax = i;
            }
        }
        let mut keep = [start, imin, imax, end - 1];
        keep.sort_unstable();
        let mut last = usize::MAX;
        for i in keep {
            if i != last {
                out.push(run[i]);
                last = i;
            }
        }
        start = end;
    }
    out
}

/// Category bands: one rectangle per run of equal category index, in its colour.
fn draw_bands(
    fig: &mut Figure,
    s: &Series,
    cats: &[(String, Color)],
    sx: &dyn Fn(f64) -> f64,
    sy: &dyn Fn(f64) -> f64,
) {
    let n = s.x.len().min(s.y.len());
    let mut k = 0;
    while k < n {
        let v = s.y[k];
        let mut end = k + 1;
        while end < n && s.y[end] == v {
            end += 1;
        }
        // The run lasts until the next run's first sample (the state holds till then).
        let x_end = if end < n { s.x[end] } else { s.x[n - 1] };
        if v.is_finite() && v >= 0.0 && (v as usize) < cats.len() {
            let color = cats[v as usize].1;
            let (xa, xb) = (sx(s.x[k]), sx(x_end));
            let (ya, yb) = (sy(v + 0.35), sy(v - 0.35));
            // At least one pixel wide, so short visits stay visible.
            fig.rect(pt(xa, ya), (xb - xa).max(1.0), yb - ya, Some(color), None);
        }
        k = end;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_extremes_in_order() {
        // 10,000 points on 100 pixels, with a single-sample spike.
        let mut run: Vec<(f64, f64)> = (0..10_000)
            .map(|i| (i as f64, (i as f64 * 0.01).sin()))
            .collect();
        run[5_555].1 = 50.0;
        run[7_777].1 = -50.0;
        let d = decimate(run, 0.0, 9_999.0, 100);
        assert!(d.len() <= 4 * 101, "{}", d.len());
        assert!(d.contains(&(5_555.0, 50.0)) && d.contains(&(7_777.0, -50.0)));
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0), "x ascending");
        assert_eq!(d.first(), Some(&(0.0, 0.0)));
        assert_eq!(d.last().map(|p| p.0), Some(9_999.0));
    }

    #[test]
    fn runs_break_at_missing_values() {
        let r = finite_runs(
            &[0.0, 1.0, 2.0, 3.0, 4.0],
            &[1.0, f64::NAN, 2.0, 3.0, f64::INFINITY],
        );
        assert_eq!(r, vec![vec![(0.0, 1.0)], vec![(2.0, 2.0), (3.0, 3.0)]]);
    }

    #[test]
    fn legend_wraps() {
        let s: Vec<Series> = (0..10)
            .map(|k| Series::new(format!("series {k}"), vec![], vec![]))
            .collect();
        let (at, rows) = legend_layout(&s, 400.0);
        assert!(rows > 1);
        assert!(at.iter().all(|(x, _)| *x < 400.0));
    }
}
