//! `silrig-logger`: subscribes to the plant and command streams with queues deep enough to absorb a 1 s stall,
//! pairs each plant sample with the command answering it, and writes `trace.csv` (the same columns and values as
//! `silrig sim`) and `timing.csv` (per-tick stamps, flags and gaps) as it goes, flushing every few rows, so a kill
//! loses at most the last unflushed batch and never corrupts earlier lines.
//!
//! A plant sample whose command never comes (controller late, dead or stopped) is written once a few newer
//! samples have arrived, with empty (NaN) command columns, and counted; samples lost on the wire show up as
//! sequence gaps.

use super::ProcessArgs;
use super::events::EventLog;
use super::loop_faults::LoopFaults;
use super::report::{ProcessReport, Recorder, ReportMeta};
use crate::control::{ControllerDiagnostics, SurfaceCommand};
use crate::fault::FaultTarget;
use crate::ipc::{self, LoopEnd, Received, Stream};
use crate::rig::controller::snapshot;
use crate::sim::trace_row;
use crate::trace::{self, Trace};
use crate::wire::{CommandSample, LogAckSample, PlantSample};
use iceoryx2::prelude::CallbackProgression;
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::Path;

/// A plant sample waits this many newer samples for its command before it is written without one.
pub const MISSING_COMMAND_WINDOW: u64 = 10;
/// Rows per flush (0.1 s of data at 100 Hz).
pub const FLUSH_EVERY_ROWS: u64 = 10;

const IPC_PLANT_TO_LOGGER: usize = 0;
const IPC_COMMAND_TO_LOGGER: usize = 1;

/// Columns of `timing.csv`.
pub const TIMING_COLUMNS: [&str; 12] = [
    "tick",
    "plant_seq",
    "plant_epoch",
    "t_plant_send_ns",
    "t_plant_recv_ns",
    "plant_flags",
    "command_seq",
    "command_epoch",
    "t_command_send_ns",
    "t_command_recv_ns",
    "compute_ns",
    "command_missing",
];

/// Open `name` in `dir` for appending; a new file gets `header` first. Appending is what lets a restarted logger
/// continue a run's log without overwriting anything.
fn open_append(dir: &Path, name: &str, header: &str) -> std::io::Result<BufWriter<File>> {
    let path = dir.join(name);
    let fresh = std::fs::metadata(&path).map_or(true, |m| m.len() == 0);
    let mut file = OpenOptions::new().create(true).append(true).open(&path)?;
    if fresh {
        writeln!(file, "{header}")?;
    } else {
        // A writer killed mid-line leaves a torn last line; start ours on a new line so it stays the only damage.
        let text = std::fs::read(&path)?;
        if text.last() != Some(&b'\n') {
            writeln!(file)?;
        }
    }
    Ok(BufWriter::new(file))
}

struct Writer {
    trace: BufWriter<File>,
    timing: BufWriter<File>,
    nodes: usize,
    rows: u64,
    last_tick: Option<u64>,
}

impl Writer {
    fn row(&mut self, plant: &Received<PlantSample>, command: Option<&Received<CommandSample>>) -> std::io::Result<()> {
        let snap = snapshot(&plant.sample);
        let nan = f64::NAN;
        let row = match command {
            Some(c) => {
                let s = &c.sample;
                let cmd = SurfaceCommand {
                    aileron_deg: s.surface_cmd_deg[0],
                    elevator_deg: s.surface_cmd_deg[1],
                    rudder_deg: s.surface_cmd_deg[2],
                };
                let diag = ControllerDiagnostics { sliding_surface: s.sliding_surface, f_hat: s.f_hat };
                trace_row(&snap, &cmd, &diag, [s.channel_weights(0), s.channel_weights(1), s.channel_weights(2)])
            }
            None => {
                let cmd = SurfaceCommand { aileron_deg: nan, elevator_deg: nan, rudder_deg: nan };
                let diag = ControllerDiagnostics { sliding_surface: [nan; 3], f_hat: [nan; 3] };
                let w = vec![nan; self.nodes];
                trace_row(&snap, &cmd, &diag, [&w, &w, &w])
            }
        };
        writeln!(self.trace, "{}", Trace::format_row(&row))?;
        let p = &plant.sample.header;
        let (cs, ce, ct, cr, cn) =
            command.map_or((String::new(), String::new(), String::new(), String::new(), String::new()), |c| {
                let h = &c.sample.header;
                (
                    h.seq.to_string(),
                    h.epoch.to_string(),
                    h.t_send_ns.to_string(),
                    c.t_recv_ns.to_string(),
                    c.sample.compute_ns.to_string(),
                )
            });
        writeln!(
            self.timing,
            "{},{},{},{},{},{},{cs},{ce},{ct},{cr},{cn},{}",
            p.tick,
            p.seq,
            p.epoch,
            p.t_send_ns,
            plant.t_recv_ns,
            plant.sample.flags,
            u8::from(command.is_none())
        )?;
        self.rows += 1;
        self.last_tick = Some(p.tick);
        if self.rows.is_multiple_of(FLUSH_EVERY_ROWS) {
            self.flush()?;
        }
        Ok(())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.trace.flush()?;
        self.timing.flush()
    }
}

/// The last tick a previous logger of this run wrote to `trace.csv` (its last complete line), so a restarted
/// logger continues after it instead of writing a tick twice.
fn last_logged_tick(out_dir: &Path, dt_s: f64) -> Option<u64> {
    let trace = Trace::load(&out_dir.join("trace.csv")).ok()?;
    let t = trace.rows.last()?[trace.index("t_s")?];
    Some((t / dt_s).round() as u64)
}

/// Run the logger until it has written every tick of the scenario (or SIGTERM), and write its report.
pub fn run_logger(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    std::fs::create_dir_all(&args.out)?;
    let nodes = scenario.controller.rbf.nodes();
    let ticks = scenario.timing.ticks();
    let events = EventLog::new(&args.out, "logger");
    let resume_after = last_logged_tick(&args.out, scenario.timing.dt_s);
    if let Some(t) = resume_after {
        events.emit(Some(t), "logger-resumed", format!("continuing trace.csv after tick {t}"));
    }
    let mut loop_faults =
        LoopFaults::new(&scenario.faults, FaultTarget::Logger, scenario.timing.dt_s, scenario.seed, events.clone());
    let mut writer = Writer {
        trace: open_append(&args.out, "trace.csv", &trace::columns(nodes).join(","))?,
        timing: open_append(&args.out, "timing.csv", &TIMING_COLUMNS.join(","))?,
        nodes,
        rows: 0,
        last_tick: resume_after,
    };

    let node = ipc::create_node(&args.run_id, "logger")?;
    let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let ack_stream = ipc::open_stream::<LogAckSample>(&node, Stream::LogAck)?;
    let plant = plant_stream.subscriber(ipc::LOGGER_BUFFER)?;
    let commands = command_stream.subscriber(ipc::LOGGER_BUFFER)?;
    let mut acks = ack_stream.publisher()?;

    let mut rec = Recorder::new(
        "logger",
        &[
            ("ipc_plant_to_logger", "plant publish to receive at the logger"),
            ("ipc_command_to_logger", "command publish to receive at the logger"),
        ],
    );
    rec.declare(&["rows_written", "rows_without_command", "plant_ticks_missing", "invalid_samples"]);

    let waitset = ipc::rig_waitset()?;
    let plant_guard = waitset
        .attach_notification(plant.listener())
        .map_err(|e| anyhow::anyhow!("attaching the plant stream: {e:?}"))?;
    let command_guard = waitset
        .attach_notification(commands.listener())
        .map_err(|e| anyhow::anyhow!("attaching the command stream: {e:?}"))?;

    let mut pending_plant: BTreeMap<u64, Received<PlantSample>> = BTreeMap::new();
    let mut pending_command: BTreeMap<u64, Received<CommandSample>> = BTreeMap::new();
    let mut error: Option<anyhow::Error> = None;
    let mut done = false;
    let mut missing_since: Option<u64> = None;

    let mut step = |rec: &mut Recorder, final_flush: bool| -> anyhow::Result<bool> {
        plant.drain(|r| {
            if r.invalid.is_some() {
                rec.count("invalid_samples", 1);
                return;
            }
            rec.record(IPC_PLANT_TO_LOGGER, r.age_ns() as i64);
            if resume_after.is_none_or(|t| r.sample.header.tick > t) {
                pending_plant.insert(r.sample.header.tick, *r);
            }
        })?;
        commands.drain(|r| {
            if r.invalid.is_some() {
                rec.count("invalid_samples", 1);
                return;
            }
            rec.record(IPC_COMMAND_TO_LOGGER, r.age_ns() as i64);
            pending_command.insert(r.sample.answers_tick, *r);
        })?;
        let rows_before = writer.rows;
        while let Some((&tick, _)) = pending_plant.first_key_value() {
            let newest = *pending_plant.keys().next_back().expect("non-empty");
            let has_command = pending_command.contains_key(&tick);
            if !(has_command || final_flush || newest >= tick + MISSING_COMMAND_WINDOW) {
                break;
            }
            let sample = pending_plant.remove(&tick).expect("present");
            if let Some(last) = writer.last_tick
                && tick > last + 1
            {
                rec.count("plant_ticks_missing", tick - last - 1);
                events.emit(Some(tick), "plant-gap", format!("ticks {}..{} never arrived", last + 1, tick - 1));
            }
            if tick <= writer.last_tick.unwrap_or(0) && writer.rows + u64::from(resume_after.is_some()) > 0 {
                // A restarted plant re-simulating ticks already logged: keep the first record of each tick.
                continue;
            }
            let command = pending_command.remove(&tick);
            match (&command, missing_since) {
                (None, None) => {
                    missing_since = Some(tick);
                    events.emit(Some(tick), "commands-missing", "rows written without a command from here");
                }
                (Some(_), Some(from)) => {
                    missing_since = None;
                    events.emit(Some(tick), "commands-resumed", format!("{} rows without a command", tick - from));
                }
                _ => {}
            }
            if command.is_none() {
                rec.count("rows_without_command", 1);
            }
            if !loop_faults.is_empty() {
                let effect = loop_faults.at(tick);
                if effect.sleep_ns > 0 {
                    std::thread::sleep(std::time::Duration::from_nanos(effect.sleep_ns));
                }
            }
            writer.row(&sample, command.as_ref())?;
            rec.count("rows_written", 1);
            // Commands answering ticks already written can no longer be used.
            pending_command.retain(|t, _| *t > tick);
        }
        if writer.rows != rows_before {
            writer.flush()?;
            acks.send(writer.last_tick.unwrap_or(0), &LogAckSample::new(writer.rows))?;
        }
        Ok(writer.last_tick.is_some_and(|t| t + 1 >= ticks))
    };

    let exit = ipc::run_waitset(&waitset, |id| {
        if id.has_event_from(&plant_guard) || id.has_event_from(&command_guard) {
            match step(&mut rec, false) {
                Ok(true) => {
                    done = true;
                    return CallbackProgression::Stop;
                }
                Ok(false) => {}
                Err(e) => {
                    error = Some(e);
                    return CallbackProgression::Stop;
                }
            }
        }
        CallbackProgression::Continue
    })?;
    // Whatever arrived before the end is written, with or without its command.
    if error.is_none()
        && let Err(e) = step(&mut rec, true)
    {
        error = Some(e);
    }
    writer.flush()?;
    let plant_stats = plant.stats();
    let command_stats = commands.stats();
    rec.count("plant_samples_lost", plant_stats.lost);
    rec.count("command_samples_lost", command_stats.lost);
    rec.count("plant_restarts", plant_stats.publisher_restarts);
    rec.count("controller_restarts", command_stats.publisher_restarts);
    rec.count("interrupted_waits", exit.interrupts);
    let ended = match (&error, exit.end, done) {
        (Some(e), _, _) => format!("error: {e}"),
        (None, _, true) => "completed".into(),
        (None, LoopEnd::TerminationRequest, false) => "terminated by signal".into(),
        (None, LoopEnd::Stopped, false) => "stopped".into(),
    };
    let meta = ReportMeta::new(args, &scenario.name, crate::clock::current_policy().to_string(), ended);
    let report = rec.finish(meta, &args.out)?;
    match error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}
