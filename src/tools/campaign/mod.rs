//! Monte Carlo campaigns (`silrig sweep`): the scenario's dispersions sampled case by case
//! ([`silrig_flight::dispersion`]), each case flown in the single-process loop ([`case`]), or with a user's
//! controller command through the three-process lockstep rig ([`rig_case`]), judged by the scenario's `[criteria]`,
//! in parallel over the cores with a progress line, and summarised with the pass rate, its interval and the worst
//! cases ([`report`]).

pub mod case;
pub mod report;
pub mod rig_case;
pub mod shard;

use anyhow::Context;
use case::CaseResult;
use rayon::prelude::*;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use silrig_flight::criteria::Criteria;
use silrig_flight::scenario::Scenario;
use silrig_rig::in_process::{FmuFlags, Models};

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
    /// `--plant-fmu`, `--controller-fmu`, `--controller-cmd` as given, repeated in the commands printed.
    pub flags: String,
    /// The plant and controller every case flies (new instances per case).
    pub models: Models,
    /// `--controller-cmd`: the user's controller, every case flown through the lockstep rig with it.
    pub controller_cmd: Option<String>,
}

impl Campaign {
    /// Load `config` (FMU paths taken relative to it), with the FMUs of `fmus` in place of its own and the
    /// controller command `controller_cmd` (if any), and check it can be swept.
    pub fn load(config: &Path, fmus: &FmuFlags, controller_cmd: Option<&str>) -> anyhow::Result<Self> {
        let mut scenario = Scenario::load(config)?;
        fmus.apply(&mut scenario)?;
        let name = config.display().to_string();
        if let Some(cmd) = controller_cmd {
            // Before the FMUs are opened, so that this is what is said.
            check_controller_cmd(cmd, &scenario, &name)?;
        }
        let mut campaign = Self::from_scenario(scenario, &name)?;
        campaign.flags = fmus.to_args();
        if let Some(cmd) = controller_cmd {
            campaign.controller_cmd = Some(cmd.to_string());
            campaign.flags += &format!(" --controller-cmd {}", silrig_launch::program::shell_quote(cmd));
        }
        Ok(campaign)
    }

    /// Fly every case through the lockstep rig with the controller `cmd`: refused when its program cannot be found,
    /// or beside a controller FMU.
    pub fn fly_controller_cmd(&mut self, cmd: &str) -> anyhow::Result<()> {
        check_controller_cmd(cmd, &self.scenario, &self.config)?;
        self.controller_cmd = Some(cmd.to_string());
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
            controller_cmd: None,
        })
    }

    /// The worker threads that may fly its cases: `jobs`, or one when an FMU's binary allows a single instance
    /// per process (said on stderr) and the cases fly in this process (through the rig, each plant is a process).
    pub fn threads(&self, jobs: usize) -> usize {
        match self.models.one_instance_per_process() {
            Some(fmu) if jobs > 1 && self.controller_cmd.is_none() => {
                eprintln!(
                    "silrig sweep: {fmu} can be instantiated only once per process \
                     (canBeInstantiatedOnlyOncePerProcess): flying its cases on one thread, not {jobs}"
                );
                1
            }
            _ => jobs,
        }
    }

    /// Fly the cases `indices` under `seed` on `jobs` threads (with a controller command, `jobs` rigs side by
    /// side), reporting progress on stderr; results in index order.
    pub fn fly(&self, seed: u64, indices: std::ops::Range<u64>, jobs: usize) -> anyhow::Result<Vec<CaseResult>> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build().context("starting the worker threads")?;
        let scratch = self.controller_cmd.as_ref().map(|_| rig_case::Scratch::new()).transpose()?;
        let total = indices.end - indices.start;
        let done = AtomicU64::new(0);
        let started = Instant::now();
        let results = std::thread::scope(|scope| {
            let progress = scope.spawn(|| report_progress(&done, total, started));
            let results: Result<Vec<CaseResult>, rig_case::Interrupted> = pool.install(|| {
                indices
                    .into_par_iter()
                    .map(|i| {
                        let r = match (&self.controller_cmd, &scratch) {
                            (Some(cmd), Some(scratch)) => scratch.fly(self, cmd, seed, i),
                            _ => Ok(case::fly(&self.models, &self.scenario, &self.criteria, seed, i)),
                        };
                        done.fetch_add(1, Ordering::Relaxed);
                        r
                    })
                    .collect()
            });
            // An interrupted sweep leaves cases unflown: the progress line ends all the same.
            done.store(total, Ordering::Relaxed);
            progress.join().expect("the progress reporter does not panic");
            results
        });
        Ok(results?)
    }
}

/// Refuse the controller command `cmd` up front when its program cannot be found, or when `scenario` (named
/// `config`) flies a controller FMU, which takes the controller's place in silrig-controller just as `cmd` would.
fn check_controller_cmd(cmd: &str, scenario: &Scenario, config: &str) -> anyhow::Result<()> {
    silrig_launch::program::check_command("controller-cmd", cmd).map_err(anyhow::Error::msg)?;
    if let Some(fmu) = &scenario.controller.fmu {
        anyhow::bail!(
            "--controller-cmd flies your controller in place of ours, but {config} flies the controller FMU {} \
             (--controller-fmu or its [controller] fmu): sweep one controller at a time (a plant FMU may stay)",
            fmu.display()
        );
    }
    Ok(())
}

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

/// Write `cases.csv` and `sweep.json` of `cases` into `out`.
pub fn write_outputs(
    campaign: &Campaign,
    seed: u64,
    cases: &[CaseResult],
    out: &Path,
) -> anyhow::Result<(report::SweepSummary, Vec<PathBuf>)> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let summary = report::summarize(
        cases,
        &campaign.scenario.name,
        &campaign.command_config(),
        seed,
        &campaign.parameters,
        &campaign.criteria,
    );
    let csv = out.join("cases.csv");
    std::fs::write(&csv, report::cases_csv(cases, &campaign.parameters))
        .with_context(|| format!("writing {}", csv.display()))?;
    let json = out.join("sweep.json");
    std::fs::write(&json, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("writing {}", json.display()))?;
    Ok((summary, vec![csv, json]))
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
    let campaign = Campaign::load(config, &opts.fmus, opts.controller_cmd.as_deref())?;
    let seed = opts.seed.unwrap_or(campaign.scenario.seed);
    let jobs = campaign.threads(jobs(opts.jobs)?);
    let out =
        opts.out.clone().unwrap_or_else(|| Path::new("out").join(format!("sweep-{}-{seed}", campaign.scenario.name)));
    anyhow::ensure!(
        !out.join("sweep.json").exists(),
        "{} already holds a sweep (sweep.json); choose another --out or move it away: nothing is overwritten",
        out.display()
    );
    let started = Instant::now();
    let cases = campaign.fly(seed, 0..runs, jobs)?;
    let fly_s = started.elapsed().as_secs_f64();
    let (summary, mut files) = write_outputs(&campaign, seed, &cases, &out)?;
    files.extend(write_plots(&campaign, &summary, &cases, &out)?);
    files.push(crate::html::sweep::write(&summary, &out)?);
    Ok(SweepRun { summary, files, fly_s, jobs })
}

/// `silrig sim CONFIG --sample I`: fly case I alone, with its trace, summary and plots in `out`; returns the text
/// (the sampled values, the summary, each criterion as `cases.csv` has it) and the files written.
pub fn fly_one(campaign: &Campaign, seed: u64, index: u64, out: &Path) -> anyhow::Result<(String, Vec<PathBuf>)> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let (result, flight) = match &campaign.controller_cmd {
        Some(cmd) => {
            // The rig writes its run (trace, report, figures) into `out` itself.
            anyhow::ensure!(
                !out.join("trace.csv").exists(),
                "{} already holds a run (trace.csv); choose another --out or move it away: nothing is overwritten",
                out.display()
            );
            rig_case::fly(campaign, cmd, seed, index, out, None, true)?
        }
        None => case::fly_with_trace(&campaign.models, &campaign.scenario, &campaign.criteria, seed, index),
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
    let mut files = match &campaign.controller_cmd {
        Some(_) => ["trace.csv", rig_case::CASE_SCENARIO, "report.json"].map(|f| out.join(f)).to_vec(),
        None => crate::outputs::write_run(out, &scenario, &trace, &summary, plant.as_ref())?,
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

/// The unit of a criterion's figure (as `Judgement::value` holds it).
fn criterion_unit(criterion: &str) -> &'static str {
    match criterion {
        "settled" => "settling time (s)",
        "alpha_max_deg" => "largest alpha (deg)",
        "overshoot_max_deg" => "overshoot (deg)",
        "final_error_max_deg" => "final error (deg)",
        "body_rate_max_dps" => "late |p|,|q|,|r| (deg/s)",
        "rate_limit_fraction_max" => "ticks at rate limit",
        "position_limit_fraction_max" => "ticks at position limit",
        "no_sustained_oscillation" => "oscillation / threshold",
        _ => "",
    }
}

/// Failed cases drawn one by one in the envelope.
const ENVELOPE_FAILED_DRAWN: usize = 30;
/// Parameters in the scatter figure.
const SCATTER_PARAMETERS: usize = 4;

/// The sweep's figures: `histograms`, `scatter` (the parameters that move the most-failed criterion's figure the
/// most, by |Spearman's rho|) and `envelope`.
pub fn write_plots(
    campaign: &Campaign,
    summary: &report::SweepSummary,
    cases: &[CaseResult],
    out: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    use silrig_plot::{Envelope, Histogram, Scatter, plot_envelope, plot_histograms, plot_scatter};
    let flown: Vec<&CaseResult> = cases.iter().filter(|c| c.outcome != case::Outcome::Infeasible).collect();
    let mut files = Vec::new();
    if flown.is_empty() {
        return Ok(files);
    }
    let name = &campaign.scenario.name;
    let limits = criterion_limits(&campaign.criteria);
    let histograms: Vec<Histogram> = summary
        .failures_by_criterion
        .iter()
        .enumerate()
        .map(|(k, (criterion, failures))| {
            let limit = limits.iter().find(|(c, _)| c == criterion).and_then(|(_, l)| *l);
            // Departed flights reach absurd figures; they are shown in the last bin, not as the axis.
            let cap = limit.map_or(f64::INFINITY, |l| 3.0 * l.abs().max(1e-9));
            let values: Vec<f64> = flown.iter().filter_map(|c| c.judgements[k].value).map(|v| v.min(cap)).collect();
            let missing = flown.len() - values.len();
            let never = if missing > 0 { format!(", {missing} never") } else { String::new() };
            Histogram {
                caption: format!("{criterion}: {failures} of {} failed{never}", flown.len()),
                unit: criterion_unit(criterion).into(),
                values,
                limit,
            }
        })
        .collect();
    let title = format!("{name}: {} cases, seed {}", summary.runs, summary.seed);
    files.extend(plot_histograms(&histograms, out, "histograms", &format!("{title}: criteria"))?);

    // The criterion that failed most, and the parameters whose rank moves its figure most.
    if let Some((k, (criterion, _))) =
        summary.failures_by_criterion.iter().enumerate().max_by_key(|(k, (_, n))| (*n, usize::MAX - k))
    {
        let figure: Vec<f64> = flown.iter().map(|c| c.judgements[k].value.unwrap_or(f64::INFINITY)).collect();
        let mut influence: Vec<(usize, f64)> = (0..campaign.parameters.len())
            .map(|p| {
                let x: Vec<f64> = flown.iter().map(|c| c.values[p]).collect();
                (p, spearman_or_zero(&x, &figure))
            })
            .collect();
        influence.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
        // Departed flights reach absurd figures: the axis stops at 3x the limit, and a case beyond it (or that never
        // settled) is drawn at that edge.
        let largest = figure.iter().copied().filter(|v| v.is_finite()).fold(0.0_f64, f64::max);
        let limit = limits.iter().find(|(c, _)| c == criterion).and_then(|(_, l)| *l);
        let shown = limit.map_or(largest, |l| largest.min(3.0 * l.abs()));
        let scatters: Vec<Scatter> = influence
            .iter()
            .take(SCATTER_PARAMETERS)
            .map(|(p, rho)| {
                let point = |c: &&&CaseResult| (c.values[*p], c.judgements[k].value.unwrap_or(shown).min(shown));
                let split = |passed: bool| {
                    flown.iter().filter(|c| c.judgements[k].passed == passed).map(|c| point(&c)).collect()
                };
                Scatter {
                    caption: format!("{} (Spearman rho {rho:+.2})", campaign.parameters[*p]),
                    x_desc: campaign.parameters[*p].clone(),
                    y_desc: format!("{} (cap {shown:.3})", criterion_unit(criterion)),
                    passed: split(true),
                    failed: split(false),
                }
            })
            .collect();
        files.extend(plot_scatter(&scatters, out, "scatter", &format!("{title}: what drives {criterion}"))?);
    }

    let setpoints =
        [campaign.scenario.setpoint.phi_deg, campaign.scenario.setpoint.theta_deg, campaign.scenario.setpoint.psi_deg];
    let envelopes: Vec<Envelope> = ["φ roll", "θ pitch", "ψ yaw"]
        .iter()
        .enumerate()
        .map(|(a, caption)| {
            let passed: Vec<&&CaseResult> = flown.iter().filter(|c| c.outcome == case::Outcome::Pass).collect();
            let ticks = flown.iter().map(|c| c.envelope.len()).max().unwrap_or(0);
            let band = (0..ticks)
                .filter_map(|k| {
                    let at: Vec<&[f32; 4]> = passed.iter().filter_map(|c| c.envelope.get(k)).collect();
                    let t = *at.first()?.first()? as f64;
                    let (lo, hi) = at.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
                        (l.min(r[a + 1] as f64), h.max(r[a + 1] as f64))
                    });
                    Some((t, lo, hi))
                })
                .collect();
            // A departed flight is drawn up to its departure: past it the model has no data to show.
            let failed = flown
                .iter()
                .filter(|c| c.outcome == case::Outcome::Fail)
                .take(ENVELOPE_FAILED_DRAWN)
                .map(|c| {
                    let until = c.figures.as_ref().and_then(|f| f.departed_at_s).unwrap_or(f64::INFINITY);
                    c.envelope
                        .iter()
                        .filter(|r| (r[0] as f64) <= until)
                        .map(|r| (r[0] as f64, r[a + 1] as f64))
                        .collect()
                })
                .collect();
            Envelope { caption: caption.to_string(), band, failed, setpoint: setpoints[a] }
        })
        .collect();
    let failed = flown.iter().filter(|c| c.outcome == case::Outcome::Fail).count();
    files.extend(plot_envelope(
        &envelopes,
        out,
        "envelope",
        &format!(
            "{title}: attitude, {} passed (band), {} of {failed} failed (drawn to their departure, if any)",
            summary.passed,
            failed.min(ENVELOPE_FAILED_DRAWN)
        ),
    )?);
    Ok(files)
}

fn spearman_or_zero(x: &[f64], y: &[f64]) -> f64 {
    let r = report::spearman(x, y);
    if r.is_finite() { r } else { 0.0 }
}

/// Each flight criterion's limit as a number in the unit of its figure.
fn criterion_limits(c: &Criteria) -> Vec<(String, Option<f64>)> {
    vec![
        ("settled".into(), c.settled.map(|s| s.within_s)),
        ("alpha_max_deg".into(), c.alpha_max_deg),
        ("overshoot_max_deg".into(), c.overshoot_max_deg),
        ("final_error_max_deg".into(), c.final_error_max_deg),
        ("body_rate_max_dps".into(), c.body_rate_max_dps.map(|b| b.max)),
        ("rate_limit_fraction_max".into(), c.rate_limit_fraction_max),
        ("position_limit_fraction_max".into(), c.position_limit_fraction_max),
        ("no_sustained_oscillation".into(), Some(1.0)),
    ]
}
