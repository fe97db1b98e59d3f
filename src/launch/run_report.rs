//! The merged report of one `silrig run` (`report.json` and the text it prints): the processes' reports, the OS
//! floor measured beside them, control quality of the logged trace, the fault table, failures, the figures left
//! out and leftovers.

use super::fault_report::{Discontinuity, FaultRecord, PlantResume};
use crate::floor::timer_baseline::BaselineReport;
use serde::{Deserialize, Serialize};
use silrig_flight::summary::{Summary, summarize};
use silrig_flight::trace::Trace;
use silrig_rig::report::{MachineConditions, ProcessReport};
use silrig_wire::timing::{LatencyHistogram, LatencySummary, WARM_UP_NS, summary_line, summary_table_header};
use std::path::Path;

/// The merged report of one run (`report.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RigReport {
    /// Run id.
    pub run_id: String,
    /// Scenario name.
    pub scenario: String,
    /// realtime or lockstep.
    pub mode: String,
    /// Output folder.
    pub out_dir: String,
    /// Machine conditions at the start of the run.
    pub conditions_start: MachineConditions,
    /// Machine conditions at the end of the run.
    pub conditions_end: MachineConditions,
    /// Wall time from starting the processes to the plant's last tick, s.
    pub wall_s: f64,
    /// Plant ticks per wall second (the lockstep throughput figure).
    pub cycles_per_s: f64,
    /// The three processes' reports: of a restarted process, every life's that wrote one, merged (its
    /// `lives_merged`; the notes name a life that wrote none).
    pub processes: Vec<ProcessReport>,
    /// Every process the launcher started, one entry per life, with how it ended and its report file.
    #[serde(default)]
    pub lives: Vec<ProcessLife>,
    /// The OS floor measured beside a realtime run.
    pub timer_baseline: Option<BaselineReport>,
    /// Why a realtime run that started its OS floor has none to show (it was killed from outside, say).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timer_baseline_missing: Option<String>,
    /// Control quality of the logged trace (as `silrig sim` reports it).
    pub control: Option<Summary>,
    /// Every fault of the plan and what became of it.
    pub faults: Vec<FaultRecord>,
    /// Every place the logged flight joins a re-flown one (a restarted plant), planned or not.
    #[serde(default)]
    pub discontinuities: Vec<Discontinuity>,
    /// Every restart of the plant, planned or not: the tick it flew on from and how many ticks it flew again.
    #[serde(default)]
    pub plant_resumes: Vec<PlantResume>,
    /// The scenario's duration, s.
    #[serde(default)]
    pub duration_s: f64,
    /// The user stopped the run (Ctrl-C, SIGTERM to the launcher): not a failure, but not a whole run either.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_by: Option<StoppedBy>,
    /// Processes that failed, and how.
    pub failures: Vec<String>,
    /// What the run wants the reader to know that is not a failure (a controller started by hand without a report).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// The figures the run did not draw, each with why (a plant without the paper's signals has no fig1).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub figures_left_out: Vec<FigureLeftOut>,
    /// What was left of the run's iceoryx2 resources after cleanup (empty when clean).
    pub leftovers: Vec<String>,
    /// The plant's per-tick distributions and the controller's compute time split into warm-up (the first second)
    /// and steady state.
    #[serde(default)]
    pub phases: Vec<PhaseSplit>,
}

/// A figure the run did not draw (see [`super::run_figures`]), and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureLeftOut {
    /// The figure's file, without its folder (`fig1_states.png`).
    pub figure: String,
    /// Why, in words.
    pub reason: String,
}

/// One of the plant's per-tick distributions, split at the end of the warm-up.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PhaseSplit {
    /// e.g. `plant.wake_lateness`.
    pub name: String,
    /// Ticks of the first second, µs.
    pub warm_up: LatencySummary,
    /// Ticks after it, µs.
    pub steady: LatencySummary,
}

/// The plant's per-tick wake-up lateness (realtime) and step execution time from `timing.csv`, µs.
pub(crate) fn per_tick_values_us(out: &Path, realtime: bool) -> Vec<(String, Vec<f64>)> {
    let Ok(text) = std::fs::read_to_string(out.join("timing.csv")) else { return Vec::new() };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let names: &[&str] = if realtime { &["wake_lateness_ns", "step_exec_ns"] } else { &["step_exec_ns"] };
    names
        .iter()
        .filter_map(|name| {
            let c = header.iter().position(|h| h == name)?;
            let values = rows.iter().filter_map(|r| r.get(c)?.parse::<f64>().ok()).map(|ns| ns / 1e3).collect();
            Some((format!("plant.{}", name.trim_end_matches("_ns")), values))
        })
        .collect()
}

/// When the plant held its last command because the controller's answer was not there (or was refused): the send
/// time (CLOCK_MONOTONIC ns) of each logged sample whose flags say the tick before it held one. That is the moment
/// the plant needed the command, which a check sets beside the stalls of the OS floor.
pub fn held_command_times_ns(out: &Path) -> Vec<u64> {
    let Ok(text) = std::fs::read_to_string(out.join("timing.csv")) else { return Vec::new() };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let column = |name: &str| header.iter().position(|c| *c == name);
    let (Some(sent), Some(flags)) = (column("t_plant_send_ns"), column("plant_flags")) else { return Vec::new() };
    lines
        .filter_map(|l| {
            let row: Vec<&str> = l.split(',').collect();
            let flags: u32 = row.get(flags)?.parse().ok()?;
            (flags & silrig_wire::wire::FLAG_COMMAND_STALE != 0).then(|| row.get(sent)?.parse().ok()).flatten()
        })
        .collect()
}

/// The plant's wake-up lateness (realtime), its step execution time and the controller's compute time split at the
/// end of the warm-up, from the per-tick columns of the logger's `timing.csv` (ticks by simulated time: tick * dt <
/// 1 s is warm-up).
pub fn phase_splits(out: &Path, dt_s: f64, realtime: bool) -> Vec<PhaseSplit> {
    let Ok(text) = std::fs::read_to_string(out.join("timing.csv")) else { return Vec::new() };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let column = |name: &str| header.iter().position(|c| *c == name);
    let (Some(tick), Some(wake), Some(exec), Some(compute)) =
        (column("tick"), column("wake_lateness_ns"), column("step_exec_ns"), column("compute_ns"))
    else {
        return Vec::new();
    };
    let mut columns = vec![("plant.step_exec", exec), ("controller.compute", compute)];
    if realtime {
        columns.insert(0, ("plant.wake_lateness", wake));
    }
    let warm_up_ticks = (WARM_UP_NS as f64 / 1e9 / dt_s).round() as u64;
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    columns
        .into_iter()
        .map(|(name, c)| {
            let (mut warm_up, mut steady) = (LatencyHistogram::new(), LatencyHistogram::new());
            for row in &rows {
                let (Some(t), Some(v)) =
                    (row.get(tick).and_then(|t| t.parse::<u64>().ok()), row.get(c).and_then(|v| v.parse::<i64>().ok()))
                else {
                    continue;
                };
                if t < warm_up_ticks { &mut warm_up } else { &mut steady }.record_ns(v);
            }
            PhaseSplit { name: name.into(), warm_up: warm_up.summary(), steady: steady.summary() }
        })
        .collect()
}

/// The control quality of the logged `trace` in `out`, with the plant's own announcement (read from the recording)
/// for a plant of your own, the built-in F-16's otherwise; for a plant of your own whose announcement cannot be read,
/// no summary and a note saying why (its rows would be guesses).
pub(crate) fn control_summary(
    out: &Path,
    trace: Option<&Trace>,
    scenario: &silrig_flight::scenario::Scenario,
    builtin_f16: bool,
) -> (Option<Summary>, Option<String>) {
    let Some(trace) = trace else { return (None, None) };
    if builtin_f16 {
        return (Some(summarize(trace, scenario, None)), None);
    }
    let announced = silrig_recording::reader::RecordedRun::read(out).and_then(|r| r.plant_signals());
    match announced {
        Ok(plant) => (Some(summarize(trace, scenario, Some(&plant))), None),
        Err(e) => (
            None,
            Some(format!(
                "control quality not summarised: the plant's announcement of its signals (their units, which input \
                 each actuator drives) could not be read from the recording: {e}"
            )),
        ),
    }
}

/// One life of a process the launcher started: from its start to its exit (each restart starts a new life).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ProcessLife {
    /// plant, controller or logger.
    pub process: String,
    /// 1 for the first start, 2 after the first restart, ...
    pub life: u32,
    /// Process id.
    pub pid: u32,
    /// When it started, s of wall time from the start of the run.
    pub started_at_s: f64,
    /// When the launcher saw it end, s of wall time from the start of the run.
    pub ended_at_s: Option<f64>,
    /// How it ended as the launcher saw it: `exit status 0 at the end of the run`, `killed by signal 9 (the fault
    /// plan)`, ...
    pub exit: String,
    /// The report this life wrote (`plant.report.json`, or `plant.life1.report.json` for a life that was
    /// followed by a restart), if it wrote one: a process killed with SIGKILL writes none.
    pub report: Option<String>,
}

/// A restarted process's report over all its lives: each life that wrote a report (an earlier life's kept as
/// `<role>.life<N>.report.json`) merged into the process's entry of `processes` (its latencies merged exactly
/// from their histograms, with their `.hgrm` files in `out` rewritten, its counters and CPU time summed; the last
/// report's identity and end kept), and for each life that wrote none (a SIGKILL), a note in `notes` saying what the
/// totals miss.
pub(crate) fn merge_lives(
    processes: &mut Vec<ProcessReport>,
    lives: &[ProcessLife],
    out: &Path,
    notes: &mut Vec<String>,
) {
    for role in silrig_flight::role::Role::ALL.map(|r| r.label()) {
        let role_lives: Vec<&ProcessLife> = lives.iter().filter(|l| l.process == role).collect();
        if role_lives.len() < 2 {
            continue;
        }
        let last = processes.iter().position(|p| p.process == role);
        let mut reports: Vec<(u32, ProcessReport)> = Vec::new();
        let mut missing = Vec::new();
        for l in &role_lives {
            let own = last.map(|i| &processes[i]).filter(|p| p.pid == l.pid).cloned();
            let read = || {
                let text = std::fs::read_to_string(out.join(l.report.as_ref()?)).ok()?;
                serde_json::from_str::<ProcessReport>(&text).ok()
            };
            match own.or_else(read) {
                Some(r) => reports.push((l.life, r)),
                None => missing.push(*l),
            }
        }
        let merged_lives: Vec<u32> = reports.iter().map(|(life, _)| *life).collect();
        let Some((_, mut merged)) = reports.pop() else { continue };
        for (_, r) in &reports {
            merged.cpu_s += r.cpu_s;
            for (k, v) in &r.counters {
                *merged.counters.entry(k.clone()).or_insert(0) += v;
            }
            for (k, v) in &r.command_age_ticks {
                *merged.command_age_ticks.entry(*k).or_insert(0) += v;
            }
        }
        for l in &mut merged.latencies {
            let mut h = LatencyHistogram::from_buckets(&l.buckets);
            for (_, r) in &reports {
                if let Some(e) = r.latencies.iter().find(|e| e.name == l.name) {
                    h.merge(&LatencyHistogram::from_buckets(&e.buckets));
                }
            }
            *l = silrig_rig::report::NamedLatency::new(&l.name, &l.description, &h);
            let _ = silrig_flight::files::write_atomically(&out.join(format!("{}.hgrm", l.name)), &h.hgrm());
        }
        merged.lives_merged = merged_lives.clone();
        for l in &missing {
            let span = match l.ended_at_s {
                Some(end) => format!("{:.2}..{end:.2} s", l.started_at_s),
                None => format!("from {:.2} s", l.started_at_s),
            };
            notes.push(format!(
                "{role}: life {} (pid {}, {span}, {}) wrote no report: its latencies and counters are missing from \
                 the {role}'s, which merge lives {}",
                l.life,
                l.pid,
                l.exit,
                merged_lives.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
            ));
        }
        match last {
            Some(i) => processes[i] = merged,
            None => processes.push(merged),
        }
    }
}

/// How the user stopped a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StoppedBy {
    /// SIGINT or SIGTERM.
    pub signal: String,
    /// Simulated time flown when it stopped, s (the logged trace's end).
    pub at_s: f64,
    /// The launcher's exit status (128 + the signal, as a shell reports it).
    pub exit_status: u8,
}

/// Command ages in doubling buckets (1, 2, 3-4, 5-8, ...), so a long outage is a few entries on one line and not
/// one per tick it lasted.
pub fn command_age_buckets(ages: &std::collections::BTreeMap<u64, u64>) -> Vec<String> {
    let mut buckets: std::collections::BTreeMap<(u64, u64), u64> = Default::default();
    for (&age, &count) in ages {
        let (lo, hi) = if age <= 2 {
            (age, age)
        } else {
            let hi = age.next_power_of_two();
            (hi / 2 + 1, hi)
        };
        *buckets.entry((lo, hi)).or_insert(0) += count;
    }
    buckets
        .into_iter()
        .map(|((lo, hi), n)| if lo == hi { format!("{lo}: {n}") } else { format!("{lo}-{hi}: {n}") })
        .collect()
}

impl RigReport {
    /// The report as a person reads it: conditions, a cyclictest-style table, counters, control quality, faults,
    /// failures.
    pub fn to_text(&self) -> String {
        let mut out = self.conditions_text();
        out += &self.timing_text();
        out += &self.counters_text();
        match &self.control {
            Some(s) => out += &s.to_text(),
            None => out += "no trace to summarise\n",
        }
        out += &self.faults_text();
        if let Some(s) = &self.stopped_by {
            out += &format!("stopped by the user ({}) at t = {:.2} s of {:.2} s\n", s.signal, s.at_s, self.duration_s);
        }
        for r in self.unplanned_plant_resumes() {
            out += &format!("plant restarted outside the fault plan: {}\n", r.describe());
        }
        for d in &self.discontinuities {
            out += &format!("flight discontinuity at t = {:.2} s: {}\n", d.at_s, d.detail);
        }
        for n in &self.notes {
            out += &format!("note: {n}\n");
        }
        if self.failures.is_empty() && self.stopped_by.is_none() {
            out += "all processes ended cleanly";
            if !self.discontinuities.is_empty() {
                out += &format!(
                    "; the logged flight has {} discontinuit{} (above)",
                    self.discontinuities.len(),
                    if self.discontinuities.len() == 1 { "y" } else { "ies" }
                );
            }
            out += "\n";
        } else {
            for f in &self.failures {
                out += &format!("FAILED: {f}\n");
            }
        }
        if !self.leftovers.is_empty() {
            out += &format!("iceoryx2 leftovers after cleanup: {}\n", self.leftovers.join("; "));
        }
        let path = Path::new(&self.out_dir).join("report.json");
        if path.exists() {
            out += &format!("report: {}\n", path.display());
        }
        out
    }

    /// The run, the machine, and how each process ran and ended.
    fn conditions_text(&self) -> String {
        let c = &self.conditions_start;
        let mut out = format!(
            "silrig run {}: scenario {}, {} mode, {} CPUs, load average {:.2} {:.2} {:.2} (end {:.2}), kernel {}\n",
            self.run_id,
            self.scenario,
            self.mode,
            c.cpu_count,
            c.load_average[0],
            c.load_average[1],
            c.load_average[2],
            self.conditions_end.load_average[0],
            c.kernel
        );
        for role in silrig_flight::role::Role::ALL.map(|r| r.label()) {
            let lives: Vec<&ProcessLife> = self.lives.iter().filter(|l| l.process == role).collect();
            let report = self.processes.iter().find(|p| p.process == role);
            if lives.is_empty() {
                // Not started by the launcher (`--controller external`): its report is all there is.
                if let Some(p) = report {
                    out += &format!("  {:<10} pid {:<7} {:<34} {}\n", p.process, p.pid, p.scheduling, p.ended);
                }
                continue;
            }
            for l in &lives {
                let name = if lives.len() > 1 { format!("{role} #{}", l.life) } else { role.to_string() };
                let own = report.filter(|p| p.pid == l.pid);
                let scheduling = own.map_or("-", |p| p.scheduling.as_str());
                let ended = match (own, &l.report) {
                    (Some(p), _) => p.ended.clone(),
                    (None, Some(file)) => format!("{} (its report: {file})", l.exit),
                    (None, None) => format!("{}, no report", l.exit),
                };
                let span = match l.ended_at_s {
                    Some(end) if lives.len() > 1 => format!(" [{:.2}..{:.2} s]", l.started_at_s, end),
                    _ => String::new(),
                };
                out += &format!("  {name:<10} pid {:<7} {scheduling:<34} {ended}{span}\n", l.pid);
            }
            if let Some(p) = report.filter(|_| lives.len() > 1) {
                let merged: Vec<String> = p.lives_merged.iter().map(|l| format!("#{l}")).collect();
                let unreported = lives.len().saturating_sub(merged.len().max(1));
                out += &format!(
                    "  {:<10} {} lives: the latencies and counters below merge {}{}\n",
                    "",
                    lives.len(),
                    if merged.is_empty() { "its last life's only".to_string() } else { merged.join(", ") },
                    if unreported > 0 {
                        format!(" ({unreported} wrote no report: see the notes)")
                    } else {
                        String::new()
                    }
                );
            }
        }
        out
    }

    /// Every distribution, the OS floor's last, and the plant's wake-up read against it.
    fn timing_text(&self) -> String {
        let mut out = format!("\n{}\n", summary_table_header());
        for l in self.processes.iter().flat_map(|p| &p.latencies).filter(|l| l.summary.count > 0) {
            out += &format!("{}\n", summary_line(&l.name, &l.summary));
        }
        if let Some(why) = &self.timer_baseline_missing {
            out += &format!(
                "no OS floor to read the plant's wake-up lateness against: {why}; the figures above stand alone\n"
            );
        }
        if let Some(b) = &self.timer_baseline {
            out += &format!("{}\n", summary_line("os-floor.wake_lateness", &b.lateness));
            if let Some(plant) = self.latency("plant.wake_lateness") {
                out += &format!(
                    "plant wake-up lateness p99 is {:.2}x the OS floor's p99 measured beside it ({}, {})\n",
                    plant.p99_us / b.lateness.p99_us,
                    b.source,
                    b.policy
                );
            }
        }
        if !self.phases.is_empty() {
            out += &format!(
                "\nwarm-up (the first second) apart from steady state (after it)\n{}\n",
                summary_table_header()
            );
            for p in &self.phases {
                out += &format!("{}\n", summary_line(&format!("{} warm-up", p.name), &p.warm_up));
                out += &format!("{}\n", summary_line(&format!("{} steady", p.name), &p.steady));
            }
            let floor = self.timer_baseline.as_ref().and_then(|b| Some((b, b.lateness_steady?)));
            if let Some((b, floor_steady)) = floor {
                out += &format!("{}\n", summary_line("os-floor.wake_lateness steady", &floor_steady));
                if let Some(plant) = self.phases.iter().find(|p| p.name == "plant.wake_lateness") {
                    out += &format!(
                        "steady state: plant wake-up lateness p99 is {:.2}x the OS floor's ({})\n",
                        plant.steady.p99_us / floor_steady.p99_us,
                        b.source
                    );
                }
            }
        }
        out.push('\n');
        out
    }

    /// Each process's counters, the command ages, the throughput.
    fn counters_text(&self) -> String {
        let mut out = String::new();
        for p in &self.processes {
            let counters: Vec<String> = p.counters.iter().map(|(k, v)| format!("{k} {v}")).collect();
            out += &format!("  {:<10} {}\n", p.process, counters.join(", "));
            if !p.command_age_ticks.is_empty() {
                out += &format!(
                    "  {:<10} command age at use (ticks: count) {}\n",
                    "",
                    command_age_buckets(&p.command_age_ticks).join(", ")
                );
            }
        }
        out += &format!("  wall time {:.3} s, {:.0} plant cycles/s\n\n", self.wall_s, self.cycles_per_s);
        out
    }

    /// The plant's restarts no fault of the plan accounts for (`--restart on-failure`, a plant killed from outside):
    /// the fault table shows the others.
    pub fn unplanned_plant_resumes(&self) -> impl Iterator<Item = &PlantResume> {
        self.plant_resumes.iter().filter(|r| !self.faults.iter().any(|f| f.plant_resume.as_ref() == Some(*r)))
    }

    /// The fault table (empty without faults).
    fn faults_text(&self) -> String {
        if self.faults.is_empty() {
            return String::new();
        }
        let mut out = "\nfaults (simulated s)             injected  detected  by                               failsafe  recovered  plant lost  cmd lost\n".to_string();
        let t = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
        for f in &self.faults {
            // Wall time beside simulated time once a stall or a restart has set them apart.
            let wall = match (f.injected_at_s, f.injected_at_wall_s) {
                (Some(sim), Some(wall)) if wall - sim > 0.005 => format!(" (injected at {wall:.3} s of wall time)"),
                _ => String::new(),
            };
            out += &format!(
                "  {}{wall}\n  {:<32} {:>8} {:>9}  {:<32} {:>8} {:>10} {:>11} {:>9}\n",
                f.fault,
                "",
                t(f.injected_at_s),
                t(f.detected_at_s),
                f.detected_by.clone().unwrap_or_else(|| "-".into()),
                t(f.failsafe_at_s),
                t(f.recovered_at_s),
                f.plant_samples_lost,
                f.command_samples_lost
            );
            if let Some(r) = &f.plant_resume {
                out += &format!("  {:<32} plant {}\n", "", r.describe());
            }
            if let Some(d) = &f.discontinuity {
                out += &format!("  {:<32} flight discontinuity at {:.3} s (below)\n", "", d.at_s);
            }
        }
        out
    }

    /// A latency summary by name, from any process.
    pub fn latency(&self, name: &str) -> Option<&silrig_wire::timing::LatencySummary> {
        self.processes.iter().flat_map(|p| &p.latencies).find(|l| l.name == name).map(|l| &l.summary)
    }

    /// The steady state (after the first second) of a distribution [`Self::phases`] splits, when it has values.
    pub fn steady(&self, name: &str) -> Option<&silrig_wire::timing::LatencySummary> {
        self.phases.iter().find(|p| p.name == name).map(|p| &p.steady).filter(|s| s.count > 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_ages_of_a_long_outage_fit_on_a_few_entries() {
        // One tick of each age 1..=506, as a 5 s outage leaves them, and the usual 1-tick age.
        let mut ages: std::collections::BTreeMap<u64, u64> = (1..=506).map(|a| (a, 1)).collect();
        *ages.get_mut(&1).unwrap() += 900;
        let b = command_age_buckets(&ages);
        assert_eq!(
            b,
            [
                "1: 901",
                "2: 1",
                "3-4: 2",
                "5-8: 4",
                "9-16: 8",
                "17-32: 16",
                "33-64: 32",
                "65-128: 64",
                "129-256: 128",
                "257-512: 250"
            ]
        );
    }

    #[test]
    fn the_ticks_that_held_a_command_are_the_samples_flagged_after_them() {
        let dir = std::env::temp_dir().join(format!("silrig-run-report-held-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut timing = silrig_recording::TIMING_COLUMNS.join(",") + "\n";
        // Flags 1 (held) after ticks 1 and 3; 2 (saturated) alone is not a held command.
        for (tick, flags) in [(0, 0), (1, 2), (2, 1), (3, 0), (4, 3)] {
            timing += &format!("{tick},{tick},7,{},0,{flags},0,0,0,0,0,0,0,0\n", 1000 + tick * 10);
        }
        std::fs::write(dir.join("timing.csv"), timing).unwrap();
        let held = held_command_times_ns(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(held, [1020, 1040]);
    }
}
