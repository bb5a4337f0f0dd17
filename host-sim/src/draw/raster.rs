//! Raster rendering of a [`Figure`]: shapes anti-aliased by `tiny-skia` (its portable
//! code, no SIMD feature, so every machine computes the same pixels), texts blitted
//! from the pre-rasterized Noto Sans Mono glyphs of `noto-sans-mono-bitmap` (shipped
//! in the crate: no system font), PNG encoded by `png`.

use super::{Anchor, Color, DrawError, Figure, Shape, Stroke, Text, TextSize, MAX_SIDE};
use noto_sans_mono_bitmap::{get_raster, get_raster_width, FontWeight, RasterHeight};
use tiny_skia::{FillRule, LineCap, LineJoin, Paint, PathBuilder, Pixmap, Transform};

fn raster_height(s: TextSize) -> RasterHeight {
    match s {
        TextSize::Small => RasterHeight::Size16,
        TextSize::Medium => RasterHeight::Size20,
        TextSize::Large => RasterHeight::Size24,
    }
}

/// Line height of a text size, px.
pub fn line_height(s: TextSize) -> usize {
    raster_height(s).val()
}

/// Whether the PNG's font draws `ch` (else it draws `?`): Latin letters and Latin-1's
/// signs (`·`, `°`, `²`), no Greek.
pub fn has_glyph(ch: char) -> bool {
    get_raster(ch, FontWeight::Regular, RasterHeight::Size16).is_some()
}

/// Advance of one character, px (regular and bold have the same width).
pub fn advance(s: TextSize) -> usize {
    get_raster_width(FontWeight::Regular, raster_height(s))
}

fn skia_color(c: Color) -> tiny_skia::Color {
    tiny_skia::Color::from_rgba8(c.r, c.g, c.b, c.a)
}

fn paint(c: Color) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(skia_color(c));
    p.anti_alias = true;
    p
}

fn skia_stroke(s: &Stroke) -> tiny_skia::Stroke {
    tiny_skia::Stroke {
        width: s.width.max(0.0) as f32,
        line_cap: LineCap::Butt,
        line_join: LineJoin::Round,
        dash: s
            .dash
            .and_then(|(d, g)| tiny_skia::StrokeDash::new(vec![d as f32, g as f32], 0.0)),
        ..tiny_skia::Stroke::default()
    }
}

fn path_of(points: &[super::Pt], close: bool) -> Option<tiny_skia::Path> {
    let mut pb = PathBuilder::new();
    let mut it = points.iter().filter(|p| p.x.is_finite() && p.y.is_finite());
    let first = it.next()?;
    pb.move_to(first.x as f32, first.y as f32);
    for p in it {
        pb.line_to(p.x as f32, p.y as f32);
    }
    if close {
        pb.close();
    }
    pb.finish()
}

fn fill_and_stroke(
    pm: &mut Pixmap,
    path: Option<tiny_skia::Path>,
    fill: Option<Color>,
    stroke: Option<&Stroke>,
) {
    let Some(path) = path else { return };
    if let Some(c) = fill {
        pm.fill_path(
            &path,
            &paint(c),
            FillRule::Winding,
            Transform::identity(),
            None,
        );
    }
    if let Some(s) = stroke {
        if s.width > 0.0 {
            pm.stroke_path(
                &path,
                &paint(s.color),
                &skia_stroke(s),
                Transform::identity(),
                None,
            );
        }
    }
}

/// Renders `f` into a pixmap (premultiplied RGBA).
pub fn render(f: &Figure) -> Result<Pixmap, DrawError> {
    let size_err = DrawError::Size {
        width: f.width,
        height: f.height,
    };
    if f.width == 0 || f.height == 0 || f.width > MAX_SIDE || f.height > MAX_SIDE {
        return Err(size_err);
    }
    let mut pm = Pixmap::new(f.width, f.height).ok_or(size_err)?;
    pm.fill(skia_color(f.background.with_alpha(255)));
    for s in &f.shapes {
        match s {
            Shape::Line { a, b, stroke } => {
                fill_and_stroke(&mut pm, path_of(&[*a, *b], false), None, Some(stroke))
            }
            Shape::Polyline { points, stroke } => {
                if points.len() >= 2 {
                    fill_and_stroke(&mut pm, path_of(points, false), None, Some(stroke))
                }
            }
            Shape::Polygon {
                points,
                fill,
                stroke,
            } => fill_and_stroke(&mut pm, path_of(points, true), *fill, stroke.as_ref()),
            Shape::Circle { c, r, fill, stroke } => {
                let path = (c.x.is_finite() && c.y.is_finite() && *r > 0.0)
                    .then(|| PathBuilder::from_circle(c.x as f32, c.y as f32, *r as f32))
                    .flatten();
                fill_and_stroke(&mut pm, path, *fill, stroke.as_ref())
            }
            Shape::Rect {
                at,
                w,
                h,
                fill,
                stroke,
            } => {
                let path =
                    tiny_skia::Rect::from_xywh(at.x as f32, at.y as f32, *w as f32, *h as f32)
                        .map(PathBuilder::from_rect);
                fill_and_stroke(&mut pm, path, *fill, stroke.as_ref())
            }
            Shape::Text(t) => draw_text(&mut pm, t),
        }
    }
    Ok(pm)
}

/// Blends a glyph's coverage `cov` (0..=255) of colour `c` into pixel (x, y).
fn blend(pm: &mut Pixmap, x: i64, y: i64, c: Color, cov: u8) {
    let (w, h) = (pm.width() as i64, pm.height() as i64);
    if cov == 0 || x < 0 || y < 0 || x >= w || y >= h {
        return;
    }
    let a = cov as u32 * c.a as u32 / 255;
    let i = ((y * w + x) * 4) as usize;
    let d = pm.data_mut();
    for (k, src) in [c.r, c.g, c.b].into_iter().enumerate() {
        let dst = d[i + k] as u32;
        d[i + k] = ((src as u32 * a + dst * (255 - a) + 127) / 255) as u8;
    }
    let da = d[i + 3] as u32;
    d[i + 3] = (a + da * (255 - a) / 255).min(255) as u8;
}

fn draw_text(pm: &mut Pixmap, t: &Text) {
    let height = raster_height(t.size);
    let weight = if t.bold {
        FontWeight::Bold
    } else {
        FontWeight::Regular
    };
    let adv = advance(t.size) as f64;
    let lh = line_height(t.size) as f64;
    let width = adv * t.text.chars().count() as f64;
    // Offset of the text's start along its reading direction.
    let start = match t.anchor {
        Anchor::Start => 0.0,
        Anchor::Middle => -width / 2.0,
        Anchor::End => -width,
    };
    let (x0, y0) = (t.at.x.round() as i64, t.at.y.round() as i64);
    let along0 = start.round() as i64;
    let across0 = (-lh / 2.0).round() as i64;
    for (k, ch) in t.text.chars().enumerate() {
        let glyph = get_raster(ch, weight, height).or_else(|| get_raster('?', weight, height));
        let Some(g) = glyph else { continue };
        let base = along0 + (k as f64 * adv) as i64;
        for (row, line) in g.rows().enumerate() {
            for (col, &cov) in line.iter().enumerate() {
                let (u, v) = (base + col as i64, across0 + row as i64);
                // Horizontal: (u, v) as is; vertical (turned 90° CCW): x = v, y = -u.
                let (x, y) = if t.vertical {
                    (x0 + v, y0 - u)
                } else {
                    (x0 + u, y0 + v)
                };
                blend(pm, x, y, t.color, cov);
            }
        }
    }
}

/// The PNG file (8-bit RGB) of `f`.
pub fn to_png(f: &Figure) -> Result<Vec<u8>, DrawError> {
    let (w, h, rgb) = to_rgb(f)?;
    encode_rgb(w, h, &rgb)
}

/// Encodes 8-bit RGB pixels, row by row, as a PNG file.
pub fn encode_rgb(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, DrawError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::High);
        let mut w = enc
            .write_header()
            .map_err(|e| DrawError::Encode(e.to_string()))?;
        w.write_image_data(rgb)
            .map_err(|e| DrawError::Encode(e.to_string()))?;
        w.finish().map_err(|e| DrawError::Encode(e.to_string()))?;
    }
    Ok(out)
}

/// Opaque RGB pixels of `f` (the background is opaque, so premultiplied = straight).
pub fn to_rgb(f: &Figure) -> Result<(u32, u32, Vec<u8>), DrawError> {
    let pm = render(f)?;
    let rgb = pm
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok((pm.width(), pm.height(), rgb))
}
