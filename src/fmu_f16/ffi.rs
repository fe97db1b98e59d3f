//! The FMI 2.0 C functions (`fmi2Functions.h`), every one exported since importers resolve them all: the
//! co-simulation ones over [`crate::instance::FmuInstance`] (the F-16's or the quadrotor's, as the start file in the
//! FMU's resources says), the model-exchange ones refusing with a logged message.
//! This is the crate's only unsafe code: pointers from the importer are checked for null and read as the standard
//! defines them, and no panic crosses the boundary (each call runs under `catch_unwind`; a panic is logged and
//! answered with fmi2Fatal). Errors go to the importer's fmi2CallbackLogger.

use crate::description::{Experiment, START_FILE, guid, read_start_file};
use crate::instance::{FmuInstance, Instance};
use crate::models::{F16, Quad};
use crate::variables::Parameters;
use silrig_fmu_f16_description::quad::{quad_guid, read_quad_start_file};
use std::ffi::{CStr, CString, c_char, c_double, c_int, c_uint, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// fmi2Status.
type Status = c_int;
const OK: Status = 0;
const ERROR: Status = 3;
const FATAL: Status = 4;

/// fmi2Type: fmi2CoSimulation.
const CO_SIMULATION: c_int = 1;

/// fmi2StatusKind: fmi2LastSuccessfulTime and fmi2Terminated.
const LAST_SUCCESSFUL_TIME: c_int = 2;
const TERMINATED: c_int = 3;

/// fmi2CallbackLogger: (componentEnvironment, instanceName, status, category, message, ...), the message a
/// printf format.
type Logger = unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...);

/// fmi2CallbackFunctions, as the importer hands it to fmi2Instantiate.
#[repr(C)]
pub struct CallbackFunctions {
    logger: Option<Logger>,
    // Declared for the layout only: the FMU allocates with Rust's allocator (canNotUseMemoryManagementFunctions)
    // and never steps asynchronously.
    #[allow(dead_code)]
    allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    #[allow(dead_code)]
    free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    #[allow(dead_code)]
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    component_environment: *mut c_void,
}

/// What an fmi2Component points to: the instance and how to talk to its importer.
struct Component {
    instance: Box<dyn FmuInstance>,
    log: Log,
}

/// The importer's logger for one instance.
struct Log {
    logger: Option<Logger>,
    environment: *mut c_void,
    name: CString,
    /// fmi2SetDebugLogging: also log what is not an error.
    debug: bool,
}

impl Log {
    /// Send `message` with `status` (errors always; anything else only with debug logging on).
    fn send(&self, status: Status, category: &str, message: &str) {
        if status < ERROR && !self.debug {
            return;
        }
        let Some(logger) = self.logger else { return };
        // The message is a printf format: a literal `%` is written `%%`; a NUL would cut it short.
        let text = CString::new(message.replace('%', "%%").replace('\0', " ")).unwrap_or_default();
        let category = CString::new(category).unwrap_or_default();
        // SAFETY: the logger is the importer's, called as fmi2CallbackLogger is declared, with valid NUL-terminated
        // strings that outlive the call and a format with no conversions (so no variadic arguments are read).
        unsafe { logger(self.environment, self.name.as_ptr(), status, category.as_ptr(), text.as_ptr()) };
    }

    fn error(&self, message: &str) {
        self.send(ERROR, "logStatusError", message);
    }
}

/// A string from the importer, if it is one.
///
/// SAFETY (for the caller): `s` is null or a NUL-terminated string valid for the call.
unsafe fn text<'a>(s: *const c_char) -> Option<&'a str> {
    if s.is_null() {
        return None;
    }
    // SAFETY: not null, and NUL-terminated per the caller's contract.
    unsafe { CStr::from_ptr(s) }.to_str().ok()
}

/// A slice from the importer's array of `n` elements (empty when `n` is 0, whatever the pointer).
///
/// SAFETY (for the caller): `p` points to `n` valid elements when `n` > 0.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    match (n, p.is_null()) {
        (0, _) => Some(&[]),
        (_, true) => None,
        // SAFETY: not null, `n` elements per the caller's contract.
        _ => Some(unsafe { std::slice::from_raw_parts(p, n) }),
    }
}

/// The same, writable.
///
/// SAFETY (for the caller): `p` points to `n` valid, writable elements, not aliased, when `n` > 0.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    match (n, p.is_null()) {
        (0, _) => Some(&mut []),
        (_, true) => None,
        // SAFETY: not null, `n` writable elements per the caller's contract.
        _ => Some(unsafe { std::slice::from_raw_parts_mut(p, n) }),
    }
}

/// Run `f` on the component `c` points to; its error is logged and answered with fmi2Error, a panic with
/// fmi2Fatal.
fn with(c: *mut c_void, function: &str, f: impl FnOnce(&mut Component) -> Result<(), String>) -> Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null fmi2Component is what fmi2Instantiate returned (Box<Component>::into_raw) and not yet
    // freed; the standard forbids calling one instance from two threads at once.
    let component = unsafe { &mut *c.cast::<Component>() };
    match catch_unwind(AssertUnwindSafe(|| f(component))) {
        Ok(Ok(())) => OK,
        Ok(Err(e)) => {
            component.log.error(&format!("{function}: {e}"));
            ERROR
        }
        Err(_) => {
            component.log.send(FATAL, "logStatusFatal", &format!("{function}: internal error (a panic)"));
            FATAL
        }
    }
}

/// The path of a `file:` URI (`file:///a/b`, `file:/a/b`, `file://localhost/a/b`), percent-escapes decoded.
fn uri_path(uri: &str) -> Option<String> {
    let rest = uri.strip_prefix("file:")?;
    let path = match rest.strip_prefix("//") {
        Some(r) => r.strip_prefix("localhost").unwrap_or(r),
        None => rest,
    };
    let bytes = path.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The start file the FMU carries in `resources/`, if any.
fn start_text(resource_location: Option<&str>) -> Result<Option<String>, String> {
    let Some(dir) = resource_location.and_then(uri_path) else { return Ok(None) };
    let file = std::path::Path::new(&dir).join(START_FILE);
    match std::fs::read_to_string(&file) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(format!("{}: {e}", file.display())),
    }
}

/// A new instance of the vehicle and start values the FMU carries in `resources/` (the quadrotor's start file
/// says so on its first line; without one, the book's F-16), refused under a GUID other than theirs.
fn new_instance(resource_location: Option<&str>, given_guid: &str) -> Result<Box<dyn FmuInstance>, String> {
    let text = start_text(resource_location)?;
    let wrong = |expected: &str| format!("wrong GUID {given_guid}: this FMU (with its resources) is {expected}");
    let named = |e: String| format!("{START_FILE}: {e}");
    if let Some(quad) = text.as_deref().and_then(read_quad_start_file) {
        let (starts, experiment) = quad.map_err(named)?;
        let expected = quad_guid(&starts, &experiment)?;
        if given_guid != expected {
            return Err(wrong(&expected));
        }
        return Ok(Box::new(Instance::<Quad>::new(&expected, starts)?));
    }
    let (parameters, experiment) = match text {
        Some(text) => read_start_file(&text).map_err(named)?,
        None => (Parameters::default(), Experiment::default()),
    };
    let expected = guid(&parameters, &experiment)?;
    if given_guid != expected {
        return Err(wrong(&expected));
    }
    Ok(Box::new(Instance::<F16>::new(&expected, parameters)?))
}

/// "default": the standard's types.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// "2.0".
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// A new co-simulation instance of the vehicle at the start values the FMU carries; null (with a logged reason) for another
/// type, a GUID other than the one those start values give ("wrong GUID ..."), or start values that give no
/// flight.
///
/// # Safety
/// The arguments are as fmi2Functions.h declares them: strings null or NUL-terminated, `functions` null or a valid
/// fmi2CallbackFunctions that outlives the instance.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    fmu_guid: *const c_char,
    fmu_resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> *mut c_void {
    // SAFETY: null or a valid struct, per the caller's contract.
    let callbacks = unsafe { functions.as_ref() };
    // SAFETY: null or NUL-terminated, per the caller's contract.
    let (name, given_guid, resources) = unsafe { (text(instance_name), text(fmu_guid), text(fmu_resource_location)) };
    let log = Log {
        logger: callbacks.and_then(|f| f.logger),
        environment: callbacks.map_or(std::ptr::null_mut(), |f| f.component_environment),
        name: CString::new(name.unwrap_or("")).unwrap_or_default(),
        debug: logging_on != 0,
    };
    let made = catch_unwind(AssertUnwindSafe(|| -> Result<Box<dyn FmuInstance>, String> {
        if fmu_type != CO_SIMULATION {
            return Err("this FMU is for co-simulation only: model exchange is not implemented".into());
        }
        new_instance(resources, given_guid.unwrap_or(""))
    }));
    match made {
        Ok(Ok(instance)) => Box::into_raw(Box::new(Component { instance, log })).cast(),
        Ok(Err(e)) => {
            log.error(&format!("fmi2Instantiate: {e}"));
            std::ptr::null_mut()
        }
        Err(_) => {
            log.error("fmi2Instantiate: internal error (a panic)");
            std::ptr::null_mut()
        }
    }
}

/// Free an instance.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2FreeInstance(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: what fmi2Instantiate returned, freed once (the importer's duty per the standard).
        drop(unsafe { Box::from_raw(c.cast::<Component>()) });
    }
}

/// Debug logging on or off (this FMU declares no log categories).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetDebugLogging(
    c: *mut c_void,
    logging_on: c_int,
    n_categories: usize,
    _categories: *const *const c_char,
) -> Status {
    with(c, "fmi2SetDebugLogging", |c| {
        c.log.debug = logging_on != 0;
        match n_categories {
            0 => Ok(()),
            _ => Err("this FMU declares no log categories".into()),
        }
    })
}

/// The start time (tolerance and stop time are not used: the step is fixed).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetupExperiment(
    c: *mut c_void,
    _tolerance_defined: c_int,
    _tolerance: c_double,
    start_time: c_double,
    _stop_time_defined: c_int,
    _stop_time: c_double,
) -> Status {
    with(c, "fmi2SetupExperiment", |c| c.instance.setup_experiment(start_time))
}

/// Enter initialization mode.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> Status {
    with(c, "fmi2EnterInitializationMode", |c| c.instance.enter_initialization())
}

/// Leave initialization mode: the F-16 is built and trimmed with the parameters as set.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2ExitInitializationMode(c: *mut c_void) -> Status {
    with(c, "fmi2ExitInitializationMode", |c| c.instance.exit_initialization())
}

/// End the simulation.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Terminate(c: *mut c_void) -> Status {
    with(c, "fmi2Terminate", |c| c.instance.terminate())
}

/// Back to the start values, as instantiated.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Reset(c: *mut c_void) -> Status {
    with(c, "fmi2Reset", |c| c.instance.reset())
}

/// Read Real variables.
///
/// # Safety
/// `vr` and `value` point to `nvr` elements (or `nvr` is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(c: *mut c_void, vr: *const c_uint, nvr: usize, value: *mut c_double) -> Status {
    with(c, "fmi2GetReal", |c| {
        // SAFETY: `nvr` elements each, per the caller's contract.
        let (vrs, values) = unsafe { (slice(vr, nvr), slice_mut(value, nvr)) };
        c.instance.get_real(vrs.ok_or("null value references")?, values.ok_or("null values")?)
    })
}

/// Set Real variables: inputs, and parameters before the end of initialization.
///
/// # Safety
/// `vr` and `value` point to `nvr` elements (or `nvr` is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(c: *mut c_void, vr: *const c_uint, nvr: usize, value: *const c_double) -> Status {
    with(c, "fmi2SetReal", |c| {
        // SAFETY: `nvr` elements each, per the caller's contract.
        let (vrs, values) = unsafe { (slice(vr, nvr), slice(value, nvr)) };
        c.instance.set_real(vrs.ok_or("null value references")?, values.ok_or("null values")?)
    })
}

/// Read Boolean variables (the Boolean parameters).
///
/// # Safety
/// `vr` and `value` point to `nvr` elements (or `nvr` is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(c: *mut c_void, vr: *const c_uint, nvr: usize, value: *mut c_int) -> Status {
    with(c, "fmi2GetBoolean", |c| {
        // SAFETY: `nvr` elements each, per the caller's contract.
        let (vrs, values) = unsafe { (slice(vr, nvr), slice_mut(value, nvr)) };
        let (vrs, values) = (vrs.ok_or("null value references")?, values.ok_or("null values")?);
        let mut read = vec![false; vrs.len()];
        c.instance.get_boolean(vrs, &mut read)?;
        for (v, r) in values.iter_mut().zip(read) {
            *v = c_int::from(r);
        }
        Ok(())
    })
}

/// Set Boolean variables (the Boolean parameters, before the end of initialization).
///
/// # Safety
/// `vr` and `value` point to `nvr` elements (or `nvr` is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(c: *mut c_void, vr: *const c_uint, nvr: usize, value: *const c_int) -> Status {
    with(c, "fmi2SetBoolean", |c| {
        // SAFETY: `nvr` elements each, per the caller's contract.
        let (vrs, values) = unsafe { (slice(vr, nvr), slice(value, nvr)) };
        let values: Vec<bool> = values.ok_or("null values")?.iter().map(|v| *v != 0).collect();
        c.instance.set_boolean(vrs.ok_or("null value references")?, &values)
    })
}

/// A type with no variables: only an empty request succeeds.
fn none_of(kind: &str, nvr: usize) -> Result<(), String> {
    if nvr == 0 { Ok(()) } else { Err(format!("this FMU has no {kind} variables")) }
}

/// No Integer variables.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetInteger(c: *mut c_void, _vr: *const c_uint, nvr: usize, _value: *mut c_int) -> Status {
    with(c, "fmi2GetInteger", |_| none_of("Integer", nvr))
}

/// No Integer variables.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetInteger(c: *mut c_void, _vr: *const c_uint, nvr: usize, _value: *const c_int) -> Status {
    with(c, "fmi2SetInteger", |_| none_of("Integer", nvr))
}

/// No String variables.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetString(c: *mut c_void, _vr: *const c_uint, nvr: usize, _value: *mut *const c_char) -> Status {
    with(c, "fmi2GetString", |_| none_of("String", nvr))
}

/// No String variables.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetString(
    c: *mut c_void,
    _vr: *const c_uint,
    nvr: usize,
    _value: *const *const c_char,
) -> Status {
    with(c, "fmi2SetString", |_| none_of("String", nvr))
}

/// Save the instance's whole state into `*state` (a new one when null, else the one given is overwritten).
///
/// # Safety
/// `state` points to an fmi2FMUstate: null or one this FMU made for this instance.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: *mut c_void, state: *mut *mut c_void) -> Status {
    with(c, "fmi2GetFMUstate", |c| {
        if state.is_null() {
            return Err("null FMU state pointer".into());
        }
        // SAFETY: a valid pointer to an fmi2FMUstate, per the caller's contract.
        let slot = unsafe { &mut *state };
        if slot.is_null() {
            *slot = Box::into_raw(Box::new(c.instance.boxed())).cast();
        } else {
            // SAFETY: a state this FMU made (Box<Box<dyn FmuInstance>>::into_raw), per the caller's contract.
            unsafe { *slot.cast::<Box<dyn FmuInstance>>() = c.instance.boxed() };
        }
        Ok(())
    })
}

/// Continue from a saved state.
///
/// # Safety
/// `state` is one this FMU made and has not freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: *mut c_void, state: *mut c_void) -> Status {
    with(c, "fmi2SetFMUstate", |c| {
        // SAFETY: null or a live Box<Box<dyn FmuInstance>> this FMU made, per the caller's contract.
        let saved = unsafe { state.cast::<Box<dyn FmuInstance>>().as_ref() }.ok_or("null FMU state")?;
        c.instance = saved.boxed();
        Ok(())
    })
}

/// Free a saved state and set `*state` to null.
///
/// # Safety
/// `state` points to null or to a state this FMU made and has not freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: *mut c_void, state: *mut *mut c_void) -> Status {
    with(c, "fmi2FreeFMUstate", |_| {
        if state.is_null() {
            return Ok(());
        }
        // SAFETY: a valid pointer to an fmi2FMUstate, per the caller's contract.
        let slot = unsafe { &mut *state };
        if !slot.is_null() {
            // SAFETY: a Box<Box<dyn FmuInstance>> this FMU made, freed once.
            drop(unsafe { Box::from_raw(slot.cast::<Box<dyn FmuInstance>>()) });
            *slot = std::ptr::null_mut();
        }
        Ok(())
    })
}

/// The size of a saved state's bytes.
///
/// # Safety
/// `state` is a live state this FMU made; `size` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(c: *mut c_void, state: *mut c_void, size: *mut usize) -> Status {
    with(c, "fmi2SerializedFMUstateSize", |_| {
        // SAFETY: null or a live Box<Box<dyn FmuInstance>>, per the caller's contract.
        let saved = unsafe { state.cast::<Box<dyn FmuInstance>>().as_ref() }.ok_or("null FMU state")?;
        // SAFETY: null or writable, per the caller's contract.
        let size = unsafe { size.as_mut() }.ok_or("null size")?;
        *size = saved.serialize().len();
        Ok(())
    })
}

/// A saved state as bytes, into `bytes` of `size` (at least fmi2SerializedFMUstateSize).
///
/// # Safety
/// `state` is a live state this FMU made; `bytes` points to `size` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: *mut c_void,
    state: *mut c_void,
    bytes: *mut c_char,
    size: usize,
) -> Status {
    with(c, "fmi2SerializeFMUstate", |_| {
        // SAFETY: null or a live Box<Box<dyn FmuInstance>>, per the caller's contract.
        let saved = unsafe { state.cast::<Box<dyn FmuInstance>>().as_ref() }.ok_or("null FMU state")?;
        let data = saved.serialize();
        if size < data.len() {
            return Err(format!("{size} bytes given, the state needs {}", data.len()));
        }
        // SAFETY: `size` writable bytes, per the caller's contract.
        let out = unsafe { slice_mut(bytes.cast::<u8>(), size) }.ok_or("null bytes")?;
        out[..data.len()].copy_from_slice(&data);
        Ok(())
    })
}

/// A saved state from its bytes, into `*state` (a new one when null, else the one given is overwritten); bytes of
/// another FMU, another description or cut short are refused.
///
/// # Safety
/// `bytes` points to `size` bytes; `state` points to null or to a live state this FMU made.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: *mut c_void,
    bytes: *const c_char,
    size: usize,
    state: *mut *mut c_void,
) -> Status {
    with(c, "fmi2DeSerializeFMUstate", |c| {
        // SAFETY: `size` bytes, per the caller's contract.
        let data = unsafe { slice(bytes.cast::<u8>(), size) }.ok_or("null bytes")?;
        let read = c.instance.deserialize_same(data)?;
        if state.is_null() {
            return Err("null FMU state pointer".into());
        }
        // SAFETY: a valid pointer to an fmi2FMUstate, per the caller's contract.
        let slot = unsafe { &mut *state };
        if slot.is_null() {
            *slot = Box::into_raw(Box::new(read)).cast();
        } else {
            // SAFETY: a state this FMU made, per the caller's contract.
            unsafe { *slot.cast::<Box<dyn FmuInstance>>() = read };
        }
        Ok(())
    })
}

/// Not provided (providesDirectionalDerivative is false).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetDirectionalDerivative(
    c: *mut c_void,
    _unknown: *const c_uint,
    _n_unknown: usize,
    _known: *const c_uint,
    _n_known: usize,
    _dv_known: *const c_double,
    _dv_unknown: *mut c_double,
) -> Status {
    with(c, "fmi2GetDirectionalDerivative", |_| Err("directional derivatives are not provided".into()))
}

/// Not provided (canInterpolateInputs is false: inputs are held over a step, as the rig holds a command).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut c_void,
    _vr: *const c_uint,
    _nvr: usize,
    _order: *const c_int,
    _value: *const c_double,
) -> Status {
    with(c, "fmi2SetRealInputDerivatives", |_| Err("input derivatives are not used: inputs are held".into()))
}

/// Not provided (maxOutputDerivativeOrder is 0).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: *mut c_void,
    _vr: *const c_uint,
    _nvr: usize,
    _order: *const c_int,
    _value: *mut c_double,
) -> Status {
    with(c, "fmi2GetRealOutputDerivatives", |_| Err("output derivatives are not provided".into()))
}

/// One communication step: one tick of the rig's plant (fixed step size, set by the first call).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2DoStep(
    c: *mut c_void,
    current_communication_point: c_double,
    communication_step_size: c_double,
    _no_set_fmu_state_prior: c_int,
) -> Status {
    with(c, "fmi2DoStep", |c| c.instance.do_step(current_communication_point, communication_step_size))
}

/// Steps are never asynchronous: nothing to cancel.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2CancelStep(c: *mut c_void) -> Status {
    with(c, "fmi2CancelStep", |_| Err("steps are synchronous: nothing to cancel".into()))
}

/// Steps are never asynchronous (fmi2Pending is never returned).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetStatus(c: *mut c_void, _kind: c_int, _value: *mut Status) -> Status {
    with(c, "fmi2GetStatus", |_| Err("steps are synchronous: no pending status".into()))
}

/// fmi2LastSuccessfulTime: the time the last step reached.
///
/// # Safety
/// `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: *mut c_void, kind: c_int, value: *mut c_double) -> Status {
    with(c, "fmi2GetRealStatus", |c| {
        // SAFETY: null or writable, per the caller's contract.
        let value = unsafe { value.as_mut() }.ok_or("null value")?;
        match kind {
            LAST_SUCCESSFUL_TIME => {
                *value = c.instance.time_s();
                Ok(())
            }
            _ => Err(format!("no Real status of kind {kind}")),
        }
    })
}

/// No Integer status.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetIntegerStatus(c: *mut c_void, kind: c_int, _value: *mut c_int) -> Status {
    with(c, "fmi2GetIntegerStatus", |_| Err(format!("no Integer status of kind {kind}")))
}

/// fmi2Terminated: false (the FMU never asks to end the simulation; a flight leaving the envelope is an error).
///
/// # Safety
/// `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(c: *mut c_void, kind: c_int, value: *mut c_int) -> Status {
    with(c, "fmi2GetBooleanStatus", |_| {
        // SAFETY: null or writable, per the caller's contract.
        let value = unsafe { value.as_mut() }.ok_or("null value")?;
        match kind {
            TERMINATED => {
                *value = 0;
                Ok(())
            }
            _ => Err(format!("no Boolean status of kind {kind}")),
        }
    })
}

/// No String status.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetStringStatus(c: *mut c_void, kind: c_int, _value: *mut *const c_char) -> Status {
    with(c, "fmi2GetStringStatus", |_| Err(format!("no String status of kind {kind}")))
}

/// The model-exchange functions: this FMU is for co-simulation only; each refuses, logging which.
macro_rules! model_exchange_only {
    ($($name:ident($($arg:ident: $ty:ty),*);)*) => {$(
        /// Model exchange only: refused (this FMU is for co-simulation).
        #[unsafe(no_mangle)]
        pub extern "C" fn $name(c: *mut c_void $(, $arg: $ty)*) -> Status {
            $(let _ = $arg;)*
            with(c, stringify!($name), |_| Err("model exchange is not implemented: this FMU is for co-simulation".into()))
        }
    )*};
}

model_exchange_only! {
    fmi2EnterEventMode();
    fmi2NewDiscreteStates(event_info: *mut c_void);
    fmi2EnterContinuousTimeMode();
    fmi2CompletedIntegratorStep(no_set_prior: c_int, enter_event_mode: *mut c_int, terminate: *mut c_int);
    fmi2SetTime(time: c_double);
    fmi2SetContinuousStates(x: *const c_double, nx: usize);
    fmi2GetDerivatives(derivatives: *mut c_double, nx: usize);
    fmi2GetEventIndicators(indicators: *mut c_double, ni: usize);
    fmi2GetContinuousStates(x: *mut c_double, nx: usize);
    fmi2GetNominalsOfContinuousStates(x_nominal: *mut c_double, nx: usize);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris_give_their_paths() {
        assert_eq!(uri_path("file:///tmp/a%20b/resources").as_deref(), Some("/tmp/a b/resources"));
        assert_eq!(uri_path("file:/tmp/x").as_deref(), Some("/tmp/x"));
        assert_eq!(uri_path("file://localhost/tmp/x").as_deref(), Some("/tmp/x"));
        assert_eq!(uri_path("http://x/y"), None);
        assert_eq!(uri_path("file:///tmp/%2"), Some("/tmp/%2".into()));
    }
}
