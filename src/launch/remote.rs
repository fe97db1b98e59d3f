//! A controller on another host (`silrig run --bridge-listen`): the launcher starts the plant-side bridge
//! (`silrig-bridge`, see [`silrig::bridge`] when built with the `bridge` feature) instead of a controller, starts it
//! again if it dies, and stops it at the end. The controller, and the bridge beside it, run on the other host.

use crate::child::{ChildProcess, end_with_launcher};
use crate::program::binary_dir;
use anyhow::Context;
use silrig_rig::ProcessArgs;
use silrig_rig::events::{EventLog, read_events};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The bridge's binary, built only with `cargo build --release --features bridge`.
pub const BRIDGE_BINARY: &str = "silrig-bridge";

/// The plant-side bridge of a run, supervised by the launcher.
pub(crate) struct RemoteBridge {
    exe: PathBuf,
    argv: Vec<String>,
    log: PathBuf,
    events: EventLog,
    child: ChildProcess,
    restarts: u32,
    started: Instant,
    /// Deaths in a row, each soon after its start: a bridge that cannot run at all is not restarted for ever.
    quick_deaths: u32,
    restart_at: Option<Instant>,
    /// A fault of the plan ends this life: when to start it again; the death is not one of a bridge that cannot
    /// run.
    planned_restart_at: Option<Instant>,
    /// Why the bridge was given up on, for the run's failures.
    pub(crate) failure: Option<String>,
}

/// A bridge that dies within this long of its start died of something a restart does not cure, after
/// [`MAX_QUICK_DEATHS`] of them in a row.
const QUICK_DEATH: Duration = Duration::from_secs(5);
/// See [`QUICK_DEATH`].
const MAX_QUICK_DEATHS: u32 = 3;
/// A dead bridge is started again after this pause, doubled for each quick death in a row before it.
const RESTART_PAUSE: Duration = Duration::from_millis(200);
/// How long the launcher waits for the controller's report from the other host: the controller side's grace, its
/// wait for the file and the network, with room.
const REPORT_BACK_WAIT: Duration = Duration::from_secs(6);

impl RemoteBridge {
    /// Start the plant-side bridge listening on `listen` with `security` (its key or `--insecure`, see [`check`])
    /// for the run `args` describes.
    pub(crate) fn start(
        listen: &str,
        security: &[String],
        args: &ProcessArgs,
        events: EventLog,
    ) -> anyhow::Result<Self> {
        let exe = bridge_binary()?;
        let mut argv = vec!["--listen".to_string(), listen.to_string()];
        argv.extend(security.iter().cloned());
        argv.extend(args.to_argv());
        let log = args.out.join("bridge.stderr.log");
        let child = spawn(&exe, &argv, &log)?;
        events.emit(None, "process-started", format!("bridge as pid {}, listening on {listen}", child.pid()));
        let started = Instant::now();
        Ok(Self {
            exe,
            argv,
            log,
            events,
            child,
            restarts: 0,
            started,
            quick_deaths: 0,
            restart_at: None,
            planned_restart_at: None,
            failure: None,
        })
    }

    /// A bridge that died is started again after a pause that doubles while it keeps dying young: the plant flies
    /// on in failsafe meanwhile, and the controller side reconnects to the new one. One that dies young
    /// [`MAX_QUICK_DEATHS`] times in a row is given up on (its log says why).
    pub(crate) fn poll(&mut self) -> anyhow::Result<()> {
        if self.failure.is_some() || silrig_rig::signals::termination_requested() {
            return Ok(());
        }
        if let Some(at) = self.restart_at {
            if Instant::now() >= at {
                self.restart_at = None;
                self.restarts += 1;
                self.child = spawn(&self.exe, &self.argv, &self.log)?;
                self.started = Instant::now();
                let detail = format!("bridge as pid {} (restart {})", self.child.pid(), self.restarts);
                self.events.emit(None, "process-restarted", detail);
            }
            return Ok(());
        }
        let Some(status) = self.child.poll()? else { return Ok(()) };
        if let Some(restart_at) = self.planned_restart_at.take() {
            let detail = format!("bridge {} (planned)", super::child::describe(status));
            self.events.emit(None, "process-ended", detail);
            self.restart_at = Some(restart_at);
            return Ok(());
        }
        let young = self.started.elapsed() < QUICK_DEATH;
        self.quick_deaths = if young { self.quick_deaths + 1 } else { 0 };
        let died = format!("bridge {}", super::child::describe(status));
        self.events.emit(None, "process-died", died.clone());
        if self.quick_deaths >= MAX_QUICK_DEATHS {
            let failure = format!(
                "{died} {MAX_QUICK_DEATHS} times within {QUICK_DEATH:?} of its start; not restarted again (see {}); \
                 the plant flew on in failsafe",
                self.log.display()
            );
            eprintln!("silrig run: {failure}");
            self.failure = Some(failure);
            return Ok(());
        }
        let pause = RESTART_PAUSE * 2u32.pow(self.quick_deaths);
        eprintln!("silrig run: {died}; the controller's commands stop until it is back; restarting it in {pause:?}");
        self.restart_at = Some(Instant::now() + pause);
        Ok(())
    }

    /// The bridge's process, for a fault of the plan.
    pub(crate) fn child_mut(&mut self) -> &mut ChildProcess {
        &mut self.child
    }

    /// A fault of the plan killed or terminated the bridge: restart it at `restart_at`, or after [`RESTART_PAUSE`].
    pub(crate) fn planned_death(&mut self, restart_at: Option<Instant>) {
        self.planned_restart_at = Some(restart_at.unwrap_or_else(|| Instant::now() + RESTART_PAUSE));
    }

    /// Before it is stopped: the controller-side bridge sends the controller's report when the flight ends (after
    /// a grace of 0.5 s, waiting up to 3 s for the controller to write it), and this side writes it into the run's
    /// folder. Wait for it, or for word that there is none, up to [`REPORT_BACK_WAIT`] (only if the plant flew).
    pub(crate) fn wait_for_controller_report(&mut self, out: &Path) {
        let flew = read_events(out).iter().any(|e| e.process == "plant" && e.kind == "ticking");
        let deadline = Instant::now() + REPORT_BACK_WAIT;
        while flew && Instant::now() < deadline && matches!(self.child.poll(), Ok(None)) {
            // The kinds the plant-side bridge emits (silrig-bridge's CONTROLLER_REPORT handling).
            let done = read_events(out).iter().any(|e| {
                e.process == "bridge"
                    && (e.kind == "controller-report-received" || e.kind == "controller-report-absent")
            });
            if done {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// SIGTERM, and reap (SIGKILL after 5 s).
    pub(crate) fn stop(&mut self) -> std::io::Result<()> {
        self.child.signal(libc::SIGTERM);
        self.child.finish(Duration::from_secs(5)).map(|_| ())
    }
}

fn bridge_binary() -> anyhow::Result<PathBuf> {
    let exe = binary_dir()?.join(BRIDGE_BINARY);
    anyhow::ensure!(
        exe.is_file(),
        "--bridge-listen needs {}, which this build does not have: build it with `cargo build --release --features \
         bridge`",
        exe.display()
    );
    Ok(exe)
}

/// Before anything starts: whether the plant-side bridge would start on `listen` with `security` (its key read and
/// owner-only, or no key needed there, or `--insecure`), asked of `silrig-bridge --check`, which owns those rules,
/// and refused in its words. A bridge that could never start would otherwise die three times before the run fails.
pub(crate) fn check(listen: &str, security: &[String], run_id: &str) -> anyhow::Result<()> {
    let exe = bridge_binary()?;
    let o = Command::new(&exe)
        .args(["--check", "--listen", listen])
        .args(security)
        .args(["--run-id", run_id])
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("starting {}", exe.display()))?;
    if o.status.success() {
        return Ok(());
    }
    let said = String::from_utf8_lossy(&o.stderr);
    let said = said.trim().trim_start_matches("silrig-bridge: ").trim_start_matches("error: ");
    anyhow::bail!("--bridge-listen {listen}: {said}")
}

fn spawn(exe: &PathBuf, argv: &[String], log: &PathBuf) -> anyhow::Result<ChildProcess> {
    let file = std::fs::OpenOptions::new().create(true).append(true).open(log)?;
    let mut command = Command::new(exe);
    end_with_launcher(&mut command, libc::SIGTERM);
    let child = command
        .args(argv)
        .stdin(Stdio::null())
        .stdout(file.try_clone()?)
        .stderr(file)
        .spawn()
        .with_context(|| format!("starting {}", exe.display()))?;
    Ok(ChildProcess::new(child))
}
