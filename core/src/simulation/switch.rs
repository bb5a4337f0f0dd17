//! Dead points of the driven coordinates (SPEC 3, "Dead points of the coordinates are
//! not the machine's"), for any mechanism: when the group sequence of the coordinates
//! in use loses its conditioning (a crank driving a triad at its dead point, a piston
//! driving a slider-crank at bottom dead centre), the mechanism is described by another
//! choice of independent coordinates that drives it there (another link's angle or
//! slide and its own group sequence, prepared at set-up), and switched back once the
//! first is conditioned again.
//!
//! The alternatives are whole models of the same links ([`Alternatives`], owned by the
//! user beside the [`Simulation`]: the simulation's size does not change). An
//! alternative's motors act across the joints their motor elements drove in the first
//! model ([`ModelBuilder::drive_across`](crate::ModelBuilder::drive_across)): the
//! generalized force of a motor maps through the transmission (virtual power), and the
//! energy balance meters its power `τ (ω_i - ω_j)` as before.
//!
//! A switch maps the state exactly: the new coordinates are read off the bodies' poses
//! and speeds (a motor element R's angle and speed, a motor element T's offset along
//! its guide and its rate: the transmission `V q̇` the old coordinates gave the
//! bodies), the new sequence is assembled at them on the branch nearest the bodies'
//! poses, and the switch is refused if any link lands more than a tolerance away.

use super::singular::{at_singularity, locate_from};
use super::{check_outputs, check_reactions, Simulation};
use crate::balance::Balance;
use crate::config::{MAX_DOF, MAX_GROUPS, STATE_DIM};
use crate::dynamics::{finish_accelerations, forward};
use crate::error::{GroupFault, GroupId, ModelError, StepError};
use crate::kinematics::{assemble_near, group_id};
use crate::kinetostatics::reactions;
use crate::model::Model;
use crate::scalar::{perp, rotate_cs, Real};
use crate::structomat::{GroupKind, Term};
use crate::workspace::{BodyState, Workspace};
use nalgebra::SVector;

/// When to switch coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwitchSettings<T> {
    /// Switch away from the coordinates in use when their worst group's conditioning
    /// (normalized determinant, the sine of a dyad's transmission angle) falls below
    /// this, to the best conditioned alternative if it is better conditioned.
    pub switch_below: T,
    /// Switch back to the first coordinates when their conditioning is at least this
    /// (above `switch_below`: the hysteresis keeps a pose near the threshold from
    /// switching every step).
    pub back_above: T,
}

impl<T: Real> Default for SwitchSettings<T> {
    /// 0.2 and 0.3: a dyad switches below a transmission angle of 11.5° and back above
    /// 17.5°; the built-in five-bar and slider-crank never reach the first (their worst
    /// conditioning over their main jobs: 0.349 and 0.964). Closer to the dead point
    /// the old coordinates' accelerations grow so that the steps there break the energy
    /// balance and are redone in sub-steps (at 0.1 the piston-driven slider-crank of
    /// `host-sim/mechanisms` redoes 18 steps of h = 1 ms, at 0.2 none).
    fn default() -> Self {
        SwitchSettings {
            switch_below: T::c(0.2),
            back_above: T::c(0.3),
        }
    }
}

/// A change of independent coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoordinateSwitch<T> {
    /// Time, s.
    pub time: T,
    /// The alternative in use before (0: the simulation's first model).
    pub from: u8,
    /// The alternative in use after.
    pub to: u8,
    /// The worst group's conditioning before, and after.
    pub conditioning: [T; 2],
    /// The worst group before (in its sequence).
    pub group: GroupId,
    /// Largest distance between a link's origin placed by the two sequences, m.
    pub position_gap: T,
}

/// Alternative choices of coordinates of one mechanism and which is in use. Index 0
/// is the simulation's own model at set-up.
pub struct Alternatives<T: Real, const N: usize> {
    models: heapless::Vec<Model<T>, N>,
    /// The candidate's evaluation (a switch copies it into the simulation).
    scratch: Workspace<T>,
    active: u8,
    settings: SwitchSettings<T>,
    /// The first model's coordinates, followed through their turns while another is in
    /// use (its angles are read off the links modulo 2π).
    first_q: [T; MAX_DOF],
    switches: u32,
}

/// A candidate's evaluation at the simulation's pose.
struct Trial<T> {
    q: [T; MAX_DOF],
    qd: [T; MAX_DOF],
    conditioning: T,
    worst: GroupId,
    gap: T,
}

impl<T: Real, const N: usize> Alternatives<T, N> {
    /// The coordinates of `sim`'s model, alone so far; add the others with
    /// [`Alternatives::add`].
    pub fn new(sim: &Simulation<T>, settings: SwitchSettings<T>) -> Result<Self, ModelError> {
        if !(settings.switch_below > T::zero() && settings.back_above >= settings.switch_below) {
            return Err(ModelError::NotPositive(
                "switch thresholds (0 < switch_below <= back_above)",
            ));
        }
        let mut models = heapless::Vec::new();
        if models.push(sim.model().clone()).is_err() {
            return Err(ModelError::Capacity("alternative models"));
        }
        let mut first_q = [T::zero(); MAX_DOF];
        for (d, s) in first_q.iter_mut().zip(sim.q()) {
            *d = *s;
        }
        Ok(Alternatives {
            models,
            scratch: Workspace::new(),
            active: 0,
            settings,
            first_q,
            switches: 0,
        })
    }

    /// Adds an alternative choice of coordinates: a model of the same links and degrees
    /// of freedom whose motors act across the first model's driven joints.
    pub fn add(&mut self, model: Model<T>) -> Result<(), ModelError> {
        let first = self.models.first();
        if first.is_none_or(|f| f.dof() != model.dof() || f.n_links() != model.n_links()) {
            return Err(ModelError::Coordinates(
                "an alternative has other links or degrees of freedom",
            ));
        }
        self.models
            .push(model)
            .map_err(|_| ModelError::Capacity("alternative models"))
    }

    /// The models, the first one first.
    pub fn models(&self) -> &[Model<T>] {
        &self.models
    }

    /// The alternative in use (0: the first model).
    pub fn active(&self) -> usize {
        self.active as usize
    }

    /// Switches made so far.
    pub fn switches(&self) -> u32 {
        self.switches
    }

    /// The first model's coordinates and speeds at `sim`'s state, whichever is in use.
    pub fn first_state(&self, sim: &Simulation<T>) -> ([T; MAX_DOF], [T; MAX_DOF]) {
        match self.models.first() {
            Some(m) if self.active != 0 => coordinates(m, &sim.ws.body, Some(&self.first_q))
                .unwrap_or(([T::c(f64::NAN); MAX_DOF], [T::c(f64::NAN); MAX_DOF])),
            _ => {
                let (mut q, mut qd) = ([T::zero(); MAX_DOF], [T::zero(); MAX_DOF]);
                for (d, s) in q.iter_mut().zip(sim.q()) {
                    *d = *s;
                }
                for (d, s) in qd.iter_mut().zip(sim.qd()) {
                    *d = *s;
                }
                (q, qd)
            }
        }
    }

    /// The first model evaluated at `sim`'s physical state while an alternative drives
    /// (`None` while the first model is in use, or where it does not evaluate: exactly
    /// at its dead point, where its coordinates do not place the links). Its workspace
    /// holds the first coordinates, rates and accelerations read off the links (the
    /// accelerations those the alternative solved, `motion`), the motors' torques
    /// (each motor's law reads its joint's relative motion, the same in either model),
    /// and the reactions of the first model's kinetostatics at that motion: the joints
    /// are the mechanism's own, loaded as in the machine, the motors' torques at their
    /// joints and none at the alternative's driven joint (whose kinetostatics puts
    /// there the torque its coordinate would need, a torque no motor applies). The
    /// first drivers' driving torques are then the torques the first coordinates would
    /// need for the motion, the motors' own (virtual power). Valid until the next step
    /// (it shares the candidates' scratch workspace).
    pub fn first_evaluation(&mut self, sim: &Simulation<T>) -> Option<(&Model<T>, &Workspace<T>)> {
        if self.active == 0 {
            return None;
        }
        let model = self.models.first()?;
        let (q, qd, qdd) = motion(model, &sim.ws.body, Some(&self.first_q))?;
        let m = model.dof();
        let (q_, qd_, qdd_) = (q.get(..m)?, qd.get(..m)?, qdd.get(..m)?);
        let ws = &mut self.scratch;
        assemble_near(model, ws, q_, &sim.ws.body).ok()?;
        forward(model, ws, sim.t, q_, qd_).ok()?;
        // The accelerations the alternative solved, in place of the first model's
        // equations of motion solved again (the same motion; these do not lose
        // digits to the first coordinates' conditioning).
        for (d, s) in ws.qdd.iter_mut().zip(qdd_) {
            *d = *s;
        }
        finish_accelerations(model, ws);
        let time = sim.t.to_f64();
        check_outputs(model, ws, time).ok()?;
        reactions(model, ws, time).ok()?;
        check_reactions(model, ws, time).ok()?;
        Some((model, &self.scratch))
    }

    /// The workspace of the last [`Alternatives::first_evaluation`] (or of a
    /// candidate's trial, if a step came after it).
    pub fn last_evaluation(&self) -> &Workspace<T> {
        &self.scratch
    }

    /// One step of `sim` ([`Simulation::step`]) in the best coordinates: before it,
    /// switches away from coordinates whose conditioning is under
    /// [`SwitchSettings::switch_below`] to a better conditioned alternative, or back to
    /// the first model once it is conditioned [`SwitchSettings::back_above`]; if the
    /// step fails in a group (a dead point met inside the step), switches at the last
    /// good state to the best alternative and takes the step again, once. Returns the
    /// switch made, if any. A step that fails in every choice of coordinates fails with
    /// [`GroupFault::DeadPoint`], naming the group, the time and the best alternative;
    /// the last good state is kept.
    pub fn step(
        &mut self,
        sim: &mut Simulation<T>,
    ) -> Result<Option<CoordinateSwitch<T>>, StepError> {
        let mut switched = self.choose(sim, false);
        // Under the threshold the coordinates' accelerations grow without bound toward
        // the dead point: a step there that breaks the energy balance fails as at it.
        let ill = worst_group(&sim.model, &sim.ws).0 < self.settings.switch_below;
        let at_dead_point = |e: &StepError| {
            at_singularity(e) || (ill && matches!(e, StepError::EnergyBalance { .. }))
        };
        match sim.step() {
            Ok(()) => {}
            Err(e) if at_dead_point(&e) => {
                let Some(s) = self.choose(sim, true) else {
                    return Err(self.dead_point(sim, e));
                };
                switched = Some(s);
                sim.step().map_err(|e| {
                    if at_dead_point(&e) {
                        self.dead_point(sim, e)
                    } else {
                        e
                    }
                })?;
            }
            Err(e) => return Err(e),
        }
        if self.active != 0 {
            if let Some((q, _)) = self
                .models
                .first()
                .and_then(|m| coordinates(m, &sim.ws.body, Some(&self.first_q)))
            {
                self.first_q = q;
            }
        }
        Ok(switched)
    }

    /// Where the motion from `sim`'s state meets a singularity of the mechanism within
    /// `steps` step lengths, in any of its coordinates:
    /// [`Simulation::locate_singularity`] in the coordinates in use and, while an
    /// alternative drives, in the first coordinates too (a trial from the same physical
    /// state in them); the earlier located time, with its error. Call it after a step
    /// failed (at a singularity, or breaking the energy balance on the way into one).
    ///
    /// Why the first coordinates as well: an alternative that drives the links through
    /// the first coordinates' singular pose need not carry the mechanism through it. The
    /// stretched four-bar's crank (a flywheel at 1 rad/s) reaches its limit angle where
    /// coupler and rocker stretch in line; on the rocker's angle φ the crank's inertia
    /// weighs `I (dθ/dφ)²`, which vanishes there, so φ̇ grows as `(t* - t)^-½` and a trial
    /// step in φ jumps the pose without an evaluation failing: it fails only at the
    /// rocker's own limit, 4e-4 s later. In the first coordinates every trial past the
    /// pose fails (the dyad cannot assemble), so the bisection brackets it.
    pub fn locate_singularity(
        &mut self,
        sim: &Simulation<T>,
        scratch: &mut Workspace<T>,
        steps: u32,
    ) -> Option<(T, StepError)> {
        let own = sim.locate_singularity(scratch, steps);
        if self.active == 0 {
            return own;
        }
        let first = self.locate_in_first(sim, scratch, steps);
        match (own, first) {
            (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// [`Simulation::locate_singularity`] in the first coordinates from `sim`'s
    /// physical state (mapped by [`Alternatives::trial`]), the error naming the first
    /// sequence's group.
    fn locate_in_first(
        &mut self,
        sim: &Simulation<T>,
        scratch: &mut Workspace<T>,
        steps: u32,
    ) -> Option<(T, StepError)> {
        let t = self.trial(0, sim)?;
        let model = self.models.first()?;
        let mut y = SVector::<T, STATE_DIM>::zeros();
        for k in 0..model.dof().min(MAX_DOF) {
            y[k] = t.q[k];
            y[MAX_DOF + k] = t.qd[k];
        }
        locate_from(
            model,
            &self.scratch,
            sim.t,
            &y,
            sim.span_end(steps),
            scratch,
        )
        .filter(|(_, e)| at_singularity(e))
        .map(|(t, e)| (t, e.at_time(t.to_f64())))
    }

    /// Switches `sim` to the best alternative if its coordinates are ill-conditioned
    /// (`failed`: a step in them failed; any better alternative then), or back to the
    /// first model when it is conditioned again.
    fn choose(&mut self, sim: &mut Simulation<T>, failed: bool) -> Option<CoordinateSwitch<T>> {
        if self.models.len() < 2 {
            return None;
        }
        let (cond, group) = worst_group(&sim.model, &sim.ws);
        if !failed && cond >= self.settings.switch_below {
            if self.active == 0 {
                return None;
            }
            // Back to the first coordinates once they are conditioned again.
            let t = self.trial(0, sim)?;
            if t.conditioning < self.settings.back_above {
                return None;
            }
            return Some(self.commit(0, t, sim, cond, group));
        }
        if self.active == 0 {
            self.first_state_from(sim);
        }
        let mut best: Option<(usize, Trial<T>)> = None;
        // The alternative whose evaluation the scratch workspace holds.
        let mut evaluated = None;
        for k in 0..self.models.len() {
            if k == self.active as usize {
                continue;
            }
            if let Some(t) = self.trial(k, sim) {
                evaluated = Some(k);
                if best
                    .as_ref()
                    .is_none_or(|(_, b)| t.conditioning > b.conditioning)
                {
                    best = Some((k, t));
                }
            }
        }
        let (k, mut t) = best?;
        // The threshold's own scale: a switch must gain conditioning, not trade one
        // ill-conditioned choice for another just as bad.
        if !(t.conditioning > cond * T::c(1.5)) || !(t.conditioning > sim.model.singular_tol()) {
            return None;
        }
        if evaluated != Some(k) {
            // A later candidate's trial overwrote its evaluation: again (the same bits).
            t = self.trial(k, sim)?;
        }
        Some(self.commit(k, t, sim, cond, group))
    }

    fn first_state_from(&mut self, sim: &Simulation<T>) {
        for (d, s) in self.first_q.iter_mut().zip(sim.q()) {
            *d = *s;
        }
    }

    /// Evaluates alternative `k` at `sim`'s state in the scratch workspace; `None` if it
    /// does not assemble there, lands elsewhere, or fails to evaluate.
    fn trial(&mut self, k: usize, sim: &Simulation<T>) -> Option<Trial<T>> {
        let model = self.models.get(k)?;
        let reference = (k == 0).then_some(&self.first_q);
        let (q, qd) = coordinates(model, &sim.ws.body, reference)?;
        let m = model.dof();
        let (q_, qd_) = (q.get(..m)?, qd.get(..m)?);
        assemble_near(model, &mut self.scratch, q_, &sim.ws.body).ok()?;
        forward(model, &mut self.scratch, sim.t, q_, qd_).ok()?;
        let time = sim.t.to_f64();
        check_outputs(model, &self.scratch, time).ok()?;
        let mut gap = T::zero();
        let mut size = T::one();
        for (a, b) in self
            .scratch
            .body
            .iter()
            .zip(sim.ws.body.iter())
            .skip(1)
            .take(model.n_links())
        {
            let e = a.theta - b.theta;
            let e = e - T::two_pi() * (e / T::two_pi()).round();
            gap = gap.max((a.o - b.o).norm()).max(e.abs());
            size = size.max(b.o.norm());
        }
        // Positions by assembly agree to the solvers' rounding; a larger gap is another
        // assembly of the links (a branch the old sequence is not on).
        if !(gap <= T::default_epsilon().sqrt() * size) {
            return None;
        }
        let (conditioning, worst) = worst_group(model, &self.scratch);
        Some(Trial {
            q,
            qd,
            conditioning,
            worst,
            gap,
        })
    }

    /// Puts alternative `k`, evaluated by [`Alternatives::trial`] as `t`, into `sim`.
    fn commit(
        &mut self,
        k: usize,
        t: Trial<T>,
        sim: &mut Simulation<T>,
        cond: T,
        group: GroupId,
    ) -> CoordinateSwitch<T> {
        let from = self.active;
        if let Some(model) = self.models.get(k) {
            sim.adopt(model, &self.scratch, &t.q, &t.qd);
        }
        self.active = k as u8;
        self.switches = self.switches.saturating_add(1);
        let _ = t.worst;
        CoordinateSwitch {
            time: sim.t,
            from,
            to: k as u8,
            conditioning: [cond, t.conditioning],
            group,
            position_gap: t.gap,
        }
    }

    /// The error of a step that fails in every choice of coordinates.
    fn dead_point(&mut self, sim: &Simulation<T>, e: StepError) -> StepError {
        let (cond, worst) = worst_group(&sim.model, &sim.ws);
        let group = match e {
            StepError::Group { group, .. } => group,
            _ => worst,
        };
        let mut best = f32::NAN;
        for k in 0..self.models.len() {
            if k == self.active as usize {
                continue;
            }
            if let Some(t) = self.trial(k, sim) {
                let c = t.conditioning.to_f64() as f32;
                if best.is_nan() || c > best {
                    best = c;
                }
            }
        }
        StepError::Group {
            time: sim.t.to_f64(),
            group,
            fault: GroupFault::DeadPoint {
                conditioning: cond.to_f64(),
                best,
                alternatives: self.models.len().saturating_sub(1) as u8,
            },
        }
    }
}

/// The worst-conditioned group of `model` at the workspace's last evaluation.
fn worst_group<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> (T, GroupId) {
    let mut worst = (T::one(), 0usize);
    for (k, gd) in ws
        .group
        .iter()
        .enumerate()
        .take(model.groups().len().min(MAX_GROUPS))
    {
        if gd.conditioning < worst.0 {
            worst = (gd.conditioning, k);
        }
    }
    let id = model.groups().get(worst.1).map_or(
        GroupId {
            index: 0,
            kind: GroupKind::MotorR,
            links: [0; crate::config::MAX_GROUP_LINKS],
            count: 0,
        },
        |g| group_id(g, worst.1),
    );
    (worst.0, id)
}

/// The coordinates of `model` and their rates read off the bodies `b` (motor element R:
/// its link's angle less the offset, and its angular speed; motor element T: the offset
/// of the slider's point along the guide from the guide's point, and its rate), angles
/// taken to the turn nearest `reference` when given.
fn coordinates<T: Real>(
    model: &Model<T>,
    b: &[BodyState<T>],
    reference: Option<&[T; MAX_DOF]>,
) -> Option<([T; MAX_DOF], [T; MAX_DOF])> {
    motion(model, b, reference).map(|(q, qd, _)| (q, qd))
}

/// [`coordinates`] with the coordinates' accelerations: motor element R, its link's
/// angular acceleration; motor element T, the second derivative of `s = gap · u` with
/// the guide's direction `u` turning with the guide's body g (`u̇ = ω_g u⊥`):
/// `s̈ = (a_p - a_g)·u + 2 ω_g (v_p - v_g)·u⊥ - ω_g² gap·u + α_g gap·u⊥`, the points'
/// accelerations `a + α r⊥ - ω² r`.
fn motion<T: Real>(
    model: &Model<T>,
    b: &[BodyState<T>],
    reference: Option<&[T; MAX_DOF]>,
) -> Option<Coordinates<T>> {
    let (mut q, mut qd, mut qdd) = (
        [T::zero(); MAX_DOF],
        [T::zero(); MAX_DOF],
        [T::zero(); MAX_DOF],
    );
    for g in model.groups() {
        let Some(c) = g.coord else { continue };
        let c = c as usize;
        let p = g.placements.first()?;
        let link = b.get(p.link as usize)?;
        let (value, rate, acceleration) = match g.kind {
            GroupKind::MotorR => {
                let raw = link.theta - p.angle.offset;
                let v = match reference.and_then(|r| r.get(c)) {
                    Some(r) => raw - T::two_pi() * ((raw - *r) / T::two_pi()).round(),
                    None => raw,
                };
                (v, link.omega, link.alpha)
            }
            GroupKind::MotorT => {
                let chain = g.chains.first()?;
                let Some(Term::Slide { angle, dir, .. }) = chain.terms.first() else {
                    return None;
                };
                let gb = b
                    .get(chain.start.body as usize)
                    .copied()
                    .unwrap_or_default();
                let rg = if chain.start.body == 0 {
                    model.point_local(chain.start) - gb.o
                } else {
                    rotate_cs(gb.c, gb.s, &model.point_local(chain.start))
                };
                let r = rotate_cs(link.c, link.s, &p.local);
                let (s, co) = (gb.theta + angle.offset).sin_cos();
                let u = rotate_cs(co, s, dir);
                let gap = (link.o + r) - (gb.o + rg);
                let vp = link.v + perp(&r) * link.omega;
                let vg = gb.v + perp(&rg) * gb.omega;
                let ap = link.a + perp(&r) * link.alpha - r * (link.omega * link.omega);
                let ag = gb.a + perp(&rg) * gb.alpha - rg * (gb.omega * gb.omega);
                let (un, w) = (perp(&u), gb.omega);
                (
                    gap.dot(&u),
                    (vp - vg).dot(&u) + gap.dot(&un) * w,
                    (ap - ag).dot(&u) + (vp - vg).dot(&un) * (w + w) - gap.dot(&u) * (w * w)
                        + gap.dot(&un) * gb.alpha,
                )
            }
            _ => continue,
        };
        *q.get_mut(c)? = value;
        *qd.get_mut(c)? = rate;
        *qdd.get_mut(c)? = acceleration;
    }
    Some((q, qd, qdd))
}

/// Coordinates, rates and accelerations.
type Coordinates<T> = ([T; MAX_DOF], [T; MAX_DOF], [T; MAX_DOF]);

impl<T: Real> Simulation<T> {
    /// Takes `model` as the simulation's model at the same time and physical state, in
    /// its coordinates `q`, `qd`, with `ws` its evaluation there
    /// ([`Alternatives::trial`]): the energy balance goes on with the works so far, the
    /// step count (time `n·h`) is kept, the integrator starts afresh.
    fn adopt(&mut self, model: &Model<T>, ws: &Workspace<T>, q: &[T; MAX_DOF], qd: &[T; MAX_DOF]) {
        self.model.clone_from(model);
        self.ws.clone_from(ws);
        self.y.fill(T::zero());
        for k in 0..model.dof().min(MAX_DOF) {
            self.y[k] = q[k];
            self.y[MAX_DOF + k] = qd[k];
        }
        self.dp5.invalidate();
        Balance::rebase(&mut self.balance, &self.model, &self.ws);
    }
}
