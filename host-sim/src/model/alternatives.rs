//! Alternative choices of independent coordinates of a mechanism (issue 17, item 5),
//! for the core's coordinate switching at dead points
//! ([`structomat::simulation::switch`]): the same links with one driver moved onto
//! another joint to the ground, its group sequence found by the structomatic analysis,
//! its motor kept on its own joint (a drive across that joint).

use super::analysis::{analyze, build_model_with};
use super::runfile::{DriverSpec, Mechanism};
use structomat::{Model, ModelError, Real};

/// At most this many alternatives per mechanism (the core holds them beside the
/// simulation, one model each).
pub const MAX_ALTERNATIVES: usize = 3;

/// The alternative coordinate choices of `m`, in file order of the drivers and then of
/// the joints: driver `k` moved onto a joint `J` from the ground to a link that no
/// driver drives (revolute: the link's angle, element R; prismatic: its slide, element
/// T), when the analysis finds a sequence for it; `k`'s motor then acts across its own
/// joint. At most [`MAX_ALTERNATIVES`].
pub fn alternatives<T: Real>(m: &Mechanism) -> Result<Vec<Model<T>>, ModelError> {
    let mut out = Vec::new();
    let driven: Vec<usize> = m.drivers.iter().map(|d| d.link).collect();
    for (k, d) in m.drivers.iter().enumerate() {
        for (j, joint) in m.joints.iter().enumerate() {
            if out.len() >= MAX_ALTERNATIVES {
                return Ok(out);
            }
            let [p, q] = joint.kind.bodies();
            let link = match (p, q) {
                (0, l) | (l, 0) if l != 0 => l,
                _ => continue,
            };
            if driven.contains(&link) || m.drivers.iter().any(|e| e.joint == j) {
                continue;
            }
            let mut alt = m.clone();
            alt.drivers[k] = DriverSpec {
                link,
                joint: j,
                q0: 0.0,
                q0_written: 0.0,
                qd0: 0.0,
                offset_deg: 0.0,
                motor: None,
            };
            let Ok(a) = analyze(&alt) else { continue };
            let [dp, dq] = m.joints[d.joint].kind.bodies();
            let on = if dp == d.link { dq } else { dp };
            let motor = d.motor.as_ref().map(|s| s.motor::<T>()).transpose()?;
            let model = build_model_with::<T>(&alt, &a, |b| {
                if let Some(motor) = motor {
                    b.drive_across(d.link as u8, on as u8, motor)?;
                }
                Ok(())
            });
            if let Ok(model) = model {
                out.push(model);
            }
        }
    }
    Ok(out)
}
