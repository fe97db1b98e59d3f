//! A Python controller flown in this process: the object `serve()` flies (`step`, and `diagnostic_names`,
//! `start` when it has them) as the rig's [`Controller`], for the in-process loop of `silrig.sim(...,
//! controller=...)` and `silrig.sweep(..., controller=...)` ([`silrig_adapters::in_process::Models::fly_controller`]),
//! and [`InProcessSession`], what its `start(session)` is handed there in place of the rig's session. The answer is
//! read as `serve()` reads it ([`crate::controller::read_answer`]) and the loop around it keeps the lockstep rig's
//! rules, so a controller gives the trace here that it gives through `silrig run --mode lockstep`.

use crate::controller::{Plant, Sample, read_answer};
use crate::silrig_error;
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use silrig_adapters::in_process::MakeController;
use silrig_flight::scenario::{Scenario, Setpoint};
use silrig_flight::setpoints::{self, SetpointStep};
use silrig_flight::signals::PlantSignals;
use silrig_rig::controller::Controller;
use silrig_rig::session::Status;
use silrig_wire::wire::PlantSample;
use std::sync::{Arc, Mutex};

/// What a controller's `start(session)` is handed when it flies in this process (`silrig.sim(...,
/// controller=...)`): the rig session's methods a controller reads its set-up with (`dt_s`, `setpoint`,
/// `setpoint_deg`, `plant`, `output`, `input`, `held_command`). There is no transport, so no `next_sample` or `send`:
/// the loop hands each sample to `step`.
#[pyclass(module = "silrig")]
pub struct InProcessSession {
    plant: Py<Plant>,
    signals: PlantSignals,
    setpoint: Setpoint,
    /// The scenario's `[[setpoint_steps]]`, for `setpoint(name, t_s=...)`.
    setpoint_steps: Vec<SetpointStep>,
    /// The controller's step, s.
    #[pyo3(get)]
    dt_s: f64,
    /// Where each actuator is at the sample being answered (the hold values before the first).
    held: Vec<f64>,
}

#[pymethods]
impl InProcessSession {
    /// The scenario's attitude set point, deg: (roll, pitch, yaw).
    #[getter]
    fn setpoint_deg(&self) -> (f64, f64, f64) {
        (self.setpoint.phi_deg, self.setpoint.theta_deg, self.setpoint.psi_deg)
    }

    /// The scenario's set point of output `name` in its unit; `default` when the scenario gives none. At the start,
    /// or with `t_s` (a sample's `t_s`) the value in force then, as the served session's `setpoint` reads it.
    #[pyo3(signature = (name, default = None, t_s = None))]
    fn setpoint(&self, name: &str, default: Option<f64>, t_s: Option<f64>) -> Option<f64> {
        setpoints::value_at(&self.setpoint, &self.setpoint_steps, name, t_s.unwrap_or(0.0)).or(default)
    }

    /// The plant's announcement (a `Plant`).
    #[getter]
    fn plant(&self, py: Python<'_>) -> Py<Plant> {
        self.plant.clone_ref(py)
    }

    /// The index of output `name` in a sample's outputs; `SilrigError` (`ERR_PLANT`, naming the plant's outputs)
    /// when the plant has none of that name.
    fn output(&self, py: Python<'_>, name: &str) -> PyResult<usize> {
        self.signals.output(name).map_err(|e| silrig_error(py, Status::ErrPlant, e))
    }

    /// The index of input `name` in a command; `SilrigError` (`ERR_PLANT`) when the plant has none.
    fn input(&self, py: Python<'_>, name: &str) -> PyResult<usize> {
        self.signals.input(name).map_err(|e| silrig_error(py, Status::ErrPlant, e))
    }

    /// A command that leaves every input where its actuator is now (one value per plant input).
    fn held_command(&self) -> Vec<f64> {
        self.held.clone()
    }
}

/// The first exception a Python controller raised in a flight (or in being copied for one), kept for the caller to
/// raise: a bug in `step` is the user's to see with its traceback, not a flight that merely ended early.
pub type RaisedSlot = Arc<Mutex<Option<PyErr>>>;

/// Keep `err` in `slot` unless an earlier one is there; its text, for the flight's end.
fn keep(py: Python<'_>, slot: &RaisedSlot, err: PyErr) -> String {
    let text = crate::controller::failure(Some(err.get_type(py).as_any()), Some(err.value(py).as_any()))
        .ok()
        .flatten()
        .unwrap_or_else(|| "the controller raised an exception".into());
    let mut kept = slot.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    kept.get_or_insert(err);
    text
}

/// A Python controller as the rig's [`Controller`].
struct PythonController {
    controller: Py<PyAny>,
    diagnostic_names: Vec<String>,
    setpoint: Setpoint,
    setpoint_steps: Vec<SetpointStep>,
    dt_s: f64,
    /// Set by `connect`.
    session: Option<Py<InProcessSession>>,
    /// The plant's outputs by name, shared by every sample (set by `connect`).
    output_index: Option<Py<PyDict>>,
    raised: RaisedSlot,
    failed: Option<String>,
}

impl PythonController {
    fn new(py: Python<'_>, controller: Py<PyAny>, scenario: &Scenario, raised: RaisedSlot) -> PyResult<Self> {
        let diagnostic_names: Vec<String> = match controller.bind(py).getattr(intern!(py, "diagnostic_names")) {
            Ok(names) => names.extract()?,
            Err(_) => Vec::new(),
        };
        Ok(Self {
            controller,
            diagnostic_names,
            setpoint: scenario.setpoint.clone(),
            setpoint_steps: scenario.setpoint_steps.clone(),
            dt_s: scenario.timing.controller_dt_s(),
            session: None,
            output_index: None,
            raised,
            failed: None,
        })
    }

    fn open(&mut self, py: Python<'_>, signals: &PlantSignals) -> PyResult<()> {
        let plant = Plant::new(py, signals)?;
        self.output_index = Some(plant.output_index_dict(py));
        let session = InProcessSession {
            plant: Py::new(py, plant)?,
            signals: signals.clone(),
            setpoint: self.setpoint.clone(),
            setpoint_steps: self.setpoint_steps.clone(),
            dt_s: self.dt_s,
            held: signals.hold(),
        };
        let session = Py::new(py, session)?;
        self.session = Some(session.clone_ref(py));
        let controller = self.controller.bind(py);
        if controller.hasattr(intern!(py, "start"))? {
            controller.call_method1(intern!(py, "start"), (session,))?;
        }
        Ok(())
    }

    fn answer(
        &mut self,
        py: Python<'_>,
        sample: &PlantSample,
        command: &mut [f64],
        diagnostics: &mut [f64],
    ) -> PyResult<()> {
        let (Some(session), Some(index)) = (&self.session, &self.output_index) else {
            return Err(silrig_error(py, Status::ErrInternal, "a step before the plant was connected"));
        };
        session.borrow_mut(py).held.copy_from_slice(command);
        let sample = Sample::new(sample.header.tick, sample.t_sim_s, sample.outputs().to_vec(), index.clone_ref(py));
        let out = self.controller.bind(py).call_method1(intern!(py, "step"), (sample, self.dt_s))?;
        let session = session.borrow(py);
        let plant = session.plant.get();
        let said = read_answer(py, out, &plant.input_index_dict(py).into_bound(py), &session.signals, command)?;
        if said.len() != diagnostics.len() {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "step returned {} diagnostics for the {} names in diagnostic_names ({})",
                said.len(),
                diagnostics.len(),
                self.diagnostic_names.join(", ")
            )));
        }
        diagnostics.copy_from_slice(&said);
        Ok(())
    }
}

impl Controller for PythonController {
    fn diagnostic_names(&self) -> Vec<String> {
        self.diagnostic_names.clone()
    }

    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String> {
        Python::attach(|py| self.open(py, plant).map_err(|e| keep(py, &self.raised, e)))
    }

    fn step(&mut self, sample: &PlantSample, _dt_s: f64, command: &mut [f64], diagnostics: &mut [f64]) {
        if self.failed.is_some() {
            return;
        }
        self.failed =
            Python::attach(|py| self.answer(py, sample, command, diagnostics).err().map(|e| keep(py, &self.raised, e)));
    }

    fn failure(&mut self) -> Option<String> {
        self.failed.clone()
    }
}

/// Each flight's controller: `controller` itself (`copy` false: one flight, the caller's object flies and keeps
/// its state), or a `copy.deepcopy` of it per flight (a sweep: every case starts from the object as given). An
/// exception raised on the way is kept in `raised`.
pub fn maker(
    py: Python<'_>,
    controller: &Bound<'_, PyAny>,
    copy: bool,
    raised: RaisedSlot,
) -> PyResult<MakeController> {
    if !controller.hasattr(intern!(py, "step"))? {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "controller must have a step(sample, dt_s) method (a silrig.Controller); got {}",
            controller.get_type().name()?
        )));
    }
    let controller = controller.clone().unbind();
    let deepcopy = copy.then(|| py.import("copy")?.getattr("deepcopy").map(Bound::unbind)).transpose()?;
    Ok(Arc::new(move |scenario: &Scenario| -> Result<Box<dyn Controller>, String> {
        Python::attach(|py| {
            let flown = match &deepcopy {
                Some(deepcopy) => deepcopy.bind(py).call1((controller.bind(py),))?.unbind(),
                None => controller.clone_ref(py),
            };
            PythonController::new(py, flown, scenario, raised.clone()).map(|c| Box::new(c) as Box<dyn Controller>)
        })
        .map_err(|e| Python::attach(|py| keep(py, &raised, e)))
    }))
}

/// The exception a flight's controller raised, if one did (taken: a second call gives None).
pub fn raised(slot: &RaisedSlot) -> Option<PyErr> {
    slot.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).take()
}
