//! The plant role: [`PlantSession`] (the rig's [`silrig_rig::plant_session::PlantSession`] as a Python class, its
//! methods those of the ctypes module's `PlantSession`), [`plant_parameter`], and [`serve_plant`], the loop that
//! flies a `PlantModel` (its `name`, `outputs` and `inputs`, `outputs_now()` and `step(inputs, dt_s)`). The rig keeps
//! the clock, the watchdog, the failsafe and the faults around the model, as for a plant in C.

use crate::controller::{end_served, failure};
use crate::{session_error, silrig_error, text_of};
use pyo3::exceptions::PyValueError;
use pyo3::intern;
use pyo3::prelude::*;
use silrig_flight::signals::{InputSignal, OutputSignal, PlantSignals};
use silrig_rig::ProcessArgs;
use silrig_rig::plant_session::{self as rig_plant, PlantTick};
use silrig_rig::session::{SessionError, Status};

/// The announcement of a `PlantModel`: `name`, `outputs` [(name, unit)] or [(name, unit, in_trace)], `inputs`
/// [(name, unit, min, max, hold)] or with a sixth item, the name of the output reporting the actuator's position.
/// A malformed entry is a `ValueError` naming it; the rig's rules (names, units, ranges) are checked when the
/// session opens.
fn signals_of(model: &Bound<'_, PyAny>) -> PyResult<PlantSignals> {
    let py = model.py();
    let plant: String = model.getattr(intern!(py, "name"))?.extract()?;
    let mut outputs = Vec::new();
    for (k, entry) in model.getattr(intern!(py, "outputs"))?.try_iter()?.enumerate() {
        let entry: Vec<Bound<'_, PyAny>> = entry?.extract()?;
        let (name, unit, in_trace) = match entry.as_slice() {
            [name, unit] => (name.extract()?, unit.extract()?, true),
            [name, unit, in_trace] => (name.extract()?, unit.extract()?, in_trace.is_truthy()?),
            _ => return Err(PyValueError::new_err(format!("output {k}: (name, unit) or (name, unit, in_trace)"))),
        };
        outputs.push(OutputSignal { name, unit, in_trace });
    }
    let mut inputs = Vec::new();
    for (k, entry) in model.getattr(intern!(py, "inputs"))?.try_iter()?.enumerate() {
        let entry: Vec<Bound<'_, PyAny>> = entry?.extract()?;
        if !(5..=6).contains(&entry.len()) {
            let shape = "(name, unit, min, max, hold) or (name, unit, min, max, hold, position output)";
            return Err(PyValueError::new_err(format!("input {k}: {shape}")));
        }
        let name: String = entry[0].extract()?;
        let held_output = match entry.get(5).filter(|h| !h.is_none()) {
            None => None,
            Some(held) => {
                let held: String = held.extract()?;
                let index = outputs.iter().position(|o| o.name == held).ok_or_else(|| {
                    PyValueError::new_err(format!(
                        "input {name}: its position output {held:?} is not among the plant's outputs"
                    ))
                })?;
                Some(index)
            }
        };
        inputs.push(InputSignal {
            unit: entry[1].extract()?,
            min: entry[2].extract()?,
            max: entry[3].extract()?,
            hold: entry[4].extract()?,
            held_output,
            command_in_trace: true,
            name,
        });
    }
    Ok(PlantSignals { plant, outputs, inputs })
}

/// The plant's side of one run, opened from the `SILRIG_*` variables, announcing a `PlantModel`'s signals:
/// `tick(outputs)` gives the inputs to step with, or None at the end. Create and use it on one thread.
#[pyclass(unsendable, module = "silrig")]
pub struct PlantSession {
    session: Option<rig_plant::PlantSession>,
    /// Why the session ended: `STOPPED` or `RUN_ENDED` (None while it runs).
    #[pyo3(get)]
    stop_reason: Option<i32>,
}

impl PlantSession {
    fn open(model: &Bound<'_, PyAny>) -> PyResult<Result<Self, SessionError>> {
        let signals = signals_of(model)?;
        let open = || -> Result<Self, SessionError> {
            // A sweep's warm rig forks each flight here, before the run's variables are read.
            let _ = silrig_rig::warm::serve_flights();
            let args = ProcessArgs::from_env(std::env::vars()).map_err(SessionError::Setup)?;
            let scenario = args.scenario().map_err(|e| SessionError::Setup(format!("{e:#}")))?;
            let session = rig_plant::PlantSession::open(args, scenario, &signals)?;
            Ok(Self { session: Some(session), stop_reason: None })
        };
        Ok(open())
    }

    fn live(&mut self, py: Python<'_>) -> PyResult<&mut rig_plant::PlantSession> {
        self.session.as_mut().ok_or_else(|| silrig_error(py, Status::ErrUsage, "the plant session is closed"))
    }

    fn tick_with(&mut self, py: Python<'_>, outputs: &[f64]) -> PyResult<Option<Vec<f64>>> {
        let stop = match self.live(py)?.tick(outputs).map_err(|e| session_error(py, &e))? {
            PlantTick::Inputs(inputs) => return Ok(Some(inputs.to_vec())),
            PlantTick::RunEnded => Status::RunEnded,
            PlantTick::Stopped => Status::Stopped,
        };
        self.stop_reason = Some(stop.code());
        Ok(None)
    }

    fn close_with(&mut self, py: Python<'_>, error: Option<String>) -> PyResult<()> {
        let Some(session) = self.session.take() else { return Ok(()) };
        session
            .finish(error.as_deref())
            .map(drop)
            .map_err(|e| silrig_error(py, Status::ErrSetup, format!("writing the plant report: {e:#}")))
    }
}

#[pymethods]
impl PlantSession {
    /// Open the run as its plant, announcing `model`'s name and signals, and wait for the controller and the
    /// logger. Raises `SilrigError` (`ERR_PLANT` for an announcement that breaks the rules, naming the rule;
    /// `ERR_SETUP`, ...) or `ValueError` for a malformed entry.
    #[new]
    fn py_new(py: Python<'_>, model: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::open(model)?.map_err(|e| session_error(py, &e))
    }

    /// The run's step, s.
    #[getter]
    fn dt_s(&mut self, py: Python<'_>) -> PyResult<f64> {
        Ok(self.live(py)?.dt_s())
    }

    /// What a predecessor saved (a restarted plant), or None.
    #[getter]
    fn restored_checkpoint(&mut self, py: Python<'_>) -> PyResult<Option<String>> {
        Ok(self.live(py)?.restored_checkpoint().map(str::to_string))
    }

    /// Say whether the model restored `restored_checkpoint` (before the first tick).
    #[pyo3(signature = (used, reason = None))]
    fn checkpoint_used(&mut self, py: Python<'_>, used: bool, reason: Option<String>) -> PyResult<()> {
        let outcome = if used { Ok(()) } else { Err(reason.unwrap_or_else(|| "the plant did not say why".into())) };
        self.live(py)?.checkpoint_used(outcome);
        Ok(())
    }

    /// True when the rig wants the model's state now (after stepping).
    #[getter]
    fn checkpoint_due(&mut self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.live(py)?.checkpoint_due())
    }

    /// Keep the model's state, as text, for a restarted plant.
    fn save_checkpoint(&mut self, py: Python<'_>, text: &str) -> PyResult<()> {
        self.live(py)?.save_checkpoint(text);
        Ok(())
    }

    /// Hand in the outputs at this tick (one float per announced output); the inputs to step with (a list), or
    /// None when the run is over (see `stop_reason`).
    fn tick(&mut self, py: Python<'_>, outputs: Vec<f64>) -> PyResult<Option<Vec<f64>>> {
        self.tick_with(py, &outputs)
    }

    /// Write the plant's report and end the session (`error`: why the model gave up, if it did). A second call
    /// does nothing.
    #[pyo3(signature = (error = None))]
    fn close(&mut self, py: Python<'_>, error: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        self.close_with(py, text_of(error)?)
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (kind = None, value = None, traceback = None))]
    fn __exit__(
        &mut self,
        py: Python<'_>,
        kind: Option<&Bound<'_, PyAny>>,
        value: Option<&Bound<'_, PyAny>>,
        traceback: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        let _ = traceback;
        self.close_with(py, failure(kind, value)?)?;
        Ok(false)
    }
}

/// The run's `[plant.parameters]` value of `name`, or `default` when the scenario gives none. Readable before the
/// plant's session opens, so a model can start (trim) at it and announce the trim as its hold values.
#[pyfunction]
#[pyo3(signature = (name, default = None))]
pub fn plant_parameter(py: Python<'_>, name: &str, default: Option<f64>) -> PyResult<Option<f64>> {
    // A sweep's warm rig forks each flight here, before the run's variables are read.
    let _ = silrig_rig::warm::serve_flights();
    let args = ProcessArgs::from_env(std::env::vars()).map_err(|e| silrig_error(py, Status::ErrSetup, e))?;
    let scenario = args.scenario().map_err(|e| silrig_error(py, Status::ErrSetup, format!("{e:#}")))?;
    Ok(scenario.plant.parameters.get(name).copied().or(default))
}

/// Fly `model` (a `PlantModel`) as the run's plant until the run ends or SIGTERM. Returns the process's exit
/// status: 0 at the end, 2 when the session could not open (the reason on stderr). An exception from the model
/// closes the session with it as the reason and propagates.
#[pyfunction]
pub fn serve_plant(py: Python<'_>, model: &Bound<'_, PyAny>) -> PyResult<i32> {
    let opened = match PlantSession::open(model) {
        Ok(opened) => opened.map_err(|e| e.to_string()),
        Err(e) if e.is_instance_of::<PyValueError>(py) => Err(e.value(py).to_string()),
        Err(e) => return Err(e),
    };
    let session = match opened {
        Ok(session) => Bound::new(py, session)?,
        Err(why) => {
            eprintln!("silrig: {why}");
            return Ok(2);
        }
    };
    let flown = fly(py, model, &session);
    end_served(py, flown, |why| session.borrow_mut().close_with(py, why))
}

fn fly(py: Python<'_>, model: &Bound<'_, PyAny>, session: &Bound<'_, PlantSession>) -> PyResult<()> {
    let dt_s = session.borrow_mut().live(py)?.dt_s();
    if model.hasattr(intern!(py, "start"))? {
        model.call_method1(intern!(py, "start"), (dt_s,))?;
    }
    let saved = session.borrow_mut().live(py)?.restored_checkpoint().map(str::to_string);
    if let Some(saved) = saved {
        // Whatever the model refuses with, the flight starts over from tick 0; the events say why.
        let outcome = match model.call_method1(intern!(py, "restore"), (saved,)) {
            Ok(_) => Ok(()),
            Err(e) => Err(failure(Some(e.get_type(py).as_any()), Some(e.value(py).as_any()))?.unwrap_or_default()),
        };
        session.borrow_mut().live(py)?.checkpoint_used(outcome);
    }
    let outputs_now = model.getattr(intern!(py, "outputs_now"))?;
    let step = model.getattr(intern!(py, "step"))?;
    let save = intern!(py, "save");
    loop {
        let outputs: Vec<f64> = outputs_now.call0()?.extract()?;
        let Some(inputs) = session.borrow_mut().tick_with(py, &outputs)? else { return Ok(()) };
        step.call1((inputs, dt_s))?;
        let due = session.borrow_mut().live(py)?.checkpoint_due();
        if due && model.hasattr(save)? {
            let text = model.call_method0(save)?;
            if !text.is_none() {
                let text: String = text.extract()?;
                session.borrow_mut().live(py)?.save_checkpoint(&text);
            }
        }
    }
}
