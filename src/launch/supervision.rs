//! Supervision of a run's processes by `silrig run`: starting them, reaping every exit exactly once, telling a
//! planned end from a death, restarting by policy, and stopping them all at the end. It sends signals only to
//! children it started and has not reaped, so a pid is never reused under it.

use crate::child::{ChildProcess, describe, forward_output, start_process};
use crate::joining::{self, Joining};
use crate::program::binary_dir;
use crate::run_report::ProcessLife;
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_rig::ProcessArgs;
use silrig_rig::events::EventLog;
use silrig_rig::report::{read_report, report_path};
use std::path::{Path, PathBuf};
use std::process::ExitStatus;
use std::time::{Duration, Instant};

mod stuck;

/// What to do when a process dies without a planned fault (`--restart`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RestartMode {
    /// The run continues without it and fails at the end.
    Never,
    /// Start it again, with a doubling pause, up to `--max-restarts` times.
    OnFailure,
}

/// How `silrig run` supervises its processes.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct SupervisionOptions {
    /// What to do when a process dies without a planned fault: never (the run fails) or on-failure.
    #[arg(long, value_enum, default_value = "never")]
    pub restart: RestartMode,
    /// on-failure: restarts allowed per process.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    pub max_restarts: u32,
    /// on-failure: pause before the first restart, ms (doubling each time).
    #[arg(long, default_value_t = 200.0, allow_negative_numbers = true)]
    pub restart_backoff_ms: f64,
}

impl SupervisionOptions {
    /// Every flag within its documented range.
    pub fn validate(&self) -> Result<(), String> {
        silrig_rig::flag_in_range("max-restarts", f64::from(self.max_restarts), 0.0, 100.0, "restarts")?;
        silrig_rig::flag_in_range("restart-backoff-ms", self.restart_backoff_ms, 0.0, 60_000.0, "ms")
    }
}

/// One role's process, across its restarts.
pub(crate) struct RoleProcess {
    pub(crate) role: Role,
    pub(crate) process: ChildProcess,
    /// A planned kill or term was sent and its exit not yet seen.
    pub(crate) planned_exit: bool,
    /// This instance ended by a planned kill or term.
    killed_by_plan: bool,
    /// Its exit has been dealt with (each exit is handled once).
    exit_handled: bool,
    /// When a clean exit before the plant's end was first seen.
    clean_exit_seen: Option<Instant>,
    restarts: u32,
    /// When to start it again.
    pub(crate) restart_at: Option<Instant>,
    /// Whether it has joined the run yet ([`Supervisor::watch_joins`]).
    joining: Joining,
}

impl RoleProcess {
    /// A process just started, after `restarts` restarts of its role.
    fn started(role: Role, process: ChildProcess, restarts: u32) -> Self {
        Self {
            role,
            process,
            planned_exit: false,
            killed_by_plan: false,
            exit_handled: false,
            clean_exit_seen: None,
            restarts,
            restart_at: None,
            joining: Joining::started(restarts),
        }
    }

    /// Ended for good: exited and no restart pending.
    fn ended_for_good(&self) -> bool {
        self.process.has_ended() && self.restart_at.is_none()
    }
}

/// How long a process told to stop at the end of the run (and what its command started) may take before SIGKILL.
const STOP_GRACE: Duration = Duration::from_secs(5);

/// How long a process that exited cleanly before the plant's end waits for that end before it counts as a death.
const CLEAN_EXIT_GRACE: Duration = Duration::from_secs(2);

/// A rig binary built before its sources last changed was not rebuilt with the launcher (`cargo run` builds only
/// `silrig`). Cargo's dep-info file beside it (`<binary>.d`) lists those sources; installed binaries have none and
/// are not checked. (Comparing with the launcher's own build time, as before, warned in CI: on two cores cargo
/// linked the binaries of one build up to a minute apart.)
fn warn_if_stale(bin_dir: &Path) {
    // Once a process: a sweep starts a run for every case, and the check reads every source file's time.
    static CHECKED: std::sync::Once = std::sync::Once::new();
    CHECKED.call_once(|| warn_if_stale_now(bin_dir));
}

fn warn_if_stale_now(bin_dir: &Path) {
    for role in Role::ALL {
        if let Some(source) = newer_source(&bin_dir.join(role.binary())) {
            eprintln!(
                "silrig run: warning: {} was built before {} changed; rebuild all binaries with `cargo build \
                 --release`",
                role.binary(),
                source.display()
            );
        }
    }
}

/// A source of `binary` changed after it was built, by its dep-info file.
fn newer_source(binary: &Path) -> Option<PathBuf> {
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let built = modified(binary)?;
    let mut dep_info = binary.as_os_str().to_owned();
    dep_info.push(".d");
    let text = std::fs::read_to_string(PathBuf::from(dep_info)).ok()?;
    let (_, sources) = text.lines().next()?.split_once(": ")?;
    dep_info_paths(sources).into_iter().find(|p| modified(p).is_some_and(|t| t > built))
}

/// The paths of a dep-info line, which escapes a space in a path as `\ `.
fn dep_info_paths(line: &str) -> Vec<PathBuf> {
    let (mut paths, mut path, mut chars) = (Vec::new(), String::new(), line.chars());
    while let Some(c) = chars.next() {
        match c {
            '\\' => path.extend(chars.next()),
            ' ' if !path.is_empty() => paths.push(PathBuf::from(std::mem::take(&mut path))),
            ' ' => {}
            _ => path.push(c),
        }
    }
    if !path.is_empty() {
        paths.push(PathBuf::from(path));
    }
    paths
}

/// The controller the supervisor starts, if any.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ControllerLaunch {
    /// silrig-controller.
    Ours,
    /// A user's shell command, with the run's SILRIG_* variables.
    Command(String),
    /// Started by hand; not supervised.
    External,
}

/// The last lines a process wrote to its stderr log, for the message that reports its death.
pub fn stderr_tail(out: &Path, role: Role) -> String {
    let text = std::fs::read_to_string(out.join(format!("{role}.stderr.log"))).unwrap_or_default();
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let tail = lines[lines.len().saturating_sub(3)..].join(" | ");
    if tail.is_empty() { String::new() } else { format!("; its stderr ends: {}", last_chars(&tail, 400)) }
}

/// The last `max_chars` characters of `text`.
fn last_chars(text: &str, max_chars: usize) -> &str {
    let skip = text.chars().count().saturating_sub(max_chars);
    text.char_indices().nth(skip).map_or("", |(at, _)| &text[at..])
}

/// Whether `role`'s report says a signal ended it (a SIGTERM or SIGINT it acted on, writing its report).
fn ended_on_signal(out: &Path, role: Role) -> bool {
    read_report(out, role.label()).is_ok_and(|r| r.ended == "terminated by signal")
}

/// The run's processes and what became of them.
pub(crate) struct Supervisor {
    bin_dir: PathBuf,
    controller: ControllerLaunch,
    /// `--plant-cmd`: the user's plant in place of silrig-plant.
    plant_cmd: Option<String>,
    /// `--plant external`: nobody here starts the plant; the logger's end is the run's.
    plant_external: bool,
    /// What the logger's command line gets beyond the run's arguments (`--live-foxglove`), every life.
    logger_args: Vec<String>,
    /// The FMU silrig-plant flies, if it flies one: named when the plant process dies of a signal.
    pub(crate) plant_fmu: Option<PathBuf>,
    /// The controller FMU silrig-controller flies, if any: named when the controller dies of a signal.
    pub(crate) controller_fmu: Option<PathBuf>,
    args: ProcessArgs,
    events: EventLog,
    restart: SupervisionOptions,
    started: Instant,
    processes: Vec<RoleProcess>,
    /// When the plant ended for good (its last tick, or its death without a restart).
    plant_done_at: Option<Instant>,
    /// The run is stopping: every exit is judged now, without waiting out the grace of a clean one.
    stopping: bool,
    /// Wall time from the start to the plant's end, s.
    pub(crate) wall_s: f64,
    /// Processes that failed, and how.
    pub(crate) failures: Vec<String>,
    /// What the report should say that is no failure: a process the run's end had to SIGKILL, and what it cost.
    pub(crate) notes: Vec<String>,
    /// Every process started, one entry per life (a restart starts a new life).
    pub(crate) lives: Vec<ProcessLife>,
    /// A sweep's warm rig, whose warm processes fork the run's processes.
    warm: Option<std::sync::Arc<crate::warm::WarmRig>>,
    /// Restarted processes watched until they take the plant's samples.
    stuck: stuck::StuckWatch,
}

/// The longest the launcher waits for a process's node before it starts the next ([`joining::wait_until_joined`]).
const STAGGER_AT_MOST: Duration = Duration::from_millis(20);

impl Supervisor {
    /// Start the three processes with `args`: the logger first and the plant last, each once the one before has
    /// its node (at most [`STAGGER_AT_MOST`] later), because concurrent node creation with dead-node cleanup is
    /// where iceoryx2 has had races (#1880).
    /// `launch`: where the controller comes from, the plant's command (`None`: external), and what the logger's
    /// command line gets beyond the run's arguments. `warm`: a sweep's warm rig forks them.
    pub(crate) fn start(
        args: ProcessArgs,
        events: EventLog,
        restart: SupervisionOptions,
        launch: (ControllerLaunch, Option<Option<String>>, Vec<String>),
        warm: Option<std::sync::Arc<crate::warm::WarmRig>>,
    ) -> anyhow::Result<Self> {
        let (controller, plant, logger_args) = launch;
        let bin_dir = binary_dir()?;
        warn_if_stale(&bin_dir);
        let mut sup = Self {
            bin_dir,
            controller,
            plant_cmd: plant.clone().flatten(),
            plant_external: plant.is_none(),
            plant_fmu: None,
            controller_fmu: None,
            logger_args,
            args,
            events,
            restart,
            started: Instant::now(),
            processes: Vec::new(),
            plant_done_at: None,
            stopping: false,
            wall_s: 0.0,
            failures: Vec::new(),
            notes: Vec::new(),
            lives: Vec::new(),
            warm,
            stuck: Default::default(),
        };
        for role in [Role::Logger, Role::Controller, Role::Plant] {
            if (role == Role::Controller && sup.controller == ControllerLaunch::External)
                || (role == Role::Plant && sup.plant_external)
            {
                continue;
            }
            let mut process = sup.spawn(role, false)?;
            sup.begin_life(role, 1, process.pid());
            joining::wait_until_joined(&mut process, &sup.args.run_id, STAGGER_AT_MOST);
            sup.processes.push(RoleProcess::started(role, process, 0));
        }
        Ok(sup)
    }

    /// Start `role`'s process; its stderr is appended to `<out>/<role>.stderr.log` (a restart adds a marker line,
    /// so what the dead one said stays readable).
    fn spawn(&self, role: Role, resume: bool) -> anyhow::Result<ChildProcess> {
        let log_path = self.args.out.join(format!("{role}.stderr.log"));
        let (reader, writer) = std::io::pipe().context("creating a pipe for a process's output")?;
        let log = writer.try_clone()?;
        let marker = resume.then(|| format!("--- silrig run: {role} restarted ---"));
        let output = forward_output(reader, log_path, role, marker);
        let args = ProcessArgs { resume, ..self.args.clone() };
        let command = self.command_of(role);
        let extra: &[String] = if role == Role::Logger { &self.logger_args } else { &[] };
        let process = match self.warm.as_ref().and_then(|w| w.process(role)) {
            // A sweep's warm rig: the same command line and variables, forked by the role's warm process.
            Some(warm) => {
                drop(log);
                warm.fly(role, command, &args, extra, &self.bin_dir, writer.into())?
            }
            None => start_process(role, command, &args, extra, &self.bin_dir, log.into(), writer.into())?,
        };
        Ok(process.with_output(output))
    }

    /// The user's command that runs `role` (`--controller-cmd`, `--plant-cmd`), if one does.
    fn command_of(&self, role: Role) -> Option<&str> {
        match (role, &self.controller) {
            (Role::Controller, ControllerLaunch::Command(cmd)) => Some(cmd.as_str()),
            (Role::Plant, _) => self.plant_cmd.as_deref(),
            _ => None,
        }
    }

    /// Note who has joined the run. A process still running that has not joined within the start-up timeout is
    /// the run's culprit, its failure the first: the run stops for it at once, without a restart (a second start
    /// would wait as long), and the peers that give up waiting for it are no failure of their own. Looked at until
    /// everyone started has joined, and at every exit (the exit may be a peer giving up on one that never joined).
    pub(crate) fn watch_joins(&mut self) {
        let waiting = |p: &RoleProcess| matches!(p.joining, Joining::Waited { .. });
        if self.plant_done_at.is_some() || self.stopping || !self.processes.iter().any(waiting) {
            return;
        }
        let nodes = joining::nodes(&self.args.run_id);
        let timeout = Duration::from_secs_f64(self.args.options.startup_timeout_s);
        for i in 0..self.processes.len() {
            let p = &mut self.processes[i];
            let Joining::Waited { since } = p.joining else { continue };
            if joining::has_joined(&p.process, &nodes) {
                p.joining = Joining::Joined;
                continue;
            }
            if p.process.has_ended() || since.elapsed() < timeout {
                continue;
            }
            p.joining = Joining::NeverJoined;
            let (role, pid) = (p.role, p.process.pid());
            let command = self.command_of(role);
            let who = joining::who(role, command, pid);
            let waited_s = since.elapsed().as_secs_f64();
            let failure = joining::never_joined(role, &who, command.is_some(), &self.args.run_id, waited_s);
            self.events.emit(None, "process-never-joined", failure.clone());
            eprintln!("silrig run: {failure}");
            self.failures.insert(0, failure);
            self.plant_done();
        }
    }

    fn begin_life(&mut self, role: Role, life: u32, pid: u32) {
        self.lives.push(ProcessLife {
            process: role.label().into(),
            life,
            pid,
            started_at_s: self.started.elapsed().as_secs_f64(),
            ended_at_s: None,
            exit: "running".into(),
            report: None,
        });
    }

    /// Note how the life of process `pid` ended; a death by a signal leaves an iceoryx2 node behind, which the
    /// launcher removes here, off every process's loop.
    fn end_life(&mut self, pid: u32, status: ExitStatus, how: &str) {
        let at_s = self.started.elapsed().as_secs_f64();
        if let Some(life) = self.lives.iter_mut().rev().find(|l| l.pid == pid && l.ended_at_s.is_none()) {
            life.ended_at_s = Some(at_s);
            life.exit = format!("{}{how}", describe(status));
        }
        if status.code().is_none()
            && let Ok(removed) = silrig_wire::ipc::cleanup_dead_nodes(&self.args.run_id)
            && !removed.is_empty()
        {
            let who: Vec<String> = removed.iter().map(|n| format!("`{}` (pid {})", n.name, n.pid)).collect();
            self.events.emit(None, "dead-nodes-removed", format!("by the launcher: {}", who.join(", ")));
        }
    }

    /// Time since the processes were started.
    pub(crate) fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    pub(crate) fn process_mut(&mut self, role: Role) -> &mut RoleProcess {
        self.processes.iter_mut().find(|p| p.role == role).expect("every role is supervised")
    }

    /// Whether the plant has started ticking (its `ticking` event is in the run's events).
    pub(crate) fn plant_ticking(&self) -> bool {
        std::fs::read_to_string(self.args.out.join("events.jsonl")).is_ok_and(|t| t.contains("\"ticking\""))
    }

    fn plant_done(&mut self) {
        if self.plant_done_at.is_none() {
            self.plant_done_at = Some(Instant::now());
            self.wall_s = self.started.elapsed().as_secs_f64();
        }
    }

    /// Reap what ended and decide, once per exit, what it was: a planned end, the plant's or the logger's normal
    /// end, or a death (restarted by policy, or a failure of the run while the survivors carry on).
    pub(crate) fn handle_exits(&mut self) -> std::io::Result<()> {
        for i in 0..self.processes.len() {
            let p = &mut self.processes[i];
            let Some(status) = p.process.poll()? else { continue };
            if p.exit_handled {
                continue;
            }
            // A process that ends cleanly by itself mid-run has usually seen the plant's last tick a moment before
            // the plant's own exit reaches us: judge it once the plant has had time to end. (Before the plant's
            // first tick there is no last tick to have seen; a planned end, or one its report says a signal asked
            // for, is no end of the flight: judged at once, so a death is recorded, and restarted, when it happens.)
            let wait = status.success()
                && p.role != Role::Plant
                && self.plant_done_at.is_none()
                && !self.stopping
                && !p.planned_exit
                && !ended_on_signal(&self.args.out, p.role);
            if wait && self.plant_ticking() {
                let p = &mut self.processes[i];
                let seen = *p.clean_exit_seen.get_or_insert_with(Instant::now);
                if seen.elapsed() < CLEAN_EXIT_GRACE {
                    continue;
                }
            }
            self.processes[i].exit_handled = true;
            // Before its node is cleaned up: whether it had joined, and whether a peer it waited for never did.
            self.watch_joins();
            let p = &mut self.processes[i];
            let (role, pid, planned) = (p.role, p.process.pid(), p.planned_exit);
            let renewed = self.stuck.take_renewing(pid);
            self.end_life(
                pid,
                status,
                match (renewed, planned) {
                    (true, _) => " (renewed: it took no sample)",
                    (false, true) => " (the fault plan)",
                    (false, false) => "",
                },
            );
            let p = &mut self.processes[i];
            if std::mem::take(&mut p.planned_exit) {
                p.killed_by_plan = true;
                let restarting = p.restart_at.is_some();
                let why = if renewed { "renewed" } else { "planned" };
                self.events.emit(None, "process-ended", format!("{role} {} ({why})", describe(status)));
                if !restarting && role == Role::Plant {
                    self.plant_done();
                }
                continue;
            }
            self.judge_exit(i, role, status);
        }
        Ok(())
    }

    /// An exit neither planned nor awaiting a restart, judged: the end of the flight (the plant's, or the logger's
    /// with a plant started by hand), an expected end, or a death.
    fn judge_exit(&mut self, i: usize, role: Role, status: ExitStatus) {
        if self.processes[i].restart_at.is_some() {
            return;
        }
        // Ctrl-C reaches the whole process group: whatever ends now, the user stopped the run.
        if silrig_rig::signals::termination_requested() {
            if role == Role::Plant {
                self.plant_done();
            }
            return;
        }
        // Only a flight flown to its end is the run's end: a clean exit on somebody else's SIGTERM is not.
        let ended = read_report(&self.args.out, role.label()).map(|r| r.ended).unwrap_or_default();
        // The launcher signals a process only for the fault plan (handled above) and when it stops the run
        // (reaped in `stop_all`): a clean exit on SIGTERM or SIGINT here came from outside, whenever the plant
        // ends, and the flight it cut short is a failure.
        if status.success() && ended == "terminated by signal" {
            let tail = stderr_tail(&self.args.out, role);
            let death = format!("{role}: ended by a SIGTERM or SIGINT the launcher did not send{tail}");
            self.on_death(i, death);
            return;
        }
        // A plant of the user's own that speaks the contract itself writes no report: its clean exit is the end
        // of its flight (the logger's rows say how much of it there was).
        let raw_plant_done = role == Role::Plant && self.plant_cmd.is_some() && ended.is_empty();
        let completed = status.success() && (ended == "completed" || raw_plant_done);
        if role == Role::Plant && completed && self.plant_done_at.is_none() {
            self.plant_done();
            return;
        }
        // The logger ends by itself once it has written the last tick; the others end when told to. With a plant
        // started by hand, that is the end of the flight as seen from here.
        if role == Role::Logger && completed && self.plant_external {
            self.plant_done();
        }
        // A controller's session says "completed" only after the plant's end-of-run sample: the flight ended,
        // and under load its exit can be reaped before the plant's (or, with a plant started by hand, the
        // logger's).
        if (matches!(role, Role::Logger | Role::Controller) && completed)
            || self.plant_done_at.is_some()
            || self.failures.iter().any(|f| f.starts_with(role.label()))
        {
            return;
        }
        let death = self.death_of(i, status, &ended);
        self.on_death(i, death);
    }

    /// A death in words: how it ended, when (a user's command before it joined the run: with the command and how
    /// soon), which FMU it was flying if it crashed, and the end of its stderr.
    fn death_of(&self, i: usize, status: ExitStatus, ended: &str) -> String {
        let p = &self.processes[i];
        let role = p.role;
        let how = if status.success() && !ended.is_empty() {
            format!("ended ({ended}; the launcher sent no signal)")
        } else {
            describe(status)
        };
        let tail = stderr_tail(&self.args.out, role);
        let ticking = self.plant_ticking();
        // A user's command that ends before it joined: said with the command, so the first line names the culprit.
        if let (Joining::Waited { since }, false, Some(command)) = (p.joining, ticking, self.command_of(role)) {
            let who = joining::who(role, Some(command), p.process.pid());
            return joining::exited_before_joining(role, &who, &how, since.elapsed().as_secs_f64(), &tail);
        }
        let when = if ticking { "before the end of the run" } else { "before the plant's first tick" };
        let fmu = match (role, status.code()) {
            // A crash in an FMU's code takes its process with it: say which FMU it was flying.
            (Role::Plant, None) => self.plant_fmu.as_ref(),
            (Role::Controller, None) => self.controller_fmu.as_ref(),
            _ => None,
        }
        .map(|fmu| {
            format!(" while flying the FMU {} (a crash in the FMU's code ends the {role} process)", fmu.display())
        })
        .unwrap_or_default();
        format!("{role}: {how} {when}{fmu}{tail}")
    }

    fn on_death(&mut self, index: usize, death: String) {
        self.events.emit(None, "process-died", death.clone());
        let p = &mut self.processes[index];
        let role = p.role;
        match self.restart {
            SupervisionOptions { restart: RestartMode::OnFailure, max_restarts, restart_backoff_ms }
                if p.restarts < max_restarts =>
            {
                let pause_s = restart_backoff_ms / 1e3 * 2f64.powi(p.restarts as i32);
                eprintln!("silrig run: {death}; restarting in {pause_s:.2} s");
                p.restart_at = Some(Instant::now() + Duration::from_secs_f64(pause_s));
            }
            _ => {
                // The survivors carry on (the plant in failsafe, the logger marking the gap): the run goes to its
                // end and reports the failure. Without a plant there is nothing left to run, and a controller that
                // dies before the plant's first tick leaves it waiting out its start-up timeout for nothing.
                if role == Role::Plant || (role == Role::Controller && !self.plant_ticking()) {
                    self.plant_done();
                }
                self.failures.push(death);
            }
        }
    }

    /// Start again every process whose restart is due; a restarted plant or controller resumes what its
    /// predecessor saved.
    pub(crate) fn restart_due(&mut self) -> anyhow::Result<()> {
        for i in 0..self.processes.len() {
            let p = &self.processes[i];
            if !(p.process.has_ended() && p.restart_at.is_some_and(|t| Instant::now() >= t)) {
                continue;
            }
            let (role, restarts) = (p.role, p.restarts + 1);
            self.keep_report_of_life(role, restarts);
            // Stamped when it is started, not once started: a quick process joins (and says so) before that.
            let spawned_ns = silrig_wire::clock::monotonic_ns();
            let process = self.spawn(role, role.resumes())?;
            let pid = process.pid();
            self.begin_life(role, restarts + 1, pid);
            self.processes[i] = RoleProcess::started(role, process, restarts);
            let detail = format!("{role} as pid {pid} (restart {restarts})");
            self.events.emit_at(spawned_ns, None, "process-restarted", detail);
            self.watch_restart(role, pid);
        }
        Ok(())
    }

    /// A process that is restarted keeps the report of the life that ended (one it wrote on SIGTERM, say) as
    /// `<role>.life<N>.report.json`, so the next life's report does not overwrite it.
    fn keep_report_of_life(&mut self, role: Role, life: u32) {
        let current = report_path(&self.args.out, role.label());
        let kept = self.args.out.join(format!("{}.life{life}.report.json", role.label()));
        if std::fs::rename(&current, &kept).is_ok()
            && let Some(l) = self.lives.iter_mut().find(|l| l.process == role.label() && l.life == life)
        {
            l.report = Some(kept.file_name().expect("a file name").to_string_lossy().into_owned());
        }
    }

    /// After the run, the last life of each role gets the report it wrote, if any.
    pub(crate) fn note_final_reports(&mut self) {
        for role in Role::ALL {
            let path = report_path(&self.args.out, role.label());
            if let Some(l) = self.lives.iter_mut().rev().find(|l| l.process == role.label())
                && path.exists()
            {
                l.report = Some(path.file_name().expect("a file name").to_string_lossy().into_owned());
            }
        }
    }

    /// What [`crate::child::wait_for_an_exit`] waits on: the exit descriptors of the processes still running.
    pub(crate) fn exit_fds(&self) -> Vec<std::os::fd::RawFd> {
        self.processes.iter().filter_map(|p| p.process.exit_fd()).collect()
    }

    /// The plant has ended for good and the others have too (the logger had 2 s to write its last rows, the
    /// controller 1 s to see the end-of-run sample and leave): one still running then is stopped.
    pub(crate) fn run_is_over(&self) -> bool {
        let done = |role: Role| self.processes.iter().all(|p| p.role != role || p.ended_for_good());
        self.plant_done_at.is_some_and(|t| {
            (done(Role::Logger) || t.elapsed() > Duration::from_secs(2))
                && (done(Role::Controller) || t.elapsed() > Duration::from_secs(1))
        })
    }

    /// Roles a planned kill or term ended for good (they have no report to give).
    pub(crate) fn ended_by_plan(&self) -> Vec<Role> {
        self.processes.iter().filter(|p| p.ended_for_good() && p.killed_by_plan).map(|p| p.role).collect()
    }

    /// SIGTERM to every process still running, reap all (SIGKILL after [`STOP_GRACE`]); an exit other than a clean one of a
    /// process that was still running is a failure, unless one is recorded for it already.
    pub(crate) fn stop_all(&mut self) -> std::io::Result<()> {
        if self.plant_done_at.is_none() {
            self.wall_s = self.started.elapsed().as_secs_f64();
        }
        // Exits already there are judged as exits by themselves (an outside SIGTERM to the logger included) before
        // the launcher's own SIGTERM makes every exit look asked for.
        self.stopping = true;
        self.handle_exits()?;
        for p in self.processes.iter_mut() {
            p.process.signal(libc::SIGTERM);
        }
        // A run stopped for a process that never joined: its peers' ends now are consequences of it, not failures of
        // their own (a controller still looking for the plant's services gave up at twice the timeout, with exit
        // status 2, a moment before it acted on this SIGTERM: one CI run of 2026-11-29 blamed it beside the plant).
        let culprit_never_joined = self.processes.iter().any(|p| matches!(p.joining, Joining::NeverJoined));
        for i in 0..self.processes.len() {
            let p = &mut self.processes[i];
            let already_ended = p.process.has_ended();
            let consequence = culprit_never_joined && !matches!(p.joining, Joining::NeverJoined);
            let status = p.process.finish(STOP_GRACE)?;
            let (role, pid) = (p.role, p.process.pid());
            for what in p.process.take_outlasted() {
                self.notes.push(format!("{role}: {what}, which the end of the run waited for"));
            }
            // A life already noted stays as it was: only open ones are ended here. One that never joined was
            // stopped for that, and its end on the launcher's signal is no death of its own.
            let how = match (already_ended, p.joining) {
                (true, _) => "",
                (false, Joining::NeverJoined) => " on the launcher's SIGTERM (it never joined the run)",
                (false, _) => " at the end of the run",
            };
            self.end_life(pid, status, how);
            // In a run that failed already, a process the stop's SIGTERM killed before it could act on it (one
            // still starting when a peer died at once) is the launcher's doing, not a failure of its own.
            use std::os::unix::process::ExitStatusExt;
            let stopped_by_us = status.signal() == Some(libc::SIGTERM) && !self.failures.is_empty();
            if !already_ended
                && !status.success()
                && !stopped_by_us
                && !consequence
                && !self.failures.iter().any(|f| f.starts_with(role.label()))
            {
                let tail = stderr_tail(&self.args.out, role);
                self.failures.push(format!("{role}: {}{tail}", describe(status)));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, SystemTime};

    #[test]
    fn a_binary_is_stale_when_a_source_its_dep_info_lists_changed_after_it() {
        assert_eq!(
            dep_info_paths("/a/b.rs /c/with\\ space.rs  /d.toml"),
            [PathBuf::from("/a/b.rs"), PathBuf::from("/c/with space.rs"), PathBuf::from("/d.toml")]
        );
        let dir = std::env::temp_dir().join(format!("silrig-stale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (bin, source) = (dir.join("silrig-plant"), dir.join("plant.rs"));
        let at =
            |p: &Path, t: SystemTime| std::fs::File::options().write(true).open(p).unwrap().set_modified(t).unwrap();
        std::fs::write(&bin, "").unwrap();
        std::fs::write(&source, "").unwrap();
        std::fs::write(dir.join("silrig-plant.d"), format!("{}: {}\n", bin.display(), source.display())).unwrap();
        let now = SystemTime::now();
        at(&source, now - Duration::from_secs(60));
        at(&bin, now);
        assert_eq!(newer_source(&bin), None, "built after its sources");
        at(&source, now + Duration::from_secs(1));
        assert_eq!(newer_source(&bin), Some(source.clone()), "a source changed after the build");
        std::fs::remove_file(dir.join("silrig-plant.d")).unwrap();
        assert_eq!(newer_source(&bin), None, "no dep-info (an installed binary): not checked");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
