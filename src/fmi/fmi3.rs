//! The FMI 3.0 co-simulation API as an importer calls it: the functions' C types (from the standard's
//! `fmi3FunctionTypes.h`), loaded from the FMU's binary, and an [`Instance`] whose every call checks the returned
//! status and, on failure, says which call, what status and what the FMU logged. Event mode, early return and
//! clocks are not used (the instance is created without them).

use crate::calls::{Calls, FmuState, StateCalls, Status, keep_log_line};
use crate::{CallContext, FmiError, SavedState, c_string};
use std::ffi::{c_char, c_void};
use std::path::Path;
use std::sync::Arc;

type InstanceHandle = *mut c_void;

const STATE_CALLS: StateCalls = StateCalls {
    get: "fmi3GetFMUState",
    size: "fmi3SerializedFMUStateSize",
    serialize: "fmi3SerializeFMUState",
    deserialize: "fmi3DeserializeFMUState",
    set: "fmi3SetFMUState",
};

/// fmi3LogMessageCallback: keeps the message. SAFETY: `env` is the `Log` the instance owns (alive as long as the
/// instance); the strings are NUL-terminated or null, as FMI 3 requires.
unsafe extern "C" fn log_message(env: *mut c_void, status: Status, category: *const c_char, message: *const c_char) {
    // SAFETY: see above.
    unsafe { keep_log_line(env as *const crate::Log, 3, status, category, message) }
}

type LogCallback = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

fmi_functions! {
    "FMI 3.0",
    instantiate: "fmi3InstantiateCoSimulation": fn(*const c_char, *const c_char, *const c_char, bool, bool, bool, bool, *const u32, usize, *mut c_void, Option<LogCallback>, *const c_void) -> InstanceHandle;
    free_instance: "fmi3FreeInstance": fn(InstanceHandle);
    enter_initialization_mode: "fmi3EnterInitializationMode": fn(InstanceHandle, bool, f64, f64, bool, f64) -> Status;
    exit_initialization_mode: "fmi3ExitInitializationMode": fn(InstanceHandle) -> Status;
    terminate: "fmi3Terminate": fn(InstanceHandle) -> Status;
    get_float64: "fmi3GetFloat64": fn(InstanceHandle, *const u32, usize, *mut f64, usize) -> Status;
    set_float64: "fmi3SetFloat64": fn(InstanceHandle, *const u32, usize, *const f64, usize) -> Status;
    get_int32: "fmi3GetInt32": fn(InstanceHandle, *const u32, usize, *mut i32, usize) -> Status;
    set_int32: "fmi3SetInt32": fn(InstanceHandle, *const u32, usize, *const i32, usize) -> Status;
    get_boolean: "fmi3GetBoolean": fn(InstanceHandle, *const u32, usize, *mut u8, usize) -> Status;
    set_boolean: "fmi3SetBoolean": fn(InstanceHandle, *const u32, usize, *const u8, usize) -> Status;
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
    calls: Calls,
    /// The log the FMU's callback writes to, alive as long as the instance.
    _log: Box<crate::Log>,
    initialized: bool,
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
        Ok(Self { f, handle, calls: Calls::new(ctx, 3, &STATE_CALLS), _log: log, initialized: false })
    }

    pub(crate) fn enter_initialization(&mut self, start_time_s: f64) -> Result<(), FmiError> {
        self.calls.usable("fmi3EnterInitializationMode")?;
        // SAFETY: a live instance.
        let status = unsafe { (self.f.enter_initialization_mode)(self.handle, false, 0.0, start_time_s, false, 0.0) };
        self.calls.check(status, || "fmi3EnterInitializationMode".into())
    }

    pub(crate) fn exit_initialization(&mut self) -> Result<(), FmiError> {
        self.calls.usable("fmi3ExitInitializationMode")?;
        // SAFETY: a live instance.
        let status = unsafe { (self.f.exit_initialization_mode)(self.handle) };
        self.calls.check(status, || "fmi3ExitInitializationMode".into())?;
        self.initialized = true;
        Ok(())
    }

    pub(crate) fn set_reals(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: both slices hold refs.len() elements, one value a scalar variable (`values` checks it first).
        self.calls.values("fmi3SetFloat64", refs, values.len(), || unsafe {
            (f.set_float64)(h, refs.as_ptr(), refs.len(), values.as_ptr(), values.len())
        })
    }

    pub(crate) fn get_reals(&mut self, refs: &[u32], values: &mut [f64]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: both slices hold refs.len() elements, one value a scalar variable (`values` checks it first).
        self.calls.values("fmi3GetFloat64", refs, values.len(), || unsafe {
            (f.get_float64)(h, refs.as_ptr(), refs.len(), values.as_mut_ptr(), values.len())
        })
    }

    pub(crate) fn set_integers(&mut self, refs: &[u32], values: &[i32]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: both slices hold refs.len() elements, one value a scalar variable (`values` checks it first).
        self.calls.values("fmi3SetInt32", refs, values.len(), || unsafe {
            (f.set_int32)(h, refs.as_ptr(), refs.len(), values.as_ptr(), values.len())
        })
    }

    pub(crate) fn get_integers(&mut self, refs: &[u32], values: &mut [i32]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: both slices hold refs.len() elements, one value a scalar variable (`values` checks it first).
        self.calls.values("fmi3GetInt32", refs, values.len(), || unsafe {
            (f.get_int32)(h, refs.as_ptr(), refs.len(), values.as_mut_ptr(), values.len())
        })
    }

    /// fmi3Boolean is a C bool, read and written as its byte (0 or 1) so that no other byte an FMU writes is ever
    /// a Rust bool.
    pub(crate) fn set_booleans(&mut self, refs: &[u32], values: &[u8]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: both slices hold refs.len() elements, one value a scalar variable (`values` checks it first).
        self.calls.values("fmi3SetBoolean", refs, values.len(), || unsafe {
            (f.set_boolean)(h, refs.as_ptr(), refs.len(), values.as_ptr(), values.len())
        })
    }

    pub(crate) fn get_booleans(&mut self, refs: &[u32], values: &mut [u8]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: both slices hold refs.len() elements, one value a scalar variable (`values` checks it first).
        self.calls.values("fmi3GetBoolean", refs, values.len(), || unsafe {
            (f.get_boolean)(h, refs.as_ptr(), refs.len(), values.as_mut_ptr(), values.len())
        })
    }

    pub(crate) fn do_step(&mut self, t_s: f64, step_s: f64) -> Result<(), FmiError> {
        self.calls.usable("fmi3DoStep")?;
        let (mut event, mut terminate, mut early) = (false, false, false);
        let mut last_t_s = t_s;
        // SAFETY: a live instance; the out-parameters are ours.
        let status = unsafe {
            (self.f.do_step)(self.handle, t_s, step_s, true, &mut event, &mut terminate, &mut early, &mut last_t_s)
        };
        self.calls.check(status, || format!("fmi3DoStep at t = {t_s} s by {step_s} s"))?;
        if terminate {
            return Err(self.calls.ctx.error(
                format!("fmi3DoStep at t = {t_s} s by {step_s} s"),
                "terminateSimulation = true (the model cannot go on)",
            ));
        }
        Ok(())
    }

    pub(crate) fn save_state(&mut self) -> Result<SavedState, FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: a live instance; each state pointer is the FMU's own, sized as it says.
        self.calls.save_state(
            |state| unsafe { (f.get_fmu_state)(h, state) },
            |state, size| unsafe { (f.serialized_size)(h, state, size) },
            |state, bytes, size| unsafe { (f.serialize)(h, state, bytes, size) },
            |state| unsafe { (f.free_fmu_state)(h, state) },
        )
    }

    pub(crate) fn restore_state(&mut self, saved: &[u8]) -> Result<(), FmiError> {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: a live instance; `saved` holds the bytes given, and the state made from them is the FMU's.
        self.calls.restore_state(
            saved,
            |bytes, size, state| unsafe { (f.deserialize)(h, bytes, size, state) },
            |state| unsafe { (f.set_fmu_state)(h, state) },
            |state| unsafe { (f.free_fmu_state)(h, state) },
        )
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        let (f, h) = (&self.f, self.handle);
        // SAFETY: a live instance, freed once (after fmi3Fatal, `close` makes no call at all).
        self.calls.close(self.initialized, || unsafe { (f.terminate)(h) }, || unsafe { (f.free_instance)(h) });
    }
}
