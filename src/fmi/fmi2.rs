//! The FMI 2.0 co-simulation API as an importer calls it: the functions' C types (from the standard's
//! `fmi2FunctionTypes.h`), loaded from the FMU's binary, and an [`Instance`] whose every call checks the returned
//! status and, on failure, says which call, what status and what the FMU logged.

use crate::{CallContext, FmiError, SavedState, c_string};
use std::ffi::{c_char, c_int, c_void};
use std::path::Path;
use std::sync::Arc;

type Component = *mut c_void;
type Status = c_int;
type Boolean = c_int;
type FmuState = *mut c_void;

const OK: Status = 0;
const WARNING: Status = 1;
const DISCARD: Status = 2;
const ERROR: Status = 3;
const FATAL: Status = 4;
const CO_SIMULATION: c_int = 1;

fn status_name(status: Status) -> String {
    match status {
        OK => "fmi2OK".into(),
        WARNING => "fmi2Warning".into(),
        DISCARD => "fmi2Discard".into(),
        ERROR => "fmi2Error".into(),
        FATAL => "fmi2Fatal".into(),
        5 => "fmi2Pending (asynchronous doStep is not supported)".into(),
        other => format!("status {other}, which FMI 2.0 does not define"),
    }
}

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

/// Keeps one formatted message. SAFETY: `data` is the `Log` the instance owns (alive as long as the instance), and
/// the strings are NUL-terminated (logger.c formats into a terminated buffer) or null.
unsafe extern "C" fn log_sink(data: *mut c_void, status: c_int, category: *const c_char, message: *const c_char) {
    let text = |p: *const c_char| match p.is_null() {
        true => String::new(),
        // SAFETY: see above.
        false => unsafe { std::ffi::CStr::from_ptr(p) }.to_string_lossy().into_owned(),
    };
    // SAFETY: see above.
    let log = unsafe { &*(data as *const crate::Log) };
    let category = text(category);
    let message = text(message);
    log.push(match category.is_empty() {
        true => format!("[{}] {message}", status_name(status)),
        false => format!("[{}, {category}] {message}", status_name(status)),
    });
}

macro_rules! functions {
    ($($field:ident: $symbol:literal: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The FMI 2.0 functions a co-simulation importer calls, resolved in the FMU's binary.
        pub struct Functions {
            $($field: unsafe extern "C" fn($($arg),*) $(-> $ret)?,)*
            /// Keeps the binary loaded while the pointers above are in use.
            _library: libloading::Library,
        }

        impl Functions {
            /// Load the binary and resolve every function; a missing one is named.
            pub fn load(binary: &Path) -> Result<Self, String> {
                // SAFETY: loading runs the binary's initializers: an FMU's binary is code the user chose to run.
                let library = unsafe { libloading::Library::new(binary) }
                    .map_err(|e| format!("cannot load {}: {e}", binary.display()))?;
                Ok(Self {
                    $($field: {
                        // SAFETY: the symbol has the type FMI 2.0's fmi2FunctionTypes.h gives it.
                        let symbol = unsafe {
                            library.get::<unsafe extern "C" fn($($arg),*) $(-> $ret)?>($symbol.as_bytes())
                        }
                        .map_err(|_| format!("its binary {} lacks the FMI 2.0 function {}", binary.display(), $symbol))?;
                        *symbol
                    },)*
                    _library: library,
                })
            }
        }
    };
}

functions! {
    instantiate: "fmi2Instantiate": fn(*const c_char, c_int, *const c_char, *const c_char, *const CallbackFunctions, Boolean, Boolean) -> Component;
    free_instance: "fmi2FreeInstance": fn(Component);
    setup_experiment: "fmi2SetupExperiment": fn(Component, Boolean, f64, f64, Boolean, f64) -> Status;
    enter_initialization_mode: "fmi2EnterInitializationMode": fn(Component) -> Status;
    exit_initialization_mode: "fmi2ExitInitializationMode": fn(Component) -> Status;
    terminate: "fmi2Terminate": fn(Component) -> Status;
    get_real: "fmi2GetReal": fn(Component, *const u32, usize, *mut f64) -> Status;
    set_real: "fmi2SetReal": fn(Component, *const u32, usize, *const f64) -> Status;
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
    ctx: CallContext,
    /// What the FMU may keep pointers to until it is freed.
    _callbacks: Box<CallbackFunctions>,
    _log_env: Box<LogEnv>,
    _log: Box<crate::Log>,
    initialized: bool,
    /// After fmi2Fatal nothing may be called, not even fmi2FreeInstance; after fmi2Error only fmi2FreeInstance.
    broken: Option<Status>,
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
        let mut instance = Self {
            f,
            component,
            ctx,
            _callbacks: callbacks,
            _log_env: log_env,
            _log: log,
            initialized: false,
            broken: None,
        };
        // SAFETY: a live component.
        let status = unsafe { (instance.f.setup_experiment)(instance.component, 0, 0.0, 0.0, 0, 0.0) };
        instance.check(status, || "fmi2SetupExperiment".into())?;
        Ok(instance)
    }

    fn check(&mut self, status: Status, call: impl FnOnce() -> String) -> Result<(), FmiError> {
        match status {
            OK | WARNING => Ok(()),
            _ => {
                if status == ERROR || status == FATAL {
                    self.broken = Some(status);
                }
                Err(self.ctx.error(call(), &status_name(status)))
            }
        }
    }

    fn usable(&self, call: &str) -> Result<(), FmiError> {
        match self.broken {
            None => Ok(()),
            Some(s) => Err(FmiError::Call {
                file: self.ctx.file.clone(),
                call: call.into(),
                status: format!("nothing: the instance returned {} before", status_name(s)),
                log: String::new(),
            }),
        }
    }

    pub(crate) fn enter_initialization(&mut self, start_time_s: f64) -> Result<(), FmiError> {
        self.usable("fmi2EnterInitializationMode")?;
        // The start time was given to fmi2SetupExperiment at instantiation; FMI 2 has no second place for it.
        let _ = start_time_s;
        // SAFETY: a live component.
        let status = unsafe { (self.f.enter_initialization_mode)(self.component) };
        self.check(status, || "fmi2EnterInitializationMode".into())
    }

    pub(crate) fn exit_initialization(&mut self) -> Result<(), FmiError> {
        self.usable("fmi2ExitInitializationMode")?;
        // SAFETY: a live component.
        let status = unsafe { (self.f.exit_initialization_mode)(self.component) };
        self.check(status, || "fmi2ExitInitializationMode".into())?;
        self.initialized = true;
        Ok(())
    }

    pub(crate) fn set_reals(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmiError> {
        assert_eq!(refs.len(), values.len(), "one value per reference");
        self.usable("fmi2SetReal")?;
        // SAFETY: both slices hold refs.len() elements.
        let status = unsafe { (self.f.set_real)(self.component, refs.as_ptr(), refs.len(), values.as_ptr()) };
        self.check(status, || format!("fmi2SetReal of value references {refs:?}"))
    }

    pub(crate) fn get_reals(&mut self, refs: &[u32], values: &mut [f64]) -> Result<(), FmiError> {
        assert_eq!(refs.len(), values.len(), "one value per reference");
        self.usable("fmi2GetReal")?;
        // SAFETY: both slices hold refs.len() elements.
        let status = unsafe { (self.f.get_real)(self.component, refs.as_ptr(), refs.len(), values.as_mut_ptr()) };
        self.check(status, || format!("fmi2GetReal of value references {refs:?}"))
    }

    pub(crate) fn do_step(&mut self, t_s: f64, step_s: f64) -> Result<(), FmiError> {
        self.usable("fmi2DoStep")?;
        // SAFETY: a live component. noSetFMUStatePriorToCurrentPoint is true: the rig never steps backwards (a
        // restored state is put back before stepping on from it).
        let status = unsafe { (self.f.do_step)(self.component, t_s, step_s, 1) };
        self.check(status, || format!("fmi2DoStep at t = {t_s} s by {step_s} s"))
    }

    pub(crate) fn save_state(&mut self) -> Result<SavedState, FmiError> {
        self.usable("fmi2GetFMUstate")?;
        let mut state: FmuState = std::ptr::null_mut();
        // SAFETY: a live component; a null state asks the FMU for a new one.
        let status = unsafe { (self.f.get_fmu_state)(self.component, &mut state) };
        self.check(status, || "fmi2GetFMUstate".into())?;
        let mut size = 0usize;
        // SAFETY: `state` is the FMU's.
        let status = unsafe { (self.f.serialized_size)(self.component, state, &mut size) };
        let mut bytes = vec![0u8; size];
        let serialized = self.check(status, || "fmi2SerializedFMUstateSize".into()).and_then(|()| {
            // SAFETY: `bytes` holds `size` bytes.
            let status = unsafe { (self.f.serialize)(self.component, state, bytes.as_mut_ptr(), size) };
            self.check(status, || "fmi2SerializeFMUstate".into())
        });
        // SAFETY: the state was the FMU's to free.
        unsafe { (self.f.free_fmu_state)(self.component, &mut state) };
        serialized.map(|()| bytes)
    }

    pub(crate) fn restore_state(&mut self, saved: &[u8]) -> Result<(), FmiError> {
        self.usable("fmi2DeSerializeFMUstate")?;
        let mut state: FmuState = std::ptr::null_mut();
        // SAFETY: `saved` holds saved.len() bytes; a null state asks the FMU for a new one.
        let status = unsafe { (self.f.deserialize)(self.component, saved.as_ptr(), saved.len(), &mut state) };
        self.check(status, || format!("fmi2DeSerializeFMUstate of {} bytes", saved.len()))?;
        // SAFETY: `state` is the FMU's.
        let status = unsafe { (self.f.set_fmu_state)(self.component, state) };
        let set = self.check(status, || "fmi2SetFMUstate".into());
        // SAFETY: the state was the FMU's to free.
        unsafe { (self.f.free_fmu_state)(self.component, &mut state) };
        set
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: a live component, freed once; after fmi2Fatal the standard allows no call at all.
        unsafe {
            if self.broken == Some(FATAL) {
                return;
            }
            if self.initialized && self.broken.is_none() {
                (self.f.terminate)(self.component);
            }
            (self.f.free_instance)(self.component);
        }
    }
}
