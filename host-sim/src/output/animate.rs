//! Animations of a run (`host-sim run ... --animate FILE.svg|FILE.gif`): the mechanism
//! drawn from its joint positions at frame times, links as bars between their joints,
//! ground pivots hatched, sliders as blocks. For the converter also the diode's state
//! (the locked or engaged lever highlighted), the shaft with a mark that turns with it,
//! the oscillating mass as a disk, a caption with time, mode and c6/c8, and a strip of
//! c6/c8 over the run with a cursor.
//!
//! Frames are taken at the steps nearest to `k · dt` of simulated time, `dt = 1 /
//! (fps · slow)`; the picture plays `fps` frames a second, so `slow` times slower than
//! the run. Every frame is a [`Figure`] of the same structure, so one piece of code
//! draws the PNG frames of the GIF and the animated SVG ([`crate::draw::svg::animated`]).

use super::{Observer, State};
use crate::draw::plot::decimate;
use crate::draw::ticks::ticks;
use crate::draw::{
    pt, raster, svg, Anchor, Color, DrawError, Figure, Format, Pt, Shape, Stroke, Text, TextSize,
    PALETTE,
};
use crate::options::AnimFormat;
use std::path::Path;
use structomat::ccc::{Clutch, Mode, Twin};
use structomat::{Real, Simulation};

/// Frame size, px.
pub const FRAME_SIZE: (u32, u32) = (800, 600);

/// One link's joints at a frame, world coordinates, m.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkPose {
    /// The link's number (1-based).
    pub link: usize,
    /// Its joints: a bar's two ends first (the converter's rocker: E, C, then D).
    pub points: Vec<[f64; 2]>,
    /// Its frame angle, rad (the block of a slider is drawn turned by it).
    pub theta: f64,
}

/// The state drawn in one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Time, s.
    pub t: f64,
    /// Steps taken to this state.
    pub step: u64,
    /// The links.
    pub links: Vec<LinkPose>,
    /// Converter: the mode.
    pub mode: Option<Mode>,
    /// Converter: `[c6, c8]`, N·m.
    pub clutch: [f64; 2],
    /// Converter: the shaft angle, rad, CCW positive.
    pub shaft_angle: f64,
    /// Converter: the oscillating mass's position, m.
    pub mass: Option<[f64; 2]>,
}

/// The frames of a run, taken as it steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// Simulated time between frames, s.
    pub dt: f64,
    /// Frames a second of the picture.
    pub fps: u32,
    /// Ground pivots, m.
    pub ground: Vec<[f64; 2]>,
    /// Converter: the output shaft H, m.
    pub shaft: Option<[f64; 2]>,
    /// The frames, in time order.
    pub frames: Vec<Frame>,
    /// Converter: every state's time and `[c6, c8]` (the strip under the picture).
    pub strip: Vec<(f64, [f64; 2])>,
    /// Title (the scenario).
    pub title: String,
}

impl Frames {
    /// No frames yet: one every `1 / (fps · slow)` s of simulated time.
    pub fn new(title: &str, fps: u32, slow: f64) -> Frames {
        Frames {
            dt: 1.0 / (fps as f64 * slow),
            fps,
            ground: Vec::new(),
            shaft: None,
            frames: Vec::new(),
            strip: Vec::new(),
            title: title.to_string(),
        }
    }

    /// Whether the state at `t` (step `h`) is the next frame's: the nearest step to
    /// `k · dt` (the first state within half a step of it, or past it).
    fn due(&self, t: f64, h: f64) -> bool {
        t >= self.frames.len() as f64 * self.dt - 0.5 * h
    }

    /// Records the converter's state (call at t = 0 and after every step).
    pub fn converter<T: Real>(&mut self, twin: &Twin<T>) {
        let [c6, c8] = twin.clutch_torques();
        let t = twin.time().to_f64();
        self.strip.push((t, [c6.to_f64(), c8.to_f64()]));
        let h = twin.h().to_f64();
        if self.frames.is_empty() {
            let p = twin.params();
            let v = |v: structomat::scalar::Vec2<T>| [v.x.to_f64(), v.y.to_f64()];
            self.ground = vec![v(p.a), v(p.f)];
            self.shaft = Some(v(p.h));
        }
        while self.due(t, h) {
            let v = |v: structomat::scalar::Vec2<T>| [v.x.to_f64(), v.y.to_f64()];
            let links = (1..=8)
                .map(|p| {
                    let mut points =
                        vec![v(twin.joint_position(p, 0)), v(twin.joint_position(p, 1))];
                    if p == 3 {
                        points.push(v(twin.joint_position(3, 2)));
                    }
                    LinkPose {
                        link: p,
                        points,
                        theta: twin.link(p).theta.to_f64(),
                    }
                })
                .collect();
            let rocker = twin.link(3);
            let at = twin.params().mass_at;
            let mass = rocker.origin
                + structomat::scalar::Vec2::new(rocker.theta.cos(), rocker.theta.sin()) * at;
            self.frames.push(Frame {
                t,
                step: twin.steps(),
                links,
                mode: Some(twin.mode()),
                clutch: [c6.to_f64(), c8.to_f64()],
                shaft_angle: twin.shaft_angle().to_f64(),
                mass: Some(v(mass)),
            });
        }
    }

    /// Records a mechanism's state (call at t = 0 and after every step): every link's
    /// points, `o + R(θ) p`.
    pub fn mechanism<T: Real>(&mut self, sim: &Simulation<T>) {
        let model = sim.model();
        let t = sim.time().to_f64();
        if self.frames.is_empty() {
            self.ground = model
                .ground_points()
                .iter()
                .map(|g| [g.x.to_f64(), g.y.to_f64()])
                .collect();
        }
        while self.due(t, sim.h().to_f64()) {
            let ws = sim.workspace();
            let links = model
                .links()
                .iter()
                .enumerate()
                .map(|(k, l)| {
                    let b = ws.body.get(k + 1).copied().unwrap_or_default();
                    let points = l
                        .points
                        .iter()
                        .map(|p| {
                            let w = b.o
                                + structomat::scalar::Vec2::new(
                                    b.c * p.x - b.s * p.y,
                                    b.s * p.x + b.c * p.y,
                                );
                            [w.x.to_f64(), w.y.to_f64()]
                        })
                        .collect();
                    LinkPose {
                        link: k + 1,
                        points,
                        theta: b.theta.to_f64(),
                    }
                })
                .collect();
            self.frames.push(Frame {
                t,
                step: sim.steps(),
                links,
                mode: None,
                clutch: [0.0; 2],
                shaft_angle: 0.0,
                mass: None,
            });
        }
    }

    /// The figures of the frames.
    pub fn figures(&self) -> Vec<Figure> {
        let view = View::of(self);
        self.frames
            .iter()
            .map(|f| draw_frame(self, &view, f))
            .collect()
    }
}

impl<T: Real> Observer<T> for Frames {
    fn on_state(&mut self, state: State<'_, T>) {
        match state {
            State::Mechanism(sim) => self.mechanism(sim),
            State::Converter(twin) => self.converter(twin),
        }
    }
}

/// The world-to-pixel map: one for all frames, so the picture does not jump.
struct View {
    scale: f64,
    ox: f64,
    oy: f64,
    strip: bool,
}

const CAPTION_H: f64 = 70.0;
const STRIP_H: f64 = 130.0;

impl View {
    fn of(f: &Frames) -> View {
        let strip = f.shaft.is_some() && !f.strip.is_empty();
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let pts = f
            .frames
            .iter()
            .flat_map(|fr| {
                fr.links
                    .iter()
                    .flat_map(|l| l.points.iter())
                    .chain(fr.mass.iter())
            })
            .chain(f.ground.iter())
            .chain(f.shaft.iter());
        for p in pts.filter(|p| p[0].is_finite() && p[1].is_finite()) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if !(lo[0].is_finite() && lo[1].is_finite()) {
            lo = [-1.0, -1.0];
            hi = [1.0, 1.0];
        }
        let (w, h) = (FRAME_SIZE.0 as f64, FRAME_SIZE.1 as f64);
        let area_h = h - CAPTION_H - if strip { STRIP_H } else { 0.0 } - 40.0;
        let area_w = w - 80.0;
        let span = [(hi[0] - lo[0]).max(1e-6), (hi[1] - lo[1]).max(1e-6)];
        let scale = (area_w / span[0]).min(area_h / span[1]);
        // Centre the drawing in its area.
        let ox = 40.0 + (area_w - span[0] * scale) / 2.0 - lo[0] * scale;
        let oy = CAPTION_H + 20.0 + (area_h - span[1] * scale) / 2.0 + hi[1] * scale;
        View {
            scale,
            ox,
            oy,
            strip,
        }
    }
    fn px(&self, p: [f64; 2]) -> Pt {
        pt(self.ox + p[0] * self.scale, self.oy - p[1] * self.scale)
    }
}

const BAR: Color = Color::rgb(60, 70, 90);
const FREE: Color = Color::rgb(150, 150, 150);
const LOCKED: Color = Color::rgb(0, 114, 178);
const ENGAGED: Color = Color::rgb(213, 94, 0);

/// A hatched ground pivot under `c`.
fn ground(f: &mut Figure, c: Pt) {
    let ink = Stroke::solid(Color::INK, 1.5);
    f.push(Shape::Polygon {
        points: vec![c, pt(c.x - 10.0, c.y + 16.0), pt(c.x + 10.0, c.y + 16.0)],
        fill: Some(Color::rgb(235, 235, 235)),
        stroke: Some(ink),
    });
    f.line(pt(c.x - 16.0, c.y + 16.0), pt(c.x + 16.0, c.y + 16.0), ink);
    f.hatch(
        pt(c.x - 16.0, c.y + 16.0),
        32.0,
        8.0,
        5.0,
        Stroke::solid(Color::INK, 1.0),
    );
}

fn joint(f: &mut Figure, c: Pt) {
    f.push(Shape::Circle {
        c,
        r: 4.0,
        fill: Some(Color::WHITE),
        stroke: Some(Stroke::solid(Color::INK, 1.5)),
    });
}

fn clutch_color(c: Clutch) -> Color {
    match c {
        Clutch::Free => FREE,
        Clutch::Locked => LOCKED,
        Clutch::Engaged => ENGAGED,
    }
}

fn draw_frame(frames: &Frames, view: &View, fr: &Frame) -> Figure {
    let (w, h) = FRAME_SIZE;
    let mut f = Figure::new(w, h);
    let mut title = Text::new(
        pt(w as f64 / 2.0, 18.0),
        &frames.title,
        TextSize::Large,
        Anchor::Middle,
    );
    title.bold = true;
    f.text(title);
    let caption = match fr.mode {
        Some(m) => format!(
            "t = {:.4} s   mode {:<4}  c6 = {:6.1} N·m   c8 = {:6.1} N·m",
            fr.t,
            m.name(),
            fr.clutch[0],
            fr.clutch[1]
        ),
        None => format!("t = {:.4} s", fr.t),
    };
    f.text(Text::new(
        pt(w as f64 / 2.0, 46.0),
        caption,
        TextSize::Medium,
        Anchor::Middle,
    ));
    for g in &frames.ground {
        ground(&mut f, view.px(*g));
    }
    let clutches = fr.mode.map(Mode::clutches);
    let block = (0.035 * (w as f64)).max(12.0);
    for l in &fr.links {
        let pts: Vec<Pt> = l.points.iter().map(|p| view.px(*p)).collect();
        let lever = match (clutches, l.link) {
            (Some(c), 6) => Some(c[0]),
            (Some(c), 8) => Some(c[1]),
            _ => None,
        };
        let (color, width) = match lever {
            Some(c) => (clutch_color(c), if c == Clutch::Free { 6.0 } else { 9.0 }),
            None if frames.shaft.is_some() && l.link == 3 => (BAR, 9.0),
            None => (BAR, 6.0),
        };
        match pts.len() {
            0 => {}
            1 => {
                // A slider: a block turned with its frame.
                let (c, s) = (l.theta.cos(), -l.theta.sin());
                let (a, b) = (block * 0.7, block * 0.45);
                let corner =
                    |u: f64, v: f64| pt(pts[0].x + c * u - s * v, pts[0].y + s * u + c * v);
                f.push(Shape::Polygon {
                    points: vec![corner(-a, -b), corner(a, -b), corner(a, b), corner(-a, b)],
                    fill: Some(Color::rgb(200, 210, 225)),
                    stroke: Some(Stroke::solid(BAR, 2.0)),
                });
            }
            2 => f.line(pts[0], pts[1], Stroke::solid(color, width)),
            _ if frames.shaft.is_some() => f.line(pts[0], pts[1], Stroke::solid(color, width)),
            _ => f.push(Shape::Polygon {
                points: pts.clone(),
                fill: Some(Color::rgb(200, 210, 225)),
                stroke: Some(Stroke::solid(color, 3.0)),
            }),
        }
    }
    if let Some(m) = fr.mass {
        f.push(Shape::Circle {
            c: view.px(m),
            r: 15.0,
            fill: Some(Color::rgb(90, 90, 100)),
            stroke: Some(Stroke::solid(Color::INK, 1.5)),
        });
    }
    for l in &fr.links {
        for p in &l.points {
            joint(&mut f, view.px(*p));
        }
    }
    if let Some(hs) = frames.shaft {
        let c = view.px(hs);
        let shaft_turning = fr.mode.is_some_and(Mode::shaft_turning);
        f.push(Shape::Circle {
            c,
            r: 16.0,
            fill: Some(if shaft_turning {
                Color::rgb(250, 220, 200)
            } else {
                Color::rgb(230, 230, 230)
            }),
            stroke: Some(Stroke::solid(Color::INK, 2.0)),
        });
        let a = fr.shaft_angle;
        f.line(
            c,
            pt(c.x + 16.0 * a.cos(), c.y - 16.0 * a.sin()),
            Stroke::solid(Color::INK, 3.0),
        );
        f.text(Text::new(
            pt(c.x, c.y + 30.0),
            "shaft H",
            TextSize::Small,
            Anchor::Middle,
        ));
        // The key to the lever colours.
        let y = 74.0;
        let mut x = 20.0;
        for (name, c) in [
            ("lever free", FREE),
            ("locked (shaft held)", LOCKED),
            ("engaged (shaft turns)", ENGAGED),
        ] {
            f.line(pt(x, y), pt(x + 22.0, y), Stroke::solid(c, 7.0));
            f.text(Text::new(
                pt(x + 28.0, y),
                name,
                TextSize::Small,
                Anchor::Start,
            ));
            x += 28.0 + TextSize::Small.width(name) + 24.0;
        }
    }
    if view.strip {
        draw_strip(&mut f, frames, fr.t);
    }
    f
}

/// c6 and c8 over the whole run, with a cursor at `t`.
fn draw_strip(f: &mut Figure, frames: &Frames, t: f64) {
    let (w, h) = (FRAME_SIZE.0 as f64, FRAME_SIZE.1 as f64);
    let (left, right) = (90.0, w - 30.0);
    let (top, bottom) = (h - STRIP_H + 14.0, h - 28.0);
    let t0 = frames.strip.first().map_or(0.0, |s| s.0);
    let t1 = frames.strip.last().map_or(1.0, |s| s.0).max(t0 + 1e-9);
    let (lo, hi) = frames
        .strip
        .iter()
        .flat_map(|s| s.1)
        .filter(|v| v.is_finite())
        .fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let yt = ticks(lo, hi, 3);
    let sx = |x: f64| left + (x - t0) / (t1 - t0) * (right - left);
    let sy = |y: f64| bottom - (y - yt.lo) / (yt.hi - yt.lo) * (bottom - top);
    for v in &yt.values {
        f.line(
            pt(left, sy(*v)),
            pt(right, sy(*v)),
            Stroke::solid(Color::GRID, 1.0),
        );
        f.text(Text::new(
            pt(left - 6.0, sy(*v)),
            yt.label(*v),
            TextSize::Small,
            Anchor::End,
        ));
    }
    let xt = ticks(t0, t1, 6);
    for v in xt.values.iter().filter(|v| **v >= t0 && **v <= t1 + 1e-12) {
        f.text(Text::new(
            pt(sx(*v), bottom + 12.0),
            xt.label(*v),
            TextSize::Small,
            Anchor::Middle,
        ));
    }
    // Left of the first tick label (centred at `left`), on its line.
    f.text(Text::new(
        pt(left - 22.0, bottom + 12.0),
        "t, s",
        TextSize::Small,
        Anchor::End,
    ));
    for (k, &c) in PALETTE.iter().take(2).enumerate() {
        let run: Vec<(f64, f64)> = frames
            .strip
            .iter()
            .map(|s| (s.0, s.1[k]))
            .filter(|p| p.1.is_finite())
            .collect();
        let pts: Vec<Pt> = decimate(run, t0, t1, (right - left) as usize)
            .into_iter()
            .map(|(x, y)| pt(sx(x), sy(y)))
            .collect();
        if pts.len() >= 2 {
            f.push(Shape::Polyline {
                points: pts,
                stroke: Stroke::solid(c, 1.5),
            });
        }
    }
    // The legend on a white box over the curves' top-right corner, drawn after them.
    f.rect(
        pt(right - 84.0, top + 1.0),
        83.0,
        33.0,
        Some(Color::WHITE),
        Some(Stroke::solid(Color::GRID, 1.0)),
    );
    for (k, name) in ["c6", "c8"].iter().enumerate() {
        let ly = top + 9.0 + 16.0 * k as f64;
        f.line(
            pt(right - 78.0, ly),
            pt(right - 60.0, ly),
            Stroke::solid(PALETTE[k], 2.5),
        );
        f.text(Text::new(
            pt(right - 54.0, ly),
            format!("{name}, N·m"),
            TextSize::Small,
            Anchor::Start,
        ));
    }
    f.rect(
        pt(left, top),
        right - left,
        bottom - top,
        None,
        Some(Stroke::solid(Color::INK, 1.0)),
    );
    let mut yl = Text::new(
        pt(24.0, (top + bottom) / 2.0),
        "N·m",
        TextSize::Small,
        Anchor::Middle,
    );
    yl.vertical = true;
    f.text(yl);
    let x = sx(t.clamp(t0, t1));
    f.line(
        pt(x, top),
        pt(x, bottom),
        Stroke::solid(Color::rgb(220, 0, 0), 2.0),
    );
}

/// Writes the animation of `frames` to `path` (`.svg` or `.gif`).
pub fn write(frames: &Frames, path: &Path) -> Result<(), DrawError> {
    let figures = frames.figures();
    let bytes =
        match AnimFormat::of(path).map_err(|_| DrawError::Extension(path.display().to_string()))? {
            AnimFormat::Svg => svg::animated(&figures, 1.0 / frames.fps as f64)?.into_bytes(),
            AnimFormat::Gif => gif(&figures, frames.fps)?,
        };
    crate::error::write_whole(path, &bytes).map_err(|e| DrawError::Write {
        path: path.display().to_string(),
        error: e.to_string(),
    })
}

/// Writes frame `k` alone as a picture (`.svg` or `.png`).
pub fn write_frame(frames: &Frames, k: usize, path: &Path) -> Result<(), DrawError> {
    Format::of(path)?;
    let view = View::of(frames);
    let fr = frames.frames.get(k).ok_or_else(|| {
        DrawError::Frames(format!("no frame {k} ({} frames)", frames.frames.len()))
    })?;
    draw_frame(frames, &view, fr).write(path)
}

/// The fixed GIF palette: the 6 x 6 x 6 colour cube (216) and 40 greys.
fn palette() -> Vec<u8> {
    let mut p = Vec::with_capacity(768);
    for r in 0..6u32 {
        for g in 0..6u32 {
            for b in 0..6u32 {
                p.extend([(r * 51) as u8, (g * 51) as u8, (b * 51) as u8]);
            }
        }
    }
    for k in 0..40u32 {
        let v = ((k * 255 + 19) / 39) as u8;
        p.extend([v, v, v]);
    }
    p
}

/// The palette index nearest to an RGB pixel: the cube's colour or a grey, whichever is
/// closer.
fn index_of(r: u8, g: u8, b: u8) -> u8 {
    let q = |v: u8| (v as u32 + 25) / 51;
    let (qr, qg, qb) = (q(r), q(g), q(b));
    let d2 = |a: u32, v: u8| {
        let d = a as i64 - v as i64;
        d * d
    };
    let cube = d2(qr * 51, r) + d2(qg * 51, g) + d2(qb * 51, b);
    let mean = (r as u32 + g as u32 + b as u32) / 3;
    let k = (mean * 39 + 127) / 255;
    let gv = (k * 255 + 19) / 39;
    let grey = d2(gv, r) + d2(gv, g) + d2(gv, b);
    if grey < cube {
        216 + k as u8
    } else {
        (qr * 36 + qg * 6 + qb) as u8
    }
}

/// A looping GIF of `figures` at `fps`, fixed palette; each frame after the first is
/// the rectangle of pixels that changed.
pub fn gif(figures: &[Figure], fps: u32) -> Result<Vec<u8>, DrawError> {
    let Some(first) = figures.first() else {
        return Err(DrawError::Frames("no frame".into()));
    };
    let (w, h) = (first.width, first.height);
    if w > u16::MAX as u32 || h > u16::MAX as u32 {
        return Err(DrawError::Size {
            width: w,
            height: h,
        });
    }
    let enc_err = |e: gif::EncodingError| DrawError::Encode(e.to_string());
    let mut out = Vec::new();
    {
        let mut enc =
            gif::Encoder::new(&mut out, w as u16, h as u16, &palette()).map_err(enc_err)?;
        enc.set_repeat(gif::Repeat::Infinite).map_err(enc_err)?;
        let delay = (100.0 / fps.max(1) as f64).round().max(2.0) as u16;
        let mut prev: Option<Vec<u8>> = None;
        for fig in figures {
            let (fw, fh, rgb) = raster::to_rgb(fig)?;
            if (fw, fh) != (w, h) {
                return Err(DrawError::Frames("frames of different sizes".into()));
            }
            let idx: Vec<u8> = rgb
                .chunks_exact(3)
                .map(|p| index_of(p[0], p[1], p[2]))
                .collect();
            // The rectangle that changed since the previous frame (all of the first).
            let (x0, y0, x1, y1) = match &prev {
                None => (0, 0, w as usize, h as usize),
                Some(p) => changed(p, &idx, w as usize, h as usize),
            };
            let (cw, ch) = (x1 - x0, y1 - y0);
            let mut buf = Vec::with_capacity(cw * ch);
            for y in y0..y1 {
                buf.extend_from_slice(&idx[y * w as usize + x0..y * w as usize + x1]);
            }
            let frame = gif::Frame {
                left: x0 as u16,
                top: y0 as u16,
                width: cw as u16,
                height: ch as u16,
                delay,
                dispose: gif::DisposalMethod::Keep,
                buffer: std::borrow::Cow::Owned(buf),
                ..gif::Frame::default()
            };
            enc.write_frame(&frame).map_err(enc_err)?;
            prev = Some(idx);
        }
    }
    Ok(out)
}

/// The smallest rectangle `[x0, x1) x [y0, y1)` holding every pixel that differs (at
/// least one pixel, so that every frame is written and keeps its delay).
fn changed(a: &[u8], b: &[u8], w: usize, h: usize) -> (usize, usize, usize, usize) {
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        let (ra, rb) = (&a[y * w..(y + 1) * w], &b[y * w..(y + 1) * w]);
        if ra == rb {
            continue;
        }
        y0 = y0.min(y);
        y1 = y + 1;
        let first = (0..w).find(|&x| ra[x] != rb[x]).unwrap_or(0);
        let last = (0..w).rev().find(|&x| ra[x] != rb[x]).unwrap_or(0);
        x0 = x0.min(first);
        x1 = x1.max(last + 1);
    }
    if x1 <= x0 || y1 <= y0 {
        (0, 0, 1, 1)
    } else {
        (x0, y0, x1, y1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn palette_indices() {
        assert_eq!(palette().len(), 768);
        assert_eq!(index_of(255, 255, 255), 215);
        assert_eq!(index_of(0, 0, 0), 0);
        // A mid grey goes to the grey ramp, which is finer than the cube's greys.
        let k = index_of(128, 128, 128) as usize;
        let p = palette();
        assert!(k >= 216 && (p[3 * k] as i32 - 128).abs() <= 4, "{k}");
        // Pure red stays red.
        assert_eq!(index_of(255, 0, 0), 5 * 36);
    }

    #[test]
    fn changed_rectangle() {
        let a = vec![0u8; 20];
        let mut b = a.clone();
        b[5 * 2 + 3] = 1; // (x 3, y 2) in a 5 x 4 image
        assert_eq!(changed(&a, &b, 5, 4), (3, 2, 4, 3));
        assert_eq!(changed(&a, &a, 5, 4), (0, 0, 1, 1));
    }
}
