//! The device's program, when the rig runs it (a SITL): started with the link, its output kept in the run's folder
//! (`device.log`), watched every tick and started again when it dies, up to `max_restarts` times; stopped with the
//! controller, and killed by the kernel if the controller dies first (so no SITL outlives its run holding the
//! ports). In realtime it runs at the controller's real-time priority from its first start: it is the controller, and
//! one left on the normal scheduler answered under half of a 1 kHz loop's packets when the machine was busy (while
//! its restarts, forked once the controller had its priority, answered nearly all).

use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// `[process]` of a layout file: how to start the device.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeviceProcess {
    /// The program and its arguments; a program given as a path (with a `/`) is relative to `working_dir`.
    pub command: Vec<String>,
    /// Where it runs (a SITL keeps its settings there), relative to the layout file's folder.
    pub working_dir: PathBuf,
    /// Restarts allowed after the program dies, before the run fails.
    #[serde(default = "max_restarts")]
    pub max_restarts: u32,
}

fn max_restarts() -> u32 {
    5
}

/// Checking whether the program lives costs a system call: once every this many ns is enough to restart it
/// within a few ticks of its death.
const CHECK_EVERY_NS: u64 = 20_000_000;

/// A started device program.
pub struct Supervisor {
    device: String,
    process: DeviceProcess,
    working_dir: PathBuf,
    log: PathBuf,
    child: Child,
    restarts: u32,
    checked_ns: u64,
    fifo_priority: Option<i32>,
}

impl Supervisor {
    /// Start the program for device `device` (`folder`: the layout file's; `run_dir`: where its log goes), asking
    /// for SCHED_FIFO at `fifo_priority` for it when given (a refusal leaves it on the normal scheduler, as the
    /// controller itself is then).
    pub fn start(
        device: &str,
        process: &DeviceProcess,
        folder: &Path,
        run_dir: &Path,
        fifo_priority: Option<i32>,
    ) -> Result<Self, String> {
        if process.command.is_empty() {
            return Err(format!("device `{device}`: [process] command is empty; give the program and its arguments"));
        }
        let working_dir = folder.join(&process.working_dir);
        if !working_dir.is_dir() {
            return Err(format!(
                "device `{device}`: its working folder {} does not exist (for Betaflight, build and configure it \
                 first: examples/betaflight/setup.sh)",
                working_dir.display()
            ));
        }
        let log = run_dir.join("device.log");
        let child = spawn(device, process, &working_dir, &log, fifo_priority)?;
        Ok(Self {
            device: device.to_string(),
            process: process.clone(),
            working_dir,
            log,
            child,
            restarts: 0,
            checked_ns: 0,
            fifo_priority,
        })
    }

    /// Whether the program was started again since the last call (it had died); an error when it died more often
    /// than allowed or cannot be started.
    pub fn check(&mut self, now_ns: u64) -> Result<bool, String> {
        if now_ns.saturating_sub(self.checked_ns) < CHECK_EVERY_NS {
            return Ok(false);
        }
        self.checked_ns = now_ns;
        let status = match self.child.try_wait() {
            Ok(None) => return Ok(false),
            Ok(Some(status)) => status,
            Err(e) => return Err(format!("device `{}`: cannot watch its program: {e}", self.device)),
        };
        if self.restarts >= self.process.max_restarts {
            return Err(format!(
                "device `{}`: its program {} ended ({status}) after {} restarts; its output is in {}",
                self.device,
                self.process.command[0],
                self.restarts,
                self.log.display()
            ));
        }
        eprintln!("silrig controller: device `{}`: its program ended ({status}); starting it again", self.device);
        self.restarts += 1;
        self.child = spawn(&self.device, &self.process, &self.working_dir, &self.log, self.fifo_priority)?;
        Ok(true)
    }

    /// SIGKILL to the program (a `device:kill` fault): [`Self::check`] then sees it dead and starts it again.
    pub fn kill(&mut self) {
        // SAFETY: signalling our own child by its pid; it is reaped by `check`'s try_wait.
        unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGKILL) };
        // Checked at once on the next tick, not after CHECK_EVERY_NS.
        self.checked_ns = 0;
    }

    /// The program's process id (tests kill it to see it restarted).
    pub fn pid(&self) -> u32 {
        self.child.id()
    }
}

impl Drop for Supervisor {
    fn drop(&mut self) {
        // SAFETY: signalling our own child by its pid; it is reaped right after.
        unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGTERM) };
        let _ = self.child.wait();
    }
}

fn spawn(
    device: &str,
    process: &DeviceProcess,
    working_dir: &Path,
    log: &Path,
    fifo_priority: Option<i32>,
) -> Result<Child, String> {
    let program = &process.command[0];
    let program = if program.contains('/') { working_dir.join(program) } else { PathBuf::from(program) };
    let out = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(log)
        .map_err(|e| format!("device `{device}`: cannot write its log {}: {e}", log.display()))?;
    let err = out.try_clone().map_err(|e| format!("device `{device}`: {e}"))?;
    let mut command = Command::new(&program);
    command.args(&process.command[1..]).current_dir(working_dir).stdin(Stdio::null()).stdout(out).stderr(err);
    // SAFETY: prctl sets this process's parent-death signal and sched_setscheduler its own scheduling (a refusal
    // leaves it as it was); both are plain system calls, and nothing else runs between fork and exec.
    unsafe {
        use std::os::unix::process::CommandExt;
        command.pre_exec(move || {
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM);
            if let Some(priority) = fifo_priority {
                let param = libc::sched_param { sched_priority: priority };
                libc::sched_setscheduler(0, libc::SCHED_FIFO, &param);
            }
            Ok(())
        });
    }
    command
        .spawn()
        .map_err(|e| format!("device `{device}`: cannot start {} in {}: {e}", program.display(), working_dir.display()))
}
