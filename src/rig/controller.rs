//! `silrig-controller` and the session every controller runs in. A [`Controller`] is the control law alone (one
//! step per plant sample, its diagnostics' names, optional checkpoint and restore, as copper's `Freezable`);
//! [`serve`] is everything around it: the streams, the announcement of the diagnostics, the WaitSet loop woken by
//! each plant sample (with a deadline that flags the plant stale), the in-loop faults, checkpoint files, the
//! bumpless blend and the report. Our controller is [`AttitudeLaw`], the same [`crate::control::AttitudeController`]
//! as `silrig sim`, served by [`run_controller`].
//!
//! A controller that joins a plant already flying (a restart) blends its output from the surfaces' current
//! positions to its own command over [`BUMPLESS_BLEND_S`], so the switch from the plant's held or failsafe command
//! causes no bump; the blend lives here, in the session, so every controller gets it. With a fault plan the session
//! saves the controller's checkpoint every few ticks; restarted with `--resume`, it restores it, so ours need not
//! re-learn its weights. While the plant is silent it idles and says so once.
//!
//! Phases: [`ControllerLoop::setup`] (scenario, law, recorder), [`ControllerPorts::connect`] (streams and the
//! announcement), the event loop (`on_samples` per wake-up, `on_plant_silent`
//! per missed deadline), and [`ControllerLoop::finish`].

use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::plant::snapshot;
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::{ProcessArgs, RigMode};
use crate::clock::monotonic_ns;
use crate::control::AttitudeController;
use crate::ipc::{self, LoopEnd, Received, StreamPublisher, StreamService, StreamSubscriber};
use crate::scenario::Scenario;
use crate::sim::{measurement, setpoint_rad, write_attitude_diagnostics};
use crate::topology::{Role, Stream};
use crate::wire::{CommandSample, ControllerInfo, MAX_DIAGNOSTICS, PlantSample};
use anyhow::Context;
use iceoryx2::prelude::CallbackProgression;
use std::path::PathBuf;
use std::time::Duration;

/// How long a controller joining a running plant blends from the current surface positions to its command, s.
pub const BUMPLESS_BLEND_S: f64 = 0.5;

/// With a fault plan, the controller saves its weights every this many ticks.
const CHECKPOINT_EVERY_TICKS: u64 = 10;

const IPC_PLANT_TO_CONTROLLER: usize = 0;
const COMPUTE: usize = 1;

/// What a controller commands for one plant sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ControlCommand {
    /// Surfaces, deg: aileron, elevator, rudder.
    pub surface_cmd_deg: [f64; 3],
    /// Throttle, 0..1.
    pub throttle_cmd: f64,
}

/// A controller the rig can fly. The session around it ([`serve`]) owns everything else: the transport, the
/// clock, the in-loop faults, the bumpless blend when it joins a flying plant, checkpoint files, and the report.
pub trait Controller {
    /// Names of the diagnostics [`Controller::step`] reports, in order (announced once per epoch; at most
    /// [`MAX_DIAGNOSTICS`], see [`ControllerInfo::new`] for the characters allowed).
    fn diagnostic_names(&self) -> Vec<String>;

    /// The command for one plant sample; write the diagnostics of this step into `diagnostics` (one per name).
    fn step(&mut self, sample: &PlantSample, dt_s: f64, diagnostics: &mut [f64]) -> ControlCommand;

    /// The state a restarted controller should resume from, as text (`None`: nothing worth saving).
    fn checkpoint(&self) -> Option<String> {
        None
    }

    /// Resume from what [`Controller::checkpoint`] saved; false leaves the controller as it was.
    fn restore(&mut self, _saved: &str) -> bool {
        false
    }
}

/// The paper's adaptive SMC/RBF controller behind the [`Controller`] trait; its checkpoint is its RBF weights.
pub struct AttitudeLaw {
    controller: AttitudeController,
    setpoint: [f64; 3],
}

impl AttitudeLaw {
    /// The scenario's controller, with zero weights.
    pub fn new(scenario: &Scenario) -> Self {
        let tables = crate::plant::F16Model::new(scenario.plant.xcg).tables();
        Self {
            controller: AttitudeController::new(scenario.controller.clone(), tables),
            setpoint: setpoint_rad(scenario),
        }
    }
}

impl Controller for AttitudeLaw {
    fn diagnostic_names(&self) -> Vec<String> {
        crate::trace::attitude_diagnostic_names(self.controller.gains().rbf.nodes())
    }

    fn step(&mut self, sample: &PlantSample, dt_s: f64, diagnostics: &mut [f64]) -> ControlCommand {
        let (command, diag) = self.controller.step(&measurement(&snapshot(sample)), &self.setpoint, dt_s);
        write_attitude_diagnostics(diagnostics, &diag, &self.controller);
        ControlCommand {
            surface_cmd_deg: [command.aileron_deg, command.elevator_deg, command.rudder_deg],
            throttle_cmd: sample.throttle,
        }
    }

    fn checkpoint(&self) -> Option<String> {
        let weights: [&Vec<f64>; 3] = std::array::from_fn(|c| &self.controller.networks()[c].weights);
        serde_json::to_string(&weights).ok()
    }

    fn restore(&mut self, saved: &str) -> bool {
        serde_json::from_str::<[Vec<f64>; 3]>(saved).is_ok_and(|w| self.controller.set_weights(&w))
    }
}

/// The controller's side of the run's streams.
pub struct ControllerPorts {
    plant_stream: StreamService<PlantSample>,
    samples: StreamSubscriber<PlantSample>,
    outputs: ControllerOutputs,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl ControllerPorts {
    /// Open the controller's streams: read plant samples, announce the names of its diagnostics, then publish
    /// commands. The announcement goes out before the command publisher exists, which is what the plant waits for,
    /// and again with the first command (iceoryx2 hands a late subscriber the last announcement only on a later
    /// send, and the logger's subscriber may come after this one), so the logger knows the trace's columns before
    /// its first row. A run that has a controller refuses this one before it announces anything.
    pub fn connect(args: &ProcessArgs, diagnostic_names: &[String]) -> anyhow::Result<Self> {
        let info = ControllerInfo::new(diagnostic_names).map_err(|e| anyhow::anyhow!("announcing diagnostics: {e}"))?;
        let node = ipc::create_node(&args.run_id, Role::Controller.label())?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let info_stream = ipc::open_stream::<ControllerInfo>(&node, Stream::ControllerInfo)?;
        let second = "refusing to start a second controller for this run";
        let mut announcer = info_stream.publisher().context(second)?;
        let samples = plant_stream.subscriber(Stream::Plant.queue_depth(Role::Controller))?;
        announcer.send(0, &info)?;
        let commands = command_stream.publisher().context(second)?;
        Ok(Self { plant_stream, samples, outputs: ControllerOutputs { commands, announcer, info }, _node: node })
    }
}

/// What the controller publishes: its announcement and its commands.
struct ControllerOutputs {
    commands: StreamPublisher<CommandSample>,
    // Held for the run, so a second controller is refused before it could announce other names.
    announcer: StreamPublisher<ControllerInfo>,
    info: ControllerInfo,
}

/// Everything the event loop keeps between wake-ups.
pub struct ControllerLoop {
    scenario: Scenario,
    scheduling: String,
    law: Box<dyn Controller>,
    diagnostics_len: usize,
    rec: Recorder,
    events: EventLog,
    loop_faults: LoopFaults,
    checkpoint_path: PathBuf,
    save_weights: bool,
    resumed: bool,
    blend_ticks: u64,
    /// First tick of the bumpless blend: set when this controller's first sample is not the plant's tick 0.
    blend: Option<u64>,
    plant_stale: bool,
    /// (epoch, tick) of the last sample acted on.
    last_tick: Option<(u64, u64)>,
    error: Option<anyhow::Error>,
}

impl ControllerLoop {
    /// Phase 1: the scenario, the control law (with the state a predecessor saved, on `--resume`), the recorder.
    pub fn setup(args: &ProcessArgs, scenario: Scenario, law: Box<dyn Controller>) -> anyhow::Result<Self> {
        let diagnostics_len = law.diagnostic_names().len();
        anyhow::ensure!(
            diagnostics_len <= MAX_DIAGNOSTICS,
            "a command carries at most {MAX_DIAGNOSTICS} diagnostics; the controller reports {diagnostics_len}"
        );
        let scheduling = request_scheduling(Role::Controller, args.mode == RigMode::Realtime);
        let mut rec = Recorder::new(
            Role::Controller.label(),
            &[
                ("ipc_plant_to_controller", "plant publish to receive at the controller"),
                ("compute", "controller step execution time"),
            ],
        );
        rec.declare(&[
            "commands_sent",
            "samples_skipped",
            "samples_invalid",
            "plant_stale_deadlines",
            "errors",
            "commands_dropped",
        ]);
        let dt = scenario.timing.dt_s;
        let events = EventLog::new(&args.out, Role::Controller.label());
        let mut this = Self {
            law,
            diagnostics_len,
            loop_faults: LoopFaults::new(&scenario.faults, Role::Controller, dt, scenario.seed, events.clone()),
            events,
            rec,
            checkpoint_path: args.out.join("controller.checkpoint.json"),
            save_weights: !scenario.faults.is_empty() && args.mode == RigMode::Realtime,
            resumed: args.resume,
            blend_ticks: (BUMPLESS_BLEND_S / dt).round().max(1.0) as u64,
            blend: None,
            plant_stale: false,
            last_tick: None,
            error: None,
            scheduling,
            scenario,
        };
        if args.resume {
            this.resume();
        }
        Ok(this)
    }

    fn resume(&mut self) {
        let loaded = std::fs::read_to_string(&self.checkpoint_path).is_ok_and(|t| self.law.restore(&t));
        if !loaded {
            eprintln!(
                "silrig-controller: warning: --resume without a usable checkpoint in {}; starting fresh",
                self.checkpoint_path.display()
            );
        }
    }

    /// Phase 3: wait for plant samples until SIGTERM (or an error); returns how the loop ended.
    pub fn serve(&mut self, args: &ProcessArgs, ports: &mut ControllerPorts) -> anyhow::Result<ipc::LoopExit> {
        let waitset = ipc::rig_waitset()?;
        let period_ns = self.scenario.timing.period_ns();
        let stale_after = Duration::from_nanos(period_ns * u64::from(args.options.stale_after_periods.max(1)));
        let guard = waitset
            .attach_deadline(ports.samples.listener(), stale_after)
            .map_err(|e| anyhow::anyhow!("attaching the plant stream to the WaitSet: {e:?}"))?;
        Ok(ipc::run_waitset(&waitset, |id| {
            if id.has_event_from(&guard) {
                return self.on_samples(&ports.samples, &mut ports.outputs);
            }
            if id.has_missed_deadline(&guard) {
                self.on_plant_silent(&ports.plant_stream, stale_after);
            }
            CallbackProgression::Continue
        })?)
    }

    /// Samples arrived: act on the newest valid one.
    fn on_samples(
        &mut self,
        samples: &StreamSubscriber<PlantSample>,
        outputs: &mut ControllerOutputs,
    ) -> CallbackProgression {
        let mut newest: Option<Received<PlantSample>> = None;
        let mut fresh = 0u64;
        let drained = samples.drain(|r| {
            if r.invalid.is_some() {
                self.rec.count("samples_invalid", 1);
            } else {
                fresh += 1;
                newest = Some(*r);
            }
        });
        if let Err(e) = drained {
            self.error = Some(e.into());
            return CallbackProgression::Stop;
        }
        // After a stall several samples wait; acting on stale ones would only delay the newest.
        self.rec.count("samples_skipped", fresh.saturating_sub(1));
        let Some(r) = newest else { return CallbackProgression::Continue };
        let h = r.sample.header;
        if self.last_tick.is_some_and(|(epoch, tick)| epoch == h.epoch && tick >= h.tick) {
            return CallbackProgression::Continue;
        }
        if self.last_tick.is_none()
            && let Err(e) = outputs.announcer.send(h.tick, &outputs.info)
        {
            self.error = Some(e.into());
            return CallbackProgression::Stop;
        }
        self.note_plant(h.epoch, h.tick);
        self.rec.record(IPC_PLANT_TO_CONTROLLER, r.age_ns() as i64);
        let command = self.compute(&r.sample);
        if self.save_weights && h.tick.is_multiple_of(CHECKPOINT_EVERY_TICKS) {
            self.save_checkpoint();
        }
        self.publish(&mut outputs.commands, h.tick, &command);
        CallbackProgression::Continue
    }

    /// What this sample says about the plant: a first sample past tick 0 (we joined a flying plant: blend), a new
    /// plant epoch (it restarted), samples back after silence.
    fn note_plant(&mut self, epoch: u64, tick: u64) {
        match self.last_tick {
            None if tick > 0 => {
                self.blend = Some(tick);
                let state = if self.resumed { "checkpointed" } else { "fresh" };
                let detail =
                    format!("plant already at tick {tick}: {state} state, {BUMPLESS_BLEND_S} s bumpless blend");
                self.events.emit(Some(tick), "controller-joined", detail);
            }
            Some((last_epoch, _)) if last_epoch != epoch => {
                self.events.emit(Some(tick), "plant-restarted", "samples from a new plant epoch");
            }
            _ => {}
        }
        if self.plant_stale {
            self.plant_stale = false;
            self.events.emit(Some(tick), "plant-recovered", "samples resumed");
        }
        self.last_tick = Some((epoch, tick));
    }

    /// The control law on one sample, blended while joining, as a command sample with its diagnostics.
    fn compute(&mut self, sample: &PlantSample) -> CommandSample {
        let t0 = monotonic_ns();
        let tick = sample.header.tick;
        let mut out = CommandSample { answers_tick: tick, ..CommandSample::zeroed() };
        let dt = self.scenario.timing.dt_s;
        let mut command = self.law.step(sample, dt, &mut out.diagnostics[..self.diagnostics_len]);
        if let Some(start) = self.blend {
            let k = ((tick - start + 1) as f64 / self.blend_ticks as f64).min(1.0);
            for (cmd, now) in command.surface_cmd_deg.iter_mut().zip(sample.surfaces_deg) {
                *cmd = now + k * (*cmd - now);
            }
            if k >= 1.0 {
                self.blend = None;
            }
        }
        out.compute_ns = monotonic_ns() - t0;
        self.rec.record(COMPUTE, out.compute_ns as i64);
        out.surface_cmd_deg = command.surface_cmd_deg;
        out.throttle_cmd = command.throttle_cmd;
        out.diagnostics_len = self.diagnostics_len as u32;
        out
    }

    fn save_checkpoint(&self) {
        let Some(text) = self.law.checkpoint() else { return };
        if let Err(e) = super::write_atomically(&self.checkpoint_path, &text) {
            eprintln!("silrig-controller: cannot save a checkpoint: {e}");
        }
    }

    /// Send the command, after any delay fault, unless a drop fault swallows it.
    fn publish(&mut self, publisher: &mut StreamPublisher<CommandSample>, tick: u64, command: &CommandSample) {
        let effect = if self.loop_faults.is_empty() { Default::default() } else { self.loop_faults.at(tick) };
        if effect.sleep_ns > 0 {
            std::thread::sleep(Duration::from_nanos(effect.sleep_ns));
        }
        if effect.drop {
            self.rec.count("commands_dropped", 1);
            return;
        }
        match publisher.send(tick, command) {
            Ok(_) => self.rec.count("commands_sent", 1),
            Err(e) => {
                // A NaN command is refused by the transport: say so and keep running on the next sample.
                eprintln!("silrig-controller: tick {tick}: {e}");
                self.rec.count("errors", 1);
            }
        }
    }

    /// No sample within the deadline: once the plant has been seen (waiting for it to start is not staleness),
    /// flag it stale once, and clean up its node if it died so a restarted plant can take its place.
    fn on_plant_silent(&mut self, plant_stream: &StreamService<PlantSample>, stale_after: Duration) {
        if self.last_tick.is_none() {
            return;
        }
        self.rec.count("plant_stale_deadlines", 1);
        if !self.plant_stale {
            self.plant_stale = true;
            let tick = self.last_tick.map(|(_, t)| t);
            self.events.emit(tick, "plant-stale", format!("no plant sample for {stale_after:?}; idling"));
        }
        let _ = plant_stream.try_cleanup_dead_nodes();
    }

    /// Phase 4: the report; an error that stopped the loop is returned after the report is written.
    pub fn finish(
        mut self,
        args: &ProcessArgs,
        ports: &ControllerPorts,
        exit: ipc::LoopExit,
    ) -> anyhow::Result<ProcessReport> {
        let stats = ports.samples.stats();
        self.rec.count("plant_samples_lost", stats.lost);
        self.rec.count("plant_restarts", stats.publisher_restarts);
        let ended = match (&self.error, exit.end) {
            (Some(e), _) => format!("error: {e}"),
            (None, LoopEnd::TerminationRequest) => "terminated by signal".into(),
            (None, LoopEnd::Stopped) => "completed".into(),
        };
        self.rec.count("interrupted_waits", exit.interrupts);
        let meta = ReportMeta::new(args, &self.scenario.name, self.scheduling, ended);
        let report = self.rec.finish(meta, &args.out)?;
        match self.error {
            Some(e) => Err(e),
            None => Ok(report),
        }
    }
}

/// Serve `law` as the run's controller until SIGTERM and write the report: the session every controller runs in.
pub fn serve(args: &ProcessArgs, scenario: Scenario, law: Box<dyn Controller>) -> anyhow::Result<ProcessReport> {
    let names = law.diagnostic_names();
    let mut controller = ControllerLoop::setup(args, scenario, law)?;
    let mut ports = ControllerPorts::connect(args, &names)?;
    let exit = controller.serve(args, &mut ports)?;
    controller.finish(args, &ports, exit)
}

/// Run our controller (the paper's, from the scenario) until SIGTERM and write its report.
pub fn run_controller(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    let law = AttitudeLaw::new(&scenario);
    serve(args, scenario, Box::new(law))
}
