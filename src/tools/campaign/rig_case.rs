//! One case of a campaign flown through the three-process lockstep rig (`silrig sweep --controller-cmd CMD`,
//! `--plant-cmd CMD`, or both): a user's controller or plant in a process of its own (C, Python, JSBSim, anything
//! that speaks the contract) flying the case's sampled scenario, exactly as `silrig run --mode lockstep` with the
//! same commands flies that scenario, and judged by [`case::judge`] like a case flown in one process. Which
//! commands a sweep flies, and what is refused before any case flies, is [`RigCommands`]. Each case is a rig of its
//! own (its own run id, so its own iceoryx2 namespace and claims), so several fly side by side on a sweep's worker
//! threads; a sweep's case runs in a scratch folder ([`Scratch`]) removed once it is judged, so a sweep of any length
//! leaves no run folders.
//!
//! Why `launcher::run` may run on several threads of one process: each run claims its own folder and run id (lock
//! files holding this process's pid, which `remove_stale_claims` leaves alone since the pid is alive), waits for its
//! own children by their handles (never `waitpid(-1)`), installs the same process-wide SIGINT/SIGTERM flag every
//! time (which then stops every rig, and the sweep: [`Interrupted`]), and clears only runs whose nodes are all dead
//! and older than a grace period. Its children die with the worker thread that forked them (PR_SET_PDEATHSIG),
//! which outlives its run. Run ids are made here rather than by the launcher, whose fresh ids (pid and microseconds)
//! two threads could draw alike.

use super::case::{self, CaseResult, Flight};
use crate::outputs::FlownScenario;
use serde::{Deserialize, Serialize};
use silrig_flight::scenario::Scenario;
use silrig_flight::trace::Trace;
use silrig_launch::launcher::{self, LaunchOptions};
use silrig_rig::signals;
use silrig_wire::ipc::RunId;
use std::path::Path;

/// The case's scenario as the rig is given it, in the case's run folder.
pub const CASE_SCENARIO: &str = "case-scenario.toml";

/// A sweep stopped by SIGINT or SIGTERM (named).
#[derive(Debug, thiserror::Error)]
#[error("interrupted by {0}")]
pub struct Interrupted(pub &'static str);

/// Stop when the user asked to: launcher::run routes SIGINT and SIGTERM to a flag, so a sweep must look at it.
pub fn check_interrupted() -> Result<(), Interrupted> {
    match signals::termination_signal() {
        Some(signal) => Err(Interrupted(signals::name(signal))),
        None => Ok(()),
    }
}

/// The processes of the user's own that a sweep's cases fly in place of ours, through the lockstep rig: with
/// neither, the cases fly in one process. A plant command flies under our controller, a controller command or a
/// controller FMU (which silrig-controller flies).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RigCommands {
    /// `--controller-cmd`: the user's controller, in place of silrig-controller.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller_cmd: Option<String>,
    /// `--plant-cmd`: the user's plant, in place of silrig-plant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plant_cmd: Option<String>,
    /// `--cold`: every case's processes started afresh instead of forked from warm programs
    /// ([`super::scratch`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub cold: bool,
}

impl RigCommands {
    /// Whether the cases fly through the rig (a command is given).
    pub fn any(&self) -> bool {
        self.controller_cmd.is_some() || self.plant_cmd.is_some()
    }

    /// The commands given, each with its flag's name.
    fn given(&self) -> impl Iterator<Item = (&'static str, &str)> {
        [("controller-cmd", &self.controller_cmd), ("plant-cmd", &self.plant_cmd)]
            .into_iter()
            .filter_map(|(flag, cmd)| cmd.as_deref().map(|cmd| (flag, cmd)))
    }

    /// The flags as a command line repeats them (` --controller-cmd '...'`), quoted for a shell; empty when none.
    pub fn to_args(&self) -> String {
        let commands =
            self.given().map(|(flag, cmd)| format!(" --{flag} {}", silrig_launch::program::shell_quote(cmd)));
        commands.chain(self.cold.then(|| " --cold".to_string())).collect()
    }

    /// Refuse, before any case flies, a command whose program cannot be found; a command beside the FMU that would
    /// take the same place (`scenario`, named `config`, flies a controller FMU under a controller command, or a
    /// plant FMU under a plant command); and with a plant command, a dispersion of a key that only the built-in
    /// F-16 reads, which would change nothing the plant process flies.
    pub fn check(&self, scenario: &Scenario, config: &str) -> anyhow::Result<()> {
        for (flag, cmd) in self.given() {
            silrig_launch::program::check_command(flag, cmd).map_err(anyhow::Error::msg)?;
        }
        let one_at_a_time = |side: &str, fmu: &Path, other: &str| {
            anyhow::anyhow!(
                "--{side}-cmd flies your {side} in place of ours, but {config} flies the {side} FMU {} \
                 (--{side}-fmu or its [{side}] fmu): sweep one {side} at a time (a {other} FMU may stay)",
                fmu.display()
            )
        };
        if let (Some(_), Some(fmu)) = (&self.controller_cmd, &scenario.controller.fmu) {
            return Err(one_at_a_time("controller", fmu, "plant"));
        }
        if let (Some(_), Some(fmu)) = (&self.plant_cmd, &scenario.plant.fmu) {
            return Err(one_at_a_time("plant", fmu, "controller"));
        }
        if self.plant_cmd.is_some()
            && let Some(key) = scenario.dispersions.keys().find(|k| silrig_flight::dispersion::is_f16_only(k))
        {
            anyhow::bail!(
                "{config}: dispersions.\"{key}\": the plant is your process (--plant-cmd), which does not read \
                 `{key}` (only the built-in F-16 does); disperse what your plant reads with plant_parameter as \
                 `plant.parameters.<name>` (its start values too, by the names it reads them with) and its set \
                 points as `setpoint.<output>`"
            );
        }
        Ok(())
    }
}

/// The options `silrig run --mode lockstep --quiet --controller-cmd CMD --plant-cmd CMD --run-id ID --out DIR
/// CONFIG` is given (each command when there is one), parsed as the command line parses them: every other flag at
/// its default, so a case is that run, byte for byte (with `--no-figures` when the run's folder is thrown away once
/// judged: the figures change nothing in it but the time). No restarts (the default): a controller or plant that
/// dies fails its case.
fn launch_options(
    commands: &RigCommands,
    config: &Path,
    out: &Path,
    run_id: Option<&RunId>,
    figures: bool,
) -> anyhow::Result<LaunchOptions> {
    #[derive(clap::Parser)]
    struct Run {
        #[command(flatten)]
        launch: LaunchOptions,
    }
    let mut argv = vec!["silrig-run".to_string(), "--mode".into(), "lockstep".into(), "--quiet".into()];
    for (flag, cmd) in commands.given() {
        argv.extend([format!("--{flag}"), cmd.into()]);
    }
    argv.extend(["--out".into(), out.display().to_string()]);
    if let Some(id) = run_id {
        argv.extend(["--run-id".into(), id.to_string()]);
    }
    if !figures {
        argv.push("--no-figures".into());
    }
    argv.push(config.display().to_string());
    Ok(<Run as clap::Parser>::try_parse_from(argv)?.launch)
}

/// Fly case `index` of `campaign` under `seed` with its commands through the lockstep rig in `run_dir` (created;
/// it must not hold a run), as `run_id` (None: a fresh one), drawing the run's figures or not; returns the result
/// and, when flown, the flight. A rig that could not be set up makes the case infeasible; a controller or plant that
/// crashed, exited or never answered fails it, the rig's failures as its reason. Err only when the user stopped the
/// sweep.
pub fn fly(
    campaign: &super::Campaign,
    seed: u64,
    index: u64,
    run_dir: &Path,
    run_id: Option<&RunId>,
    figures: bool,
) -> Result<(CaseResult, Option<Flight>), Interrupted> {
    fly_in(campaign, (seed, index), run_dir, run_id, figures, None).map(|(result, flight, _)| (result, flight))
}

/// [`fly`], its processes forked by `warm` when given (a sweep's warm rig); the third value says whether the rig
/// failed (a process crashed, went silent or could not be started), after which a warm rig is started again cold.
pub fn fly_in(
    campaign: &super::Campaign,
    (seed, index): (u64, u64),
    run_dir: &Path,
    run_id: Option<&RunId>,
    figures: bool,
    warm: Option<std::sync::Arc<silrig_launch::warm::WarmRig>>,
) -> Result<(CaseResult, Option<Flight>, bool), Interrupted> {
    check_interrupted()?;
    let (values, scenario) = case::sample(&campaign.scenario, seed, index);
    let scenario = match scenario {
        Ok(scenario) => scenario,
        Err(reason) => return Ok((case::infeasible(index, values, reason), None, false)),
    };
    // A built-in vehicle is built in the plant's process, which would fail the case with only its stderr to say
    // why: a case that cannot be trimmed (the F-16) or flown (the quadrotor's parameters) is infeasible, as in one
    // process, with the same reason.
    if scenario.plant.fmu.is_none() && campaign.commands.plant_cmd.is_none() {
        let built = if silrig_flight::quad::is_quad(&scenario) {
            silrig_flight::quad::check_for_quad(&scenario).map_err(|(key, problem)| format!("`{key}`: {problem}"))
        } else {
            silrig_flight::sim::PlantRunner::new(&scenario).map(drop).map_err(|e| e.to_string())
        };
        if let Err(e) = built {
            return Ok((case::infeasible(index, values, e), None, false));
        }
    }
    let config = run_dir.join(CASE_SCENARIO);
    let report = std::fs::create_dir_all(run_dir)
        .and_then(|()| std::fs::write(&config, scenario.to_toml()))
        .map_err(anyhow::Error::from)
        .and_then(|()| launch_options(&campaign.commands, &config, run_dir, run_id, figures))
        .and_then(|opts| launcher::run_with(&opts, warm));
    let report = match report {
        Ok(report) => report,
        Err(e) => {
            let reason = format!("the rig could not be set up: {e:#}");
            return Ok((case::infeasible(index, values, reason), None, true));
        }
    };
    let rig_failed = !report.failures.is_empty();
    check_interrupted()?;
    // A controller or plant that died before the plant's first tick leaves no trace: the case is judged on none (every
    // criterion fails, its figures are empty), with the rig's failures as the reason.
    let trace = Trace::load(&run_dir.join("trace.csv")).unwrap_or_else(|_| Trace::new(Vec::new()));
    // A rig that failed fails the case. When its trace stops short of the scenario's end (in lockstep the plant
    // gives up on a controller that no longer answers), the flight stopped there: a departure, as an FMU's failed
    // call is in one process.
    let last_t_s = trace.column("t_s").and_then(|t| t.last().copied());
    let short = last_t_s.is_none_or(|t| t + scenario.timing.dt_s / 2.0 < scenario.timing.duration_s);
    let (ended_early, refusals) = match report.failures {
        failures if short && !failures.is_empty() => (Some((last_t_s.unwrap_or(0.0), failures.join("; "))), vec![]),
        failures => (None, failures),
    };
    // The plant's signals for its summary: an FMU's as it announces them, none for the built-in F-16.
    let plant = campaign.models.plant_signals(&scenario).ok().flatten();
    let flown = FlownScenario { trace, plant, ended_early, refusals };
    let (result, flight) = case::judge(&campaign.criteria, index, values, scenario, flown);
    Ok((result, Some(flight), rig_failed))
}
