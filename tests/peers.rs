//! The rig beside its peers (`examples/peers`, the book's measurements/peers.md), held to their values; the timings
//! are the book's, measured, never asserted here. `silrig sim --plant-fmu` of the exported F-16 for 100 s and FMPy's
//! own master, `simulate_fmu`, of the same FMU fed that trace's commands give every output bit for bit; JSBSim's
//! F-16 trims at the condition `silrig bench` times ours at, holds it, and trims within 0.5 deg of alpha of ours
//! (the same airframe data, not the same model), and its timed steps are flown; a campaign of the C PID through the
//! lockstep rig (`silrig sweep --controller-cmd`) and the same cases flown by a Python loop over FMPy with the PID
//! FMU and the campaign's F-16 FMU give every case's figures bit for bit, and the loop refuses, in words, a
//! dispersed key the FMU has no parameter for. Python is target/test-venv's, with `fmpy` and `jsbsim`.

mod common;

use common::fmu::{build_fmu, export_builtin, fmpy_python};
use common::{run_leaving_nothing, temp_dir, venv_python};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "peers";

/// `examples/peers/SCRIPT ARGS` under the test venv's Python, from the repository root: what it did.
fn script(script: &str, args: &[&str]) -> Output {
    let python = fmpy_python();
    Command::new(python).arg(format!("{ROOT}/examples/peers/{script}")).args(args).current_dir(ROOT).output().unwrap()
}

/// The same, which must succeed: its stdout.
fn script_ok(name: &str, args: &[&str]) -> String {
    let o = script(name, args);
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{name} {args:?} failed: {stdout}{stderr}");
    stdout.into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn silrig_sim_and_fmpy_simulate_fmu_fly_the_same_100_s() {
    let dir = temp_dir(SUITE, "sim");
    let config = format!("{ROOT}/examples/peers/f16-100s.toml");
    let (fmu, _) = export_builtin(SILRIG, &dir, "f16-100s.fmu", Some(&config));
    let out = dir.join("sim");
    let o =
        Command::new(SILRIG).args(["sim", "--plant-fmu", path(&fmu), "--out", path(&out), &config]).output().unwrap();
    assert!(o.status.success(), "silrig sim: {}", String::from_utf8_lossy(&o.stderr));
    let trace = out.join("trace.csv");
    let flown = dir.join("fmpy.csv");
    let said = script_ok("fmpy_f16.py", &["simulate", path(&fmu), path(&trace), path(&flown)]);
    assert_eq!(said.trim(), "10001 points over 100.00 s");
    let said = script_ok("fmpy_f16.py", &["compare", path(&trace), path(&flown)]);
    // 16 outputs of 10,001 rows, less the last row's 4 positions (from after a step FMPy does not take).
    assert_eq!(
        said.trim(),
        "10001 rows, 16 outputs: 160012 values, 160012 bit-identical; largest difference 0.0",
        "{said}"
    );
    // The flight moves: it is not a trim held still (each set point step is flown).
    let text = std::fs::read_to_string(&trace).unwrap();
    let phi: Vec<f64> = text.lines().skip(1).map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect();
    assert!(phi[5000] > 15.0 && phi[7000].abs() < 5.0, "bank at 50 s {}, at 70 s {}", phi[5000], phi[7000]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn jsbsim_f16_trims_where_ours_does_and_its_steps_are_flown() {
    venv_python("jsbsim", "jsbsim");
    let o = Command::new(SILRIG).args(["trim", "--airspeed-mps", "150", "--altitude-ft", "25000", "--json"]).output();
    let ours: Value = serde_json::from_slice(&o.unwrap().stdout).unwrap();
    let theirs: Value = serde_json::from_str(&script_ok("jsbsim_f16.py", &["trim"])).unwrap();
    let (trim, after) = (&theirs["trim"], &theirs["after_10_s"]);
    let f = |v: &Value| v.as_f64().unwrap();
    assert_eq!(f(&theirs["dt_s"]), 0.01);
    assert!((f(&trim["vt_mps"]) - 150.0).abs() < 1e-6 && (f(&trim["alt_ft"]) - 25000.0).abs() < 1e-3, "{trim}");
    // Trimmed: 10 s later it is still level at the condition.
    assert!((f(&after["alt_ft"]) - 25000.0).abs() < 5.0 && (f(&after["vt_mps"]) - 150.0).abs() < 0.1, "{after}");
    // The same wind-tunnel data (NASA TP-1538) and inertias, not the same model: alpha within 0.5 deg of ours.
    let (alpha_theirs, alpha_ours) = (f(&trim["alpha_deg"]), f(&ours["alpha_deg"]));
    assert!((alpha_theirs - alpha_ours).abs() < 0.5, "JSBSim trims at alpha {alpha_theirs}, ours at {alpha_ours}");
    let said = script_ok("jsbsim_f16.py", &["bench", "3"]);
    assert!(said.contains("(3 batches of 1000)"), "{said}");
    // The warm-up batch and the three timed ones: 4,000 steps of 0.01 s.
    assert!(said.contains("steps/s median; 40.0 s flown"), "{said}");
    let refused = script("jsbsim_f16.py", &["bench", "0"]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("BATCHES must be at least 1"));
}

/// `cases.csv` (or the FMPy loop's output) as index -> (column -> the value's text).
fn cases(path: &Path) -> BTreeMap<String, BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            // Only the reason column is quoted (and may hold commas): split on the commas outside quotes.
            let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
            for c in l.chars() {
                match c {
                    '"' => quoted = !quoted,
                    ',' if !quoted => fields.push(std::mem::take(&mut field)),
                    c => field.push(c),
                }
            }
            fields.push(field);
            let row: BTreeMap<String, String> = header.iter().zip(fields).map(|(h, v)| (h.to_string(), v)).collect();
            (row["index"].clone(), row)
        })
        .collect()
}

#[test]
fn a_campaign_of_the_c_pid_equals_the_fmpy_loop_case_by_case() {
    let dir = temp_dir(SUITE, "campaign");
    let config = format!("{ROOT}/examples/peers/pid-campaign.toml");
    let pid = common::c_pid(SILRIG, SUITE);
    let out = dir.join("sweep");
    let args = ["sweep", &config, "--runs", "8", "--jobs", "2", "--controller-cmd", &pid, "--out", path(&out)];
    let (code, stdout, stderr) = run_leaving_nothing(SILRIG, &args);
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    let (f16, _) = export_builtin(SILRIG, &dir, "campaign.fmu", Some(&config));
    let pid_fmu = build_fmu("pid", &dir);
    let flown = dir.join("fmpy.csv");
    let said = script_ok("fmpy_campaign.py", &[path(&f16), path(&pid_fmu), path(&out.join("cases.csv")), path(&flown)]);
    assert_eq!(said.trim(), "flew 8 cases of 1000 ticks");
    let (rig, fmpy) = (cases(&out.join("cases.csv")), cases(&flown));
    assert_eq!(rig.len(), 8);
    assert_eq!(fmpy.keys().collect::<Vec<_>>(), rig.keys().collect::<Vec<_>>());
    let mut flown = 0;
    for (index, row) in &rig {
        // A case the rig could not start (a controller that found no stream on a loaded machine) has no figures to
        // compare: it is said, and at most one of the eight may be such.
        if row["reason"].contains("before the plant's first tick") {
            eprintln!("case {index} not flown by the rig: {}", row["reason"]);
            continue;
        }
        assert!(row["reason"].is_empty(), "case {index} ended early: {}", row["reason"]);
        flown += 1;
        for figure in ["phi_final_error_deg", "theta_final_error_deg", "psi_final_error_deg", "alpha_peak_deg"] {
            let (a, b): (f64, f64) = (row[figure].parse().unwrap(), fmpy[index][figure].parse().unwrap());
            assert_eq!(a.to_bits(), b.to_bits(), "case {index} {figure}: the rig {a}, FMPy's loop {b}");
        }
    }
    assert!(flown >= 7, "only {flown} of 8 cases flown by the rig");
    // The cases differ from each other: the dispersions reached both.
    let peaks: std::collections::BTreeSet<&String> = fmpy.values().map(|r| &r["alpha_peak_deg"]).collect();
    assert_eq!(peaks.len(), 8);
    // A dispersed key the FMU has no parameter for is refused by name.
    let text = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    let foreign = dir.join("foreign.csv");
    std::fs::write(&foreign, text.replacen("plant.xcg", "disturbance.amplitude_radps2", 1)).unwrap();
    let o = script("fmpy_campaign.py", &[path(&f16), path(&pid_fmu), path(&foreign), path(&dir.join("x.csv")), "1"]);
    assert!(!o.status.success());
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(said.contains("no parameter for the dispersed key `disturbance.amplitude_radps2`"), "{said}");
    std::fs::remove_dir_all(&dir).unwrap();
}
