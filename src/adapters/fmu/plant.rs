//! A co-simulation FMU as the run's plant (`silrig run --plant-fmu`, a scenario's `[plant] fmu`): its numeric
//! variables (Real/Float64, Integer/Int32 and Boolean, as doubles) of causality output and input become the plant's
//! named signals ([`fmu_signals`]; the others are left out, each named with the reason), its
//! parameters and start values come from `[plant.parameters]` by variable name, and [`run_fmu_plant`] flies it
//! through the same [`PlantSession`] as any plant of the user's own, so it gets the rig's clock, actuators, sensor
//! and actuator faults, watchdog and failsafe, logger, recording and timing report. The step time the report gives
//! is the FMU's: setting the inputs, `doStep` and reading the outputs. Checkpoints go through the FMU's own
//! serialized state where its description offers it; where it does not, the run's events say so.
//!
//! How variables become signals: the plant's name is the model's (`modelName`, or a vendor annotation's
//! `<Tool name="silrig"><Plant name=".."/>`); a signal's name is the variable's, with every character other than an ASCII
//! letter, digit or '_' turned into '_' (`body.w[1]` is `body_w_1_`); an input's range is its min and max (the
//! whole finite range of a double where the FMU declares none) and its failsafe holds its start value; the output
//! named `<input>_<unit>` (`aileron_deg` for an input `aileron` in deg) reports that input's actuator. A variable
//! may say otherwise with an annotation `<Tool name="silrig"><Signal name=".." trace="false" position_of=".."/>`
//! (how the exported F-16 keeps the built-in plant's names): `name` renames it, `trace="false"` keeps an output out
//! of `trace.csv` (an input's command out of it), `position_of` names the input whose actuator an output reports.

use super::variables::{can_checkpoint, from_hex, set_parameters, signal_variables, to_hex};
use silrig_flight::scenario::Scenario;
use silrig_flight::signal_chain::SignalChain;
use silrig_flight::signals::{InputSignal, OutputSignal, PlantSignals, valid_name, valid_unit};
use silrig_fmi::description::{Causality, ModelDescription, ValueKind, Variable};
use silrig_fmi::numbers::Numbers;
use silrig_fmi::{Fmu, Instance};
use silrig_rig::ProcessArgs;
use silrig_rig::plant_model::{ActuatorFlags, PlantModel};
use silrig_rig::plant_session::{PlantSession, PlantTick};
use silrig_rig::report::ProcessReport;
use std::path::Path;
use std::sync::Arc;

pub use super::variables::signal_name;

/// The plant's signals of an FMU, and where each lives in it.
#[derive(Debug, Clone, PartialEq)]
pub struct FmuSignals {
    /// What the plant announces.
    pub signals: PlantSignals,
    /// The kind and value reference of each output, in the announced order.
    pub output_refs: Vec<(ValueKind, u32)>,
    /// The kind and value reference of each input, in the announced order.
    pub input_refs: Vec<(ValueKind, u32)>,
    /// `[plant.parameters]`: kinds, value references and the values set before initialization.
    pub parameters: Vec<super::variables::Parameter>,
    /// The inputs and outputs that are not signals, each `"name" (why)`.
    pub left_out: Vec<String>,
}

impl FmuSignals {
    /// What the `plant-fmu` event adds about the variables left out (empty when none is).
    pub fn left_out_note(&self) -> String {
        match self.left_out.is_empty() {
            true => String::new(),
            false => format!("; left out: {}", self.left_out.join(", ")),
        }
    }
}

/// Map an FMU's variables to the plant's signals, and `[plant.parameters]` to its parameters. Errors name the
/// FMU, the variable and the rule.
pub fn fmu_signals(file: &str, d: &ModelDescription, scenario: &Scenario) -> Result<FmuSignals, String> {
    let bad = |problem: String| format!("FMU {file}: {problem}");
    let traced = |v: &Variable| v.silrig.get("trace").is_none_or(|t| t != "false");
    let named = |v: &Variable| -> Result<String, String> {
        let name = v.silrig.get("name").cloned().unwrap_or_else(|| signal_name(&v.name));
        if !valid_name(&name) {
            return Err(bad(format!(
                "variable {:?} makes the signal name {name:?}, longer than 31 characters: give it a shorter one \
                 with a silrig annotation (<Tool name=\"silrig\"><Signal name=\"...\"/>)",
                v.name
            )));
        }
        Ok(name)
    };
    let unit = |v: &Variable| -> Result<String, String> {
        let unit = v.unit.clone().unwrap_or_default();
        match valid_unit(&unit) {
            true => Ok(unit),
            false => Err(bad(format!(
                "variable {:?}: unit {unit:?} is not one a signal can carry (at most 15 printable characters, no \
                 comma or quote)",
                v.name
            ))),
        }
    };
    let (outputs, mut left_out) = signal_variables(d, Causality::Output);
    let (inputs, inputs_left_out) = signal_variables(d, Causality::Input);
    left_out.extend(inputs_left_out);
    let plant = d.silrig_plant_name.clone().unwrap_or_else(|| signal_name(&d.model_name));
    let mut signals = PlantSignals { plant, outputs: Vec::new(), inputs: Vec::new() };
    if !valid_name(&signals.plant) {
        signals.plant = d.co_simulation.model_identifier.clone();
    }
    for v in &outputs {
        let trace = traced(v);
        signals.outputs.push(OutputSignal { name: named(v)?, unit: unit(v)?, in_trace: trace });
    }
    for v in &inputs {
        let (min, max) = (v.min.unwrap_or(f64::MIN), v.max.unwrap_or(f64::MAX));
        let hold = v.start.unwrap_or(0.0).clamp(min, max);
        let name = named(v)?;
        let unit = unit(v)?;
        // The output that reports this input's actuator: named by an annotation, or `<input>_<unit>`.
        let by_annotation =
            outputs.iter().position(|o| o.silrig.get("position_of").is_some_and(|p| *p == v.name || *p == name));
        let by_name = format!("{name}_{}", signal_name(&unit));
        let held_output = by_annotation.or_else(|| signals.outputs.iter().position(|o| o.name == by_name));
        signals.inputs.push(InputSignal { name, unit, min, max, hold, held_output, command_in_trace: traced(v) });
    }
    signals.check(silrig_wire::wire::MAX_OUTPUTS, silrig_wire::wire::MAX_INPUTS).map_err(|e| {
        let why = match left_out.is_empty() {
            true => String::new(),
            false => format!(" (left out, not being signals: {})", left_out.join(", ")),
        };
        bad(format!("its variables as the plant's signals: {e}{why}"))
    })?;
    let parameters = super::variables::parameters(file, d, "plant.parameters", &scenario.plant.parameters)?;
    Ok(FmuSignals {
        output_refs: outputs.iter().map(|v| (v.kind, v.value_reference)).collect(),
        input_refs: inputs.iter().map(|v| (v.kind, v.value_reference)).collect(),
        signals,
        parameters,
        left_out,
    })
}

/// An FMU unpacked, mapped and initialized at t = 0, ready to fly.
pub struct FmuPlant {
    // Dropped before `fmu`: the instance is freed before its folder is removed.
    instance: Instance,
    fmu: Arc<Fmu>,
    /// Its signals and references.
    pub map: FmuSignals,
    outputs: Numbers,
    inputs: Numbers,
    tick: u64,
    dt_s: f64,
}

/// A checkpoint of an FMU plant: the tick its state belongs to and the FMU's serialized state, hex-encoded.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
struct SavedFmu {
    tick: u64,
    state_hex: String,
}

impl FmuPlant {
    /// Open the FMU at `path`, map its signals, set `[plant.parameters]` and initialize it.
    pub fn open(path: &Path, scenario: &Scenario) -> anyhow::Result<Self> {
        Self::new(Arc::new(Fmu::open(path)?), scenario)
    }

    /// [`Self::open`] for an FMU already unpacked: one instance of it, mapped, with `[plant.parameters]` set and
    /// initialized (what each case of an in-process sweep flies).
    pub fn new(fmu: Arc<Fmu>, scenario: &Scenario) -> anyhow::Result<Self> {
        let map = Self::describe(&fmu, scenario).map_err(anyhow::Error::msg)?;
        let mut instance = fmu.instantiate("plant")?;
        set_parameters(&mut instance, &map.parameters)?;
        instance.enter_initialization(0.0)?;
        instance.exit_initialization()?;
        let (outputs, inputs) = (Numbers::new(map.output_refs.clone()), Numbers::new(map.input_refs.clone()));
        Ok(Self { instance, fmu, map, outputs, inputs, tick: 0, dt_s: scenario.timing.dt_s })
    }

    /// The signals of the FMU at `path` under `scenario`, without instantiating it: what the launcher checks
    /// before starting a run.
    pub fn check(path: &Path, scenario: &Scenario) -> anyhow::Result<FmuSignals> {
        let fmu = Fmu::open(path)?;
        Self::describe(&fmu, scenario).map_err(anyhow::Error::msg)
    }

    fn describe(fmu: &Fmu, scenario: &Scenario) -> Result<FmuSignals, String> {
        fmu_signals(fmu.file(), &fmu.description, scenario)
    }

    /// Whether a restarted plant can resume from the FMU's state, or why not.
    pub fn can_checkpoint(&self) -> Result<(), String> {
        can_checkpoint(&self.fmu.description)
    }

    /// Its outputs now, in the announced order.
    pub fn outputs(&mut self, values: &mut [f64]) -> Result<(), String> {
        self.instance.get_numbers(&mut self.outputs, values).map_err(|e| e.to_string())
    }

    /// Set the inputs and step one period.
    pub fn step(&mut self, inputs: &[f64]) -> Result<(), String> {
        self.instance.set_numbers(&mut self.inputs, inputs).map_err(|e| e.to_string())?;
        let t_s = self.tick as f64 * self.dt_s;
        self.instance.do_step(t_s, self.dt_s).map_err(|e| e.to_string())?;
        self.tick += 1;
        Ok(())
    }

    /// The FMU's state after the last step, as checkpoint text.
    pub fn checkpoint(&mut self) -> Result<String, String> {
        let bytes = self.instance.save_state().map_err(|e| e.to_string())?;
        let state_hex = to_hex(&bytes);
        serde_json::to_string(&SavedFmu { tick: self.tick, state_hex }).map_err(|e| e.to_string())
    }

    /// Put back the state a checkpoint holds.
    pub fn restore(&mut self, text: &str) -> Result<(), String> {
        let saved: SavedFmu = serde_json::from_str(text).map_err(|e| format!("not an FMU plant's checkpoint: {e}"))?;
        let bytes = from_hex(&saved.state_hex)?;
        self.instance.restore_state(&bytes).map_err(|e| e.to_string())?;
        self.tick = saved.tick;
        Ok(())
    }
}

/// Fly the scenario's FMU as the run's plant, to the end of the scenario (or SIGTERM), and write the report.
pub fn run_fmu_plant(args: &ProcessArgs, scenario: Scenario, path: &Path) -> anyhow::Result<ProcessReport> {
    let mut plant = FmuPlant::open(path, &scenario)?;
    let mut outputs = vec![0.0; plant.map.output_refs.len()];
    plant.outputs(&mut outputs).map_err(anyhow::Error::msg)?;
    // The actuators start where the FMU says they are (an input's position output at t = 0), else at the hold.
    let signals = plant.map.signals.clone();
    let initial = signals.inputs.iter().map(|i| i.held_output.map_or(i.hold, |k| outputs[k])).collect();
    let mut session = PlantSession::open_at(args.clone(), scenario, &signals, initial)?;
    let checkpoints = plant.can_checkpoint();
    let left_out = plant.map.left_out_note();
    session.event(
        "plant-fmu",
        match &checkpoints {
            Ok(()) => format!("flying {}: checkpoints through its own state{left_out}", plant.fmu.label()),
            Err(why) => {
                format!("flying {}: {why}, so a restarted plant flies again from tick 0{left_out}", plant.fmu.label())
            }
        },
    );
    if let Some(text) = session.restored_checkpoint() {
        let outcome = match &checkpoints {
            Ok(()) => plant.restore(text),
            Err(why) => Err(why.clone()),
        };
        session.checkpoint_used(outcome);
    }
    let error = loop {
        if let Err(e) = plant.outputs(&mut outputs) {
            break Some(e);
        }
        match session.tick(&outputs)? {
            PlantTick::Inputs(inputs) => {
                if let Err(e) = plant.step(inputs) {
                    break Some(e);
                }
            }
            PlantTick::RunEnded | PlantTick::Stopped => break None,
        }
        if checkpoints.is_ok() && session.checkpoint_due() {
            match plant.checkpoint() {
                Ok(text) => session.save_checkpoint(&text),
                Err(e) => session.event("plant-checkpoint-failed", e),
            }
        }
    };
    session.finish(error.as_deref())
}

/// An FMU with the rig's actuators and sensors around it, as one [`PlantModel`]: what the in-process loop
/// ([`crate::in_process`]) flies. The same steps as [`run_fmu_plant`] takes through its [`PlantSession`], in the
/// same order (the chain's actuators move under the command, the FMU steps with their positions, its outputs are
/// read, refused when not finite, and measured once per tick), so both give the same trace.
pub struct FmuModel {
    plant: FmuPlant,
    chain: SignalChain,
    initial_inputs: Vec<f64>,
    /// The FMU's last valid outputs, before the sensors.
    raw_outputs: Vec<f64>,
    /// The outputs of the current tick as the sensors report them.
    measured: Vec<f64>,
    /// The FMU's outputs as read after a step.
    read: Vec<f64>,
    tick: u64,
    ticks: u64,
    /// Outputs with NaN or infinity refused so far (the last valid ones stood in), and the first one's output.
    pub outputs_refused: (u64, Option<String>),
}

impl FmuModel {
    /// The FMU initialized at t = 0 under `scenario`, its actuators where its outputs say they are.
    pub fn new(mut plant: FmuPlant, scenario: &Scenario) -> anyhow::Result<Self> {
        let mut outputs = vec![0.0; plant.map.output_refs.len()];
        plant.outputs(&mut outputs).map_err(anyhow::Error::msg)?;
        let signals = &plant.map.signals;
        let initial_inputs: Vec<f64> =
            signals.inputs.iter().map(|i| i.held_output.map_or(i.hold, |k| outputs[k])).collect();
        if let Some((input, value)) = signals.inputs.iter().zip(&initial_inputs).find(|(_, v)| !v.is_finite()) {
            anyhow::bail!("FMU {}: input {}'s actuator starts at {value}", plant.fmu.file(), input.name);
        }
        let chain = SignalChain::new(scenario, signals, &initial_inputs)
            .map_err(|(key, problem)| anyhow::anyhow!("the scenario: `{key}`: {problem}"))?;
        let n = outputs.len();
        let mut model = Self {
            plant,
            chain,
            initial_inputs,
            raw_outputs: vec![0.0; n],
            measured: vec![0.0; n],
            read: vec![0.0; n],
            tick: 0,
            ticks: scenario.timing.ticks(),
            outputs_refused: (0, None),
        };
        model.take_outputs(&outputs);
        model.measure();
        Ok(model)
    }

    fn take_outputs(&mut self, outputs: &[f64]) {
        match outputs.iter().position(|v| !v.is_finite()) {
            None => self.raw_outputs.copy_from_slice(outputs),
            Some(k) => {
                let first = || {
                    format!("output {} is {} at tick {}", self.plant.map.signals.outputs[k].name, outputs[k], self.tick)
                };
                let (count, first_seen) = &mut self.outputs_refused;
                *count += 1;
                first_seen.get_or_insert_with(first);
            }
        }
    }

    fn measure(&mut self) {
        self.measured.copy_from_slice(&self.raw_outputs);
        let t_s = self.t_s();
        self.chain.measure(t_s, &mut self.measured);
    }
}

impl PlantModel for FmuModel {
    fn signals(&self) -> &PlantSignals {
        &self.plant.map.signals
    }

    fn tick(&self) -> u64 {
        self.tick
    }

    fn t_s(&self) -> f64 {
        self.tick as f64 * self.plant.dt_s
    }

    fn outputs(&self) -> Vec<f64> {
        self.measured.clone()
    }

    fn initial_inputs(&self) -> Vec<f64> {
        self.initial_inputs.clone()
    }

    /// As the session does, the FMU steps on the last tick too: the end-of-run sample's actuator positions are
    /// its outputs after that step.
    fn step(&mut self, inputs: &[f64], last: bool) -> Result<ActuatorFlags, String> {
        let hits = self.chain.actuate(self.t_s(), inputs);
        self.plant.step(self.chain.positions())?;
        let mut read = std::mem::take(&mut self.read);
        self.plant.outputs(&mut read)?;
        self.take_outputs(&read);
        self.read = read;
        if !last && self.tick < self.ticks {
            self.tick += 1;
        }
        self.measure();
        Ok(ActuatorFlags { saturated: hits.position, rate_limited: hits.rate })
    }

    fn checkpoint(&self) -> Option<String> {
        None
    }

    fn restore(&mut self, _saved: &str, _ticks: u64) -> Result<u64, String> {
        Err("a flight in one process is never restarted".into())
    }
}
