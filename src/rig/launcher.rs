//! `silrig run`: starts the plant, controller and logger as separate processes of one run id, supervises them
//! (reaps its children, reports any that die), stops them with SIGTERM at the end, merges their reports with the
//! control-quality summary of the logged trace, and removes the run's iceoryx2 resources. In realtime mode it also
//! runs a bare absolute-deadline timer loop beside the rig, so the plant's wake-up lateness can be read against the
//! OS floor measured under the same conditions.

use super::report::{MachineConditions, ProcessReport, read_report};
use super::{RigMode, load_scenario, signals};
use crate::ipc::{self, RunId};
use crate::summary::{Summary, summarize};
use crate::timing::{BaselineReport, summary_line, summary_table_header};
use crate::trace::Trace;
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// What `silrig run` was asked to do.
#[derive(Debug, Clone)]
pub struct LaunchOptions {
    /// Scenario file; `None` for the embedded default.
    pub config: Option<PathBuf>,
    /// Realtime or lockstep.
    pub mode: RigMode,
    /// Duration override, s.
    pub duration_s: Option<f64>,
    /// Output folder; `None` for `out/run-<run id>`.
    pub out: Option<PathBuf>,
    /// Run id; `None` for a fresh one.
    pub run_id: Option<RunId>,
    /// Run the timer baseline beside a realtime rig.
    pub baseline: bool,
    /// Same-tick command budget, ms.
    pub command_budget_ms: f64,
    /// How long the plant polls for a command before it blocks, µs.
    pub command_spin_us: f64,
    /// Faults from `--fault` flags, added to the scenario's plan.
    pub faults: Vec<crate::fault::Fault>,
    /// What to do when a process dies unplanned.
    pub restart: RestartPolicy,
}

/// What the launcher does when a process dies without a planned fault.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RestartPolicy {
    /// The run fails.
    Never,
    /// Start it again, at most `max_restarts` times per process, after `backoff_s` doubling each time.
    OnFailure {
        /// Restarts allowed per process.
        max_restarts: u32,
        /// Pause before the first restart, s.
        backoff_s: f64,
    },
}

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
    pub faults: Vec<super::fault_report::FaultRecord>,
    /// Processes that failed, and how.
    pub failures: Vec<String>,
    /// What was left of the run's iceoryx2 resources after cleanup (empty when clean).
    pub leftovers: Vec<String>,
}

/// A fresh run id: short, lowercase, unique per launcher process and start time.
pub fn fresh_run_id() -> RunId {
    let t = crate::clock::monotonic_ns();
    let id = format!("r{:x}-{:x}", std::process::id(), (t / 1_000) & 0xff_ffff);
    RunId::new(&id).expect("generated run ids are valid")
}

/// A process fault of the plan and its progress.
struct PlannedFault {
    fault: crate::fault::Fault,
    injected: bool,
    /// When to send SIGCONT (stop faults).
    follow_up: Option<Instant>,
}

struct Proc {
    name: &'static str,
    child: Child,
    status: Option<ExitStatus>,
    /// A planned kill or term was sent and its exit not yet seen.
    planned_exit: bool,
    /// This instance ended by a planned kill or term.
    killed_by_plan: bool,
    /// Its exit has been dealt with (each exit is handled once).
    exit_handled: bool,
    restarts: u32,
    /// When to start it again.
    restart_at: Option<Instant>,
}

impl Proc {
    fn new(name: &'static str, child: Child) -> Self {
        Self {
            name,
            child,
            status: None,
            planned_exit: false,
            killed_by_plan: false,
            exit_handled: false,
            restarts: 0,
            restart_at: None,
        }
    }

    fn poll(&mut self) -> std::io::Result<Option<ExitStatus>> {
        if self.status.is_none() {
            self.status = self.child.try_wait()?;
        }
        Ok(self.status)
    }

    fn signal(&mut self, signal: libc::c_int) {
        if self.status.is_none() {
            // SAFETY: kill(2) on the pid of a child we have not reaped yet, so the pid cannot have been reused.
            unsafe {
                libc::kill(self.child.id() as libc::pid_t, signal);
            }
        }
    }

    /// Wait up to `timeout` for the process to end; then SIGKILL it. Always reaps.
    fn finish(&mut self, timeout: Duration) -> std::io::Result<ExitStatus> {
        let deadline = Instant::now() + timeout;
        while self.poll()?.is_none() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        if self.status.is_none() {
            self.signal(libc::SIGKILL);
            self.status = Some(self.child.wait()?);
        }
        Ok(self.status.expect("reaped"))
    }
}

fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exit status {c}"),
        (None, Some(s)) => format!("killed by signal {s}"),
        _ => "ended".into(),
    }
}

/// Folder of the rig binaries: next to the running executable (`target/release/` in a build tree).
pub fn binary_dir() -> anyhow::Result<PathBuf> {
    let exe = std::env::current_exe().context("locating the running executable")?;
    Ok(exe.parent().context("the executable has no folder")?.to_path_buf())
}

/// A rig binary much older than the launcher was probably not rebuilt with it (`cargo run` builds only `silrig`).
/// Cargo links the binaries of one build within seconds of each other, hence the tolerance.
fn warn_if_stale(bin_dir: &Path) {
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let Some(launcher) = std::env::current_exe().ok().and_then(|p| modified(&p)) else { return };
    for name in ["plant", "controller", "logger"] {
        let stale = |t: std::time::SystemTime| launcher.duration_since(t).is_ok_and(|d| d > Duration::from_secs(30));
        if modified(&bin_dir.join(format!("silrig-{name}"))).is_some_and(stale) {
            eprintln!(
                "silrig run: warning: silrig-{name} is older than silrig; rebuild all binaries with `cargo build --release`"
            );
        }
    }
}

fn spawn(bin_dir: &Path, name: &'static str, args: &[String], out_dir: &Path) -> anyhow::Result<Proc> {
    let exe = bin_dir.join(format!("silrig-{name}"));
    let log = std::fs::File::create(out_dir.join(format!("{name}.stderr.log")))?;
    let child = Command::new(&exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .with_context(|| format!("starting {} (build it with `cargo build --release`)", exe.display()))?;
    Ok(Proc::new(name, child))
}

/// Run the three processes to the end of the scenario and return the merged report (also written as
/// `report.json`). An `Err` means the run could not be set up; a run whose processes failed returns `Ok` with
/// `failures` filled in.
pub fn run(opts: &LaunchOptions) -> anyhow::Result<RigReport> {
    signals::install_termination_flag();
    let mut scenario = load_scenario(opts.config.as_deref(), opts.duration_s)?;
    scenario.faults.extend(opts.faults.iter().cloned());
    scenario.validate().map_err(|(key, problem)| anyhow::anyhow!("fault plan: `{key}`: {problem}"))?;
    if opts.mode == RigMode::Lockstep
        && let Some(f) = scenario.faults.iter().find(|f| !f.action().is_plant_model_fault())
    {
        anyhow::bail!("fault plan: {} needs realtime mode (lockstep has no clock to fault)", f.describe());
    }
    let run_id = opts.run_id.clone().unwrap_or_else(fresh_run_id);
    let out = opts.out.clone().unwrap_or_else(|| Path::new("out").join(format!("run-{run_id}")));
    anyhow::ensure!(
        !out.join("trace.csv").exists(),
        "{} already holds a run (trace.csv); choose another --out or move it away: nothing is overwritten",
        out.display()
    );
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let scenario_path = out.join("scenario.toml");
    std::fs::write(&scenario_path, scenario.to_toml())?;
    // A crashed run with this id may have left resources behind; they must not poison this one.
    let pre = ipc::cleanup_run(&run_id)?;
    anyhow::ensure!(pre.is_clean(), "run id {run_id} is in use by live processes: {pre:?}");

    let bin_dir = binary_dir()?;
    warn_if_stale(&bin_dir);
    let args: Vec<String> = vec![
        scenario_path.display().to_string(),
        "--run-id".into(),
        run_id.to_string(),
        "--mode".into(),
        opts.mode.label().into(),
        "--out".into(),
        out.display().to_string(),
        "--command-budget-ms".into(),
        opts.command_budget_ms.to_string(),
        "--command-spin-us".into(),
        opts.command_spin_us.to_string(),
    ];
    let conditions_start = MachineConditions::now();
    let started = Instant::now();
    let mut procs = Vec::new();
    // Staggered starts: concurrent node creation with dead-node cleanup is where iceoryx2 has had races (#1880).
    for name in ["logger", "controller", "plant"] {
        procs.push(spawn(&bin_dir, name, &args, &out)?);
        std::thread::sleep(Duration::from_millis(20));
    }
    let baseline_path = out.join("timer-baseline.json");
    let mut baseline = if opts.mode == RigMode::Realtime && opts.baseline {
        let file = std::fs::File::create(&baseline_path)?;
        let child = Command::new(std::env::current_exe()?)
            .args(["timer-baseline", "--duration-s", &scenario.timing.duration_s.to_string(), "--json"])
            .args(["--hgrm", &out.join("baseline.wake_lateness.hgrm").display().to_string()])
            .stdin(Stdio::null())
            .stdout(file)
            .stderr(Stdio::null())
            .spawn()
            .context("starting the timer baseline")?;
        Some(Proc::new("timer-baseline", child))
    } else {
        None
    };

    let mut failures = Vec::new();
    let events = super::events::EventLog::new(&out, "launcher");
    let mut plan: Vec<PlannedFault> = scenario
        .faults
        .iter()
        .filter(|f| f.action().is_process_fault())
        .map(|f| PlannedFault { fault: f.clone(), injected: false, follow_up: None })
        .collect();
    let timeout = Duration::from_secs_f64(scenario.timing.duration_s * 3.0 + 30.0);
    let mut plant_done_at: Option<Instant> = None;
    let mut wall_s = 0.0;
    let mut t0_ns: Option<u64> = None;
    loop {
        let now_ns = crate::clock::monotonic_ns();
        if t0_ns.is_none() {
            t0_ns = super::fault_report::plant_t0_ns(&out);
        }
        // Faults due now, and their follow-ups (SIGCONT, restart).
        if let Some(t0) = t0_ns {
            for pf in plan.iter_mut() {
                let f = &pf.fault;
                let target = f.target().label();
                let due = t0 + (f.at_s * 1e9) as u64;
                if !pf.injected && now_ns >= due {
                    pf.injected = true;
                    let Some(p) = procs.iter_mut().find(|p| p.name == target) else { continue };
                    if p.poll()?.is_some() {
                        eprintln!("silrig run: warning: {} skipped: {target} is not running", f.describe());
                        events.emit(None, "fault-skipped", format!("{}: {target} is not running", f.describe()));
                        continue;
                    }
                    let (signal, name) = match f.action() {
                        crate::fault::FaultAction::Kill => (libc::SIGKILL, "SIGKILL"),
                        crate::fault::FaultAction::Term => (libc::SIGTERM, "SIGTERM"),
                        _ => (libc::SIGSTOP, "SIGSTOP"),
                    };
                    events.emit(None, "fault-injected", format!("{} ({name} to pid {})", f.describe(), p.child.id()));
                    p.signal(signal);
                    match f.action() {
                        crate::fault::FaultAction::Stop => {
                            pf.follow_up = Some(Instant::now() + Duration::from_secs_f64(f.duration_s.unwrap_or(0.0)));
                        }
                        _ => {
                            p.planned_exit = true;
                            if let Some(r) = f.restart_after_s {
                                p.restart_at = Some(Instant::now() + Duration::from_secs_f64(r));
                            }
                        }
                    }
                }
                if let Some(at) = pf.follow_up
                    && Instant::now() >= at
                {
                    pf.follow_up = None;
                    if let Some(p) = procs.iter_mut().find(|p| p.name == target) {
                        p.signal(libc::SIGCONT);
                        events.emit(None, "fault-ended", format!("SIGCONT to {target} (pid {})", p.child.id()));
                    }
                }
            }
        }
        for p in procs.iter_mut() {
            if let Some(status) = p.poll()?
                && !std::mem::replace(&mut p.exit_handled, true)
            {
                let ok = status.success();
                let planned = std::mem::take(&mut p.planned_exit);
                if planned {
                    p.killed_by_plan = true;
                    events.emit(None, "process-ended", format!("{} {} (planned)", p.name, describe(status)));
                    if p.restart_at.is_none() && p.name == "plant" && plant_done_at.is_none() {
                        plant_done_at = Some(Instant::now());
                        wall_s = started.elapsed().as_secs_f64();
                    }
                    continue;
                }
                if p.restart_at.is_some() {
                    continue;
                }
                if p.name == "plant" && ok && plant_done_at.is_none() {
                    plant_done_at = Some(Instant::now());
                    wall_s = started.elapsed().as_secs_f64();
                    continue;
                }
                // The logger ends by itself once it has written the last tick; the others end when told to.
                if (p.name == "logger" && ok)
                    || plant_done_at.is_some()
                    || failures.iter().any(|f: &String| f.starts_with(p.name))
                {
                    continue;
                }
                let death = format!("{}: {} before the end of the run", p.name, describe(status));
                events.emit(None, "process-died", death.clone());
                match opts.restart {
                    RestartPolicy::OnFailure { max_restarts, backoff_s } if p.restarts < max_restarts => {
                        let pause = backoff_s * 2f64.powi(p.restarts as i32);
                        eprintln!("silrig run: {death}; restarting in {pause:.2} s");
                        p.restart_at = Some(Instant::now() + Duration::from_secs_f64(pause));
                    }
                    _ => {
                        // The survivors carry on (the plant in failsafe, the logger marking the gap): the run goes
                        // to its end and reports the failure. Without a plant there is nothing left to run.
                        if p.name == "plant" {
                            plant_done_at = Some(Instant::now());
                            wall_s = started.elapsed().as_secs_f64();
                        }
                        failures.push(death);
                    }
                }
            }
        }
        for slot in procs.iter_mut() {
            if slot.status.is_some() && slot.restart_at.is_some_and(|t| Instant::now() >= t) {
                let name = slot.name;
                let restarts = slot.restarts + 1;
                let mut restart_args = args.clone();
                if name == "plant" || name == "controller" {
                    restart_args.push("--resume".into());
                }
                let mut p = spawn(&bin_dir, name, &restart_args, &out)?;
                p.restarts = restarts;
                events.emit(None, "process-restarted", format!("{name} as pid {} (restart {restarts})", p.child.id()));
                *slot = p;
            }
        }
        let logger_done =
            procs.iter_mut().find(|p| p.name == "logger").is_some_and(|p| p.status.is_some() && p.restart_at.is_none());
        if let Some(t) = plant_done_at
            && (logger_done || t.elapsed() > Duration::from_secs(2))
        {
            break;
        }
        if signals::termination_requested() || started.elapsed() > timeout {
            if signals::termination_requested() {
                failures.push("silrig run: interrupted".into());
            } else if started.elapsed() > timeout {
                failures.push(format!("silrig run: no end after {timeout:?}"));
            }
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let ended_by_plan: Vec<&str> = procs
        .iter()
        .filter(|p| p.status.is_some() && p.restart_at.is_none() && p.killed_by_plan)
        .map(|p| p.name)
        .collect();
    // A process left stopped by an interrupted plan must be continued to hear SIGTERM.
    for pf in plan.iter().filter(|pf| pf.follow_up.is_some()) {
        if let Some(p) = procs.iter_mut().find(|p| p.name == pf.fault.target().label()) {
            p.signal(libc::SIGCONT);
        }
    }
    if plant_done_at.is_none() {
        wall_s = started.elapsed().as_secs_f64();
    }
    for p in procs.iter_mut() {
        p.signal(libc::SIGTERM);
    }
    for p in procs.iter_mut() {
        let already_ended = p.status.is_some();
        let status = p.finish(Duration::from_secs(5))?;
        // The controller ends on our SIGTERM; anything else than a clean exit is a failure, unless a planned
        // fault ended the process already.
        if !already_ended && !status.success() && !failures.iter().any(|f| f.starts_with(p.name)) {
            failures.push(format!("{}: {}", p.name, describe(status)));
        }
    }
    let timer_baseline = match baseline.as_mut() {
        Some(b) => {
            if !failures.is_empty() {
                b.signal(libc::SIGKILL);
            }
            b.finish(Duration::from_secs_f64(scenario.timing.duration_s + 10.0))?;
            std::fs::read_to_string(&baseline_path).ok().and_then(|t| serde_json::from_str(&t).ok())
        }
        None => None,
    };
    let conditions_end = MachineConditions::now();

    let mut processes = Vec::new();
    for name in ["plant", "controller", "logger"] {
        match read_report(&out, name) {
            Ok(r) => processes.push(r),
            // A process a planned fault killed for good has no report to give; anything else should have one.
            Err(_) if ended_by_plan.contains(&name) => {}
            Err(e) => failures.push(format!("{name}: no report ({e})")),
        }
    }
    let control =
        Trace::load(&out.join("trace.csv")).ok().filter(|t| !t.rows.is_empty()).map(|t| summarize(&t, &scenario));
    let cleanup = ipc::cleanup_run(&run_id)?;
    let leftovers = if cleanup.is_clean() { Vec::new() } else { vec![format!("{cleanup:?}")] };
    let ticks =
        processes.iter().find(|p| p.process == "plant").and_then(|p| p.counters.get("ticks").copied()).unwrap_or(0);
    let report = RigReport {
        run_id: run_id.to_string(),
        scenario: scenario.name.clone(),
        mode: opts.mode.label().into(),
        out_dir: out.display().to_string(),
        conditions_start,
        conditions_end,
        wall_s,
        cycles_per_s: if wall_s > 0.0 { ticks as f64 / wall_s } else { 0.0 },
        processes,
        timer_baseline,
        control,
        faults: super::fault_report::fault_records(&scenario.faults, &out),
        failures,
        leftovers,
    };
    std::fs::write(out.join("report.json"), serde_json::to_string_pretty(&report)? + "\n")?;
    write_plots(&report, &out, &scenario)?;
    Ok(report)
}

/// The closed-loop figures of the logged trace and the latency distributions of every process.
fn write_plots(report: &RigReport, out: &Path, scenario: &crate::scenario::Scenario) -> anyhow::Result<()> {
    if report.control.is_some() {
        let trace = Trace::load(&out.join("trace.csv"))?;
        // Rows without a command (a lost controller) have NaN command columns, which the plots skip.
        crate::plot::plot_closed_loop(&trace, out, &crate::outputs::plot_title(scenario))?;
    }
    let mut series: Vec<(String, Vec<(f64, f64)>)> = report
        .processes
        .iter()
        .flat_map(|p| &p.latencies)
        .filter(|l| l.summary.count > 0 && !l.name.ends_with("step_exec") && !l.name.ends_with("compute"))
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
    /// The report as a person reads it: conditions, a cyclictest-style table, counters, control quality.
    pub fn to_text(&self) -> String {
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
        out += &format!("\n{}\n", summary_table_header());
        for p in &self.processes {
            for l in &p.latencies {
                if l.summary.count > 0 {
                    out += &format!("{}\n", summary_line(&l.name, &l.summary));
                }
            }
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
        for p in &self.processes {
            let counters: Vec<String> = p.counters.iter().map(|(k, v)| format!("{k} {v}")).collect();
            out += &format!("  {:<10} {}\n", p.process, counters.join(", "));
            if !p.command_age_ticks.is_empty() {
                let ages: Vec<String> = p.command_age_ticks.iter().map(|(a, n)| format!("{a}: {n}")).collect();
                out += &format!("  {:<10} command age at use (ticks: count) {}\n", "", ages.join(", "));
            }
        }
        out += &format!("  wall time {:.3} s, {:.0} plant cycles/s\n\n", self.wall_s, self.cycles_per_s);
        match &self.control {
            Some(s) => out += &s.to_text(),
            None => out += "no trace to summarise\n",
        }
        if !self.faults.is_empty() {
            out += "\nfaults (s from tick 0)            injected  detected  by                               failsafe  recovered  plant lost  cmd lost\n";
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
        }
        if self.failures.is_empty() {
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

    /// A latency summary by name, from any process.
    pub fn latency(&self, name: &str) -> Option<&crate::timing::LatencySummary> {
        self.processes.iter().flat_map(|p| &p.latencies).find(|l| l.name == name).map(|l| &l.summary)
    }
}
