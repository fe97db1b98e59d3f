//! `silrig-plant`: the time master. Each tick it publishes the plant sample, gathers the controller's command
//! (same-tick: waits for the answer to this tick up to a budget; next-tick: takes the answer to the previous tick),
//! holds the last command when none is in time (a miss), moves the actuators and integrates one step with the
//! same [`crate::sim::PlantRunner`] as `silrig sim`.
//!
//! Realtime: absolute-deadline ticks with `clock_nanosleep(TIMER_ABSTIME)`; a tick that starts a whole period late
//! is an overrun: the missed ticks are skipped and counted, never caught up in a burst. Lockstep: no sleeping; the
//! plant waits for every command, and never runs further ahead of the logger than its queue holds.

use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::{ProcessArgs, RigMode, period_ns, signals};
use crate::clock::{self, TickSchedule, monotonic_ns};
use crate::control::SurfaceCommand;
use crate::fault::FaultTarget;
use crate::ipc::{self, Stream};
use crate::scenario::CommandTiming;
use crate::sim::{ActuatorCommand, PlantRunner, PlantSnapshot, StepHits};
use crate::wire::{self, CommandSample, LogAckSample, PlantSample};
use anyhow::Context;
use std::collections::VecDeque;
use std::time::Duration;

/// A realtime plant with a fault plan saves a checkpoint this often, so a restarted plant continues the flight.
pub const CHECKPOINT_EVERY_TICKS: u64 = 10;

/// In lockstep the plant stays at most this many ticks ahead of the rows the logger has written (its queue holds
/// `ipc::LOGGER_BUFFER`).
pub const LOCKSTEP_LOGGER_WINDOW: u64 = 64;
/// In lockstep, a peer silent for this long is an error rather than a slow peer.
pub const LOCKSTEP_PEER_TIMEOUT: Duration = Duration::from_secs(5);

const WAKE_LATENESS: usize = 0;
const STEP_EXEC: usize = 1;
const SENSE_TO_ACTUATE: usize = 2;
const IPC_CONTROLLER_TO_PLANT: usize = 3;

/// The wire sample for a snapshot.
pub fn plant_sample(snap: &PlantSnapshot, flags: u32) -> PlantSample {
    PlantSample {
        state: snap.state.to_array(),
        surfaces_deg: snap.surfaces_deg,
        throttle: snap.throttle,
        t_sim_s: snap.t_s,
        flags,
        ..PlantSample::zeroed()
    }
}

/// Flags describing the step that led to the next sample.
fn step_flags(hits: &StepHits, held: bool) -> u32 {
    let mut flags = 0;
    if held {
        flags |= wire::FLAG_COMMAND_STALE;
    }
    if hits[..3].iter().any(|h| h.position) {
        flags |= wire::FLAG_SATURATED;
    }
    if hits[..3].iter().any(|h| h.rate) {
        flags |= wire::FLAG_RATE_LIMITED;
    }
    flags
}

/// A command as the actuators take it; the attitude controller does not command throttle, so the plant holds the
/// scenario's.
fn actuator_command(c: &CommandSample, throttle: f64) -> ActuatorCommand {
    ActuatorCommand {
        surfaces: SurfaceCommand {
            aileron_deg: c.surface_cmd_deg[0],
            elevator_deg: c.surface_cmd_deg[1],
            rudder_deg: c.surface_cmd_deg[2],
        },
        throttle,
    }
}

/// The trim surfaces of the scenario's initial airspeed and altitude, or `hold` when level flight has no trim
/// there.
fn failsafe_command(scenario: &crate::scenario::Scenario, hold: ActuatorCommand) -> ActuatorCommand {
    let model = crate::plant::F16Model::new(scenario.plant.xcg);
    let vt_fps = crate::units::m_to_ft(scenario.initial.airspeed_mps);
    match crate::plant::trim::trim_level_flight(&model, vt_fps, scenario.initial.altitude_ft) {
        Ok(trim) => ActuatorCommand {
            surfaces: SurfaceCommand { aileron_deg: 0.0, elevator_deg: trim.elevator_deg, rudder_deg: 0.0 },
            throttle: hold.throttle,
        },
        Err(_) => hold,
    }
}

/// The tick a (possibly resumed) plant starts at.
fn sim_tick_start(runner: &PlantRunner) -> u64 {
    runner.snapshot().tick
}

/// Wait until `ready()` or time out; SIGTERM ends the wait early.
fn wait_for_peers(what: &str, timeout_s: f64, ready: impl Fn() -> bool) -> anyhow::Result<bool> {
    let deadline = monotonic_ns() + (timeout_s * 1e9) as u64;
    while !ready() {
        if signals::termination_requested() {
            return Ok(false);
        }
        anyhow::ensure!(
            monotonic_ns() < deadline,
            "no {what} connected within {timeout_s} s (start silrig-controller and silrig-logger with the same --run-id)"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    Ok(true)
}

/// Run the plant process to the end of the scenario (or SIGTERM) and write its report.
pub fn run_plant(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    signals::install_termination_flag();
    let scenario = args.scenario()?;
    let realtime = args.mode == RigMode::Realtime;
    let scheduling = request_scheduling("plant", realtime, 80);

    let node = ipc::create_node(&args.run_id, "plant")?;
    let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let ack_stream = ipc::open_stream::<LogAckSample>(&node, Stream::LogAck)?;
    let mut publisher = plant_stream.publisher().context("the plant stream")?;
    let commands = command_stream.subscriber(ipc::CONSUMER_BUFFER)?;
    let acks = ack_stream.subscriber(ipc::CONSUMER_BUFFER)?;

    let mut runner = PlantRunner::new(&scenario)?;
    let ticks = scenario.timing.ticks();
    let period = period_ns(&scenario);
    let budget_ns = (args.command_budget_ms * 1e6) as u64;
    let spin_ns = if realtime { (args.command_spin_us * 1e3) as u64 } else { 0 };
    let timing = scenario.timing.command_timing;
    let mut rec = Recorder::new(
        "plant",
        &[
            ("wake_lateness", "actual minus ideal tick start (realtime only)"),
            ("step_exec", "actuators + RK4 step execution time"),
            ("sense_to_actuate", "plant publish of tick k to the command answering k received at the plant"),
            ("ipc_controller_to_plant", "command publish to receive at the plant"),
        ],
    );
    rec.declare(&[
        "ticks",
        "overruns",
        "skipped_ticks",
        "command_misses",
        "commands_received",
        "commands_invalid",
        "failsafe_ticks",
        "samples_dropped",
    ]);
    let events = EventLog::new(&args.out, "plant");
    let mut loop_faults =
        LoopFaults::new(&scenario.faults, FaultTarget::Plant, scenario.timing.dt_s, scenario.seed, events.clone());
    // Failsafe: the trim surfaces of the scenario's flight condition (the initial hold if no trim exists there).
    let failsafe = failsafe_command(&scenario, runner.initial_command());
    let stale_after_ns = period * u64::from(args.stale_after_periods.max(1));
    let hold_ns = (args.controller_hold_ms * 1e6) as u64;

    let started = wait_for_peers("controller and logger", args.startup_timeout_s, || {
        plant_stream.number_of_subscribers() >= 2 && command_stream.number_of_publishers() >= 1
    })?;

    let checkpoint_path = args.out.join("plant.checkpoint.json");
    if args.resume {
        match std::fs::read_to_string(&checkpoint_path).map(|t| serde_json::from_str::<crate::sim::PlantCheckpoint>(&t))
        {
            Ok(Ok(c)) => {
                runner.restore(&c);
                events.emit(
                    Some(c.tick),
                    "plant-resumed",
                    format!("continuing from the checkpoint at tick {}", c.tick),
                );
            }
            _ => eprintln!(
                "silrig-plant: warning: --resume without a readable {}; starting over",
                checkpoint_path.display()
            ),
        }
    }
    let throttle = runner.initial_command().throttle;
    let mut applied = runner.initial_command();
    // Tick whose sample the applied command answers (None: the initial hold, before any command).
    let mut applied_answers: Option<u64> = None;
    let mut received: VecDeque<CommandSample> = VecDeque::with_capacity(8);
    let mut publish_ns = [0u64; 16];
    let mut flags = 0u32;
    let mut rows_acked = 0u64;
    let schedule = TickSchedule::new(monotonic_ns() + 2 * period, period);
    events.emit(Some(0), "ticking", format!("t0_ns={}", schedule.t0_ns));
    let mut last_fresh_ns = schedule.t0_ns;
    let mut last_fresh_tick = sim_tick_start(&runner);
    let mut command_epoch: Option<u64> = None;
    let (mut stale, mut in_failsafe) = (false, false);
    let mut expected_wall_tick = 0u64;
    let mut sim_tick = sim_tick_start(&runner);
    let mut overrun_counted = false;
    let mut ended = if started { "completed".to_string() } else { "terminated by signal".to_string() };

    while started && sim_tick < ticks {
        if signals::termination_requested() {
            ended = "terminated by signal".into();
            break;
        }
        if realtime {
            clock::sleep_until_ns(schedule.deadline_ns(expected_wall_tick));
            let outcome = schedule.on_wake(expected_wall_tick, monotonic_ns());
            rec.record(WAKE_LATENESS, outcome.wake_lateness_ns);
            if outcome.skipped > 0 {
                // One stall is one overrun, whether it showed first as work past the deadline or as a late start.
                if !std::mem::take(&mut overrun_counted) {
                    rec.count("overruns", 1);
                }
                rec.count("skipped_ticks", outcome.skipped);
                events.emit(
                    Some(sim_tick),
                    "overrun",
                    format!(
                        "woke {:.2} ms late; {} tick(s) skipped",
                        outcome.wake_lateness_ns as f64 / 1e6,
                        outcome.skipped
                    ),
                );
            }
            expected_wall_tick = outcome.next_tick;
            overrun_counted = false;
        } else {
            // Lockstep: keep within the logger's queue, so nothing is overwritten however slow the disk.
            let deadline = monotonic_ns() + LOCKSTEP_PEER_TIMEOUT.as_nanos() as u64;
            while sim_tick >= rows_acked + LOCKSTEP_LOGGER_WINDOW {
                acks.drain(|r| {
                    if r.invalid.is_none() {
                        rows_acked = rows_acked.max(r.sample.rows_written);
                    }
                })?;
                if sim_tick < rows_acked + LOCKSTEP_LOGGER_WINDOW || signals::termination_requested() {
                    break;
                }
                anyhow::ensure!(monotonic_ns() < deadline, "lockstep: the logger stopped acknowledging rows");
                let _ = acks.listener().timed_wait(|_| {}, Duration::from_millis(50));
            }
        }

        let snap = runner.snapshot();
        let effect = if loop_faults.is_empty() { Default::default() } else { loop_faults.at(sim_tick) };
        if effect.sleep_ns > 0 {
            std::thread::sleep(Duration::from_nanos(effect.sleep_ns));
        }
        let receipt = if effect.drop {
            rec.count("samples_dropped", 1);
            ipc::SendReceipt { delivered: 0, t_send_ns: monotonic_ns() }
        } else {
            publisher.send(sim_tick, &plant_sample(&snap, flags))?
        };
        publish_ns[(sim_tick % 16) as usize] = receipt.t_send_ns;

        // The command this tick applies answers `target`: this tick (same-tick) or the previous one (next-tick).
        let target = match timing {
            CommandTiming::SameTick => Some(sim_tick),
            CommandTiming::NextTick => sim_tick.checked_sub(1),
        };
        // Wait for the answer to this tick whichever timing applies: next-tick applies it one tick later, but
        // receiving it now measures the transport honestly, and lockstep never runs ahead of the controller.
        let wait_until = receipt.t_send_ns + if realtime { budget_ns } else { LOCKSTEP_PEER_TIMEOUT.as_nanos() as u64 };
        loop {
            commands.drain(|r| {
                if r.invalid.is_some() {
                    rec.count("commands_invalid", 1);
                    return;
                }
                rec.count("commands_received", 1);
                let epoch = r.sample.header.epoch;
                if command_epoch.is_some_and(|e| e != epoch) {
                    events.emit(Some(sim_tick), "controller-restarted", "commands from a new controller epoch");
                }
                command_epoch = Some(epoch);
                rec.record(IPC_CONTROLLER_TO_PLANT, r.age_ns() as i64);
                let answers = r.sample.answers_tick;
                if answers <= sim_tick && sim_tick - answers < 16 {
                    let sent = publish_ns[(answers % 16) as usize];
                    rec.record(SENSE_TO_ACTUATE, r.t_recv_ns as i64 - sent as i64);
                }
                if received.len() == 8 {
                    received.pop_front();
                }
                received.push_back(r.sample);
            })?;
            let have = |t: u64| received.iter().any(|c| c.answers_tick == t);
            if have(sim_tick) || signals::termination_requested() {
                break;
            }
            let now = monotonic_ns();
            if now < receipt.t_send_ns + spin_ns.min(budget_ns) {
                std::hint::spin_loop();
                continue;
            }
            if now >= wait_until {
                anyhow::ensure!(realtime, "lockstep: no command for tick {sim_tick} within {LOCKSTEP_PEER_TIMEOUT:?}");
                break;
            }
            // EINTR (SIGSTOP/SIGCONT, SIGTERM) just ends this wait early; the loop looks again.
            let _ = commands.listener().timed_wait(|_| {}, Duration::from_nanos(wait_until - now));
        }

        let fresh = target.and_then(|t| received.iter().find(|c| c.answers_tick == t).copied());
        let now = monotonic_ns();
        let held = match (target, fresh) {
            (None, _) => false,
            (Some(t), Some(c)) => {
                applied = actuator_command(&c, throttle);
                applied_answers = Some(t);
                last_fresh_ns = now;
                last_fresh_tick = sim_tick;
                if stale || in_failsafe {
                    let how = if in_failsafe { "failsafe released, " } else { "" };
                    events.emit(Some(sim_tick), "controller-recovered", format!("{how}commands resumed"));
                    stale = false;
                    in_failsafe = false;
                }
                false
            }
            (Some(_), None) => {
                rec.count("command_misses", 1);
                true
            }
        };
        // Watchdog on the controller: stale after a few periods without a fresh command, failsafe after the hold.
        if realtime && held {
            let silent_ns = now.saturating_sub(last_fresh_ns);
            if !stale && silent_ns >= stale_after_ns {
                stale = true;
                events.emit(Some(sim_tick), "controller-stale", format!("no command for {} ms", silent_ns / 1_000_000));
                // A dead controller's publisher must go before a new one can take its place; a stopped one stays.
                let _ = command_stream.try_cleanup_dead_nodes();
            }
            if !in_failsafe && silent_ns >= hold_ns {
                in_failsafe = true;
                events.emit(
                    Some(sim_tick),
                    "failsafe-engaged",
                    format!(
                        "{} ticks after the last fresh command; trim surfaces: aileron {:.3}, elevator {:.3}, rudder {:.3} deg",
                        sim_tick - last_fresh_tick,
                        failsafe.surfaces.aileron_deg,
                        failsafe.surfaces.elevator_deg,
                        failsafe.surfaces.rudder_deg
                    ),
                );
            }
            if in_failsafe {
                applied = failsafe;
                rec.count("failsafe_ticks", 1);
            }
        }
        if let Some(a) = applied_answers {
            *rec.command_age_ticks.entry(sim_tick - a).or_insert(0) += 1;
        }

        let t0 = monotonic_ns();
        let hits = runner.step(&applied);
        rec.record(STEP_EXEC, (monotonic_ns() - t0) as i64);
        flags = step_flags(&hits, held) | if in_failsafe { wire::FLAG_FAILSAFE } else { 0 };
        if realtime {
            let late_ns = monotonic_ns() as i64 - schedule.deadline_ns(expected_wall_tick) as i64;
            if late_ns > 0 {
                // The work of this tick ran past the next tick's due time: an overrun (the Simulink/dSPACE sense).
                rec.count("overruns", 1);
                overrun_counted = true;
                events.emit(
                    Some(sim_tick),
                    "overrun",
                    format!("tick work ended {:.2} ms after the next tick was due", late_ns as f64 / 1e6),
                );
            }
        }
        if realtime && !scenario.faults.is_empty() && (sim_tick + 1).is_multiple_of(CHECKPOINT_EVERY_TICKS) {
            let saved = serde_json::to_string(&runner.checkpoint())
                .map_err(std::io::Error::other)
                .and_then(|t| super::write_atomically(&checkpoint_path, &t));
            if let Err(e) = saved {
                eprintln!("silrig-plant: cannot write {}: {e}", checkpoint_path.display());
            }
        }
        sim_tick += 1;
        rec.count("ticks", 1);
    }
    let stats = commands.stats();
    rec.count("commands_lost", stats.lost);
    rec.count("controller_restarts", stats.publisher_restarts);
    let meta = ReportMeta::new(args, &scenario.name, scheduling, ended);
    Ok(rec.finish(meta, &args.out)?)
}
