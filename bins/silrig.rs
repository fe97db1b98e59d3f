//! `silrig`: the command-line front end. Parses arguments and calls the library; no logic of its own.

use anyhow::Context;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use silrig::campaign::{SweepAction, SweepCommand};
use silrig::derivative_csv;
use silrig::plant::{F16Model, trim::trim_level_flight};
use silrig::rig::load_scenario;
use silrig::units::m_to_ft;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "silrig",
    version,
    about = "Software-in-the-loop rig for flight control: your plant and your controller (Python, C, Rust, FMUs, \
             JSBSim) as real-time processes over shared memory, with faults, recordings and verdicts; the Stevens & \
             Lewis F-16 and an adaptive sliding-mode controller are its reference pair",
    after_help = "Exit status, every command: 0 yes; 1 done, and the answer is no (a failed run, a failing verdict, a \
                  divergence); 2 not done as asked (bad input or flag, a file that cannot be used; nothing started); \
                  3 (silrig check only) inconclusive: the machine, not the controller; 130 and 143 stopped by Ctrl-C \
                  or SIGTERM, keeping what was done. Each command's: docs/src/reference/exit-status.md"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Trim for steady wings-level flight and print throttle, elevator and alpha.
    Trim {
        /// True airspeed, m/s.
        #[arg(long)]
        airspeed_mps: f64,
        /// Altitude, ft.
        #[arg(long)]
        altitude_ft: f64,
        /// CG position, fraction of the mean aerodynamic chord.
        #[arg(long, default_value_t = 0.35)]
        xcg: f64,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Plant tools.
    Plant {
        #[command(subcommand)]
        command: PlantCommand,
    },
    /// Run a scenario's closed loop in one process (deterministic) and write trace, summary and plots.
    Sim {
        /// Scenario file (TOML); without it, the embedded default scenario.
        config: Option<PathBuf>,
        /// Output folder (default: out/<scenario name>, or out/<scenario name>-sample-<I> with --sample).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Fly case I of the scenario's [dispersions] (as `silrig sweep` did) and judge it by its [criteria].
        #[arg(long, value_name = "I")]
        sample: Option<u64>,
        /// With --sample: the sweep's seed (default: the scenario's).
        #[arg(long, requires = "sample")]
        seed: Option<u64>,
        /// The plant or controller as an FMU, in place of the scenario's.
        #[command(flatten)]
        fmus: silrig::adapters::in_process::FmuFlags,
        /// With --sample: fly the case through the lockstep rig with your controller, as `silrig sweep
        /// --controller-cmd CMD` did (the rig's run, with its report, in the output folder).
        #[arg(long, value_name = "CMD", requires = "sample")]
        controller_cmd: Option<String>,
        /// With --sample: fly the case through the lockstep rig with your plant, as `silrig sweep --plant-cmd CMD`
        /// did (the rig's run, with its report, in the output folder).
        #[arg(long, value_name = "CMD", requires = "sample")]
        plant_cmd: Option<String>,
    },
    /// Monte Carlo: fly N dispersed cases of a scenario ([dispersions]) in parallel, judge each by its [criteria],
    /// and write cases.csv, sweep.json and the pass rate with the worst cases. Exit status 0 whatever the pass rate
    /// (gate on it with a sweep case in silrig check); 2: a bad scenario, dispersion or plan; 130, 143: stopped,
    /// the cases flown kept.
    Sweep(silrig::campaign::SweepCommand),
    /// Run several scenarios and print their summaries side by side, with an overlay plot.
    Compare {
        /// Scenario files (TOML).
        #[arg(required = true, num_args = 1..)]
        configs: Vec<PathBuf>,
        /// Output folder (default: out/compare).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run the three-process rig (plant, controller, logger over iceoryx2) and report control quality and timing.
    /// Exit status 0: every process flew and logged the whole scenario; 1: a process failed, the plant was killed
    /// for good, the state left the model's envelope or a file could not be written; 2: a bad scenario, flag or
    /// fault plan, or the output folder or run id is taken; 130, 143: stopped by Ctrl-C or SIGTERM.
    Run(silrig::launch::launcher::LaunchOptions),
    /// Watch a running rig of this machine: each process's tick, counters and p99s so far, refreshed every second
    /// until the run ends. Read-only: it changes nothing the rig does.
    Top {
        /// Run id of the rig (as `silrig run` printed it).
        run_id: silrig::ipc::RunId,
        /// Stop after this many refreshes.
        #[arg(long)]
        count: Option<u64>,
    },
    /// Fly a suite of cases with one controller and give a verdict a CI pipeline can gate on: a table,
    /// check.json and check.junit.xml. Exit status 0: every case passed; 1: a case failed; 2: nothing could be
    /// judged (a malformed suite, a controller command that cannot run); 3: inconclusive (nothing failed, but the
    /// machine disturbed a timing figure in every flight of a case: retry on a quieter machine); 130:
    /// interrupted by Ctrl-C or SIGTERM (the cases flown are in check.json).
    Check(silrig::check::CheckOptions),
    /// Fly a controller against a recorded flight: the recorded plant samples, tick by tick in lockstep, to our
    /// controller or yours (--controller-cmd), and compare its commands with the recorded ones. Exit status 0: every
    /// compared value within --tolerance (default: bit-identical); 1: a divergence (the first is printed, with a
    /// table of the largest difference per field); 2: the recording or the controller could not be used.
    Replay(silrig::replay::ReplayOptions),
    /// Print the wire contract a peer of the rig must match (every rule it must keep), or write it as a C header or
    /// a Python ctypes module; --c-dir writes every header a C peer includes.
    Contract {
        /// Write the C header (C11 or C++11) to this file.
        #[arg(long)]
        c_header: Option<PathBuf>,
        /// Write every header a C peer includes into this folder (created if missing): silrig_contract.h (the
        /// wire types) and silrig_client.h (libsilrig_client.so's functions, which include the former).
        #[arg(long)]
        c_dir: Option<PathBuf>,
        /// Write the Python ctypes module to this file.
        #[arg(long)]
        python: Option<PathBuf>,
    },
    /// Write the built-in plant a scenario flies (the F-16 with its actuators, trim and parameters, or the
    /// quadrotor of `[plant] model = "quad"`) as an FMI 2.0 co-simulation FMU, for `--plant-fmu` or any FMI
    /// importer; the parameters' start values come from the scenario.
    ExportFmu {
        /// Scenario file (TOML); without it, the book's F-16 at the model's default initial condition.
        config: Option<PathBuf>,
        /// The FMU to write (`f16.fmu`, `quad.fmu`).
        #[arg(long)]
        out: PathBuf,
    },
    /// Start a controller or a plant of your own: write the example as a working starting point into DIR, with a
    /// scenario, a check suite and a README saying how to build, fly and check it.
    New {
        /// What to start: a controller (flown against the built-in F-16) or a plant (flown by the example PID).
        kind: silrig::new_project::Kind,
        /// Its language.
        #[arg(long)]
        lang: silrig::new_project::Lang,
        /// The folder to write (created; it must be empty or absent).
        dir: PathBuf,
        /// With --lang rust: the checkout whose crates the project depends on by path (default: the one this binary
        /// was built from).
        #[arg(long)]
        silrig_path: Option<PathBuf>,
    },
    /// Micro-benchmarks of the model (median of batches; run on an idle machine); `bench ipc`: the transport's
    /// ping-pong ceiling and the lockstep rig against it.
    Bench {
        #[command(subcommand)]
        what: Option<BenchCommand>,
    },
    /// The chaos soak: a realtime run (default 10 minutes) whose processes are killed, stopped, delayed and
    /// restarted at times drawn from a seed; prints its figures and writes soak.json; exit 1 unless it passed.
    Soak(silrig::soak::SoakArgs),
    /// Measure the OS timer floor: a bare absolute-deadline loop, wake-up lateness as cyclictest reports it.
    #[command(name = silrig::launch::floor::timer_baseline::SUBCOMMAND)]
    TimerBaseline(silrig::launch::floor::timer_baseline::BaselineArgs),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// The iceoryx2 ping-pong ceiling between two processes on this machine, and lockstep rig runs as a ratio to it.
    #[command(name = silrig::bench::ipc::SUBCOMMAND)]
    Ipc(silrig::bench::ipc::IpcBenchArgs),
    /// One plant tick through an FMU (set inputs, doStep, get outputs) against the built-in F-16's tick.
    #[command(name = silrig::bench::fmu::SUBCOMMAND)]
    Fmu(silrig::bench::fmu::FmuBenchArgs),
}

#[derive(Subcommand)]
enum PlantCommand {
    /// Read CSV rows of states and controls on stdin, write the 13 state derivatives as CSV on stdout.
    Derivative,
}

fn main() -> ExitCode {
    silrig::rig::owner_only_files();
    let matches = silrig::rig::negative_numbers_as_values(Cli::command()).get_matches();
    match run(Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Trim { airspeed_mps, altitude_ft, xcg, json } => trim(airspeed_mps, altitude_ft, xcg, json),
        Command::Plant { command: PlantCommand::Derivative } => plant_derivative(),
        Command::Sim { config, out, sample: Some(index), seed, fmus, controller_cmd, plant_cmd } => {
            let commands = silrig::campaign::RigCommands { controller_cmd, plant_cmd, cold: false };
            sim_sample(config.as_deref(), out, index, seed, &fmus, &commands)
        }
        Command::Sim { config, out, fmus, .. } => sim(config.as_deref(), out, &fmus),
        Command::Sweep(SweepCommand { action: None, local }) => sweep(&local),
        Command::Sweep(SweepCommand { action: Some(SweepAction::Plan(opts)), .. }) => plan_sweep(&opts),
        Command::Sweep(SweepCommand { action: Some(SweepAction::Run(opts)), .. }) => fly_shard(&opts),
        Command::Sweep(SweepCommand { action: Some(SweepAction::Merge { dir }), .. }) => merge_shards(&dir),
        Command::Sweep(SweepCommand { action: Some(SweepAction::Slurm(opts)), .. }) => write_slurm_script(&opts),
        Command::Compare { configs, out } => compare(&configs, out),
        Command::Run(opts) => run_rig(&opts),
        Command::Top { run_id, count } => top(&run_id, count),
        Command::Check(opts) => check(&opts),
        Command::Replay(opts) => replay(&opts),
        Command::Contract { c_header, c_dir, python } => contract(c_header, c_dir, python),
        Command::ExportFmu { config, out } => export_fmu(config.as_deref(), &out),
        Command::New { kind, lang, dir, silrig_path } => {
            let written = silrig::new_project::write(kind, lang, &dir, silrig_path.as_deref())?;
            print!("{}", silrig::new_project::summary(kind, lang, &dir, &written));
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench { what: None } => bench(),
        Command::Bench { what: Some(BenchCommand::Ipc(args)) } => bench_ipc(&args),
        Command::Bench { what: Some(BenchCommand::Fmu(args)) } => {
            print!("{}", silrig::bench::fmu::run(&args)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::TimerBaseline(args) => timer_baseline(&args),
        Command::Soak(args) => soak(&args),
    }
}

fn trim(airspeed_mps: f64, altitude_ft: f64, xcg: f64, json: bool) -> anyhow::Result<ExitCode> {
    anyhow::ensure!((0.0..=1.0).contains(&xcg), "--xcg must be a fraction of the chord in 0..1, got {xcg}");
    let trim = trim_level_flight(&F16Model::new(xcg), m_to_ft(airspeed_mps), altitude_ft)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&trim)?);
    } else {
        print!("{}", trim.to_text());
    }
    Ok(ExitCode::SUCCESS)
}

fn plant_derivative() -> anyhow::Result<ExitCode> {
    let rows = derivative_csv::run(std::io::stdin().lock(), std::io::stdout().lock()).context("plant derivative")?;
    eprintln!("{rows} {}", if rows == 1 { "row" } else { "rows" });
    Ok(ExitCode::SUCCESS)
}

fn sim(
    config: Option<&Path>,
    out: Option<PathBuf>,
    fmus: &silrig::adapters::in_process::FmuFlags,
) -> anyhow::Result<ExitCode> {
    let mut scenario = load_scenario(config, None)?;
    fmus.apply(&mut scenario)?;
    let out = out.unwrap_or_else(|| Path::new("out").join(&scenario.name));
    let run = silrig::outputs::simulate(&scenario, &out)?;
    print!("{}", run.summary.to_text());
    print_written(run.files);
    for refused in &run.refusals {
        eprintln!("warning: {refused}");
    }
    if let Some(why) = run.ended_early {
        eprintln!("error: {why}; the files above hold the flight up to there");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

fn sim_sample(
    config: Option<&Path>,
    out: Option<PathBuf>,
    index: u64,
    seed: Option<u64>,
    fmus: &silrig::adapters::in_process::FmuFlags,
    commands: &silrig::campaign::RigCommands,
) -> anyhow::Result<ExitCode> {
    let path = config.ok_or_else(|| anyhow::anyhow!("--sample needs the sweep's scenario file"))?;
    let campaign = silrig::campaign::Campaign::load(path, fmus, commands)?;
    let seed = seed.unwrap_or(campaign.scenario.seed);
    let out = out.unwrap_or_else(|| Path::new("out").join(format!("{}-sample-{index}", campaign.scenario.name)));
    let (text, files) = silrig::campaign::fly_one(&campaign, seed, index, &out)?;
    print!("{text}");
    print_written(files);
    Ok(ExitCode::SUCCESS)
}

fn sweep(opts: &silrig::campaign::SweepOptions) -> anyhow::Result<ExitCode> {
    let run = silrig::campaign::sweep(opts)?;
    print!("{}", run.summary.to_text());
    let rate = run.summary.runs as f64 / run.fly_s.max(1e-9);
    // A sweep through the rig flies a few cases a second: a decimal tells --jobs 1 from 2.
    let decimals = if rate < 100.0 { 1 } else { 0 };
    println!(
        "flew {} cases in {:.2} s on {} thread(s): {rate:.decimals$} cases/s",
        run.summary.runs, run.fly_s, run.jobs
    );
    print_written(run.files);
    if run.summary.interrupted.is_some() {
        // As a shell reports a command ended by the signal (SIGINT is 2), though what was flown is written.
        let signal = silrig::rig::signals::termination_signal().unwrap_or(2);
        return Ok(ExitCode::from(silrig::rig::signals::exit_status_for(signal)));
    }
    Ok(ExitCode::SUCCESS)
}

fn plan_sweep(opts: &silrig::campaign::shard::PlanOptions) -> anyhow::Result<ExitCode> {
    let m = silrig::campaign::shard::plan(opts)?;
    println!(
        "planned {} cases of {} in {} shards (seed {}) in {}",
        m.runs,
        m.config,
        m.shards,
        m.seed,
        opts.out.display()
    );
    println!("fly each shard with `silrig sweep run {} --index K` (K = 0..{})", opts.out.display(), m.shards - 1);
    Ok(ExitCode::SUCCESS)
}

fn fly_shard(opts: &silrig::campaign::shard::RunOptions) -> anyhow::Result<ExitCode> {
    let (path, result) = silrig::campaign::shard::run(opts)?;
    println!(
        "shard {}: cases {}..{} flown; wrote {}",
        result.shard,
        result.cases_range.0,
        result.cases_range.1,
        path.display()
    );
    Ok(ExitCode::SUCCESS)
}

fn merge_shards(dir: &Path) -> anyhow::Result<ExitCode> {
    let run = silrig::campaign::shard::merge(dir)?;
    print!("{}", run.summary.to_text());
    print_written(run.files);
    Ok(ExitCode::SUCCESS)
}

fn write_slurm_script(opts: &silrig::campaign::shard::SlurmOptions) -> anyhow::Result<ExitCode> {
    let (path, _) = silrig::campaign::shard::slurm_script(opts)?;
    println!(
        "wrote {}; submit it with `sbatch {}`, then merge (the script's header says how)",
        path.display(),
        path.display()
    );
    Ok(ExitCode::SUCCESS)
}

fn compare(configs: &[PathBuf], out: Option<PathBuf>) -> anyhow::Result<ExitCode> {
    let out = out.unwrap_or_else(|| Path::new("out").join("compare"));
    let scenarios = configs.iter().map(|p| load_scenario(Some(p), None)).collect::<anyhow::Result<Vec<_>>>()?;
    let comparison = silrig::outputs::compare(&scenarios, &out)?;
    print!("{}", silrig::outputs::compare_table(&comparison.summaries));
    print_written(comparison.overlay);
    println!("runs written under {}", out.display());
    for (name, exit) in &comparison.left_envelope {
        eprintln!("error: {name}: {exit}; compared as far as it flew");
    }
    if !comparison.left_envelope.is_empty() {
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

fn run_rig(opts: &silrig::launch::launcher::LaunchOptions) -> anyhow::Result<ExitCode> {
    let report = silrig::launch::launcher::run(opts)?;
    print!("{}", report.to_text());
    // The page is for reading the run later: failing to write it (a full disk) costs the run nothing else.
    match silrig::html::run::write(&report, &silrig::html::run::this_command()) {
        Ok(page) => println!("page: {}", page.display()),
        Err(e) => eprintln!("silrig run: warning: no report.html: {e:#}"),
    }
    if !report.failures.is_empty() {
        return Ok(ExitCode::FAILURE);
    }
    if let Some(stopped) = &report.stopped_by {
        return Ok(ExitCode::from(stopped.exit_status));
    }
    Ok(ExitCode::SUCCESS)
}

fn top(run_id: &silrig::ipc::RunId, count: Option<u64>) -> anyhow::Result<ExitCode> {
    silrig::rig::signals::install_termination_flag();
    silrig::rig::status::top(run_id, count)?;
    Ok(ExitCode::SUCCESS)
}

fn check(opts: &silrig::check::CheckOptions) -> anyhow::Result<ExitCode> {
    if let Some(n) = opts.repeat {
        let (repeated, file) = silrig::check::repeat::run(opts, n)?;
        print!("{}", repeated.to_text());
        println!("wrote {}", file.display());
        return Ok(ExitCode::from(silrig::check::exit_status(repeated.outcome())));
    }
    let verdict = silrig::check::run(opts)?;
    print!("{}", verdict.to_text());
    if verdict.interrupted {
        return Ok(ExitCode::from(130));
    }
    Ok(ExitCode::from(silrig::check::exit_status(verdict.outcome())))
}

fn replay(opts: &silrig::replay::ReplayOptions) -> anyhow::Result<ExitCode> {
    let outcome = silrig::replay::replay(opts)?;
    print!("{}", outcome.to_text());
    if !outcome.passed() {
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

fn contract(c_header: Option<PathBuf>, c_dir: Option<PathBuf>, python: Option<PathBuf>) -> anyhow::Result<ExitCode> {
    let mut files: Vec<(PathBuf, String)> = Vec::new();
    files.extend(c_header.map(|path| (path, silrig::contract::c_header())));
    files.extend(python.map(|path| (path, silrig::contract::python_module())));
    if let Some(dir) = c_dir {
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("--c-dir: cannot create the folder {}", dir.display()))?;
        files.extend(silrig::contract::c_headers().into_iter().map(|(name, text)| (dir.join(name), text)));
    }
    if files.is_empty() {
        print!("{}", silrig::contract::text());
    }
    for (path, text) in files {
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn export_fmu(config: Option<&Path>, out: &Path) -> anyhow::Result<ExitCode> {
    let scenario = config.map(|path| load_scenario(Some(path), None)).transpose()?;
    let library = silrig::export_fmu::library_beside_executable()?;
    let exported = silrig::export_fmu::export_fmu(out, scenario.as_ref(), &library)?;
    for note in &exported.notes {
        eprintln!("note: {note}");
    }
    println!("wrote {} (FMI 2.0 co-simulation, GUID {})", out.display(), exported.guid);
    Ok(ExitCode::SUCCESS)
}

fn bench() -> anyhow::Result<ExitCode> {
    for figure in silrig::bench::plant_figures() {
        println!("{figure}");
    }
    let closed_loop = silrig::bench::closed_loop_figure(20);
    println!("{closed_loop}");
    println!(
        "closed loop: {:.0} steps/s median ({:.0}x real time at 100 Hz)",
        1e9 / closed_loop.median_ns,
        1e9 / closed_loop.median_ns / 100.0
    );
    Ok(ExitCode::SUCCESS)
}

fn bench_ipc(args: &silrig::bench::ipc::IpcBenchArgs) -> anyhow::Result<ExitCode> {
    print!("{}", silrig::bench::ipc::run(args)?);
    Ok(ExitCode::SUCCESS)
}

fn soak(args: &silrig::soak::SoakArgs) -> anyhow::Result<ExitCode> {
    if args.print_schedule {
        for flag in silrig::soak::schedule::flags(args.seed, args.duration_s, args.bridge) {
            println!("--fault {flag}");
        }
        return Ok(ExitCode::SUCCESS);
    }
    let report = silrig::soak::run(args, &std::env::current_exe()?)?;
    print!("{}", silrig::soak::text::to_text(&report));
    Ok(if report.problems.is_empty() { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

fn timer_baseline(args: &silrig::launch::floor::timer_baseline::BaselineArgs) -> anyhow::Result<ExitCode> {
    print!("{}", silrig::launch::floor::timer_baseline::run(args)?);
    Ok(ExitCode::SUCCESS)
}

fn print_written(files: impl IntoIterator<Item = PathBuf>) {
    for f in files {
        println!("wrote {}", f.display());
    }
}
