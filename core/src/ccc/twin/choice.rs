//! The mode choice at an event (SPEC 3): candidates in order of preference, each built
//! and judged by the consistency conditions, the first consistent one taken.

use super::super::build::BRANCHES;
use super::super::mode::{Clutch, Mode};
use super::candidate::{Candidate, Place};
use super::coast::Coast;
use super::consistency::Touch;
use super::coordinates::best_slot;
use super::error::TwinStepError;
use super::evaluate::{Stage, Torques};
use super::guards::{Event, EventKind};
use super::impact::{constraint_rows, project, rows_mismatch};
use super::inputs::Inputs;
use super::settings::*;
use super::slot::unwrap_near;
use super::slot::{LinkState, QD, STATE};
use super::slots::Slots;
use super::{joint_gap, shaft_turn, Twin, Work};
use crate::scalar::Real;
use nalgebra::{SMatrix, SVector};

/// Lower is preferred: whether the candidate agrees with the event that fired (0) or
/// not (1), then how many clutches and shaft states change from the current mode.
pub(super) fn preference(from: Mode, to: Mode, kind: EventKind) -> u8 {
    let c = to.clutches();
    let agrees = match kind {
        EventKind::Catch(l) => c[if l == 6 { 0 } else { 1 }] != Clutch::Free,
        EventKind::Release(l) => c[if l == 6 { 0 } else { 1 }] == Clutch::Free,
        EventKind::Breakaway => to.shaft_turning(),
        EventKind::ShaftStop => !to.shaft_turning(),
        EventKind::Start | EventKind::Inputs => true,
    };
    let changes = from
        .clutches()
        .iter()
        .zip(c.iter())
        .filter(|(a, b)| a != b)
        .count() as u8
        + u8::from(from.shaft_turning() != to.shaft_turning());
    (if agrees { 0 } else { 8 }) + changes
}

impl<T: Real> Twin<T> {
    /// Chooses the consistent mode at `w`'s state (the current slot evaluated there)
    /// after event `kind`, projects the speeds if the new constraints need it (plastic
    /// impact), and switches to it.
    pub(super) fn choose(
        &mut self,
        w: &mut Work<T>,
        kind: EventKind,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        let from = self.slots.cur().mode;
        let pose = self.slot_links_unwrapped();
        let links = self.slots.cur().links(&self.params);
        // A coasting shaft's motion up to the event booked; its speed there is the one
        // a candidate that leaves the shaft coasting starts from (no constraint moves
        // it), the candidates' acceleration then their own.
        self.coast_to(w, w.t, self.coast.accel);
        let shaft = self.shaft_at(from, &links, w.t);
        self.coast = Coast {
            t0: w.t,
            omega: shaft,
            accel: self.coast.accel,
        };
        if w.audit_at_events && !core::mem::take(&mut w.event_audited) {
            // A finer rung would redo the step, this event and its choice: stop here
            // if the state at the event already breaks the energy balance.
            self.balance_within(w, &links, T::c(EVENT_AUDIT_MARGIN))?;
        }
        let tol_w = speed_tol::<T>() * speed_scale(&links);
        let with_shaft = self.params.shaft_inertia > T::zero();
        let cands = candidate_modes(from, kind, &links, shaft, tol_w, with_shaft);
        let space = self.momentum_space(w, &pose, &links, shaft, inputs)?;
        let judge = Judge {
            kind,
            from,
            pose: &pose,
            space: &space,
            inputs,
            touch: Touch {
                tol_w,
                held_at_stop: if kind == EventKind::ShaftStop {
                    from.clutches().map(|c| c != Clutch::Free)
                } else {
                    [false; 2]
                },
            },
        };
        let pick = self.pick(w, &cands, &judge)?;
        // The segment in `from` ends here (positions are continuous through an event).
        w.shaft_turn += shaft_turn(from, &links, &w.segment_levers);
        for (s, lever) in w.segment_levers.iter_mut().zip([&links[6], &links[8]]) {
            *s = unwrap_near(lever.theta, *s);
        }
        self.take_pick(w, kind, from, &links, pick, inputs)
    }

    /// The generalized momentum space of the unconstrained diode at `w`'s state: I0 (the
    /// 2-DOF model, plus the shaft when it has inertia) built in the slot the choice
    /// leaves free ([`Slots::reference_role`]; the scratch is its spare) at
    /// `pose` and evaluated at the links' speeds `links` and the shaft's `shaft`.
    fn momentum_space(
        &mut self,
        w: &Work<T>,
        pose: &[T; 9],
        links: &[LinkState<T>; 9],
        shaft: T,
        inputs: &Inputs<T>,
    ) -> Result<MomentumSpace<T>, TwinStepError> {
        self.slots.reference = Slots::<T>::reference_role(w.switched);
        let (reference, scratch) = self.slots.reference_and_scratch();
        let qr = best_slot(
            &self.params,
            Mode::I0,
            pose,
            w.t.to_f64(),
            self.settings.switch_below,
            reference,
            scratch,
        )?;
        let mut yr = SVector::<T, STATE>::zeros();
        for k in 0..2 {
            yr[k] = qr[k];
            let p = self.slots.reference().map.coord_link[k] as usize;
            yr[QD + k] = links.get(p).map_or_else(T::zero, |l| l.omega);
        }
        self.slots
            .reference_mut()
            .eval(
                w.t,
                &yr,
                inputs,
                self.drive,
                self.lossy.then_some(&self.params.friction),
                T::zero(),
            )
            .map_err(|e| self.physical_error(e))?;
        let js = self.params.shaft_inertia;
        let with_shaft = js > T::zero();
        let mut mass = SMatrix::<T, 3, 3>::identity();
        for r in 0..2 {
            for c in 0..2 {
                mass[(r, c)] = self.slots.reference().ws.mass_q[(r, c)];
            }
        }
        if with_shaft {
            mass[(2, 2)] = js;
        }
        let u = SVector::<T, 3>::new(
            yr[QD],
            yr[QD + 1],
            if with_shaft { shaft } else { T::zero() },
        );
        Ok(MomentumSpace {
            mass,
            u,
            with_shaft,
            yr,
        })
    }

    /// Mode `m`'s constraint rows in the reference's momentum space and the speeds
    /// projected onto them (with the impact's loss, J); `None` if they are
    /// rank-deficient.
    fn projected(&self, m: Mode, space: &MomentumSpace<T>) -> Projected<T> {
        let r = self.slots.reference();
        let rows = constraint_rows(m, space.with_shaft, |lever| r.lever_row(lever));
        let projection = project(&space.mass, &space.u, &rows);
        (rows, projection)
    }

    /// Judges the candidates `cands` in order and returns the first consistent one,
    /// built and evaluated; if none is, the least violating one (every candidate's
    /// violation then the built model's, see [`Twin::rejudge`]), built again.
    fn pick(
        &mut self,
        w: &Work<T>,
        cands: &[(u8, Mode)],
        judge: &Judge<'_, T>,
    ) -> Result<Pick<T>, TwinStepError> {
        let mut best: Option<(T, Mode)> = None;
        // The state the reference's workspace was last evaluated at.
        let mut yr_at = judge.space.yr;
        // Candidates the screen found clearly inconsistent, not built.
        let mut screened_out = false;
        self.candidates.clear();
        for (_, m) in cands.iter().copied() {
            let (rows, projection) = self.projected(m, judge.space);
            let Some((u_plus, loss)) = projection else {
                let _ = self.candidates.push((m, T::c(f64::INFINITY)));
                continue; // rank-deficient constraints
            };
            let (from, inputs, touch) = (judge.from, judge.inputs, judge.touch);
            let cand = match self.screen(m, from, &mut yr_at, &u_plus, w.t, inputs, touch) {
                Some((v, _)) if v > screen_margin::<T>() => {
                    screened_out = true;
                    Candidate::rejected(v)
                }
                screened => {
                    let c = screened.map(|(_, c)| c);
                    let pose = judge.pose;
                    self.try_candidate(w, m, pose, &u_plus, from, inputs, touch, c)?
                }
            };
            let _ = self.candidates.push((m, cand.violation));
            if cand.violation <= T::zero() {
                return Ok(Pick {
                    mode: m,
                    loss,
                    mismatch: rows_mismatch(&rows, &judge.space.u),
                    cand,
                    consistent: true,
                });
            }
            if best.as_ref().is_none_or(|(v, _)| cand.violation < *v) {
                best = Some((cand.violation, m));
            }
        }
        if screened_out {
            best = self.rejudge(w, judge)?;
        }
        let Some((v, m)) = best else {
            return Err(TwinStepError::Mechanism {
                time: w.t.to_f64(),
                mode: judge.from,
                failures: heapless::Vec::new(),
            });
        };
        crate::trace::warn!(
            "t = {:.6} s: no mode is consistent after {}; taking {m} (violation {v:?})",
            w.t.to_f64(),
            judge.kind.name()
        );
        let (rows, projection) = self.projected(m, judge.space);
        let (u_plus, loss) = projection.unwrap_or((judge.space.u, T::zero()));
        let (from, pose, inputs, touch) = (judge.from, judge.pose, judge.inputs, judge.touch);
        let cand = self.try_candidate(w, m, pose, &u_plus, from, inputs, touch, None)?;
        Ok(Pick {
            mode: m,
            loss,
            mismatch: rows_mismatch(&rows, &judge.space.u),
            cand,
            consistent: false,
        })
    }

    /// No candidate is consistent and the screen judged some: each candidate that can
    /// be built is judged by its built model, so that the least violating one is
    /// taken as when none is screened; returns it with its violation.
    fn rejudge(
        &mut self,
        w: &Work<T>,
        judge: &Judge<'_, T>,
    ) -> Result<Option<(T, Mode)>, TwinStepError> {
        let mut best: Option<(T, Mode)> = None;
        let (from, pose, inputs, touch) = (judge.from, judge.pose, judge.inputs, judge.touch);
        for i in 0..self.candidates.len() {
            let Some(&(m, mut v)) = self.candidates.get(i) else {
                break;
            };
            if v.finite() {
                if let (_, Some((u_plus, _))) = self.projected(m, judge.space) {
                    v = self
                        .try_candidate(w, m, pose, &u_plus, from, inputs, touch, None)?
                        .violation;
                }
            }
            if let Some(c) = self.candidates.get_mut(i) {
                c.1 = v;
            }
            if best.as_ref().is_none_or(|(b, _)| v < *b) {
                best = Some((v, m));
            }
        }
        Ok(best)
    }

    /// Takes the mode `pick` (its candidate slot holds it, evaluated) at `w`: the state
    /// read back from it, the impact's loss booked, and the event logged.
    fn take_pick(
        &mut self,
        w: &mut Work<T>,
        kind: EventKind,
        from: Mode,
        links: &[LinkState<T>; 9],
        pick: Pick<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        let time = w.t.to_f64();
        let Pick {
            mode: m,
            loss,
            mismatch,
            cand,
            consistent,
        } = pick;
        // The candidate slot holds the chosen mode, evaluated: take it. If that was the
        // reference model, its slot takes the scratch's role first (no copy).
        if cand.place == Place::Reference {
            self.slots.reference_to_scratch();
        }
        self.take_candidate(w);
        w.chosen = true;
        w.y = self.cand_state(w);
        w.impact += loss;
        self.dp5.invalidate();
        if consistent {
            // `try_candidate` evaluated the chosen mode in full (kinetostatics
            // included, or its clutch torques `cand.screened` from the screen) at this very
            // state, `w.y` being read back from it: evaluating again would give the
            // same bits.
            self.evaluate_from(
                Stage::Readout,
                w,
                inputs,
                cand.screened
                    .map_or(Torques::Kinetostatics, Torques::Screened),
            )?;
            self.seed_first_stage(w, inputs);
        } else {
            self.restart_at(w, inputs)?;
        }
        let after = self.slots.cur().links(&self.params);
        if m == Mode::Coast {
            // The shaft coasts from its speed at the event under its own torque.
            self.coast.accel = self.coast_accel(&after, self.coast.omega, inputs.load);
        }
        let position_gap = joint_gap(&self.params, links, &after);
        crate::trace::info!(
            "t = {time:.6} s: {} -> {m} ({}, {} coordinates, impact loss {loss:?} J)",
            from,
            kind.name(),
            self.slots.cur().coords
        );
        // Another mode, other coordinates: none is barred ([`Twin::broke_in`]).
        self.broke_in = None;
        let _ = self.events.push(Event {
            time: w.t,
            kind,
            from,
            to: m,
            c: self.c,
            impact_loss: loss,
            mismatch,
            consistent,
            position_gap,
            speed_gap: cand.speed_gap,
        });
        Ok(())
    }

    /// The state vector of the slot just taken (stored by [`Twin::try_candidate`]).
    pub(super) fn cand_state(&self, w: &Work<T>) -> SVector<T, STATE> {
        let mut y = w.y;
        let n = self.slots.cur().map.dof.min(2);
        for k in 0..2 {
            y[k] = if k < n {
                self.slots.cur().ws.q[k]
            } else {
                T::zero()
            };
            y[QD + k] = if k < n {
                self.slots.cur().ws.qd[k]
            } else {
                T::zero()
            };
        }
        y
    }
}

/// The candidate modes at event `kind` from mode `from`, with their [`preference`],
/// most preferred first (ties in the enumeration order): each lever that touches the
/// shaft (its speed `shaft`, to `tol_w`), holds, or is caught, free or holding; the
/// shaft held, if it may be, or turning (with no lever, [`Mode::Coast`], only if it
/// has inertia, `with_shaft`, and turns: a standing shaft with no lever is held).
fn candidate_modes<T: Real>(
    from: Mode,
    kind: EventKind,
    links: &[LinkState<T>; 9],
    shaft: T,
    tol_w: T,
    with_shaft: bool,
) -> heapless::Vec<(u8, Mode), 8> {
    // Which levers touch the shaft (may lock or engage), and the shaft's options.
    let mut contact = [false; 2];
    for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(from.clutches()).enumerate() {
        let rel = links.get(*lever).map_or_else(T::zero, |l| l.omega) - shaft;
        contact[k] = clutch != Clutch::Free
            || (rel.abs() <= tol_w)
            || kind == EventKind::Catch(*lever as u8);
    }
    let held_possible =
        !from.shaft_turning() || kind == EventKind::ShaftStop || shaft.abs() <= tol_w;
    let mut cands: heapless::Vec<(u8, Mode), 8> = heapless::Vec::new();
    for turning in [false, true] {
        if !turning && !held_possible {
            continue;
        }
        let hold = if turning {
            Clutch::Engaged
        } else {
            Clutch::Locked
        };
        let options = |k: usize| {
            if contact[k] {
                [Clutch::Free, hold]
            } else {
                [Clutch::Free, Clutch::Free]
            }
        };
        for c6 in options(0) {
            for c8 in options(1) {
                let Some(m) = Mode::from_clutches([c6, c8], turning) else {
                    continue;
                };
                if m == Mode::Coast && !(with_shaft && shaft.abs() > tol_w) {
                    continue;
                }
                if !cands.iter().any(|(_, x)| *x == m) {
                    let _ = cands.push((preference(from, m, kind), m));
                }
            }
        }
    }
    // Insertion sort by preference (stable: ties keep the enumeration order).
    for i in 1..cands.len() {
        for j in (1..=i).rev() {
            match cands.get_mut(j - 1..=j) {
                Some([a, b]) if a.0 > b.0 => core::mem::swap(a, b),
                _ => break,
            }
        }
    }
    cands
}

/// The reference model's (I0's) generalized momentum space at an event.
struct MomentumSpace<T: Real> {
    /// Its mass matrix over `(q̇₁, q̇₂, ω_shaft)` (the shaft's entry 1 without inertia).
    mass: SMatrix<T, 3, 3>,
    /// The speeds before the event over the same coordinates.
    u: SVector<T, 3>,
    /// Whether the shaft has inertia (a third coordinate).
    with_shaft: bool,
    /// The state the reference was evaluated at.
    yr: SVector<T, STATE>,
}

/// A mode's constraint rows and, unless they are rank-deficient, the speeds projected
/// onto them and the impact's loss, J.
type Projected<T> = (heapless::Vec<SVector<T, 3>, 3>, Option<(SVector<T, 3>, T)>);

/// What every candidate of one mode choice is judged at.
struct Judge<'a, T: Real> {
    /// The event.
    kind: EventKind,
    /// The mode before the event.
    from: Mode,
    /// The physical angles, rad.
    pose: &'a [T; 9],
    /// The reference's momentum space.
    space: &'a MomentumSpace<T>,
    /// The step's inputs.
    inputs: &'a Inputs<T>,
    /// Which free levers touch the shaft.
    touch: Touch<T>,
}

/// The mode a choice takes.
struct Pick<T: Real> {
    /// The mode.
    mode: Mode,
    /// Kinetic energy lost in the impact, J.
    loss: T,
    /// How far the speeds before the event violate its constraints.
    mismatch: T,
    /// It, built and judged.
    cand: Candidate<T>,
    /// Whether it is consistent (else the least violating).
    consistent: bool,
}
