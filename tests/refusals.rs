//! Every refusal the command line has, provoked: bad flags and values, missing and malformed files (scenarios,
//! suites, sweeps, FMUs, device layouts), bad fault strings, a used output folder, a taken run id, a second
//! controller on a run, commands that cannot be split. Each must exit as documented and say the problem in words:
//! no Rust path, no Debug dump of an error ([`common::assert_in_words`]), and the words that name it.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");

/// The files the cases refuse, in `dir`.
fn write_bad_files(dir: &Path) {
    let config =
        |name: &str| std::fs::read_to_string(format!("{}/configs/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let robust = config("robust.toml");
    let negative = robust.replace("duration_s = 10.0", "duration_s = -1.0");
    assert_ne!(negative, robust);
    let betaflight = config("quad-betaflight.toml");
    let device = betaflight.replace("device = \"devices/betaflight-sitl.toml\"", "device = \"layout.toml\"");
    assert_ne!(device, betaflight);
    let files = [
        ("unclosed.toml", "[timing\n"),
        ("unknown-key.toml", "nonsense = 1\n"),
        ("negative.toml", &negative),
        ("notazip.fmu", "not a zip archive\n"),
        ("suite.toml", "name = \"x\"\n[[cases]]\nbogus = 1\n"),
        ("no-dispersions.toml", &robust),
        ("device.toml", &device),
        ("layout.toml", "[[packets]]\nbogus = 1\n"),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    std::fs::create_dir_all(dir.join("used")).unwrap();
    std::fs::write(dir.join("used/trace.csv"), "t_s\n0\n").unwrap();
}

/// `program ARGS` in `dir`, which must exit with `code` saying `words` in words; its stderr.
fn refused(program: &str, dir: &Path, args: &[&str], code: i32, words: &str) -> String {
    let child = Command::new(program)
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = common::wait_with_watchdog(child, Duration::from_secs(60));
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    let what = format!("{program} {}", args.join(" "));
    assert_eq!(o.status.code(), Some(code), "{what}: {stderr}{}", String::from_utf8_lossy(&o.stdout));
    assert!(stderr.contains(words), "{what}: no `{words}` in: {stderr}");
    common::assert_in_words(&what, &stderr);
    stderr
}

#[test]
fn every_refusal_of_the_command_line_is_in_words() {
    let dir = common::temp_dir("refusals", "cli");
    write_bad_files(&dir);
    let out = |name: &str| dir.join(name).display().to_string();
    let (o1, o3, o4, o5) = (out("o1"), out("o3"), out("o4"), out("o5"));
    let cases: &[(&[&str], i32, &str)] = &[
        (&["run", "--bogus"], 2, "unexpected argument '--bogus'"),
        (&["run", "--duration-s", "abc"], 2, "invalid value 'abc' for '--duration-s"),
        (&["run", "missing.toml", "--out", &o1], 2, "missing.toml: No such file or directory"),
        (&["run", "unclosed.toml", "--out", &o1], 2, "unclosed table"),
        (&["run", "unknown-key.toml", "--out", &o1], 2, "unknown field `nonsense`"),
        (&["run", "negative.toml", "--out", &o1], 2, "`timing.duration_s`: must be within (0, 3600] s, got -1"),
        (&["run", "--fault", "plant:explode@1s", "--out", &o1], 2, "unknown action \"explode\"; the actions: kill"),
        (&["run", "--fault", "plant:kill", "--out", &o1], 2, "expected TARGET:ACTION@TIME"),
        (&["run", "--fault", "sensor:bias@1s", "--out", &o1], 2, "unknown target \"sensor\""),
        (&["run", "--fault", "plant:kill@soon", "--out", &o1], 2, "not a duration"),
        (&["run", "--run-id", "Bad_Id", "--out", &o1], 2, "it contains a character outside [a-z0-9-]"),
        (&["run", "--startup-timeout-s", "1e30", "--out", &o1], 2, "--startup-timeout-s must be within 0.1..3600 s"),
        (&["run", "--plant-fmu", "missing.fmu", "--out", &o1], 2, "missing.fmu: cannot be read"),
        (&["run", "--plant-fmu", "notazip.fmu", "--out", &o1], 2, "not a zip archive, as an FMU is"),
        (&["run", "--controller-cmd", "a \"b", "--out", &o1], 2, "--controller-cmd: unbalanced \""),
        (&["run", "--live", "bogus", "--out", &o1], 2, "`bogus` is no live protocol"),
        (&["run", "--out", "used"], 2, "already holds a run (trace.csv)"),
        (&["sim", "unclosed.toml", "--out", &o3], 2, "unclosed table"),
        (&["sweep", "no-dispersions.toml", "--runs", "2", "--out", &o4], 2, "no [dispersions]: a sweep needs"),
        (&["sweep", "merge", "used"], 2, "write it with `silrig sweep plan`"),
        (&["check", "suite.toml", "--out", &o5], 2, "unknown field `bogus`"),
        (&["check", "missing.toml"], 2, "missing.toml: No such file or directory"),
        (&["replay", "used"], 2, "is this a run folder of `silrig run`?"),
        (&["top", "no-such-run-here"], 2, "no running rig with run id `no-such-run-here`"),
        (&["new", "controller", "--lang", "cobol", "n"], 2, "invalid value 'cobol'"),
        (&["contract", "--c-header", "/nonexistent/x.h"], 2, "writing /nonexistent/x.h: No such file or directory"),
        (&["timer-baseline", "--period-ms", "-1"], 2, "--period-ms must be within 0.1..1000 ms"),
        (&["export-fmu", "--out", "/nonexistent/x.fmu"], 2, "writing /nonexistent/x.fmu"),
    ];
    for (args, code, words) in cases {
        refused(SILRIG, &dir, args, *code, words);
    }
    for binary in [env!("CARGO_BIN_EXE_silrig-plant"), env!("CARGO_BIN_EXE_silrig-controller")] {
        refused(binary, &dir, &["--stale-after-periods", "many"], 2, "invalid value 'many'");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bad_device_layout_fails_the_run_in_words() {
    let dir = common::temp_dir("refusals", "layout");
    write_bad_files(&dir);
    let id = format!("dl{}", std::process::id());
    let out = dir.join("run").display().to_string();
    let args = ["run", "device.toml", "--no-baseline", "--quiet", "--run-id", &id, "--out", &out];
    // The controller reads the layout when it starts: the run fails (1), naming the key, and the launcher's own
    // stderr (iceoryx2's warnings included) is in words too.
    refused(SILRIG, &dir, &args, 1, "");
    let report = std::fs::read_to_string(dir.join("run/report.json")).unwrap();
    assert!(report.contains("unknown field `packets`"), "{report}");
    common::no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_taken_run_id_is_refused_in_words() {
    let dir = common::temp_dir("refusals", "taken");
    let id = format!("tk{}", std::process::id());
    // The claim of a live holder (this test process): the run id is in use.
    let lock = format!("/tmp/silrig_{id}.lock");
    std::fs::write(&lock, std::process::id().to_string()).unwrap();
    let out = dir.join("run").display().to_string();
    let said = refused(SILRIG, &dir, &["run", "--run-id", &id, "--out", &out], 2, "is taken by another silrig run");
    assert!(said.contains(&format!("pid {}", std::process::id())), "{said}");
    std::fs::remove_file(&lock).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_second_controller_on_a_run_is_refused_in_words() {
    let dir = common::temp_dir("refusals", "second");
    let id = format!("sc{}", std::process::id());
    let out = dir.join("run");
    let rig = Command::new(SILRIG)
        .args(["run", "--duration-s", "3", "--no-baseline", "--quiet", "--run-id", &id, "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !std::fs::read_to_string(out.join("events.jsonl")).is_ok_and(|t| t.contains("\"ticking\"")) {
        assert!(start.elapsed() < Duration::from_secs(30), "the rig did not start");
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = dir.join("second").display().to_string();
    let controller = env!("CARGO_BIN_EXE_silrig-controller");
    refused(controller, &dir, &["--run-id", &id, "--out", &second], 2, "second controller");
    let o = common::wait_with_watchdog(rig, Duration::from_secs(60));
    assert!(o.status.success(), "the running rig was harmed: {}", String::from_utf8_lossy(&o.stdout));
    common::no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}
