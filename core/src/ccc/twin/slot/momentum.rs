//! The coordinates' rates of a motion given by the links' speeds: a coordinate switch
//! maps the state through them ([`Slot::nearest_rates`]).

use super::super::super::build::physical_link;
use super::super::super::params::CccParams;
use super::{LinkState, Slot};
use crate::scalar::{perp, rotate_cs, Real, Vec2};

impl<T: Real> Slot<T> {
    /// The coordinates' rates whose motion is nearest the physical `links`' in kinetic
    /// energy, at the slot's last evaluated positions and `V`: `q̇ = (VᵀMV)⁻¹ VᵀM v`
    /// (the generalized momentum of `v` over the generalized mass), where `v` are the
    /// links' centre-of-mass and angular speeds and `M` the audit's masses and inertias,
    /// link by link (A68's joined levers each with its own centre of mass, on their
    /// body's rotation), and the shaft's `J_s` on the shaft's speed. Where `links` are a
    /// motion of this slot's mechanism the rates are that motion's; where rounding
    /// leaves them a little off it, the energy of the result is theirs less the `M`-norm
    /// of the difference, a second-order loss. (Reading one link's speed as its
    /// coordinate's rate carries that speed's rounding into every other link through
    /// the transmission, at first order: in f32 at 20/200 N·m, a switch from A68's crank
    /// near its dead point moved the kinetic energy by 2.5e-3 of it.) `None` where
    /// `VᵀMV` is singular. Not inlined: a coordinate switch is rare, and inlined into
    /// the switch it deepened the M7 step's painted stack by 0.4 KB.
    #[inline(never)]
    pub fn nearest_rates(
        &self,
        params: &CccParams<T>,
        links: &[LinkState<T>; 9],
    ) -> Option<[T; 2]> {
        let n = self.map.dof.min(2);
        let v = &self.ws.v;
        let at = |r: usize, c: usize| v.get((r, c)).copied().unwrap_or_else(T::zero);
        // Body `b`'s COG and angular speed per unit rate of coordinate `c`.
        let col = |b: usize, c: usize| {
            let r = 3 * (b - 1);
            (Vec2::new(at(r, c), at(r + 1, c)), at(r + 2, c))
        };
        let (mut g, mut p) = ([[T::zero(); 2]; 2], [T::zero(); 2]);
        let mut add =
            |mass: T, inertia: T, rows: &dyn Fn(usize) -> (Vec2<T>, T), vg: Vec2<T>, w: T| {
                for (i, (pi, gi)) in p.iter_mut().zip(g.iter_mut()).enumerate().take(n) {
                    let (ui, wi) = rows(i);
                    *pi += mass * ui.dot(&vg) + inertia * wi * w;
                    for (j, gij) in gi.iter_mut().enumerate().take(n) {
                        let (uj, wj) = rows(j);
                        *gij += mass * ui.dot(&uj) + inertia * wi * wj;
                    }
                }
            };
        for (k, s) in links.iter().enumerate().skip(1) {
            let b = self.body(k) as usize;
            let (Some(body), Some(model)) = (self.ws.body.get(b), self.model.link(b as u8)) else {
                continue;
            };
            let l = physical_link(params, k);
            let f = self.frame(k);
            let (r, vg) = s.point_motion(&f, &l.cog);
            // The link's COG from its body's, both from the common frame origin.
            let d = perp(&(r - rotate_cs(body.c, body.s, &model.cog)));
            let rows = |c: usize| {
                let (u, w) = col(b, c);
                (u + d * w, w)
            };
            add(l.mass, l.inertia, &rows, vg, s.omega);
        }
        if let Some(b) = self.shaft_body().filter(|b| *b != 0) {
            // The shaft turns with the engaged lever (its speed is that lever's).
            let shaft = links.get(self.map.phys.get(b as usize).copied().unwrap_or(0) as usize);
            let w = shaft.map_or(T::zero(), |s| s.omega);
            let rows = |c: usize| (Vec2::zeros(), col(b as usize, c).1);
            add(T::zero(), params.shaft_inertia, &rows, Vec2::zeros(), w);
        }
        let rates = match n {
            1 => [p[0] / g[0][0], T::zero()],
            _ => {
                let det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
                [
                    (g[1][1] * p[0] - g[0][1] * p[1]) / det,
                    (g[0][0] * p[1] - g[1][0] * p[0]) / det,
                ]
            }
        };
        rates.iter().all(|r| r.finite()).then_some(rates)
    }
}
