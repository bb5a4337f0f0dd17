//! The converter parameters `host-sim identify` can fit, by their run-file keys (the
//! dotted keys of a sweep: `converter.link.2.mass`, `converter.friction.viscous.A`,
//! `converter.motor_offset`), with the bounds of the search.
//!
//! Bounds: a mass or an inertia within ±[`MASS_SPAN`] of the base file's value (the
//! bench README's "known to within about ±10 %"); a friction coefficient in
//! `[0, MAX_FRICTION]`; the motor-torque offset within ±[`MAX_MOTOR_OFFSET`].

use crate::model::runfile::Converter;
use structomat::ccc::FRICTION_JOINT_NAMES;

/// The parameters fitted without `--fit`: the ones that explain bench1's drift from
/// SPEC's machine (README, "From a bench log to an identified twin").
///
/// On bench1, a replay at a time of each of the 9 joints' viscous friction, of the
/// Coulomb friction at A, of each bar's mass and inertia and of the motor offset showed
/// the crank's viscous friction the main cause (0.07 N·m·s/rad alone: 261 → 22 counts
/// RMS, every event the same), the rocker's and coupler's masses the first release's
/// time. Fitted together with those, the viscous friction at E (rocker on swing link)
/// takes the crank residual from 2.08 to 0.59 counts RMS. The friction at F (swing link
/// on the ground) is the last term: added one at a time to that six-parameter optimum
/// (each search started there), every joint's viscous and Coulomb friction and the
/// clutch drag, it alone brought the fit to the counts' quantization (its residual
/// standard deviation 0.44 → 0.28 counts, against 1/√12 = 0.29 for the quantization
/// alone; the cost 396 → 154; with it, each further term lowered the cost by 2 % at
/// most), and the seven parameters from SPEC's machine find the same optimum.
/// Identified from bench1's first 0.5 s, the seven predict the rest of the log (its
/// last 5 events within 0.032 ms, the crank 0.19 counts RMS there) where the six
/// without F miss by 0.21 ms and 0.37 counts: the six's masses had taken up F's
/// friction (the rocker 5.36 kg, the oscillating mass 6.48, for 5.47 and 6.45).
pub const DEFAULT_FIT: &str = "converter.mass,converter.link.1.mass,converter.link.2.mass,\
converter.friction.viscous.A,converter.friction.viscous.B,converter.friction.viscous.E;\
converter.friction.viscous.F";

/// Nelder-Mead's iterations without `--max-iters`.
pub const DEFAULT_MAX_ITERS: u64 = 600;

/// The most iterations `--max-iters` takes.
pub const MAX_ITERS: u64 = 100_000;

/// A mass's or an inertia's bounds: the base value ± this fraction of it.
pub const MASS_SPAN: f64 = 0.10;

/// The largest friction coefficient searched: N·m·s/rad (viscous, clutch drag) or N·m
/// (Coulomb). 1 N·m at a joint is a twelfth of the 12 N·m motor; 1 N·m·s/rad at the
/// crank's 10 rad/s takes most of the motor's torque.
pub const MAX_FRICTION: f64 = 1.0;

/// The largest motor-torque offset searched, N·m (a sixth of the 12 N·m motor).
pub const MAX_MOTOR_OFFSET: f64 = 2.0;

/// What a bar's parameter is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BarField {
    /// Its mass, kg.
    Mass,
    /// Its moment of inertia about its COG, kg·m².
    Inertia,
}

/// A parameter `identify` can fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    /// Bar `k`'s (from 0, SPEC 3's order) mass or inertia.
    Bar(usize, BarField),
    /// The oscillating mass, kg.
    Mass,
    /// Its own moment of inertia, kg·m².
    MassInertia,
    /// Viscous friction at the joint [`FRICTION_JOINT_NAMES`]`[k]`, N·m·s/rad.
    Viscous(usize),
    /// Dry friction at the joint [`FRICTION_JOINT_NAMES`]`[k]`, N·m.
    Coulomb(usize),
    /// An overrunning clutch's drag, N·m·s/rad.
    ClutchDrag,
    /// The offset added to the measured motor torque, N·m.
    MotorOffset,
}

impl Param {
    /// The parameter of a run-file key, or why there is none.
    pub fn parse(key: &str) -> Result<Param, String> {
        let joint = |name: &str| FRICTION_JOINT_NAMES.iter().position(|j| *j == name);
        let segments: Vec<&str> = key.split('.').collect();
        let p = match segments.as_slice() {
            ["converter", "mass"] => Some(Param::Mass),
            ["converter", "mass_inertia"] => Some(Param::MassInertia),
            ["converter", "motor_offset"] => Some(Param::MotorOffset),
            ["converter", "friction", "clutch_drag"] => Some(Param::ClutchDrag),
            ["converter", "friction", "viscous", j] => joint(j).map(Param::Viscous),
            ["converter", "friction", "coulomb", j] => joint(j).map(Param::Coulomb),
            ["converter", "link", k, field] => {
                let field = match *field {
                    "mass" => Some(BarField::Mass),
                    "inertia" => Some(BarField::Inertia),
                    _ => None,
                };
                match (k.parse::<usize>().ok().filter(|k| *k < 8), field) {
                    (Some(k), Some(f)) => Some(Param::Bar(k, f)),
                    _ => None,
                }
            }
            _ => None,
        };
        p.ok_or_else(|| {
            format!(
                "'{key}' is no parameter identify fits (converter.link.K.mass, \
                 converter.link.K.inertia with K = 0..7, converter.mass, \
                 converter.mass_inertia, converter.friction.viscous.J, \
                 converter.friction.coulomb.J with J one of {}, \
                 converter.friction.clutch_drag, converter.motor_offset)",
                FRICTION_JOINT_NAMES.join(", ")
            )
        })
    }

    /// The run file's dotted key.
    pub fn key(&self) -> String {
        match *self {
            Param::Bar(k, BarField::Mass) => format!("converter.link.{k}.mass"),
            Param::Bar(k, BarField::Inertia) => format!("converter.link.{k}.inertia"),
            Param::Mass => "converter.mass".to_string(),
            Param::MassInertia => "converter.mass_inertia".to_string(),
            Param::Viscous(j) => format!("converter.friction.viscous.{}", joint_name(j)),
            Param::Coulomb(j) => format!("converter.friction.coulomb.{}", joint_name(j)),
            Param::ClutchDrag => "converter.friction.clutch_drag".to_string(),
            Param::MotorOffset => "converter.motor_offset".to_string(),
        }
    }

    /// The value's unit.
    pub fn unit(&self) -> &'static str {
        match self {
            Param::Bar(_, BarField::Mass) | Param::Mass => "kg",
            Param::Bar(_, BarField::Inertia) | Param::MassInertia => "kg·m²",
            Param::Viscous(_) | Param::ClutchDrag => "N·m·s/rad",
            Param::Coulomb(_) | Param::MotorOffset => "N·m",
        }
    }

    /// The value in `c`.
    pub fn get(&self, c: &Converter) -> f64 {
        let p = &c.params;
        let bar = |k: usize| p.links.get(k).copied();
        match *self {
            Param::Bar(k, BarField::Mass) => bar(k).map_or(f64::NAN, |b| b.mass),
            Param::Bar(k, BarField::Inertia) => bar(k).map_or(f64::NAN, |b| b.inertia),
            Param::Mass => p.mass,
            Param::MassInertia => p.mass_inertia,
            Param::Viscous(j) => p.friction.viscous.get(j).copied().unwrap_or(f64::NAN),
            Param::Coulomb(j) => p.friction.coulomb.get(j).copied().unwrap_or(f64::NAN),
            Param::ClutchDrag => p.friction.clutch_drag,
            Param::MotorOffset => c.motor_offset,
        }
    }

    /// Sets the value in `c`.
    pub fn set(&self, c: &mut Converter, v: f64) {
        let p = &mut c.params;
        let slot = match *self {
            Param::Bar(k, BarField::Mass) => p.links.get_mut(k).map(|b| &mut b.mass),
            Param::Bar(k, BarField::Inertia) => p.links.get_mut(k).map(|b| &mut b.inertia),
            Param::Mass => Some(&mut p.mass),
            Param::MassInertia => Some(&mut p.mass_inertia),
            Param::Viscous(j) => p.friction.viscous.get_mut(j),
            Param::Coulomb(j) => p.friction.coulomb.get_mut(j),
            Param::ClutchDrag => Some(&mut p.friction.clutch_drag),
            Param::MotorOffset => Some(&mut c.motor_offset),
        };
        if let Some(s) = slot {
            *s = v;
        }
    }

    /// The search's bounds `(lo, hi)` for a base value `base`.
    pub fn bounds(&self, base: f64) -> (f64, f64) {
        match self {
            Param::Bar(..) | Param::Mass | Param::MassInertia => {
                (base * (1.0 - MASS_SPAN), base * (1.0 + MASS_SPAN))
            }
            Param::Viscous(_) | Param::Coulomb(_) | Param::ClutchDrag => (0.0, MAX_FRICTION),
            Param::MotorOffset => (-MAX_MOTOR_OFFSET, MAX_MOTOR_OFFSET),
        }
    }
}

fn joint_name(j: usize) -> &'static str {
    FRICTION_JOINT_NAMES.get(j).copied().unwrap_or("?")
}

/// Parses a comma-separated list of keys (`--fit`), in stages separated by `;` (`a,b;c`:
/// `a` and `b` searched first, then all three from their best): at least one key a
/// stage, none twice. Returns the parameters and, per stage, how many of them (the
/// first ones) it searches.
pub fn parse_stages(list: &str) -> Result<(Vec<Param>, Vec<usize>), String> {
    let mut out: Vec<Param> = Vec::new();
    let mut stages = Vec::new();
    for stage in list.split(';') {
        if stage.trim().is_empty() {
            return Err(format!("'{list}' has an empty stage"));
        }
        for key in stage.split(',').map(str::trim) {
            let p = Param::parse(key)?;
            if out.contains(&p) {
                return Err(format!("'{key}' is given twice"));
            }
            out.push(p);
        }
        stages.push(out.len());
    }
    Ok((out, stages))
}

#[cfg(test)]
mod tests {
    use super::{parse_stages, Param, DEFAULT_FIT};

    /// `;` separates the stages, `,` the keys: each stage's count is the keys up to its
    /// end; the default is six, then seven.
    #[test]
    fn stages_count_the_keys_up_to_their_end() {
        let (params, stages) = parse_stages(
            "converter.mass, converter.friction.viscous.A;converter.friction.viscous.F",
        )
        .unwrap();
        assert_eq!(
            params,
            [
                Param::parse("converter.mass").unwrap(),
                Param::parse("converter.friction.viscous.A").unwrap(),
                Param::parse("converter.friction.viscous.F").unwrap(),
            ]
        );
        assert_eq!(stages, [2, 3]);
        let (params, stages) = parse_stages(DEFAULT_FIT).unwrap();
        assert_eq!((params.len(), stages), (7, vec![6, 7]));
        assert_eq!(
            params[6],
            Param::parse("converter.friction.viscous.F").unwrap()
        );
        let (_, one) = parse_stages("converter.mass").unwrap();
        assert_eq!(one, [1]);
        for (list, named) in [
            ("converter.mass;", "empty stage"),
            (";converter.mass", "empty stage"),
            ("converter.mass;converter.mass", "twice"),
        ] {
            let e = parse_stages(list).unwrap_err();
            assert!(e.contains(named), "{list}: {e}");
        }
    }
}
