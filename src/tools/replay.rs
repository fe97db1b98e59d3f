//! `silrig replay`: fly a controller against a recorded flight. The recorded plant samples are sent again, tick by
//! tick, on a fresh run's plant stream, to a controller started as the rig starts one (ours, or a user's command
//! with the run's `SILRIG_*` variables), in lockstep: each sample waits for its answer. The replayed commands are
//! then compared with the recorded ones, field by field.
//!
//! Replay is open loop: the plant does not respond to the replayed commands, it shows the controller what it saw
//! in the recorded flight. So it answers "what would this controller have commanded then", which is what a
//! regression test of a controller change asks; a closed-loop rerun is `silrig run` of the recording's scenario.

use anyhow::Context;
use serde::Serialize;
use silrig_flight::role::Role;
use silrig_flight::signals::PlantSignals;
use silrig_launch::child::start_process;
use silrig_launch::launcher::fresh_run_id;
use silrig_launch::program::binary_dir;
use silrig_recording::reader::RecordedRun;
use silrig_rig::{ProcessArgs, ProcessOptions, RigMode};
use silrig_wire::ipc::{self, RunId};
use silrig_wire::topology::Stream;
use silrig_wire::wire::{self, CommandSample, PlantInfo, PlantSample};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// What `silrig replay` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct ReplayOptions {
    /// The run folder holding the recording (`recording.mcap`, written by the logger of `silrig run`).
    pub run_dir: PathBuf,
    /// Replay against your own controller: this command, started with the replay run's SILRIG_* variables as
    /// `silrig run --controller-cmd` starts it (default: silrig-controller with the recording's scenario).
    #[arg(long, value_name = "CMD")]
    pub controller_cmd: Option<String>,
    /// Largest difference between a recorded and a replayed value that still counts as the same (same unit as the
    /// field); 0: bit-identical.
    #[arg(long, default_value_t = 0.0)]
    pub tolerance: f64,
    /// Output folder (default: `<RUN_DIR>/replay`, or `replay-2`, ... if taken): the controller's report, events and
    /// output, and `replay.json`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// How long the controller may take to connect, and to answer one sample, s.
    #[arg(long, default_value_t = 10.0)]
    pub answer_timeout_s: f64,
}

/// A compared field: its largest difference, and where.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldDifference {
    /// Field name (`elevator_cmd_deg`, `throttle_cmd`, or a diagnostic's name).
    pub field: String,
    /// Largest |recorded - replayed| (infinite where one side is NaN and the other is not).
    pub max_abs_difference: f64,
    /// The tick of that difference.
    pub at_tick: u64,
    /// Ticks at which the two differ beyond the tolerance.
    pub ticks_differing: u64,
}

/// The first tick, in tick order, where a replayed value differs from the recorded one beyond the tolerance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Divergence {
    /// Plant tick.
    pub tick: u64,
    /// Its simulated time, s.
    pub t_s: f64,
    /// The field (the first in field order at that tick).
    pub field: String,
    /// The recorded value.
    pub recorded: f64,
    /// The replayed value.
    pub replayed: f64,
}

/// What a replay found.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayOutcome {
    /// The recording's folder.
    pub run_dir: PathBuf,
    /// The replay's own folder.
    pub out_dir: PathBuf,
    /// The replay's own run id (its iceoryx2 namespace, removed when it ends).
    pub run_id: String,
    /// Who answered: `silrig-controller` or the command.
    pub controller: String,
    /// Recorded plant samples sent.
    pub samples_sent: u64,
    /// Ticks with both a recorded and a replayed command.
    pub ticks_compared: u64,
    /// Recorded rows without a command (the controller was late, dead or stopped then): sent, not compared.
    pub ticks_without_recorded_command: u64,
    /// Compared ticks whose every field is bit-identical.
    pub ticks_bit_identical: u64,
    /// Controller lives (command epochs) in the recording: more than one means a restarted controller flew part
    /// of it, from other state than a controller flying from tick 0.
    pub recorded_controller_lives: u64,
    /// The tolerance applied.
    pub tolerance: f64,
    /// The first divergence beyond the tolerance.
    pub first_divergence: Option<Divergence>,
    /// Every compared field.
    pub fields: Vec<FieldDifference>,
}

impl ReplayOutcome {
    /// Every compared value within the tolerance.
    pub fn passed(&self) -> bool {
        self.first_divergence.is_none()
    }

    /// The outcome as `silrig replay` prints it.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut t = String::new();
        let _ = writeln!(
            t,
            "replayed {} recorded plant samples from {} to {}",
            self.samples_sent,
            self.run_dir.display(),
            self.controller
        );
        let _ = writeln!(
            t,
            "compared {} ticks: {} bit-identical; {} recorded rows had no command (not compared)",
            self.ticks_compared, self.ticks_bit_identical, self.ticks_without_recorded_command
        );
        if self.recorded_controller_lives > 1 {
            let _ = writeln!(
                t,
                "note: the recording holds commands of {} controller lives (restarts): from the first restart on, \
                 the recorded controller resumed from a checkpoint or started fresh, so differences there are expected",
                self.recorded_controller_lives
            );
        }
        match &self.first_divergence {
            None if self.tolerance == 0.0 => {
                let _ = writeln!(t, "every compared command is bit-identical to the recording");
            }
            None => {
                let _ = writeln!(t, "every compared value is within the tolerance {}", self.tolerance);
            }
            Some(d) => {
                let _ = writeln!(
                    t,
                    "first divergence: tick {} (t = {:.2} s), {}: recorded {:?}, replayed {:?}",
                    d.tick, d.t_s, d.field, d.recorded, d.replayed
                );
            }
        }
        let width = self.fields.iter().map(|f| f.field.len()).max().unwrap_or(5).max(5);
        let _ = writeln!(t, "{:<width$}  {:>12}  {:>8}  {:>10}", "field", "max |diff|", "at tick", "ticks over");
        for f in &self.fields {
            let _ = writeln!(
                t,
                "{:<width$}  {:>12}  {:>8}  {:>10}",
                f.field,
                format!("{:.3e}", f.max_abs_difference),
                f.at_tick,
                f.ticks_differing
            );
        }
        let verdict = if self.passed() { "PASSED" } else { "FAILED" };
        let _ =
            writeln!(t, "{verdict} (tolerance {}); details: {}", self.tolerance, self.out_dir.join(REPORT).display());
        t
    }
}

/// The replay's report file in its folder.
pub const REPORT: &str = "replay.json";

/// The first free `replay`, `replay-2`, ... folder in `run_dir`.
fn fresh_out_dir(run_dir: &Path) -> PathBuf {
    (1..)
        .map(|n: u32| run_dir.join(if n == 1 { "replay".to_string() } else { format!("replay-{n}") }))
        .find(|p| !p.exists())
        .expect("some folder name is free")
}

/// Compares replayed commands with recorded ones, field by field, in tick order.
struct Comparison {
    names: Vec<String>,
    inputs: usize,
    tolerance: f64,
    fields: Vec<FieldDifference>,
    first: Option<Divergence>,
    compared: u64,
    identical: u64,
}

impl Comparison {
    /// The fields compared: each input's command (named as its trace column), the diagnostics count, each
    /// diagnostic.
    fn new(plant: &PlantSignals, diagnostic_names: &[String], tolerance: f64) -> Self {
        let names: Vec<String> = (0..plant.inputs.len())
            .map(|k| plant.command_column(k))
            .chain(["diagnostics_len".to_string()])
            .chain(diagnostic_names.iter().cloned())
            .collect();
        let inputs = plant.inputs.len();
        let fields = names
            .iter()
            .map(|n| FieldDifference { field: n.clone(), max_abs_difference: 0.0, at_tick: 0, ticks_differing: 0 })
            .collect();
        Self { names, inputs, tolerance, fields, first: None, compared: 0, identical: 0 }
    }

    fn values(c: &CommandSample, inputs: usize, n_diagnostics: usize) -> Vec<f64> {
        // An input past the ones in use is compared as NaN, as a diagnostic is.
        let mut v: Vec<f64> = (0..inputs).map(|i| c.inputs().get(i).copied().unwrap_or(f64::NAN)).collect();
        v.push(f64::from(c.diagnostics_len));
        // A diagnostic past the ones in use is compared as NaN, so a changed count shows in each of them too.
        v.extend((0..n_diagnostics).map(|i| c.diagnostics().get(i).copied().unwrap_or(f64::NAN)));
        v
    }

    fn add(&mut self, sample: &PlantSample, recorded: &CommandSample, replayed: &CommandSample) {
        let tick = sample.header.tick;
        let n = self.names.len() - self.inputs - 1;
        let (r, p) = (Self::values(recorded, self.inputs, n), Self::values(replayed, self.inputs, n));
        self.compared += 1;
        let mut identical = true;
        for (i, (r, p)) in r.iter().zip(&p).enumerate() {
            let same_bits = r.to_bits() == p.to_bits() || (r.is_nan() && p.is_nan());
            identical &= same_bits;
            let diff = if r.is_nan() && p.is_nan() {
                0.0
            } else if r.is_nan() || p.is_nan() {
                f64::INFINITY
            } else {
                (r - p).abs()
            };
            let differs = if self.tolerance == 0.0 { !same_bits } else { !(diff <= self.tolerance) };
            let f = &mut self.fields[i];
            if diff > f.max_abs_difference {
                f.max_abs_difference = diff;
                f.at_tick = tick;
            }
            if differs {
                f.ticks_differing += 1;
                if self.first.is_none() {
                    self.first = Some(Divergence {
                        tick,
                        t_s: sample.t_sim_s,
                        field: self.names[i].clone(),
                        recorded: *r,
                        replayed: *p,
                    });
                }
            }
        }
        self.identical += u64::from(identical);
    }
}

/// The controller process of a replay, and the plant side of its run.
struct ReplayRig {
    run_id: RunId,
    child: silrig_launch::child::ChildProcess,
    publisher: ipc::StreamPublisher<PlantSample>,
    announcer: ipc::StreamPublisher<PlantInfo>,
    commands: ipc::StreamSubscriber<CommandSample>,
    command_stream: ipc::StreamService<CommandSample>,
    out_dir: PathBuf,
    // Dropped last: the ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

impl ReplayRig {
    /// Open a fresh run as its plant and start the controller on it; on failure nothing of the run is left.
    fn start(opts: &ReplayOptions, info: &PlantInfo, scenario_path: &Path, out_dir: &Path) -> anyhow::Result<Self> {
        let run_id = fresh_run_id();
        let started = Self::open(run_id.clone(), opts, info, scenario_path, out_dir);
        if started.is_err() {
            let _ = ipc::cleanup_run(&run_id);
        }
        started
    }

    fn open(
        run_id: RunId,
        opts: &ReplayOptions,
        info: &PlantInfo,
        scenario_path: &Path,
        out_dir: &Path,
    ) -> anyhow::Result<Self> {
        let args = ProcessArgs {
            config: Some(scenario_path.to_path_buf()),
            run_id: run_id.clone(),
            mode: RigMode::Lockstep,
            duration_s: None,
            out: out_dir.to_path_buf(),
            resume: false,
            options: ProcessOptions::default(),
        };
        let node = ipc::create_node(&run_id, Role::Plant.label())?;
        let plant_stream = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
        let command_stream = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
        let publisher = plant_stream.publisher().context("the plant stream")?;
        // The recorded plant's announcement, as its plant made it: the controller finds its signals there.
        let mut announcer =
            ipc::open_stream::<PlantInfo>(&node, Stream::PlantInfo)?.publisher().context("the plant-info stream")?;
        announcer.send(0, info)?;
        let commands = command_stream.subscriber(Stream::Command.queue_depth(Role::Plant))?;
        let log_path = out_dir.join(format!("{}.stderr.log", Role::Controller));
        let log = std::fs::File::create(&log_path).with_context(|| format!("creating {}", log_path.display()))?;
        let child = start_process(
            Role::Controller,
            opts.controller_cmd.as_deref(),
            &args,
            &[],
            &binary_dir()?,
            log.try_clone()?.into(),
            log.into(),
        )?;
        Ok(Self {
            run_id,
            child,
            publisher,
            announcer,
            commands,
            command_stream,
            out_dir: out_dir.to_path_buf(),
            _node: node,
        })
    }

    /// What the controller wrote to its log, for an error message.
    fn controller_said(&self) -> String {
        silrig_launch::supervision::stderr_tail(&self.out_dir, Role::Controller)
    }

    fn ensure_alive(&mut self, waiting_for: &str) -> anyhow::Result<()> {
        if let Some(status) = self.child.poll()? {
            anyhow::bail!(
                "the controller ended ({}) while the replay waited for {waiting_for}{}",
                silrig_launch::child::describe(status),
                self.controller_said()
            );
        }
        Ok(())
    }

    fn wait_connected(&mut self, timeout: Duration) -> anyhow::Result<()> {
        let deadline = std::time::Instant::now() + timeout;
        while self.command_stream.number_of_publishers() == 0 {
            self.announcer.deliver_history()?;
            self.ensure_alive("it to connect")?;
            anyhow::ensure!(
                std::time::Instant::now() < deadline,
                "the controller did not connect within {} s{}",
                timeout.as_secs_f64(),
                self.controller_said()
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(())
    }

    /// Send one recorded sample and wait for the command answering it.
    fn answer(&mut self, sample: &PlantSample, timeout: Duration) -> anyhow::Result<CommandSample> {
        let tick = sample.header.tick;
        self.announcer.deliver_history()?;
        self.publisher.send(tick, sample)?;
        let deadline_ns = silrig_wire::clock::monotonic_ns() + timeout.as_nanos() as u64;
        loop {
            let mut answer = None;
            self.commands.drain(|r| {
                if r.invalid.is_none() && r.sample.answers_tick == tick {
                    answer = Some(r.sample);
                }
            })?;
            if let Some(answer) = answer {
                return Ok(answer);
            }
            self.ensure_alive(&format!("its answer to tick {tick}"))?;
            anyhow::ensure!(
                silrig_wire::clock::monotonic_ns() < deadline_ns,
                "the controller did not answer tick {tick} within {} s{}",
                timeout.as_secs_f64(),
                self.controller_said()
            );
            self.commands.wait_readable_until((silrig_wire::clock::monotonic_ns() + 50_000_000).min(deadline_ns));
        }
    }

    /// Tell the controller the flight is over, let it write its report, and reap it; then remove the run's
    /// iceoryx2 files.
    fn stop(mut self, last: Option<&PlantSample>) -> anyhow::Result<()> {
        if let Some(last) = last {
            let end = PlantSample { flags: last.flags | wire::FLAG_END_OF_RUN, ..*last };
            let _ = self.publisher.send(last.header.tick, &end);
        }
        let _ = self.publisher.announce_finished();
        if self.child.poll()?.is_none() {
            let deadline = std::time::Instant::now() + Duration::from_secs(5);
            while self.child.poll()?.is_none() && std::time::Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(5));
            }
            self.child.signal(libc::SIGTERM);
        }
        self.child.finish(Duration::from_secs(5))?;
        let run_id = self.run_id.clone();
        drop(self);
        ipc::cleanup_run(&run_id)?;
        Ok(())
    }
}

/// A recording copied into another run's folder would be replayed against that run's files and leave its
/// `replay.json` there: the folder's `report.json` and the recording must name the same run.
fn check_same_run(run_dir: &Path, recorded: &RecordedRun) -> anyhow::Result<()> {
    let Ok(text) = std::fs::read_to_string(run_dir.join("report.json")) else { return Ok(()) };
    let folder_run =
        serde_json::from_str::<serde_json::Value>(&text).ok().and_then(|r| r["run_id"].as_str().map(str::to_string));
    let recording_run = recorded.run.get("run_id");
    match (folder_run, recording_run) {
        (Some(folder), Some(recording)) if &folder != recording => anyhow::bail!(
            "{}: the recording is of run `{recording}`, but this folder's report.json is of run `{folder}`: it was \
             copied here from another run; replay it from a folder of its own",
            recorded.files[0].display()
        ),
        _ => Ok(()),
    }
}

/// Replay the recording in `opts.run_dir` against the controller, and compare. A recording that cannot be read is
/// an error ([`silrig_recording::reader::RecordingError`]); a controller that dies or stops answering is an error
/// naming the tick.
pub fn replay(opts: &ReplayOptions) -> anyhow::Result<ReplayOutcome> {
    silrig_rig::flag_in_range("tolerance", opts.tolerance, 0.0, f64::MAX, "").map_err(anyhow::Error::msg)?;
    silrig_rig::flag_in_range("answer-timeout-s", opts.answer_timeout_s, 0.1, 3600.0, "s")
        .map_err(anyhow::Error::msg)?;
    let recorded = RecordedRun::read(&opts.run_dir)?;
    check_same_run(&opts.run_dir, &recorded)?;
    anyhow::ensure!(
        !recorded.plant.is_empty(),
        "{}: the recording holds no plant samples",
        recorded.files[0].display()
    );
    let out_dir = opts.out.clone().unwrap_or_else(|| fresh_out_dir(&opts.run_dir));
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let scenario_path = out_dir.join("scenario.toml");
    std::fs::write(&scenario_path, &recorded.scenario_toml)
        .with_context(|| format!("writing {}", scenario_path.display()))?;
    silrig_flight::scenario::Scenario::load(&scenario_path)
        .with_context(|| format!("the scenario in {} does not load", recorded.files[0].display()))?;

    let plant = recorded.plant_signals()?;
    let diagnostic_names = recorded.diagnostic_names()?;
    let info = recorded.plant_info.expect("plant_signals found it");
    let timeout = Duration::from_secs_f64(opts.answer_timeout_s);
    let mut rig = ReplayRig::start(opts, &info, &scenario_path, &out_dir)?;
    let run_id = rig.run_id.to_string();
    let mut replayed = Vec::with_capacity(recorded.plant.len());
    let flown = (|| -> anyhow::Result<()> {
        rig.wait_connected(timeout)?;
        for sample in &recorded.plant {
            replayed.push(rig.answer(sample, timeout)?);
        }
        Ok(())
    })();
    let stopped = rig.stop(recorded.plant.last());
    flown?;
    stopped?;

    let mut comparison = Comparison::new(&plant, &diagnostic_names, opts.tolerance);
    let mut without_command = 0;
    for (sample, answer) in recorded.plant.iter().zip(&replayed) {
        match recorded.commands.get(&sample.header.tick) {
            Some(command) => comparison.add(sample, command, answer),
            None => without_command += 1,
        }
    }
    let lives: std::collections::BTreeSet<u64> = recorded.commands.values().map(|c| c.header.epoch).collect();
    let outcome = ReplayOutcome {
        run_dir: opts.run_dir.clone(),
        out_dir: out_dir.clone(),
        run_id,
        controller: opts.controller_cmd.clone().unwrap_or_else(|| Role::Controller.binary().to_string()),
        samples_sent: replayed.len() as u64,
        ticks_compared: comparison.compared,
        ticks_without_recorded_command: without_command,
        ticks_bit_identical: comparison.identical,
        recorded_controller_lives: lives.len() as u64,
        tolerance: opts.tolerance,
        first_divergence: comparison.first,
        fields: comparison.fields,
    };
    let json = serde_json::to_string_pretty(&outcome).expect("the outcome serialises");
    silrig_flight::files::write_atomically(&out_dir.join(REPORT), &json)?;
    Ok(outcome)
}
