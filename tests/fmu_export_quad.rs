//! The built-in quadrotor exported as an FMI 2.0 co-simulation FMU (`silrig export-fmu` of a scenario with
//! `[plant] model = "quad"`), checked by an independent importer, FMPy (PyPI `fmpy`, in `target/test-venv`),
//! through `tests/fmu/fly_quad_fmu.py` and `tests/fmu/fly_fmu.py` (the F-16's checks it shares): FMPy's validation
//! reports no problems and `simulate_fmu` flies the default experiment; its variables are the quadrotor's outputs,
//! motor commands and `[plant.parameters]` by the rig's names; fed the motor commands of `silrig sim`'s trace of
//! the same scenario (our quadrotor controller's), it gives that trace's outputs bit for bit, from the ground
//! (`quad-hover`) and in the air with attitude steps (`quad-steps`); a saved and serialised state continues
//! bit-identically; a wrong GUID is refused; what of the scenario it leaves out is said.

mod common;

use common::fmu::{export_builtin, fmpy_python};
use common::temp_dir;
use silrig::quad::outputs::{INPUTS, OUTPUTS};
use silrig::quad::params::{PARAMS, START_VALUES};
use std::path::{Path, PathBuf};
use std::process::Command;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn config(name: &str) -> String {
    format!("{ROOT}/configs/{name}.toml")
}

/// `SCRIPT ARGS` (in tests/fmu) under the test venv's Python with FMPy; its stdout.
fn fmpy(script: &str, args: &[&str]) -> String {
    let o = Command::new(fmpy_python()).arg(format!("{ROOT}/tests/fmu/{script}")).args(args).output().unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{script} {args:?} failed: {stdout}{stderr}");
    stdout.into_owned()
}

fn export(dir: &Path, name: &str, scenario: &str) -> (PathBuf, String) {
    export_builtin(SILRIG, dir, name, Some(scenario))
}

#[test]
fn fmpy_validates_the_quadrotor_and_reads_the_rigs_names() {
    let dir = temp_dir("fmu_export_quad", "validate");
    let (fmu, said) = export(&dir, "quad.fmu", &config("quad-hover"));
    assert!(said.contains("FMI 2.0 co-simulation, GUID {"), "{said}");
    assert_eq!(fmpy("fly_fmu.py", &["validate", fmu.to_str().unwrap()]).trim(), "no problems");
    let described = fmpy("fly_quad_fmu.py", &["describe", fmu.to_str().unwrap()]);
    let mut lines = described.lines();
    assert_eq!(lines.next(), Some("silrig_fmu_quad"));
    let variables: Vec<Vec<&str>> = lines.map(|l| l.split(' ').collect()).collect();
    let named =
        |causality: &str| -> Vec<&str> { variables.iter().filter(|v| v[0] == causality).map(|v| v[1]).collect() };
    assert_eq!(named("output"), OUTPUTS.map(|o| o.0), "the outputs in the rig's order");
    assert_eq!(named("input"), INPUTS.map(|i| i.0));
    let parameters: Vec<&str> = PARAMS.iter().chain(&START_VALUES).map(|p| p.name).collect();
    assert_eq!(named("parameter"), parameters);
    // The scenario's values are the start values: quad-hover's mass and its start on the ground.
    assert!(variables.contains(&vec!["parameter", "mass_kg", "kg", "0.68"]), "{described}");
    assert!(variables.contains(&vec!["input", "motor1", "1", "0.0"]), "stopped on the ground: {described}");
    let simulated = fmpy("fly_quad_fmu.py", &["simulate", fmu.to_str().unwrap()]);
    // The default experiment is the scenario's (10 s at 1 ms); the motors held stopped, it stays on the ground.
    assert_eq!(simulated.trim(), "10001 samples; final alt_m 0.0");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `silrig sim SCENARIO`'s trace, and the scenario's FMU fed its motor commands: every output bit for bit.
fn replay_equals_sim(scenario: &str) {
    let dir = temp_dir("fmu_export_quad", scenario);
    let out = dir.join("sim");
    let o = Command::new(SILRIG).arg("sim").arg(config(scenario)).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let (fmu, said) = export(&dir, "quad.fmu", &config(scenario));
    assert!(!said.contains("note:"), "the FMU carries all of {scenario}: {said}");
    // The scenarios fly `command_timing = "next-tick"`: the command of tick k acts over the step after tick k + 1.
    let trace = out.join("trace.csv");
    let replayed = fmpy("fly_quad_fmu.py", &["replay", fmu.to_str().unwrap(), trace.to_str().unwrap(), "1"]);
    eprintln!("{scenario}: {replayed}");
    let rows = std::fs::read_to_string(&trace).unwrap().lines().count() - 1;
    let values = rows * OUTPUTS.len();
    assert_eq!(replayed.trim(), format!("{rows} rows; {values} values; {values} bit-identical"));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn fed_the_sim_traces_commands_from_the_ground_it_gives_the_trace_bit_for_bit() {
    replay_equals_sim("quad-hover");
}

#[test]
fn fed_the_sim_traces_commands_through_attitude_steps_it_gives_the_trace_bit_for_bit() {
    replay_equals_sim("quad-steps");
}

#[test]
fn a_saved_and_serialised_state_continues_bit_for_bit_and_a_wrong_guid_is_refused() {
    let dir = temp_dir("fmu_export_quad", "state");
    let (fmu, _) = export(&dir, "quad.fmu", &config("quad-steps"));
    let said = fmpy("fly_quad_fmu.py", &["state", fmu.to_str().unwrap()]);
    eprintln!("{said}");
    for case in ["setFMUstate", "deserialised", "second instance"] {
        assert!(said.contains(&format!("{case}: bit-identical over 400 samples")), "{said}");
    }
    let moved: usize = said.split("outputs that moved over the 0.4 s: ").nth(1).unwrap().trim().parse().unwrap();
    assert!(moved > 20, "{said}");
    let refused = fmpy("fly_fmu.py", &["wrong-guid", fmu.to_str().unwrap()]);
    assert!(refused.contains("wrong GUID {00000000-0000-0000-0000-000000000000}"), "{refused}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn what_the_fmu_leaves_out_is_said_and_an_f16_key_is_refused() {
    let dir = temp_dir("fmu_export_quad", "notes");
    let text = std::fs::read_to_string(config("quad-hover")).unwrap();
    let lagged = dir.join("lagged.toml");
    let with_lag = "[actuators.motor1]\nmin = 0.0\nmax = 1.0\nlag_time_constant_s = 0.02";
    std::fs::write(&lagged, text.replace("[actuators.motor1]\nmin = 0.0\nmax = 1.0", with_lag)).unwrap();
    let (_, said) = export(&dir, "lagged.fmu", lagged.to_str().unwrap());
    assert!(said.contains("note: the scenario's [actuators.motor*] lags, rate limits and stops"), "{said}");
    let f16_key = dir.join("f16-key.toml");
    std::fs::write(&f16_key, text.replace("[plant]\nmodel = \"quad\"", "[plant]\nmodel = \"quad\"\nxcg = 0.3"))
        .unwrap();
    let o = Command::new(SILRIG).arg("export-fmu").arg("--out").arg(dir.join("x.fmu")).arg(&f16_key).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("`plant.xcg`: is the F-16's"), "{stderr}");
    assert!(!dir.join("x.fmu").exists());
    std::fs::remove_dir_all(dir).unwrap();
}
