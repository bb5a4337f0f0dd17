//! The core's model built on a structomatic analysis ([`super::analyze`]): each placed
//! group as the core's group spec (poles, link points, guesses from the links'
//! `angle_deg` and the prismatic joints' `offset`), the scenario of a mechanism file, and
//! the report of `host-sim analyze`.

use super::{analyze, name, Analysis, AnalysisError, Placed};
use crate::model::runfile::{Body, JointKind, Mechanism, PointId, RunFile};
use std::fmt;
use structomat::config::MAX_DOF;
use structomat::mechanisms::Scenario;
use structomat::model::Load;
use structomat::scalar::Vec2;
use structomat::structomat::{
    DyadRrr, DyadRrt, DyadRtr, DyadRtt, DyadTrt, MotorR, MotorT, PointRef, TriadRrRrRr,
};
use structomat::{Link, Model, ModelBuilder, ModelError, Real};

fn pref(p: PointId) -> PointRef {
    // Bodies and points are bounded by the core's capacities (checked in the file's
    // validation), far below u8::MAX.
    PointRef {
        body: p.body as u8,
        point: p.point as u8,
    }
}

fn deg<T: Real>(d: f64) -> T {
    // As the core's `mechanisms::deg`: to radians in f64, then one conversion to T.
    T::c(d.to_radians())
}

/// Builds the core model of `m` on the sequence `a`, in scalar `T`.
pub fn build_model<T: Real>(m: &Mechanism, a: &Analysis) -> Result<Model<T>, ModelError> {
    build_model_with(m, a, |_| Ok(()))
}

/// [`build_model`] with `more` declared last (after the drives and loads).
pub(crate) fn build_model_with<T: Real>(
    m: &Mechanism,
    a: &Analysis,
    more: impl FnOnce(&mut ModelBuilder<T>) -> Result<(), ModelError>,
) -> Result<Model<T>, ModelError> {
    let c = T::c;
    let mut b = ModelBuilder::<T>::new();
    b.gravity(Vec2::new(c(m.gravity[0]), c(m.gravity[1])));
    for g in &m.ground {
        b.ground_point(c(g.at[0]), c(g.at[1]))?;
    }
    for l in &m.links {
        let mut link = Link::block(c(l.mass), c(l.inertia));
        link.points.clear();
        for p in &l.points {
            link.add_point(Vec2::new(c(p[0]), c(p[1])))?;
        }
        link.cog = Vec2::new(c(l.cog[0]), c(l.cog[1]));
        b.link(link)?;
    }
    let joint = |j: usize| m.joints[j].kind;
    // The point of joint `j` on `body`, and the joint's point on the other body.
    let on = |j: usize, body: usize| -> (u8, PointRef) {
        let k = joint(j);
        let here = k.point_on(body).map_or(0, |p| p.point as u8);
        let [p, q] = k.bodies();
        let other = if p == body { q } else { p };
        let there = k
            .point_on(other)
            .map_or(PointRef { body: 0, point: 0 }, pref);
        (here, there)
    };
    let angle = |body: usize| deg::<T>(m.links.get(body - 1).map_or(0.0, |l| l.angle_deg));
    // A prismatic joint's guide angle, slider angle (rad) and offset guess (m).
    let slide = |j: usize| match joint(j) {
        JointKind::Prismatic {
            guide_angle_deg,
            slider_angle_deg,
            offset,
            ..
        } => (
            deg::<T>(guide_angle_deg),
            deg::<T>(slider_angle_deg),
            c(offset),
        ),
        JointKind::Revolute { .. } => (T::zero(), T::zero(), T::zero()),
    };
    let u8_ = |x: usize| x as u8;
    for g in &a.groups {
        match *g {
            Placed::MotorR {
                link,
                joint: j,
                driver,
            } => {
                let (link_point, pivot) = on(j, link);
                b.group(&MotorR {
                    link: u8_(link),
                    pivot,
                    link_point,
                    coord: u8_(driver),
                    offset: deg(m.drivers[driver].offset_deg),
                })?;
            }
            Placed::MotorT {
                link,
                joint: j,
                driver,
            } => {
                let (link_point, guide) = on(j, link);
                let (guide_angle, link_angle, _) = slide(j);
                b.group(&MotorT {
                    link: u8_(link),
                    guide,
                    guide_angle,
                    link_point,
                    link_angle,
                    coord: u8_(driver),
                })?;
            }
            Placed::Rrr {
                a,
                b: lb,
                ja,
                jb,
                jab,
            } => {
                let (a_at_pole, pole_a) = on(ja, a);
                let (b_at_pole, pole_b) = on(jb, lb);
                b.group(&DyadRrr {
                    a: u8_(a),
                    b: u8_(lb),
                    pole_a,
                    a_at_pole,
                    pole_b,
                    b_at_pole,
                    a_joint: on(jab, a).0,
                    b_joint: on(jab, lb).0,
                    guess: [angle(a), angle(lb)],
                })?;
            }
            Placed::Rrt {
                rod,
                slider,
                jp,
                jc,
                jg,
            } => {
                let (rod_at_pole, pole) = on(jp, rod);
                let (slider_on_guide, guide) = on(jg, slider);
                let (guide_angle, slider_angle, s) = slide(jg);
                b.group(&DyadRrt {
                    rod: u8_(rod),
                    slider: u8_(slider),
                    pole,
                    rod_at_pole,
                    rod_joint: on(jc, rod).0,
                    slider_joint: on(jc, slider).0,
                    guide,
                    guide_angle,
                    slider_on_guide,
                    slider_angle,
                    guess: [angle(rod), s],
                })?;
            }
            Placed::Rtr {
                block,
                guide,
                ja,
                jb,
                jab,
            } => {
                let (a_at_pole, pole_a) = on(ja, block);
                let (b_at_pole, pole_b) = on(jb, guide);
                let (b_line_angle, a_angle, s) = slide(jab);
                b.group(&DyadRtr {
                    a: u8_(block),
                    b: u8_(guide),
                    pole_a,
                    a_at_pole,
                    pole_b,
                    b_at_pole,
                    b_line: on(jab, guide).0,
                    b_line_angle,
                    a_on_line: on(jab, block).0,
                    a_angle,
                    guess: [angle(guide), s],
                })?;
            }
            Placed::Rtt {
                a,
                b: lb,
                ja,
                jab,
                jb,
            } => {
                let (a_at_pole, pole_a) = on(ja, a);
                let (b_on_guide, guide) = on(jb, lb);
                let (guide_angle, b_angle, _) = slide(jb);
                let (b_line_angle, a_angle, _) = slide(jab);
                b.group(&DyadRtt {
                    a: u8_(a),
                    b: u8_(lb),
                    pole_a,
                    a_at_pole,
                    guide,
                    guide_angle,
                    b_on_guide,
                    b_angle,
                    b_line: on(jab, lb).0,
                    b_line_angle,
                    a_on_line: on(jab, a).0,
                    a_angle,
                })?;
            }
            Placed::Trt {
                a,
                b: lb,
                ja,
                jb,
                jab,
            } => {
                let (a_on_guide, guide_a) = on(ja, a);
                let (b_on_guide, guide_b) = on(jb, lb);
                let (guide_a_angle, a_angle, _) = slide(ja);
                let (guide_b_angle, b_angle, _) = slide(jb);
                b.group(&DyadTrt {
                    a: u8_(a),
                    b: u8_(lb),
                    guide_a,
                    guide_a_angle,
                    a_on_guide,
                    a_angle,
                    guide_b,
                    guide_b_angle,
                    b_on_guide,
                    b_angle,
                    a_joint: on(jab, a).0,
                    b_joint: on(jab, lb).0,
                })?;
            }
            Placed::Triad {
                ternary,
                binary,
                jt,
                jk,
            } => {
                let poles = [0, 1, 2].map(|i| on(jk[i], binary[i]).1);
                b.group(&TriadRrRrRr {
                    ternary: u8_(ternary),
                    ternary_joints: [0, 1, 2].map(|i| on(jt[i], ternary).0),
                    binary: binary.map(u8_),
                    binary_at_pole: [0, 1, 2].map(|i| on(jk[i], binary[i]).0),
                    binary_at_ternary: [0, 1, 2].map(|i| on(jt[i], binary[i]).0),
                    poles,
                    guess: [
                        angle(binary[0]),
                        angle(binary[1]),
                        angle(binary[2]),
                        angle(ternary),
                    ],
                })?;
            }
        }
    }
    for (k, d) in m.drivers.iter().enumerate() {
        if let Some(motor) = &d.motor {
            b.drive(u8_(k), motor.motor::<T>()?)?;
        }
    }
    for l in &m.loads {
        b.load(Load {
            body: u8_(l.link),
            point: Vec2::new(c(l.at[0]), c(l.at[1])),
            force: Vec2::new(c(l.force[0]), c(l.force[1])),
            moment: c(l.moment),
        })?;
    }
    more(&mut b)?;
    b.build()
}

/// Why a mechanism file cannot become a scenario.
#[derive(Clone, Debug, PartialEq)]
pub enum BuildError {
    /// The file describes the converter (run by [`crate::run::converter`]).
    Converter,
    /// The analysis found no sequence.
    Analysis(AnalysisError),
    /// The core refused the model (e.g. a group cannot assemble at its guesses).
    Model(ModelError),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Converter => f.write_str("a converter file, not a mechanism"),
            BuildError::Analysis(e) => write!(f, "structomatic analysis: {e}"),
            BuildError::Model(e) => write!(f, "the core's model: {e}"),
        }
    }
}

impl std::error::Error for BuildError {}

/// The core scenario of a mechanism file in scalar `T`: the analysed model, the
/// drivers' initial values, `h` and `t_end`.
pub fn scenario<T: Real>(file: &RunFile) -> Result<Scenario<T>, BuildError> {
    let Body::Mechanism(m) = &file.body else {
        return Err(BuildError::Converter);
    };
    let a = analyze(m).map_err(BuildError::Analysis)?;
    let model = build_model::<T>(m, &a).map_err(BuildError::Model)?;
    let mut q0 = [T::zero(); MAX_DOF];
    let mut qd0 = [T::zero(); MAX_DOF];
    for (k, d) in m.drivers.iter().enumerate().take(MAX_DOF) {
        q0[k] = if m.joints[d.joint].kind.is_revolute() {
            deg(d.q0_written)
        } else {
            T::c(d.q0)
        };
        qd0[k] = T::c(d.qd0);
    }
    Ok(Scenario {
        model,
        q0,
        qd0,
        h: T::c(file.run.h),
        t_end: T::c(file.run.t_end),
    })
}

/// Writes the report of `host-sim analyze`: the formula, the DOF and each group with its
/// links and joints.
pub fn report(m: &Mechanism, a: &Analysis, model: &Model<f64>) -> String {
    let mut s = String::new();
    s.push_str(&format!("formula   {}\n", model.formula()));
    s.push_str(&format!(
        "DOF       {} (Grübler: 3·{} − 2·({} revolute + {} prismatic)), {} driver(s)\n",
        a.dof,
        a.links,
        a.revolute,
        a.prismatic,
        m.drivers.len()
    ));
    s.push_str("groups\n");
    let names: Vec<String> = a.groups.iter().map(name).collect();
    let w = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    for (g, n) in a.groups.iter().zip(&names) {
        let links: Vec<String> = g
            .links()
            .iter()
            .map(|&l| format!("{l} {}", m.body_name(l)))
            .collect();
        let joints: Vec<String> = g
            .joints()
            .iter()
            .map(|&j| {
                let js = &m.joints[j];
                let kind = if js.kind.is_revolute() { "R" } else { "P" };
                let [p, q] = js.kind.bodies();
                format!(
                    "\"{}\" {kind} {}–{}",
                    js.name,
                    m.point_name(js.kind.point_on(p).unwrap_or(PointId { body: p, point: 0 })),
                    m.point_name(js.kind.point_on(q).unwrap_or(PointId { body: q, point: 0 }))
                )
            })
            .collect();
        let coord = match g {
            Placed::MotorR { driver, .. } | Placed::MotorT { driver, .. } => {
                format!("; coordinate q{}", driver + 1)
            }
            _ => String::new(),
        };
        s.push_str(&format!(
            "  {n:<w$}  links {}; joints {}{coord}\n",
            links.join(", "),
            joints.join(", ")
        ));
    }
    s
}
