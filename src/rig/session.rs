//! The controller's side of a run, for any controller: [`ControllerSession`] opens the run's streams, announces the
//! controller's diagnostics, waits for the plant's announcement of its signals ([`ControllerSession::plant`]: what
//! the controller finds its outputs and inputs in, by name), hands out plant samples one at a time
//! ([`ControllerSession::next_sample`]) and takes one command in answer to each ([`ControllerSession::send`]). Everything a controller should not have to write
//! lives here: header stamps, validation (a NaN or out-of-range command is refused, never sent), the in-loop faults
//! of the plan (delay, jitter, drop), the bumpless blend after a restart, checkpoint files, staleness of the plant,
//! stop requests (SIGTERM/SIGINT, the end of the run) and the timing report. `silrig-controller` is one user of it
//! ([`super::controller::serve`]); the C ABI of `libsilrig_client.so` (`src/client/`) is another, through which
//! controllers in C, C++, Python and anything with a C FFI fly.
//!
//! A session installs a SIGTERM/SIGINT flag handler when it opens (so a stop request ends the loop with a report
//! instead of killing the process) and waits on the plant stream's listener, not on a WaitSet, so iceoryx2 never
//! takes the process's signals.

use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::plant::LOCKSTEP_LOOK_NS;
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::{ProcessArgs, RigMode, signals};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::{self, IpcError, StreamPublisher, StreamService, StreamSubscriber, WaitOutcome};
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

/// What can go wrong in a session, each phrased for the person running the controller.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The run's arguments, environment or scenario are not usable.
    #[error("{0}")]
    Setup(String),
    /// The client was built against another contract than this library.
    #[error("{0}")]
    Layout(String),
    /// No plant announced itself, or sent a sample, in time after opening.
    #[error(
        "no plant on run `{run}` within {waited_s} s: is the rig running with this run id? (start it first, \
         e.g. `silrig run --controller external`, and give the controller the SILRIG_* variables it prints)"
    )]
    NoRig {
        /// Run id.
        run: String,
        /// How long it waited, s.
        waited_s: f64,
    },
    /// The run has a controller already.
    #[error("refusing to start a second controller: run `{run}` has one already")]
    SecondController {
        /// Run id.
        run: String,
    },
    /// The command was refused and not sent; the plant holds the last valid command for this tick.
    #[error("tick {tick}: command refused, not sent ({reason}); the plant holds the last valid command")]
    CommandRefused {
        /// The tick it answered.
        tick: u64,
        /// What is wrong with it.
        reason: String,
    },
    /// The API was used out of order or with wrong sizes.
    #[error("{0}")]
    Usage(String),
    /// The plant's announcement does not fit: unreadable, a signal the controller asks for is missing, or a
    /// restarted plant announced other signals.
    #[error("{0}")]
    Plant(String),
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] IpcError),
}

/// Every outcome of a session call as the C ABI of `libsilrig_client.so` returns it: 0 and positive values are not
/// errors, negative ones are (the reason is in `silrig_last_error()`). `silrig contract` writes them into the C
/// header and the Python module, so a client never types them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum Status {
    /// The call did what it says.
    Ok = 0,
    /// SIGTERM or SIGINT arrived: close the session (its report is written) and exit.
    Stopped = 1,
    /// The plant has flown the whole scenario: close the session and exit.
    RunEnded = 2,
    /// The scenario gives no value of that name (`silrig_plant_parameter`): the model keeps its own.
    NotGiven = 3,
    /// The API was used wrongly (a NULL pointer, a command without a sample, a count that does not match).
    ErrUsage = -1,
    /// The client was built against another contract (layout version or sample sizes differ).
    ErrLayout = -2,
    /// The run's variables or scenario are unusable, or the diagnostics do not fit a command.
    ErrSetup = -3,
    /// No plant sample arrived within twice the startup timeout: no rig runs with this run id.
    ErrNoRig = -4,
    /// The run has a controller already.
    ErrSecondController = -5,
    /// The command was refused (NaN, infinity, out of range) and not sent; the plant holds the last valid one.
    ErrCommandRefused = -6,
    /// The transport failed.
    ErrTransport = -7,
    /// A bug in the library (a panic was caught at the boundary).
    ErrInternal = -8,
    /// The plant's signals do not fit: a name the controller asks for is missing, or a restarted plant announced
    /// other signals.
    ErrPlant = -9,
}

impl Status {
    /// Every status, in code order of appearance.
    pub const ALL: [Status; 13] = [
        Status::Ok,
        Status::Stopped,
        Status::RunEnded,
        Status::NotGiven,
        Status::ErrUsage,
        Status::ErrLayout,
        Status::ErrSetup,
        Status::ErrNoRig,
        Status::ErrSecondController,
        Status::ErrCommandRefused,
        Status::ErrTransport,
        Status::ErrInternal,
        Status::ErrPlant,
    ];

    /// The code the C ABI returns.
    pub const fn code(self) -> i32 {
        self as i32
    }

    /// The constant's name without the `SILRIG_` prefix (`OK`, `ERR_NO_RIG`).
    pub const fn name(self) -> &'static str {
        match self {
            Status::Ok => "OK",
            Status::Stopped => "STOPPED",
            Status::RunEnded => "RUN_ENDED",
            Status::NotGiven => "NOT_GIVEN",
            Status::ErrUsage => "ERR_USAGE",
            Status::ErrLayout => "ERR_LAYOUT",
            Status::ErrSetup => "ERR_SETUP",
            Status::ErrNoRig => "ERR_NO_RIG",
            Status::ErrSecondController => "ERR_SECOND_CONTROLLER",
            Status::ErrCommandRefused => "ERR_COMMAND_REFUSED",
            Status::ErrTransport => "ERR_TRANSPORT",
            Status::ErrInternal => "ERR_INTERNAL",
            Status::ErrPlant => "ERR_PLANT",
        }
    }

    /// What it means, for the header's comments.
    pub const fn meaning(self) -> &'static str {
        match self {
            Status::Ok => "the call did what it says",
            Status::Stopped => "SIGTERM or SIGINT arrived: close the session and exit",
            Status::RunEnded => "the plant has flown the whole scenario: close the session and exit",
            Status::NotGiven => "the scenario gives no value of that name: the model keeps its own",
            Status::ErrUsage => "API misuse: NULL pointer, command without a sample, wrong count",
            Status::ErrLayout => "built against another contract (layout version or sample sizes)",
            Status::ErrSetup => "SILRIG_* variables, scenario or diagnostics unusable",
            Status::ErrNoRig => "no plant announced itself within twice the startup timeout",
            Status::ErrSecondController => "the run has a controller already",
            Status::ErrCommandRefused => "command refused (NaN, infinity, out of range), not sent; plant holds",
            Status::ErrTransport => "the transport failed",
            Status::ErrInternal => "a bug in the library (a panic caught at the boundary)",
            Status::ErrPlant => "the plant lacks a signal asked for, or a restarted plant announced other signals",
        }
    }
}

impl SessionError {
    /// The status the C ABI returns for this error.
    pub fn status(&self) -> Status {
        match self {
            SessionError::Setup(_) => Status::ErrSetup,
            SessionError::Layout(_) => Status::ErrLayout,
            SessionError::NoRig { .. } => Status::ErrNoRig,
            SessionError::SecondController { .. } => Status::ErrSecondController,
            SessionError::CommandRefused { .. } => Status::ErrCommandRefused,
            SessionError::Usage(_) => Status::ErrUsage,
            SessionError::Plant(_) => Status::ErrPlant,
            SessionError::Transport(_) => Status::ErrTransport,
        }
    }
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

        let realtime = args.mode == RigMode::Realtime;
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
        rec.start_status(&args.run_id);
        let dt = scenario.timing.dt_s;
        let events = EventLog::new(&args.out, Role::Controller.label());
        let checkpoint_path = args.out.join("controller.checkpoint.json");
        let restored = if args.resume {
            let saved = std::fs::read_to_string(&checkpoint_path).ok();
            if saved.is_none() {
                eprintln!(
                    "silrig controller: warning: --resume without a checkpoint in {}; starting fresh",
                    checkpoint_path.display()
                );
            }
            saved
        } else {
            None
        };
        let stale_after =
            Duration::from_nanos(scenario.timing.period_ns() * u64::from(args.options.stale_after_periods.max(1)));
        Ok(Self {
            scheduling: request_scheduling(Role::Controller, realtime),
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

    /// The controller's step, s.
    pub fn dt_s(&self) -> f64 {
        self.scenario.timing.dt_s
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

    /// Block until the next plant sample to answer (the newest one waiting: after a stall, older ones are skipped
    /// and counted), or until the session should stop. While the plant is silent the session idles and says so
    /// once; with no sample at all within twice `--startup-timeout-s` of opening, it gives up
    /// ([`SessionError::NoRig`]).
    pub fn next_sample(&mut self) -> Result<Next, SessionError> {
        if self.pending.take().is_some() {
            self.rec.count("samples_unanswered", 1);
        }
        if !self.wait_for_plant()? {
            return Ok(self.stop(StopReason::TerminationRequested));
        }
        if let Some(deadline_ns) = self.next_deadline_ns.take()
            && let Some(sample) = self.look_near_deadline(deadline_ns)?
        {
            return Ok(Next::Sample(sample));
        }
        if let Some(sample) = self.look_lockstep()? {
            return Ok(Next::Sample(sample));
        }
        // Every sample waiting is taken at each wake-up, so waiting first costs nothing: a sample that came since
        // has left a wake-up behind.
        loop {
            if signals::termination_requested() {
                return Ok(self.stop(StopReason::TerminationRequested));
            }
            if self.samples.stats().finished_notices > 0 || self.plant_ended {
                return Ok(self.stop(StopReason::RunEnded));
            }
            match self.samples.wait(self.stale_after)? {
                WaitOutcome::Notified => {
                    if let Some(sample) = self.take_newest()? {
                        return Ok(Next::Sample(sample));
                    }
                }
                WaitOutcome::Interrupted => self.rec.count("interrupted_waits", 1),
                WaitOutcome::TimedOut => {
                    // A sample that came without its wake-up (a lost notification) is taken here, at the latest a
                    // stale deadline after it, instead of never.
                    if let Some(sample) = self.take_newest()? {
                        if self.rec.counters.get("samples_without_wakeup").is_none_or(|n| *n == 0) {
                            let detail = "a plant sample was waiting without its wake-up; taken at the deadline";
                            self.events.emit(Some(sample.header.tick), "sample-without-wakeup", detail);
                        }
                        self.rec.count("samples_without_wakeup", 1);
                        return Ok(Next::Sample(sample));
                    }
                    self.on_plant_silent()?
                }
            }
        }
    }

    /// Realtime: block until shortly before the plant's next deadline (a sample that comes earlier, after a stall
    /// or a restart, is taken at once), then look for it again and again until `sample_poll_ns` past the deadline.
    /// A controller that blocks until the sample's notification pays an idle vCPU's wake-up on every tick (about
    /// 90 µs p50, 320 µs p99 on this kind of VM); one already awake takes the sample within a few µs. Costs at most
    /// `SAMPLE_LOOK_LEAD_NS` + `sample_poll_ns` of CPU a tick; `None` leaves the rest to the blocking wait.
    fn look_near_deadline(&mut self, deadline_ns: u64) -> Result<Option<PlantSample>, SessionError> {
        let look_from = deadline_ns.saturating_sub(SAMPLE_LOOK_LEAD_NS);
        loop {
            let now = monotonic_ns();
            if now >= look_from || signals::termination_requested() {
                break;
            }
            match self.samples.wait(Duration::from_nanos(look_from - now))? {
                WaitOutcome::Notified => {
                    if let Some(sample) = self.take_newest()? {
                        return Ok(Some(sample));
                    }
                }
                WaitOutcome::Interrupted => return Ok(None),
                WaitOutcome::TimedOut => break,
            }
        }
        self.look_until(deadline_ns + self.sample_poll_ns, false)
    }

    /// Look at the sample queue again and again until `until_ns`, spinning or (`yield_cpu`) yielding between looks.
    /// The queue only: consuming wake-ups while a notification lands can lose the wake-up for good.
    fn look_until(&mut self, until_ns: u64, yield_cpu: bool) -> Result<Option<PlantSample>, SessionError> {
        while monotonic_ns() < until_ns {
            if signals::termination_requested() || self.plant_ended {
                return Ok(None);
            }
            if let Some(sample) = self.take_newest_from(false)? {
                return Ok(Some(sample));
            }
            match yield_cpu {
                true => std::thread::yield_now(),
                false => std::hint::spin_loop(),
            }
        }
        Ok(None)
    }

    /// Lockstep: look for the next sample again and again, yielding the CPU between looks, for up to
    /// [`LOCKSTEP_LOOK_NS`] before blocking. The plant's step takes a few µs: a controller still on its CPU takes its
    /// sample then, where one asleep pays an idle vCPU's wake-up (tens of µs on this kind of VM) every tick.
    fn look_lockstep(&mut self) -> Result<Option<PlantSample>, SessionError> {
        if !self.lockstep {
            return Ok(None);
        }
        self.look_until(monotonic_ns() + LOCKSTEP_LOOK_NS, true)
    }

    /// The plant's signals as it announced them, waiting for the announcement if it has not come yet (as long as
    /// [`Self::next_sample`] waits for a first sample). A controller looks up the outputs it reads and the inputs it
    /// commands here, by name ([`PlantSignals::output`], [`PlantSignals::input`]).
    pub fn plant(&mut self) -> Result<&PlantSignals, SessionError> {
        if !self.wait_for_plant()? {
            return Err(SessionError::Setup("terminated by signal before the plant announced its signals".into()));
        }
        Ok(self.plant.as_ref().expect("announced"))
    }

    /// Wait until the plant has announced itself; false when a stop request came first.
    fn wait_for_plant(&mut self) -> Result<bool, SessionError> {
        loop {
            self.take_announcements()?;
            if self.plant.is_some() {
                return Ok(true);
            }
            if signals::termination_requested() {
                return Ok(false);
            }
            self.give_up_without_rig()?;
            // The announcement reaches a late subscriber from the stream's history, which wakes no listener.
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// Take the plant's announcements: the first says what the plant is; a later plant epoch (a restart) must say
    /// the same, since this controller found its signals by name in the first.
    fn take_announcements(&mut self) -> Result<(), SessionError> {
        let mut announced = Vec::new();
        // Nothing waits on this listener, so its wake-ups are left unconsumed: taking them is a `recvfrom` at every
        // look of the lockstep and realtime polls, and a listener left notified costs the plant no `sendto` either.
        self.plant_info.receive_queued(|r| announced.push(*r))?;
        for r in announced {
            let signals = r
                .sample
                .signals()
                .map_err(|e| SessionError::Plant(format!("the plant's announcement is refused: {e}")))?;
            if let Some(e) = r.invalid {
                return Err(SessionError::Plant(format!("the plant's announcement is refused: {e}")));
            }
            match &self.plant {
                None => self.plant = Some(signals),
                Some(known) if *known != signals => {
                    return Err(SessionError::Plant(format!(
                        "a restarted plant (epoch {}) announces plant {} with other signals than plant {} this \
                         controller started with",
                        r.sample.header.epoch, signals.plant, known.plant
                    )));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }

    /// Before any sample: give up after twice the startup timeout (no rig runs with this run id).
    fn give_up_without_rig(&mut self) -> Result<(), SessionError> {
        let waited_s = (monotonic_ns() - self.opened_ns) as f64 / 1e9;
        let limit_s = 2.0 * self.args.options.startup_timeout_s;
        if waited_s > limit_s {
            self.no_rig = true;
            return Err(SessionError::NoRig { run: self.args.run_id.to_string(), waited_s: limit_s });
        }
        Ok(())
    }

    fn stop(&mut self, reason: StopReason) -> Next {
        let ended = match reason {
            StopReason::TerminationRequested => "terminated by signal",
            StopReason::RunEnded => "completed",
        };
        self.ended.get_or_insert_with(|| ended.into());
        Next::Stop(reason)
    }

    /// Take what waits; hand out the newest valid sample of a tick not handed out yet.
    fn take_newest(&mut self) -> Result<Option<PlantSample>, SessionError> {
        self.take_newest_from(true)
    }

    /// [`Self::take_newest`]; with `consume_wakeups` false the wake-ups are left to the next wait (see
    /// [`StreamSubscriber::receive_queued`]).
    fn take_newest_from(&mut self, consume_wakeups: bool) -> Result<Option<PlantSample>, SessionError> {
        self.take_announcements()?;
        let mut newest = None;
        let mut fresh = 0u64;
        let mut invalid = 0u64;
        let mut ended = false;
        let mut on_sample = |r: &ipc::Received<PlantSample>| {
            if r.invalid.is_some() {
                invalid += 1;
            } else if r.sample.flags & wire::FLAG_END_OF_RUN != 0 {
                // The plant's last word: nothing to answer (it repeats a tick already flown).
                ended = true;
            } else {
                fresh += 1;
                newest = Some(*r);
            }
        };
        self.samples.take(consume_wakeups, &mut on_sample)?;
        self.plant_ended |= ended;
        // Counted only when there is something to count: this runs at every look, and a counter is a lookup by name.
        if invalid > 0 {
            self.rec.count("samples_invalid", invalid);
        }
        // After a stall several samples wait; acting on stale ones would only delay the newest.
        if fresh > 1 {
            self.rec.count("samples_skipped", fresh - 1);
        }
        let Some(r) = newest else { return Ok(None) };
        let h = r.sample.header;
        if self.last_tick.is_some_and(|(epoch, tick)| epoch == h.epoch && tick >= h.tick) {
            return Ok(None);
        }
        if self.last_tick.is_none() {
            self.announcer.send(h.tick, &self.info)?;
        }
        self.note_plant(h.epoch, h.tick);
        self.rec.record(IPC_PLANT_TO_CONTROLLER, r.age_ns() as i64);
        let mut held = [f64::NAN; MAX_INPUTS];
        let plant = self.plant.as_ref().expect("announced before any sample is taken");
        for (slot, input) in held.iter_mut().zip(&plant.inputs) {
            *slot = input.held_output.and_then(|o| r.sample.outputs().get(o).copied()).unwrap_or(f64::NAN);
        }
        self.pending = Some(Pending { tick: h.tick, held, delivered_ns: monotonic_ns() });
        if self.sample_poll_ns > 0 {
            // The plant publishes right after it wakes for its tick's deadline: the next deadline is a period after
            // this one, which is the send time less the wake-up's lateness.
            let deadline_ns = h.t_send_ns.saturating_add_signed(-r.sample.wake_lateness_ns);
            self.next_deadline_ns = Some(deadline_ns + self.scenario.timing.period_ns());
        }
        Ok(Some(r.sample))
    }

    /// What this sample says about the plant: a first sample past tick 0 (we joined a flying plant: blend), a new
    /// plant epoch (it restarted), samples back after silence.
    fn note_plant(&mut self, epoch: u64, tick: u64) {
        match self.last_tick {
            None if tick > 0 => {
                self.blend = Some(tick);
                let state = match &self.resumed {
                    Resumed::Fresh => "fresh state".to_string(),
                    Resumed::Checkpoint => "checkpointed state".to_string(),
                    Resumed::Rejected(why) => format!("fresh state (its checkpoint was rejected: {why})"),
                    Resumed::Unconfirmed => {
                        "a checkpoint was offered; the controller did not say whether it used it".to_string()
                    }
                };
                let detail = format!("plant already at tick {tick}: {state}, {BUMPLESS_BLEND_S} s bumpless blend");
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

    /// No sample within the deadline: before the first sample, give up after the startup timeout; after it, flag
    /// the plant stale once, and clean up its node if it died so a restarted plant can take its place.
    fn on_plant_silent(&mut self) -> Result<(), SessionError> {
        let Some((_, tick)) = self.last_tick else {
            return self.give_up_without_rig();
        };
        self.rec.count("plant_stale_deadlines", 1);
        if !self.plant_stale {
            self.plant_stale = true;
            let detail = format!("no plant sample for {:?}; idling", self.stale_after);
            self.events.emit(Some(tick), "plant-stale", detail);
        }
        let _ = self.plant_stream.try_cleanup_dead_nodes();
        Ok(())
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

/// Refuse a client built against another contract than this library: another layout version (named both ways)
/// or samples of other sizes (a header edited by hand, or packed by another compiler setting).
pub fn check_client_layout(layout_version: u32, plant_size: usize, command_size: usize) -> Result<(), SessionError> {
    let ours = silrig_wire::wire::WIRE_LAYOUT_VERSION;
    if layout_version != ours {
        return Err(SessionError::Layout(format!(
            "the client was built against wire layout version {layout_version}, this library speaks version {ours}: \
             rebuild the client with the header `silrig contract --c-header` writes for this build"
        )));
    }
    for (what, theirs, ours) in [
        ("plant sample", plant_size, size_of::<PlantSample>()),
        ("command sample", command_size, size_of::<CommandSample>()),
    ] {
        if theirs != ours {
            return Err(SessionError::Layout(format!(
                "the client's {what} is {theirs} bytes, the contract's is {ours} (layout version {layout_version}): \
                 the header was changed or compiled with other packing"
            )));
        }
    }
    Ok(())
}
