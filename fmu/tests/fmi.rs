//! The FMU's C functions called as an importer calls them (through their Rust
//! signatures, with a logger callback), against the core's twin stepped directly:
//! S2 through fmi2DoStep is the twin's S2 bit for bit; a NaN input, a refused twin
//! step and a communication step off the twin's grid are fmi2Error with their message
//! in the log; fmi2Reset makes the instance usable again.

use core::ffi::{c_char, c_int, c_void, CStr};
use std::ffi::CString;
use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings};
use structomat_fmu::description::Description;
use structomat_fmu::ffi::*;
use structomat_fmu::instance::Status;
use structomat_fmu::variables::{vr, N_REAL};

/// The messages an instance logged: (status, category, message).
type Messages = Vec<(Status, String, String)>;

/// The logger: appends to the `Messages` behind `env`. Declared without the variadic
/// tail (the FMU passes none: its messages have no conversion left, `%` doubled).
unsafe extern "C" fn logger(
    env: *mut c_void,
    _name: *const c_char,
    status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    let log = unsafe { &mut *env.cast::<Messages>() };
    let text = |p| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    log.push((status, text(category), text(message)));
}

/// An instance with the default start values, logging into `log`.
struct Fmu {
    c: Component,
    log: Box<Messages>,
    _callbacks: Box<CallbackFunctions>,
}

impl Fmu {
    fn new() -> Self {
        Fmu::with_guid(&Description::default().guid(), CO_SIMULATION).expect("instantiates")
    }

    fn with_guid(guid: &str, kind: c_int) -> Result<Self, Messages> {
        let mut log: Box<Messages> = Box::default();
        // SAFETY: the same C ABI for the named arguments; no variadic one is passed.
        let f: Logger =
            unsafe { core::mem::transmute::<unsafe extern "C" fn(_, _, _, _, _), Logger>(logger) };
        let callbacks = Box::new(CallbackFunctions {
            logger: Some(f),
            allocate_memory: None,
            free_memory: None,
            step_finished: None,
            component_environment: (&mut *log as *mut Messages).cast(),
        });
        let (name, guid) = (CString::new("twin").unwrap(), CString::new(guid).unwrap());
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                kind,
                guid.as_ptr(),
                core::ptr::null(),
                &*callbacks,
                0,
                0,
            )
        };
        if c.is_null() {
            return Err(*log);
        }
        Ok(Fmu {
            c,
            log,
            _callbacks: callbacks,
        })
    }

    fn init(&self) {
        assert_eq!(fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0), Status::Ok);
        assert_eq!(fmi2EnterInitializationMode(self.c), Status::Ok);
        assert_eq!(fmi2ExitInitializationMode(self.c), Status::Ok);
    }

    fn set(&self, r: u32, x: f64) -> Status {
        unsafe { fmi2SetReal(self.c, &r, 1, &x) }
    }

    fn reals(&self) -> [f64; N_REAL] {
        let refs: Vec<u32> = (0..N_REAL as u32).collect();
        let mut v = [0.0; N_REAL];
        let s = unsafe { fmi2GetReal(self.c, refs.as_ptr(), N_REAL, v.as_mut_ptr()) };
        assert_eq!(s, Status::Ok, "{:?}", self.log);
        v
    }

    fn mode(&self) -> i32 {
        let mut m = -1;
        let s = unsafe { fmi2GetInteger(self.c, &vr::MODE, 1, &mut m) };
        assert_eq!(s, Status::Ok);
        m
    }

    fn last(&self) -> &str {
        self.log.last().map_or("", |m| m.2.as_str())
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

/// The outputs of the twin in the FMU's order: crank angle and speed, shaft angle and
/// speed, c6, c8, the audit's kinetic, potential, motor work, load work, impact loss
/// and residual.
fn outputs(t: &Twin<f64>) -> [f64; 12] {
    let (c, a) = (t.link(1), t.audit());
    let [c6, c8] = t.clutch_torques();
    [
        c.theta,
        c.omega,
        t.shaft_angle(),
        t.shaft_speed(),
        c6,
        c8,
        a.kinetic,
        a.potential,
        a.motor_work,
        a.load_work,
        a.impact_loss,
        a.residual(),
    ]
}

fn s2_twin(h: f64) -> Twin<f64> {
    let inputs = Inputs {
        motor: MotorInput::Torque(12.0),
        load: 800.0,
        measured: None,
    };
    Twin::new(CccParams::reference(), TwinSettings::reference(h), inputs).unwrap()
}

/// The FMU's outputs equal the twin's, bit for bit, and its mode code.
fn same(fmu: &Fmu, twin: &Twin<f64>, what: &str) {
    let got = fmu.reals();
    let want = outputs(twin);
    for (k, w) in want.iter().enumerate() {
        let g = got[vr::FIRST_OUTPUT as usize + k];
        assert_eq!(g.to_bits(), w.to_bits(), "{what}: output {k}: {g} vs {w}");
    }
    assert_eq!(fmu.mode(), i32::from(twin.mode().code()), "{what}: mode");
}

// S2 through fmi2DoStep at the communication step h (the time grid as FMPy makes it,
// k·h) is the core's twin stepped directly, every output bit for bit, through the
// first breakaway (0.0666 s) and the events after it.
#[test]
fn s2_through_do_step_is_the_twin_bit_for_bit() {
    let h = 1e-4;
    let fmu = Fmu::new();
    fmu.init();
    let mut twin = s2_twin(h);
    same(&fmu, &twin, "t = 0");
    let mut modes = std::collections::BTreeSet::new();
    for k in 0..2500u32 {
        let t = f64::from(k) * h;
        assert_eq!(fmi2DoStep(fmu.c, t, h, 1), Status::Ok, "{:?}", fmu.log);
        twin.step(&Inputs {
            motor: MotorInput::Torque(12.0),
            load: 800.0,
            measured: None,
        })
        .unwrap();
        same(&fmu, &twin, &format!("step {}", k + 1));
        modes.insert(fmu.mode());
    }
    assert!(
        modes.len() >= 3,
        "S2 goes through several modes by 0.25 s: {modes:?}"
    );
    let mut t = 0.0;
    assert_eq!(unsafe { fmi2GetRealStatus(fmu.c, 2, &mut t) }, Status::Ok);
    assert!((t - 0.25).abs() < 1e-12, "{t}");
    assert_eq!(fmi2Terminate(fmu.c), Status::Ok);
}

// A communication step of 10 h is ten twin steps; h is a parameter set before
// initialization.
#[test]
fn a_communication_step_is_whole_steps_of_h() {
    let h = 2e-4;
    let fmu = Fmu::new();
    assert_eq!(fmu.set(vr::H, h), Status::Ok);
    fmu.init();
    let mut twin = s2_twin(h);
    for k in 0..30u32 {
        assert_eq!(
            fmi2DoStep(fmu.c, f64::from(k) * 10.0 * h, 10.0 * h, 1),
            Status::Ok
        );
        for _ in 0..10 {
            twin.step(&Inputs {
                motor: MotorInput::Torque(12.0),
                load: 800.0,
                measured: None,
            })
            .unwrap();
        }
    }
    same(&fmu, &twin, "60 ms in 30 communication steps");
    // 1.5 h is refused, named.
    let t = 300.0 * h;
    assert_eq!(fmi2DoStep(fmu.c, t, 1.5 * h, 1), Status::Error);
    assert!(
        fmu.last().contains("not a whole multiple"),
        "{}",
        fmu.last()
    );
    assert_eq!(fmu.log.last().unwrap().1, "logStatusError");
}

// A NaN input is fmi2Error naming the input; further steps are refused until
// fmi2Reset, after which the FMU runs S2 again as a new twin does.
#[test]
fn nan_input_is_an_error_named_and_reset_recovers() {
    let h = 1e-4;
    let fmu = Fmu::new();
    fmu.init();
    assert_eq!(fmi2DoStep(fmu.c, 0.0, h, 1), Status::Ok);
    assert_eq!(fmu.set(vr::MOTOR, f64::NAN), Status::Error);
    let (status, cat, msg) = fmu.log.last().unwrap().clone();
    assert_eq!((status, cat.as_str()), (Status::Error, "logStatusError"));
    assert!(msg.contains("motor_torque") && msg.contains("NaN"), "{msg}");
    assert_eq!(fmi2DoStep(fmu.c, h, h, 1), Status::Error);
    assert!(
        fmu.last().contains("not allowed in state error"),
        "{}",
        fmu.last()
    );
    assert_eq!(fmi2Reset(fmu.c), Status::Ok);
    fmu.init();
    let mut twin = s2_twin(h);
    same(&fmu, &twin, "after reset");
    for k in 0..20u32 {
        assert_eq!(fmi2DoStep(fmu.c, f64::from(k) * h, h, 1), Status::Ok);
        twin.step(&Inputs {
            motor: MotorInput::Torque(12.0),
            load: 800.0,
            measured: None,
        })
        .unwrap();
    }
    same(&fmu, &twin, "20 steps after reset");
}

// A twin step that fails (a negative load: the core refuses it) is fmi2Error with the
// twin's own message; the outputs keep the last good state; fmi2Reset recovers.
#[test]
fn a_failed_twin_step_is_an_error_with_its_message() {
    let h = 1e-4;
    let fmu = Fmu::new();
    fmu.init();
    for k in 0..5u32 {
        assert_eq!(fmi2DoStep(fmu.c, f64::from(k) * h, h, 1), Status::Ok);
    }
    let good = fmu.reals();
    assert_eq!(fmu.set(vr::LOAD, -1.0), Status::Ok);
    assert_eq!(fmi2DoStep(fmu.c, 5.0 * h, h, 1), Status::Error);
    let msg = fmu.last().to_string();
    assert!(msg.contains("fmi2DoStep") && msg.contains("load"), "{msg}");
    let o = vr::FIRST_OUTPUT as usize;
    assert_eq!(fmu.reals()[o..], good[o..], "the last good state is kept");
    assert_eq!(fmi2DoStep(fmu.c, 5.0 * h, h, 1), Status::Error);
    assert_eq!(fmi2Reset(fmu.c), Status::Ok);
    fmu.init();
    assert_eq!(fmi2DoStep(fmu.c, 0.0, h, 1), Status::Ok);
}

// Calls out of order and values that cannot be set are errors, named.
#[test]
fn misuse_is_named() {
    let fmu = Fmu::new();
    assert_eq!(fmi2DoStep(fmu.c, 0.0, 1e-4, 1), Status::Error);
    assert!(fmu
        .last()
        .contains("fmi2DoStep is not allowed in state instantiated"));
    assert_eq!(fmi2Reset(fmu.c), Status::Ok);
    fmu.init();
    assert_eq!(fmu.set(vr::MASS, 7.0), Status::Error);
    assert!(
        fmu.last().contains("mass cannot be set in state step mode"),
        "{}",
        fmu.last()
    );
    assert_eq!(fmi2Reset(fmu.c), Status::Ok);
    assert_eq!(fmu.set(vr::FIRST_OUTPUT, 1.0), Status::Error);
    assert!(
        fmu.last().contains("crank_angle is an output"),
        "{}",
        fmu.last()
    );
    assert_eq!(fmi2Reset(fmu.c), Status::Ok);
    // A converter that does not assemble fails at the end of initialization.
    assert_eq!(fmu.set(vr::LINK, 5.0), Status::Ok);
    assert_eq!(fmi2EnterInitializationMode(fmu.c), Status::Ok);
    assert_eq!(fmi2ExitInitializationMode(fmu.c), Status::Error);
    assert!(fmu.last().contains("cannot be set up"), "{}", fmu.last());
    assert_eq!(
        fmi2SerializedFMUstateSize(fmu.c, core::ptr::null_mut(), core::ptr::null_mut()),
        Status::Error
    );
    assert!(fmu.last().contains("canSerializeFMUstate is false"));
    assert_eq!(
        fmi2DoStep(core::ptr::null_mut(), 0.0, 1e-4, 1),
        Status::Error
    );
}

// fmi2Instantiate refuses Model Exchange and a GUID that is not the description's.
#[test]
fn instantiate_checks_type_and_guid() {
    let log = Fmu::with_guid(&Description::default().guid(), 0)
        .err()
        .unwrap();
    assert!(log[0].2.contains("Co-Simulation"), "{log:?}");
    let log = Fmu::with_guid("{0}", CO_SIMULATION).err().unwrap();
    assert!(log[0].2.contains("GUID {0}"), "{log:?}");
    let v = unsafe { CStr::from_ptr(fmi2GetVersion()) };
    assert_eq!(v.to_str(), Ok("2.0"));
    let p = unsafe { CStr::from_ptr(fmi2GetTypesPlatform()) };
    assert_eq!(p.to_str(), Ok("default"));
}

// A saved FMU state restored replays the same steps bit for bit, also after a failed
// call put the instance in its error state (a rollback); a state saved over is reused.
#[test]
fn a_saved_state_replays_bit_for_bit() {
    let h = 1e-4;
    let fmu = Fmu::new();
    fmu.init();
    let step = |k: u32| fmi2DoStep(fmu.c, f64::from(k) * h, h, 1);
    for k in 0..600 {
        assert_eq!(step(k), Status::Ok);
    }
    let mut state: FmuState = core::ptr::null_mut();
    assert_eq!(unsafe { fmi2GetFMUstate(fmu.c, &mut state) }, Status::Ok);
    assert!(!state.is_null());
    let first = state;
    // Saving again over the same state reuses it.
    assert_eq!(unsafe { fmi2GetFMUstate(fmu.c, &mut state) }, Status::Ok);
    assert_eq!(state, first);
    for k in 600..900 {
        assert_eq!(step(k), Status::Ok);
    }
    let (end, mode) = (fmu.reals(), fmu.mode());
    assert_eq!(fmu.set(vr::LOAD, f64::NAN), Status::Error);
    assert_eq!(unsafe { fmi2SetFMUstate(fmu.c, state) }, Status::Ok);
    for k in 600..900 {
        assert_eq!(step(k), Status::Ok, "{:?}", fmu.log.last());
    }
    let again = fmu.reals();
    for k in 0..N_REAL {
        assert_eq!(again[k].to_bits(), end[k].to_bits(), "value reference {k}");
    }
    assert_eq!(fmu.mode(), mode);
    // Into a fresh instance (not yet initialized) too.
    let other = Fmu::new();
    assert_eq!(unsafe { fmi2SetFMUstate(other.c, state) }, Status::Ok);
    for k in 600..900 {
        assert_eq!(fmi2DoStep(other.c, f64::from(k) * h, h, 1), Status::Ok);
    }
    assert_eq!(other.reals(), end);
    assert_eq!(unsafe { fmi2FreeFMUstate(fmu.c, &mut state) }, Status::Ok);
    assert!(state.is_null());
}

// A machine's losses set as parameters (every joint's viscous and dry coefficient, ε,
// the clutches' drag) make the FMU the core's twin of that machine, bit for bit through
// S2's first 0.1 s; the twin without them is another machine (its outputs differ): the
// parameters reach the twin.
#[test]
fn friction_parameters_are_the_twin_s_friction() {
    let h = 1e-4;
    let mut p = CccParams::reference();
    for k in 0..9 {
        p.friction.viscous[k] = 0.01 + 0.002 * k as f64;
        p.friction.coulomb[k] = 0.02 + 0.001 * k as f64;
    }
    p.friction.coulomb_eps = 0.02;
    p.friction.clutch_drag = 0.03;
    let fmu = Fmu::new();
    let f = vr::FRICTION;
    for k in 0..9u32 {
        assert_eq!(fmu.set(f + k, p.friction.viscous[k as usize]), Status::Ok);
        assert_eq!(
            fmu.set(f + 9 + k, p.friction.coulomb[k as usize]),
            Status::Ok
        );
    }
    assert_eq!(fmu.set(f + 18, p.friction.coulomb_eps), Status::Ok);
    assert_eq!(fmu.set(f + 19, p.friction.clutch_drag), Status::Ok);
    fmu.init();
    let inputs = Inputs {
        motor: MotorInput::Torque(12.0),
        load: 800.0,
        measured: None,
    };
    let mut twin = Twin::new(p, TwinSettings::reference(h), inputs).unwrap();
    let mut ideal = s2_twin(h);
    for k in 0..1000u32 {
        assert_eq!(
            fmi2DoStep(fmu.c, f64::from(k) * h, h, 1),
            Status::Ok,
            "{:?}",
            fmu.log
        );
        twin.step(&inputs).unwrap();
        ideal.step(&inputs).unwrap();
        same(&fmu, &twin, &format!("step {}", k + 1));
    }
    assert_ne!(
        outputs(&twin),
        outputs(&ideal),
        "the losses changed nothing"
    );
    // A coefficient the core refuses is named at initialization.
    let bad = Fmu::new();
    assert_eq!(bad.set(f + 18, 0.0), Status::Ok);
    assert_eq!(fmi2SetupExperiment(bad.c, 0, 0.0, 0.0, 0, 0.0), Status::Ok);
    assert_eq!(fmi2EnterInitializationMode(bad.c), Status::Ok);
    assert_eq!(fmi2ExitInitializationMode(bad.c), Status::Error);
    assert!(bad.last().contains("coulomb_eps"), "{}", bad.last());
}

// Null arrays with a count > 0 are the importer's error on every call that takes
// arrays, named (they returned fmi2OK for the String and Integer setters); a value
// reference that names no variable is said as such, before the outputs' state.
#[test]
fn null_arrays_and_unknown_references_are_named() {
    let fmu = Fmu::new();
    let null_vr = core::ptr::null::<u32>();
    let mut s: FmiString = core::ptr::null();
    let r = [0u32];
    let cases: [(&str, Status); 4] = [
        ("fmi2GetString", unsafe {
            fmi2GetString(fmu.c, null_vr, 3, &mut s)
        }),
        ("fmi2SetInteger", unsafe {
            fmi2SetInteger(fmu.c, r.as_ptr(), 1, core::ptr::null())
        }),
        ("fmi2SetString", unsafe {
            fmi2SetString(fmu.c, null_vr, 2, core::ptr::null())
        }),
        ("fmi2SetDebugLogging", unsafe {
            fmi2SetDebugLogging(fmu.c, 1, 2, core::ptr::null())
        }),
    ];
    for (call, status) in cases {
        assert_eq!(status, Status::Error, "{call}");
    }
    let nulls = fmu
        .log
        .iter()
        .filter(|m| m.2.contains("a null array"))
        .count();
    assert_eq!(nulls, 4, "{:?}", fmu.log);
    let mut v = 0.0;
    assert_eq!(
        unsafe { fmi2GetReal(fmu.c, &1000, 1, &mut v) },
        Status::Error
    );
    assert!(
        fmu.last()
            .contains("no Real variable has value reference 1000"),
        "{}",
        fmu.last()
    );
}
