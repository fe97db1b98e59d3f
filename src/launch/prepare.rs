//! Phase 1 of `silrig run`: the options checked, the scenario with the plan's faults and the FMUs checked before
//! anything starts, a folder that holds no run yet claimed with the run id, and the effective scenario written there.

use super::claim::{Claim, fresh_run_id, refuse_used_folder, remove_stale_claims};
use super::options::{ControllerKind, LaunchOptions, LiveServe, PlantKind};
use crate::program::check_command;
use crate::supervision::ControllerLaunch;
use anyhow::Context;
use silrig_flight::fault::FaultTarget;
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_rig::{RigMode, load_scenario_for};
use silrig_wire::ipc::{self, RunId};
use std::path::{Path, PathBuf};

/// A run ready to start: its scenario with the plan's faults, its id and its folder.
pub(crate) struct Prepared {
    pub(crate) scenario: Scenario,
    pub(crate) run_id: RunId,
    pub(crate) out: PathBuf,
    /// The scenario as the processes load it (`<out>/scenario.toml`).
    pub(crate) scenario_path: PathBuf,
    /// The folder and the run id, held for the run.
    pub(crate) _claims: [Claim; 2],
}

/// Phase 1: the scenario with `--fault` flags added and validated, a folder that holds no run yet, the effective
/// scenario written there, and the run id's namespace free of a crashed run's leftovers.
pub(crate) fn prepare(opts: &LaunchOptions) -> anyhow::Result<Prepared> {
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
    place_fmus(opts, &mut scenario)?;
    check_fault_plan(opts, &scenario)?;
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
    if let Some(listen) = &opts.bridge_listen {
        super::remote::check(listen, &opts.bridge_security(), run_id.as_str())?;
    }
    let out = opts.out.clone().unwrap_or_else(|| Path::new("out").join(format!("run-{run_id}")));
    refuse_used_folder(&out)?;
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
    refuse_used_folder(&out)?;
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
    let (dead, claims_removed) = match machine_cleanup_due() {
        true => (ipc::cleanup_dead_runs(&run_id), remove_stale_claims()),
        false => (Vec::new(), 0),
    };
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

/// The FMUs of `--plant-fmu` and `--controller-fmu` (or the scenario's) by their absolute paths, as the processes
/// read them from the run's folder, each checked here with its variables and parameters, before any process starts.
fn place_fmus(opts: &LaunchOptions, scenario: &mut Scenario) -> anyhow::Result<()> {
    let mut plant_fmu_signals = None;
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
        plant_fmu_signals = Some(silrig_adapters::fmu::plant::FmuPlant::check(&fmu, scenario)?.signals);
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
            Some(silrig_adapters::fmu::plant::FmuPlant::check(plant_fmu, scenario)?.signals)
        } else if opts.flies_builtin(scenario) {
            Some(silrig_flight::quad::builtin_signals(scenario).map_err(|(k, p)| anyhow::anyhow!("`{k}`: {p}"))?)
        } else {
            None
        };
        silrig_adapters::fmu::controller::FmuController::check(&fmu, scenario, plant.as_ref())?;
        scenario.controller.fmu = Some(fmu);
    }
    // A plant FMU under silrig-controller with no controller named flies the built-in law that fits its signals;
    // one that fits none is refused now, naming them.
    if let Some(signals) = plant_fmu_signals
        && matches!(opts.controller_launch(), ControllerLaunch::Ours)
    {
        silrig_adapters::process::ControllerKind::fitting(scenario, |_| Ok(signals))?;
    }
    Ok(())
}

/// The plan's faults can happen in this run: lockstep has no clock to fault, and a process the launcher did not
/// start (or a bridge it does not run) cannot be signalled.
fn check_fault_plan(opts: &LaunchOptions, scenario: &Scenario) -> anyhow::Result<()> {
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
    // A device fault is carried out by the controller process that flies the device.
    if (scenario.controller.device.is_none()
        || opts.controller_cmd.is_some()
        || opts.controller == ControllerKind::External)
        && let Some(f) = scenario.faults.iter().find(|f| f.target() == FaultTarget::Device)
    {
        anyhow::bail!(
            "fault plan: {} needs a device flown as the controller: a scenario with [controller] device = \"<layout>\"",
            f.describe()
        );
    }
    if opts.plant == PlantKind::External
        && let Some(f) = scenario.faults.iter().find(|f| f.target() == Role::Plant && f.action().is_process_fault())
    {
        anyhow::bail!("fault plan: {} needs a plant the launcher starts, not --plant external", f.describe());
    }
    Ok(())
}

/// Whether this run should look for what dead runs left on the machine: the first run of a process, then at most
/// every [`MACHINE_CLEANUP_EVERY`]. Looking reads every entry of `/tmp` and `/dev/shm` (thousands on a busy
/// machine), which a sweep's every case would pay; its own runs clean up after themselves.
fn machine_cleanup_due() -> bool {
    static LAST: std::sync::Mutex<Option<std::time::Instant>> = std::sync::Mutex::new(None);
    let mut last = LAST.lock().unwrap_or_else(|e| e.into_inner());
    let due = last.is_none_or(|t| t.elapsed() >= MACHINE_CLEANUP_EVERY);
    if due {
        *last = Some(std::time::Instant::now());
    }
    due
}

/// See [`machine_cleanup_due`].
const MACHINE_CLEANUP_EVERY: std::time::Duration = std::time::Duration::from_secs(10);
