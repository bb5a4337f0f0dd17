//! Every structomat kind in a small mechanism, checked against independent oracles:
//!
//! 1. position: loop closures recomputed here from the body poses and the links' points
//!    (`P = o + R(θ) p`), prismatic points on their lines at their constant angles; the
//!    closed forms against the Newton second method started from perturbed unknowns;
//!    both assembly branches of the closed-form dyads against circle/line intersections
//!    computed here; the triad against the configuration it was constructed from; the
//!    six-link Assur group found back from guesses 0.05 rad off;
//! 2. velocity: `V = ∂P/∂q` and each group's `∂x/∂q` against 4th-order central
//!    differences of positions (thesis eq. 5.12, step 1e-4);
//! 3. acceleration: `a_b` at `q̇ = e_j` and each group's `ẍ` bias against central second
//!    differences of positions (eq. 5.13); the mixed terms of a 2-DOF mechanism
//!    (`second_derivative`) against differences of `V`;
//! 4. dynamics: conservation of `kinetic + potential` with no drive;
//! 5. kinetostatics: driving torque = applied torque, every link's equilibrium summed
//!    here from the reactions, gravity and d'Alembert loads, and the virtual power balance
//!    (thesis eq. 3.19);
//! 6. errors: a group that cannot assemble is named, with its formula, in the error.
//!
//! The mechanisms (ground = body 0, links numbered 1.. as added):
//!
//! | mechanism | formula |
//! |---|---|
//! | offset slider-crank, guide at 20° | `Z(0) + R(1) + RRT(2,3)` |
//! | inverted slider-crank (quick return) | `Z(0) + R(1) + RTR(2,3)` |
//! | pendulum crank with a slot, cross slider on a 60° guide | `Z(0) + R(1) + TRT(2,3)` |
//! | inclined Scotch yoke | `Z(0) + R(1) + RTT(2,3)` |
//! | slider on a 30° incline driving a dyad | `Z(0) + T(1) + RRR(2,3)` |
//! | crank driving a triad | `Z(0) + R(1) + RR-RR-RR(2,3,4,5)` |
//! | the converter in mode A68, crank-driven: a six-link Assur group | `Z(0) + R(1) + ASSUR(2,3,4,5,6,7)` |
//! | crank with a slider driven along it, 2 DOF | `Z(0) + R(1) + T(2) + RRR(3,4)` |
//!
//! Run with `--nocapture` to see the worst error of every check.

use std::f64::consts::PI;
use structomat::kinematics::{assemble, position, position_newton};
use structomat::kinetostatics::driving_torque;
use structomat::motor::Motor;
use structomat::scalar::Vec2;
use structomat::structomat::{
    DyadRrr, DyadRrt, DyadRtr, DyadRtt, DyadTrt, GroupKind, JointKind, MotorR, MotorT, PointRef,
    TriadRrRrRr,
};
use structomat::transmission::{evaluate, second_derivative};
use structomat::{
    GroupFault, Link, Model, ModelBuilder, Real, SetupError, Simulation, StepError, Workspace,
};
use structomat_suite::{
    assert_close, central_diff4, central_second_diff4, isclose, pose, unwrap_near,
};

const G: f64 = 9.81;

fn deg(d: f64) -> f64 {
    d * PI / 180.0
}

// ---------------------------------------------------------------------------------------
// Test-side geometry (independent of the core's chains).
// ---------------------------------------------------------------------------------------

type P2 = [f64; 2];

fn rot(th: f64, p: P2) -> P2 {
    let (s, c) = th.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

fn add(a: P2, b: P2) -> P2 {
    [a[0] + b[0], a[1] + b[1]]
}

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn norm(a: P2) -> f64 {
    a[0].hypot(a[1])
}

fn unit(th: f64) -> P2 {
    [th.cos(), th.sin()]
}

/// Angle of a body (the ground's is 0).
fn angle_of(ws: &Workspace<f64>, body: u8) -> f64 {
    if body == 0 {
        0.0
    } else {
        ws.body[body as usize].theta
    }
}

/// World position of point `p` of `body` (`p` is already world for the ground), from the
/// body's angle and origin only: `o + R(θ) p`.
fn world(ws: &Workspace<f64>, body: u8, p: P2) -> P2 {
    if body == 0 {
        return p;
    }
    let b = &ws.body[body as usize];
    add([b.o.x, b.o.y], rot(b.theta, p))
}

/// Centre of gravity of a link in world coordinates, from its pose and its COG.
fn cog_world(model: &Model<f64>, ws: &Workspace<f64>, body: u8) -> P2 {
    let l = model.link(body).expect("link");
    world(ws, body, [l.cog.x, l.cog.y])
}

/// `a - b` reduced to `(-π, π]`.
fn angle_diff(a: f64, b: f64) -> f64 {
    unwrap_near(a, b) - b
}

/// A joint of a mechanism as designed here (not read from the core).
#[derive(Clone, Copy, Debug)]
enum TJ {
    /// Point `pa` of body `a` coincides with point `pb` of body `b`.
    Rev { a: u8, pa: P2, b: u8, pb: P2 },
    /// Point `ps` of slider `s` runs on the line of body `g` through `pg` with direction
    /// `dir` (rad, frame of `g`), and `θs - θg = rel`.
    Pri {
        s: u8,
        ps: P2,
        g: u8,
        pg: P2,
        dir: f64,
        rel: f64,
    },
}

/// Whether unknown `k` of a group of this kind is an angle (the unknowns as documented
/// in each kind's file), else a length.
fn var_is_angle(kind: GroupKind, k: usize) -> bool {
    match kind {
        GroupKind::Rrr | GroupKind::Triad | GroupKind::Assur => true,
        GroupKind::Rrt | GroupKind::Rtr => k == 0,
        GroupKind::Trt | GroupKind::Rtt => false,
        GroupKind::MotorR | GroupKind::MotorT => unreachable!("motor elements have no unknowns"),
    }
}

/// A mechanism with its test plan.
struct Mech {
    name: &'static str,
    model: Model<f64>,
    joints: Vec<TJ>,
    /// Structomatic formula expected from the design.
    formula: &'static str,
    /// Configurations of the kinematic checks, in the order they are visited (the first is
    /// the assembly configuration; the walk between them follows the assembly branch).
    qs: Vec<Vec<f64>>,
    /// Start of the dynamics runs.
    q0: Vec<f64>,
    qd0: Vec<f64>,
    /// Constant torque (N·m) or force (N) on each coordinate in the kinetostatics run
    /// (coordinate k is driven by group k).
    drives: Vec<f64>,
}

// ---------------------------------------------------------------------------------------
// The mechanisms.
// ---------------------------------------------------------------------------------------

/// `Z(0) + R(1) + RRT(2,3)`: offset slider-crank with its guide at 20°.
///
/// ```text
///                                   C = pin of slider 3 at (0.02, 0.03) in its frame
///        B ________ rod 2 (0.35) ____o
///        /                         [3]   slider 3, its origin on the guide
///  crank 1 (0.10)               __/_____ guide through G0 = (0.05, -0.06) at 20°
///      /                   __/‾‾
///  A = (0, 0)
/// ```
/// The pin's line is 0.0435 m from A (offset e ≠ 0); B is at most 0.144 m from it, far
/// less than the rod: the rod is never perpendicular to the guide (no dead point of the
/// dyad) and the crank turns fully. Branch: the slider ahead of the crank (`s ≈ 0.3`).
/// The slider's frame is turned 0.3 rad from its guide (`θ3 = 20° + 0.3`), so that its
/// pin offset turns too.
fn m_rrt(drive: Option<f64>) -> Mech {
    m_rrt_with(drive, [0.35, 0.3])
}

/// Slider tilt of [`m_rrt`] relative to its guide, rad.
const RRT_TILT: f64 = 0.3;

/// [`m_rrt`] with the given guesses `(θ2, s)`.
fn m_rrt_with(drive: Option<f64>, guess: [f64; 2]) -> Mech {
    m_rrt_sized(drive, guess, 0.35)
}

/// [`m_rrt_with`] with a rod of the given length, m (its centre of mass 0.15 m from the
/// crank pin).
fn m_rrt_sized(drive: Option<f64>, guess: [f64; 2], rod_len: f64) -> Mech {
    let gamma = deg(20.0);
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let g0 = b.ground_point(0.05, -0.06).unwrap();
    let crank = b.link(Link::bar(0.10, 0.5, 1.0e-3, 0.04)).unwrap();
    let rod = b.link(Link::bar(rod_len, 1.0, 0.012, 0.15)).unwrap();
    let mut sl = Link::block(0.8, 2.0e-3);
    let pin = sl.add_point(Vec2::new(0.02, 0.03)).unwrap();
    let slider = b.link(sl).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    b.group(&DyadRrt {
        rod,
        slider,
        pole: PointRef {
            body: crank,
            point: 1,
        },
        rod_at_pole: 0,
        rod_joint: 1,
        slider_joint: pin,
        guide: g0,
        guide_angle: gamma,
        slider_on_guide: 0,
        slider_angle: gamma + RRT_TILT,
        guess,
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(t)).unwrap();
    }
    Mech {
        name: "R+RRT",
        model: b.build().unwrap(),
        joints: vec![
            TJ::Rev {
                a: 1,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.0, 0.0],
            },
            TJ::Rev {
                a: 1,
                pa: [0.10, 0.0],
                b: 2,
                pb: [0.0, 0.0],
            },
            TJ::Rev {
                a: 2,
                pa: [rod_len, 0.0],
                b: 3,
                pb: [0.02, 0.03],
            },
            TJ::Pri {
                s: 3,
                ps: [0.0, 0.0],
                g: 0,
                pg: [0.05, -0.06],
                dir: gamma,
                rel: gamma + RRT_TILT,
            },
        ],
        formula: "Z(0) + R(1) + RRT(2,3)",
        qs: [0.3, 1.7, 3.0, 4.4, 5.9].iter().map(|&q| vec![q]).collect(),
        q0: vec![0.3],
        qd0: vec![6.0],
        drives: vec![0.7],
    }
}

/// `Z(0) + R(1) + RTR(2,3)`: inverted slider-crank (crank-shaper quick return).
///
/// ```text
///        B = crank pin = pin of block 3 at (0.01, -0.02) in its frame
///       /|\  block 3 slides along rocker 2 (its origin on the rocker's line)
///  crank 1 (0.10)   \  rocker 2 (0.5 m), its guide line parallel to its axis,
///     /              \ through its point (0, 0.015)
///  A = (0, 0)         \
///                      C = (0.02, -0.25)   θ3 = θ2 + 0.1 rad
/// ```
/// |CB| ≥ 0.15 m while the line's offset from the block's pin is 0.004 m: the dyad's
/// Jacobian (det = -(s + c·d)) never vanishes; the crank turns fully (|AC| > 0.1).
/// Rocker added before the block so that the formula reads RTR(2,3).
fn m_rtr(drive: Option<f64>) -> Mech {
    m_rtr_with(drive, [1.6, 0.35])
}

/// [`m_rtr`] with the given guesses `(θ2, s)`.
fn m_rtr_with(drive: Option<f64>, guess: [f64; 2]) -> Mech {
    m_rtr_offset(drive, guess, RTR_LINE)
}

/// The offset of [`m_rtr`]'s guide line from the rocker's axis, m.
const RTR_LINE: f64 = 0.015;
/// [`m_rtr`]'s block pin (the crank pin) in the block's frame, m.
const RTR_PIN: P2 = [0.01, -0.02];
/// [`m_rtr`]'s block angle to the rocker, rad.
const RTR_ANGLE: f64 = 0.1;

/// [`m_rtr_with`] with the guide line `line` m off the rocker's axis.
fn m_rtr_offset(drive: Option<f64>, guess: [f64; 2], line: f64) -> Mech {
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let c = b.ground_point(0.02, -0.25).unwrap();
    let crank = b.link(Link::bar(0.10, 0.5, 1.0e-3, 0.04)).unwrap();
    let mut rk = Link::bar(0.5, 1.2, 0.03, 0.25);
    let line_point = rk.add_point(Vec2::new(0.0, line)).unwrap();
    let rocker = b.link(rk).unwrap();
    let mut bl = Link::block(0.3, 5.0e-4);
    let pin = bl.add_point(Vec2::new(RTR_PIN[0], RTR_PIN[1])).unwrap();
    let block = b.link(bl).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    b.group(&DyadRtr {
        a: block,
        b: rocker,
        pole_a: PointRef {
            body: crank,
            point: 1,
        },
        a_at_pole: pin,
        pole_b: c,
        b_at_pole: 0,
        b_line: line_point,
        b_line_angle: 0.0,
        a_on_line: 0,
        a_angle: RTR_ANGLE,
        guess,
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(t)).unwrap();
    }
    Mech {
        name: "R+RTR",
        model: b.build().unwrap(),
        joints: vec![
            TJ::Rev {
                a: 1,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.0, 0.0],
            },
            TJ::Rev {
                a: 1,
                pa: [0.10, 0.0],
                b: 3,
                pb: RTR_PIN,
            },
            TJ::Rev {
                a: 2,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.02, -0.25],
            },
            TJ::Pri {
                s: 3,
                ps: [0.0, 0.0],
                g: 2,
                pg: [0.0, line],
                dir: 0.0,
                rel: RTR_ANGLE,
            },
        ],
        formula: "Z(0) + R(1) + RTR(2,3)",
        qs: [1.6, 2.9, 4.2, 5.5, 6.8].iter().map(|&q| vec![q]).collect(),
        q0: vec![1.6],
        qd0: vec![5.0],
        drives: vec![0.4],
    }
}

/// `Z(0) + R(1) + TRT(2,3)`: a heavy pendulum crank carrying a slot, and a cross slider
/// on a fixed 60° guide.
///
/// ```text
///  A = (0, 0)            crank 1 (0.3 m, 2 kg, COG 0.2 m) hanging down from A; its
///     |                  slot runs at 60° to it through its point (0.2, 0.03)
///     |   \              block 2 in the slot (aligned with the crank), pin (0.02, 0.01)
///     |  [2]o[3]         block 3 on the guide through (0.1, -0.3) at 60° (aligned with
///     |      / \         it), pin at (0.015, -0.01)
///           / 60°
/// ```
/// The slot's direction is `q + 60°`: it is parallel to the fixed guide (TRT singular)
/// at `q = 0` and `q = ±π`. The tested range `q ∈ [-2.3, -0.8]` and the pendulum's swing
/// about its equilibrium stay more than 0.5 rad away from both.
fn m_trt(drive: Option<f64>) -> Mech {
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let gb = b.ground_point(0.1, -0.3).unwrap();
    let mut cr = Link::bar(0.3, 6.0, 0.05, 0.25);
    let slot = cr.add_point(Vec2::new(0.2, 0.03)).unwrap();
    let crank = b.link(cr).unwrap();
    let mut ba = Link::block(0.3, 1.0e-3);
    let pin_a = ba.add_point(Vec2::new(0.02, 0.01)).unwrap();
    let sa = b.link(ba).unwrap();
    let mut bb = Link::block(0.4, 2.0e-3);
    let pin_b = bb.add_point(Vec2::new(0.015, -0.01)).unwrap();
    let sb = b.link(bb).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    b.group(&DyadTrt {
        a: sa,
        b: sb,
        guide_a: PointRef {
            body: crank,
            point: slot,
        },
        guide_a_angle: deg(60.0),
        a_on_guide: 0,
        a_angle: 0.0,
        guide_b: gb,
        guide_b_angle: deg(60.0),
        b_on_guide: 0,
        b_angle: deg(60.0),
        a_joint: pin_a,
        b_joint: pin_b,
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(t)).unwrap();
    }
    Mech {
        name: "R+TRT",
        model: b.build().unwrap(),
        joints: vec![
            TJ::Rev {
                a: 1,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.0, 0.0],
            },
            TJ::Pri {
                s: 2,
                ps: [0.0, 0.0],
                g: 1,
                pg: [0.2, 0.03],
                dir: deg(60.0),
                rel: 0.0,
            },
            TJ::Pri {
                s: 3,
                ps: [0.0, 0.0],
                g: 0,
                pg: [0.1, -0.3],
                dir: deg(60.0),
                rel: deg(60.0),
            },
            TJ::Rev {
                a: 2,
                pa: [0.02, 0.01],
                b: 3,
                pb: [0.015, -0.01],
            },
        ],
        formula: "Z(0) + R(1) + TRT(2,3)",
        qs: [-1.57, -1.9, -2.3, -1.2, -0.8]
            .iter()
            .map(|&q| vec![q])
            .collect(),
        q0: vec![-1.65],
        qd0: vec![1.2],
        drives: vec![1.5],
    }
}

/// `Z(0) + R(1) + RTT(2,3)`: an inclined Scotch yoke.
///
/// ```text
///        slot of yoke 2 (80° in its frame: vertical in the world), through its
///        point (-0.25, 0.02)
///   B o==[3]      block 3 pinned at the crank pin B by its point (0.01, -0.015),
///    /   ||       its origin on the slot, θ3 = θ2 + 0.2 rad
///   / 1  ||____[2]______  yoke 2 on the ground guide through (0.3, 0.05) at 10°
///  A = (0, 0)
/// ```
/// Both unknowns are slides (linear loop closure); the slot is never parallel to the
/// guide, the crank turns fully. The motor element has an offset: `θ1 = q - 0.3`.
fn m_rtt(drive: Option<f64>) -> Mech {
    let phi = deg(10.0);
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let g0 = b.ground_point(0.3, 0.05).unwrap();
    let crank = b.link(Link::bar(0.10, 0.5, 1.0e-3, 0.05)).unwrap();
    let mut yk = Link::block(1.0, 0.01);
    let line = yk.add_point(Vec2::new(-0.25, 0.02)).unwrap();
    let yoke = b.link(yk).unwrap();
    let mut bl = Link::block(0.3, 5.0e-4);
    let pin = bl.add_point(Vec2::new(0.01, -0.015)).unwrap();
    let block = b.link(bl).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: -0.3,
    })
    .unwrap();
    b.group(&DyadRtt {
        a: block,
        b: yoke,
        pole_a: PointRef {
            body: crank,
            point: 1,
        },
        a_at_pole: pin,
        guide: g0,
        guide_angle: phi,
        b_on_guide: 0,
        b_angle: phi,
        b_line: line,
        b_line_angle: deg(80.0),
        a_on_line: 0,
        a_angle: 0.2,
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(t)).unwrap();
    }
    Mech {
        name: "R+RTT",
        model: b.build().unwrap(),
        joints: vec![
            TJ::Rev {
                a: 1,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.0, 0.0],
            },
            TJ::Rev {
                a: 3,
                pa: [0.01, -0.015],
                b: 1,
                pb: [0.10, 0.0],
            },
            TJ::Pri {
                s: 3,
                ps: [0.0, 0.0],
                g: 2,
                pg: [-0.25, 0.02],
                dir: deg(80.0),
                rel: 0.2,
            },
            TJ::Pri {
                s: 2,
                ps: [0.0, 0.0],
                g: 0,
                pg: [0.3, 0.05],
                dir: phi,
                rel: phi,
            },
        ],
        formula: "Z(0) + R(1) + RTT(2,3)",
        qs: [0.0, 1.2, 2.5, 3.8, 5.1].iter().map(|&q| vec![q]).collect(),
        q0: vec![0.0],
        qd0: vec![6.0],
        drives: vec![0.5],
    }
}

/// `Z(0) + T(1) + RRR(2,3)`: a slider on a 30° incline driving a dyad.
///
/// ```text
///                      slider 1 on the guide through (0, 0) at 30° (q = offset, m),
///          P o[1]      its pin P at (0, 0.02) in its frame
///           /  \
///   link 2 /    \__  link 2: P -> C (0.30 m), link 3: D -> C (0.40 m)
///         /     C o
///                \  link 3
///                 o D = (-0.4, -0.6)
/// ```
/// Branch: C to the left of P→D. Over `q ∈ [-0.54, -0.34]` the angle at C stays in
/// 59°..81°. Gravity has a stable equilibrium near `q = -0.44` (the slider's weight
/// down the incline against the dyad's elbow that rises as P nears D), so the free
/// motion oscillates there, far from the dyad's dead points.
fn m_trrr(drive: Option<f64>) -> Mech {
    m_trrr_with(drive, [-0.4, 0.78])
}

/// [`m_trrr`] with the given guesses `(θ2, θ3)`.
fn m_trrr_with(drive: Option<f64>, guess: [f64; 2]) -> Mech {
    m_trrr_sized(drive, guess, [0.30, 0.40])
}

/// [`m_trrr_with`] with links 2 and 3 of the given lengths, m (their centres of mass
/// at their middles).
fn m_trrr_sized(drive: Option<f64>, guess: [f64; 2], [len2, len3]: [f64; 2]) -> Mech {
    let th = deg(30.0);
    let mut b = ModelBuilder::<f64>::new();
    let g0 = b.ground_point(0.0, 0.0).unwrap();
    let d = b.ground_point(-0.4, -0.6).unwrap();
    let mut sl = Link::block(0.3, 1.0e-3);
    let pin = sl.add_point(Vec2::new(0.0, 0.02)).unwrap();
    let slider = b.link(sl).unwrap();
    let l2 = b.link(Link::bar(len2, 0.8, 0.006, 0.5 * len2)).unwrap();
    let l3 = b.link(Link::bar(len3, 0.7, 0.0093, 0.5 * len3)).unwrap();
    b.group(&MotorT {
        link: slider,
        guide: g0,
        guide_angle: th,
        link_point: 0,
        link_angle: th,
        coord: 0,
    })
    .unwrap();
    b.group(&DyadRrr {
        a: l2,
        b: l3,
        pole_a: PointRef {
            body: slider,
            point: pin,
        },
        a_at_pole: 0,
        pole_b: d,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess,
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(t)).unwrap();
    }
    Mech {
        name: "T+RRR",
        model: b.build().unwrap(),
        joints: vec![
            TJ::Pri {
                s: 1,
                ps: [0.0, 0.0],
                g: 0,
                pg: [0.0, 0.0],
                dir: th,
                rel: th,
            },
            TJ::Rev {
                a: 2,
                pa: [0.0, 0.0],
                b: 1,
                pb: [0.0, 0.02],
            },
            TJ::Rev {
                a: 3,
                pa: [0.0, 0.0],
                b: 0,
                pb: [-0.4, -0.6],
            },
            TJ::Rev {
                a: 2,
                pa: [len2, 0.0],
                b: 3,
                pb: [len3, 0.0],
            },
        ],
        formula: "Z(0) + T(1) + RRR(2,3)",
        qs: [-0.44, -0.49, -0.54, -0.39, -0.34]
            .iter()
            .map(|&q| vec![q])
            .collect(),
        q0: vec![-0.44],
        qd0: vec![0.2],
        drives: vec![3.0],
    }
}

/// The triad mechanism's construction: the configuration it is built from.
struct TriadDesign {
    q0: f64,
    /// Angles of binaries 2, 3, 4 and of the ternary link 5, rad.
    angles: [f64; 4],
    /// Origin of the ternary link (its joint with binary 2), m.
    origin: P2,
}

const TRIAD_T: [P2; 3] = [[0.0, 0.0], [0.32, 0.0], [0.14, 0.20]];

fn triad_design() -> TriadDesign {
    TriadDesign {
        q0: deg(70.0),
        angles: [0.0, deg(100.0), deg(-30.0), deg(15.0)],
        origin: [0.30, 0.30],
    }
}

/// `Z(0) + R(1) + RR-RR-RR(2,3,4,5)`: a crank driving a triad.
///
/// Built from a chosen configuration at `q0 = 70°` (so that it assembles there):
/// ```text
///                K3 o
///                    \ binary 4 (0.25 m at -30°)
///               T3 o--\--__
///                 /  [5]   ‾‾‾o T2      ternary 5: T1 = origin (0.30, 0.30), 15°,
///                /__________/ |         local T1 (0,0), T2 (0.32,0), T3 (0.14,0.20)
///             T1 o            | binary 3 (0.30 m at 100°)
///   binary 2    /             o K2
///        B o---‾
///         /  crank 1 (0.12 m; 5 kg with its COG 0.12 m behind A: a counterweight)
///    A = (0, 0)
/// ```
/// Binary 2 runs from the crank pin B to T1 (its length and angle follow from them);
/// K2 = T2 - 0.30 e(100°), K3 = T3 - 0.25 e(-30°). Guesses: the construction's angles
/// perturbed by ±0.05 rad.
fn triad_model<T: Real>(drive: Option<f64>) -> (Model<T>, Vec<TJ>, TriadDesign) {
    let c = T::c;
    let mut des = triad_design();
    let r1 = 0.12;
    let bq = rot(des.q0, [r1, 0.0]);
    let tw: Vec<P2> = TRIAD_T
        .iter()
        .map(|&t| add(des.origin, rot(des.angles[3], t)))
        .collect();
    let v2 = sub(tw[0], bq);
    let l2 = norm(v2);
    des.angles[0] = v2[1].atan2(v2[0]);
    let (l3, l4) = (0.30, 0.25);
    let k2 = sub(tw[1], rot(des.angles[1], [l3, 0.0]));
    let k3 = sub(tw[2], rot(des.angles[2], [l4, 0.0]));
    let mut b = ModelBuilder::<T>::new();
    let a = b.ground_point(c(0.0), c(0.0)).unwrap();
    let pk2 = b.ground_point(c(k2[0]), c(k2[1])).unwrap();
    let pk3 = b.ground_point(c(k3[0]), c(k3[1])).unwrap();
    let crank = b.link(Link::bar(c(r1), c(5.0), c(0.02), c(-0.12))).unwrap();
    let b2 = b
        .link(Link::bar(c(l2), c(0.6), c(6.0e-3), c(l2 / 2.0)))
        .unwrap();
    let b3 = b
        .link(Link::bar(c(l3), c(0.5), c(4.0e-3), c(0.12)))
        .unwrap();
    let b4 = b
        .link(Link::bar(c(l4), c(0.45), c(2.5e-3), c(0.14)))
        .unwrap();
    let mut tl = Link::block(c(1.5), c(0.012));
    tl.add_point(Vec2::new(c(TRIAD_T[1][0]), c(TRIAD_T[1][1])))
        .unwrap();
    tl.add_point(Vec2::new(c(TRIAD_T[2][0]), c(TRIAD_T[2][1])))
        .unwrap();
    tl.cog = Vec2::new(c(0.46 / 3.0), c(0.2 / 3.0));
    let tern = b.link(tl).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: c(0.0),
    })
    .unwrap();
    let ga = des.angles;
    b.group(&TriadRrRrRr {
        ternary: tern,
        ternary_joints: [0, 1, 2],
        binary: [b2, b3, b4],
        binary_at_pole: [0, 0, 0],
        binary_at_ternary: [1, 1, 1],
        poles: [
            PointRef {
                body: crank,
                point: 1,
            },
            pk2,
            pk3,
        ],
        guess: [
            c(ga[0] + 0.05),
            c(ga[1] - 0.05),
            c(ga[2] + 0.05),
            c(ga[3] - 0.05),
        ],
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(c(t))).unwrap();
    }
    let joints = vec![
        TJ::Rev {
            a: 1,
            pa: [0.0, 0.0],
            b: 0,
            pb: [0.0, 0.0],
        },
        TJ::Rev {
            a: 1,
            pa: [r1, 0.0],
            b: 2,
            pb: [0.0, 0.0],
        },
        TJ::Rev {
            a: 3,
            pa: [0.0, 0.0],
            b: 0,
            pb: k2,
        },
        TJ::Rev {
            a: 4,
            pa: [0.0, 0.0],
            b: 0,
            pb: k3,
        },
        TJ::Rev {
            a: 2,
            pa: [l2, 0.0],
            b: 5,
            pb: TRIAD_T[0],
        },
        TJ::Rev {
            a: 3,
            pa: [l3, 0.0],
            b: 5,
            pb: TRIAD_T[1],
        },
        TJ::Rev {
            a: 4,
            pa: [l4, 0.0],
            b: 5,
            pb: TRIAD_T[2],
        },
    ];
    (b.build().unwrap(), joints, des)
}

/// The triad mechanism's test plan: kinematics around its construction (70° ± 17°); the
/// crank rocks between dead points near -1.78 and 3.95 rad, and its counterweight makes a
/// stable equilibrium near 1.85 rad, where the dynamics runs start.
fn m_triad(drive: Option<f64>) -> Mech {
    let (model, joints, des) = triad_model::<f64>(drive);
    let q0 = des.q0;
    Mech {
        name: "R+triad",
        model,
        joints,
        formula: "Z(0) + R(1) + RR-RR-RR(2,3,4,5)",
        qs: [0.0, -0.15, -0.3, 0.15, 0.3]
            .iter()
            .map(|&d| vec![q0 + d])
            .collect(),
        q0: vec![1.85],
        qd0: vec![1.5],
        drives: vec![0.6],
    }
}

/// `Z(0) + R(1) + T(2) + RRR(3,4)`: 2 DOF, a crank (q1, rad) and a slider (q2, m) driven
/// along the crank, joined to the ground by a dyad.
///
/// ```text
///                 P o  pin of slider 2 at (0, 0.03) in its frame
///      crank 1   [2]\  link 3: P -> C (0.35 m)
///      (0.5 m) /     o C
///             /     /  link 4: D -> C (0.30 m)
///  A = (0, 0)      o D = (0.45, -0.05)
/// ```
/// Slider 2 runs on the crank's line through its point (0, 0.02) at 0.1 rad to the crank
/// (`q2` from that point), its frame turned 0.25 rad from that line: its guide turns,
/// and its driving force reacts on the crank. Branch: C to the left of P→D. Over
/// `q1 ∈ [0.8, 1.2]`, `q2 ∈ [0.2, 0.3]` the angle at C stays in 70°..95°.
fn m_two_dof(drive: bool) -> Mech {
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let d = b.ground_point(0.45, -0.05).unwrap();
    let mut cr = Link::bar(0.5, 1.5, 0.03, 0.25);
    let guide = cr.add_point(Vec2::new(0.0, 0.02)).unwrap();
    let crank = b.link(cr).unwrap();
    let mut sl = Link::block(0.6, 1.0e-3);
    let pin = sl.add_point(Vec2::new(0.0, 0.03)).unwrap();
    let slider = b.link(sl).unwrap();
    let l3 = b.link(Link::bar(0.35, 0.8, 0.008, 0.2)).unwrap();
    let l4 = b.link(Link::bar(0.30, 0.7, 0.005, 0.15)).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    b.group(&MotorT {
        link: slider,
        guide: PointRef {
            body: crank,
            point: guide,
        },
        guide_angle: 0.1,
        link_point: 0,
        link_angle: 0.35,
        coord: 1,
    })
    .unwrap();
    b.group(&DyadRrr {
        a: l3,
        b: l4,
        pole_a: PointRef {
            body: slider,
            point: pin,
        },
        a_at_pole: 0,
        pole_b: d,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess: [-0.3, 1.5],
    })
    .unwrap();
    let drives = [0.8, 2.0];
    if drive {
        for (k, t) in drives.iter().enumerate() {
            b.drive(k as u8, Motor::Constant(*t)).unwrap();
        }
    }
    let mut qs = Vec::new();
    for &q1 in &[1.0, 0.8, 1.2] {
        for &q2 in &[0.25, 0.2, 0.3] {
            qs.push(vec![q1, q2]);
        }
    }
    Mech {
        name: "R+T+RRR",
        model: b.build().unwrap(),
        joints: vec![
            TJ::Rev {
                a: 1,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.0, 0.0],
            },
            TJ::Pri {
                s: 2,
                ps: [0.0, 0.0],
                g: 1,
                pg: [0.0, 0.02],
                dir: 0.1,
                rel: 0.35,
            },
            TJ::Rev {
                a: 3,
                pa: [0.0, 0.0],
                b: 2,
                pb: [0.0, 0.03],
            },
            TJ::Rev {
                a: 4,
                pa: [0.0, 0.0],
                b: 0,
                pb: [0.45, -0.05],
            },
            TJ::Rev {
                a: 3,
                pa: [0.35, 0.0],
                b: 4,
                pb: [0.30, 0.0],
            },
        ],
        formula: "Z(0) + R(1) + T(2) + RRR(3,4)",
        qs,
        q0: vec![1.0, 0.25],
        qd0: vec![0.5, -0.2],
        drives: drives.to_vec(),
    }
}

/// The 1-DOF mechanisms (each a builder taking an optional constant drive).
/// `Z(0) + R(1) + ASSUR(2,3,4,5,6,7)`: the converter of SPEC 3 in mode A68 driven by
/// its crank, as one general Assur group of 6 links and 9 revolute joints.
///
/// ```text
///   F o        E  rocker 3 (E -> C, D at its midpoint)     rod 5 (D -> G)   G
///      \ 4 ___o________o D ____________________________________o  \
///             \         \___ rod 7 (D -> I) ___________ I o   o H  levers 6+8 as
///   A o-- 1 --o B -- 2 --o C                                       one body (H, G, I)
/// ```
/// SPEC 3's lengths and ground points (A = (0, 0), F = (0.2, 0.5), H = (1.1, 0)), the
/// levers joined at the angle they have at q1 = 105°, q2 = 90° (so I = H + 0.3 at that
/// angle in the joined body's frame). Plain bars of made-up masses. The group is solved
/// by Newton on 3 loops from B: to F, and to H through each rod and lever.
fn m_assur(drive: Option<f64>) -> Mech {
    use structomat::ccc::{initial_pose, CccParams};
    use structomat::structomat::{AssurGroup, AssurJoint, AssurLoop, AssurStep};
    let p = CccParams::<f64>::reference();
    let pose = initial_pose(&p, deg(105.0), deg(90.0)).unwrap();
    let d = pose[8] - pose[6];
    let i_local = [0.3 * d.cos(), 0.3 * d.sin()];
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let f = b.ground_point(0.2, 0.5).unwrap();
    let h = b.ground_point(1.1, 0.0).unwrap();
    let crank = b.link(Link::bar(0.075, 0.7, 1.0e-3, 0.0375)).unwrap();
    let coupler = b.link(Link::bar(0.35, 2.9, 0.033, 0.175)).unwrap();
    let mut r = Link::bar(0.70, 5.5, 0.24, 0.35);
    let rocker_d = r.add_point(Vec2::new(0.35, 0.0)).unwrap();
    let rocker = b.link(r).unwrap();
    let swing = b.link(Link::bar(0.10, 0.9, 1.0e-3, 0.05)).unwrap();
    let rod5 = b.link(Link::bar(0.65, 5.3, 0.196, 0.325)).unwrap();
    let mut l = Link::bar(0.30, 5.0, 0.05, 0.1);
    let lever_i = l.add_point(Vec2::new(i_local[0], i_local[1])).unwrap();
    let lever = b.link(l).unwrap();
    let rod7 = b.link(Link::bar(0.65, 5.3, 0.196, 0.325)).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    let (l2, l3, l4, l5, l7, l6) = (0, 1, 2, 3, 4, 5);
    let st = |link: u8, from: u8, to: u8| AssurStep { link, from, to };
    let to_f = [st(l2, 0, 1), st(l3, 1, 0), st(l4, 1, 0)];
    let to_h6 = [
        st(l2, 0, 1),
        st(l3, 1, rocker_d),
        st(l5, 0, 1),
        st(l6, 1, 0),
    ];
    let to_h8 = [
        st(l2, 0, 1),
        st(l3, 1, rocker_d),
        st(l7, 0, 1),
        st(l6, lever_i, 0),
    ];
    let pt = |body: u8, point: u8| PointRef { body, point };
    let jt = |link: u8, at: u8, other: PointRef| AssurJoint { link, at, other };
    let bb = pt(crank, 1);
    let off = 0.05;
    b.group(&AssurGroup {
        links: &[coupler, rocker, swing, rod5, rod7, lever],
        loops: &[
            AssurLoop {
                start: bb,
                steps: &to_f,
                end: f,
            },
            AssurLoop {
                start: bb,
                steps: &to_h6,
                end: h,
            },
            AssurLoop {
                start: bb,
                steps: &to_h8,
                end: h,
            },
        ],
        joints: &[
            jt(coupler, 0, bb),
            jt(rocker, 1, pt(coupler, 1)),
            jt(swing, 1, pt(rocker, 0)),
            jt(swing, 0, f),
            jt(rod5, 0, pt(rocker, rocker_d)),
            jt(rod7, 0, pt(rocker, rocker_d)),
            jt(lever, 1, pt(rod5, 1)),
            jt(lever, lever_i, pt(rod7, 1)),
            jt(lever, 0, h),
        ],
        // 0.05 rad off the pose: Newton finds it back.
        guess: &[
            pose[2] + off,
            pose[3] - off,
            pose[4] + off,
            pose[5] - off,
            pose[7] + off,
            pose[6] - off,
        ],
    })
    .unwrap();
    if let Some(t) = drive {
        b.drive(0, Motor::Constant(t)).unwrap();
    }
    let rev = |a: u8, pa: P2, b: u8, pb: P2| TJ::Rev { a, pa, b, pb };
    let joints = vec![
        rev(1, [0.0, 0.0], 0, [0.0, 0.0]),
        rev(1, [0.075, 0.0], 2, [0.0, 0.0]),
        rev(2, [0.35, 0.0], 3, [0.70, 0.0]),
        rev(3, [0.0, 0.0], 4, [0.10, 0.0]),
        rev(4, [0.0, 0.0], 0, [0.2, 0.5]),
        rev(5, [0.0, 0.0], 3, [0.35, 0.0]),
        rev(7, [0.0, 0.0], 3, [0.35, 0.0]),
        rev(5, [0.65, 0.0], 6, [0.30, 0.0]),
        rev(7, [0.65, 0.0], 6, i_local),
        rev(6, [0.0, 0.0], 0, [1.1, 0.0]),
    ];
    let q0 = deg(105.0);
    Mech {
        name: "R+ASSUR (converter A68)",
        model: b.build().unwrap(),
        joints,
        formula: "Z(0) + R(1) + ASSUR(2,3,4,5,6,7)",
        qs: [0.0, -0.15, -0.3, 0.15, 0.3]
            .iter()
            .map(|&dq| vec![q0 + dq])
            .collect(),
        // The crank's range in A68 is about [0.8, 4.86] rad (it reverses at both ends),
        // with a shallow well of the weights near 3.38 rad (0.04 J deep towards 3.9 rad):
        // the dynamics runs swing in it, slowly.
        q0: vec![3.38],
        qd0: vec![0.3],
        drives: vec![0.05],
    }
}

fn one_dof() -> Vec<fn(Option<f64>) -> Mech> {
    vec![m_rrt, m_rtr, m_trt, m_rtt, m_trrr, m_triad, m_assur]
}

// ---------------------------------------------------------------------------------------
// Shared steps.
// ---------------------------------------------------------------------------------------

/// Moves the workspace from `from` to `to` by small position passes (continuation, so
/// that Newton groups stay on their branch).
fn walk(model: &Model<f64>, ws: &mut Workspace<f64>, from: &[f64], to: &[f64]) {
    let span = from
        .iter()
        .zip(to)
        .map(|(a, b)| (b - a).abs())
        .fold(0.0, f64::max);
    let n = (span / 0.02).ceil().max(1.0) as usize;
    for k in 1..=n {
        let t = k as f64 / n as f64;
        let q: Vec<f64> = from.iter().zip(to).map(|(a, b)| a + t * (b - a)).collect();
        position(model, ws, &q, 0.0).unwrap_or_else(|e| panic!("position at {q:?}: {e}"));
    }
}

/// Assembles at `m.qs[0]` and visits every configuration of `m.qs`, calling `f` there.
fn visit(m: &Mech, mut f: impl FnMut(&[f64], &mut Workspace<f64>)) {
    let mut ws = Workspace::new();
    assemble(&m.model, &mut ws, &m.qs[0]).unwrap_or_else(|e| panic!("{}: assemble: {e}", m.name));
    let mut cur = m.qs[0].clone();
    for q in &m.qs {
        walk(&m.model, &mut ws, &cur, q);
        cur = q.clone();
        f(q, &mut ws);
    }
}

/// Worst closure error of the designed joints: (point distance, angle error), m and rad.
fn closure_errors(ws: &Workspace<f64>, joints: &[TJ]) -> (f64, f64) {
    let (mut dp, mut da) = (0.0f64, 0.0f64);
    for j in joints {
        match *j {
            TJ::Rev { a, pa, b, pb } => dp = dp.max(norm(sub(world(ws, a, pa), world(ws, b, pb)))),
            TJ::Pri {
                s,
                ps,
                g,
                pg,
                dir,
                rel,
            } => {
                let u = unit(angle_of(ws, g) + dir);
                dp = dp.max(cross(u, sub(world(ws, s, ps), world(ws, g, pg))).abs());
                da = da.max(angle_diff(angle_of(ws, s) - angle_of(ws, g), rel).abs());
            }
        }
    }
    (dp, da)
}

/// The group unknowns of the workspace, angles unwrapped against `reference`.
fn group_vars(model: &Model<f64>, ws: &Workspace<f64>, reference: Option<&[f64]>) -> Vec<f64> {
    let mut out = Vec::new();
    for (g, gd) in model.groups().iter().zip(ws.group.iter()) {
        for k in 0..g.n_vars as usize {
            let mut x = gd.x[k];
            if let (Some(r), true) = (reference, var_is_angle(g.kind, k)) {
                x = unwrap_near(x, r[out.len()]);
            }
            out.push(x);
        }
    }
    out
}

/// Position pass at `q` from a copy of `base` (same branch and warm start): the pose `P`
/// followed by the groups' unknowns, angles unwrapped against `reference`.
fn pose_and_vars(
    model: &Model<f64>,
    base: &Workspace<f64>,
    q: &[f64],
    reference: Option<&[f64]>,
) -> Vec<f64> {
    let mut ws = base.clone();
    position(model, &mut ws, q, 0.0).unwrap_or_else(|e| panic!("position at {q:?}: {e}"));
    let np = 3 * model.n_links();
    let mut p = pose(model, &ws, reference.map(|r| &r[..np]));
    p.extend(group_vars(model, &ws, reference.map(|r| &r[np..])));
    p
}

// ---------------------------------------------------------------------------------------
// 1. Position.
// ---------------------------------------------------------------------------------------

fn check_position(m: &Mech) {
    assert_eq!(
        m.model.formula().to_string(),
        m.formula,
        "{}: formula",
        m.name
    );
    // The core's joint descriptions are the designed joints (same bodies, same points).
    let n_core = m
        .model
        .groups()
        .iter()
        .flat_map(|g| g.joints.iter())
        .filter(|j| matches!(j.kind, JointKind::Revolute | JointKind::Prismatic { .. }))
        .count();
    assert_eq!(n_core, m.joints.len(), "{}: number of joints", m.name);
    let near = |a: P2, v: &Vec2<f64>| (a[0] - v.x).abs() < 1e-15 && (a[1] - v.y).abs() < 1e-15;
    for j in m.model.groups().iter().flat_map(|g| g.joints.iter()) {
        let found = m.joints.iter().any(|t| match (*t, j.kind) {
            (TJ::Rev { a, pa, b, pb }, JointKind::Revolute) => {
                (j.i == a && j.j == b && near(pa, &j.pi) && near(pb, &j.pj))
                    || (j.i == b && j.j == a && near(pb, &j.pi) && near(pa, &j.pj))
            }
            (
                TJ::Pri {
                    s: sl,
                    ps,
                    g,
                    pg,
                    dir,
                    ..
                },
                JointKind::Prismatic { dir: u },
            ) => j.i == sl && j.j == g && near(ps, &j.pi) && near(pg, &j.pj) && near(unit(dir), &u),
            _ => false,
        });
        let drive = matches!(
            j.kind,
            JointKind::DriveTorque | JointKind::DriveForce { .. }
        );
        assert!(
            found || drive,
            "{}: core joint {j:?} is not in the design",
            m.name
        );
    }
    let (mut w_close, mut w_angle, mut w_core, mut w_newton) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    visit(m, |q, ws| {
        let (dp, da) = closure_errors(ws, &m.joints);
        assert!(
            dp < 1e-12 && da < 1e-12,
            "{} at {q:?}: closure {dp:.3e} m, {da:.3e} rad",
            m.name
        );
        w_close = w_close.max(dp);
        w_angle = w_angle.max(da);
        // Every joint the core describes (used by its kinetostatics) closes too.
        for g in m.model.groups() {
            for j in g.joints.iter() {
                let pi = world(ws, j.i, [j.pi.x, j.pi.y]);
                let pj = world(ws, j.j, [j.pj.x, j.pj.y]);
                let e = match j.kind {
                    JointKind::Revolute => norm(sub(pi, pj)),
                    JointKind::Prismatic { dir } => {
                        let u = rot(angle_of(ws, j.j), [dir.x, dir.y]);
                        cross(u, sub(pi, pj)).abs()
                    }
                    _ => 0.0,
                };
                assert!(
                    e < 1e-12,
                    "{} at {q:?}: core joint {j:?} misses by {e:.3e} m",
                    m.name
                );
                w_core = w_core.max(e);
            }
        }
        // Newton from perturbed unknowns lands on the closed form's configuration.
        let mut wn = ws.clone();
        for (g, gd) in m.model.groups().iter().zip(wn.group.iter_mut()) {
            for k in 0..g.n_vars as usize {
                gd.x[k] += if var_is_angle(g.kind, k) { 0.05 } else { 0.01 };
            }
        }
        position_newton(&m.model, &mut wn, q, 0.0)
            .unwrap_or_else(|e| panic!("{}: Newton at {q:?}: {e}", m.name));
        for b in 1..=m.model.n_links() {
            let (x, y) = (&ws.body[b], &wn.body[b]);
            let e = (x.o - y.o).amax().max(angle_diff(y.theta, x.theta).abs());
            assert!(
                e < 1e-10,
                "{} at {q:?}: body {b} closed form vs Newton {e:.3e}",
                m.name
            );
            w_newton = w_newton.max(e);
        }
        let (xa, xb) = (
            group_vars(&m.model, ws, None),
            group_vars(&m.model, &wn, None),
        );
        let xb = group_vars_unwrapped(&m.model, &xb, &xa);
        for (a, b) in xa.iter().zip(&xb) {
            assert!(
                (a - b).abs() < 1e-10,
                "{} at {q:?}: unknowns {xa:?} vs Newton {xb:?}",
                m.name
            );
            w_newton = w_newton.max((a - b).abs());
        }
    });
    println!(
        "[{}] position: closure {w_close:.1e} m / {w_angle:.1e} rad, core joints {w_core:.1e} m, \
         closed form vs Newton {w_newton:.1e}",
        m.name
    );
}

/// `x` with its angles unwrapped against `reference` (same layout as [`group_vars`]).
fn group_vars_unwrapped(model: &Model<f64>, x: &[f64], reference: &[f64]) -> Vec<f64> {
    let mut out = x.to_vec();
    let mut i = 0;
    for g in model.groups() {
        for k in 0..g.n_vars as usize {
            if var_is_angle(g.kind, k) {
                out[i] = unwrap_near(x[i], reference[i]);
            }
            i += 1;
        }
    }
    out
}

#[test]
fn position_closures_and_newton() {
    for build in one_dof() {
        check_position(&build(None));
    }
    check_position(&m_two_dof(false));
}

/// The triad assembles exactly at the configuration it was constructed from (an oracle
/// independent of any solver), from guesses 0.05 rad off.
#[test]
fn triad_assembles_at_its_construction() {
    let m = m_triad(None);
    let des = triad_design();
    let mut ws = Workspace::new();
    assemble(&m.model, &mut ws, &[des.q0]).unwrap();
    let (_, _, d) = triad_model::<f64>(None);
    let mut worst = 0.0f64;
    for (k, body) in [2u8, 3, 4, 5].iter().enumerate() {
        worst = worst.max(angle_diff(ws.body[*body as usize].theta, d.angles[k]).abs());
    }
    let o = ws.body[5].o;
    worst = worst
        .max((o.x - d.origin[0]).abs())
        .max((o.y - d.origin[1]).abs());
    assert!(
        worst < 1e-12,
        "triad: assembled pose off the construction by {worst:.3e}"
    );
    println!("[R+triad] assembled vs constructed configuration {worst:.1e}");
}

/// The closed-form dyads take, at assembly, the branch nearest their guesses: both
/// branches computed here (circle/line intersections) are reached from guesses 0.1 rad /
/// 0.02 m off each, and the walk along the crank's range keeps the branch.
#[test]
fn dyads_take_the_branch_nearest_their_guesses() {
    let mut worst = 0.0f64;
    // RRT (offset slider-crank): C = K + s u on the pin's line at 0.35 m from B.
    let gamma = deg(20.0);
    for q in [0.3, 2.0, 4.0] {
        let bq = rot(q, [0.10, 0.0]);
        let k = add([0.05, -0.06], rot(gamma + RRT_TILT, [0.02, 0.03]));
        let u = unit(gamma);
        let e = sub(k, bq);
        let ue = u[0] * e[0] + u[1] * e[1];
        let root = (ue * ue - (e[0] * e[0] + e[1] * e[1]) + 0.35 * 0.35).sqrt();
        for s in [-ue + root, -ue - root] {
            let c = add(k, [s * u[0], s * u[1]]);
            let th = (c[1] - bq[1]).atan2(c[0] - bq[0]);
            let m = m_rrt_with(None, [th + 0.1, s - 0.02]);
            let mut ws = Workspace::new();
            assemble(&m.model, &mut ws, &[q]).unwrap();
            let o = world(&ws, 3, [0.0, 0.0]);
            let err = norm(sub(o, add([0.05, -0.06], [s * u[0], s * u[1]])))
                .max(angle_diff(ws.body[2].theta, th).abs());
            assert!(err < 1e-12, "RRT at q = {q}, s = {s}: off by {err:.3e}");
            worst = worst.max(err);
            walk(&m.model, &mut ws, &[q], &[q + 1.0]);
            let (dp, _) = closure_errors(&ws, &m.joints);
            let s_now = {
                let o = world(&ws, 3, [0.0, 0.0]);
                let d = sub(o, [0.05, -0.06]);
                d[0] * u[0] + d[1] * u[1]
            };
            assert!(dp < 1e-12 && (s_now - s).abs() < 0.25, "RRT: branch lost");
        }
    }
    // RRR (slider on the incline): C on circle(P, 0.30) ∩ circle(D, 0.40).
    let th = deg(30.0);
    for q in [-0.54, -0.44, -0.34] {
        let p = rot(th, [q, 0.02]);
        let dvec = sub([-0.4, -0.6], p);
        let d = norm(dvec);
        let a = (0.30 * 0.30 - 0.40 * 0.40 + d * d) / (2.0 * d);
        let h = (0.30 * 0.30 - a * a).sqrt();
        let mid = add(p, [a * dvec[0] / d, a * dvec[1] / d]);
        for side in [1.0, -1.0] {
            let c = add(mid, [-side * h * dvec[1] / d, side * h * dvec[0] / d]);
            let t2 = (c[1] - p[1]).atan2(c[0] - p[0]);
            let t3 = (c[1] + 0.6).atan2(c[0] + 0.4);
            let m = m_trrr_with(None, [t2 - 0.1, t3 + 0.1]);
            let mut ws = Workspace::new();
            assemble(&m.model, &mut ws, &[q]).unwrap();
            let err = norm(sub(world(&ws, 2, [0.30, 0.0]), c))
                .max(angle_diff(ws.body[2].theta, t2).abs())
                .max(angle_diff(ws.body[3].theta, t3).abs());
            assert!(err < 1e-12, "RRR at q = {q}, side {side}: off by {err:.3e}");
            worst = worst.max(err);
        }
    }
    // RTR (quick return): in the rocker's frame the block's pin sits at c + s e_x with
    // c = (0, 0.015) + R(0.1)(0.01, -0.02), at |B - C| from the rocker's pivot.
    let cvec = add([0.0, 0.015], rot(0.1, [0.01, -0.02]));
    for q in [1.6, 3.5, 5.0] {
        let bq = rot(q, [0.10, 0.0]);
        let bc = sub(bq, [0.02, -0.25]);
        let root = (cvec[0] * cvec[0] - (cvec[0] * cvec[0] + cvec[1] * cvec[1])
            + bc[0] * bc[0]
            + bc[1] * bc[1])
            .sqrt();
        for s in [-cvec[0] + root, -cvec[0] - root] {
            let r = [cvec[0] + s, cvec[1]];
            let t2 = bc[1].atan2(bc[0]) - r[1].atan2(r[0]);
            let m = m_rtr_with(None, [t2 - 0.1, s + 0.02]);
            let mut ws = Workspace::new();
            assemble(&m.model, &mut ws, &[q]).unwrap();
            let line_pt = add([0.02, -0.25], rot(t2, [s, 0.015]));
            let err = norm(sub(world(&ws, 3, [0.0, 0.0]), line_pt))
                .max(angle_diff(ws.body[2].theta, t2).abs());
            assert!(err < 1e-12, "RTR at q = {q}, s = {s}: off by {err:.3e}");
            worst = worst.max(err);
        }
    }
    println!("[branches] RRT, RRR, RTR: both branches vs circle/line intersections {worst:.1e}");
}

// ---------------------------------------------------------------------------------------
// 2. and 3. Velocity and acceleration against finite differences.
// ---------------------------------------------------------------------------------------

/// Step of the first differences (thesis eq. 5.12).
const H1: f64 = 1e-4;
/// Step of the second differences (thesis eq. 5.13): truncation `O(h⁴)`, noise
/// `O(δ/h²)` with `δ` the positions' own error. The triad's positions come from Newton,
/// which stops at a residual of 64 ulps of the mechanism's size, so they carry ~1e-13 m
/// of noise. Measured worst `a_b` error over all mechanisms: h = 1e-4 fails on the triad
/// (> 1e-6); 5e-4: 1.6e-6 (triad); 1e-3: 1.1e-7 (triad); 2e-3: 3.3e-8 (triad; the
/// truncation reaches 3.0e-8 on the 2-DOF mechanism), hence 2e-3.
const H2: f64 = 2e-3;

fn unit_rate(dof: usize, j: usize) -> Vec<f64> {
    let mut e = vec![0.0; dof];
    e[j] = 1.0;
    e
}

fn check_derivatives(m: &Mech) {
    let dof = m.model.dof();
    let np = 3 * m.model.n_links();
    let (mut w_v, mut w_c, mut w_a, mut w_x) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut w_s: Option<f64> = None;
    visit(m, |q, ws| {
        let base = ws.clone();
        let center = pose_and_vars(&m.model, &base, q, None);
        let fd_at = |j: usize, h: f64, second: bool| {
            let mut f = |t: f64| {
                let mut qq = q.to_vec();
                qq[j] = t;
                pose_and_vars(&m.model, &base, &qq, Some(&center))
            };
            if second {
                central_second_diff4(&mut f, q[j], h)
            } else {
                central_diff4(&mut f, q[j], h)
            }
        };
        for j in 0..dof {
            // Velocity: V column j and the groups' dx/dq_j.
            evaluate(&m.model, ws, q, &vec![0.0; dof], 0.0).unwrap();
            let d1 = fd_at(j, H1, false);
            for (r, &fd) in d1[..np].iter().enumerate() {
                let v = ws.v[(r, j)];
                assert!(
                    isclose(v, fd, 1e-8, 1e-8),
                    "{} at {q:?}: V[{r},{j}] {v:.12e} vs FD {fd:.12e}",
                    m.name
                );
                w_v = w_v.max((v - fd).abs());
            }
            let mut i = np;
            for (g, gd) in m.model.groups().iter().zip(ws.group.iter()) {
                for k in 0..g.n_vars as usize {
                    let (c, fd) = (gd.dx_dq[(k, j)], d1[i]);
                    assert!(
                        isclose(c, fd, 1e-8, 1e-8),
                        "{} at {q:?}: dx{k}/dq{j} {c:.12e} vs FD {fd:.12e}",
                        m.name
                    );
                    w_c = w_c.max((c - fd).abs());
                    i += 1;
                }
            }
            // Acceleration: a_b and the groups' ẍ bias at q̇ = e_j are ∂²/∂q_j².
            evaluate(&m.model, ws, q, &unit_rate(dof, j), 0.0).unwrap();
            let d2 = fd_at(j, H2, true);
            for (r, &fd) in d2[..np].iter().enumerate() {
                let a = ws.a_bias[r];
                assert!(
                    isclose(a, fd, 1e-6, 1e-6),
                    "{} at {q:?}: a_b[{r}] (q̇=e{j}) {a:.12e} vs FD {fd:.12e}",
                    m.name
                );
                w_a = w_a.max((a - fd).abs());
            }
            let mut i = np;
            for (g, gd) in m.model.groups().iter().zip(ws.group.iter()) {
                for k in 0..g.n_vars as usize {
                    let (x, fd) = (gd.xdd_bias[k], d2[i]);
                    assert!(
                        isclose(x, fd, 1e-6, 1e-6),
                        "{} at {q:?}: ẍ{k} bias {x:.12e} vs FD {fd:.12e}",
                        m.name
                    );
                    w_x = w_x.max((x - fd).abs());
                    i += 1;
                }
            }
            // The bias is quadratic in the speed and even in its sign: at q̇ = -1.7 e_j
            // it is 1.7² times the second difference.
            if dof == 1 {
                evaluate(&m.model, ws, q, &[-1.7], 0.0).unwrap();
                for (r, &d2r) in d2[..np].iter().enumerate() {
                    let (a, fd) = (ws.a_bias[r], 1.7 * 1.7 * d2r);
                    assert!(
                        isclose(a, fd, 1e-6, 3e-6),
                        "{} at {q:?}: a_b[{r}] (q̇=-1.7) {a:.12e} vs {fd:.12e}",
                        m.name
                    );
                    w_s = Some(w_s.unwrap_or(0.0).max((a - fd).abs()));
                }
            }
        }
    });
    println!(
        "[{}] velocity: V vs FD {w_v:.1e}, dx/dq vs FD {w_c:.1e}; acceleration: a_b vs FD {w_a:.1e}, \
         ẍ bias vs FD {w_x:.1e}, a_b at q̇=-1.7 vs FD {}",
        m.name,
        w_s.map_or("n/a (2 DOF)".to_string(), |w| format!("{w:.1e}"))
    );
}

#[test]
fn velocity_and_acceleration_against_finite_differences() {
    for build in one_dof() {
        check_derivatives(&build(None));
    }
    check_derivatives(&m_two_dof(false));
}

/// The 2-DOF mechanism's mixed second derivatives `∂²P/∂q_j∂q_k` and `∂²x/∂q_j∂q_k`
/// (`second_derivative`) against central differences of `V` and `C`, and the bias at a
/// general `q̇` against `Σ D_jk q̇_j q̇_k`.
#[test]
fn mixed_second_derivatives_two_dof() {
    let m = m_two_dof(false);
    let np = 3 * m.model.n_links();
    let (mut w_d, mut w_dx, mut w_b) = (0.0f64, 0.0f64, 0.0f64);
    visit(&m, |q, ws| {
        let base = ws.clone();
        // Columns of V and C at q + t e_k, from `evaluate` on a copy of the workspace.
        let v_and_c = |qq: &[f64], j: usize| {
            let mut w = base.clone();
            evaluate(&m.model, &mut w, qq, &[0.0, 0.0], 0.0).unwrap();
            let mut out: Vec<f64> = (0..np).map(|r| w.v[(r, j)]).collect();
            for (g, gd) in m.model.groups().iter().zip(w.group.iter()) {
                for k in 0..g.n_vars as usize {
                    out.push(gd.dx_dq[(k, j)]);
                }
            }
            out
        };
        let mut d = [[Vec::new(), Vec::new()], [Vec::new(), Vec::new()]];
        for (j, dj) in d.iter_mut().enumerate() {
            for (k, djk) in dj.iter_mut().enumerate() {
                let mut f = |t: f64| {
                    let mut qq = q.to_vec();
                    qq[k] = t;
                    v_and_c(&qq, j)
                };
                *djk = central_diff4(&mut f, q[k], H1);
                let mut pose_d =
                    nalgebra::SVector::<f64, { structomat::config::POSE_ROWS }>::zeros();
                let mut vars =
                    [[0.0; structomat::config::MAX_GROUP_VARS]; structomat::config::MAX_GROUPS];
                let mut w = base.clone();
                position(&m.model, &mut w, q, 0.0).unwrap();
                second_derivative(&m.model, &mut w, j, k, &mut pose_d, &mut vars);
                for (r, &fd) in djk[..np].iter().enumerate() {
                    let a = pose_d[r];
                    assert!(
                        isclose(a, fd, 1e-7, 1e-7),
                        "at {q:?}: D[{r}]({j},{k}) {a:.12e} vs FD {fd:.12e}"
                    );
                    w_d = w_d.max((a - fd).abs());
                }
                // The dyad is group 2; its unknowns follow the pose in `d`.
                for v in 0..2 {
                    let (a, fd) = (vars[2][v], djk[np + v]);
                    assert!(
                        isclose(a, fd, 1e-7, 1e-7),
                        "at {q:?}: d²x{v}/dq{j}dq{k} {a:.12e} vs FD {fd:.12e}"
                    );
                    w_dx = w_dx.max((a - fd).abs());
                }
            }
        }
        // Symmetry of the FD oracle itself (∂V_j/∂q_k = ∂V_k/∂q_j) is a sanity check of
        // the differences, then the bias at a general speed.
        let qd = [1.3, -0.7];
        let mut w = base.clone();
        evaluate(&m.model, &mut w, q, &qd, 0.0).unwrap();
        for (r, &ab) in w.a_bias.iter().take(np).enumerate() {
            assert!(
                isclose(d[0][1][r], d[1][0][r], 1e-7, 1e-7),
                "FD oracle not symmetric"
            );
            let mut expect = 0.0;
            for j in 0..2 {
                for k in 0..2 {
                    expect += d[j][k][r] * qd[j] * qd[k];
                }
            }
            assert!(
                isclose(ab, expect, 1e-7, 1e-7),
                "at {q:?}: a_b[{r}] {ab:.12e} vs {expect:.12e}"
            );
            w_b = w_b.max((ab - expect).abs());
        }
    });
    println!("[R+T+RRR] mixed: D vs FD of V {w_d:.1e}, d²x vs FD of C {w_dx:.1e}, a_b(q̇) vs Σ D q̇q̇ {w_b:.1e}");
}

// ---------------------------------------------------------------------------------------
// 4. Energy.
// ---------------------------------------------------------------------------------------

fn check_energy(m: &Mech) {
    let h = 1e-3;
    let mut sim = Simulation::new(m.model.clone(), &m.q0, &m.qd0, h).unwrap();
    // The run starts on the assembly branch of the kinematic checks.
    let mut ws = Workspace::new();
    assemble(&m.model, &mut ws, &m.qs[0]).unwrap();
    walk(&m.model, &mut ws, &m.qs[0], &m.q0);
    for b in 1..=m.model.n_links() {
        let (x, y) = (&ws.body[b], &sim.workspace().body[b]);
        let e = (x.o - y.o).amax().max(angle_diff(y.theta, x.theta).abs());
        assert!(
            e < 1e-9,
            "{}: the run starts on another branch (body {b}: {e:.3e})",
            m.name
        );
    }
    let e0 = sim.energy();
    let total0 = e0.kinetic + e0.potential;
    let (mut drift, mut ke_max, mut cond_min) = (0.0f64, e0.kinetic, f64::INFINITY);
    let (mut q_lo, mut q_hi) = (m.q0[0], m.q0[0]);
    for _ in 0..2000 {
        sim.step()
            .unwrap_or_else(|e| panic!("{}: step: {e}", m.name));
        let e = sim.energy();
        drift = drift.max((e.kinetic + e.potential - total0).abs());
        ke_max = ke_max.max(e.kinetic);
        q_lo = q_lo.min(sim.q()[0]);
        q_hi = q_hi.max(sim.q()[0]);
        for (g, gd) in m.model.groups().iter().zip(sim.workspace().group.iter()) {
            if g.n_vars > 0 {
                cond_min = cond_min.min(gd.conditioning);
            }
        }
    }
    // The potential's zero is arbitrary: the drift is measured against the energy that
    // actually moves between the two forms, the largest kinetic energy of the run.
    let rel = drift / ke_max;
    println!(
        "[{}] energy: 2 s at h = 1 ms, drift {drift:.2e} J = {rel:.2e} of max KE {ke_max:.3} J \
         (q in [{q_lo:.3}, {q_hi:.3}], min group conditioning {cond_min:.2})",
        m.name
    );
    assert!(
        cond_min > 0.2,
        "{}: the run came near a singular position ({cond_min:.3})",
        m.name
    );
    assert!(
        rel < 1e-8,
        "{}: energy drift {rel:.3e} of the kinetic energy",
        m.name
    );
}

#[test]
fn energy_is_conserved_without_drive() {
    for build in one_dof() {
        check_energy(&build(None));
    }
}

// ---------------------------------------------------------------------------------------
// 5. Kinetostatics.
// ---------------------------------------------------------------------------------------

/// Checks the reactions of the simulation's current state; returns the worst
/// (driving torque rel. error, force residual, moment residual, power balance rel.).
fn check_reactions(m: &Mech, sim: &mut Simulation<f64>) -> [f64; 4] {
    let (q, qd) = (sim.q().to_vec(), sim.qd().to_vec());
    let ws = sim
        .kinetostatics()
        .unwrap_or_else(|e| panic!("{}: kinetostatics: {e}", m.name))
        .clone();
    let model = &m.model;
    assert_eq!(
        &ws.q[..q.len()],
        &q[..],
        "{}: workspace not at the state",
        m.name
    );
    // Driving torques: the reaction of each motor element's driver equals its motor's.
    let mut e_tau = 0.0f64;
    for (k, &t) in m.drives.iter().enumerate() {
        let tau = driving_torque(model, &ws, k).expect("group k is a motor element");
        assert_close(
            tau,
            t,
            1e-9,
            0.0,
            &format!("{}: driving torque {k}", m.name),
        );
        e_tau = e_tau.max((tau - t).abs() / t.abs());
    }
    // Every link's equilibrium: reactions (on i, and opposite on j), gravity, inertia.
    let n = model.n_links();
    let mut force = vec![[0.0f64; 2]; n + 1];
    let mut moment = vec![0.0f64; n + 1];
    let cogs: Vec<P2> = (0..=n as u8)
        .map(|b| {
            if b == 0 {
                [0.0, 0.0]
            } else {
                cog_world(model, &ws, b)
            }
        })
        .collect();
    for (gi, g) in model.groups().iter().enumerate() {
        for (k, jt) in g.joints.iter().enumerate() {
            let r = ws.reactions[gi][k];
            let f = [r.force.x, r.force.y];
            let at = world(&ws, jt.i, [jt.pi.x, jt.pi.y]);
            for (body, sign) in [(jt.i, 1.0), (jt.j, -1.0)] {
                if body == 0 {
                    continue;
                }
                let b = body as usize;
                force[b] = add(force[b], [sign * f[0], sign * f[1]]);
                moment[b] += sign * (r.moment + cross(sub(at, cogs[b]), f));
            }
        }
    }
    let (mut e_f, mut e_m) = (0.0f64, 0.0f64);
    let mut power = Vec::new();
    for b in 1..=n {
        let l = model.link(b as u8).unwrap();
        let s = &ws.body[b];
        // COG kinematics from the body's origin motion (P = o + R(θ) c).
        let rc = rot(s.theta, [l.cog.x, l.cog.y]);
        let v_g = add([s.v.x, s.v.y], [-s.omega * rc[1], s.omega * rc[0]]);
        let a_g = [
            s.a.x - s.alpha * rc[1] - s.omega * s.omega * rc[0],
            s.a.y + s.alpha * rc[0] - s.omega * s.omega * rc[1],
        ];
        let load = [-l.mass * a_g[0], l.mass * (-G - a_g[1])];
        let m_in = -l.inertia * s.alpha;
        let rf = add(force[b], load);
        let rm = moment[b] + m_in;
        e_f = e_f.max(norm(rf));
        e_m = e_m.max(rm.abs());
        power.push(load[0] * v_g[0] + load[1] * v_g[1]);
        power.push(m_in * s.omega);
    }
    assert!(
        e_f < 1e-9 && e_m < 1e-9,
        "{}: equilibrium residual {e_f:.3e} N, {e_m:.3e} N·m",
        m.name
    );
    // Virtual power (thesis eq. 3.19): applied + inertia loads on the real velocities,
    // plus the drives' power τ q̇, vanish.
    for (t, v) in m.drives.iter().zip(&qd) {
        power.push(t * v);
    }
    let sum: f64 = power.iter().sum();
    let scale = power.iter().fold(0.0f64, |a, p| a.max(p.abs()));
    let e_p = sum.abs() / scale;
    assert!(
        e_p < 1e-9,
        "{}: virtual power {sum:.3e} W of terms up to {scale:.3e} W",
        m.name
    );
    [e_tau, e_f, e_m, e_p]
}

#[test]
fn kinetostatics_with_a_constant_drive() {
    let mechs = one_dof()
        .into_iter()
        .map(|build| build(Some(build(None).drives[0])));
    for m in mechs.chain([m_two_dof(true)]) {
        let mut sim = Simulation::new(m.model.clone(), &m.q0, &m.qd0, 1e-3).unwrap();
        let mut worst = [0.0f64; 4];
        for steps in [1, 50, 200] {
            for _ in 0..steps {
                sim.step()
                    .unwrap_or_else(|e| panic!("{}: step: {e}", m.name));
            }
            let w = check_reactions(&m, &mut sim);
            for (a, b) in worst.iter_mut().zip(w) {
                *a = a.max(b);
            }
        }
        println!(
            "[{}] kinetostatics: driving torque rel. {:.1e}, link equilibrium {:.1e} N / {:.1e} N·m, \
             virtual power rel. {:.1e}",
            m.name, worst[0], worst[1], worst[2], worst[3]
        );
    }
}

// ---------------------------------------------------------------------------------------
// 6. Errors.
// ---------------------------------------------------------------------------------------

/// Asserts that setting up `model` at `q0` fails in group `index`, of `kind`, with
/// links `links`, and that the message names it as `formula`; returns the fault.
fn setup_fault(
    model: Model<f64>,
    q0: &[f64],
    index: u8,
    kind: GroupKind,
    links: &[u8],
    formula: &str,
) -> GroupFault {
    let err = match Simulation::new(model, q0, &vec![0.0; q0.len()], 1e-3) {
        Ok(_) => panic!("{formula}: the mechanism assembled"),
        Err(e) => e,
    };
    let SetupError::Initial(StepError::Group { group, fault, .. }) = err else {
        panic!("{formula}: unexpected error {err:?}");
    };
    assert_eq!(group.index, index, "{formula}: group index");
    assert_eq!(group.kind, kind, "{formula}: group kind");
    assert_eq!(
        &group.links[..group.count as usize],
        links,
        "{formula}: group links"
    );
    let msg = err.to_string();
    assert!(
        msg.contains(formula),
        "message {msg:?} does not name {formula}"
    );
    println!("[errors] {msg}");
    fault
}

/// RRR: links 2 and 3 of 0.05 m each cannot span the slider pin, 0.40 m away from D.
#[test]
fn rrr_too_short_cannot_assemble() {
    let th = deg(30.0);
    let m = m_trrr_sized(None, [-0.4, 0.78], [0.05, 0.05]);
    let q0 = -0.44;
    let p = add(rot(th, [q0, 0.02]), [0.0, 0.0]);
    let gap = norm(sub(p, [-0.4, -0.6])) - 0.1;
    let fault = setup_fault(m.model, &[q0], 1, GroupKind::Rrr, &[2, 3], "RRR(2,3)");
    let GroupFault::CannotAssemble { gap: g } = fault else {
        panic!("RRR: fault {fault:?}")
    };
    assert_close(g, gap, 1e-12, 1e-15, "RRR: gap");
}

/// RRT: a 0.02 m rod cannot reach the line of the slider's pin, 0.138 m from the crank
/// pin at q = 1.8 rad.
#[test]
fn rrt_too_short_cannot_assemble() {
    let gamma = deg(20.0);
    let m = m_rrt_sized(None, [0.35, 0.3], 0.02);
    let q0 = 1.8;
    // Distance from the crank pin to the line of the slider's pin, minus the rod.
    let k = add([0.05, -0.06], rot(gamma + RRT_TILT, [0.02, 0.03]));
    let bq = rot(q0, [0.10, 0.0]);
    let gap = cross(unit(gamma), sub(bq, k)).abs() - 0.02;
    assert!(gap > 0.05);
    let fault = setup_fault(m.model, &[q0], 1, GroupKind::Rrt, &[2, 3], "RRT(2,3)");
    let GroupFault::CannotAssemble { gap: g } = fault else {
        panic!("RRT: fault {fault:?}")
    };
    assert_close(g, gap, 1e-12, 1e-15, "RRT: gap");
}

/// RTR: the guide line 0.4 m off the rocker's axis puts the block's pin 0.381 m off it,
/// more than the 0.17 m between the crank pin and the rocker's pivot at q = -60°.
#[test]
fn rtr_offset_too_large_cannot_assemble() {
    let m = m_rtr_offset(None, [1.6, 0.35], 0.4);
    let q0 = deg(-60.0);
    let dist = norm(sub(rot(q0, [0.10, 0.0]), [0.02, -0.25]));
    // The pin's distance from the rocker's axis: the line's offset and the pin's own,
    // the block turned by RTR_ANGLE on the line.
    let off = 0.4 + rot(RTR_ANGLE, RTR_PIN)[1];
    assert!(dist < off);
    let fault = setup_fault(m.model, &[q0], 1, GroupKind::Rtr, &[2, 3], "RTR(2,3)");
    let GroupFault::CannotAssemble { gap: g } = fault else {
        panic!("RTR: fault {fault:?}")
    };
    assert_close(g, off - dist, 1e-12, 1e-15, "RTR: gap");
}

/// TRT with the slot parallel to the fixed guide (q = 0): a dead point at assembly.
#[test]
fn trt_parallel_guides_are_singular() {
    let m = m_trt(None);
    let fault = setup_fault(m.model, &[0.0], 1, GroupKind::Trt, &[2, 3], "TRT(2,3)");
    assert!(
        matches!(
            fault,
            GroupFault::Singular { .. } | GroupFault::NewtonDidNotConverge { .. }
        ),
        "TRT: fault {fault:?}"
    );
}

/// Triad whose ground poles are moved 1 m away: Newton cannot close the loops.
#[test]
fn triad_too_far_fails_naming_the_triad() {
    let (model, _, des) = triad_model::<f64>(None);
    let mut b = ModelBuilder::<f64>::new();
    for (k, p) in model.ground_points().iter().enumerate() {
        let dx = if k == 0 { 0.0 } else { 1.0 };
        b.ground_point(p.x + dx, p.y).unwrap();
    }
    for l in model.links() {
        b.link(l.clone()).unwrap();
    }
    // The same groups as `triad_model`, against the moved poles.
    let (k2, k3) = (
        PointRef { body: 0, point: 1 },
        PointRef { body: 0, point: 2 },
    );
    b.group(&MotorR {
        link: 1,
        pivot: PointRef { body: 0, point: 0 },
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    b.group(&TriadRrRrRr {
        ternary: 5,
        ternary_joints: [0, 1, 2],
        binary: [2, 3, 4],
        binary_at_pole: [0, 0, 0],
        binary_at_ternary: [1, 1, 1],
        poles: [PointRef { body: 1, point: 1 }, k2, k3],
        guess: [des.angles[0], des.angles[1], des.angles[2], des.angles[3]],
    })
    .unwrap();
    let fault = setup_fault(
        b.build().unwrap(),
        &[des.q0],
        1,
        GroupKind::Triad,
        &[2, 3, 4, 5],
        "RR-RR-RR(2,3,4,5)",
    );
    assert!(
        matches!(
            fault,
            GroupFault::NewtonDidNotConverge { .. } | GroupFault::Singular { .. }
        ),
        "triad: fault {fault:?}"
    );
}

// ---------------------------------------------------------------------------------------
// f32.
// ---------------------------------------------------------------------------------------

/// The triad mechanism in `f32` assembles within 1e-4 of `f64` (positions, m, and
/// angles, rad), at its construction configuration and along a walk of the crank.
#[test]
fn triad_f32_matches_f64() {
    let (m64, _, des) = triad_model::<f64>(None);
    let (m32, _, _) = triad_model::<f32>(None);
    let mut w64 = Workspace::<f64>::new();
    let mut w32 = Workspace::<f32>::new();
    assemble(&m64, &mut w64, &[des.q0]).unwrap();
    assemble(&m32, &mut w32, &[des.q0 as f32]).unwrap();
    let mut worst = 0.0f64;
    let mut compare = |w64: &Workspace<f64>, w32: &Workspace<f32>| {
        for b in 1..=m64.n_links() {
            let (x, y) = (&w64.body[b], &w32.body[b]);
            let e = (x.o.x - y.o.x as f64)
                .abs()
                .max((x.o.y - y.o.y as f64).abs())
                .max(angle_diff(y.theta as f64, x.theta).abs());
            assert!(e < 1e-4, "f32 vs f64: body {b} differs by {e:.3e}");
            worst = worst.max(e);
        }
    };
    compare(&w64, &w32);
    for k in 1..=15 {
        let q = des.q0 + 0.02 * k as f64;
        position(&m64, &mut w64, &[q], 0.0).unwrap();
        position(&m32, &mut w32, &[q as f32], 0.0).unwrap();
        compare(&w64, &w32);
    }
    println!("[R+triad] f32 vs f64 positions: worst {worst:.1e}");
}
