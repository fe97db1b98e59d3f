//! `silrig-logger`: subscribes to the plant and command streams with queues deep enough to absorb a stall of seconds
//! ([`silrig_wire::topology::LOGGER_BUFFER`]; in realtime its loop also asks for a real-time priority below the
//! plant's and the controller's),
//! pairs each plant sample with the command answering it, and writes each row, as it goes, to its sinks
//! ([`silrig_recording`]): `trace.csv` (its columns from the plant's announcement,
//! [`PlantSignals::trace_columns`]: for the F-16 the same columns and values as `silrig sim`), `timing.csv` (per-tick
//! stamps, flags and gaps) and the MCAP recording (the samples as received, for viewers and replay). Sinks are flushed
//! every few rows, so a kill loses at most the last unflushed batch and never corrupts earlier rows.
//!
//! Row k's deflections are those held over [t_k, t_k+1): the plant reports them with its next sample (or, for the
//! last tick, with its end-of-run sample), so a row is written once its command and that next sample are in. A
//! plant sample whose command never comes (controller late, dead or stopped) is written once a few newer samples
//! have arrived, with empty (NaN) command columns, and counted; one whose next sample never comes gets empty
//! deflection columns; samples lost on the wire show up as sequence gaps.
//!
//! Phases: [`LoggerLoop::setup`] (the files, continued after a previous logger's last row: [`super::logger_writer`]),
//! [`LoggerPorts::connect`],
//! the event loop ([`LoggerLoop::serve`]: take samples, write the rows that are ready, acknowledge), and
//! [`LoggerLoop::finish`].

use super::ProcessArgs;
use super::events::EventLog;
pub use super::logger_writer::FLUSH_PERIOD_NS;
use super::logger_writer::Writer;
use super::loop_faults::LoopFaults;
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::tick_queue::TickQueue;
use iceoryx2::prelude::CallbackProgression;
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace;
use silrig_wire::clock::{TickSchedule, monotonic_ns};
use silrig_wire::ipc::{self, LoopEnd, Received, StreamPublisher, StreamSubscriber};
use silrig_wire::topology::Stream;
use silrig_wire::wire::{self, CommandSample, ControllerInfo, LogAckSample, PlantInfo, PlantSample};
use std::net::SocketAddr;

/// A plant sample waits this many newer samples for its command before it is written without one.
pub const MISSING_COMMAND_WINDOW: u64 = 10;
/// Lockstep: the logger looks for new samples this often instead of being woken by each one, ns. Two wake-ups a
/// tick of a third process on a two-core machine cost the plant and controller about a third of their speed
/// (docs/src/explanations/timing.md, "Lockstep speed"); at 40,000 ticks/s this is 10 ticks a look, well inside the
/// plant's window.
pub const LOCKSTEP_POLL_NS: u64 = 250_000;

const IPC_PLANT_TO_LOGGER: usize = 0;
const IPC_COMMAND_TO_LOGGER: usize = 1;

/// Ticks a restarted plant flew again.
struct Reflown {
    /// The plant life (epoch) re-flying them.
    epoch: u64,
    /// The first tick it flew again.
    first_tick: u64,
    /// Its outputs minus the written ones at the last written tick.
    jump: Option<Vec<f64>>,
    /// At the last written tick its sample equals the written one in every output.
    identical: bool,
}

/// The logger's side of the run's streams.
pub struct LoggerPorts {
    inputs: LoggerInputs,
    acks: StreamPublisher<LogAckSample>,
    // Dropped last: the ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl LoggerPorts {
    /// Open the logger's streams: read plant samples and commands with deep queues, publish acknowledgements.
    pub fn connect(args: &ProcessArgs) -> anyhow::Result<Self> {
        let node = ipc::create_node(&args.run_id, Role::Logger.label())?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let ack_stream = ipc::open_stream::<LogAckSample>(&node, Stream::LogAck)?;
        let info_stream = ipc::open_stream::<ControllerInfo>(&node, Stream::ControllerInfo)?;
        // Announcements first: the plant starts once it sees the logger's plant subscriber, and every announcement
        // made after that must reach this queue.
        let info = info_stream.subscriber(Stream::ControllerInfo.queue_depth(Role::Logger))?;
        let plant_info = ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?
            .subscriber(Stream::PlantInfo.queue_depth(Role::Logger))?;
        let plant = plant_stream.subscriber(Stream::Plant.queue_depth(Role::Logger))?;
        let commands = command_stream.subscriber(Stream::Command.queue_depth(Role::Logger))?;
        let acks = ack_stream.publisher()?;
        Ok(Self { inputs: LoggerInputs { plant, commands, info, plant_info }, acks, _node: node })
    }
}

/// The streams the logger reads.
pub struct LoggerInputs {
    plant: StreamSubscriber<PlantSample>,
    commands: StreamSubscriber<CommandSample>,
    info: StreamSubscriber<ControllerInfo>,
    plant_info: StreamSubscriber<PlantInfo>,
}

/// Everything the logger keeps between wake-ups: the files, the samples waiting for their partner, the counters.
pub struct LoggerLoop {
    scenario: Scenario,
    ticks: u64,
    writer: Writer,
    rec: Recorder,
    events: EventLog,
    loop_faults: LoopFaults,
    /// The last tick a previous logger of this run wrote (a restart), which this one continues after.
    resume_after: Option<u64>,
    pending_plant: TickQueue<Received<PlantSample>>,
    /// The plant's end-of-run sample: the deflections of its last tick.
    end: Option<Received<PlantSample>>,
    /// Commands by the tick they answer.
    pending_command: TickQueue<Received<CommandSample>>,
    /// First tick of the current run of rows written without a command.
    missing_since: Option<u64>,
    /// The diagnostic names the newest controller epoch announced.
    announced: Option<Vec<String>>,
    /// What the plant announced: the trace's columns come from it. Shared, so writing rows needs no copy of it.
    plant: Option<std::rc::Rc<PlantSignals>>,
    /// A restarted plant re-flying ticks already written (its checkpoint is older than its predecessor's last
    /// tick, or it had none): those samples are not written, and the first row it adds is a discontinuity.
    reflown: Option<Reflown>,
    /// Lockstep: paced by a timer ([`LOCKSTEP_POLL_NS`]) rather than woken by every sample.
    lockstep: bool,
    /// What the loop's thread got of the real-time priority it asks for in realtime mode, for the report.
    scheduling: String,
    done: bool,
    error: Option<anyhow::Error>,
}

impl LoggerLoop {
    /// Phase 1: the scenario, and the files, opened for appending after whatever a previous logger wrote.
    /// With `live_foxglove`, the recording's channels are also served there as they are written
    /// ([`crate::live_foxglove`]).
    pub fn setup(args: &ProcessArgs, live_foxglove: Option<SocketAddr>) -> anyhow::Result<Self> {
        let scenario = args.scenario()?;
        std::fs::create_dir_all(&args.out)?;
        let events = EventLog::new(&args.out, Role::Logger.label());
        let loop_faults =
            LoopFaults::new(&scenario.faults, Role::Logger, scenario.timing.dt_s, scenario.seed, events.clone());
        let (writer, resume_after) = Writer::open(args, &scenario, &events, live_foxglove)?;
        let mut rec = Recorder::new(
            Role::Logger.label(),
            &[
                ("ipc_plant_to_logger", "plant publish to receive at the logger"),
                ("ipc_command_to_logger", "command publish to receive at the logger"),
            ],
        );
        rec.declare(&[
            "rows_written",
            "rows_without_command",
            "plant_ticks_missing",
            "invalid_samples",
            "flight_discontinuities",
        ]);
        rec.start_status(&args.run_id);
        Ok(Self {
            ticks: scenario.timing.ticks(),
            scenario,
            writer,
            rec,
            events,
            loop_faults,
            resume_after,
            pending_plant: TickQueue::default(),
            end: None,
            pending_command: TickQueue::default(),
            missing_since: None,
            announced: None,
            plant: None,
            reflown: None,
            lockstep: args.mode == super::RigMode::Lockstep,
            scheduling: String::new(),
            done: false,
            error: None,
        })
    }

    /// Phase 3: write rows as samples arrive until the last tick is written or SIGTERM, then whatever arrived
    /// before the end, with or without its command.
    pub fn serve(&mut self, ports: &mut LoggerPorts) -> anyhow::Result<ipc::LoopExit> {
        let waitset = ipc::rig_waitset()?;
        let pace = match self.lockstep {
            true => Some(ipc::TickTimer::new(TickSchedule::new(monotonic_ns() + LOCKSTEP_POLL_NS, LOCKSTEP_POLL_NS))?),
            false => None,
        };
        let pace_guard = pace
            .as_ref()
            .map(|timer| waitset.attach_notification(timer))
            .transpose()
            .map_err(|e| anyhow::anyhow!("attaching the lockstep timer: {}", ipc::in_words(&e)))?;
        let attach = |listener| (!self.lockstep).then(|| waitset.attach_notification(listener)).transpose();
        let plant_guard = attach(ports.inputs.plant.listener())
            .map_err(|e| anyhow::anyhow!("attaching the plant stream: {}", ipc::in_words(&e)))?;
        let command_guard = attach(ports.inputs.commands.listener())
            .map_err(|e| anyhow::anyhow!("attaching the command stream: {}", ipc::in_words(&e)))?;
        let exit = ipc::run_waitset(&waitset, |id| {
            let paced = pace_guard.as_ref().is_some_and(|g| id.has_event_from(g));
            if paced && let Some(timer) = &pace {
                // Only clears the timer's readiness: however many expirations passed, one look takes everything.
                let _ = timer.read_expirations();
            }
            let woken = [&plant_guard, &command_guard].iter().any(|g| g.as_ref().is_some_and(|g| id.has_event_from(g)));
            if paced || woken {
                match self.step(&ports.inputs, &mut ports.acks, false) {
                    Ok(true) => {
                        self.done = true;
                        return CallbackProgression::Stop;
                    }
                    Ok(false) => {}
                    Err(e) => {
                        self.error = Some(e);
                        return CallbackProgression::Stop;
                    }
                }
            }
            CallbackProgression::Continue
        })?;
        if self.error.is_none()
            && let Err(e) = self.step(&ports.inputs, &mut ports.acks, true)
        {
            self.error = Some(e);
        }
        if let Err(e) = self.writer.finish()
            && self.error.is_none()
        {
            self.error = Some(e.into());
        }
        Ok(exit)
    }

    /// Take what arrived, write every row that is ready, acknowledge; true once the last tick is written (the
    /// scenario's last, or the one the end-of-run sample names).
    fn step(
        &mut self,
        inputs: &LoggerInputs,
        acks: &mut StreamPublisher<LogAckSample>,
        final_flush: bool,
    ) -> anyhow::Result<bool> {
        self.take_samples(inputs)?;
        let rows_before = self.writer.rows;
        self.write_ready_rows(final_flush)?;
        if self.writer.rows != rows_before {
            self.writer.flush_if_due()?;
            // Rows taken, flushed or not: the acknowledgement bounds the queues, the flush period what a kill loses.
            acks.send(self.writer.last_tick.unwrap_or(0), &LogAckSample::new(self.writer.rows))?;
        }
        let (tick, dt_s) = (self.writer.last_tick.unwrap_or(0), self.scenario.timing.dt_s);
        // Rows are counted by the writer, not by name at each row (a string lookup a row was 5 % of a lockstep
        // logger's time); the report takes the count at the end.
        let kept = [
            ("plant_samples_lost", inputs.plant.stats().lost),
            ("command_samples_lost", inputs.commands.stats().lost),
            ("rows_written", self.writer.rows),
        ];
        self.rec.status(tick, tick as f64 * dt_s, self.scenario.timing.duration_s, false, &kept);
        let end_tick = self.end.as_ref().map(|e| e.sample.header.tick);
        Ok(self.writer.last_tick.is_some_and(|t| t >= self.ticks || end_tick.is_some_and(|e| t >= e)))
    }

    fn take_samples(&mut self, inputs: &LoggerInputs) -> anyhow::Result<()> {
        // Announcements first: a plant announces before its first sample, a controller before its first command.
        // Their listeners wake nothing (no WaitSet has them), so their wake-ups are left unconsumed: a listener
        // left notified costs its notifiers no further system call, and taking it costs this one none.
        let mut announced = Vec::new();
        inputs.plant_info.receive_queued(|r| announced.push(*r))?;
        for r in announced {
            self.on_plant_announcement(&r)?;
        }
        // Lockstep looks on a timer, so the same holds for the sample streams there; realtime is woken by them and
        // must consume the wake-ups, or the WaitSet spins.
        let consume_wakeups = !self.lockstep;
        inputs.info.receive_queued(|r| match &r.invalid {
            Some(e) => {
                self.rec.count("invalid_samples", 1);
                self.events.emit(None, "controller-info-invalid", e.to_string());
            }
            None => self.on_announcement(r.sample.names()),
        })?;
        inputs.plant.take(consume_wakeups, |r| {
            if r.invalid.is_some() {
                self.rec.count("invalid_samples", 1);
                return;
            }
            self.rec.record(IPC_PLANT_TO_LOGGER, r.age_ns() as i64);
            if r.sample.flags & wire::FLAG_END_OF_RUN != 0 {
                self.end = Some(*r);
            } else if self.resume_after.is_none_or(|t| r.sample.header.tick > t) {
                self.pending_plant.insert(r.sample.header.tick, *r);
            }
        })?;
        inputs.commands.take(consume_wakeups, |r| {
            if r.invalid.is_some() {
                self.rec.count("invalid_samples", 1);
                return;
            }
            self.rec.record(IPC_COMMAND_TO_LOGGER, r.age_ns() as i64);
            self.pending_command.insert(r.sample.answers_tick, *r);
        })?;
        Ok(())
    }

    /// A plant epoch's signals: the first gives the trace its columns and goes into the recording; a restarted
    /// plant must announce the same, or its rows would not fit the trace.
    fn on_plant_announcement(&mut self, r: &Received<PlantInfo>) -> anyhow::Result<()> {
        let signals = r.sample.signals().map_err(|e| anyhow::anyhow!("the plant's announcement is refused: {e}"))?;
        match &self.plant {
            None => {
                self.writer.announce_plant(&r.sample)?;
                self.plant = Some(std::rc::Rc::new(signals));
            }
            Some(known) if **known != signals => anyhow::bail!(
                "a restarted plant (epoch {}) announces plant {} with other signals than plant {} whose rows the \
                 trace holds",
                r.sample.header.epoch,
                signals.plant,
                known.plant
            ),
            Some(_) => {}
        }
        Ok(())
    }

    /// A controller epoch's diagnostic names. Once the trace has started its columns stay; a controller that names
    /// other diagnostics (another controller restarted into the run) is reported, its values written by position.
    fn on_announcement(&mut self, names: Vec<String>) {
        if self.writer.started && names != self.writer.diagnostic_names {
            let detail = format!(
                "the controller names {} diagnostics ({}), the trace has columns for {}: values are written by position",
                names.len(),
                names.join(","),
                self.writer.diagnostic_names.len()
            );
            self.events.emit(self.writer.last_tick, "diagnostics-renamed", detail);
        }
        self.announced = Some(names);
    }

    /// The trace's diagnostic columns when its first row is due: those the controller announced, or, with no
    /// announcement (no controller yet), the scenario's controller's, said in an event.
    fn start_trace(&mut self, plant: &PlantSignals, tick: u64) -> anyhow::Result<()> {
        if self.writer.started {
            return Ok(());
        }
        let names = match &self.announced {
            Some(names) => names.clone(),
            // A restarted logger continues the trace's own columns, whoever announced them.
            None if self.writer.previous_columns.is_some() => Vec::new(),
            None => {
                let detail = "no controller announced its diagnostics before the first row; columns from the scenario";
                self.events.emit(Some(tick), "controller-unannounced", detail);
                trace::attitude_diagnostic_names(self.scenario.controller.rbf.nodes())
            }
        };
        self.writer.start_trace(plant, &names)
    }

    /// The sample that closes this tick, with the actuator positions held over [t_tick, t_tick+1): the next plant
    /// sample, or the end-of-run sample when it closes this tick.
    fn closing(&self, tick: u64) -> Option<PlantSample> {
        let next = self.pending_plant.get(tick + 1);
        let end = self.end.as_ref().filter(|e| e.sample.header.tick == tick);
        next.or(end).map(|r| r.sample)
    }

    /// The execution time of this tick's step, which the sample closing the tick carries (as it carries the
    /// deflections); none when that sample is from another plant life, which did not run this step.
    fn step_exec_after(&self, tick: u64, epoch: u64) -> Option<u64> {
        let next = self.pending_plant.get(tick + 1);
        let end = self.end.as_ref().filter(|e| e.sample.header.tick == tick);
        next.or(end).filter(|r| r.sample.header.epoch == epoch).map(|r| r.sample.previous_step_exec_ns)
    }

    /// Write the oldest waiting plant samples, each with the command answering it and the deflections the next
    /// sample reports; one whose command or next sample has not come while [`MISSING_COMMAND_WINDOW`] newer samples
    /// arrived (or at the end) is written without them.
    fn write_ready_rows(&mut self, final_flush: bool) -> anyhow::Result<()> {
        let Some(plant) = self.plant.clone() else {
            if final_flush && !self.pending_plant.is_empty() {
                let detail = format!(
                    "{} plant samples came, but no announcement of the plant's signals: no rows written",
                    self.pending_plant.len()
                );
                self.events.emit(None, "plant-unannounced", detail);
            }
            return Ok(());
        };
        while let Some(tick) = self.pending_plant.first_tick() {
            let newest = self.pending_plant.last_tick().expect("non-empty");
            let given_up = final_flush || newest >= tick + MISSING_COMMAND_WINDOW;
            let has_command = self.pending_command.contains(tick);
            let next = self.closing(tick);
            if !((has_command && next.is_some()) || given_up) {
                break;
            }
            let sample = self.pending_plant.remove(tick).expect("present");
            if let Some(last) = self.writer.last_tick
                && tick > last + 1
            {
                self.rec.count("plant_ticks_missing", tick - last - 1);
                self.events.emit(Some(tick), "plant-gap", format!("ticks {}..{} never arrived", last + 1, tick - 1));
            }
            if tick <= self.writer.last_tick.unwrap_or(0)
                && self.writer.rows + u64::from(self.resume_after.is_some()) > 0
            {
                // A restarted plant re-simulating ticks already logged: keep the first record of each tick.
                self.note_reflown(&sample.sample);
                continue;
            }
            self.mark_discontinuity(&sample.sample);
            let command = self.pending_command.remove(tick);
            self.note_command_gap(tick, command.is_some());
            if !self.loop_faults.is_empty() {
                let effect = self.loop_faults.at(tick);
                if effect.sleep_ns > 0 {
                    std::thread::sleep(std::time::Duration::from_nanos(effect.sleep_ns));
                }
            }
            self.start_trace(&plant, tick)?;
            let step_exec_ns = self.step_exec_after(tick, sample.sample.header.epoch);
            let end = self.end.as_ref().filter(|e| e.sample.header.tick == tick);
            self.writer.row(&plant, &sample, next.as_ref(), command.as_ref(), step_exec_ns, end)?;
            // Commands answering ticks already written can no longer be used (they sort first: no walk of the rest).
            self.pending_command.drop_through(tick);
        }
        Ok(())
    }

    /// A sample of a tick already written, from a plant life other than the one that wrote it: remember which
    /// ticks were flown twice and, at the last written tick, how far the two flights are apart.
    fn note_reflown(&mut self, sample: &PlantSample) {
        let Some(written) = self.writer.last_written else { return };
        if sample.header.epoch == written.header.epoch {
            return;
        }
        let r = self.reflown.get_or_insert(Reflown {
            epoch: sample.header.epoch,
            first_tick: sample.header.tick,
            jump: None,
            identical: false,
        });
        r.first_tick = r.first_tick.min(sample.header.tick);
        if sample.header.tick == written.header.tick {
            r.jump = Some(sample.outputs().iter().zip(written.outputs()).map(|(a, b)| a - b).collect());
            r.identical = sample.outputs() == written.outputs();
        }
    }

    /// The first row a plant life writes after another life re-flew ticks already written: the trace joins two
    /// flights here. Said in an event (which the fault table and the report show) with the size of the jump.
    fn mark_discontinuity(&mut self, sample: &PlantSample) {
        let Some(r) = self.reflown.take_if(|r| r.epoch == sample.header.epoch) else { return };
        let last = self.writer.last_tick.unwrap_or(0);
        let tick = sample.header.tick;
        if r.identical && r.first_tick == last {
            // It resumed from a checkpoint of the last written tick itself: the same state, one flight.
            let detail = format!("the restarted plant flew tick {last} again with the state already written: no jump");
            self.events.emit(Some(tick), "flight-continued", detail);
            return;
        }
        let jump = match (&r.jump, &self.plant) {
            (Some(jump), Some(plant)) => {
                // The first four traced outputs (the F-16's: phi, theta, psi, alpha).
                let shown: Vec<String> = (plant.outputs.iter().zip(jump))
                    .filter(|(o, _)| o.in_trace)
                    .take(4)
                    .map(|(o, d)| format!("{} {d:+.3} {}", o.name, o.unit))
                    .collect();
                format!("at tick {last} the two flights differed by {}", shown.join(", "))
            }
            _ => format!("the re-flown tick {last} never arrived, so the jump is unknown"),
        };
        let detail = format!(
            "rows from tick {tick} come from a restarted plant that flew again from tick {} (ticks {}..{last} \
             were already written and are kept from the first flight); {jump}",
            r.first_tick, r.first_tick
        );
        self.rec.count("flight_discontinuities", 1);
        self.writer.flight_segment += 1;
        self.events.emit(Some(tick), "flight-discontinuity", detail);
    }

    /// Mark where rows start and stop going without a command.
    fn note_command_gap(&mut self, tick: u64, has_command: bool) {
        match (has_command, self.missing_since) {
            (false, None) => {
                self.missing_since = Some(tick);
                self.events.emit(Some(tick), "commands-missing", "rows written without a command from here");
            }
            (true, Some(from)) => {
                self.missing_since = None;
                self.events.emit(Some(tick), "commands-resumed", format!("{} rows without a command", tick - from));
            }
            _ => {}
        }
        if !has_command {
            self.rec.count("rows_without_command", 1);
        }
    }

    /// Phase 4: the report; an error that stopped the loop is returned after the report is written.
    pub fn finish(
        mut self,
        args: &ProcessArgs,
        ports: &LoggerPorts,
        exit: ipc::LoopExit,
    ) -> anyhow::Result<ProcessReport> {
        let plant_stats = ports.inputs.plant.stats();
        let command_stats = ports.inputs.commands.stats();
        self.rec.count("rows_written", self.writer.rows);
        self.rec.count("plant_samples_lost", plant_stats.lost);
        self.rec.count("command_samples_lost", command_stats.lost);
        self.rec.count("plant_restarts", plant_stats.publisher_restarts);
        self.rec.count("controller_restarts", command_stats.publisher_restarts);
        self.rec.count("interrupted_waits", exit.interrupts);
        let ended = match (&self.error, exit.end, self.done) {
            (Some(e), _, _) => format!("error: {e}"),
            (None, _, true) => "completed".into(),
            (None, LoopEnd::TerminationRequest, false) => "terminated by signal".into(),
            (None, LoopEnd::Stopped, false) => "stopped".into(),
        };
        let meta = ReportMeta::new(args, &self.scenario.name, self.scheduling.clone(), ended);
        // On a full disk the report cannot be written either: say both, the loop's error first.
        let report = self.rec.finish(meta, &args.out).map_err(|report_error| match &self.error {
            Some(e) => anyhow::anyhow!("{e:#}; and the report: {report_error}"),
            None => report_error.into(),
        })?;
        match self.error {
            Some(e) => Err(e),
            None => Ok(report),
        }
    }
}

/// Run the logger until it has written every tick of the scenario (or SIGTERM), and write its report; with
/// `live_foxglove`, serving the recording's channels there as it goes.
pub fn run_logger(args: &ProcessArgs, live_foxglove: Option<SocketAddr>) -> anyhow::Result<ProcessReport> {
    let mut logger = LoggerLoop::setup(args, live_foxglove)?;
    // Asked for after the setup, which starts the status and live-server threads: SCHED_FIFO is a thread's, so only
    // the loop (and what it starts later) takes it, and those threads stay with the ordinary processes.
    logger.scheduling = request_scheduling(Role::Logger, args.mode == super::RigMode::Realtime);
    let mut ports = LoggerPorts::connect(args)?;
    let exit = logger.serve(&mut ports)?;
    logger.finish(args, &ports, exit)
}
