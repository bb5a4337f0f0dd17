//! Every FMI 2.0 function (fmi2Functions.h: the common ones, Co-Simulation's and Model
//! Exchange's), exported under its own name as the FMI 2.0 standard's C API. Each one
//! checks its pointers, runs its body inside `catch_unwind` (no panic crosses into the
//! importer: a caught one is `fmi2Fatal`, logged) and hands over to
//! [`Instance`]. The FMU state is saved and restored
//! (`fmi2GetFMUstate`, a copy of the twin); Model Exchange's functions, the state's
//! serialization and directional derivatives are not offered by this Co-Simulation FMU
//! (modelDescription.xml says so): they return `fmi2Error` with a message.

#![allow(non_snake_case)]
#![allow(clippy::missing_safety_doc)]

use crate::description::{Description, LOG_CATEGORIES};
use crate::instance::{Instance, Log, Saved, Status};
use crate::variables::Start;
use core::ffi::{c_char, c_int, c_void, CStr};
use std::ffi::CString;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// `fmi2Component`: the instance.
pub type Component = *mut c_void;
/// `fmi2ComponentEnvironment`.
pub type Environment = *mut c_void;
/// `fmi2FMUstate`.
pub type FmuState = *mut c_void;
/// `fmi2ValueReference`.
pub type ValueReference = u32;
/// `fmi2Boolean`.
pub type Boolean = c_int;
/// `fmi2String`.
pub type FmiString = *const c_char;

/// `fmi2CallbackLogger`: `(environment, instanceName, status, category, message, ...)`,
/// the message a printf format.
pub type Logger = unsafe extern "C" fn(Environment, FmiString, Status, FmiString, FmiString, ...);

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    /// The logger (may be null: nothing is logged).
    pub logger: Option<Logger>,
    /// `allocateMemory` (not used: canNotUseMemoryManagementFunctions).
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// `freeMemory` (not used).
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// `stepFinished` (not used: doStep is synchronous).
    pub step_finished: Option<unsafe extern "C" fn(Environment, Status)>,
    /// `componentEnvironment`, handed back to the logger.
    pub component_environment: Environment,
}

/// `fmi2Type`: fmi2ModelExchange = 0, fmi2CoSimulation = 1.
pub const CO_SIMULATION: c_int = 1;

/// The text of a message for a printf-format logger: `%` doubled.
fn c_message(s: &str) -> CString {
    let text = s.replace('%', "%%").replace('\0', " ");
    CString::new(text).unwrap_or_default()
}

/// A [`Log`] that calls the importer's logger with `env` and the instance name.
fn c_log(logger: Option<Logger>, env: Environment, name: &str) -> Log {
    let name = c_message(name);
    Box::new(move |status, category, msg| {
        if let Some(f) = logger {
            let cat = c_message(category);
            let msg = c_message(msg);
            // SAFETY: the importer's logger, with the environment it gave and
            // NUL-terminated strings that live over the call; the message has no
            // conversion specification left (`%` doubled), so no variadic argument is
            // read.
            unsafe { f(env, name.as_ptr(), status, cat.as_ptr(), msg.as_ptr()) };
        }
    })
}

/// Runs `body` on the instance behind `c`; a null `c` is `fmi2Error`, a panic
/// `fmi2Fatal` (logged, and the instance left in its error state).
fn with(c: Component, body: impl FnOnce(&mut Instance) -> Status) -> Status {
    if c.is_null() {
        return Status::Error;
    }
    // SAFETY: a non-null component is an instance from `fmi2Instantiate`, not yet
    // freed, used by one thread at a time (FMI 2.0 2.1.3).
    let inst = unsafe { &mut *c.cast::<Instance>() };
    match catch_unwind(AssertUnwindSafe(|| body(inst))) {
        Ok(s) => s,
        Err(_) => {
            let _ = catch_unwind(AssertUnwindSafe(|| {
                inst.fail("internal error: a panic was caught at the FMI boundary");
            }));
            Status::Fatal
        }
    }
}

/// The slice of `n` elements at `p` (empty for `n` = 0 or a null `p`).
///
/// # Safety
/// A non-null `p` must point to `n` valid elements.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> &'a [T] {
    if p.is_null() || n == 0 {
        &[]
    } else {
        // SAFETY: the caller's.
        unsafe { core::slice::from_raw_parts(p, n) }
    }
}

/// The mutable slice of `n` elements at `p`.
///
/// # Safety
/// A non-null `p` must point to `n` valid, writable elements.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> &'a mut [T] {
    if p.is_null() || n == 0 {
        &mut []
    } else {
        // SAFETY: the caller's.
        unsafe { core::slice::from_raw_parts_mut(p, n) }
    }
}

/// A C string's text ("" for null).
///
/// # Safety
/// A non-null `s` must be NUL-terminated.
unsafe fn text(s: FmiString) -> String {
    if s.is_null() {
        String::new()
    } else {
        // SAFETY: the caller's.
        unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned()
    }
}

/// Null pointers given with a count > 0: `fmi2Error`, named.
fn null_args(inst: &mut Instance, call: &str, n: usize, ptrs: &[bool]) -> Option<Status> {
    (n > 0 && ptrs.iter().any(|null| *null))
        .then(|| inst.fail(&format!("{call}: a null array with {n} value references")))
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> FmiString {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> FmiString {
    c"2.0".as_ptr()
}

/// The directory path of a `file:` URI (`file:///a/b%20c`, `file:/a/b`).
pub fn uri_path(uri: &str) -> Option<String> {
    let rest = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))?;
    // `file://localhost/a` and `file:///a` both name /a.
    let rest = rest.strip_prefix("localhost").unwrap_or(rest);
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%' {
            let hex = bytes
                .get(k + 1..k + 3)
                .and_then(|h| core::str::from_utf8(h).ok())?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The start values of the FMU at `resources` (its `start.txt`), checked against
/// `guid`; with no resources, the defaults, whose GUID `guid` must be.
fn start_values(resources: &str, guid: &str) -> Result<Start, String> {
    let file = uri_path(resources).map(|d| std::path::Path::new(&d).join("start.txt"));
    let Some(text) = file.as_ref().and_then(|f| std::fs::read_to_string(f).ok()) else {
        let defaults = Description::default();
        return if defaults.guid() == guid {
            Ok(defaults.start)
        } else {
            Err(format!(
                "no start values at '{resources}' (resources/start.txt) and the GUID {guid} is not the defaults' ({})",
                defaults.guid()
            ))
        };
    };
    let (start, file_guid) = Start::parse(&text)?;
    match file_guid {
        Some(g) if g == guid => Ok(start),
        g => Err(format!(
            "resources/start.txt is for GUID {}, the modelDescription's is {guid}",
            g.unwrap_or_else(|| "(none)".to_string())
        )),
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: FmiString,
    fmu_type: c_int,
    fmu_guid: FmiString,
    fmu_resource_location: FmiString,
    functions: *const CallbackFunctions,
    _visible: Boolean,
    logging_on: Boolean,
) -> Component {
    let made = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the importer's callbacks, if given.
        let (logger, env) = unsafe { functions.as_ref() }
            .map_or((None, core::ptr::null_mut()), |f| {
                (f.logger, f.component_environment)
            });
        // SAFETY: NUL-terminated strings from the importer.
        let (name, guid, resources) = unsafe {
            (
                text(instance_name),
                text(fmu_guid),
                text(fmu_resource_location),
            )
        };
        let mut log = c_log(logger, env, &name);
        let refuse = |log: &mut Log, msg: String| {
            log(
                Status::Error,
                "logStatusError",
                &format!("fmi2Instantiate: {msg}"),
            );
            core::ptr::null_mut()
        };
        if fmu_type != CO_SIMULATION {
            return refuse(
                &mut log,
                format!("fmuType {fmu_type}: this FMU is for Co-Simulation (1) only"),
            );
        }
        let start = match start_values(&resources, &guid) {
            Ok(s) => s,
            Err(e) => return refuse(&mut log, e),
        };
        let mut inst = Instance::new(&name, start, log);
        inst.logging_on = logging_on != 0;
        Box::into_raw(Box::new(inst)).cast::<c_void>()
    }));
    made.unwrap_or(core::ptr::null_mut())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: Component) {
    if !c.is_null() {
        // SAFETY: an instance from `fmi2Instantiate`, freed once (FMI 2.0 2.1.5).
        let _ = catch_unwind(AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(c.cast::<Instance>()) })
        }));
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Component,
    logging_on: Boolean,
    n: usize,
    categories: *const FmiString,
) -> Status {
    with(c, |inst| {
        if n > 0 && categories.is_null() {
            return inst.fail(&format!(
                "fmi2SetDebugLogging: a null array with {n} categories"
            ));
        }
        // SAFETY: `n` strings from the importer.
        let cats = unsafe { slice(categories, n) };
        for &cat in cats {
            // SAFETY: NUL-terminated.
            let name = unsafe { text(cat) };
            if !LOG_CATEGORIES.iter().any(|(c, _)| *c == name) {
                return inst.fail(&format!(
                    "fmi2SetDebugLogging: no log category '{name}' (logStatusError, logStatusWarning, logEvents)"
                ));
            }
        }
        inst.logging_on = logging_on != 0;
        Status::Ok
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetupExperiment(
    c: Component,
    _tolerance_defined: Boolean,
    _tolerance: f64,
    start_time: f64,
    _stop_time_defined: Boolean,
    _stop_time: f64,
) -> Status {
    with(c, |inst| inst.setup_experiment(start_time))
}

#[no_mangle]
pub extern "C" fn fmi2EnterInitializationMode(c: Component) -> Status {
    with(c, Instance::enter_initialization)
}

#[no_mangle]
pub extern "C" fn fmi2ExitInitializationMode(c: Component) -> Status {
    with(c, Instance::exit_initialization)
}

#[no_mangle]
pub extern "C" fn fmi2Terminate(c: Component) -> Status {
    with(c, Instance::terminate)
}

#[no_mangle]
pub extern "C" fn fmi2Reset(c: Component) -> Status {
    with(c, Instance::reset)
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *mut f64,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2GetReal", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: `n` references and `n` values from the importer.
        let (refs, values) = unsafe { (slice(vr, n), slice_mut(value, n)) };
        inst.get_real(refs, values)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *mut c_int,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2GetInteger", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: as fmi2GetReal.
        let (refs, values) = unsafe { (slice(vr, n), slice_mut(value, n)) };
        inst.get_integer(refs, values)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *mut Boolean,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2GetBoolean", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: as fmi2GetReal.
        let (refs, values) = unsafe { (slice(vr, n), slice_mut(value, n)) };
        let mut b = vec![false; n];
        let s = inst.get_boolean(refs, &mut b);
        for (v, x) in values.iter_mut().zip(b) {
            *v = Boolean::from(x);
        }
        s
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *mut FmiString,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2GetString", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: `n` references.
        let refs = unsafe { slice(vr, n) };
        match refs.first() {
            None => Status::Ok,
            Some(r) => inst.fail(&format!(
                "fmi2GetString: no String variable has value reference {r}"
            )),
        }
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *const f64,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2SetReal", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: `n` references and values.
        let (refs, values) = unsafe { (slice(vr, n), slice(value, n)) };
        inst.set_real(refs, values)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *const c_int,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2SetInteger", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: `n` references.
        let refs = unsafe { slice(vr, n) };
        inst.set_other("fmi2SetInteger", "Integer", refs)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *const Boolean,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2SetBoolean", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: `n` references and values.
        let (refs, values) = unsafe { (slice(vr, n), slice(value, n)) };
        let b: Vec<bool> = values.iter().map(|v| *v != 0).collect();
        inst.set_boolean(refs, &b)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: Component,
    vr: *const ValueReference,
    n: usize,
    value: *const FmiString,
) -> Status {
    with(c, |inst| {
        if let Some(s) = null_args(inst, "fmi2SetString", n, &[vr.is_null(), value.is_null()]) {
            return s;
        }
        // SAFETY: `n` references.
        let refs = unsafe { slice(vr, n) };
        inst.set_other("fmi2SetString", "String", refs)
    })
}

/// A function this FMU does not offer: `fmi2Error`, named, with the capability flag
/// that says so.
fn unsupported(c: Component, call: &str, why: &str) -> Status {
    with(c, |inst| {
        inst.log(
            Status::Error,
            "logStatusError",
            &format!("{call} is not supported: {why}"),
        );
        Status::Error
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Component, state: *mut FmuState) -> Status {
    with(c, |inst| {
        if state.is_null() {
            return inst.fail("fmi2GetFMUstate: a null FMUstate pointer");
        }
        // SAFETY: the importer's pointer to a state: null, or one this FMU returned
        // and has not freed (FMI 2.0 2.1.8).
        let p = unsafe { *state };
        if p.is_null() {
            let saved = Box::new(inst.save());
            // SAFETY: writable, checked above.
            unsafe { *state = Box::into_raw(saved).cast() };
        } else {
            // SAFETY: a state from fmi2GetFMUstate.
            inst.save_into(unsafe { &mut *p.cast::<Saved>() });
        }
        Status::Ok
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Component, state: FmuState) -> Status {
    with(c, |inst| {
        if state.is_null() {
            return inst.fail("fmi2SetFMUstate: a null FMUstate");
        }
        // SAFETY: a state from fmi2GetFMUstate, not freed.
        inst.restore(unsafe { &*state.cast::<Saved>() })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: Component, state: *mut FmuState) -> Status {
    with(c, |_| {
        // SAFETY: the importer's pointer to a state from fmi2GetFMUstate (or null).
        if let Some(p) = unsafe { state.as_mut() } {
            if !p.is_null() {
                // SAFETY: allocated by fmi2GetFMUstate, freed once: nulled here.
                drop(unsafe { Box::from_raw(p.cast::<Saved>()) });
                *p = core::ptr::null_mut();
            }
        }
        Status::Ok
    })
}

#[no_mangle]
pub extern "C" fn fmi2SerializedFMUstateSize(
    c: Component,
    _state: FmuState,
    _size: *mut usize,
) -> Status {
    unsupported(
        c,
        "fmi2SerializedFMUstateSize",
        "canSerializeFMUstate is false",
    )
}

#[no_mangle]
pub extern "C" fn fmi2SerializeFMUstate(
    c: Component,
    _state: FmuState,
    _bytes: *mut c_char,
    _size: usize,
) -> Status {
    unsupported(c, "fmi2SerializeFMUstate", "canSerializeFMUstate is false")
}

#[no_mangle]
pub extern "C" fn fmi2DeSerializeFMUstate(
    c: Component,
    _bytes: *const c_char,
    _size: usize,
    _state: *mut FmuState,
) -> Status {
    unsupported(
        c,
        "fmi2DeSerializeFMUstate",
        "canSerializeFMUstate is false",
    )
}

#[no_mangle]
pub extern "C" fn fmi2GetDirectionalDerivative(
    c: Component,
    _unknown: *const ValueReference,
    _n_unknown: usize,
    _known: *const ValueReference,
    _n_known: usize,
    _dv_known: *const f64,
    _dv_unknown: *mut f64,
) -> Status {
    unsupported(
        c,
        "fmi2GetDirectionalDerivative",
        "providesDirectionalDerivative is false",
    )
}

// ---- Co-Simulation ----

#[no_mangle]
pub extern "C" fn fmi2SetRealInputDerivatives(
    c: Component,
    _vr: *const ValueReference,
    _n: usize,
    _order: *const c_int,
    _value: *const f64,
) -> Status {
    unsupported(
        c,
        "fmi2SetRealInputDerivatives",
        "canInterpolateInputs is false",
    )
}

#[no_mangle]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: Component,
    _vr: *const ValueReference,
    _n: usize,
    _order: *const c_int,
    _value: *mut f64,
) -> Status {
    unsupported(
        c,
        "fmi2GetRealOutputDerivatives",
        "maxOutputDerivativeOrder is 0",
    )
}

#[no_mangle]
pub extern "C" fn fmi2DoStep(
    c: Component,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior: Boolean,
) -> Status {
    with(c, |inst| {
        inst.do_step(current_communication_point, communication_step_size)
    })
}

#[no_mangle]
pub extern "C" fn fmi2CancelStep(c: Component) -> Status {
    unsupported(c, "fmi2CancelStep", "fmi2DoStep never returns fmi2Pending")
}

/// `fmi2StatusKind`: fmi2DoStepStatus = 0, fmi2PendingStatus, fmi2LastSuccessfulTime,
/// fmi2Terminated.
const LAST_SUCCESSFUL_TIME: c_int = 2;
/// `fmi2Terminated`.
const TERMINATED: c_int = 3;

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(c: Component, _kind: c_int, _value: *mut Status) -> Status {
    unsupported(
        c,
        "fmi2GetStatus",
        "fmi2DoStep is synchronous (no pending status)",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(c: Component, kind: c_int, value: *mut f64) -> Status {
    with(c, |inst| {
        if kind != LAST_SUCCESSFUL_TIME || value.is_null() {
            return inst.fail(&format!(
                "fmi2GetRealStatus: status kind {kind}: only fmi2LastSuccessfulTime (2) is a Real"
            ));
        }
        // SAFETY: a writable f64 from the importer.
        unsafe { *value = inst.time() };
        Status::Ok
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: Component,
    _kind: c_int,
    _value: *mut c_int,
) -> Status {
    unsupported(
        c,
        "fmi2GetIntegerStatus",
        "no Integer status is defined in FMI 2.0",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Component,
    kind: c_int,
    value: *mut Boolean,
) -> Status {
    with(c, |inst| {
        if kind != TERMINATED || value.is_null() {
            return inst.fail(&format!(
                "fmi2GetBooleanStatus: status kind {kind}: only fmi2Terminated (3) is a Boolean"
            ));
        }
        // A failed step is fmi2Error, never a request to terminate.
        // SAFETY: a writable fmi2Boolean from the importer.
        unsafe { *value = 0 };
        Status::Ok
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: Component,
    _kind: c_int,
    _value: *mut FmiString,
) -> Status {
    unsupported(
        c,
        "fmi2GetStringStatus",
        "fmi2DoStep never returns fmi2Pending",
    )
}

// ---- Model Exchange (not offered: modelDescription.xml has no ModelExchange) ----

/// The Model Exchange functions, each `fmi2Error` with a message.
macro_rules! model_exchange {
    ($($name:ident($($arg:ident: $ty:ty),*);)*) => {$(
        #[no_mangle]
        pub extern "C" fn $name(c: Component, $($arg: $ty),*) -> Status {
            $(let _ = $arg;)*
            unsupported(c, stringify!($name), "this FMU is for Co-Simulation only")
        }
    )*};
}

model_exchange! {
    fmi2EnterEventMode();
    fmi2NewDiscreteStates(info: *mut c_void);
    fmi2EnterContinuousTimeMode();
    fmi2CompletedIntegratorStep(no_prior: Boolean, enter_event: *mut Boolean, terminate: *mut Boolean);
    fmi2SetTime(time: f64);
    fmi2SetContinuousStates(x: *const f64, nx: usize);
    fmi2GetDerivatives(dx: *mut f64, nx: usize);
    fmi2GetEventIndicators(z: *mut f64, nz: usize);
    fmi2GetContinuousStates(x: *mut f64, nx: usize);
    fmi2GetNominalsOfContinuousStates(x: *mut f64, nx: usize);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris() {
        assert_eq!(
            uri_path("file:///tmp/a%20b/resources").as_deref(),
            Some("/tmp/a b/resources")
        );
        assert_eq!(uri_path("file:/tmp/x").as_deref(), Some("/tmp/x"));
        assert_eq!(
            uri_path("file://localhost/tmp/x").as_deref(),
            Some("/tmp/x")
        );
        assert_eq!(uri_path("http://x/y"), None);
        assert_eq!(uri_path("file:///bad%2"), None);
    }
}
