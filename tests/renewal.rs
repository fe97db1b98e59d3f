//! A restarted controller that joins the run but never takes a sample is killed and started again by the launcher,
//! and the flight goes on under the controller's next life. iceoryx2 0.10 sometimes never connects a subscriber
//! that joins a publisher already running (iceoryx2 #129); an hour's soak saw a restarted controller and logger
//! take nothing for 17 s while the plant flew its failsafe out of the model's envelope. Here the stuck life is a C
//! program that opens its session (its node and subscribers exist) and sleeps; a shell wrapper runs it as the
//! controller's second life, between two lives of the example C PID.

mod common;

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

/// Opens a controller session of the run in its environment and never asks for a sample.
const STUCK_C: &str = r#"#define _POSIX_C_SOURCE 200809L
#include <unistd.h>
#include "silrig_client.h"
static const char *const NAMES[3] = {"err_phi_deg", "err_theta_deg", "err_psi_deg"};
int main(void) {
    silrig_session *session = NULL;
    if (SILRIG_SESSION_OPEN(NAMES, 3, &session) != SILRIG_OK) {
        return 2;
    }
    sleep(120);
    return 0;
}
"#;

fn compile_stuck(dir: &Path) -> String {
    let source = dir.join("stuck.c");
    std::fs::write(&source, STUCK_C).unwrap();
    let exe = dir.join("stuck");
    common::compile_c(SILRIG, &source, &exe);
    exe.display().to_string()
}

fn events(out: &Path) -> Vec<Value> {
    let text = std::fs::read_to_string(out.join("events.jsonl")).unwrap();
    text.lines().map(|l| serde_json::from_str(l).unwrap()).collect()
}

#[test]
fn a_restarted_controller_that_takes_no_sample_is_started_again_and_the_flight_goes_on() {
    let dir = common::temp_dir("renewal", "stuck");
    let pid = common::c_pid(SILRIG, "renewal");
    let stuck = compile_stuck(&dir);
    // Lives 1 and 3 fly the PID, life 2 is stuck: the wrapper counts its lives in a file.
    let lives = dir.join("lives");
    let script = dir.join("controller.sh");
    let body = format!(
        "n=$(cat {l} 2>/dev/null || echo 0)\necho $((n + 1)) > {l}\nif [ \"$n\" = 1 ]; then exec {stuck}; else exec {pid}; \
         fi\n",
        l = lives.display()
    );
    std::fs::write(&script, body).unwrap();
    let wrapper = format!("sh {}", script.display());
    let out = dir.join("run");
    let id = format!("rn{}", std::process::id());
    let child = Command::new(SILRIG)
        .args(["run", "--no-baseline", "--quiet", "--run-id", &id, "--duration-s", "12"])
        .args(["--fault", "controller:kill@2s,restart_after=0.2s", "--controller-cmd", &wrapper, "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = common::wait_with_watchdog(child, Duration::from_secs(120));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert_eq!(std::fs::read_to_string(&lives).unwrap().trim(), "3", "three lives: {text}");
    let ev = events(&out);
    let renewed = ev.iter().find(|e| e["kind"] == "process-renewed").unwrap_or_else(|| panic!("no renewal: {text}"));
    let detail = renewed["detail"].as_str().unwrap();
    assert!(
        detail.contains("controller pid") && detail.contains("took no sample") && detail.contains("#129"),
        "{detail}"
    );
    // The plant flies under the third life: commands resume after the renewal.
    let renewed_ns = renewed["t_ns"].as_u64().unwrap();
    let resumed = ev.iter().any(|e| {
        e["process"] == "plant" && e["kind"] == "controller-recovered" && e["t_ns"].as_u64().unwrap() > renewed_ns
    });
    assert!(resumed, "no commands after the renewal: {text}");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let exits: Vec<&str> = report["lives"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|l| l["process"] == "controller")
        .map(|l| l["exit"].as_str().unwrap_or(""))
        .collect();
    assert_eq!(exits.len(), 3, "{exits:?}");
    assert!(exits[1].contains("renewed: it took no sample"), "{exits:?}");
    assert!(report["failures"].as_array().unwrap().is_empty(), "{text}");
    common::no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}
