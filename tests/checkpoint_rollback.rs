//! A restarted plant goes back at most one checkpoint interval, however loaded the machine: the plant killed at
//! seeded random ticks, several times in one run, while the test keeps the run's CPU busy with a real-time
//! busy loop (the load that starved the checkpoint file's writer thread and made a restart fly up to 98 ticks
//! again), each rollback read from report.json and bounded by `CHECKPOINT_EVERY_TICKS`. A correctness bound, not a
//! timing one: the number of ticks flown again does not depend on how fast anything ran.

use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

mod common;
use common::{no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const CHECKPOINT_EVERY_TICKS: u64 = silrig::rig::plant::CHECKPOINT_EVERY_TICKS;

/// Seeded kill times: `n` ticks in [100, 500) of a 100 Hz flight, at least 100 ticks apart (room for a restart).
fn kill_ticks(seed: u64, n: usize) -> Vec<u64> {
    let mut rng = silrig::rng::SplitMix64::new(seed);
    (0..n as u64).map(|i| 100 + i * 130 + rng.next_u64() % 30).collect()
}

/// Pin the calling thread (and what it starts) to `cpu`.
fn pin_to(cpu: usize) {
    // SAFETY: a zeroed cpu_set_t is valid; CPU_SET and sched_setaffinity on the calling thread (0) with its size.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
}

/// A busy loop on `cpu` until `stop`, at SCHED_FIFO 1 where allowed (above every normal thread on that CPU, below
/// the rig's plant and controller; the kernel's throttling leaves normal threads 5 % of it), else a normal one.
fn busy_loop(cpu: usize, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<bool> {
    std::thread::spawn(move || {
        pin_to(cpu);
        let param = libc::sched_param { sched_priority: 1 };
        // SAFETY: sched_setscheduler on the calling thread with a valid parameter.
        let realtime = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } == 0;
        while !stop.load(Ordering::Relaxed) {
            std::hint::spin_loop();
        }
        realtime
    })
}

#[test]
fn a_plant_killed_at_random_ticks_under_load_flies_again_at_most_one_checkpoint_interval() {
    let dir = common::temp_dir("checkpoint-rollback", "kills");
    let id = format!("ck{}-kills", std::process::id());
    let out = dir.join("run");
    let ticks = kill_ticks(45, 3);
    let faults: Vec<String> =
        ticks.iter().map(|t| format!("plant:kill@{:.2}s,restart_after=0.2s", *t as f64 * 0.01)).collect();
    let cpu = std::thread::available_parallelism().map_or(0, |n| n.get() - 1);
    let stop = Arc::new(AtomicBool::new(false));
    let load = busy_loop(cpu, stop.clone());
    let mut cmd = Command::new(SILRIG);
    cmd.args(["run", "--no-baseline", "--duration-s", "6", "--run-id", &id, "--out", out.to_str().unwrap()]);
    for f in &faults {
        cmd.args(["--fault", f]);
    }
    // The whole run on the busy CPU: its normal threads (the checkpoint file's writer, the launcher, the logger)
    // get what the busy loop leaves.
    use std::os::unix::process::CommandExt;
    // SAFETY: only sched_setaffinity, async-signal-safe, between fork and exec.
    unsafe { cmd.pre_exec(move || Ok(pin_to(cpu))) };
    let launcher = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let o = wait_with_watchdog(launcher, Duration::from_secs(120));
    stop.store(true, Ordering::Relaxed);
    let realtime_load = load.join().unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "kills at ticks {ticks:?}:\n{text}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let resumes = report["plant_resumes"].as_array().unwrap();
    assert_eq!(resumes.len(), ticks.len(), "one resume per kill: {resumes:?}\n{text}");
    for (f, resume) in report["faults"].as_array().unwrap().iter().zip(resumes) {
        let again = resume["ticks_flown_again"].as_u64().unwrap_or_else(|| panic!("unknown rollback: {resume}"));
        assert!(
            again <= CHECKPOINT_EVERY_TICKS,
            "{}: {again} ticks flown again, more than the checkpoint interval (load at SCHED_FIFO: {realtime_load})",
            f["fault"]
        );
        assert_eq!(&f["plant_resume"], resume, "the fault's row says its own resume");
        let line = format!("resumed at tick {}, {again} ticks flown again", resume["at_tick"]);
        assert!(text.contains(&line), "the fault table says `{line}`:\n{text}");
    }
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_seeded_kill_ticks_are_spread_over_the_flight() {
    let ticks = kill_ticks(45, 3);
    assert_eq!(ticks, kill_ticks(45, 3), "the same seed, the same kills");
    assert!(ticks.windows(2).all(|w| w[1] >= w[0] + 100) && ticks[2] < 500, "{ticks:?}");
}
