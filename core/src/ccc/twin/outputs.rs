//! What the twin reports of its last good state: time, mode, coordinates, the links'
//! physical state, the shaft, clutch torques, joint reactions, the audit and the logs
//! of the last step.

use super::super::build::{CRANK, ROCKER};
use super::super::mode::{Coordinates, Mode};
use super::super::params::CccParams;
use super::audit::Audit;
use super::coordinates::CoordinateSwitch;
use super::guards::Event;
use super::settings::TwinSettings;
use super::slot::{LinkState, QD};
use super::Twin;
use crate::scalar::{unit, Real, Vec2};

/// The twin's angles less the measured ones, rad, of each encoder measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderResiduals<T> {
    /// The crank's θ1.
    pub crank: Option<T>,
    /// The shaft's angle in the drive direction.
    pub shaft: Option<T>,
    /// The rocker's θ.
    pub rocker: Option<T>,
}

impl<T: Real> Twin<T> {
    /// Time, s: `n·h` after `n` steps, unless the twin spreads its events
    /// ([`TwinSettings::spread_events`]) and is
    /// behind the clock after one ([`Twin::lag`]).
    pub fn time(&self) -> T {
        self.t
    }

    /// How far the twin's time is behind the clock's `n·h` after `n` steps, s: 0
    /// unless it spreads its events ([`TwinSettings::spread_events`]): an event adds
    /// up to 2 `h` (the step to its location, the step to its choice), and each
    /// catching-up step takes [`CATCH_UP`](super::CATCH_UP)` - 1` steps off (S2 at
    /// h = 1 ms: at most 4.0 `h`, after two events 0.9 ms apart).
    pub fn lag(&self) -> T {
        T::c(self.steps as f64) * self.settings.h - self.t
    }

    /// The settings fixed at start.
    pub fn settings(&self) -> &TwinSettings<T> {
        &self.settings
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The fixed step, s.
    pub fn h(&self) -> T {
        self.settings.h
    }

    /// The parameters.
    pub fn params(&self) -> &CccParams<T> {
        &self.params
    }

    /// The current mode.
    pub fn mode(&self) -> Mode {
        self.slots.cur().mode
    }

    /// The current independent coordinates.
    pub fn coordinates(&self) -> Coordinates {
        self.slots.cur().coords
    }

    /// Values of the current coordinates (`[..dof]`), rad.
    pub fn q(&self) -> &[T] {
        self.y
            .as_slice()
            .get(..self.slots.cur().map.dof.min(2))
            .unwrap_or(&[])
    }

    /// Their speeds, rad/s.
    pub fn qd(&self) -> &[T] {
        self.y
            .as_slice()
            .get(QD..QD + self.slots.cur().map.dof.min(2))
            .unwrap_or(&[])
    }

    /// The crank's transmission `∂θ1/∂q` (= `∂ω1/∂q̇`) over the current coordinates
    /// (`[..dof]`): 1 where the crank is a coordinate, 0 at the crank's reversals.
    pub fn crank_transmission(&self) -> [T; 2] {
        self.slots.cur().omega_row(CRANK)
    }

    /// The crank's mobility `b = r M⁻¹ rᵀ`, 1/(kg·m²): the crank's angular acceleration
    /// per N·m of torque on it in the present mode, at the last evaluation (`r` =
    /// [`crank_transmission`](Self::crank_transmission), the generalized force of a
    /// crank torque `τ` being `rᵀ τ`; `M` the mode's mass matrix in its coordinates;
    /// `1/b` the crank-reduced inertia). 0 with no degree of freedom or a singular `M`.
    pub fn crank_mobility(&self) -> T {
        let slot = self.slots.cur();
        let [r0, r1] = slot.omega_row(CRANK);
        let m = |i: usize, j: usize| slot.ws.mass_q.get((i, j)).copied().unwrap_or(T::zero());
        let (num, det) = match slot.map.dof {
            1 => (r0 * r0, m(0, 0)),
            2 => (
                r0 * r0 * m(1, 1) - (m(0, 1) + m(1, 0)) * r0 * r1 + r1 * r1 * m(0, 0),
                m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0),
            ),
            _ => return T::zero(),
        };
        if det > T::zero() {
            num / det
        } else {
            T::zero()
        }
    }

    /// Their accelerations, rad/s².
    pub fn qdd(&self) -> &[T] {
        self.slots
            .cur()
            .ws
            .qdd
            .get(..self.slots.cur().map.dof.min(2))
            .unwrap_or(&[])
    }

    /// Physical state of link `p` (1..=8).
    pub fn link(&self, p: usize) -> LinkState<T> {
        self.links.get(p).copied().unwrap_or_default()
    }

    /// World position of point `point` (0 or 1: a bar's first or second joint; 2: D on
    /// the rocker) of physical link `p`, m.
    pub fn joint_position(&self, p: usize, point: usize) -> Vec2<T> {
        let s = self.link(p);
        let x = match point {
            0 => T::zero(),
            1 => self.params.link(p).length,
            _ => self.params.rocker_d,
        };
        s.origin + unit(s.theta) * x
    }

    /// Shaft speed, rad/s, CCW positive (0 while held).
    pub fn shaft_speed(&self) -> T {
        self.shaft_at(self.slots.cur().mode, &self.links, self.t)
    }

    /// Shaft acceleration, rad/s², CCW positive (0 while held; the coasting shaft's
    /// own under its brake and drag in [`Mode::Coast`]).
    pub fn shaft_acceleration(&self) -> T {
        self.shaft_alpha(self.slots.cur().mode, &self.links)
    }

    /// Shaft angle turned since the start, rad, CCW positive.
    pub fn shaft_angle(&self) -> T {
        self.shaft_angle
    }

    /// Transmitted torques `[c6, c8]`, N·m, positive in the drive direction.
    pub fn clutch_torques(&self) -> [T; 2] {
        self.c
    }

    /// Reactions at the physical joints ([`JOINTS`](super::JOINTS)), N.
    pub fn joint_reactions(&self) -> &[Vec2<T>; 11] {
        &self.joints
    }

    /// Motor torque at the current state, N·m.
    pub fn motor_torque(&self) -> T {
        let c = self.link(CRANK);
        self.inputs.motor.torque(self.t, c.theta, c.omega)
    }

    /// The energy audit.
    pub fn audit(&self) -> Audit<T> {
        self.audit
    }

    /// The twin's angles less the measured ones of the last step's inputs (each
    /// encoder's angle, [`Encoder::angle`](super::Encoder::angle)), rad: the crank's
    /// θ1, the shaft's angle in the drive direction, the rocker's θ. `None` while the
    /// twin is behind the clock ([`Twin::lag`]): its state is not the machine's at the
    /// measurements' time.
    pub fn measurement_residual(&self) -> Option<EncoderResiduals<T>> {
        if self.behind {
            return None;
        }
        let [crank, shaft, rocker] = self.inputs.angles?;
        let of = |a: Option<T>, twin: T| a.map(|a| twin - a);
        Some(EncoderResiduals {
            crank: of(crank, self.link(CRANK).theta),
            shaft: of(shaft, self.drive * self.shaft_angle),
            rocker: of(rocker, self.link(ROCKER).theta),
        })
    }

    /// The shaft's angle turned in the drive direction since the start, rad.
    pub fn shaft_drive_angle(&self) -> T {
        self.drive * self.shaft_angle
    }

    /// The mode changes of the last step (or of the setup).
    pub fn events(&self) -> &[Event<T>] {
        &self.events
    }

    /// The coordinate switches of the last step.
    pub fn switches(&self) -> &[CoordinateSwitch<T>] {
        &self.switches
    }

    /// The candidates of the last mode choice, in the order tried, with how far each
    /// violates SPEC 3's consistency conditions (0: consistent; infinite: its
    /// constraints are rank-deficient or it cannot assemble).
    pub fn candidates(&self) -> &[(Mode, T)] {
        &self.candidates
    }

    /// Smallest normalized determinant over the current sequence's groups.
    pub fn conditioning(&self) -> T {
        self.slots.cur().conditioning()
    }

    /// The current mode's core model.
    pub fn model(&self) -> &crate::model::Model<T, super::Converter> {
        &self.slots.cur().model
    }
}
