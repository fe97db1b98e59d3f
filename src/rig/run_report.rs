//! The merged report of one `silrig run` (`report.json` and the text it prints): the processes' reports, the OS
//! floor measured beside them, control quality of the logged trace, the fault table, failures and leftovers; and
//! the run's figures.

use super::fault_report::FaultRecord;
use super::report::{MachineConditions, ProcessReport};
use crate::bench::timer_baseline::BaselineReport;
use crate::summary::Summary;
use crate::timing::{summary_line, summary_table_header};
use crate::trace::Trace;
use serde::{Deserialize, Serialize};
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
    /// The three processes' reports.
    pub processes: Vec<ProcessReport>,
    /// The OS floor measured beside a realtime run.
    pub timer_baseline: Option<BaselineReport>,
    /// Control quality of the logged trace (as `silrig sim` reports it).
    pub control: Option<Summary>,
    /// Every fault of the plan and what became of it.
    pub faults: Vec<FaultRecord>,
    /// The scenario's duration, s.
    #[serde(default)]
    pub duration_s: f64,
    /// The user stopped the run (Ctrl-C, SIGTERM to the launcher): not a failure, but not a whole run either.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_by: Option<StoppedBy>,
    /// Processes that failed, and how.
    pub failures: Vec<String>,
    /// What was left of the run's iceoryx2 resources after cleanup (empty when clean).
    pub leftovers: Vec<String>,
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

/// The closed-loop figures of the logged trace and the latency distributions of every process.
pub(super) fn write_plots(report: &RigReport, out: &Path, scenario: &crate::scenario::Scenario) -> anyhow::Result<()> {
    if report.control.is_some() {
        let trace = Trace::load(&out.join("trace.csv"))?;
        // Rows without a command (a lost controller) have NaN command columns, which the plots skip.
        let f_true = crate::f_true::from_trace(&trace, scenario);
        crate::plot::plot_closed_loop(&trace, f_true.as_ref(), out, &crate::outputs::plot_title(scenario))?;
    }
    let mut series: Vec<(String, Vec<(f64, f64)>)> = report
        .processes
        .iter()
        .flat_map(|p| &p.latencies)
        .filter(|l| {
            l.summary.count > 0
                && !["step_exec", "compute", "checkpoint_write"].iter().any(|work| l.name.ends_with(work))
        })
        .map(|l| (l.name.clone(), l.percentile_points.clone()))
        .collect();
    if let Some(b) = &report.timer_baseline {
        series.push(("os-floor.wake_lateness".into(), b.percentile_points.clone()));
    }
    if !series.is_empty() {
        let title = format!("{} ({}, run {}): latency distributions", report.scenario, report.mode, report.run_id);
        crate::plot::plot_percentile_distributions(&series, out, "latency", &title)?;
    }
    if !report.faults.is_empty() && report.control.is_some() {
        let trace = Trace::load(&out.join("trace.csv"))?;
        let mut marks = Vec::new();
        for f in &report.faults {
            let short = f.fault.split(',').next().unwrap_or(&f.fault).to_string();
            if let Some(t) = f.injected_at_s {
                marks.push(crate::plot::TimelineEvent { t_s: t, label: short.clone() });
            }
            if let Some(t) = f.failsafe_at_s {
                marks.push(crate::plot::TimelineEvent { t_s: t, label: "failsafe".into() });
            }
            if let Some(t) = f.recovered_at_s {
                marks.push(crate::plot::TimelineEvent { t_s: t, label: "recovered".into() });
            }
        }
        let title = format!("{} ({}, run {}): faults", report.scenario, report.mode, report.run_id);
        crate::plot::plot_timeline(&trace, &marks, out, "faults", &title)?;
    }
    Ok(())
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
        if self.failures.is_empty() && self.stopped_by.is_none() {
            out += "all processes ended cleanly\n";
        } else {
            for f in &self.failures {
                out += &format!("FAILED: {f}\n");
            }
        }
        if !self.leftovers.is_empty() {
            out += &format!("iceoryx2 leftovers after cleanup: {}\n", self.leftovers.join("; "));
        }
        out += &format!("report: {}/report.json\n", self.out_dir);
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
        for p in &self.processes {
            out += &format!("  {:<10} pid {:<7} {:<34} {}\n", p.process, p.pid, p.scheduling, p.ended);
        }
        out
    }

    /// Every distribution, the OS floor's last, and the plant's wake-up read against it.
    fn timing_text(&self) -> String {
        let mut out = format!("\n{}\n", summary_table_header());
        for l in self.processes.iter().flat_map(|p| &p.latencies).filter(|l| l.summary.count > 0) {
            out += &format!("{}\n", summary_line(&l.name, &l.summary));
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
                let ages: Vec<String> = p.command_age_ticks.iter().map(|(a, n)| format!("{a}: {n}")).collect();
                out += &format!("  {:<10} command age at use (ticks: count) {}\n", "", ages.join(", "));
            }
        }
        out += &format!("  wall time {:.3} s, {:.0} plant cycles/s\n\n", self.wall_s, self.cycles_per_s);
        out
    }

    /// The fault table (empty without faults).
    fn faults_text(&self) -> String {
        if self.faults.is_empty() {
            return String::new();
        }
        let mut out = "\nfaults (s from tick 0)            injected  detected  by                               failsafe  recovered  plant lost  cmd lost\n".to_string();
        let t = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
        for f in &self.faults {
            out += &format!(
                "  {}\n  {:<32} {:>8} {:>9}  {:<32} {:>8} {:>10} {:>11} {:>9}\n",
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
        }
        out
    }

    /// A latency summary by name, from any process.
    pub fn latency(&self, name: &str) -> Option<&crate::timing::LatencySummary> {
        self.processes.iter().flat_map(|p| &p.latencies).find(|l| l.name == name).map(|l| &l.summary)
    }
}
