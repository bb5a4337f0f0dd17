//! Capacities of the fixed-size data, in one place (heapless/smoltcp habit).
//!
//! Every array in a [`Model`](crate::model::Model) and a
//! [`Workspace`](crate::workspace::Workspace) is sized by these constants: nothing is
//! allocated at run time. They fit the thesis's mechanisms with room to spare (the CCC
//! has 8 moving links, 5 groups and 2 degrees of freedom).

/// Moving links of a mechanism (bodies `1..=MAX_LINKS`; body 0 is the ground).
pub const MAX_LINKS: usize = 12;
/// Bodies: the ground plus the moving links.
pub const MAX_BODIES: usize = MAX_LINKS + 1;
/// Points (joint locations and extra points) on one link, including its two ends.
pub const MAX_LINK_POINTS: usize = 6;
/// Fixed points on the ground (the zero-pole).
pub const MAX_GROUND_POINTS: usize = 12;
/// Groups (structomats) in a motion-transmission sequence.
pub const MAX_GROUPS: usize = 8;
/// Degrees of freedom (generalized coordinates) of a mechanism.
pub const MAX_DOF: usize = 3;
/// Size of the integrated state `[q, q̇]`.
pub const STATE_DIM: usize = 2 * MAX_DOF;
/// Links in one group: 4 for the triad RR-RR-RR, 6 for the converter's A68 group.
pub const MAX_GROUP_LINKS: usize = 6;
/// Unknowns of one group (link angles, slider offsets): 4 for the triad, 6 for the
/// converter's crank-driven A68 group (see [`AssurGroup`](crate::structomat::AssurGroup)).
pub const MAX_GROUP_VARS: usize = 6;
/// Vector chains of one group: two closing loops for the triad, three for A68's group.
pub const MAX_CHAINS: usize = 3;
/// Terms (rotating arms and slides) in one chain.
pub const MAX_TERMS: usize = 4;
/// Joints of one group: 6 revolute joints for the triad, 9 for A68's group.
pub const MAX_GROUP_JOINTS: usize = 9;
/// Rows of the stacked pose vector `P` (`x_G, y_G, θ` per moving link).
pub const POSE_ROWS: usize = 3 * MAX_LINKS;
/// External loads (force and moment on a link) in a model.
pub const MAX_LOADS: usize = 8;
/// Motor elements that carry a motor model.
pub const MAX_DRIVES: usize = MAX_DOF;

/// Newton-Raphson iterations allowed for one group's position problem. Warm-started
/// from the previous configuration it converges in 2-4; the bound makes the worst case
/// of a step finite.
pub const NEWTON_MAX_ITER: u32 = 30;
