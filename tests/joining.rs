//! A role that never joins the run, or ends before it does: the run fails within the start-up timeout (a bound
//! with generous slack here, never a timing figure), its first failure names that role, its command, how long it
//! was waited for and what to check, and neither the peers that gave up waiting for it nor the launcher's own
//! SIGTERM are blamed. Each run has its own run id and folder, reaped and removed.

mod common;

use common::Run;
use std::time::{Duration, Instant};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
/// The start-up timeout the runs here are given, s.
const TIMEOUT_S: f64 = 2.0;

/// `silrig run` with `args` and a start-up timeout of [`TIMEOUT_S`], and how long it took from outside.
fn run(test: &str, args: &[&str]) -> (Run, Duration) {
    let timeout = TIMEOUT_S.to_string();
    let mut all = vec!["--duration-s", "2", "--startup-timeout-s", &timeout];
    all.extend_from_slice(args);
    let start = Instant::now();
    let r = Run::start(SILRIG, "joining", "j", test, &all);
    (r, start.elapsed())
}

/// The report's failures, each in words; the first FAILED line printed is the first of them.
fn failures(r: &Run) -> Vec<String> {
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures: Vec<String> =
        r.report["failures"].as_array().unwrap().iter().map(|f| f.as_str().unwrap().to_string()).collect();
    for f in &failures {
        common::assert_in_words("a failure of the run", f);
        assert!(!f.contains("killed by signal 15"), "the launcher's SIGTERM blamed: {f}");
    }
    let first = r.stdout.lines().find(|l| l.starts_with("FAILED: ")).unwrap_or_else(|| panic!("{}", r.stdout));
    assert_eq!(first, format!("FAILED: {}", failures[0]), "{}", r.stdout);
    failures
}

/// The run ended well before the peers' own give-up (twice the timeout) plus a stop: a correctness bound.
fn ended_in_time(took: Duration, r: &Run) {
    assert!(took.as_secs_f64() < TIMEOUT_S + 15.0, "took {took:?}: {}", r.stdout);
}

/// Nobody but `role` is blamed: one failure, `role`'s.
fn only_failure_is(role: &str, failures: &[String]) {
    assert_eq!(failures.len(), 1, "{failures:#?}");
    assert!(failures[0].starts_with(&format!("{role}: ")), "{failures:#?}");
}

#[test]
fn a_plant_command_that_never_joins_is_named_within_the_start_up_timeout() {
    let (r, took) = run("plant-never", &["--plant-cmd", "sleep 100"]);
    let failures = failures(&r);
    only_failure_is("plant", &failures);
    let f = &failures[0];
    assert!(f.starts_with("plant: your --plant-cmd `sleep 100` (pid "), "{f}");
    assert!(f.contains(&format!("never joined run `{}`: no node of its own after 2.", r.id)), "{f}");
    assert!(f.contains("(--startup-timeout-s)") && f.contains("plant session") && f.contains("serve_plant"), "{f}");
    // Not waited for twice: the controller's own give-up (twice the timeout) is not what ended the run.
    let waited_s: f64 = f.split("after ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((TIMEOUT_S..2.0 * TIMEOUT_S).contains(&waited_s), "{f}");
    ended_in_time(took, &r);
    assert!(r.event("launcher", "process-never-joined").is_some());
    // Its life says the launcher stopped it for that, not that it died.
    let lives = r.report["lives"].as_array().unwrap();
    let plant = lives.iter().find(|l| l["process"] == "plant").unwrap();
    assert!(
        plant["exit"].as_str().unwrap().ends_with("on the launcher's SIGTERM (it never joined the run)"),
        "{plant}"
    );
    r.finish();
}

#[test]
fn a_controller_command_that_never_joins_is_named_and_the_plant_giving_up_is_not_blamed() {
    let (r, took) = run("controller-never", &["--controller-cmd", "sleep 100"]);
    let failures = failures(&r);
    only_failure_is("controller", &failures);
    let f = &failures[0];
    assert!(f.starts_with("controller: your --controller-cmd `sleep 100` (pid "), "{f}");
    assert!(f.contains("never joined run") && f.contains("controller session") && f.contains("serve"), "{f}");
    ended_in_time(took, &r);
    r.finish();
}

#[test]
fn a_plant_command_that_exits_at_once_is_named_with_its_status_and_stderr() {
    let cmd = "sh -c 'echo cannot open my model file >&2; exit 3'";
    let (r, took) = run("plant-exits", &["--plant-cmd", cmd]);
    let failures = failures(&r);
    only_failure_is("plant", &failures);
    let f = &failures[0];
    let head = format!("plant: your --plant-cmd `{cmd}` (pid ");
    assert!(f.starts_with(&head) && f.contains(") ended before it joined the run (exit status 3, "), "{f}");
    assert!(f.ends_with("; its stderr ends: cannot open my model file"), "{f}");
    ended_in_time(took, &r);
    r.finish();
}
