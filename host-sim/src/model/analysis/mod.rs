//! Automatic structomatic analysis (issue 5): from a mechanism's joints and its drivers,
//! the motion-transmission sequence of groups, which the thesis finds by hand "by trial
//! and error" (section 3.1.1).
//!
//! The search is bounded and deterministic. Starting from the ground as the only known
//! body, it repeatedly places the smallest group of the library whose links join only
//! bodies already known:
//! 1. a motor element (1 link): the first driver, in file order, whose joint's other
//!    body is known: R on a revolute joint, T on a prismatic one;
//! 2. a dyad (2 links, 3 joints): the first pair of unknown links `(a, b)`, `a < b` in
//!    file order, with exactly one joint between them and one from each to a known body
//!    (RRR, RRT, RTR, RTT, TRT by the kinds and orientations of the three joints);
//! 3. a triad RR-RR-RR (4 links, 6 revolute joints): the first ternary link (file
//!    order) and the first three binary links joined to it, each also joined to a known
//!    body.
//!
//! Links with a driver are placed only by their motor element. Each step places at least
//! one link, so the search ends after at most as many steps as links. What is left when
//! no group fits is reported with its links and joints. General Assur groups of more
//! than four links ([`structomat::structomat::AssurGroup`]) are not searched: a
//! mechanism that needs one is reported as left over.
//!
//! Each placed group maps to the core's group spec, and the sequence becomes a
//! [`structomat::Model`] whose formula names the groups, so host and core agree on the
//! names (`build.rs`).

mod build;

pub(crate) use build::build_model_with;
pub use build::{build_model, report, scenario, BuildError};

use super::runfile::{JointKind, Mechanism};
use std::fmt;
use structomat::config::MAX_GROUPS;
use structomat::structomat::GroupKind;

/// A group of the sequence and the roles of its links and joints (indices: links are
/// bodies `1..`, joints index [`Mechanism::joints`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placed {
    /// Motor element R: `link` turns about joint `joint`; coordinate `driver`.
    MotorR {
        /// The driven link.
        link: usize,
        /// Its revolute joint to a known body.
        joint: usize,
        /// The driver (coordinate) index.
        driver: usize,
    },
    /// Motor element T: `link` slides along joint `joint`; coordinate `driver`.
    MotorT {
        /// The driven slider.
        link: usize,
        /// Its prismatic joint on a known guide.
        joint: usize,
        /// The driver (coordinate) index.
        driver: usize,
    },
    /// RRR: `a` on a known pole by `ja`, `b` by `jb`, joined by `jab`.
    Rrr {
        /// First link.
        a: usize,
        /// Second link.
        b: usize,
        /// `a` to a known body.
        ja: usize,
        /// `b` to a known body.
        jb: usize,
        /// `a` to `b`.
        jab: usize,
    },
    /// RRT: `rod` on a known pole by `jp`, pinned to `slider` by `jc`; `slider` runs on
    /// a known guide by `jg`.
    Rrt {
        /// The rod.
        rod: usize,
        /// The slider.
        slider: usize,
        /// Rod to a known body (revolute).
        jp: usize,
        /// Rod to slider (revolute).
        jc: usize,
        /// Slider on a known guide (prismatic).
        jg: usize,
    },
    /// RTR: `block` on a known pole by `ja` slides along `guide` (on a known pole by
    /// `jb`) by `jab`.
    Rtr {
        /// The sliding block.
        block: usize,
        /// The guide link.
        guide: usize,
        /// Block to a known body (revolute).
        ja: usize,
        /// Guide link to a known body (revolute).
        jb: usize,
        /// Block on the guide link (prismatic).
        jab: usize,
    },
    /// RTT: `a` on a known pole by `ja` slides in `b` by `jab`; `b` runs on a known
    /// guide by `jb`.
    Rtt {
        /// The link on the pole.
        a: usize,
        /// The slider on the known guide.
        b: usize,
        /// `a` to a known body (revolute).
        ja: usize,
        /// `a` on `b` (prismatic).
        jab: usize,
        /// `b` on a known guide (prismatic).
        jb: usize,
    },
    /// TRT: sliders `a` and `b` on known guides (`ja`, `jb`), pinned together (`jab`).
    Trt {
        /// First slider.
        a: usize,
        /// Second slider.
        b: usize,
        /// `a` on its guide.
        ja: usize,
        /// `b` on its guide.
        jb: usize,
        /// The pin.
        jab: usize,
    },
    /// RR-RR-RR: three binary links, each on a known pole (`jk`) and pinned to the
    /// ternary link (`jt`).
    Triad {
        /// The ternary link.
        ternary: usize,
        /// The binary links.
        binary: [usize; 3],
        /// Binary link `i` to the ternary link.
        jt: [usize; 3],
        /// Binary link `i` to a known body.
        jk: [usize; 3],
    },
}

impl Placed {
    /// The group's kind (the core's symbol).
    pub fn kind(&self) -> GroupKind {
        match self {
            Placed::MotorR { .. } => GroupKind::MotorR,
            Placed::MotorT { .. } => GroupKind::MotorT,
            Placed::Rrr { .. } => GroupKind::Rrr,
            Placed::Rrt { .. } => GroupKind::Rrt,
            Placed::Rtr { .. } => GroupKind::Rtr,
            Placed::Rtt { .. } => GroupKind::Rtt,
            Placed::Trt { .. } => GroupKind::Trt,
            Placed::Triad { .. } => GroupKind::Triad,
        }
    }

    /// Its links, in role order.
    pub fn links(&self) -> Vec<usize> {
        match *self {
            Placed::MotorR { link, .. } | Placed::MotorT { link, .. } => vec![link],
            Placed::Rrr { a, b, .. } | Placed::Rtt { a, b, .. } | Placed::Trt { a, b, .. } => {
                vec![a, b]
            }
            Placed::Rrt { rod, slider, .. } => vec![rod, slider],
            Placed::Rtr { block, guide, .. } => vec![block, guide],
            Placed::Triad {
                ternary, binary, ..
            } => vec![binary[0], binary[1], binary[2], ternary],
        }
    }

    /// Its joints.
    pub fn joints(&self) -> Vec<usize> {
        match *self {
            Placed::MotorR { joint, .. } | Placed::MotorT { joint, .. } => vec![joint],
            Placed::Rrr { ja, jb, jab, .. }
            | Placed::Rtr { ja, jb, jab, .. }
            | Placed::Rtt { ja, jb, jab, .. }
            | Placed::Trt { ja, jb, jab, .. } => vec![ja, jab, jb],
            Placed::Rrt { jp, jc, jg, .. } => vec![jp, jc, jg],
            Placed::Triad { jt, jk, .. } => vec![jk[0], jt[0], jk[1], jt[1], jk[2], jt[2]],
        }
    }
}

/// The result of the analysis: the sequence and the degrees of freedom.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    /// The groups in motion-transmission order.
    pub groups: Vec<Placed>,
    /// Grübler's count for planar lower pairs: `3 n - 2 j`.
    pub dof: i64,
    /// Moving links `n`.
    pub links: usize,
    /// Revolute joints.
    pub revolute: usize,
    /// Prismatic joints.
    pub prismatic: usize,
}

/// Why no sequence of the library's groups solves a mechanism.
#[derive(Clone, Debug, PartialEq)]
pub enum AnalysisError {
    /// Grübler's count and the number of drivers differ.
    Drivers {
        /// Grübler's DOF.
        dof: i64,
        /// Drivers in the file.
        drivers: usize,
        /// `3·n − 2·(revolute + prismatic) = dof`, spelled out.
        count: String,
    },
    /// Links that no group of the library places.
    Leftover {
        /// The groups found before the search stopped (formula-like names).
        placed: Vec<String>,
        /// The links left over (names).
        links: Vec<String>,
        /// The joints not in any group (names).
        joints: Vec<String>,
        /// Drivers not placed (their links).
        drivers: Vec<String>,
    },
    /// Every link is placed but joints are left over (an over-constrained mechanism).
    Redundant {
        /// The joints not in any group.
        joints: Vec<String>,
    },
    /// Too many groups for the core ([`MAX_GROUPS`]).
    Capacity(usize),
}

impl fmt::Display for AnalysisError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AnalysisError::Drivers {
                dof,
                drivers,
                count,
            } => {
                let what = if (*drivers as i64) < *dof {
                    "too few drivers"
                } else {
                    "too many drivers"
                };
                write!(
                    f,
                    "{what}: Grübler's count gives {dof} degrees of freedom ({count}), the file has {drivers} driver(s)"
                )
            }
            AnalysisError::Leftover {
                placed,
                links,
                joints,
                drivers,
            } => {
                write!(
                    f,
                    "no group of the library (motor elements R, T; dyads RRR, RRT, RTR, RTT, TRT; triad RR-RR-RR) places links {} (joints left: {})",
                    links.join(", "),
                    if joints.is_empty() { "none".to_string() } else { joints.join(", ") }
                )?;
                if !drivers.is_empty() {
                    write!(f, "; drivers not placed: {}", drivers.join(", "))?;
                }
                write!(
                    f,
                    "; placed so far: Z(0){}",
                    placed.iter().map(|p| format!(" + {p}")).collect::<String>()
                )
            }
            AnalysisError::Redundant { joints } => write!(
                f,
                "every link is placed but joints {} are in no group (the mechanism is over-constrained)",
                joints.join(", ")
            ),
            AnalysisError::Capacity(n) => write!(
                f,
                "the sequence needs {n} groups, the core holds at most {MAX_GROUPS}"
            ),
        }
    }
}

impl std::error::Error for AnalysisError {}

/// Finds the motion-transmission sequence of `m` (see the module docs).
pub fn analyze(m: &Mechanism) -> Result<Analysis, AnalysisError> {
    let n = m.links.len();
    let revolute = m.joints.iter().filter(|j| j.kind.is_revolute()).count();
    let prismatic = m.joints.len() - revolute;
    let dof = 3 * n as i64 - 2 * m.joints.len() as i64;
    if dof != m.drivers.len() as i64 {
        return Err(AnalysisError::Drivers {
            dof,
            drivers: m.drivers.len(),
            count: format!("3·{n} − 2·({revolute} revolute + {prismatic} prismatic) = {dof}"),
        });
    }
    let mut s = Search {
        m,
        known: vec![false; n + 1],
        used: vec![false; m.joints.len()],
        driven: vec![None; n + 1],
        placed_driver: vec![false; m.drivers.len()],
    };
    s.known[0] = true;
    for (k, d) in m.drivers.iter().enumerate() {
        if let Some(slot) = s.driven.get_mut(d.link) {
            *slot = Some(k);
        }
    }
    let mut groups = Vec::new();
    // Each round places at least one link: at most n rounds.
    for _ in 0..n {
        let next = s.motor().or_else(|| s.dyad()).or_else(|| s.triad());
        let Some(g) = next else { break };
        for l in g.links() {
            s.known[l] = true;
        }
        for j in g.joints() {
            s.used[j] = true;
        }
        if let Placed::MotorR { driver, .. } | Placed::MotorT { driver, .. } = g {
            s.placed_driver[driver] = true;
        }
        groups.push(g);
    }
    let unused_joints: Vec<String> = (0..m.joints.len())
        .filter(|&j| !s.used[j])
        .map(|j| format!("\"{}\"", m.joints[j].name))
        .collect();
    if s.known.iter().any(|k| !k) {
        return Err(AnalysisError::Leftover {
            placed: groups.iter().map(name).collect(),
            links: (1..=n)
                .filter(|&b| !s.known[b])
                .map(|b| m.body_name(b))
                .collect(),
            joints: unused_joints,
            drivers: (0..m.drivers.len())
                .filter(|&d| !s.placed_driver[d])
                .map(|d| format!("driver[{d}] on {}", m.body_name(m.drivers[d].link)))
                .collect(),
        });
    }
    if !unused_joints.is_empty() {
        return Err(AnalysisError::Redundant {
            joints: unused_joints,
        });
    }
    if groups.len() > MAX_GROUPS {
        return Err(AnalysisError::Capacity(groups.len()));
    }
    Ok(Analysis {
        groups,
        dof,
        links: n,
        revolute,
        prismatic,
    })
}

/// A group's name as the core's formula writes it, `RRR(2,3)` (links ascending).
fn name(g: &Placed) -> String {
    let mut links = g.links();
    links.sort_unstable();
    let l: Vec<String> = links.iter().map(|l| l.to_string()).collect();
    format!("{}({})", g.kind().symbol(), l.join(","))
}

struct Search<'a> {
    m: &'a Mechanism,
    /// Known bodies (index 0: the ground).
    known: Vec<bool>,
    /// Joints already in a group.
    used: Vec<bool>,
    /// The driver of each body, if any.
    driven: Vec<Option<usize>>,
    placed_driver: Vec<bool>,
}

impl Search<'_> {
    fn other(&self, j: usize, body: usize) -> usize {
        let [p, q] = self.m.joints[j].kind.bodies();
        if p == body {
            q
        } else {
            p
        }
    }

    /// Unplaced links without a driver (a driven link is placed by its motor element).
    fn free(&self, b: usize) -> bool {
        !self.known[b] && self.driven[b].is_none()
    }

    /// Unused joints of `body` whose other body is known or in `set`.
    fn closing(&self, body: usize, set: &[usize]) -> Vec<usize> {
        (0..self.m.joints.len())
            .filter(|&j| !self.used[j] && self.m.joints[j].kind.bodies().contains(&body))
            .filter(|&j| {
                let o = self.other(j, body);
                self.known[o] || set.contains(&o)
            })
            .collect()
    }

    fn motor(&self) -> Option<Placed> {
        self.m.drivers.iter().enumerate().find_map(|(driver, d)| {
            if self.placed_driver[driver] || self.known[d.link] {
                return None;
            }
            let joint = d.joint;
            if !self.known[self.other(joint, d.link)] {
                return None;
            }
            let link = d.link;
            Some(match self.m.joints[joint].kind {
                JointKind::Revolute { .. } => Placed::MotorR {
                    link,
                    joint,
                    driver,
                },
                JointKind::Prismatic { .. } => Placed::MotorT {
                    link,
                    joint,
                    driver,
                },
            })
        })
    }

    fn dyad(&self) -> Option<Placed> {
        let n = self.m.links.len();
        for a in 1..=n {
            if !self.free(a) {
                continue;
            }
            for b in a + 1..=n {
                if !self.free(b) {
                    continue;
                }
                if let Some(g) = self.dyad_of(a, b) {
                    return Some(g);
                }
            }
        }
        None
    }

    /// The dyad of links `a`, `b`, if their closing joints are exactly one between them
    /// and one from each to a known body, in a combination of the library.
    fn dyad_of(&self, a: usize, b: usize) -> Option<Placed> {
        let set = [a, b];
        let ca = self.closing(a, &set);
        let cb = self.closing(b, &set);
        let between: Vec<usize> = ca.iter().copied().filter(|&j| cb.contains(&j)).collect();
        let to_known = |c: &[usize]| -> Vec<usize> {
            c.iter().copied().filter(|j| !between.contains(j)).collect()
        };
        let (ka, kb) = (to_known(&ca), to_known(&cb));
        let ([jab], [ja], [jb]) = (between.as_slice(), ka.as_slice(), kb.as_slice()) else {
            return None;
        };
        let (jab, ja, jb) = (*jab, *ja, *jb);
        let kind = |j: usize| self.m.joints[j].kind;
        // The sliding body of a prismatic joint (its guide is on the other body).
        let slides = |j: usize, body: usize| match kind(j) {
            JointKind::Prismatic { slider, .. } => slider.body == body,
            JointKind::Revolute { .. } => false,
        };
        let r = |j: usize| kind(j).is_revolute();
        match (r(ja), r(jab), r(jb)) {
            (true, true, true) => Some(Placed::Rrr { a, b, ja, jb, jab }),
            (true, true, false) if slides(jb, b) => Some(Placed::Rrt {
                rod: a,
                slider: b,
                jp: ja,
                jc: jab,
                jg: jb,
            }),
            (false, true, true) if slides(ja, a) => Some(Placed::Rrt {
                rod: b,
                slider: a,
                jp: jb,
                jc: jab,
                jg: ja,
            }),
            (true, false, true) => {
                let (block, guide, ja, jb) = if slides(jab, a) {
                    (a, b, ja, jb)
                } else {
                    (b, a, jb, ja)
                };
                Some(Placed::Rtr {
                    block,
                    guide,
                    ja,
                    jb,
                    jab,
                })
            }
            (true, false, false) if slides(jab, a) && slides(jb, b) => {
                Some(Placed::Rtt { a, b, ja, jab, jb })
            }
            (false, false, true) if slides(jab, b) && slides(ja, a) => Some(Placed::Rtt {
                a: b,
                b: a,
                ja: jb,
                jab,
                jb: ja,
            }),
            (false, true, false) if slides(ja, a) && slides(jb, b) => {
                Some(Placed::Trt { a, b, ja, jb, jab })
            }
            _ => None,
        }
    }

    fn triad(&self) -> Option<Placed> {
        let n = self.m.links.len();
        for t in 1..=n {
            if !self.free(t) {
                continue;
            }
            // Binary candidates: free links with one revolute joint to t.
            let cands: Vec<(usize, usize)> = (0..self.m.joints.len())
                .filter(|&j| !self.used[j] && self.m.joints[j].kind.is_revolute())
                .filter(|&j| self.m.joints[j].kind.bodies().contains(&t))
                .map(|j| (self.other(j, t), j))
                .filter(|&(b, _)| b != 0 && self.free(b))
                .collect();
            let k = cands.len();
            for x in 0..k {
                for y in x + 1..k {
                    for z in y + 1..k {
                        let pick = [cands[x], cands[y], cands[z]];
                        if let Some(g) = self.triad_of(t, pick) {
                            return Some(g);
                        }
                    }
                }
            }
        }
        None
    }

    fn triad_of(&self, t: usize, pick: [(usize, usize); 3]) -> Option<Placed> {
        let mut binary = pick.map(|p| p.0);
        let jt = pick.map(|p| p.1);
        if binary[0] == binary[1] || binary[1] == binary[2] || binary[0] == binary[2] {
            return None;
        }
        let set = [t, binary[0], binary[1], binary[2]];
        let mut ct = self.closing(t, &set);
        ct.sort_unstable();
        let mut want = jt.to_vec();
        want.sort_unstable();
        if ct != want {
            return None;
        }
        let mut jk = [0usize; 3];
        for (i, &b) in binary.iter().enumerate() {
            let c = self.closing(b, &set);
            let others: Vec<usize> = c.into_iter().filter(|j| *j != jt[i]).collect();
            let [k] = others.as_slice() else { return None };
            let o = self.other(*k, b);
            if !(self.known[o] && self.m.joints[*k].kind.is_revolute()) {
                return None;
            }
            jk[i] = *k;
        }
        // Keep the binary links in file order with their joints.
        let mut order = [0usize, 1, 2];
        order.sort_by_key(|&i| binary[i]);
        let (jt, jk) = (order.map(|i| jt[i]), order.map(|i| jk[i]));
        binary = order.map(|i| binary[i]);
        Some(Placed::Triad {
            ternary: t,
            binary,
            jt,
            jk,
        })
    }
}
