//! The closed loop of any plant and any controller the rig flies in one process, with no clock and no transport:
//! a built-in vehicle (the F-16, the quadrotor) or an FMU ([`crate::fmu::plant::FmuModel`]) against our controller or
//! a controller FMU, tick
//! by tick in lockstep. `silrig sim` and `silrig sweep` fly scenarios that name an FMU here, so a user's models get
//! Monte Carlo at in-process speed.
//!
//! It keeps the three-process lockstep rig's rules, so both give the same `trace.csv`: tick k's sample goes to the
//! controller, whose command starts from where each actuator is (the sample's held outputs, else the hold value)
//! and is checked as the controller's session checks it (NaN, infinity or out of range: refused, the plant holds
//! its last valid command, the trace shows the last valid command sent); the plant applies the answer to tick k
//! (`same-tick`) or k-1 (`next-tick`), steps, and row k takes the actuator positions from the sample after the
//! step. The F-16 against our controller gives `silrig_flight::sim::run`'s trace exactly (tested).
//!
//! [`Models`] opens a scenario's FMUs once (unpacking is the slow part) and flies any number of flights of it, each
//! with fresh instances, from any number of threads unless an FMU says its binary allows one instance per process.
//! What it opens and flies is a match on the scenario's [`PlantKind`] and [`ControllerKind`], one arm per adapter,
//! as in [`crate::process`] (a plant FMU with no controller named gets the built-in law that fits its signals, or
//! a refusal when it would fly); or, in place of the scenario's controller, one the caller brings
//! ([`Models::fly_controller`]: the Python package's `silrig.sim(..., controller=...)`), made anew for each flight.

use crate::builtin::attitude_law::AttitudeLaw;
use crate::builtin::f16_plant::F16Plant;
use crate::builtin::quad_law::QuadLaw;
use crate::builtin::quad_plant::QuadPlant;
use crate::fmu::controller::FmuController;
use crate::fmu::plant::{FmuModel, FmuPlant};
use crate::process::{ControllerKind, PlantKind};
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::Trace;
use silrig_fmi::Fmu;
use silrig_rig::controller::Controller;
use silrig_rig::plant_model::PlantModel;
use silrig_wire::wire::{self, CommandSample, PlantSample, WireSample};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Which side ended a flight before the scenario's end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndedBy {
    /// The plant could not step (the F-16 left its envelope, an FMU's call failed).
    Plant,
    /// The controller could not go on (a controller FMU's call failed).
    Controller,
}

/// Why a flight ended before the scenario's end.
#[derive(Debug, Clone, PartialEq)]
pub struct EndedEarly {
    /// Which side.
    pub by: EndedBy,
    /// The tick it happened at.
    pub tick: u64,
    /// Its simulated time, s.
    pub t_s: f64,
    /// What it said.
    pub why: String,
}

impl std::fmt::Display for EndedEarly {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let side = match self.by {
            EndedBy::Plant => "the plant",
            EndedBy::Controller => "the controller",
        };
        write!(f, "{side} stopped at t = {:.2} s (tick {}): {}", self.t_s, self.tick, self.why)
    }
}

/// A flight flown in one process.
#[derive(Debug, Clone)]
pub struct Flown {
    /// The plant's signals (what the trace's columns come from).
    pub plant: PlantSignals,
    /// `trace.csv`: one row per tick flown.
    pub trace: Trace,
    /// Set when it ended before the scenario's end; the trace holds it up to there.
    pub ended_early: Option<EndedEarly>,
    /// Commands the controller's session would refuse (NaN, infinity, out of range), and the first reason.
    pub commands_refused: (u64, Option<String>),
    /// Plant outputs with NaN or infinity, refused (the last valid ones stood in), and the first one.
    pub outputs_refused: (u64, Option<String>),
}

impl Flown {
    /// What the rig would refuse in this flight, as sentences (empty: nothing).
    pub fn refusals(&self) -> Vec<String> {
        let mut said = Vec::new();
        if let (n @ 1.., Some(first)) = &self.commands_refused {
            said.push(format!("{n} command(s) refused (first at {first})"));
        }
        if let (n @ 1.., Some(first)) = &self.outputs_refused {
            said.push(format!("{n} plant sample(s) with outputs refused (first: {first})"));
        }
        said
    }
}

/// What the controller's session does in one process: ask the controller for a command on its ticks, check it as
/// the session would (a refused one holds the plant's inputs and shows no diagnostics), and repeat its last answer
/// on the plant's ticks between (`timing.controller_every_ticks`).
struct Answers {
    signals: PlantSignals,
    dt_s: f64,
    command: Vec<f64>,
    diagnostics: Vec<f64>,
    /// Whether the last answer was valid.
    valid: bool,
    /// The last valid command sent: what the session repeats for a refused one (the hold values before any).
    last_sent: Vec<f64>,
    refused: (u64, Option<String>),
}

impl Answers {
    /// The answer to `tick`'s sample (`outputs`, at `t_s`); an error: the controller's failure.
    fn answer(
        &mut self,
        scenario: &Scenario,
        controller: &mut dyn Controller,
        tick: u64,
        t_s: f64,
        outputs: &[f64],
    ) -> Result<(), String> {
        if !scenario.timing.is_controller_tick(tick) {
            return Ok(());
        }
        let mut sample = PlantSample { t_sim_s: t_s, ..PlantSample::with_outputs(outputs) };
        sample.header.tick = tick;
        for (c, i) in self.command.iter_mut().zip(&self.signals.inputs) {
            *c = i.held_output.map(|o| outputs[o]).filter(|v| v.is_finite()).unwrap_or(i.hold);
        }
        controller.step(&sample, self.dt_s, &mut self.command, &mut self.diagnostics);
        if let Some(why) = controller.failure() {
            return Err(why);
        }
        let inputs = self.command.len();
        let mut sent = CommandSample { answers_tick: tick, ..CommandSample::zeroed() };
        sent.inputs_len = inputs as u32;
        sent.inputs[..inputs].copy_from_slice(&self.command);
        sent.diagnostics_len = self.diagnostics.len() as u32;
        sent.diagnostics[..self.diagnostics.len()].copy_from_slice(&self.diagnostics);
        let refused =
            sent.validate().map_err(|e| e.to_string()).and_then(|()| wire::check_command(&self.signals, &sent));
        self.valid = refused.is_ok();
        match refused {
            Err(reason) => {
                self.refused.0 += 1;
                self.refused.1.get_or_insert(format!("tick {tick}: {reason}"));
            }
            Ok(()) => self.last_sent.copy_from_slice(&self.command),
        }
        Ok(())
    }
}

/// Fly `plant` against `controller` under `scenario` from tick 0 to its end. An error: the controller cannot
/// connect to the plant (a signal it needs is missing).
pub fn fly(scenario: &Scenario, plant: &mut dyn PlantModel, controller: &mut dyn Controller) -> Result<Flown, String> {
    let signals = plant.signals().clone();
    controller.connect(&signals)?;
    let names = controller.diagnostic_names();
    let mut trace = Trace::new(signals.trace_columns(&names));
    let ticks = scenario.timing.ticks();
    trace.rows.reserve(ticks as usize + 1);
    let delay = scenario.timing.command_delay_ticks() as usize;
    let mut applied = plant.initial_inputs();
    // Answers not yet acting, oldest first: whether valid, and the command (buffers recycled through `spare`).
    let mut pending: VecDeque<(bool, Vec<f64>)> = VecDeque::with_capacity(delay + 1);
    let mut spare: Vec<Vec<f64>> = Vec::new();
    let mut answers = Answers {
        dt_s: scenario.timing.controller_dt_s(),
        command: vec![0.0; signals.inputs.len()],
        diagnostics: vec![0.0; names.len()],
        valid: true,
        last_sent: signals.hold(),
        refused: (0, None),
        signals: signals.clone(),
    };
    let no_diagnostics = vec![f64::NAN; names.len()];
    let mut ended_early = None;
    let mut outputs = plant.outputs();
    for tick in 0..=ticks {
        let t_s = plant.t_s();
        if let Err(why) = answers.answer(scenario, controller, tick, t_s, &outputs) {
            ended_early = Some(EndedEarly { by: EndedBy::Controller, tick, t_s, why });
            break;
        }
        let mut answer = spare.pop().unwrap_or_else(|| vec![0.0; answers.command.len()]);
        answer.copy_from_slice(&answers.command);
        pending.push_back((answers.valid, answer));
        if pending.len() > delay
            && let Some((valid, answer)) = pending.pop_front()
        {
            if valid {
                applied.copy_from_slice(&answer);
            }
            spare.push(answer);
        }
        let stepped = plant.step(&applied, tick >= ticks);
        let next = plant.outputs();
        // The trace shows what the session sends: the command, or for a refused one the last valid command and no
        // diagnostics.
        let shown_diagnostics = if answers.valid { &answers.diagnostics } else { &no_diagnostics };
        let mut row = Vec::with_capacity(trace.columns.len());
        signals.trace_row(&mut row, t_s, &outputs, Some(&answers.last_sent), Some(&next), 0, shown_diagnostics);
        trace.rows.push(row);
        if let Err(why) = stepped {
            ended_early = Some(EndedEarly { by: EndedBy::Plant, tick, t_s, why });
            break;
        }
        outputs = next;
    }
    let commands_refused = answers.refused;
    Ok(Flown { plant: signals, trace, ended_early, commands_refused, outputs_refused: (0, None) })
}

/// `--plant-fmu` and `--controller-fmu` of the commands that fly in one process (`silrig sim`, `silrig sweep`).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct FmuFlags {
    /// Fly this co-simulation FMU (FMI 2.0 or 3.0, Linux x86-64 binary) as the plant, in one process: the same as
    /// the scenario key `[plant] fmu` (and as `silrig run --plant-fmu`).
    #[arg(long, value_name = "FILE.fmu")]
    pub plant_fmu: Option<PathBuf>,
    /// Fly this co-simulation FMU as the controller, in one process: the same as the scenario key
    /// `[controller] fmu` (and as `silrig run --controller-fmu`).
    #[arg(long, value_name = "FILE.fmu")]
    pub controller_fmu: Option<PathBuf>,
}

impl FmuFlags {
    /// Put the FMUs given into `scenario`, by their absolute paths (a scenario written down means the same files
    /// wherever it is read).
    pub fn apply(&self, scenario: &mut Scenario) -> anyhow::Result<()> {
        let absolute =
            |flag: &str, p: &Path| std::path::absolute(p).map_err(|e| anyhow::anyhow!("--{flag} {}: {e}", p.display()));
        if let Some(p) = &self.plant_fmu {
            scenario.plant.fmu = Some(absolute("plant-fmu", p)?);
        }
        if let Some(p) = &self.controller_fmu {
            scenario.controller.fmu = Some(absolute("controller-fmu", p)?);
        }
        Ok(())
    }

    /// The flags as a command line repeats them (` --plant-fmu FILE`), empty when none was given.
    pub fn to_args(&self) -> String {
        let mut args = String::new();
        for (flag, path) in [("plant-fmu", &self.plant_fmu), ("controller-fmu", &self.controller_fmu)] {
            if let Some(p) = path {
                args += &format!(" --{flag} {}", p.display());
            }
        }
        args
    }
}

/// A scenario's plant and controller, their FMUs unpacked once, ready to fly any number of times.
pub struct Models {
    plant: OpenedPlant,
    controller: OpenedController,
}

/// A plant of each [`PlantKind`], opened: what [`Models::fly`] makes each flight's plant from.
enum OpenedPlant {
    F16,
    Quad,
    Fmu(Arc<Fmu>),
}

/// A controller of each [`ControllerKind`], opened, or the caller's: what [`Models::fly`] makes each flight's
/// controller from.
enum OpenedController {
    AttitudeLaw,
    QuadLaw,
    Fmu(Arc<Fmu>),
    Given(MakeController),
    /// A plant FMU that no built-in law fits, with no controller named: why, said when it would fly.
    Unfit(String),
}

/// Makes a flight's controller for that flight's scenario (a sweep's case: its dispersed set points and step); an
/// error says why it could not (the case is then infeasible). Called from the thread that flies it.
pub type MakeController = Arc<dyn Fn(&Scenario) -> Result<Box<dyn Controller>, String> + Send + Sync>;

impl OpenedPlant {
    fn fmu(&self) -> Option<&Arc<Fmu>> {
        match self {
            Self::Fmu(fmu) => Some(fmu),
            Self::F16 | Self::Quad => None,
        }
    }
}

impl OpenedController {
    fn fmu(&self) -> Option<&Arc<Fmu>> {
        match self {
            Self::Fmu(fmu) => Some(fmu),
            Self::AttitudeLaw | Self::QuadLaw | Self::Given(_) | Self::Unfit(_) => None,
        }
    }
}

/// Why a flight could not start (not a verdict on the controller: the case is infeasible).
#[derive(Debug, thiserror::Error)]
#[error("{0:#}")]
pub struct SetupError(pub anyhow::Error);

impl Models {
    /// Unpack and load the FMUs `scenario` names (`[plant] fmu`, `[controller] fmu`); the built-in F-16 and our
    /// controller need nothing, the quadrotor a scenario it can fly (checked here, naming the key).
    pub fn open(scenario: &Scenario) -> anyhow::Result<Self> {
        let plant = match PlantKind::of(scenario) {
            PlantKind::F16 => OpenedPlant::F16,
            PlantKind::Quad => {
                silrig_flight::quad::check_for_quad(scenario).map_err(|(k, p)| anyhow::anyhow!("`{k}`: {p}"))?;
                OpenedPlant::Quad
            }
            PlantKind::Fmu(path) => OpenedPlant::Fmu(Arc::new(Fmu::open(&path)?)),
        };
        // A plant FMU that no built-in law fits is refused when it would fly, not now: the caller may bring its
        // own controller (`fly_controller`, a sweep's `--controller-cmd`).
        let fmu_signals = |_: &Path| -> anyhow::Result<PlantSignals> {
            let fmu = plant.fmu().expect("a plant FMU is opened as one");
            let signals = crate::fmu::plant::fmu_signals(fmu.file(), &fmu.description, scenario);
            Ok(signals.map_err(anyhow::Error::msg)?.signals)
        };
        let controller = match ControllerKind::fitting(scenario, fmu_signals) {
            Err(unfit) => OpenedController::Unfit(format!("{unfit:#}")),
            Ok(ControllerKind::AttitudeLaw) => OpenedController::AttitudeLaw,
            Ok(ControllerKind::QuadLaw) => OpenedController::QuadLaw,
            Ok(ControllerKind::Fmu(path)) => OpenedController::Fmu(Arc::new(Fmu::open(&path)?)),
            Ok(ControllerKind::Device(layout)) => anyhow::bail!(
                "the controller is the device of {}: a device flies through the rig (`silrig run`), not in one \
                 process",
                layout.display()
            ),
        };
        Ok(Self { plant, controller })
    }

    /// Fly the controllers `make` makes, one per flight, in place of the scenario's (its `[controller]` table is
    /// then not read, but for the step: `timing.controller_every_ticks`).
    pub fn fly_controller(&mut self, make: MakeController) {
        self.controller = OpenedController::Given(make);
    }

    /// Whether a controller flies the plant: the error says why no built-in controller fits a plant FMU and how
    /// to name one (a caller's controller, [`Models::fly_controller`], flies it instead).
    pub fn controller_fits(&self) -> anyhow::Result<()> {
        match &self.controller {
            OpenedController::Unfit(why) => Err(anyhow::anyhow!("{why}")),
            _ => Ok(()),
        }
    }

    /// Whether the scenario flies an FMU.
    pub fn has_fmu(&self) -> bool {
        self.plant.fmu().is_some() || self.controller.fmu().is_some()
    }

    /// Whether `scenario` is the F-16 against our controller at the plant's rate, which `silrig_flight::sim` flies
    /// (the reference loop); anything else flies here.
    pub fn flies_reference_loop(&self, scenario: &Scenario) -> bool {
        matches!((&self.plant, &self.controller), (OpenedPlant::F16, OpenedController::AttitudeLaw))
            && scenario.timing.controller_every_ticks == 1
    }

    /// `plant`, a flight's announcement, when the plant is not the built-in F-16 (an FMU, the quadrotor); `None`
    /// for the F-16 under any controller, whose actuators are its own: what the summary and the figures take.
    pub fn own_plant(&self, plant: PlantSignals) -> Option<PlantSignals> {
        (!matches!(self.plant, OpenedPlant::F16)).then_some(plant)
    }

    /// The plant FMU's or the quadrotor's signals under `scenario`, as it announces them when it flies; `None` for
    /// the built-in F-16 (what the summary takes: `silrig_flight::summary::summarize`).
    pub fn plant_signals(&self, scenario: &Scenario) -> Result<Option<PlantSignals>, String> {
        if let OpenedPlant::Quad = self.plant {
            return silrig_flight::quad::builtin_signals(scenario).map(Some).map_err(|(k, p)| format!("`{k}`: {p}"));
        }
        let Some(fmu) = self.plant.fmu() else { return Ok(None) };
        crate::fmu::plant::fmu_signals(fmu.file(), &fmu.description, scenario).map(|f| Some(f.signals))
    }

    /// The FMU whose binary allows one instance per process (`canBeInstantiatedOnlyOncePerProcess`), if any:
    /// its flights must be flown one after the other.
    pub fn one_instance_per_process(&self) -> Option<String> {
        [self.plant.fmu(), self.controller.fmu()]
            .into_iter()
            .flatten()
            .find(|f| f.description.co_simulation.one_instance_per_process)
            .map(|f| f.label())
    }

    /// Whether a dispersion of `key` reaches what flies: an FMU plant reads `[plant.parameters]`, not the F-16's
    /// keys (`plant.xcg`, `initial.*`, `disturbance.*`), and a controller FMU `[controller.parameters]`, not our
    /// gains. The error names the key and what to disperse instead.
    pub fn check_dispersed(&self, key: &str) -> Result<(), String> {
        let unread = |fmu: &Arc<Fmu>, side: &str| {
            format!(
                "the {side} is the FMU {}: it does not read `{key}`; disperse its parameters as \
                 `{side}.parameters.<variable>`",
                fmu.file()
            )
        };
        if let Some(fmu) = self.plant.fmu()
            && silrig_flight::dispersion::is_f16_only(key)
        {
            return Err(unread(fmu, "plant"));
        }
        if let OpenedPlant::Quad = self.plant
            && silrig_flight::dispersion::is_f16_only(key)
        {
            return Err(format!(
                "the plant is the built-in quadrotor: it does not read `{key}`; disperse its parameters as \
                 `plant.parameters.<name>`"
            ));
        }
        if let Some(fmu) = self.controller.fmu()
            && key.starts_with("controller.")
            && !key.starts_with("controller.parameters.")
        {
            return Err(unread(fmu, "controller"));
        }
        Ok(())
    }

    /// Fly `scenario` (this scenario, or a sample of its dispersions: the same FMU files) with fresh instances.
    pub fn fly(&self, scenario: &Scenario) -> Result<Flown, SetupError> {
        let setup = |e: anyhow::Error| SetupError(e);
        let mut controller: Box<dyn Controller> = match &self.controller {
            OpenedController::AttitudeLaw => Box::new(AttitudeLaw::new(scenario)),
            OpenedController::QuadLaw => Box::new(QuadLaw::new(scenario).map_err(|e| setup(anyhow::anyhow!(e)))?),
            OpenedController::Fmu(fmu) => Box::new(FmuController::new(fmu.clone(), scenario).map_err(setup)?),
            OpenedController::Given(make) => make(scenario).map_err(|e| setup(anyhow::anyhow!(e)))?,
            OpenedController::Unfit(why) => return Err(setup(anyhow::anyhow!("{why}"))),
        };
        let connect = |e: String| setup(anyhow::anyhow!(e));
        match &self.plant {
            OpenedPlant::F16 => {
                let mut plant = F16Plant::new(scenario).map_err(|e| setup(e.into()))?;
                fly(scenario, &mut plant, controller.as_mut()).map_err(connect)
            }
            OpenedPlant::Quad => {
                let mut plant = QuadPlant::new(scenario).map_err(setup)?;
                fly(scenario, &mut plant, controller.as_mut()).map_err(connect)
            }
            OpenedPlant::Fmu(fmu) => {
                let plant = FmuPlant::new(fmu.clone(), scenario).map_err(setup)?;
                let mut model = FmuModel::new(plant, scenario).map_err(setup)?;
                let mut flown = fly(scenario, &mut model, controller.as_mut()).map_err(connect)?;
                flown.outputs_refused = model.outputs_refused.clone();
                Ok(flown)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::fault::parse_fault_flag;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// The generic loop flying the F-16 against our controller is the reference loop, bit for bit.
    fn same_as_sim(scenario: &Scenario) {
        same_as_sim_with(&Models::open(scenario).unwrap(), scenario);
    }

    fn same_as_sim_with(models: &Models, scenario: &Scenario) {
        let reference = silrig_flight::sim::run(scenario).expect("the scenario flies");
        let flown = models.fly(scenario).unwrap();
        assert!(flown.ended_early.is_none(), "{:?}", flown.ended_early);
        assert_eq!(flown.trace.columns, reference.columns);
        assert_eq!(flown.trace.rows.len(), reference.rows.len());
        for (k, (a, b)) in flown.trace.rows.iter().zip(&reference.rows).enumerate() {
            let same = a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
            assert!(same, "row {k} differs:\n{a:?}\n{b:?}");
        }
    }

    #[test]
    fn the_f16_against_our_controller_flies_as_the_reference_loop() {
        same_as_sim(&Scenario::embedded_default());
    }

    #[test]
    fn so_it_does_with_a_command_delay_and_plant_model_faults() {
        let mut s = Scenario::embedded_default();
        s.timing.duration_s = 4.0;
        s.timing.command_timing = silrig_flight::scenario::CommandTiming::NextTick;
        s.timing.transport_delay_ticks = 1;
        for flag in
            ["plant:sensor-noise@1s,channel=p_radps,std=0.01,for=2s", "plant:actuator-stuck@2s,surface=aileron,for=1s"]
        {
            s.faults.push(parse_fault_flag(flag).unwrap());
        }
        s.validate().unwrap();
        same_as_sim(&s);
    }

    #[test]
    fn a_controller_the_caller_brings_flies_in_place_of_the_scenarios_one_per_flight() {
        let scenario = Scenario::embedded_default();
        let mut models = Models::open(&scenario).unwrap();
        let made = Arc::new(AtomicUsize::new(0));
        let counted = made.clone();
        models.fly_controller(Arc::new(move |s: &Scenario| -> Result<Box<dyn Controller>, String> {
            counted.fetch_add(1, Ordering::Relaxed);
            Ok(Box::new(AttitudeLaw::new(s)))
        }));
        // Never the reference loop: the caller's controller flies in the generic one.
        assert!(!models.flies_reference_loop(&scenario));
        same_as_sim_with(&models, &scenario);
        same_as_sim_with(&models, &scenario);
        assert_eq!(made.load(Ordering::Relaxed), 2);
    }

    #[test]
    fn a_controller_that_cannot_be_made_is_a_setup_error_saying_why() {
        let scenario = Scenario::embedded_default();
        let mut models = Models::open(&scenario).unwrap();
        models.fly_controller(Arc::new(|_: &Scenario| -> Result<Box<dyn Controller>, String> {
            Err("copying the controller failed: no".into())
        }));
        let err = models.fly(&scenario).expect_err("refused");
        assert_eq!(err.to_string(), "copying the controller failed: no");
    }
}
