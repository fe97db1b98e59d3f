//! What each rig process reports at its end (`<process>.report.json` plus one `.hgrm` file per distribution), and
//! the conditions a timing figure needs to be read honestly: scheduling policy, CPU count, load average.

use serde::{Deserialize, Serialize};
use silrig_flight::role::Role;
use silrig_wire::timing::{LatencyHistogram, LatencySummary};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One timing distribution of a process.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct NamedLatency {
    /// Short name, also the `.hgrm` file stem (e.g. `plant.wake_lateness`).
    pub name: String,
    /// What was measured, from when to when.
    pub description: String,
    /// The distribution, µs.
    pub summary: LatencySummary,
    /// `(percentile, µs)` points for plots.
    #[serde(default)]
    pub percentile_points: Vec<(f64, f64)>,
    /// The histogram itself ([`LatencyHistogram::buckets`]: value ns, count), so the reports of a restarted
    /// process's lives merge exactly.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub buckets: Vec<(u64, u64)>,
}

impl NamedLatency {
    /// The distribution `h` named `name` (described by `description`).
    pub fn new(name: &str, description: &str, h: &LatencyHistogram) -> Self {
        Self {
            name: name.into(),
            description: description.into(),
            summary: h.summary(),
            percentile_points: h.percentile_points(),
            buckets: h.buckets(),
        }
    }
}

/// The end-of-run report of one process.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ProcessReport {
    /// plant, controller or logger.
    pub process: String,
    /// Process id.
    pub pid: u32,
    /// Run id.
    pub run_id: String,
    /// Scenario name.
    pub scenario: String,
    /// realtime or lockstep.
    pub mode: String,
    /// Scheduling obtained, e.g. "SCHED_FIFO 80, memory locked".
    pub scheduling: String,
    /// How the process ended: "completed", "terminated by signal", or an error.
    pub ended: String,
    /// Timing distributions.
    pub latencies: Vec<NamedLatency>,
    /// Counters (ticks, misses, overruns, lost samples, ...).
    pub counters: BTreeMap<String, u64>,
    /// Command age at use, in ticks -> number of ticks (plant only).
    #[serde(default)]
    pub command_age_ticks: BTreeMap<u64, u64>,
    /// CPU time the process used, user plus system, s (what it costs beside the loop's figures).
    #[serde(default)]
    pub cpu_s: f64,
    /// A restarted process: the lives (1, 2, ...) whose reports these figures merge, latencies merged and counters
    /// and CPU time summed (the run's `lives` give each one's span; a life killed with SIGKILL wrote none, and the
    /// run's notes say what is missing). Empty: one life's report.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lives_merged: Vec<u32>,
}

/// CPU time this process has used so far, user plus system, s.
fn process_cpu_s() -> f64 {
    // SAFETY: getrusage fills the struct we own; RUSAGE_SELF is always valid.
    let usage = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_SELF, &mut usage);
        usage
    };
    let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    s(usage.ru_utime) + s(usage.ru_stime)
}

/// What a controller (`super::controller::Controller::figures`) adds to the controller's report: distributions
/// (short name, what was measured from when to when, the histogram) and counters by name.
#[derive(Debug, Default)]
pub struct ControllerFigures {
    /// Distributions, named as the session's own (the report prefixes `controller.`).
    pub distributions: Vec<(String, String, LatencyHistogram)>,
    /// Counters.
    pub counters: Vec<(String, u64)>,
}

/// Collects a process's distributions and counters while it runs.
#[derive(Debug)]
pub struct Recorder {
    process: String,
    histograms: Vec<(String, String, LatencyHistogram)>,
    /// Counters by name.
    pub counters: BTreeMap<String, u64>,
    /// Command age at use in ticks (plant only).
    pub command_age_ticks: BTreeMap<u64, u64>,
    /// The live status this process publishes, once started.
    status: Option<super::status::StatusFeed>,
}

impl Recorder {
    /// A recorder for `process` with the named distributions (name, description).
    pub fn new(process: &str, distributions: &[(&str, &str)]) -> Self {
        Self {
            process: process.into(),
            histograms: distributions
                .iter()
                .map(|(n, d)| (format!("{process}.{n}"), d.to_string(), LatencyHistogram::new()))
                .collect(),
            counters: BTreeMap::new(),
            command_age_ticks: BTreeMap::new(),
            status: None,
        }
    }

    /// Publish this process's live status for `run` from now on ([`super::status`]).
    pub fn start_status(&mut self, run: &silrig_wire::ipc::RunId) {
        let prefix = format!("{}.", self.process);
        let names = self.histograms.iter().map(|(n, _, _)| n.trim_start_matches(&prefix).to_string()).collect();
        self.status = Some(super::status::StatusFeed::start(run, &self.process, names));
    }

    /// At most once a second, hand the counters over to the live status; `extra` are counters the process keeps
    /// elsewhere until its end (a subscriber's losses and restarts).
    pub fn status(&mut self, tick: u64, sim_s: f64, duration_s: f64, failsafe: bool, extra: &[(&str, u64)]) {
        let Some(feed) = self.status.as_mut().filter(|f| f.snapshot_due()) else { return };
        let mut counters = self.counters.clone();
        counters.extend(extra.iter().map(|(k, v)| (k.to_string(), *v)));
        feed.snapshot(super::status::ProcessStatus {
            process: self.process.clone(),
            pid: std::process::id(),
            tick,
            sim_s,
            duration_s,
            p99_us: BTreeMap::new(),
            counters,
            failsafe,
            taken_ns: silrig_wire::clock::monotonic_ns(),
        });
    }

    /// Record `value_ns` into distribution `index` (the order given to [`Recorder::new`]).
    #[inline]
    pub fn record(&mut self, index: usize, value_ns: i64) {
        self.histograms[index].2.record_ns(value_ns);
        if let Some(feed) = &self.status {
            feed.value(index, value_ns);
        }
    }

    /// Add `n` to a counter.
    #[inline]
    pub fn count(&mut self, counter: &str, n: u64) {
        if let Some(c) = self.counters.get_mut(counter) {
            *c += n;
        } else {
            self.counters.insert(counter.to_string(), n);
        }
    }

    /// Add a distribution measured elsewhere (named as those of [`Recorder::new`]), reported beside the others.
    pub fn add_distribution(&mut self, name: &str, description: &str, h: LatencyHistogram) {
        self.histograms.push((format!("{}.{name}", self.process), description.to_string(), h));
    }

    /// Make sure a counter shows up in the report even when it stays 0.
    pub fn declare(&mut self, counters: &[&str]) {
        for c in counters {
            self.counters.entry(c.to_string()).or_insert(0);
        }
    }

    /// Finish: the report, with `.hgrm` files written into `out_dir`.
    pub fn finish(self, meta: ReportMeta, out_dir: &Path) -> std::io::Result<ProcessReport> {
        std::fs::create_dir_all(out_dir)?;
        let mut latencies = Vec::new();
        for (name, description, h) in &self.histograms {
            silrig_flight::files::write_atomically(&out_dir.join(format!("{name}.hgrm")), &h.hgrm())?;
            latencies.push(NamedLatency::new(name, description, h));
        }
        let report = ProcessReport {
            process: self.process.clone(),
            pid: std::process::id(),
            run_id: meta.run_id,
            scenario: meta.scenario,
            mode: meta.mode,
            scheduling: meta.scheduling,
            ended: meta.ended,
            latencies,
            counters: self.counters,
            command_age_ticks: self.command_age_ticks,
            cpu_s: process_cpu_s(),
            lives_merged: Vec::new(),
        };
        silrig_flight::files::write_atomically(
            &report_path(out_dir, &self.process),
            &(serde_json::to_string_pretty(&report)? + "\n"),
        )?;
        Ok(report)
    }
}

/// Identity and conditions of a process's report.
#[derive(Debug, Clone)]
pub struct ReportMeta {
    /// Run id.
    pub run_id: String,
    /// Scenario name.
    pub scenario: String,
    /// realtime or lockstep.
    pub mode: String,
    /// Scheduling obtained.
    pub scheduling: String,
    /// How it ended.
    pub ended: String,
}

impl ReportMeta {
    /// The identity a process of this run reports under.
    pub fn new(args: &super::ProcessArgs, scenario: &str, scheduling: String, ended: String) -> Self {
        Self {
            run_id: args.run_id.to_string(),
            scenario: scenario.into(),
            mode: args.mode.label().into(),
            scheduling,
            ended,
        }
    }
}

/// Where a process's report goes.
pub fn report_path(out_dir: &Path, process: &str) -> PathBuf {
    out_dir.join(format!("{process}.report.json"))
}

/// Read a process's report.
pub fn read_report(out_dir: &Path, process: &str) -> anyhow::Result<ProcessReport> {
    let path = report_path(out_dir, process);
    let text = std::fs::read_to_string(&path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// The machine's conditions while a timing figure was taken.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MachineConditions {
    /// Online CPUs.
    pub cpu_count: usize,
    /// 1, 5 and 15 minute load averages (from /proc/loadavg).
    pub load_average: [f64; 3],
    /// Kernel release.
    pub kernel: String,
}

impl MachineConditions {
    /// Read them now.
    pub fn now() -> Self {
        let load_average = std::fs::read_to_string("/proc/loadavg")
            .ok()
            .map(|s| {
                let v: Vec<f64> = s.split_whitespace().take(3).filter_map(|x| x.parse().ok()).collect();
                [
                    v.first().copied().unwrap_or(f64::NAN),
                    v.get(1).copied().unwrap_or(f64::NAN),
                    v.get(2).copied().unwrap_or(f64::NAN),
                ]
            })
            .unwrap_or([f64::NAN; 3]);
        Self {
            cpu_count: std::thread::available_parallelism().map_or(0, |n| n.get()),
            load_average,
            kernel: std::fs::read_to_string("/proc/sys/kernel/osrelease")
                .map(|s| s.trim().to_string())
                .unwrap_or_default(),
        }
    }
}

/// Ask for SCHED_FIFO at the role's priority and mlockall when `realtime` (one warning line on stderr when refused),
/// and return the scheduling obtained as report text ("SCHED_FIFO 80, memory locked", "SCHED_OTHER, memory not locked
/// (limit 8192 KiB)"). Lockstep processes block on each
/// other rather than on a clock; FIFO there would only starve their peers on a small machine.
pub fn request_scheduling(role: Role, realtime: bool) -> String {
    let Some(priority) = role.fifo_priority().filter(|_| realtime) else {
        return silrig_wire::clock::current_policy().to_string();
    };
    let status = silrig_wire::clock::try_realtime(priority);
    if let Some(w) = &status.warning {
        eprintln!("silrig-{role}: warning: {w}");
    }
    format!("{}, {}", status.policy, status.memory)
}
