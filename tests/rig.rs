//! The three-process rig with the real binaries: realtime and lockstep runs complete with every report field,
//! lockstep reproduces `silrig sim` bit for bit, two rigs side by side do not interfere, and a second controller
//! for a run is refused. Each test uses its own run id and output folder; the launcher reaps its children and
//! removes the run's shared memory, and the test checks that it did. No timing figure is asserted as a bound.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

fn temp_dir(test: &str) -> PathBuf {
    common::temp_dir("rig", test)
}

fn run_id(test: &str) -> String {
    format!("t{}-{test}", std::process::id())
}

fn config(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs").join(format!("{name}.toml")).display().to_string()
}

fn silrig_run(args: &[&str]) -> Child {
    Command::new(SILRIG).arg("run").args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap()
}

/// The trace's diagnostic columns came from the controller's announcement, not from the logger's fallback (checked
/// in lockstep, where row 0 always waits for the command answering tick 0, which follows the announcement; in
/// realtime a controller that falls 10 ticks behind at its start is allowed to leave the fallback in place).
fn diagnostics_were_announced(out: &Path) {
    let events = std::fs::read_to_string(out.join("events.jsonl")).unwrap_or_default();
    assert!(!events.contains("controller-unannounced"), "the logger fell back on the scenario's names:\n{events}");
    assert!(!events.contains("diagnostics-renamed"), "{events}");
}

fn report(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap()
}

fn process<'a>(r: &'a Value, name: &str) -> &'a Value {
    r["processes"].as_array().unwrap().iter().find(|p| p["process"] == name).unwrap()
}

#[derive(PartialEq)]
enum Mode {
    Lockstep,
    Realtime,
    RealtimeWithBaseline,
}

fn check_report(r: &Value, ticks: u64, mode: Mode) {
    let realtime = mode != Mode::Lockstep;
    assert_eq!(r["failures"].as_array().unwrap().len(), 0, "{}", r["failures"]);
    assert_eq!(r["leftovers"].as_array().unwrap().len(), 0, "{}", r["leftovers"]);
    for key in ["run_id", "scenario", "mode", "conditions_start", "conditions_end", "wall_s", "cycles_per_s", "control"]
    {
        assert!(!r[key].is_null(), "report lacks {key}");
    }
    assert!(r["conditions_start"]["cpu_count"].as_u64().unwrap() >= 1);
    let plant = process(r, "plant");
    assert_eq!(plant["counters"]["ticks"], ticks);
    assert_eq!(plant["ended"], "completed");
    // The launcher's SIGTERM at the end is not a kill: a controller it stopped there says so.
    let controller = process(r, "controller")["ended"].as_str().unwrap();
    assert!(controller == "completed" || controller == "stopped at end", "{controller}");
    let logger = process(r, "logger");
    assert_eq!(logger["counters"]["rows_written"], ticks);
    for (p, counter) in
        [("logger", "plant_samples_lost"), ("logger", "command_samples_lost"), ("plant", "commands_lost")]
    {
        assert_eq!(process(r, p)["counters"][counter], 0, "{p}.{counter}");
    }
    let without = logger["counters"]["rows_without_command"].as_u64().unwrap();
    if realtime {
        // Nothing sent is lost: on a loaded machine the controller may act on the newest of several waiting samples,
        // leaving a tick it never answered, but every command it sent is in the log.
        let sent = process(r, "controller")["counters"]["commands_sent"].as_u64().unwrap();
        assert_eq!(ticks - without, sent);
    } else {
        assert_eq!(without, 0, "lockstep answers every tick");
        assert_eq!(process(r, "controller")["counters"]["plant_samples_lost"], 0);
    }
    for p in ["plant", "controller", "logger"] {
        assert!(process(r, p)["scheduling"].as_str().unwrap().starts_with("SCHED_"), "{p}");
        for l in process(r, p)["latencies"].as_array().unwrap() {
            let s = &l["summary"];
            let name = l["name"].as_str().unwrap();
            if (name == "plant.wake_lateness" || name == "plant.checkpoint_write") && !realtime {
                assert_eq!(s["count"], 0, "lockstep neither sleeps nor saves checkpoints");
                continue;
            }
            assert!(s["count"].as_u64().unwrap() > 0, "{name} is empty");
            let f = |k: &str| s[k].as_f64().unwrap();
            assert!(f("min_us") <= f("p50_us") && f("p50_us") <= f("p90_us"), "{name}: {s}");
            assert!(
                f("p90_us") <= f("p99_us") && f("p99_us") <= f("p999_us") && f("p999_us") <= f("max_us"),
                "{name}: {s}"
            );
        }
    }
    if mode == Mode::RealtimeWithBaseline {
        assert!(r["timer_baseline"]["lateness"]["count"].as_u64().unwrap() > 0);
        assert!(r["timer_baseline"]["lateness_steady"]["count"].as_u64().unwrap() > 0);
    }
    // The plant's per-tick distributions and the controller's compute time split at 1 s of simulated time: ticks
    // 0..=99 are the warm-up.
    let phases: Vec<&str> = r["phases"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    let mut expected = vec!["plant.step_exec", "controller.compute"];
    if realtime {
        expected.insert(0, "plant.wake_lateness");
    }
    assert_eq!(phases, expected);
    for p in r["phases"].as_array().unwrap() {
        assert_eq!((p["warm_up"]["count"].as_u64(), p["steady"]["count"].as_u64()), (Some(100), Some(ticks - 100)));
    }
}

#[test]
fn a_2_s_realtime_run_completes_with_every_report_field() {
    let dir = temp_dir("realtime");
    let id = run_id("rt");
    let out = dir.join("out");
    let child = silrig_run(&["--duration-s", "2", "--run-id", &id, "--out", out.to_str().unwrap()]);
    let o = wait_with_watchdog(child, Duration::from_secs(60));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("plant.wake_lateness") && text.contains("os-floor.wake_lateness"), "{text}");
    check_report(&report(&out), 201, Mode::RealtimeWithBaseline);
    for f in [
        "trace.csv",
        "timing.csv",
        "latency.png",
        "latency_histogram.png",
        "fig1_states.png",
        "plant.sense_to_actuate.hgrm",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let hgrm = std::fs::read_to_string(out.join("plant.wake_lateness.hgrm")).unwrap();
    assert!(hgrm.contains("Percentile") && hgrm.contains("#[Max"), "{hgrm}");
    per_tick_timing_matches_the_report(&out, true);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `timing.csv` has the plant's wake-up lateness and step execution time of every tick, and they are the values
/// the report's distributions were recorded from (their maxima agree to the histogram's 3 significant digits).
fn per_tick_timing_matches_the_report(out: &Path, realtime: bool) {
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    let mut lines = timing.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap_or_else(|| panic!("no {name} column"));
    let (wake, exec) = (column("wake_lateness_ns"), column("step_exec_ns"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let wake_ns: Vec<i64> = rows.iter().map(|r| r[wake].parse().unwrap()).collect();
    let exec_ns: Vec<u64> = rows.iter().map(|r| r[exec].parse().unwrap()).collect();
    let r = report(out);
    let summary = |name: &str| {
        let p = process(&r, "plant")["latencies"].as_array().unwrap().iter().find(|l| l["name"] == name).cloned();
        p.unwrap()["summary"].clone()
    };
    let close =
        |column_max_ns: f64, report_max_us: f64| (column_max_ns / 1e3 - report_max_us).abs() <= 2e-3 * report_max_us;
    let exec_max = summary("plant.step_exec")["max_us"].as_f64().unwrap();
    assert!(close(*exec_ns.iter().max().unwrap() as f64, exec_max), "step_exec column against {exec_max} us");
    if realtime {
        let wake_max = summary("plant.wake_lateness")["max_us"].as_f64().unwrap();
        assert!(close(*wake_ns.iter().max().unwrap() as f64, wake_max), "wake_lateness column against {wake_max} us");
    } else {
        assert!(wake_ns.iter().all(|&w| w == 0), "lockstep does not sleep");
    }
}

fn lockstep_matches_sim(scenario: &str, test: &str) {
    let dir = temp_dir(test);
    let id = run_id(test);
    let (rig_out, sim_out) = (dir.join("rig"), dir.join("sim"));
    let child = silrig_run(&[scenario, "--mode", "lockstep", "--run-id", &id, "--out", rig_out.to_str().unwrap()]);
    let o = wait_with_watchdog(child, Duration::from_secs(60));
    assert!(o.status.success(), "{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    check_report(&report(&rig_out), 1001, Mode::Lockstep);
    diagnostics_were_announced(&rig_out);
    per_tick_timing_matches_the_report(&rig_out, false);
    let sim = Command::new(SILRIG).args(["sim", scenario, "--out", sim_out.to_str().unwrap()]).output().unwrap();
    assert!(sim.status.success());
    let (a, b) = (std::fs::read(rig_out.join("trace.csv")).unwrap(), std::fs::read(sim_out.join("trace.csv")).unwrap());
    assert!(a == b, "lockstep trace differs from silrig sim for {scenario}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_flight_leaving_the_models_envelope_ends_the_run_with_the_reason_and_the_same_trace_as_sim() {
    let tumble = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenarios/tumble.toml").display().to_string();
    let dir = temp_dir("envelope");
    let id = run_id("envelope");
    let (rig_out, sim_out) = (dir.join("rig"), dir.join("sim"));
    let child = silrig_run(&[&tumble, "--mode", "lockstep", "--run-id", &id, "--out", rig_out.to_str().unwrap()]);
    let o = wait_with_watchdog(child, Duration::from_secs(60));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("the state left the model's envelope at t = 2.18 s: `beta_rad`"), "{stdout}");
    let r = report(&rig_out);
    assert!(process(&r, "plant")["ended"].as_str().unwrap().contains("left the model's envelope"));
    for peer in ["controller", "logger"] {
        assert_eq!(process(&r, peer)["ended"], "completed", "{peer} saw the run end");
    }
    // The plant's end-of-run sample completed the last row: the rig logged exactly what `silrig sim` flew.
    let sim = Command::new(SILRIG).args(["sim", &tumble, "--out", sim_out.to_str().unwrap()]).output().unwrap();
    assert_eq!(sim.status.code(), Some(1));
    let (a, b) = (std::fs::read(rig_out.join("trace.csv")).unwrap(), std::fs::read(sim_out.join("trace.csv")).unwrap());
    assert!(a == b, "the rig's trace differs from silrig sim's");
    assert_eq!(String::from_utf8_lossy(&a).lines().count() - 1, 218);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn lockstep_next_tick_equals_sim_bit_for_bit() {
    lockstep_matches_sim(&config("paper-next-tick"), "lock-next");
}

#[test]
fn lockstep_same_tick_equals_sim_bit_for_bit() {
    lockstep_matches_sim(&config("paper"), "lock-same");
}

/// Every plant-model fault at once: the rig's plant applies them through the same runner, and draws the same
/// sensor noise from the seed, so its trace still equals `silrig sim`'s bit for bit.
#[test]
fn lockstep_with_plant_faults_equals_sim_bit_for_bit() {
    let dir = temp_dir("lock-faults-scenario");
    let scenario = dir.join("faults.toml");
    let plan = r#"
[[faults]]
at_s = 1.0
target = "plant"
action = "sensor-noise"
channel = "phi_rad"
std = 0.005

[[faults]]
at_s = 2.0
duration_s = 3.0
target = "plant"
action = "sensor-bias"
channel = "q_radps"
bias = 0.01

[[faults]]
at_s = 3.0
duration_s = 1.0
target = "plant"
action = "actuator-stuck"
surface = "rudder"

[[faults]]
at_s = 5.0
duration_s = 0.3
target = "plant"
action = "actuator-hard-over"
surface = "aileron"
limit = "min"

[[faults]]
at_s = 6.0
duration_s = 0.5
target = "plant"
action = "actuator-rate-frozen"
surface = "elevator"
"#;
    let base = std::fs::read_to_string(config("paper-next-tick")).unwrap();
    std::fs::write(&scenario, format!("{base}\n{plan}")).unwrap();
    lockstep_matches_sim(scenario.to_str().unwrap(), "lock-faults");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An elevator hard-over drives our controller's demand past the ±90 deg the plant accepts (the chaos soak's
/// departure: its refused commands left the plant on the failsafe trim). Our controller limits its commands to the
/// announced range, as a flight computer does, so nothing is refused and the rig still flies what `silrig sim` flies.
#[test]
fn our_controller_limits_its_demand_to_the_plants_range_after_a_hard_over() {
    let dir = temp_dir("hard-over");
    let scenario = dir.join("hard-over.toml");
    let plan = "\n[[faults]]\nat_s = 1.0\nduration_s = 0.5\ntarget = \"plant\"\naction = \"actuator-hard-over\"\n\
                surface = \"elevator\"\nlimit = \"min\"\n";
    let base = std::fs::read_to_string(config("robust")).unwrap();
    std::fs::write(&scenario, format!("{base}{plan}")).unwrap();
    lockstep_matches_sim(scenario.to_str().unwrap(), "hard-over-rig");
    // The same flight once more, for its report and trace.
    let id = run_id("hard-over-limits");
    let out = dir.join("again");
    let child = silrig_run(&[
        scenario.to_str().unwrap(),
        "--mode",
        "lockstep",
        "--run-id",
        &id,
        "--out",
        out.to_str().unwrap(),
    ]);
    let o = wait_with_watchdog(child, Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    assert_eq!(process(&report(&out), "controller")["counters"]["commands_refused"], 0);
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let header: Vec<&str> = trace.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|c| *c == "elevator_cmd_deg").unwrap();
    let elevator: Vec<f64> = trace.lines().skip(1).map(|l| l.split(',').nth(col).unwrap().parse().unwrap()).collect();
    assert!(elevator.iter().all(|e| e.abs() <= 90.0), "within the range");
    assert!(elevator.iter().any(|e| e.abs() == 90.0), "the demand reached the limit: the test tests something");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn two_rigs_with_different_run_ids_do_not_interfere() {
    let dir = temp_dir("two");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let (id_a, id_b) = (run_id("two-a"), run_id("two-b"));
    // Different scenarios, so a crossed stream would show in the traces.
    let ca = silrig_run(&[&config("paper"), "--mode", "lockstep", "--run-id", &id_a, "--out", a.to_str().unwrap()]);
    let cb = silrig_run(&[&config("robust"), "--mode", "lockstep", "--run-id", &id_b, "--out", b.to_str().unwrap()]);
    let (oa, ob) = (wait_with_watchdog(ca, Duration::from_secs(60)), wait_with_watchdog(cb, Duration::from_secs(60)));
    assert!(
        oa.status.success() && ob.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&oa.stdout),
        String::from_utf8_lossy(&ob.stdout)
    );
    check_report(&report(&a), 1001, Mode::Lockstep);
    check_report(&report(&b), 1001, Mode::Lockstep);
    for (out, name) in [(&a, "paper"), (&b, "robust")] {
        let sim_out = dir.join(format!("sim-{name}"));
        Command::new(SILRIG).args(["sim", &config(name), "--out", sim_out.to_str().unwrap()]).output().unwrap();
        assert!(
            std::fs::read(out.join("trace.csv")).unwrap() == std::fs::read(sim_out.join("trace.csv")).unwrap(),
            "{name}"
        );
    }
    no_shared_memory_left(&id_a);
    no_shared_memory_left(&id_b);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_second_controller_for_the_same_run_is_refused() {
    let dir = temp_dir("second");
    let id = run_id("second");
    let out = dir.join("out");
    let child = silrig_run(&["--duration-s", "3", "--run-id", &id, "--out", out.to_str().unwrap(), "--no-baseline"]);
    // Wait until the rig is ticking (the logger has written rows).
    let start = Instant::now();
    while std::fs::read_to_string(out.join("trace.csv")).map_or(0, |t| t.lines().count()) < 20 {
        assert!(start.elapsed() < Duration::from_secs(20), "the rig did not start");
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = Command::new(env!("CARGO_BIN_EXE_silrig-controller"))
        .args(["--run-id", &id, "--out", dir.join("second").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(second.status.code(), Some(2));
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(err.contains("second controller") && err.contains("already"), "{err}");
    // The running rig is unharmed.
    let o = wait_with_watchdog(child, Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    check_report(&report(&out), 301, Mode::Realtime);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_output_folder_holding_a_run_is_never_overwritten() {
    let dir = temp_dir("reuse");
    std::fs::write(dir.join("trace.csv"), "t_s\n0\n").unwrap();
    let o = Command::new(SILRIG).args(["run", "--mode", "lockstep", "--out", dir.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("already holds a run"));
    assert_eq!(std::fs::read_to_string(dir.join("trace.csv")).unwrap(), "t_s\n0\n");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_failed_runs_folder_is_refused_too_and_a_file_is_not_a_folder() {
    let dir = temp_dir("reuse-failed");
    let out = dir.join("run");
    let run = |out: &std::path::Path, controller: &str| {
        let mut cmd = Command::new(SILRIG);
        cmd.args(["run", "--mode", "lockstep", "--duration-s", "0.5", "--startup-timeout-s", "5"]);
        cmd.args(["--controller-cmd", controller, "--out", out.to_str().unwrap()]).output().unwrap()
    };
    // A controller that exits at once: the run fails and writes no trace.csv, but its events, report and recording.
    let failed = run(&out, "false");
    assert_ne!(failed.status.code(), Some(0), "{}", String::from_utf8_lossy(&failed.stdout));
    assert!(!out.join("trace.csv").exists());
    let events = std::fs::read(out.join("events.jsonl")).unwrap();
    let again = Command::new(SILRIG)
        .args(["run", "--mode", "lockstep", "--duration-s", "0.5", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(2));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("already holds a run (report.json)") && err.contains("choose another --out"), "{err}");
    assert_eq!(std::fs::read(out.join("events.jsonl")).unwrap(), events, "the failed run's events are kept");
    let file = dir.join("afile");
    std::fs::write(&file, "mine").unwrap();
    let o = Command::new(SILRIG).args(["run", "--mode", "lockstep", "--out", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("it is a file, not a folder"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_misspelled_flag_gets_the_flag_it_resembles_and_an_unknown_fault_action_the_actions() {
    let o = Command::new(SILRIG).args(["run", "--duration", "5"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("a similar argument exists: '--duration-s'"), "{err}");
    let o = Command::new(SILRIG).args(["run", "--fault", "controller:kil@3s"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("unknown action \"kil\"; the actions: kill, term, stop"), "{err}");
}

#[test]
fn a_controller_with_more_diagnostics_than_a_command_carries_is_refused_before_it_connects() {
    let dir = temp_dir("too-many");
    let centres: Vec<String> = (0..20).map(|k| format!("[{}.0, 0.0]", k)).collect();
    let base = std::fs::read_to_string(config("robust")).unwrap();
    let scenario = format!(
        "{base}\n[controller.rbf]\ncentres = [{}]\nwidths = [{}]\n",
        centres.join(", "),
        vec!["1.0"; 20].join(", ")
    );
    let path = dir.join("big.toml");
    std::fs::write(&path, scenario).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_silrig-controller"))
        .arg(&path)
        .args(["--run-id", &run_id("too-many"), "--out", dir.join("out").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("at most 64 diagnostics") && err.contains("reports 66"), "{err}");
    no_shared_memory_left(&run_id("too-many"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The uncertainty keys a sweep disperses act identically in the rig's plant: extra transport delay, aerodynamic
/// and mass scales (and they change the flight).
#[test]
fn lockstep_with_delay_and_model_scales_equals_sim_bit_for_bit() {
    let dir = temp_dir("lock-scales-scenario");
    let scenario = dir.join("scaled.toml");
    let base = std::fs::read_to_string(config("robust")).unwrap();
    let text = base
        .replace("xcg = 0.35\n", "xcg = 0.35\nmass_scale = 1.1\naero_scale = { cm = 0.9, cl = 1.2 }\n")
        .replace("command_timing = \"next-tick\"\n", "command_timing = \"next-tick\"\ntransport_delay_ticks = 2\n");
    assert_ne!(text, base);
    std::fs::write(&scenario, text).unwrap();
    lockstep_matches_sim(scenario.to_str().unwrap(), "lock-scales");
    let nominal = silrig::sim::run(&silrig::scenario::Scenario::load(Path::new(&config("robust"))).unwrap()).unwrap();
    let scaled = silrig::sim::run(&silrig::scenario::Scenario::load(&scenario).unwrap()).unwrap();
    assert_ne!(nominal.rows[300], scaled.rows[300], "the keys change the flight");
    std::fs::remove_dir_all(&dir).unwrap();
}
