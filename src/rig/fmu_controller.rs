//! A co-simulation FMU as the run's controller (`silrig run --controller-fmu`, a scenario's `[controller] fmu`):
//! [`FmuController`] is one more [`Controller`], served by [`super::controller::serve`] in `silrig-controller`, so
//! it gets the session, supervision, the in-loop and process faults, the bumpless blend after a restart, checkpoints
//! and the report as any controller does. What it owns is the mapping between the FMU's variables and the plant's
//! signals, by name:
//!
//! - each Real input of the FMU takes, every tick, the plant output of its name; an input named `<output>_sp`
//!   takes instead the scenario's set point of that output (`[setpoint]`, in the output's unit);
//! - each Real output of the FMU named like a plant input is that input's command; inputs no output names stay where
//!   their actuators are (the throttle under an attitude controller);
//! - every Real output is also one of the controller's diagnostics, under the variable's signal name (so the trace
//!   shows what the FMU itself asked for, before the rig's blend and checks): diagnostics are announced before the
//!   plant is known, when which outputs are commands is not;
//! - `[controller.map]` renames (`FMU variable = "plant signal"`) where the names differ;
//! - `[controller.parameters]` sets the FMU's parameters by variable name before its initialization.
//!
//! What can be judged from the file alone ([`ControllerMap::describe`]: the map's variables exist and are inputs or
//! outputs, the parameters, the diagnostics' names) the launcher checks before starting anything; what needs the
//! plant ([`ControllerMap::bind`]) is checked there too when the launcher knows the plant (the F-16, an FMU plant),
//! else when the plant announces itself. Every error names the FMU file, the variable, and what the FMU or the plant
//! has. Each step sets the inputs, calls `doStep(t, dt)` with t the sample's tick times dt, and reads the outputs; a
//! failed FMI call ends the controller with the FMU's own message. Checkpoints are the FMU's serialized state where
//! its description offers it; where it does not, the `controller-fmu` event says so and a restart starts it fresh.

use super::ProcessArgs;
use super::controller::{Controller, serve};
use super::events::EventLog;
use super::fmu_variables::{can_checkpoint, from_hex, parameters, signal_name, to_hex};
use super::report::ProcessReport;
use silrig_flight::scenario::{ControllerOptions, Scenario, Setpoint};
use silrig_flight::signals::{PlantSignals, valid_name};
use silrig_fmi::description::{Causality, ModelDescription, ValueKind, Variable};
use silrig_fmi::{Fmu, Instance};
use silrig_wire::wire::{ControllerInfo, MAX_DIAGNOSTICS, PlantSample};
use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;

/// The suffix of an FMU input that takes a set point: `theta_deg_sp` takes `[setpoint] theta_deg`.
pub const SETPOINT_SUFFIX: &str = "_sp";

/// One Real input or output of the controller FMU.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedVariable {
    /// The variable's name in the FMU.
    pub variable: String,
    /// The plant signal it is matched with: `[controller.map]`'s, or the variable's signal name.
    pub signal: String,
    /// Whether `[controller.map]` named it (its errors then say so).
    pub mapped: bool,
    /// Its value reference.
    pub value_reference: u32,
}

/// What the FMU file and `[controller]` say, before the plant is known.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerMap {
    /// The FMU as given, for messages.
    pub file: String,
    /// Its Real inputs, in the description's order.
    pub inputs: Vec<MappedVariable>,
    /// Its Real outputs, in the description's order.
    pub outputs: Vec<MappedVariable>,
    /// The diagnostics' names: the signal names of the first [`MAX_DIAGNOSTICS`] outputs.
    pub diagnostics: Vec<String>,
    /// `[controller.parameters]`: value references and the values set before initialization.
    pub parameters: Vec<(u32, f64)>,
}

/// Where an FMU input's value comes from each tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// The plant output at this index of the sample.
    Output(usize),
    /// A set point (constant over the run).
    Setpoint(f64),
}

/// The FMU bound to the plant: where each input comes from and which outputs command which inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct Binding {
    /// One per FMU input, in [`ControllerMap::inputs`]' order.
    pub sources: Vec<Source>,
    /// (index into [`ControllerMap::outputs`], index of the plant input it commands).
    pub commands: Vec<(usize, usize)>,
}

fn list(names: impl IntoIterator<Item = impl AsRef<str>>) -> String {
    let names: Vec<String> = names.into_iter().map(|n| n.as_ref().to_string()).collect();
    if names.is_empty() { "none".into() } else { names.join(", ") }
}

impl ControllerMap {
    /// Check the FMU's variables against `[controller]` (its map and parameters) and name its diagnostics. Errors
    /// name the file, the key and what the FMU has.
    pub fn describe(file: &str, d: &ModelDescription, options: &ControllerOptions) -> Result<Self, String> {
        let bad = |problem: String| format!("FMU {file}: {problem}");
        let real = |c: Causality| -> Vec<&Variable> {
            d.variables.iter().filter(|v| v.kind == ValueKind::Real && v.causality == c).collect()
        };
        let (inputs, outputs) = (real(Causality::Input), real(Causality::Output));
        let names = |vs: &[&Variable]| list(vs.iter().map(|v| v.name.as_str()));
        for (key, signal) in &options.map {
            let found = d.variable(key).or_else(|| d.variables.iter().find(|v| signal_name(&v.name) == *key));
            let Some(v) = found else {
                return Err(bad(format!(
                    "`controller.map.{key}` = {signal:?}: the FMU has no variable {key:?}; its Real inputs: {}; its \
                     Real outputs: {}",
                    names(&inputs),
                    names(&outputs)
                )));
            };
            if v.kind != ValueKind::Real {
                return Err(bad(format!("`controller.map.{key}`: variable {:?} is not a Real (Float64)", v.name)));
            }
            if !matches!(v.causality, Causality::Input | Causality::Output) {
                return Err(bad(format!(
                    "`controller.map.{key}`: variable {:?} has causality {}: only an input (fed from a plant output \
                     or a set point) or an output (a plant input's command) can be mapped; its Real inputs: {}; its \
                     Real outputs: {}",
                    v.name,
                    v.causality.label(),
                    names(&inputs),
                    names(&outputs)
                )));
            }
        }
        let mapped = |v: &Variable| -> Result<MappedVariable, String> {
            let given = options.map.get(&v.name).or_else(|| options.map.get(&signal_name(&v.name)));
            let signal = given.cloned().unwrap_or_else(|| signal_name(&v.name));
            if !valid_name(&signal) {
                return Err(bad(format!(
                    "variable {:?} makes the signal name {signal:?}, longer than 31 characters: map it to the plant's \
                     signal in `[controller.map]`",
                    v.name
                )));
            }
            Ok(MappedVariable {
                variable: v.name.clone(),
                signal,
                mapped: given.is_some(),
                value_reference: v.value_reference,
            })
        };
        let inputs = inputs.into_iter().map(mapped).collect::<Result<Vec<_>, _>>()?;
        let outputs = outputs.into_iter().map(mapped).collect::<Result<Vec<_>, _>>()?;
        if outputs.is_empty() {
            return Err(bad("it has no Real outputs, so nothing to command the plant with".into()));
        }
        for (i, o) in outputs.iter().enumerate() {
            if let Some(other) = outputs[..i].iter().find(|p| p.signal == o.signal) {
                return Err(bad(format!(
                    "outputs {:?} and {:?} both become `{}`: one plant signal, one output",
                    other.variable, o.variable, o.signal
                )));
            }
        }
        // The diagnostics are the outputs' own names, not the mapped ones: the plant's signals are columns already.
        let mut diagnostics: Vec<String> = outputs.iter().map(|o| signal_name(&o.variable)).collect();
        diagnostics.truncate(MAX_DIAGNOSTICS);
        if let Err(e) = ControllerInfo::new(&diagnostics) {
            return Err(bad(format!("its outputs as the controller's diagnostics: {e}")));
        }
        let parameters = parameters(file, d, "controller.parameters", &options.parameters)?;
        Ok(Self { file: file.to_string(), inputs, outputs, diagnostics, parameters })
    }

    /// Bind the FMU to the plant's signals: each input to a plant output or a set point, the outputs named like the
    /// plant's inputs to their commands. Errors name the file, the variable and the plant's signals.
    pub fn bind(&self, plant: &PlantSignals, setpoint: &Setpoint) -> Result<Binding, String> {
        let bad = |problem: String| format!("FMU {}: {problem}", self.file);
        let outputs = || list(plant.outputs.iter().map(|o| o.name.as_str()));
        let inputs = || list(plant.inputs.iter().map(|i| i.name.as_str()));
        let as_given = |v: &MappedVariable| match v.mapped {
            true => format!("{:?} (mapped to `{}` by `controller.map`)", v.variable, v.signal),
            false => format!("{:?}", v.variable),
        };
        let output_index = |name: &str| plant.outputs.iter().position(|o| o.name == name);
        let input_index = |name: &str| plant.inputs.iter().position(|i| i.name == name);
        let mut sources = Vec::new();
        for v in &self.inputs {
            if let Some(k) = output_index(&v.signal) {
                sources.push(Source::Output(k));
                continue;
            }
            if let Some(of) = v.signal.strip_suffix(SETPOINT_SUFFIX).filter(|of| output_index(of).is_some()) {
                let Some(value) = setpoint.get(of) else {
                    return Err(bad(format!(
                        "input {} takes the set point of `{of}`, and the scenario gives none: add `{of} = ...` to its \
                         [setpoint]",
                        as_given(v)
                    )));
                };
                sources.push(Source::Setpoint(value));
                continue;
            }
            let problem = match input_index(&v.signal) {
                Some(_) => format!(
                    "input {} is `{}`, an input of plant {}: an FMU input reads a plant output (or the set point \
                     `<output>{SETPOINT_SUFFIX}`)",
                    as_given(v),
                    v.signal,
                    plant.plant
                ),
                None => format!(
                    "input {} is neither an output of plant {} nor the set point `<output>{SETPOINT_SUFFIX}` of one \
                     (map it in `[controller.map]`)",
                    as_given(v),
                    plant.plant
                ),
            };
            return Err(bad(format!("{problem}; its outputs: {}", outputs())));
        }
        let mut commands = Vec::new();
        for (j, v) in self.outputs.iter().enumerate() {
            if let Some(k) = input_index(&v.signal) {
                commands.push((j, k));
            } else if v.mapped {
                // Mapped, so meant as a command: a plant output or a name the plant lacks is a mistake.
                let what = match output_index(&v.signal) {
                    Some(_) => format!("an output of plant {}: an FMU output commands a plant input", plant.plant),
                    None => format!("which plant {} does not have", plant.plant),
                };
                return Err(bad(format!("output {} is `{}`, {what}; its inputs: {}", as_given(v), v.signal, inputs())));
            }
        }
        if commands.is_empty() {
            return Err(bad(format!(
                "none of its Real outputs ({}) is named like an input of plant {} ({}): map them in \
                 `[controller.map]`",
                list(self.outputs.iter().map(|o| o.variable.as_str())),
                plant.plant,
                inputs()
            )));
        }
        Ok(Binding { sources, commands })
    }
}

/// A checkpoint of a controller FMU: the tick of the sample it last answered and the FMU's serialized state.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
struct SavedFmu {
    tick: u64,
    state_hex: String,
}

/// A controller FMU, unpacked, instantiated and initialized at t = 0, flown as a [`Controller`].
pub struct FmuController {
    // Dropped before `fmu`: the instance is freed before its folder is removed. In a cell because
    // `Controller::checkpoint` takes `&self` and getting an FMU's state is a call that may change it.
    instance: RefCell<Instance>,
    fmu: Arc<Fmu>,
    /// Its variables and how they meet `[controller]`.
    pub map: ControllerMap,
    setpoint: Setpoint,
    binding: Option<Binding>,
    input_refs: Vec<u32>,
    output_refs: Vec<u32>,
    input_values: Vec<f64>,
    output_values: Vec<f64>,
    last_tick: u64,
    /// The FMU's time after its last step, s (None before the first, and after a restore: the next sample's tick
    /// says).
    fmu_time_s: Option<f64>,
    failure: Option<String>,
}

impl FmuController {
    /// Open the FMU at `path`, check it against the scenario's `[controller]`, set its parameters and initialize it.
    pub fn open(path: &Path, scenario: &Scenario) -> anyhow::Result<Self> {
        Self::new(Arc::new(Fmu::open(path)?), scenario)
    }

    /// [`Self::open`] for an FMU already unpacked: one instance of it, checked, with its parameters set and
    /// initialized (what each case of an in-process sweep flies).
    pub fn new(fmu: Arc<Fmu>, scenario: &Scenario) -> anyhow::Result<Self> {
        let map =
            ControllerMap::describe(fmu.file(), &fmu.description, &scenario.controller).map_err(anyhow::Error::msg)?;
        let mut instance = fmu.instantiate("controller")?;
        if !map.parameters.is_empty() {
            let (refs, values): (Vec<u32>, Vec<f64>) = map.parameters.iter().copied().unzip();
            instance.set_reals(&refs, &values)?;
        }
        instance.enter_initialization(0.0)?;
        instance.exit_initialization()?;
        Ok(Self {
            input_refs: map.inputs.iter().map(|v| v.value_reference).collect(),
            output_refs: map.outputs.iter().map(|v| v.value_reference).collect(),
            input_values: vec![0.0; map.inputs.len()],
            output_values: vec![0.0; map.outputs.len()],
            instance: RefCell::new(instance),
            fmu,
            map,
            setpoint: scenario.setpoint.clone(),
            binding: None,
            last_tick: 0,
            fmu_time_s: None,
            failure: None,
        })
    }

    /// What the launcher checks before starting a run: the FMU at `path` against `[controller]`, and against the
    /// plant's signals when they are known; without instantiating it.
    pub fn check(path: &Path, scenario: &Scenario, plant: Option<&PlantSignals>) -> anyhow::Result<ControllerMap> {
        let fmu = Fmu::open(path)?;
        let map =
            ControllerMap::describe(fmu.file(), &fmu.description, &scenario.controller).map_err(anyhow::Error::msg)?;
        if let Some(plant) = plant {
            map.bind(plant, &scenario.setpoint).map_err(anyhow::Error::msg)?;
        }
        Ok(map)
    }

    /// The FMU as given, and what it is, with what a restart resumes from: the `controller-fmu` event.
    pub fn describe_fmu(&self) -> String {
        let d = &self.fmu.description;
        let resumes = match can_checkpoint(d) {
            Ok(()) => "checkpoints through its own state".to_string(),
            Err(why) => format!("{why}, so a restarted controller starts it fresh"),
        };
        let mut text = format!("flying {}: {resumes}", self.fmu.label());
        if self.map.outputs.len() > self.map.diagnostics.len() {
            let left: Vec<&str> =
                self.map.outputs[self.map.diagnostics.len()..].iter().map(|o| o.variable.as_str()).collect();
            text += &format!("; outputs beyond the {MAX_DIAGNOSTICS} diagnostics not logged: {}", left.join(", "));
        }
        text
    }

    fn try_step(&mut self, sample: &PlantSample, dt_s: f64, command: &mut [f64]) -> Result<(), String> {
        let binding = self.binding.as_ref().expect("connect comes before the first step");
        let outputs = sample.outputs();
        for (value, source) in self.input_values.iter_mut().zip(&binding.sources) {
            *value = match *source {
                Source::Output(k) => outputs[k],
                Source::Setpoint(v) => v,
            };
        }
        let instance = self.instance.get_mut();
        if !self.input_refs.is_empty() {
            instance.set_reals(&self.input_refs, &self.input_values).map_err(|e| e.to_string())?;
        }
        // A plant resumed from its checkpoint sends ticks the controller has flown already; an FMU refuses a
        // communication point before its own time, so the controller's time goes on, as a controller's clock on a
        // bench does (in lockstep, and in a run without a plant restart, it is the sample's tick).
        let t_s = (sample.header.tick as f64 * dt_s).max(self.fmu_time_s.unwrap_or(f64::NEG_INFINITY));
        instance.do_step(t_s, dt_s).map_err(|e| e.to_string())?;
        self.fmu_time_s = Some(t_s + dt_s);
        instance.get_reals(&self.output_refs, &mut self.output_values).map_err(|e| e.to_string())?;
        for &(j, k) in &binding.commands {
            command[k] = self.output_values[j];
        }
        self.last_tick = sample.header.tick;
        Ok(())
    }
}

impl Controller for FmuController {
    fn diagnostic_names(&self) -> Vec<String> {
        self.map.diagnostics.clone()
    }

    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String> {
        self.binding = Some(self.map.bind(plant, &self.setpoint)?);
        Ok(())
    }

    fn step(&mut self, sample: &PlantSample, dt_s: f64, command: &mut [f64], diagnostics: &mut [f64]) {
        if let Err(e) = self.try_step(sample, dt_s, command) {
            self.failure = Some(e);
            return;
        }
        let n = diagnostics.len();
        diagnostics.copy_from_slice(&self.output_values[..n]);
    }

    fn failure(&mut self) -> Option<String> {
        self.failure.take()
    }

    fn checkpoint(&self) -> Option<String> {
        can_checkpoint(&self.fmu.description).ok()?;
        // A state that cannot be taken now is no reason to stop flying: the previous checkpoint stays.
        let bytes = self.instance.borrow_mut().save_state().ok()?;
        serde_json::to_string(&SavedFmu { tick: self.last_tick, state_hex: to_hex(&bytes) }).ok()
    }

    fn restore(&mut self, saved: &str) -> Result<(), String> {
        can_checkpoint(&self.fmu.description)?;
        let saved: SavedFmu =
            serde_json::from_str(saved).map_err(|e| format!("not a controller FMU's checkpoint: {e}"))?;
        let bytes = from_hex(&saved.state_hex)?;
        self.instance.get_mut().restore_state(&bytes).map_err(|e| e.to_string())?;
        self.last_tick = saved.tick;
        self.fmu_time_s = None;
        Ok(())
    }
}

/// Fly the scenario's controller FMU at `path` as the run's controller, to the end of the run (or SIGTERM), and
/// write the report.
pub fn run_fmu_controller(args: &ProcessArgs, scenario: Scenario, path: &Path) -> anyhow::Result<ProcessReport> {
    let controller = FmuController::open(path, &scenario)?;
    EventLog::new(&args.out, silrig_flight::role::Role::Controller.label()).emit(
        None,
        "controller-fmu",
        controller.describe_fmu(),
    );
    serve(args, scenario, Box::new(controller))
}
