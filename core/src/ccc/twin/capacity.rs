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

impl<T: Real> Capacity<T> for Converter {
    type GroundPoints = heapless::Vec<Vec2<T>, GROUND_POINTS>;
    type Links = heapless::Vec<Link<T>, LINKS>;
    type Groups = heapless::Vec<Group<T>, GROUPS>;
    type Loads = heapless::Vec<Load<T>, LOADS>;
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

#[cfg(test)]
mod tests {
    use super::*;
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
