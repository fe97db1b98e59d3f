//! Fault injection with the real processes: each test runs `silrig run` in realtime with its own run id and
//! folder and reads the report, the event log and `timing.csv`. Counts and orderings are asserted, never how fast
//! something happened in wall time (the machine is shared); the failsafe delay is checked in plant ticks.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("silrig-faults-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A test's folder, removed when the test ends.
struct Folder(PathBuf);

impl Drop for Folder {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl std::ops::Deref for Folder {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

/// `silrig run` with a watchdog; returns (exit code, stdout and stderr, report, output folder).
fn run(test: &str, args: &[&str]) -> (Option<i32>, String, Value, Folder) {
    let out = temp_dir(test);
    let id = format!("f{}-{test}", std::process::id());
    let mut child = Command::new(SILRIG)
        .args(["run", "--no-baseline", "--run-id", &id, "--out", out.to_str().unwrap()])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(90) {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!("no end; {}", String::from_utf8_lossy(&o.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    let report =
        std::fs::read_to_string(out.join("report.json")).map_or(Value::Null, |t| serde_json::from_str(&t).unwrap());
    let prefix = format!("sr_{id}_");
    let left = std::fs::read_dir("/dev/shm")
        .unwrap()
        .filter_map(|e| e.ok())
        .any(|e| e.file_name().to_string_lossy().starts_with(&prefix));
    assert!(!left, "shared memory left behind by {id}");
    (o.status.code(), stdout, report, Folder(out))
}

fn process<'a>(r: &'a Value, name: &str) -> &'a Value {
    r["processes"].as_array().unwrap().iter().find(|p| p["process"] == name).unwrap()
}

fn events(out: &Path) -> Vec<Value> {
    std::fs::read_to_string(out.join("events.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn first<'a>(events: &'a [Value], process: &str, kind: &str) -> Option<&'a Value> {
    events.iter().find(|e| e["process"] == process && e["kind"] == kind)
}

fn trace_rows(out: &Path) -> usize {
    std::fs::read_to_string(out.join("trace.csv")).unwrap().lines().count() - 1
}

#[test]
fn controller_sigkill_and_restart_failsafe_then_resume_with_the_gap_marked() {
    let (code, text, r, out) =
        run("ctl-kill", &["--duration-s", "4", "--fault", "controller:kill@1.5s,restart_after=0.5s"]);
    assert_eq!(code, Some(0), "{text}");
    assert_eq!(process(&r, "plant")["counters"]["ticks"], 401, "the plant kept ticking");
    let ev = events(&out);
    let stale = first(&ev, "plant", "controller-stale").expect("detected");
    let failsafe = first(&ev, "plant", "failsafe-engaged").expect("failsafe");
    let recovered = first(&ev, "plant", "controller-recovered").expect("recovered");
    assert!(first(&ev, "controller", "controller-joined").is_some(), "bumpless join announced");
    // Failsafe within the 100 ms hold (10 ticks) plus two ticks of the last command the plant received, counted in
    // the plant's own ticks (which a loaded machine can only make fewer).
    let detail = failsafe["detail"].as_str().unwrap();
    let silent_ticks: u64 = detail.split(' ').next().unwrap().parse().unwrap();
    assert!(silent_ticks <= 10 + 2, "{detail}");
    assert!(first(&ev, "logger", "commands-missing").is_some(), "gap marked in the log");
    assert!(
        stale["t_ns"].as_u64() <= failsafe["t_ns"].as_u64() && failsafe["t_ns"].as_u64() < recovered["t_ns"].as_u64()
    );
    assert!(process(&r, "plant")["counters"]["failsafe_ticks"].as_u64().unwrap() > 0);
    // The log is complete, with the gap marked in the rows and in timing.csv.
    assert_eq!(trace_rows(&out), 401);
    let without = process(&r, "logger")["counters"]["rows_without_command"].as_u64().unwrap();
    assert!(without > 0);
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    let missing = timing.lines().skip(1).filter(|l| l.split(',').nth(11) == Some("1")).count() as u64;
    assert_eq!(missing, without);
    let fault = &r["faults"][0];
    assert!(fault["detected_at_s"].as_f64().unwrap() >= fault["injected_at_s"].as_f64().unwrap());
    assert!(fault["recovered_at_s"].as_f64().unwrap() > fault["failsafe_at_s"].as_f64().unwrap());
    assert!(out.join("faults.png").exists());
}

#[test]
fn a_restarted_controllers_report_merges_every_life_that_wrote_one_and_names_the_one_that_did_not() {
    // Life 1 ends on SIGTERM and writes its report, life 2 is killed with SIGKILL and writes none, life 3 runs to
    // the end.
    let (code, text, r, out) = run(
        "lives",
        &[
            "--duration-s",
            "4",
            "--fault",
            "controller:term@1s,restart_after=0.3s",
            "--fault",
            "controller:kill@2.2s,restart_after=0.3s",
        ],
    );
    assert!(text.contains("controller #3"), "{code:?} {text}");
    let c = process(&r, "controller");
    assert_eq!(c["lives_merged"], serde_json::json!([1, 3]), "{c}");
    let first: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("controller.life1.report.json")).unwrap())
            .expect("life 1's report kept");
    let lives: Vec<&Value> = r["lives"].as_array().unwrap().iter().filter(|l| l["process"] == "controller").collect();
    assert_eq!(lives.len(), 3);
    let last_pid = lives[2]["pid"].as_u64().unwrap();
    assert_eq!(c["pid"].as_u64(), Some(last_pid), "the last life's identity");
    // Counters summed, latencies merged: life 1's values are in the totals, beside life 3's.
    let counters = first["counters"].as_object().unwrap();
    assert!(!counters.is_empty());
    for (k, v) in counters {
        assert!(c["counters"][k].as_u64().unwrap() >= v.as_u64().unwrap(), "{k}: {c}");
    }
    let count = |p: &Value, name: &str| {
        p["latencies"].as_array().unwrap().iter().find(|l| l["name"] == name).unwrap()["summary"]["count"]
            .as_u64()
            .unwrap()
    };
    let name = first["latencies"][0]["name"].as_str().unwrap();
    assert!(count(&first, name) > 0 && count(c, name) > count(&first, name), "{name}: {c}");
    let buckets: u64 = c["latencies"][0]["buckets"].as_array().unwrap().iter().map(|b| b[1].as_u64().unwrap()).sum();
    assert_eq!(buckets, count(c, name), "the merged histogram is the merged summary's");
    // The life without a report is named, with what is missing.
    let notes = r["notes"].to_string();
    assert!(notes.contains("controller: life 2 (pid ") && notes.contains("merge lives 1, 3"), "{notes}");
    assert!(text.contains("3 lives: the latencies and counters below merge #1, #3 (1 wrote no report"), "{text}");
}

#[test]
fn plant_sigkill_and_restart_continues_the_flight_from_its_checkpoint() {
    let (code, text, r, out) = run("plant-kill", &["--duration-s", "3", "--fault", "plant:kill@1s,restart_after=0.3s"]);
    assert_eq!(code, Some(0), "{text}");
    let ev = events(&out);
    assert!(first(&ev, "controller", "plant-stale").is_some(), "the controller noticed");
    assert!(first(&ev, "plant", "plant-resumed").is_some());
    assert!(first(&ev, "controller", "plant-recovered").is_some());
    // Every tick is logged exactly once, in order.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let t: Vec<f64> = trace.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert_eq!(t.len(), 301);
    assert!(t.windows(2).all(|w| w[1] > w[0]), "ticks out of order or repeated");
    assert_eq!(r["failures"].as_array().unwrap().len(), 0);
}

/// The quadrotor's hover, flown at 1 kHz (the rate of Betaflight's loop).
const QUAD_1KHZ: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/quad-hover.toml");

/// A logger frozen for `stop` (SIGSTOP, then SIGCONT, by the launcher's fault plan) in a realtime run of `ticks`
/// ticks: every row logged once, nothing counted lost, every command the controller sent in the log.
fn logger_frozen_loses_nothing(test: &str, scenario: Option<&str>, duration_s: &str, stop: &str, ticks: usize) {
    let fault = format!("logger:stop@1s,for={stop}");
    let mut args: Vec<&str> = scenario.into_iter().collect();
    args.extend(["--duration-s", duration_s, "--fault", &fault]);
    let (code, text, r, out) = run(test, &args);
    assert_eq!(code, Some(0), "{text}");
    let logger = process(&r, "logger");
    for c in ["plant_samples_lost", "command_samples_lost", "plant_ticks_missing"] {
        assert_eq!(logger["counters"][c], 0, "{c}: {logger}");
    }
    assert_eq!(trace_rows(&out), ticks);
    // Every command the controller sent is in the log (on a loaded machine the controller may skip a stale sample,
    // which leaves a row without a command that the logger did not lose).
    let with_command = ticks as u64 - logger["counters"]["rows_without_command"].as_u64().unwrap();
    assert_eq!(with_command, process(&r, "controller")["counters"]["commands_sent"].as_u64().unwrap());
    let ev = events(&out);
    let (stopped, resumed) = (first(&ev, "launcher", "fault-injected"), first(&ev, "launcher", "fault-ended"));
    assert!(stopped.is_some() && resumed.is_some(), "the launcher stopped the logger and let it go on");
    assert_eq!(r["faults"][0]["plant_samples_lost"], 0, "{}", r["faults"][0]);
}

#[test]
fn logger_stopped_500_ms_loses_no_sample() {
    logger_frozen_loses_nothing("log-stop", None, "3", "500ms", 301);
}

#[test]
fn a_logger_frozen_for_2_s_loses_no_row_at_100_hz_nor_at_1_khz() {
    // The stall of the one-hour soaks (docs/src/measurements/soak.md), longer than the logger's queue was (1.28 s
    // at 100 Hz, 0.128 s at 1 kHz): 200 and 2000 samples of each stream wait for it now.
    logger_frozen_loses_nothing("log-freeze-100hz", None, "4", "2s", 401);
    logger_frozen_loses_nothing("log-freeze-1khz", Some(QUAD_1KHZ), "4", "2s", 4001);
}

#[test]
fn a_logger_stopped_past_its_buffer_counts_the_commands_it_lost_in_the_fault_table() {
    // 5 s at 1 kHz is 5000 ticks, more than the logger's queue holds: the rows and their commands are lost together.
    let (code, text, r, _out) =
        run("log-stop-long", &[QUAD_1KHZ, "--duration-s", "7", "--fault", "logger:stop@1s,for=5s"]);
    assert_eq!(code, Some(0), "{text}");
    let logger = process(&r, "logger");
    let lost = logger["counters"]["command_samples_lost"].as_u64().unwrap();
    assert!(lost > 0 && logger["counters"]["plant_ticks_missing"].as_u64().unwrap() > 0, "{logger}");
    let fault = &r["faults"][0];
    let (plant, commands) =
        (fault["plant_samples_lost"].as_u64().unwrap(), fault["command_samples_lost"].as_u64().unwrap());
    assert!(plant > 0 && commands >= plant, "{fault}");
}

#[test]
fn controller_stopped_500_ms_is_detected_and_recovered() {
    let (code, text, r, out) = run("ctl-stop", &["--duration-s", "3", "--fault", "controller:stop@1s,for=500ms"]);
    assert_eq!(code, Some(0), "{text}");
    let ev = events(&out);
    assert!(first(&ev, "plant", "controller-stale").is_some());
    assert!(first(&ev, "plant", "failsafe-engaged").is_some());
    assert!(first(&ev, "plant", "controller-recovered").is_some());
    // It ran to the run's end (it saw the plant's last tick, or the launcher's SIGTERM came first): SIGCONT did not
    // end its loop.
    let ended = process(&r, "controller")["ended"].as_str().unwrap().to_string();
    assert!(ended == "completed" || ended == "stopped at end", "{ended}");
    assert_eq!(trace_rows(&out), 301);
}

/// Runs of ticks published back to back (two consecutive intervals under 1 ms): what catching up in a burst looks
/// like. A single short interval is only the tick after a stall starting late; the plant always sleeps to the next
/// grid point after it.
fn bursts(out: &Path) -> usize {
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    let sends: Vec<u64> = timing.lines().skip(1).map(|l| l.split(',').nth(3).unwrap().parse().unwrap()).collect();
    let short: Vec<bool> = sends.windows(2).map(|w| w[1] - w[0] < 1_000_000).collect();
    short.windows(2).filter(|w| w[0] && w[1]).count()
}

#[test]
fn a_15_ms_delay_in_the_plant_is_one_overrun_and_no_burst() {
    let (code, text, r, out) = run("plant-delay", &["--duration-s", "2", "--fault", "plant:delay@1s,delay=15ms"]);
    assert_eq!(code, Some(0), "{text}");
    let plant = process(&r, "plant");
    // The delayed tick's work ends 5 ms past the next tick's due time: one overrun. That next tick then starts
    // 5 ms late, less than a period, so it runs at once (the only back-to-back publish) and the loop is back on
    // its grid.
    assert!(plant["counters"]["overruns"].as_u64().unwrap() >= 1);
    assert_eq!(plant["counters"]["ticks"], 201);
    assert!(first(&events(&out), "plant", "overrun").is_some());
    assert!(first(&events(&out), "plant", "fault-injected").is_some());
    assert_eq!(bursts(&out), 0);
}

#[test]
fn a_35_ms_delay_counts_the_periods_without_a_tick_instead_of_bursting() {
    let (code, text, r, out) = run("plant-delay35", &["--duration-s", "2", "--fault", "plant:delay@1s,delay=35ms"]);
    assert_eq!(code, Some(0), "{text}");
    let plant = process(&r, "plant");
    // 35 ms: the next start is 25 ms late, two whole periods without a tick, counted with the stall as one
    // overrun, and no run of back-to-back ticks to catch up; no tick number is skipped.
    assert!(plant["counters"]["periods_without_tick"].as_u64().unwrap() >= 2, "{}", plant["counters"]);
    assert!(plant["counters"].get("skipped_ticks").is_none());
    assert!(plant["counters"]["overruns"].as_u64().unwrap() >= 1);
    assert_eq!(bursts(&out), 0);
    assert_eq!(plant["counters"]["ticks"], 201, "the flight still has all its ticks");
}

#[test]
fn leftovers_of_a_killed_run_are_cleaned_by_the_next() {
    let dir = temp_dir("leftovers");
    let id = format!("f{}-left", std::process::id());
    // A controller and a logger of a run whose launcher died: SIGKILL them, leaving dead nodes and shared memory.
    let mut kids: Vec<std::process::Child> = ["silrig-controller", "silrig-logger"]
        .iter()
        .map(|b| {
            let exe = Path::new(SILRIG).with_file_name(b);
            Command::new(exe).args(["--run-id", &id, "--out", dir.join("old").to_str().unwrap()]).spawn().unwrap()
        })
        .collect();
    let prefix = format!("sr_{id}_");
    let shm = || {
        std::fs::read_dir("/dev/shm")
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
            .count()
    };
    let start = Instant::now();
    while shm() == 0 && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(200));
    for k in kids.iter_mut() {
        k.kill().unwrap();
        k.wait().unwrap();
    }
    assert!(shm() > 0, "the killed run left nothing to clean");
    let o = Command::new(SILRIG)
        .args([
            "run",
            "--mode",
            "lockstep",
            "--duration-s",
            "1",
            "--run-id",
            &id,
            "--out",
            dir.join("new").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(shm(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn malformed_fault_plans_are_rejected_naming_the_problem() {
    let bad = |args: &[&str], needle: &str| {
        let o =
            Command::new(SILRIG).arg("run").args(args).args(["--out", "/nonexistent/never-created"]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    };
    bad(&["--fault", "pilot:kill@1s"], "unknown target \"pilot\"");
    bad(&["--fault", "controller:explode@1s"], "unknown action \"explode\"");
    bad(&["--fault", "controller:kill@60s"], "beyond the run");
    bad(&["--fault", "controller:stop@1s"], "duration_s");
    bad(&["--mode", "lockstep", "--fault", "controller:kill@1s"], "needs realtime mode");
    bad(&["--fault", "bridge:kill@1s"], "bridge kill at 1 s needs a plant-side bridge: a run with --bridge-listen");
    bad(&["--fault", "bridge:drop@1s,ticks=5"], "the bridge can be killed, terminated or stopped");
    bad(
        &["--fault", "controller:kill@1s", "--fault", "controller:kill@1s"],
        "`faults[1]`: controller kill at 1 s is faults[0] again: give it once",
    );
    let dir = temp_dir("plan");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/robust.toml")).unwrap()
        + "\n[[faults]]\nat_s = 1.0\ntarget = \"controller\"\naction = \"kill\"\nrestart = true\n";
    std::fs::write(dir.join("bad.toml"), text).unwrap();
    bad(&[dir.join("bad.toml").to_str().unwrap()], "unknown field `restart`");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn process_faults_land_on_their_simulated_time_after_a_stall_with_the_wall_clock_beside_it() {
    // The plant stands still for 0.5 s from 1 s: simulated time falls 0.5 s behind the wall clock. The controller
    // kill planned at 2 s still lands at 2 s of flight (the launcher waits for the plant's tick 200), which is about
    // 2.5 s of wall time.
    let (code, text, r, _out) = run(
        "sim-time",
        &["--duration-s", "3", "--fault", "plant:stop@1s,for=0.5s", "--fault", "controller:kill@2s,restart_after=0.3s"],
    );
    assert_eq!(code, Some(0), "{text}");
    let kill = r["faults"].as_array().unwrap().iter().find(|f| f["fault"].as_str().unwrap().contains("kill")).unwrap();
    let (sim, wall) = (kill["injected_at_s"].as_f64().unwrap(), kill["injected_at_wall_s"].as_f64().unwrap());
    assert!(sim >= 2.0, "not before its tick: simulated {sim}");
    assert!(wall - sim > 0.3, "the stall held simulated time back: simulated {sim} against wall {wall}");
    assert!(text.contains("faults (simulated s)") && text.contains("of wall time)"), "{text}");
}
