//! The live view of a running rig: `silrig run`'s status line (one a second on a non-terminal, none with `--quiet`)
//! and `silrig top` attached to a realtime rig, showing every process and changing none of the rig's counters.
//! Each test uses its own run ids and folders; the launchers reap their children and clean up, and the test checks
//! that they did. No timing figure is asserted.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{no_shared_memory_left, temp_dir, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

fn report(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap()
}

fn counters(r: &Value, process: &str) -> serde_json::Map<String, Value> {
    let p = r["processes"].as_array().unwrap().iter().find(|p| p["process"] == process).unwrap();
    p["counters"].as_object().unwrap().clone()
}

#[test]
fn top_shows_every_process_of_a_running_rig_and_changes_none_of_its_counters() {
    let dir = temp_dir("live", "top");
    let (watched, alone) = (format!("t{}-top-a", std::process::id()), format!("t{}-top-b", std::process::id()));
    let (out_watched, out_alone) = (dir.join("watched"), dir.join("alone"));
    let run = |id: &str, out: &Path, quiet: bool| {
        let mut args = vec!["run", "--duration-s", "4", "--run-id", id, "--out", out.to_str().unwrap()];
        if quiet {
            args.push("--quiet");
        }
        Command::new(SILRIG).args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap()
    };
    let rig_watched = run(&watched, &out_watched, false);
    let rig_alone = run(&alone, &out_alone, true);
    let status = Path::new("/dev/shm").join(format!("silrig_{watched}")).join("status");
    let start = Instant::now();
    while !status.join("plant.json").exists() {
        assert!(start.elapsed() < Duration::from_secs(20), "no status from the plant");
        std::thread::sleep(Duration::from_millis(20));
    }
    let top =
        Command::new(SILRIG).args(["top", &watched]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let top = wait_with_watchdog(top, Duration::from_secs(60));
    let (watched_o, alone_o) = (
        wait_with_watchdog(rig_watched, Duration::from_secs(60)),
        wait_with_watchdog(rig_alone, Duration::from_secs(60)),
    );
    assert!(watched_o.status.success() && alone_o.status.success());

    let shown = String::from_utf8_lossy(&top.stdout);
    assert!(top.status.success(), "{shown}{}", String::from_utf8_lossy(&top.stderr));
    for figure in ["plant ", "controller ", "logger ", "wake_lateness", "compute", "ticks", "rows_written", "has ended"]
    {
        assert!(shown.contains(figure), "top shows no {figure}:\n{shown}");
    }
    // Without a terminal, one live line a second on stderr; none with --quiet.
    let live = String::from_utf8_lossy(&watched_o.stderr);
    assert!(live.lines().filter(|l| l.starts_with("t ") && l.contains(" ticks ")).count() >= 2, "{live}");
    assert!(!String::from_utf8_lossy(&alone_o.stderr).contains(" ticks "));

    let (a, b) = (report(&out_watched), report(&out_alone));
    for r in [&a, &b] {
        assert_eq!(r["failures"].as_array().unwrap().len(), 0, "{}", r["failures"]);
        assert_eq!(r["leftovers"].as_array().unwrap().len(), 0, "{}", r["leftovers"]);
    }
    for process in ["plant", "controller", "logger"] {
        let (ca, cb) = (counters(&a, process), counters(&b, process));
        assert_eq!(ca.keys().collect::<Vec<_>>(), cb.keys().collect::<Vec<_>>(), "{process}");
        for lost in ["commands_lost", "plant_samples_lost", "command_samples_lost", "invalid_samples"] {
            if let Some(v) = ca.get(lost) {
                assert_eq!(v, &cb[lost], "{process}.{lost}");
                assert_eq!(v, 0, "{process}.{lost}");
            }
        }
    }
    assert_eq!(counters(&a, "plant")["ticks"], counters(&b, "plant")["ticks"]);
    assert_eq!(counters(&a, "logger")["rows_written"], counters(&b, "logger")["rows_written"]);
    no_shared_memory_left(&watched);
    no_shared_memory_left(&alone);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn top_of_a_run_that_does_not_exist_says_so_and_lists_the_runs_it_sees() {
    let o = Command::new(SILRIG).args(["top", &format!("t{}-nosuch", std::process::id())]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no running rig with run id") && err.contains("running rigs it can see: "), "{err}");
}

/// Without the `live` feature, `silrig run --live foxglove` is refused before anything starts, naming the feature
/// and the build command (with it, tests/foxglove_live.rs flies it).
#[cfg(not(feature = "live"))]
#[test]
fn live_foxglove_without_the_feature_is_refused_with_the_build_command() {
    let stderr = common::Run::refused(SILRIG, "live", "lv", "nofeature", &["--live", "foxglove", "--duration-s", "1"]);
    assert!(stderr.contains("`live` feature") && stderr.contains("cargo build --release --features live"), "{stderr}");
}

/// `--live` takes `foxglove` or `foxglove=IP:PORT`; anything else is refused, saying what was wrong.
#[test]
fn a_live_target_other_than_foxglove_at_an_address_is_refused() {
    for (value, said) in
        [("rerun", "`rerun` is no live protocol"), ("foxglove=localhost", "`localhost` is no IP:PORT address")]
    {
        let stderr = common::Run::refused(SILRIG, "live", "lv", "badtarget", &["--live", value, "--duration-s", "1"]);
        assert!(stderr.contains(said), "--live {value}: {stderr}");
    }
}
