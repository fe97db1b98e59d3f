//! The quadrotor, the second built-in vehicle, flown everywhere the F-16 flies with our quadrotor controller: `silrig
//! sim` takes it off to its hover and tracks attitude steps, the lockstep rig gives sim's trace byte for byte, a
//! realtime run at 1 kHz completes, `silrig check configs/check-quad.toml` passes its suite (timing criteria only
//! measured, never required: the machine is shared), `silrig sweep` flies its dispersed parameters, and every key
//! of the F-16's is refused for it, in words, by each command. Each rig run has its own run id and folder and leaves
//! no shared memory.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

mod common;
use common::{Run, no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Criteria whose outcome depends on how busy the machine is.
const TIMING_CRITERIA: [&str; 4] =
    ["compute_p99", "sense_to_actuate_p99", "deadline_misses_max", "every_tick_answered"];

fn config(name: &str) -> String {
    Path::new(ROOT).join("configs").join(format!("{name}.toml")).display().to_string()
}

fn silrig(args: &[&str]) -> Output {
    let child = Command::new(SILRIG)
        .args(args)
        .current_dir(ROOT)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_with_watchdog(child, Duration::from_secs(300))
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn summary(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The summary's row of set point `name`.
fn setpoint<'a>(s: &'a Value, name: &str) -> &'a Value {
    s["setpoints"].as_array().unwrap().iter().find(|r| r["name"] == name).unwrap_or_else(|| panic!("no {name}: {s}"))
}

fn sim(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(format!("sim-{name}"));
    let o = silrig(&["sim", &config(name), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    out
}

#[test]
fn sim_takes_it_off_to_its_hover_and_tracks_attitude_steps() {
    let dir = common::temp_dir("quad", "sim");
    let hover = summary(&sim(&dir, "quad-hover"));
    assert_eq!(hover["plant"], "quad");
    assert_eq!(hover["ticks"], 10001);
    let alt = setpoint(&hover, "alt_m");
    assert_eq!((alt["initial"].as_f64(), alt["setpoint"].as_f64()), (Some(0.0), Some(2.0)), "{alt}");
    assert!((alt["final_value"].as_f64().unwrap() - 2.0).abs() < 0.01, "{alt}");
    let steps = summary(&sim(&dir, "quad-steps"));
    for (name, set) in [("phi_deg", 10.0), ("theta_deg", -10.0), ("psi_deg", 30.0)] {
        let row = setpoint(&steps, name);
        assert!((row["final_value"].as_f64().unwrap() - set).abs() < 0.2, "{row}");
    }
    assert!(setpoint(&steps, "alt_m")["max_error"].as_f64().unwrap() < 0.1, "{steps}");
    let motors: Vec<&str> =
        steps["actuators"].as_array().unwrap().iter().map(|a| a["name"].as_str().unwrap()).collect();
    assert_eq!(motors, ["motor1", "motor2", "motor3", "motor4"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn lockstep_flies_sims_trace_and_realtime_completes_at_1_khz() {
    let dir = common::temp_dir("quad", "rig");
    let reference = std::fs::read(sim(&dir, "quad-hover").join("trace.csv")).unwrap();
    let lockstep = Run::start(SILRIG, "quad", "q", "lockstep", &[&config("quad-hover"), "--mode", "lockstep"]);
    assert_eq!(lockstep.code, Some(0), "{}{}", lockstep.stdout, lockstep.stderr);
    assert!(std::fs::read(lockstep.out.join("trace.csv")).unwrap() == reference, "lockstep's trace is not sim's");
    lockstep.finish();
    let realtime = Run::start(SILRIG, "quad", "q", "realtime", &[&config("quad-hover"), "--mode", "realtime"]);
    assert_eq!(realtime.code, Some(0), "{}{}", realtime.stdout, realtime.stderr);
    assert_eq!(realtime.counter("plant", "ticks"), 10001);
    let (header, rows) = realtime.trace();
    let alt = Run::column(&header, "alt_m");
    assert!((rows.last().unwrap()[alt] - 2.0).abs() < 0.05, "{:?}", rows.last());
    assert!(realtime.stdout.contains("scenario quad-hover: 10001 samples every 0.001 s"), "{}", realtime.stdout);
    realtime.finish();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_roll_step_late_in_the_run_is_flown_from_its_time_alike_in_sim_and_lockstep() {
    let dir = common::temp_dir("quad", "late-step-sim");
    let out = sim(&dir, "quad-roll-step");
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let header: Vec<String> = csv.lines().next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> =
        csv.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect();
    let (t, phi) = (Run::column(&header, "t_s"), Run::column(&header, "phi_deg"));
    let phi_over = |from_s: f64, to_s: f64| {
        let values = rows.iter().filter(|r| r[t] >= from_s && r[t] < to_s).map(|r| r[phi]);
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    // Level until the step at 2 s (nothing moves it before), near 10 deg once it has settled, level again after 4 s.
    let before = phi_over(0.0, 2.0);
    assert!(before.0 > -0.1 && before.1 < 0.1, "roll before the step: {before:?}");
    let during = phi_over(3.0, 4.0);
    assert!(during.0 > 9.5 && during.1 < 10.5, "roll after the step to 10 deg: {during:?}");
    let after = phi_over(5.0, 6.1);
    assert!(after.0 > -0.5 && after.1 < 0.5, "roll after the step back: {after:?}");
    // The summary describes the last step (back to 0 at 4 s), measured from the roll it started at.
    let flown = summary(&out);
    let row = setpoint(&flown, "phi_deg");
    assert_eq!(row["setpoint"].as_f64(), Some(0.0), "{row}");
    assert!(row["initial"].as_f64().unwrap() > 9.5, "{row}");
    // The lockstep rig flies the same schedule: the same trace, byte for byte.
    let lockstep = Run::start(SILRIG, "quad", "q", "late-step", &[&config("quad-roll-step"), "--mode", "lockstep"]);
    assert_eq!(lockstep.code, Some(0), "{}{}", lockstep.stdout, lockstep.stderr);
    assert!(std::fs::read_to_string(lockstep.out.join("trace.csv")).unwrap() == csv, "lockstep's trace is not sim's");
    lockstep.finish();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_quadrotor_suite_passes_in_lockstep_and_realtime() {
    let dir = common::temp_dir("quad", "check");
    let out = dir.join("out");
    let o = silrig(&["check", &config("check-quad"), "--out", out.to_str().unwrap()]);
    let verdict: Value = serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap())
        .unwrap_or_else(|e| panic!("{e}: {}", text(&o)));
    let cases = verdict["cases"].as_array().unwrap();
    let names: Vec<&str> = cases.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "hover-lockstep",
            "hover-realtime",
            "attitude-steps-lockstep",
            "attitude-steps-realtime",
            "controller-kill-restart",
            "dispersed-vehicles"
        ]
    );
    let mut timing_failed = false;
    for case in cases {
        for j in case["judgements"].as_array().unwrap() {
            let criterion = j["criterion"].as_str().unwrap();
            if TIMING_CRITERIA.contains(&criterion) {
                timing_failed |= j["passed"] != true;
                assert_ne!(j["measured"], "-", "{}: {criterion} was not measured", case["name"]);
            } else {
                assert_eq!(j["passed"], true, "{}: {criterion} failed: {j}\n{}", case["name"], text(&o));
            }
        }
    }
    // 0: every criterion passed; 1 or 3 only from a timing criterion this shared machine failed or left open.
    let code = o.status.code();
    assert!(code == Some(0) || timing_failed && matches!(code, Some(1 | 3)), "{code:?}: {}", text(&o));
    for case in cases.iter().filter(|c| c["mode"] != "sweep") {
        for run in case["run_dirs"].as_array().unwrap() {
            let report: Value = serde_json::from_str(
                &std::fs::read_to_string(Path::new(run.as_str().unwrap()).join("report.json")).unwrap(),
            )
            .unwrap();
            no_shared_memory_left(report["run_id"].as_str().unwrap());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_sweep_flies_its_dispersed_parameters() {
    let dir = common::temp_dir("quad", "sweep");
    let out = dir.join("out");
    let o = silrig(&["sweep", &config("quad-sweep"), "--runs", "6", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let cases = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    let header = cases.lines().next().unwrap();
    assert!(header.contains("plant.parameters.mass_kg") && header.contains("plant.parameters.motor_tau_up_s"));
    let mass = header.split(',').position(|c| c == "plant.parameters.mass_kg").unwrap();
    let masses: Vec<&str> = cases.lines().skip(1).map(|l| l.split(',').nth(mass).unwrap_or("")).collect();
    assert_eq!(masses.len(), 6, "{cases}");
    assert!(masses.windows(2).any(|w| w[0] != w[1]), "the mass is dispersed: {cases}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_f16s_keys_are_refused_for_the_quadrotor_by_every_command() {
    let dir = common::temp_dir("quad", "refused");
    let hover = std::fs::read_to_string(config("quad-hover")).unwrap();
    let with_initial = dir.join("with-initial.toml");
    std::fs::write(&with_initial, format!("{hover}\n[initial]\naltitude_ft = 100.0\nairspeed_mps = 150.0\n")).unwrap();
    let said = "`initial`: is the F-16's initial condition; the scenario flies the built-in quadrotor \
                (`plant.model = \"quad\"`): it starts from `plant.parameters.start_alt_m`";
    let suite = dir.join("suite.toml");
    let case = "[[cases]]\nname = \"c\"\nmode = \"lockstep\"\n[cases.criteria]\nno_invalid_command = true\n";
    std::fs::write(&suite, format!("name = \"s\"\nscenario = \"with-initial.toml\"\n{case}")).unwrap();
    for args in [["sim", with_initial.to_str().unwrap()], ["check", suite.to_str().unwrap()]] {
        let o = silrig(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains(said), "{args:?}: {}", text(&o));
    }
    let stderr = Run::refused(SILRIG, "quad", "q", "refused-run", &[with_initial.to_str().unwrap()]);
    assert!(stderr.contains(said), "{stderr}");
    let dispersed = dir.join("dispersed.toml");
    std::fs::write(
        &dispersed,
        format!(
            "{hover}\n[criteria]\nno_sustained_oscillation = true\n\n[dispersions]\n\
             \"plant.xcg\" = {{ dist = \"uniform\", min = 0.3, max = 0.4 }}\n"
        ),
    )
    .unwrap();
    let o = silrig(&["sweep", dispersed.to_str().unwrap(), "--runs", "2", "--out", dir.join("s").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("does not read `plant.xcg`: disperse its parameters as `plant.parameters.<name>`"));
    // The quadrotor exports as an FMU of its own (tests/fmu_export_quad.rs holds it to FMPy and to `silrig sim`).
    let o = silrig(&["export-fmu", &config("quad-hover"), "--out", dir.join("q.fmu").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(dir.join("q.fmu").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn our_controller_at_250_hz_flies_the_1_khz_plant_alike_in_sim_lockstep_and_realtime() {
    let dir = common::temp_dir("quad", "rates");
    // The hover with the controller every 4th plant tick: 250 Hz against the plant's 1 kHz.
    let hover = std::fs::read_to_string(config("quad-hover")).unwrap();
    let slower = hover.replace("dt_s = 0.001\n", "dt_s = 0.001\ncontroller_every_ticks = 4\n");
    assert_ne!(slower, hover);
    let scenario = dir.join("quad-hover-250hz.toml");
    std::fs::write(&scenario, slower).unwrap();
    let scenario = scenario.to_str().unwrap();
    let out = dir.join("sim");
    let o = silrig(&["sim", scenario, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let reference = std::fs::read(out.join("trace.csv")).unwrap();
    assert_ne!(
        reference,
        std::fs::read(sim(&dir, "quad-hover").join("trace.csv")).unwrap(),
        "the rate changed nothing"
    );
    // The trace keeps the plant's rate; the commands change only on the controller's ticks.
    let text_trace = String::from_utf8(reference.clone()).unwrap();
    let mut lines = text_trace.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let motor = header.iter().position(|h| *h == "motor1_cmd").unwrap();
    let commands: Vec<&str> = lines.map(|l| l.split(',').nth(motor).unwrap()).collect();
    assert_eq!(commands.len(), 10001);
    let changes: Vec<usize> = (1..commands.len()).filter(|&k| commands[k] != commands[k - 1]).collect();
    assert!(changes.len() > 100 && changes.iter().all(|k| k % 4 == 0), "commands changed off the controller's ticks");
    assert!((setpoint(&summary(&out), "alt_m")["final_value"].as_f64().unwrap() - 2.0).abs() < 0.05);
    let lockstep = Run::start(SILRIG, "quad", "q", "rates-lockstep", &[scenario, "--mode", "lockstep"]);
    assert_eq!(lockstep.code, Some(0), "{}{}", lockstep.stdout, lockstep.stderr);
    assert!(std::fs::read(lockstep.out.join("trace.csv")).unwrap() == reference, "lockstep's trace is not sim's");
    // 2,501 controller ticks of 10,001: the session answered the other 7,500 with the controller's last answer.
    assert_eq!(lockstep.counter("controller", "commands_repeated"), 7500);
    assert_eq!(lockstep.counter("controller", "commands_sent"), 10001);
    assert_eq!(lockstep.counter("plant", "command_misses"), 0);
    lockstep.finish();
    let realtime = Run::start(SILRIG, "quad", "q", "rates-realtime", &[scenario, "--mode", "realtime"]);
    assert_eq!(realtime.code, Some(0), "{}{}", realtime.stdout, realtime.stderr);
    assert_eq!(realtime.counter("plant", "ticks"), 10001);
    assert!(realtime.counter("controller", "commands_repeated") > 0);
    let (header, rows) = realtime.trace();
    let alt = Run::column(&header, "alt_m");
    assert!((rows.last().unwrap()[alt] - 2.0).abs() < 0.05, "{:?}", rows.last());
    realtime.finish();
    std::fs::remove_dir_all(&dir).unwrap();
}
