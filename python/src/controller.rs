//! The controller role: [`ControllerSession`] (the rig's [`silrig_rig::session::ControllerSession`] as a Python
//! class, its methods those of the ctypes module's `Session`), what it hands out ([`Plant`], [`Sample`]), and
//! [`serve`], the loop that flies a `Controller` (any object with `step`; the package's base class gives the rest).
//! The loop runs here, in Rust: per tick it calls the controller's `step` once and nothing else in Python.

use crate::{session_error, silrig_error, text_of};
use pyo3::exceptions::PyValueError;
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString, PyTuple};
use silrig_rig::ProcessArgs;
use silrig_rig::session::{self as rig_session, Next, SessionError, Status, StopReason};

/// What the plant announced: its name and signals, and where each is by name.
#[pyclass(frozen, module = "silrig")]
pub struct Plant {
    /// The plant's name (`f16`, `toy`).
    #[pyo3(get)]
    name: String,
    /// The outputs, `(name, unit)`, in the order of every sample's outputs.
    #[pyo3(get)]
    outputs: Vec<(String, String)>,
    /// The inputs, `(name, unit, min, max, hold)`, in the order a command gives them.
    #[pyo3(get)]
    inputs: Vec<(String, String, f64, f64, f64)>,
    // Python dicts: looking a `str` up in one uses the hash the string keeps, with no conversion to UTF-8.
    output_index: Py<PyDict>,
    input_index: Py<PyDict>,
}

#[pymethods]
impl Plant {
    /// `{output name: index in a sample's outputs}` (a copy).
    #[getter]
    fn output_index<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.output_index.bind(py).copy()
    }

    /// `{input name: index in a command}` (a copy).
    #[getter]
    fn input_index<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.input_index.bind(py).copy()
    }

    fn __repr__(&self) -> String {
        let names = |v: Vec<&String>| v.into_iter().map(String::as_str).collect::<Vec<_>>().join(", ");
        format!(
            "Plant({}: outputs {}; inputs {})",
            self.name,
            names(self.outputs.iter().map(|o| &o.0).collect()),
            names(self.inputs.iter().map(|i| &i.0).collect())
        )
    }
}

impl Plant {
    pub(crate) fn new(py: Python<'_>, signals: &silrig_flight::signals::PlantSignals) -> PyResult<Self> {
        let outputs: Vec<(String, String)> = signals.outputs.iter().map(|o| (o.name.clone(), o.unit.clone())).collect();
        let inputs: Vec<_> =
            signals.inputs.iter().map(|i| (i.name.clone(), i.unit.clone(), i.min, i.max, i.hold)).collect();
        let output_index = PyDict::new(py);
        for (k, o) in outputs.iter().enumerate() {
            output_index.set_item(&o.0, k)?;
        }
        let input_index = PyDict::new(py);
        for (k, i) in inputs.iter().enumerate() {
            input_index.set_item(&i.0, k)?;
        }
        Ok(Self {
            name: signals.plant.clone(),
            outputs,
            inputs,
            output_index: output_index.unbind(),
            input_index: input_index.unbind(),
        })
    }

    /// `{output name: index}`, the dict itself (each sample reads its outputs by name through it).
    pub(crate) fn output_index_dict(&self, py: Python<'_>) -> Py<PyDict> {
        self.output_index.clone_ref(py)
    }

    /// `{input name: index}`, the dict itself.
    pub(crate) fn input_index_dict(&self, py: Python<'_>) -> Py<PyDict> {
        self.input_index.clone_ref(py)
    }
}

/// One plant sample: read an output by name (`sample["theta_deg"]`) or by index (`sample[3]`); `tick`, `t_s` and
/// `outputs` (the values in the plant's order) beside.
#[pyclass(frozen, module = "silrig")]
pub struct Sample {
    /// The plant's tick this sample is of.
    #[pyo3(get)]
    tick: u64,
    /// Simulated time, s.
    #[pyo3(get)]
    t_s: f64,
    /// The outputs in the order the plant announced them.
    #[pyo3(get)]
    outputs: Vec<f64>,
    index: Py<PyDict>,
}

impl Sample {
    /// The sample of `tick` at `t_s`, its outputs read by name through `index` (the plant's `{output: index}`).
    pub(crate) fn new(tick: u64, t_s: f64, outputs: Vec<f64>, index: Py<PyDict>) -> Self {
        Self { tick, t_s, outputs, index }
    }
}

#[pymethods]
impl Sample {
    fn __getitem__(&self, py: Python<'_>, key: &Bound<'_, PyAny>) -> PyResult<f64> {
        let index = self.index.bind(py);
        let k = match key.cast::<PyString>() {
            Ok(name) => match index.get_item(name)? {
                Some(k) => k.extract::<usize>()?,
                None => {
                    let names: Vec<String> = index.keys().extract()?;
                    return Err(pyo3::exceptions::PyKeyError::new_err(format!(
                        "the plant has no output `{name}`; its outputs: {}",
                        names.join(", ")
                    )));
                }
            },
            Err(_) => {
                let i: isize = key.extract()?;
                let n = self.outputs.len() as isize;
                let k = if i < 0 { i + n } else { i };
                if !(0..n).contains(&k) {
                    return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                        "output {i} of a plant with {n} outputs"
                    )));
                }
                k as usize
            }
        };
        Ok(self.outputs[k])
    }

    fn __len__(&self) -> usize {
        self.outputs.len()
    }

    fn __repr__(&self) -> String {
        format!("Sample(tick {}, t_s {}, {} outputs)", self.tick, self.t_s, self.outputs.len())
    }
}

/// The controller's side of one run, opened from the `SILRIG_*` variables the launcher sets: `next_sample()`, then
/// one `send()` per sample, then `close()` (or use it as a context manager). Create and use it on one thread.
#[pyclass(unsendable, module = "silrig")]
pub struct ControllerSession {
    session: Option<rig_session::ControllerSession>,
    plant: Option<Py<Plant>>,
    /// Why the session stopped handing out samples: `STOPPED` or `RUN_ENDED` (None while it runs).
    #[pyo3(get)]
    stop_reason: Option<i32>,
}

impl ControllerSession {
    /// Open from the environment, announcing `diagnostic_names`.
    fn open(diagnostic_names: Vec<String>) -> Result<Self, SessionError> {
        // A sweep's warm rig forks each flight here, before the run's variables are read.
        let _ = silrig_rig::warm::serve_flights();
        let args = ProcessArgs::from_env(std::env::vars()).map_err(SessionError::Setup)?;
        let scenario = args.scenario().map_err(|e| SessionError::Setup(format!("{e:#}")))?;
        let session = rig_session::ControllerSession::open(args, scenario, &diagnostic_names)?;
        Ok(Self { session: Some(session), plant: None, stop_reason: None })
    }

    fn live(&mut self, py: Python<'_>) -> PyResult<&mut rig_session::ControllerSession> {
        self.session.as_mut().ok_or_else(|| silrig_error(py, Status::ErrUsage, "the session is closed"))
    }

    /// The plant's announcement, waiting for it; the name maps are kept for the loop.
    fn plant_info(&mut self, py: Python<'_>) -> PyResult<Py<Plant>> {
        if let Some(plant) = &self.plant {
            return Ok(plant.clone_ref(py));
        }
        let session = self.live(py)?;
        let signals = session.plant().map_err(|e| session_error(py, &e))?;
        let plant = Py::new(py, Plant::new(py, signals)?)?;
        self.plant = Some(plant.clone_ref(py));
        Ok(plant)
    }

    fn next(&mut self, py: Python<'_>) -> PyResult<Option<Sample>> {
        let index = self.plant_info(py)?.get().output_index.clone_ref(py);
        let session = self.live(py)?;
        match session.next_sample().map_err(|e| session_error(py, &e))? {
            Next::Sample(raw) => {
                let n = (raw.outputs_len as usize).min(raw.outputs.len());
                Ok(Some(Sample { tick: raw.header.tick, t_s: raw.t_sim_s, outputs: raw.outputs[..n].to_vec(), index }))
            }
            Next::Stop(reason) => {
                self.stop_reason = Some(
                    match reason {
                        StopReason::TerminationRequested => Status::Stopped,
                        StopReason::RunEnded => Status::RunEnded,
                    }
                    .code(),
                );
                Ok(None)
            }
        }
    }

    fn send_command(&mut self, py: Python<'_>, inputs: &[f64], diagnostics: &[f64]) -> PyResult<bool> {
        match self.live(py)?.send(inputs, diagnostics) {
            Ok(()) => Ok(true),
            Err(SessionError::CommandRefused { .. }) => Ok(false),
            Err(e) => Err(session_error(py, &e)),
        }
    }

    fn close_with(&mut self, py: Python<'_>, error: Option<String>) -> PyResult<()> {
        let Some(mut session) = self.session.take() else { return Ok(()) };
        if let Some(error) = error {
            session.fail(&error);
        }
        session
            .finish()
            .map(drop)
            .map_err(|e| silrig_error(py, Status::ErrSetup, format!("writing the controller report: {e:#}")))
    }
}

#[pymethods]
impl ControllerSession {
    /// Open the run's controller session from the `SILRIG_*` variables, announcing the controller's diagnostics
    /// (1..31 of `[A-Za-z0-9_]` each). Raises `SilrigError` (`ERR_SETUP`, `ERR_NO_RIG`, `ERR_SECOND_CONTROLLER`,
    /// ...) naming what is wrong.
    #[new]
    #[pyo3(signature = (diagnostic_names = Vec::new()))]
    fn py_new(py: Python<'_>, diagnostic_names: Vec<String>) -> PyResult<Self> {
        Self::open(diagnostic_names).map_err(|e| session_error(py, &e))
    }

    /// The controller's step, s.
    #[getter]
    fn dt_s(&mut self, py: Python<'_>) -> PyResult<f64> {
        Ok(self.live(py)?.dt_s())
    }

    /// The scenario's attitude set point at the start, deg: (roll, pitch, yaw).
    #[getter]
    fn setpoint_deg(&mut self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        let sp = &self.live(py)?.scenario().setpoint;
        Ok((sp.phi_deg, sp.theta_deg, sp.psi_deg))
    }

    /// The scenario's set point of output `name` (`[setpoint] alt_ft = 4000.0`) in its unit; `default` when the
    /// scenario gives none. At the start, or with `t_s` (a sample's `t_s`) the value in force then: the last of
    /// `[[setpoint_steps]]` at or before it that changes `name`, else `[setpoint]`'s.
    #[pyo3(signature = (name, default = None, t_s = None))]
    fn setpoint(
        &mut self,
        py: Python<'_>,
        name: &str,
        default: Option<f64>,
        t_s: Option<f64>,
    ) -> PyResult<Option<f64>> {
        if t_s.is_some_and(f64::is_nan) {
            return Err(PyValueError::new_err("t_s is NaN: pass the sample's t_s"));
        }
        Ok(self.live(py)?.scenario().setpoint_at(name, t_s.unwrap_or(0.0)).or(default))
    }

    /// The plant's announcement (a `Plant`), waiting for it if it has not come yet.
    #[getter]
    fn plant(&mut self, py: Python<'_>) -> PyResult<Py<Plant>> {
        self.plant_info(py)
    }

    /// The index of output `name` in a sample's outputs; `SilrigError` (`ERR_PLANT`, naming the plant's outputs)
    /// when the plant has none of that name.
    fn output(&mut self, py: Python<'_>, name: &str) -> PyResult<usize> {
        let plant = self.live(py)?.plant().map_err(|e| session_error(py, &e))?;
        plant.output(name).map_err(|e| silrig_error(py, Status::ErrPlant, e))
    }

    /// The index of input `name` in a command; `SilrigError` (`ERR_PLANT`) when the plant has none.
    fn input(&mut self, py: Python<'_>, name: &str) -> PyResult<usize> {
        let plant = self.live(py)?.plant().map_err(|e| session_error(py, &e))?;
        plant.input(name).map_err(|e| silrig_error(py, Status::ErrPlant, e))
    }

    /// A command that leaves every input where its actuator is now (one value per plant input).
    fn held_command(&mut self, py: Python<'_>) -> PyResult<Vec<f64>> {
        self.plant_info(py)?;
        Ok(self.live(py)?.held_command())
    }

    /// What a predecessor saved (a restarted controller), or None.
    #[getter]
    fn restored_checkpoint(&mut self, py: Python<'_>) -> PyResult<Option<String>> {
        Ok(self.live(py)?.restored_checkpoint().map(str::to_string))
    }

    /// The next plant sample to answer (a `Sample`), or None when the run ended or a stop was requested (see
    /// `stop_reason`).
    fn next_sample(&mut self, py: Python<'_>) -> PyResult<Option<Sample>> {
        self.next(py)
    }

    /// Answer the sample: one value per plant input, in the plant's order, and one value per diagnostic name.
    /// Returns False when the command was refused (NaN, outside an input's range: the plant holds the last valid
    /// one; the run's events say why); raises `SilrigError` on anything else.
    #[pyo3(signature = (inputs, diagnostics = Vec::new()))]
    fn send(&mut self, py: Python<'_>, inputs: Vec<f64>, diagnostics: Vec<f64>) -> PyResult<bool> {
        self.send_command(py, &inputs, &diagnostics)
    }

    /// Say whether you resumed from `restored_checkpoint` (False: with the reason it did not fit).
    #[pyo3(signature = (used, reason = None))]
    fn checkpoint_used(&mut self, py: Python<'_>, used: bool, reason: Option<String>) -> PyResult<()> {
        let outcome =
            if used { Ok(()) } else { Err(reason.unwrap_or_else(|| "the controller did not say why".into())) };
        self.live(py)?.checkpoint_used(outcome);
        Ok(())
    }

    /// Whether the session wants a checkpoint now.
    fn checkpoint_due(&mut self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.live(py)?.checkpoint_due())
    }

    /// Save the state a restarted controller resumes from.
    fn save_checkpoint(&mut self, py: Python<'_>, text: &str) -> PyResult<()> {
        self.live(py)?.save_checkpoint(text);
        Ok(())
    }

    /// Write the controller's report and end the session (`error`: why your controller gave up, if it did). A
    /// second call does nothing.
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

/// `"KindName: value"` of an exception leaving a `with` block, as the ctypes module says it.
pub(crate) fn failure(kind: Option<&Bound<'_, PyAny>>, value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(value) = value.filter(|v| !v.is_none()) else { return Ok(None) };
    let name = match kind.filter(|k| !k.is_none()) {
        Some(kind) => kind.getattr(intern!(kind.py(), "__name__"))?.str()?.to_string(),
        None => value.get_type().name()?.to_string(),
    };
    Ok(Some(format!("{name}: {}", value.str()?)))
}

/// Fly `controller` (a `Controller`: `step(sample, dt_s)`, and `diagnostic_names`, `start`, `checkpoint`, `restore`)
/// until the run ends or SIGTERM. Returns the process's exit status: 0 when the run ended or a stop was requested,
/// 2 when the session could not open (the reason on stderr). An exception from the controller closes the session
/// with it as the reason (the report says so) and propagates.
#[pyfunction]
pub fn serve(py: Python<'_>, controller: &Bound<'_, PyAny>) -> PyResult<i32> {
    let names: Vec<String> = match controller.getattr(intern!(py, "diagnostic_names")) {
        Ok(names) => names.extract()?,
        Err(_) => Vec::new(),
    };
    let session = match ControllerSession::open(names) {
        Ok(session) => Bound::new(py, session)?,
        Err(e) => {
            eprintln!("silrig: {e}");
            return Ok(2);
        }
    };
    let flown = fly(py, controller, &session);
    end_served(py, flown, |why| session.borrow_mut().close_with(py, why))
}

/// The end of `serve` and `serve_plant`: the session closed with no reason after a flight that ended (exit status
/// 0), or with the exception that ended it, which propagates (the caller must see it; a failure to write the report
/// beside it is said on stderr).
pub(crate) fn end_served(
    py: Python<'_>,
    flown: PyResult<()>,
    close: impl FnOnce(Option<String>) -> PyResult<()>,
) -> PyResult<i32> {
    match flown {
        Ok(()) => {
            close(None)?;
            Ok(0)
        }
        Err(e) => {
            let why = failure(Some(e.get_type(py).as_any()), Some(e.value(py).as_any()))?;
            if let Err(closing) = close(why) {
                eprintln!("silrig: {closing}");
            }
            Err(e)
        }
    }
}

fn fly(py: Python<'_>, controller: &Bound<'_, PyAny>, session: &Bound<'_, ControllerSession>) -> PyResult<()> {
    let saved = session.borrow_mut().live(py)?.restored_checkpoint().map(str::to_string);
    if let Some(saved) = saved {
        // The session says in the run's events whether the controller resumed or started fresh.
        let used = call_optional(controller, intern!(py, "restore"), (saved,))?
            .is_some_and(|r| r.is_truthy().unwrap_or(false));
        let outcome = if used { Ok(()) } else { Err("the controller's restore() returned False".to_string()) };
        session.borrow_mut().live(py)?.checkpoint_used(outcome);
    }
    call_optional(controller, intern!(py, "start"), (session.clone(),))?;
    let dt_s = session.borrow_mut().live(py)?.dt_s();
    let plant = session.borrow_mut().plant_info(py)?;
    let input_index = plant.get().input_index.bind(py);
    let step = controller.getattr(intern!(py, "step"))?;
    let checkpoint = intern!(py, "checkpoint");
    loop {
        let Some(sample) = session.borrow_mut().next(py)? else { return Ok(()) };
        let out = step.call1((sample, dt_s))?;
        let mut s = session.borrow_mut();
        let mut inputs = s.live(py)?.held_command();
        let signals = s.live(py)?.plant().map_err(|e| session_error(py, &e))?;
        let diagnostics = read_answer(py, out, input_index, signals, &mut inputs)?;
        // False when refused: the run's events say why and the plant holds; the next sample may do better.
        s.send_command(py, &inputs, &diagnostics)?;
        let due = s.live(py)?.checkpoint_due();
        drop(s);
        if due {
            let text = controller.call_method0(checkpoint)?;
            if !text.is_none() {
                let text: String = text.extract()?;
                session.borrow_mut().live(py)?.save_checkpoint(&text);
            }
        }
    }
}

/// What a controller's `step` returned (`commands`, or `(commands, diagnostics)`; commands a dict, or anything with
/// `items()`, of input names and values) written into `inputs` (each input left out keeps its value there), with
/// `input_index` the plant's `{input: index}`; returns the diagnostics (none when not given). An unknown input name
/// raises `SilrigError` (`ERR_PLANT`) naming the plant's inputs. `serve()` and the in-process flight read it alike.
pub(crate) fn read_answer(
    py: Python<'_>,
    out: Bound<'_, PyAny>,
    input_index: &Bound<'_, PyDict>,
    plant: &silrig_flight::signals::PlantSignals,
    inputs: &mut [f64],
) -> PyResult<Vec<f64>> {
    let (commands, diagnostics) = match out.cast::<PyTuple>() {
        Ok(pair) if pair.len() == 2 => (pair.get_item(0)?, Some(pair.get_item(1)?)),
        _ => (out, None),
    };
    let mut set = |name: &Bound<'_, PyAny>, value: &Bound<'_, PyAny>| -> PyResult<()> {
        let k = match input_index.get_item(name)? {
            Some(k) => k.extract::<usize>()?,
            None => {
                let name: String = name.extract()?;
                return Err(silrig_error(py, Status::ErrPlant, plant.input(&name).err().unwrap_or_default()));
            }
        };
        inputs[k] = value.extract()?;
        Ok(())
    };
    match commands.cast::<PyDict>() {
        Ok(dict) => {
            for (name, value) in dict.iter() {
                set(&name, &value)?;
            }
        }
        Err(_) => {
            for item in commands.call_method0(intern!(py, "items"))?.try_iter()? {
                let (name, value): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item?.extract()?;
                set(&name, &value)?;
            }
        }
    }
    match diagnostics {
        Some(d) => d.extract(),
        None => Ok(Vec::new()),
    }
}

/// Call `controller.name(*args)` if it has such a method (duck-typed controllers may leave `start` or `restore`
/// out); None when it has not.
fn call_optional<'py>(
    controller: &Bound<'py, PyAny>,
    name: &Bound<'py, pyo3::types::PyString>,
    args: impl pyo3::call::PyCallArgs<'py>,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    if !controller.hasattr(name)? {
        return Ok(None);
    }
    controller.call_method1(name, args).map(Some)
}
