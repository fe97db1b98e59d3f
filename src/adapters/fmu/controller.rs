//! A co-simulation FMU as the run's controller (`silrig run --controller-fmu`, a scenario's `[controller] fmu`):
//! [`FmuController`] is one more [`Controller`], served by [`silrig_rig::controller::serve`] in `silrig-controller`, so
//! it gets the session, supervision, the in-loop and process faults, the bumpless blend after a restart, checkpoints
//! and the report as any controller does. What it owns is the mapping between the FMU's variables and the plant's
//! signals, by name:
//!
//! - its inputs and outputs are its numeric variables (Real/Float64, Integer/Int32, Boolean, as doubles); the others
//!   are left out, and refused by name when `[controller.map]` names one;
//! - each input of the FMU takes, every tick, the plant output of its name; an input named `<output>_sp` takes
//!   instead the scenario's set point of that output in force at the sample's time (`[setpoint]`, then any step of
//!   `[[setpoint_steps]]`, in the output's unit); an input that is neither stays unconnected at its start value;
//! - each output of the FMU named like a plant input is that input's command; inputs no output names stay where
//!   their actuators are (the throttle under an attitude controller);
//! - every output is also one of the controller's diagnostics, under the variable's signal name (so the trace
//!   shows what the FMU itself asked for, before the rig's blend and checks): diagnostics are announced before the
//!   plant is known, when which outputs are commands is not;
//! - `[controller.map]` renames (`FMU variable = "plant signal"`) where the names differ, and holds an input at a
//!   constant (`FMU input = 0.0`);
//! - `[controller.parameters]` sets the FMU's parameters by variable name before its initialization.
//!
//! What can be judged from the file alone ([`ControllerMap::describe`]: the map's variables exist and are inputs or
//! outputs, the parameters, the diagnostics' names) the launcher checks before starting anything; what needs the
//! plant ([`ControllerMap::bind`]) is checked there too when the launcher knows the plant (the F-16, an FMU plant),
//! else when the plant announces itself. Every error names the FMU file, the variable, and what the FMU or the plant
//! has. Each step sets the inputs, calls `doStep(t, dt)` with t the sample's tick times dt, and reads the outputs; a
//! failed FMI call ends the controller with the FMU's own message. Checkpoints are the FMU's serialized state where
//! its description offers it; where it does not, the `controller-fmu` event says so and a restart starts it fresh.

use super::variables::{can_checkpoint, from_hex, parameters, set_parameters, signal_name, signal_variables, to_hex};
use silrig_flight::controller_map::MapTarget;
use silrig_flight::scenario::{ControllerOptions, Scenario, Setpoint, SetpointStep};
use silrig_flight::setpoints::SetpointTrack;
use silrig_flight::signals::{PlantSignals, valid_name};
use silrig_fmi::description::{Causality, ModelDescription, ValueKind, Variable};
use silrig_fmi::numbers::Numbers;
use silrig_fmi::{Fmu, Instance};
use silrig_rig::ProcessArgs;
use silrig_rig::controller::{Controller, serve};
use silrig_rig::events::EventLog;
use silrig_rig::report::ProcessReport;
use silrig_wire::wire::{ControllerInfo, MAX_DIAGNOSTICS, PlantSample};
use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;

/// The suffix of an FMU input that takes a set point: `theta_deg_sp` takes `[setpoint] theta_deg`.
pub const SETPOINT_SUFFIX: &str = "_sp";

/// One input or output of the controller FMU.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedVariable {
    /// The variable's name in the FMU.
    pub variable: String,
    /// The plant signal it is matched with: `[controller.map]`'s, or the variable's signal name.
    pub signal: String,
    /// The constant `[controller.map]` holds an input at, if it does.
    pub constant: Option<f64>,
    /// Whether `[controller.map]` named it (its errors then say so).
    pub mapped: bool,
    /// Its kind (Real, Integer, Boolean) and value reference.
    pub value_reference: (ValueKind, u32),
    /// Its start value, if it declares one (what an unconnected input stays at).
    pub start: Option<f64>,
}

/// What the FMU file and `[controller]` say, before the plant is known.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerMap {
    /// The FMU as given, for messages.
    pub file: String,
    /// Its inputs, in the description's order.
    pub inputs: Vec<MappedVariable>,
    /// Its outputs, in the description's order.
    pub outputs: Vec<MappedVariable>,
    /// Its inputs and outputs that are not numbers, each `"name" (why)`.
    pub left_out: Vec<String>,
    /// The diagnostics' names: the signal names of the first [`MAX_DIAGNOSTICS`] outputs.
    pub diagnostics: Vec<String>,
    /// `[controller.parameters]`: kinds, value references and the values set before initialization.
    pub parameters: Vec<super::variables::Parameter>,
}

/// A set point's history by its name, `None` when the scenario gives none.
pub type SetpointOf<'a> = dyn Fn(&str) -> Option<SetpointTrack> + 'a;

/// Where an FMU input's value comes from each tick.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// The plant output at this index of the sample.
    Output(usize),
    /// A set point, its value in force at the sample's time (`[[setpoint_steps]]` change it).
    Setpoint(SetpointTrack),
    /// The constant `[controller.map]` gives.
    Constant(f64),
    /// Unconnected: the input's start value.
    Start(f64),
}

impl Source {
    /// The input's value for a sample of `outputs` at `t_s`.
    pub fn value(&self, outputs: &[f64], t_s: f64) -> f64 {
        match self {
            Source::Output(k) => outputs[*k],
            Source::Setpoint(track) => track.at(t_s),
            Source::Constant(v) | Source::Start(v) => *v,
        }
    }
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

/// Each key of `[controller.map]` names an input or output of the FMU that is a number; a constant is given to an
/// input only. Errors name the key and what the FMU has.
fn check_map_keys(
    d: &ModelDescription,
    options: &ControllerOptions,
    inputs: &[&Variable],
    outputs: &[&Variable],
) -> Result<(), String> {
    let names = |vs: &[&Variable]| list(vs.iter().map(|v| v.name.as_str()));
    let has = || format!("its inputs: {}; its outputs: {}", names(inputs), names(outputs));
    for (key, target) in &options.map {
        let found = d.variable(key).or_else(|| d.variables.iter().find(|v| signal_name(&v.name) == *key));
        let Some(v) = found else {
            return Err(format!("`controller.map.{key}` = {target}: the FMU has no variable {key:?}; {}", has()));
        };
        if let Some(why) = v.kind.refusal() {
            return Err(format!("`controller.map.{key}`: variable {:?} cannot be mapped: {why}", v.name));
        }
        if !matches!(v.causality, Causality::Input | Causality::Output) {
            return Err(format!(
                "`controller.map.{key}`: variable {:?} has causality {}: only an input (fed from a plant output, a \
                 set point or a constant) or an output (a plant input's command) can be mapped; {}",
                v.name,
                v.causality.label(),
                has()
            ));
        }
        if let (Causality::Output, MapTarget::Constant(value)) = (v.causality, target) {
            return Err(format!(
                "`controller.map.{key}` = {value}: variable {:?} is an output, which the FMU computes: only an input \
                 can be held at a constant (map an output to the plant input it commands)",
                v.name
            ));
        }
    }
    Ok(())
}

impl ControllerMap {
    /// Check the FMU's variables against `[controller]` (its map and parameters) and name its diagnostics. Errors
    /// name the file, the key and what the FMU has.
    pub fn describe(file: &str, d: &ModelDescription, options: &ControllerOptions) -> Result<Self, String> {
        let bad = |problem: String| format!("FMU {file}: {problem}");
        let (inputs, mut left_out) = signal_variables(d, Causality::Input);
        let (outputs, outputs_left_out) = signal_variables(d, Causality::Output);
        left_out.extend(outputs_left_out);
        check_map_keys(d, options, &inputs, &outputs).map_err(&bad)?;
        let mapped = |v: &Variable| -> Result<MappedVariable, String> {
            let given = options.map.get(&v.name).or_else(|| options.map.get(&signal_name(&v.name)));
            let (signal, constant) = match given {
                Some(MapTarget::Signal(name)) => (name.clone(), None),
                Some(MapTarget::Constant(value)) => (signal_name(&v.name), Some(*value)),
                None => (signal_name(&v.name), None),
            };
            if constant.is_none() && !valid_name(&signal) {
                return Err(bad(format!(
                    "variable {:?} makes the signal name {signal:?}, longer than 31 characters: map it to the plant's \
                     signal in `[controller.map]`",
                    v.name
                )));
            }
            Ok(MappedVariable {
                variable: v.name.clone(),
                signal,
                constant,
                mapped: given.is_some(),
                value_reference: (v.kind, v.value_reference),
                start: v.start,
            })
        };
        let inputs = inputs.into_iter().map(mapped).collect::<Result<Vec<_>, _>>()?;
        let outputs = outputs.into_iter().map(mapped).collect::<Result<Vec<_>, _>>()?;
        if outputs.is_empty() {
            let why = match left_out.is_empty() {
                true => String::new(),
                false => format!(" (left out, not being numbers: {})", left_out.join(", ")),
            };
            return Err(bad(format!("it has no outputs, so nothing to command the plant with{why}")));
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
        Ok(Self { file: file.to_string(), inputs, outputs, left_out, diagnostics, parameters })
    }

    /// Bind the FMU to the plant's signals: each input to a plant output, a set point, a constant or its start
    /// value, the outputs named like the plant's inputs to their commands; `setpoint` gives a set point's history by
    /// name ([`Scenario::setpoint_track`]). Errors name the file, the variable and the plant's signals.
    pub fn bind(&self, plant: &PlantSignals, setpoint: &SetpointOf) -> Result<Binding, String> {
        let bad = |problem: String| format!("FMU {}: {problem}", self.file);
        let inputs = || list(plant.inputs.iter().map(|i| i.name.as_str()));
        let output_index = |name: &str| plant.outputs.iter().position(|o| o.name == name);
        let input_index = |name: &str| plant.inputs.iter().position(|i| i.name == name);
        let sources = self.inputs.iter().map(|v| source(v, plant, setpoint).map_err(&bad)).collect::<Result<_, _>>()?;
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
        // A plant without inputs (a model that only reports, as the Reference FMU `Stair`) is watched, not commanded.
        if commands.is_empty() && !plant.inputs.is_empty() {
            return Err(bad(format!(
                "none of its outputs ({}) is named like an input of plant {} ({}): map them in `[controller.map]`",
                list(self.outputs.iter().map(|o| o.variable.as_str())),
                plant.plant,
                inputs()
            )));
        }
        Ok(Binding { sources, commands })
    }

    /// The inputs that stay unconnected at their start value on `plant` (for the `controller-fmu` event and the
    /// launcher's note).
    pub fn unconnected(&self, binding: &Binding) -> Vec<String> {
        let at_start = binding.sources.iter().zip(&self.inputs).filter(|(s, _)| matches!(s, Source::Start(_)));
        at_start.map(|(_, v)| v.variable.clone()).collect()
    }
}

/// How a variable is named in errors: with its mapping when `[controller.map]` gave one.
fn as_given(v: &MappedVariable) -> String {
    match v.mapped {
        true => format!("{:?} (mapped to `{}` by `controller.map`)", v.variable, v.signal),
        false => format!("{:?}", v.variable),
    }
}

/// Where input `v` takes its value each tick: a constant of the map, the plant output of its name, the set point
/// `<output>_sp`, or, when it names nothing of the plant and the map does not name it, its start value.
fn source(v: &MappedVariable, plant: &PlantSignals, setpoint: &SetpointOf) -> Result<Source, String> {
    let output_index = |name: &str| plant.outputs.iter().position(|o| o.name == name);
    if let Some(value) = v.constant {
        return Ok(Source::Constant(value));
    }
    if let Some(k) = output_index(&v.signal) {
        return Ok(Source::Output(k));
    }
    if let Some(of) = v.signal.strip_suffix(SETPOINT_SUFFIX).filter(|of| output_index(of).is_some()) {
        return match setpoint(of) {
            Some(track) => Ok(Source::Setpoint(track)),
            None => Err(format!(
                "input {} takes the set point of `{of}`, and the scenario gives none: add `{of} = ...` to its \
                 [setpoint]",
                as_given(v)
            )),
        };
    }
    let is_plant_input = plant.inputs.iter().any(|i| i.name == v.signal);
    if let (false, false, Some(start)) = (v.mapped, is_plant_input, v.start) {
        return Ok(Source::Start(start));
    }
    let problem = match (is_plant_input, v.mapped) {
        (true, _) => format!(
            "input {} is `{}`, an input of plant {}: an FMU input reads a plant output (or the set point \
             `<output>{SETPOINT_SUFFIX}`, or a constant)",
            as_given(v),
            v.signal,
            plant.plant
        ),
        (false, true) => format!(
            "input {} is `{}`, neither an output of plant {} nor the set point `<output>{SETPOINT_SUFFIX}` of one",
            as_given(v),
            v.signal,
            plant.plant
        ),
        (false, false) => format!(
            "input {} is neither an output of plant {} nor the set point `<output>{SETPOINT_SUFFIX}` of one, and \
             it declares no start value to stay at: map it in `[controller.map]`, to a signal or a constant",
            as_given(v),
            plant.plant
        ),
    };
    let outputs = list(plant.outputs.iter().map(|o| o.name.as_str()));
    Err(format!("{problem}; its outputs: {outputs}"))
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
    /// The scenario's set points and their steps, which the `_sp` inputs are bound to.
    setpoint: Setpoint,
    setpoint_steps: Vec<SetpointStep>,
    /// The plant's period, s: a sample's tick at this period is its time (the controller's own step may be longer,
    /// `timing.controller_every_ticks`).
    plant_dt_s: f64,
    binding: Option<Binding>,
    inputs: Numbers,
    outputs: Numbers,
    input_values: Vec<f64>,
    output_values: Vec<f64>,
    last_tick: u64,
    /// The FMU's time after its last step, s (None before the first, and after a restore: the next sample's tick
    /// says).
    fmu_time_s: Option<f64>,
    failure: Option<String>,
    /// Where connecting says which inputs stay unconnected (the run's events; none in one process).
    events: Option<EventLog>,
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
        set_parameters(&mut instance, &map.parameters)?;
        instance.enter_initialization(0.0)?;
        instance.exit_initialization()?;
        Ok(Self {
            inputs: Numbers::new(map.inputs.iter().map(|v| v.value_reference)),
            outputs: Numbers::new(map.outputs.iter().map(|v| v.value_reference)),
            input_values: vec![0.0; map.inputs.len()],
            output_values: vec![0.0; map.outputs.len()],
            instance: RefCell::new(instance),
            fmu,
            map,
            setpoint: scenario.setpoint.clone(),
            setpoint_steps: scenario.setpoint_steps.clone(),
            plant_dt_s: scenario.timing.dt_s,
            binding: None,
            last_tick: 0,
            fmu_time_s: None,
            failure: None,
            events: None,
        })
    }

    /// What the launcher checks before starting a run: the FMU at `path` against `[controller]`, and against the
    /// plant's signals when they are known; without instantiating it.
    pub fn check(path: &Path, scenario: &Scenario, plant: Option<&PlantSignals>) -> anyhow::Result<ControllerMap> {
        let fmu = Fmu::open(path)?;
        let map =
            ControllerMap::describe(fmu.file(), &fmu.description, &scenario.controller).map_err(anyhow::Error::msg)?;
        if let Some(plant) = plant {
            map.bind(plant, &|name| scenario.setpoint_track(name)).map_err(anyhow::Error::msg)?;
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
        if !self.map.left_out.is_empty() {
            text += &format!("; left out: {}", self.map.left_out.join(", "));
        }
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
            *value = source.value(outputs, sample.t_sim_s);
        }
        let instance = self.instance.get_mut();
        if !self.inputs.is_empty() {
            instance.set_numbers(&mut self.inputs, &self.input_values).map_err(|e| e.to_string())?;
        }
        // A plant resumed from its checkpoint sends ticks the controller has flown already; an FMU refuses a
        // communication point before its own time, so the controller's time goes on, as a controller's clock on a
        // bench does (in lockstep, and in a run without a plant restart, it is the sample's tick).
        let t_s = (sample.header.tick as f64 * self.plant_dt_s).max(self.fmu_time_s.unwrap_or(f64::NEG_INFINITY));
        instance.do_step(t_s, dt_s).map_err(|e| e.to_string())?;
        self.fmu_time_s = Some(t_s + dt_s);
        instance.get_numbers(&mut self.outputs, &mut self.output_values).map_err(|e| e.to_string())?;
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
        let binding = self.map.bind(plant, &|name| SetpointTrack::of(&self.setpoint, &self.setpoint_steps, name))?;
        let unconnected = self.map.unconnected(&binding);
        if let (Some(events), false) = (&self.events, unconnected.is_empty()) {
            let detail = format!(
                "inputs plant {} has no signal for, at their start values: {}",
                plant.plant,
                unconnected.join(", ")
            );
            events.emit(None, "controller-fmu-unconnected", detail);
        }
        self.binding = Some(binding);
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
    let mut controller = FmuController::open(path, &scenario)?;
    let events = EventLog::new(&args.out, silrig_flight::role::Role::Controller.label());
    events.emit(None, "controller-fmu", controller.describe_fmu());
    controller.events = Some(events);
    serve(args, scenario, Box::new(controller))
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::signals::{InputSignal, OutputSignal};

    /// A controller FMU with a Real input `a`, an Integer input `n` (start 4), a Boolean input `b` without start, a
    /// String input `label`, a Real output `u` and a Boolean output `on`.
    const FMU: &str = r#"<fmiModelDescription fmiVersion="2.0" modelName="c" guid="{g}">
  <CoSimulation modelIdentifier="c"/>
  <ModelVariables>
    <ScalarVariable name="a" valueReference="0" causality="input"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="n" valueReference="1" causality="input"><Integer start="4"/></ScalarVariable>
    <ScalarVariable name="b" valueReference="2" causality="input"><Boolean/></ScalarVariable>
    <ScalarVariable name="label" valueReference="3" causality="input"><String start="x"/></ScalarVariable>
    <ScalarVariable name="u" valueReference="4" causality="output"><Real/></ScalarVariable>
    <ScalarVariable name="on" valueReference="5" causality="output"><Boolean/></ScalarVariable>
  </ModelVariables>
</fmiModelDescription>"#;

    fn plant(outputs: &[&str], inputs: &[&str]) -> PlantSignals {
        let output = |n: &&str| OutputSignal { name: n.to_string(), unit: String::new(), in_trace: true };
        let input = |n: &&str| InputSignal {
            name: n.to_string(),
            unit: String::new(),
            min: -1.0,
            max: 1.0,
            hold: 0.0,
            held_output: None,
            command_in_trace: true,
        };
        PlantSignals {
            plant: "p".into(),
            outputs: outputs.iter().map(output).collect(),
            inputs: inputs.iter().map(input).collect(),
        }
    }

    fn map_of(entries: &str) -> Result<ControllerMap, String> {
        let d = ModelDescription::parse(FMU, "c.fmu").unwrap();
        let table: toml::Value = toml::from_str(entries).unwrap();
        let options =
            ControllerOptions { map: silrig_flight::controller_map::from_toml(table).unwrap(), ..Default::default() };
        ControllerMap::describe("c.fmu", &d, &options)
    }

    #[test]
    fn number_variables_are_mapped_and_the_others_left_out_with_the_reason() {
        let map = map_of("").unwrap();
        let kinds: Vec<_> = map.inputs.iter().map(|v| (v.variable.as_str(), v.value_reference.0)).collect();
        assert_eq!(kinds, [("a", ValueKind::Real), ("n", ValueKind::Integer), ("b", ValueKind::Boolean)]);
        assert_eq!(
            map.outputs.iter().map(|v| v.value_reference.0).collect::<Vec<_>>(),
            [ValueKind::Real, ValueKind::Boolean]
        );
        assert_eq!(map.left_out, ["\"label\" (String is not a signal: a String is text, not a number)"]);
        let e = map_of("label = \"x\"").unwrap_err();
        assert!(
            e.contains("`controller.map.label`: variable \"label\" cannot be mapped: String is not a signal"),
            "{e}"
        );
    }

    #[test]
    fn inputs_take_a_constant_or_stay_unconnected_at_their_start_value() {
        let map = map_of("a = 0.25\nb = 1").unwrap();
        let binding = map.bind(&plant(&["y"], &["u"]), &|_| None).unwrap();
        assert_eq!(binding.sources, [Source::Constant(0.25), Source::Start(4.0), Source::Constant(1.0)]);
        assert_eq!(binding.commands, [(0, 0)]);
        assert_eq!(map.unconnected(&binding), ["n"]);
        // Named like a plant output, an input reads it; a Boolean without a start value must be connected.
        let map = map_of("a = 0.25").unwrap();
        let binding = map.bind(&plant(&["b", "n"], &["u"]), &|_| None).unwrap();
        assert_eq!(binding.sources, [Source::Constant(0.25), Source::Output(1), Source::Output(0)]);
        let e = map.bind(&plant(&["y"], &["u"]), &|_| None).unwrap_err();
        assert!(
            e.contains("input \"b\" is neither an output of plant p") && e.contains("declares no start value"),
            "{e}"
        );
    }

    #[test]
    fn a_constant_for_an_output_and_an_input_mapped_to_a_missing_signal_are_refused() {
        let e = map_of("u = 0.0").unwrap_err();
        assert!(e.contains("`controller.map.u` = 0: variable \"u\" is an output"), "{e}");
        let map = map_of("a = \"alpha\"").unwrap();
        let e = map.bind(&plant(&["y", "n", "b"], &["u"]), &|_| None).unwrap_err();
        assert!(e.contains("input \"a\" (mapped to `alpha` by `controller.map`) is `alpha`, neither"), "{e}");
    }

    #[test]
    fn a_plant_without_inputs_is_watched_and_one_with_inputs_must_be_commanded() {
        let map = map_of("").unwrap();
        assert!(map.bind(&plant(&["b"], &[]), &|_| None).unwrap().commands.is_empty());
        let e = map.bind(&plant(&["b"], &["elevator"]), &|_| None).unwrap_err();
        assert!(e.contains("none of its outputs (u, on) is named like an input of plant p (elevator)"), "{e}");
    }

    #[test]
    fn an_input_named_for_a_set_point_takes_the_value_in_force_at_each_sample() {
        let map = map_of("a = \"y_sp\"").unwrap();
        let setpoint = Setpoint { outputs: [("y".to_string(), 1.0)].into(), ..Default::default() };
        let steps = [SetpointStep { at_s: 2.0, values: [("y".to_string(), 3.0)].into() }];
        let binding = map.bind(&plant(&["y", "n", "b"], &["u"]), &|n| SetpointTrack::of(&setpoint, &steps, n)).unwrap();
        let source = &binding.sources[0];
        let values: Vec<f64> = [0.0, 1.99, 2.0, 5.0].map(|t| source.value(&[7.0, 0.0, 0.0], t)).into();
        assert_eq!(values, [1.0, 1.0, 3.0, 3.0]);
        assert_eq!(binding.sources[1].value(&[7.0, 8.0, 9.0], 5.0), 8.0);
        let e = map.bind(&plant(&["y", "n", "b"], &["u"]), &|_| None).unwrap_err();
        assert!(e.contains("takes the set point of `y`, and the scenario gives none"), "{e}");
    }
}
