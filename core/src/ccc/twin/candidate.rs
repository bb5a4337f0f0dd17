//! One candidate mode of the mode choice, built and judged: where it is built (the
//! reference model itself, or the coordinate choice that carries the projected speeds),
//! its evaluation, and its violation of SPEC 3's consistency conditions.

use super::super::build::{driving_link, dyads_conditioning};
use super::super::mode::{Coordinates, Mode};
use super::consistency::{torques_clear, Touch};
use super::error::TwinStepError;
use super::inputs::Inputs;
use super::settings::*;
use super::slot::QD;
use super::{load_state, same_bits, Twin, Work};
use crate::dynamics::finish_accelerations;
use crate::kinetostatics::reactions;
use crate::scalar::Real;
use nalgebra::SVector;

impl<T: Real> Twin<T> {
    /// Builds mode `m` into the candidate slot at `pose` with the projected speeds
    /// `u_plus` (reference coordinates), evaluates it and judges it by SPEC 3's
    /// consistency conditions ([`Candidate`]); `screened`: its clutch torques from the
    /// screen, which spare its kinetostatics if they are clear of the thresholds.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn try_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        pose: &[T; 9],
        u_plus: &SVector<T, 3>,
        from: Mode,
        inputs: &Inputs<T>,
        touch: Touch<T>,
        screened: Option<[T; 2]>,
    ) -> Result<Candidate<T>, TwinStepError> {
        // Physical angular speeds after the impact, from the reference model's V.
        let mut omega = [T::zero(); 9];
        for (p, o) in omega.iter_mut().enumerate().skip(1) {
            let [v0, v1] = self.slots.reference().omega_row(p);
            *o = v0 * u_plus[0] + v1 * u_plus[1];
        }
        let placed = self.place_candidate(w, m, pose, &omega, inputs, screened.is_some());
        // The kinetostatics (the clutch torques) of the choice taken only, and not
        // even of it when the screen's clutch torques are clear of the conditions'
        // thresholds: the signs that decide then read the same from either (they
        // differ by rounding), and the screen's torques stand for the model's until
        // the next full evaluation (8.3k instructions of S2's worst event step).
        // (Not with clutch drag: the held shaft's torque condition then has the
        // overrunning levers' drag as well, which `torques_clear` does not see.)
        let no_drag = self.params.friction.clutch_drag == T::zero();
        let clear = screened.filter(|c| no_drag && torques_clear(m, c, inputs));
        let place = placed.map_or(Place::Scratch, |(p, _)| p);
        let (cand, params) = match place {
            Place::Reference => (self.slots.reference_mut(), &self.params),
            Place::Scratch => self.scratch(w.switched),
        };
        let ok = placed.is_some() && {
            finish_accelerations(&cand.model, &mut cand.ws);
            clear.is_some() || reactions(&cand.model, &mut cand.ws, w.t.to_f64()).is_ok()
        };
        let Some((place, speed_gap)) = placed.filter(|_| ok) else {
            return Ok(Candidate::rejected(T::c(f64::INFINITY)));
        };
        let links = cand.links(params);
        let c = clear.unwrap_or_else(|| cand.clutch_torques(params, &links));
        let shaft = self.coast.omega;
        let coast = [shaft, self.coast_accel(&links, shaft, inputs.load)];
        crate::trace::debug!(
            "candidate {m}: c = {:?}, alpha6 = {:?}, alpha8 = {:?}",
            c,
            links[6].alpha,
            links[8].alpha,
        );
        Ok(Candidate {
            violation: self.violation(m, from, &c, &links, inputs, touch, coast),
            screened: clear,
            speed_gap,
            place,
        })
    }

    /// Places mode `m` at `pose` with the physical speeds `omega`, its equations of
    /// motion evaluated: in the reference model if that is the pick itself
    /// (`screened`: the reference's evaluation succeeded), else in the coordinate
    /// choice that assembles here, represents these speeds (a choice at its dead point
    /// maps them wrongly: the lever of A68 cannot carry a crank turning at its dead
    /// point) and is conditioned at least `switch_below`; else the best conditioned of
    /// those that carry the speeds (a later one only if 1.5 times better, as in
    /// `switch_coordinates`). Near its dead point a choice still carries the speeds,
    /// but the rest of the step in it is far off: A6 -> A68 with the lever at 0.003
    /// lost 0.45 J of kinetic energy in one step. Returns where it is and its speed
    /// gap (rad/s); `None` if no choice carries it.
    fn place_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        pose: &[T; 9],
        omega: &[T; 9],
        inputs: &Inputs<T>,
        screened: bool,
    ) -> Option<(Place, T)> {
        let scale_w = omega.iter().fold(T::one(), |a, w| a.max(w.abs()));
        // A choice whose coordinate link stands still (under `speed_tol` of the largest
        // speed) while the mechanism moves (a shaft stop can leave it all at rest) is
        // at its dead point: it fails to assemble,
        // cannot carry the speeds, or carries them through a velocity ratio over 1e6,
        // conditioned far below any other choice that assembles, which it would have
        // to beat by 1.5. So it is tried only if no other choice assembled. At S2's
        // catches into A68 from a held shaft the lever stops as it catches (the rocker
        // reverses): its choice failed to build each time (19k instructions).
        let still = |w: T| !(w.abs() > speed_tol::<T>() * scale_w);
        let moving = !omega.iter().all(|w| still(*w));
        let dead = |c: Coordinates| {
            moving
                && driving_link(m, c)
                    .is_some_and(|p| still(omega.get(p).copied().unwrap_or(T::zero())))
        };
        let choices = m.coordinate_choices();
        // The reference model may be the pick itself, the first choice of its mode,
        // evaluated at the candidate's state.
        let mut live = choices.iter().copied().filter(|c| !dead(*c));
        let (c1, c2) = (live.next(), live.next());
        let first = c1.or(choices.first().copied());
        if screened {
            if let Some(gap) = self.reference_is_candidate(w, m, first, omega, scale_w) {
                return Some((Place::Reference, gap));
            }
        }
        // A dyads-only first choice whose conditioning at the pose (no build:
        // `dyads_conditioning`) is under `switch_below` is not the pick if the next
        // choice that assembles is conditioned at least `switch_below` and 1.5 times
        // better: that one is then built first, and alone. (S2's catch at 0.0632 s
        // built I6's swing choice, 0.13, before taking the crank's; the margins keep
        // rounding of the prediction from deciding.)
        let poor = c1
            .and_then(|c| dyads_conditioning(m, c, pose))
            .filter(|p| *p < self.settings.switch_below * T::c(1.0 - 1e-9));
        if let (Some(p), Some(c2)) = (poor, c2) {
            let load = Load {
                pose,
                omega,
                inputs,
                scale_w,
            };
            if let Some(gap) = self.load_candidate(w, m, c2, &load) {
                let cond = self.scratch(w.switched).0.conditioning();
                if cond >= self.settings.switch_below && cond > p * T::c(1.5 * (1.0 + 1e-9)) {
                    return Some((Place::Scratch, gap));
                }
            }
        }
        let ordered = choices
            .iter()
            .filter(|c| !dead(**c))
            .chain(choices.iter().filter(|c| dead(**c)))
            .map(|c| (*c, dead(*c)));
        let load = Load {
            pose,
            omega,
            inputs,
            scale_w,
        };
        self.scan_candidate(w, m, ordered, &load)
            .map(|gap| (Place::Scratch, gap))
    }

    /// Builds mode `m` in the coordinate choices `ordered` (each with whether it is at
    /// its dead point) in turn, keeps the first conditioned at least `switch_below`,
    /// else the best (a later one only if 1.5 times better), and leaves it in the
    /// scratch slot; returns its speed gap (rad/s), `None` if none carries the speeds.
    fn scan_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        ordered: impl Iterator<Item = (Coordinates, bool)>,
        load: &Load<'_, T>,
    ) -> Option<T> {
        // (conditioning, choice, speed gap) of the choice taken, and whether the
        // scratch slot still holds it (a later choice built there overwrites it).
        // One slot is free for candidates: the other holds the reference model.
        let mut chosen: Option<(T, Coordinates, T)> = None;
        let mut kept = false;
        for (coords, dead) in ordered {
            if chosen.is_some() && dead {
                break;
            }
            let Some(gap) = self.load_candidate(w, m, coords, load) else {
                kept = false;
                continue;
            };
            let cond = self.scratch(w.switched).0.conditioning();
            if chosen.is_none_or(|(c, _, _)| cond > c * T::c(1.5)) {
                chosen = Some((cond, coords, gap));
                kept = true;
            } else {
                kept = false;
            }
            if chosen.is_some_and(|(c, _, _)| c >= self.settings.switch_below) {
                break;
            }
        }
        match (chosen, kept) {
            (Some((_, _, gap)), true) => Some(gap),
            // Overwritten by a later choice in the one free slot: built again at the
            // scan's pose and speeds.
            (Some((_, coords, _)), false) => self.load_candidate(w, m, coords, load),
            (None, _) => None,
        }
    }

    /// Whether the reference model is candidate `m` as [`Twin::try_candidate`] would
    /// build it: the same mode (I0) in `first`, the coordinate choice it tries first,
    /// conditioned at least `switch_below` (so the choice it would take) and evaluated
    /// exactly at the candidate's state (the coordinates at the pose, both models'
    /// `coordinates_at`, and the speeds `omega` of the coordinates' links, bit for
    /// bit), which it carries (its speed gap, returned, within the tolerance). Its evaluation is then the one a build would make: a dyads-only
    /// model at the same pose gives the same bits. At S2's shaft stops and releases
    /// into I0 this spares the build and evaluation of the candidate (~25k
    /// instructions) for a swap of the two slots ([`Twin::choose`]).
    pub(super) fn reference_is_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        first: Option<Coordinates>,
        omega: &[T; 9],
        scale_w: T,
    ) -> Option<T> {
        let r = self.slots.reference();
        if !(r.built
            && r.mode == m
            && Some(r.coords) == first
            && r.conditioning() >= self.settings.switch_below)
        {
            return None;
        }
        let q = [r.ws.q[0], r.ws.q[1]];
        let mut y = w.y;
        load_state(r, &q, omega, &mut y);
        let n = r.map.dof.min(2);
        let at_state =
            r.ws.qd
                .iter()
                .zip(y.iter().skip(QD))
                .take(n)
                .all(|(a, b)| same_bits(*a, *b));
        if !at_state {
            return None;
        }
        let mapped = r.links(&self.params);
        let off = (1..9).fold(T::zero(), |e, p| e.max((mapped[p].omega - omega[p]).abs()));
        (off <= speed_tol::<T>() * scale_w).then_some(off)
    }

    /// Builds mode `m` driven by `coords` at `load`'s pose with its physical speeds
    /// into the scratch slot ([`Twin::scratch`]), moving the model it holds if it is that one (see
    /// [`Slot::reposition`](super::slot::Slot::reposition)), and evaluates its equations of motion (not the
    /// kinetostatics); returns its speed gap (rad/s: the largest difference between a
    /// link's speed in the built model and the one it was given), `None` if it does
    /// not assemble, fails, or cannot carry the speeds.
    pub(super) fn load_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        coords: Coordinates,
        load: &Load<'_, T>,
    ) -> Option<T> {
        let time = w.t.to_f64();
        // A coasting candidate's shaft turns at its speed at the event.
        let (drive, lossy, shaft) = (self.drive, self.lossy, self.coast.omega);
        let (cand, params) = self.scratch(w.switched);
        let q = match cand.reposition(params, m, coords, load.pose, time) {
            Ok(q) => q,
            Err(e) => {
                crate::trace::debug!(
                    "candidate {m} in {coords} coordinates does not assemble: {e:?}"
                );
                return None;
            }
        };
        let omega = load.omega;
        let mut y = w.y;
        load_state(cand, &q, omega, &mut y);
        if cand
            .eval(
                w.t,
                &y,
                load.inputs,
                drive,
                lossy.then_some(&params.friction),
                shaft,
            )
            .is_err()
        {
            return None;
        }
        let mapped = cand.links(params);
        let off = (1..9).fold(T::zero(), |e, p| e.max((mapped[p].omega - omega[p]).abs()));
        if !(off <= speed_tol::<T>() * load.scale_w) {
            crate::trace::debug!("candidate {m} in {coords} coordinates cannot carry the speeds (off by {off:?} rad/s)");
            return None;
        }
        Some(off)
    }
}

/// What a candidate is built at: the pose (physical angles, rad), the physical
/// angular speeds (rad/s) and the inputs, and the largest speed (at least 1 rad/s), the
/// scale of the speed tolerance.
pub(super) struct Load<'a, T: Real> {
    pub pose: &'a [T; 9],
    pub omega: &'a [T; 9],
    pub inputs: &'a Inputs<T>,
    pub scale_w: T,
}

/// Where a candidate built by [`Twin::try_candidate`] is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Place {
    /// The scratch slot ([`Twin::scratch`]).
    Scratch,
    /// The reference model itself (I0 evaluated at the candidate's state): taking it
    /// swaps the reference and the scratch slot.
    Reference,
}

/// A candidate mode judged by [`Twin::try_candidate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Candidate<T> {
    /// How far it violates SPEC 3's consistency conditions (0: consistent; infinite:
    /// it could not be built).
    pub violation: T,
    /// Its clutch torques from the screen, N·m, if they stood for its kinetostatics.
    pub screened: Option<[T; 2]>,
    /// Largest difference between a link's speed in its model and the speed it should
    /// have after the impact projection, rad/s.
    pub speed_gap: T,
    /// Where it is held.
    pub place: Place,
}

impl<T: Real> Candidate<T> {
    /// A candidate not built (screened out, or not buildable), with its violation.
    pub(super) fn rejected(violation: T) -> Self {
        Candidate {
            violation,
            screened: None,
            speed_gap: T::zero(),
            place: Place::Scratch,
        }
    }
}
