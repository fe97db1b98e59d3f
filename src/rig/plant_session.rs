//! The plant's side of a run for a vehicle model of the user's own (Python on JSBSim, C, an FMU's wrapper):
//! [`PlantSession`] opens the run as its plant and announces the model's signals, then each [`PlantSession::tick`]
//! takes the model's outputs for the tick and gives back the inputs to step it with. Everything around the model
//! is the rig's plant loop ([`super::plant::PlantLoop`], the same as for a built-in model): the clock (realtime
//! sleeps or lockstep), the commands and their misses, the watchdog and the failsafe (the announced hold values),
//! the in-loop faults, the flags and the timing report. `libsilrig_client.so` exports it to C and Python.
//!
//! The model's step time is what passes between handing out the inputs and the next `tick`; outputs with NaN or
//! infinity are refused (counted, the first said in an event) and the last valid ones are published instead, each
//! such sample flagged ([`silrig_wire::wire::FLAG_OUTPUTS_HELD`]).
//! Between the loop and the model sits the rig's [`SignalChain`]: the scenario's `[actuators.<input>]` and actuator
//! faults move the inputs the model is stepped with, sensor faults change the outputs the controller reads (the
//! trace and the recording show those, as for a built-in model).
//! Checkpoints (realtime): when [`PlantSession::checkpoint_due`] says so, the model hands its state as text to
//! [`PlantSession::save_checkpoint`] after stepping; the rig writes it with the tick it belongs to and the
//! actuators' positions. A restarted plant finds it in [`PlantSession::restored_checkpoint`] and says whether it
//! restored it ([`PlantSession::checkpoint_used`]): then the flight goes on from that tick, otherwise it flies again
//! from tick 0 and the logger marks the join. Not yet: a model leaving its envelope other than by closing the
//! session with an error.

use super::ProcessArgs;
use super::plant::{PlantLoop, PlantPorts};
use super::plant_model::{ActuatorFlags, PlantModel};
use super::report::ProcessReport;
use super::session::SessionError;
use super::signals;
use silrig_flight::scenario::Scenario;
use silrig_flight::signal_chain::SignalChain;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::IpcError;
use silrig_wire::wire::PlantInfo;
use std::cell::RefCell;
use std::rc::Rc;

/// What the session and the loop share of the user's model: its outputs for the tick being flown, and what it
/// saved for a restarted plant.
#[derive(Debug)]
struct Latest {
    outputs: Vec<f64>,
    tick: u64,
    t_s: f64,
    /// The model's state as text, and the tick it belongs to.
    saved: Option<(u64, String)>,
    /// The actuators' positions over the step being flown (what a checkpoint resumes them from).
    positions: Vec<f64>,
}

/// A plant checkpoint as written to `plant.checkpoint.json`.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct SavedPlant {
    /// The tick the saved state belongs to: the flight goes on from here.
    tick: u64,
    /// The rig's actuators at that tick, one per input.
    actuator_positions: Vec<f64>,
    /// The model's own text.
    model: String,
}

/// The user's model as the plant loop sees it: the outputs the session was given; stepping happens outside.
struct ExternalModel {
    signals: PlantSignals,
    latest: Rc<RefCell<Latest>>,
    /// What the actuators hold before the first command.
    initial_inputs: Vec<f64>,
}

impl PlantModel for ExternalModel {
    fn signals(&self) -> &PlantSignals {
        &self.signals
    }

    fn tick(&self) -> u64 {
        self.latest.borrow().tick
    }

    fn t_s(&self) -> f64 {
        self.latest.borrow().t_s
    }

    fn outputs(&self) -> Vec<f64> {
        self.latest.borrow().outputs.clone()
    }

    fn initial_inputs(&self) -> Vec<f64> {
        self.initial_inputs.clone()
    }

    fn step(&mut self, _inputs: &[f64], _last: bool) -> Result<ActuatorFlags, String> {
        Ok(ActuatorFlags::default())
    }

    /// What the model saved for the tick after the one just flown (nothing when it saved nothing then).
    fn checkpoint(&self) -> Option<String> {
        let latest = self.latest.borrow();
        let (tick, model) = latest.saved.as_ref().filter(|(tick, _)| *tick == latest.tick + 1)?;
        let saved = SavedPlant { tick: *tick, actuator_positions: latest.positions.clone(), model: model.clone() };
        serde_json::to_string(&saved).ok()
    }

    /// Never called: the session offers a checkpoint to the model, which says whether it took it.
    fn restore(&mut self, _saved: &str, _ticks: u64) -> Result<u64, String> {
        Err("a plant of your own resumes through its session (restored_checkpoint, checkpoint_used)".into())
    }
}

/// A restarted plant's predecessor's newest checkpoint (offered to the model), or why it flies again from tick 0.
/// One that exists but cannot be used is an error: flying from tick 0 would splice a different flight into the run.
fn read_checkpoint(lp: &PlantLoop, plant: &PlantSignals) -> Result<(Option<SavedPlant>, Option<String>), SessionError> {
    let Some((text, source)) = lp.saved_checkpoint().map_err(|e| SessionError::Setup(format!("{e:#}")))? else {
        let path = lp.checkpoint_path().display();
        return Ok((None, Some(format!("no checkpoint in {path}: flying again from tick 0{}", lp.flown_again(0)))));
    };
    let bad = |why: String| SessionError::Setup(format!("cannot resume: {source}: {why}"));
    let saved: SavedPlant = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    if saved.actuator_positions.len() != plant.inputs.len() || saved.actuator_positions.iter().any(|v| !v.is_finite()) {
        return Err(bad(format!(
            "its {} actuator positions do not fit the plant's {} inputs",
            saved.actuator_positions.len(),
            plant.inputs.len()
        )));
    }
    Ok((Some(saved), None))
}

/// What [`PlantSession::tick`] gives.
#[derive(Debug, Clone, PartialEq)]
pub enum PlantTick<'a> {
    /// Step the model with these inputs (one per announced input) over one period, then call `tick` again.
    Inputs(&'a [f64]),
    /// The run is over (the scenario's last tick was flown, its end-of-run sample sent): close the session.
    RunEnded,
    /// SIGTERM or SIGINT: close the session.
    Stopped,
}

/// The plant's side of one run for a model of the user's own.
pub struct PlantSession {
    args: ProcessArgs,
    lp: PlantLoop,
    ports: PlantPorts,
    latest: Rc<RefCell<Latest>>,
    /// The rig's actuators and sensors around the model.
    chain: SignalChain,
    /// The model's last valid outputs, before the sensors.
    raw_outputs: Vec<f64>,
    /// The tick whose inputs were handed out: whether its command was held, when, and what the actuators did.
    pending: Option<(bool, u64, ActuatorFlags)>,
    /// A restarted plant: its predecessor's checkpoint, until the model says whether it restored it.
    offered: Option<SavedPlant>,
    /// Why a restarted plant flies again from tick 0, said when it starts.
    from_start: Option<String>,
    started: bool,
    refused_outputs: u64,
    ended: Option<String>,
}

impl PlantSession {
    /// Open the run as its plant, announce `plant`, and wait (up to `--startup-timeout-s`) for the controller and
    /// the logger. A second plant for the run, an announcement that breaks the rules and peers that never come are
    /// errors naming the problem.
    pub fn open(args: ProcessArgs, scenario: Scenario, plant: &PlantSignals) -> Result<Self, SessionError> {
        Self::open_at(args, scenario, plant, plant.hold())
    }

    /// [`Self::open`], with the actuators holding `initial_inputs` (one per input) until the first command, not
    /// the hold values: where a model's actuators start (an FMU reports them in its outputs at t = 0).
    pub fn open_at(
        args: ProcessArgs,
        scenario: Scenario,
        plant: &PlantSignals,
        initial_inputs: Vec<f64>,
    ) -> Result<Self, SessionError> {
        signals::install_termination_flag();
        let info = PlantInfo::new(plant).map_err(|e| SessionError::Plant(format!("the plant's announcement: {e}")))?;
        if initial_inputs.len() != plant.inputs.len() || initial_inputs.iter().any(|v| !v.is_finite()) {
            return Err(SessionError::Usage(format!(
                "{} initial inputs given (all finite); the plant announced {}",
                initial_inputs.len(),
                plant.inputs.len()
            )));
        }
        let chain = SignalChain::new(&scenario, plant, &initial_inputs)
            .map_err(|(key, problem)| SessionError::Setup(format!("the scenario: `{key}`: {problem}")))?;
        let latest = Rc::new(RefCell::new(Latest {
            outputs: vec![0.0; plant.outputs.len()],
            tick: 0,
            t_s: 0.0,
            saved: None,
            positions: initial_inputs.clone(),
        }));
        let model = ExternalModel { signals: plant.clone(), latest: latest.clone(), initial_inputs };
        let lp =
            PlantLoop::setup(&args, scenario, Box::new(model)).map_err(|e| SessionError::Setup(format!("{e:#}")))?;
        let ports = PlantPorts::connect(&args, &info).map_err(|e| {
            match e.chain().any(|c| matches!(c.downcast_ref(), Some(IpcError::PublisherAlreadyActive { .. }))) {
                true => SessionError::Plant(format!("refusing to start a second plant: run `{}` has one", args.run_id)),
                false => SessionError::Setup(format!("{e:#}")),
            }
        })?;
        let ready =
            ports.wait_for_peers(args.options.startup_timeout_s).map_err(|e| SessionError::Setup(e.to_string()))?;
        let (offered, from_start) = match args.resume {
            true => read_checkpoint(&lp, plant)?,
            false => (None, None),
        };
        let raw_outputs = vec![0.0; plant.outputs.len()];
        let mut session = Self {
            offered,
            from_start,
            args,
            lp,
            ports,
            latest,
            chain,
            raw_outputs,
            pending: None,
            started: false,
            refused_outputs: 0,
            ended: None,
        };
        if !ready {
            session.ended = Some("terminated by signal".into());
        }
        Ok(session)
    }

    /// Put an event in the run's log (`events.jsonl`, the report's event list) at the tick being flown.
    pub fn event(&self, kind: &str, detail: String) {
        self.lp.event(kind, detail);
    }

    /// The run's step, s.
    pub fn dt_s(&self) -> f64 {
        self.lp.scenario().timing.dt_s
    }

    /// The scenario the run flies.
    pub fn scenario(&self) -> &Scenario {
        self.lp.scenario()
    }

    /// Hand in the model's outputs at this tick (one per announced output); get back the inputs to step it with
    /// over the next period, or the end of the run. In realtime the call returns when the tick is due and its
    /// command is in (or missed); in lockstep as soon as the controller has answered.
    pub fn tick(&mut self, outputs: &[f64]) -> Result<PlantTick<'_>, SessionError> {
        if self.ended.is_some() {
            return Ok(PlantTick::Stopped);
        }
        let expected = self.latest.borrow().outputs.len();
        if outputs.len() != expected {
            return Err(SessionError::Usage(format!(
                "{} outputs given; the plant announced {expected}",
                outputs.len()
            )));
        }
        self.take_outputs(outputs);
        let fail = |e: anyhow::Error| SessionError::Setup(format!("{e:#}"));
        match self.pending.take() {
            Some((held, handed_out_ns, actuators)) => {
                let step_exec_ns = monotonic_ns().saturating_sub(handed_out_ns);
                self.lp.end_tick(&self.ports, Ok(actuators), step_exec_ns, held);
                // The end-of-run sample repeats the last tick with these outputs (the positions its command set).
                // Only then: the sensors measure once per tick, so their noise is a function of the tick alone
                // (as the in-process loop draws it).
                if self.lp.sim_tick() >= self.lp.scenario().timing.ticks() {
                    self.set_tick(self.lp.sim_tick());
                }
                if let Some(ended) = self.lp.next_tick(&mut self.ports).map_err(fail)? {
                    self.ended = Some(ended);
                    let _ = self.ports.announce_finished();
                    return Ok(PlantTick::RunEnded);
                }
            }
            None if !self.started => {
                self.started = true;
                if self.offered.is_some() {
                    self.checkpoint_used(Err("the model never said whether it restored it".into()));
                }
                self.lp.start_clock();
                if let Some(why) = self.from_start.take() {
                    eprintln!("silrig-plant: warning: --resume: {why}");
                    self.lp.event("plant-restarted-from-start", why);
                }
            }
            None => {}
        }
        if signals::termination_requested() {
            self.ended = Some("terminated by signal".into());
            return Ok(PlantTick::Stopped);
        }
        self.set_tick(self.lp.sim_tick());
        let held = self.lp.begin_tick(&mut self.ports).map_err(fail)?;
        let t_s = self.latest.borrow().t_s;
        let hits = self.chain.actuate(t_s, self.lp.applied());
        let actuators = ActuatorFlags { saturated: hits.position, rate_limited: hits.rate };
        self.latest.borrow_mut().positions.copy_from_slice(self.chain.positions());
        self.pending = Some((held, monotonic_ns(), actuators));
        Ok(PlantTick::Inputs(self.chain.positions()))
    }

    /// A restarted plant: the model's text its predecessor saved, to restore before the first `tick` (then say so
    /// with [`Self::checkpoint_used`]).
    pub fn restored_checkpoint(&self) -> Option<&str> {
        self.offered.as_ref().map(|o| o.model.as_str())
    }

    /// Say whether the model restored [`Self::restored_checkpoint`] (`Err`: why not). Restored, the flight goes on
    /// from its tick with the actuators where they were; otherwise it flies again from tick 0.
    pub fn checkpoint_used(&mut self, outcome: Result<(), String>) {
        let Some(offer) = self.offered.take() else { return };
        match outcome {
            Ok(()) => {
                self.latest.borrow_mut().tick = offer.tick;
                self.chain.set_positions(&offer.actuator_positions);
                let again = self.lp.flown_again(offer.tick);
                let detail = format!("resumed at tick {} from its checkpoint{again}", offer.tick);
                self.lp.event_at(offer.tick, "plant-resumed", detail);
            }
            Err(why) => {
                let again = self.lp.flown_again(0);
                self.from_start =
                    Some(format!("the model did not restore its checkpoint ({why}): flying again from tick 0{again}"))
            }
        }
    }

    /// Whether the model should save its state now, after stepping with the inputs just handed out (every few
    /// ticks of a realtime run): hand it to [`Self::save_checkpoint`].
    pub fn checkpoint_due(&self) -> bool {
        self.lp.is_realtime()
            && self.pending.is_some()
            && (self.lp.sim_tick() + 1).is_multiple_of(super::plant::CHECKPOINT_EVERY_TICKS)
    }

    /// Keep the model's state, as text, for a restarted plant: the state after the step just taken.
    pub fn save_checkpoint(&mut self, text: &str) {
        let tick = self.lp.sim_tick() + 1;
        self.latest.borrow_mut().saved = Some((tick, text.to_string()));
    }

    /// Keep the outputs for the tick, or, with NaN or infinity among them, the last valid ones (refused, counted,
    /// the first of a series said in an event).
    fn take_outputs(&mut self, outputs: &[f64]) {
        match outputs.iter().position(|v| !v.is_finite()) {
            None => {
                self.raw_outputs.copy_from_slice(outputs);
                if self.refused_outputs > 0 {
                    let detail = format!("valid outputs again after {} refused", self.refused_outputs);
                    self.lp.event("outputs-accepted", detail);
                    self.refused_outputs = 0;
                    self.lp.outputs_held = false;
                }
            }
            Some(k) => {
                if self.refused_outputs == 0 {
                    let name = &self.lp.signals().outputs[k].name;
                    let detail =
                        format!("output {name} is {}: refused, the last valid outputs are published", outputs[k]);
                    self.lp.event("outputs-refused", detail);
                }
                self.refused_outputs += 1;
                self.lp.count("outputs_refused", 1);
                self.lp.outputs_held = true;
            }
        }
    }

    /// The tick the outputs belong to, and the outputs as the sensors measure them then.
    fn set_tick(&mut self, tick: u64) {
        let mut latest = self.latest.borrow_mut();
        latest.tick = tick;
        latest.t_s = tick as f64 * self.lp.scenario().timing.dt_s;
        latest.outputs.copy_from_slice(&self.raw_outputs);
        let t_s = latest.t_s;
        self.chain.measure(t_s, &mut latest.outputs);
    }

    /// Write the plant's report and close the session; `error` is why the model gave up, if it did.
    pub fn finish(mut self, error: Option<&str>) -> anyhow::Result<ProcessReport> {
        let ended = match (error, self.ended.take()) {
            (Some(e), _) => format!("error: {e}"),
            (None, Some(ended)) => ended,
            (None, None) => "closed by the plant".into(),
        };
        self.lp.finish(&self.args, &self.ports, ended)
    }
}
