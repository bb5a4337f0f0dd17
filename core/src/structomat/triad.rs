//! Triad RR-RR-RR (thesis figures 11c and 20c): three binary links on known poles
//! K1, K2, K3, joined to a ternary link at its points T1, T2, T3.
//!
//! Loop closures (two chains from K1):
//! `K1 + R(θ1)(T_1 - K_1) + R(θt)(t2 - t1) - R(θ2)(T_2 - K_2) - K2 = 0` and the same to K3
//! through `t3`; unknowns `x = (θ1, θ2, θ3, θt)`. No closed form in general (the
//! assembly is a root of a degree-6 polynomial): Newton-Raphson, bounded and warm-started
//! from the last configuration ([`newton`](super::newton)).

use super::{
    extend, guesses, push_chain, Angle, Base, Group, GroupKind, Joint, JointKind, Placement,
    PointRef, Term,
};
use crate::capacity::Capacity;
use crate::error::ModelError;
use crate::model::{Model, Points, WriteGroup};
use crate::scalar::Real;

/// Triad RR-RR-RR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriadRrRrRr<T: Real> {
    /// The ternary link (body index).
    pub ternary: u8,
    /// The ternary link's points where binary links 1, 2, 3 attach.
    pub ternary_joints: [u8; 3],
    /// The binary links (body indices).
    pub binary: [u8; 3],
    /// Each binary link's point at its pole.
    pub binary_at_pole: [u8; 3],
    /// Each binary link's point at the ternary link.
    pub binary_at_ternary: [u8; 3],
    /// The known poles K1, K2, K3.
    pub poles: [PointRef; 3],
    /// Guesses of `(θ1, θ2, θ3, θt)`, rad: the starting point of Newton-Raphson, which
    /// picks the assembly branch.
    pub guess: [T; 4],
}

impl<T: Real> TriadRrRrRr<T> {
    /// Builds the group's description.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let mut g = Group::empty();
        self.write(&model.points(), &mut g)?;
        Ok(g)
    }
}

impl<T: Real> WriteGroup<T> for TriadRrRrRr<T> {
    /// [`TriadRrRrRr::build`], in place.
    fn write(&self, model: &Points<'_, T>, g: &mut Group<T>) -> Result<(), ModelError> {
        let mut kp = [nalgebra::Vector2::zeros(); 3];
        let mut tp = kp;
        let mut tt = kp;
        let mut world = kp;
        for k in 0..3 {
            kp[k] = model.local(
                self.binary[k],
                self.binary_at_pole[k],
                "triad: binary at pole",
            )?;
            tp[k] = model.local(
                self.binary[k],
                self.binary_at_ternary[k],
                "triad: binary at ternary",
            )?;
            tt[k] = model.local(self.ternary, self.ternary_joints[k], "triad: ternary joint")?;
            world[k] = model.resolve(self.poles[k], "triad: pole")?;
            if !((tp[k] - kp[k]).norm() > T::zero()) {
                return Err(ModelError::Degenerate(
                    "triad: a binary link's joints coincide",
                ));
            }
        }
        if !((tt[1] - tt[0]).norm() > T::zero() && (tt[2] - tt[0]).norm() > T::zero()) {
            return Err(ModelError::Degenerate(
                "triad: the ternary link's joints coincide",
            ));
        }
        let ang = |k: u8| Angle::of(Base::Var(k));
        let chain_to = |g: &mut Group<T>, k: usize, var: u8| {
            push_chain(
                g,
                self.poles[0],
                &[
                    Term::Arm {
                        angle: ang(0),
                        v: tp[0] - kp[0],
                    },
                    Term::Arm {
                        angle: ang(3),
                        v: tt[k] - tt[0],
                    },
                    Term::Arm {
                        angle: ang(var),
                        v: -(tp[k] - kp[k]),
                    },
                ],
                Some(self.poles[k]),
            )
        };
        let mut joints = [Joint {
            i: 0,
            pi: kp[0],
            j: 0,
            pj: kp[0],
            kind: JointKind::Revolute,
        }; 6];
        for k in 0..3 {
            joints[k] = Joint {
                i: self.binary[k],
                pi: kp[k],
                j: self.poles[k].body,
                pj: world[k],
                kind: JointKind::Revolute,
            };
            joints[3 + k] = Joint {
                i: self.binary[k],
                pi: tp[k],
                j: self.ternary,
                pj: tt[k],
                kind: JointKind::Revolute,
            };
        }
        g.kind = GroupKind::Triad;
        g.n_vars = 4;
        chain_to(g, 1, 1)?;
        chain_to(g, 2, 2)?;
        extend(
            &mut g.placements,
            &[
                Placement {
                    link: self.binary[0],
                    angle: ang(0),
                    chain: 0,
                    prefix: 0,
                    local: kp[0],
                },
                Placement {
                    link: self.ternary,
                    angle: ang(3),
                    chain: 0,
                    prefix: 1,
                    local: tt[0],
                },
                Placement {
                    link: self.binary[1],
                    angle: ang(1),
                    chain: 0,
                    prefix: 2,
                    local: tp[1],
                },
                Placement {
                    link: self.binary[2],
                    angle: ang(2),
                    chain: 1,
                    prefix: 2,
                    local: tp[2],
                },
            ],
            "placements",
        )?;
        extend(&mut g.joints, &joints, "joints")?;
        g.guess = guesses(&self.guess);
        Ok(())
    }
}
