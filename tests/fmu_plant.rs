//! FMUs as the run's plant (`silrig run --plant-fmu`, `[plant] fmu`): the example airframe (FMI 2.0, C,
//! `examples/fmu/airframe`) flies lockstep and realtime against the example controllers unchanged, its parameters
//! set by name; an FMI 3.0 FMU (`tests/fmu/lag3`) flies and follows its equation; a plant killed mid-flight
//! resumes from the FMU's own serialized state with no discontinuity. Every bad input is refused with a message
//! naming the file: not a zip, no modelDescription.xml, no Linux binary, model exchange only, FMI 1.0, a wrong
//! GUID, a parameter that does not exist or cannot be set; and every misbehaviour of the FMU's code is seen
//! (`tests/fmu/misbehave`): doStep returning error, discard or fatal fails the run saying so, NaN outputs are
//! refused and counted, a segfault is the plant's death with the FMU named, a doStep slower than the period is
//! counted as overruns. The FMUs are built by `examples/fmu/build.sh` with the system compiler.
//! Each test has its own run id and folder; the launcher reaps what it started, and the tests check that it
//! removed the run's shared memory. No timing figure is asserted as a bound.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::Run;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn run(test: &str, args: &[&str]) -> Run {
    Run::start(SILRIG, "fmu-plant", "f", test, args)
}

fn fmu(name: &str) -> String {
    common::fmu::cached_fmu("fmu-plant", name)
}

fn python_pid() -> String {
    common::client_lib(SILRIG);
    format!("python3 {ROOT}/examples/python/pid_attitude.py")
}

/// A controller that holds each named input at a constant.
fn hold(inputs: &str) -> String {
    common::client_lib(SILRIG);
    format!("python3 {ROOT}/tests/clients/hold_inputs.py {inputs}")
}

fn airframe_scenario() -> String {
    format!("{ROOT}/examples/fmu/airframe.toml")
}

/// A scenario file in `dir`: `duration_s` of next-tick flight with these `[plant.parameters]`.
fn scenario(dir: &Path, name: &str, duration_s: f64, parameters: &str) -> String {
    let path = dir.join(format!("{name}.toml"));
    let text = format!(
        "name = \"{name}\"\n[timing]\ndt_s = 0.01\nduration_s = {duration_s}\ncommand_timing = \"next-tick\"\n\
         [plant.parameters]\n{parameters}\n"
    );
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

fn column(header: &[String], name: &str) -> usize {
    Run::column(header, name)
}

#[test]
fn the_example_airframe_fmu_flies_lockstep_with_the_python_pid_unchanged() {
    let plant = fmu("airframe");
    let r = run(
        "airframe-lockstep",
        &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &python_pid(), &airframe_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0);
    assert_eq!(r.counter("logger", "rows_written"), 1001);
    let started = r.event("plant", "plant-fmu").expect("the plant says which FMU it flies");
    let detail = started["detail"].as_str().unwrap();
    assert!(
        detail.contains(&plant) && detail.contains("FMI 2.0") && detail.contains("checkpoints through"),
        "{detail}"
    );
    let (header, rows) = r.trace();
    // The FMU's outputs, its inputs' commands, then the servo positions it reports (`<input>_deg`).
    assert_eq!(
        header[..16].join(","),
        "t_s,phi_deg,theta_deg,psi_deg,p_dps,q_dps,r_dps,alpha_deg,beta_deg,airspeed_mps,aileron_cmd_deg,\
         elevator_cmd_deg,rudder_cmd_deg,aileron_deg,elevator_deg,rudder_deg"
    );
    let last = rows.last().unwrap();
    let (phi, theta) = (last[column(&header, "phi_deg")], last[column(&header, "theta_deg")]);
    assert!((phi - 10.0).abs() < 0.5 && (theta - 5.0).abs() < 0.5, "not settled on the set points: {phi} {theta}");
    r.finish();
}

#[test]
fn the_c_example_pid_flies_the_airframe_fmu() {
    let exe = common::c_pid(SILRIG, "fmu-plant");
    let plant = fmu("airframe");
    let r = run(
        "airframe-c",
        &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &exe, &airframe_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (header, rows) = r.trace();
    let last = rows.last().unwrap();
    let (phi, theta) = (last[column(&header, "phi_deg")], last[column(&header, "theta_deg")]);
    assert!((phi - 10.0).abs() < 0.5 && (theta - 5.0).abs() < 0.5, "not settled on the set points: {phi} {theta}");
    r.finish();
}

#[test]
fn a_foreign_attitude_fmu_flies_lockstep_under_the_python_pid() {
    // tests/fmu/attitude names its inputs with their unit (`aileron_deg`), reports no surface position and has a
    // dimensionless throttle: the PID finds its surfaces by those names and leaves the throttle where it is.
    let plant = fmu("attitude");
    let scenario = format!("{ROOT}/tests/scenarios/attitude.toml");
    let r =
        run("attitude", &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &python_pid(), &scenario]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0);
    let (header, rows) = r.trace();
    assert_eq!(&header[..7], ["t_s", "phi_deg", "theta_deg", "psi_deg", "p_dps", "q_dps", "r_dps"]);
    let throttle = header.iter().position(|c| c.starts_with("throttle")).expect("the throttle's command is traced");
    assert!(rows.iter().all(|row| row[throttle] == 0.5), "the PID moved the throttle off its hold value");
    let last = rows.last().unwrap();
    let (phi, theta, psi) =
        (last[column(&header, "phi_deg")], last[column(&header, "theta_deg")], last[column(&header, "psi_deg")]);
    assert!((phi - 10.0).abs() < 0.5 && (theta - 5.0).abs() < 0.5, "not settled on the set points: {phi} {theta}");
    assert!(psi.abs() < 0.5, "heading not held: {psi}");
    r.finish();
}

#[test]
fn a_fault_run_of_the_foreign_attitude_fmu_completes_and_says_once_which_figures_it_left_out() {
    // The paper's fig1 needs the F-16's states and surfaces, which this plant does not announce: the run leaves it
    // out, says why in report.json and report.html (not on every run's console), and draws faults.png and
    // signals.png from the plant's own signals.
    let plant = fmu("attitude");
    let scenario = format!("{ROOT}/tests/scenarios/attitude.toml");
    let args = ["--plant-fmu", &plant, "--controller-cmd", &python_pid(), "--fault", "controller:kill@3s", &scenario];
    let r = run("attitude-fault", &args);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.failures(), "[]");
    assert!(r.report["faults"][0]["injected_at_s"].is_number(), "the kill did not happen: {}", r.report["faults"]);
    let left = r.report["figures_left_out"].as_array().expect("report.json lists the figures left out");
    assert_eq!(left.len(), 1, "{left:?}");
    assert_eq!(left[0]["figure"], "fig1_states.png");
    let reason = left[0]["reason"].as_str().unwrap();
    assert!(reason.contains("has no column `") && reason.contains("signals.png shows every signal"), "{reason}");
    for figure in ["faults.png", "faults.svg", "signals.png", "signals.svg"] {
        assert!(r.out.join(figure).exists(), "{figure} was not drawn");
    }
    assert!(!r.out.join("fig1_states.png").exists());
    assert!(!r.stdout.contains("not drawn"), "a warning line on the console: {}", r.stdout);
    let html = std::fs::read_to_string(r.out.join("report.html")).unwrap();
    assert!(html.contains("fig1_states.png not drawn: the trace has no column"), "report.html does not say it");
    r.finish();
}

#[test]
fn a_parameter_set_by_name_reaches_the_fmu() {
    // The airframe flies at its trim airspeed, a parameter, and reports it as an output.
    let dir = common::temp_dir("fmu-plant", "parameter-files");
    let text =
        std::fs::read_to_string(airframe_scenario()).unwrap().replace("servo_tau_s = 0.04", "trim_airspeed_mps = 31.5");
    let path = dir.join("faster.toml");
    std::fs::write(&path, text).unwrap();
    let plant = fmu("airframe");
    let r = run(
        "parameter",
        &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &python_pid(), path.to_str().unwrap()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (header, rows) = r.trace();
    let airspeed = column(&header, "airspeed_mps");
    assert!(rows.iter().all(|row| row[airspeed] == 31.5), "the parameter did not reach the model");
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_fmi3_fmu_flies_and_follows_its_equation() {
    let dir = common::temp_dir("fmu-plant", "lag3-files");
    let path = scenario(&dir, "lag", 2.0, "gain = 3.0\ntau = 0.2");
    let plant = fmu("lag3");
    let r = run("lag3", &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &hold("u=1.5"), &path]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.event("plant", "plant-fmu").unwrap()["detail"].as_str().unwrap().contains("FMI 3.0"));
    let (header, rows) = r.trace();
    assert_eq!(header[..4].join(","), "t_s,y,u_cmd_N,flight_segment");
    // The first command (answering tick 0) is applied from tick 1 on (next-tick): y(t) = 4.5 (1 - e^-(t - 0.01)/0.2).
    let (t, y) = (column(&header, "t_s"), column(&header, "y"));
    for row in &rows[1..] {
        let expected = 4.5 * (1.0 - (-(row[t] - 0.01) / 0.2).exp());
        assert!((row[y] - expected).abs() < 1e-9, "t = {}: y = {} against {expected}", row[t], row[y]);
    }
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_killed_fmu_plant_resumes_from_the_fmus_own_state() {
    let plant = fmu("airframe");
    let r = run(
        "resume",
        &[
            "--duration-s",
            "3",
            "--plant-fmu",
            &plant,
            "--controller-cmd",
            &python_pid(),
            "--fault",
            "plant:kill@1.5s,restart_after=0.3s",
            &airframe_scenario(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let resumed = r.event("plant", "plant-resumed").expect("the restarted plant resumed from its checkpoint");
    let detail = resumed["detail"].as_str().unwrap();
    assert!(detail.contains("resumed at tick") && detail.contains("ticks flown again"), "{resumed}");
    assert_eq!(r.counter("logger", "flight_discontinuities"), 0, "the resumed flight jumped");
    assert_eq!(r.counter("logger", "plant_restarts"), 1);
    r.finish();
}

/// A folder packed as an FMU with Python's zipfile (what build.sh uses), from `files` (name, bytes).
fn pack(dir: &Path, name: &str, files: &[(&str, Vec<u8>)]) -> String {
    let src = dir.join(format!("{name}-src"));
    for (file, bytes) in files {
        let path = src.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
    let out = dir.join(format!("{name}.fmu"));
    let tops: std::collections::BTreeSet<&str> = files.iter().map(|(f, _)| f.split('/').next().unwrap()).collect();
    let o =
        Command::new("python3").args(["-m", "zipfile", "-c"]).arg(&out).args(tops).current_dir(&src).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.display().to_string()
}

fn refused(test: &str, args: &[&str]) -> String {
    Run::refused(SILRIG, "fmu-plant", "f", test, args)
}

#[test]
fn bad_fmu_files_are_refused_naming_the_file_and_the_problem() {
    let dir = common::temp_dir("fmu-plant", "bad-files");
    let airframe = PathBuf::from(fmu("airframe"));
    let unpacked = dir.join("airframe");
    let o = Command::new("python3").args(["-m", "zipfile", "-e"]).arg(&airframe).arg(&unpacked).output().unwrap();
    assert!(o.status.success());
    let xml = std::fs::read_to_string(unpacked.join("modelDescription.xml")).unwrap();
    let binary = std::fs::read(unpacked.join("binaries/linux64/airframe.so")).unwrap();
    let not_zip = dir.join("not-a-zip.fmu");
    std::fs::write(&not_zip, "hello").unwrap();
    let cases: Vec<(String, &str)> = vec![
        (not_zip.display().to_string(), "not a zip archive"),
        (
            pack(&dir, "no-description", &[("binaries/linux64/airframe.so", binary.clone())]),
            "modelDescription.xml: not in the archive",
        ),
        (
            pack(&dir, "no-binary", &[("modelDescription.xml", xml.clone().into_bytes())]),
            "no Linux x86-64 binary: binaries/linux64/airframe.so",
        ),
        (
            pack(
                &dir,
                "windows-only",
                &[("modelDescription.xml", xml.clone().into_bytes()), ("binaries/win64/airframe.dll", vec![0])],
            ),
            "it has binaries/win64/airframe.dll",
        ),
        (
            pack(
                &dir,
                "model-exchange",
                &[("modelDescription.xml", xml.replace("<CoSimulation", "<ModelExchange").into_bytes())],
            ),
            "ModelExchange only",
        ),
        (
            pack(
                &dir,
                "fmi1",
                &[("modelDescription.xml", xml.replace("fmiVersion=\"2.0\"", "fmiVersion=\"1.0\"").into_bytes())],
            ),
            "FMI 1.0 is not supported",
        ),
        (dir.join("missing.fmu").display().to_string(), "cannot be read"),
    ];
    for (k, (file, expected)) in cases.iter().enumerate() {
        let stderr =
            refused(&format!("bad-file-{k}"), &["--mode", "lockstep", "--plant-fmu", file, &airframe_scenario()]);
        assert!(stderr.contains(&format!("FMU {file}")) && stderr.contains(expected), "{file}: {stderr}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn parameters_that_do_not_exist_or_cannot_be_set_are_refused_by_name() {
    let dir = common::temp_dir("fmu-plant", "bad-parameters-files");
    let plant = fmu("misbehave");
    let unknown = scenario(&dir, "unknown", 1.0, "nope = 1.0");
    let stderr = refused("unknown-parameter", &["--mode", "lockstep", "--plant-fmu", &plant, &unknown]);
    assert!(
        stderr.contains("`plant.parameters.nope`: no variable of that name") && stderr.contains("fault_time_s"),
        "{stderr}"
    );
    let output = scenario(&dir, "output", 1.0, "y = 1.0");
    let stderr = refused("output-parameter", &["--mode", "lockstep", "--plant-fmu", &plant, &output]);
    assert!(stderr.contains("variable \"y\" has causality output"), "{stderr}");
    let range = scenario(&dir, "range", 1.0, "fault = 9.0");
    let stderr = refused("range-parameter", &["--mode", "lockstep", "--plant-fmu", &plant, &range]);
    assert!(stderr.contains("`plant.parameters.fault` = 9 is outside the variable's range 0..6"), "{stderr}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_wrong_guid_fails_the_plant_with_what_the_fmu_logged() {
    let dir = common::temp_dir("fmu-plant", "wrong-guid-files");
    let plant = common::fmu::build_wrong_guid_fmu(&dir);
    let path = scenario(&dir, "guid", 1.0, "");
    let r = run(
        "wrong-guid",
        &["--mode", "lockstep", "--plant-fmu", plant.to_str().unwrap(), "--controller-cmd", &hold("u=1"), &path],
    );
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.failures();
    assert!(failures.contains("fmi2Instantiate") && failures.contains("wrong GUID"), "{failures}");
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn do_step_error_discard_and_fatal_fail_the_run_saying_so() {
    let dir = common::temp_dir("fmu-plant", "do-step-files");
    let plant = fmu("misbehave");
    for (fault, status) in [(1, "fmi2Error"), (2, "fmi2Discard"), (3, "fmi2Fatal")] {
        let path = scenario(&dir, &format!("fault{fault}"), 2.0, &format!("fault = {fault}\nfault_time_s = 0.5"));
        let r = run(
            &format!("do-step-{fault}"),
            &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &hold("u=1"), &path],
        );
        assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
        let ended = r.process("plant")["ended"].as_str().unwrap().to_string();
        assert!(
            ended.contains(&format!("FMU {plant}: fmi2DoStep at t = 0.5 s by 0.01 s returned {status}"))
                && ended.contains("the FMU logged"),
            "{ended}"
        );
        assert_eq!(r.counter("plant", "ticks"), 50, "the flight did not end at the failing step");
        r.finish();
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn nan_outputs_of_an_fmu_are_refused_and_counted() {
    let dir = common::temp_dir("fmu-plant", "nan-files");
    let plant = fmu("misbehave");
    let path = scenario(&dir, "nan", 1.0, "fault = 5\nfault_time_s = 0.5");
    let r = run("nan", &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &hold("u=1"), &path]);
    let refused = r.event("plant", "outputs-refused").expect("the NaN is said");
    assert!(refused["detail"].as_str().unwrap().contains("output y is NaN"), "{refused}");
    assert!(r.counter("plant", "outputs_refused") >= 40, "{}", r.stdout);
    let (header, rows) = r.trace();
    let y = column(&header, "y");
    assert!(rows.iter().all(|row| row[y].is_finite()), "a NaN reached the trace");
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_segfault_in_the_fmu_is_the_plants_death_with_the_fmu_named() {
    let dir = common::temp_dir("fmu-plant", "segfault-files");
    let plant = fmu("misbehave");
    let path = scenario(&dir, "segfault", 2.0, "fault = 4\nfault_time_s = 0.5");
    let r = run("segfault", &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &hold("u=1"), &path]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.failures();
    assert!(
        failures.contains("plant: killed by signal 11") && failures.contains(&format!("while flying the FMU {plant}")),
        "{failures}"
    );
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_do_step_slower_than_the_period_is_counted_as_overruns() {
    let dir = common::temp_dir("fmu-plant", "slow-files");
    let plant = fmu("misbehave");
    let path = scenario(&dir, "slow", 1.5, "fault = 6\nfault_time_s = 0.5");
    let r = run("slow", &["--plant-fmu", &plant, "--controller-cmd", &hold("u=1"), &path]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    // From 0.5 s on every step takes 15 ms of a 10 ms period: at least one overrun per two ticks.
    assert!(r.counter("plant", "overruns") >= 40, "{}", r.stdout);
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn silrig_check_judges_the_airframe_fmu_and_its_recording_replays_bit_identical() {
    let plant = fmu("airframe");
    let dir = common::temp_dir("fmu-plant", "check-files");
    let check = Command::new(SILRIG)
        .args(["check", &format!("{ROOT}/examples/fmu/airframe_check.toml"), "--case", "lockstep-steps"])
        .args(["--plant-fmu", &plant, "--controller-cmd", &python_pid(), "--out"])
        .arg(dir.join("check"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&check.stdout);
    assert_eq!(check.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&check.stderr));
    assert!(stdout.contains("outputs.phi_deg.settled") && stdout.contains("verdict: PASS"), "{stdout}");
    assert!(stdout.contains("identical over 1001 ticks"), "{stdout}");
    let r = run(
        "replayed",
        &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &python_pid(), &airframe_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let replay = Command::new(SILRIG)
        .arg("replay")
        .arg(&r.out)
        .args(["--controller-cmd", &python_pid(), "--out"])
        .arg(dir.join("replay"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&replay.stdout);
    assert_eq!(replay.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&replay.stderr));
    assert!(stdout.contains("PASSED (tolerance 0)"), "{stdout}");
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn what_a_killed_plant_unpacked_is_removed_by_the_next_fmu_opened() {
    // The folder a SIGKILLed plant (or an FMU's segfault) left: its process is gone, nothing dropped it.
    let mut child = Command::new("true").spawn().unwrap();
    let dead_pid = child.id();
    child.wait().unwrap();
    let left = std::env::temp_dir().join(format!("silrig-fmu-{dead_pid}-0"));
    std::fs::create_dir_all(left.join("binaries")).unwrap();
    let dir = common::temp_dir("fmu-plant", "leftover-files");
    let unknown = scenario(&dir, "unknown", 1.0, "nope = 1.0");
    // A refused run still opens the FMU, and that open cleans up.
    refused("leftover", &["--mode", "lockstep", "--plant-fmu", &fmu("misbehave"), &unknown]);
    assert!(!left.exists(), "{} is still there", left.display());
    std::fs::remove_dir_all(dir).unwrap();
}
