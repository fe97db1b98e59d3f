//! `silrig check`: flies a suite of cases with one controller (ours, or a user's through `--controller-cmd`) on the
//! three-process rig, judges each run by its criteria and gives one verdict: a table, `check.json` and a JUnit XML
//! file a CI pipeline can gate on. The suite format is in [`suite`], the criteria in [`criteria`], the files in
//! [`verdict`]; `--in-process` flies the lockstep cases in one process ([`one_process`]).

pub mod criteria;
pub mod one_process;
mod recovery;
pub mod repeat;
pub mod suite;
pub(crate) mod timing;
pub mod verdict;

use anyhow::Context;
use criteria::{RigCriteria, RunEvidence};
use silrig_flight::criteria::Outcome;
use silrig_flight::trace::Trace;
use silrig_launch::launcher::{self, ControllerKind, LaunchOptions};
use silrig_launch::program::{check_command, shell_quote};
use silrig_launch::supervision::{RestartMode, SupervisionOptions};
use silrig_rig::{ProcessOptions, signals};
use std::path::{Path, PathBuf};
use suite::{Case, Suite};
use verdict::{CaseVerdict, Verdict};

/// What `silrig check` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct CheckOptions {
    /// Suite file (TOML); without it, the embedded default suite (configs/check-default.toml), or with
    /// --plant-cmd or --plant-fmu the one for a plant of your own (configs/check-any-plant.toml: nothing of the
    /// F-16).
    pub suite: Option<PathBuf>,
    /// Run only this case of the suite.
    #[arg(long, value_name = "NAME")]
    pub case: Option<String>,
    /// Judge your own controller: this command runs in place of silrig-controller in every case (as with
    /// `silrig run --controller-cmd`).
    #[arg(long, value_name = "CMD")]
    pub controller_cmd: Option<String>,
    /// Judge a co-simulation FMU as the controller in every case (as with `silrig run --controller-fmu`).
    #[arg(long, value_name = "FILE.fmu", conflicts_with = "controller_cmd")]
    pub controller_fmu: Option<PathBuf>,
    /// Fly your own vehicle model: this command runs in place of silrig-plant in every case (as with `silrig run
    /// --plant-cmd`).
    #[arg(long, value_name = "CMD")]
    pub plant_cmd: Option<String>,
    /// Fly a co-simulation FMU as the plant in every case (as with `silrig run --plant-fmu`).
    #[arg(long, value_name = "FILE.fmu", conflicts_with = "plant_cmd")]
    pub plant_fmu: Option<PathBuf>,
    /// Fly the lockstep cases in one process, as `silrig sim` flies a scenario (the built-in F-16 or a plant FMU
    /// against our controller or a controller FMU): the lockstep rig's trace in a fraction of its time. Realtime
    /// cases still fly the rig; a case that needs the rig's processes (process or loop faults, timing or recovery
    /// criteria) is refused.
    #[arg(long, conflicts_with_all = ["controller_cmd", "plant_cmd"])]
    pub in_process: bool,
    /// Output folder (default: out/check-<suite>-<UTC time>); must not hold a check already.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Fly a case whose verdict is inconclusive (the machine disturbed a timing figure) again, up to this many
    /// more times, before it stays inconclusive (0..=10).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=10))]
    pub retries: u32,
    /// A flake benchmark: fly the whole suite this many times (each into `<out>/repeat-<k>`) and report how often
    /// each criterion's answer changed (1..=1000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeat: Option<u32>,
    /// Loop and watchdog tuning, passed on to every run.
    #[command(flatten)]
    pub process: ProcessOptions,
}

/// The exit status of a verdict: 0 pass, 1 a criterion failed, 3 nothing failed but a timing figure stayed
/// inconclusive (2 is nothing judged, [`CheckError`]; 130 interrupted).
pub fn exit_status(outcome: Outcome) -> u8 {
    match outcome {
        Outcome::Pass => 0,
        Outcome::Fail => 1,
        Outcome::Inconclusive => 3,
    }
}

/// Why a check could not judge anything (exit status 2).
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The suite is malformed, or a case's scenario does not load (transparent: its message is said once, not
    /// again as its own source).
    #[error(transparent)]
    Suite(#[from] suite::SuiteError),
    /// A bad command-line argument.
    #[error("{0}")]
    Usage(String),
    /// A case could not be set up (not a verdict on the controller).
    #[error("case `{case}`: {problem:#}")]
    Setup {
        /// The case.
        case: String,
        /// What failed (named so that it is not also printed as the error's source).
        problem: anyhow::Error,
    },
}

impl CheckOptions {
    /// The suite to run, narrowed to `--case`.
    fn load_suite(&self) -> Result<Suite, CheckError> {
        let mut suite = match &self.suite {
            Some(path) => Suite::load(path)?,
            // A plant of your own has none of the F-16's signals, sections or criteria.
            None if self.plant_cmd.is_some() || self.plant_fmu.is_some() => Suite::embedded_any_plant(),
            None => Suite::embedded_default(),
        };
        if let Some(name) = &self.case {
            suite.only(name).map_err(CheckError::Usage)?;
        }
        Ok(suite)
    }

    /// The command that runs just `case` again, as a user types it.
    fn reproduce(&self, case: &str) -> String {
        self.command(Some(case))
    }

    /// The command that runs the suite again (only `case` of it, if given), as a user types it: the suite, the
    /// controller and plant, and the tuning flags that differ from their defaults.
    fn command(&self, case: Option<&str>) -> String {
        let mut cmd = "silrig check".to_string();
        if let Some(s) = &self.suite {
            cmd += &format!(" {}", shell_quote(&s.display().to_string()));
        }
        if let Some(case) = case {
            cmd += &format!(" --case {}", shell_quote(case));
        }
        if let Some(c) = &self.controller_cmd {
            cmd += &format!(" --controller-cmd {}", shell_quote(c));
        }
        if let Some(f) = &self.controller_fmu {
            cmd += &format!(" --controller-fmu {}", shell_quote(&f.display().to_string()));
        }
        if let Some(c) = &self.plant_cmd {
            cmd += &format!(" --plant-cmd {}", shell_quote(c));
        }
        if let Some(f) = &self.plant_fmu {
            cmd += &format!(" --plant-fmu {}", shell_quote(&f.display().to_string()));
        }
        if self.in_process {
            cmd += " --in-process";
        }
        // Only the tuning flags that differ from their defaults, so the command stays short.
        let defaults = default_process_options().to_argv();
        for (flag, value) in self
            .process
            .to_argv()
            .chunks(2)
            .zip(defaults.chunks(2))
            .filter(|(a, b)| a != b)
            .map(|(a, _)| (&a[0], &a[1]))
        {
            cmd += &format!(" {flag} {value}");
        }
        cmd
    }
}

/// The process options with every flag at its default.
fn default_process_options() -> ProcessOptions {
    #[derive(clap::Parser)]
    struct Defaults {
        #[command(flatten)]
        process: ProcessOptions,
    }
    <Defaults as clap::Parser>::parse_from(["silrig"]).process
}

/// The options of one `silrig run` of a case.
fn launch_options(opts: &CheckOptions, case: &Case, scenario_path: &Path, out: PathBuf) -> LaunchOptions {
    LaunchOptions {
        config: Some(scenario_path.to_path_buf()),
        mode: case.mode,
        duration_s: None,
        out: Some(out),
        run_id: None,
        no_baseline: false,
        floor: silrig_launch::launcher::FloorSource::Builtin,
        // The verdict table is what a CI log should show, not each case's live line.
        quiet: true,
        // Each case's figures are what a user opens when it fails.
        no_figures: false,
        process: opts.process.clone(),
        faults: Vec::new(),
        supervision: SupervisionOptions { restart: RestartMode::Never, max_restarts: 0, restart_backoff_ms: 200.0 },
        controller_cmd: opts.controller_cmd.clone(),
        plant_cmd: opts.plant_cmd.clone(),
        plant_fmu: opts.plant_fmu.clone(),
        controller_fmu: opts.controller_fmu.clone(),
        plant: silrig_launch::launcher::PlantKind::Builtin,
        controller: ControllerKind::Builtin,
        // Not used: the controller is always one the launcher starts.
        external_timeout_s: 120.0,
        bridge_listen: None,
        bridge_key: None,
        bridge_insecure: false,
        // The case's scenario says.
        command_timing: None,
        live: None,
    }
}

/// Fly one case (twice for determinism) and judge it; fly it again while its answer is inconclusive, up to
/// `--retries` more times. With the verdict, why no other case can fly, if this one's flight never started.
fn run_case(opts: &CheckOptions, case: &Case, out: &Path) -> Result<(CaseVerdict, Option<String>), CheckError> {
    let setup = |problem: anyhow::Error| CheckError::Setup { case: case.name.clone(), problem };
    let started = std::time::Instant::now();
    let case_dir = out.join(&case.name);
    std::fs::create_dir_all(&case_dir).with_context(|| format!("creating {}", case_dir.display())).map_err(setup)?;
    let scenario_path = case_dir.join("case-scenario.toml");
    std::fs::write(&scenario_path, case.scenario.to_toml())
        .with_context(|| format!("writing {}", scenario_path.display()))
        .map_err(setup)?;
    if let Some(sweep) = &case.sweep {
        return Ok((sweep_case(opts, case, sweep, &scenario_path, &case_dir, started).map_err(setup)?, None));
    }
    if opts.in_process && one_process::flies_in_one_process(case) {
        return Ok((in_process_case(opts, case, &case_dir, started).map_err(setup)?, None));
    }
    let mut run_dirs = Vec::new();
    let mut attempts = 0;
    let (judgements, never_started) = loop {
        attempts += 1;
        // The first flight goes where it always has; a retry into a folder of its own beside it.
        let attempt_dir =
            if attempts == 1 { case_dir.clone() } else { case_dir.join(format!("retry-{}", attempts - 1)) };
        let evidence = fly_runs(opts, case, &scenario_path, &attempt_dir, &mut run_dirs)?;
        let judgements = case.criteria.judge(&case.scenario, &evidence);
        let never_started = evidence.last().and_then(RunEvidence::never_started);
        let outcome = verdict::case_outcome(&judgements);
        if outcome != Outcome::Inconclusive || attempts > opts.retries || signals::termination_requested() {
            break (judgements, never_started);
        }
        eprintln!(
            "silrig check: case {} inconclusive (the machine disturbed a timing figure): flying it again ({} of {})",
            case.name, attempts, opts.retries
        );
    };
    let verdict = CaseVerdict::judged(
        case,
        case.mode.label().into(),
        attempts,
        started.elapsed().as_secs_f64(),
        run_dirs,
        opts.reproduce(&case.name),
        judgements,
    );
    Ok((verdict, never_started.map(|why| format!("the flight never started in case `{}`: {why}", case.name))))
}

/// One flight of a case into `dir`: its run (or two, for determinism), each run's folder added to `run_dirs`. A
/// run whose flight never started ends it: a second one would wait as long for the same thing.
fn fly_runs(
    opts: &CheckOptions,
    case: &Case,
    scenario_path: &Path,
    dir: &Path,
    run_dirs: &mut Vec<String>,
) -> Result<Vec<RunEvidence>, CheckError> {
    let runs = case.criteria.runs();
    let mut evidence: Vec<RunEvidence> = Vec::new();
    for i in 1..=runs {
        let dir = if runs == 1 { dir.to_path_buf() } else { dir.join(format!("run-{i}")) };
        let report = launcher::run(&launch_options(opts, case, scenario_path, dir.clone()))
            .map_err(|problem| CheckError::Setup { case: case.name.clone(), problem })?;
        // The run's page, as `silrig run` writes it: what a reader of a failed case opens first.
        if let Err(e) = crate::html::run::write(&report, &opts.reproduce(&case.name)) {
            eprintln!("silrig check: case {}: no report.html in {}: {e:#}", case.name, dir.display());
        }
        let trace = Trace::load(&dir.join("trace.csv")).ok().filter(|t| !t.rows.is_empty());
        run_dirs.push(dir.display().to_string());
        let held_ns = silrig_launch::run_report::held_command_times_ns(&dir);
        evidence.push(RunEvidence { report, trace, held_ns });
        if signals::termination_requested() || evidence.last().and_then(RunEvidence::never_started).is_some() {
            break;
        }
    }
    Ok(evidence)
}

/// Fly a lockstep case in one process (`--in-process`) and judge it: no inconclusive answer is possible (no
/// timing criterion), so it flies once (twice for determinism).
fn in_process_case(
    opts: &CheckOptions,
    case: &Case,
    case_dir: &Path,
    started: std::time::Instant,
) -> anyhow::Result<CaseVerdict> {
    let mut case = case.clone();
    silrig_adapters::in_process::FmuFlags {
        plant_fmu: opts.plant_fmu.clone(),
        controller_fmu: opts.controller_fmu.clone(),
    }
    .apply(&mut case.scenario)?;
    let (judgements, run_dirs) = one_process::fly_and_judge(&case, case_dir)?;
    let wall_s = started.elapsed().as_secs_f64();
    let mode = "lockstep, one process".into();
    Ok(CaseVerdict::judged(&case, mode, 1, wall_s, run_dirs, opts.reproduce(&case.name), judgements))
}

/// Fly a sweep case: its dispersed cases as `silrig sweep` flies them (in one process; through the lockstep rig
/// with `--controller-cmd` or `--plant-cmd`), with `cases.csv`, `sweep.json` and the figures in the case's folder, judged on the
/// 95 % Wilson lower bound of the pass rate.
fn sweep_case(
    opts: &CheckOptions,
    case: &Case,
    sweep: &suite::SweepCase,
    scenario_path: &Path,
    case_dir: &Path,
    started: std::time::Instant,
) -> anyhow::Result<CaseVerdict> {
    let mut scenario = case.scenario.clone();
    let fmus = silrig_adapters::in_process::FmuFlags {
        plant_fmu: opts.plant_fmu.clone(),
        controller_fmu: opts.controller_fmu.clone(),
    };
    fmus.apply(&mut scenario)?;
    let mut campaign = crate::campaign::Campaign::from_scenario(scenario, &scenario_path.display().to_string())?;
    // A controller or plant of the user's own flies each dispersed case through the lockstep rig, as `silrig sweep
    // --controller-cmd` and `--plant-cmd` do; the worst cases' commands name them.
    let commands = crate::campaign::RigCommands {
        controller_cmd: opts.controller_cmd.clone(),
        plant_cmd: opts.plant_cmd.clone(),
        cold: false,
    };
    if commands.any() {
        campaign.flags = commands.to_args();
        campaign.fly_commands(commands)?;
    }
    let seed = sweep.seed.unwrap_or(campaign.scenario.seed);
    let jobs = campaign.threads(crate::campaign::jobs(None)?);
    let crate::campaign::SweepRun { summary, .. } =
        crate::campaign::fly_into(&campaign, seed, 0..sweep.runs, jobs, case_dir)?;
    if let Some(why) = &summary.interrupted {
        anyhow::bail!("the sweep was {why}");
    }
    let flown = summary.passed + summary.failed;
    let (low, high) = summary.pass_rate_95;
    let measured = format!(
        "{:.1} % lower bound ({} of {flown} passed, 95 % Wilson {:.1} .. {:.1} %; {} infeasible)",
        low * 100.0,
        summary.passed,
        low * 100.0,
        high * 100.0,
        summary.infeasible
    );
    let limit = format!("at least {:.1} % over {} cases", sweep.pass_rate_min * 100.0, sweep.runs);
    let failure = (low < sweep.pass_rate_min).then(|| {
        let mut most: Vec<&(String, u64)> = summary.failures_by_criterion.iter().filter(|(_, n)| *n > 0).collect();
        most.sort_by_key(|(_, n)| std::cmp::Reverse(*n));
        let worst: Vec<String> = most
            .iter()
            .take(3)
            .map(|(name, n)| {
                let case = summary.worst.iter().find(|(w, _)| w == name).and_then(|(_, w)| w.first());
                let example = case.map(|c| format!(", worst case {}: `{}`", c.index, c.reproduce)).unwrap_or_default();
                format!("{name} failed in {n} of {flown}{example}")
            })
            .collect();
        format!(
            "with 95 % confidence the pass rate may be as low as {:.1} %, below the {:.1} % asked: {}. cases.csv and \
             the figures in the case's folder show every case",
            low * 100.0,
            sweep.pass_rate_min * 100.0,
            if worst.is_empty() {
                "no criterion failed, too few cases were flown".to_string()
            } else {
                worst.join("; ")
            }
        )
    });
    let judgements = vec![silrig_flight::judge::judgement("pass_rate", measured, limit, failure)];
    let (wall_s, dirs) = (started.elapsed().as_secs_f64(), vec![case_dir.display().to_string()]);
    Ok(CaseVerdict::judged(case, "sweep".into(), 1, wall_s, dirs, opts.reproduce(&case.name), judgements))
}

/// Say which case flies now, and how (a CI log's progress).
fn announce(opts: &CheckOptions, i: usize, of: usize, case: &Case) {
    eprintln!(
        "silrig check: case {}/{} {} ({}{}) ...",
        i + 1,
        of,
        case.name,
        match case.sweep {
            Some(sweep) => format!(
                "a sweep of {} dispersed cases {}",
                sweep.runs,
                if opts.controller_cmd.is_some() { "through the lockstep rig" } else { "in one process" }
            ),
            None if opts.in_process && one_process::flies_in_one_process(case) => "lockstep, in one process".into(),
            None => case.mode.label().to_string(),
        },
        if case.sweep.is_none() && case.criteria.runs() > 1 { ", flown twice" } else { "" }
    );
}

/// Run the suite and write the verdict's files. An `Err` means nothing could be judged (exit status 2); a verdict
/// with failed cases is `Ok` (exit status 1).
pub fn run(opts: &CheckOptions) -> Result<Verdict, CheckError> {
    signals::install_termination_flag();
    let suite = opts.load_suite()?;
    if let Some(cmd) = &opts.controller_cmd {
        check_command("controller-cmd", cmd).map_err(CheckError::Usage)?;
    }
    if opts.in_process {
        for case in suite.cases.iter().filter(|c| one_process::flies_in_one_process(c)) {
            one_process::refuse_rig_only(case).map_err(CheckError::Usage)?;
        }
    }
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("check-{}-{}", suite.name, verdict::utc_stamp(None))));
    if out.join(verdict::JSON_FILE).exists() {
        return Err(CheckError::Usage(format!(
            "{} already holds a check ({}); choose another --out or move it away: nothing is overwritten",
            out.display(),
            verdict::JSON_FILE
        )));
    }
    let started = std::time::Instant::now();
    let started_unix_s = verdict::unix_now_s();
    let mut cases = Vec::new();
    for (i, case) in suite.cases.iter().enumerate() {
        announce(opts, i, suite.cases.len(), case);
        let (verdict, never_started) = run_case(opts, case, &out)?;
        eprintln!(
            "silrig check: case {} {} in {:.1} s",
            case.name,
            match verdict.outcome() {
                Outcome::Pass => "passed",
                Outcome::Fail => "FAILED",
                Outcome::Inconclusive => "INCONCLUSIVE",
            },
            verdict.wall_s
        );
        cases.push(verdict);
        if signals::termination_requested() {
            break;
        }
        // A controller or plant that never joins, or exits at once, would only make every other case wait as long
        // to say the same: the rest are reported, not flown.
        if let Some(why) = never_started {
            eprintln!("silrig check: {why}; the other cases are not flown");
            let rest = &suite.cases[i + 1..];
            cases.extend(rest.iter().map(|c| CaseVerdict::not_flown(c, opts.reproduce(&c.name), why.clone())));
            break;
        }
    }
    let verdict = Verdict {
        suite: suite.name.clone(),
        suite_file: suite.path.as_ref().map(|p| p.display().to_string()),
        description: suite.description.clone(),
        controller: match (&opts.controller_cmd, &opts.controller_fmu) {
            (Some(cmd), _) => cmd.clone(),
            (None, Some(fmu)) => format!("the FMU {} in silrig-controller", fmu.display()),
            (None, None) => "silrig-controller".into(),
        },
        out_dir: out.display().to_string(),
        started_unix_s,
        wall_s: started.elapsed().as_secs_f64(),
        interrupted: signals::termination_requested(),
        cases_in_suite: suite.cases.len(),
        passed: false,
        inconclusive: false,
        cases,
    }
    .concluded();
    verdict
        .write(&out)
        .and_then(|()| crate::html::check::write(&verdict, &opts.command(opts.case.as_deref())))
        .map_err(|problem| CheckError::Setup { case: "(verdict files)".into(), problem })?;
    Ok(verdict)
}
