//! Supervision of a run's processes by `silrig run`: starting them, reaping every exit exactly once, telling a
//! planned end from a death, restarting by policy, and stopping them all at the end. It sends signals only to
//! children it started and has not reaped, so a pid is never reused under it.

use super::ProcessArgs;
use super::events::EventLog;
use crate::topology::Role;
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

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
    #[arg(long, default_value_t = 3)]
    pub max_restarts: u32,
    /// on-failure: pause before the first restart, ms (doubling each time).
    #[arg(long, default_value_t = 200.0)]
    pub restart_backoff_ms: f64,
}

/// A child process the launcher started: reaped once, signalled only while not reaped.
pub(super) struct ChildProcess {
    child: std::process::Child,
    status: Option<ExitStatus>,
}

impl ChildProcess {
    pub(super) fn new(child: std::process::Child) -> Self {
        Self { child, status: None }
    }

    pub(super) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The exit status, reaping the child if it has ended.
    pub(super) fn poll(&mut self) -> std::io::Result<Option<ExitStatus>> {
        if self.status.is_none() {
            self.status = self.child.try_wait()?;
        }
        Ok(self.status)
    }

    pub(super) fn has_ended(&self) -> bool {
        self.status.is_some()
    }

    pub(super) fn signal(&mut self, signal: libc::c_int) {
        if self.status.is_none() {
            // SAFETY: kill(2) on the pid of a child we have not reaped yet, so the pid cannot have been reused.
            unsafe {
                libc::kill(self.child.id() as libc::pid_t, signal);
            }
        }
    }

    /// Wait up to `timeout` for the process to end; then SIGKILL it. Always reaps.
    pub(super) fn finish(&mut self, timeout: Duration) -> std::io::Result<ExitStatus> {
        let deadline = Instant::now() + timeout;
        while self.poll()?.is_none() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
        }
        if self.status.is_none() {
            self.signal(libc::SIGKILL);
            self.status = Some(self.child.wait()?);
        }
        Ok(self.status.expect("reaped"))
    }
}

/// An exit status as a person reads it.
pub(super) fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exit status {c}"),
        (None, Some(s)) => format!("killed by signal {s}"),
        _ => "ended".into(),
    }
}

/// One role's process, across its restarts.
pub(super) struct RoleProcess {
    pub(super) role: Role,
    pub(super) process: ChildProcess,
    /// A planned kill or term was sent and its exit not yet seen.
    pub(super) planned_exit: bool,
    /// This instance ended by a planned kill or term.
    killed_by_plan: bool,
    /// Its exit has been dealt with (each exit is handled once).
    exit_handled: bool,
    /// When a clean exit before the plant's end was first seen.
    clean_exit_seen: Option<Instant>,
    restarts: u32,
    /// When to start it again.
    pub(super) restart_at: Option<Instant>,
}

impl RoleProcess {
    /// Ended for good: exited and no restart pending.
    fn ended_for_good(&self) -> bool {
        self.process.has_ended() && self.restart_at.is_none()
    }
}

/// How long a process that exited cleanly before the plant's end waits for that end before it counts as a death.
const CLEAN_EXIT_GRACE: Duration = Duration::from_secs(2);

/// Folder of the rig binaries: next to the running executable (`target/release/` in a build tree).
pub fn binary_dir() -> anyhow::Result<PathBuf> {
    let exe = std::env::current_exe().context("locating the running executable")?;
    Ok(exe.parent().context("the executable has no folder")?.to_path_buf())
}

/// A rig binary much older than the launcher was probably not rebuilt with it (`cargo run` builds only `silrig`).
/// Cargo links the binaries of one build within seconds of each other, hence the tolerance.
fn warn_if_stale(bin_dir: &Path) {
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let Some(launcher) = std::env::current_exe().ok().and_then(|p| modified(&p)) else { return };
    for role in Role::ALL {
        let stale = |t: std::time::SystemTime| launcher.duration_since(t).is_ok_and(|d| d > Duration::from_secs(30));
        if modified(&bin_dir.join(role.binary())).is_some_and(stale) {
            eprintln!(
                "silrig run: warning: {} is older than silrig; rebuild all binaries with `cargo build --release`",
                role.binary()
            );
        }
    }
}

/// The run's processes and what became of them.
pub(super) struct Supervisor {
    bin_dir: PathBuf,
    args: ProcessArgs,
    events: EventLog,
    restart: SupervisionOptions,
    started: Instant,
    processes: Vec<RoleProcess>,
    /// When the plant ended for good (its last tick, or its death without a restart).
    plant_done_at: Option<Instant>,
    /// Wall time from the start to the plant's end, s.
    pub(super) wall_s: f64,
    /// Processes that failed, and how.
    pub(super) failures: Vec<String>,
}

impl Supervisor {
    /// Start the three processes with `args`: the logger first and the plant last, staggered, because concurrent
    /// node creation with dead-node cleanup is where iceoryx2 has had races (#1880).
    pub(super) fn start(args: ProcessArgs, events: EventLog, restart: SupervisionOptions) -> anyhow::Result<Self> {
        let bin_dir = binary_dir()?;
        warn_if_stale(&bin_dir);
        let mut sup = Self {
            bin_dir,
            args,
            events,
            restart,
            started: Instant::now(),
            processes: Vec::new(),
            plant_done_at: None,
            wall_s: 0.0,
            failures: Vec::new(),
        };
        for role in [Role::Logger, Role::Controller, Role::Plant] {
            let process = sup.spawn(role, false)?;
            sup.processes.push(RoleProcess {
                role,
                process,
                planned_exit: false,
                killed_by_plan: false,
                exit_handled: false,
                clean_exit_seen: None,
                restarts: 0,
                restart_at: None,
            });
            std::thread::sleep(Duration::from_millis(20));
        }
        Ok(sup)
    }

    fn spawn(&self, role: Role, resume: bool) -> anyhow::Result<ChildProcess> {
        let exe = self.bin_dir.join(role.binary());
        let log = std::fs::File::create(self.args.out.join(format!("{role}.stderr.log")))?;
        let args = ProcessArgs { resume, ..self.args.clone() };
        let child = Command::new(&exe)
            .args(args.to_argv())
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .with_context(|| format!("starting {} (build it with `cargo build --release`)", exe.display()))?;
        Ok(ChildProcess::new(child))
    }

    /// Time since the processes were started.
    pub(super) fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    pub(super) fn process_mut(&mut self, role: Role) -> &mut RoleProcess {
        self.processes.iter_mut().find(|p| p.role == role).expect("every role is supervised")
    }

    fn plant_done(&mut self) {
        if self.plant_done_at.is_none() {
            self.plant_done_at = Some(Instant::now());
            self.wall_s = self.started.elapsed().as_secs_f64();
        }
    }

    /// Reap what ended and decide, once per exit, what it was: a planned end, the plant's or the logger's normal
    /// end, or a death (restarted by policy, or a failure of the run while the survivors carry on).
    pub(super) fn handle_exits(&mut self) -> std::io::Result<()> {
        for i in 0..self.processes.len() {
            let p = &mut self.processes[i];
            let Some(status) = p.process.poll()? else { continue };
            if p.exit_handled {
                continue;
            }
            // A process that ends cleanly by itself mid-run has usually seen the plant's last tick a moment before
            // the plant's own exit reaches us: judge it once the plant has had time to end.
            if status.success() && p.role != Role::Plant && self.plant_done_at.is_none() {
                let seen = *p.clean_exit_seen.get_or_insert_with(Instant::now);
                if seen.elapsed() < CLEAN_EXIT_GRACE {
                    continue;
                }
            }
            p.exit_handled = true;
            let role = p.role;
            if std::mem::take(&mut p.planned_exit) {
                p.killed_by_plan = true;
                let restarting = p.restart_at.is_some();
                self.events.emit(None, "process-ended", format!("{role} {} (planned)", describe(status)));
                if !restarting && role == Role::Plant {
                    self.plant_done();
                }
                continue;
            }
            if p.restart_at.is_some() {
                continue;
            }
            if role == Role::Plant && status.success() && self.plant_done_at.is_none() {
                self.plant_done();
                continue;
            }
            // The logger ends by itself once it has written the last tick; the others end when told to.
            if (role == Role::Logger && status.success())
                || self.plant_done_at.is_some()
                || self.failures.iter().any(|f| f.starts_with(role.label()))
            {
                continue;
            }
            self.on_death(i, format!("{role}: {} before the end of the run", describe(status)));
        }
        Ok(())
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
                // end and reports the failure. Without a plant there is nothing left to run.
                if role == Role::Plant {
                    self.plant_done();
                }
                self.failures.push(death);
            }
        }
    }

    /// Start again every process whose restart is due; a restarted plant or controller resumes what its
    /// predecessor saved.
    pub(super) fn restart_due(&mut self) -> anyhow::Result<()> {
        for i in 0..self.processes.len() {
            let p = &self.processes[i];
            if !(p.process.has_ended() && p.restart_at.is_some_and(|t| Instant::now() >= t)) {
                continue;
            }
            let (role, restarts) = (p.role, p.restarts + 1);
            let process = self.spawn(role, role.resumes())?;
            let pid = process.pid();
            self.processes[i] = RoleProcess {
                role,
                process,
                planned_exit: false,
                killed_by_plan: false,
                exit_handled: false,
                clean_exit_seen: None,
                restarts,
                restart_at: None,
            };
            self.events.emit(None, "process-restarted", format!("{role} as pid {pid} (restart {restarts})"));
        }
        Ok(())
    }

    /// The plant has ended for good and the logger has too (or had 2 s to write its last rows).
    pub(super) fn run_is_over(&self) -> bool {
        let logger_done = self.processes.iter().any(|p| p.role == Role::Logger && p.ended_for_good());
        self.plant_done_at.is_some_and(|t| logger_done || t.elapsed() > Duration::from_secs(2))
    }

    /// Roles a planned kill or term ended for good (they have no report to give).
    pub(super) fn ended_by_plan(&self) -> Vec<Role> {
        self.processes.iter().filter(|p| p.ended_for_good() && p.killed_by_plan).map(|p| p.role).collect()
    }

    /// SIGTERM to every process still running, reap all (SIGKILL after 5 s); an exit other than a clean one of a
    /// process that was still running is a failure, unless one is recorded for it already.
    pub(super) fn stop_all(&mut self) -> std::io::Result<()> {
        if self.plant_done_at.is_none() {
            self.wall_s = self.started.elapsed().as_secs_f64();
        }
        for p in self.processes.iter_mut() {
            p.process.signal(libc::SIGTERM);
        }
        for p in self.processes.iter_mut() {
            let already_ended = p.process.has_ended();
            let status = p.process.finish(Duration::from_secs(5))?;
            if !already_ended && !status.success() && !self.failures.iter().any(|f| f.starts_with(p.role.label())) {
                self.failures.push(format!("{}: {}", p.role, describe(status)));
            }
        }
        Ok(())
    }
}
