//! `silrig timer-baseline` as a user runs it. Counts and formats only: no timing figure is asserted as a bound.

use std::process::Command;

fn silrig(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_silrig")).args(args).output().unwrap();
    (out.status.code().unwrap(), String::from_utf8(out.stdout).unwrap(), String::from_utf8(out.stderr).unwrap())
}

#[test]
fn timer_baseline_prints_json_text_and_hgrm() {
    let (code, out, err) =
        silrig(&["timer-baseline", "--duration-s", "0.1", "--period-ms", "5", "--fifo-priority", "0", "--json"]);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["period_ns"], 5_000_000);
    assert_eq!(report["source"], "Nanosleep");
    assert!(report["wakeups"].as_u64().unwrap() >= 1);
    let l = &report["lateness"];
    assert!(l["p50_us"].as_f64().unwrap() <= l["max_us"].as_f64().unwrap());

    let hgrm = std::env::temp_dir().join(format!("silrig-cli-timing-{}.hgrm", std::process::id()));
    let hgrm_arg = hgrm.to_string_lossy().into_owned();
    let (code, out, err) = silrig(&[
        "timer-baseline",
        "--duration-s",
        "0.05",
        "--period-ms",
        "5",
        "--fifo-priority",
        "0",
        "--timerfd",
        "--hgrm",
        &hgrm_arg,
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("absolute timerfd in an iceoryx2 WaitSet") && out.contains("wake-up lateness"), "{out}");
    let text = std::fs::read_to_string(&hgrm).unwrap();
    std::fs::remove_file(&hgrm).unwrap();
    assert!(text.starts_with("       Value     Percentile TotalCount 1/(1-Percentile)") && text.contains("#[Buckets"));
}

#[test]
fn timer_baseline_rejects_a_zero_period() {
    let (code, _, err) = silrig(&["timer-baseline", "--period-ms", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--period-ms must be within 0.1..1000 ms, got 0"), "{err}");
}

#[test]
fn bench_ipc_measures_the_ceiling_and_a_lockstep_run_against_it() {
    let (code, out, err) =
        silrig(&["bench", "ipc", "--round-trips", "300", "--lockstep-ticks", "200", "--repeats", "1", "--json"]);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    // Both wait strategies, blocking first; the ceiling is the polling one's.
    let pings = report["ping_pongs"].as_array().unwrap();
    assert_eq!(pings.iter().map(|p| p["wait"].as_str().unwrap()).collect::<Vec<_>>(), ["block", "poll"]);
    for ping in pings {
        assert_eq!(ping["round_trips"], 300);
        assert_eq!(ping["round_trip"]["count"], 300);
    }
    assert_eq!(report["ceiling_per_s"], pings[1]["round_trips_per_s"]);
    assert_eq!(report["blocking_per_s"], pings[0]["round_trips_per_s"]);
    assert_eq!(report["lockstep"][0]["ticks"], 200);
    let (ceiling, lockstep) =
        (report["ceiling_per_s"].as_f64().unwrap(), report["lockstep_loop_per_s"].as_f64().unwrap());
    assert!(ceiling > 0.0 && lockstep > 0.0, "{report}");
    assert!((report["ratio"].as_f64().unwrap() - lockstep / ceiling).abs() < 1e-9);
    let blocking = report["blocking_per_s"].as_f64().unwrap();
    assert!((report["ratio_to_blocking"].as_f64().unwrap() - lockstep / blocking).abs() < 1e-9);
}

#[test]
fn bench_ipc_refuses_too_few_round_trips() {
    let (code, _, err) = silrig(&["bench", "ipc", "--round-trips", "5"]);
    assert_eq!(code, 2);
    assert!(err.contains("--round-trips must be within 100..100000000 round trips, got 5"), "{err}");
}

/// `silrig run --floor cyclictest` with its own run id and folder; (exit code, stdout + stderr, folder).
fn run_with_cyclictest_floor(test: &str, path: Option<&str>) -> (Option<i32>, String, std::path::PathBuf) {
    let out = std::env::temp_dir().join(format!("silrig-cli-timing-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let id = format!("t{}-{test}", std::process::id());
    let mut command = Command::new(env!("CARGO_BIN_EXE_silrig"));
    command.args(["run", "--quiet", "--floor", "cyclictest", "--duration-s", "1", "--run-id", &id, "--out"]).arg(&out);
    if let Some(path) = path {
        command.env("PATH", path);
    }
    let o = command.output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(!std::path::Path::new(&format!("/dev/shm/silrig_{id}")).exists(), "iceoryx2 root folder left behind");
    (o.status.code(), text, out)
}

#[test]
fn the_os_floor_can_be_taken_by_cyclictest_itself() {
    let (code, text, out) = run_with_cyclictest_floor("cyclictest", None);
    assert_eq!(code, Some(0), "{text}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let floor = &report["timer_baseline"];
    assert_eq!(floor["source"], "Cyclictest", "{floor}");
    // 1 s at 100 Hz: cyclictest's loop count is the scenario's ticks.
    assert_eq!(floor["wakeups"], 100);
    assert!(text.contains("the OS floor's p99 measured beside it (cyclictest (rt-tests), SCHED_FIFO 80)"), "{text}");
    assert!(std::fs::read_to_string(out.join("cyclictest.txt")).unwrap().contains("# Total: 000000100"));
    let _ = std::fs::remove_dir_all(&out);

    // Without cyclictest on PATH the run is refused before anything flies.
    let (code, text, out) = run_with_cyclictest_floor("no-cyclictest", Some("/nonexistent"));
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("--floor cyclictest: cyclictest is not installed (Debian: apt-get install rt-tests)"),
        "{text}"
    );
    assert!(!out.join("plant.report.json").exists(), "nothing flew");
    let _ = std::fs::remove_dir_all(&out);
}
