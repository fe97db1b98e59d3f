//! `silrig-controller`: event-driven. A WaitSet wakes it on each plant sample (with a deadline that flags the
//! plant stale); it runs the same [`crate::control::AttitudeController`] as `silrig sim` on the newest sample and
//! publishes the command with a notify.
//!
//! A controller that joins a plant already flying (a restart) blends its output from the surfaces' current
//! positions to its own command over [`BUMPLESS_BLEND_S`], so the switch from the plant's held or failsafe command
//! causes no bump. With a fault plan it saves its RBF weights every few ticks; restarted with `--resume`, it starts
//! from them instead of from zero, so it need not re-learn. While the plant is silent it idles and says so once.

use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::report::{ProcessReport, Recorder, ReportMeta, request_scheduling};
use super::{ProcessArgs, RigMode, period_ns};
use crate::clock::monotonic_ns;
use crate::control::AttitudeController;
use crate::fault::FaultTarget;
use crate::ipc::{self, LoopEnd, Stream};
use crate::sim::{PlantSnapshot, measurement, setpoint_rad};
use crate::wire::{CommandSample, MAX_RBF_NODES, PlantSample};
use anyhow::Context;
use iceoryx2::prelude::CallbackProgression;
use std::time::Duration;

/// How long a controller joining a running plant blends from the current surface positions to its command, s.
pub const BUMPLESS_BLEND_S: f64 = 0.5;

const IPC_PLANT_TO_CONTROLLER: usize = 0;
const COMPUTE: usize = 1;

/// The snapshot a plant sample carries.
pub fn snapshot(s: &PlantSample) -> PlantSnapshot {
    PlantSnapshot {
        tick: s.header.tick,
        t_s: s.t_sim_s,
        state: crate::plant::F16State::from_array(&s.state),
        surfaces_deg: s.surfaces_deg,
        throttle: s.throttle,
    }
}

/// Run the controller until SIGTERM and write its report.
pub fn run_controller(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    anyhow::ensure!(
        scenario.controller.rbf.nodes() <= MAX_RBF_NODES,
        "the rig carries at most {MAX_RBF_NODES} RBF nodes per channel, the scenario has {}",
        scenario.controller.rbf.nodes()
    );
    let scheduling = request_scheduling("controller", args.mode == RigMode::Realtime, 79);

    let node = ipc::create_node(&args.run_id, "controller")?;
    let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let samples = plant_stream.subscriber(ipc::CONSUMER_BUFFER)?;
    let mut publisher = command_stream.publisher().context("refusing to start a second controller for this run")?;

    let tables = crate::plant::F16Model::new(scenario.plant.xcg).tables();
    let mut controller = AttitudeController::new(scenario.controller.clone(), tables);
    let checkpoint_path = args.out.join("controller.checkpoint.json");
    let save_weights = !scenario.faults.is_empty() && args.mode == RigMode::Realtime;
    if args.resume {
        let loaded = std::fs::read_to_string(&checkpoint_path)
            .ok()
            .and_then(|t| serde_json::from_str::<[Vec<f64>; 3]>(&t).ok())
            .is_some_and(|w| controller.set_weights(&w));
        if !loaded {
            eprintln!(
                "silrig-controller: warning: --resume without usable weights in {}; starting from zero",
                checkpoint_path.display()
            );
        }
    }
    let setpoint = setpoint_rad(&scenario);
    let dt = scenario.timing.dt_s;
    let nodes = scenario.controller.rbf.nodes();
    let mut rec = Recorder::new(
        "controller",
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
    let events = EventLog::new(&args.out, "controller");
    let mut loop_faults = LoopFaults::new(&scenario.faults, FaultTarget::Controller, dt, scenario.seed, events.clone());
    let blend_ticks = (BUMPLESS_BLEND_S / dt).round().max(1.0) as u64;
    // (first tick of the blend, ticks left): set when this controller's first sample is not the plant's tick 0.
    let mut blend: Option<u64> = None;
    let mut plant_stale = false;

    let waitset = ipc::rig_waitset()?;
    let stale_after = Duration::from_nanos(period_ns(&scenario) * u64::from(args.stale_after_periods.max(1)));
    let guard = waitset
        .attach_deadline(samples.listener(), stale_after)
        .map_err(|e| anyhow::anyhow!("attaching the plant stream to the WaitSet: {e:?}"))?;
    let mut last_tick: Option<(u64, u64)> = None;
    let mut error: Option<anyhow::Error> = None;

    let exit = ipc::run_waitset(&waitset, |id| {
        if id.has_event_from(&guard) {
            let mut newest: Option<ipc::Received<PlantSample>> = None;
            let mut fresh = 0u64;
            let drained = samples.drain(|r| {
                if r.invalid.is_some() {
                    rec.count("samples_invalid", 1);
                } else {
                    fresh += 1;
                    newest = Some(*r);
                }
            });
            if let Err(e) = drained {
                error = Some(e.into());
                return CallbackProgression::Stop;
            }
            // After a stall several samples wait; acting on stale ones would only delay the newest.
            rec.count("samples_skipped", fresh.saturating_sub(1));
            let Some(r) = newest else { return CallbackProgression::Continue };
            let h = r.sample.header;
            if last_tick.is_some_and(|(epoch, tick)| epoch == h.epoch && tick >= h.tick) {
                return CallbackProgression::Continue;
            }
            match last_tick {
                None if h.tick > 0 => {
                    blend = Some(h.tick);
                    events.emit(
                        Some(h.tick),
                        "controller-joined",
                        format!(
                            "plant already at tick {}: {} weights, {BUMPLESS_BLEND_S} s bumpless blend",
                            h.tick,
                            if args.resume { "checkpointed" } else { "fresh" }
                        ),
                    );
                }
                Some((epoch, _)) if epoch != h.epoch => {
                    events.emit(Some(h.tick), "plant-restarted", "samples from a new plant epoch");
                }
                _ => {}
            }
            if plant_stale {
                plant_stale = false;
                events.emit(Some(h.tick), "plant-recovered", "samples resumed");
            }
            last_tick = Some((h.epoch, h.tick));
            rec.record(IPC_PLANT_TO_CONTROLLER, r.age_ns() as i64);
            let t0 = monotonic_ns();
            let snap = snapshot(&r.sample);
            let (mut command, diag) = controller.step(&measurement(&snap), &setpoint, dt);
            if let Some(start) = blend {
                let k = ((h.tick - start + 1) as f64 / blend_ticks as f64).min(1.0);
                let mix = |now: f64, cmd: f64| now + k * (cmd - now);
                command.aileron_deg = mix(snap.surfaces_deg[0], command.aileron_deg);
                command.elevator_deg = mix(snap.surfaces_deg[1], command.elevator_deg);
                command.rudder_deg = mix(snap.surfaces_deg[2], command.rudder_deg);
                if k >= 1.0 {
                    blend = None;
                }
            }
            let compute_ns = monotonic_ns() - t0;
            rec.record(COMPUTE, compute_ns as i64);
            let mut out = CommandSample {
                answers_tick: h.tick,
                surface_cmd_deg: [command.aileron_deg, command.elevator_deg, command.rudder_deg],
                throttle_cmd: r.sample.throttle,
                sliding_surface: diag.sliding_surface,
                f_hat: diag.f_hat,
                compute_ns,
                rbf_nodes: nodes as u32,
                ..CommandSample::zeroed()
            };
            for (c, net) in controller.networks().iter().enumerate() {
                out.weights[c * nodes..(c + 1) * nodes].copy_from_slice(&net.weights);
            }
            if save_weights && h.tick.is_multiple_of(10) {
                let weights: [&Vec<f64>; 3] = std::array::from_fn(|c| &controller.networks()[c].weights);
                let saved = serde_json::to_string(&weights)
                    .map_err(std::io::Error::other)
                    .and_then(|t| super::write_atomically(&checkpoint_path, &t));
                if let Err(e) = saved {
                    eprintln!("silrig-controller: cannot save weights: {e}");
                }
            }
            let effect = if loop_faults.is_empty() { Default::default() } else { loop_faults.at(h.tick) };
            if effect.sleep_ns > 0 {
                std::thread::sleep(Duration::from_nanos(effect.sleep_ns));
            }
            if effect.drop {
                rec.count("commands_dropped", 1);
                return CallbackProgression::Continue;
            }
            match publisher.send(h.tick, &out) {
                Ok(_) => rec.count("commands_sent", 1),
                Err(e) => {
                    // A NaN command is refused by the transport: say so and keep running on the next sample.
                    eprintln!("silrig-controller: tick {}: {e}", h.tick);
                    rec.count("errors", 1);
                }
            }
        } else if id.has_missed_deadline(&guard) && last_tick.is_some() {
            // Only once the plant has been seen: waiting for it to start is not staleness.
            rec.count("plant_stale_deadlines", 1);
            if !plant_stale {
                plant_stale = true;
                events.emit(
                    last_tick.map(|(_, t)| t),
                    "plant-stale",
                    format!("no plant sample for {stale_after:?}; idling"),
                );
            }
            let _ = plant_stream.try_cleanup_dead_nodes();
        }
        CallbackProgression::Continue
    })?;
    let stats = samples.stats();
    rec.count("plant_samples_lost", stats.lost);
    rec.count("plant_restarts", stats.publisher_restarts);
    let ended = match (&error, exit.end) {
        (Some(e), _) => format!("error: {e}"),
        (None, LoopEnd::TerminationRequest) => "terminated by signal".into(),
        (None, LoopEnd::Stopped) => "completed".into(),
    };
    rec.count("interrupted_waits", exit.interrupts);
    let meta = ReportMeta::new(args, &scenario.name, scheduling, ended);
    let report = rec.finish(meta, &args.out)?;
    match error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}
