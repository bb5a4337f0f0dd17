//! The twin's construction: by value ([`Twin::new`]) or where it lives
//! ([`Twin::new_in`], in place: no slot on the stack), the same twin bit for bit; its
//! first evaluation and mode choice.

use super::super::build::{initial_pose, CRANK};
use super::super::mode::Mode;
use super::super::params::CccParams;
use super::audit::{audit_finite, Audit};
use super::coast::Coast;
use super::coordinates::best_slot;
use super::error::{TwinSetupError, TwinStepError};
use super::evaluate::TorqueSource;
use super::guards::{EventKind, Guards};
use super::inputs::{check_inputs, Held, Inputs};
use super::rungs::JumpHistory;
use super::settings::{check_settings, TwinSettings};
use super::slot::{LinkState, Slot};
use super::slots::Slots;
use super::{load_state, Twin};
use crate::in_place::{elements, uninit};
use crate::integrator::Dp5;
use crate::scalar::{Real, Vec2};
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use nalgebra::SVector;

impl<T: Real> Twin<T> {
    /// A twin of `params` from `settings`' initial state, its first mode chosen by the
    /// consistency conditions under `inputs`, returned by value: building it needs
    /// several times its size of stack (219 KiB in f32, 445 KiB in f64 on the Cortex-M
    /// boards). For a `static` or a small stack, [`Twin::new_in`] builds the same twin
    /// where it lives.
    pub fn new(
        params: CccParams<T>,
        settings: TwinSettings<T>,
        inputs: Inputs<T>,
    ) -> Result<Self, TwinSetupError> {
        let (pose, mode) = setup(&params, &settings, &inputs)?;
        let (mut slot, mut spare) = (Slot::empty(), Slot::empty());
        let q = best_slot(
            &params,
            mode,
            &pose,
            0.0,
            settings.switch_below,
            &mut slot,
            &mut spare,
        )?;
        let mut twin = Twin {
            drive: params.drive.sign(),
            lossy: params.friction.active(),
            params,
            settings,
            slots: Slots {
                s: [slot.clone(), slot, spare],
                role: [0, 1, 2],
                reference: 2,
            },
            dp5: Dp5::new(),
            y: SVector::zeros(),
            t: T::zero(),
            steps: 0,
            inputs: Held::of(&inputs),
            links: [LinkState::default(); 9],
            shaft_angle: T::zero(),
            coast: Coast::default(),
            c: [T::zero(); 2],
            joints: [Vec2::zeros(); 11],
            guards: Guards::NONE,
            guard_rates: Guards::NONE,
            last_guards: None,
            audit: Audit::default(),
            events: heapless::Vec::new(),
            switches: heapless::Vec::new(),
            candidates: heapless::Vec::new(),
            torque_source: TorqueSource::Kinetostatics,
            at_rest: false,
            jumps: JumpHistory::NONE,
            pending: None,
            may_catch_up: false,
            behind: false,
            state_evaluated: false,
            broke_in: None,
        };
        twin.start_at(&q, &pose, &inputs)?;
        Ok(twin)
    }

    /// [`Twin::new`]'s twin built where it lives, in `place` (a `static`'s
    /// `MaybeUninit`, a `Box::new_uninit`): bit for bit the same twin, but nothing
    /// larger than a group's data (1.2 KB) is built on the stack: construction needs 7.2
    /// KiB of stack on a Cortex-M4F in f32 and 11.0 KiB on a Cortex-M7 in f64 (the first
    /// mode choice's frames, a step's), where `new` needs 219 and 445 KiB. On an error
    /// `place` holds a twin that must not be stepped (build it again).
    ///
    /// ```
    /// use core::mem::MaybeUninit;
    /// use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings};
    /// let inputs = Inputs { motor: MotorInput::Torque(20.0), load: 0.0, measured: None };
    /// let mut place = Box::new(MaybeUninit::uninit());
    /// let params = CccParams::<f64>::reference();
    /// let twin = Twin::new_in(&mut place, params, TwinSettings::reference(1e-4), inputs)?;
    /// twin.step(&inputs)?;
    /// assert_eq!(twin.steps(), 1);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new_in(
        place: &mut MaybeUninit<Self>,
        params: CccParams<T>,
        settings: TwinSettings<T>,
        inputs: Inputs<T>,
    ) -> Result<&mut Self, TwinSetupError> {
        let (pose, mode) = setup(&params, &settings, &inputs)?;
        let twin = Twin::init_shell(place, params, settings, inputs);
        let [slot, backup, spare] = &mut twin.slots.s;
        let q = best_slot(
            &twin.params,
            mode,
            &pose,
            0.0,
            twin.settings.switch_below,
            slot,
            spare,
        )?;
        backup.clone_from(slot);
        twin.start_at(&q, &pose, &inputs)?;
        Ok(twin)
    }

    /// Initialises `place` in place as a twin at rest with empty slots: the fields
    /// [`Twin::new`] sets before its slots are built.
    fn init_shell(
        place: &mut MaybeUninit<Self>,
        params: CccParams<T>,
        settings: TwinSettings<T>,
        inputs: Inputs<T>,
    ) -> &mut Self {
        let p = place.as_mut_ptr();
        // SAFETY: every field of `*p` is written once through a raw pointer to it (no
        // reference to an uninitialised field is made; `fields_of` below fails to
        // compile if a field is added and not listed there), the slots one by one by
        // their in-place constructor, so `*p` is initialised before `assume_init_mut`.
        unsafe {
            addr_of_mut!((*p).drive).write(params.drive.sign());
            addr_of_mut!((*p).lossy).write(params.friction.active());
            addr_of_mut!((*p).params).write(params);
            addr_of_mut!((*p).settings).write(settings);
            for s in elements(uninit(addr_of_mut!((*p).slots.s))) {
                Slot::init_empty(s);
            }
            addr_of_mut!((*p).slots.role).write([0, 1, 2]);
            addr_of_mut!((*p).slots.reference).write(2);
            addr_of_mut!((*p).dp5).write(Dp5::new());
            addr_of_mut!((*p).y).write(SVector::zeros());
            addr_of_mut!((*p).t).write(T::zero());
            addr_of_mut!((*p).steps).write(0);
            addr_of_mut!((*p).inputs).write(Held::of(&inputs));
            addr_of_mut!((*p).links).write([LinkState::default(); 9]);
            addr_of_mut!((*p).shaft_angle).write(T::zero());
            addr_of_mut!((*p).coast).write(Coast::default());
            addr_of_mut!((*p).c).write([T::zero(); 2]);
            addr_of_mut!((*p).joints).write([Vec2::zeros(); 11]);
            addr_of_mut!((*p).guards).write(Guards::NONE);
            addr_of_mut!((*p).guard_rates).write(Guards::NONE);
            addr_of_mut!((*p).last_guards).write(None);
            addr_of_mut!((*p).audit).write(Audit::default());
            addr_of_mut!((*p).events).write(heapless::Vec::new());
            addr_of_mut!((*p).switches).write(heapless::Vec::new());
            addr_of_mut!((*p).candidates).write(heapless::Vec::new());
            addr_of_mut!((*p).torque_source).write(TorqueSource::Kinetostatics);
            addr_of_mut!((*p).at_rest).write(false);
            addr_of_mut!((*p).jumps).write(JumpHistory::NONE);
            addr_of_mut!((*p).pending).write(None);
            addr_of_mut!((*p).may_catch_up).write(false);
            addr_of_mut!((*p).behind).write(false);
            addr_of_mut!((*p).state_evaluated).write(false);
            addr_of_mut!((*p).broke_in).write(None);
            place.assume_init_mut()
        }
    }

    /// The initial state from the current slot's coordinates `q` at the physical angles
    /// `pose`, and [`Twin::start`].
    fn start_at(
        &mut self,
        q: &[T; 2],
        pose: &[T; 9],
        inputs: &Inputs<T>,
    ) -> Result<(), TwinSetupError> {
        // Initial link speeds: those of the crank and the swing link (the others follow
        // from the kinematics; the first choice of a 2-DOF mode is crank + swing link).
        let mut omega = [T::zero(); 9];
        omega[CRANK] = self.settings.crank_speed;
        omega[4] = self.settings.swing_speed;
        load_state(self.slots.cur(), q, &omega, &mut self.y);
        if self.y.iter().any(|v| !v.finite()) {
            return Err(TwinSetupError::InitialState);
        }
        for (l, p) in self.links.iter_mut().zip(pose.iter()) {
            l.theta = *p;
        }
        self.start(inputs)?;
        Ok(())
    }

    /// The start at the initial state: its first evaluation, with the diode its first
    /// mode chosen by the consistency conditions, and the audit's initial energy.
    fn start(&mut self, inputs: &Inputs<T>) -> Result<(), TwinStepError> {
        let mut w = self.work_from_state();
        self.restart_at(&w, inputs)?;
        if self.settings.clutch {
            self.choose(&mut w, EventKind::Start, inputs)?;
        }
        self.settle_clutch_torques(&w, inputs)?;
        self.y = w.y;
        let links = self.slots.cur().links(&self.params);
        let audit = self.audit_of(&links, &w);
        audit_finite(&audit, w.t)?;
        self.commit(&w, audit, &links);
        let (k, u) = (self.audit.kinetic, self.audit.potential);
        self.audit.initial = k + u;
        Ok(())
    }
}

/// The checks of a new twin's parameters, settings and inputs, and its initial pose
/// and mode (I0 with the clutch in, else free).
fn setup<T: Real>(
    params: &CccParams<T>,
    settings: &TwinSettings<T>,
    inputs: &Inputs<T>,
) -> Result<([T; 9], Mode), TwinSetupError> {
    params.validate()?;
    check_settings(settings)?;
    check_inputs(inputs, T::zero())?;
    let pose =
        initial_pose(params, settings.crank, settings.swing).ok_or(TwinSetupError::Assembly {
            crank: settings.crank.to_f64(),
            swing: settings.swing.to_f64(),
        })?;
    let mode = if settings.clutch {
        Mode::I0
    } else {
        Mode::Free
    };
    Ok((pose, mode))
}

/// The fields [`Twin::init_shell`] writes: a field added to [`Twin`] and not there
/// fails to compile here.
#[allow(dead_code)]
fn fields_of<T: Real>(t: &Twin<T>) {
    let Twin {
        params: _,
        settings: _,
        drive: _,
        slots: Slots {
            s: _,
            role: _,
            reference: _,
        },
        dp5: _,
        y: _,
        t: _,
        steps: _,
        inputs: _,
        links: _,
        shaft_angle: _,
        coast: _,
        c: _,
        joints: _,
        guards: _,
        guard_rates: _,
        last_guards: _,
        audit: _,
        events: _,
        switches: _,
        candidates: _,
        torque_source: _,
        at_rest: _,
        lossy: _,
        jumps: _,
        pending: _,
        may_catch_up: _,
        behind: _,
        state_evaluated: _,
        broke_in: _,
    } = t;
}
