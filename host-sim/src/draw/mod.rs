//! Pictures: a [`Figure`] is a list of primitives (lines, polylines, polygons, circles,
//! rectangles, text) in pixel coordinates (x right, y down), rendered to SVG
//! ([`Figure::to_svg`], hand-written text, numbers with two decimals) or PNG
//! ([`Figure::to_png`], anti-aliased by `tiny-skia`, text from the bitmap font that
//! ships in the crate `noto-sans-mono-bitmap`: no system font is read). Both are
//! deterministic: the same figure gives the same bytes.
//!
//! On top of it: [`plot`] (line plots, category bands, stacked panels, nice ticks),
//! [`heatmap()`] (parameter sweeps), [`ticks`] (nice numbers), and [`svg::animated`] (a
//! sequence of figures of one structure as one animated SVG).

pub mod heatmap;
pub mod plot;
pub mod raster;
pub mod svg;
pub mod ticks;

pub use heatmap::{heatmap, try_heatmap, HeatMap};
pub use plot::{panels, Plot, Series};

use std::fmt;

/// An sRGB colour with alpha (255: opaque).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Color {
    /// Red.
    pub r: u8,
    /// Green.
    pub g: u8,
    /// Blue.
    pub b: u8,
    /// Alpha.
    pub a: u8,
}

impl Color {
    /// An opaque colour.
    pub const fn rgb(r: u8, g: u8, b: u8) -> Color {
        Color { r, g, b, a: 255 }
    }
    /// The same colour with alpha `a`.
    pub const fn with_alpha(self, a: u8) -> Color {
        Color { a, ..self }
    }
    /// `#rrggbb`.
    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.r, self.g, self.b)
    }
    /// White.
    pub const WHITE: Color = Color::rgb(255, 255, 255);
    /// Black.
    pub const BLACK: Color = Color::rgb(0, 0, 0);
    /// Dark grey (text, axes).
    pub const INK: Color = Color::rgb(40, 40, 40);
    /// Light grey (grid).
    pub const GRID: Color = Color::rgb(225, 225, 225);
    /// Mid grey.
    pub const GREY: Color = Color::rgb(150, 150, 150);
}

/// The series colours: Okabe and Ito's colour-blind-safe palette (without its yellow,
/// too pale on white), then greys.
pub const PALETTE: [Color; 8] = [
    Color::rgb(0, 114, 178),   // blue
    Color::rgb(213, 94, 0),    // vermillion
    Color::rgb(0, 158, 115),   // bluish green
    Color::rgb(204, 121, 167), // reddish purple
    Color::rgb(230, 159, 0),   // orange
    Color::rgb(86, 180, 233),  // sky blue
    Color::rgb(0, 0, 0),       // black
    Color::rgb(140, 140, 140), // grey
];

/// A point, px.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pt {
    /// x, px, rightwards.
    pub x: f64,
    /// y, px, downwards.
    pub y: f64,
}

/// A point, px.
pub const fn pt(x: f64, y: f64) -> Pt {
    Pt { x, y }
}

/// How a line is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stroke {
    /// Colour.
    pub color: Color,
    /// Width, px.
    pub width: f64,
    /// Dash and gap lengths, px (`None`: solid).
    pub dash: Option<(f64, f64)>,
}

impl Stroke {
    /// A solid line.
    pub const fn solid(color: Color, width: f64) -> Stroke {
        Stroke {
            color,
            width,
            dash: None,
        }
    }
    /// A dashed line.
    pub const fn dashed(color: Color, width: f64, dash: f64, gap: f64) -> Stroke {
        Stroke {
            color,
            width,
            dash: Some((dash, gap)),
        }
    }
}

/// Horizontal placement of a text relative to its point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// The text starts at the point.
    Start,
    /// The text is centred on the point.
    Middle,
    /// The text ends at the point.
    End,
}

/// Text size: the three sizes of the shipped bitmap font.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextSize {
    /// 16 px line height (tick labels, legends).
    Small,
    /// 20 px (axis labels).
    Medium,
    /// 24 px (titles).
    Large,
}

impl TextSize {
    /// Line height, px.
    pub fn height(self) -> f64 {
        raster::line_height(self) as f64
    }
    /// Advance of one character, px (the font is monospaced).
    pub fn advance(self) -> f64 {
        raster::advance(self) as f64
    }
    /// Width of `text`, px.
    pub fn width(self, text: &str) -> f64 {
        self.advance() * text.chars().count() as f64
    }
}

/// A text: one line, vertically centred on its point.
#[derive(Clone, Debug, PartialEq)]
pub struct Text {
    /// Where, px.
    pub at: Pt,
    /// What.
    pub text: String,
    /// How large.
    pub size: TextSize,
    /// Horizontal placement.
    pub anchor: Anchor,
    /// Colour.
    pub color: Color,
    /// Bold.
    pub bold: bool,
    /// Turned 90° counter-clockwise (reading upwards, as a y-axis label).
    pub vertical: bool,
}

impl Text {
    /// A horizontal text in the ink colour, regular weight.
    pub fn new(at: Pt, text: impl Into<String>, size: TextSize, anchor: Anchor) -> Text {
        Text {
            at,
            text: text.into(),
            size,
            anchor,
            color: Color::INK,
            bold: false,
            vertical: false,
        }
    }
}

/// A primitive of a figure.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A straight segment.
    Line {
        /// Start.
        a: Pt,
        /// End.
        b: Pt,
        /// How.
        stroke: Stroke,
    },
    /// An open polyline (at least 2 points to be drawn).
    Polyline {
        /// Points.
        points: Vec<Pt>,
        /// How.
        stroke: Stroke,
    },
    /// A closed polygon.
    Polygon {
        /// Corners.
        points: Vec<Pt>,
        /// Fill.
        fill: Option<Color>,
        /// Outline.
        stroke: Option<Stroke>,
    },
    /// A circle.
    Circle {
        /// Centre.
        c: Pt,
        /// Radius, px.
        r: f64,
        /// Fill.
        fill: Option<Color>,
        /// Outline.
        stroke: Option<Stroke>,
    },
    /// An axis-aligned rectangle.
    Rect {
        /// Top-left corner.
        at: Pt,
        /// Width, px.
        w: f64,
        /// Height, px.
        h: f64,
        /// Fill.
        fill: Option<Color>,
        /// Outline.
        stroke: Option<Stroke>,
    },
    /// A text.
    Text(Text),
}

/// A picture: a size, a background and primitives drawn in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Background (opaque).
    pub background: Color,
    /// The primitives, back to front.
    pub shapes: Vec<Shape>,
    /// Why the figure does not show what was asked (a heat map of inconsistent
    /// lengths shows the message): [`Figure::to_png`] and [`Figure::write`] return it.
    pub invalid: Option<DrawError>,
}

/// The largest figure side, px (a guard against a typo that would allocate gigabytes).
pub const MAX_SIDE: u32 = 8192;

impl Figure {
    /// An empty figure on white.
    pub fn new(width: u32, height: u32) -> Figure {
        Figure {
            width,
            height,
            background: Color::WHITE,
            shapes: Vec::new(),
            invalid: None,
        }
    }
    /// Adds a primitive.
    pub fn push(&mut self, s: Shape) {
        self.shapes.push(s);
    }
    /// Adds a segment.
    pub fn line(&mut self, a: Pt, b: Pt, stroke: Stroke) {
        self.push(Shape::Line { a, b, stroke });
    }
    /// Adds a text.
    pub fn text(&mut self, t: Text) {
        self.push(Shape::Text(t));
    }
    /// Adds a rectangle.
    pub fn rect(&mut self, at: Pt, w: f64, h: f64, fill: Option<Color>, stroke: Option<Stroke>) {
        self.push(Shape::Rect {
            at,
            w,
            h,
            fill,
            stroke,
        });
    }
    /// Adds hatching (45° lines `spacing` px apart) clipped to the rectangle.
    pub fn hatch(&mut self, at: Pt, w: f64, h: f64, spacing: f64, stroke: Stroke) {
        for (a, b) in hatch_segments(at, w, h, spacing) {
            self.line(a, b, stroke);
        }
    }
    /// The SVG document.
    pub fn to_svg(&self) -> String {
        svg::render(self)
    }
    /// The PNG file (8-bit RGB).
    pub fn to_png(&self) -> Result<Vec<u8>, DrawError> {
        if let Some(e) = &self.invalid {
            return Err(e.clone());
        }
        raster::to_png(self)
    }
    /// Writes `path` as SVG or PNG by its extension (`.svg`, `.png`).
    pub fn write(&self, path: &std::path::Path) -> Result<(), DrawError> {
        if let Some(e) = &self.invalid {
            return Err(e.clone());
        }
        let bytes = match Format::of(path)? {
            Format::Svg => self.to_svg().into_bytes(),
            Format::Png => self.to_png()?,
        };
        crate::error::write_whole(path, &bytes).map_err(|e| DrawError::Write {
            path: path.display().to_string(),
            error: e.to_string(),
        })
    }
}

/// Segments of 45° hatching (from bottom-left to top-right) inside a rectangle.
pub fn hatch_segments(at: Pt, w: f64, h: f64, spacing: f64) -> Vec<(Pt, Pt)> {
    let mut out = Vec::new();
    if !(w > 0.0 && h > 0.0 && spacing > 0.0) {
        return out;
    }
    // Lines x - (bottom - y) = c: from the bottom edge going up-right; c from -h to w.
    let bottom = at.y + h;
    let n = ((w + h) / spacing).ceil() as i64;
    for k in 1..n {
        let c = -h + k as f64 * spacing;
        // Start on the bottom edge or the left edge; end on the right edge or the top edge.
        let (x0, y0) = if c >= 0.0 {
            (at.x + c, bottom)
        } else {
            (at.x, bottom + c)
        };
        let (x1, y1) = if c + h <= w {
            (at.x + c + h, at.y)
        } else {
            (at.x + w, bottom - (w - c))
        };
        out.push((pt(x0, y0), pt(x1, y1)));
    }
    out
}

/// A picture file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.svg`.
    Svg,
    /// `.png`.
    Png,
}

impl Format {
    /// The format of `path` by its extension (case-insensitive).
    pub fn of(path: &std::path::Path) -> Result<Format, DrawError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(DrawError::Extension(path.display().to_string())),
        }
    }
}

/// Why a picture could not be made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DrawError {
    /// Data of inconsistent lengths (e.g. a heat map's `z` is not `x.len() * y.len()`).
    Length(String),
    /// A figure of zero size or larger than [`MAX_SIDE`].
    Size {
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
    },
    /// Frames of an animation differ in structure.
    Frames(String),
    /// Encoding failed.
    Encode(String),
    /// A file name with an extension that names no picture format.
    Extension(String),
    /// Writing a file failed.
    Write {
        /// The path.
        path: String,
        /// The I/O error.
        error: String,
    },
}

impl fmt::Display for DrawError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DrawError::Length(m) => write!(f, "inconsistent lengths: {m}"),
            DrawError::Size { width, height } => write!(
                f,
                "figure size {width} x {height} px is not in 1..={MAX_SIDE}"
            ),
            DrawError::Frames(m) => write!(f, "animation frames: {m}"),
            DrawError::Encode(m) => write!(f, "cannot encode: {m}"),
            DrawError::Extension(p) => {
                write!(f, "{p}: unknown picture extension (.svg or .png expected)")
            }
            DrawError::Write { path, error } => write!(f, "cannot write {path}: {error}"),
        }
    }
}

impl std::error::Error for DrawError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hatch_stays_inside() {
        let segs = hatch_segments(pt(10.0, 20.0), 30.0, 12.0, 5.0);
        assert_eq!(segs.len(), 8);
        for (a, b) in segs {
            for p in [a, b] {
                assert!((10.0..=40.0).contains(&p.x) && (20.0..=32.0).contains(&p.y));
            }
            // 45° up-right.
            assert!(((b.x - a.x) - (a.y - b.y)).abs() < 1e-12);
        }
    }
}
