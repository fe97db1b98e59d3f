//! The FMUs written in C here, checked through FMPy (PyPI `fmpy` in `target/test-venv`) before any importer of ours
//! touches them: `examples/fmu/airframe` (the example vehicle, a small fixed-wing UAV) and `tests/fmu/misbehave`
//! (the importer's error fixture), each built by `examples/fmu/build.sh` with the system `cc`.
//!
//! - Both build, FMPy's validation finds no problem, and their binaries export the whole FMI 2.0 API.
//! - The airframe flies open loop under FMPy's own master: a step of each surface moves its axis the way the
//!   Stevens & Lewis signs say (a positive deflection, a negative moment); its parameters' start values in
//!   modelDescription.xml are the ones the C code uses, set by name they reach the model, and once initialized
//!   they are fixed.
//! - Closed loop with the example PID (`examples/python/pid_attitude.py`'s class, the F-16 gains it picks for a
//!   plant in deg) at 100 Hz with the rig's one tick of delay, and with one more: the 10 deg roll and 5 deg pitch
//!   steps settle and nothing keeps swinging (`tests/fmu/fly_airframe.py`); the C example's gains are the same.
//! - Its FMU state, taken, serialized and put back (in the same instance, and in a new one from the bytes), flies
//!   on bit-identically; bytes that are not a state are refused.
//! - misbehave fails as its `fault` says (fmi2Error, fmi2Discard, fmi2Fatal from doStep, a segfault, NaN, a slow
//!   step) from `fault_time_s` on, and one whose modelDescription.xml has another GUID is refused at instantiation.
//! - build.sh fails loudly and writes nothing on bad input.
//!
//! Each test works in its own folder; simulated times are judged, wall-clock times only from below.

use std::path::Path;
use std::process::Command;

mod common;
use common::fmu::{build_fmu, build_wrong_guid_fmu, fmpy_python, run_build_sh};
use common::temp_dir;
use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "fmu-examples";

/// `python3 tests/fmu/SCRIPT ARGS` in the venv: its last line of stdout as JSON.
fn python_json(script: &str, args: &[&str]) -> Value {
    let o = Command::new(fmpy_python())
        .arg(Path::new(ROOT).join("tests/fmu").join(script))
        .args(args)
        .output()
        .expect("the venv's python runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{script} {args:?}: {}\n{stdout}\n{}", o.status, String::from_utf8_lossy(&o.stderr));
    let last = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(last).unwrap_or_else(|e| panic!("{script} {args:?} printed no JSON ({e}): {stdout}"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn check_valid(fmu: &Path) {
    let r = python_json("check_fmu.py", &["validate", fmu.to_str().unwrap()]);
    assert_eq!(r["problems"], serde_json::json!([]), "FMPy's validation of {}: {r}", fmu.display());
    assert_eq!(r["missing_functions"], serde_json::json!([]), "{}: {r}", fmu.display());
    assert!(r["api_functions"].as_u64().unwrap() >= 44, "fmpy's header lists too few functions: {r}");
}

#[test]
fn airframe_builds_and_validates() {
    let dir = temp_dir(SUITE, "airframe_builds_and_validates");
    let fmu = build_fmu("airframe", &dir);
    check_valid(&fmu);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn fmu_sources_compile_without_warnings() {
    let headers = common::fmu::fmi_headers();
    for src in ["examples/fmu/airframe/airframe.c", "tests/fmu/misbehave/misbehave.c"] {
        let o = Command::new("cc")
            .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-fsyntax-only", "-I"])
            .arg(headers)
            .arg("-I")
            .arg(Path::new(ROOT).join("examples/fmu/common"))
            .arg(Path::new(ROOT).join(src))
            .output()
            .expect("cc runs");
        assert!(o.status.success(), "{src}: {}", String::from_utf8_lossy(&o.stderr));
    }
}

#[test]
fn airframe_open_loop_responds_with_the_book_signs() {
    let dir = temp_dir(SUITE, "airframe_open_loop");
    let fmu = build_fmu("airframe", &dir);
    let r = python_json("check_fmu.py", &["open-loop", fmu.to_str().unwrap()]);
    assert_eq!(r["parameter_start_mismatch"], serde_json::json!([]), "{r}");
    assert_eq!(r["parameters"], 28, "{r}");
    // surface, its rate, its angle; +5 deg at 0.5 s: the rate is negative 0.2 s later, the angle 1 s later.
    for (surface, rate, angle) in
        [("aileron", "p_dps", "phi_deg"), ("elevator", "q_dps", "theta_deg"), ("rudder", "r_dps", "psi_deg")]
    {
        let s = &r["steps"][surface];
        assert_eq!(s["quiet_before"], true, "{surface}: something moved before the step: {s}");
        assert_eq!(s["finite"], true, "{surface}: {s}");
        assert!((f(&s["position_at_1s"]) - 5.0).abs() < 1e-3, "{surface}: the servo is not at 5 deg 0.5 s on: {s}");
        assert!(f(&s["at_0.7s"][rate]) < -1.0, "{surface} +5 deg: {rate} should be negative: {s}");
        assert!(f(&s["at_1.5s"][angle]) < -1.0, "{surface} +5 deg: {angle} should be negative: {s}");
    }
    // The elevator leaves the lateral axes alone (symmetric airframe); the rudder sideslips nose left and the
    // dihedral effect then rolls it left; the elevator's nose-down pitch lowers alpha.
    let e = &r["steps"]["elevator"]["at_1.5s"];
    for lateral in ["phi_deg", "psi_deg", "p_dps", "r_dps", "beta_deg"] {
        assert_eq!(f(&e[lateral]), 0.0, "the elevator moved {lateral}: {e}");
    }
    assert!(f(&e["alpha_deg"]) < -0.5, "{e}");
    let rd = &r["steps"]["rudder"];
    assert!(f(&rd["at_0.7s"]["beta_deg"]) > 0.1, "{rd}");
    assert!(f(&rd["at_1.5s"]["phi_deg"]) < -1.0, "{rd}");
    assert_eq!(f(&e["airspeed_mps"]), 25.0, "{e}");

    // Parameters set by name before initialization reach the model; after it they are refused and kept.
    let off = &r["ineffective_aileron"];
    for axis in ["phi_deg", "psi_deg", "p_dps", "r_dps", "beta_deg"] {
        assert_eq!(f(&off[axis]), 0.0, "Cl_da = Cn_da = 0, yet the aileron moved {axis}: {off}");
    }
    assert!((f(&off["aileron_deg"]) - 5.0).abs() < 1e-6, "{off}");
    assert_eq!(f(&off["airspeed_mps"]), 30.0, "{off}");
    assert_eq!(r["fixed_parameter_set_after_initialization"], "error", "{r}");
    assert_eq!(f(&r["Cl_da_after"]), -0.07, "{r}");
    assert!(r["fixed_log"].to_string().contains("is fixed"), "{r}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The closed loop's numbers for one transport delay.
fn fly(fmu: &Path, delay_ticks: u32) -> Value {
    let r = python_json(
        "fly_airframe.py",
        &[
            fmu.to_str().unwrap(),
            "--phi",
            "10",
            "--theta",
            "5",
            "--psi",
            "0",
            "--duration-s",
            "20",
            "--delay-ticks",
            &delay_ticks.to_string(),
        ],
    );
    println!("delay {delay_ticks} tick(s): {r}");
    r
}

#[test]
fn airframe_flies_with_the_example_pid() {
    let dir = temp_dir(SUITE, "airframe_flies_with_the_example_pid");
    let fmu = build_fmu("airframe", &dir);
    for delay in [1, 2] {
        let r = fly(&fmu, delay);
        assert_eq!(r["plant"], "airframe");
        assert_eq!(r["gains"], "f16", "the PID should fly a plant with surfaces in deg on the F-16's gains: {r}");
        assert_eq!(r["finite"], true, "{r}");
        let a = &r["angles"];
        for (angle, setpoint, overshoot_max) in [("phi_deg", 10.0, 2.0), ("theta_deg", 5.0, 1.5)] {
            let x = &a[angle];
            assert!((f(&x["final"]) - setpoint).abs() < 0.05, "delay {delay}: {angle} ends off its set point: {x}");
            assert!(f(&x["settling_s"]) < 8.0, "delay {delay}: {angle} not within 2 % of its step by 8 s: {x}");
            assert!(f(&x["overshoot"]) < overshoot_max, "delay {delay}: {angle} overshoots: {x}");
            assert!(f(&x["last3s_p2p"]) < 0.01, "delay {delay}: {angle} still swings in the last 3 s: {x}");
        }
        let psi = &a["psi_deg"];
        assert!(f(&psi["final"]).abs() < 0.05 && f(&psi["peak"]).abs() < 1.0, "delay {delay}: heading wanders: {psi}");
        for surface in ["aileron", "elevator", "rudder"] {
            let s = &r["surfaces"][surface];
            assert!(f(&s["last3s_p2p"]) < 0.05, "delay {delay}: the {surface} is still moving (limit cycle?): {s}");
            assert!(f(&s["peak_abs"]) < 21.5, "delay {delay}: the {surface} hit the PID's travel: {s}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The C example (`examples/c/pid_attitude.c`) flies every plant on the F-16's gains: the same numbers as the Python
/// example's `F16`, which the closed loop above flew, so what it showed holds for the C controller too.
#[test]
fn c_example_pid_has_the_gains_the_closed_loop_flew() {
    let c = std::fs::read_to_string(Path::new(ROOT).join("examples/c/pid_attitude.c")).unwrap();
    let array = |name: &str| -> Vec<f64> {
        let line = c
            .lines()
            .find(|l| l.starts_with(&format!("static const double {name}[3] = {{")))
            .unwrap_or_else(|| panic!("pid_attitude.c has no {name}[3]"));
        let inside = &line[line.find('{').unwrap() + 1..line.find('}').unwrap()];
        inside.split(',').map(|x| x.trim().parse().unwrap()).collect()
    };
    let c_gains: Vec<Vec<f64>> = ["KP", "KD", "KI", "TRAVEL"].iter().map(|n| array(n)).collect();
    let o = Command::new(fmpy_python())
        .current_dir(Path::new(ROOT).join("examples/python"))
        .args(["-c", "import json, pid_attitude; print(json.dumps(pid_attitude.F16))"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let python: Vec<Vec<f64>> = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(c_gains, python, "pid_attitude.c's KP, KD, KI, TRAVEL against pid_attitude.py's F16");
}

#[test]
fn airframe_state_round_trip_continues_bit_identically() {
    let dir = temp_dir(SUITE, "airframe_state_round_trip");
    let fmu = build_fmu("airframe", &dir);
    let r = python_json("check_fmu.py", &["roundtrip", fmu.to_str().unwrap()]);
    assert_eq!(r["moved"], true, "the flight after the checkpoint does not move, so it proves nothing: {r}");
    assert_eq!(r["steps"], 150, "{r}");
    assert_eq!(r["serialized_twice_identical"], true, "{r}");
    assert_eq!(r["same_instance_identical"], true, "set back in the same instance: {r}");
    assert_eq!(r["new_instance_identical"], true, "deserialized into a new instance: {r}");
    assert_eq!(r["reserialized_identical"], true, "{r}");
    assert_eq!(r["refused"]["truncated"], true, "{r}");
    assert_eq!(r["refused"]["foreign"], true, "{r}");
    let log = r["log"].to_string();
    assert!(log.contains("fmi2DeSerializeFMUstate"), "the refusals were not logged: {log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn misbehave(fmu: &Path, fault: u32) -> Value {
    python_json("check_fmu.py", &["misbehave", fmu.to_str().unwrap(), &fault.to_string()])
}

#[test]
fn misbehave_builds_validates_and_fails_as_told() {
    let dir = temp_dir(SUITE, "misbehave_fails_as_told");
    let fmu = build_fmu("misbehave", &dir);
    check_valid(&fmu);

    let ok = misbehave(&fmu, 0);
    assert_eq!(ok["failed_at"], Value::Null, "{ok}");
    let ys = ok["ys"].as_array().unwrap();
    assert_eq!(ys.len(), 100);
    let (t, y) = (f(&ys[99][0]), f(&ys[99][1]));
    assert!((t - 1.0).abs() < 1e-9 && (y - (1.0 - (-1.0f64).exp())).abs() < 1e-12, "y(1) of y' = -y + 1: {t} {y}");

    for (fault, status, terminated) in [(1, "error", false), (2, "discard", true), (3, "fatal", true)] {
        let r = misbehave(&fmu, fault);
        assert_eq!(r["status"], status, "fault {fault}: {r}");
        assert_eq!(f(&r["failed_at"]), 0.5, "fault {fault}: from fault_time_s on: {r}");
        assert_eq!(r["ys"].as_array().unwrap().len(), 50, "fault {fault}: steps before it: {r}");
        assert_eq!(f(&r["last_successful_time"]), 0.5, "fault {fault}: {r}");
        assert_eq!(r["terminated"], terminated, "fault {fault}: {r}");
        let log = r["log"].to_string();
        assert!(log.contains(&format!("fault {fault} at t = 0.5 s")), "fault {fault}: not logged: {log}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn misbehave_segfaults_goes_nan_and_slows_down() {
    use std::os::unix::process::ExitStatusExt;
    let dir = temp_dir(SUITE, "misbehave_segfaults");
    let fmu = build_fmu("misbehave", &dir);

    // 4: the process that loaded it dies of SIGSEGV in doStep at 0.5 s.
    let o = Command::new(fmpy_python())
        .arg(Path::new(ROOT).join("tests/fmu/check_fmu.py"))
        .args(["misbehave", fmu.to_str().unwrap(), "4"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.signal(), Some(libc::SIGSEGV), "fault 4: {} {stdout}", o.status);
    assert!(stdout.contains("\"stepping_into_fault_at\": 0.5"), "fault 4 came before 0.5 s: {stdout}");

    // 5: y reads NaN after the step from 0.5 s on, and not before.
    let r = misbehave(&fmu, 5);
    assert_eq!(r["failed_at"], Value::Null, "{r}");
    for point in r["ys"].as_array().unwrap() {
        let (t, y) = (f(&point[0]), &point[1]);
        if t <= 0.5 + 1e-9 {
            assert!(y.is_f64(), "y is not a number at {t}: {r}");
        } else {
            assert_eq!(y, "nan", "y is not NaN at {t}: {r}");
        }
    }
    assert!(r["log"].to_string().contains("fault 5 from t = 0.5 s"), "{r}");

    // 6: every step from 0.5 s on takes at least 15 ms (and stays correct).
    let r = misbehave(&fmu, 6);
    assert_eq!(r["failed_at"], Value::Null, "{r}");
    let slow: Vec<f64> =
        r["step_s"].as_array().unwrap().iter().filter(|s| f(&s[0]) >= 0.5 - 1e-9).map(|s| f(&s[1])).collect();
    assert_eq!(slow.len(), 50, "{r}");
    assert!(slow.iter().all(|&d| d >= 0.015), "a step from 0.5 s on took less than 15 ms: {slow:?}");
    let last = &r["ys"].as_array().unwrap()[99];
    assert!((f(&last[1]) - (1.0 - (-1.0f64).exp())).abs() < 1e-12, "{last}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn wrong_guid_is_refused_at_instantiation() {
    let dir = temp_dir(SUITE, "wrong_guid");
    let right = build_fmu("misbehave", &dir);
    let r = python_json("check_fmu.py", &["instantiate", right.to_str().unwrap()]);
    assert_eq!(r["instantiated"], true, "the right GUID: {r}");
    let wrong = build_wrong_guid_fmu(&dir);
    let r = python_json("check_fmu.py", &["instantiate", wrong.to_str().unwrap()]);
    assert_eq!(r["instantiated"], false, "a wrong GUID must not instantiate: {r}");
    assert!(r["log"].to_string().contains("wrong GUID {00000000-0000-4000-8000-000000000bad}"), "{r}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn build_sh_fails_loudly_and_writes_nothing() {
    let dir = temp_dir(SUITE, "build_sh_fails");
    let out = dir.join("x.fmu");
    let stderr = |o: &std::process::Output| String::from_utf8_lossy(&o.stderr).to_string();

    // No such folder; a folder without modelDescription.xml; a name that is not .fmu.
    let o = run_build_sh(&dir.join("nowhere"), &out);
    assert!(
        !o.status.success() && stderr(&o).contains("build.sh: ") && stderr(&o).contains("is not a folder"),
        "{}",
        stderr(&o)
    );
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = run_build_sh(&empty, &out);
    assert!(!o.status.success() && stderr(&o).contains("has no modelDescription.xml"), "{}", stderr(&o));
    let o = run_build_sh(&common::fmu::fmu_source("misbehave"), &dir.join("x.zip"));
    assert!(!o.status.success() && stderr(&o).contains("must end in .fmu"), "{}", stderr(&o));

    // C that does not compile: the compiler's message, then build.sh's, and no FMU.
    let broken = dir.join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    std::fs::copy(
        common::fmu::fmu_source("misbehave").join("modelDescription.xml"),
        broken.join("modelDescription.xml"),
    )
    .unwrap();
    std::fs::write(broken.join("model.c"), "int fmi2DoStep(void) { return undeclared; }\n").unwrap();
    let o = run_build_sh(&broken, &out);
    assert!(!o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("undeclared") && stderr(&o).contains("build.sh: compiling"), "{}", stderr(&o));
    assert!(!out.exists(), "a failed build left {}", out.display());

    // Headers that are not there.
    let o = Command::new("sh")
        .arg(Path::new(ROOT).join("examples/fmu/build.sh"))
        .arg(common::fmu::fmu_source("misbehave"))
        .arg(&out)
        .env("FMI_HEADERS", dir.join("no-headers"))
        .env("PYTHON", fmpy_python())
        .output()
        .unwrap();
    assert!(!o.status.success() && stderr(&o).contains("has no fmi2Functions.h"), "{}", stderr(&o));
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
