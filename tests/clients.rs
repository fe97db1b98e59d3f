//! Bring your own controller: the C and the Python examples fly through `silrig run --controller-cmd` (lockstep to
//! the set points with every tick answered, and 2 s realtime with the same timing report as ours), a controller
//! started by hand joins `--controller external`, the in-loop faults and restarts reach a user's controller, and
//! every bad input the contract names gets a clear message without losing recorded data. The client library is
//! built here (`cargo build --release -p silrig-client`, once per test binary) and the C example with the system
//! compiler. Each test has its own run id and folder; the launcher reaps what it started and removes the run's
//! shared memory, and the tests check that it did. No timing figure is asserted as a bound.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

mod common;
use common::{Run, no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn temp_dir(test: &str) -> PathBuf {
    common::temp_dir("clients", test)
}

fn run_id(test: &str) -> String {
    format!("c{}-{test}", std::process::id())
}

fn client_lib() -> &'static Path {
    common::client_lib(SILRIG)
}

/// The C example, compiled with the system compiler against the header and the library.
fn c_example() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let lib_dir = client_lib().parent().unwrap().to_path_buf();
        let out = std::env::temp_dir().join(format!("silrig-clients-{}-pid_attitude", std::process::id()));
        let o = Command::new("cc")
            .args(["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
            .arg(Path::new(ROOT).join("examples/c"))
            .arg(Path::new(ROOT).join("examples/c/pid_attitude.c"))
            .arg("-L")
            .arg(&lib_dir)
            .arg("-lsilrig_client")
            .arg(format!("-Wl,-rpath,{}", lib_dir.display()))
            .args(["-lm", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "cc: {}", String::from_utf8_lossy(&o.stderr));
        out
    })
}

fn python_example() -> String {
    client_lib();
    format!("python3 {ROOT}/examples/python/pid_attitude.py")
}

fn misbehaving(mode: &str) -> String {
    client_lib();
    format!("python3 {ROOT}/tests/clients/misbehaving.py {mode}")
}

/// `silrig run` with its own run id and folder, to the end.
fn run(test: &str, args: &[&str]) -> Run {
    Run::start(SILRIG, "clients", "c", test, args)
}

fn robust() -> String {
    format!("{ROOT}/configs/robust.toml")
}

/// A 10 s lockstep flight of robust.toml: every tick answered, the announced diagnostics in the trace, the
/// attitude within 1 deg of the set points (0, 10, 0 deg) at the end.
fn flies_lockstep_to_the_set_points(test: &str, controller_cmd: &str) {
    let r = run(test, &["--mode", "lockstep", "--controller-cmd", controller_cmd, &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 1001);
    assert_eq!(r.counter("plant", "command_misses"), 0, "a tick went unanswered");
    assert_eq!(r.counter("controller", "commands_sent"), 1001);
    assert_eq!(r.counter("controller", "commands_refused"), 0);
    assert_eq!(r.process("controller")["ended"], "completed");
    let (header, rows) = r.trace();
    assert_eq!(rows.len(), 1001);
    assert!(header.ends_with(&["err_phi_deg".into(), "err_theta_deg".into(), "err_psi_deg".into()]), "{header:?}");
    let last = rows.last().unwrap();
    for (angle, setpoint) in [("phi_deg", 0.0), ("theta_deg", 10.0), ("psi_deg", 0.0)] {
        let value = last[header.iter().position(|h| h == angle).unwrap()];
        assert!((value - setpoint).abs() < 1.0, "{angle} ends at {value}, set point {setpoint}");
    }
    r.finish();
}

#[test]
fn the_client_library_reads_the_set_point_in_force_at_each_sample() {
    // robust.toml (theta 10 deg) with a step of theta to 4 deg at 1 s; the reader logs what it reads each sample.
    let dir = common::temp_dir("clients", "setpoint-steps-files");
    let scenario = dir.join("steps.toml");
    let text = std::fs::read_to_string(robust()).unwrap() + "\n[[setpoint_steps]]\nat_s = 1.0\ntheta_deg = 4.0\n";
    std::fs::write(&scenario, text).unwrap();
    client_lib();
    let reader = format!("python3 {ROOT}/tests/clients/setpoint_reader.py");
    let r = run(
        "setpoint-steps",
        &["--mode", "lockstep", "--duration-s", "2", "--controller-cmd", &reader, scenario.to_str().unwrap()],
    );
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (header, rows) = r.trace();
    let column = |name: &str| Run::column(&header, name);
    let (t, now, start) = (column("t_s"), column("sp_theta_now_deg"), column("sp_theta_start_deg"));
    assert_eq!(rows.len(), 201);
    for row in &rows {
        let expected = if row[t] < 1.0 - 1e-9 { 10.0 } else { 4.0 };
        assert_eq!((row[now], row[start]), (expected, 10.0), "at {} s", row[t]);
    }
    r.finish();
}

/// A 2 s realtime flight: it completes, and the report covers the user's controller as ours (its compute time and
/// IPC latency at the controller, sense-to-actuate at the plant).
fn flies_realtime(test: &str, controller_cmd: &str) {
    let r = run(test, &["--duration-s", "2", "--controller-cmd", controller_cmd, &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("plant", "ticks"), 201);
    assert!(r.counter("controller", "commands_sent") > 150);
    let latencies = |p: &str| r.process(p)["latencies"].as_array().unwrap().clone();
    let count = |p: &str, name: &str| {
        let name = format!("{p}.{name}");
        latencies(p).iter().find(|l| l["name"] == name.as_str()).map_or(0, |l| l["summary"]["count"].as_u64().unwrap())
    };
    assert!(count("controller", "compute") > 150);
    assert!(count("controller", "ipc_plant_to_controller") > 150);
    assert!(count("plant", "sense_to_actuate") > 150);
    assert_eq!(r.trace().1.len(), 201);
    r.finish();
}

#[test]
fn the_c_example_flies_lockstep_to_the_set_points() {
    flies_lockstep_to_the_set_points("c-lock", c_example().to_str().unwrap());
}

#[test]
fn the_python_example_flies_lockstep_to_the_set_points() {
    flies_lockstep_to_the_set_points("py-lock", &python_example());
}

#[test]
fn the_c_example_flies_2_s_realtime() {
    flies_realtime("c-rt", c_example().to_str().unwrap());
}

#[test]
fn the_python_example_flies_2_s_realtime() {
    flies_realtime("py-rt", &python_example());
}

#[test]
fn in_loop_faults_and_a_restart_reach_a_users_controller() {
    let r = run(
        "c-faults",
        &[
            "--duration-s",
            "3",
            "--controller-cmd",
            c_example().to_str().unwrap(),
            "--restart",
            "on-failure",
            "--fault",
            "controller:drop@0.5s,ticks=10",
            "--fault",
            "controller:kill@1.5s,restart_after=0.3s",
            &robust(),
        ],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.event("controller", "fault-injected").is_some_and(|e| e["detail"].as_str().unwrap().contains("drop")));
    assert!(r.event("launcher", "process-restarted").is_some());
    // The restarted C controller resumed its integrators from the checkpoint it saved through the library.
    let joined = r.event("controller", "controller-joined").expect("the restarted controller joined the flight");
    assert!(joined["detail"].as_str().unwrap().contains("checkpointed state"), "{joined}");
    assert!(r.event("plant", "controller-recovered").is_some());
    assert_eq!(r.trace().1.len(), 301, "the logger lost rows");
    r.finish();
}

/// A lockstep `silrig run --controller external` started for `test`, once it waits for a controller: its folder,
/// run id, run folder and launcher.
fn start_external_run(test: &str) -> (PathBuf, String, PathBuf, std::process::Child) {
    let dir = temp_dir(test);
    let id = run_id(test);
    let out = dir.join("out");
    let launcher = Command::new(SILRIG)
        .args(["run", "--mode", "lockstep", "--controller", "external", "--external-timeout-s", "60"])
        .args(["--run-id", &id, "--out", out.to_str().unwrap(), &robust()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !out.join("controller.env").exists() {
        assert!(start.elapsed() < Duration::from_secs(20), "no controller.env");
        std::thread::sleep(Duration::from_millis(20));
    }
    (dir, id, out, launcher)
}

#[test]
fn a_controller_started_by_hand_joins_an_external_run() {
    let (dir, id, out, launcher) = start_external_run("external");
    let env_file = out.join("controller.env");
    std::thread::sleep(Duration::from_millis(50));
    let controller = Command::new("sh")
        .arg("-c")
        .arg(format!(". '{}' && exec {}", env_file.display(), python_example()))
        .env("SILRIG_CLIENT_LIB", client_lib())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let c = wait_with_watchdog(controller, Duration::from_secs(90));
    let o = wait_with_watchdog(launcher, Duration::from_secs(90));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(c.status.success(), "controller: {}", String::from_utf8_lossy(&c.stderr));
    assert!(o.status.success(), "{}\n{stderr}", String::from_utf8_lossy(&o.stdout));
    assert!(stderr.contains("waiting up to 60 s for a controller"), "{stderr}");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let controller = report["processes"].as_array().unwrap().iter().find(|p| p["process"] == "controller").unwrap();
    assert_eq!(controller["ended"], "completed", "the controller saw the run end by itself");
    assert_eq!(controller["counters"]["commands_sent"], 1001);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_raw_iceoryx2_peer_written_from_the_contract_flies_an_external_run_without_a_report() {
    let python = common::venv_python("iceoryx2", "iceoryx2==0.10.0");
    let (dir, id, out, launcher) = start_external_run("raw");
    // Only the run id, as a user of another language would take it from the launcher's message.
    let peer = Command::new(&python)
        .arg(Path::new(ROOT).join("tests/clients/raw_controller.py"))
        .arg("10")
        .env("SILRIG_RUN_ID", &id)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let p = wait_with_watchdog(peer, Duration::from_secs(90));
    let o = wait_with_watchdog(launcher, Duration::from_secs(90));
    let peer_said = String::from_utf8_lossy(&p.stderr);
    assert!(p.status.success(), "raw peer: {peer_said}");
    assert!(peer_said.contains("answered 1001 samples"), "{peer_said}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("note: controller: started outside the launcher, it wrote no report"), "{stdout}");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let plant = report["processes"].as_array().unwrap().iter().find(|p| p["process"] == "plant").unwrap();
    assert_eq!(plant["counters"]["ticks"], 1001);
    assert_eq!(plant["counters"]["command_misses"], 0, "a tick went unanswered");
    assert_eq!(plant["counters"]["commands_invalid"], 0);
    assert!(report["failures"].as_array().unwrap().is_empty(), "{}", report["failures"]);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A client run by hand against `out`'s run, or none: (exit code, stderr).
fn client(mode: &str, env: &[(&str, &str)]) -> (Option<i32>, String) {
    let o = Command::new("python3")
        .arg(Path::new(ROOT).join("tests/clients/misbehaving.py"))
        .arg(mode)
        .env("SILRIG_CLIENT_LIB", client_lib())
        .envs(env.iter().copied())
        .output()
        .unwrap();
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into())
}

#[test]
fn a_client_of_another_layout_or_sample_size_is_refused_by_name() {
    let out = temp_dir("layout");
    let env = [("SILRIG_RUN_ID", "nobody"), ("SILRIG_OUT", out.to_str().unwrap())];
    let (code, err) = client("layout", &env);
    assert_eq!(code, Some(2));
    assert!(err.contains("status -2") && err.contains("version 12") && err.contains("version 5"), "{err}");
    let (code, err) = client("size", &env);
    assert_eq!(code, Some(2));
    assert!(err.contains("status -2") && err.contains("plant sample is 320 bytes, the contract's is 328"), "{err}");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_variables_and_a_controller_without_a_rig_get_clear_errors() {
    let out = temp_dir("no-rig");
    let id = run_id("no-rig");
    let (code, err) = client("open", &[("SILRIG_RUN_ID", &id), ("SILRIG_STALE_AFTER_PERIODS", "many")]);
    assert_eq!(code, Some(2));
    assert!(err.contains("status -3") && err.contains("--stale-after-periods") && err.contains("many"), "{err}");
    let env =
        [("SILRIG_RUN_ID", id.as_str()), ("SILRIG_OUT", out.to_str().unwrap()), ("SILRIG_STARTUP_TIMEOUT_S", "0.3")];
    let (code, err) = client("never", &env);
    assert_eq!(code, Some(2));
    assert!(err.contains("status -4") && err.contains(&format!("no plant on run `{id}`")), "{err}");
    // It said why in its report too, and left nothing behind.
    let report = std::fs::read_to_string(out.join("controller.report.json")).unwrap();
    assert!(report.contains("no plant on run"), "{report}");
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn a_second_controller_is_refused_and_the_run_goes_on() {
    let dir = temp_dir("second");
    let id = run_id("second");
    let out = dir.join("out");
    let launcher = Command::new(SILRIG)
        .args(["run", "--duration-s", "3", "--no-baseline", "--controller-cmd", &python_example()])
        .args(["--run-id", &id, "--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while std::fs::read_to_string(out.join("trace.csv")).map_or(0, |t| t.lines().count()) < 20 {
        assert!(start.elapsed() < Duration::from_secs(30), "the rig did not start");
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = dir.join("second");
    let (code, err) = client("open", &[("SILRIG_RUN_ID", &id), ("SILRIG_OUT", second.to_str().unwrap())]);
    assert_eq!(code, Some(2));
    assert!(err.contains("status -5") && err.contains("second controller"), "{err}");
    let o = wait_with_watchdog(launcher, Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    assert_eq!(std::fs::read_to_string(out.join("trace.csv")).unwrap().lines().count(), 302);
    no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn nan_commands_are_refused_counted_held_and_reported() {
    let r = run("nan", &["--mode", "lockstep", "--controller-cmd", &misbehaving("nan"), &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert_eq!(r.counter("controller", "commands_refused"), 50);
    assert_eq!(r.counter("plant", "commands_refused_held"), 50);
    let refused = r.event("controller", "command-refused").expect("an event for the refused commands");
    assert_eq!(refused["tick"], 100);
    assert!(refused["detail"].as_str().unwrap().contains("NaN"), "{refused}");
    assert!(r.event("controller", "command-accepted").is_some());
    // Every tick was still recorded, and no NaN reached the trace.
    let (header, rows) = r.trace();
    assert_eq!(rows.len(), 1001);
    let aileron_cmd = header.iter().position(|h| h == "aileron_cmd_deg").unwrap();
    assert!(rows.iter().all(|row| row[aileron_cmd].is_finite()));
    r.finish();
}

#[test]
fn a_controller_that_never_answers_leaves_the_plant_in_failsafe() {
    let r = run("never", &["--duration-s", "2", "--controller-cmd", &misbehaving("never"), &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    assert!(r.event("plant", "controller-stale").is_some());
    assert!(r.event("plant", "failsafe-engaged").is_some());
    assert!(r.counter("plant", "failsafe_ticks") > 100);
    assert!(r.counter("controller", "samples_unanswered") > 100);
    assert_eq!(r.trace().1.len(), 201);
    r.finish();
}

#[test]
fn a_controller_that_never_answers_in_lockstep_fails_the_run_and_the_plant_says_why_in_its_report() {
    let r = run("never-lockstep", &["--mode", "lockstep", "--controller-cmd", &misbehaving("never"), &robust()]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let plant = r.report["processes"].as_array().unwrap().iter().find(|p| p["process"] == "plant").unwrap().clone();
    let ended = plant["ended"].as_str().unwrap();
    assert!(ended.starts_with("error: lockstep: no command for tick 0 within"), "{ended}");
    r.finish();
}

#[test]
fn a_controller_asking_for_a_signal_the_plant_lacks_is_told_what_the_plant_has() {
    let r = run("missing", &["--duration-s", "1", "--controller-cmd", &misbehaving("missing"), &robust()]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.report["failures"].to_string();
    assert!(
        failures.contains("status -9: plant f16 has no output `theta`; its outputs: phi_deg, theta_deg"),
        "{failures}"
    );
    // The flight itself is whole: the plant flew its failsafe without a controller, and the logger kept every tick.
    assert_eq!(r.trace().1.len(), 101);
    r.finish();
}

#[test]
fn a_controller_that_exits_at_once_is_reported_with_its_status_and_stderr() {
    let cmd = "python3 -c 'import sys; print(\"cannot find my gains file\", file=sys.stderr); sys.exit(3)'";
    let r = run("exits", &["--duration-s", "1", "--startup-timeout-s", "1", "--controller-cmd", cmd, &robust()]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let failures = r.report["failures"].to_string();
    let said = format!("controller: your --controller-cmd `{cmd}` (pid ");
    assert!(failures.contains(&said.replace('"', "\\\"")), "{failures}");
    assert!(failures.contains(") ended before it joined the run (exit status 3, "), "{failures}");
    assert!(failures.contains("cannot find my gains file"), "{failures}");
    // The run ends there: the plant never flew (no row logged), and is not left waiting out its start-up timeout.
    assert!(!r.out.join("trace.csv").exists() || r.trace().1.is_empty());
    r.finish();
}

#[test]
fn a_controllers_children_end_with_the_run_and_an_early_clean_exit_fails_it_at_once() {
    // A marker no other test's process carries, so the check below finds only what this test started.
    let marker = format!("{}.{}", 300 + std::process::id() % 100, std::process::id());
    let pid = format!("{ROOT}/examples/python/pid_attitude.py");
    let cmd = format!("sh -c \"sleep {marker} & exec python3 {pid}\"");
    let r = run("children", &["--duration-s", "1", "--controller-cmd", &cmd, &robust()]);
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let left = Command::new("pgrep").args(["-f", &format!("sleep {marker}")]).output().unwrap();
    assert!(left.stdout.is_empty(), "left running: {}", String::from_utf8_lossy(&left.stdout));
    r.finish();

    let cmd = format!("sh -c \"sleep {marker} & exit 0\"");
    let r = run("exits-clean", &["--duration-s", "1", "--controller-cmd", &cmd, &robust()]);
    assert_eq!(r.code, Some(1), "{}\n{}", r.stdout, r.stderr);
    let said = ") ended before it joined the run (exit status 0, ";
    assert!(
        r.failures().contains("controller: your --controller-cmd `sh -c") && r.failures().contains(said),
        "{}",
        r.failures()
    );
    let left = Command::new("pgrep").args(["-f", &format!("sleep {marker}")]).output().unwrap();
    assert!(left.stdout.is_empty(), "left running: {}", String::from_utf8_lossy(&left.stdout));
    r.finish();
}

#[test]
fn a_controller_command_that_cannot_start_is_refused_before_anything_runs() {
    let r = run("no-such", &["--controller-cmd", "./no/such/controller --fast"]);
    assert_eq!(r.code, Some(2));
    assert!(r.stderr.contains("cannot find `./no/such/controller`"), "{}", r.stderr);
    let r2 = run("quote", &["--controller-cmd", "python3 'unbalanced"]);
    assert_eq!(r2.code, Some(2));
    assert!(r2.stderr.contains("unbalanced '"), "{}", r2.stderr);
    r.finish();
    r2.finish();
}

#[test]
fn a_controller_that_writes_without_end_has_its_log_capped_and_the_drop_counted() {
    // 300 lines of 100 KB (30 MB) against the 16 MiB cap, then it exits.
    let cmd = "python3 -c \"import sys; [sys.stderr.write('x' * 100000 + '\\n') for _ in range(300)]\"";
    let r = run("log-cap", &["--duration-s", "1", "--controller-cmd", cmd, &robust()]);
    let log = std::fs::read(r.out.join("controller.stderr.log")).unwrap();
    let cap = silrig::launch::child::STDERR_LOG_CAP_BYTES as usize;
    assert!(log.len() <= cap + 200 && log.len() > cap - 200_000, "{} bytes", log.len());
    let tail = String::from_utf8_lossy(&log[log.len() - 200..]);
    assert!(tail.contains("lines (") && tail.contains("bytes) past the cap were dropped"), "{tail}");
    r.finish();
}
