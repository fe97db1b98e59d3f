//! The soak's figures, from the run folder a soak leaves: what became of each fault (the launcher's fault table,
//! completed where the rig has no recovery event by the trace itself), losses inside and outside the faults' own
//! windows (those outside set beside the OS floor's stalls: [`super::losses`]), torn rows, failsafe engagements, and
//! the verdict over them and the processes' measurements.

use super::losses::{FloorStalls, losses, split_by_stalls};
use super::probe::{Leftovers, LifeProbe, ProcessProbe};
use super::schedule::{kind_label, watched};
use serde::{Deserialize, Serialize};
use silrig_flight::fault::Fault;
use silrig_launch::fault_report::FaultRecord;
use silrig_launch::floor::timer_baseline::BaselineReport;
use silrig_rig::events::read_events;
use std::collections::BTreeMap;
use std::path::Path;

/// A fault's own window reaches this far before its injection (a killed logger loses the rows it had not flushed
/// yet, up to 0.1 s) and after its recovery, s.
pub const WINDOW_MARGIN_S: f64 = 0.2;
/// The loop is whole again when this many consecutive ticks are logged with their commands; the flight is back
/// when as many hold the attitude within [`ATTITUDE_BACK_DEG`] of where it was before the fault.
pub const WHOLE_TICKS: usize = 10;
/// How close roll and pitch must come back to the band they flew in before a fault, deg.
pub const ATTITUDE_BACK_DEG: f64 = 5.0;
/// Where the flight was before a fault: the band of roll and pitch over this long before the injection, s. One tick
/// would judge an oscillating flight by its phase (seed 2's hour of 2026-11-29: a trough 7.4 deg of a 6.9 to 11.5 deg
/// pitch oscillation made the same oscillation flown again read as 5 deg off).
pub const BEFORE_BAND_S: f64 = 1.5;

/// What became of one fault of the soak.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FaultOutcome {
    /// The fault, as the run's fault table names it.
    pub fault: String,
    /// `target:action`.
    pub kind: String,
    /// Whether the rig has a detector that must fire for it (see the soak's chapter).
    pub watched: bool,
    /// Injected at, simulated s (None: not injected).
    pub injected_at_s: Option<f64>,
    /// Detected at, simulated s, and by whom.
    pub detected_at_s: Option<f64>,
    /// The detecting process and event.
    pub detected_by: Option<String>,
    /// Recovered at, simulated s.
    pub recovered_at_s: Option<f64>,
    /// `rig` (the rig's own recovery event) or `trace` (the first of 10 ticks logged in a row with their commands
    /// after the fault's end, where the rig has no recovery event for it).
    pub recovered_by: Option<String>,
    /// When the flight was back: roll and pitch within 5 deg of the band they flew in over the 1.5 s before the
    /// injection from then up to the next fault (10 ticks at least), after the fault's own end, simulated s.
    pub flight_back_at_s: Option<f64>,
    /// The largest departure of roll or pitch from that band, until the next fault, deg.
    pub max_attitude_change_deg: Option<f64>,
    /// The fault's own window for losses, simulated s.
    pub window_s: Option<(f64, f64)>,
    /// Rows missing from the log inside that window.
    pub rows_lost: u64,
}

/// One kind's totals.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct KindFigures {
    /// `target:action`.
    pub kind: String,
    /// Whether its detection is required.
    pub watched: bool,
    /// Faults of the kind injected, detected and recovered from.
    pub injected: u64,
    /// Detected.
    pub detected: u64,
    /// Recovered.
    pub recovered: u64,
    /// Whose flight came back to its attitude.
    pub flight_back: u64,
}

/// The logged rows: how many, how many lost inside and outside the faults' windows, torn, written twice.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Rows {
    /// Rows of `trace.csv`.
    pub trace_rows: u64,
    /// Rows of `timing.csv`.
    pub timing_rows: u64,
    /// Ticks missing from the log (between tick 0 and the last tick flown) inside some fault's window.
    pub lost_in_fault_windows: u64,
    /// ... outside every fault's window.
    pub lost_outside_fault_windows: u64,
    /// Of those, the ones lost in a stall the OS floor beside the run saw too: the machine's (a figure, not a
    /// failure; see [`super::losses`]).
    #[serde(default)]
    pub lost_in_machine_stalls: u64,
    /// The floor's latest wake-up in those stalls, µs.
    #[serde(default)]
    pub worst_machine_stall_us: f64,
    /// The ticks lost outside the windows with no stall of the floor's beside them (must be none), for the reader
    /// (first 20).
    pub lost_outside_ticks: Vec<u64>,
    /// Rows of either file that are not whole (a field missing or too many, a value that is not a number, no end
    /// of line) (must be 0).
    pub torn: u64,
    /// Ticks logged more than once (must be 0).
    pub duplicated: u64,
}

/// Everything the soak reports (`soak.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SoakReport {
    /// The seed the schedule came from.
    pub seed: u64,
    /// The run's length, s.
    pub duration_s: f64,
    /// Its run id and folder.
    pub run_id: String,
    /// The run's folder.
    pub out_dir: String,
    /// The `silrig run` command the soak started.
    pub command: Vec<String>,
    /// When it started (UTC, from the system clock).
    pub started_utc: String,
    /// Load average (1, 5, 15 min) at the start and the end.
    pub load_average_start: Vec<f64>,
    /// At the end.
    pub load_average_end: Vec<f64>,
    /// `silrig run`'s exit status.
    pub run_exit: Option<i32>,
    /// Faults scheduled, injected, detected (watched ones), recovered.
    pub scheduled: u64,
    /// Injected.
    pub injected: u64,
    /// `fault-injected` events in `events.jsonl` (the plant-model faults have none: they act at their time).
    pub fault_events: u64,
    /// Injected faults detected.
    pub detected: u64,
    /// Injected faults of watched kinds.
    pub watched: u64,
    /// Injected faults recovered from.
    pub recovered: u64,
    /// Injected faults after which the flight came back to its attitude.
    pub flight_back: u64,
    /// Per kind.
    pub kinds: Vec<KindFigures>,
    /// `failsafe-engaged` events.
    pub failsafe_engagements: u64,
    /// The logged rows.
    pub rows: Rows,
    /// The long-lived processes at the start (after start-up, before the first fault) and at the end (after the
    /// last fault's recovery, before the run's end).
    pub processes_start: Vec<ProcessProbe>,
    /// At the end.
    pub processes_end: Vec<ProcessProbe>,
    /// Every life of every process, measured settled and last (growth is judged within a life).
    pub lives: Vec<LifeProbe>,
    /// The run's `/dev/shm` entries at the start and at the end.
    pub run_shm_start: Vec<String>,
    /// At the end.
    pub run_shm_end: Vec<String>,
    /// What was left after the run (must be empty).
    pub leftovers: Leftovers,
    /// With `--bridge`: the controller's host on this machine.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller_host: Option<ControllerHostFigures>,
    /// Each fault.
    pub faults: Vec<FaultOutcome>,
    /// Why the soak failed (empty: it passed).
    pub problems: Vec<String>,
}

/// The controller's host of a soak with the bridge: its namespace and folder, and how often its bridge and
/// controller were started (once each, when nothing there failed: the soak faults nothing on that host).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ControllerHostFigures {
    /// The iceoryx2 namespace of the controller's half.
    pub local_run_id: String,
    /// Its folder (the controller's report, events and logs).
    pub folder: String,
    /// Starts of the controller-side bridge.
    pub bridge_starts: u32,
    /// Starts of the controller.
    pub controller_starts: u32,
    /// What was still running 10 s after the run and had to be ended (must be empty).
    #[serde(default)]
    pub still_running: Vec<String>,
}

/// What the soak measured while the run went, for [`report`].
pub struct Measured {
    /// The schedule's seed.
    pub seed: u64,
    /// Length, s.
    pub duration_s: f64,
    /// Run id.
    pub run_id: String,
    /// The run's folder.
    pub out: std::path::PathBuf,
    /// The command.
    pub command: Vec<String>,
    /// Start, UTC.
    pub started_utc: String,
    /// Load averages.
    pub load_average: (Vec<f64>, Vec<f64>),
    /// `silrig run`'s exit status.
    pub run_exit: Option<i32>,
    /// The processes and the run's `/dev/shm` entries at the start and the end.
    pub start: Option<(Vec<ProcessProbe>, Vec<String>)>,
    /// At the end.
    pub end: Option<(Vec<ProcessProbe>, Vec<String>)>,
    /// Every life of every process, settled and last.
    pub lives: Vec<LifeProbe>,
    /// After the run.
    pub leftovers: Leftovers,
    /// With `--bridge`.
    pub controller_host: Option<ControllerHostFigures>,
}

/// The figures and the verdict of a soak of `plan` (loop period `dt_s`) from its run folder and measurements.
pub fn report(plan: &[Fault], dt_s: f64, m: Measured) -> SoakReport {
    let out = m.out.as_path();
    let run_report = std::fs::read_to_string(out.join("report.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .unwrap_or_default();
    let records: Vec<FaultRecord> = serde_json::from_value(run_report["faults"].clone()).unwrap_or_default();
    let floor: Option<BaselineReport> = serde_json::from_value(run_report["timer_baseline"].clone()).ok();
    let timing = read_csv(&out.join("timing.csv"));
    let trace = read_csv(&out.join("trace.csv"));
    // (tick, command present) per logged row.
    let logged: Vec<(u64, bool)> = timing
        .rows
        .iter()
        .filter_map(|r| Some((r.first()?.parse().ok()?, r.get(11).map(|c| c.as_str()) == Some("0"))))
        .collect();
    let attitude = attitude_by_tick(&trace, dt_s);
    let mut plan: Vec<&Fault> = plan.iter().collect();
    plan.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    let last_tick = logged.iter().map(|r| r.0).max().unwrap_or(0);
    let faults: Vec<FaultOutcome> = plan
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let rec = records.iter().find(|r| r.fault == f.describe());
            let next_s = plan.get(i + 1).map_or(f64::INFINITY, |n| n.at_s);
            outcome(f, rec, &logged, &attitude, dt_s, next_s, last_tick)
        })
        .collect();
    let mut faults = faults;
    let windows_s: Vec<Option<(f64, f64)>> = faults.iter().map(|o| o.window_s).collect();
    let (per_fault, lost_out) = losses(&logged, &windows_s, dt_s, flown_to(&run_report, dt_s));
    for (o, lost) in faults.iter_mut().zip(&per_fault) {
        o.rows_lost = *lost;
    }
    let lost_in = per_fault.iter().sum();
    // The plant's send time of each logged tick, for the lost ones' place among the floor's stalls.
    let sends: BTreeMap<u64, u64> =
        timing.rows.iter().filter_map(|r| Some((r.first()?.parse().ok()?, r.get(3)?.parse().ok()?))).collect();
    let stalls = floor.as_ref().map(|b| FloorStalls { stalls: &b.stalls, period_ns: b.period_ns });
    let split = split_by_stalls(&lost_out, &sends, (dt_s * 1e9).round() as u64, stalls.as_ref());
    let rows = rows(&trace, &timing, &logged, lost_in, split);
    let events = read_events(out);
    let injected: Vec<&FaultOutcome> = faults.iter().filter(|o| o.injected_at_s.is_some()).collect();
    let mut r = SoakReport {
        seed: m.seed,
        duration_s: m.duration_s,
        run_id: m.run_id,
        out_dir: out.display().to_string(),
        command: m.command,
        started_utc: m.started_utc,
        load_average_start: m.load_average.0,
        load_average_end: m.load_average.1,
        run_exit: m.run_exit,
        scheduled: faults.len() as u64,
        injected: injected.len() as u64,
        fault_events: events.iter().filter(|e| e.kind == "fault-injected").count() as u64,
        detected: injected.iter().filter(|o| o.detected_at_s.is_some()).count() as u64,
        watched: injected.iter().filter(|o| o.watched).count() as u64,
        recovered: injected.iter().filter(|o| o.recovered_at_s.is_some()).count() as u64,
        flight_back: injected.iter().filter(|o| o.flight_back_at_s.is_some()).count() as u64,
        kinds: kinds(&plan, &faults),
        failsafe_engagements: events.iter().filter(|e| e.kind == "failsafe-engaged").count() as u64,
        rows,
        processes_start: m.start.as_ref().map(|s| s.0.clone()).unwrap_or_default(),
        processes_end: m.end.as_ref().map(|s| s.0.clone()).unwrap_or_default(),
        lives: m.lives,
        run_shm_start: m.start.map(|s| s.1).unwrap_or_default(),
        run_shm_end: m.end.map(|s| s.1).unwrap_or_default(),
        leftovers: m.leftovers,
        controller_host: m.controller_host,
        faults,
        problems: Vec::new(),
    };
    r.problems = problems(&r);
    r
}

/// The flight's last tick when the plant completed it (it flies ticks 0 to duration / dt), which the log must reach;
/// None when it did not complete (then the run has failed already, and the log's own end is taken).
fn flown_to(run_report: &serde_json::Value, dt_s: f64) -> Option<u64> {
    let plant = run_report["processes"].as_array()?.iter().find(|p| p["process"] == "plant")?;
    let duration_s = run_report["duration_s"].as_f64()?;
    (plant["ended"] == "completed").then(|| (duration_s / dt_s).round() as u64)
}

/// The rows' figures: logged, lost inside and outside the faults' windows (`lost_out`: those in the floor's stalls,
/// its worst lateness there, the others), torn and logged twice.
fn rows(trace: &Csv, timing: &Csv, logged: &[(u64, bool)], lost_in: u64, lost_out: (Vec<u64>, f64, Vec<u64>)) -> Rows {
    let mut ticks: Vec<u64> = logged.iter().map(|r| r.0).collect();
    ticks.sort_unstable();
    let before = ticks.len();
    ticks.dedup();
    Rows {
        trace_rows: trace.rows.len() as u64,
        timing_rows: timing.rows.len() as u64,
        lost_in_fault_windows: lost_in,
        lost_outside_fault_windows: (lost_out.0.len() + lost_out.2.len()) as u64,
        lost_in_machine_stalls: lost_out.0.len() as u64,
        worst_machine_stall_us: lost_out.1,
        lost_outside_ticks: lost_out.2.iter().take(20).copied().collect(),
        torn: trace.torn + timing.torn,
        duplicated: (before - ticks.len()) as u64,
    }
}

/// The figures of each kind of fault: injected, detected, recovered from, the flight back.
fn kinds(plan: &[&Fault], faults: &[FaultOutcome]) -> Vec<KindFigures> {
    let mut kinds: BTreeMap<String, KindFigures> = BTreeMap::new();
    for (f, o) in plan.iter().zip(faults) {
        let k = kinds.entry(o.kind.clone()).or_insert_with(|| KindFigures {
            kind: o.kind.clone(),
            watched: watched(f.target(), f.action()),
            ..KindFigures::default()
        });
        k.injected += o.injected_at_s.is_some() as u64;
        k.detected += (o.injected_at_s.is_some() && o.detected_at_s.is_some()) as u64;
        k.recovered += (o.injected_at_s.is_some() && o.recovered_at_s.is_some()) as u64;
        k.flight_back += (o.injected_at_s.is_some() && o.flight_back_at_s.is_some()) as u64;
    }
    kinds.into_values().collect()
}

/// The run's exit code in words: a number, or none when a signal ended it.
fn exit_in_words(code: Option<i32>) -> String {
    code.map_or_else(|| "no exit status (a signal ended it)".to_string(), |c| format!("exit status {c}"))
}

/// Why the soak failed: every figure that must be 0 and is not, every fault not injected, not detected (watched
/// kinds) or not recovered from, every process holding more descriptors or shared-memory files at the end.
fn problems(r: &SoakReport) -> Vec<String> {
    let mut p = Vec::new();
    if r.run_exit != Some(0) {
        p.push(format!("silrig run ended with {} (see its report)", exit_in_words(r.run_exit)));
    }
    for o in &r.faults {
        if o.injected_at_s.is_none() {
            p.push(format!("{}: not injected", o.fault));
        } else if o.watched && o.detected_at_s.is_none() {
            p.push(format!("{}: not detected", o.fault));
        }
        if o.injected_at_s.is_some() && o.recovered_at_s.is_none() {
            p.push(format!("{}: not recovered from", o.fault));
        }
        if o.injected_at_s.is_some() && o.flight_back_at_s.is_none() {
            p.push(format!(
                "{}: the flight did not come back within {ATTITUDE_BACK_DEG} deg of the roll and pitch it flew in the \
                 {BEFORE_BAND_S} s before it, before the next fault (largest departure {:.1} deg)",
                o.fault,
                o.max_attitude_change_deg.unwrap_or(f64::NAN)
            ));
        }
    }
    p.extend(rows_problems(&r.rows));
    if r.processes_start.is_empty() || r.processes_end.is_empty() {
        p.push("the processes were not measured at the start and the end (see the soak's chapter)".into());
    }
    for l in &r.lives {
        let (s, (fds, shm_files)) = (&l.settled, l.held_to_the_end());
        if fds > s.fds {
            p.push(format!(
                "{} (pid {}): {fds} open file descriptors at its last two looks, {} settled",
                l.process, l.pid, s.fds
            ));
        }
        if shm_files > s.shm_files {
            p.push(format!(
                "{} (pid {}): {shm_files} shared-memory files at its last two looks, {} settled",
                l.process, l.pid, s.shm_files
            ));
        }
    }
    if r.leftovers.count() > 0 {
        p.push(format!("left after the run: {}", r.leftovers.describe()));
    }
    if let Some(h) = &r.controller_host
        && (h.bridge_starts, h.controller_starts) != (1, 1)
    {
        p.push(format!(
            "the controller's host, where nothing was faulted, started its bridge {} times and its controller {}              (see {})",
            h.bridge_starts, h.controller_starts, h.folder
        ));
    }
    if let Some(h) = r.controller_host.as_ref().filter(|h| !h.still_running.is_empty()) {
        p.push(format!(
            "on the controller's host, still running 10 s after the run and ended by the soak: {}",
            h.still_running.join(", ")
        ));
    }
    p
}

/// What is wrong with the logged rows: lost outside the faults' windows with no stall of the OS floor to explain
/// them, torn, logged twice, or the two files disagreeing.
fn rows_problems(rows: &Rows) -> Vec<String> {
    let mut p = Vec::new();
    let rigs = rows.lost_outside_fault_windows - rows.lost_in_machine_stalls.min(rows.lost_outside_fault_windows);
    if rigs > 0 {
        p.push(format!(
            "{rigs} rows lost outside the faults' windows with no stall of the OS floor beside them (ticks {:?})",
            rows.lost_outside_ticks
        ));
    }
    if rows.torn > 0 {
        p.push(format!("{} torn rows", rows.torn));
    }
    if rows.duplicated > 0 {
        p.push(format!("{} ticks logged twice", rows.duplicated));
    }
    if rows.trace_rows != rows.timing_rows {
        p.push(format!("trace.csv has {} rows, timing.csv {}", rows.trace_rows, rows.timing_rows));
    }
    p
}

/// The fault's own length after its injection, s: a stop, a window, a restart's pause, a delay, dropped ticks.
fn own_length_s(f: &Fault, dt_s: f64) -> f64 {
    f.duration_s
        .or(f.restart_after_s)
        .or(f.delay_ms.map(|d| d / 1000.0))
        .or(f.ticks.map(|t| t as f64 * dt_s))
        .unwrap_or(0.0)
}

fn outcome(
    f: &Fault,
    rec: Option<&FaultRecord>,
    logged: &[(u64, bool)],
    attitude: &BTreeMap<u64, (f64, f64)>,
    dt_s: f64,
    next_s: f64,
    last_tick: u64,
) -> FaultOutcome {
    let injected_at_s = rec.and_then(|r| r.injected_at_s).filter(|t| *t <= last_tick as f64 * dt_s);
    let mut o = FaultOutcome {
        fault: f.describe(),
        kind: kind_label(f.target(), f.action()),
        watched: watched(f.target(), f.action()),
        injected_at_s,
        detected_at_s: rec.and_then(|r| r.detected_at_s),
        detected_by: rec.and_then(|r| r.detected_by.clone()),
        recovered_at_s: rec.and_then(|r| r.recovered_at_s),
        recovered_by: rec.and_then(|r| r.recovered_at_s).map(|_| "rig".to_string()),
        flight_back_at_s: None,
        max_attitude_change_deg: None,
        window_s: None,
        rows_lost: 0,
    };
    let Some(inj) = injected_at_s else { return o };
    let own_end_s = inj + own_length_s(f, dt_s);
    if o.recovered_at_s.is_none() {
        // No recovery event of the rig's for this fault: the loop is whole again when WHOLE_TICKS ticks in a row
        // after the fault's end are logged with their commands, before the next fault.
        let from = (own_end_s / dt_s).ceil() as u64;
        let by_tick: BTreeMap<u64, bool> = logged.iter().copied().collect();
        let whole = by_tick
            .range(from..)
            .map(|(k, _)| *k)
            .find(|k| (0..WHOLE_TICKS as u64).all(|j| by_tick.get(&(k + j)).copied().unwrap_or(false)));
        if let Some(k) = whole.filter(|k| (*k as f64 * dt_s) < next_s) {
            o.recovered_at_s = Some(k as f64 * dt_s);
            o.recovered_by = Some("trace".into());
        }
    }
    // The flight: roll and pitch against the band they flew in before the injection.
    let inj_tick = (inj / dt_s).floor() as u64;
    let next_tick = if next_s.is_finite() { (next_s / dt_s).floor() as u64 } else { u64::MAX };
    if let Some(band) = AttitudeBand::before(attitude, inj_tick, (BEFORE_BAND_S / dt_s).round() as u64) {
        let change = |a: &(f64, f64)| band.departure(*a);
        o.max_attitude_change_deg = attitude.range(inj_tick..next_tick).map(|(_, a)| change(a)).reduce(f64::max);
        // Back, and staying back up to the next fault: the trailing run of ticks within the bound, if it is at
        // least WHOLE_TICKS long (a flight passing through its old attitude on its way elsewhere is not back).
        let from = (own_end_s / dt_s).ceil() as u64;
        let slot: Vec<(u64, bool)> =
            attitude.range(from..next_tick).map(|(k, a)| (*k, change(a) <= ATTITUDE_BACK_DEG)).collect();
        let trailing = slot.iter().rev().take_while(|(_, ok)| *ok).count();
        if trailing >= WHOLE_TICKS {
            o.flight_back_at_s = Some(slot[slot.len() - trailing].0 as f64 * dt_s);
        }
    }
    let end_s = [Some(own_end_s), o.detected_at_s, o.recovered_at_s].into_iter().flatten().fold(inj, f64::max);
    o.window_s = Some((inj - WINDOW_MARGIN_S, end_s + WINDOW_MARGIN_S));
    o
}

/// The band of roll and pitch (deg) a flight held over a stretch of ticks.
#[derive(Debug, Clone, Copy, PartialEq)]
struct AttitudeBand {
    phi_deg: (f64, f64),
    theta_deg: (f64, f64),
}

impl AttitudeBand {
    /// Over the `ticks` logged before `tick` (at least the last logged tick at or before it); None when none is.
    fn before(attitude: &BTreeMap<u64, (f64, f64)>, tick: u64, ticks: u64) -> Option<Self> {
        let (&last, &(phi, theta)) = attitude.range(..=tick).next_back()?;
        let seed = Self { phi_deg: (phi, phi), theta_deg: (theta, theta) };
        Some(attitude.range(last.saturating_sub(ticks)..=last).fold(seed, |b, (_, &(phi, theta))| Self {
            phi_deg: (b.phi_deg.0.min(phi), b.phi_deg.1.max(phi)),
            theta_deg: (b.theta_deg.0.min(theta), b.theta_deg.1.max(theta)),
        }))
    }

    /// How far roll or pitch lie outside the band, deg (0 inside).
    fn departure(&self, (phi, theta): (f64, f64)) -> f64 {
        let outside = |(low, high): (f64, f64), x: f64| (low - x).max(x - high).max(0.0);
        outside(self.phi_deg, phi).max(outside(self.theta_deg, theta))
    }
}

/// Roll and pitch (deg) of each logged tick, from `trace.csv`.
fn attitude_by_tick(trace: &Csv, dt_s: f64) -> BTreeMap<u64, (f64, f64)> {
    let col = |name: &str| trace.header.iter().position(|h| h == name);
    let (Some(t), Some(phi), Some(theta)) = (col("t_s"), col("phi_deg"), col("theta_deg")) else {
        return BTreeMap::new();
    };
    let num = |r: &[String], i: usize| r.get(i).and_then(|v| v.parse::<f64>().ok());
    trace
        .rows
        .iter()
        .filter_map(|r| Some(((num(r, t)? / dt_s).round() as u64, (num(r, phi)?, num(r, theta)?))))
        .collect()
}

/// A CSV file's rows (as text fields), and how many of them are torn.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
    torn: u64,
}

fn read_csv(path: &Path) -> Csv {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let mut lines = text.split_inclusive('\n');
    let header: Vec<String> = lines.next().map_or(Vec::new(), |h| h.trim_end().split(',').map(String::from).collect());
    let width = header.len();
    let mut csv = Csv { header, rows: Vec::new(), torn: 0 };
    for line in lines {
        let fields: Vec<String> = line.trim_end_matches('\n').split(',').map(String::from).collect();
        let whole = line.ends_with('\n')
            && fields.len() == width
            && fields.iter().all(|v| v.is_empty() || v.parse::<f64>().is_ok());
        if whole {
            csv.rows.push(fields);
        } else {
            csv.torn += 1;
        }
    }
    csv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_lost_in_the_machines_stalls_pass_those_lost_without_one_fail() {
        let mut rows = Rows { trace_rows: 1000, timing_rows: 1000, ..Rows::default() };
        assert!(rows_problems(&rows).is_empty());
        // 195 lost outside the windows, all in a 2 s stall the floor saw.
        (rows.lost_outside_fault_windows, rows.lost_in_machine_stalls) = (195, 195);
        assert!(rows_problems(&rows).is_empty(), "{:?}", rows_problems(&rows));
        // 121 of them with no stall beside them: the rig's, and the soak fails naming them.
        (rows.lost_in_machine_stalls, rows.lost_outside_ticks) = (74, vec![196512, 196513]);
        let p = rows_problems(&rows);
        assert_eq!(p.len(), 1);
        assert!(p[0].starts_with("121 rows lost outside the faults' windows with no stall of the OS floor"), "{p:?}");
        assert!(p[0].contains("[196512, 196513]"), "{p:?}");
    }

    #[test]
    fn the_flight_is_judged_against_the_band_it_flew_before_the_fault_not_one_tick_of_it() {
        // Pitch oscillating 7 to 11 deg before the fault.
        let attitude: BTreeMap<u64, (f64, f64)> =
            (0..=150u64).map(|k| (k, (0.0, 9.0 - 2.0 * (k as f64 * 0.2).cos()))).collect();
        let band = AttitudeBand::before(&attitude, 150, 150).unwrap();
        assert!((band.theta_deg.0 - 7.0).abs() < 0.01 && (band.theta_deg.1 - 11.0).abs() < 0.01, "{band:?}");
        // The same oscillation flown again is back (12.3 deg lies 1.3 past the band, 5.3 past the trough) ...
        assert!((band.departure((0.0, 12.3)) - 1.3).abs() < 0.01);
        assert_eq!(band.departure((0.0, 9.0)), 0.0);
        // ... and a flight that left it is not, by roll as by pitch.
        assert!(band.departure((0.0, 16.5)) > ATTITUDE_BACK_DEG);
        assert!((band.departure((-6.0, 9.0)) - 6.0).abs() < 1e-9);
        // Only the ticks before the fault count; none logged before it, no band.
        assert_eq!(AttitudeBand::before(&attitude, 0, 150).unwrap().theta_deg, (7.0, 7.0));
        let late: BTreeMap<u64, (f64, f64)> = [(10, (0.0, 0.0))].into();
        assert_eq!(AttitudeBand::before(&late, 5, 150), None);
    }

    #[test]
    fn the_runs_exit_is_said_in_words() {
        assert_eq!(exit_in_words(Some(1)), "exit status 1");
        assert_eq!(exit_in_words(None), "no exit status (a signal ended it)");
    }

    #[test]
    fn a_row_cut_short_or_holding_garbage_is_torn() {
        let dir = std::env::temp_dir().join(format!("silrig-soak-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.csv");
        std::fs::write(&p, "a,b\n1,2\n3\n4,x\n5,6\n7,").unwrap();
        let csv = read_csv(&p);
        assert_eq!((csv.rows.len(), csv.torn), (2, 3));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
