//! The validation of a run file's raw structures: every value (units, signs, ranges)
//! and every reference (names, capacities) checked before anything runs; errors name
//! the key.

use super::raw::*;
use super::*;

/// The message for a link name that is not one of `links`.
fn unknown_link(name: &str, links: &[LinkSpec]) -> String {
    format!(
        "unknown link \"{name}\" (links: {})",
        list(links.iter().map(|l| l.name.as_str()))
    )
}

struct Check<'a> {
    origin: &'a str,
}

impl Check<'_> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> FileError {
        FileError {
            origin: self.origin.to_string(),
            position: None,
            field: field.into(),
            message: message.into(),
        }
    }

    fn finite(&self, field: &str, x: f64) -> Result<f64, FileError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(field, format!("must be finite, got {x}")))
        }
    }

    fn positive(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, format!("must be > 0, got {x}")))
        }
    }

    fn non_negative(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.finite(field, x)?;
        if x >= 0.0 {
            // -0 is 0.
            Ok(x + 0.0)
        } else {
            Err(self.err(field, format!("must be >= 0, got {x}")))
        }
    }

    /// A load (N·m or N): finite and below [`MAX_LOAD`] in magnitude.
    fn load(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.below(
            field,
            x,
            MAX_LOAD,
            "",
            "the energy and clutch tolerances lose their meaning",
        )
    }

    /// The converter's load torque T_r (N·m): finite and below [`MAX_CONVERTER_LOAD`].
    fn converter_load(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.below(
            field,
            x,
            MAX_CONVERTER_LOAD,
            " N·m",
            "the clutch tolerance 1e-9 (T_r + 1 N·m) lets a locked lever hold a negative torque past 1e-3 N·m and releases it late",
        )
    }

    /// `x` finite and below `bound` in magnitude, else an error saying `why` (`unit`
    /// follows the numbers).
    fn below(
        &self,
        field: &str,
        x: f64,
        bound: f64,
        unit: &str,
        why: &str,
    ) -> Result<f64, FileError> {
        self.finite(field, x)?;
        if x.abs() < bound {
            Ok(x)
        } else {
            Err(self.err(
                field,
                format!(
                    "{}{unit} is too large: from {}{unit} on {why}",
                    Sci(x),
                    Sci(bound)
                ),
            ))
        }
    }

    fn vec2(&self, field: &str, v: [f64; 2]) -> Result<[f64; 2], FileError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(v)
        } else {
            Err(self.err(field, format!("must be finite, got [{}, {}]", v[0], v[1])))
        }
    }
}

/// `[run] integrator` and its tolerances: `rtol`, `atol`, `h_max` only with
/// `"adaptive"` (defaults 1e-9, 1e-9 and 10·h).
fn integrator(ck: &Check<'_>, r: &RawRun) -> Result<Integrator, FileError> {
    let tolerances = [("rtol", r.rtol), ("atol", r.atol), ("h_max", r.h_max)];
    match r.integrator.unwrap_or(RawIntegrator::Dp5) {
        RawIntegrator::Dp5 => match tolerances.iter().find(|t| t.1.is_some()) {
            Some((key, _)) => Err(ck.err(
                format!("run.{key}"),
                "only with integrator = \"adaptive\" (the fixed-step dp5 steps by h)",
            )),
            None => Ok(Integrator::Dp5),
        },
        RawIntegrator::Adaptive => Ok(Integrator::Adaptive {
            rtol: ck.positive("run.rtol", r.rtol.unwrap_or(1e-9))?,
            atol: ck.positive("run.atol", r.atol.unwrap_or(1e-9))?,
            h_max: ck.positive("run.h_max", r.h_max.unwrap_or(10.0 * r.h))?,
        }),
    }
}

pub(super) fn validate(raw: RawFile, origin: &str) -> Result<RunFile, FileError> {
    let ck = Check { origin };
    let r = &raw.run;
    let run = RunSettings {
        h: ck.positive("run.h", r.h)?,
        t_end: ck.positive("run.t_end", r.t_end)?,
        every: match r.every {
            Some(0) => return Err(ck.err("run.every", "must be at least 1, got 0")),
            Some(n) => n,
            None => 1,
        },
        f32: r.f32.unwrap_or(false),
        integrator: integrator(&ck, r)?,
    };
    let mechanism_keys = [
        ("gravity", raw.gravity.is_some()),
        ("ground", !raw.ground.is_empty()),
        ("link", !raw.link.is_empty()),
        ("joint", !raw.joint.is_empty()),
        ("driver", !raw.driver.is_empty()),
        ("load", !raw.load.is_empty()),
    ];
    let body = match raw.converter {
        Some(c) => {
            if let Some((key, _)) = mechanism_keys.iter().find(|(_, given)| *given) {
                return Err(ck.err(
                    *key,
                    "not in a converter file ([converter] describes the whole mechanism)",
                ));
            }
            if run.integrator != Integrator::Dp5 {
                return Err(ck.err(
                    "run.integrator",
                    "the converter's twin steps with a fixed h, as in firmware: only \"dp5\"",
                ));
            }
            Body::Converter(Box::new(converter(&ck, c, &raw.run)?))
        }
        None => {
            for (key, given) in [
                ("run.mode", r.mode.is_some()),
                ("run.motor", r.motor.is_some()),
                ("run.load", r.load.is_some()),
            ] {
                if given {
                    return Err(ck.err(
                        key,
                        "only in a converter file (a mechanism's motors are in [[driver]])",
                    ));
                }
            }
            if r.spread_events.is_some() {
                return Err(ck.err(
                    "run.spread_events",
                    "only in a converter file (a mechanism's simulation has no events to spread)",
                ));
            }
            Body::Mechanism(mechanism(
                &ck,
                raw.gravity,
                raw.ground,
                raw.link,
                raw.joint,
                raw.driver,
                raw.load,
            )?)
        }
    };
    Ok(RunFile {
        name: raw.name,
        description: raw.description,
        body,
        run,
    })
}

fn converter(ck: &Check<'_>, c: RawConverter, run: &RawRun) -> Result<Converter, FileError> {
    if c.link.len() != 8 {
        return Err(ck.err(
            "converter.link",
            format!(
                "needs the 8 bars of SPEC 3 in order (crank, coupler, rocker, swing link, rod 5, lever 6, rod 7, lever 8), got {}",
                c.link.len()
            ),
        ));
    }
    let mut links = [Bar {
        length: 1.0,
        mass: 0.0,
        inertia: 0.0,
    }; 8];
    for (k, (slot, b)) in links.iter_mut().zip(&c.link).enumerate() {
        let f = |key: &str| format!("converter.link[{}] (link {}).{key}", k, k + 1);
        *slot = Bar {
            length: ck.positive(&f("length"), b.length)?,
            mass: ck.positive(&f("mass"), b.mass)?,
            inertia: ck.non_negative(&f("inertia"), b.inertia)?,
        };
    }
    let v = |field: &str, p: [f64; 2]| ck.vec2(field, p).map(|p| Vec2::new(p[0], p[1]));
    let params = CccParams {
        a: v("converter.a", c.a)?,
        f: v("converter.f", c.f)?,
        h: v("converter.h", c.h)?,
        links,
        rocker_d: ck.positive("converter.rocker_d", c.rocker_d)?,
        mass: ck.non_negative("converter.mass", c.mass)?,
        mass_inertia: ck.non_negative("converter.mass_inertia", c.mass_inertia)?,
        mass_at: ck.non_negative("converter.mass_at", c.mass_at)?,
        shaft_inertia: ck.non_negative("converter.shaft_inertia", c.shaft_inertia)?,
        friction: friction_of(ck, c.friction.as_ref())?,
        drive: match c.drive {
            RawDrive::Cw => DriveDirection::Cw,
            RawDrive::Ccw => DriveDirection::Ccw,
        },
        gravity: v("converter.gravity", c.gravity)?,
        branch_c: c.branch_c.into(),
        branch_g: c.branch_g.into(),
        branch_i: c.branch_i.into(),
    };
    // What the core checks beyond these (overflow of the size squared): its message.
    params
        .validate()
        .map_err(|e| ck.err("converter", e.to_string()))?;
    let clutch = run.mode.unwrap_or(RawMode::Clutch) == RawMode::Clutch;
    let load = match run.load {
        Some(l) if !clutch && l != 0.0 => {
            return Err(ck.err(
                "run.load",
                "free mode has no clutch, so no shaft load (use mode = \"clutch\")",
            ))
        }
        Some(l) => ck.converter_load("run.load", ck.non_negative("run.load", l)?)?,
        None => 0.0,
    };
    let motor = match &run.motor {
        Some(m) => motor(ck, "run.motor", m)?,
        None => {
            return Err(ck.err(
                "run.motor",
                "missing (the motor on the crank: a torque in N·m, or a motor table)",
            ))
        }
    };
    Ok(Converter {
        params,
        crank_deg: ck.finite("converter.crank_deg", c.crank_deg.unwrap_or(105.0))?,
        swing_deg: ck.finite("converter.swing_deg", c.swing_deg.unwrap_or(90.0))?,
        crank_speed: ck.finite("converter.crank_speed", c.crank_speed.unwrap_or(0.0))?,
        swing_speed: ck.finite("converter.swing_speed", c.swing_speed.unwrap_or(0.0))?,
        motor_offset: ck.finite("converter.motor_offset", c.motor_offset.unwrap_or(0.0))?,
        clutch,
        motor,
        load,
        spread_events: run.spread_events.unwrap_or(false),
    })
}

/// The motor keys by type, for messages.
const MOTOR_KEYS: [(&str, &[&str]); 3] = [
    ("constant", &["type", "torque"]),
    (
        "asynchronous",
        &[
            "type",
            "breakdown_rpm",
            "breakdown_torque",
            "rated_rpm",
            "rated_torque",
            "synchronous_rpm",
        ],
    ),
    ("polynomial", &["type", "a", "b", "c"]),
];

/// A motor: a number (constant torque, N·m) or a table with `type`.
fn motor(ck: &Check<'_>, field: &str, v: &toml::Value) -> Result<MotorSpec, FileError> {
    let num = |key: &str, v: Option<&toml::Value>| -> Result<f64, FileError> {
        let f = format!("{field}.{key}");
        match v {
            Some(toml::Value::Float(x)) => ck.finite(&f, *x),
            Some(toml::Value::Integer(i)) => Ok(*i as f64),
            Some(other) => Err(ck.err(f, format!("must be a number, got {}", other.type_str()))),
            None => Err(ck.err(f, "missing")),
        }
    };
    let t = match v {
        toml::Value::Float(_) | toml::Value::Integer(_) => {
            return Ok(MotorSpec::Constant(num("torque", Some(v)).map_err(|mut e| {
                e.field = field.to_string();
                e
            })?))
        }
        toml::Value::Table(t) => t,
        other => {
            return Err(ck.err(
                field,
                format!(
                    "must be a torque in N·m or a table with type = \"constant\" | \"asynchronous\" | \"polynomial\", got {}",
                    other.type_str()
                ),
            ))
        }
    };
    let kind = match t.get("type") {
        Some(toml::Value::String(s)) => s.as_str(),
        Some(other) => {
            return Err(ck.err(
                format!("{field}.type"),
                format!("must be a string, got {}", other.type_str()),
            ))
        }
        None => {
            return Err(ck.err(
                format!("{field}.type"),
                "missing (constant, asynchronous or polynomial)",
            ))
        }
    };
    let Some((_, keys)) = MOTOR_KEYS.iter().find(|(k, _)| *k == kind) else {
        return Err(ck.err(
            format!("{field}.type"),
            format!("unknown motor type \"{kind}\" (known: constant, asynchronous, polynomial)"),
        ));
    };
    if let Some(k) = t.keys().find(|k| !keys.contains(&k.as_str())) {
        return Err(ck.err(
            format!("{field}.{k}"),
            format!(
                "unknown key for a {kind} motor (allowed: {})",
                keys.join(", ")
            ),
        ));
    }
    let g = |key: &str| num(key, t.get(key));
    Ok(match kind {
        "constant" => MotorSpec::Constant(g("torque")?),
        "asynchronous" => {
            let m = MotorSpec::Asynchronous {
                breakdown_rpm: g("breakdown_rpm")?,
                breakdown_torque: g("breakdown_torque")?,
                rated_rpm: g("rated_rpm")?,
                rated_torque: g("rated_torque")?,
                synchronous_rpm: g("synchronous_rpm")?,
            };
            if let MotorSpec::Asynchronous {
                breakdown_rpm: a,
                rated_rpm: b,
                synchronous_rpm: c,
                ..
            } = m
            {
                if !(0.0 <= a && a < b && b < c) {
                    return Err(ck.err(
                        field,
                        format!("needs 0 <= breakdown_rpm < rated_rpm < synchronous_rpm, got {a}, {b}, {c}"),
                    ));
                }
            }
            m.motor::<f64>().map_err(|e| ck.err(field, e.to_string()))?;
            starts(ck, field, m)?
        }
        _ => starts(
            ck,
            field,
            MotorSpec::Polynomial {
                a: g("a")?,
                b: g("b")?,
                c: g("c")?,
            },
        )?,
    })
}

/// A quadratic characteristic must give a torque `T(0) ≥ 0` at standstill: with
/// `T(0) < 0` the motor cannot start; it turns backward, down the parabola's other
/// branch, until its torque is no longer finite.
fn starts(ck: &Check<'_>, field: &str, m: MotorSpec) -> Result<MotorSpec, FileError> {
    match m.quadratic() {
        Some((a, b, c)) if a < 0.0 => Err(ck.err(
            field,
            format!(
                "the characteristic {} gives T(0) = {} N·m < 0 at standstill: the motor \
                 cannot start; check its speeds and torques",
                characteristic(a, b, c),
                Sci(a)
            ),
        )),
        _ => Ok(m),
    }
}

/// Names: not empty, no `.` (it separates a link from its point in references).
fn check_name(ck: &Check<'_>, field: &str, name: &str) -> Result<(), FileError> {
    if name.is_empty() {
        return Err(ck.err(field, "must not be empty"));
    }
    if name.contains('.') {
        return Err(ck.err(
            field,
            format!("\"{name}\": a name must not contain '.' (it separates a link from its point)"),
        ));
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn mechanism(
    ck: &Check<'_>,
    gravity: Option<[f64; 2]>,
    raw_ground: Vec<RawGround>,
    raw_links: Vec<RawLink>,
    raw_joints: Vec<RawJoint>,
    raw_drivers: Vec<RawDriver>,
    raw_loads: Vec<RawLoad>,
) -> Result<Mechanism, FileError> {
    let gravity = ck.vec2("gravity", gravity.unwrap_or([0.0, -9.81]))?;
    if raw_links.is_empty() {
        return Err(ck.err("link", "missing: a mechanism needs at least one [[link]]"));
    }
    if raw_links.len() > MAX_LINKS {
        return Err(ck.err(
            "link",
            format!(
                "{} links, the core holds at most {MAX_LINKS}",
                raw_links.len()
            ),
        ));
    }
    if raw_ground.len() > MAX_GROUND_POINTS {
        return Err(ck.err(
            "ground",
            format!(
                "{} ground points, the core holds at most {MAX_GROUND_POINTS}",
                raw_ground.len()
            ),
        ));
    }
    // Names: one namespace for ground points and links (a reference `X` is a ground
    // point, `X.p` a link's point).
    let mut names: BTreeMap<String, String> = BTreeMap::new();
    let mut declare = |field: String, name: &str| -> Result<(), FileError> {
        check_name(ck, &field, name)?;
        if let Some(first) = names.get(name) {
            return Err(ck.err(
                field,
                format!("duplicate name \"{name}\" (already used by {first})"),
            ));
        }
        names.insert(name.to_string(), field);
        Ok(())
    };
    let mut ground = Vec::new();
    for (k, g) in raw_ground.into_iter().enumerate() {
        declare(format!("ground[{k}].name"), &g.name)?;
        let at = ck.vec2(&format!("ground \"{}\".at", g.name), g.at)?;
        ground.push(GroundPoint { name: g.name, at });
    }
    let mut links = Vec::new();
    for (k, l) in raw_links.into_iter().enumerate() {
        declare(format!("link[{k}].name"), &l.name)?;
        let f = |key: &str| format!("link \"{}\".{key}", l.name);
        let mass = ck.non_negative(&f("mass"), l.mass)?;
        let inertia = ck.non_negative(&f("inertia"), l.inertia)?;
        let (mut points, mut point_names) = match l.length {
            Some(len) => {
                let len = ck.positive(&f("length"), len)?;
                (
                    vec![[0.0, 0.0], [len, 0.0]],
                    vec!["start".to_string(), "end".to_string()],
                )
            }
            None => (vec![[0.0, 0.0]], vec!["origin".to_string()]),
        };
        for (name, p) in &l.points {
            let pf = f(&format!("points.{name}"));
            check_name(ck, &pf, name)?;
            if point_names.iter().any(|n| n == name) || name.parse::<usize>().is_ok() {
                return Err(ck.err(
                    pf,
                    format!("\"{name}\" is reserved (start, end, origin and numbers name the built-in points and indices)"),
                ));
            }
            points.push(ck.vec2(&pf, *p)?);
            point_names.push(name.clone());
        }
        if points.len() > MAX_LINK_POINTS {
            return Err(ck.err(
                f("points"),
                format!(
                    "{} points on the link, the core holds at most {MAX_LINK_POINTS}",
                    points.len()
                ),
            ));
        }
        let cog = match (l.cog, l.length) {
            (Some(RawCog::Along(d)), Some(_)) => [ck.finite(&f("cog"), d)?, 0.0],
            (Some(RawCog::Along(_)), None) => return Err(ck.err(
                f("cog"),
                "a distance along the bar needs `length`; give [x, y] for a link without length",
            )),
            (Some(RawCog::At(p)), _) => ck.vec2(&f("cog"), p)?,
            // The midpoint of a bar (SPEC: bars have their COG at the midpoint), the
            // origin of a block.
            (None, Some(len)) => [0.5 * len, 0.0],
            (None, None) => [0.0, 0.0],
        };
        let angle_deg = ck.finite(&f("angle_deg"), l.angle_deg.unwrap_or(0.0))?;
        links.push(LinkSpec {
            name: l.name,
            points,
            point_names,
            mass,
            inertia,
            cog,
            angle_deg,
        });
    }
    let body_of = |name: &str| links.iter().position(|l| l.name == name).map(|k| k + 1);
    // A point reference: `G` (ground point G) or `link.point` (`start`, `end`,
    // `origin`, a named point, or an index).
    let point = |field: &str, r: &str| -> Result<PointId, FileError> {
        match r.split_once('.') {
            None => match ground.iter().position(|g| g.name == r) {
                Some(point) => Ok(PointId { body: 0, point }),
                None if body_of(r).is_some() => Err(ck.err(
                    field,
                    format!("\"{r}\" is a link: name one of its points, e.g. \"{r}.start\""),
                )),
                None => Err(ck.err(
                    field,
                    format!(
                        "unknown point \"{r}\" (ground points: {}; a link's point is written link.point)",
                        list(ground.iter().map(|g| g.name.as_str()))
                    ),
                )),
            },
            Some((link, p)) => {
                let Some(body) = body_of(link) else {
                    return Err(ck.err(
                        field,
                        format!(
                            "unknown link \"{link}\" in \"{r}\" (links: {})",
                            list(links.iter().map(|l| l.name.as_str()))
                        ),
                    ));
                };
                let l = &links[body - 1];
                let point = l
                    .point_names
                    .iter()
                    .position(|n| n == p)
                    .or_else(|| p.parse::<usize>().ok().filter(|&i| i < l.points.len()));
                match point {
                    Some(point) => Ok(PointId { body, point }),
                    None => Err(ck.err(
                        field,
                        format!(
                            "link \"{link}\" has no point \"{p}\" (its points: {}, or 0..{})",
                            list(l.point_names.iter().map(String::as_str)),
                            l.points.len() - 1
                        ),
                    )),
                }
            }
        }
    };
    let mut joints: Vec<JointSpec> = Vec::new();
    for (k, j) in raw_joints.into_iter().enumerate() {
        let name = j.name.clone().unwrap_or_else(|| format!("J{}", k + 1));
        let jf = format!("joint \"{name}\"");
        check_name(ck, &format!("{jf}.name"), &name)?;
        if joints.iter().any(|o| o.name == name) {
            return Err(ck.err(
                format!("{jf}.name"),
                format!("duplicate joint name \"{name}\""),
            ));
        }
        let f = |key: &str| format!("{jf}.{key}");
        let kind = match j.kind {
            RawJointType::Revolute => {
                for (key, given) in [
                    ("slider", j.slider.is_some()),
                    ("guide", j.guide.is_some()),
                    ("guide_angle_deg", j.guide_angle_deg.is_some()),
                    ("slider_angle_deg", j.slider_angle_deg.is_some()),
                    ("offset", j.offset.is_some()),
                ] {
                    if given {
                        return Err(ck.err(f(key), "only for a prismatic joint"));
                    }
                }
                let Some([p, q]) = &j.points else {
                    return Err(ck.err(
                        f("points"),
                        "missing: a revolute joint joins two points, points = [\"A\", \"crank.start\"]",
                    ));
                };
                let points = [point(&f("points"), p)?, point(&f("points"), q)?];
                if points[0].body == points[1].body {
                    return Err(ck.err(f("points"), "both points are on the same body"));
                }
                JointKind::Revolute { points }
            }
            RawJointType::Prismatic => {
                if j.points.is_some() {
                    return Err(ck.err(
                        f("points"),
                        "only for a revolute joint (a prismatic joint has slider and guide)",
                    ));
                }
                let (Some(s), Some(g)) = (&j.slider, &j.guide) else {
                    let missing = if j.slider.is_none() {
                        "slider"
                    } else {
                        "guide"
                    };
                    return Err(ck.err(
                        f(missing),
                        "missing: a prismatic joint needs slider and guide",
                    ));
                };
                let slider = point(&f("slider"), s)?;
                let guide = point(&f("guide"), g)?;
                if slider.body == guide.body {
                    return Err(ck.err(f("guide"), "slider and guide are on the same body"));
                }
                if slider.body == 0 {
                    return Err(ck.err(
                        f("slider"),
                        "the slider must be a link (the guide may be on the ground)",
                    ));
                }
                JointKind::Prismatic {
                    slider,
                    guide,
                    guide_angle_deg: ck
                        .finite(&f("guide_angle_deg"), j.guide_angle_deg.unwrap_or(0.0))?,
                    slider_angle_deg: ck
                        .finite(&f("slider_angle_deg"), j.slider_angle_deg.unwrap_or(0.0))?,
                    offset: ck.finite(&f("offset"), j.offset.unwrap_or(0.0))?,
                }
            }
        };
        joints.push(JointSpec { name, kind });
    }
    if raw_drivers.len() > MAX_DOF {
        return Err(ck.err(
            "driver",
            format!(
                "{} drivers, the core integrates at most {MAX_DOF} coordinates",
                raw_drivers.len()
            ),
        ));
    }
    let mut drivers: Vec<DriverSpec> = Vec::new();
    for (k, d) in raw_drivers.into_iter().enumerate() {
        let df = format!("driver[{k}]");
        let f = |key: &str| format!("{df}.{key}");
        let Some(link) = body_of(&d.link) else {
            return Err(ck.err(f("link"), unknown_link(&d.link, &links)));
        };
        let Some(joint) = joints.iter().position(|j| j.name == d.joint) else {
            return Err(ck.err(
                f("joint"),
                format!(
                    "unknown joint \"{}\" (joints: {})",
                    d.joint,
                    list(joints.iter().map(|j| j.name.as_str()))
                ),
            ));
        };
        let kind = joints[joint].kind;
        if !kind.bodies().contains(&link) {
            return Err(ck.err(
                f("joint"),
                format!("joint \"{}\" does not join link \"{}\"", d.joint, d.link),
            ));
        }
        if let JointKind::Prismatic { slider, .. } = kind {
            if slider.body != link {
                return Err(ck.err(
                    f("link"),
                    format!(
                        "a prismatic driver moves the joint's slider; \"{}\" is its guide",
                        d.link
                    ),
                ));
            }
        }
        if let Some(first) = drivers.iter().position(|o| o.link == link) {
            return Err(ck.err(
                f("link"),
                format!("link \"{}\" is already driven by driver[{first}]", d.link),
            ));
        }
        let (q0_written, q0) = if kind.is_revolute() {
            if d.q0.is_some() {
                return Err(ck.err(
                    f("q0"),
                    "a revolute driver's initial angle is q0_deg, degrees",
                ));
            }
            let Some(q) = d.q0_deg else {
                return Err(ck.err(f("q0_deg"), "missing (the initial angle, degrees)"));
            };
            let q = ck.finite(&f("q0_deg"), q)?;
            (q, q.to_radians())
        } else {
            if d.q0_deg.is_some() || d.offset_deg.is_some() {
                let key = if d.q0_deg.is_some() {
                    "q0_deg"
                } else {
                    "offset_deg"
                };
                return Err(ck.err(
                    f(key),
                    "only for a revolute driver (a prismatic driver's q0 is in m)",
                ));
            }
            let Some(q) = d.q0 else {
                return Err(ck.err(f("q0"), "missing (the initial offset along the guide, m)"));
            };
            let q = ck.finite(&f("q0"), q)?;
            (q, q)
        };
        let motor = match &d.motor {
            Some(m) => Some(motor(ck, &f("motor"), m)?),
            None => None,
        };
        drivers.push(DriverSpec {
            link,
            joint,
            q0,
            q0_written,
            qd0: ck.finite(&f("qd0"), d.qd0.unwrap_or(0.0))?,
            offset_deg: ck.finite(&f("offset_deg"), d.offset_deg.unwrap_or(0.0))?,
            motor,
        });
    }
    if raw_loads.len() > MAX_LOADS {
        return Err(ck.err(
            "load",
            format!(
                "{} loads, the core holds at most {MAX_LOADS}",
                raw_loads.len()
            ),
        ));
    }
    let mut loads = Vec::new();
    for (k, l) in raw_loads.into_iter().enumerate() {
        let f = |key: &str| format!("load[{k}].{key}");
        let Some(link) = body_of(&l.link) else {
            return Err(ck.err(f("link"), unknown_link(&l.link, &links)));
        };
        loads.push(LoadSpec {
            link,
            at: ck.vec2(&f("at"), l.at.unwrap_or([0.0, 0.0]))?,
            force: {
                let v = ck.vec2(&f("force"), l.force.unwrap_or([0.0, 0.0]))?;
                [ck.load(&f("force"), v[0])?, ck.load(&f("force"), v[1])?]
            },
            moment: ck.load(&f("moment"), l.moment.unwrap_or(0.0))?,
        });
    }
    Ok(Mechanism {
        gravity,
        ground,
        links,
        joints,
        drivers,
        loads,
    })
}

fn list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = names.collect();
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}

/// The friction of `[converter.friction]`, validated: every coefficient finite and
/// non-negative, ε positive; errors name the key (`converter.friction.viscous.A`).
fn friction_of(ck: &Check<'_>, raw: Option<&RawFriction>) -> Result<Friction<f64>, FileError> {
    let mut f = Friction::<f64>::none();
    let Some(raw) = raw else {
        return Ok(f);
    };
    for (table, kind, out) in [
        (&raw.viscous, "viscous", &mut f.viscous),
        (&raw.coulomb, "coulomb", &mut f.coulomb),
    ] {
        let Some(joints) = table else {
            continue;
        };
        for ((slot, value), name) in out
            .iter_mut()
            .zip(joints.values())
            .zip(FRICTION_JOINT_NAMES)
        {
            if let Some(v) = value {
                *slot = ck.non_negative(&format!("converter.friction.{kind}.{name}"), v)?;
            }
        }
    }
    if let Some(v) = raw.clutch_drag {
        f.clutch_drag = ck.non_negative("converter.friction.clutch_drag", v)?;
    }
    if let Some(v) = raw.coulomb_eps {
        f.coulomb_eps = ck.positive("converter.friction.coulomb_eps", v)?;
    }
    Ok(f)
}
