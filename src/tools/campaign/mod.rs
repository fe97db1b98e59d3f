//! Monte Carlo campaigns (`silrig sweep`): the scenario's dispersions sampled case by case
//! ([`silrig_flight::dispersion`]), each case flown in the single-process loop ([`case`]), or with a user's
//! controller or plant command through the three-process lockstep rig ([`rig_case`]), judged by the scenario's
//! `[criteria]`, in parallel over the cores with a progress line, each case written as it comes ([`SweepWriter`]:
//! memory bounded whatever the number of cases), and summarised with the pass rate, its interval and the worst cases
//! ([`report`], [`figures`]).

pub mod case;
pub mod figures;
pub mod report;
pub mod rig_case;
pub mod scratch;
pub mod shard;

use anyhow::Context;
use case::CaseResult;
pub use rig_case::RigCommands;
use std::collections::BTreeMap;
use std::io::{IsTerminal, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

use silrig_adapters::in_process::{FmuFlags, Models};
use silrig_flight::criteria::Criteria;
use silrig_flight::scenario::Scenario;

/// `silrig sweep`: every case on this machine, or (with a subcommand) a sweep split over many.
#[derive(Debug, Clone, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepCommand {
    /// Split the sweep over machines: plan, run a shard, merge, or write a Slurm array script.
    #[command(subcommand)]
    pub action: Option<SweepAction>,
    /// The sweep on this machine.
    #[command(flatten)]
    pub local: SweepOptions,
}

/// The steps of a sweep split over machines.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum SweepAction {
    /// Write the plan (manifest.json) into a folder every worker can read.
    Plan(shard::PlanOptions),
    /// Fly one shard of a plan (the index from --index, --shard, $SLURM_ARRAY_TASK_ID or $JOB_COMPLETION_INDEX).
    Run(shard::RunOptions),
    /// Check that every shard of a plan is done and write the outputs a single-machine sweep writes.
    Merge {
        /// The sweep folder.
        dir: PathBuf,
    },
    /// Write the Slurm array script (sweep.sbatch) for a plan.
    Slurm(shard::SlurmOptions),
}

/// What `silrig sweep CONFIG` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct SweepOptions {
    /// Scenario file (TOML) with `[dispersions]` and `[criteria]`.
    #[arg(required = true)]
    pub config: Option<PathBuf>,
    /// Number of cases.
    #[arg(long, required = true)]
    pub runs: Option<u64>,
    /// Seed of the dispersions (default: the scenario's `seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Output folder (default: out/sweep-<scenario>-<seed>); must not hold a sweep already.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The plant or controller as an FMU, in place of the scenario's.
    #[command(flatten)]
    pub fmus: FmuFlags,
    /// Sweep your own controller: fly every case through the three-process lockstep rig with this command in place
    /// of silrig-controller (as `silrig run --mode lockstep --controller-cmd CMD`), --jobs rigs side by side. A case
    /// whose controller crashes, exits or never answers fails, with the rig's reason.
    #[arg(long, value_name = "CMD")]
    pub controller_cmd: Option<String>,
    /// Sweep your own plant: fly every case through the three-process lockstep rig with this command in place of
    /// silrig-plant (as `silrig run --mode lockstep --plant-cmd CMD`), under our controller, --controller-cmd or a
    /// controller FMU. Disperse what it reads as `plant.parameters.<name>` and its set points as
    /// `setpoint.<output>`. A case whose plant crashes or exits early fails, with the rig's reason.
    #[arg(long, value_name = "CMD")]
    pub plant_cmd: Option<String>,
    /// With --controller-cmd or --plant-cmd: start every case's processes afresh, as `silrig run` does, instead of
    /// forking them from programs kept warm from case to case (slower; the same results).
    #[arg(long)]
    pub cold: bool,
}

impl SweepOptions {
    /// `--controller-cmd` and `--plant-cmd`, as given.
    pub fn commands(&self) -> RigCommands {
        RigCommands { controller_cmd: self.controller_cmd.clone(), plant_cmd: self.plant_cmd.clone(), cold: self.cold }
    }
}

/// Largest number of cases in one sweep.
pub const MAX_RUNS: u64 = 10_000_000;

/// A scenario ready to sweep: loaded, with dispersions and criteria, its FMUs (if any) unpacked once.
pub struct Campaign {
    /// The nominal scenario (with its dispersions).
    pub scenario: Scenario,
    /// Its criteria.
    pub criteria: Criteria,
    /// The dispersed keys, in sample order.
    pub parameters: Vec<String>,
    /// The file as the user named it (for the commands printed).
    pub config: String,
    /// `--plant-fmu`, `--controller-fmu`, `--controller-cmd`, `--plant-cmd` as given, repeated in the commands
    /// printed.
    pub flags: String,
    /// The plant and controller every case flies in one process (new instances per case).
    pub models: Models,
    /// The user's controller and plant commands: when either is given, every case flies through the lockstep rig.
    pub commands: RigCommands,
}

impl Campaign {
    /// Load `config` (FMU paths taken relative to it), with the FMUs of `fmus` in place of its own and the
    /// `commands` of the user's own (if any), and check it can be swept.
    pub fn load(config: &Path, fmus: &FmuFlags, commands: &RigCommands) -> anyhow::Result<Self> {
        let mut scenario = Scenario::load(config)?;
        fmus.apply(&mut scenario)?;
        let name = config.display().to_string();
        // Before the FMUs are opened, so that this is what is said.
        commands.check(&scenario, &name)?;
        let mut campaign = Self::from_scenario(scenario, &name)?;
        campaign.commands = commands.clone();
        campaign.flags = fmus.to_args() + &commands.to_args();
        Ok(campaign)
    }

    /// Fly every case through the lockstep rig with `commands`: refused as [`RigCommands::check`] says.
    pub fn fly_commands(&mut self, commands: RigCommands) -> anyhow::Result<()> {
        commands.check(&self.scenario, &self.config)?;
        self.commands = commands;
        Ok(())
    }

    /// A campaign from a scenario's text; `config` names it in errors and printed commands.
    pub fn from_text(text: &str, config: &str) -> anyhow::Result<Self> {
        Self::from_scenario(Scenario::from_toml(text, config)?, config)
    }

    /// The scenario as a command names it: the file and the FMU flags given with it.
    pub fn command_config(&self) -> String {
        format!("{}{}", self.config, self.flags)
    }

    /// A campaign of `scenario` (with its dispersions and criteria); `config` names it in errors and printed
    /// commands.
    pub fn from_scenario(scenario: Scenario, config: &str) -> anyhow::Result<Self> {
        anyhow::ensure!(
            !scenario.dispersions.is_empty(),
            "{config}: no [dispersions]: a sweep needs at least one dispersed key"
        );
        let criteria = scenario.criteria.clone().filter(Criteria::has_flight_criteria).ok_or_else(|| {
            anyhow::anyhow!("{config}: no [criteria]: a sweep judges every case by them (e.g. settled, alpha_max_deg)")
        })?;
        let parameters = scenario.dispersions.keys().cloned().collect();
        let models = Models::open(&scenario)?;
        for key in scenario.dispersions.keys() {
            models.check_dispersed(key).map_err(|e| anyhow::anyhow!("{config}: dispersions.\"{key}\": {e}"))?;
        }
        Ok(Self {
            scenario,
            criteria,
            parameters,
            config: config.to_string(),
            flags: String::new(),
            models,
            commands: RigCommands::default(),
        })
    }

    /// The worker threads that may fly its cases: `jobs`, or one when an FMU's binary allows a single instance
    /// per process (said on stderr) and the cases fly in this process (through the rig, each plant is a process).
    pub fn threads(&self, jobs: usize) -> usize {
        match self.models.one_instance_per_process() {
            Some(fmu) if jobs > 1 && !self.commands.any() => {
                eprintln!(
                    "silrig sweep: {fmu} can be instantiated only once per process \
                     (canBeInstantiatedOnlyOncePerProcess): flying its cases on one thread, not {jobs}"
                );
                1
            }
            _ => jobs,
        }
    }

    /// Whether a controller flies its plant: without `--controller-cmd` its cases fly in one process or under the
    /// rig's silrig-controller, where a plant FMU needs a built-in controller that fits it (or one named).
    pub fn controller_fits(&self) -> anyhow::Result<()> {
        if self.commands.controller_cmd.is_none() { self.models.controller_fits() } else { Ok(()) }
    }

    /// The criteria's names, in the order every flown case's judgements come in.
    pub fn criterion_names(&self) -> Vec<String> {
        silrig_flight::judge::judge_flight(&self.criteria, &self.scenario, None, None)
            .into_iter()
            .map(|j| j.criterion)
            .collect()
    }

    /// The summary's columns of `cases.csv`, named by the plant's signals (the F-16's, or its plant FMU's).
    pub fn figure_columns(&self) -> anyhow::Result<Vec<String>> {
        let plant = self.models.plant_signals(&self.scenario).map_err(anyhow::Error::msg)?;
        Ok(silrig_flight::summary::case_columns(&self.scenario, plant.as_ref()))
    }

    /// An empty `sweep.json` of this campaign under `seed`, whose cases are judged as `criterion_names` (theirs).
    pub fn tally(&self, seed: u64, criterion_names: &[String]) -> report::Tally {
        report::Tally::new(
            &self.scenario.name,
            &self.command_config(),
            seed,
            &self.parameters,
            &self.criteria,
            criterion_names,
        )
    }

    /// What flying takes first: SIGINT and SIGTERM caught, the controller checked against the plant, and with a
    /// controller or plant command the cases' run folders (and each worker's warm rig, unless cold).
    fn ready_to_fly(&self) -> anyhow::Result<Option<scratch::Scratch>> {
        silrig_rig::signals::install_termination_flag();
        self.controller_fits()?;
        self.commands.any().then(|| scratch::Scratch::new(self.commands.cold)).transpose()
    }

    /// Fly the cases `indices` under `seed` on `jobs` threads (with a controller or plant command, `jobs` rigs side
    /// by side), reporting progress on stderr, and hand each result to `sink` in index order as soon as the cases
    /// before it are flown: at most [`REORDER_WINDOW`] results wait for their turn, so memory stays bounded
    /// whatever the number of cases. SIGINT or SIGTERM stops it: the cases in flight finish (a rig's case is
    /// stopped, and not handed on), no case is started, and it returns the interruption, every case before the
    /// first one not flown having been handed to `sink`. An error of `sink` stops it too, and is returned.
    pub fn fly_each(
        &self,
        seed: u64,
        indices: std::ops::Range<u64>,
        jobs: usize,
        mut sink: impl FnMut(CaseResult) -> anyhow::Result<()>,
    ) -> anyhow::Result<Option<rig_case::Interrupted>> {
        let scratch = self.ready_to_fly()?;
        let total = indices.end - indices.start;
        let (done, next, stop) = (AtomicU64::new(0), AtomicU64::new(indices.start), AtomicBool::new(false));
        // The first case not yet handed to `sink`: no worker starts a case a window or more past it.
        let (handed, turn) = (Mutex::new(indices.start), Condvar::new());
        let stopped = || stop.load(Ordering::Relaxed) || silrig_rig::signals::termination_requested();
        let started = Instant::now();
        std::thread::scope(|scope| {
            let progress = scope.spawn(|| report_progress(&done, total, started));
            let (tx, rx) = std::sync::mpsc::channel();
            for _ in 0..jobs {
                let tx = tx.clone();
                let (next, handed, turn, done, scratch) = (&next, &handed, &turn, &done, &scratch);
                let stop = &stop;
                scope.spawn(move || {
                    // A case that panics stops the others (who might wait for it at the window's edge for ever);
                    // the scope then passes the panic on.
                    let _stop_on_panic = StopOnPanic(stop);
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if i >= indices.end || stopped() {
                            break;
                        }
                        let mut first = handed.lock().expect("no worker panics holding it");
                        while i >= *first + REORDER_WINDOW && !stopped() {
                            first = turn.wait_timeout(first, Duration::from_millis(100)).expect("not poisoned").0;
                        }
                        drop(first);
                        let r = match scratch {
                            Some(scratch) => scratch.fly(self, seed, i),
                            None => Ok(case::fly(&self.models, &self.scenario, &self.criteria, seed, i)),
                        };
                        done.fetch_add(1, Ordering::Relaxed);
                        if tx.send((i, r)).is_err() {
                            break;
                        }
                    }
                });
            }
            drop(tx);
            let mut waiting = BTreeMap::new();
            let mut expected = indices.start;
            let mut outcome = Ok(None);
            for (i, r) in rx {
                waiting.insert(i, r);
                while outcome.as_ref().is_ok_and(Option::is_none)
                    && let Some(r) = waiting.remove(&expected)
                {
                    match r.map(&mut sink) {
                        Ok(Ok(())) => expected += 1,
                        Ok(Err(e)) => outcome = Err(e),
                        Err(interrupted) => outcome = Ok(Some(interrupted)),
                    }
                    *handed.lock().expect("no worker panics holding it") = expected;
                    turn.notify_all();
                }
                if !outcome.as_ref().is_ok_and(Option::is_none) {
                    stop.store(true, Ordering::Relaxed);
                    waiting.clear();
                }
            }
            // An interrupted sweep leaves cases unflown: the progress line ends all the same.
            done.store(total, Ordering::Relaxed);
            progress.join().expect("the progress reporter does not panic");
            match outcome {
                Ok(None) if expected < indices.end => {
                    Ok(Some(rig_case::check_interrupted().err().unwrap_or(rig_case::Interrupted("a signal"))))
                }
                outcome => outcome,
            }
        })
    }
}

/// Sets its flag when dropped by a panicking thread.
struct StopOnPanic<'a>(&'a AtomicBool);

impl Drop for StopOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

/// Cases flown ahead of the first one not yet written, at most: bounds the memory of the results waiting for the
/// cases before them (a case of the rig may take seconds while the others fly on).
pub const REORDER_WINDOW: u64 = 4096;

/// Progress on stderr until `done` reaches `total`: a bar redrawn in place on a terminal, a plain line every few
/// seconds otherwise (logs, CI, Slurm).
fn report_progress(done: &AtomicU64, total: u64, started: Instant) {
    let tty = std::io::stderr().is_terminal();
    let bar = tty.then(|| {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template("sweep [{bar:30}] {pos}/{len} cases, {per_sec}, ETA {eta}")
                .expect("a valid template")
                .progress_chars("=> "),
        );
        bar
    });
    let mut last_line = Instant::now();
    loop {
        let n = done.load(Ordering::Relaxed);
        match &bar {
            Some(b) => b.set_position(n),
            None if n == total || last_line.elapsed() >= Duration::from_secs(5) => {
                let elapsed = started.elapsed().as_secs_f64();
                let rate = n as f64 / elapsed.max(1e-9);
                let eta = if n > 0 { (total - n) as f64 / rate } else { f64::NAN };
                eprintln!("sweep: {n}/{total} cases, {rate:.0} cases/s, ETA {eta:.1} s");
                last_line = Instant::now();
            }
            None => {}
        }
        if n >= total {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    if let Some(b) = bar {
        b.finish();
    }
}

/// What a finished sweep wrote and measured.
pub struct SweepRun {
    /// The summary (`sweep.json`).
    pub summary: report::SweepSummary,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// Wall time of flying the cases, s.
    pub fly_s: f64,
    /// Worker threads.
    pub jobs: usize,
}

/// A sweep's outputs written as its cases come in index order: each case's row of `cases.csv` at once, the summary
/// and the figures gathered in bounded memory and written at the end.
pub struct SweepWriter<'a> {
    campaign: &'a Campaign,
    out: PathBuf,
    /// Where `cases.csv` is written: `cases.csv` itself, or a name it gets only once the sweep is whole.
    csv_path: PathBuf,
    csv: std::io::BufWriter<std::fs::File>,
    row: String,
    /// The summary's columns of `cases.csv`.
    columns: Vec<String>,
    criteria: usize,
    tally: report::Tally,
    figures: figures::Figures,
}

impl<'a> SweepWriter<'a> {
    /// Start the outputs of `campaign` under `seed` in `out` (created); with `staged`, `cases.csv` is written under
    /// another name and takes its own only when [`finish`](Self::finish)ed, so a sweep that fails half way (a
    /// merge that finds a bad shard) leaves none.
    pub fn create(campaign: &'a Campaign, seed: u64, out: &Path, staged: bool) -> anyhow::Result<Self> {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let names = campaign.criterion_names();
        let columns = campaign.figure_columns()?;
        let csv_path = out.join(if staged { "cases.csv.partial" } else { "cases.csv" });
        let file = std::fs::File::create(&csv_path).with_context(|| format!("writing {}", csv_path.display()))?;
        let mut csv = std::io::BufWriter::with_capacity(1 << 16, file);
        csv.write_all(report::cases_csv_header(&campaign.parameters, &columns, &names).as_bytes())
            .with_context(|| format!("writing {}", csv_path.display()))?;
        let tally = campaign.tally(seed, &names);
        Ok(Self {
            campaign,
            out: out.to_path_buf(),
            csv_path,
            csv,
            row: String::new(),
            columns,
            criteria: names.len(),
            tally,
            figures: figures::Figures::default(),
        })
    }

    /// The next case, in index order.
    pub fn add(&mut self, case: &CaseResult) -> anyhow::Result<()> {
        self.row.clear();
        report::case_csv_row(&mut self.row, case, &self.columns, self.criteria);
        self.csv.write_all(self.row.as_bytes()).with_context(|| format!("writing {}", self.csv_path.display()))?;
        self.tally.add(case);
        self.figures.add(case);
        Ok(())
    }

    /// Cases written so far.
    pub fn cases(&self) -> u64 {
        self.tally.cases()
    }

    /// Finish `cases.csv`, write `sweep.json` (saying why the sweep stopped short, if `interrupted` says it did)
    /// and the figures; returns the summary and the files written.
    pub fn finish(self, interrupted: Option<String>) -> anyhow::Result<(report::SweepSummary, Vec<PathBuf>)> {
        let Self { campaign, out, csv_path, csv, tally, figures, .. } = self;
        csv.into_inner().map_err(|e| e.into_error()).with_context(|| format!("writing {}", csv_path.display()))?;
        let csv = out.join("cases.csv");
        if csv_path != csv {
            std::fs::rename(&csv_path, &csv)
                .with_context(|| format!("renaming {} to cases.csv", csv_path.display()))?;
        }
        let summary = tally.finish(interrupted);
        let json = out.join("sweep.json");
        std::fs::write(&json, serde_json::to_string_pretty(&summary)? + "\n")
            .with_context(|| format!("writing {}", json.display()))?;
        let plant = campaign.models.plant_signals(&campaign.scenario).ok().flatten();
        let signals = case::envelope_signals(&campaign.scenario, plant.as_ref());
        let mut files = vec![csv, json];
        files.extend(figures.write(&summary, &campaign.criteria, &signals, &out)?);
        files.push(crate::html::sweep::write(&summary, &out)?);
        Ok((summary, files))
    }

    /// Remove what was written (a sweep refused half way).
    pub fn discard(self) {
        let _ = std::fs::remove_file(&self.csv_path);
    }
}

/// Fly the cases `indices` of `campaign` under `seed` on `jobs` threads with their outputs in `out` as they come;
/// a sweep stopped by SIGINT or SIGTERM keeps the cases flown before the first one that was not, and its
/// `sweep.json` says so.
pub fn fly_into(
    campaign: &Campaign,
    seed: u64,
    indices: std::ops::Range<u64>,
    jobs: usize,
    out: &Path,
) -> anyhow::Result<SweepRun> {
    let mut writer = SweepWriter::create(campaign, seed, out, false)?;
    let started = Instant::now();
    let interrupted = campaign.fly_each(seed, indices.clone(), jobs, |case| writer.add(&case))?;
    let fly_s = started.elapsed().as_secs_f64();
    let interrupted = interrupted.map(|i| {
        format!(
            "stopped by {} after {} of the {} cases asked: cases.csv and this summary hold the cases flown before \
             it, in index order; the rest were not flown",
            i.0,
            writer.cases(),
            indices.end - indices.start
        )
    });
    let (summary, files) = writer.finish(interrupted)?;
    Ok(SweepRun { summary, files, fly_s, jobs })
}

/// Refuse a number of cases outside 1..=MAX_RUNS.
fn check_runs(runs: u64) -> anyhow::Result<()> {
    anyhow::ensure!((1..=MAX_RUNS).contains(&runs), "--runs must be within 1..={MAX_RUNS}, got {runs}");
    Ok(())
}

/// Worker threads: as asked (1..=1024), or one per core.
pub fn jobs(asked: Option<usize>) -> anyhow::Result<usize> {
    let jobs = asked.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    anyhow::ensure!((1..=1024).contains(&jobs), "--jobs must be within 1..=1024, got {jobs}");
    Ok(jobs)
}

/// `silrig sweep CONFIG --runs N`: every case on this machine.
pub fn sweep(opts: &SweepOptions) -> anyhow::Result<SweepRun> {
    let (Some(config), Some(runs)) = (&opts.config, opts.runs) else {
        anyhow::bail!("silrig sweep needs a scenario file and --runs N (or a subcommand: plan, run, merge, slurm)");
    };
    check_runs(runs)?;
    let campaign = Campaign::load(config, &opts.fmus, &opts.commands())?;
    // Before its folder is made: a sweep no controller can fly is refused with nothing written.
    campaign.controller_fits()?;
    let seed = opts.seed.unwrap_or(campaign.scenario.seed);
    let jobs = campaign.threads(jobs(opts.jobs)?);
    let out =
        opts.out.clone().unwrap_or_else(|| Path::new("out").join(format!("sweep-{}-{seed}", campaign.scenario.name)));
    anyhow::ensure!(
        !out.join("sweep.json").exists(),
        "{} already holds a sweep (sweep.json); choose another --out or move it away: nothing is overwritten",
        out.display()
    );
    fly_into(&campaign, seed, 0..runs, jobs, &out)
}

/// `silrig sim CONFIG --sample I`: fly case I alone, with its trace, summary and plots in `out`; returns the text
/// (the sampled values, the summary, each criterion as `cases.csv` has it) and the files written.
pub fn fly_one(campaign: &Campaign, seed: u64, index: u64, out: &Path) -> anyhow::Result<(String, Vec<PathBuf>)> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let (result, flight) = if campaign.commands.any() {
        // The rig writes its run (trace, report, figures) into `out` itself.
        silrig_launch::claim::refuse_used_folder(out)?;
        rig_case::fly(campaign, seed, index, out, None, true)?
    } else {
        case::fly_with_trace(&campaign.models, &campaign.scenario, &campaign.criteria, seed, index)
    };
    let mut text = format!("case {index} of {} (seed {seed}): {}\n", campaign.command_config(), result.outcome.label());
    for (key, value) in campaign.parameters.iter().zip(&result.values) {
        text += &format!("  {key} = {value}\n");
    }
    let case_json = out.join("case.json");
    std::fs::write(&case_json, serde_json::to_string_pretty(&result)? + "\n")
        .with_context(|| format!("writing {}", case_json.display()))?;
    let Some(case::Flight { scenario, trace, plant, summary }) = flight else {
        text += &format!("  infeasible: {}\n", result.reason);
        return Ok((text, vec![case_json]));
    };
    let mut files = if campaign.commands.any() {
        ["trace.csv", rig_case::CASE_SCENARIO, "report.json"].map(|f| out.join(f)).to_vec()
    } else {
        crate::outputs::write_run(out, &scenario, &trace, &summary, plant.as_ref())?
    };
    files.push(case_json);
    text += &summary.to_text();
    if !result.reason.is_empty() {
        text += &format!("  failed: {}\n", result.reason);
    }
    let width = result.judgements.iter().map(|j| j.criterion.len()).max().unwrap_or(0).max(26);
    for j in &result.judgements {
        text += &format!(
            "  {:<width$} {:<34} {:<28} {}\n",
            j.criterion,
            j.measured,
            j.limit,
            if j.passed { "pass" } else { "FAIL" }
        );
    }
    Ok((text, files))
}
