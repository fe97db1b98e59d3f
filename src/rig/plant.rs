//! `silrig-plant`: the time master. Each tick it publishes the plant sample, gathers the controller's command
//! (same-tick: waits for the answer to this tick up to a budget; next-tick: takes the answer to the previous tick),
//! holds the last command when none is in time (a miss), moves the actuators and integrates one step with the
//! same [`silrig_flight::sim::PlantRunner`] as `silrig sim`. It flies the scenario's N + 1 samples (t = 0 to the
//! duration; the last one only moves the actuators) and ends with an end-of-run sample ([`wire::FLAG_END_OF_RUN`]) that
//! carries the deflections of the last tick, which the logger's last row shows. A state that leaves the model's
//! envelope ends the flight the same way, one tick early, and the process with an error.
//!
//! Realtime: absolute-deadline ticks with `clock_nanosleep(TIMER_ABSTIME)`; a tick that starts a whole period late
//! is an overrun: the periods that passed without a tick are counted and never caught up in a burst. No tick number
//! is skipped: simulated time pauses while the plant cannot run (stopped, delayed) and then falls behind wall time.
//! Lockstep: no sleeping; the plant waits for every command, and never runs further ahead of the logger than its queue
//! holds.
//!
//! The loop flies any [`PlantModel`] (the vehicle behind named signals; the F-16 is
//! [`super::f16_plant::F16Plant`]) and keeps everything around it: the clock, the commands, the watchdog and the
//! failsafe (the model's announced hold values), the checkpoints and the report.
//!
//! The process runs in four phases: [`PlantLoop::setup`] (scenario, model, recorder, watchdog settings),
//! [`PlantPorts::connect`] (streams, then waiting for the peers), the tick loop ([`PlantLoop::fly`], one tick at a time
//! in named steps), and [`PlantLoop::finish`] (the report).

use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::plant_model::{ActuatorFlags, PlantModel};
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::tick_beacon::TickBeacon;
use super::{ProcessArgs, RigMode, signals};
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::{self, TickSchedule, monotonic_ns};
use silrig_wire::ipc::{self, Received, StreamPublisher, StreamService, StreamSubscriber};
use silrig_wire::topology::Stream;
use silrig_wire::wire::{self, CommandSample, LogAckSample, PlantInfo, PlantSample};
use std::collections::VecDeque;
use std::time::Duration;

/// A realtime plant saves a checkpoint this often, so a restarted plant continues the flight.
pub const CHECKPOINT_EVERY_TICKS: u64 = 10;

/// In lockstep the plant stays at most this many ticks ahead of the rows the logger has written (its queue holds
/// [`silrig_wire::topology::LOGGER_BUFFER`]).
pub const LOCKSTEP_LOGGER_WINDOW: u64 = 64;
/// In lockstep the plant looks for each command, and the controller's session for each sample, this long before it
/// blocks, ns (yielding between looks): the other side's step takes a few µs, an idle vCPU's wake-up tens.
pub const LOCKSTEP_LOOK_NS: u64 = 50_000;
/// In lockstep, a peer silent for this long is an error rather than a slow peer.
pub const LOCKSTEP_PEER_TIMEOUT: Duration = Duration::from_secs(5);

const WAKE_LATENESS: usize = 0;
const STEP_EXEC: usize = 1;
const SENSE_TO_ACTUATE: usize = 2;
const IPC_CONTROLLER_TO_PLANT: usize = 3;
const CHECKPOINT_WRITE: usize = 4;
const SENSE_TO_ACTUATE_STEADY: usize = 5;

/// Publish stamps kept to measure sense-to-actuate of commands answering recent ticks.
const PUBLISH_STAMPS: usize = 16;

/// Flags describing the step that led to the next sample.
fn step_flags(actuators: ActuatorFlags, held: bool) -> u32 {
    let mut flags = 0;
    if held {
        flags |= wire::FLAG_COMMAND_STALE;
    }
    if actuators.saturated {
        flags |= wire::FLAG_SATURATED;
    }
    if actuators.rate_limited {
        flags |= wire::FLAG_RATE_LIMITED;
    }
    flags
}

/// The plant's side of the run's streams.
pub struct PlantPorts {
    plant_stream: StreamService<PlantSample>,
    command_stream: StreamService<CommandSample>,
    publisher: StreamPublisher<PlantSample>,
    /// Held for the run, so a second plant is refused before it could announce other signals.
    announcer: StreamPublisher<PlantInfo>,
    commands: StreamSubscriber<CommandSample>,
    acks: StreamSubscriber<LogAckSample>,
    // Dropped last: the services and ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl PlantPorts {
    /// Open the plant's streams: announce `info`, publish plant samples, read commands and the logger's
    /// acknowledgements. The announcement goes out now and again with the first sample (a reader that subscribed
    /// in between gets it then), and any reader that joins later gets it from the stream's history
    /// ([`StreamPublisher::deliver_history`], every tick).
    pub fn connect(args: &ProcessArgs, info: &PlantInfo) -> anyhow::Result<Self> {
        let node = ipc::create_node(&args.run_id, Role::Plant.label())?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let ack_stream = ipc::open_stream::<LogAckSample>(&node, Stream::LogAck)?;
        let info_stream = ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?;
        let mut announcer = info_stream.publisher().context("the plant-info stream")?;
        announcer.send(0, info)?;
        let publisher = plant_stream.publisher().context("the plant stream")?;
        let commands = command_stream.subscriber(Stream::Command.queue_depth(Role::Plant))?;
        let acks = ack_stream.subscriber(Stream::LogAck.queue_depth(Role::Plant))?;
        Ok(Self { plant_stream, command_stream, publisher, announcer, commands, acks, _node: node })
    }

    /// Tell readers that did not start with the run (`--controller external`) that it is over.
    pub fn announce_finished(&self) -> anyhow::Result<()> {
        Ok(self.publisher.announce_finished()?)
    }

    /// Wait until the controller and the logger are connected, or time out; SIGTERM ends the wait early (false).
    pub fn wait_for_peers(&self, timeout_s: f64) -> anyhow::Result<bool> {
        // Every port the peers read with, the logger's command subscriber too (it subscribes to commands after
        // plant samples): otherwise the first commands of a fast lockstep run can go out before it listens.
        let ready = || {
            self.plant_stream.number_of_subscribers() >= 2
                && self.command_stream.number_of_publishers() >= 1
                && self.command_stream.number_of_subscribers() >= 2
        };
        let deadline = monotonic_ns() + (timeout_s * 1e9) as u64;
        while !ready() {
            if signals::termination_requested() {
                return Ok(false);
            }
            anyhow::ensure!(
                monotonic_ns() < deadline,
                "no controller and logger connected within {timeout_s} s (start silrig-controller and silrig-logger \
                 with the same --run-id)"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(true)
    }
}

/// The controller watchdog: stale after a few periods without a fresh command, failsafe after the hold.
#[derive(Debug)]
struct Watchdog {
    stale_after_ns: u64,
    hold_ns: u64,
    /// The model's announced hold values (the F-16's: the trim surfaces of the scenario's flight condition).
    failsafe: Vec<f64>,
    last_fresh_ns: u64,
    last_fresh_tick: u64,
    stale: bool,
    in_failsafe: bool,
}

/// Everything the tick loop keeps from one tick to the next.
pub struct PlantLoop {
    scenario: Scenario,
    realtime: bool,
    scheduling: String,
    model: Box<dyn PlantModel>,
    rec: Recorder,
    events: EventLog,
    loop_faults: LoopFaults,
    /// Realtime only (a lockstep plant is never restarted).
    checkpoints: Option<super::CheckpointWriter>,
    checkpoint_path: std::path::PathBuf,
    ticks: u64,
    budget_ns: u64,
    spin_ns: u64,
    /// What this plant announces, and the inputs every command is checked against.
    info: PlantInfo,
    signals: PlantSignals,
    announced: bool,
    /// The inputs the actuators follow now.
    applied: Vec<f64>,
    /// Tick whose sample the applied command answers (None: the initial hold, before any command).
    applied_answers: Option<u64>,
    /// The newest commands received, oldest first.
    received: VecDeque<CommandSample>,
    publish_ns: [u64; PUBLISH_STAMPS],
    /// Flags of the next sample, from the step that leads to it.
    flags: u32,
    rows_acked: u64,
    schedule: TickSchedule,
    command_epoch: Option<u64>,
    watchdog: Watchdog,
    expected_wall_tick: u64,
    sim_tick: u64,
    /// This stall was already counted as an overrun when the tick's work ran past the next due time.
    overrun_counted: bool,
    /// Why the flight cannot go on, from the last step (the state left the model's envelope).
    left_envelope: Option<String>,
    /// This tick's wake-up lateness (0 in lockstep) and the last step's execution time, ns: the samples carry
    /// them to the logger's `timing.csv`.
    wake_lateness_ns: i64,
    step_exec_ns: u64,
    /// Where the launcher reads the newest tick (see [`super::tick_beacon`]).
    beacon: Option<TickBeacon>,
    /// The model's outputs now are the last valid ones, its own refused: every sample carrying them is flagged
    /// ([`wire::FLAG_OUTPUTS_HELD`]) until they are the model's own again. Set by a plant session.
    pub(crate) outputs_held: bool,
}

impl PlantLoop {
    /// Phase 1: the scenario, the model at its initial condition, the recorder and the watchdog settings.
    pub fn setup(args: &ProcessArgs, scenario: Scenario, model: Box<dyn PlantModel>) -> anyhow::Result<Self> {
        let realtime = args.mode == RigMode::Realtime;
        let checkpoint_path = args.out.join("plant.checkpoint.json");
        let scheduling = request_scheduling(Role::Plant, realtime);
        let period = scenario.timing.period_ns();
        let o = &args.options;
        let mut rec = Recorder::new(
            Role::Plant.label(),
            &[
                ("wake_lateness", "actual minus ideal tick start (realtime only)"),
                ("step_exec", "actuators + RK4 step execution time"),
                ("sense_to_actuate", "plant publish of tick k to the command answering k received at the plant"),
                ("ipc_controller_to_plant", "command publish to receive at the plant"),
                (
                    "checkpoint_write",
                    "serialising the checkpoint a restarted plant resumes from and handing it to the writer thread (realtime)",
                ),
                ("sense_to_actuate_steady", "sense_to_actuate of the ticks after the first second (what check judges)"),
            ],
        );
        rec.declare(&[
            "ticks",
            "overruns",
            "periods_without_tick",
            "command_misses",
            "commands_received",
            "commands_invalid",
            "commands_refused_held",
            "failsafe_ticks",
            "samples_dropped",
        ]);
        rec.start_status(&args.run_id);
        let events = EventLog::new(&args.out, Role::Plant.label());
        // Without it the launcher schedules process faults on the wall clock from tick 0, as it must for a plant
        // that does not use this library.
        let beacon = TickBeacon::create(&args.run_id)
            .map_err(|e| eprintln!("silrig-plant: warning: no tick beacon ({e}): process faults follow the wall clock"))
            .ok();
        let loop_faults =
            LoopFaults::new(&scenario.faults, Role::Plant, scenario.timing.dt_s, scenario.seed, events.clone());
        let info = PlantInfo::new(model.signals()).map_err(|e| anyhow::anyhow!("the plant's announcement: {e}"))?;
        let watchdog = Watchdog {
            stale_after_ns: period * u64::from(o.stale_after_periods.max(1)),
            hold_ns: (o.controller_hold_ms * 1e6) as u64,
            failsafe: model.signals().hold(),
            last_fresh_ns: 0,
            last_fresh_tick: 0,
            stale: false,
            in_failsafe: false,
        };
        Ok(Self {
            ticks: scenario.timing.ticks(),
            budget_ns: (o.command_budget_ms * 1e6) as u64,
            spin_ns: if realtime { (o.command_spin_us * 1e3) as u64 } else { LOCKSTEP_LOOK_NS },
            signals: model.signals().clone(),
            info,
            announced: false,
            applied: model.initial_inputs(),
            applied_answers: None,
            received: VecDeque::with_capacity(8),
            publish_ns: [0; PUBLISH_STAMPS],
            flags: 0,
            rows_acked: 0,
            schedule: TickSchedule::new(0, period),
            command_epoch: None,
            watchdog,
            expected_wall_tick: 0,
            sim_tick: 0,
            overrun_counted: false,
            left_envelope: None,
            wake_lateness_ns: 0,
            step_exec_ns: 0,
            checkpoints: realtime.then(|| super::CheckpointWriter::new(checkpoint_path.clone())),
            checkpoint_path,
            scenario,
            realtime,
            scheduling,
            model,
            rec,
            events,
            loop_faults,
            beacon,
            outputs_held: false,
        })
    }

    /// A restarted plant (`--resume`) continues the flight from the checkpoint its predecessor saved. Without one
    /// (its predecessor died before saving any), it flies again from tick 0 and says so; the logger marks where
    /// the new flight joins the logged one. A checkpoint that exists but cannot be used (torn, garbage, out of
    /// range) is an error: flying again from tick 0 would splice a different flight into the run.
    pub fn resume_from_checkpoint(&mut self) -> anyhow::Result<()> {
        let path = &self.checkpoint_path;
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let detail = format!("no checkpoint in {}: flying again from tick 0", path.display());
                eprintln!("silrig-plant: warning: --resume: {detail}");
                self.events.emit(Some(0), "plant-restarted-from-start", detail);
                return Ok(());
            }
            Err(e) => anyhow::bail!("cannot resume: reading {}: {e}", path.display()),
        };
        let tick = self
            .model
            .restore(&text, self.ticks)
            .map_err(|e| anyhow::anyhow!("cannot resume: {}: {e}", path.display()))?;
        let detail = format!("continuing from the checkpoint at tick {tick}");
        self.events.emit(Some(tick), "plant-resumed", detail);
        Ok(())
    }

    /// Phase 3: tick until the end of the scenario (ticks 0..=N), a state outside the model's envelope, or SIGTERM;
    /// returns how the loop ended. The first two end with the end-of-run sample.
    pub fn fly(&mut self, ports: &mut PlantPorts) -> anyhow::Result<String> {
        self.start_clock();
        loop {
            if signals::termination_requested() {
                return Ok("terminated by signal".into());
            }
            let held = self.begin_tick(ports)?;
            let t0 = monotonic_ns();
            let last = self.sim_tick >= self.ticks;
            let actuators = self.model.step(&self.applied, last);
            self.end_tick(ports, actuators, monotonic_ns() - t0, held);
            if let Some(ended) = self.next_tick(ports)? {
                return Ok(ended);
            }
        }
    }

    /// After a tick's step: the end of the flight (the state left the model's envelope, or the scenario's last
    /// tick: the end-of-run sample goes out and how the flight ended is returned), or on to the next tick.
    pub fn next_tick(&mut self, ports: &mut PlantPorts) -> anyhow::Result<Option<String>> {
        if let Some(exit) = self.left_envelope.take() {
            self.events.emit(Some(self.sim_tick), "left-envelope", exit.clone());
            self.publish_end(ports)?;
            let last_t = self.model.t_s();
            return Ok(Some(format!("error: {exit}; the flight is logged up to t = {last_t:.2} s")));
        }
        if self.sim_tick >= self.ticks {
            self.publish_end(ports)?;
            return Ok(Some("completed".into()));
        }
        self.sim_tick += 1;
        Ok(None)
    }

    /// The end-of-run sample: the last tick's outputs once the actuators have moved under its command, so the
    /// logger's last row shows the positions that tick set (what every other row takes from the next sample).
    /// Never dropped by a loop fault.
    fn publish_end(&mut self, ports: &mut PlantPorts) -> anyhow::Result<()> {
        let sample =
            PlantSample { previous_step_exec_ns: self.step_exec_ns, ..self.sample(self.flags | wire::FLAG_END_OF_RUN) };
        ports.publisher.send(self.model.tick(), &sample)?;
        Ok(())
    }

    /// The wire sample of the model's outputs now.
    fn sample(&self, flags: u32) -> PlantSample {
        let flags = flags | if self.outputs_held { wire::FLAG_OUTPUTS_HELD } else { 0 };
        PlantSample { t_sim_s: self.model.t_s(), flags, ..PlantSample::with_outputs(&self.model.outputs()) }
    }

    /// Tick 0 is due two periods from now, giving the peers' first wake-ups a margin.
    pub fn start_clock(&mut self) {
        let period = self.schedule.period_ns;
        self.schedule = TickSchedule::new(monotonic_ns() + 2 * period, period);
        self.events.emit(Some(0), "ticking", format!("t0_ns={}", self.schedule.t0_ns));
        self.watchdog.last_fresh_ns = self.schedule.t0_ns;
        self.sim_tick = self.model.tick();
        self.watchdog.last_fresh_tick = self.sim_tick;
    }

    /// One tick: wait for its time, publish the sample, gather the command, check the controller, step.
    /// The first half of a tick: wait for its time, publish the model's outputs, gather the command, check the
    /// controller; [`Self::applied`] then holds the inputs to step with. True when the command is held (a miss).
    pub fn begin_tick(&mut self, ports: &mut PlantPorts) -> anyhow::Result<bool> {
        if self.realtime {
            self.sleep_until_due();
        } else {
            self.stay_within_logger_window(ports)?;
        }
        let receipt = self.publish(ports)?;
        self.gather_commands(ports, receipt.t_send_ns)?;
        let held = self.choose_command();
        if self.realtime && held {
            self.watch_controller();
        }
        if let Some(a) = self.applied_answers {
            *self.rec.command_age_ticks.entry(self.sim_tick - a).or_insert(0) += 1;
        }
        Ok(held)
    }

    /// The inputs the actuators follow over this tick's step.
    pub fn applied(&self) -> &[f64] {
        &self.applied
    }

    /// The tick being flown.
    pub fn sim_tick(&self) -> u64 {
        self.sim_tick
    }

    /// The scenario the run flies.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Whether the plant keeps realtime (and so saves checkpoints a restarted plant resumes from).
    pub fn is_realtime(&self) -> bool {
        self.realtime
    }

    /// Where the checkpoints go, and where a restarted plant finds its predecessor's.
    pub fn checkpoint_path(&self) -> &std::path::Path {
        &self.checkpoint_path
    }

    /// What the model announced.
    pub fn signals(&self) -> &PlantSignals {
        &self.signals
    }

    /// An event of the plant at the current tick.
    pub fn event(&self, kind: &str, detail: String) {
        self.events.emit(Some(self.sim_tick), kind, detail);
    }

    /// Add to one of the report's counters.
    pub fn count(&mut self, counter: &str, n: u64) {
        self.rec.count(counter, n);
    }

    /// The second half of a tick, once the model has stepped (in `step_exec_ns`): the next sample's flags, an
    /// overrun if the work ran past the next tick's due time, a checkpoint every few ticks (realtime), the counts.
    pub fn end_tick(
        &mut self,
        ports: &PlantPorts,
        actuators: Result<ActuatorFlags, String>,
        step_exec_ns: u64,
        held: bool,
    ) {
        let actuators = actuators.unwrap_or_else(|exit| {
            self.left_envelope = Some(exit);
            ActuatorFlags::default()
        });
        self.step_exec_ns = step_exec_ns;
        self.rec.record(STEP_EXEC, step_exec_ns as i64);
        self.flags = step_flags(actuators, held) | if self.watchdog.in_failsafe { wire::FLAG_FAILSAFE } else { 0 };
        if self.realtime {
            let late_ns = monotonic_ns() as i64 - self.schedule.deadline_ns(self.expected_wall_tick) as i64;
            if late_ns > 0 {
                // The work of this tick ran past the next tick's due time: an overrun (the Simulink/dSPACE sense).
                self.rec.count("overruns", 1);
                self.overrun_counted = true;
                let detail = format!("tick work ended {:.2} ms after the next tick was due", late_ns as f64 / 1e6);
                self.events.emit(Some(self.sim_tick), "overrun", detail);
            }
        }
        // Any realtime plant may be restarted (a planned fault, --restart on-failure, a user with --resume), so
        // recovery never depends on whether a death was planned. Written after the tick's work; its cost is in the
        // report (`checkpoint_write`).
        if self.realtime && (self.sim_tick + 1).is_multiple_of(CHECKPOINT_EVERY_TICKS) {
            let t0 = monotonic_ns();
            self.save_checkpoint();
            self.rec.record(CHECKPOINT_WRITE, (monotonic_ns() - t0) as i64);
        }
        self.rec.count("ticks", 1);
        let stats = ports.commands.stats();
        let extra = [("commands_lost", stats.lost), ("controller_restarts", stats.publisher_restarts)];
        let t_s = self.sim_tick as f64 * self.scenario.timing.dt_s;
        let duration_s = self.scenario.timing.duration_s;
        self.rec.status(self.sim_tick, t_s, duration_s, self.watchdog.in_failsafe, &extra);
    }

    /// Realtime: sleep to the tick's absolute due time; a wake-up a whole period late skips to the newest due tick.
    fn sleep_until_due(&mut self) {
        clock::sleep_until_ns(self.schedule.deadline_ns(self.expected_wall_tick));
        let outcome = self.schedule.on_wake(self.expected_wall_tick, monotonic_ns());
        self.rec.record(WAKE_LATENESS, outcome.wake_lateness_ns);
        self.wake_lateness_ns = outcome.wake_lateness_ns;
        if outcome.skipped > 0 {
            // One stall is one overrun, whether it showed first as work past the deadline or as a late start.
            if !std::mem::take(&mut self.overrun_counted) {
                self.rec.count("overruns", 1);
            }
            self.rec.count("periods_without_tick", outcome.skipped);
            let late_ms = outcome.wake_lateness_ns as f64 / 1e6;
            let detail = format!(
                "woke {late_ms:.2} ms late: {} period(s) passed without a tick; simulated time paused there (tick {} \
                 follows tick {} and is now that much behind wall time)",
                outcome.skipped,
                self.sim_tick,
                self.sim_tick.saturating_sub(1)
            );
            self.events.emit(Some(self.sim_tick), "overrun", detail);
        }
        self.expected_wall_tick = outcome.next_tick;
        self.overrun_counted = false;
    }

    /// Lockstep: keep within the logger's queue, so nothing is overwritten however slow the disk.
    fn stay_within_logger_window(&mut self, ports: &PlantPorts) -> anyhow::Result<()> {
        let deadline = monotonic_ns() + LOCKSTEP_PEER_TIMEOUT.as_nanos() as u64;
        while self.sim_tick >= self.rows_acked + LOCKSTEP_LOGGER_WINDOW {
            let rows_acked = &mut self.rows_acked;
            ports.acks.drain(|r| {
                if r.invalid.is_none() {
                    *rows_acked = (*rows_acked).max(r.sample.rows_written);
                }
            })?;
            if self.sim_tick < self.rows_acked + LOCKSTEP_LOGGER_WINDOW || signals::termination_requested() {
                break;
            }
            anyhow::ensure!(monotonic_ns() < deadline, "lockstep: the logger stopped acknowledging rows");
            let _ = ports.acks.listener().timed_wait(|_| {}, Duration::from_millis(50));
        }
        Ok(())
    }

    /// Publish this tick's sample (unless a drop fault swallows it), after any delay fault.
    fn publish(&mut self, ports: &mut PlantPorts) -> anyhow::Result<ipc::SendReceipt> {
        let effect = if self.loop_faults.is_empty() { Default::default() } else { self.loop_faults.at(self.sim_tick) };
        if effect.sleep_ns > 0 {
            std::thread::sleep(Duration::from_nanos(effect.sleep_ns));
        }
        let receipt = if effect.drop {
            self.rec.count("samples_dropped", 1);
            ipc::SendReceipt { delivered: 0, t_send_ns: monotonic_ns() }
        } else {
            let sample = PlantSample {
                wake_lateness_ns: self.wake_lateness_ns,
                previous_step_exec_ns: self.step_exec_ns,
                ..self.sample(self.flags)
            };
            if !std::mem::replace(&mut self.announced, true) {
                ports.announcer.send(self.sim_tick, &self.info)?;
            }
            ports.announcer.deliver_history()?;
            ports.publisher.send(self.sim_tick, &sample)?
        };
        self.publish_ns[(self.sim_tick % PUBLISH_STAMPS as u64) as usize] = receipt.t_send_ns;
        if let Some(beacon) = &self.beacon {
            beacon.publish(self.sim_tick);
        }
        Ok(receipt)
    }

    /// Wait for the answer to this tick whichever timing applies: next-tick applies it one tick later, but
    /// receiving it now measures the transport honestly, and lockstep never runs ahead of the controller.
    /// Realtime: poll for `spin_ns`, then block, up to the budget; lockstep: up to the peer timeout.
    fn gather_commands(&mut self, ports: &PlantPorts, t_send_ns: u64) -> anyhow::Result<()> {
        let wait_until =
            t_send_ns + if self.realtime { self.budget_ns } else { LOCKSTEP_PEER_TIMEOUT.as_nanos() as u64 };
        // Wake-ups are consumed only after a blocking wait: consuming them while a notification lands can lose the
        // wake-up for good (iceoryx2 0.10), and the next blocking wait would then sleep to its timeout.
        let mut woken = false;
        loop {
            self.take_commands(ports, woken)?;
            if self.received.iter().any(|c| c.answers_tick == self.sim_tick) || signals::termination_requested() {
                return Ok(());
            }
            let now = monotonic_ns();
            if now < t_send_ns + self.spin_ns.min(self.budget_ns) {
                match self.realtime {
                    true => std::hint::spin_loop(),
                    // Two vCPUs for three processes: a look that yields lets the logger have its turn.
                    false => std::thread::yield_now(),
                }
                continue;
            }
            if now >= wait_until {
                anyhow::ensure!(
                    self.realtime,
                    "lockstep: no command for tick {} within {LOCKSTEP_PEER_TIMEOUT:?}",
                    self.sim_tick
                );
                return Ok(());
            }
            // EINTR (SIGSTOP/SIGCONT, SIGTERM) just ends this wait early; the loop looks again.
            ports.commands.wait_readable_until(wait_until);
            woken = true;
        }
    }

    /// Drain the command queue, and its wake-ups with `consume_wakeups`: count, time and keep the newest valid
    /// commands.
    fn take_commands(&mut self, ports: &PlantPorts, consume_wakeups: bool) -> anyhow::Result<()> {
        let tick = self.sim_tick;
        let steady_from = silrig_wire::timing::WARM_UP_NS / self.scenario.timing.period_ns();
        let on_command = |r: &Received<CommandSample>| {
            let invalid = match &r.invalid {
                Some(e) => Some(e.to_string()),
                None if r.sample.flags & wire::FLAG_COMMAND_REFUSED != 0 => None,
                None => wire::check_command(&self.signals, &r.sample).err(),
            };
            if let Some(why) = invalid {
                if self.rec.counters.get("commands_invalid").is_none_or(|n| *n == 0) {
                    self.events.emit(Some(tick), "command-invalid", format!("{why}; the plant holds its last command"));
                }
                self.rec.count("commands_invalid", 1);
                return;
            }
            self.rec.count("commands_received", 1);
            let epoch = r.sample.header.epoch;
            if self.command_epoch.is_some_and(|e| e != epoch) {
                self.events.emit(Some(tick), "controller-restarted", "commands from a new controller epoch");
            }
            self.command_epoch = Some(epoch);
            self.rec.record(IPC_CONTROLLER_TO_PLANT, r.age_ns() as i64);
            let answers = r.sample.answers_tick;
            if answers <= tick && tick - answers < PUBLISH_STAMPS as u64 {
                let sent = self.publish_ns[(answers % PUBLISH_STAMPS as u64) as usize];
                self.rec.record(SENSE_TO_ACTUATE, r.t_recv_ns as i64 - sent as i64);
                if answers >= steady_from {
                    self.rec.record(SENSE_TO_ACTUATE_STEADY, r.t_recv_ns as i64 - sent as i64);
                }
            }
            if self.received.len() == 8 {
                self.received.pop_front();
            }
            self.received.push_back(r.sample);
        };
        ports.commands.take(consume_wakeups, on_command)?;
        Ok(())
    }

    /// Apply the command this tick wants (the answer to this tick, same-tick, or to the previous one, next-tick);
    /// returns true when it is missing and the last command is held (a miss).
    fn choose_command(&mut self) -> bool {
        let target = self.sim_tick.checked_sub(self.scenario.timing.command_delay_ticks());
        let Some(target) = target else { return false };
        let Some(fresh) = self.received.iter().find(|c| c.answers_tick == target).copied() else {
            self.rec.count("command_misses", 1);
            return true;
        };
        if fresh.flags & wire::FLAG_COMMAND_REFUSED != 0 {
            // The controller's session refused its command (its event says why): hold, as for a missing one.
            self.rec.count("command_misses", 1);
            self.rec.count("commands_refused_held", 1);
            return true;
        }
        self.applied.copy_from_slice(fresh.inputs());
        self.applied_answers = Some(target);
        let w = &mut self.watchdog;
        w.last_fresh_ns = monotonic_ns();
        w.last_fresh_tick = self.sim_tick;
        if w.stale || w.in_failsafe {
            let how = if w.in_failsafe { "failsafe released, " } else { "" };
            self.events.emit(Some(self.sim_tick), "controller-recovered", format!("{how}commands resumed"));
            w.stale = false;
            w.in_failsafe = false;
        }
        false
    }

    /// A held command: the controller is stale after a few periods without a fresh command, and after the hold
    /// the plant flies the failsafe (its announced hold values: the F-16's trim surfaces) until commands return.
    fn watch_controller(&mut self) {
        let tick = self.sim_tick;
        let w = &mut self.watchdog;
        let silent_ns = monotonic_ns().saturating_sub(w.last_fresh_ns);
        if !w.stale && silent_ns >= w.stale_after_ns {
            w.stale = true;
            self.events.emit(Some(tick), "controller-stale", format!("no command for {} ms", silent_ns / 1_000_000));
        }
        if !w.in_failsafe && silent_ns >= w.hold_ns {
            w.in_failsafe = true;
            let hold: Vec<String> = (self.signals.inputs.iter().zip(&w.failsafe))
                .map(|(i, v)| format!("{} {v:.3} {}", i.name, i.unit))
                .collect();
            let detail =
                format!("{} ticks after the last fresh command; holding {}", tick - w.last_fresh_tick, hold.join(", "));
            self.events.emit(Some(tick), "failsafe-engaged", detail);
        }
        if w.in_failsafe {
            self.applied.copy_from_slice(&w.failsafe);
            self.rec.count("failsafe_ticks", 1);
        }
    }

    fn save_checkpoint(&self) {
        if let (Some(w), Some(text)) = (&self.checkpoints, self.model.checkpoint()) {
            w.save(text);
        }
    }

    /// Phase 4: the report, with what the command subscriber counted.
    pub fn finish(mut self, args: &ProcessArgs, ports: &PlantPorts, ended: String) -> anyhow::Result<ProcessReport> {
        let stats = ports.commands.stats();
        self.rec.count("commands_lost", stats.lost);
        self.rec.count("controller_restarts", stats.publisher_restarts);
        let meta = ReportMeta::new(args, &self.scenario.name, self.scheduling, ended);
        Ok(self.rec.finish(meta, &args.out)?)
    }
}

/// Fly a built-in vehicle (`model`: the F-16, the quadrotor) as the plant process to the end of the scenario (or
/// SIGTERM) and write its report.
pub fn run_model_plant(
    args: &ProcessArgs,
    scenario: Scenario,
    model: Box<dyn PlantModel>,
) -> anyhow::Result<ProcessReport> {
    let mut plant = PlantLoop::setup(args, scenario, model)?;
    let mut ports = PlantPorts::connect(args, &plant.info)?;
    let ended = if ports.wait_for_peers(args.options.startup_timeout_s)? {
        if args.resume {
            plant.resume_from_checkpoint()?;
        }
        // A plant that gives up (a lockstep peer silent past its timeout) still writes its report, saying why.
        let ended = plant.fly(&mut ports).unwrap_or_else(|e| format!("error: {e:#}"));
        if ended == "completed" {
            // A controller that was not started by a launcher (`--controller external`) learns here that the run
            // is over.
            let _ = ports.announce_finished();
        }
        ended
    } else {
        "terminated by signal".into()
    };
    plant.finish(args, &ports, ended)
}
