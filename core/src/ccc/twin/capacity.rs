//! What the converter's mode models need of the core's capacities: the largest of every
//! mode and coordinate choice (the test below builds them all), the capacity
//! [`Converter`] of the twin's models and workspaces (a slot 20 KB in f64 where the
//! generic limits take 30 KB), and checked at compile time to fit the core's own
//! limits ([`config`](crate::config)), which bound what its algorithms index.

use crate::capacity::{Array, Capacity};
use crate::config::{
    MAX_BODIES, MAX_CHAINS, MAX_DOF, MAX_GROUND_POINTS, MAX_GROUPS, MAX_GROUP_JOINTS,
    MAX_GROUP_LINKS, MAX_GROUP_VARS, MAX_LINKS, MAX_LINK_POINTS, MAX_TERMS,
};
use crate::model::{Link, Load};
use crate::scalar::{Real, Vec2};
use crate::structomat::{Group, GroupData};
use crate::workspace::Reaction;
use core::mem::size_of;

use super::Twin;

/// Groups of a mode's sequence: 5 (free, I0, A6 and A8: the crank, the dyads of the
/// coupler and rocker, and of each rod and lever).
pub(crate) const GROUPS: usize = 5;
/// Moving links: 8 (every mode with both levers free or turning).
pub(crate) const LINKS: usize = 8;
/// Ground points: 5 (jam: A, F, H and both locked levers' pins).
pub(crate) const GROUND_POINTS: usize = 5;
/// Points on a link: 3 (the rocker carries D between its ends).
pub(crate) const LINK_POINTS: usize = 3;
/// Coordinates: 2.
pub(crate) const DOF: usize = 2;
/// A68 driven by the crank: one six-link group of 3 chains, up to 4 terms a chain, 9
/// joints and 6 unknowns.
pub(crate) const CHAINS: usize = 3;
/// Terms in a chain (A68's six-link group).
pub(crate) const TERMS: usize = 4;
/// Joints of a group (A68's six-link group).
pub(crate) const GROUP_JOINTS: usize = 9;
/// Links and unknowns of a group (A68's six-link group).
pub(crate) const GROUP_LINKS: usize = 6;
/// External loads: none (the twin applies the motor's and the shaft's torques as the
/// workspace's applied moments).
pub(crate) const LOADS: usize = 0;

/// The capacities of the twin's models and workspaces: the lists of `GROUPS` (5) groups,
/// `LINKS` (8) links, `GROUND_POINTS` (5) ground points and no loads; the rest (a group's
/// chains, terms, joints and unknowns, a link's points, the bodies and coordinates) at
/// the core's limits, which are the converter's needs or close to them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Converter;

// The converter's lists count in a byte (their lengths are at most 8): 7 bytes less a
// list than `usize`'s on a 64-bit host, 3 on the Cortex-M (where f32 data is 4-byte
// aligned, the bytes are not padding).
impl<T: Real> Capacity<T> for Converter {
    type GroundPoints = heapless::Vec<Vec2<T>, GROUND_POINTS, u8>;
    type Links = heapless::Vec<Link<T>, LINKS, u8>;
    type Groups = heapless::Vec<Group<T>, GROUPS, u8>;
    type Loads = heapless::Vec<Load<T>, LOADS, u8>;
    type GroupData = Array<GroupData<T>, GROUPS>;
    type Reactions = Array<[Reaction<T>; MAX_GROUP_JOINTS], GROUPS>;
}

const _: () = assert!(
    GROUPS <= MAX_GROUPS
        && LINKS <= MAX_LINKS
        && LINKS < MAX_BODIES
        && GROUND_POINTS <= MAX_GROUND_POINTS
        && LINK_POINTS <= MAX_LINK_POINTS
        && DOF <= MAX_DOF
        && CHAINS <= MAX_CHAINS
        && TERMS <= MAX_TERMS
        && GROUP_JOINTS <= MAX_GROUP_JOINTS
        && GROUP_LINKS <= MAX_GROUP_LINKS
        && GROUP_LINKS <= MAX_GROUP_VARS,
    "the converter's mode models fit the core's capacities"
);

/// The twin's RAM budget, checked at compile time on every target: `Twin<f32>` in 32
/// KiB (a quarter of a 128 KiB Cortex-M4F's RAM), `Twin<f64>` in 64 KiB. Its three
/// slots, each a model and a workspace of these capacities, are 94 % of it.
const _: () = assert!(
    size_of::<Twin<f32>>() <= 32 * 1024,
    "Twin<f32> fits in 32 KiB"
);
const _: () = assert!(
    size_of::<Twin<f64>>() <= 64 * 1024,
    "Twin<f64> fits in 64 KiB"
);

#[cfg(test)]
mod tests {
    use super::super::slot::Slot;
    use super::*;

    /// The twin is its three slots and under 2 KiB (f32) / 4 KiB (f64) of state and
    /// logs (the fields of `Twin` other than `slots`: 1.6 and 3.1 KB on x86_64), and
    /// within the budgets asserted at compile time above.
    #[test]
    fn the_twin_is_three_slots_and_its_state() {
        fn check<T: Real>(budget: usize, rest: usize) -> usize {
            let (twin, slot) = (size_of::<Twin<T>>(), size_of::<Slot<T>>());
            assert!(twin >= 3 * slot, "{twin} B < 3 slots of {slot} B");
            assert!(
                twin < 3 * slot + rest,
                "{twin} B: more than 3 slots of {slot} B"
            );
            assert!(twin <= budget, "{twin} B over {budget} B");
            twin
        }
        let t32 = check::<f32>(32 * 1024, 2 * 1024);
        let t64 = check::<f64>(64 * 1024, 4 * 1024);
        // f32 halves the floating-point data; indices, lengths and flags stay.
        let ratio = t32 as f64 / t64 as f64;
        assert!(
            (0.5..0.56).contains(&ratio),
            "f32/f64 twin size ratio {ratio}"
        );
    }
    use crate::ccc::build::{build, initial_pose};
    use crate::ccc::mode::Mode;
    use crate::ccc::params::CccParams;

    /// Every mode and coordinate choice, built by the model builder at poses across
    /// S2's range: the counts stay within the converter's capacities above, and each
    /// capacity is reached by some model (they are the converter's needs, not bounds).
    #[test]
    fn the_converters_models_need_these_capacities() {
        let p = CccParams::<f64>::reference();
        let mut most = [0usize; 9];
        let mut built = 0;
        for (crank, swing) in [(0.3, 1.9), (2.0, 1.7), (-1.1, 2.1), (4.0, 1.8)] {
            let Some(pose) = initial_pose(&p, crank, swing) else {
                continue;
            };
            for mode in Mode::ALL {
                for coords in mode.coordinate_choices().iter().copied() {
                    let Ok((m, _)) = build(&p, mode, coords, &pose) else {
                        continue;
                    };
                    built += 1;
                    assert!(
                        m.loads().is_empty(),
                        "the converter has no loads (LOADS = 0)"
                    );
                    let g = m.groups();
                    let needs = [
                        g.len(),
                        m.n_links(),
                        m.ground_points().len(),
                        m.links().iter().map(|l| l.points.len()).max().unwrap_or(0),
                        m.dof(),
                        g.iter().map(|g| g.chains.len()).max().unwrap_or(0),
                        g.iter()
                            .flat_map(|g| g.chains.iter().map(|c| c.terms.len()))
                            .max()
                            .unwrap_or(0),
                        g.iter().map(|g| g.joints.len()).max().unwrap_or(0),
                        g.iter().map(|g| g.placements.len()).max().unwrap_or(0),
                    ];
                    for (m, n) in most.iter_mut().zip(needs) {
                        *m = (*m).max(n);
                    }
                }
            }
        }
        assert!(built >= 20, "{built} models built");
        assert_eq!(
            most,
            [
                GROUPS,
                LINKS,
                GROUND_POINTS,
                LINK_POINTS,
                DOF,
                CHAINS,
                TERMS,
                GROUP_JOINTS,
                GROUP_LINKS
            ]
        );
    }
}
