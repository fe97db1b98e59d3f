//! The controller's host of a soak with `--bridge`, on this machine: the controller-side bridge
//! (`silrig-bridge --connect`) and our controller in an iceoryx2 namespace of their own (`--local-run-id`), kept
//! running as a person or a service manager on that host would: either one that ends before the flight does is
//! started again (the controller with `--resume`, from its checkpoint).

use anyhow::Context;
use silrig_rig::ProcessArgs;
use silrig_wire::ipc::namespace::RunId;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The controller's host, on this machine.
pub struct ControllerHost {
    bin_dir: PathBuf,
    endpoint: String,
    run_id: String,
    /// The namespace of the controller's half.
    pub local: RunId,
    /// Its folder (`<run folder>/controller-host`).
    pub out: PathBuf,
    bridge: Option<Child>,
    controller: Option<Child>,
    /// How often the bridge and the controller were started.
    pub starts: (u32, u32),
    /// Every pid it started.
    pub pids: super::probe::SeenPids,
}

impl ControllerHost {
    /// The host of run `run_id` whose plant-side bridge listens at `endpoint`; binaries from `bin_dir`.
    pub fn new(bin_dir: &Path, endpoint: &str, run_id: &str, run_out: &Path) -> anyhow::Result<Self> {
        let bridge = bin_dir.join(silrig_launch::remote::BRIDGE_BINARY);
        anyhow::ensure!(
            bridge.is_file(),
            "--bridge needs {}, which this build does not have: build it with `cargo build --release --features \
             bridge`",
            bridge.display()
        );
        let local = RunId::new(&format!("{run_id}-c"))
            .with_context(|| format!("the controller host's namespace for run {run_id} (a run id of 22 at most)"))?;
        Ok(Self {
            bin_dir: bin_dir.to_path_buf(),
            endpoint: endpoint.to_string(),
            run_id: run_id.to_string(),
            local,
            out: run_out.join("controller-host"),
            bridge: None,
            controller: None,
            starts: (0, 0),
            pids: super::probe::SeenPids::new(),
        })
    }

    /// Start what is not running (once the run's folder exists, which the launcher makes). The bridge ends by
    /// itself after the flight, the controller with the plant's last sample, both with success; until the
    /// launcher has ended, any other end of either is a fault, and it is started again.
    pub fn keep_up(&mut self) -> anyhow::Result<()> {
        if !self.out.parent().is_some_and(|p| p.join("events.jsonl").is_file()) {
            return Ok(());
        }
        std::fs::create_dir_all(&self.out)?;
        if needs_start(&mut self.bridge) {
            let argv = [
                "--connect",
                &self.endpoint,
                "--run-id",
                &self.run_id,
                "--local-run-id",
                self.local.as_str(),
                "--out",
                &self.out.display().to_string(),
            ]
            .map(String::from);
            self.bridge = Some(self.spawn("silrig-bridge", &argv, "bridge.stderr.log")?);
            self.starts.0 += 1;
        }
        // The bridge writes the controller's arguments once it has the run from the plant side.
        let env = self.out.join("controller.env");
        if env.is_file() && needs_start(&mut self.controller) {
            let mut args = controller_args(&env)?;
            args.resume = self.starts.1 > 0;
            self.controller = Some(self.spawn("silrig-controller", &args.to_argv(), "controller.stderr.log")?);
            self.starts.1 += 1;
        }
        Ok(())
    }

    /// The bridge and the controller as they are now (their iceoryx2 files are the local namespace's).
    pub fn probes(&self) -> Vec<super::probe::ProcessProbe> {
        let prefix = self.local.prefix();
        [(&self.bridge, "bridge@ctl-host"), (&self.controller, "controller")]
            .into_iter()
            .filter_map(|(child, name)| super::probe::probe(child.as_ref()?.id(), name, &prefix))
            .collect()
    }

    fn spawn(&mut self, program: &str, argv: &[String], log: &str) -> anyhow::Result<Child> {
        let log = std::fs::OpenOptions::new().create(true).append(true).open(self.out.join(log))?;
        let child = Command::new(self.bin_dir.join(program))
            .args(argv)
            .stdin(Stdio::null())
            .stdout(log.try_clone()?)
            .stderr(log)
            .spawn()
            .with_context(|| format!("starting {program} on the controller's host"))?;
        super::probe::note_seen(&mut self.pids, child.id());
        Ok(child)
    }

    /// After the run: the bridge and the controller end by themselves once the flight has ended (the bridge sends
    /// the controller's report first); whatever is still running after `grace` is terminated, then killed, and
    /// reaped, and named in what this returns. The namespace's files are removed.
    pub fn finish(&mut self, grace: Duration) -> Vec<String> {
        let deadline = Instant::now() + grace;
        let mut ended_by_us = Vec::new();
        for (child, name) in [(self.bridge.as_mut(), "bridge"), (self.controller.as_mut(), "controller")] {
            let Some(child) = child else { continue };
            while Instant::now() < deadline && matches!(child.try_wait(), Ok(None)) {
                std::thread::sleep(Duration::from_millis(50));
            }
            if matches!(child.try_wait(), Ok(None)) {
                ended_by_us.push(format!("{name} (pid {})", child.id()));
                // SAFETY: kill(2) on a child of ours that has not been reaped, so its pid is still its own.
                unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
                let term = Instant::now() + Duration::from_secs(3);
                while Instant::now() < term && matches!(child.try_wait(), Ok(None)) {
                    std::thread::sleep(Duration::from_millis(50));
                }
                let _ = child.kill();
            }
            let _ = child.wait();
        }
        let _ = silrig_wire::ipc::namespace::cleanup_run(&self.local);
        ended_by_us
    }
}

/// Whether the child was never started or has ended otherwise than with success (reaped).
fn needs_start(child: &mut Option<Child>) -> bool {
    match child {
        None => true,
        Some(c) => matches!(c.try_wait(), Ok(Some(status)) if !status.success()),
    }
}

/// The controller's arguments from the `controller.env` the controller-side bridge wrote (`export K='V'` lines).
fn controller_args(env: &Path) -> anyhow::Result<ProcessArgs> {
    let text = std::fs::read_to_string(env).with_context(|| format!("reading {}", env.display()))?;
    let vars = text.lines().filter_map(|l| {
        let (k, v) = l.strip_prefix("export ")?.split_once('=')?;
        Some((k.to_string(), v.trim_matches('\'').replace("'\\''", "'")))
    });
    ProcessArgs::from_env(vars).map_err(|e| anyhow::anyhow!("{}: {e}", env.display()))
}
