//! A sweep's warm rig: the plant, logger and controller programs started once ([`WarmRig::start`]) and kept
//! warm, each forking every case's process from the state it reached when it first opened its session
//! (`silrig_rig::warm` is their side). The launcher flies a case through a warm rig exactly as through fresh
//! processes ([`super::launcher::run_with`]): the same command lines and variables, the same output logs, lives,
//! exits and reports; only the program's start (exec, the dynamic linker, an interpreter and its imports) is not
//! paid again. A program that never says it is ready (a peer that speaks the contract without silrig's
//! libraries) has no warm rig: [`WarmRig::start`] says so and the sweep flies it cold.

use crate::child::{ChildProcess, ForkedChild, death_signal, process_command, process_env};
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_rig::ProcessArgs;
use silrig_rig::warm::{self, FlightRequest, WARM_FD_ENV};
use std::os::fd::{AsRawFd, OwnedFd};
use std::path::Path;
use std::process::Stdio;
use std::sync::Arc;
use std::time::Duration;

/// The descriptor a warm process finds its socket on.
const WARM_FD: i32 = 3;

/// One program kept warm for a role.
pub struct WarmProcess {
    socket: Arc<OwnedFd>,
    process: ChildProcess,
    /// The user's command it runs (`None`: the rig's binary).
    command: Option<String>,
}

/// The three warm programs of one rig (the roles a sweep flies).
pub struct WarmRig {
    processes: Vec<(Role, WarmProcess)>,
}

impl WarmRig {
    /// Start every role's program (`commands`: the user's controller and plant commands, else the rig's binaries)
    /// with `args` and wait up to `ready_within` for each to say it is ready. Their own output goes to
    /// `<dir>/<role>.warm.log`. An `Err` says, in words, which program did not become warm and why.
    pub fn start(
        commands: (Option<&str>, Option<&str>),
        args: &ProcessArgs,
        dir: &Path,
        ready_within: Duration,
    ) -> anyhow::Result<Self> {
        let bin_dir = crate::program::binary_dir()?;
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let mut processes = Vec::new();
        for role in [Role::Logger, Role::Controller, Role::Plant] {
            let command = match role {
                Role::Controller => commands.0,
                Role::Plant => commands.1,
                _ => None,
            };
            let log = std::fs::File::create(dir.join(format!("{role}.warm.log")))?;
            let process = WarmProcess::start(role, command, args, &bin_dir, log, ready_within)?;
            processes.push((role, process));
        }
        Ok(Self { processes })
    }

    /// The warm program of `role`.
    pub fn process(&self, role: Role) -> Option<&WarmProcess> {
        self.processes.iter().find(|(r, _)| *r == role).map(|(_, p)| p)
    }
}

impl Drop for WarmRig {
    /// Closing their sockets ends the warm programs; each is reaped (SIGKILL after a second).
    fn drop(&mut self) {
        for (_, p) in &mut self.processes {
            // SAFETY: shutdown on a socket this rig owns; the warm program reads the end of its requests.
            unsafe { libc::shutdown(p.socket.as_raw_fd(), libc::SHUT_RDWR) };
        }
        for (_, p) in &mut self.processes {
            p.process.signal(libc::SIGTERM);
            let _ = p.process.finish(Duration::from_secs(1));
        }
    }
}

impl WarmProcess {
    fn start(
        role: Role,
        command: Option<&str>,
        args: &ProcessArgs,
        bin_dir: &Path,
        log: std::fs::File,
        ready_within: Duration,
    ) -> anyhow::Result<Self> {
        use std::os::unix::process::CommandExt;
        let (ours, theirs) = warm::socket_pair().context("creating a warm program's socket")?;
        let (mut process, group) = process_command(role, command, args, &[], bin_dir)?;
        let fd = theirs.as_raw_fd();
        // SAFETY: between fork and exec, dup2 and fcntl only (async-signal-safe), on a descriptor this process
        // owns until the child has started.
        unsafe {
            process.pre_exec(move || {
                if fd == WARM_FD {
                    libc::fcntl(fd, libc::F_SETFD, 0);
                } else if libc::dup2(fd, WARM_FD) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let what = command.map_or_else(|| role.binary().to_string(), |c| format!("the {role} command `{c}`"));
        let child = process
            .env(WARM_FD_ENV, WARM_FD.to_string())
            .stdin(Stdio::null())
            .stdout(log.try_clone()?)
            .stderr(log)
            .spawn()
            .with_context(|| format!("starting {what}"))?;
        drop(theirs);
        let process = if group { ChildProcess::group_leader(child) } else { ChildProcess::new(child) };
        let mut warm = Self { socket: Arc::new(ours), process, command: command.map(str::to_owned) };
        warm.wait_ready(&what, ready_within)?;
        Ok(warm)
    }

    /// Wait for `ready`: a program that ends first, or says nothing in time, is not warm.
    fn wait_ready(&mut self, what: &str, within: Duration) -> anyhow::Result<()> {
        let mut poll = libc::pollfd { fd: self.socket.as_raw_fd(), events: libc::POLLIN, revents: 0 };
        // SAFETY: poll on one valid descriptor.
        let ready = unsafe { libc::poll(&mut poll, 1, within.as_millis() as i32) };
        let said = if ready > 0 { warm::receive(&self.socket)?.map(|(text, _)| text) } else { None };
        match said {
            Some(text) if text == b"ready" => Ok(()),
            _ => {
                self.process.signal(libc::SIGKILL);
                let _ = self.process.finish(Duration::from_secs(1));
                anyhow::bail!(
                    "{what} did not become warm within {:.1} s (a program opens its session through silrig's \
                     libraries to fly warm: the C ABI, the Python package, the Rust crates)",
                    within.as_secs_f64()
                )
            }
        }
    }

    /// Fork `role`'s process of the run `args` describes, as [`crate::child::start_process`] would start it, its
    /// output to `output`.
    pub(crate) fn fly(
        &self,
        role: Role,
        command: Option<&str>,
        args: &ProcessArgs,
        extra_args: &[String],
        bin_dir: &Path,
        output: OwnedFd,
    ) -> anyhow::Result<ChildProcess> {
        anyhow::ensure!(
            command == self.command.as_deref(),
            "the warm {role} runs {:?}, not {command:?}: a warm rig flies the commands it was started with",
            self.command
        );
        let mut argv = vec![bin_dir.join(role.binary()).display().to_string()];
        argv.extend(args.to_argv());
        argv.extend_from_slice(extra_args);
        let env = if command.is_some() { process_env(args, bin_dir) } else { Vec::new() };
        let request = FlightRequest { argv, env, pdeathsig: death_signal(role) };
        let text = serde_json::to_vec(&request)?;
        let lost = |e: std::io::Error| anyhow::anyhow!("the warm {role} is gone ({e}): its rig is started again");
        warm::send_with_fd(&self.socket, &text, Some(output.as_raw_fd())).map_err(lost)?;
        drop(output);
        let reply = warm::receive(&self.socket).map_err(lost)?;
        let pid = reply
            .and_then(|(text, _)| String::from_utf8(text).ok()?.strip_prefix("started ")?.parse::<u32>().ok())
            .ok_or_else(|| {
                anyhow::anyhow!("the warm {role} did not fork the case's process: its rig is started again")
            })?;
        Ok(ChildProcess::forked(ForkedChild::new(pid, Arc::clone(&self.socket))))
    }
}
