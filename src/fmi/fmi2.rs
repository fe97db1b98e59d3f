//! The FMI 2.0 co-simulation API as an importer calls it: the functions' C types (from the standard's
//! `fmi2FunctionTypes.h`), loaded from the FMU's binary, and an [`Instance`] whose every call checks the returned
//! status and, on failure, says which call, what status and what the FMU logged.

use crate::calls::{Calls, FmuState, StateCalls, Status, keep_log_line};
use crate::{CallContext, FmiError, SavedState, c_string};
use std::ffi::{c_char, c_int, c_void};
use std::path::Path;
use std::sync::Arc;

type Component = *mut c_void;
type Boolean = c_int;

const CO_SIMULATION: c_int = 1;

const STATE_CALLS: StateCalls = StateCalls {
    get: "fmi2GetFMUstate",
    size: "fmi2SerializedFMUstateSize",
    serialize: "fmi2SerializeFMUstate",
    deserialize: "fmi2DeSerializeFMUstate",
    set: "fmi2SetFMUstate",
};

/// fmi2CallbackFunctions.
#[repr(C)]
struct CallbackFunctions {
    logger: unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...),
    allocate_memory: unsafe extern "C" fn(usize, usize) -> *mut c_void,
    free_memory: unsafe extern "C" fn(*mut c_void),
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    component_environment: *mut c_void,
}

/// What the C logger shim (logger.c) hands each formatted message to.
#[repr(C)]
struct LogEnv {
    sink: unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char),
    data: *const crate::Log,
}

unsafe extern "C" {
    fn silrig_fmi2_logger(
        env: *mut c_void,
        instance: *const c_char,
        status: Status,
        cat: *const c_char,
        msg: *const c_char,
        ...
    );
    fn calloc(count: usize, size: usize) -> *mut c_void;
    fn free(ptr: *mut c_void);
}

/// Keeps one formatted message (logger.c's sink). SAFETY: `data` is the `Log` the instance owns, alive as long as
/// the instance; the strings are NUL-terminated (logger.c formats into a terminated buffer) or null.
unsafe extern "C" fn log_sink(data: *mut c_void, status: c_int, category: *const c_char, message: *const c_char) {
    // SAFETY: see above.
    unsafe { keep_log_line(data as *const crate::Log, 2, status, category, message) }
}

fmi_functions! {
    "FMI 2.0",
    instantiate: "fmi2Instantiate": fn(*const c_char, c_int, *const c_char, *const c_char, *const CallbackFunctions, Boolean, Boolean) -> Component;
    free_instance: "fmi2FreeInstance": fn(Component);
    setup_experiment: "fmi2SetupExperiment": fn(Component, Boolean, f64, f64, Boolean, f64) -> Status;
    enter_initialization_mode: "fmi2EnterInitializationMode": fn(Component) -> Status;
    exit_initialization_mode: "fmi2ExitInitializationMode": fn(Component) -> Status;
    terminate: "fmi2Terminate": fn(Component) -> Status;
    get_real: "fmi2GetReal": fn(Component, *const u32, usize, *mut f64) -> Status;
    set_real: "fmi2SetReal": fn(Component, *const u32, usize, *const f64) -> Status;
    get_integer: "fmi2GetInteger": fn(Component, *const u32, usize, *mut c_int) -> Status;
    set_integer: "fmi2SetInteger": fn(Component, *const u32, usize, *const c_int) -> Status;
    get_boolean: "fmi2GetBoolean": fn(Component, *const u32, usize, *mut Boolean) -> Status;
    set_boolean: "fmi2SetBoolean": fn(Component, *const u32, usize, *const Boolean) -> Status;
    do_step: "fmi2DoStep": fn(Component, f64, f64, Boolean) -> Status;
    get_fmu_state: "fmi2GetFMUstate": fn(Component, *mut FmuState) -> Status;
    set_fmu_state: "fmi2SetFMUstate": fn(Component, FmuState) -> Status;
    free_fmu_state: "fmi2FreeFMUstate": fn(Component, *mut FmuState) -> Status;
    serialized_size: "fmi2SerializedFMUstateSize": fn(Component, FmuState, *mut usize) -> Status;
    serialize: "fmi2SerializeFMUstate": fn(Component, FmuState, *mut u8, usize) -> Status;
    deserialize: "fmi2DeSerializeFMUstate": fn(Component, *const u8, usize, *mut FmuState) -> Status;
}

/// One FMI 2.0 co-simulation instance.
pub struct Instance {
    f: Arc<Functions>,
    component: Component,
    calls: Calls,
    /// What the FMU may keep pointers to until it is freed.
    _callbacks: Box<CallbackFunctions>,
    _log_env: Box<LogEnv>,
    _log: Box<crate::Log>,
    initialized: bool,
}

impl Instance {
    pub(crate) fn new(
        f: Arc<Functions>,
        name: &str,
        guid: &str,
        resources: &Path,
        ctx: CallContext,
    ) -> Result<Self, FmiError> {
        let log = Box::new(ctx.log.clone());
        let log_env = Box::new(LogEnv { sink: log_sink, data: &*log });
        let callbacks = Box::new(CallbackFunctions {
            logger: silrig_fmi2_logger,
            allocate_memory: calloc,
            free_memory: free,
            step_finished: None,
            component_environment: &*log_env as *const LogEnv as *mut c_void,
        });
        let uri = format!("file://{}", resources.display()).replace(' ', "%20");
        let (name_c, guid_c, uri_c) = (c_string(name), c_string(guid), c_string(&uri));
        // SAFETY: the strings and the callbacks outlive the call (the callbacks the instance too).
        let component = unsafe {
            (f.instantiate)(name_c.as_ptr(), CO_SIMULATION, guid_c.as_ptr(), uri_c.as_ptr(), &*callbacks, 0, 0)
        };
        if component.is_null() {
            return Err(ctx.error(
                format!("fmi2Instantiate (guid {guid})"),
                "no instance (a GUID that does not match its binary's, or a failure it logged)",
            ));
        }
        let calls = Calls::new(ctx, 2, &STATE_CALLS);
        Ok(Self { f, component, calls, _callbacks: callbacks, _log_env: log_env, _log: log, initialized: false })
    }

    pub(crate) fn enter_initialization(&mut self, start_time_s: f64) -> Result<(), FmiError> {
        self.calls.usable("fmi2SetupExperiment")?;
        // FMI 2 takes the start time in fmi2SetupExperiment, which may follow the start values set after
        // instantiation; no tolerance, no stop time.
        // SAFETY: a live component.
        let status = unsafe { (self.f.setup_experiment)(self.component, 0, 0.0, start_time_s, 0, 0.0) };
        self.calls.check(status, || format!("fmi2SetupExperiment at t = {start_time_s} s"))?;
        // SAFETY: a live component.
        let status = unsafe { (self.f.enter_initialization_mode)(self.component) };
        self.calls.check(status, || "fmi2EnterInitializationMode".into())
    }

    pub(crate) fn exit_initialization(&mut self) -> Result<(), FmiError> {
        self.calls.usable("fmi2ExitInitializationMode")?;
        // SAFETY: a live component.
        let status = unsafe { (self.f.exit_initialization_mode)(self.component) };
        self.calls.check(status, || "fmi2ExitInitializationMode".into())?;
        self.initialized = true;
        Ok(())
    }

    pub(crate) fn set_reals(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: both slices hold refs.len() elements (`values` checks it first).
        self.calls.values("fmi2SetReal", refs, values.len(), || unsafe {
            (f.set_real)(c, refs.as_ptr(), refs.len(), values.as_ptr())
        })
    }

    pub(crate) fn get_reals(&mut self, refs: &[u32], values: &mut [f64]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: both slices hold refs.len() elements (`values` checks it first).
        self.calls.values("fmi2GetReal", refs, values.len(), || unsafe {
            (f.get_real)(c, refs.as_ptr(), refs.len(), values.as_mut_ptr())
        })
    }

    pub(crate) fn set_integers(&mut self, refs: &[u32], values: &[c_int]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: both slices hold refs.len() elements (`values` checks it first).
        self.calls.values("fmi2SetInteger", refs, values.len(), || unsafe {
            (f.set_integer)(c, refs.as_ptr(), refs.len(), values.as_ptr())
        })
    }

    pub(crate) fn get_integers(&mut self, refs: &[u32], values: &mut [c_int]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: both slices hold refs.len() elements (`values` checks it first).
        self.calls.values("fmi2GetInteger", refs, values.len(), || unsafe {
            (f.get_integer)(c, refs.as_ptr(), refs.len(), values.as_mut_ptr())
        })
    }

    /// fmi2Boolean is a C int (0 or 1).
    pub(crate) fn set_booleans(&mut self, refs: &[u32], values: &[c_int]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: both slices hold refs.len() elements (`values` checks it first).
        self.calls.values("fmi2SetBoolean", refs, values.len(), || unsafe {
            (f.set_boolean)(c, refs.as_ptr(), refs.len(), values.as_ptr())
        })
    }

    pub(crate) fn get_booleans(&mut self, refs: &[u32], values: &mut [c_int]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: both slices hold refs.len() elements (`values` checks it first).
        self.calls.values("fmi2GetBoolean", refs, values.len(), || unsafe {
            (f.get_boolean)(c, refs.as_ptr(), refs.len(), values.as_mut_ptr())
        })
    }

    pub(crate) fn do_step(&mut self, t_s: f64, step_s: f64) -> Result<(), FmiError> {
        self.calls.usable("fmi2DoStep")?;
        // SAFETY: a live component. noSetFMUStatePriorToCurrentPoint is true: the rig never steps backwards (a
        // restored state is put back before stepping on from it).
        let status = unsafe { (self.f.do_step)(self.component, t_s, step_s, 1) };
        self.calls.check(status, || format!("fmi2DoStep at t = {t_s} s by {step_s} s"))
    }

    pub(crate) fn save_state(&mut self) -> Result<SavedState, FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: a live component; each state pointer is the FMU's own, sized as it says.
        self.calls.save_state(
            |state| unsafe { (f.get_fmu_state)(c, state) },
            |state, size| unsafe { (f.serialized_size)(c, state, size) },
            |state, bytes, size| unsafe { (f.serialize)(c, state, bytes, size) },
            |state| unsafe { (f.free_fmu_state)(c, state) },
        )
    }

    pub(crate) fn restore_state(&mut self, saved: &[u8]) -> Result<(), FmiError> {
        let (f, c) = (&self.f, self.component);
        // SAFETY: a live component; `saved` holds the bytes given, and the state made from them is the FMU's.
        self.calls.restore_state(
            saved,
            |bytes, size, state| unsafe { (f.deserialize)(c, bytes, size, state) },
            |state| unsafe { (f.set_fmu_state)(c, state) },
            |state| unsafe { (f.free_fmu_state)(c, state) },
        )
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        let (f, c) = (&self.f, self.component);
        // SAFETY: a live component, freed once (after fmi2Fatal, `close` makes no call at all).
        self.calls.close(self.initialized, || unsafe { (f.terminate)(c) }, || unsafe { (f.free_instance)(c) });
    }
}
