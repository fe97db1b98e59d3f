//! The logger's writer: every row to each sink (`trace.csv` and `timing.csv`, the MCAP recording), so the pairing
//! and restart logic of [`super::logger`] is written once; flushed in batches ([`FLUSH_PERIOD_NS`]), and continued
//! after a previous logger's last row under its header.

use super::ProcessArgs;
use super::events::EventLog;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_flight::trace::Trace;
use silrig_recording::csv::CsvSink;
use silrig_recording::mcap_file::McapSink;
use silrig_recording::{LoggedRow, RecordingMeta, RowSink};
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::Received;
use silrig_wire::wire::{CommandSample, PlantInfo, PlantSample};
use std::net::SocketAddr;

/// The sinks are flushed this long after their last flush, once a row has come since, ns: 10 rows at 100 Hz in
/// realtime; in lockstep (about 2,000 rows at 20,000 ticks/s) it keeps the syscalls and the recording's chunks off
/// the per-tick cost. A kill loses at most this much of the trace.
pub const FLUSH_PERIOD_NS: u64 = 100_000_000;
/// What the logger has written, and where it writes: every row goes to each sink (the CSV files, the MCAP
/// recording), so the pairing and restart logic above them is written once.
pub(super) struct Writer {
    sinks: Vec<Box<dyn RowSink>>,
    /// Set once the sinks have the trace's columns (the first row, or a previous logger's `trace.csv` header).
    pub(super) started: bool,
    /// A previous logger's `trace.csv` header, which this one continues under.
    pub(super) previous_columns: Option<Vec<String>>,
    /// The diagnostic columns of the trace, after its loop columns.
    pub(super) diagnostic_names: Vec<String>,
    pub(super) rows: u64,
    pub(super) last_tick: Option<u64>,
    /// The plant sample of the last row written (its epoch tells which plant life flew it).
    pub(super) last_written: Option<PlantSample>,
    /// The trace's `flight_segment`: one more at each flight discontinuity.
    pub(super) flight_segment: u32,
    /// When the sinks were last flushed, ns.
    flushed_ns: u64,
    /// Rows written since the last flush.
    unflushed: u64,
    /// The row's diagnostics, reused from row to row.
    diagnostics: Vec<f64>,
    /// The row's trace values, reused from row to row.
    trace_row: Vec<f64>,
}

impl Writer {
    /// Open the sinks (`trace.csv` and `timing.csv`, the MCAP recording, served live on `live_foxglove` if
    /// given) after whatever a previous logger of this run wrote: its last tick, which this one continues after, is
    /// returned beside the writer, its header and flight segment kept.
    pub(super) fn open(
        args: &ProcessArgs,
        scenario: &Scenario,
        events: &EventLog,
        live_foxglove: Option<SocketAddr>,
    ) -> anyhow::Result<(Self, Option<u64>)> {
        // What a previous logger of this run wrote, if anything.
        let previous = Trace::load_last_row(&args.out.join("trace.csv")).ok();
        let resume_after = previous.as_ref().and_then(|p| last_logged_tick(p, scenario.timing.dt_s));
        // A restarted logger continues the segment count where its predecessor's last row left it.
        let previous_segment =
            previous.as_ref().and_then(|p| Some(p.rows.last()?[p.index("flight_segment")?])).map_or(0, |s| s as u32);
        if let Some(t) = resume_after {
            events.emit(Some(t), "logger-resumed", format!("continuing trace.csv after tick {t}"));
        }
        let meta = RecordingMeta {
            run_id: args.run_id.to_string(),
            scenario_name: scenario.name.clone(),
            scenario_toml: scenario.to_toml(),
            mode: args.mode.label().into(),
            ticks: scenario.timing.ticks(),
        };
        let tap = match live_foxglove {
            Some(addr) => {
                let tap = crate::live_foxglove::serve(addr, &args.run_id.to_string())?;
                events.emit(None, "live-serving", format!("Foxglove WebSocket server on ws://{addr}"));
                Some(tap)
            }
            None => None,
        };
        let recording = McapSink::create(&args.out, &meta, tap)?;
        if resume_after.is_some() {
            let file = recording.path().display().to_string();
            events.emit(resume_after, "recording-continued", format!("the recording continues in {file}"));
        }
        let writer = Writer {
            sinks: vec![Box::new(CsvSink::open(&args.out)?), Box::new(recording)],
            started: false,
            previous_columns: previous.as_ref().map(|p| p.columns.clone()),
            diagnostic_names: Vec::new(),
            rows: 0,
            last_tick: resume_after,
            last_written: None,
            flight_segment: previous_segment,
            flushed_ns: monotonic_ns(),
            unflushed: 0,
            diagnostics: Vec::new(),
            trace_row: Vec::new(),
        };
        Ok((writer, resume_after))
    }

    /// Give the sinks the trace's columns for `plant` with these diagnostics, unless they have them. A previous
    /// logger's header is kept, its diagnostics included, if it starts with this plant's columns.
    pub(super) fn start_trace(&mut self, plant: &PlantSignals, diagnostic_names: &[String]) -> anyhow::Result<()> {
        if self.started {
            return Ok(());
        }
        let mut columns = plant.trace_columns(diagnostic_names);
        if let Some(previous) = self.previous_columns.take() {
            let ours = plant.trace_columns(&[]);
            anyhow::ensure!(
                previous.starts_with(&ours),
                "trace.csv of this run has the columns {} but plant {} writes {}: it is another plant's trace",
                previous.join(","),
                plant.plant,
                ours.join(",")
            );
            self.diagnostic_names = previous[ours.len()..].to_vec();
            columns = previous;
        } else {
            self.diagnostic_names = diagnostic_names.to_vec();
        }
        for sink in &mut self.sinks {
            sink.start(&columns)?;
        }
        self.started = true;
        Ok(())
    }

    pub(super) fn row(
        &mut self,
        plant: &PlantSignals,
        sample: &Received<PlantSample>,
        next: Option<&PlantSample>,
        command: Option<&Received<CommandSample>>,
        step_exec_ns: Option<u64>,
        end_of_run: Option<&Received<PlantSample>>,
    ) -> std::io::Result<()> {
        // The trace's columns are fixed by its header: missing diagnostics are empty, extra ones dropped.
        let diagnostics = &mut self.diagnostics;
        diagnostics.clear();
        diagnostics.resize(self.diagnostic_names.len(), f64::NAN);
        if let Some(c) = command {
            let given = c.sample.diagnostics();
            let n = given.len().min(diagnostics.len());
            diagnostics[..n].copy_from_slice(&given[..n]);
        }
        plant.trace_row(
            &mut self.trace_row,
            sample.sample.t_sim_s,
            sample.sample.outputs(),
            command.map(|c| c.sample.inputs()),
            next.map(PlantSample::outputs),
            self.flight_segment,
            &self.diagnostics,
        );
        let row = LoggedRow { plant: sample, command, step_exec_ns, end_of_run, trace: &self.trace_row };
        for sink in &mut self.sinks {
            sink.row(&row)?;
        }
        self.rows += 1;
        self.last_tick = Some(sample.sample.header.tick);
        self.last_written = Some(sample.sample);
        self.unflushed += 1;
        Ok(())
    }

    /// Flush when rows have come since the last flush and [`FLUSH_PERIOD_NS`] has passed.
    pub(super) fn flush_if_due(&mut self) -> std::io::Result<()> {
        if self.unflushed > 0 && monotonic_ns() >= self.flushed_ns + FLUSH_PERIOD_NS {
            self.flush()?;
        }
        Ok(())
    }

    /// Hand the plant's announcement to the sinks (the recording keeps it, for viewers and replay).
    pub(super) fn announce_plant(&mut self, info: &PlantInfo) -> std::io::Result<()> {
        for sink in &mut self.sinks {
            sink.plant(info)?;
        }
        Ok(())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        for sink in &mut self.sinks {
            sink.flush()?;
        }
        (self.flushed_ns, self.unflushed) = (monotonic_ns(), 0);
        Ok(())
    }

    pub(super) fn finish(&mut self) -> std::io::Result<()> {
        for sink in &mut self.sinks {
            sink.finish()?;
        }
        Ok(())
    }
}

/// The last tick a previous logger of this run wrote to its trace (its last complete line), so a restarted logger
/// continues after it instead of writing a tick twice.
fn last_logged_tick(trace: &Trace, dt_s: f64) -> Option<u64> {
    let t = trace.rows.last()?[trace.index("t_s")?];
    Some((t / dt_s).round() as u64)
}
