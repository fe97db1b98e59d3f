//! `silrig run`: starts the plant, controller and logger as separate processes of one run id, supervises them
//! ([`super::supervision`]), injects the plan's process faults ([`super::fault_schedule`]), stops them with SIGTERM
//! at the end, merges their reports with the control-quality summary of the logged trace ([`super::run_report`]),
//! and removes the run's iceoryx2 resources. In realtime mode it also runs a bare absolute-deadline timer loop
//! beside the rig, so the plant's wake-up lateness can be read against the OS floor measured under the same
//! conditions.

pub use super::claim::fresh_run_id;
use super::claim::{Claim, remove_stale_claims};
use super::fault_schedule::FaultSchedule;
use super::process_env::{wait_for_external_report, write_controller_env, write_plant_env};
use super::run_figures::{remove_empty_figures, write_plots};
use super::run_report::{ProcessLife, RigReport};
use crate::floor::{timer_baseline, timer_baseline::BaselineArgs, timer_baseline::BaselineReport};
use crate::program::check_command;
use crate::supervision::{ChildProcess, ControllerLaunch, SupervisionOptions, Supervisor};
use anyhow::Context;
use silrig_flight::fault::{Fault, FaultTarget};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::trace::Trace;
use silrig_rig::events::EventLog;
use silrig_rig::report::{MachineConditions, ProcessReport, read_report};
use silrig_rig::status::LiveLine;
use silrig_rig::{ProcessArgs, ProcessOptions, RigMode, load_scenario_for, signals};
use silrig_wire::ipc::{self, RunId};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// What `silrig run` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct LaunchOptions {
    /// Scenario file (TOML); without it, the embedded default scenario (for a plant of your own, --plant-cmd,
    /// --plant-fmu or --plant external: the embedded any-plant scenario, set points and timing only).
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
    /// Who takes the OS floor beside a realtime rig: builtin (`silrig timer-baseline`) or cyclictest (rt-tests,
    /// which must be installed); the report names which.
    #[arg(long, value_enum, default_value = "builtin")]
    pub floor: FloorSource,
    /// No live status line while the run goes.
    #[arg(long)]
    pub quiet: bool,
    /// Draw no figures (the trace, report and timing files are written as ever): for runs judged from their files
    /// alone, such as the cases of `silrig sweep --controller-cmd`, where drawing them would take as long as flying.
    #[arg(long)]
    pub no_figures: bool,
    /// Loop and watchdog tuning, passed on to every process.
    #[command(flatten)]
    pub process: ProcessOptions,
    /// A fault to inject, added to the scenario's [[faults]]: TARGET:ACTION@TIME[,KEY=VALUE...], e.g.
    /// `controller:kill@3s,restart_after=0.5s`, `logger:stop@2s,for=500ms`, `plant:delay@2s,delay=15ms`.
    /// Repeatable.
    #[arg(long = "fault", value_parser = silrig_flight::fault::parse_fault_flag)]
    pub faults: Vec<Fault>,
    /// What to do when a process dies.
    #[command(flatten)]
    pub supervision: SupervisionOptions,
    /// Fly your own controller: run this command in place of silrig-controller, with the run's SILRIG_* variables
    /// in its environment (`silrig contract` lists them). Split into words like a shell does, but run directly
    /// (wrap it in `sh -c '...'` yourself for shell syntax). Supervised, restarted and faulted like ours; its stdout
    /// and stderr go to <out>/controller.stderr.log.
    #[arg(long, value_name = "CMD")]
    pub controller_cmd: Option<String>,
    /// Fly your own vehicle model: run this command in place of silrig-plant, with the run's SILRIG_* variables in
    /// its environment; it opens a plant session of libsilrig_client.so (Python: `silrig_client.serve_plant`),
    /// announces its signals and steps its model with the inputs each tick hands it, while the rig keeps the
    /// clock, the watchdog, the failsafe and the faults. Split and supervised like --controller-cmd; its stdout and
    /// stderr go to <out>/plant.stderr.log.
    #[arg(long, value_name = "CMD")]
    pub plant_cmd: Option<String>,
    /// Fly a co-simulation FMU (FMI 2.0 or 3.0, with a Linux x86-64 binary) as the plant: silrig-plant loads it,
    /// announces its Real, Integer and Boolean outputs and inputs as the plant's signals and steps it once per tick;
    /// the scenario's `[plant.parameters]` set its parameters by variable name. Same as the scenario key
    /// `[plant] fmu`.
    #[arg(long, value_name = "FILE.fmu", conflicts_with_all = ["plant_cmd", "plant"])]
    pub plant_fmu: Option<PathBuf>,
    /// Fly a co-simulation FMU (FMI 2.0 or 3.0, with a Linux x86-64 binary) as the controller: silrig-controller
    /// loads it, feeds its inputs (Real, Integer, Boolean) the plant's outputs of the same name (an input `<output>_sp`
    /// the scenario's set point of that output; an input that names nothing of the plant its start value), commands
    /// the plant's inputs with its outputs of the same name and logs all its outputs as diagnostics;
    /// `[controller.map]` renames or holds an input at a constant, `[controller.parameters]` sets its parameters.
    /// Same as the scenario key `[controller] fmu`.
    #[arg(long, value_name = "FILE.fmu", conflicts_with_all = ["controller_cmd", "controller", "bridge_listen"])]
    pub controller_fmu: Option<PathBuf>,
    /// builtin (silrig-plant, or --plant-cmd) or external: wait for a plant started by hand (in a debugger, in a
    /// simulation tool) with the variables printed and written to <out>/plant.env.
    #[arg(long, value_enum, default_value = "builtin", conflicts_with = "plant_cmd")]
    pub plant: PlantKind,
    /// builtin (silrig-controller, or --controller-cmd) or external: wait for a controller started by hand (in a
    /// debugger, in MATLAB) with the variables printed and written to <out>/controller.env.
    #[arg(long, value_enum, default_value = "builtin", conflicts_with = "controller_cmd")]
    pub controller: ControllerKind,
    /// --controller or --plant external: how long the rig waits for the process started by hand to connect, s.
    #[arg(long, default_value_t = 120.0)]
    pub external_timeout_s: f64,
    /// The controller runs on another host: start the plant-side bridge listening here (IP:PORT, tcp/IP:PORT or
    /// udp/IP:PORT) instead of a controller, and wait up to --external-timeout-s for `silrig-bridge --connect` and a
    /// controller on the other host. Next-tick timing unless --command-timing says otherwise. Needs silrig-bridge
    /// (`cargo build --release --features bridge`).
    #[arg(long, value_name = "ENDPOINT", conflicts_with_all = ["controller_cmd", "controller"])]
    pub bridge_listen: Option<String>,
    /// Override the scenario's command timing: same-tick (the plant waits up to --command-budget-ms for the answer
    /// to the tick it just published) or next-tick.
    #[arg(long, value_enum)]
    pub command_timing: Option<silrig_flight::scenario::CommandTiming>,
    /// Serve the run live while it flies: `foxglove` or `foxglove=IP:PORT` (default 127.0.0.1:8765), the
    /// recording's channels over the Foxglove WebSocket protocol, from the logger, for Foxglove or Lichtblick to
    /// connect to. Needs the `live` feature (`cargo build --release --features live`).
    #[arg(long, value_name = "foxglove[=IP:PORT]", value_parser = parse_live)]
    pub live: Option<LiveServe>,
}

/// Where `--live` serves the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LiveServe {
    /// The Foxglove WebSocket protocol, on this address.
    Foxglove(SocketAddr),
}

/// Where `--live foxglove` serves without an address: Foxglove's own default.
pub const LIVE_FOXGLOVE_DEFAULT: &str = "127.0.0.1:8765";

/// `--live`'s value: `foxglove` or `foxglove=IP:PORT`.
pub fn parse_live(value: &str) -> Result<LiveServe, String> {
    let (protocol, addr) = value.split_once('=').unwrap_or((value, LIVE_FOXGLOVE_DEFAULT));
    if protocol != "foxglove" {
        return Err(format!("`{protocol}` is no live protocol: the one served is `foxglove` (foxglove[=IP:PORT])"));
    }
    addr.parse()
        .map(LiveServe::Foxglove)
        .map_err(|e| format!("`{addr}` is no IP:PORT address ({e}), e.g. foxglove=127.0.0.1:8765"))
}

/// Who measures the OS floor beside a realtime run (`--floor`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FloorSource {
    /// `silrig timer-baseline`: a bare clock_nanosleep loop with the rig's skip-on-overrun rule, which also gives
    /// the floor's steady state apart from warm-up.
    Builtin,
    /// cyclictest itself (`cyclictest -q -m -t1 -p80 -i<period> -h`), the reference engineers already trust.
    Cyclictest,
}

/// Where the run's controller comes from (`--controller`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ControllerKind {
    /// The launcher starts it: silrig-controller, or the `--controller-cmd` command.
    Builtin,
    /// Somebody else starts it; the launcher waits for it.
    External,
}

/// Where the run's plant comes from (`--plant`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PlantKind {
    /// The launcher starts it: silrig-plant, or the `--plant-cmd` command.
    Builtin,
    /// Somebody else starts it; the launcher waits for it.
    External,
}

impl LaunchOptions {
    /// Whether the plant is a built-in vehicle (no `--plant-cmd`, `--plant external` or plant FMU).
    fn flies_builtin(&self, scenario: &Scenario) -> bool {
        self.plant_cmd.is_none() && self.plant != PlantKind::External && scenario.plant.fmu.is_none()
    }

    /// Whether the plant is the built-in F-16.
    fn flies_builtin_f16(&self, scenario: &Scenario) -> bool {
        self.flies_builtin(scenario) && !silrig_flight::quad::is_quad(scenario)
    }

    fn controller_launch(&self) -> ControllerLaunch {
        match (&self.controller_cmd, self.controller) {
            _ if self.bridge_listen.is_some() => ControllerLaunch::External,
            (_, ControllerKind::External) => ControllerLaunch::External,
            (Some(cmd), _) => ControllerLaunch::Command(cmd.clone()),
            (None, _) => ControllerLaunch::Ours,
        }
    }
}

/// A run ready to start: its scenario with the plan's faults, its id and its folder.
struct Prepared {
    scenario: Scenario,
    run_id: RunId,
    out: PathBuf,
    /// The scenario as the processes load it (`<out>/scenario.toml`).
    scenario_path: PathBuf,
    /// The folder and the run id, held for the run.
    _claims: [Claim; 2],
}

/// Phase 1: the scenario with `--fault` flags added and validated, a folder that holds no run yet, the effective
/// scenario written there, and the run id's namespace free of a crashed run's leftovers.
fn prepare(opts: &LaunchOptions) -> anyhow::Result<Prepared> {
    if let Some(LiveServe::Foxglove(addr)) = opts.live {
        anyhow::ensure!(
            silrig_rig::live_foxglove::AVAILABLE,
            "--live foxglove: {}",
            silrig_rig::live_foxglove::NOT_BUILT
        );
        // The logger binds it once the run has started: a port in use is said now, before anything flies.
        std::net::TcpListener::bind(addr).with_context(|| format!("--live foxglove={addr}: cannot listen there"))?;
    }
    opts.process.validate().map_err(|e| anyhow::anyhow!(e))?;
    opts.supervision.validate().map_err(|e| anyhow::anyhow!(e))?;
    silrig_rig::flag_in_range("external-timeout-s", opts.external_timeout_s, 0.1, 86_400.0, "s")
        .map_err(|e| anyhow::anyhow!(e))?;
    // Without a file, a plant of the user's own flies the any-plant scenario: the F-16's would refuse it.
    let own_plant = opts.plant_cmd.is_some() || opts.plant_fmu.is_some() || opts.plant != PlantKind::Builtin;
    let mut scenario = load_scenario_for(opts.config.as_deref(), opts.duration_s, own_plant)?;
    // Across hosts a network leg sits in every answer: next-tick unless the user asks for same-tick.
    let across_hosts = opts.bridge_listen.is_some().then_some(silrig_flight::scenario::CommandTiming::NextTick);
    if let Some(timing) = opts.command_timing.or(across_hosts) {
        scenario.timing.command_timing = timing;
    }
    scenario.faults.extend(opts.faults.iter().cloned());
    scenario.validate().map_err(|(key, problem)| anyhow::anyhow!("fault plan: `{key}`: {problem}"))?;
    if let Some(fmu) = &opts.plant_fmu {
        scenario.plant.fmu = Some(fmu.clone());
    }
    if let Some(fmu) = scenario.plant.fmu.take() {
        anyhow::ensure!(
            opts.plant_cmd.is_none() && opts.plant == PlantKind::Builtin,
            "the scenario's plant is the FMU {}: it flies in silrig-plant, not with --plant-cmd or --plant external",
            fmu.display()
        );
        // The processes read the scenario from the run's folder: the FMU by its absolute path.
        let fmu = std::path::absolute(&fmu).map_err(|e| anyhow::anyhow!("--plant-fmu {}: {e}", fmu.display()))?;
        // Every problem of the file, its variables and the parameters is said here, before any process starts.
        silrig_rig::fmu_plant::FmuPlant::check(&fmu, &scenario)?;
        scenario.plant.fmu = Some(fmu);
    }
    if let Some(fmu) = &opts.controller_fmu {
        scenario.controller.fmu = Some(fmu.clone());
    }
    if let Some(fmu) = scenario.controller.fmu.take() {
        anyhow::ensure!(
            opts.controller_cmd.is_none() && opts.controller == ControllerKind::Builtin && opts.bridge_listen.is_none(),
            "the scenario's controller is the FMU {}: it flies in silrig-controller, not with --controller-cmd, \
             --controller external or --bridge-listen",
            fmu.display()
        );
        let fmu = std::path::absolute(&fmu).map_err(|e| anyhow::anyhow!("--controller-fmu {}: {e}", fmu.display()))?;
        // The file and `[controller]` are checked here; against the plant's signals too when they are known before
        // it runs (a built-in vehicle, an FMU plant), else when the plant announces them.
        let plant = if let Some(plant_fmu) = &scenario.plant.fmu {
            Some(silrig_rig::fmu_plant::FmuPlant::check(plant_fmu, &scenario)?.signals)
        } else if opts.flies_builtin(&scenario) {
            Some(silrig_flight::quad::builtin_signals(&scenario).map_err(|(k, p)| anyhow::anyhow!("`{k}`: {p}"))?)
        } else {
            None
        };
        silrig_rig::fmu_controller::FmuController::check(&fmu, &scenario, plant.as_ref())?;
        scenario.controller.fmu = Some(fmu);
    }
    if opts.mode == RigMode::Lockstep
        && let Some(f) = scenario.faults.iter().find(|f| !f.action().is_plant_model_fault())
    {
        anyhow::bail!("fault plan: {} needs realtime mode (lockstep has no clock to fault)", f.describe());
    }
    if (opts.controller == ControllerKind::External || opts.bridge_listen.is_some())
        && let Some(f) =
            scenario.faults.iter().find(|f| f.target() == Role::Controller && f.action().is_process_fault())
    {
        anyhow::bail!("fault plan: {} needs a controller the launcher starts, not --controller external", f.describe());
    }
    if opts.bridge_listen.is_none()
        && let Some(f) = scenario.faults.iter().find(|f| f.target() == FaultTarget::Bridge)
    {
        anyhow::bail!("fault plan: {} needs a plant-side bridge: a run with --bridge-listen", f.describe());
    }
    if opts.plant == PlantKind::External
        && let Some(f) = scenario.faults.iter().find(|f| f.target() == Role::Plant && f.action().is_process_fault())
    {
        anyhow::bail!("fault plan: {} needs a plant the launcher starts, not --plant external", f.describe());
    }
    // A built-in vehicle is known now; a plant of your own is checked against the signals it announces when it joins
    // (its `[actuators]`, sensor and actuator faults by its own names: `silrig_flight::signal_chain`).
    if opts.flies_builtin(&scenario) {
        silrig_flight::sim::check_builtin(&scenario)
            .map_err(|(key, problem)| anyhow::anyhow!("the scenario: `{key}`: {problem}"))?;
    }
    for (flag, cmd) in [("controller-cmd", &opts.controller_cmd), ("plant-cmd", &opts.plant_cmd)] {
        if let Some(cmd) = cmd {
            check_command(flag, cmd).map_err(anyhow::Error::msg)?;
        }
    }
    let run_id = opts.run_id.clone().unwrap_or_else(fresh_run_id);
    let out = opts.out.clone().unwrap_or_else(|| Path::new("out").join(format!("run-{run_id}")));
    anyhow::ensure!(
        !out.join("trace.csv").exists(),
        "{} already holds a run (trace.csv); choose another --out or move it away: nothing is overwritten",
        out.display()
    );
    let created = !out.exists();
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    claim(scenario, run_id, out.clone()).inspect_err(|_| {
        // A refused run leaves no folder behind: only an empty one it made itself goes (never one that another
        // run, racing for it, has put anything in).
        if created {
            let _ = std::fs::remove_dir(&out);
        }
    })
}

/// Phase 1, once the folder exists: claim it and the run id, clear a crashed run's leftovers, and write the
/// effective scenario last, so that a refusal leaves the folder as it found it.
fn claim(scenario: Scenario, run_id: RunId, out: PathBuf) -> anyhow::Result<Prepared> {
    let claims = [
        Claim::take(out.join(".silrig-run.lock"), &format!("the folder {}", out.display()))?,
        Claim::take(PathBuf::from(format!("/tmp/silrig_{run_id}.lock")), &format!("run id {run_id}"))?,
    ];
    // Checked again now that the folder is ours: a run that finished between the first check and the claim.
    anyhow::ensure!(
        !out.join("trace.csv").exists(),
        "{} already holds a run (trace.csv); choose another --out or move it away: nothing is overwritten",
        out.display()
    );
    let root = run_id.root_dir();
    anyhow::ensure!(
        // Without its trailing slash, so that a file there is seen as one.
        std::fs::symlink_metadata(root.components().as_path()).ok().is_none_or(|m| m.is_dir()),
        "run id {run_id}: {} exists and is not a folder (iceoryx2 keeps the run's state there): remove it, or \
         choose another --run-id",
        root.components().as_path().display()
    );
    // A crashed run with this id may have left resources behind; they must not poison this one.
    let pre = ipc::cleanup_run(&run_id)?;
    if !pre.is_clean() {
        let who: Vec<String> = pre.alive.iter().map(|n| format!("{} (pid {})", n.name, n.pid)).collect();
        anyhow::bail!("run id {run_id} is in use by live processes: {}; choose another --run-id", who.join(", "));
    }
    let dead = ipc::cleanup_dead_runs(&run_id);
    let claims_removed = remove_stale_claims();
    if !dead.is_empty() || claims_removed > 0 {
        let runs: Vec<&str> = dead.iter().map(|r| r.run.as_str()).collect();
        let files: usize = dead.iter().map(|r| r.removed_shm_files.len()).sum();
        eprintln!(
            "silrig run: removed what {} dead run(s) left on this machine ({files} shared-memory files, \
             {claims_removed} run-id locks): {}",
            dead.len(),
            runs.join(", ")
        );
    }
    let scenario_path = out.join("scenario.toml");
    std::fs::write(&scenario_path, scenario.to_toml())?;
    Ok(Prepared { scenario, run_id, out, scenario_path, _claims: claims })
}

/// The OS-floor timer loop beside a realtime rig, for the scenario's duration at the scenario's period.
fn start_baseline(scenario: &Scenario, out: &Path, floor: FloorSource) -> anyhow::Result<ChildProcess> {
    let priority = Role::Plant.fifo_priority().unwrap_or(0);
    if floor == FloorSource::Cyclictest {
        let mut command =
            crate::floor::cyclictest::command(scenario.timing.duration_s, scenario.timing.period_ns(), priority)
                .map_err(anyhow::Error::msg)?;
        super::supervision::end_with_launcher(&mut command, libc::SIGKILL);
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
    super::supervision::end_with_launcher(&mut command, libc::SIGKILL);
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
        sup.restart_due()?;
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
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// cyclictest's output in the run's folder, as it printed it.
const CYCLICTEST_OUTPUT: &str = "cyclictest.txt";

/// The baseline's report (None if it wrote none); after a failed run it is not waited for.
fn finish_baseline(
    baseline: &mut ChildProcess,
    floor: FloorSource,
    scenario: &Scenario,
    out: &Path,
    failed: bool,
) -> std::io::Result<Option<BaselineReport>> {
    if failed {
        baseline.signal(libc::SIGKILL);
    } else if signals::termination_requested() {
        // A terminal's Ctrl-C reaches the baseline too; a SIGINT or SIGTERM to the launcher alone must end it as
        // well, or the run waits out its planned duration. SIGINT, as Ctrl-C: cyclictest then prints its summary.
        baseline.signal(libc::SIGINT);
    }
    baseline.finish(Duration::from_secs_f64(scenario.timing.duration_s + 10.0))?;
    if floor == FloorSource::Cyclictest {
        let text = std::fs::read_to_string(out.join(CYCLICTEST_OUTPUT)).unwrap_or_default();
        let timing = &scenario.timing;
        let priority = Role::Plant.fifo_priority().unwrap_or(0);
        return Ok(match crate::floor::cyclictest::parse(&text, timing.period_ns(), timing.duration_s, priority) {
            Ok(report) => Some(report),
            Err(e) => {
                eprintln!("silrig run: warning: no OS floor: {e} (see {})", out.join(CYCLICTEST_OUTPUT).display());
                None
            }
        });
    }
    let path = out.join("timer-baseline.json");
    let report = std::fs::read_to_string(&path).ok().and_then(|t| serde_json::from_str(&t).ok());
    if report.is_none() {
        // Killed, or its output did not fit on the disk: no file rather than a torn one.
        let _ = std::fs::remove_file(&path);
    }
    Ok(report)
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
    signals::install_termination_flag();
    let Prepared { scenario, run_id, out, scenario_path, _claims } = prepare(opts)?;
    let controller = opts.controller_launch();
    let mut args = ProcessArgs {
        config: Some(scenario_path),
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
    let mut baseline = if realtime_floor { Some(start_baseline(&scenario, &out, opts.floor)?) } else { None };
    write_controller_env(&args, &controller, opts.bridge_listen.is_some())?;
    if plant_external {
        write_plant_env(&args)?;
    }
    let conditions_start = MachineConditions::now();
    let events = EventLog::new(&out, "launcher");
    let mut bridge = match &opts.bridge_listen {
        Some(listen) => Some(super::remote::RemoteBridge::start(listen, &args, events.clone())?),
        None => None,
    };
    let plant_launch = if plant_external { None } else { Some(opts.plant_cmd.clone()) };
    let logger_args = match opts.live {
        Some(LiveServe::Foxglove(addr)) => {
            eprintln!("silrig run: serving the run live on ws://{addr} (Foxglove WebSocket protocol)");
            vec!["--live-foxglove".to_string(), addr.to_string()]
        }
        None => Vec::new(),
    };
    let launch = (controller.clone(), plant_launch, logger_args);
    let mut sup = Supervisor::start(args, events.clone(), opts.supervision.clone(), launch)?;
    sup.plant_fmu = scenario.plant.fmu.clone();
    sup.controller_fmu = scenario.controller.fmu.clone();
    let mut faults = FaultSchedule::new(&scenario.faults, &out, events, &run_id, scenario.timing.dt_s);
    let mut live = (!opts.quiet).then(|| LiveLine::new(&run_id));
    let supervised = supervise(&mut sup, &mut faults, &scenario, &mut bridge, live.as_mut());
    if let Some(live) = live {
        live.finish();
    }
    supervised?;
    let ended_by_plan = sup.ended_by_plan();
    faults.release_stopped(&mut sup, bridge.as_mut());
    sup.stop_all()?;
    if let Some(b) = bridge.as_mut() {
        b.wait_for_controller_report(&out);
        b.stop()?;
        sup.failures.extend(b.failure.take());
    }
    sup.note_final_reports();
    let timer_baseline = match baseline.as_mut() {
        Some(b) => finish_baseline(b, opts.floor, &scenario, &out, !sup.failures.is_empty())?,
        None => None,
    };
    let conditions_end = MachineConditions::now();

    if controller == ControllerLaunch::External && bridge.is_none() {
        wait_for_external_report(&out, Role::Controller);
    }
    if plant_external {
        wait_for_external_report(&out, Role::Plant);
    }
    let mut failures = std::mem::take(&mut sup.failures);
    let mut notes = Vec::new();
    let mut processes = Vec::new();
    for role in Role::ALL {
        match read_report(&out, role.label()) {
            Ok(r) => processes.push(r),
            // It runs on the other host, which sends its report back at the end (see the bridge's events).
            Err(_) if role == Role::Controller && bridge.is_some() => notes.push(
                "controller: on the other host; its report did not come back (the controller-side bridge sends it \
                 when the flight ends: see events.jsonl), so the run's timing is what this host measured"
                    .to_string(),
            ),
            // A plant of the user's own that speaks the contract itself need not write one either; had it failed,
            // its exit is a failure already.
            Err(_) if role == Role::Plant && plant_external => notes.push(
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
            Err(_) if role == Role::Controller && controller == ControllerLaunch::External => notes.push(
                "controller: started outside the launcher, it wrote no report (a peer that speaks the contract \
                 need not): its timing is what the plant and the logger measured (sense-to-actuate, misses)"
                    .to_string(),
            ),
            // A process a planned fault killed for good has no report to give; anything else should have one.
            Err(_) if ended_by_plan.contains(&role) => {}
            Err(e) => failures.push(format!("{role}: no report ({e})")),
        }
    }
    if bridge.is_some() {
        match read_report(&out, "bridge") {
            Ok(r) => processes.push(r),
            Err(e) => failures.push(format!("bridge: no report ({e})")),
        }
    }
    super::run_report::merge_lives(&mut processes, &sup.lives, &out, &mut notes);
    mark_stopped_at_end(&mut processes, &sup.lives);
    failures.extend(super::held_outputs::flag_held_rows(&out, &scenario));
    let trace = Trace::load(&out.join("trace.csv")).ok().filter(|t| !t.rows.is_empty());
    let (control, unsummarised) =
        super::run_report::control_summary(&out, trace.as_ref(), &scenario, opts.flies_builtin_f16(&scenario));
    notes.extend(unsummarised);
    let flown_s = trace
        .as_ref()
        .and_then(|t| t.column("t_s"))
        .and_then(|t| t.last().copied())
        .map_or(0.0, |t| t + scenario.timing.dt_s);
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
    let mut cleanup = ipc::cleanup_run(&run_id)?;
    if controller == ControllerLaunch::External || plant_external {
        // A process we did not start writes its report before it closes its ports and exits: give it a moment to
        // leave, or cleaning up finds it alive and removes nothing.
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        while !cleanup.is_clean() && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
            cleanup = ipc::cleanup_run(&run_id)?;
        }
    }
    // Processes of this run still alive after every child was reaped: something else joined the run.
    let leftovers = cleanup
        .alive
        .iter()
        .map(|n| {
            format!("node `{}` of pid {} is still alive, so the run's shared memory was left in place", n.name, n.pid)
        })
        .collect();
    // A plant that left no report (killed), or whose report covers only its last life, flew at least what the
    // logger wrote.
    let plant_ticks =
        processes.iter().find(|p| p.process == Role::Plant.label()).and_then(|p| p.counters.get("ticks").copied());
    let ticks = plant_ticks.unwrap_or(0).max((flown_s / scenario.timing.dt_s).round() as u64);
    let wall_s = sup.wall_s;
    let mut report = RigReport {
        run_id: run_id.to_string(),
        scenario: scenario.name.clone(),
        mode: opts.mode.label().into(),
        out_dir: out.display().to_string(),
        conditions_start,
        conditions_end,
        wall_s,
        cycles_per_s: if wall_s > 0.0 { ticks as f64 / wall_s } else { 0.0 },
        processes,
        lives: sup.lives,
        timer_baseline,
        control,
        faults: super::fault_report::fault_records(&scenario.faults, &out, scenario.timing.dt_s),
        discontinuities: super::fault_report::discontinuities(&out, scenario.timing.dt_s),
        duration_s: scenario.timing.duration_s,
        stopped_by,
        failures,
        notes,
        figures_left_out: Vec::new(),
        leftovers,
        phases: super::run_report::phase_splits(&out, scenario.timing.dt_s, opts.mode == RigMode::Realtime),
    };
    // A full disk must not cost the user the report: it is printed whatever happens to the files.
    if !opts.no_figures {
        match write_plots(&report, &out, &scenario) {
            Ok(left_out) => report.figures_left_out = left_out,
            Err(e) => {
                report.failures.push(format!("silrig run: the figures: {e:#}"));
                remove_empty_figures(&out);
            }
        }
    }
    if let Err(e) = silrig_flight::files::write_atomically(
        &out.join("report.json"),
        &(serde_json::to_string_pretty(&report)? + "\n"),
    ) {
        report.failures.push(format!("silrig run: {e}"));
    }
    Ok(report)
}
