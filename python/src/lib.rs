//! `silrig._native`, the Rust half of the `silrig` Python package (python/silrig/ holds the Python half, the base
//! classes `Controller` and `PlantModel`): the rig's controller session ([`controller`]) and plant session
//! ([`plant`]) as Python classes, with the loops that fly a user's controller or model (`serve`, `serve_plant`),
//! and the in-process tools `sim` and `sweep` ([`tools`]), which fly a Python controller in process too
//! ([`in_process`]). The sessions are the ones `silrig-controller`, the C ABI
//! of `libsilrig_client.so` and the rig's own plant use: this is a fourth way in, not a reimplementation, so a
//! Python controller flies here exactly as through the ctypes module `examples/python/silrig_client.py`.
//!
//! Errors: whatever the rig refuses raises `silrig.SilrigError` (a `RuntimeError`) whose `code` is the contract's
//! status code (`silrig.ERR_*`, the same numbers the C ABI returns); malformed arguments raise `TypeError` or
//! `ValueError`, as Python does.

use pyo3::prelude::*;
use silrig_rig::session::{SessionError, Status};

mod controller;
mod in_process;
mod plant;
mod tools;

pyo3::create_exception!(
    silrig,
    SilrigError,
    pyo3::exceptions::PyRuntimeError,
    "The rig refused a call or failed; `code` is one of the contract's status codes (silrig.ERR_*)."
);

/// A `SilrigError` with its `code`.
pub(crate) fn silrig_error(py: Python<'_>, code: Status, message: impl Into<String>) -> PyErr {
    let err = SilrigError::new_err(message.into());
    // Setting an attribute on a fresh exception instance cannot fail but for memory; the message still goes.
    let _ = err.value(py).setattr("code", code.code());
    err
}

/// A session's error as a `SilrigError`.
pub(crate) fn session_error(py: Python<'_>, e: &SessionError) -> PyErr {
    silrig_error(py, e.status(), e.to_string())
}

/// `str(value)`, for the error texts a caller hands over as any object.
pub(crate) fn text_of(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    value.filter(|v| !v.is_none()).map(|v| v.str().map(|s| s.to_string())).transpose()
}

/// The extension module: the classes, functions and status codes `silrig/__init__.py` re-exports.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SilrigError", py.get_type::<SilrigError>())?;
    for status in Status::ALL {
        m.add(status.name(), status.code())?;
    }
    m.add("WIRE_LAYOUT_VERSION", silrig_wire::wire::WIRE_LAYOUT_VERSION)?;
    m.add("MAX_INPUTS", silrig_wire::wire::MAX_INPUTS)?;
    m.add("MAX_OUTPUTS", silrig_wire::wire::MAX_OUTPUTS)?;
    m.add_class::<controller::Plant>()?;
    m.add_class::<controller::Sample>()?;
    m.add_class::<controller::ControllerSession>()?;
    m.add_class::<in_process::InProcessSession>()?;
    m.add_function(wrap_pyfunction!(controller::serve, m)?)?;
    m.add_class::<plant::PlantSession>()?;
    m.add_function(wrap_pyfunction!(plant::plant_parameter, m)?)?;
    m.add_function(wrap_pyfunction!(plant::serve_plant, m)?)?;
    m.add_function(wrap_pyfunction!(tools::sim, m)?)?;
    m.add_function(wrap_pyfunction!(tools::sweep, m)?)?;
    Ok(())
}
