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
