//! FMUs as the run's controller (`silrig run --controller-fmu`, `[controller] fmu`): the example PID as an FMI 2.0
//! co-simulation FMU (`examples/fmu/pid`, C) builds, passes FMPy's validation and exports the whole API; it flies
//! the airframe FMU plant and the built-in F-16 in lockstep and settles, with the very trace the C example
//! (`examples/c/pid_attitude.c`, the same law and gains) gives on the same plant; renamed variables fly the same
//! through `[controller.map]`; `[controller.parameters]` reach it; killed and restarted in realtime it resumes from
//! its own serialized state, and it flies on when a restarted plant resumes from an earlier tick; `silrig check
//! --controller-fmu` judges it; its run replays bit-identically; an FMI 3.0
//! FMU (`tests/fmu/lag3`) flies as a controller through its map and parameters. Every mapping mistake is refused with a
//! message naming the FMU file, the variable and what the plant or the FMU has: before any process starts when
//! the plant is known (the F-16, an FMU plant), else by the controller when the plant announces itself.
//! Each test has its own run id and folder (`common::Run`); no timing figure is asserted as a bound.

use std::path::Path;
use std::process::Command;

mod common;
use common::Run;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "fmu-controller";

fn run(test: &str, args: &[&str]) -> Run {
    Run::start(SILRIG, SUITE, "c", test, args)
}

fn fmu(name: &str) -> String {
    common::fmu::cached_fmu(SUITE, name)
}

/// The PID FMU with some of its variables renamed in its modelDescription.xml (same C code, same value references):
/// `dir/renamed_pid.fmu`.
fn renamed_pid(dir: &Path, renames: &[(&str, &str)]) -> String {
    let src = dir.join("renamed_pid_src");
    std::fs::create_dir_all(&src).unwrap();
    let original = common::fmu::fmu_source("pid");
    std::fs::copy(original.join("pid.c"), src.join("pid.c")).unwrap();
    let mut xml = std::fs::read_to_string(original.join("modelDescription.xml")).unwrap();
    for (from, to) in renames {
        let (from, to) = (format!("name=\"{from}\""), format!("name=\"{to}\""));
        assert_eq!(xml.matches(&from).count(), 1, "{from} in pid's modelDescription.xml");
        xml = xml.replace(&from, &to);
    }
    std::fs::write(src.join("modelDescription.xml"), xml).unwrap();
    let out = dir.join("renamed_pid.fmu");
    let o = common::fmu::run_build_sh(&src, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.display().to_string()
}

fn c_pid() -> String {
    common::c_pid(SILRIG, SUITE)
}

fn airframe_scenario() -> String {
    format!("{ROOT}/examples/fmu/airframe.toml")
}

fn robust() -> String {
    format!("{ROOT}/configs/robust.toml")
}

fn column(header: &[String], name: &str) -> usize {
    Run::column(header, name)
}

/// The largest |difference| between two traces over the columns they share (t_s included), and the column where it
/// is; the traces must have the same number of rows.
fn largest_difference(a: &(Vec<String>, Vec<Vec<f64>>), b: &(Vec<String>, Vec<Vec<f64>>)) -> (f64, String) {
    assert_eq!(a.1.len(), b.1.len(), "the traces have different lengths");
    let mut worst = (0.0, String::from("(none)"));
    let mut shared = 0;
    for (i, name) in a.0.iter().enumerate() {
        let Some(j) = b.0.iter().position(|h| h == name) else { continue };
        shared += 1;
        for (ra, rb) in a.1.iter().zip(&b.1) {
            let d = (ra[i] - rb[j]).abs();
            if d > worst.0 || (d.is_nan() && !worst.0.is_nan()) {
                worst = (d, name.clone());
            }
        }
    }
    assert!(shared >= 10, "the traces share only {shared} columns: {:?} / {:?}", a.0, b.0);
    worst
}

/// A scenario file in `dir`: `base` with `extra` TOML appended.
fn scenario_with(dir: &Path, name: &str, base: &str, extra: &str) -> String {
    let path = dir.join(format!("{name}.toml"));
    let text = std::fs::read_to_string(base).unwrap();
    std::fs::write(&path, format!("{text}\n{extra}\n")).unwrap();
    path.display().to_string()
}

fn refused(test: &str, args: &[&str]) -> String {
    Run::refused(SILRIG, SUITE, "c", test, args)
}

#[test]
fn the_pid_fmu_builds_validates_and_compiles_cleanly() {
    let pid = fmu("pid");
    let o = Command::new(common::fmu::fmpy_python())
        .arg(Path::new(ROOT).join("tests/fmu/check_fmu.py"))
        .args(["validate", &pid])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    assert_eq!(r["problems"], serde_json::json!([]), "FMPy's validation: {r}");
    assert_eq!(r["missing_functions"], serde_json::json!([]), "{r}");
    assert!(r["api_functions"].as_u64().unwrap() >= 44, "{r}");
    let o = Command::new("cc")
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-fsyntax-only", "-I"])
        .arg(common::fmu::fmi_headers())
        .arg("-I")
        .arg(Path::new(ROOT).join("examples/fmu/common"))
        .arg(Path::new(ROOT).join("examples/fmu/pid/pid.c"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn the_pid_fmu_flies_the_airframe_fmu_as_the_c_example_does() {
    let (plant, pid) = (fmu("airframe"), fmu("pid"));
    let r =
        run("airframe", &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-fmu", &pid, &airframe_scenario()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0);
    let started = r.event("controller", "controller-fmu").expect("the controller says which FMU it flies");
    let detail = started["detail"].as_str().unwrap();
    assert!(detail.contains(&pid) && detail.contains("FMI 2.0") && detail.contains("checkpoints through"), "{detail}");
    let fmu_trace = r.trace();
    let header = &fmu_trace.0;
    // Every Real output of the FMU is a diagnostic, after the plant's columns.
    let n = header.len();
    assert_eq!(header[n - 6..].join(","), "aileron,elevator,rudder,err_phi_deg,err_theta_deg,err_psi_deg");
    let last = fmu_trace.1.last().unwrap();
    let (phi, theta) = (last[column(header, "phi_deg")], last[column(header, "theta_deg")]);
    assert!((phi - 10.0).abs() < 0.5 && (theta - 5.0).abs() < 0.5, "not settled on the set points: {phi} {theta}");
    // The FMU's own elevator output is the command the plant got (no blend at a first start).
    let (raw, sent) = (column(header, "elevator"), column(header, "elevator_cmd_deg"));
    assert!(fmu_trace.1.iter().all(|row| row[raw] == row[sent]), "the FMU's elevator is not the command sent");
    r.finish();

    let c = run(
        "airframe-c",
        &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-cmd", &c_pid(), &airframe_scenario()],
    );
    assert_eq!(c.code, Some(0), "{}\n{}", c.stdout, c.stderr);
    let (worst, at) = largest_difference(&fmu_trace, &c.trace());
    assert_eq!(worst, 0.0, "the FMU and the C example differ by {worst} in {at}");
    c.finish();
}

#[test]
fn the_pid_fmu_flies_the_f16_as_the_c_example_does() {
    let pid = fmu("pid");
    let r = run("f16", &["--mode", "lockstep", "--controller-fmu", &pid, &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "command_misses"), 0);
    let fmu_trace = r.trace();
    let header = &fmu_trace.0;
    let last = fmu_trace.1.last().unwrap();
    let angles = ["phi_deg", "theta_deg", "psi_deg"].map(|a| last[column(header, a)]);
    // configs/robust.toml: hold 0, 10, 0 deg.
    assert!(
        angles[0].abs() < 0.5 && (angles[1] - 10.0).abs() < 0.5 && angles[2].abs() < 0.5,
        "not settled on the set points: {angles:?}"
    );
    r.finish();

    let c = run("f16-c", &["--mode", "lockstep", "--controller-cmd", &c_pid(), &robust()]);
    assert_eq!(c.code, Some(0), "{}\n{}", c.stdout, c.stderr);
    let (worst, at) = largest_difference(&fmu_trace, &c.trace());
    assert_eq!(worst, 0.0, "the FMU and the C example differ by {worst} in {at}");
    c.finish();
}

#[test]
fn renamed_variables_fly_the_same_through_controller_map() {
    let dir = common::temp_dir(SUITE, "renamed-files");
    let renamed = renamed_pid(&dir, &[("theta_deg", "pitch"), ("elevator", "elev_cmd"), ("theta_deg_sp", "theta_ref")]);
    let scenario = scenario_with(
        &dir,
        "mapped",
        &airframe_scenario(),
        "[controller.map]\npitch = \"theta_deg\"\nelev_cmd = \"elevator\"\ntheta_ref = \"theta_deg_sp\"",
    );
    let plant = fmu("airframe");
    let r = run("renamed", &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-fmu", &renamed, &scenario]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let mapped = r.trace();
    // The diagnostics keep the FMU's own names.
    assert!(mapped.0.iter().any(|h| h == "elev_cmd"), "{:?}", mapped.0);
    r.finish();
    let plain = run(
        "renamed-plain",
        &["--mode", "lockstep", "--plant-fmu", &plant, "--controller-fmu", &fmu("pid"), &airframe_scenario()],
    );
    assert_eq!(plain.code, Some(0), "{}\n{}", plain.stdout, plain.stderr);
    let (worst, at) = largest_difference(&mapped, &plain.trace());
    assert_eq!(worst, 0.0, "mapped and plain differ by {worst} in {at}");
    plain.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_relative_fmu_path_and_parameters_by_name_reach_the_controller() {
    // Without roll gains the PID never moves the aileron, so the airframe cannot roll to its 10 deg: the parameters
    // reached the FMU. The FMU is named relative to the scenario file.
    let dir = common::temp_dir(SUITE, "parameters-files");
    std::fs::copy(fmu("pid"), dir.join("pid.fmu")).unwrap();
    let scenario = scenario_with(
        &dir,
        "no-roll",
        &airframe_scenario(),
        "[controller]\nfmu = \"pid.fmu\"\n[controller.parameters]\nkp_phi = 0.0\nkd_phi = 0.0\nki_phi = 0.0",
    );
    let r = run("parameters", &["--mode", "lockstep", "--plant-fmu", &fmu("airframe"), &scenario]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let detail = r.event("controller", "controller-fmu").unwrap()["detail"].as_str().unwrap().to_string();
    assert!(detail.contains(&dir.join("pid.fmu").display().to_string()), "{detail}");
    let (header, rows) = r.trace();
    let (phi, aileron) = (column(&header, "phi_deg"), column(&header, "aileron_cmd_deg"));
    assert!(rows.iter().all(|row| row[aileron] == rows[0][aileron]), "the aileron moved without roll gains");
    assert!(rows.iter().all(|row| row[phi].abs() < 5.0), "rolled to the set point without roll gains");
    let theta = rows.last().unwrap()[column(&header, "theta_deg")];
    assert!((theta - 5.0).abs() < 0.5, "pitch, whose gains were left alone, did not settle: {theta}");
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_killed_fmu_controller_resumes_from_its_fmu_state() {
    let pid = fmu("pid");
    let r = run(
        "resume",
        &[
            "--duration-s",
            "3",
            "--controller-fmu",
            &pid,
            "--fault",
            "controller:kill@1.5s,restart_after=0.3s",
            &robust(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.event("launcher", "process-restarted").is_some(), "{}", r.stdout);
    let joined: Vec<serde_json::Value> =
        r.events().into_iter().filter(|e| e["process"] == "controller" && e["kind"] == "controller-joined").collect();
    assert_eq!(joined.len(), 1, "one join of a flying plant (the restart): {joined:?}");
    assert!(joined[0]["detail"].as_str().unwrap().contains("checkpointed state"), "{}", joined[0]);
    assert!(r.event("controller", "checkpoint-rejected").is_none());
    let checkpoint = std::fs::read_to_string(r.out.join("controller.checkpoint.json")).unwrap();
    assert!(checkpoint.contains("state_hex"), "{checkpoint}");
    assert!(r.event("plant", "controller-recovered").is_some());
    let (header, rows) = r.trace();
    assert_eq!(rows.len(), 301, "the logger lost rows");
    // From the kill on (the failsafe, the restart, the blend into the restored FMU's commands) the elevator command
    // never moves more than 0.5 deg in a tick (0.15 measured; the take-off transient at 0.26 s moves 0.93).
    let (t, elevator) = (column(&header, "t_s"), column(&header, "elevator_cmd_deg"));
    let jump =
        rows.windows(2).filter(|w| w[0][t] >= 1.4).map(|w| (w[1][elevator] - w[0][elevator]).abs()).fold(0.0, f64::max);
    assert!(jump < 0.5, "the elevator command jumped {jump} deg in a tick after the kill");
    r.finish();
}

#[test]
fn a_controller_fmu_flies_on_when_the_plant_resumes_from_an_earlier_tick() {
    // The restarted plant resumes from its checkpoint, a tick or more before the controller's time: the FMU's own
    // time goes on (an FMU refuses a communication point before it), and the run ends clean.
    let r = run(
        "plant-restart",
        &[
            "--duration-s",
            "3",
            "--controller-fmu",
            &fmu("pid"),
            "--fault",
            "plant:kill@1.5s,restart_after=0.3s",
            &robust(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.event("launcher", "process-restarted").is_some(), "{}", r.stdout);
    assert!(!r.stdout.contains("fmi2DoStep"), "{}", r.stdout);
    r.finish();
}

#[test]
fn silrig_check_judges_a_controller_fmu() {
    let dir = common::temp_dir(SUITE, "check-files");
    let suite = dir.join("suite.toml");
    std::fs::write(
        &suite,
        "name = \"fmu-controller\"\n\
         description = \"the PID FMU on the default scenario\"\n\
         [[cases]]\nname = \"lockstep-flight\"\nwhy = \"flight quality, twice for determinism\"\nmode = \"lockstep\"\n\
         duration_s = 8.0\n[cases.criteria]\nevery_tick_answered = true\nno_invalid_command = true\n\
         settled = { within_s = 6.0, band_deg = 1.0 }\nalpha_max_deg = 15.0\ndeterministic = true\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = Command::new(SILRIG)
        .arg("check")
        .arg(&suite)
        .args(["--controller-fmu", &fmu("pid"), "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let verdict: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap()).unwrap();
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{stderr}");
    assert_eq!(verdict["passed"], true, "{verdict}");
    assert!(verdict["controller"].as_str().unwrap().contains("pid.fmu"), "{}", verdict["controller"]);
    let judged = verdict["cases"][0]["judgements"].as_array().unwrap().len();
    assert!(judged >= 5, "{verdict}");
    // The line that flies the case again names the FMU.
    let reproduce = verdict["cases"][0]["reproduce"].as_str().unwrap();
    assert!(reproduce.contains(&format!("--controller-fmu {}", fmu("pid"))), "{reproduce}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn mapping_mistakes_are_refused_before_the_run_naming_the_file() {
    let dir = common::temp_dir(SUITE, "mapping-files");
    let pid = fmu("pid");
    let cases: [(&str, &[&str]); 6] = [
        (
            "[controller.map]\nnope = \"phi_deg\"",
            &["`controller.map.nope` = \"phi_deg\": the FMU has no variable \"nope\"", "its inputs: phi_deg"],
        ),
        (
            "[controller.map]\nkp_phi = \"phi_deg\"",
            &["`controller.map.kp_phi`: variable \"kp_phi\" has causality parameter", "its outputs: aileron"],
        ),
        (
            "[controller.map]\naileron = \"phi_deg\"",
            &["output \"aileron\" (mapped to `phi_deg` by `controller.map`) is `phi_deg`, an output of plant f16"],
        ),
        (
            "[controller.map]\naileron = \"flap\"",
            &[
                "output \"aileron\" (mapped to `flap` by `controller.map`) is `flap`, which plant f16 does not have",
                "its inputs: aileron, elevator",
            ],
        ),
        (
            "[controller.map]\nphi_deg = \"aileron\"",
            &["input \"phi_deg\" (mapped to `aileron` by `controller.map`) is `aileron`, an input of plant f16"],
        ),
        ("[controller.parameters]\nnope = 1.0", &["`controller.parameters.nope`: no variable of that name", "kp_phi"]),
    ];
    for (k, (extra, expected)) in cases.iter().enumerate() {
        let scenario = scenario_with(&dir, &format!("case{k}"), &robust(), extra);
        let stderr = refused(&format!("mapping-{k}"), &["--mode", "lockstep", "--controller-fmu", &pid, &scenario]);
        assert!(stderr.contains(&format!("FMU {pid}")), "case {k}: the file is not named: {stderr}");
        for e in *expected {
            assert!(stderr.contains(e), "case {k}: no {e:?} in: {stderr}");
        }
    }
    // A plant that has nothing the FMU reads or commands, known before the run (an FMU plant): its inputs would
    // stay at their start values, but none of its outputs commands the plant, named with the plant's inputs.
    let lag = scenario_with(&dir, "lag", &format!("{ROOT}/tests/scenarios/toy.toml"), "");
    let stderr =
        refused("mapping-lag3", &["--mode", "lockstep", "--plant-fmu", &fmu("lag3"), "--controller-fmu", &pid, &lag]);
    assert!(
        stderr.contains(&format!("FMU {pid}"))
            && stderr.contains("none of its outputs (aileron, elevator, rudder, err_phi_deg")
            && stderr.contains("named like an input of plant lag3 (u)"),
        "{stderr}"
    );
    // A `[controller] fmu` beside --controller-cmd is a contradiction, said as such.
    let both = scenario_with(&dir, "both", &robust(), "");
    let text = std::fs::read_to_string(&both)
        .unwrap()
        .replace("\n[controller]\n", &format!("\n[controller]\nfmu = \"{pid}\"\n"));
    std::fs::write(&both, text).unwrap();
    let stderr = refused("both", &["--mode", "lockstep", "--controller-cmd", "true", &both]);
    assert!(stderr.contains("the scenario's controller is the FMU") && stderr.contains(&pid), "{stderr}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_mapping_mistake_against_a_plant_known_only_when_it_joins_fails_the_controller_naming_the_file() {
    // A plant of the user's own announces its signals only when it runs: the controller FMU is bound then, and a
    // mistake ends the controller with the same message while the plant flies its failsafe.
    let dir = common::temp_dir(SUITE, "late-mapping-files");
    let scenario = scenario_with(
        &dir,
        "late",
        &format!("{ROOT}/tests/scenarios/toy.toml"),
        "[controller.map]\naileron = \"flap\"",
    );
    let pid = fmu("pid");
    common::client_lib(SILRIG);
    let toy = format!("python3 {ROOT}/tests/clients/toy_plant.py");
    let r = run(
        "late",
        &["--mode", "lockstep", "--duration-s", "1", "--plant-cmd", &toy, "--controller-fmu", &pid, &scenario],
    );
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let ended = r.process("controller")["ended"].as_str().unwrap_or_default().to_string();
    let said = format!("{ended}\n{}", r.failures());
    assert!(
        said.contains(&format!("FMU {pid}")) && said.contains("which plant toy does not have"),
        "{said}\n{}",
        r.stdout
    );
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_controller_fmu_run_replays_bit_identically() {
    // The recorded scenario names the FMU by its absolute path, so `silrig replay` flies the same FMU again.
    let pid = fmu("pid");
    let r = run("replay", &["--mode", "lockstep", "--duration-s", "3", "--controller-fmu", &pid, &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let o = Command::new(SILRIG).arg("replay").arg(&r.out).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    let replay: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(r.out.join("replay/replay.json")).unwrap()).unwrap();
    let text = replay.to_string();
    assert!(text.contains("err_theta_deg"), "the FMU's diagnostics were not compared: {text}");
    r.finish();
}

#[test]
fn an_fmi3_fmu_flies_as_a_controller_through_its_map() {
    // tests/fmu/lag3 (FMI 3.0: y' = (gain u - y) / tau) as a controller of the F-16: u reads theta_deg, y commands
    // the elevator. Not a good controller, but every value of its output is the command the plant got.
    let dir = common::temp_dir(SUITE, "fmi3-files");
    let scenario = scenario_with(
        &dir,
        "lag",
        &robust(),
        "[controller.map]\nu = \"theta_deg\"\ny = \"elevator\"\n[controller.parameters]\ngain = -0.2\ntau = 0.1",
    );
    let r = run("fmi3", &["--mode", "lockstep", "--duration-s", "1", "--controller-fmu", &fmu("lag3"), &scenario]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let detail = r.event("controller", "controller-fmu").unwrap()["detail"].as_str().unwrap().to_string();
    assert!(detail.contains("FMI 3.0"), "{detail}");
    let (header, rows) = r.trace();
    let (y, elevator, theta) =
        (column(&header, "y"), column(&header, "elevator_cmd_deg"), column(&header, "theta_deg"));
    assert!(rows.iter().all(|row| row[y] == row[elevator]), "the FMU's y is not the elevator command");
    // Its first step, integrated exactly by the FMU from y = 0 with u = theta at tick 0: the parameters reached it.
    let expected = -0.2 * rows[0][theta] * (1.0 - (-0.01f64 / 0.1).exp());
    assert!((rows[0][y] - expected).abs() < 1e-12, "y after one step: {} against {expected}", rows[0][y]);
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}
