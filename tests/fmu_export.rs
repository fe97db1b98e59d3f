//! The built-in F-16 exported as an FMI 2.0 co-simulation FMU (`silrig export-fmu`), checked by an independent
//! importer, FMPy (PyPI `fmpy`, in `target/test-venv`), through `tests/fmu/fly_fmu.py`: its validation reports no
//! problems and `simulate_fmu` flies the default experiment; a scripted run of a trimmed open-loop flight (inputs
//! held at the trim command, and an elevator doublet with an aileron step) gives, at t = 0 and after each of 1000
//! doSteps of 0.01 s, the very outputs the built-in plant gives stepped here in Rust with the same inputs (compared
//! bit for bit, far inside the required 1e-9); parameters set by name reproduce a scenario; a saved, serialised
//! and restored state continues bit-identically, in the same instance and in another; a wrong GUID is refused.
//! Flown back through the rig's own importer (`silrig run --plant-fmu`, lockstep, our controller), the export of a
//! scenario gives that scenario's `trace.csv` of the built-in plant byte for byte.

mod common;

use common::{temp_dir, venv_python};
use silrig::f16_outputs::{OUTPUTS_LEN, f16_outputs, output_signals};
use silrig::scenario::Scenario;
use silrig::sim::{ActuatorCommand, PlantRunner};
use std::path::{Path, PathBuf};
use std::process::Command;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fmu/fly_fmu.py");
const SCENARIO: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenarios/fmu_trim.toml");

/// `silrig export-fmu --out DIR/NAME [SCENARIO]`; the FMU's path and what it printed.
fn export(dir: &Path, name: &str, scenario: Option<&str>) -> (PathBuf, String) {
    common::fmu::export_builtin(SILRIG, dir, name, scenario)
}

/// `fly_fmu.py ARGS` under the test venv's Python with FMPy; its stdout.
fn fmpy(args: &[&str]) -> String {
    let python = venv_python("fmpy", "fmpy");
    let o = Command::new(python).arg(SCRIPT).args(args).output().unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "fly_fmu.py {args:?} failed: {stdout}{stderr}");
    stdout.into_owned()
}

/// The inputs over step k: the same numbers as `fly_fmu.py`'s `command`.
fn command(program: &str, trim: &ActuatorCommand, k: usize) -> ActuatorCommand {
    let mut c = *trim;
    if program == "doublet" {
        if (100..200).contains(&k) {
            c.surfaces.elevator_deg = trim.surfaces.elevator_deg + 2.0;
        } else if (200..300).contains(&k) {
            c.surfaces.elevator_deg = trim.surfaces.elevator_deg - 2.0;
        }
        if k >= 400 {
            c.surfaces.aileron_deg = trim.surfaces.aileron_deg + 5.0;
        }
    }
    c
}

/// The built-in plant of `scenario` as the rig's plant process steps it (`F16Plant`: `PlantRunner::step` with the
/// inputs, then the outputs of the next snapshot): the outputs at t = 0 and after each of 1000 steps.
fn built_in(scenario: &Scenario, program: &str) -> Vec<[f64; OUTPUTS_LEN]> {
    let mut runner = PlantRunner::new(scenario).unwrap();
    let trim = runner.initial_command();
    let mut rows = vec![f16_outputs(&runner.snapshot())];
    for k in 0..1000 {
        runner.step(&command(program, &trim, k)).unwrap();
        rows.push(f16_outputs(&runner.snapshot()));
    }
    rows
}

/// How two flights compare, column by column.
struct Agreement {
    /// Values compared.
    values: usize,
    /// Of those, bit-identical.
    identical: usize,
    /// Largest |fmu - rust|, and its column.
    max_abs: (f64, String),
    /// Largest |fmu - rust| / max(|rust|, 1e-300), and its column.
    max_rel: (f64, String),
}

/// The FMU's CSV (header of output names, repr() of each double) against the built-in plant's rows.
fn compare(csv: &Path, rust: &[[f64; OUTPUTS_LEN]]) -> Agreement {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let names: Vec<&str> = lines.next().unwrap().split(',').collect();
    let expected: Vec<&str> = output_signals().iter().map(|(n, _, _)| *n).collect();
    assert_eq!(names, expected, "the FMU's outputs are not the built-in plant's, in its order");
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), rust.len(), "samples");
    let mut a = Agreement { values: 0, identical: 0, max_abs: (0.0, String::new()), max_rel: (0.0, String::new()) };
    for (fmu, rust) in rows.iter().zip(rust) {
        for (k, (x, y)) in fmu.iter().zip(rust).enumerate() {
            a.values += 1;
            a.identical += usize::from(x.to_bits() == y.to_bits());
            let abs = (x - y).abs();
            let rel = abs / y.abs().max(1e-300);
            // NaN (a value one side has and the other not) counts as the largest.
            if abs > a.max_abs.0 || abs.is_nan() {
                a.max_abs = (abs, names[k].to_string());
            }
            if rel > a.max_rel.0 || rel.is_nan() {
                a.max_rel = (rel, names[k].to_string());
            }
        }
    }
    a
}

/// Fly `fmu` from FMPy with `params` ("none" or an FMU to copy parameters from) and `program`, and compare with
/// the built-in plant of `scenario`: every output within 1e-9, relative where |value| > 1 and absolute below, and
/// in fact bit for bit.
fn fly_and_compare(dir: &Path, fmu: &Path, params: &str, program: &str, scenario: &Scenario) -> Agreement {
    let csv = dir.join(format!("{program}.csv"));
    let said = fmpy(&["fly", fmu.to_str().unwrap(), params, program, csv.to_str().unwrap()]);
    assert_eq!(said.trim(), "1001 rows");
    let rust = built_in(scenario, program);
    let a = compare(&csv, &rust);
    eprintln!(
        "{program} ({}): {} of {} values bit-identical; largest |difference| {:e} ({}), relative {:e} ({})",
        if params == "none" { "start values of the export" } else { "parameters set by name" },
        a.identical,
        a.values,
        a.max_abs.0,
        a.max_abs.1,
        a.max_rel.0,
        a.max_rel.1
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    for (fmu, rust) in text.lines().skip(1).zip(&rust) {
        for (x, y) in fmu.split(',').map(|v| v.parse::<f64>().unwrap()).zip(rust) {
            assert!((x - y).abs() <= 1e-9 * y.abs().max(1.0), "{x} against {y}");
        }
    }
    assert_eq!(a.identical, a.values, "not bit for bit: largest difference {:e} in {}", a.max_abs.0, a.max_abs.1);
    a
}

#[test]
fn fmpy_validates_the_export_and_simulates_it() {
    let dir = temp_dir("fmu_export", "validate");
    let (plain, said) = export(&dir, "f16.fmu", None);
    assert!(said.contains("FMI 2.0 co-simulation, GUID {"), "{said}");
    assert_eq!(fmpy(&["validate", plain.to_str().unwrap()]).trim(), "no problems");
    let (from_scenario, _) = export(&dir, "f16-trim.fmu", Some(SCENARIO));
    assert_eq!(fmpy(&["validate", from_scenario.to_str().unwrap()]).trim(), "no problems");
    let simulated = fmpy(&["simulate", from_scenario.to_str().unwrap()]);
    // The default experiment is the scenario's: 10 s at 0.01 s.
    assert!(simulated.starts_with("1001 samples; final theta_deg "), "{simulated}");
    // What of a scenario the FMU leaves out is said: the default scenario's disturbance.
    let robust = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/robust.toml");
    let (_, said) = export(&dir, "robust.fmu", Some(robust));
    assert!(said.contains("note: the scenario's [disturbance] is not in the FMU"), "{said}");
}

#[test]
fn a_scripted_fmpy_flight_is_the_built_in_plants_bit_for_bit() {
    let dir = temp_dir("fmu_export", "flight");
    let scenario = Scenario::load(Path::new(SCENARIO)).unwrap();
    let (fmu, _) = export(&dir, "f16-trim.fmu", Some(SCENARIO));
    let held = fly_and_compare(&dir, &fmu, "none", "hold", &scenario);
    assert!(held.values == 1001 * OUTPUTS_LEN);
    fly_and_compare(&dir, &fmu, "none", "doublet", &scenario);
    // The book's FMU with the scenario's parameters set by name (copied from the other FMU's start values by FMPy)
    // flies the scenario's plant.
    let (plain, _) = export(&dir, "f16.fmu", None);
    fly_and_compare(&dir, &plain, fmu.to_str().unwrap(), "doublet", &scenario);
}

#[test]
fn a_saved_and_serialised_state_continues_bit_for_bit() {
    let dir = temp_dir("fmu_export", "state");
    let (fmu, _) = export(&dir, "f16-trim.fmu", Some(SCENARIO));
    let said = fmpy(&["state", fmu.to_str().unwrap()]);
    eprintln!("{said}");
    for case in ["setFMUstate", "deserialised", "second instance"] {
        assert!(said.contains(&format!("{case}: bit-identical over 301 samples")), "{said}");
    }
    // Not a flight that stood still: the doublet and the aileron step moved the outputs.
    let moved: usize = said.split("outputs that moved over the 3 s: ").nth(1).unwrap().trim().parse().unwrap();
    assert!(moved > 20, "{said}");
}

#[test]
fn a_wrong_guid_is_refused() {
    let dir = temp_dir("fmu_export", "guid");
    let (fmu, _) = export(&dir, "f16.fmu", None);
    let said = fmpy(&["wrong-guid", fmu.to_str().unwrap()]);
    assert!(said.contains("refused: Failed to instantiate model"), "{said}");
    assert!(said.contains("wrong GUID {00000000-0000-0000-0000-000000000000}"), "{said}");
}

#[test]
fn a_missing_library_is_named_with_the_command_that_builds_it() {
    // A copy of `silrig` in a folder without the library.
    let dir = temp_dir("fmu_export", "missing");
    let copy = dir.join("silrig");
    common::copy_program(Path::new(SILRIG), &copy);
    let o = Command::new(&copy).args(["export-fmu", "--out"]).arg(dir.join("f16.fmu")).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    let lib = dir.join("libsilrig_fmu_f16.so");
    assert!(stderr.contains(&format!("{} not found", lib.display())), "{stderr}");
    assert!(stderr.contains("cargo build --release -p silrig-fmu-f16"), "{stderr}");
    assert!(!dir.join("f16.fmu").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// `configs/robust.toml` without its disturbance (an input the FMU does not have), and the same without the
/// `[actuators.*]` tables (the FMU carries them, from the export): what the built-in plant and the FMU fly.
fn robust_undisturbed(dir: &Path) -> (String, String) {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/robust.toml")).unwrap();
    let undisturbed: String = text
        .lines()
        .map(|l| if l.starts_with("amplitude_radps2") { "amplitude_radps2 = 0.0" } else { l })
        .map(|l| format!("{l}\n"))
        .collect();
    let mut in_actuators = false;
    let for_fmu: String = undisturbed
        .lines()
        .filter(|l| {
            if l.starts_with('[') {
                in_actuators = l.starts_with("[actuators.");
            }
            !in_actuators
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let (builtin, fmu) = (dir.join("robust-undisturbed.toml"), dir.join("robust-fmu.toml"));
    std::fs::write(&builtin, undisturbed).unwrap();
    std::fs::write(&fmu, for_fmu).unwrap();
    (builtin.display().to_string(), fmu.display().to_string())
}

#[test]
fn flown_back_through_plant_fmu_the_export_gives_the_built_in_trace_byte_for_byte() {
    let dir = temp_dir("fmu-export", "flown-back-files");
    let (builtin_scenario, fmu_scenario) = robust_undisturbed(&dir);
    let (fmu, _) = export(&dir, "f16.fmu", Some(&builtin_scenario));
    let builtin = common::Run::start(SILRIG, "fmu-export", "e", "builtin", &["--mode", "lockstep", &builtin_scenario]);
    assert_eq!(builtin.code, Some(0), "{}\n{}", builtin.stdout, builtin.stderr);
    let flown = common::Run::start(
        SILRIG,
        "fmu-export",
        "e",
        "flown-back",
        &["--mode", "lockstep", "--plant-fmu", fmu.to_str().unwrap(), &fmu_scenario],
    );
    assert_eq!(flown.code, Some(0), "{}\n{}", flown.stdout, flown.stderr);
    let (a, b) = (builtin.trace(), flown.trace());
    assert_eq!(a.0, b.0, "the columns differ");
    assert_eq!(a.1.len(), 1001);
    for (k, (x, y)) in a.1.iter().zip(&b.1).enumerate() {
        for (c, (u, v)) in x.iter().zip(y).enumerate() {
            assert!(u.to_bits() == v.to_bits(), "tick {k}, {}: built-in {u}, FMU {v}", a.0[c]);
        }
    }
    let bytes = |r: &common::Run| std::fs::read(r.out.join("trace.csv")).unwrap();
    assert_eq!(bytes(&builtin), bytes(&flown), "trace.csv differs");
    let started = flown.event("plant", "plant-fmu").unwrap();
    assert!(started["detail"].as_str().unwrap().contains("checkpoints through its own state"), "{started}");
    builtin.finish();
    flown.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn in_one_process_the_export_gives_the_built_in_sim_trace_byte_for_byte() {
    // `silrig sim --plant-fmu` flies the FMU through the generic in-process loop, the built-in F-16 through the
    // reference loop (silrig_flight::sim): two loops, two plants, one trace.
    let dir = temp_dir("fmu-export", "in-process-files");
    let (builtin_scenario, fmu_scenario) = robust_undisturbed(&dir);
    let (fmu, _) = export(&dir, "f16.fmu", Some(&builtin_scenario));
    let sim = |out: &str, args: &[&str]| {
        let o = Command::new(SILRIG).arg("sim").args(args).arg("--out").arg(dir.join(out)).output().unwrap();
        assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        std::fs::read(dir.join(out).join("trace.csv")).unwrap()
    };
    let builtin = sim("builtin", &[&builtin_scenario]);
    let flown = sim("fmu", &["--plant-fmu", fmu.to_str().unwrap(), &fmu_scenario]);
    assert_eq!(String::from_utf8_lossy(&builtin).lines().count(), 1002);
    assert!(builtin == flown, "trace.csv differs between the built-in F-16 and its FMU in one process");
    std::fs::remove_dir_all(dir).unwrap();
}
