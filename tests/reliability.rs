//! Nothing outlives its run, and an early end is never "clean": `kill -9` of the launcher ends every process it
//! started (a stopped plant included) and the next run removes what they left, saying so; an outside SIGTERM to
//! the plant or the logger fails the run; Ctrl-C and SIGTERM to the launcher stop it with 130 and 143 and say when;
//! a plant restarted after an unplanned `kill -9` continues from its checkpoint, and one restarted between two
//! checkpoints marks where the flights join; damaged checkpoints are refused; every life of a process is in the
//! report; a dead peer is cleaned up by the launcher. Each test has its own run id and
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
    launch_with(&["--no-baseline"], id, out, args)
}

/// `silrig run` with `flags` (the default configuration with none).
fn launch_with(flags: &[&str], id: &str, out: &Path, args: &[&str]) -> Child {
    Command::new(SILRIG)
        .arg("run")
        .args(flags)
        .args(["--run-id", id, "--out", out.to_str().unwrap()])
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

/// The `t_s` column of the run's trace.
fn trace_times(out: &Path) -> Vec<f64> {
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    trace.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect()
}

fn pid_of(out: &Path, role: &str, launcher: u32) -> u32 {
    // The kernel keeps the first 15 bytes of a process's name; the OS-floor baseline beside a run is a `silrig` child.
    let exe = format!("silrig-{role}");
    let comm = &exe[..exe.len().min(15)];
    *children_of(launcher)
        .iter()
        .find(|p| std::fs::read_to_string(format!("/proc/{p}/comm")).is_ok_and(|c| c.trim() == comm))
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
    // The default configuration (with the OS-floor baseline beside the run), as users run it.
    let launcher = launch_with(&[], &id, &out, &["--duration-s", "4"]);
    wait_until_ticking(&out);
    std::thread::sleep(Duration::from_secs(1));
    signal(pid_of(&out, role, launcher.id()), libc::SIGTERM);
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into())
}

#[test]
fn an_outside_sigterm_to_any_process_is_a_failed_run_not_a_clean_one() {
    for role in ["plant", "logger", "controller"] {
        let (code, stdout) = outside_sigterm(role);
        assert_eq!(code, Some(1), "{role}: {stdout}");
        assert!(!stdout.contains("all processes ended cleanly"), "{role}: {stdout}");
        assert!(
            stdout.contains(&format!("FAILED: {role}: ended by a SIGTERM or SIGINT the launcher did not send")),
            "{role}: {stdout}"
        );
    }
}

#[test]
fn ctrl_c_sigterm_and_a_hangup_stop_the_run_with_130_143_and_129_saying_when() {
    for (sig, code, name) in
        [(libc::SIGINT, 130, "SIGINT"), (libc::SIGTERM, 143, "SIGTERM"), (libc::SIGHUP, 129, "SIGHUP")]
    {
        let dir = temp_dir(&format!("stop-{code}"));
        let id = run_id(&format!("stop-{code}"));
        let out = dir.join("run");
        let mut command = Command::new(SILRIG);
        command.args(["run", "--no-baseline", "--run-id", &id, "--out", out.to_str().unwrap(), "--duration-s", "120"]);
        // In a process group of its own, as a shell's job: a closed terminal or a dropped ssh session hangs up
        // the whole group, the rig's processes with the launcher.
        std::os::unix::process::CommandExt::process_group(&mut command, 0);
        // As from a terminal: a hangup its default. Under `nohup` (a test run started so) the launcher keeps the
        // hangup ignored, as it should, and the run would fly on.
        // SAFETY: between fork and exec, signal(2) only, which is async-signal-safe.
        unsafe {
            std::os::unix::process::CommandExt::pre_exec(&mut command, || {
                libc::signal(libc::SIGHUP, libc::SIG_DFL);
                Ok(())
            });
        }
        let launcher = command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        wait_until_ticking(&out);
        std::thread::sleep(Duration::from_secs(1));
        // SIGINT and SIGTERM to the launcher alone (a script's `kill`, a CI runner's), not to the group as a
        // terminal's Ctrl-C: the launcher ends the timer baseline too, which once ran on to the end of the planned
        // 120 s. SIGHUP to the group, as a terminal's hangup.
        let target = if sig == libc::SIGHUP { -(launcher.id() as i32) } else { launcher.id() as i32 };
        // SAFETY: kill(2) on the launcher this test started, or the process group it leads.
        unsafe { libc::kill(target, sig) };
        let signalled = std::time::Instant::now();
        let o = wait_with_watchdog(launcher, Duration::from_secs(150));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(signalled.elapsed() < Duration::from_secs(60), "{name}: the run went on to its end: {stdout}");
        assert_eq!(o.status.code(), Some(code), "{name}: {stdout}{}", String::from_utf8_lossy(&o.stderr));
        assert!(stdout.contains(&format!("stopped by the user ({name}) at t = ")), "{stdout}");
        assert!(stdout.contains(" s of 120.00 s"), "{stdout}");
        assert!(!stdout.contains("FAILED") && !stdout.contains("all processes ended cleanly"), "{stdout}");
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
        assert_eq!(report["stopped_by"]["signal"], name);
        assert_eq!(report["stopped_by"]["exit_status"], code);
        assert!(report["stopped_by"]["at_s"].as_f64().unwrap() < 60.0);
        assert!(!out.join(".silrig-run.lock").exists(), "{name}: the folder's lock is removed");
        assert!(!Path::new(&format!("/tmp/silrig_{id}.lock")).exists(), "{name}: the run id's lock is removed");
        for role in ["plant", "controller", "logger"] {
            let p = report["processes"].as_array().unwrap().iter().find(|p| p["process"] == role);
            assert!(p.is_some(), "{name}: the {role} ended cleanly, writing its report: {stdout}");
        }
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
    let t = trace_times(&out);
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
        let (winner, loser) = if a.status.success() { (&out1, &out2) } else { (&out2, &out1) };
        let rows = std::fs::read_to_string(winner.join("trace.csv")).unwrap().lines().count() - 1;
        assert_eq!(rows, 151, "one row per tick, written once");
        // The refused run leaves no folder of its own behind (in the shared folder, nothing of its own).
        if loser != winner {
            assert!(!loser.exists(), "{} left behind", loser.display());
        }
        no_shared_memory_left(&id1);
        no_shared_memory_left(&id2);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_number_that_enters_is_range_checked_with_our_message_and_exit_2() {
    let dir = temp_dir("ranges");
    let robust = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/robust.toml")).unwrap();
    let flags: [(&[&str], &str); 10] = [
        (&["--command-budget-ms", "0"], "--command-budget-ms must be within 0.01..1000 ms, got 0"),
        (&["--command-budget-ms", "NaN"], "--command-budget-ms must be within 0.01..1000 ms, got NaN"),
        (&["--command-budget-ms", "-1"], "--command-budget-ms must be within 0.01..1000 ms, got -1"),
        (&["--command-spin-us", "1e12"], "--command-spin-us must be within 0..10000 us"),
        (&["--sample-poll-us", "-5"], "--sample-poll-us must be within 0..10000 us, got -5"),
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

/// Run the launcher to its end with these flags; (exit code, stdout + stderr, report.json, events.jsonl).
fn run_to_end(id: &str, out: &Path, args: &[&str]) -> (Option<i32>, String, serde_json::Value, String) {
    let o = wait_with_watchdog(launch(id, out, args), Duration::from_secs(90));
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let report = std::fs::read_to_string(out.join("report.json"))
        .map_or(serde_json::Value::Null, |t| serde_json::from_str(&t).unwrap());
    let events = std::fs::read_to_string(out.join("events.jsonl")).unwrap_or_default();
    (o.status.code(), text, report, events)
}

/// Wait until the launcher has injected the fault described as `what` (its `fault-injected` event).
fn wait_for_injection(out: &Path, what: &str) {
    let start = Instant::now();
    while !std::fs::read_to_string(out.join("events.jsonl"))
        .unwrap_or_default()
        .lines()
        .any(|l| l.contains("\"fault-injected\"") && l.contains(what))
    {
        assert!(start.elapsed() < Duration::from_secs(30), "`{what}` was never injected");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_peer_that_dies_is_cleaned_up_by_the_launcher_and_every_life_is_in_the_report() {
    let dir = temp_dir("peer-dies");
    let id = run_id("peer-dies");
    let out = dir.join("run");
    let launcher = launch(&id, &out, &["--duration-s", "3", "--fault", "controller:kill@1s,restart_after=0.3s"]);
    wait_until_ticking(&out);
    // Every file of the run is its owner's only: iceoryx2 makes its node counter world-writable, the rig narrows it.
    let shared: Vec<_> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(&format!("sr_{id}_")))
        .collect();
    assert!(!shared.is_empty());
    for e in shared {
        use std::os::unix::fs::PermissionsExt;
        let mode = e.metadata().unwrap().permissions().mode() & 0o777;
        assert_eq!(mode & 0o077, 0, "{} has mode {mode:o}", e.path().display());
    }
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    // The dead controller's node is removed by the launcher, off the plant's tick.
    let events = std::fs::read_to_string(out.join("events.jsonl")).unwrap();
    let removed = events.lines().find(|l| l.contains("\"dead-nodes-removed\"")).unwrap_or_else(|| panic!("{events}"));
    assert!(removed.contains("\"launcher\"") && removed.contains("`controller`"), "{removed}");
    // Both lives of the controller are in the report and the printed table, each with how it ended.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let lives: Vec<&serde_json::Value> =
        report["lives"].as_array().unwrap().iter().filter(|l| l["process"] == "controller").collect();
    assert_eq!(lives.len(), 2, "{}", report["lives"]);
    assert_eq!(lives[0]["exit"], "killed by signal 9 (the fault plan)");
    assert!(lives[0]["report"].is_null());
    assert_eq!(lives[1]["report"], "controller.report.json");
    assert!(text.contains("controller #1") && text.contains("controller #2"), "{text}");
    assert!(
        text.contains("2 lives: the latencies and counters below merge #2 (1 wrote no report: see the notes)"),
        "{text}"
    );
    let notes = report["notes"].to_string();
    assert!(notes.contains("controller: life 1 (pid ") && notes.contains("wrote no report"), "{notes}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_plant_killed_for_good_ends_the_flight_early_and_the_run_fails_saying_when() {
    let dir = temp_dir("plant-gone");
    let id = run_id("plant-gone");
    let out = dir.join("run");
    let (code, text, report, _) = run_to_end(&id, &out, &["--duration-s", "3", "--fault", "plant:kill@1s"]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("FAILED: plant: ended by the fault plan and not restarted: the flight ended at t = 1."),
        "{text}"
    );
    // The dead plant stays in the process table, the throughput counts what it flew, the summary has no NaN.
    assert!(text.contains("killed by signal 9 (the fault plan), no report"), "{text}");
    assert!(report["cycles_per_s"].as_f64().unwrap() > 0.0, "{}", report["cycles_per_s"]);
    assert!(!text.contains("NaN"), "{text}");
    // The late window (0.3 of the planned 3 s) is judged on what was flown, not left out.
    assert!(text.contains("max |p|, |q|, |r| in the last 0.9 s"), "{text}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_plant_restarted_between_two_checkpoints_marks_where_the_flights_join() {
    let dir = temp_dir("splice");
    let id = run_id("splice");
    let out = dir.join("run");
    // Killed half way between two checkpoints (every 10 ticks): the restarted plant flies ticks again.
    let (code, text, report, events) =
        run_to_end(&id, &out, &["--duration-s", "3", "--fault", "plant:kill@1.55s,restart_after=0.3s"]);
    assert_eq!(code, Some(0), "{text}");
    let mark = events.lines().find(|l| l.contains("\"flight-discontinuity\"")).unwrap_or_else(|| panic!("{events}"));
    assert!(mark.contains("flew again from tick") && mark.contains("differed by phi"), "{mark}");
    assert_eq!(report["discontinuities"].as_array().unwrap().len(), 1, "{}", report["discontinuities"]);
    assert!(report["faults"][0]["discontinuity"]["at_s"].as_f64().unwrap() > 1.5);
    assert!(text.contains("the logged flight has 1 discontinuity"), "{text}");
    let logger: &serde_json::Value =
        report["processes"].as_array().unwrap().iter().find(|p| p["process"] == "logger").unwrap();
    assert_eq!(logger["counters"]["flight_discontinuities"], 1);
    // The trace itself marks the join: flight_segment steps from 0 to 1 at the discontinuity's row.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let header: Vec<&str> = trace.lines().next().unwrap().split(',').collect();
    let (t_col, seg_col) = (0, header.iter().position(|c| *c == "flight_segment").expect("a flight_segment column"));
    let rows: Vec<(f64, f64)> = trace
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[t_col].parse().unwrap(), c[seg_col].parse().unwrap())
        })
        .collect();
    let at_s = report["discontinuities"][0]["at_s"].as_f64().unwrap();
    assert!(rows.iter().all(|(t, seg)| *seg == if *t + 1e-9 < at_s { 0.0 } else { 1.0 }), "segments: {rows:?}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_damaged_plant_checkpoint_stops_the_restart_rather_than_flying_again_from_the_start() {
    let dir = temp_dir("bad-plant-ckpt");
    let id = run_id("bad-plant-ckpt");
    let out = dir.join("run");
    let launcher = launch(&id, &out, &["--duration-s", "4", "--fault", "plant:kill@1s,restart_after=1s"]);
    wait_for_injection(&out, "plant kill");
    // Without the run's shared-memory copy (as for a plant resumed by hand after the run's end) the file is what
    // the restarted plant reads: torn, as a disk that filled mid-write would leave it.
    std::fs::remove_file(format!("/dev/shm/sr_{id}_plant.checkpoint")).unwrap();
    std::fs::write(out.join("plant.checkpoint.json"), "{\"tick\": 100, \"state\": {\"vt_fps\": 5").unwrap();
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("cannot resume") && text.contains("plant.checkpoint.json"), "{text}");
    // Nothing of a second flight was spliced in: the logged time only moves forward and stops at the kill.
    let t = trace_times(&out);
    assert!(t.windows(2).all(|w| w[1] > w[0]), "the trace's time goes back");
    assert!(*t.last().unwrap() < 1.2, "rows after the kill: {}", t.last().unwrap());
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_controller_checkpoint_with_absurd_weights_is_refused_and_the_events_say_it_started_fresh() {
    let dir = temp_dir("bad-ctl-ckpt");
    let id = run_id("bad-ctl-ckpt");
    let out = dir.join("run");
    let launcher = launch(&id, &out, &["--duration-s", "3", "--fault", "controller:kill@1s,restart_after=0.5s"]);
    wait_for_injection(&out, "controller kill");
    let path = out.join("controller.checkpoint.json");
    let mut weights: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    weights[0][0] = serde_json::json!(1e300);
    std::fs::write(&path, weights.to_string()).unwrap();
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{text}");
    let events = std::fs::read_to_string(out.join("events.jsonl")).unwrap();
    let joined = events.lines().find(|l| l.contains("\"controller-joined\"")).unwrap_or_else(|| panic!("{events}"));
    assert!(joined.contains("fresh state (its checkpoint was rejected: channel 0 has a weight of 1e300"), "{joined}");
    assert!(events.contains("\"checkpoint-rejected\""), "{events}");
    // The plant never flew a command built on those weights.
    let plant: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plant.report.json")).unwrap()).unwrap();
    assert_eq!(plant["counters"]["commands_invalid"], 0);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_id_whose_iceoryx2_folder_is_squatted_by_a_file_is_refused_naming_the_file() {
    let dir = temp_dir("squat");
    let id = run_id("squat");
    let squat = PathBuf::from(format!("/dev/shm/silrig_{id}"));
    std::fs::write(&squat, "not a folder").unwrap();
    let (code, text, _, _) = run_to_end(&id, &dir.join("run"), &["--duration-s", "1"]);
    std::fs::remove_file(&squat).unwrap();
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains(&format!("/dev/shm/silrig_{id} exists and is not a folder")), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A 64 KiB tmpfs mounted for one test, unmounted however the test ends.
struct SmallDisk(PathBuf);

impl SmallDisk {
    fn mount(at: PathBuf) -> Self {
        std::fs::create_dir_all(&at).unwrap();
        let o = Command::new("mount").args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"]).arg(&at).output().unwrap();
        assert!(o.status.success(), "this test mounts a small tmpfs (as root): {}", String::from_utf8_lossy(&o.stderr));
        Self(at)
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn a_full_disk_is_named_with_the_file_and_the_process_and_leaves_every_file_whole_or_absent() {
    let dir = temp_dir("full-disk");
    let id = run_id("full-disk");
    let disk = SmallDisk::mount(dir.join("disk"));
    let out = disk.0.join("run");
    let (code, text, _, _) = run_to_end(&id, &out, &["--duration-s", "3"]);
    assert_eq!(code, Some(1), "{text}");
    assert!(!text.contains("panicked"), "{text}");
    // The logger's error reaches the launcher's own stderr, naming the file (whichever of its files the disk
    // refused first), though its log is on the full disk.
    let logger_error =
        text.lines().find(|l| l.contains("silrig-logger: error: writing")).unwrap_or_else(|| panic!("{text}"));
    assert!(
        ["trace.csv", "timing.csv", "recording.mcap"].iter().any(|f| logger_error.contains(f))
            && logger_error.contains("No space left on device"),
        "{logger_error}"
    );
    // Each file's error said once, not again as its own cause.
    assert!(!logger_error.contains("(os error 28): No space left on device"), "said twice: {logger_error}");
    assert!(text.contains("FAILED"), "{text}");
    for entry in std::fs::read_dir(&out).unwrap().flatten() {
        let path = entry.path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(&path).unwrap();
        if name.ends_with(".csv") || name.ends_with(".jsonl") || name.ends_with(".log") {
            assert!(bytes.is_empty() || bytes.ends_with(b"\n"), "{name} ends mid-line");
        }
        if name.ends_with(".csv") {
            let text = String::from_utf8(bytes).unwrap();
            let fields = text.lines().next().unwrap().split(',').count();
            assert!(text.lines().all(|l| l.split(',').count() == fields), "{name} has a partial row");
        } else if name.ends_with(".json") {
            assert!(serde_json::from_slice::<serde_json::Value>(&bytes).is_ok(), "{name} is not whole");
        } else if name.ends_with(".png") || name.ends_with(".hgrm") {
            assert!(!bytes.is_empty(), "{name} is empty");
        }
        assert!(!name.ends_with(".tmp"), "{name} left behind");
    }
    drop(disk);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_process_started_by_hand_that_fails_at_start_up_leaves_no_iceoryx2_files() {
    let dir = temp_dir("by-hand");
    let id = run_id("by-hand");
    let o = Command::new(env!("CARGO_BIN_EXE_silrig-plant"))
        .args(["--run-id", &id, "--startup-timeout-s", "0.5", "--out", dir.join("run").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no controller and logger connected within 0.5 s"));
    assert!(!Path::new(&format!("/dev/shm/silrig_{id}")).exists(), "the run's iceoryx2 folder is left");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_file_of_a_run_is_its_owners_only_whatever_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;
    let dir = temp_dir("umask");
    let id = run_id("umask");
    let out = dir.join("run");
    let mut command = Command::new(SILRIG);
    command
        .args(["run", "--run-id", &id, "--out", out.to_str().unwrap(), "--duration-s", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    // SAFETY: umask(2) in the child between fork and exec is async-signal-safe.
    unsafe {
        command.pre_exec(|| {
            libc::umask(0);
            Ok(())
        })
    };
    let launcher = command.spawn().unwrap();
    wait_until_ticking(&out);
    let open_to_others = |path: &Path| {
        let mut found = Vec::new();
        let mut stack = vec![path.to_path_buf()];
        while let Some(p) = stack.pop() {
            let Ok(meta) = std::fs::symlink_metadata(&p) else { continue };
            if meta.permissions().mode() & 0o077 != 0 {
                found.push(format!("{} {:o}", p.display(), meta.permissions().mode() & 0o777));
            }
            if meta.is_dir() {
                stack.extend(std::fs::read_dir(&p).unwrap().flatten().map(|e| e.path()));
            }
        }
        found
    };
    // While it flies: the run's iceoryx2 folder (status files, locks) and its lock file.
    let running: Vec<String> = [format!("/dev/shm/silrig_{id}"), format!("/tmp/silrig_{id}.lock")]
        .iter()
        .flat_map(|p| open_to_others(Path::new(p)))
        .collect();
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    assert!(running.is_empty(), "open to others while running: {running:?}");
    let after = open_to_others(&out);
    assert!(after.is_empty(), "open to others: {after:?}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_os_floor_killed_from_outside_is_a_line_of_the_report_and_the_comparison_says_it_is_missing() {
    let dir = temp_dir("floor-killed");
    let id = run_id("floor-killed");
    let out = dir.join("run");
    let launcher = launch_with(&[], &id, &out, &["--duration-s", "3"]);
    wait_until_ticking(&out);
    // The baseline is the launcher's `silrig timer-baseline` child.
    let baseline = *children_of(launcher.id())
        .iter()
        .find(|p| std::fs::read_to_string(format!("/proc/{p}/comm")).is_ok_and(|c| c.trim() == "silrig"))
        .expect("the OS-floor baseline beside the run");
    signal(baseline, libc::SIGKILL);
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let said = format!(
        "the OS floor (the timer baseline, pid {baseline}) ended before the run did, killed by signal 9: no signal of \
         the launcher's, so something else ended it"
    );
    assert!(stdout.contains(&format!("no OS floor to read the plant's wake-up lateness against: {said}")), "{stdout}");
    assert!(stdout.contains(&format!("note: {said}")), "{stdout}");
    assert!(!stdout.contains("x the OS floor"), "no comparison with a floor that is not there: {stdout}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert!(report["timer_baseline"].is_null());
    assert_eq!(report["timer_baseline_missing"], said.as_str());
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        page.contains("No OS floor to read the plant's wake-up lateness against: the OS floor (the timer baseline"),
        "report.html"
    );
    // The flight itself is whole: the run passes, saying what it could not measure.
    assert_eq!(o.status.code(), Some(0), "{stdout}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// CLOCK_MONOTONIC now, ns: the clock of the run's events.
fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// The first event of `kind` in the run's log: its time, ns.
fn event_ns(out: &Path, kind: &str) -> u64 {
    let text = std::fs::read_to_string(out.join("events.jsonl")).unwrap();
    let event = text.lines().map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()).find(|e| e["kind"] == kind);
    event.unwrap_or_else(|| panic!("no {kind} event: {text}"))["t_ns"].as_u64().unwrap()
}

/// The plant's tick 0 due time, ns, as its `ticking` event gives it.
fn ticking_t0_ns(out: &Path) -> u64 {
    let text = std::fs::read_to_string(out.join("events.jsonl")).unwrap();
    let ticking =
        text.lines().map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()).find(|e| e["kind"] == "ticking");
    let detail = ticking.unwrap_or_else(|| panic!("no ticking event: {text}"))["detail"].as_str().unwrap().to_string();
    detail.strip_prefix("t0_ns=").and_then(|t| t.parse().ok()).unwrap_or_else(|| panic!("{detail}"))
}

/// When the plant sent its last logged tick, ns (`timing.csv`'s `t_plant_send_ns`).
fn last_tick_sent_ns(out: &Path) -> u64 {
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    timing.lines().last().unwrap().split(',').nth(3).unwrap().parse().unwrap()
}

#[test]
fn a_death_is_recorded_and_restarted_when_it_happens_not_seconds_later() {
    let dir = temp_dir("death-seen");
    let id = run_id("death-seen");
    let out = dir.join("run");
    let launcher = launch(&id, &out, &["--duration-s", "3", "--restart", "on-failure"]);
    wait_until_ticking(&out);
    // SIGTERM the controller 1.05 s into the 3 s flight: less than the launcher's old grace for a clean exit (2 s,
    // `CLEAN_EXIT_GRACE`) before the plant's last tick. A death judged only after that grace finds the flight over
    // and is no death at all (no event, no restart); one recorded when it happens comes between the kill and the
    // flight's end, in that order, however long the machine's load made the time between them.
    let kill_at_ns = ticking_t0_ns(&out) + 1_050_000_000;
    while monotonic_ns() < kill_at_ns {
        std::thread::sleep(Duration::from_millis(5));
    }
    let killed_ns = monotonic_ns();
    signal(pid_of(&out, "controller", launcher.id()), libc::SIGTERM);
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("controller #2"), "restarted: {stdout}");
    let last_tick_ns = last_tick_sent_ns(&out);
    assert!(killed_ns < last_tick_ns, "the test's SIGTERM came after the flight's end: it proves nothing: {stdout}");
    let died_ns = event_ns(&out, "process-died");
    assert!(
        killed_ns <= died_ns && died_ns <= last_tick_ns,
        "the death was recorded at {died_ns} ns, not between the SIGTERM ({killed_ns}) and the last tick \
         ({last_tick_ns}): {stdout}"
    );
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_command_that_ignores_sigterm_at_the_end_is_named_with_the_time_it_cost() {
    let dir = temp_dir("ignores-term");
    let id = run_id("ignores-term");
    let out = dir.join("run");
    // A helper the controller's command starts that ignores SIGTERM, as a wrapper script's might (the controller
    // itself sets its own handler).
    let cmd = "sh -c \"trap '' TERM; sleep 60 & exec python3 examples/python/pid_attitude.py\"";
    let launcher = launch(&id, &out, &["--duration-s", "1", "--controller-cmd", cmd]);
    let o = wait_with_watchdog(launcher, Duration::from_secs(90));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let note = stdout.lines().find(|l| l.starts_with("note: controller: pid ")).unwrap_or_else(|| panic!("{stdout}"));
    assert!(note.contains("(`sleep`) of its command ignored SIGTERM: killed after "), "{note}");
    assert!(note.ends_with(" s, which the end of the run waited for"), "{note}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}
