//! The FMI 3.0 co-simulation API as an importer calls it: the functions' C types (from the standard's
//! `fmi3FunctionTypes.h`), loaded from the FMU's binary, and an [`Instance`] whose every call checks the returned
//! status and, on failure, says which call, what status and what the FMU logged. Event mode, early return and
//! clocks are not used (the instance is created without them).

use crate::{CallContext, FmiError, SavedState, c_string};
use std::ffi::{c_char, c_int, c_void};
use std::path::Path;
use std::sync::Arc;

type InstanceHandle = *mut c_void;
type Status = c_int;
type FmuState = *mut c_void;

const OK: Status = 0;
const WARNING: Status = 1;
const DISCARD: Status = 2;
const ERROR: Status = 3;
const FATAL: Status = 4;

fn status_name(status: Status) -> String {
    match status {
        OK => "fmi3OK".into(),
        WARNING => "fmi3Warning".into(),
        DISCARD => "fmi3Discard".into(),
        ERROR => "fmi3Error".into(),
        FATAL => "fmi3Fatal".into(),
        other => format!("status {other}, which FMI 3.0 does not define"),
    }
}

/// fmi3LogMessageCallback: keeps the message. SAFETY: `env` is the `Log` the instance owns (alive as long as the
/// instance); the strings are NUL-terminated or null, as FMI 3 requires.
unsafe extern "C" fn log_message(env: *mut c_void, status: Status, category: *const c_char, message: *const c_char) {
    let text = |p: *const c_char| match p.is_null() {
        true => String::new(),
        // SAFETY: see above.
        false => unsafe { std::ffi::CStr::from_ptr(p) }.to_string_lossy().into_owned(),
    };
    // SAFETY: see above.
    let log = unsafe { &*(env as *const crate::Log) };
    let category = text(category);
    let message = text(message);
    log.push(match category.is_empty() {
        true => format!("[{}] {message}", status_name(status)),
        false => format!("[{}, {category}] {message}", status_name(status)),
    });
}

type LogCallback = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

macro_rules! functions {
    ($($field:ident: $symbol:literal: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The FMI 3.0 functions a co-simulation importer calls, resolved in the FMU's binary.
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
                        // SAFETY: the symbol has the type FMI 3.0's fmi3FunctionTypes.h gives it.
                        let symbol = unsafe {
                            library.get::<unsafe extern "C" fn($($arg),*) $(-> $ret)?>($symbol.as_bytes())
                        }
                        .map_err(|_| format!("its binary {} lacks the FMI 3.0 function {}", binary.display(), $symbol))?;
                        *symbol
                    },)*
                    _library: library,
                })
            }
        }
    };
}

functions! {
    instantiate: "fmi3InstantiateCoSimulation": fn(*const c_char, *const c_char, *const c_char, bool, bool, bool, bool, *const u32, usize, *mut c_void, Option<LogCallback>, *const c_void) -> InstanceHandle;
    free_instance: "fmi3FreeInstance": fn(InstanceHandle);
    enter_initialization_mode: "fmi3EnterInitializationMode": fn(InstanceHandle, bool, f64, f64, bool, f64) -> Status;
    exit_initialization_mode: "fmi3ExitInitializationMode": fn(InstanceHandle) -> Status;
    terminate: "fmi3Terminate": fn(InstanceHandle) -> Status;
    get_float64: "fmi3GetFloat64": fn(InstanceHandle, *const u32, usize, *mut f64, usize) -> Status;
    set_float64: "fmi3SetFloat64": fn(InstanceHandle, *const u32, usize, *const f64, usize) -> Status;
    do_step: "fmi3DoStep": fn(InstanceHandle, f64, f64, bool, *mut bool, *mut bool, *mut bool, *mut f64) -> Status;
    get_fmu_state: "fmi3GetFMUState": fn(InstanceHandle, *mut FmuState) -> Status;
    set_fmu_state: "fmi3SetFMUState": fn(InstanceHandle, FmuState) -> Status;
    free_fmu_state: "fmi3FreeFMUState": fn(InstanceHandle, *mut FmuState) -> Status;
    serialized_size: "fmi3SerializedFMUStateSize": fn(InstanceHandle, FmuState, *mut usize) -> Status;
    serialize: "fmi3SerializeFMUState": fn(InstanceHandle, FmuState, *mut u8, usize) -> Status;
    deserialize: "fmi3DeserializeFMUState": fn(InstanceHandle, *const u8, usize, *mut FmuState) -> Status;
}

/// One FMI 3.0 co-simulation instance.
pub struct Instance {
    f: Arc<Functions>,
    handle: InstanceHandle,
    ctx: CallContext,
    /// The log the FMU's callback writes to, alive as long as the instance.
    _log: Box<crate::Log>,
    initialized: bool,
    /// After fmi3Fatal nothing may be called; after fmi3Error only fmi3FreeInstance.
    broken: Option<Status>,
}

impl Instance {
    pub(crate) fn new(
        f: Arc<Functions>,
        name: &str,
        token: &str,
        resources: &Path,
        ctx: CallContext,
    ) -> Result<Self, FmiError> {
        let log = Box::new(ctx.log.clone());
        // FMI 3 takes the resource folder as a path with a trailing separator, not a URI.
        let folder = format!("{}/", resources.display());
        let (name_c, token_c, folder_c) = (c_string(name), c_string(token), c_string(&folder));
        let env = &*log as *const crate::Log as *mut c_void;
        // SAFETY: the strings outlive the call; the log outlives the instance.
        let handle = unsafe {
            (f.instantiate)(
                name_c.as_ptr(),
                token_c.as_ptr(),
                folder_c.as_ptr(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                env,
                Some(log_message),
                std::ptr::null(),
            )
        };
        if handle.is_null() {
            return Err(ctx.error(
                format!("fmi3InstantiateCoSimulation (instantiationToken {token})"),
                "no instance (a token that does not match its binary's, or a failure it logged)",
            ));
        }
        Ok(Self { f, handle, ctx, _log: log, initialized: false, broken: None })
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
        self.usable("fmi3EnterInitializationMode")?;
        // SAFETY: a live instance.
        let status = unsafe { (self.f.enter_initialization_mode)(self.handle, false, 0.0, start_time_s, false, 0.0) };
        self.check(status, || "fmi3EnterInitializationMode".into())
    }

    pub(crate) fn exit_initialization(&mut self) -> Result<(), FmiError> {
        self.usable("fmi3ExitInitializationMode")?;
        // SAFETY: a live instance.
        let status = unsafe { (self.f.exit_initialization_mode)(self.handle) };
        self.check(status, || "fmi3ExitInitializationMode".into())?;
        self.initialized = true;
        Ok(())
    }

    pub(crate) fn set_reals(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmiError> {
        assert_eq!(refs.len(), values.len(), "one value per reference");
        self.usable("fmi3SetFloat64")?;
        // SAFETY: both slices hold refs.len() elements (scalar variables: one value each).
        let status =
            unsafe { (self.f.set_float64)(self.handle, refs.as_ptr(), refs.len(), values.as_ptr(), values.len()) };
        self.check(status, || format!("fmi3SetFloat64 of value references {refs:?}"))
    }

    pub(crate) fn get_reals(&mut self, refs: &[u32], values: &mut [f64]) -> Result<(), FmiError> {
        assert_eq!(refs.len(), values.len(), "one value per reference");
        self.usable("fmi3GetFloat64")?;
        // SAFETY: both slices hold refs.len() elements (scalar variables: one value each).
        let status =
            unsafe { (self.f.get_float64)(self.handle, refs.as_ptr(), refs.len(), values.as_mut_ptr(), values.len()) };
        self.check(status, || format!("fmi3GetFloat64 of value references {refs:?}"))
    }

    pub(crate) fn do_step(&mut self, t_s: f64, step_s: f64) -> Result<(), FmiError> {
        self.usable("fmi3DoStep")?;
        let (mut event, mut terminate, mut early) = (false, false, false);
        let mut last_t_s = t_s;
        // SAFETY: a live instance; the out-parameters are ours.
        let status = unsafe {
            (self.f.do_step)(self.handle, t_s, step_s, true, &mut event, &mut terminate, &mut early, &mut last_t_s)
        };
        self.check(status, || format!("fmi3DoStep at t = {t_s} s by {step_s} s"))?;
        if terminate {
            return Err(self.ctx.error(
                format!("fmi3DoStep at t = {t_s} s by {step_s} s"),
                "terminateSimulation = true (the model cannot go on)",
            ));
        }
        Ok(())
    }

    pub(crate) fn save_state(&mut self) -> Result<SavedState, FmiError> {
        self.usable("fmi3GetFMUState")?;
        let mut state: FmuState = std::ptr::null_mut();
        // SAFETY: a live instance; a null state asks the FMU for a new one.
        let status = unsafe { (self.f.get_fmu_state)(self.handle, &mut state) };
        self.check(status, || "fmi3GetFMUState".into())?;
        let mut size = 0usize;
        // SAFETY: `state` is the FMU's.
        let status = unsafe { (self.f.serialized_size)(self.handle, state, &mut size) };
        let mut bytes = vec![0u8; size];
        let serialized = self.check(status, || "fmi3SerializedFMUStateSize".into()).and_then(|()| {
            // SAFETY: `bytes` holds `size` bytes.
            let status = unsafe { (self.f.serialize)(self.handle, state, bytes.as_mut_ptr(), size) };
            self.check(status, || "fmi3SerializeFMUState".into())
        });
        // SAFETY: the state was the FMU's to free.
        unsafe { (self.f.free_fmu_state)(self.handle, &mut state) };
        serialized.map(|()| bytes)
    }

    pub(crate) fn restore_state(&mut self, saved: &[u8]) -> Result<(), FmiError> {
        self.usable("fmi3DeserializeFMUState")?;
        let mut state: FmuState = std::ptr::null_mut();
        // SAFETY: `saved` holds saved.len() bytes; a null state asks the FMU for a new one.
        let status = unsafe { (self.f.deserialize)(self.handle, saved.as_ptr(), saved.len(), &mut state) };
        self.check(status, || format!("fmi3DeserializeFMUState of {} bytes", saved.len()))?;
        // SAFETY: `state` is the FMU's.
        let status = unsafe { (self.f.set_fmu_state)(self.handle, state) };
        let set = self.check(status, || "fmi3SetFMUState".into());
        // SAFETY: the state was the FMU's to free.
        unsafe { (self.f.free_fmu_state)(self.handle, &mut state) };
        set
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: a live instance, freed once; after fmi3Fatal the standard allows no call at all.
        unsafe {
            if self.broken == Some(FATAL) {
                return;
            }
            if self.initialized && self.broken.is_none() {
                (self.f.terminate)(self.handle);
            }
            (self.f.free_instance)(self.handle);
        }
    }
}
