//! The FMU importer's edges: Int32 outputs fly as signals (`tests/fmu/stair` and `tests/fmu/resource`, the
//! Reference FMUs `Stair` and `Resource` written again in C with their interfaces, since no registry package ships
//! them) in `silrig sim` and `silrig run --plant-fmu`; a controller FMU's input held at a constant by
//! `[controller.map]` or left unconnected at its start value; and a binary that cannot be loaded safely (cut short,
//! 32-bit, built for another machine, lacking a function: each made here from a good one) refused by `run`, `sim`
//! and `check` with exit status 2, naming the file, and with no unpacked folder left behind (each command runs with
//! a TMPDIR of its own, looked into afterwards). The FMUs are built by `examples/fmu/build.sh`.

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::Run;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "fmu-edges";

fn fmu(name: &str) -> String {
    common::fmu::cached_fmu(SUITE, name)
}

/// A scenario file in `dir`: `duration_s` of next-tick flight at 100 Hz, with `extra` TOML after it.
fn scenario(dir: &Path, name: &str, duration_s: f64, extra: &str) -> String {
    let path = dir.join(format!("{name}.toml"));
    let text = format!(
        "name = \"{name}\"\n[timing]\ndt_s = 0.01\nduration_s = {duration_s}\ncommand_timing = \"next-tick\"\n{extra}\n"
    );
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// `silrig ARGS` with TMPDIR set to `tmp`, within the watchdog's limit.
fn silrig(args: &[&str], tmp: &Path) -> Output {
    std::fs::create_dir_all(tmp).unwrap();
    let child = Command::new(SILRIG)
        .args(args)
        .env("TMPDIR", tmp)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_with_watchdog(child, std::time::Duration::from_secs(120))
}

/// The trace of a `sim` output folder: header and rows.
fn trace(out: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect();
    (header, rows)
}

/// The unpacked FMUs (`silrig-fmu-*`) left in `tmp`.
fn unpacked_left(tmp: &Path) -> Vec<String> {
    let entries = std::fs::read_dir(tmp).unwrap().flatten();
    entries.map(|e| e.file_name().to_string_lossy().into_owned()).filter(|n| n.starts_with("silrig-fmu-")).collect()
}

/// `silrig sim ARGS --out OUT` that must succeed: the trace.
fn sim(args: &[&str], dir: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let out = dir.join("out");
    let mut all = vec!["sim"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    let o = silrig(&all, &dir.join("tmp"));
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(unpacked_left(&dir.join("tmp")), Vec::<String>::new());
    trace(&out)
}

/// lag3 (y' = (2 u - y) / 0.5, y = 0 at t = 0) after one 0.01 s step with u held, as its C code computes it.
fn lag3_first_step(u: f64) -> f64 {
    let target = 2.0 * u;
    target + (0.0 - target) * (-0.01f64 / 0.5).exp()
}

#[test]
fn stair_flies_in_sim_its_integer_counter_read_by_a_controller_fmu() {
    let dir = common::temp_dir(SUITE, "stair-sim");
    let scenario = scenario(&dir, "stair", 2.5, "[controller.map]\nu = \"counter\"");
    let (header, rows) = sim(&["--plant-fmu", &fmu("stair"), "--controller-fmu", &fmu("lag3"), &scenario], &dir);
    let (t, counter, y) = (Run::column(&header, "t_s"), Run::column(&header, "counter"), Run::column(&header, "y"));
    assert_eq!(rows.len(), 251);
    for row in &rows {
        assert_eq!(row[counter], 1.0 + (row[t] + 1e-9).floor(), "the counter at t = {} s", row[t]);
    }
    // The counter (an Int32) reached the controller FMU's Real input: its first step is the lag's from u = 1.
    assert_eq!(rows[0][y], lag3_first_step(1.0));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn resource_reads_its_resources_folder_in_sim_and_run() {
    let dir = common::temp_dir(SUITE, "resource");
    // In sim, against lag3 with its input held at a constant by [controller.map]: y (the plant's column comes
    // first; lag3's own output y is a diagnostic of the same name after it) is 97, the code of "a" in y.txt.
    let held = scenario(&dir, "held", 0.5, "[controller.map]\nu = 3.0");
    let (header, rows) = sim(&["--plant-fmu", &fmu("resource"), "--controller-fmu", &fmu("lag3"), &held], &dir);
    let y = Run::column(&header, "y");
    let lag_y = y + 1 + header[y + 1..].iter().position(|h| h == "y").expect("lag3's output y as a diagnostic");
    assert!(rows.iter().all(|row| row[y] == 97.0), "Resource's y is not 97 throughout");
    assert_eq!(rows[0][lag_y], lag3_first_step(3.0), "the constant 3.0 did not reach lag3's input");
    // In the rig, against a controller that commands nothing (the plant has no inputs).
    common::client_lib(SILRIG);
    let hold = format!("python3 {ROOT}/tests/clients/hold_inputs.py");
    let plain = scenario(&dir, "plain", 0.5, "");
    let r = Run::start(
        SILRIG,
        SUITE,
        "e",
        "resource-run",
        &["--mode", "lockstep", "--plant-fmu", &fmu("resource"), "--controller-cmd", &hold, &plain],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (header, rows) = r.trace();
    let y = Run::column(&header, "y");
    assert!(rows.len() == 51 && rows.iter().all(|row| row[y] == 97.0), "{} rows", rows.len());
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn stair_flies_in_the_rig_with_an_unconnected_controller_input_at_its_start_value() {
    let dir = common::temp_dir(SUITE, "stair-run-files");
    let plain = scenario(&dir, "plain", 1.5, "");
    // lag3's input u names no signal of Stair and no map names it: it stays at its start value, 0, so y stays 0.
    let r = Run::start(
        SILRIG,
        SUITE,
        "e",
        "stair-run",
        &["--mode", "lockstep", "--plant-fmu", &fmu("stair"), "--controller-fmu", &fmu("lag3"), &plain],
    );
    assert_eq!(r.code, Some(0), "{}\n{}", r.stdout, r.stderr);
    let (header, rows) = r.trace();
    let (t, counter, y) = (Run::column(&header, "t_s"), Run::column(&header, "counter"), Run::column(&header, "y"));
    assert_eq!(rows.len(), 151);
    assert!(rows.iter().all(|row| row[counter] == 1.0 + (row[t] + 1e-9).floor() && row[y] == 0.0));
    assert_eq!(rows[150][counter], 2.0);
    let detail = r.event("controller", "controller-fmu-unconnected").expect("no controller-fmu-unconnected event");
    assert_eq!(detail["detail"], "inputs plant Stair has no signal for, at their start values: u");
    // Mapped to a signal Stair lacks, the same input is a mistake, refused before the run.
    let mistaken = scenario(&dir, "mistaken", 1.5, "[controller.map]\nu = \"count\"");
    let stderr = Run::refused(
        SILRIG,
        SUITE,
        "e",
        "stair-mistaken",
        &["--mode", "lockstep", "--plant-fmu", &fmu("stair"), "--controller-fmu", &fmu("lag3"), &mistaken],
    );
    assert!(stderr.contains("input \"u\" (mapped to `count` by `controller.map`) is `count`, neither"), "{stderr}");
    r.finish();
    std::fs::remove_dir_all(dir).unwrap();
}

/// `lag3.fmu` unpacked into `dir/name`, its binary changed by `change`, packed again as `dir/name.fmu`.
fn broken_lag3(dir: &Path, name: &str, change: impl FnOnce(&mut Vec<u8>)) -> String {
    let unpacked = dir.join(name);
    let o = Command::new("python3").args(["-m", "zipfile", "-e", &fmu("lag3")]).arg(&unpacked).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let binary = unpacked.join("binaries/x86_64-linux/lag3.so");
    let mut bytes = std::fs::read(&binary).unwrap();
    change(&mut bytes);
    std::fs::write(&binary, bytes).unwrap();
    let out = dir.join(format!("{name}.fmu"));
    let o = Command::new("python3")
        .args(["-m", "zipfile", "-c"])
        .arg(&out)
        .args(["modelDescription.xml", "binaries"])
        .current_dir(&unpacked)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.display().to_string()
}

/// Every occurrence of `from` in `bytes` replaced by `to`, of the same length; at least one.
fn replace_all(bytes: &mut [u8], from: &[u8], to: &[u8]) {
    assert_eq!(from.len(), to.len());
    let mut found = 0;
    for k in 0..bytes.len() - from.len() {
        if &bytes[k..k + from.len()] == from {
            bytes[k..k + from.len()].copy_from_slice(to);
            found += 1;
        }
    }
    assert!(found > 0, "{} is not in the binary", String::from_utf8_lossy(from));
}

#[test]
fn binaries_that_cannot_be_loaded_safely_are_refused_by_run_sim_and_check_leaving_nothing_unpacked() {
    let dir = common::temp_dir(SUITE, "broken-binaries");
    let cases: Vec<(String, &str)> = vec![
        (
            broken_lag3(&dir, "cut-short", |b| b.truncate(b.len() / 2)),
            "its binary binaries/x86_64-linux/lag3.so is cut short: its ",
        ),
        (broken_lag3(&dir, "class32", |b| b[4] = 1), "is a 32-bit binary (ELFCLASS32)"),
        (
            broken_lag3(&dir, "aarch64", |b| b[18..20].copy_from_slice(&183u16.to_le_bytes())),
            "is built for AArch64 (machine 183), not x86-64",
        ),
        (
            broken_lag3(&dir, "no-do-step", |b| replace_all(b, b"fmi3DoStep\0", b"fmi3DoStXp\0")),
            "lacks the FMI 3.0 function fmi3DoStep",
        ),
    ];
    let plain = scenario(&dir, "plain", 1.0, "[controller.map]\nu = \"y\"");
    let stair = fmu("stair");
    for (k, (file, expected)) in cases.iter().enumerate() {
        let out = dir.join(format!("out-{k}"));
        let out = out.to_str().unwrap();
        let run_id = format!("e{}-broken-{k}", std::process::id());
        let commands: [Vec<&str>; 4] = [
            vec![
                "run",
                "--mode",
                "lockstep",
                "--no-baseline",
                "--run-id",
                &run_id,
                "--plant-fmu",
                file,
                &plain,
                "--out",
                out,
            ],
            vec!["sim", "--plant-fmu", file, "--controller-fmu", &stair, &plain, "--out", out],
            vec!["sim", "--plant-fmu", &stair, "--controller-fmu", file, &plain, "--out", out],
            vec!["check", "--plant-fmu", file, "--out", out],
        ];
        for (j, args) in commands.iter().enumerate() {
            let tmp = dir.join(format!("tmp-{k}-{j}"));
            let o = silrig(args, &tmp);
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(stderr.contains(&format!("FMU {file}")) && stderr.contains(expected), "{args:?}: {stderr}");
            assert_eq!(unpacked_left(&tmp), Vec::<String>::new(), "{args:?} left its unpacked FMU");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}
