//! What the FMI 2.0 and 3.0 instances share: the status codes both standards give the same numbers, every call's
//! check (anything but OK or a warning is an error naming the call, the status and what the FMU logged; after
//! Error only freeing is allowed, after Fatal nothing), the get and set of values by reference, the end of an
//! instance, the FMU state's take-serialize-free and deserialize-set-free sequences, and the log callback's line.

use crate::{CallContext, FmiError, Log, SavedState};
use std::ffi::{c_char, c_int, c_void};

/// A status as both standards number them.
pub(crate) type Status = c_int;
/// An FMU's opaque state.
pub(crate) type FmuState = *mut c_void;

pub(crate) const OK: Status = 0;
pub(crate) const WARNING: Status = 1;
pub(crate) const ERROR: Status = 3;
pub(crate) const FATAL: Status = 4;

/// The names a version gives the calls the shared sequences make (for errors).
pub(crate) struct StateCalls {
    pub(crate) get: &'static str,
    pub(crate) size: &'static str,
    pub(crate) serialize: &'static str,
    pub(crate) deserialize: &'static str,
    pub(crate) set: &'static str,
}

/// One instance's call bookkeeping.
pub(crate) struct Calls {
    pub(crate) ctx: CallContext,
    /// 2 or 3: the prefix of every name.
    version: u8,
    state_calls: &'static StateCalls,
    /// The Error or Fatal an earlier call returned.
    broken: Option<Status>,
}

impl Calls {
    pub(crate) fn new(ctx: CallContext, version: u8, state_calls: &'static StateCalls) -> Self {
        Self { ctx, version, state_calls, broken: None }
    }

    /// `fmi2OK`, `fmi3Discard`, ...
    pub(crate) fn status_name(version: u8, status: Status) -> String {
        let word = match status {
            0 => "OK",
            1 => "Warning",
            2 => "Discard",
            3 => "Error",
            4 => "Fatal",
            5 if version == 2 => return "fmi2Pending (asynchronous doStep is not supported)".into(),
            other => return format!("status {other}, which FMI {version}.0 does not define"),
        };
        format!("fmi{version}{word}")
    }

    /// OK or a warning goes on; anything else is the error of `call`.
    pub(crate) fn check(&mut self, status: Status, call: impl FnOnce() -> String) -> Result<(), FmiError> {
        match status {
            OK | WARNING => Ok(()),
            _ => {
                if status == ERROR || status == FATAL {
                    self.broken = Some(status);
                }
                Err(self.ctx.error(call(), &Self::status_name(self.version, status)))
            }
        }
    }

    /// An error instead of `call` when an earlier call broke the instance.
    pub(crate) fn usable(&self, call: &str) -> Result<(), FmiError> {
        match self.broken {
            None => Ok(()),
            Some(s) => Err(FmiError::Call {
                file: self.ctx.file.clone(),
                call: call.into(),
                status: format!("nothing: the instance returned {} before", Self::status_name(self.version, s)),
                log: String::new(),
            }),
        }
    }

    /// One get or set of scalar values by reference (`run` makes the call): one value per reference, the instance
    /// still usable, the status checked, an error naming the call and the references.
    pub(crate) fn values(
        &mut self,
        call: &str,
        refs: &[u32],
        n_values: usize,
        run: impl FnOnce() -> Status,
    ) -> Result<(), FmiError> {
        assert_eq!(refs.len(), n_values, "one value per reference");
        self.usable(call)?;
        let status = run();
        self.check(status, || format!("{call} of value references {refs:?}"))
    }

    /// The end of an instance: `terminate` if it was initialized and no call failed, then `free`, unless a Fatal
    /// status forbids any call at all. Terminate's status changes nothing: freeing follows either way.
    pub(crate) fn close(&self, initialized: bool, terminate: impl FnOnce() -> Status, free: impl FnOnce()) {
        if !self.may_free() {
            return;
        }
        if initialized && self.healthy() {
            let _ = terminate();
        }
        free();
    }

    /// Whether the instance may be terminated (no error so far).
    pub(crate) fn healthy(&self) -> bool {
        self.broken.is_none()
    }

    /// Whether the instance may still be freed (not after Fatal).
    pub(crate) fn may_free(&self) -> bool {
        self.broken != Some(FATAL)
    }

    /// Take the state (`get`), serialize it (`size`, `serialize`) and free it (`free`), whatever failed.
    pub(crate) fn save_state(
        &mut self,
        get: impl FnOnce(*mut FmuState) -> Status,
        size: impl FnOnce(FmuState, *mut usize) -> Status,
        serialize: impl FnOnce(FmuState, *mut u8, usize) -> Status,
        free: impl FnOnce(*mut FmuState) -> Status,
    ) -> Result<SavedState, FmiError> {
        let names = self.state_calls;
        self.usable(names.get)?;
        let mut state: FmuState = std::ptr::null_mut();
        self.check(get(&mut state), || names.get.into())?;
        let mut bytes = Vec::new();
        let mut n = 0usize;
        let serialized = self.check(size(state, &mut n), || names.size.into()).and_then(|()| {
            bytes = vec![0u8; n];
            self.check(serialize(state, bytes.as_mut_ptr(), n), || names.serialize.into())
        });
        free(&mut state);
        serialized.map(|()| bytes)
    }

    /// Deserialize `saved` into a new state, put it in place (`set`) and free it, whatever failed.
    pub(crate) fn restore_state(
        &mut self,
        saved: &[u8],
        deserialize: impl FnOnce(*const u8, usize, *mut FmuState) -> Status,
        set: impl FnOnce(FmuState) -> Status,
        free: impl FnOnce(*mut FmuState) -> Status,
    ) -> Result<(), FmiError> {
        let names = self.state_calls;
        self.usable(names.deserialize)?;
        let mut state: FmuState = std::ptr::null_mut();
        let status = deserialize(saved.as_ptr(), saved.len(), &mut state);
        self.check(status, || format!("{} of {} bytes", names.deserialize, saved.len()))?;
        let set = self.check(set(state), || names.set.into());
        free(&mut state);
        set
    }
}

/// Keep one message the FMU logged. SAFETY: `log` points to the `Log` the instance owns (alive as long as the
/// instance); the strings are NUL-terminated or null, as both standards require.
pub(crate) unsafe fn keep_log_line(
    log: *const Log,
    version: u8,
    status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    let text = |p: *const c_char| match p.is_null() {
        true => String::new(),
        // SAFETY: see above.
        false => unsafe { std::ffi::CStr::from_ptr(p) }.to_string_lossy().into_owned(),
    };
    // SAFETY: see above.
    let log = unsafe { &*log };
    let (category, message) = (text(category), text(message));
    let status = Calls::status_name(version, status);
    log.push(match category.is_empty() {
        true => format!("[{status}] {message}"),
        false => format!("[{status}, {category}] {message}"),
    });
}
