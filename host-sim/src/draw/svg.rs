//! SVG text of a [`Figure`]: hand-written, numbers with two decimals, so the same
//! figure is the same bytes. [`animated`] plays a sequence of figures of one structure
//! (SMIL `<animate>` of the attributes that change; texts that change become one element
//! per distinct run of frames, shown in turn).

use super::{Anchor, Color, DrawError, Figure, Pt, Shape, Stroke, Text, TextSize};
use std::fmt::Write;

/// A number with two decimals, `-0.00` printed as `0.00`.
pub fn num(x: f64) -> String {
    let x = if x.is_finite() { x } else { 0.0 };
    let s = format!("{x:.2}");
    if s == "-0.00" {
        "0.00".to_string()
    } else {
        s
    }
}

/// `&`, `<`, `>`, `"` escaped.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            c => o.push(c),
        }
    }
    o
}

fn paint(name: &str, c: Color) -> String {
    if c.a == 255 {
        format!(" {name}=\"{}\"", c.hex())
    } else {
        format!(
            " {name}=\"{}\" {name}-opacity=\"{}\"",
            c.hex(),
            num(c.a as f64 / 255.0)
        )
    }
}

fn stroke_attrs(s: &Stroke) -> String {
    let mut o = paint("stroke", s.color);
    let _ = write!(o, " stroke-width=\"{}\"", num(s.width));
    if let Some((d, g)) = s.dash {
        let _ = write!(o, " stroke-dasharray=\"{} {}\"", num(d), num(g));
    }
    o
}

fn fill_stroke(fill: Option<Color>, stroke: Option<&Stroke>) -> String {
    let mut o = match fill {
        Some(c) => paint("fill", c),
        None => " fill=\"none\"".to_string(),
    };
    if let Some(s) = stroke {
        o.push_str(&stroke_attrs(s));
    }
    o
}

fn points(ps: &[Pt]) -> String {
    let mut o = String::new();
    for (k, p) in ps.iter().enumerate() {
        if k > 0 {
            o.push(' ');
        }
        let _ = write!(o, "{},{}", num(p.x), num(p.y));
    }
    o
}

/// SVG font size of a text size: the bitmap font's line height is about 1.36 em.
fn font_size(s: TextSize) -> f64 {
    (s.height() / 1.36).round()
}

fn text_open(t: &Text) -> String {
    let anchor = match t.anchor {
        Anchor::Start => "start",
        Anchor::Middle => "middle",
        Anchor::End => "end",
    };
    let mut o = format!(
        "<text x=\"{}\" y=\"{}\" font-size=\"{}\" text-anchor=\"{anchor}\" dominant-baseline=\"central\"{}",
        num(t.at.x),
        num(t.at.y),
        num(font_size(t.size)),
        paint("fill", t.color)
    );
    if t.bold {
        o.push_str(" font-weight=\"bold\"");
    }
    if t.text.contains("  ") {
        // Keep runs of spaces (aligned columns in captions).
        o.push_str(" xml:space=\"preserve\"");
    }
    if t.vertical {
        let _ = write!(
            o,
            " transform=\"rotate(-90 {} {})\"",
            num(t.at.x),
            num(t.at.y)
        );
    }
    o
}

/// One element's opening tag (without `>` or `/>`) and its closing part.
fn element(s: &Shape) -> (String, String) {
    match s {
        Shape::Line { a, b, stroke } => (
            format!(
                "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"{}",
                num(a.x),
                num(a.y),
                num(b.x),
                num(b.y),
                stroke_attrs(stroke)
            ),
            "</line>".into(),
        ),
        Shape::Polyline { points: ps, stroke } => (
            format!(
                "<polyline points=\"{}\" fill=\"none\"{} stroke-linejoin=\"round\"",
                points(ps),
                stroke_attrs(stroke)
            ),
            "</polyline>".into(),
        ),
        Shape::Polygon {
            points: ps,
            fill,
            stroke,
        } => (
            format!(
                "<polygon points=\"{}\"{} stroke-linejoin=\"round\"",
                points(ps),
                fill_stroke(*fill, stroke.as_ref())
            ),
            "</polygon>".into(),
        ),
        Shape::Circle { c, r, fill, stroke } => (
            format!(
                "<circle cx=\"{}\" cy=\"{}\" r=\"{}\"{}",
                num(c.x),
                num(c.y),
                num(*r),
                fill_stroke(*fill, stroke.as_ref())
            ),
            "</circle>".into(),
        ),
        Shape::Rect {
            at,
            w,
            h,
            fill,
            stroke,
        } => (
            format!(
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"{}",
                num(at.x),
                num(at.y),
                num(w.max(0.0)),
                num(h.max(0.0)),
                fill_stroke(*fill, stroke.as_ref())
            ),
            "</rect>".into(),
        ),
        Shape::Text(t) => (text_open(t), "</text>".into()),
    }
}

fn header(o: &mut String, f: &Figure) {
    let _ = writeln!(
        o,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"'Noto Sans Mono', 'DejaVu Sans Mono', monospace\">",
        w = f.width,
        h = f.height
    );
    let _ = writeln!(
        o,
        "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\"{}/>",
        f.width,
        f.height,
        paint("fill", f.background)
    );
}

/// The SVG document of `f`.
pub fn render(f: &Figure) -> String {
    let mut o = String::new();
    header(&mut o, f);
    for s in &f.shapes {
        let (open, _) = element(s);
        match s {
            Shape::Text(t) => {
                let _ = writeln!(o, "{open}>{}</text>", escape(&t.text));
            }
            _ => {
                let _ = writeln!(o, "{open}/>");
            }
        }
    }
    o.push_str("</svg>\n");
    o
}

/// The animated attributes of a shape: (name, value) pairs.
fn attributes(s: &Shape) -> Vec<(&'static str, String)> {
    let fill = |c: &Option<Color>| c.map_or("none".to_string(), |c| c.hex());
    let stroke = |s: &Option<Stroke>| {
        s.map_or(("none".to_string(), num(0.0)), |s| {
            (s.color.hex(), num(s.width))
        })
    };
    match s {
        Shape::Line { a, b, stroke: st } => vec![
            ("x1", num(a.x)),
            ("y1", num(a.y)),
            ("x2", num(b.x)),
            ("y2", num(b.y)),
            ("stroke", st.color.hex()),
            ("stroke-width", num(st.width)),
        ],
        Shape::Polyline {
            points: ps,
            stroke: st,
        } => vec![
            ("points", points(ps)),
            ("stroke", st.color.hex()),
            ("stroke-width", num(st.width)),
        ],
        Shape::Polygon {
            points: ps,
            fill: fl,
            stroke: st,
        } => {
            let (sc, sw) = stroke(st);
            vec![
                ("points", points(ps)),
                ("fill", fill(fl)),
                ("stroke", sc),
                ("stroke-width", sw),
            ]
        }
        Shape::Circle {
            c,
            r,
            fill: fl,
            stroke: st,
        } => {
            let (sc, sw) = stroke(st);
            vec![
                ("cx", num(c.x)),
                ("cy", num(c.y)),
                ("r", num(*r)),
                ("fill", fill(fl)),
                ("stroke", sc),
                ("stroke-width", sw),
            ]
        }
        Shape::Rect {
            at,
            w,
            h,
            fill: fl,
            stroke: st,
        } => {
            let (sc, sw) = stroke(st);
            vec![
                ("x", num(at.x)),
                ("y", num(at.y)),
                ("width", num(w.max(0.0))),
                ("height", num(h.max(0.0))),
                ("fill", fill(fl)),
                ("stroke", sc),
                ("stroke-width", sw),
            ]
        }
        Shape::Text(t) => vec![("x", num(t.at.x)), ("y", num(t.at.y))],
    }
}

fn same_kind(a: &Shape, b: &Shape) -> bool {
    std::mem::discriminant(a) == std::mem::discriminant(b)
        && match (a, b) {
            (
                Shape::Polygon {
                    fill: f1,
                    stroke: s1,
                    ..
                },
                Shape::Polygon {
                    fill: f2,
                    stroke: s2,
                    ..
                },
            )
            | (
                Shape::Circle {
                    fill: f1,
                    stroke: s1,
                    ..
                },
                Shape::Circle {
                    fill: f2,
                    stroke: s2,
                    ..
                },
            )
            | (
                Shape::Rect {
                    fill: f1,
                    stroke: s1,
                    ..
                },
                Shape::Rect {
                    fill: f2,
                    stroke: s2,
                    ..
                },
            ) => f1.is_some() == f2.is_some() && s1.is_some() == s2.is_some(),
            _ => true,
        }
}

/// One animated SVG of `frames`, each shown for `frame_seconds`, looping. Every frame
/// must have the size and the same sequence of primitive kinds as the first (the
/// values may change: positions, colours, widths, texts); else [`DrawError::Frames`].
/// Changing attributes are `<animate calcMode="discrete">` lists, one value a frame; a
/// text whose words change is one element per run of frames with the same words, shown
/// during its run.
pub fn animated(frames: &[Figure], frame_seconds: f64) -> Result<String, DrawError> {
    let Some(first) = frames.first() else {
        return Err(DrawError::Frames("no frame".into()));
    };
    if !(frame_seconds.is_finite() && frame_seconds > 0.0) {
        return Err(DrawError::Frames(format!(
            "frame duration {frame_seconds} s is not positive"
        )));
    }
    for (k, f) in frames.iter().enumerate() {
        if (f.width, f.height) != (first.width, first.height)
            || f.shapes.len() != first.shapes.len()
        {
            return Err(DrawError::Frames(format!(
                "frame {k} has another size or number of primitives than frame 0"
            )));
        }
        if let Some(i) = (0..f.shapes.len()).find(|&i| !same_kind(&f.shapes[i], &first.shapes[i])) {
            return Err(DrawError::Frames(format!(
                "primitive {i} of frame {k} is of another kind than in frame 0"
            )));
        }
    }
    let n = frames.len();
    let dur = num_s(frame_seconds * n as f64);
    let timing = format!("dur=\"{dur}s\" repeatCount=\"indefinite\" calcMode=\"discrete\"");
    let mut o = String::new();
    header(&mut o, first);
    for (i, s0) in first.shapes.iter().enumerate() {
        if let Shape::Text(_) = s0 {
            animated_text(&mut o, frames, i, &timing);
            continue;
        }
        let (open, close) = element(s0);
        let per_frame: Vec<Vec<(&str, String)>> =
            frames.iter().map(|f| attributes(&f.shapes[i])).collect();
        let mut anims = String::new();
        for (a, (name, v0)) in per_frame[0].iter().enumerate() {
            if per_frame.iter().all(|attrs| attrs[a].1 == *v0) {
                continue;
            }
            let values: Vec<&str> = per_frame.iter().map(|attrs| attrs[a].1.as_str()).collect();
            let _ = writeln!(
                anims,
                "<animate attributeName=\"{name}\" values=\"{}\" {timing}/>",
                values.join(";")
            );
        }
        if anims.is_empty() {
            let _ = writeln!(o, "{open}/>");
        } else {
            let _ = write!(o, "{open}>\n{anims}{close}\n");
        }
    }
    o.push_str("</svg>\n");
    Ok(o)
}

/// Seconds with up to 6 decimals.
fn num_s(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// Text `i` of every frame: one element per run of frames with the same words and
/// style, visible during that run (SMIL `visibility`, discrete key times).
fn animated_text(o: &mut String, frames: &[Figure], i: usize, timing: &str) {
    let n = frames.len();
    let text = |k: usize| match &frames[k].shapes[i] {
        Shape::Text(t) => Some(t),
        _ => None,
    };
    let mut k = 0;
    while k < n {
        let Some(t) = text(k) else { return };
        let mut end = k + 1;
        while end < n && text(end) == Some(t) {
            end += 1;
        }
        let _ = write!(o, "{}", text_open(t));
        if k == 0 && end == n {
            let _ = writeln!(o, ">{}</text>", escape(&t.text));
        } else {
            // Visible on [k/n, end/n): key times 0, k/n, end/n with discrete values.
            let (a, b) = (k as f64 / n as f64, end as f64 / n as f64);
            let (values, times) = if k == 0 {
                ("visible;hidden".to_string(), format!("0;{}", num_s(b)))
            } else if end == n {
                ("hidden;visible".to_string(), format!("0;{}", num_s(a)))
            } else {
                (
                    "hidden;visible;hidden".to_string(),
                    format!("0;{};{}", num_s(a), num_s(b)),
                )
            };
            let initial = if k == 0 { "visible" } else { "hidden" };
            let _ = writeln!(
                o,
                " visibility=\"{initial}\">{}<animate attributeName=\"visibility\" values=\"{values}\" keyTimes=\"{times}\" {timing}/></text>",
                escape(&t.text)
            );
        }
        k = end;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::draw::{pt, Figure};

    #[test]
    fn numbers_are_fixed_and_never_negative_zero() {
        assert_eq!(num(1.0), "1.00");
        assert_eq!(num(-0.001), "0.00");
        assert_eq!(num(2.345678), "2.35");
        assert_eq!(num(f64::NAN), "0.00");
        assert_eq!(num_s(0.04), "0.04");
        assert_eq!(num_s(10.0), "10");
    }

    #[test]
    fn frames_of_other_structure_are_an_error() {
        let mut a = Figure::new(10, 10);
        a.line(pt(0.0, 0.0), pt(1.0, 1.0), Stroke::solid(Color::BLACK, 1.0));
        let mut b = Figure::new(10, 10);
        b.rect(pt(0.0, 0.0), 1.0, 1.0, None, None);
        assert!(matches!(
            animated(&[a.clone(), b], 0.1),
            Err(DrawError::Frames(_))
        ));
        assert!(matches!(animated(&[], 0.1), Err(DrawError::Frames(_))));
        assert!(matches!(animated(&[a], 0.0), Err(DrawError::Frames(_))));
    }
}
