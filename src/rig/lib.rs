//! silrig-rig: the rig's three processes over iceoryx2, the plant (time master), the controller and the logger,
//! each a process body the thin binaries in `bins/` reach through `silrig-adapters` (which picks what flies), and
//! the sessions a plant or controller of the user's own links (through `libsilrig_client.so` or directly).
//!
//! - [`plant`]: the plant process's loop around any [`plant_model::PlantModel`] (clock, commands, watchdog,
//!   failsafe, checkpoints, report; its streams in `plant/ports.rs`, its commands and watchdog in
//!   `plant/commands.rs`); [`plant_model`]: the trait a plant model implements; [`plant_session`]: the plant's
//!   side of the contract for a model stepped outside the loop (announce, then outputs in, inputs out, tick by
//!   tick).
//! - [`controller`]: the [`controller::Controller`] trait and [`controller::serve`], which flies one in a
//!   [`session::ControllerSession`]: the controller side of the contract as one reusable session (open a run, wait
//!   for a sample, send a command, stamps, checks, in-loop faults; the plant's side as it sees it in
//!   `session/samples.rs`, its errors and the C ABI's status codes in `session/errors.rs`).
//! - [`logger`]: the logger process, and `logger_writer`: its rows to every sink, flushed in batches, continued
//!   after a restarted logger's last row; [`live_foxglove`]: its Foxglove WebSocket server (`silrig run --live
//!   foxglove`, feature `live`).
//! - [`loop_faults`]: faults a process applies to its own loop (delay, jitter, drop); [`events`]: the run's event
//!   log; [`signals`]: SIGTERM and SIGINT handling outside a WaitSet.
//! - [`report`]: each process's report (counters, timing, machine conditions); [`status`]: the live status
//!   snapshots `silrig run` and `silrig top` read; [`tick_beacon`]: the plant's newest tick, by which the
//!   launcher times process faults; [`checkpoint_slot`]: the plant's newest checkpoint in shared memory, what a
//!   restarted plant resumes from.
//! - [`warm`]: a process kept warm for a campaign, forking one flight after another.
//! - Here: the arguments and options every process takes ([`ProcessArgs`], [`ProcessOptions`]), the
//!   checkpoint writer, and how a process ends.
//!
//! All processes of one run load the same scenario and use the same run id, which selects the iceoryx2
//! namespace (see [`silrig_wire::ipc::rig_config`]), so rigs side by side never see each other.
//!
//! Layers: uses `silrig-model`, `silrig-flight`, `silrig-wire` and `silrig-recording` (the logger's files); the
//! adapters (the F-16, our law, FMUs, which of them a process flies) are `silrig-adapters`, and the launcher that
//! starts these processes is `silrig-launch`, both above.

pub mod checkpoint_slot;
pub mod controller;
pub mod events;
pub mod live_foxglove;
pub mod logger;
mod logger_writer;
pub mod loop_faults;
pub mod plant;
pub mod plant_model;
pub mod plant_session;
pub mod report;
pub mod session;
pub mod signals;
pub mod status;
pub mod tick_beacon;
pub mod tick_queue;
pub mod warm;

use silrig_flight::files::write_atomically;
use silrig_flight::scenario::Scenario;
use silrig_wire::ipc::RunId;
use std::path::{Path, PathBuf};

/// How the loop keeps time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RigMode {
    /// 100 Hz (the scenario's dt) on the wall clock: absolute-deadline ticks, commands within a budget.
    Realtime,
    /// As fast as possible: no sleeping, the plant waits for every command (and for the logger); deterministic.
    Lockstep,
}

impl RigMode {
    /// Name as on the command line.
    pub fn label(self) -> &'static str {
        match self {
            RigMode::Realtime => "realtime",
            RigMode::Lockstep => "lockstep",
        }
    }
}

/// Tuning of the rig processes' loops and watchdogs: the same flags on `silrig run`, which passes them on, and on each
/// process started by hand.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct ProcessOptions {
    /// Same-tick mode: how long the plant waits for the command of the tick it just published, ms.
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub command_budget_ms: f64,
    /// Realtime: after publishing, the plant polls for the command this long before it blocks, µs (0: block at
    /// once). A blocked wait costs a vCPU wake-up (about 70 µs on this kind of VM); polling costs at most this much
    /// CPU per tick.
    #[arg(long, default_value_t = 400.0, allow_negative_numbers = true)]
    pub command_spin_us: f64,
    /// Realtime: the controller's session looks for the plant's next sample from 50 µs before the plant's next
    /// deadline until this long after it, then blocks, µs (0: block at once). Waking for the deadline instead of
    /// for the sample's notification takes the vCPU wake-up off the sense-to-actuate path; costs at most 50 µs
    /// more than this of CPU per tick.
    #[arg(long, default_value_t = 300.0, allow_negative_numbers = true)]
    pub sample_poll_us: f64,
    /// Consumers flag their input stale after this many periods without a sample.
    #[arg(long, default_value_t = 5, allow_negative_numbers = true)]
    pub stale_after_periods: u32,
    /// Plant: how long it holds the last command after the controller goes silent before it commands the trim
    /// surfaces and flags failsafe, ms.
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true)]
    pub controller_hold_ms: f64,
    /// How long the plant waits for the controller and logger to connect, s.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub startup_timeout_s: f64,
}

/// `Err` naming the flag when `v` is outside `lo..=hi` (NaN included): every numeric flag has a documented range.
pub fn flag_in_range(flag: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), String> {
    if (lo..=hi).contains(&v) { Ok(()) } else { Err(format!("--{flag} must be within {lo}..{hi} {unit}, got {v}")) }
}

impl Default for ProcessOptions {
    /// The flags' defaults, as a process started without them has them.
    fn default() -> Self {
        use clap::{Args, FromArgMatches};
        let matches = Self::augment_args(clap::Command::new("defaults")).get_matches_from(["defaults"]);
        Self::from_arg_matches(&matches).expect("every flag has a default")
    }
}

impl ProcessOptions {
    /// Every flag within its documented range.
    pub fn validate(&self) -> Result<(), String> {
        flag_in_range("command-budget-ms", self.command_budget_ms, 0.01, 1000.0, "ms")?;
        flag_in_range("command-spin-us", self.command_spin_us, 0.0, 10_000.0, "us")?;
        flag_in_range("sample-poll-us", self.sample_poll_us, 0.0, 10_000.0, "us")?;
        flag_in_range("stale-after-periods", f64::from(self.stale_after_periods), 1.0, 1000.0, "periods")?;
        flag_in_range("controller-hold-ms", self.controller_hold_ms, 1.0, 60_000.0, "ms")?;
        flag_in_range("startup-timeout-s", self.startup_timeout_s, 0.1, 3600.0, "s")
    }

    /// The flags that give these options to a process.
    pub fn to_argv(&self) -> Vec<String> {
        vec![
            "--command-budget-ms".into(),
            self.command_budget_ms.to_string(),
            "--command-spin-us".into(),
            self.command_spin_us.to_string(),
            "--sample-poll-us".into(),
            self.sample_poll_us.to_string(),
            "--stale-after-periods".into(),
            self.stale_after_periods.to_string(),
            "--controller-hold-ms".into(),
            self.controller_hold_ms.to_string(),
            "--startup-timeout-s".into(),
            self.startup_timeout_s.to_string(),
        ]
    }
}

/// Arguments every rig process takes (the launcher passes the same ones to all three).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct ProcessArgs {
    /// Scenario file (TOML); without it, the embedded default scenario.
    pub config: Option<PathBuf>,
    /// Run id shared by the three processes of one run (1..=24 of a-z, 0-9, '-').
    #[arg(long)]
    pub run_id: RunId,
    /// Realtime (wall clock) or lockstep (as fast as possible, deterministic).
    #[arg(long, value_enum, default_value = "realtime")]
    pub mode: RigMode,
    /// Override the scenario's duration, s.
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Folder for this process's report (and, for the logger, trace.csv and timing.csv).
    #[arg(long, default_value = "out/rig")]
    pub out: PathBuf,
    /// Plant: continue from the state a previous plant of this run saved in `--out`; controller: start from the
    /// checkpoint a previous controller saved there (a restart).
    #[arg(long)]
    pub resume: bool,
    /// Loop and watchdog tuning.
    #[command(flatten)]
    pub options: ProcessOptions,
}

impl ProcessArgs {
    /// The scenario with the duration override applied, validated (and the tuning flags with it).
    pub fn scenario(&self) -> anyhow::Result<Scenario> {
        self.options.validate().map_err(|e| anyhow::anyhow!(e))?;
        load_scenario(self.config.as_deref(), self.duration_s)
    }

    /// The command line that gives these arguments to a rig process.
    pub fn to_argv(&self) -> Vec<String> {
        let mut argv: Vec<String> = self.config.iter().map(|c| c.display().to_string()).collect();
        argv.extend(["--run-id".into(), self.run_id.to_string(), "--mode".into(), self.mode.label().into()]);
        if let Some(d) = self.duration_s {
            argv.extend(["--duration-s".into(), d.to_string()]);
        }
        argv.extend(["--out".into(), self.out.display().to_string()]);
        if self.resume {
            argv.push("--resume".into());
        }
        argv.extend(self.options.to_argv());
        argv
    }
}

/// The environment variable that carries the scenario path to a controller started by `--controller-cmd`; every
/// flag `--some-flag` travels as `SILRIG_SOME_FLAG` ([`ProcessArgs::to_env`]).
pub const SCENARIO_ENV: &str = "SILRIG_SCENARIO";

fn flag_env_name(flag: &str) -> String {
    format!("SILRIG_{}", flag.trim_start_matches("--").replace('-', "_").to_uppercase())
}

impl ProcessArgs {
    /// These arguments as environment variables (what `silrig run --controller-cmd` gives the user's command):
    /// the scenario path as [`SCENARIO_ENV`], each flag `--x-y` as `SILRIG_X_Y`, a switch as `1`.
    pub fn to_env(&self) -> Vec<(String, String)> {
        let mut argv = self.to_argv().into_iter().peekable();
        let mut env = Vec::new();
        if let Some(config) = &self.config {
            argv.next();
            env.push((SCENARIO_ENV.to_string(), config.display().to_string()));
        }
        while let Some(flag) = argv.next() {
            let value = argv.next_if(|v| !v.starts_with("--")).unwrap_or_else(|| "1".into());
            env.push((flag_env_name(&flag), value));
        }
        env
    }

    /// Every variable [`Self::from_env`] reads, with what it means (for `silrig contract` and the book).
    pub fn env_variables() -> Vec<(String, String)> {
        use clap::Args;
        let command = Self::augment_args(clap::Command::new("silrig-client"));
        command
            .get_arguments()
            .map(|arg| {
                let name = arg.get_long().map_or_else(|| SCENARIO_ENV.to_string(), flag_env_name);
                let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
                (name, help)
            })
            .collect()
    }

    /// The arguments from `SILRIG_*` variables (see [`Self::to_env`]), parsed and checked like the command line;
    /// variables of other names are ignored. The error names the variable at fault where clap can.
    pub fn from_env(vars: impl IntoIterator<Item = (String, String)>) -> Result<Self, String> {
        use clap::{Args, FromArgMatches};
        let vars: std::collections::HashMap<String, String> = vars.into_iter().collect();
        let command = Self::augment_args(clap::Command::new("silrig-client").no_binary_name(true));
        let mut argv = Vec::new();
        for arg in command.get_arguments() {
            let Some(long) = arg.get_long() else {
                if let Some(path) = vars.get(SCENARIO_ENV) {
                    argv.push(path.clone());
                }
                continue;
            };
            let Some(value) = vars.get(&flag_env_name(long)) else { continue };
            if arg.get_action().takes_values() {
                argv.extend([format!("--{long}"), value.clone()]);
            } else if !matches!(value.as_str(), "" | "0" | "false") {
                argv.push(format!("--{long}"));
            }
        }
        let matches = command.try_get_matches_from(&argv).map_err(|e| {
            let problem = e.render().to_string();
            format!("the SILRIG_* variables are not a usable run (flag --x-y below is variable SILRIG_X_Y): {problem}")
        })?;
        Self::from_arg_matches(&matches).map_err(|e| e.to_string())
    }
}

/// Load a scenario (or the embedded default) and apply a duration override.
pub fn load_scenario(path: Option<&Path>, duration_s: Option<f64>) -> anyhow::Result<Scenario> {
    load_scenario_for(path, duration_s, false)
}

/// [`load_scenario`], where without a file a plant of the user's own (`own_plant`) flies the embedded any-plant
/// scenario (set points and timing only) instead of the F-16's.
pub fn load_scenario_for(path: Option<&Path>, duration_s: Option<f64>, own_plant: bool) -> anyhow::Result<Scenario> {
    let mut scenario = match path {
        Some(p) => Scenario::load(p)?,
        None if own_plant => Scenario::embedded_any_plant(),
        None => Scenario::embedded_default(),
    };
    if let Some(d) = duration_s {
        scenario.timing.duration_s = d;
        scenario.validate().map_err(|(key, problem)| anyhow::anyhow!("--duration-s: `{key}`: {problem}"))?;
    }
    Ok(scenario)
}

/// Writes checkpoints on a thread of its own, at normal scheduling priority, so the file I/O (about a millisecond
/// on this kind of machine) stays off the real-time loop, which only hands the text over. A checkpoint handed over
/// while the previous one is still being written replaces it; the newest always wins.
pub struct CheckpointWriter {
    latest: std::sync::Arc<(std::sync::Mutex<Option<String>>, std::sync::Condvar)>,
}

impl CheckpointWriter {
    /// A writer of `path`; its thread ends with the process.
    pub fn new(path: PathBuf) -> Self {
        let latest = std::sync::Arc::new((std::sync::Mutex::new(None::<String>), std::sync::Condvar::new()));
        let (shared, target) = (latest.clone(), path.clone());
        std::thread::Builder::new()
            .name("checkpoints".into())
            .stack_size(256 * 1024)
            .spawn(move || {
                silrig_wire::clock::leave_realtime_scheduling();
                let (slot, ready) = &*shared;
                // A full disk fails every write: say so when it starts and when it ends, not ten times a second.
                let mut failing = false;
                loop {
                    let text = {
                        let mut guard = slot.lock().unwrap_or_else(|e| e.into_inner());
                        while guard.is_none() {
                            guard = ready.wait(guard).unwrap_or_else(|e| e.into_inner());
                        }
                        guard.take().expect("checked")
                    };
                    match write_atomically(&target, &text) {
                        Err(e) if !failing => {
                            failing = true;
                            eprintln!("silrig: {e} (the checkpoint stays the last one written; retrying every save)");
                        }
                        Ok(()) if failing => {
                            failing = false;
                            eprintln!("silrig: {} written again", target.display());
                        }
                        _ => {}
                    }
                }
            })
            .expect("starting the checkpoint writer thread");
        Self { latest }
    }

    /// Hand a checkpoint over (never blocks on I/O).
    pub fn save(&self, text: String) {
        let (slot, ready) = &*self.latest;
        *slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(text);
        ready.notify_one();
    }
}

/// `cmd` with every option that takes a value accepting a negative number (`--duration-s -1`), in every
/// subcommand, so an out-of-range number reaches the range check that names the range instead of being taken for
/// an unknown flag.
pub fn negative_numbers_as_values(cmd: clap::Command) -> clap::Command {
    let options: Vec<String> = cmd
        .get_arguments()
        .filter(|a| a.get_long().is_some() && a.get_action().takes_values())
        .map(|a| a.get_id().to_string())
        .collect();
    let mut cmd = options.iter().fold(cmd, |c, id| c.mut_arg(id, |a| a.allow_negative_numbers(true)));
    let subcommands: Vec<String> = cmd.get_subcommands().map(|s| s.get_name().to_string()).collect();
    for name in subcommands {
        cmd = cmd.mut_subcommand(name, negative_numbers_as_values);
    }
    cmd
}

/// Every file and folder this process creates from now on is its owner's only (umask 077), whatever umask it was
/// started with: a run's trace, reports, checkpoints, recordings, status files and locks say how someone's
/// controller behaves and are nobody else's to read or change. Children (the rig's processes, a user's command)
/// inherit it. Called first thing by every silrig binary.
pub fn owner_only_files() {
    // SAFETY: umask(2) only sets the calling process's file mode creation mask.
    unsafe { libc::umask(0o077) };
}

/// End a rig process: its exit status ([`exit_status`]), and, for a process started by hand (not by `silrig
/// run`, which cleans up after its run), the run's iceoryx2 files once no process of the run is left, so a process
/// that fails at start-up leaves no `/dev/shm/silrig_<run>` folder or shared memory behind.
pub fn finish_process(
    process: &str,
    args: &ProcessArgs,
    result: anyhow::Result<report::ProcessReport>,
) -> std::process::ExitCode {
    let status = exit_status(process, result);
    if !started_by_launcher() {
        // Removes nothing while another process of the run is alive.
        let _ = silrig_wire::ipc::cleanup_run(&args.run_id);
    }
    status
}

/// Whether our parent is `silrig` (the launcher), read from /proc.
fn started_by_launcher() -> bool {
    // A warm process's flight: the sweep that asked for it cleans up its run.
    if warm::is_flight() {
        return true;
    }
    // SAFETY: getppid has no preconditions.
    let parent = unsafe { libc::getppid() };
    std::fs::read_to_string(format!("/proc/{parent}/comm")).is_ok_and(|c| c.trim() == "silrig")
}

/// The exit status of a rig process: 0 when it ended cleanly, 1 when it ended on an error it reported, 2 when it
/// could not run at all (bad arguments, scenario or peer); the reason goes to stderr.
pub fn exit_status(process: &str, result: anyhow::Result<report::ProcessReport>) -> std::process::ExitCode {
    match result {
        Ok(report) if report.ended.starts_with("error") => {
            eprintln!("silrig-{process}: {}", report.ended);
            std::process::ExitCode::FAILURE
        }
        Ok(_) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("silrig-{process}: error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Process {
        #[command(flatten)]
        args: ProcessArgs,
    }

    #[test]
    fn bad_environment_is_named() {
        let vars = [("SILRIG_RUN_ID", "r1"), ("SILRIG_STALE_AFTER_PERIODS", "many"), ("OTHER", "x")];
        let err = ProcessArgs::from_env(vars.map(|(k, v)| (k.to_string(), v.to_string()))).unwrap_err();
        assert!(err.contains("--stale-after-periods") && err.contains("many"), "{err}");
        let err = ProcessArgs::from_env(std::iter::empty()).unwrap_err();
        assert!(err.contains("--run-id"), "{err}");
    }

    #[test]
    fn process_arguments_survive_their_command_line() {
        let args = ProcessArgs {
            config: Some("some dir/scenario.toml".into()),
            run_id: RunId::new("r1-a").unwrap(),
            mode: RigMode::Lockstep,
            duration_s: Some(2.5),
            out: "out dir/x".into(),
            resume: true,
            options: ProcessOptions {
                command_budget_ms: 1.25,
                command_spin_us: 0.0,
                sample_poll_us: 120.0,
                stale_after_periods: 7,
                controller_hold_ms: 250.0,
                startup_timeout_s: 3.0,
            },
        };
        let argv = std::iter::once("silrig-plant".to_string()).chain(args.to_argv());
        assert_eq!(Process::parse_from(argv).args, args);
        assert_eq!(ProcessArgs::from_env(args.to_env()).unwrap(), args);
        let defaults = Process::parse_from(["silrig-plant", "--run-id", "r2"]).args;
        assert_eq!(ProcessArgs::from_env(defaults.to_env()).unwrap(), defaults);
        let argv = std::iter::once("silrig-plant".to_string()).chain(defaults.to_argv());
        assert_eq!(Process::parse_from(argv).args, defaults);
    }
}
