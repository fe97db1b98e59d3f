//! `silrig run` in its phases: prepared ([`super::prepare`], from [`super::options`]), it starts the plant,
//! controller and logger as separate processes of one run id, supervises them ([`super::supervision`]), injects the
//! plan's process faults ([`super::fault_schedule`]), stops them with SIGTERM at the end, merges their reports with
//! the control-quality summary of the logged trace ([`super::run_report`]), and removes the run's iceoryx2
//! resources. In realtime mode it also runs a bare absolute-deadline timer loop
//! beside the rig, so the plant's wake-up lateness can be read against the OS floor measured under the same
//! conditions.

pub use super::claim::{fresh_run_id, refuse_used_folder};
use super::fault_schedule::FaultSchedule;
pub use super::options::{
    ControllerKind, FloorSource, LIVE_FOXGLOVE_DEFAULT, LaunchOptions, LiveServe, PlantKind, parse_live,
};
use super::prepare::{Prepared, prepare};
use super::process_env::{wait_for_external_report, write_controller_env, write_plant_env};
use super::run_figures::{remove_empty_figures, write_plots};
use super::run_report::{ProcessLife, RigReport};
use crate::child::{ChildProcess, end_with_launcher};
use crate::floor::{timer_baseline, timer_baseline::BaselineArgs, timer_baseline::BaselineReport};
use crate::supervision::{ControllerLaunch, Supervisor};
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::trace::Trace;
use silrig_rig::events::EventLog;
use silrig_rig::report::{MachineConditions, ProcessReport, read_report};
use silrig_rig::status::LiveLine;
use silrig_rig::{ProcessArgs, RigMode, signals};
use silrig_wire::ipc::{self, RunId};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

/// The OS-floor timer loop beside a realtime rig, for the scenario's duration at the scenario's period.
fn start_baseline(scenario: &Scenario, out: &Path, floor: FloorSource) -> anyhow::Result<ChildProcess> {
    let priority = Role::Plant.fifo_priority().unwrap_or(0);
    if floor == FloorSource::Cyclictest {
        let mut command =
            crate::floor::cyclictest::command(scenario.timing.duration_s, scenario.timing.period_ns(), priority)
                .map_err(anyhow::Error::msg)?;
        end_with_launcher(&mut command, libc::SIGKILL);
        let child = command
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(out.join(CYCLICTEST_OUTPUT))?)
            .stderr(Stdio::null())
            .spawn()
            .context("starting cyclictest")?;
        return Ok(ChildProcess::new(child));
    }
    let args = BaselineArgs {
        duration_s: scenario.timing.duration_s,
        period_ms: scenario.timing.period_ns() as f64 / 1e6,
        fifo_priority: priority,
        timerfd: false,
        hgrm: Some(out.join("baseline.wake_lateness.hgrm")),
        json: true,
    };
    let mut command = Command::new(std::env::current_exe()?);
    end_with_launcher(&mut command, libc::SIGKILL);
    let child = command
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
fn supervise(
    sup: &mut Supervisor,
    faults: &mut FaultSchedule,
    scenario: &Scenario,
    bridge: &mut Option<super::remote::RemoteBridge>,
    mut live: Option<&mut LiveLine>,
) -> anyhow::Result<()> {
    let timeout = Duration::from_secs_f64(scenario.timing.duration_s * 3.0 + 30.0);
    loop {
        faults.poll(sup, bridge.as_mut())?;
        if let Some(b) = bridge.as_mut() {
            b.poll()?;
        }
        sup.handle_exits()?;
        sup.watch_joins();
        sup.restart_due()?;
        sup.renew_stuck();
        if let Some(live) = live.as_deref_mut() {
            live.update(sup.lives.iter().filter(|l| l.life > 1).count() as u32);
        }
        if sup.run_is_over() {
            return Ok(());
        }
        if signals::termination_requested() {
            // Stopped by the user: not a failure of the run; the report says when (`stopped_by`).
            return Ok(());
        }
        if sup.elapsed() > timeout {
            sup.failures.push(format!("silrig run: no end after {timeout:?}"));
            return Ok(());
        }
        crate::child::wait_for_an_exit(&sup.exit_fds(), Duration::from_millis(5));
    }
}

/// cyclictest's output in the run's folder, as it printed it.
const CYCLICTEST_OUTPUT: &str = "cyclictest.txt";

/// The OS floor measured beside the run, or why there is none: a baseline that ended before the launcher stopped
/// it (killed from outside, say) or wrote nothing readable is a line of the report, never a silent absence.
struct Floor {
    report: Option<BaselineReport>,
    missing: Option<String>,
}

/// The baseline's report; after a failed run it is not waited for.
fn finish_baseline(
    baseline: &mut ChildProcess,
    floor: FloorSource,
    scenario: &Scenario,
    out: &Path,
    failed: bool,
) -> std::io::Result<Floor> {
    // Looked at before the launcher signals it: an end already there came from somewhere else.
    let ended_early = baseline.poll()?.filter(|status| !status.success());
    if failed {
        baseline.signal(libc::SIGKILL);
    } else if signals::termination_requested() {
        // A terminal's Ctrl-C reaches the baseline too; a SIGINT or SIGTERM to the launcher alone must end it as
        // well, or the run waits out its planned duration. SIGINT, as Ctrl-C: cyclictest then prints its summary.
        baseline.signal(libc::SIGINT);
    }
    baseline.finish(Duration::from_secs_f64(scenario.timing.duration_s + 10.0))?;
    let report = if floor == FloorSource::Cyclictest {
        let text = std::fs::read_to_string(out.join(CYCLICTEST_OUTPUT)).unwrap_or_default();
        let timing = &scenario.timing;
        let priority = Role::Plant.fifo_priority().unwrap_or(0);
        crate::floor::cyclictest::parse(&text, timing.period_ns(), timing.duration_s, priority)
            .map_err(|e| format!("{e} (see {})", out.join(CYCLICTEST_OUTPUT).display()))
    } else {
        let path = out.join("timer-baseline.json");
        let report = std::fs::read_to_string(&path).ok().and_then(|t| serde_json::from_str(&t).ok());
        if report.is_none() {
            // Killed, or its output did not fit on the disk: no file rather than a torn one.
            let _ = std::fs::remove_file(&path);
        }
        report.ok_or_else(|| "it wrote no report".to_string())
    };
    let source = if floor == FloorSource::Cyclictest { "cyclictest" } else { "the timer baseline" };
    let missing = match (&report, ended_early) {
        (_, Some(status)) => Some(format!(
            "the OS floor ({source}, pid {}) ended before the run did, {}: no signal of the launcher's, so \
             something else ended it",
            baseline.pid(),
            crate::child::describe(status)
        )),
        (Err(why), None) if !failed => Some(format!("the OS floor ({source}): {why}")),
        _ => None,
    };
    Ok(Floor { report: report.ok(), missing })
}

/// What a process the launcher stopped at the normal end of a run reports as "terminated by signal" (its SIGTERM)
/// is shown as "stopped at end": the plant completed, nobody else sent a signal, and it exited cleanly when told.
fn mark_stopped_at_end(processes: &mut [ProcessReport], lives: &[ProcessLife]) {
    let plant_completed = processes.iter().any(|p| p.process == Role::Plant.label() && p.ended == "completed");
    if !plant_completed || signals::termination_signal().is_some() {
        return;
    }
    for p in processes.iter_mut().filter(|p| p.ended == "terminated by signal") {
        let life = lives.iter().rev().find(|l| l.pid == p.pid);
        if life.is_some_and(|l| l.exit == "exit status 0 at the end of the run") {
            p.ended = "stopped at end".into();
        }
    }
}

/// Run the three processes to the end of the scenario and return the merged report (also written as
/// `report.json`). An `Err` means the run could not be set up; a run whose processes failed returns `Ok` with
/// `failures` filled in.
pub fn run(opts: &LaunchOptions) -> anyhow::Result<RigReport> {
    run_with(opts, None)
}

/// [`run`], its processes forked by a sweep's warm rig when given one (see [`crate::warm`]): the same run, the
/// same files, without starting the programs again.
pub fn run_with(opts: &LaunchOptions, warm: Option<std::sync::Arc<crate::warm::WarmRig>>) -> anyhow::Result<RigReport> {
    signals::install_termination_flag();
    let prepared = prepare(opts)?;
    let flown = fly(opts, &prepared, warm)?;
    let mut report = report_of(opts, &prepared, flown)?;
    // A full disk must not cost the user the report: it is printed whatever happens to the files.
    if !opts.no_figures {
        match write_plots(&report, &prepared.out, &prepared.scenario) {
            Ok(left_out) => report.figures_left_out = left_out,
            Err(e) => {
                report.failures.push(format!("silrig run: the figures: {e:#}"));
                remove_empty_figures(&prepared.out);
            }
        }
    }
    if let Err(e) = silrig_flight::files::write_atomically(
        &prepared.out.join("report.json"),
        &(serde_json::to_string_pretty(&report)? + "\n"),
    ) {
        report.failures.push(format!("silrig run: {e}"));
    }
    Ok(report)
}

/// A run flown and its processes stopped: their supervisor (lives, failures), the bridge and the OS floor.
struct Flown {
    sup: Supervisor,
    controller: ControllerLaunch,
    bridge: Option<super::remote::RemoteBridge>,
    /// The processes a planned fault ended for good.
    ended_by_plan: Vec<Role>,
    floor: Floor,
    conditions: (MachineConditions, MachineConditions),
}

/// Phases 2 and 3: start the processes (the OS floor first), supervise them to the end of the flight with the
/// plan's faults, and stop them.
fn fly(
    opts: &LaunchOptions,
    prepared: &Prepared,
    warm: Option<std::sync::Arc<crate::warm::WarmRig>>,
) -> anyhow::Result<Flown> {
    let Prepared { scenario, run_id, out, scenario_path, .. } = prepared;
    let controller = opts.controller_launch();
    let mut args = ProcessArgs {
        config: Some(scenario_path.clone()),
        run_id: run_id.clone(),
        mode: opts.mode,
        duration_s: None,
        out: out.clone(),
        resume: false,
        options: opts.process.clone(),
    };
    let plant_external = opts.plant == PlantKind::External;
    if controller == ControllerLaunch::External || plant_external {
        args.options.startup_timeout_s = opts.external_timeout_s;
    }
    // First, so a floor that cannot be taken (cyclictest not installed) stops the run before anything flies.
    let realtime_floor = opts.mode == RigMode::Realtime && !opts.no_baseline;
    let mut baseline = if realtime_floor { Some(start_baseline(scenario, out, opts.floor)?) } else { None };
    write_controller_env(&args, &controller, opts.bridge_listen.is_some())?;
    if plant_external {
        write_plant_env(&args)?;
    }
    let conditions_start = MachineConditions::now();
    let events = EventLog::new(out, "launcher");
    let mut bridge = match &opts.bridge_listen {
        Some(listen) => {
            Some(super::remote::RemoteBridge::start(listen, &opts.bridge_security(), &args, events.clone())?)
        }
        None => None,
    };
    let plant_launch = if plant_external { None } else { Some(opts.plant_cmd.clone()) };
    let logger_args = match opts.live {
        Some(LiveServe::Foxglove(addr)) => {
            eprintln!("{}", super::options::live_line(addr));
            vec!["--live-foxglove".to_string(), addr.to_string()]
        }
        None => Vec::new(),
    };
    let launch = (controller.clone(), plant_launch, logger_args);
    let mut sup = Supervisor::start(args, events.clone(), opts.supervision.clone(), launch, warm)?;
    sup.plant_fmu = scenario.plant.fmu.clone();
    sup.controller_fmu = scenario.controller.fmu.clone();
    let mut faults = FaultSchedule::new(&scenario.faults, out, events, run_id, scenario.timing.dt_s);
    let mut live = (!opts.quiet).then(|| LiveLine::new(run_id));
    let supervised = supervise(&mut sup, &mut faults, scenario, &mut bridge, live.as_mut());
    if let Some(live) = live {
        live.finish();
    }
    supervised?;
    let ended_by_plan = sup.ended_by_plan();
    faults.release_stopped(&mut sup, bridge.as_mut());
    sup.stop_all()?;
    if let Some(b) = bridge.as_mut() {
        b.wait_for_controller_report(out);
        b.stop()?;
        sup.failures.extend(b.failure.take());
    }
    sup.note_final_reports();
    let floor = match baseline.as_mut() {
        Some(b) => finish_baseline(b, opts.floor, scenario, out, !sup.failures.is_empty())?,
        None => Floor { report: None, missing: None },
    };
    let conditions = (conditions_start, MachineConditions::now());
    if controller == ControllerLaunch::External && bridge.is_none() {
        wait_for_external_report(out, Role::Controller);
    }
    if plant_external {
        wait_for_external_report(out, Role::Plant);
    }
    Ok(Flown { sup, controller, bridge, ended_by_plan, floor, conditions })
}

/// Phase 4: the processes' reports merged with their lives, the trace's control summary, how the run ended and
/// what it left behind.
fn report_of(opts: &LaunchOptions, prepared: &Prepared, flown: Flown) -> anyhow::Result<RigReport> {
    let Prepared { scenario, run_id, out, .. } = prepared;
    let Flown { mut sup, controller, bridge, ended_by_plan, floor, conditions } = flown;
    let dt_s = scenario.timing.dt_s;
    // A run that failed before the plant's first tick (a process never joined, or ended at once) stopped its
    // peers before they had anything to report: their missing reports are no failures of their own.
    let stopped_before_flight = !sup.failures.is_empty() && !sup.plant_ticking();
    let mut failures = std::mem::take(&mut sup.failures);
    let mut notes: Vec<String> = floor.missing.iter().cloned().collect();
    notes.append(&mut sup.notes);
    let external = (controller == ControllerLaunch::External, opts.plant == PlantKind::External);
    // A process the plan ended for good has no report to give, nor has any of a run stopped before its flight.
    let no_report_due = if stopped_before_flight { Role::ALL.to_vec() } else { ended_by_plan.clone() };
    let mut processes =
        process_reports(opts, out, (external.0, bridge.is_some()), &no_report_due, &mut failures, &mut notes);
    super::run_report::merge_lives(&mut processes, &sup.lives, out, &mut notes);
    mark_stopped_at_end(&mut processes, &sup.lives);
    failures.extend(super::held_outputs::flag_held_rows(out, scenario));
    let trace = Trace::load(&out.join("trace.csv")).ok().filter(|t| !t.rows.is_empty());
    let (control, unsummarised) =
        super::run_report::control_summary(out, trace.as_ref(), scenario, opts.flies_builtin_f16(scenario));
    notes.extend(unsummarised);
    let flown_s =
        trace.as_ref().and_then(|t| t.column("t_s")).and_then(|t| t.last().copied()).map_or(0.0, |t| t + dt_s);
    if ended_by_plan.contains(&Role::Plant) {
        // Nothing flies without a plant: the plan ended the flight early, which is not the run the scenario asks.
        failures.push(format!(
            "plant: ended by the fault plan and not restarted: the flight ended at t = {flown_s:.2} s of {:.2} s",
            scenario.timing.duration_s
        ));
    }
    let stopped_by = signals::termination_signal().map(|signal| super::run_report::StoppedBy {
        signal: signals::name(signal).into(),
        at_s: flown_s,
        exit_status: signals::exit_status_for(signal),
    });
    let leftovers = leftovers(run_id, external.0 || external.1)?;
    // A plant that left no report (killed), or whose report covers only its last life, flew at least what the
    // logger wrote.
    let plant_ticks =
        processes.iter().find(|p| p.process == Role::Plant.label()).and_then(|p| p.counters.get("ticks").copied());
    let ticks = plant_ticks.unwrap_or(0).max((flown_s / dt_s).round() as u64);
    let wall_s = sup.wall_s;
    Ok(RigReport {
        run_id: run_id.to_string(),
        scenario: scenario.name.clone(),
        mode: opts.mode.label().into(),
        out_dir: out.display().to_string(),
        conditions_start: conditions.0,
        conditions_end: conditions.1,
        wall_s,
        cycles_per_s: if wall_s > 0.0 { ticks as f64 / wall_s } else { 0.0 },
        processes,
        lives: sup.lives,
        timer_baseline: floor.report,
        timer_baseline_missing: floor.missing,
        control,
        faults: super::fault_report::fault_records(&scenario.faults, out, dt_s),
        discontinuities: super::fault_report::discontinuities(out, dt_s),
        plant_resumes: super::fault_report::plant_resumes(out),
        duration_s: scenario.timing.duration_s,
        stopped_by,
        failures,
        notes,
        figures_left_out: Vec::new(),
        leftovers,
        phases: super::run_report::phase_splits(out, dt_s, opts.mode == RigMode::Realtime),
    })
}

/// Every process's report (the bridge's too when there is one); a missing one is a failure, or a note saying why
/// none was due: a process on the other host, or started outside the launcher, or `no_report_due` (ended for good
/// by the plan, or of a run that failed before its flight started).
/// `(controller_external, across_hosts)`: the controller started by hand, the controller on the other host.
fn process_reports(
    opts: &LaunchOptions,
    out: &Path,
    (controller_external, across_hosts): (bool, bool),
    no_report_due: &[Role],
    failures: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Vec<ProcessReport> {
    let mut processes = Vec::new();
    for role in Role::ALL {
        match read_report(out, role.label()) {
            Ok(r) => processes.push(r),
            // A process a planned fault killed for good, or of a run that failed before its flight, has no report
            // to give; anything else should have one.
            Err(_) if no_report_due.contains(&role) => {}
            // It runs on the other host, which sends its report back at the end (see the bridge's events).
            Err(_) if role == Role::Controller && across_hosts => notes.push(
                "controller: on the other host; its report did not come back (the controller-side bridge sends it \
                 when the flight ends: see events.jsonl), so the run's timing is what this host measured"
                    .to_string(),
            ),
            // A plant of the user's own that speaks the contract itself need not write one either; had it failed,
            // its exit is a failure already.
            Err(_) if role == Role::Plant && opts.plant == PlantKind::External => notes.push(
                "plant: started outside the launcher, it wrote no report (a peer that speaks the contract need not): \
                 the run's timing is what the controller and the logger measured"
                    .to_string(),
            ),
            Err(_) if role == Role::Plant && opts.plant_cmd.is_some() => notes.push(
                "plant: your --plant-cmd wrote no report (a peer that speaks the contract need not): the run's timing \
                 is what the controller and the logger measured"
                    .to_string(),
            ),
            // A peer of the contract started by hand need not use the session library, which writes the report.
            Err(_) if role == Role::Controller && controller_external => notes.push(
                "controller: started outside the launcher, it wrote no report (a peer that speaks the contract \
                 need not): its timing is what the plant and the logger measured (sense-to-actuate, misses)"
                    .to_string(),
            ),
            Err(e) => failures.push(format!("{role}: no report ({e})")),
        }
    }
    if across_hosts {
        match read_report(out, "bridge") {
            Ok(r) => processes.push(r),
            Err(e) => failures.push(format!("bridge: no report ({e})")),
        }
    }
    processes
}

/// The run's iceoryx2 resources removed; what could not be, because a process of the run is still alive, in
/// words. A process started by hand (`external`) is given a moment to leave first.
fn leftovers(run_id: &RunId, external: bool) -> anyhow::Result<Vec<String>> {
    let mut cleanup = ipc::cleanup_run(run_id)?;
    if external {
        // A process we did not start writes its report before it closes its ports and exits: give it a moment to
        // leave, or cleaning up finds it alive and removes nothing.
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        while !cleanup.is_clean() && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
            cleanup = ipc::cleanup_run(run_id)?;
        }
    }
    // Processes of this run still alive after every child was reaped: something else joined the run.
    Ok(cleanup
        .alive
        .iter()
        .map(|n| {
            format!("node `{}` of pid {} is still alive, so the run's shared memory was left in place", n.name, n.pid)
        })
        .collect())
}
