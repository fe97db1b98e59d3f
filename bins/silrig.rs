//! `silrig`: the command-line front end. Parses arguments and calls the library; no logic of its own.

use anyhow::Context;
use clap::{Parser, Subcommand};
use silrig::plant::{F16Model, derivative_csv, trim::trim_level_flight};
use silrig::scenario::Scenario;
use silrig::units::m_to_ft;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "silrig", version, about = "Software-in-the-loop rig for the Stevens & Lewis F-16")]
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
        /// Output folder (default: out/<scenario name>).
        #[arg(long)]
        out: Option<PathBuf>,
    },
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
    Run {
        /// Scenario file (TOML); without it, the embedded default scenario.
        config: Option<PathBuf>,
        /// realtime (the scenario's rate on the wall clock) or lockstep (as fast as possible, deterministic).
        #[arg(long, value_enum, default_value = "realtime")]
        mode: silrig::rig::RigMode,
        /// Override the scenario's duration, s.
        #[arg(long)]
        duration_s: Option<f64>,
        /// Output folder (default: out/run-<run id>); must not hold a run already.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run id (default: a fresh one).
        #[arg(long)]
        run_id: Option<silrig::ipc::RunId>,
        /// Do not run the OS-floor timer loop beside a realtime rig.
        #[arg(long)]
        no_baseline: bool,
        /// Same-tick mode: how long the plant waits for the command of the tick it just published, ms.
        #[arg(long, default_value_t = 2.0)]
        command_budget_ms: f64,
        /// Realtime: how long the plant polls for the command before it blocks, µs (0: block at once).
        #[arg(long, default_value_t = 400.0)]
        command_spin_us: f64,
        /// A fault to inject, added to the scenario's [[faults]]: TARGET:ACTION@TIME[,KEY=VALUE...], e.g.
        /// `controller:kill@3s,restart_after=0.5s`, `logger:stop@2s,for=500ms`, `plant:delay@2s,delay=15ms`.
        /// Repeatable.
        #[arg(long = "fault", value_parser = silrig::fault::parse_fault_flag)]
        faults: Vec<silrig::fault::Fault>,
        /// What to do when a process dies without a planned fault: never (the run fails) or on-failure.
        #[arg(long, default_value = "never", value_parser = ["never", "on-failure"])]
        restart: String,
        /// on-failure: restarts allowed per process.
        #[arg(long, default_value_t = 3)]
        max_restarts: u32,
        /// on-failure: pause before the first restart, ms (doubling each time).
        #[arg(long, default_value_t = 200.0)]
        restart_backoff_ms: f64,
    },
    /// Micro-benchmarks of the model (median of batches; run on an idle machine).
    Bench,
    /// Measure the OS timer floor: a bare absolute-deadline loop, wake-up lateness as cyclictest reports it.
    TimerBaseline {
        /// How long to run, s.
        #[arg(long, default_value_t = 10.0)]
        duration_s: f64,
        /// Period, ms.
        #[arg(long, default_value_t = 10.0)]
        period_ms: f64,
        /// SCHED_FIFO priority to ask for (1..=99); 0 stays with SCHED_OTHER.
        #[arg(long, default_value_t = 80)]
        fifo_priority: i32,
        /// Wait on an absolute timerfd in an iceoryx2 WaitSet instead of clock_nanosleep.
        #[arg(long)]
        timerfd: bool,
        /// Also write the HdrHistogram percentile distribution (.hgrm, µs) to this file.
        #[arg(long)]
        hgrm: Option<std::path::PathBuf>,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum PlantCommand {
    /// Read CSV rows of states and controls on stdin, write the 13 state derivatives as CSV on stdout.
    Derivative,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Trim { airspeed_mps, altitude_ft, xcg, json } => {
            anyhow::ensure!((0.0..=1.0).contains(&xcg), "--xcg must be a fraction of the chord in 0..1, got {xcg}");
            let trim = trim_level_flight(&F16Model::new(xcg), m_to_ft(airspeed_mps), altitude_ft)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&trim)?);
            } else {
                print!("{}", trim.to_text());
            }
        }
        Command::Plant { command: PlantCommand::Derivative } => {
            let rows =
                derivative_csv::run(std::io::stdin().lock(), std::io::stdout().lock()).context("plant derivative")?;
            eprintln!("{rows} rows");
        }
        Command::Sim { config, out } => {
            let scenario = load_scenario(config.as_deref())?;
            let out = out.unwrap_or_else(|| Path::new("out").join(&scenario.name));
            let trace = silrig::sim::run(&scenario)?;
            let summary = silrig::summary::summarize(&trace, &scenario);
            let files = silrig::outputs::write_run(&out, &scenario, &trace, &summary)?;
            print!("{}", summary.to_text());
            for f in files {
                println!("wrote {}", f.display());
            }
        }
        Command::Compare { configs, out } => {
            let out = out.unwrap_or_else(|| Path::new("out").join("compare"));
            let mut summaries = Vec::new();
            let mut traces = Vec::new();
            for path in &configs {
                let scenario = load_scenario(Some(path))?;
                let trace = silrig::sim::run(&scenario)?;
                let summary = silrig::summary::summarize(&trace, &scenario);
                silrig::outputs::write_run(&out.join(&scenario.name), &scenario, &trace, &summary)?;
                summaries.push(summary);
                traces.push((scenario.name.clone(), trace));
            }
            print!("{}", silrig::outputs::compare_table(&summaries));
            for f in silrig::plot::plot_overlay(&traces, &out, "overlay")? {
                println!("wrote {}", f.display());
            }
            println!("runs written under {}", out.display());
        }
        Command::Run {
            config,
            mode,
            duration_s,
            out,
            run_id,
            no_baseline,
            command_budget_ms,
            command_spin_us,
            faults,
            restart,
            max_restarts,
            restart_backoff_ms,
        } => {
            let opts = silrig::rig::launcher::LaunchOptions {
                config,
                mode,
                duration_s,
                out,
                run_id,
                baseline: !no_baseline,
                command_budget_ms,
                command_spin_us,
                faults,
                restart: match restart.as_str() {
                    "on-failure" => silrig::rig::launcher::RestartPolicy::OnFailure {
                        max_restarts,
                        backoff_s: restart_backoff_ms / 1e3,
                    },
                    _ => silrig::rig::launcher::RestartPolicy::Never,
                },
            };
            let report = silrig::rig::launcher::run(&opts)?;
            print!("{}", report.to_text());
            if !report.failures.is_empty() {
                return Ok(ExitCode::FAILURE);
            }
        }
        Command::Bench => {
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
        }
        Command::TimerBaseline { duration_s, period_ms, fifo_priority, timerfd, hgrm, json } => {
            anyhow::ensure!(duration_s > 0.0, "--duration-s must be positive, got {duration_s}");
            anyhow::ensure!(period_ms > 0.0, "--period-ms must be positive, got {period_ms}");
            anyhow::ensure!((0..=99).contains(&fifo_priority), "--fifo-priority must be 0..=99, got {fifo_priority}");
            if fifo_priority > 0
                && let Some(warning) = silrig::clock::try_realtime(fifo_priority).warning
            {
                eprintln!("{warning}");
            }
            use silrig::timing::{TickSource, timer_baseline_with};
            let source = if timerfd { TickSource::TimerfdWaitSet } else { TickSource::Nanosleep };
            let report = timer_baseline_with(source, duration_s, (period_ms * 1e6).round() as u64)?;
            if let Some(path) = hgrm {
                std::fs::write(&path, &report.hgrm).with_context(|| format!("writing {}", path.display()))?;
            }
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.to_text());
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn load_scenario(path: Option<&Path>) -> anyhow::Result<Scenario> {
    Ok(match path {
        Some(p) => Scenario::load(p)?,
        None => Scenario::embedded_default(),
    })
}
