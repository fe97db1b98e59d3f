//! The plant's side of a run for a vehicle model of the user's own (Python on JSBSim, C, an FMU's wrapper):
//! [`PlantSession`] opens the run as its plant and announces the model's signals, then each [`PlantSession::tick`]
//! takes the model's outputs for the tick and gives back the inputs to step it with. Everything around the model
//! is the rig's plant loop ([`super::plant::PlantLoop`], the same as for the F-16): the clock (realtime sleeps or
//! lockstep), the commands and their misses, the watchdog and the failsafe (the announced hold values), the
//! in-loop faults, the flags and the timing report. `libsilrig_client.so` exports it to C and Python.
//!
//! The model's step time is what passes between handing out the inputs and the next `tick`; outputs with NaN or
//! infinity are refused (counted, the first said in an event) and the last valid ones are published instead.
//! Not yet: checkpoints of an external model (a restarted one flies again from tick 0, and the logger marks the
//! join), and a model leaving its envelope other than by closing the session with an error.

use super::ProcessArgs;
use super::plant::{PlantLoop, PlantPorts};
use super::plant_model::{ActuatorFlags, PlantModel};
use super::report::ProcessReport;
use super::session::SessionError;
use super::signals;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::IpcError;
use silrig_wire::wire::PlantInfo;
use std::cell::RefCell;
use std::rc::Rc;

/// What the session and the loop share of the user's model: its outputs for the tick being flown.
#[derive(Debug)]
struct Latest {
    outputs: Vec<f64>,
    tick: u64,
    t_s: f64,
}

/// The user's model as the plant loop sees it: the outputs the session was given; stepping happens outside.
struct ExternalModel {
    signals: PlantSignals,
    latest: Rc<RefCell<Latest>>,
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
        self.signals.hold()
    }

    fn step(&mut self, _inputs: &[f64], _last: bool) -> Result<ActuatorFlags, String> {
        Ok(ActuatorFlags::default())
    }

    fn checkpoint(&self) -> Option<String> {
        None
    }

    fn restore(&mut self, _saved: &str, _ticks: u64) -> Result<u64, String> {
        Err("a plant of your own keeps no checkpoint yet".into())
    }
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
    /// The tick whose inputs were handed out, whether its command was held, and when.
    pending: Option<(bool, u64)>,
    started: bool,
    refused_outputs: u64,
    ended: Option<String>,
}

impl PlantSession {
    /// Open the run as its plant, announce `plant`, and wait (up to `--startup-timeout-s`) for the controller and
    /// the logger. A second plant for the run, an announcement that breaks the rules and peers that never come are
    /// errors naming the problem.
    pub fn open(args: ProcessArgs, scenario: Scenario, plant: &PlantSignals) -> Result<Self, SessionError> {
        signals::install_termination_flag();
        let info = PlantInfo::new(plant).map_err(|e| SessionError::Plant(format!("the plant's announcement: {e}")))?;
        let latest = Rc::new(RefCell::new(Latest { outputs: vec![0.0; plant.outputs.len()], tick: 0, t_s: 0.0 }));
        let model = ExternalModel { signals: plant.clone(), latest: latest.clone() };
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
        let mut session =
            Self { args, lp, ports, latest, pending: None, started: false, refused_outputs: 0, ended: None };
        if !ready {
            session.ended = Some("terminated by signal".into());
        }
        Ok(session)
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
            Some((held, handed_out_ns)) => {
                let step_exec_ns = monotonic_ns().saturating_sub(handed_out_ns);
                self.lp.end_tick(&self.ports, Ok(ActuatorFlags::default()), step_exec_ns, held);
                // The end-of-run sample repeats the last tick with these outputs (the positions its command set).
                self.set_tick(self.lp.sim_tick());
                if let Some(ended) = self.lp.next_tick(&mut self.ports).map_err(fail)? {
                    self.ended = Some(ended);
                    let _ = self.ports.announce_finished();
                    return Ok(PlantTick::RunEnded);
                }
            }
            None if !self.started => {
                self.started = true;
                self.lp.start_clock();
            }
            None => {}
        }
        if signals::termination_requested() {
            self.ended = Some("terminated by signal".into());
            return Ok(PlantTick::Stopped);
        }
        self.set_tick(self.lp.sim_tick());
        let held = self.lp.begin_tick(&mut self.ports).map_err(fail)?;
        self.pending = Some((held, monotonic_ns()));
        Ok(PlantTick::Inputs(self.lp.applied()))
    }

    /// Keep the outputs for the tick, or, with NaN or infinity among them, the last valid ones (refused, counted,
    /// the first of a series said in an event).
    fn take_outputs(&mut self, outputs: &[f64]) {
        match outputs.iter().position(|v| !v.is_finite()) {
            None => {
                self.latest.borrow_mut().outputs.copy_from_slice(outputs);
                if self.refused_outputs > 0 {
                    let detail = format!("valid outputs again after {} refused", self.refused_outputs);
                    self.lp.event("outputs-accepted", detail);
                    self.refused_outputs = 0;
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
            }
        }
    }

    fn set_tick(&self, tick: u64) {
        let mut latest = self.latest.borrow_mut();
        latest.tick = tick;
        latest.t_s = tick as f64 * self.lp.scenario().timing.dt_s;
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
