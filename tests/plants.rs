//! Bring your own plant: a vehicle model of the user's own (`tests/clients/toy_plant.py`, three damped rotational
//! axes with the F-16's signal names, on the Python plant session of `libsilrig_client.so`) flies as the run's
//! plant through `silrig run --plant-cmd`, against the Python example controller unchanged, in lockstep and in
//! realtime, with the rig's clock, logger and report around it; the trace's columns are the ones it announced.
//! The same model in C (`examples/c/toy_plant.c`, compiled here with the system compiler) flies too.
//! JSBSim's Cessna 172 (`examples/python/jsbsim_plant.py`, PyPI `jsbsim` in `target/test-venv`) flies with the
//! example PID tuned for it, gets a verdict from `silrig check` with its own suite, and its recording replays
//! bit-identical. A broken announcement, NaN outputs, a model fault the plant cannot carry out and a controller
//! that needs signals the plant lacks get clear messages.
//! Each test has its own run id and folder; the launcher reaps what it started, and the tests check that it
//! removed the run's shared memory. No timing figure is asserted as a bound.

use std::process::{Command, Stdio};
use std::time::Duration;

mod common;
use common::{Run, no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn toy(mode: &str) -> String {
    common::client_lib(SILRIG);
    format!("python3 {ROOT}/tests/clients/toy_plant.py {mode}")
}

/// The C example plant, compiled with the system compiler against the header and the library.
fn c_plant() -> String {
    common::c_example(SILRIG, "plants", "toy_plant")
}

fn python_pid() -> String {
    format!("python3 {ROOT}/examples/python/pid_attitude.py")
}

/// `silrig run` with its own run id and folder, to the end.
fn run(test: &str, args: &[&str]) -> Run {
    Run::start(SILRIG, "plants", "p", test, args)
}

fn robust() -> String {
    format!("{ROOT}/configs/robust.toml")
}

/// The scenario the plants of our own fly: set points and timing, none of the F-16's sections.
fn toy_scenario() -> String {
    format!("{ROOT}/tests/scenarios/toy.toml")
}

#[test]
fn a_python_plant_flies_lockstep_with_the_example_controller_unchanged() {
    let r = run(
        "lockstep",
        &["--mode", "lockstep", "--plant-cmd", &toy("ok"), "--controller-cmd", &python_pid(), &toy_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0, "a tick went unanswered");
    assert_eq!(r.counter("controller", "commands_refused"), 0);
    assert_eq!(r.counter("logger", "rows_written"), 1001);
    let (header, rows) = r.trace();
    // The columns the toy announced (no alpha, no airspeed), commands before positions, then the diagnostics.
    let expected = "t_s,phi_deg,theta_deg,psi_deg,p_dps,q_dps,r_dps,aileron_cmd_deg,elevator_cmd_deg,rudder_cmd_deg,\
                    aileron_deg,elevator_deg,rudder_deg,flight_segment,err_phi_deg,err_theta_deg,err_psi_deg";
    assert_eq!(header.join(","), expected);
    assert_eq!(rows.len(), 1001);
    let theta = rows.last().unwrap()[2];
    assert!((theta - 10.0).abs() < 1.0, "theta ends at {theta}, set point 10");
    // The figures of the F-16's states do not fit this plant: said once in report.json, not failed and not on the
    // console; the signals figure shows its own.
    let left = &r.report["figures_left_out"][0];
    assert_eq!(left["figure"], "fig1_states.png", "{}", r.report["figures_left_out"]);
    assert!(left["reason"].as_str().unwrap().starts_with("the trace has no column `alpha_deg`"), "{left}");
    assert!(!r.stdout.contains("not drawn"), "{}", r.stdout);
    for file in ["signals.png", "signals.svg"] {
        let bytes = std::fs::read(r.out.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(bytes.len() > 10_000, "{file}: {} bytes", bytes.len());
    }
    let svg = std::fs::read_to_string(r.out.join("signals.svg")).unwrap();
    for caption in ["theta_deg (set point 10, dashed)", "elevator: position, command dashed", "deg/s"] {
        assert!(svg.contains(caption), "{caption} missing from signals.svg");
    }
    only_its_own_signals_summarised(&r);
    r.finish();
}

/// The toy's summary, printed and in report.json, names its signals alone: its attitude (roll and heading held at
/// their start, 0 deg, pitch stepped to 10 deg) and the late body rates; none of the F-16's alpha, flight path or
/// surfaces (the toy flies no actuator of the rig's), no NaN.
fn only_its_own_signals_summarised(r: &Run) {
    let control = &r.report["control"];
    assert_eq!(control["plant"], "toy");
    let rows: Vec<(&str, &str)> = control["setpoints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| (row["name"].as_str().unwrap(), row["response"].as_str().unwrap()))
        .collect();
    assert_eq!(rows, [("phi_deg", "held"), ("theta_deg", "stepped"), ("psi_deg", "held")], "{control}");
    assert!(control["body_rate_max_late_dps"].is_array(), "the toy announces p, q and r: {control}");
    for absent in ["alpha", "flight_path", "channels"] {
        assert!(control.get(absent).is_none(), "{absent} in {control}");
    }
    assert_eq!(control["actuators"], serde_json::json!([]));
    let json = control.to_string();
    assert!(!json.contains("null") && !json.contains("NaN"), "{json}");
    let from = r.stdout.find("scenario toy:").expect("the summary is printed");
    let to = from + r.stdout[from..].find("limit cycle").expect("the summary ends with the limit cycles");
    let summary = &r.stdout[from..to + r.stdout[to..].find('\n').unwrap_or(0)];
    for said in
        ["held: largest error", "step: settle(2%)", "max |p|, |q|, |r| in the last 3 s", "limit cycle (last 3 s)"]
    {
        assert!(summary.contains(said), "{said} missing:\n{summary}");
    }
    for absent in ["NaN", "alpha", "flight path", "surfaces", "actuator"] {
        assert!(!summary.contains(absent), "{absent} in the summary:\n{summary}");
    }
}

#[test]
fn a_c_plant_flies_lockstep_with_the_example_controller() {
    let r = run(
        "c-lockstep",
        &["--mode", "lockstep", "--plant-cmd", &c_plant(), "--controller-cmd", &python_pid(), &toy_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0);
    let (header, rows) = r.trace();
    assert_eq!(header[..4], ["t_s", "phi_deg", "theta_deg", "psi_deg"]);
    let theta = rows.last().unwrap()[2];
    assert!((theta - 10.0).abs() < 1.0, "theta ends at {theta}, set point 10");
    r.finish();

    // The plant reads its parameters from the scenario: with no control power it cannot leave 0 deg.
    let dir = common::temp_dir("plants", "c-param-scenario");
    let scenario = dir.join("toy-no-gain.toml");
    let base = std::fs::read_to_string(toy_scenario()).unwrap();
    std::fs::write(&scenario, base + "\n[plant.parameters]\ngain_dps2_per_deg = 0.0\n").unwrap();
    let args = ["--mode", "lockstep", "--duration-s", "1", "--plant-cmd", &c_plant(), "--controller-cmd"];
    let r = run("c-parameters", &[&args[..], &[&python_pid(), scenario.to_str().unwrap()]].concat());
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (_, rows) = r.trace();
    assert!(rows.iter().all(|row| row[2] == 0.0), "theta moved without control power");
    assert!(rows.iter().any(|row| row[8] != 0.0), "the controller did command the elevator");
    r.finish();
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Without a scenario file a plant of your own flies the embedded any-plant scenario (set points and timing only),
/// not the F-16's, whose initial condition and actuators it does not have.
#[test]
fn without_a_scenario_a_plant_of_your_own_flies_the_any_plant_scenario() {
    let r = run(
        "no-scenario",
        &["--mode", "lockstep", "--duration-s", "3", "--plant-cmd", &c_plant(), "--controller-cmd", &python_pid()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("scenario any-plant, lockstep mode"), "{}", r.stdout);
    assert_eq!(r.counter("plant", "ticks"), 301);
    let (_, rows) = r.trace();
    let theta = rows.last().unwrap()[2];
    assert!(theta > 5.0, "the any-plant scenario's pitch set point (10 deg) is flown: theta ends at {theta}");
    r.finish();
}

#[test]
fn a_python_plant_flies_2_s_realtime_with_the_rigs_timing_report() {
    let r = run(
        "realtime",
        &["--duration-s", "2", "--plant-cmd", &toy("ok"), "--controller-cmd", &python_pid(), &toy_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 201);
    assert!(r.counter("plant", "commands_received") > 150);
    let latencies =
        r.report["processes"].as_array().unwrap().iter().find(|p| p["process"] == "plant").unwrap()["latencies"]
            .as_array()
            .unwrap()
            .clone();
    let count = |name: &str| {
        latencies.iter().find(|l| l["name"] == name).map_or(0, |l| l["summary"]["count"].as_u64().unwrap())
    };
    assert!(count("plant.sense_to_actuate") > 150, "{latencies:?}");
    assert!(count("plant.wake_lateness") > 150);
    assert!(count("plant.step_exec") > 150);
    assert_eq!(r.trace().1.len(), 201);
    r.finish();
}

#[test]
fn nan_outputs_are_refused_counted_and_the_last_valid_ones_published() {
    let r = run(
        "nan",
        &["--mode", "lockstep", "--plant-cmd", &toy("nan"), "--controller-cmd", &python_pid(), &toy_scenario()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "outputs_refused"), 10);
    let refused = r.event("plant", "outputs-refused").expect("an outputs-refused event");
    assert!(refused["detail"].as_str().unwrap().contains("output phi_deg is NaN"), "{refused}");
    assert!(r.event("plant", "outputs-accepted").is_some());
    let (header, rows) = r.trace();
    assert_eq!(rows.len(), 1001);
    assert!(rows.iter().all(|row| row[1].is_finite()), "a NaN reached the trace");
    // Every held row is flagged, in trace.csv's last column and in timing.csv's plant_flags; 10 of 1001 ticks is
    // within the default share (1 %), so the run passes.
    assert_eq!(header.last().map(String::as_str), Some("outputs_held"));
    let held: Vec<usize> = (0..rows.len()).filter(|k| rows[*k][header.len() - 1] == 1.0).collect();
    assert_eq!(held, (300..=309).collect::<Vec<_>>());
    assert!(rows.iter().all(|row| [0.0, 1.0].contains(&row[header.len() - 1])));
    let timing = std::fs::read_to_string(r.out.join("timing.csv")).unwrap();
    let flags = timing.lines().next().unwrap().split(',').position(|c| c == "plant_flags").unwrap();
    let flagged: Vec<usize> = timing
        .lines()
        .skip(1)
        .enumerate()
        .filter(|(_, line)| line.split(',').nth(flags).unwrap().parse::<u32>().unwrap() & 64 != 0)
        .map(|(k, _)| k)
        .collect();
    assert_eq!(flagged, held, "timing.csv flags other rows than trace.csv");
    r.finish();
}

#[test]
fn a_plant_holding_its_outputs_past_the_share_fails_the_run_with_the_count() {
    // phi_deg is NaN from tick 334 on: 667 of 1001 ticks held, far past the default 1 %.
    let r = run(
        "degraded",
        &["--mode", "lockstep", "--plant-cmd", &toy("degraded"), "--controller-cmd", &python_pid(), &toy_scenario()],
    );
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.failures();
    assert!(
        failures.contains("held at the last valid ones on 667 of 1001 ticks (66.6 %)")
            && failures.contains("plant.outputs_held_fraction_max"),
        "{failures}"
    );
    assert!(r.stdout.contains("667 of 1001 ticks"), "the printed report does not say it: {}", r.stdout);
    let (header, rows) = r.trace();
    let held = rows.iter().filter(|row| row[header.len() - 1] == 1.0).count();
    assert_eq!(held, 667);
    r.finish();
    // The same flight with the key raised past two thirds passes.
    let dir = common::temp_dir("plants", "degraded-scenario");
    let scenario = dir.join("toy.toml");
    let text = std::fs::read_to_string(toy_scenario()).unwrap() + "\n[plant]\noutputs_held_fraction_max = 0.7\n";
    std::fs::write(&scenario, text).unwrap();
    let r = run(
        "degraded-allowed",
        &[
            "--mode",
            "lockstep",
            "--plant-cmd",
            &toy("degraded"),
            "--controller-cmd",
            &python_pid(),
            scenario.to_str().unwrap(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_broken_announcement_is_refused_naming_the_rule() {
    for (mode, needle) in [
        ("twice", "plant toy: output `phi_deg` named twice"),
        ("none", "plant toy announces no outputs: a plant publishes at least one"),
    ] {
        let r =
            run(mode, &["--duration-s", "1", "--startup-timeout-s", "2", "--plant-cmd", &toy(mode), &toy_scenario()]);
        assert_eq!(r.code, Some(1), "{mode}: {}\n{}", r.stdout, r.stderr);
        assert!(r.failures().contains(needle), "{mode}: {}", r.failures());
        r.finish();
    }
}

#[test]
fn a_controller_needing_signals_the_plant_lacks_is_told_what_the_plant_has() {
    // Our controller flies the F-16's states in book units, which the toy does not publish.
    let r = run("ours", &["--duration-s", "1", "--plant-cmd", &toy("ok"), &toy_scenario()]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.failures();
    assert!(failures.contains("plant toy has no output `vt_fps`; its outputs: phi_deg, theta_deg"), "{failures}");
    // The flight is whole: the plant flew its failsafe without a controller, and the logger kept every tick.
    assert_eq!(r.trace().1.len(), 101);
    r.finish();
}

fn jsbsim() -> String {
    common::client_lib(SILRIG);
    let python = common::venv_python("jsbsim", "jsbsim");
    format!("{} {ROOT}/examples/python/jsbsim_plant.py", python.display())
}

fn c172() -> String {
    format!("{ROOT}/examples/python/jsbsim_c172.toml")
}

#[test]
fn jsbsims_cessna_flies_lockstep_and_realtime_with_the_example_pid() {
    let r = run(
        "jsbsim-lockstep",
        &["--mode", "lockstep", "--plant-cmd", &jsbsim(), "--controller-cmd", &python_pid(), &c172()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0);
    assert_eq!(r.counter("controller", "commands_refused"), 0);
    let (header, rows) = r.trace();
    for column in ["alpha_deg", "vt_mps", "elevator_deg", "elevator_cmd", "throttle_cmd", "err_theta_deg"] {
        assert!(header.iter().any(|h| h == column), "{column} in {header:?}");
    }
    let theta = rows.last().unwrap()[header.iter().position(|h| h == "theta_deg").unwrap()];
    assert!((theta - 5.0).abs() < 0.5, "theta ends at {theta}, set point 5");
    // Its `[actuators.<input>]` apply, and the summary judges each of them: JSBSim reports no position of the rig's
    // servos (its aileron_deg is its own surface's), so from their commands against their limits.
    let names: Vec<(&str, Option<&str>, &str)> = r.report["control"]["actuators"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| (a["name"].as_str().unwrap(), a["position"].as_str(), a["command"].as_str().unwrap()))
        .collect();
    let by_command =
        [("aileron", None, "aileron_cmd"), ("elevator", None, "elevator_cmd"), ("rudder", None, "rudder_cmd")];
    assert_eq!(names, by_command, "{}", r.report["control"]);
    assert!(r.stdout.contains("aileron, elevator, rudder: the plant reports no position"), "{}", r.stdout);
    assert!(!r.stdout.contains("the scenario's actuator limits do not apply"), "{}", r.stdout);
    r.finish();

    // Realtime, trimmed where the scenario's [plant.parameters] says (6,000 ft instead of the example's 4,000).
    let dir = common::temp_dir("plants", "jsbsim-6000ft-scenario");
    let scenario = dir.join("c172-6000ft.toml");
    let text = std::fs::read_to_string(c172()).unwrap().replace("altitude_ft = 4000.0", "altitude_ft = 6000.0");
    std::fs::write(&scenario, text).unwrap();
    let r = run(
        "jsbsim-realtime",
        &["--duration-s", "2", "--plant-cmd", &jsbsim(), "--controller-cmd", &python_pid(), scenario.to_str().unwrap()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 201);
    assert!(r.counter("plant", "commands_received") > 150);
    let (header, rows) = r.trace();
    assert_eq!(rows.len(), 201);
    let alt_ft = rows[0][header.iter().position(|h| h == "alt_ft").unwrap()];
    assert!((alt_ft - 6000.0).abs() < 1.0, "trimmed at {alt_ft} ft");
    r.finish();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn silrig_check_gives_jsbsims_cessna_a_verdict_and_its_recording_replays_bit_identical() {
    let dir = common::temp_dir("plants", "jsbsim-check");
    let check_out = dir.join("check");
    let o = Command::new(SILRIG)
        .args(["check", &format!("{ROOT}/examples/python/jsbsim_check.toml"), "--out"])
        .arg(&check_out)
        .args(["--plant-cmd", &jsbsim(), "--controller-cmd", &python_pid()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("verdict: PASS: 2 of 2 cases passed"), "{stdout}");
    let line = |criterion: &str| stdout.lines().find(|l| l.split_whitespace().any(|w| w == criterion)).unwrap_or("");
    assert!(line("deterministic").contains("identical over 1001 ticks"), "{stdout}");
    // Criteria on the Cessna's own outputs, by name, in their units.
    for criterion in ["outputs.theta_deg.settled", "outputs.alt_ft.max", "outputs.vt_mps.min"] {
        assert!(line(criterion).trim_end().ends_with("pass"), "{criterion}: {stdout}");
    }
    assert!(line("outputs.vt_mps.min").contains("at least 40"), "{stdout}");
    std::fs::remove_dir_all(&dir).unwrap();

    let r = run(
        "jsbsim-record",
        &["--mode", "lockstep", "--plant-cmd", &jsbsim(), "--controller-cmd", &python_pid(), &c172()],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let o = Command::new(SILRIG).arg("replay").arg(&r.out).args(["--controller-cmd", &python_pid()]).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("compared 1001 ticks: 1001 bit-identical"), "{stdout}");
    assert!(stdout.contains("throttle_cmd"), "every input compared: {stdout}");
    r.finish();
}

#[test]
fn the_rigs_actuators_and_sensor_faults_act_on_the_named_signals_of_a_plant_of_your_own() {
    // The toy reports the positions its inputs held over the last step (aileron_deg ... rudder_deg): what the rig's
    // actuators gave it. Its own travel is -30..30 deg.
    let dir = common::temp_dir("plants", "chain-scenario");
    let scenario = dir.join("toy-actuators.toml");
    let base = std::fs::read_to_string(toy_scenario()).unwrap();
    std::fs::write(&scenario, base + "\n[actuators.elevator]\nmin = -20.0\nmax = 20.0\nrate_limit_per_s = 20.0\n")
        .unwrap();
    let r = run(
        "chain",
        &[
            "--mode",
            "lockstep",
            "--plant-cmd",
            &toy("ok"),
            "--controller-cmd",
            &python_pid(),
            "--fault",
            "plant:sensor-bias@5s,channel=theta_deg,bias=2.0",
            "--fault",
            "plant:actuator-hard-over@9s,surface=aileron,limit=max",
            scenario.to_str().unwrap(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (header, rows) = r.trace();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("{name} in {header:?}"));
    let (t, theta, elevator, aileron) = (col("t_s"), col("theta_deg"), col("elevator_deg"), col("aileron_deg"));
    // 20 deg/s at 100 Hz: at most 0.2 deg a tick, and the pitch step asks for more at first.
    let steps: Vec<f64> = rows.windows(2).map(|w| (w[1][elevator] - w[0][elevator]).abs()).collect();
    assert!(
        steps.iter().all(|d| *d <= 0.2 + 1e-9),
        "largest elevator step {:?}",
        steps.iter().cloned().fold(0.0, f64::max)
    );
    assert!(steps.iter().filter(|d| (**d - 0.2).abs() < 1e-9).count() >= 5, "the rate limit never cut the command");
    assert!(rows.iter().all(|row| row[elevator].abs() <= 20.0));
    // The bias shows in the measured theta from 5 s (the controller then flies it back to 10 deg measured).
    let at = |ts: f64| rows.iter().position(|row| (row[t] - ts).abs() < 1e-9).unwrap();
    // (less the tick's own motion, taken from the tick before)
    let step = |k: usize| rows[k][theta] - rows[k - 1][theta];
    let jump = step(at(5.0)) - step(at(4.99));
    assert!((jump - 2.0).abs() < 0.1, "theta jumped {jump} deg at 5 s");
    // Hard-over without `[actuators.aileron]`: instantly to the announced maximum, and held there.
    assert!(rows[at(8.99)][aileron] < 30.0);
    assert!(rows[at(9.01)..].iter().all(|row| row[aileron] == 30.0), "aileron after 9 s");
    // The summary judges the elevator, the one input under `[actuators]`, against its actuator, from the position
    // the toy reports: the ticks the trace shows at the rate limit.
    let actuators = r.report["control"]["actuators"].as_array().unwrap();
    assert_eq!(actuators.len(), 1, "{actuators:?}");
    let elevator_row = &actuators[0];
    assert_eq!((&elevator_row["name"], &elevator_row["position"]), (&"elevator".into(), &"elevator_deg".into()));
    let cut = steps.iter().filter(|d| **d >= 0.2 * (1.0 - 1e-9)).count() as u64;
    assert_eq!(elevator_row["ticks_at_rate_limit"].as_u64(), Some(cut), "{elevator_row}");
    assert_eq!(elevator_row["rate_limit_fraction"].as_f64(), Some(cut as f64 / rows.len() as f64));
    let table = r.stdout.lines().skip_while(|l| !l.trim_start().starts_with("actuator")).nth(1).unwrap_or_default();
    assert!(table.trim_start().starts_with("elevator") && table.contains(" deg "), "{}", r.stdout);
    r.finish();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_killed_plant_of_your_own_restarts_from_its_checkpoint_and_the_flight_goes_on() {
    let r = run(
        "plant-kill",
        &[
            "--duration-s",
            "3",
            "--plant-cmd",
            &toy("ok"),
            "--controller-cmd",
            &python_pid(),
            "--fault",
            "plant:kill@1s,restart_after=0.3s",
            &toy_scenario(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let resumed = r.event("plant", "plant-resumed").expect("a plant-resumed event");
    let detail = resumed["detail"].as_str().unwrap();
    let tick = resumed["tick"].as_u64().unwrap();
    assert!((50..=100).contains(&tick) && tick.is_multiple_of(10), "{detail}");
    let resumes = &r.report["plant_resumes"];
    assert_eq!(resumes[0]["at_tick"].as_u64(), Some(tick), "report.json's plant_resumes: {resumes}");
    assert!(r.event("plant", "plant-restarted-from-start").is_none(), "flew again from tick 0");
    // Every tick is logged exactly once, in order, and the model took up its state where it was saved.
    let (header, rows) = r.trace();
    let t: Vec<f64> = rows.iter().map(|row| row[0]).collect();
    assert_eq!(t.len(), 301);
    assert!(t.windows(2).all(|w| w[1] > w[0]), "ticks out of order or repeated");
    let theta = header.iter().position(|h| h == "theta_deg").unwrap();
    let jumps = rows.windows(2).map(|w| (w[1][theta] - w[0][theta]).abs()).fold(0.0, f64::max);
    assert!(jumps < 1.0, "theta jumped {jumps} deg between two ticks");
    r.finish();
}

#[test]
fn names_a_plant_lacks_are_refused_with_its_list() {
    // A plant of your own checks the scenario against the signals it announces...
    let r = run(
        "chain-names",
        &[
            "--duration-s",
            "1",
            "--plant-cmd",
            &toy("ok"),
            "--controller-cmd",
            &python_pid(),
            "--fault",
            "plant:sensor-bias@0.5s,channel=theta_rad,bias=0.01",
            &toy_scenario(),
        ],
    );
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.failures();
    assert!(failures.contains("`faults[0].channel`: plant toy has no channel"), "{failures}");
    assert!(failures.contains("theta_rad") && failures.contains("one of phi_deg, theta_deg"), "{failures}");
    r.finish();
    // ... and the built-in F-16 before anything runs.
    let r = run("f16-names", &["--fault", "plant:sensor-bias@1s,channel=theta_deg,bias=0.01", &robust()]);
    assert_eq!(r.code, Some(2), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("the F-16 has no channel \"theta_deg\"; one of vt_fps"), "{}", r.stderr);
    std::fs::remove_dir_all(&r.dir).unwrap();
}

#[test]
fn a_second_plant_for_a_run_is_refused_and_the_run_goes_on() {
    let dir = common::temp_dir("plants", "second");
    let id = format!("p{}-second", std::process::id());
    let out = dir.join("out");
    let launcher = Command::new(SILRIG)
        .args(["run", "--duration-s", "3", "--quiet", "--no-baseline", "--run-id", &id, "--out"])
        .arg(&out)
        .args(["--plant-cmd", &toy("ok"), "--controller-cmd", &python_pid(), &toy_scenario()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Once the first plant flies (its checkpoint-free run writes its events), a second one is started by hand.
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    while !std::fs::read_to_string(out.join("events.jsonl")).is_ok_and(|t| t.contains("\"ticking\"")) {
        assert!(std::time::Instant::now() < deadline, "the first plant never started ticking");
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = Command::new("python3")
        .arg(format!("{ROOT}/tests/clients/toy_plant.py"))
        .env("SILRIG_CLIENT_LIB", common::client_lib(SILRIG))
        .env("SILRIG_RUN_ID", &id)
        .env("SILRIG_SCENARIO", out.join("scenario.toml"))
        .env("SILRIG_OUT", dir.join("second"))
        .output()
        .unwrap();
    assert_eq!(second.status.code(), Some(2));
    let said = String::from_utf8_lossy(&second.stderr);
    assert!(said.contains(&format!("refusing to start a second plant: run `{id}` has one")), "{said}");
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stdout));
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_raw_iceoryx2_plant_written_from_the_contract_flies_2_s_realtime_without_a_report() {
    let python = common::venv_python("iceoryx2", "iceoryx2==0.10.0");
    let plant = format!("{} {ROOT}/tests/clients/raw_plant.py", python.display());
    let r =
        run("raw", &["--duration-s", "2", "--plant-cmd", &plant, "--controller-cmd", &python_pid(), &toy_scenario()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("note: plant: your --plant-cmd wrote no report"), "{}", r.stdout);
    assert_eq!(r.counter("logger", "rows_written"), 201);
    assert!(r.counter("controller", "commands_sent") > 150, "the controller answered the raw plant");
    let (header, rows) = r.trace();
    assert_eq!(header[..4], ["t_s", "phi_deg", "theta_deg", "psi_deg"]);
    assert_eq!(rows.len(), 201);
    r.finish();
}

#[test]
fn a_plant_started_by_hand_joins_an_external_run() {
    let dir = common::temp_dir("plants", "external");
    let id = format!("p{}-external", std::process::id());
    let out = dir.join("out");
    let launcher = Command::new(SILRIG)
        .args(["run", "--mode", "lockstep", "--plant", "external", "--external-timeout-s", "60", "--no-baseline"])
        .args(["--run-id", &id, "--out", out.to_str().unwrap(), "--controller-cmd", &python_pid(), &toy_scenario()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let env_file = out.join("plant.env");
    let start = std::time::Instant::now();
    while !env_file.exists() {
        assert!(start.elapsed() < Duration::from_secs(20), "no plant.env");
        std::thread::sleep(Duration::from_millis(20));
    }
    let plant = Command::new("sh")
        .arg("-c")
        .arg(format!(". '{}' && exec {}", env_file.display(), toy("ok")))
        .env("SILRIG_CLIENT_LIB", common::client_lib(SILRIG))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let p = wait_with_watchdog(plant, Duration::from_secs(90));
    let o = wait_with_watchdog(launcher, Duration::from_secs(90));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(p.status.success(), "plant: {}", String::from_utf8_lossy(&p.stderr));
    assert!(o.status.success(), "{}\n{stderr}", String::from_utf8_lossy(&o.stdout));
    assert!(stderr.contains("waiting up to 60 s for a plant"), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let plant = report["processes"].as_array().unwrap().iter().find(|p| p["process"] == "plant").unwrap();
    assert_eq!(plant["ended"], "completed", "the plant's own report joins the run's");
    assert_eq!(plant["counters"]["ticks"], 1001);
    assert_eq!(plant["counters"]["command_misses"], 0);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_process_fault_on_a_plant_the_launcher_did_not_start_is_refused() {
    let r = run("external-fault", &["--plant", "external", "--fault", "plant:kill@1s", &toy_scenario()]);
    assert_eq!(r.code, Some(2), "{}\n{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("needs a plant the launcher starts, not --plant external"), "{}", r.stderr);
    std::fs::remove_dir_all(&r.dir).unwrap();
}
