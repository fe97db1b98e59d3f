//! `silrig soak`: a short soak (30 s realtime, four faults: a plant kill and restart, an actuator hard-over, a
//! logger SIGTERM and restart, dropped plant samples) whose figures are checked against the run's own files: the
//! events, `trace.csv` and `timing.csv`, `/dev/shm` and the lock files. The schedule is a pure function of the seed.

mod common;

use common::{no_shared_memory_left, temp_dir, wait_with_watchdog};
use serde_json::Value;
use std::collections::BTreeSet;
use std::process::{Command, Stdio};
use std::time::Duration;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

fn schedule(seed: &str, duration_s: &str) -> Vec<String> {
    let o = Command::new(SILRIG)
        .args(["soak", "--print-schedule", "--seed", seed, "--duration-s", duration_s])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap().lines().map(String::from).collect()
}

#[test]
fn the_schedule_is_a_pure_function_of_the_seed() {
    let a = schedule("10", "600");
    assert_eq!(a, schedule("10", "600"));
    assert_ne!(a, schedule("11", "600"));
    // The short soak below flies the beginning of the long one.
    assert_eq!(schedule("10", "30")[..], a[..4]);
    assert!(a.len() > 80, "{} faults in 10 minutes", a.len());
    let o = Command::new(SILRIG).args(["soak", "--duration-s", "5"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--duration-s must be within 15..86400 s, got 5"));
}

/// A soak flown by a test, passed: its folder, the run's folder, `soak.json`, what it printed.
struct Soak {
    dir: std::path::PathBuf,
    out: std::path::PathBuf,
    soak: Value,
    stdout: String,
    /// stdout and stderr, for assertion messages.
    context: String,
}

/// `silrig soak FLAGS` with run id `run_id` in a folder of the test's own; it must pass.
fn fly_soak(name: &str, run_id: &str, flags: &[&str]) -> Soak {
    fly_soak_under(&[], name, run_id, flags)
}

/// [`fly_soak`] started through `wrappers` (`timeout 120`, `/usr/bin/time`, as CI jobs start commands).
fn fly_soak_under(wrappers: &[&str], name: &str, run_id: &str, flags: &[&str]) -> Soak {
    let dir = temp_dir("soak", name);
    let out = dir.join("out");
    let mut command = match wrappers.split_first() {
        Some((first, rest)) => {
            let mut c = Command::new(first);
            c.args(rest).arg(SILRIG);
            c
        }
        None => Command::new(SILRIG),
    };
    let child = command
        .arg("soak")
        .args(flags)
        .args(["--run-id", run_id, "--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = wait_with_watchdog(child, Duration::from_secs(300));
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    let context = format!("{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    let soak: Value = serde_json::from_str(&std::fs::read_to_string(out.join("soak.json")).unwrap()).unwrap();
    assert!(soak["problems"].as_array().unwrap().is_empty(), "{context}");
    assert_eq!(o.status.code(), Some(0), "{context}");
    Soak { dir, out, soak, stdout, context }
}

#[test]
fn a_soak_under_timeout_and_time_counts_only_what_the_run_started() {
    // Both wrappers name the run id on their command lines and outlive the run by design: they are no leftovers.
    let run_id = format!("soak{}-w", std::process::id());
    let wrappers = ["timeout", "200", "/usr/bin/time", "-f", "wrapped: %e s"];
    let Soak { dir, soak, stdout, context, .. } =
        fly_soak_under(&wrappers, "wrapped", &run_id, &["--duration-s", "15", "--seed", "3"]);
    assert!(stdout.contains("soak passed"), "{context}");
    assert!(stdout.contains("left after the run: 0 processes, 0 shared-memory files, 0 lock files"), "{context}");
    assert!(context.contains("wrapped: "), "/usr/bin/time reported the soak: {context}");
    assert_eq!(soak["leftovers"]["processes"].as_array().unwrap().len(), 0, "{context}");
    no_shared_memory_left(&run_id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_short_soak_s_figures_agree_with_the_run_s_files() {
    let run_id = format!("soak{}-t", std::process::id());
    let Soak { dir, out, soak, stdout, context } = fly_soak("short", &run_id, &["--duration-s", "30", "--seed", "10"]);
    assert!(stdout.contains("soak passed"), "{context}");
    let n = |v: &Value| v.as_u64().unwrap();

    // Faults: the four of the schedule, each injected, detected where the rig watches, recovered.
    let faults = soak["faults"].as_array().unwrap();
    let kinds: Vec<&str> = faults.iter().map(|f| f["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["plant:kill", "plant:actuator-hard-over", "logger:term", "plant:drop"]);
    assert_eq!((n(&soak["scheduled"]), n(&soak["injected"]), n(&soak["recovered"])), (4, 4, 4));
    assert_eq!(n(&soak["flight_back"]), 4, "the flight came back to its attitude after each fault");
    let events: Vec<Value> = std::fs::read_to_string(out.join("events.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let of_kind = |k: &str| events.iter().filter(|e| e["kind"] == k).collect::<Vec<_>>();
    let injected_events = of_kind("fault-injected");
    // Every fault but the plant-model one (which acts at its time, as in `silrig sim`) has its event, and only
    // those events.
    assert_eq!(injected_events.len(), 3);
    assert_eq!(n(&soak["fault_events"]), 3);
    for (f, e) in faults.iter().filter(|f| f["kind"] != "plant:actuator-hard-over").zip(&injected_events) {
        assert!(e["detail"].as_str().unwrap().starts_with(f["fault"].as_str().unwrap()), "{e} for {f}");
    }
    for f in faults {
        assert!(f["injected_at_s"].is_f64() && f["recovered_at_s"].is_f64(), "{f}");
        if f["watched"] == true {
            assert!(f["detected_at_s"].as_f64().unwrap() >= f["injected_at_s"].as_f64().unwrap() - 0.011, "{f}");
        }
    }
    assert_eq!(faults[1]["watched"], false, "the rig has no actuator fault detection");
    let per_kind: u64 = soak["kinds"].as_array().unwrap().iter().map(|k| n(&k["injected"])).sum();
    assert_eq!(per_kind, 4);
    assert_eq!(n(&soak["failsafe_engagements"]), of_kind("failsafe-engaged").len() as u64);
    // The killed plant came back from its checkpoint (a restart), and so did the logger, which went on with the
    // trace's own columns (it once said it took them from the scenario, which it did not).
    assert_eq!(of_kind("process-restarted").len(), 2);
    assert!(of_kind("controller-unannounced").is_empty(), "{context}");

    // Rows: the counts are the files', nothing torn, every tick missing from timing.csv inside a fault's window.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    let rows = &soak["rows"];
    assert_eq!(n(&rows["trace_rows"]), trace.lines().count() as u64 - 1);
    assert_eq!(n(&rows["timing_rows"]), timing.lines().count() as u64 - 1);
    assert_eq!((n(&rows["torn"]), n(&rows["duplicated"]), n(&rows["lost_outside_fault_windows"])), (0, 0, 0));
    let ticks: BTreeSet<u64> = timing.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    let missing = (0..=*ticks.last().unwrap()).filter(|k| !ticks.contains(k)).count() as u64;
    assert_eq!(missing, n(&rows["lost_in_fault_windows"]));
    let per_fault: u64 = faults.iter().map(|f| n(&f["rows_lost"])).sum();
    assert_eq!(per_fault, missing);
    // The plant's dropped samples (10 ticks at least) are rows lost in the drop's own window.
    assert!(n(&faults[3]["rows_lost"]) >= 10, "{}", faults[3]);

    // The processes: measured at the start and the end; within each life, no more descriptors or shared-memory
    // files at last than once settled.
    let start = soak["processes_start"].as_array().unwrap();
    let end = soak["processes_end"].as_array().unwrap();
    for name in ["launcher", "plant", "controller", "logger"] {
        let s = start.iter().find(|p| p["process"] == name).unwrap_or_else(|| panic!("{name} at the start"));
        assert!(end.iter().any(|p| p["process"] == name), "{name} at the end");
        assert!(n(&s["rss_kib"]) > 0 && n(&s["fds"]) > 0, "{s}");
        if name != "launcher" {
            assert!(n(&s["shm_files"]) > 0, "{name} maps the run's shared memory: {s}");
        }
    }
    let lives = soak["lives"].as_array().unwrap();
    for l in lives {
        let (s, e) = (&l["settled"], &l["last"]);
        assert!(n(&e["fds"]) <= n(&s["fds"]) && n(&e["shm_files"]) <= n(&s["shm_files"]), "{l}");
    }
    // Both lives of the plant and of the logger were measured.
    for name in ["plant", "logger"] {
        assert_eq!(lives.iter().filter(|l| l["process"] == name).count(), 2, "{name}: {lives:?}");
    }
    // The killed plant and the terminated logger are new lives at the end; the controller is the same one.
    let pid = |list: &[Value], name: &str| list.iter().find(|p| p["process"] == name).unwrap()["pid"].clone();
    assert_ne!(pid(start, "plant"), pid(end, "plant"));
    assert_ne!(pid(start, "logger"), pid(end, "logger"));
    assert_eq!(pid(start, "controller"), pid(end, "controller"));

    // Nothing left, as the soak says and as the test sees it.
    let left = &soak["leftovers"];
    for k in ["processes", "shm_files", "lock_files"] {
        assert!(left[k].as_array().unwrap().is_empty(), "{left}");
    }
    no_shared_memory_left(&run_id);
    assert!(!std::path::Path::new(&format!("/tmp/silrig_{run_id}.lock")).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The controller behind the bridge, its host on this machine: the plant-side bridge killed and stopped as the
/// schedule of seed 5 says, each seen by the plant's watchdog and recovered from by the flight, the controller's
/// report back on the plant's host, and nothing of either namespace left.
#[cfg(feature = "bridge")]
#[test]
fn a_soak_behind_the_bridge_kills_and_stops_the_plant_side_bridge_and_the_flight_recovers() {
    let run_id = format!("soakb{}", std::process::id());
    let Soak { dir, out, soak, context, .. } =
        fly_soak("bridge", &run_id, &["--bridge", "--duration-s", "36", "--seed", "5"]);
    let n = |v: &Value| v.as_u64().unwrap();
    let faults = soak["faults"].as_array().unwrap();
    let kinds: Vec<&str> = faults.iter().map(|f| f["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["plant:drop", "bridge:kill", "logger:kill", "bridge:stop"]);
    for f in faults.iter().filter(|f| f["kind"].as_str().unwrap().starts_with("bridge:")) {
        // The plant misses the commands and says so; the flight gets them back.
        assert_eq!(f["watched"], true, "{f}");
        assert!(f["detected_by"].as_str().unwrap().starts_with("plant"), "{f}");
        assert!(f["recovered_at_s"].as_f64().unwrap() > f["detected_at_s"].as_f64().unwrap(), "{f}");
    }
    let events: Vec<Value> = std::fs::read_to_string(out.join("events.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let launcher_said = |kind: &str, start: &str| {
        events.iter().any(|e| {
            e["process"] == "launcher" && e["kind"] == kind && e["detail"].as_str().unwrap().starts_with(start)
        })
    };
    assert!(launcher_said("fault-injected", "bridge kill at "), "{context}");
    assert!(launcher_said("process-ended", "bridge killed by signal 9 (planned)"), "{context}");
    assert!(launcher_said("process-restarted", "bridge as pid "), "{context}");
    assert!(launcher_said("fault-ended", "SIGCONT to bridge"), "{context}");
    assert!(!events.iter().any(|e| e["kind"] == "controller-unannounced"), "the restarted logger: {context}");
    // The controller's host: one bridge and one controller all along, in a namespace of its own, whose report
    // came back to the plant's host.
    let host = &soak["controller_host"];
    assert_eq!((n(&host["bridge_starts"]), n(&host["controller_starts"])), (1, 1), "{host}");
    let local = host["local_run_id"].as_str().unwrap();
    assert_eq!(local, format!("{run_id}-c"));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("controller.report.json")).unwrap()).unwrap();
    assert_eq!(report["run_id"], local);
    let start = soak["processes_start"].as_array().unwrap();
    for name in ["bridge", "bridge@ctl-host", "controller"] {
        assert!(start.iter().any(|p| p["process"] == name && n(&p["shm_files"]) > 0), "{name}: {start:?}");
    }
    let left = &soak["leftovers"];
    for k in ["processes", "shm_files", "lock_files"] {
        assert!(left[k].as_array().unwrap().is_empty(), "{left}");
    }
    no_shared_memory_left(&run_id);
    no_shared_memory_left(local);
    std::fs::remove_dir_all(&dir).unwrap();
}
