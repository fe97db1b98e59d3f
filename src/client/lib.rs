//! `libsilrig_client.so`: silrig's controller session ([`silrig_rig::session::ControllerSession`]) and plant
//! session ([`silrig_rig::plant_session::PlantSession`]) behind a C ABI, so that a controller in C, C++, Python
//! (ctypes), MATLAB or anything with a C FFI flies in the rig exactly as `silrig-controller` does, and a vehicle
//! model of the user's own flies as the plant. The functions and their rules are declared, with ownership and threading, in
//! `examples/c/silrig_client.h`; the status codes and sample structs come from `silrig contract --c-header`.
//!
//! Every entry point returns a status code (never unwinds into C: a panic becomes `SILRIG_ERR_INTERNAL`), and an
//! error's text is kept per thread for `silrig_last_error`.

use silrig_rig::ProcessArgs;
use silrig_rig::plant_session::{PlantSession, PlantTick};
use silrig_rig::session::{ControllerSession, Next, SessionError, Status, StopReason, check_client_layout};
use silrig_wire::wire::{PlantInfo, PlantSample};
use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(text: &str) {
    let text = CString::new(text.replace('\0', " ")).expect("NULs were replaced");
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Run `body` at the C boundary: its error becomes the thread's last error and a status code; a panic becomes
/// `SILRIG_ERR_INTERNAL`.
fn boundary(body: impl FnOnce() -> Result<Status, SessionError>) -> c_int {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(status)) => status.code(),
        Ok(Err(e)) => {
            set_last_error(&e.to_string());
            e.status().code()
        }
        Err(panic) => {
            let what = panic.downcast_ref::<&str>().copied().or(panic.downcast_ref::<String>().map(String::as_str));
            set_last_error(&format!("internal error in libsilrig_client: {}", what.unwrap_or("panic")));
            Status::ErrInternal.code()
        }
    }
}

fn usage(text: &str) -> SessionError {
    SessionError::Usage(text.into())
}

/// One controller's session: opaque to C.
pub struct SilrigSession {
    session: ControllerSession,
    restored: Option<CString>,
}

/// Borrow the session behind a pointer from C.
///
/// # Safety
/// `session` is NULL or a pointer `silrig_session_open` returned and `silrig_session_close` has not freed.
unsafe fn session_mut<'a>(session: *mut SilrigSession) -> Result<&'a mut SilrigSession, SessionError> {
    // SAFETY: the caller's contract above.
    unsafe { session.as_mut() }.ok_or_else(|| usage("the session pointer is NULL"))
}

/// The wire layout version this library speaks.
#[unsafe(no_mangle)]
pub extern "C" fn silrig_layout_version() -> u32 {
    silrig_wire::wire::WIRE_LAYOUT_VERSION
}

/// The text of the last error on this thread ("" if none); valid until the next call on this thread.
#[unsafe(no_mangle)]
pub extern "C" fn silrig_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Open the run's controller session from the `SILRIG_*` environment; see the header.
///
/// # Safety
/// `diagnostic_names` points to `diagnostic_count` NUL-terminated strings (or is NULL with a count of 0);
/// `session_out` points to writable storage for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_open(
    layout_version: u32,
    plant_sample_size: usize,
    command_sample_size: usize,
    diagnostic_names: *const *const c_char,
    diagnostic_count: usize,
    session_out: *mut *mut SilrigSession,
) -> c_int {
    boundary(|| {
        if session_out.is_null() {
            return Err(usage("session_out is NULL"));
        }
        // SAFETY: checked non-NULL; the caller gives storage for one pointer.
        unsafe { *session_out = std::ptr::null_mut() };
        check_client_layout(layout_version, plant_sample_size, command_sample_size)?;
        if diagnostic_names.is_null() && diagnostic_count > 0 {
            return Err(usage("diagnostic_names is NULL but diagnostic_count is not 0"));
        }
        let mut names = Vec::with_capacity(diagnostic_count);
        for i in 0..diagnostic_count {
            // SAFETY: the caller gives `diagnostic_count` pointers.
            let name = unsafe { *diagnostic_names.add(i) };
            if name.is_null() {
                return Err(usage(&format!("diagnostic name {i} is NULL")));
            }
            // SAFETY: the caller gives NUL-terminated strings.
            let name = unsafe { CStr::from_ptr(name) };
            names.push(name.to_str().map_err(|_| usage(&format!("diagnostic name {i} is not UTF-8")))?.to_string());
        }
        // A sweep's warm rig forks each flight here, before the run's variables are read.
        let _ = silrig_rig::warm::serve_flights();
        let args = ProcessArgs::from_env(std::env::vars()).map_err(SessionError::Setup)?;
        let scenario = args.scenario().map_err(|e| SessionError::Setup(format!("{e:#}")))?;
        let session = ControllerSession::open(args, scenario, &names)?;
        let restored = session.restored_checkpoint().map(|t| CString::new(t.replace('\0', " ")).expect("no NULs"));
        // SAFETY: checked non-NULL above.
        unsafe { *session_out = Box::into_raw(Box::new(SilrigSession { session, restored })) };
        Ok(Status::Ok)
    })
}

/// Wait for the next plant sample and copy it to `*sample_out`; see the header.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `sample_out` points to a writable `silrig_plant_sample_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_next_sample(
    session: *mut SilrigSession,
    sample_out: *mut PlantSample,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        if sample_out.is_null() {
            return Err(usage("sample_out is NULL"));
        }
        match s.session.next_sample()? {
            Next::Sample(sample) => {
                // SAFETY: checked non-NULL; the caller gives storage for one sample.
                unsafe { sample_out.write(sample) };
                Ok(Status::Ok)
            }
            Next::Stop(StopReason::TerminationRequested) => Ok(Status::Stopped),
            Next::Stop(StopReason::RunEnded) => Ok(Status::RunEnded),
        }
    })
}

/// A string from C, as UTF-8.
///
/// # Safety
/// `text` is NULL or a NUL-terminated string.
unsafe fn c_str<'a>(text: *const c_char, what: &str) -> Result<&'a str, SessionError> {
    if text.is_null() {
        return Err(usage(&format!("{what} is NULL")));
    }
    // SAFETY: the caller's contract.
    unsafe { CStr::from_ptr(text) }.to_str().map_err(|_| usage(&format!("{what} is not UTF-8")))
}

/// Copy the plant's announcement (its name and signals, waiting for it if it has not come) to `*info_out`; see
/// the header.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `info_out` points to a writable `silrig_plant_info_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_plant_info(session: *mut SilrigSession, info_out: *mut PlantInfo) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        if info_out.is_null() {
            return Err(usage("info_out is NULL"));
        }
        let info = PlantInfo::new(s.session.plant()?).map_err(SessionError::Plant)?;
        // SAFETY: checked non-NULL; the caller gives storage for one announcement.
        unsafe { info_out.write(info) };
        Ok(Status::Ok)
    })
}

/// The index of the plant's output `name` in every sample's `outputs` (or of its input `name` in a command's
/// inputs, `input` non-zero), waiting for the plant's announcement if it has not come; `SILRIG_ERR_PLANT` naming
/// the plant's signals when it has none of that name.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `name` is a NUL-terminated string; `index_out` points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_signal_index(
    session: *mut SilrigSession,
    name: *const c_char,
    input: c_int,
    index_out: *mut usize,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        // SAFETY: the caller's contract.
        let name = unsafe { c_str(name, "name") }?;
        if index_out.is_null() {
            return Err(usage("index_out is NULL"));
        }
        let plant = s.session.plant()?;
        let index = if input != 0 { plant.input(name) } else { plant.output(name) }.map_err(SessionError::Plant)?;
        // SAFETY: checked non-NULL.
        unsafe { index_out.write(index) };
        Ok(Status::Ok)
    })
}

/// Fill `inputs_out` (`input_count` doubles, the plant's input count) with a command that leaves every input where
/// it is: each actuator's position in the sample being answered, or the plant's hold value where it reports none.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `inputs_out` points to `input_count` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_held_command(
    session: *mut SilrigSession,
    inputs_out: *mut f64,
    input_count: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        let inputs = s.session.plant()?.inputs.len();
        if input_count != inputs || (inputs_out.is_null() && inputs > 0) {
            return Err(usage(&format!("{input_count} inputs given; the plant takes {inputs}")));
        }
        let held = s.session.held_command();
        // SAFETY: the caller gives `input_count` doubles, which equals the plant's input count.
        unsafe { std::ptr::copy_nonoverlapping(held.as_ptr(), inputs_out, inputs) };
        Ok(Status::Ok)
    })
}

/// Answer the sample `silrig_session_next_sample` gave with one value per plant input; see the header.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `inputs` points to `input_count` doubles; `diagnostics` points to
/// `diagnostic_count` doubles (or is NULL with a count of 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_send_command(
    session: *mut SilrigSession,
    inputs: *const f64,
    input_count: usize,
    diagnostics: *const f64,
    diagnostic_count: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        // SAFETY: the caller gives `count` doubles, or NULL with a count of 0.
        let slice = |p: *const f64, count: usize, what: &str| match (p.is_null(), count) {
            (_, 0) => Ok(&[][..]),
            (true, _) => Err(usage(&format!("{what} is NULL but its count is not 0"))),
            (false, n) => Ok(unsafe { std::slice::from_raw_parts(p, n) }),
        };
        let inputs = slice(inputs, input_count, "inputs")?;
        let diagnostics = slice(diagnostics, diagnostic_count, "diagnostics")?;
        s.session.send(inputs, diagnostics)?;
        Ok(Status::Ok)
    })
}

/// The controller's step, s (the scenario's dt); NaN for a NULL session.
///
/// # Safety
/// `session` comes from `silrig_session_open`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_dt_s(session: *mut SilrigSession) -> f64 {
    // SAFETY: the caller's contract.
    unsafe { session_mut(session) }.map_or(f64::NAN, |s| s.session.dt_s())
}

/// The scenario's attitude set point at the start, deg: roll (phi), pitch (theta), yaw (psi).
///
/// # Safety
/// `session` comes from `silrig_session_open`; `setpoint_deg_out` points to 3 writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_setpoint_deg(session: *mut SilrigSession, setpoint_deg_out: *mut f64) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        if setpoint_deg_out.is_null() {
            return Err(usage("setpoint_deg_out is NULL"));
        }
        let sp = &s.session.scenario().setpoint;
        // SAFETY: the caller gives 3 doubles.
        unsafe { std::ptr::copy_nonoverlapping([sp.phi_deg, sp.theta_deg, sp.psi_deg].as_ptr(), setpoint_deg_out, 3) };
        Ok(Status::Ok)
    })
}

/// The scenario's set point of output `name` at the start (`[setpoint]`'s), in that output's unit; see the header.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `name` is a NUL-terminated string; `value_out` points to one
/// writable double.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_setpoint(
    session: *mut SilrigSession,
    name: *const c_char,
    value_out: *mut f64,
) -> c_int {
    // SAFETY: the caller's contract, passed on.
    unsafe { silrig_session_setpoint_at(session, name, 0.0, value_out) }
}

/// The scenario's set point of output `name` in force at `t_s` (a sample's `t_sim_s`: `[setpoint]`'s, or the
/// last of `[[setpoint_steps]]` at or before it), in that output's unit; see the header.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `name` is a NUL-terminated string; `value_out` points to one
/// writable double.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_setpoint_at(
    session: *mut SilrigSession,
    name: *const c_char,
    t_s: f64,
    value_out: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        // SAFETY: the caller's contract.
        let name = unsafe { c_str(name, "name") }?;
        if value_out.is_null() {
            return Err(usage("value_out is NULL"));
        }
        if t_s.is_nan() {
            return Err(usage("t_s is NaN: pass the sample's t_sim_s"));
        }
        let Some(value) = s.session.scenario().setpoint_at(name, t_s) else { return Ok(Status::NotGiven) };
        // SAFETY: checked non-NULL.
        unsafe { value_out.write(value) };
        Ok(Status::Ok)
    })
}

/// What a predecessor saved with `silrig_session_save_checkpoint` (a restarted controller), or NULL.
///
/// # Safety
/// `session` comes from `silrig_session_open`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_restored_checkpoint(session: *mut SilrigSession) -> *const c_char {
    // SAFETY: the caller's contract.
    unsafe { session_mut(session) }.ok().and_then(|s| s.restored.as_ref()).map_or(std::ptr::null(), |c| c.as_ptr())
}

/// Say whether the controller resumed from the restored checkpoint: `used` 1, or 0 with `reason` (may be NULL)
/// saying why it did not fit. The run's events then say which state the controller joined the flight with; without
/// this call they say the controller did not tell.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `reason` is NULL or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_checkpoint_used(
    session: *mut SilrigSession,
    used: c_int,
    reason: *const c_char,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        // SAFETY: the caller's contract.
        s.session.checkpoint_used(unsafe { used_outcome(used, reason, "controller") });
        Ok(Status::Ok)
    })
}

/// What `*_checkpoint_used(used, reason)` says: restored, or why not.
///
/// # Safety
/// `reason` is NULL or a NUL-terminated string.
unsafe fn used_outcome(used: c_int, reason: *const c_char, who: &str) -> Result<(), String> {
    if used != 0 {
        Ok(())
    } else if reason.is_null() {
        Err(format!("the {who} did not say why"))
    } else {
        // SAFETY: the caller gives a NUL-terminated string.
        Err(unsafe { CStr::from_ptr(reason) }.to_string_lossy().into_owned())
    }
}

/// 1 when the session wants a checkpoint now (after the command just sent), 0 otherwise.
///
/// # Safety
/// `session` comes from `silrig_session_open`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_checkpoint_due(session: *mut SilrigSession) -> c_int {
    // SAFETY: the caller's contract.
    unsafe { session_mut(session) }.map_or(0, |s| c_int::from(s.session.checkpoint_due()))
}

/// Save `text` as the state a restarted controller resumes from.
///
/// # Safety
/// `session` comes from `silrig_session_open`; `text` is a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_save_checkpoint(session: *mut SilrigSession, text: *const c_char) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { session_mut(session) }?;
        if text.is_null() {
            return Err(usage("text is NULL"));
        }
        // SAFETY: the caller gives a NUL-terminated string.
        let text = unsafe { CStr::from_ptr(text) }.to_string_lossy();
        s.session.save_checkpoint(&text);
        Ok(Status::Ok)
    })
}

/// Write the controller's report and free the session; see the header.
///
/// # Safety
/// `session` comes from `silrig_session_open` and is not used again.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_session_close(session: *mut SilrigSession, error: *const c_char) -> c_int {
    boundary(|| {
        if session.is_null() {
            return Ok(Status::Ok);
        }
        // SAFETY: the caller's contract: a pointer from `silrig_session_open`, not freed yet.
        let mut s = unsafe { Box::from_raw(session) };
        if !error.is_null() {
            // SAFETY: the caller gives a NUL-terminated string.
            let error = unsafe { CStr::from_ptr(error) }.to_string_lossy();
            s.session.fail(&error);
        }
        s.session.finish().map_err(|e| SessionError::Setup(format!("writing the controller report: {e:#}")))?;
        Ok(Status::Ok)
    })
}

/// One plant's session: opaque to C.
pub struct SilrigPlantSession {
    session: PlantSession,
    restored: Option<CString>,
}

/// Borrow the plant session behind a pointer from C.
///
/// # Safety
/// `session` is NULL or a pointer `silrig_plant_open` returned and `silrig_plant_close` has not freed.
unsafe fn plant_mut<'a>(session: *mut SilrigPlantSession) -> Result<&'a mut SilrigPlantSession, SessionError> {
    // SAFETY: the caller's contract above.
    unsafe { session.as_mut() }.ok_or_else(|| usage("the plant session pointer is NULL"))
}

/// Open the run's plant session from the `SILRIG_*` environment, announcing `*info`; see the header.
///
/// # Safety
/// `info` points to a readable `silrig_plant_info_t`; `session_out` points to writable storage for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_open(
    layout_version: u32,
    plant_info_size: usize,
    plant_sample_size: usize,
    command_sample_size: usize,
    info: *const PlantInfo,
    session_out: *mut *mut SilrigPlantSession,
) -> c_int {
    boundary(|| {
        if session_out.is_null() || info.is_null() {
            return Err(usage("info or session_out is NULL"));
        }
        // SAFETY: checked non-NULL; the caller gives storage for one pointer.
        unsafe { *session_out = std::ptr::null_mut() };
        check_client_layout(layout_version, plant_sample_size, command_sample_size)?;
        if plant_info_size != size_of::<PlantInfo>() {
            return Err(SessionError::Layout(format!(
                "the client's plant info is {plant_info_size} bytes, the contract's is {} (layout version \
                 {layout_version}): the header was changed or compiled with other packing",
                size_of::<PlantInfo>()
            )));
        }
        // SAFETY: checked non-NULL; the caller gives a readable announcement.
        let signals = unsafe { info.read() }.signals().map_err(SessionError::Plant)?;
        // A sweep's warm rig forks each flight here, before the run's variables are read.
        let _ = silrig_rig::warm::serve_flights();
        let args = ProcessArgs::from_env(std::env::vars()).map_err(SessionError::Setup)?;
        let scenario = args.scenario().map_err(|e| SessionError::Setup(format!("{e:#}")))?;
        let session = PlantSession::open(args, scenario, &signals)?;
        // Interior NULs cannot come from the JSON-read checkpoint text of a C string; dropped if they do.
        let restored = session.restored_checkpoint().and_then(|t| CString::new(t).ok());
        // SAFETY: checked non-NULL above.
        unsafe { *session_out = Box::into_raw(Box::new(SilrigPlantSession { session, restored })) };
        Ok(Status::Ok)
    })
}

/// The run's `[plant.parameters]` value of `name`, read from the `SILRIG_*` environment before the session opens
/// (a model trims at its parameters and announces the trim as its hold values); see the header.
///
/// # Safety
/// `name` is a NUL-terminated string; `value_out` points to one writable double.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_parameter(name: *const c_char, value_out: *mut f64) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let name = unsafe { c_str(name, "name") }?;
        if value_out.is_null() {
            return Err(usage("value_out is NULL"));
        }
        // A sweep's warm rig forks each flight here, before the run's variables are read.
        let _ = silrig_rig::warm::serve_flights();
        let args = ProcessArgs::from_env(std::env::vars()).map_err(SessionError::Setup)?;
        let scenario = args.scenario().map_err(|e| SessionError::Setup(format!("{e:#}")))?;
        let Some(value) = scenario.plant.parameters.get(name) else { return Ok(Status::NotGiven) };
        // SAFETY: checked non-NULL.
        unsafe { value_out.write(*value) };
        Ok(Status::Ok)
    })
}

/// Hand in the model's outputs at this tick and get the inputs to step it with; see the header.
///
/// # Safety
/// `session` comes from `silrig_plant_open`; `outputs` points to `output_count` doubles; `inputs_out` points to
/// `input_count` writable doubles (or is NULL with a count of 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_tick(
    session: *mut SilrigPlantSession,
    outputs: *const f64,
    output_count: usize,
    inputs_out: *mut f64,
    input_count: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { plant_mut(session) }?;
        if outputs.is_null() || (inputs_out.is_null() && input_count > 0) {
            return Err(usage("outputs or inputs_out is NULL"));
        }
        // SAFETY: the caller gives `output_count` doubles.
        let outputs = unsafe { std::slice::from_raw_parts(outputs, output_count) };
        match s.session.tick(outputs)? {
            PlantTick::Inputs(inputs) => {
                if inputs.len() != input_count {
                    let n = inputs.len();
                    return Err(usage(&format!("room for {input_count} inputs given; the plant announced {n}")));
                }
                // SAFETY: the caller gives `input_count` doubles, which equals the count checked.
                unsafe { std::ptr::copy_nonoverlapping(inputs.as_ptr(), inputs_out, input_count) };
                Ok(Status::Ok)
            }
            PlantTick::RunEnded => Ok(Status::RunEnded),
            PlantTick::Stopped => Ok(Status::Stopped),
        }
    })
}

/// What a predecessor saved with `silrig_plant_save_checkpoint` (a restarted plant), or NULL.
///
/// # Safety
/// `session` comes from `silrig_plant_open`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_restored_checkpoint(session: *mut SilrigPlantSession) -> *const c_char {
    // SAFETY: the caller's contract.
    unsafe { plant_mut(session) }.ok().and_then(|s| s.restored.as_ref()).map_or(std::ptr::null(), |c| c.as_ptr())
}

/// Say whether the model restored the checkpoint: `used` 1 (the flight goes on from its tick), or 0 with `reason`
/// (may be NULL) saying why not (the flight starts again from tick 0). Call before the first `silrig_plant_tick`.
///
/// # Safety
/// `session` comes from `silrig_plant_open`; `reason` is NULL or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_checkpoint_used(
    session: *mut SilrigPlantSession,
    used: c_int,
    reason: *const c_char,
) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { plant_mut(session) }?;
        // SAFETY: the caller's contract.
        s.session.checkpoint_used(unsafe { used_outcome(used, reason, "plant") });
        s.restored = None;
        Ok(Status::Ok)
    })
}

/// 1 when the session wants the model's state now (after stepping with the inputs just handed out), 0 otherwise.
///
/// # Safety
/// `session` comes from `silrig_plant_open`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_checkpoint_due(session: *mut SilrigPlantSession) -> c_int {
    // SAFETY: the caller's contract.
    unsafe { plant_mut(session) }.map_or(0, |s| c_int::from(s.session.checkpoint_due()))
}

/// Save `text` as the model's state a restarted plant resumes from.
///
/// # Safety
/// `session` comes from `silrig_plant_open`; `text` is a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_save_checkpoint(session: *mut SilrigPlantSession, text: *const c_char) -> c_int {
    boundary(|| {
        // SAFETY: the caller's contract.
        let s = unsafe { plant_mut(session) }?;
        // SAFETY: the caller's contract.
        let text = unsafe { c_str(text, "text") }?;
        s.session.save_checkpoint(text);
        Ok(Status::Ok)
    })
}

/// The run's step, s; NaN for a NULL session.
///
/// # Safety
/// `session` comes from `silrig_plant_open`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_dt_s(session: *mut SilrigPlantSession) -> f64 {
    // SAFETY: the caller's contract.
    unsafe { plant_mut(session) }.map_or(f64::NAN, |s| s.session.dt_s())
}

/// Write the plant's report and free the session; see the header.
///
/// # Safety
/// `session` comes from `silrig_plant_open` and is not used again.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn silrig_plant_close(session: *mut SilrigPlantSession, error: *const c_char) -> c_int {
    boundary(|| {
        if session.is_null() {
            return Ok(Status::Ok);
        }
        // SAFETY: the caller's contract: a pointer from `silrig_plant_open`, not freed yet.
        let s = unsafe { Box::from_raw(session) };
        // SAFETY: the caller gives NULL or a NUL-terminated string.
        let error = (!error.is_null()).then(|| unsafe { CStr::from_ptr(error) }.to_string_lossy().into_owned());
        s.session
            .finish(error.as_deref())
            .map_err(|e| SessionError::Setup(format!("writing the plant report: {e:#}")))?;
        Ok(Status::Ok)
    })
}
