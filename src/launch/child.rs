//! A child process the launcher starts: the rig's binary or a user's command for a role, tied to the launcher's
//! life, its output copied to its log under a cap, reaped exactly once and signalled only until then (a user's
//! command as a whole process group), and its exit status in words.

use crate::program::split_command;
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_rig::ProcessArgs;
use std::os::fd::{AsRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A child process the launcher started: reaped once, signalled only while not reaped.
pub struct ChildProcess {
    child: Handle,
    status: Option<ExitStatus>,
    /// It leads a process group of its own (a user's shell command): signals go to the whole group.
    group: bool,
    /// The thread copying its output to its log ([`forward_output`]).
    output: Option<std::thread::JoinHandle<()>>,
    /// What [`ChildProcess::finish`] had to SIGKILL, in words with the time it waited for it.
    outlasted: Vec<String>,
}

/// How the process came to be: started here, or forked by a warm process of a sweep's rig (and reaped by it).
enum Handle {
    Spawned(std::process::Child),
    Forked(ForkedChild),
}

impl Handle {
    fn id(&self) -> u32 {
        match self {
            Handle::Spawned(child) => child.id(),
            Handle::Forked(child) => child.id(),
        }
    }

    fn try_wait(&mut self) -> std::io::Result<Option<ExitStatus>> {
        match self {
            Handle::Spawned(child) => child.try_wait(),
            Handle::Forked(child) => child.try_wait(),
        }
    }

    fn wait(&mut self) -> std::io::Result<ExitStatus> {
        match self {
            Handle::Spawned(child) => child.wait(),
            Handle::Forked(child) => child.wait(),
        }
    }
}

impl ChildProcess {
    pub(crate) fn new(child: std::process::Child) -> Self {
        Self { child: Handle::Spawned(child), status: None, group: false, output: None, outlasted: Vec::new() }
    }

    /// A child started with `process_group(0)`: signalled as a group, so it and what it started stop together.
    pub(crate) fn group_leader(child: std::process::Child) -> Self {
        Self { child: Handle::Spawned(child), status: None, group: true, output: None, outlasted: Vec::new() }
    }

    /// A flight a warm process forked: it leads a process group of its own, signalled as a group. While it runs
    /// its warm process holds it unreaped, so its pid and group id name it alone.
    pub(crate) fn forked(child: ForkedChild) -> Self {
        Self { child: Handle::Forked(child), status: None, group: true, output: None, outlasted: Vec::new() }
    }

    /// A descriptor that becomes readable when the process ends, while it has not been reaped: a warm process's
    /// socket (it says so there) for a forked flight, none for one started here (its end is seen by polling).
    pub(crate) fn exit_fd(&self) -> Option<std::os::fd::RawFd> {
        match &self.child {
            Handle::Forked(child) if self.status.is_none() => Some(child.socket.as_raw_fd()),
            _ => None,
        }
    }

    pub(crate) fn with_output(mut self, output: std::thread::JoinHandle<()>) -> Self {
        self.output = Some(output);
        self
    }

    /// Once it has ended, give the copy of its output a moment to reach the log, so what it said last is there
    /// when its exit is judged (a grandchild still holding the pipe is not waited for).
    fn let_output_catch_up(&mut self) {
        let deadline = Instant::now() + Duration::from_millis(500);
        while self.output.as_ref().is_some_and(|t| !t.is_finished()) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    pub(crate) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The exit status, reaping the child if it has ended.
    pub fn poll(&mut self) -> std::io::Result<Option<ExitStatus>> {
        if self.status.is_none() {
            self.status = self.child.try_wait()?;
            if self.status.is_some() {
                self.let_output_catch_up();
            }
        }
        Ok(self.status)
    }

    /// Whether process `pid` is this child or, for a user's command, a process of the group it leads (what a
    /// `sh -c` wrapper started): who a node of the run belongs to.
    pub(crate) fn owns(&self, pid: i64) -> bool {
        let own = i64::from(self.child.id());
        pid == own
            || (self.group && libc::pid_t::try_from(pid).ok().and_then(live_group_of) == Some(own as libc::pid_t))
    }

    pub(crate) fn has_ended(&self) -> bool {
        self.status.is_some()
    }

    /// Send `signal` to the process, unless it has ended (its pid may be reused by then).
    pub fn signal(&mut self, signal: libc::c_int) {
        if self.status.is_none() {
            let pid = self.child.id() as libc::pid_t;
            // SAFETY: kill(2) on the pid of a child we have not reaped yet (or the group it leads), so the pid
            // cannot have been reused.
            unsafe {
                libc::kill(if self.group { -pid } else { pid }, signal);
            }
        }
    }

    /// Wait up to `timeout` for the process to end; then SIGKILL it. Always reaps. What had to be killed is noted
    /// ([`ChildProcess::take_outlasted`]).
    pub fn finish(&mut self, timeout: Duration) -> std::io::Result<ExitStatus> {
        let start = Instant::now();
        while self.poll()?.is_none() && start.elapsed() < timeout {
            std::thread::sleep(Duration::from_millis(5));
        }
        if self.status.is_none() {
            let pid = self.child.id();
            let name = process_name(pid as libc::pid_t);
            self.signal(libc::SIGKILL);
            self.status = Some(self.child.wait()?);
            self.let_output_catch_up();
            self.outlasted.push(format!(
                "pid {pid} (`{name}`) did not end when told to: killed after {:.1} s",
                start.elapsed().as_secs_f64()
            ));
        }
        self.end_group_leftovers(timeout);
        Ok(self.status.expect("reaped"))
    }

    /// What [`ChildProcess::finish`] had to SIGKILL (the process, or what its command started), each in words with
    /// the seconds the stop waited for it; empty when everything ended when told.
    pub(crate) fn take_outlasted(&mut self) -> Vec<String> {
        std::mem::take(&mut self.outlasted)
    }

    /// A user's command may leave processes it started (`sh -c "helper & exec my_controller"`) after it ended:
    /// they end with the run. Linux never gives out a pid still used as a process group id, so while any process
    /// sits in the group the id names this group alone; SIGTERM, then SIGKILL past `timeout`.
    fn end_group_leftovers(&mut self, timeout: Duration) {
        let pgid = self.child.id() as libc::pid_t;
        if !self.group {
            return;
        }
        let start = Instant::now();
        let mut signal = libc::SIGTERM;
        let mut killed = Vec::new();
        loop {
            let members = members_of_group(pgid);
            if members.is_empty() {
                break;
            }
            if signal == libc::SIGKILL && killed.is_empty() {
                killed = members.iter().map(|pid| format!("pid {pid} (`{}`)", process_name(*pid))).collect();
            }
            // SAFETY: kill(2) on a process group that still has members (see above), so it is this group.
            unsafe { libc::kill(-pgid, signal) };
            if start.elapsed() >= timeout {
                signal = libc::SIGKILL;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        if !killed.is_empty() {
            self.outlasted.push(format!(
                "{} of its command ignored SIGTERM: killed after {:.1} s",
                killed.join(", "),
                start.elapsed().as_secs_f64()
            ));
        }
    }
}

/// Wait until one of `fds` is readable (a forked flight ended: [`ChildProcess::exit_fd`]) or `timeout` passed. A
/// sweep's launcher wakes as a case's process ends, instead of up to a polling period later (5 ms a case).
pub(crate) fn wait_for_an_exit(fds: &[std::os::fd::RawFd], timeout: Duration) {
    if fds.is_empty() {
        std::thread::sleep(timeout);
        return;
    }
    let mut polls: Vec<libc::pollfd> =
        fds.iter().map(|&fd| libc::pollfd { fd, events: libc::POLLIN, revents: 0 }).collect();
    // SAFETY: poll on descriptors the caller's processes own, for at most `timeout`.
    unsafe { libc::poll(polls.as_mut_ptr(), polls.len() as libc::nfds_t, timeout.as_millis() as libc::c_int) };
}

/// A process's name as the kernel keeps it (`/proc/<pid>/comm`), or `?` once it has gone.
fn process_name(pid: libc::pid_t) -> String {
    std::fs::read_to_string(format!("/proc/{pid}/comm")).map_or_else(|_| "?".into(), |c| c.trim().to_string())
}

/// The process group of a live process (from `/proc/<pid>/stat`); `None` for a zombie or a process gone.
fn live_group_of(pid: libc::pid_t) -> Option<libc::pid_t> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // After the command in parentheses (which may hold spaces): state, ppid, pgrp.
    let fields: Vec<&str> = stat.rsplit_once(')').map_or("", |(_, rest)| rest).split_whitespace().collect();
    if fields.first().is_none_or(|state| *state == "Z") {
        return None;
    }
    fields.get(2)?.parse().ok()
}

/// The live processes in process group `pgid` (zombies, which init reaps, left out).
fn members_of_group(pgid: libc::pid_t) -> Vec<libc::pid_t> {
    // A group with no process at all (what nearly every run's end finds) is told by one kill(2), without reading
    // the stat of every process on the machine (hundreds of files, milliseconds of a sweep's every case).
    // SAFETY: signal 0 only checks that the group exists; nothing is sent.
    if unsafe { libc::kill(-pgid, 0) } != 0 && std::io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH) {
        return Vec::new();
    }
    let Ok(entries) = std::fs::read_dir("/proc") else { return Vec::new() };
    entries
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<libc::pid_t>().ok())
        .filter(|pid| live_group_of(*pid) == Some(pgid))
        .collect()
}

/// The child gets `signal` when the launcher dies, however it dies (`kill -9` included), so nothing outlives its
/// run. Linux ties the signal to the thread that forked the child: the launcher starts and restarts every process
/// from its main thread, which lives as long as the launcher. It ignores SIGHUP: a closed terminal hangs up the
/// launcher, which stops its processes with SIGTERM as for any stop, reports and removes its locks; a hangup
/// reaching them too would end them behind its back.
pub(crate) fn end_with_launcher(command: &mut Command, signal: libc::c_int) {
    use std::os::unix::process::CommandExt;
    let launcher = std::process::id() as libc::pid_t;
    // SAFETY: the closure runs in the child between fork and exec and calls only async-signal-safe functions
    // (prctl, getppid, raise, signal).
    unsafe {
        command.pre_exec(move || {
            silrig_rig::signals::ignore_hangup();
            libc::prctl(libc::PR_SET_PDEATHSIG, signal as libc::c_ulong, 0, 0, 0);
            // The launcher may have died between fork and prctl: then the signal never comes, so send it now.
            if libc::getppid() != launcher {
                libc::raise(signal);
            }
            Ok(())
        });
    }
}

/// Start `role`'s process of the run `args` describes, tied to this process's life ([`end_with_launcher`]): the
/// rig binary from `bin_dir`, or a user's `command` for the role (`--controller-cmd`, `--plant-cmd`) with the run's
/// `SILRIG_*` variables, in a process group of its own so a stop or kill fault reaches whatever it started.
/// `extra_args` follow the run's arguments on the rig binary's command line (the logger's `--live-foxglove`).
pub fn start_process(
    role: Role,
    command: Option<&str>,
    args: &ProcessArgs,
    extra_args: &[String],
    bin_dir: &Path,
    stdout: Stdio,
    stderr: Stdio,
) -> anyhow::Result<ChildProcess> {
    let (mut process, group) = process_command(role, command, args, extra_args, bin_dir)?;
    let what = match command {
        Some(cmd) => format!("starting the {role} command `{cmd}`"),
        None => format!("starting {} (build it with `cargo build --release`)", bin_dir.join(role.binary()).display()),
    };
    let child = process.stdin(Stdio::null()).stdout(stdout).stderr(stderr).spawn().context(what)?;
    Ok(if group { ChildProcess::group_leader(child) } else { ChildProcess::new(child) })
}

/// The command that starts `role`'s process (see [`start_process`]), tied to this process's life, and whether it
/// leads a process group of its own (a user's command does).
pub(crate) fn process_command(
    role: Role,
    command: Option<&str>,
    args: &ProcessArgs,
    extra_args: &[String],
    bin_dir: &Path,
) -> anyhow::Result<(Command, bool)> {
    if let Some(cmd) = command {
        use std::os::unix::process::CommandExt;
        let words = split_command(cmd).map_err(|e| anyhow::anyhow!("--{role}-cmd: {e}"))?;
        let mut command = Command::new(&words[0]);
        end_with_launcher(&mut command, libc::SIGTERM);
        command.args(&words[1..]).envs(process_env(args, bin_dir)).process_group(0);
        return Ok((command, true));
    }
    let mut command = Command::new(bin_dir.join(role.binary()));
    end_with_launcher(&mut command, death_signal(role));
    command.args(args.to_argv()).args(extra_args);
    Ok((command, false))
}

/// The variables a user's command gets: the run's, and where the client library is.
pub(crate) fn process_env(args: &ProcessArgs, bin_dir: &Path) -> Vec<(String, String)> {
    let mut env = args.to_env();
    env.push(("SILRIG_CLIENT_LIB".into(), bin_dir.join("libsilrig_client.so").display().to_string()));
    env
}

/// The signal a process gets when its launcher dies. A stopped plant cannot act on SIGTERM until continued, and
/// nobody is left to continue it: it gets SIGKILL (the next run removes what it leaves); the others end cleanly on
/// SIGTERM, writing what they hold.
pub(crate) fn death_signal(role: Role) -> libc::c_int {
    if role == Role::Plant { libc::SIGKILL } else { libc::SIGTERM }
}

/// Copy a child's output (stdout and stderr, one pipe) into `log_path` line by line. When the log cannot be
/// written (a full disk), the rest goes to the launcher's own stderr after one line saying why, so nothing the
/// process said is lost; the child itself never sees the failure, and never dies writing its error to a full disk.
/// Largest `<role>.stderr.log`, bytes: a process that writes without end (100 KB a tick is 6 GB in ten minutes)
/// must not fill the disk the trace is written to. Past it lines are counted, and the count closes the log.
pub const STDERR_LOG_CAP_BYTES: u64 = 16 << 20;

pub(crate) fn forward_output(
    reader: std::io::PipeReader,
    log_path: PathBuf,
    role: Role,
    marker: Option<String>,
) -> std::thread::JoinHandle<()> {
    use std::io::{BufRead, Write};
    std::thread::spawn(move || {
        let mut log = std::fs::OpenOptions::new().create(true).append(true).open(&log_path);
        let mut to_log = |line: &[u8]| -> std::io::Result<()> {
            let file = log.as_mut().map_err(|e| std::io::Error::new(e.kind(), e.to_string()))?;
            let before = file.metadata()?.len();
            let mut whole = line.to_vec();
            whole.push(b'\n');
            // A line the disk takes only in part is cut back out.
            file.write_all(&whole).inspect_err(|_| {
                let _ = file.set_len(before);
            })
        };
        let mut failed = false;
        // A restarted process appends to its predecessor's log: the cap counts what is there already.
        let mut logged = std::fs::metadata(&log_path).map_or(0, |m| m.len());
        let (mut dropped_bytes, mut dropped_lines) = (0u64, 0u64);
        for line in
            marker.into_iter().map(String::into_bytes).map(Ok).chain(std::io::BufReader::new(reader).split(b'\n'))
        {
            let Ok(line) = line else { break };
            if logged + line.len() as u64 + 1 > STDERR_LOG_CAP_BYTES {
                if dropped_lines == 0 {
                    let cap_mib = STDERR_LOG_CAP_BYTES >> 20;
                    let _ = to_log(
                        format!("--- silrig run: this log reached its cap of {cap_mib} MiB; what follows is counted, not kept ---")
                            .as_bytes(),
                    );
                }
                dropped_lines += 1;
                dropped_bytes += line.len() as u64 + 1;
                continue;
            }
            logged += line.len() as u64 + 1;
            if !failed && let Err(e) = to_log(&line) {
                failed = true;
                let _ = writeln!(
                    std::io::stderr(),
                    "silrig run: cannot write {}: {e}; what the {role} says follows here",
                    log_path.display()
                );
            }
            if failed {
                let _ = writeln!(std::io::stderr(), "silrig run: {role}: {}", String::from_utf8_lossy(&line));
            }
        }
        if dropped_lines > 0 {
            let _ = to_log(
                format!("--- silrig run: {dropped_lines} lines ({dropped_bytes} bytes) past the cap were dropped ---")
                    .as_bytes(),
            );
        }
    })
}

/// A process a warm program forked; its warm program reaps it and says how it ended.
pub struct ForkedChild {
    pid: u32,
    socket: Arc<OwnedFd>,
    status: Option<ExitStatus>,
}

impl ForkedChild {
    pub(crate) fn new(pid: u32, socket: Arc<OwnedFd>) -> Self {
        Self { pid, socket, status: None }
    }

    pub(crate) fn id(&self) -> u32 {
        self.pid
    }

    /// Its exit status once its warm program has said it ended; a warm program that is gone took it with it
    /// (killed: the flight dies with its warm program).
    pub(crate) fn try_wait(&mut self) -> std::io::Result<Option<ExitStatus>> {
        use std::os::unix::process::ExitStatusExt;
        if self.status.is_some() {
            return Ok(self.status);
        }
        let mut poll = libc::pollfd { fd: self.socket.as_raw_fd(), events: libc::POLLIN, revents: 0 };
        // SAFETY: poll on one valid descriptor, without waiting.
        if unsafe { libc::poll(&mut poll, 1, 0) } <= 0 {
            return Ok(None);
        }
        let raw = match silrig_rig::warm::receive(&self.socket)? {
            None => libc::SIGKILL,
            Some((text, _)) => {
                let text = String::from_utf8_lossy(&text).into_owned();
                let mut words = text.split(' ');
                match (words.next(), words.next().and_then(|p| p.parse::<u32>().ok()), words.next()) {
                    (Some("exited"), Some(pid), Some(status)) if pid == self.pid => {
                        status.parse::<i32>().map_err(|e| std::io::Error::other(format!("`{text}`: {e}")))?
                    }
                    _ => return Err(std::io::Error::other(format!("a warm program said `{text}` out of turn"))),
                }
            }
        };
        self.status = Some(ExitStatus::from_raw(raw));
        Ok(self.status)
    }

    pub(crate) fn wait(&mut self) -> std::io::Result<ExitStatus> {
        loop {
            if let Some(status) = self.try_wait()? {
                return Ok(status);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

/// An exit status as a person reads it.
pub fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exit status {c}"),
        (None, Some(s)) => format!("killed by signal {s}"),
        _ => "ended".into(),
    }
}
