//! `silrig run`: starts the plant, controller and logger as separate processes of one run id, supervises them
//! ([`super::supervision`]), injects the plan's process faults ([`super::fault_schedule`]), stops them with SIGTERM
//! at the end, merges their reports with the control-quality summary of the logged trace ([`super::run_report`]),
//! and removes the run's iceoryx2 resources. In realtime mode it also runs a bare absolute-deadline timer loop
//! beside the rig, so the plant's wake-up lateness can be read against the OS floor measured under the same
//! conditions.

use super::events::EventLog;
use super::fault_schedule::FaultSchedule;
use super::report::{MachineConditions, read_report};
use super::run_report::{RigReport, write_plots};
use super::supervision::{ChildProcess, SupervisionOptions, Supervisor};
use super::{ProcessArgs, ProcessOptions, RigMode, load_scenario, signals};
use crate::bench::timer_baseline::{self, BaselineArgs, BaselineReport};
use crate::fault::Fault;
use crate::ipc::{self, RunId};
use crate::scenario::Scenario;
use crate::summary::summarize;
use crate::topology::Role;
use crate::trace::Trace;
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// What `silrig run` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct LaunchOptions {
    /// Scenario file (TOML); without it, the embedded default scenario.
    pub config: Option<PathBuf>,
    /// realtime (the scenario's rate on the wall clock) or lockstep (as fast as possible, deterministic).
    #[arg(long, value_enum, default_value = "realtime")]
    pub mode: RigMode,
    /// Override the scenario's duration, s.
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Output folder (default: out/run-<run id>); must not hold a run already.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run id (default: a fresh one).
    #[arg(long)]
    pub run_id: Option<RunId>,
    /// Do not run the OS-floor timer loop beside a realtime rig.
    #[arg(long)]
    pub no_baseline: bool,
    /// Loop and watchdog tuning, passed on to every process.
    #[command(flatten)]
    pub process: ProcessOptions,
    /// A fault to inject, added to the scenario's [[faults]]: TARGET:ACTION@TIME[,KEY=VALUE...], e.g.
    /// `controller:kill@3s,restart_after=0.5s`, `logger:stop@2s,for=500ms`, `plant:delay@2s,delay=15ms`.
    /// Repeatable.
    #[arg(long = "fault", value_parser = crate::fault::parse_fault_flag)]
    pub faults: Vec<Fault>,
    /// What to do when a process dies.
    #[command(flatten)]
    pub supervision: SupervisionOptions,
}

/// A fresh run id: short, lowercase, unique per launcher process and start time.
pub fn fresh_run_id() -> RunId {
    let t = crate::clock::monotonic_ns();
    let id = format!("r{:x}-{:x}", std::process::id(), (t / 1_000) & 0xff_ffff);
    RunId::new(&id).expect("generated run ids are valid")
}

/// A run ready to start: its scenario with the plan's faults, its id and its folder.
struct Prepared {
    scenario: Scenario,
    run_id: RunId,
    out: PathBuf,
    /// The scenario as the processes load it (`<out>/scenario.toml`).
    scenario_path: PathBuf,
}

/// Phase 1: the scenario with `--fault` flags added and validated, a folder that holds no run yet, the effective
/// scenario written there, and the run id's namespace free of a crashed run's leftovers.
fn prepare(opts: &LaunchOptions) -> anyhow::Result<Prepared> {
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
    Ok(Prepared { scenario, run_id, out, scenario_path })
}

/// The OS-floor timer loop beside a realtime rig, for the scenario's duration at the scenario's period.
fn start_baseline(scenario: &Scenario, out: &Path) -> anyhow::Result<ChildProcess> {
    let args = BaselineArgs {
        duration_s: scenario.timing.duration_s,
        period_ms: scenario.timing.period_ns() as f64 / 1e6,
        fifo_priority: Role::Plant.fifo_priority().unwrap_or(0),
        timerfd: false,
        hgrm: Some(out.join("baseline.wake_lateness.hgrm")),
        json: true,
    };
    let child = Command::new(std::env::current_exe()?)
        .arg(timer_baseline::SUBCOMMAND)
        .args(args.to_argv())
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(out.join("timer-baseline.json"))?)
        .stderr(Stdio::null())
        .spawn()
        .context("starting the timer baseline")?;
    Ok(ChildProcess::new(child))
}

/// Phase 3: supervise until the plant has flown the scenario (and the logger has written it), SIGTERM or the
/// watchdog on the whole run.
fn supervise(sup: &mut Supervisor, faults: &mut FaultSchedule, scenario: &Scenario) -> anyhow::Result<()> {
    let timeout = Duration::from_secs_f64(scenario.timing.duration_s * 3.0 + 30.0);
    loop {
        faults.poll(sup)?;
        sup.handle_exits()?;
        sup.restart_due()?;
        if sup.run_is_over() {
            return Ok(());
        }
        if signals::termination_requested() {
            sup.failures.push("silrig run: interrupted".into());
            return Ok(());
        }
        if sup.elapsed() > timeout {
            sup.failures.push(format!("silrig run: no end after {timeout:?}"));
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The baseline's report (None if it wrote none); after a failed run it is not waited for.
fn finish_baseline(
    baseline: &mut ChildProcess,
    scenario: &Scenario,
    out: &Path,
    failed: bool,
) -> std::io::Result<Option<BaselineReport>> {
    if failed {
        baseline.signal(libc::SIGKILL);
    }
    baseline.finish(Duration::from_secs_f64(scenario.timing.duration_s + 10.0))?;
    Ok(std::fs::read_to_string(out.join("timer-baseline.json")).ok().and_then(|t| serde_json::from_str(&t).ok()))
}

/// Run the three processes to the end of the scenario and return the merged report (also written as
/// `report.json`). An `Err` means the run could not be set up; a run whose processes failed returns `Ok` with
/// `failures` filled in.
pub fn run(opts: &LaunchOptions) -> anyhow::Result<RigReport> {
    signals::install_termination_flag();
    let Prepared { scenario, run_id, out, scenario_path } = prepare(opts)?;
    let args = ProcessArgs {
        config: Some(scenario_path),
        run_id: run_id.clone(),
        mode: opts.mode,
        duration_s: None,
        out: out.clone(),
        resume: false,
        options: opts.process.clone(),
    };
    let conditions_start = MachineConditions::now();
    let events = EventLog::new(&out, "launcher");
    let mut sup = Supervisor::start(args, events.clone(), opts.supervision.clone())?;
    let mut baseline =
        if opts.mode == RigMode::Realtime && !opts.no_baseline { Some(start_baseline(&scenario, &out)?) } else { None };
    let mut faults = FaultSchedule::new(&scenario.faults, &out, events);
    supervise(&mut sup, &mut faults, &scenario)?;
    let ended_by_plan = sup.ended_by_plan();
    faults.release_stopped(&mut sup);
    sup.stop_all()?;
    let timer_baseline = match baseline.as_mut() {
        Some(b) => finish_baseline(b, &scenario, &out, !sup.failures.is_empty())?,
        None => None,
    };
    let conditions_end = MachineConditions::now();

    let mut failures = sup.failures;
    let mut processes = Vec::new();
    for role in Role::ALL {
        match read_report(&out, role.label()) {
            Ok(r) => processes.push(r),
            // A process a planned fault killed for good has no report to give; anything else should have one.
            Err(_) if ended_by_plan.contains(&role) => {}
            Err(e) => failures.push(format!("{role}: no report ({e})")),
        }
    }
    let control =
        Trace::load(&out.join("trace.csv")).ok().filter(|t| !t.rows.is_empty()).map(|t| summarize(&t, &scenario));
    let cleanup = ipc::cleanup_run(&run_id)?;
    let leftovers = if cleanup.is_clean() { Vec::new() } else { vec![format!("{cleanup:?}")] };
    let ticks = processes
        .iter()
        .find(|p| p.process == Role::Plant.label())
        .and_then(|p| p.counters.get("ticks").copied())
        .unwrap_or(0);
    let wall_s = sup.wall_s;
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
