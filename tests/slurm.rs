//! The sweep on a real Slurm: this test starts a one-node cluster of its own (munged if none runs, slurmctld and
//! slurmd with a configuration and state in a temporary folder), plans a sweep, submits the array script
//! `silrig sweep slurm` writes, merges the shards and compares the outputs with the same sweep on this machine,
//! byte for byte, then the same with a user's controller (`--controller-cmd`) flown through the lockstep rig. It
//! stops what it started, by pid, even when it fails, and leaves a Slurm or munge that was already running alone
//! (it reuses munged; with a slurmctld already running it does not run). `.ci/run` installs slurm-wlm and munge;
//! elsewhere, without them, the test says so and passes only outside CI.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const CONFIG: &str = "configs/sweep-robust.toml";

fn found(program: &str) -> bool {
    Command::new("sh").arg("-c").arg(format!("command -v {program}")).output().is_ok_and(|o| o.status.success())
}

fn running(name: &str) -> bool {
    Command::new("pgrep").args(["-x", name]).output().is_ok_and(|o| o.status.success())
}

fn read_pid(path: &Path) -> Option<i32> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

fn alive(pid: i32) -> bool {
    // SAFETY: kill with signal 0 only checks that the process exists.
    unsafe { libc::kill(pid, 0) == 0 }
}

/// The daemons this test started, stopped by pid when it ends, however it ends.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    pid_files: Vec<PathBuf>,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let pids: Vec<i32> = self.pid_files.iter().filter_map(|p| read_pid(p)).collect();
        for pid in &pids {
            // SAFETY: signalling a daemon this test started, by the pid it wrote.
            unsafe { libc::kill(*pid, libc::SIGTERM) };
        }
        let deadline = Instant::now() + Duration::from_secs(10);
        while pids.iter().any(|p| alive(*p)) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(50));
        }
        for pid in pids.iter().filter(|p| alive(**p)) {
            // SAFETY: as above; it did not stop on SIGTERM.
            unsafe { libc::kill(*pid, libc::SIGKILL) };
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl Cluster {
    fn slurm(&self, program: &str, args: &[&str]) -> std::process::Output {
        Command::new(program).args(args).env("SLURM_CONF", &self.conf).output().unwrap()
    }

    /// munged (unless one runs), slurmctld and slurmd; waits until the node is idle.
    fn start() -> Cluster {
        let dir = std::env::temp_dir().join(format!("silrig-slurm-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for sub in ["state", "spool", "log", "run"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let mut cluster = Cluster { conf: dir.join("slurm.conf"), dir: dir.clone(), pid_files: Vec::new() };
        if !running("munged") {
            for d in ["/etc/munge", "/var/lib/munge", "/var/log/munge", "/run/munge"] {
                std::fs::create_dir_all(d).unwrap();
            }
            if !Path::new("/etc/munge/munge.key").exists() {
                assert!(Command::new("mungekey").arg("-c").status().unwrap().success(), "mungekey -c");
            }
            assert!(Command::new("munged").arg("--force").status().unwrap().success(), "munged --force");
            cluster.pid_files.push("/run/munge/munged.pid".into());
        }
        let host = String::from_utf8(Command::new("hostname").arg("-s").output().unwrap().stdout).unwrap();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let d = dir.display();
        let conf = format!(
            "ClusterName=silrigtest\nSlurmctldHost={host}\nSlurmUser=root\nSlurmdUser=root\nAuthType=auth/munge\n\
             StateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\nSlurmctldPidFile={d}/run/slurmctld.pid\n\
             SlurmdPidFile={d}/run/slurmd.pid\nSlurmctldLogFile={d}/log/slurmctld.log\nSlurmdLogFile={d}/log/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\nSchedulerType=sched/backfill\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\nReturnToService=2\nMpiDefault=none\n\
             JobAcctGatherType=jobacct_gather/none\nNodeName={host} CPUs={cpus} State=UNKNOWN\n\
             PartitionName=debug Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            host = host.trim()
        );
        std::fs::write(&cluster.conf, conf).unwrap();
        let conf_path = cluster.conf.to_str().unwrap().to_string();
        cluster.pid_files.push(dir.join("run/slurmctld.pid"));
        assert!(Command::new("slurmctld").args(["-c", "-f", &conf_path]).status().unwrap().success(), "slurmctld");
        cluster.pid_files.push(dir.join("run/slurmd.pid"));
        assert!(Command::new("slurmd").args(["-f", &conf_path]).status().unwrap().success(), "slurmd");
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let o = cluster.slurm("sinfo", &["-h", "-o", "%T"]);
            if String::from_utf8_lossy(&o.stdout).trim() == "idle" {
                break;
            }
            assert!(
                Instant::now() < deadline,
                "the node never became idle: {}{}\nslurmctld.log:\n{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr),
                std::fs::read_to_string(dir.join("log/slurmctld.log")).unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(250));
        }
        cluster
    }
}

fn silrig(args: &[&str]) -> String {
    let o = Command::new(SILRIG).args(args).current_dir(ROOT).output().unwrap();
    assert!(
        o.status.success(),
        "silrig {args:?}: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into()
}

#[test]
fn a_sweep_run_as_a_slurm_array_job_merges_into_the_single_machine_sweep() {
    let missing: Vec<&str> =
        ["sbatch", "sinfo", "slurmctld", "slurmd", "munged", "mungekey"].into_iter().filter(|p| !found(p)).collect();
    if !missing.is_empty() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have Slurm (.ci/run installs slurm-wlm and munge): {missing:?}"
        );
        eprintln!("skipped: {} not installed (apt-get install slurm-wlm munge)", missing.join(", "));
        return;
    }
    if running("slurmctld") || running("slurmd") {
        assert!(std::env::var_os("CI").is_none(), "a Slurm is already running on the CI machine");
        eprintln!("skipped: a Slurm already runs on this machine, and this test does not disturb it");
        return;
    }
    let cluster = Cluster::start();
    let sweep_dir = cluster.dir.join("sweep");
    let local_dir = cluster.dir.join("local");
    let (sweep, local) = (sweep_dir.to_str().unwrap(), local_dir.to_str().unwrap());
    silrig(&["sweep", "plan", CONFIG, "--runs", "60", "--shards", "4", "--out", sweep]);
    silrig(&["sweep", "slurm", sweep]);
    let script = sweep_dir.join("sweep.sbatch");
    let submitted = cluster.slurm("sbatch", &["--wait", script.to_str().unwrap()]);
    let logs: String = (0..4)
        .map(|k| std::fs::read_to_string(sweep_dir.join(format!("logs/shard-{k}.log"))).unwrap_or_default())
        .collect();
    assert!(
        submitted.status.success(),
        "sbatch --wait: {}{}\ntask logs:\n{logs}",
        String::from_utf8_lossy(&submitted.stdout),
        String::from_utf8_lossy(&submitted.stderr)
    );
    for k in 0..4 {
        assert!(
            sweep_dir.join(format!("shards/shard-{k}-of-4.json")).exists(),
            "shard {k} written by its task:\n{logs}"
        );
    }
    silrig(&["sweep", "merge", sweep]);
    silrig(&["sweep", CONFIG, "--runs", "60", "--out", local]);
    same_outputs(&sweep_dir, &local_dir);

    // A user's controller through the rig: the plan carries the command, the script runs it from here (a path
    // relative to the repository), each task flies its cases through lockstep rigs.
    common::client_lib(SILRIG);
    let pid = "python3 examples/python/pid_attitude.py";
    let rig_dir = cluster.dir.join("rig-sweep");
    let rig_local = cluster.dir.join("rig-local");
    let rig = rig_dir.to_str().unwrap();
    silrig(&["sweep", "plan", CONFIG, "--runs", "6", "--shards", "2", "--controller-cmd", pid, "--out", rig]);
    silrig(&["sweep", "slurm", rig]);
    let submitted = cluster.slurm("sbatch", &["--wait", rig_dir.join("sweep.sbatch").to_str().unwrap()]);
    let logs: String = (0..2)
        .map(|k| std::fs::read_to_string(rig_dir.join(format!("logs/shard-{k}.log"))).unwrap_or_default())
        .collect();
    assert!(submitted.status.success(), "sbatch --wait (rig sweep): {logs}");
    silrig(&["sweep", "merge", rig]);
    silrig(&["sweep", CONFIG, "--runs", "6", "--controller-cmd", pid, "--out", rig_local.to_str().unwrap()]);
    same_outputs(&rig_dir, &rig_local);
}

/// The merged sweep in `merged` is the single-machine sweep in `local`, byte for byte.
fn same_outputs(merged: &Path, local: &Path) {
    for file in ["cases.csv", "sweep.json"] {
        let (a, b) = (std::fs::read(merged.join(file)).unwrap(), std::fs::read(local.join(file)).unwrap());
        assert!(a == b, "{file}: the merged sweep differs from the single-machine sweep");
    }
}
