//! Nothing outlives its run, and an early end is never "clean": `kill -9` of the launcher ends every process it
//! started (a stopped plant included) and the next run removes what they left, saying so; an outside SIGTERM to
//! the plant or the logger fails the run; Ctrl-C and SIGTERM to the launcher stop it with 130 and 143 and say when;
//! a plant restarted after an unplanned `kill -9` continues from its checkpoint. Each test has its own run id and
//! folder, signals only the processes it started (by pid) and checks that no shared memory is left.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

fn temp_dir(test: &str) -> PathBuf {
    common::temp_dir("reliability", test)
}

fn run_id(test: &str) -> String {
    format!("y{}-{test}", std::process::id())
}

fn launch(id: &str, out: &Path, args: &[&str]) -> Child {
    Command::new(SILRIG)
        .args(["run", "--no-baseline", "--run-id", id, "--out", out.to_str().unwrap()])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn signal(pid: u32, sig: libc::c_int) {
    // SAFETY: kill(2) on a process this test started and has not reaped.
    unsafe { libc::kill(pid as libc::pid_t, sig) };
}

/// Gone, or a zombie nobody reaps (the launcher is dead; init reaps it in time).
fn ended(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat.rsplit(')').next().is_some_and(|rest| rest.trim_start().starts_with('Z')),
    }
}

fn children_of(pid: u32) -> Vec<u32> {
    let o = Command::new("pgrep").args(["-P", &pid.to_string()]).output().unwrap();
    String::from_utf8_lossy(&o.stdout).lines().filter_map(|l| l.trim().parse().ok()).collect()
}

/// Wait until the run's plant is ticking (its `ticking` event is in the log).
fn wait_until_ticking(out: &Path) {
    let start = Instant::now();
    while !std::fs::read_to_string(out.join("events.jsonl")).unwrap_or_default().contains("\"ticking\"") {
        assert!(start.elapsed() < Duration::from_secs(30), "the plant never started ticking");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn pid_of(out: &Path, role: &str, launcher: u32) -> u32 {
    let exe = format!("silrig-{role}");
    *children_of(launcher)
        .iter()
        .find(|p| std::fs::read_to_string(format!("/proc/{p}/comm")).is_ok_and(|c| exe.starts_with(c.trim())))
        .unwrap_or_else(|| panic!("no {role} under the launcher (out {})", out.display()))
}

#[test]
fn a_killed_launcher_takes_its_processes_with_it_and_the_next_run_cleans_up_after_them() {
    let dir = temp_dir("kill9");
    let id = run_id("kill9");
    let out = dir.join("run");
    // The plant is stopped (SIGSTOP) when the launcher dies: it cannot act on SIGTERM, and must end all the same.
    let mut launcher = launch(&id, &out, &["--duration-s", "30", "--fault", "plant:stop@1s,for=20s"]);
    wait_until_ticking(&out);
    std::thread::sleep(Duration::from_millis(1500));
    let children = children_of(launcher.id());
    assert_eq!(children.len(), 3, "plant, controller, logger");
    launcher.kill().unwrap();
    launcher.wait().unwrap();
    let start = Instant::now();
    while !children.iter().all(|p| ended(*p)) {
        assert!(start.elapsed() < Duration::from_secs(10), "processes outlived their launcher: {children:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
    // The SIGKILLed plant could not remove its shared memory; the next run does, once it is not fresh.
    std::thread::sleep(silrig::ipc::DEAD_RUN_GRACE + Duration::from_millis(500));
    let next = launch(&run_id("kill9-next"), &dir.join("next"), &["--mode", "lockstep", "--duration-s", "0.3"]);
    let o = wait_with_watchdog(next, Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Another test's run may have cleaned it first; either way nothing of it is left.
    no_shared_memory_left(&id);
    no_shared_memory_left(&run_id("kill9-next"));
    assert!(!Path::new(&format!("/tmp/silrig_{id}.lock")).exists(), "the dead launcher's run-id lock is removed");
    // When this run did the cleaning (and not another test's), it said so.
    let stderr = String::from_utf8_lossy(&o.stderr);
    if stderr.contains(&id) {
        assert!(stderr.contains("silrig run: removed what 1 dead run(s) left on this machine"), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run whose `role` gets SIGTERM from outside (not from the launcher) at about 1 s of 4.
fn outside_sigterm(role: &str) -> (Option<i32>, String) {
    let dir = temp_dir(&format!("term-{role}"));
    let id = run_id(&format!("term-{role}"));
    let out = dir.join("run");
    let launcher = launch(&id, &out, &["--duration-s", "4"]);
    wait_until_ticking(&out);
    std::thread::sleep(Duration::from_secs(1));
    signal(pid_of(&out, role, launcher.id()), libc::SIGTERM);
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into())
}

#[test]
fn an_outside_sigterm_to_the_plant_or_the_logger_is_a_failed_run_not_a_clean_one() {
    for role in ["plant", "logger"] {
        let (code, stdout) = outside_sigterm(role);
        assert_eq!(code, Some(1), "{role}: {stdout}");
        assert!(!stdout.contains("all processes ended cleanly"), "{role}: {stdout}");
        assert!(
            stdout.contains(&format!(
                "FAILED: {role}: ended (terminated by signal; the launcher sent no signal) before the end of the run"
            )),
            "{role}: {stdout}"
        );
    }
}

#[test]
fn ctrl_c_and_sigterm_to_the_launcher_stop_the_run_with_130_and_143_saying_when() {
    for (sig, code, name) in [(libc::SIGINT, 130, "SIGINT"), (libc::SIGTERM, 143, "SIGTERM")] {
        let dir = temp_dir(&format!("stop-{code}"));
        let id = run_id(&format!("stop-{code}"));
        let out = dir.join("run");
        let launcher = launch(&id, &out, &["--duration-s", "10"]);
        wait_until_ticking(&out);
        std::thread::sleep(Duration::from_secs(1));
        signal(launcher.id(), sig);
        let o = wait_with_watchdog(launcher, Duration::from_secs(60));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert_eq!(o.status.code(), Some(code), "{name}: {stdout}{}", String::from_utf8_lossy(&o.stderr));
        assert!(stdout.contains(&format!("stopped by the user ({name}) at t = ")), "{stdout}");
        assert!(stdout.contains(" s of 10.00 s"), "{stdout}");
        assert!(!stdout.contains("FAILED") && !stdout.contains("all processes ended cleanly"), "{stdout}");
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
        assert_eq!(report["stopped_by"]["signal"], name);
        assert!(report["stopped_by"]["at_s"].as_f64().unwrap() < 10.0);
        no_shared_memory_left(&id);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn a_plant_restarted_after_an_unplanned_kill_continues_from_its_checkpoint() {
    let dir = temp_dir("restart");
    let id = run_id("restart");
    let out = dir.join("run");
    let launcher = launch(&id, &out, &["--duration-s", "4", "--restart", "on-failure"]);
    wait_until_ticking(&out);
    std::thread::sleep(Duration::from_secs(2));
    signal(pid_of(&out, "plant", launcher.id()), libc::SIGKILL);
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", String::from_utf8_lossy(&o.stderr));
    let events = std::fs::read_to_string(out.join("events.jsonl")).unwrap();
    assert!(events.contains("\"plant-resumed\""), "no resume from a checkpoint:\n{events}");
    // No splice: the logged time only moves forward, and the flight does not jump back to its start.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let t: Vec<f64> = trace.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert!(t.windows(2).all(|w| w[1] > w[0]), "the trace's time goes back");
    assert!(*t.last().unwrap() > 3.9, "the flight reached its end");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn two_runs_started_together_never_share_a_folder_or_a_run_id() {
    let dir = temp_dir("twice");
    // Realtime, so the two surely overlap (a lockstep second is over in a tenth of a second).
    let quick = ["--duration-s", "1.5"];
    // One folder, two run ids; then one run id, two folders.
    let pairs = [
        ((run_id("twice-a"), dir.join("same")), (run_id("twice-b"), dir.join("same"))),
        ((run_id("twice-c"), dir.join("c")), (run_id("twice-c"), dir.join("d"))),
    ];
    for ((id1, out1), (id2, out2)) in pairs {
        let (a, b) = (launch(&id1, &out1, &quick), launch(&id2, &out2, &quick));
        let (a, b) = (wait_with_watchdog(a, Duration::from_secs(60)), wait_with_watchdog(b, Duration::from_secs(60)));
        let mut codes = [a.status.code(), b.status.code()];
        codes.sort();
        let stderr = format!("{}{}", String::from_utf8_lossy(&a.stderr), String::from_utf8_lossy(&b.stderr));
        assert_eq!(codes, [Some(0), Some(2)], "exactly one of the two runs: {stderr}");
        assert!(
            stderr.contains("is taken by another silrig run")
                || stderr.contains("already holds a run")
                || stderr.contains("is in use by live processes"),
            "{stderr}"
        );
        let winner = if a.status.success() { &out1 } else { &out2 };
        let rows = std::fs::read_to_string(winner.join("trace.csv")).unwrap().lines().count() - 1;
        assert_eq!(rows, 151, "one row per tick, written once");
        no_shared_memory_left(&id1);
        no_shared_memory_left(&id2);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_number_that_enters_is_range_checked_with_our_message_and_exit_2() {
    let dir = temp_dir("ranges");
    let robust = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/robust.toml")).unwrap();
    let flags: [(&[&str], &str); 9] = [
        (&["--command-budget-ms", "0"], "--command-budget-ms must be within 0.01..1000 ms, got 0"),
        (&["--command-budget-ms", "NaN"], "--command-budget-ms must be within 0.01..1000 ms, got NaN"),
        (&["--command-budget-ms", "-1"], "--command-budget-ms must be within 0.01..1000 ms, got -1"),
        (&["--command-spin-us", "1e12"], "--command-spin-us must be within 0..10000 us"),
        (&["--restart-backoff-ms", "nan"], "--restart-backoff-ms must be within 0..60000 ms, got NaN"),
        (&["--startup-timeout-s", "1e30"], "--startup-timeout-s must be within 0.1..3600 s"),
        (&["--fault", "controller:stop@1s,for=1e9s"], "`faults[0].duration_s`: must be at most 10"),
        (&["--fault", "plant:sensor-noise@1s,channel=p_radps,std=1e300"], "`faults[0].std`: must be at most 1000"),
        (&["--fault", "plant:sensor-bias@1s,channel=p_radps,bias=-5000"], "`faults[0].bias`: must be at most 1000"),
    ];
    let edits = [
        ("dt_s = 0.01", "dt_s = 1e-300", "`timing.dt_s`: must be within 0.0001..0.1 s"),
        ("dt_s = 0.01", "dt_s = 1e-4\n", "a run has at most 1000000"),
        (
            "amplitude_radps2 = 0.1",
            "amplitude_radps2 = 1e300",
            "`disturbance.amplitude_radps2`: must be within -100..100",
        ),
        ("max = 25.0", "max = 1e6", "`actuators.elevator_deg`: position limits must lie within -90..90"),
        ("rate_limit_per_s = 60.0", "rate_limit_per_s = 1e9", "`actuators.elevator_deg`: rate limit must be within"),
    ];
    let mut cases: Vec<(Vec<String>, String)> =
        flags.iter().map(|(f, m)| (f.iter().map(|s| s.to_string()).collect(), m.to_string())).collect();
    for (i, (from, to, message)) in edits.iter().enumerate() {
        assert!(robust.contains(from), "{from}");
        let path = dir.join(format!("bad-{i}.toml"));
        // A 10 kHz step is allowed; 200 s of it is two million ticks, which is not.
        let text = if *to == "dt_s = 1e-4\n" {
            robust.replacen(from, "dt_s = 0.0001", 1).replacen("duration_s = 10.0", "duration_s = 200.0", 1)
        } else {
            robust.replacen(from, to, 1)
        };
        std::fs::write(&path, text).unwrap();
        cases.push((vec![path.to_str().unwrap().to_string()], message.to_string()));
    }
    for (args, message) in cases {
        let out = dir.join("never");
        let child = Command::new(SILRIG)
            .arg("run")
            .args(&args)
            .args(["--out", out.to_str().unwrap()])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let o = wait_with_watchdog(child, Duration::from_secs(30));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(&message), "{args:?}: expected {message:?} in {stderr}");
        assert!(!out.exists(), "{args:?}: nothing written");
    }
    let o = Command::new(SILRIG).args(["timer-baseline", "--duration-s", "1e12"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--duration-s must be within 0.01..3600 s"));
    std::fs::remove_dir_all(&dir).unwrap();
}
