//! Warm rigs (`silrig sweep --controller-cmd`, each case's processes forked from programs kept warm): every case of
//! a 50-case sweep flown warm is its cold twin (`--cold`: fresh processes, a case flown alone) byte for byte in its
//! trace, with our controller, the C PID and the Python PID, and the sweeps' `cases.csv` are the same; a controller
//! that keeps state from one flight to the next is named on stderr and the sweep flies on cold. A case whose rig
//! fails starts its rig again (tests/sweep_rig.rs: crashing and silent controllers, whose sweeps fly warm).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "sweep_warm";

/// configs/sweep-robust.toml shortened to 1 s (its criteria's windows with it), the theta set point dispersed too.
fn short_config(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(Path::new(ROOT).join("configs/sweep-robust.toml")).unwrap();
    let text = text
        .replace("duration_s = 10.0", "duration_s = 1.0")
        .replace("within_s = 8.0", "within_s = 0.8")
        .replace("after_s = 8.0", "after_s = 0.8")
        .replace(
            "[dispersions]\n",
            "[dispersions]\n\"setpoint.theta_deg\" = { dist = \"uniform\", min = 5.0, max = 15.0 }\n",
        );
    assert!(text.contains("duration_s = 1.0") && text.contains("setpoint.theta_deg"), "the shipped sweep changed");
    let path = dir.join("short.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `silrig sweep` of `runs` cases of `config` on two rigs with `controller` (and `extra` flags), each case's trace
/// kept in `keep`; 10 minutes at most. Returns (cases.csv, stderr). Its rigs (run ids `r<its pid>-...`) left no
/// shared memory, and its scratch folders are gone.
fn sweep(config: &Path, runs: u32, controller: &str, extra: &[&str], out: &Path, keep: &Path) -> (String, String) {
    let mut command = Command::new(SILRIG);
    command.args(["sweep", config.to_str().unwrap(), "--runs", &runs.to_string(), "--jobs", "2"]);
    command.args(["--controller-cmd", controller, "--out", out.to_str().unwrap()]).args(extra);
    let child = command
        .env("SILRIG_SWEEP_KEEP", keep)
        .current_dir(ROOT)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let o = common::wait_with_watchdog(child, Duration::from_secs(600));
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "silrig sweep {controller} {extra:?}: {stderr}");
    common::assert_sweep_left_nothing(pid);
    (std::fs::read_to_string(out.join("cases.csv")).unwrap(), stderr)
}

/// Fly the 50 cases warm and cold with `controller`: every trace the same bytes, and every case judged alike.
fn warm_equals_cold(name: &str, controller: &str) {
    let dir = common::temp_dir(SUITE, name);
    let config = short_config(&dir);
    let (warm_csv, warm_err) = sweep(&config, 50, controller, &[], &dir.join("warm"), &dir.join("warm-traces"));
    assert!(!warm_err.contains("flying every case cold"), "{name} flew warm: {warm_err}");
    let (cold_csv, _) = sweep(&config, 50, controller, &["--cold"], &dir.join("cold"), &dir.join("cold-traces"));
    assert_eq!(warm_csv, cold_csv, "{name}: cases.csv warm and cold");
    let mut flown = 0;
    for i in 0..50 {
        let file = format!("case-{i}.trace.csv");
        let warm = std::fs::read(dir.join("warm-traces").join(&file)).unwrap();
        let cold = std::fs::read(dir.join("cold-traces").join(&file)).unwrap();
        assert!(warm == cold, "{name}: case {i}'s trace differs warm and cold");
        flown += usize::from(warm.len() > 100);
    }
    // Some cases of the dispersed envelope cannot be trimmed: they fly in neither.
    assert!(flown >= 40, "{name}: only {flown} of 50 cases left a trace");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_case_of_a_warm_sweep_of_our_controller_is_its_cold_twin() {
    common::client_lib(SILRIG);
    warm_equals_cold("ours", &format!("{ROOT}/tests/clients/our_controller.sh"));
}

#[test]
fn every_case_of_a_warm_sweep_of_the_c_pid_is_its_cold_twin() {
    let dir = common::temp_dir(SUITE, "c-build");
    let lib = common::client_lib(SILRIG).parent().unwrap().to_path_buf();
    let pid = dir.join("pid_attitude");
    let o = Command::new("cc")
        .args(["-std=c11", "-O2", "-I", &format!("{ROOT}/examples/c")])
        .arg(format!("{ROOT}/examples/c/pid_attitude.c"))
        .args(["-L", lib.to_str().unwrap(), "-lsilrig_client", &format!("-Wl,-rpath,{}", lib.display()), "-lm"])
        .arg("-o")
        .arg(&pid)
        .output()
        .unwrap();
    assert!(o.status.success(), "cc: {}", String::from_utf8_lossy(&o.stderr));
    warm_equals_cold("c-pid", pid.to_str().unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_case_of_a_warm_sweep_of_the_python_pid_is_its_cold_twin() {
    common::client_lib(SILRIG);
    warm_equals_cold("python-pid", &format!("python3 {ROOT}/examples/python/pid_attitude.py"));
}

#[test]
fn a_controller_that_keeps_state_across_flights_is_named_and_the_sweep_flies_on_cold() {
    common::client_lib(SILRIG);
    let dir = common::temp_dir(SUITE, "keeps-state");
    let config = short_config(&dir);
    let state = dir.join("flights");
    let controller = format!("python3 {ROOT}/tests/clients/keeps_state.py {}", state.display());
    let (csv, stderr) = sweep(&config, 6, &controller, &[], &dir.join("out"), &dir.join("traces"));
    assert!(
        stderr.contains("a program of the rig keeps state from one flight to the next")
            && stderr.contains("flying every case cold (fresh processes) from here"),
        "{stderr}"
    );
    assert_eq!(stderr.matches("keeps state").count(), 1, "said once: {stderr}");
    assert_eq!(csv.lines().filter(|l| l.contains(",pass,") || l.contains(",fail,")).count(), 6, "{csv}");
    std::fs::remove_dir_all(&dir).unwrap();
}
