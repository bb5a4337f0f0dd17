//! Heat maps of parameter sweeps: a grid of cells coloured by value (viridis, a
//! perceptually uniform colormap), a colour bar, the axes' values at the cell centres,
//! each cell's value printed when the grid is small, and cells without a value grey and
//! hatched.

use super::ticks::ticks;
use super::{pt, Anchor, Color, DrawError, Figure, Stroke, Text, TextSize};

/// A heat map's data: `z[iy * x.len() + ix]` is the value at `(x[ix], y[iy])`.
#[derive(Clone, Debug, PartialEq)]
pub struct HeatMap {
    /// Title.
    pub title: String,
    /// x-axis label with unit.
    pub x_label: String,
    /// y-axis label with unit.
    pub y_label: String,
    /// Label of the values (the colour bar's) with unit.
    pub z_label: String,
    /// The columns' parameter values.
    pub x: Vec<f64>,
    /// The rows' parameter values (drawn bottom to top).
    pub y: Vec<f64>,
    /// Row-major values; `None` (or a non-finite value): no value (e.g. the shaft never
    /// broke away), a grey hatched cell.
    pub z: Vec<Option<f64>>,
}

impl HeatMap {
    /// Checks the lengths: `x` and `y` not empty, `z.len() == x.len() * y.len()`.
    pub fn check(&self) -> Result<(), DrawError> {
        if self.x.is_empty() || self.y.is_empty() {
            return Err(DrawError::Length(format!(
                "heat map {:?}: {} x values and {} y values (at least one each)",
                self.title,
                self.x.len(),
                self.y.len()
            )));
        }
        let want = self.x.len().checked_mul(self.y.len());
        if want != Some(self.z.len()) {
            return Err(DrawError::Length(format!(
                "heat map {:?}: {} z values for {} x {} cells",
                self.title,
                self.z.len(),
                self.x.len(),
                self.y.len()
            )));
        }
        Ok(())
    }
}

/// Viridis at 0, 1/8, ..., 1 (matplotlib's), interpolated linearly in between.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (72, 40, 120),
    (62, 73, 137),
    (49, 104, 142),
    (38, 130, 142),
    (31, 158, 137),
    (53, 183, 121),
    (110, 206, 88),
    (253, 231, 37),
];

/// The viridis colour of `t` in `[0, 1]` (clamped; NaN gives the low end).
pub fn viridis(t: f64) -> Color {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * f).round() as u8;
    Color::rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A value in at most 4 significant digits (scientific when very large or small).
pub fn short(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.2e}");
    }
    let decimals = if a == 0.0 {
        0
    } else {
        (3 - a.log10().floor() as i64).clamp(0, 6) as usize
    };
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// The heat map of `h` as a figure. Inconsistent lengths give a figure that shows the
/// error, whose [`Figure::to_png`] and [`Figure::write`] return it
/// ([`HeatMap::check`], [`try_heatmap`]).
pub fn heatmap(h: &HeatMap) -> Figure {
    match try_heatmap(h) {
        Ok(f) => f,
        Err(e) => {
            let mut f = Figure::new(640, 80);
            f.text(Text::new(
                pt(10.0, 40.0),
                e.to_string(),
                TextSize::Small,
                Anchor::Start,
            ));
            f.invalid = Some(e);
            f
        }
    }
}

/// The heat map of `h`, or the error of [`HeatMap::check`].
pub fn try_heatmap(h: &HeatMap) -> Result<Figure, DrawError> {
    h.check()?;
    let (nx, ny) = (h.x.len(), h.y.len());
    let small = TextSize::Small;
    let label = TextSize::Medium;
    // Cells about square, the grid about 600 px wide (at least 6 px a cell).
    let cell = (600.0 / nx.max(ny) as f64).clamp(6.0, 90.0);
    let (gw, gh) = (cell * nx as f64, cell * ny as f64);
    let x_labels: Vec<String> = h.x.iter().map(|v| short(*v)).collect();
    let y_labels: Vec<String> = h.y.iter().map(|v| short(*v)).collect();
    let y_label_w = y_labels.iter().map(|l| small.width(l)).fold(0.0, f64::max);
    let left = 12.0 + label.height() + 10.0 + y_label_w + 8.0;
    let top = 50.0;
    let bar_x = left + gw + 30.0;
    let values: Vec<f64> =
        h.z.iter()
            .filter_map(|v| v.filter(|v| v.is_finite()))
            .collect();
    let (zlo, zhi) = values
        .iter()
        .fold(None, |r: Option<(f64, f64)>, v| match r {
            None => Some((*v, *v)),
            Some((a, b)) => Some((a.min(*v), b.max(*v))),
        })
        .unwrap_or((0.0, 1.0));
    let (zlo, zhi) = if zhi > zlo {
        (zlo, zhi)
    } else {
        (zlo - 0.5, zhi + 0.5)
    };
    let zt = ticks(zlo, zhi, 6);
    let z_tick_labels: Vec<(f64, String)> = zt
        .values
        .iter()
        .filter(|v| **v >= zlo - 1e-9 * (zhi - zlo) && **v <= zhi + 1e-9 * (zhi - zlo))
        .map(|v| (*v, zt.label(*v)))
        .collect();
    let z_label_w = z_tick_labels
        .iter()
        .map(|(_, l)| small.width(l))
        .fold(0.0, f64::max);
    let bar_h = gh.max(200.0);
    let width = bar_x + 22.0 + 8.0 + z_label_w + 12.0 + label.height() + 16.0;
    let title_w = TextSize::Large.width(&h.title) + 40.0;
    let width = width.max(title_w).ceil();
    let height = (top + gh.max(bar_h) + 8.0 + small.height() + 8.0 + label.height() + 16.0).ceil();
    let mut f = Figure::new(width as u32, height as u32);
    let mut t = Text::new(
        pt(width / 2.0, 22.0),
        &h.title,
        TextSize::Large,
        Anchor::Middle,
    );
    t.bold = true;
    f.text(t);

    let norm = |v: f64| (v - zlo) / (zhi - zlo);
    let print_values = nx * ny <= 200
        && values.iter().all(|v| small.width(&short(*v)) + 4.0 <= cell)
        && cell >= small.height() + 4.0;
    let grey = Color::rgb(205, 205, 205);
    let hatch = Stroke::solid(Color::rgb(120, 120, 120), 1.0);
    for iy in 0..ny {
        // Row 0 at the bottom.
        let cy = top + gh - cell * (iy + 1) as f64;
        for ix in 0..nx {
            let cx = left + cell * ix as f64;
            match h.z[iy * nx + ix].filter(|v| v.is_finite()) {
                Some(v) => {
                    let c = viridis(norm(v));
                    f.rect(pt(cx, cy), cell, cell, Some(c), None);
                    if print_values {
                        let mut t = Text::new(
                            pt(cx + cell / 2.0, cy + cell / 2.0),
                            short(v),
                            small,
                            Anchor::Middle,
                        );
                        // Light text on the dark half of viridis.
                        t.color = if norm(v) < 0.55 {
                            Color::WHITE
                        } else {
                            Color::BLACK
                        };
                        f.text(t);
                    }
                }
                None => {
                    f.rect(pt(cx, cy), cell, cell, Some(grey), None);
                    f.hatch(pt(cx, cy), cell, cell, (cell / 4.0).clamp(3.0, 8.0), hatch);
                }
            }
        }
    }
    f.rect(
        pt(left, top),
        gw,
        gh,
        None,
        Some(Stroke::solid(Color::INK, 1.0)),
    );
    // Axis labels at the cell centres; every k-th when they would overlap.
    let xw = x_labels.iter().map(|l| small.width(l)).fold(0.0, f64::max) + 8.0;
    let x_stride = (xw / cell).ceil().max(1.0) as usize;
    for (ix, l) in x_labels
        .iter()
        .enumerate()
        .filter(|(i, _)| i % x_stride == 0)
    {
        let x = left + cell * (ix as f64 + 0.5);
        f.line(
            pt(x, top + gh),
            pt(x, top + gh + 4.0),
            Stroke::solid(Color::INK, 1.0),
        );
        f.text(Text::new(
            pt(x, top + gh + 6.0 + small.height() / 2.0),
            l,
            small,
            Anchor::Middle,
        ));
    }
    let y_stride = ((small.height() + 2.0) / cell).ceil().max(1.0) as usize;
    for (iy, l) in y_labels
        .iter()
        .enumerate()
        .filter(|(i, _)| i % y_stride == 0)
    {
        let y = top + gh - cell * (iy as f64 + 0.5);
        f.line(
            pt(left - 4.0, y),
            pt(left, y),
            Stroke::solid(Color::INK, 1.0),
        );
        f.text(Text::new(pt(left - 8.0, y), l, small, Anchor::End));
    }
    f.text(Text::new(
        pt(
            left + gw / 2.0,
            top + gh + 6.0 + small.height() + 8.0 + label.height() / 2.0,
        ),
        &h.x_label,
        label,
        Anchor::Middle,
    ));
    let mut yl = Text::new(
        pt(12.0 + label.height() / 2.0, top + gh / 2.0),
        &h.y_label,
        label,
        Anchor::Middle,
    );
    yl.vertical = true;
    f.text(yl);
    // The colour bar: 64 slices, low at the bottom.
    let slices = 64;
    let sh = bar_h / slices as f64;
    for k in 0..slices {
        let c = viridis((k as f64 + 0.5) / slices as f64);
        let y = top + bar_h - sh * (k + 1) as f64;
        // Overlap by half a pixel so no seam shows between slices.
        f.rect(pt(bar_x, y - 0.5), 22.0, sh + 1.0, Some(c), None);
    }
    f.rect(
        pt(bar_x, top),
        22.0,
        bar_h,
        None,
        Some(Stroke::solid(Color::INK, 1.0)),
    );
    for (v, l) in &z_tick_labels {
        let y = top + bar_h - norm(*v) * bar_h;
        f.line(
            pt(bar_x + 22.0, y),
            pt(bar_x + 27.0, y),
            Stroke::solid(Color::INK, 1.0),
        );
        f.text(Text::new(pt(bar_x + 30.0, y), l, small, Anchor::Start));
    }
    let mut zl = Text::new(
        pt(
            bar_x + 30.0 + z_label_w + 10.0 + label.height() / 2.0,
            top + bar_h / 2.0,
        ),
        &h.z_label,
        label,
        Anchor::Middle,
    );
    zl.vertical = true;
    f.text(zl);
    if values.len() < h.z.len() {
        // Say what the hatched cells mean, under the colour bar.
        let y = top + bar_h + 14.0;
        f.rect(pt(bar_x, y - 7.0), 14.0, 14.0, Some(grey), None);
        f.hatch(pt(bar_x, y - 7.0), 14.0, 14.0, 4.0, hatch);
        f.text(Text::new(
            pt(bar_x + 20.0, y),
            "no value",
            small,
            Anchor::Start,
        ));
    }
    Ok(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_and_middle() {
        assert_eq!(viridis(0.0), Color::rgb(68, 1, 84));
        assert_eq!(viridis(1.0), Color::rgb(253, 231, 37));
        assert_eq!(viridis(0.5), Color::rgb(38, 130, 142));
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
    }

    #[test]
    fn short_values() {
        assert_eq!(short(800.0), "800");
        assert_eq!(short(0.0666), "0.0666");
        assert_eq!(short(12.5), "12.5");
        assert_eq!(short(123456.0), "1.23e5");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(-1.25), "-1.25");
    }

    #[test]
    fn mismatched_lengths_are_an_error() {
        let h = HeatMap {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            z_label: "z".into(),
            x: vec![1.0, 2.0],
            y: vec![1.0],
            z: vec![Some(1.0)],
        };
        assert!(matches!(try_heatmap(&h), Err(DrawError::Length(_))));
        assert!(matches!(heatmap(&h).to_png(), Err(DrawError::Length(_))));
        let empty = HeatMap {
            x: vec![],
            z: vec![],
            ..h
        };
        assert!(matches!(try_heatmap(&empty), Err(DrawError::Length(_))));
    }
}
