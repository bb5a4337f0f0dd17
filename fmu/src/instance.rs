//! One FMU instance in safe Rust: its FMI 2.0 state machine, its parameter and input
//! values, the twin it steps, and what it reports through its logger. The C functions
//! of [`crate::ffi`] are thin doors onto these methods.
//!
//! The communication step: every `fmi2DoStep` must advance a whole number n ≥ 1 of
//! the twin's fixed steps h (within 1e-6 h, the rounding of an importer's time grid),
//! starting at the FMU's own time (within 1e-6 h): the twin takes n steps of h under
//! the inputs held. Anything else is refused with `fmi2Error`, never interpolated.

use crate::variables::{lookup, vr, Kind, Role, Start, N_BOOL, N_REAL};
use core::mem::MaybeUninit;
use structomat::ccc::{Inputs, MotorInput, Twin, TwinSettings};

/// `fmi2Status`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// `fmi2OK`.
    Ok = 0,
    /// `fmi2Warning`.
    Warning = 1,
    /// `fmi2Discard`.
    Discard = 2,
    /// `fmi2Error`.
    Error = 3,
    /// `fmi2Fatal`.
    Fatal = 4,
    /// `fmi2Pending`.
    Pending = 5,
}

/// The FMI 2.0 Co-Simulation states an instance goes through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// After `fmi2Instantiate` or `fmi2Reset`: parameters and inputs may be set.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initialization,
    /// Stepping (`fmi2DoStep`).
    Step,
    /// After `fmi2Terminate`: outputs may be read.
    Terminated,
    /// After a call that returned `fmi2Error`: outputs (the last good state) may be
    /// read; only `fmi2Reset` makes it step again.
    Error,
}

impl Phase {
    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Instantiated => "instantiated",
            Phase::Initialization => "initialization mode",
            Phase::Step => "step mode",
            Phase::Terminated => "terminated",
            Phase::Error => "error (call fmi2Reset)",
        }
    }
}

/// Communication steps of more twin steps than this are refused (a bounded call).
pub const MAX_STEPS_PER_CALL: f64 = 1e8;

/// Relative tolerance, in h, of a communication point and step against the twin's
/// grid.
pub const GRID_TOL: f64 = 1e-6;

/// Where an instance's messages go: (status, category, message).
pub type Log = Box<dyn FnMut(Status, &'static str, &str)>;

/// A saved state of an instance (`fmi2GetFMUstate`): all that `fmi2SetFMUstate`
/// restores (the twin a copy, not a reference to the instance's).
pub struct Saved {
    phase: Phase,
    values: Start,
    start_time: f64,
    twin: Option<Box<Twin<f64>>>,
    dirty: bool,
}

/// One instance.
pub struct Instance {
    /// The instance name given to `fmi2Instantiate`.
    pub name: String,
    log: Log,
    /// Debug logging on (`loggingOn`, `fmi2SetDebugLogging`): mode changes are logged.
    pub logging_on: bool,
    phase: Phase,
    start: Start,
    values: Start,
    start_time: f64,
    twin: Box<MaybeUninit<Twin<f64>>>,
    /// `twin` holds a twin built from `values` (not stepped past a failed build).
    built: bool,
    /// A parameter or an input changed since the twin was built (in initialization).
    dirty: bool,
}

impl Instance {
    /// A new instance with start values `start`, telling `log` its messages.
    pub fn new(name: &str, start: Start, log: Log) -> Self {
        Instance {
            name: name.to_string(),
            log,
            logging_on: false,
            phase: Phase::Instantiated,
            start,
            values: start,
            start_time: 0.0,
            twin: Box::new_uninit(),
            built: false,
            dirty: true,
        }
    }

    /// The current state.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The twin, once built.
    pub fn twin(&self) -> Option<&Twin<f64>> {
        // SAFETY: `built` is set only after `Twin::new_in` initialised the place.
        self.built.then(|| unsafe { self.twin.assume_init_ref() })
    }

    /// Logs `msg` as an error, enters the error state and returns `fmi2Error`.
    pub fn fail(&mut self, msg: &str) -> Status {
        (self.log)(Status::Error, "logStatusError", msg);
        self.phase = Phase::Error;
        Status::Error
    }

    /// Logs `msg` at `status` in `category`.
    pub fn log(&mut self, status: Status, category: &'static str, msg: &str) {
        (self.log)(status, category, msg);
    }

    /// `fmi2Reset`: back to the state after `fmi2Instantiate`, the start values set.
    pub fn reset(&mut self) -> Status {
        self.values = self.start;
        self.phase = Phase::Instantiated;
        self.start_time = 0.0;
        self.built = false;
        self.dirty = true;
        Status::Ok
    }

    /// `fmi2GetFMUstate`: a copy of the present state.
    pub fn save(&self) -> Saved {
        Saved {
            phase: self.phase,
            values: self.values,
            start_time: self.start_time,
            twin: self.twin().map(|t| Box::new(t.clone())),
            dirty: self.dirty,
        }
    }

    /// `fmi2GetFMUstate` over a state it returned before: the present state copied
    /// into `saved` (its twin's allocation reused).
    pub fn save_into(&self, saved: &mut Saved) {
        saved.phase = self.phase;
        saved.values = self.values;
        saved.start_time = self.start_time;
        saved.dirty = self.dirty;
        match (self.twin(), &mut saved.twin) {
            (Some(t), Some(s)) => (**s).clone_from(t),
            (Some(t), none) => *none = Some(Box::new(t.clone())),
            (None, s) => *s = None,
        }
    }

    /// `fmi2SetFMUstate`: back to `saved` (also from the error state: a rollback to a
    /// state before a failed step).
    pub fn restore(&mut self, saved: &Saved) -> Status {
        match &saved.twin {
            Some(t) if self.built => {
                // SAFETY: `built`: the place holds a twin.
                unsafe { self.twin.assume_init_mut() }.clone_from(t);
            }
            Some(t) => {
                self.twin.write(Twin::clone(t));
                self.built = true;
            }
            None => self.built = false,
        }
        self.phase = saved.phase;
        self.values = saved.values;
        self.start_time = saved.start_time;
        self.dirty = saved.dirty;
        Status::Ok
    }

    /// `fmi2SetupExperiment`: the start time (the tolerance and stop time are not
    /// used: the twin's step is fixed by h).
    pub fn setup_experiment(&mut self, start_time: f64) -> Status {
        if self.phase != Phase::Instantiated {
            return self.refuse("fmi2SetupExperiment");
        }
        if !start_time.is_finite() {
            return self.fail(&format!(
                "fmi2SetupExperiment: startTime = {start_time} is not finite"
            ));
        }
        self.start_time = start_time;
        Status::Ok
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Status {
        if self.phase != Phase::Instantiated {
            return self.refuse("fmi2EnterInitializationMode");
        }
        self.phase = Phase::Initialization;
        Status::Ok
    }

    /// `fmi2ExitInitializationMode`: builds the twin from the parameters and inputs.
    pub fn exit_initialization(&mut self) -> Status {
        if self.phase != Phase::Initialization {
            return self.refuse("fmi2ExitInitializationMode");
        }
        if let Err(e) = self.ensure_built() {
            return self.fail(&format!("fmi2ExitInitializationMode: {e}"));
        }
        self.phase = Phase::Step;
        Status::Ok
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        match self.phase {
            Phase::Step | Phase::Error => {
                self.phase = Phase::Terminated;
                Status::Ok
            }
            _ => self.refuse("fmi2Terminate"),
        }
    }

    /// A call not allowed in the present state: `fmi2Error`, named.
    fn refuse(&mut self, call: &str) -> Status {
        let phase = self.phase.name();
        self.fail(&format!("{call} is not allowed in state {phase}"))
    }

    /// The twin's inputs of the present values.
    fn inputs(&self) -> Inputs<f64> {
        Inputs {
            motor: MotorInput::Torque(self.values.reals[vr::MOTOR as usize]),
            load: self.values.reals[vr::LOAD as usize],
            measured: None,
        }
    }

    /// The twin of the present values, built unless it already is.
    fn ensure_built(&mut self) -> Result<(), String> {
        if self.built && !self.dirty {
            return Ok(());
        }
        let v = &self.values;
        let r = |k: u32| v.reals[k as usize];
        let mut ts = TwinSettings::reference(r(vr::H));
        ts.clutch = v.bools[vr::CLUTCH as usize];
        ts.crank = r(vr::CRANK_DEG).to_radians();
        ts.swing = r(vr::SWING_DEG).to_radians();
        ts.crank_speed = r(vr::CRANK_SPEED0);
        ts.swing_speed = r(vr::SWING_SPEED0);
        let params = v.params();
        let inputs = self.inputs();
        self.built = false;
        match Twin::new_in(&mut self.twin, params, ts, inputs) {
            Ok(_) => {
                self.built = true;
                self.dirty = false;
                Ok(())
            }
            Err(e) => Err(format!("the converter's twin cannot be set up: {e}")),
        }
    }

    /// Whether variable `(kind, r)`, a parameter or input, may be set now; `Err`: why not.
    fn settable(&self, kind: Kind, r: u32) -> Result<(&'static str, Role), String> {
        let Some((_, v)) = lookup(kind, r) else {
            return Err(format!("no {kind:?} variable has value reference {r}"));
        };
        let ok = match (v.role, self.phase) {
            (Role::Output, _) => false,
            (_, Phase::Instantiated | Phase::Initialization) => true,
            (Role::Input, Phase::Step) => true,
            _ => false,
        };
        if ok {
            Ok((v.name, v.role))
        } else if v.role == Role::Output {
            Err(format!("{} is an output: it cannot be set", v.name))
        } else {
            Err(format!(
                "{} cannot be set in state {} (a parameter is fixed once initialization ends)",
                v.name,
                self.phase.name()
            ))
        }
    }

    /// `fmi2SetReal`. A non-finite value is refused, named.
    pub fn set_real(&mut self, refs: &[u32], values: &[f64]) -> Status {
        for (&r, &x) in refs.iter().zip(values) {
            let name = match self.settable(Kind::Real, r) {
                Ok((name, _)) => name,
                Err(e) => return self.fail(&format!("fmi2SetReal: {e}")),
            };
            if !x.is_finite() {
                return self.fail(&format!(
                    "fmi2SetReal: {name} = {x} is not a finite number (value reference {r})"
                ));
            }
            self.values.reals[r as usize] = x;
            self.dirty |= self.phase != Phase::Step;
        }
        Status::Ok
    }

    /// `fmi2SetBoolean`.
    pub fn set_boolean(&mut self, refs: &[u32], values: &[bool]) -> Status {
        for (&r, &x) in refs.iter().zip(values) {
            if let Err(e) = self.settable(Kind::Boolean, r) {
                return self.fail(&format!("fmi2SetBoolean: {e}"));
            }
            self.values.bools[r as usize] = x;
            self.dirty = true;
        }
        Status::Ok
    }

    /// `fmi2SetInteger` (the one Integer is an output) and `fmi2SetString` (none).
    pub fn set_other(&mut self, call: &str, kind: &str, refs: &[u32]) -> Status {
        match refs.first() {
            None => Status::Ok,
            Some(r) => self.fail(&format!(
                "{call}: no settable {kind} variable has value reference {r}"
            )),
        }
    }

    /// Whether outputs can be read now (building the twin in initialization mode).
    fn outputs_ready(&mut self, call: &str) -> Result<(), Status> {
        match self.phase {
            Phase::Initialization => self
                .ensure_built()
                .map_err(|e| self.fail(&format!("{call}: {e}"))),
            Phase::Step | Phase::Terminated | Phase::Error if self.built => Ok(()),
            _ => Err(self.fail(&format!(
                "{call}: the outputs are not known in state {} (before fmi2EnterInitializationMode, or after a failed set-up)",
                self.phase.name()
            ))),
        }
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, refs: &[u32], values: &mut [f64]) -> Status {
        // A reference that names no variable is the importer's error, said first (not
        // the outputs' state, nor a set-up it would trigger).
        if let Some(r) = refs.iter().find(|&&r| r as usize >= N_REAL) {
            return self.fail(&format!(
                "fmi2GetReal: no Real variable has value reference {r}"
            ));
        }
        let any_output = refs.iter().any(|&r| r >= vr::FIRST_OUTPUT);
        if any_output {
            if let Err(s) = self.outputs_ready("fmi2GetReal") {
                return s;
            }
        }
        for (&r, x) in refs.iter().zip(values.iter_mut()) {
            if r as usize >= N_REAL {
                return self.fail(&format!(
                    "fmi2GetReal: no Real variable has value reference {r}"
                ));
            }
            *x = match self.twin().filter(|_| r >= vr::FIRST_OUTPUT) {
                Some(t) => output(t, r),
                None => self.values.reals[r as usize],
            };
        }
        Status::Ok
    }

    /// `fmi2GetInteger`: the mode's code.
    pub fn get_integer(&mut self, refs: &[u32], values: &mut [i32]) -> Status {
        if refs.is_empty() {
            return Status::Ok;
        }
        if let Err(s) = self.outputs_ready("fmi2GetInteger") {
            return s;
        }
        for (&r, x) in refs.iter().zip(values.iter_mut()) {
            match (r, self.twin()) {
                (vr::MODE, Some(t)) => *x = i32::from(t.mode().code()),
                _ => {
                    return self.fail(&format!(
                        "fmi2GetInteger: no Integer variable has value reference {r}"
                    ))
                }
            }
        }
        Status::Ok
    }

    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, refs: &[u32], values: &mut [bool]) -> Status {
        for (&r, x) in refs.iter().zip(values.iter_mut()) {
            match self.values.bools.get(r as usize) {
                Some(b) => *x = *b,
                None => {
                    return self.fail(&format!(
                        "fmi2GetBoolean: no Boolean variable has value reference {r} (0..{N_BOOL})"
                    ))
                }
            }
        }
        Status::Ok
    }

    /// The FMU's time: the start time plus the twin's, s.
    pub fn time(&self) -> f64 {
        self.start_time + self.twin().map_or(0.0, |t| t.time())
    }

    /// `fmi2DoStep`: n = `dt` / h steps of the twin from `t` (the FMU's time) under
    /// the inputs held. A step that fails is `fmi2Error` with the twin's message, the
    /// twin keeps its last good state and the instance refuses to step until
    /// `fmi2Reset`.
    pub fn do_step(&mut self, t: f64, dt: f64) -> Status {
        if self.phase != Phase::Step {
            return self.refuse("fmi2DoStep");
        }
        let h = self.values.reals[vr::H as usize];
        let now = self.time();
        if !(t.is_finite() && (t - now).abs() <= GRID_TOL * h) {
            return self.fail(&format!(
                "fmi2DoStep: currentCommunicationPoint = {t} s is not the FMU's time {now} s"
            ));
        }
        let n = (dt / h).round();
        if !(dt.is_finite() && n >= 1.0 && (dt - n * h).abs() <= GRID_TOL * h) {
            return self.fail(&format!(
                "fmi2DoStep: communicationStepSize = {dt} s is not a whole multiple n >= 1 of the twin's step h = {h} s"
            ));
        }
        if n > MAX_STEPS_PER_CALL {
            return self.fail(&format!(
                "fmi2DoStep: communicationStepSize = {dt} s is {n} steps of h, over {MAX_STEPS_PER_CALL}"
            ));
        }
        let inputs = self.inputs();
        let logging = self.logging_on;
        let mut events = Vec::new();
        let mut failed = None;
        // SAFETY: in step mode the twin is built (`exit_initialization`).
        let twin = unsafe { self.twin.assume_init_mut() };
        for _ in 0..n as u64 {
            if let Err(e) = twin.step(&inputs) {
                failed = Some(format!(
                    "fmi2DoStep: the twin's step from t = {} s failed: {e}",
                    self.start_time + twin.time()
                ));
                break;
            }
            if logging {
                for e in twin.events() {
                    events.push(format!(
                        "t = {} s: {} {} -> {}",
                        self.start_time + e.time,
                        e.kind.name(),
                        e.from,
                        e.to
                    ));
                }
            }
        }
        for e in &events {
            self.log(Status::Ok, "logEvents", e);
        }
        match failed {
            Some(msg) => self.fail(&msg),
            None => Status::Ok,
        }
    }
}

/// Output `r` (a Real value reference ≥ [`vr::FIRST_OUTPUT`]) of the twin's state.
fn output(t: &Twin<f64>, r: u32) -> f64 {
    let crank = t.link(1);
    let [c6, c8] = t.clutch_torques();
    let a = t.audit();
    match r - vr::FIRST_OUTPUT {
        0 => crank.theta,
        1 => crank.omega,
        2 => t.shaft_angle(),
        3 => t.shaft_speed(),
        4 => c6,
        5 => c8,
        6 => a.kinetic,
        7 => a.potential,
        8 => a.motor_work,
        9 => a.load_work,
        10 => a.impact_loss,
        _ => a.residual(),
    }
}
