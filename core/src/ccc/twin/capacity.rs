//! What the converter's mode models need of the core's capacities
//! ([`config`](crate::config)), checked against them at compile time: the largest of
//! every mode and coordinate choice (the test below builds them all). The twin's slots
//! hold models and workspaces sized by the generic limits; these are what one sized for
//! the converter needs.

use crate::config::{
    MAX_BODIES, MAX_CHAINS, MAX_DOF, MAX_GROUND_POINTS, MAX_GROUPS, MAX_GROUP_JOINTS,
    MAX_GROUP_LINKS, MAX_GROUP_VARS, MAX_LINKS, MAX_LINK_POINTS, MAX_TERMS,
};

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
