//! The controller's side of a run, for any controller: [`ControllerSession`] opens the run's streams, announces the
//! controller's diagnostics, waits for the plant's announcement of its signals ([`ControllerSession::plant`]: what
//! the controller finds its outputs and inputs in, by name), hands out plant samples one at a time
//! ([`ControllerSession::next_sample`]) and takes one command in answer to each ([`ControllerSession::send`]).
//! Everything a controller should not have to write lives here: header stamps, validation (a NaN or out-of-range
//! command is refused, never sent), the in-loop faults of the plan (delay, jitter, drop), the bumpless blend after
//! a restart, checkpoint files, staleness of the plant, stop requests (SIGTERM/SIGINT, the end of the run) and the
//! timing report. `silrig-controller` is one user of it ([`super::controller::serve`]); the C ABI of
//! `libsilrig_client.so` (`src/client/`) is another, through which controllers in C, C++, Python and anything with
//! a C FFI fly.
//!
//! This file opens the session and answers samples (blend, checks, faults, publishing) and closes it;
//! `session/samples.rs` is the plant's side as the session sees it (its announcement, the samples, its silence),
//! `session/errors.rs` what a call can end in ([`SessionError`], the C ABI's [`Status`] codes).
//!
//! A session installs a SIGTERM/SIGINT flag handler when it opens (so a stop request ends the loop with a report
//! instead of killing the process) and waits on the plant stream's listener, not on a WaitSet, so iceoryx2 never
//! takes the process's signals.

mod errors;
mod samples;

pub use errors::{SessionError, Status, check_client_layout};

use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::{ProcessArgs, RigMode, signals};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::{self, RunId, StreamPublisher, StreamService, StreamSubscriber};
use silrig_wire::topology::Stream;
use silrig_wire::wire::{
    self, CommandSample, ControllerInfo, FLAG_COMMAND_REFUSED, MAX_INPUTS, PlantInfo, PlantSample, WireSample,
};
use std::time::Duration;

/// How long a controller joining a running plant blends from the current actuator positions to its command, s.
pub const BUMPLESS_BLEND_S: f64 = 0.5;

/// Where a controller's state came from when it started.
#[derive(Debug, Clone, PartialEq)]
enum Resumed {
    /// No checkpoint was offered.
    Fresh,
    /// It resumed from the checkpoint its predecessor saved.
    Checkpoint,
    /// It was offered one and refused it, for this reason.
    Rejected(String),
    /// It was offered one and never said ([`ControllerSession::checkpoint_used`]).
    Unconfirmed,
}

/// With a fault plan, the session asks for a checkpoint every this many ticks.
const CHECKPOINT_EVERY_TICKS: u64 = 10;

/// Realtime: how long before the plant's next deadline the session starts looking for its sample, so that its own
/// wake-up (late by about as much as the plant's) is over when the sample comes.
const SAMPLE_LOOK_LEAD_NS: u64 = 50_000;

const IPC_PLANT_TO_CONTROLLER: usize = 0;
const COMPUTE: usize = 1;

/// Why a session stops handing out samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// SIGTERM or SIGINT.
    TerminationRequested,
    /// The plant has flown the whole scenario.
    RunEnded,
}

/// What [`ControllerSession::next_sample`] gives.
// The sample is handed over by value once per tick: boxing it would allocate in the loop.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Next {
    /// A plant sample to answer with one [`ControllerSession::send`].
    Sample(PlantSample),
    /// No more samples: finish the session.
    Stop(StopReason),
}

/// The controller's report: its timing figures (in the order of the indices above) and counters, its live status
/// published under `run_id`.
fn controller_recorder(run_id: &RunId) -> Recorder {
    let mut rec = Recorder::new(
        Role::Controller.label(),
        &[
            ("ipc_plant_to_controller", "plant publish to receive at the controller"),
            ("compute", "controller step execution time: sample handed out to command given"),
        ],
    );
    rec.declare(&[
        "commands_sent",
        "commands_refused",
        "samples_skipped",
        "samples_invalid",
        "plant_stale_deadlines",
        "errors",
        "commands_dropped",
        "samples_unanswered",
        "interrupted_waits",
        "samples_without_wakeup",
    ]);
    rec.start_status(run_id);
    rec
}

/// What a predecessor saved at `path` for a restarted controller (`--resume`); without it, the controller starts
/// fresh and says so.
fn read_restored(path: &std::path::Path) -> Option<String> {
    let saved = std::fs::read_to_string(path).ok();
    if saved.is_none() {
        eprintln!("silrig controller: warning: --resume without a checkpoint in {}; starting fresh", path.display());
    }
    saved
}

/// The sample being answered.
#[derive(Debug, Clone, Copy)]
struct Pending {
    tick: u64,
    /// Per input, the position its actuator holds now (its held output), or NaN where the plant reports none.
    held: [f64; MAX_INPUTS],
    delivered_ns: u64,
}

/// The controller's side of one run (see the module doc). Create it on the thread that uses it: its ports are not
/// `Send`.
pub struct ControllerSession {
    args: ProcessArgs,
    scenario: Scenario,
    plant_stream: StreamService<PlantSample>,
    samples: StreamSubscriber<PlantSample>,
    plant_info: StreamSubscriber<PlantInfo>,
    /// What the plant announced, once it has ([`ControllerSession::plant`]).
    plant: Option<PlantSignals>,
    commands: StreamPublisher<CommandSample>,
    // Held for the run, so a second controller is refused before it could announce other names.
    announcer: StreamPublisher<ControllerInfo>,
    info: ControllerInfo,
    diagnostics_len: usize,
    scheduling: String,
    rec: Recorder,
    events: EventLog,
    loop_faults: LoopFaults,
    /// Realtime only (lockstep never restarts a controller).
    checkpoints: Option<super::CheckpointWriter>,
    save_checkpoints: bool,
    restored: Option<String>,
    /// What the controller said it did with `restored`.
    resumed: Resumed,
    blend_ticks: u64,
    /// First tick of the bumpless blend: set when the first sample is not the plant's tick 0.
    blend: Option<u64>,
    plant_stale: bool,
    stale_after: Duration,
    /// Realtime: when the plant's next sample is due (the deadline of the tick after the last one taken, on this
    /// host's clock) and how long after it to keep looking before blocking; see [`Self::look_near_deadline`].
    next_deadline_ns: Option<u64>,
    sample_poll_ns: u64,
    /// Lockstep: looks for each sample for a while before blocking ([`Self::look_lockstep`]).
    lockstep: bool,
    /// (epoch, tick) of the last sample handed out.
    last_tick: Option<(u64, u64)>,
    pending: Option<Pending>,
    /// The last command sent; what a refused command is replaced by.
    last_sent: Option<[f64; MAX_INPUTS]>,
    /// The controller's last answer as published (refused or not): what the plant's ticks between the
    /// controller's own are answered with (kept only for a controller slower than the plant).
    last_answer: Option<CommandSample>,
    /// Consecutive refused commands (an event marks the first of each run).
    refusing: u64,
    opened_ns: u64,
    ended: Option<String>,
    /// It gave up waiting for a plant: no launcher will clean the run's namespace, so [`Self::finish`] does.
    no_rig: bool,
    /// The plant's end-of-run sample came: the run is over.
    plant_ended: bool,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl ControllerSession {
    /// Open the run's streams as its controller: read plant samples, announce `diagnostic_names`, then publish
    /// commands. The announcement goes out before the command publisher exists, which is what the plant waits for,
    /// and again with the first command (iceoryx2 hands a late subscriber the last announcement only on a later
    /// send, and the logger's subscriber may come after ours), so the logger knows the trace's columns before its
    /// first row. With `--resume`, the checkpoint a predecessor saved is read ([`Self::restored_checkpoint`]).
    pub fn open(args: ProcessArgs, scenario: Scenario, diagnostic_names: &[String]) -> Result<Self, SessionError> {
        signals::install_termination_flag();
        let info = ControllerInfo::new(diagnostic_names)
            .map_err(|e| SessionError::Setup(format!("announcing diagnostics: {e}")))?;
        let run = args.run_id.to_string();
        let realtime = args.mode == RigMode::Realtime;
        // Before any port exists: the plant starts flying once it sees this controller's command publisher, and
        // locking memory takes from milliseconds to far longer on a loaded machine, which would be ticks missed at
        // the start for a reason that is not the controller's.
        let scheduling = request_scheduling(Role::Controller, realtime);
        let node = ipc::create_node(&args.run_id, Role::Controller.label())?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let info_stream = ipc::open_stream::<ControllerInfo>(&node, Stream::ControllerInfo)?;
        let mut announcer = info_stream.publisher().map_err(|_| SessionError::SecondController { run: run.clone() })?;
        let samples = plant_stream.subscriber(Stream::Plant.queue_depth(Role::Controller))?;
        let plant_info = ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?
            .subscriber(Stream::PlantInfo.queue_depth(Role::Controller))?;
        announcer.send(0, &info)?;
        let commands = command_stream.publisher().map_err(|_| SessionError::SecondController { run })?;

        let rec = controller_recorder(&args.run_id);
        let dt = scenario.timing.dt_s;
        let events = EventLog::new(&args.out, Role::Controller.label());
        let checkpoint_path = args.out.join("controller.checkpoint.json");
        let restored = if args.resume { read_restored(&checkpoint_path) } else { None };
        let stale_after =
            Duration::from_nanos(scenario.timing.period_ns() * u64::from(args.options.stale_after_periods.max(1)));
        Ok(Self {
            scheduling,
            diagnostics_len: diagnostic_names.len(),
            loop_faults: LoopFaults::new(&scenario.faults, Role::Controller, dt, scenario.seed, events.clone()),
            events,
            rec,
            checkpoints: realtime.then(|| super::CheckpointWriter::new(checkpoint_path)),
            // Any realtime controller may be restarted, planned or not: recovery must not depend on which.
            save_checkpoints: realtime,
            resumed: if restored.is_some() { Resumed::Unconfirmed } else { Resumed::Fresh },
            restored,
            blend_ticks: (BUMPLESS_BLEND_S / dt).round().max(1.0) as u64,
            blend: None,
            plant_stale: false,
            stale_after,
            next_deadline_ns: None,
            lockstep: !realtime,
            sample_poll_ns: if realtime { (args.options.sample_poll_us * 1e3) as u64 } else { 0 },
            last_tick: None,
            pending: None,
            last_sent: None,
            last_answer: None,
            refusing: 0,
            opened_ns: monotonic_ns(),
            ended: None,
            no_rig: false,
            plant_ended: false,
            plant_stream,
            samples,
            plant_info,
            plant: None,
            commands,
            announcer,
            info,
            scenario,
            args,
            _node: node,
        })
    }

    /// The scenario the run flies (its period, set points, fault plan).
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The controller's step, s: the plant's period times `timing.controller_every_ticks`.
    pub fn dt_s(&self) -> f64 {
        self.scenario.timing.controller_dt_s()
    }

    /// A plant tick between the controller's own (`timing.controller_every_ticks`): answered at once with the
    /// controller's last answer, unchanged, and true. False for a tick the controller computes, and for the first
    /// sample it sees (it has no answer yet, as when it joins a flying plant).
    fn repeat_last_answer(&mut self, tick: u64) -> Result<bool, SessionError> {
        if self.scenario.timing.is_controller_tick(tick) {
            return Ok(false);
        }
        let Some(last) = self.last_answer else { return Ok(false) };
        let p = self.pending.take().expect("a sample was just handed out");
        let repeated = CommandSample { answers_tick: p.tick, compute_ns: 0, ..last };
        self.rec.count("commands_repeated", 1);
        self.publish(p.tick, &repeated)?;
        Ok(true)
    }

    /// What a predecessor of this controller saved, when the session was opened with `--resume`.
    pub fn restored_checkpoint(&self) -> Option<&str> {
        self.restored.as_deref()
    }

    /// Say whether the controller resumed from [`Self::restored_checkpoint`] (`Err`: why it did not fit). A
    /// refusal is an event and a warning, and the controller counts as fresh; the event when it joins the flight
    /// says which it was.
    pub fn checkpoint_used(&mut self, outcome: Result<(), String>) {
        self.resumed = match outcome {
            Ok(()) => Resumed::Checkpoint,
            Err(why) => {
                eprintln!("silrig controller: warning: the checkpoint was not used ({why}); starting fresh");
                self.events.emit(None, "checkpoint-rejected", format!("the controller started fresh: {why}"));
                Resumed::Rejected(why)
            }
        };
    }

    /// Whether the controller should hand a checkpoint to [`Self::save_checkpoint`] now: every few ticks of a
    /// realtime run (any of which may see a restart, planned or not).
    pub fn checkpoint_due(&self) -> bool {
        self.save_checkpoints && self.last_tick.is_some_and(|(_, tick)| tick.is_multiple_of(CHECKPOINT_EVERY_TICKS))
    }

    /// Save the state a restarted controller resumes from: handed to a writer thread, which writes it atomically to
    /// the run's folder off the loop and reports a failed write on stderr.
    pub fn save_checkpoint(&self, text: &str) {
        if let Some(w) = &self.checkpoints {
            w.save(text.to_string());
        }
    }

    /// Where each input's actuator is now, in the sample being answered, or the plant's hold value where it reports
    /// none: a command that leaves an input as it is. Before any sample, the hold values.
    pub fn held_command(&self) -> Vec<f64> {
        let Some(plant) = &self.plant else { return Vec::new() };
        let held = self.pending.map(|p| p.held);
        plant
            .inputs
            .iter()
            .enumerate()
            .map(|(k, input)| held.map(|h| h[k]).filter(|v| v.is_finite()).unwrap_or(input.hold))
            .collect()
    }

    /// Answer the sample [`Self::next_sample`] handed out with one value per plant input, in the order of
    /// [`Self::plant`]'s inputs: blend while joining, stamp, validate, apply the plan's in-loop faults, publish.
    /// `diagnostics` holds one value per announced name. A command with NaN, infinity or a value outside its
    /// input's range is refused: what goes out instead is a marker (`FLAG_COMMAND_REFUSED`) that tells the plant
    /// to hold its last valid command for this tick, so a lockstep run goes on; it is counted, the first of a
    /// series is an event, and the error says why.
    pub fn send(&mut self, command: &[f64], diagnostics: &[f64]) -> Result<(), SessionError> {
        let Some(p) = self.pending.take() else {
            return Err(SessionError::Usage("a command answers a sample: call next_sample first".into()));
        };
        let plant = self.plant.as_ref().expect("announced before any sample is handed out");
        let inputs = plant.inputs.len();
        let wrong = if command.len() != inputs {
            Some(format!("{} inputs given; plant {} takes {inputs}", command.len(), plant.plant))
        } else if diagnostics.len() != self.diagnostics_len {
            Some(format!("{} diagnostics given; {} were announced", diagnostics.len(), self.diagnostics_len))
        } else {
            None
        };
        if let Some(wrong) = wrong {
            self.pending = Some(p);
            return Err(SessionError::Usage(wrong));
        }
        let mut out = CommandSample { answers_tick: p.tick, ..CommandSample::zeroed() };
        out.inputs_len = inputs as u32;
        self.blend_into(p, command, &mut out.inputs[..inputs]);
        out.diagnostics_len = self.diagnostics_len as u32;
        out.diagnostics[..self.diagnostics_len].copy_from_slice(diagnostics);
        let plant = self.plant.as_ref().expect("announced");
        let refused = out.validate().map_err(|e| e.to_string()).and_then(|()| wire::check_command(plant, &out)).err();
        if let Some(reason) = &refused {
            self.rec.count("commands_refused", 1);
            if self.refusing == 0 {
                self.events.emit(Some(p.tick), "command-refused", reason.clone());
            }
            self.refusing += 1;
            let mut hold = [0.0; MAX_INPUTS];
            hold[..inputs].copy_from_slice(&plant.hold());
            out = CommandSample {
                answers_tick: p.tick,
                flags: FLAG_COMMAND_REFUSED,
                inputs_len: inputs as u32,
                inputs: self.last_sent.unwrap_or(hold),
                ..CommandSample::zeroed()
            };
        } else {
            if self.refusing > 0 {
                let detail = format!("valid commands again after {} refused", self.refusing);
                self.events.emit(Some(p.tick), "command-accepted", detail);
            }
            self.refusing = 0;
            self.last_sent = Some(out.inputs);
        }
        out.compute_ns = monotonic_ns() - p.delivered_ns;
        self.rec.record(COMPUTE, out.compute_ns as i64);
        if self.scenario.timing.controller_every_ticks > 1 {
            self.last_answer = Some(out);
        }
        self.publish(p.tick, &out)?;
        match refused {
            Some(reason) => Err(SessionError::CommandRefused { tick: p.tick, reason }),
            None => Ok(()),
        }
    }

    /// `command` into `out`, blended while joining a flying plant: from each actuator's current position towards
    /// the command (inputs whose position the plant does not report take the command at once).
    fn blend_into(&mut self, p: Pending, command: &[f64], out: &mut [f64]) {
        out.copy_from_slice(command);
        let Some(start) = self.blend else { return };
        let k = ((p.tick - start + 1) as f64 / self.blend_ticks as f64).min(1.0);
        if k >= 1.0 {
            self.blend = None;
        }
        for (value, held) in out.iter_mut().zip(p.held) {
            if held.is_finite() {
                *value = held + k * (*value - held);
            }
        }
    }

    /// Send the command, after any delay fault, unless a drop fault swallows it.
    fn publish(&mut self, tick: u64, command: &CommandSample) -> Result<(), SessionError> {
        let effect = if self.loop_faults.is_empty() { Default::default() } else { self.loop_faults.at(tick) };
        if effect.sleep_ns > 0 {
            std::thread::sleep(Duration::from_nanos(effect.sleep_ns));
        }
        if effect.drop {
            self.rec.count("commands_dropped", 1);
            return Ok(());
        }
        match self.commands.send(tick, command) {
            Ok(_) => {
                self.rec.count("commands_sent", 1);
                let stats = self.samples.stats();
                let extra = [("plant_samples_lost", stats.lost), ("plant_restarts", stats.publisher_restarts)];
                let timing = &self.scenario.timing;
                self.rec.status(tick, tick as f64 * timing.dt_s, timing.duration_s, false, &extra);
                Ok(())
            }
            Err(e) => {
                self.rec.count("errors", 1);
                Err(e.into())
            }
        }
    }

    /// Record why the controller stopped on an error (the report says so; [`Self::finish`] returns it).
    pub fn fail(&mut self, error: &dyn std::fmt::Display) {
        self.ended = Some(format!("error: {error}"));
    }

    /// Add the controller's own figures (`Controller::figures`) to its report.
    pub fn add_figures(&mut self, figures: super::report::ControllerFigures) {
        for (name, description, h) in figures.distributions {
            self.rec.add_distribution(&name, &description, h);
        }
        for (name, n) in figures.counters {
            self.rec.count(&name, n);
        }
    }

    /// Write the report (`controller.report.json` in the run's folder) and close the session.
    pub fn finish(mut self) -> anyhow::Result<ProcessReport> {
        let stats = self.samples.stats();
        self.rec.count("plant_samples_lost", stats.lost);
        self.rec.count("plant_restarts", stats.publisher_restarts);
        let ended = self.ended.take().unwrap_or_else(|| "closed by the controller".into());
        let meta = ReportMeta::new(&self.args, &self.scenario.name, std::mem::take(&mut self.scheduling), ended);
        let rec = std::mem::replace(&mut self.rec, Recorder::new(Role::Controller.label(), &[]));
        let report = rec.finish(meta, &self.args.out)?;
        if self.no_rig {
            let run = self.args.run_id.clone();
            drop(self);
            // Removes nothing while another node of the run is alive.
            ipc::cleanup_run(&run)?;
        }
        Ok(report)
    }
}
