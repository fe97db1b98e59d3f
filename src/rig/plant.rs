//! `silrig-plant`: the time master. Each tick it publishes the plant sample, gathers the controller's command
//! (same-tick: waits for the answer to this tick up to a budget; next-tick: takes the answer to the previous tick),
//! holds the last command when none is in time (a miss), and steps the model (actuators, then one period). It flies
//! the scenario's N + 1 samples (t = 0 to the duration; the last one only moves the actuators) and ends with an
//! end-of-run sample ([`wire::FLAG_END_OF_RUN`]) that carries the actuator positions of the last tick, which the
//! logger's last row shows. A state that leaves the model's envelope ends the flight the same way, one tick early,
//! and the process with an error.
//!
//! Realtime: absolute-deadline ticks with `clock_nanosleep(TIMER_ABSTIME)`; a tick that starts a whole period late
//! is an overrun: the periods that passed without a tick are counted and never caught up in a burst. No tick number
//! is skipped: simulated time pauses while the plant cannot run (stopped, delayed) and then falls behind wall time.
//! Lockstep: no sleeping; the plant waits for every command, and never runs further ahead of the logger than its
//! queue holds.
//!
//! The loop flies any [`PlantModel`] (the vehicle behind named signals; which one is the adapters' choice, in
//! `silrig-adapters`) and keeps everything around it: the clock, the commands, the watchdog and the failsafe (the
//! model's announced hold values), the checkpoints and the report.
//!
//! The process runs in four phases: [`PlantLoop::setup`] (scenario, model, recorder, watchdog settings),
//! [`PlantPorts::connect`] (streams, then waiting for the peers; `plant/ports.rs`), the tick loop
//! ([`PlantLoop::fly`], one tick at a time in named steps; gathering, choosing and watching the commands is
//! `plant/commands.rs`), and [`PlantLoop::finish`] (the report).

mod commands;
mod ports;

pub use ports::PlantPorts;

use super::checkpoint_slot::{self, CheckpointSlot};
use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::plant_model::{ActuatorFlags, PlantModel};
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::tick_beacon::TickBeacon;
use super::{ProcessArgs, ProcessOptions, RigMode, signals};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_wire::clock::{self, TickSchedule, monotonic_ns};
use silrig_wire::ipc::{self, RunId};
use silrig_wire::wire::{self, CommandSample, PlantInfo, PlantSample};
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

/// The controller watchdog: stale after a few periods without a fresh command, failsafe after the hold.
#[derive(Debug)]
struct Watchdog {
    stale_after_ns: u64,
    hold_ns: u64,
    /// The model's announced hold values (a trimmed aircraft's: its trim surfaces).
    failsafe: Vec<f64>,
    last_fresh_ns: u64,
    last_fresh_tick: u64,
    stale: bool,
    in_failsafe: bool,
}

impl Watchdog {
    /// Stale after `--stale-after-periods` periods of `period_ns` without a fresh command, failsafe (holding
    /// `failsafe`) after `--controller-hold-ms`.
    fn new(period_ns: u64, options: &ProcessOptions, failsafe: Vec<f64>) -> Self {
        Self {
            stale_after_ns: period_ns * u64::from(options.stale_after_periods.max(1)),
            hold_ns: (options.controller_hold_ms * 1e6) as u64,
            failsafe,
            last_fresh_ns: 0,
            last_fresh_tick: 0,
            stale: false,
            in_failsafe: false,
        }
    }
}

/// The plant's report: its timing figures (in the order of the indices above) and counters, its live status
/// published under `run_id`.
fn plant_recorder(run_id: &RunId) -> Recorder {
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
    rec.start_status(run_id);
    rec
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
    /// Realtime: the newest checkpoint in shared memory, stored by the loop itself (see [`super::checkpoint_slot`]).
    slot: Option<CheckpointSlot>,
    /// A checkpoint too large for the slot was said once.
    slot_overflow_said: bool,
    /// A restarted plant: the newest tick its predecessor published (from the tick beacon), so the restart can say
    /// how many ticks it flies again.
    predecessor_tick: Option<u64>,
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
        let rec = plant_recorder(&args.run_id);
        let events = EventLog::new(&args.out, Role::Plant.label());
        // Read before `create` says "no tick yet" again.
        let predecessor_tick =
            if args.resume { TickBeacon::open(&args.run_id).ok().and_then(|b| b.newest()) } else { None };
        let slot = match realtime.then(|| CheckpointSlot::open(&args.run_id, !args.resume)) {
            Some(Err(e)) => anyhow::bail!(
                "cannot map the plant's checkpoint slot {}: {e} (is /dev/shm mounted and writable?)",
                checkpoint_slot::slot_path(&args.run_id).display()
            ),
            Some(Ok(slot)) => Some(slot),
            None => None,
        };
        // Without it the launcher schedules process faults on the wall clock from tick 0, as it must for a plant
        // that does not use this library.
        let beacon = TickBeacon::create(&args.run_id)
            .map_err(|e| eprintln!("silrig-plant: warning: no tick beacon ({e}): process faults follow the wall clock"))
            .ok();
        let loop_faults =
            LoopFaults::new(&scenario.faults, Role::Plant, scenario.timing.dt_s, scenario.seed, events.clone());
        let info = PlantInfo::new(model.signals()).map_err(|e| anyhow::anyhow!("the plant's announcement: {e}"))?;
        let watchdog = Watchdog::new(period, &args.options, model.signals().hold());
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
            slot,
            slot_overflow_said: false,
            predecessor_tick,
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

    /// A restarted plant (`--resume`) continues the flight from the newest checkpoint its predecessor saved (its
    /// shared-memory slot, else its file). Without one (its predecessor died before saving any), it flies again
    /// from tick 0 and says so; the logger marks where the new flight joins the logged one. A checkpoint that
    /// exists but cannot be used (torn, garbage, out of range) is an error: flying again from tick 0 would splice a
    /// different flight into the run.
    pub fn resume_from_checkpoint(&mut self) -> anyhow::Result<()> {
        let Some((text, source)) = self.saved_checkpoint()? else {
            let path = self.checkpoint_path.display();
            let detail = format!("no checkpoint in {path}: flying again from tick 0{}", self.flown_again(0));
            eprintln!("silrig-plant: warning: --resume: {detail}");
            self.events.emit(Some(0), "plant-restarted-from-start", detail);
            return Ok(());
        };
        let tick =
            self.model.restore(&text, self.ticks).map_err(|e| anyhow::anyhow!("cannot resume: {source}: {e}"))?;
        let detail = format!("resumed at tick {tick} from the checkpoint in {source}{}", self.flown_again(tick));
        self.events.emit(Some(tick), "plant-resumed", detail);
        Ok(())
    }

    /// The newest checkpoint the plant's predecessor saved, and where it was: its shared-memory slot, else the
    /// file (None: neither holds one).
    pub fn saved_checkpoint(&self) -> anyhow::Result<Option<(String, String)>> {
        if let Some(text) = self.slot.as_ref().and_then(CheckpointSlot::newest) {
            return Ok(Some((text, "shared memory".into())));
        }
        let path = &self.checkpoint_path;
        match std::fs::read_to_string(path) {
            Ok(text) => Ok(Some((text, path.display().to_string()))),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => anyhow::bail!("cannot resume: reading {}: {e}", path.display()),
        }
    }

    /// What a restarted plant adds when it flies on from `tick`: how many ticks it flies again, from its
    /// predecessor's newest tick (nothing when that is unknown). The fault table reads the "K ticks flown again".
    pub fn flown_again(&self, tick: u64) -> String {
        self.predecessor_tick.map_or(String::new(), |newest| {
            let again = (newest + 1).saturating_sub(tick);
            format!("; the plant before it had flown to tick {newest}: {again} ticks flown again")
        })
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

    /// An event of the plant at `tick`: a restarted plant's resume, said before its loop reaches that tick.
    pub fn event_at(&self, tick: u64, kind: &str, detail: String) {
        self.events.emit(Some(tick), kind, detail);
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

    /// The newest checkpoint into the shared-memory slot (memory writes: what a restarted plant takes) and to the
    /// writer thread (the file, whenever that thread gets the CPU).
    fn save_checkpoint(&mut self) {
        let (Some(w), Some(text)) = (&self.checkpoints, self.model.checkpoint()) else { return };
        if let Some(slot) = &mut self.slot
            && !slot.store(&text)
            && !std::mem::replace(&mut self.slot_overflow_said, true)
        {
            let detail = format!(
                "the checkpoint is {} bytes, more than the {} of its shared-memory slot: a restarted plant resumes \
                 from the file, which can be older under load",
                text.len(),
                checkpoint_slot::SLOT_TEXT_BYTES
            );
            self.events.emit(Some(self.sim_tick), "checkpoint-not-in-memory", detail);
        }
        w.save(text);
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

/// Fly `model` as the plant process to the end of the scenario (or SIGTERM) and write its report: the process body
/// for a model stepped in this process (a model of the user's own in another process goes through
/// [`super::plant_session`] instead). Which model flies is the caller's choice (`silrig-adapters`).
pub fn run_plant_model(
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
