//! `silrig sim` and `silrig compare` as a user runs them: outputs written, runs reproducible byte for byte.

use std::path::{Path, PathBuf};
use std::process::Command;

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("silrig-test-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn silrig(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_silrig")).args(args).output().unwrap()
}

fn config(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs").join(format!("{name}.toml")).display().to_string()
}

#[test]
fn sim_without_a_config_runs_the_embedded_default_and_is_reproducible() {
    let dir = temp_dir("sim-default");
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        let o = silrig(&["sim", "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("scenario robust") && text.contains("limit cycle"), "{text}");
    }
    for file in ["trace.csv", "summary.json", "scenario.toml"] {
        let (x, y) = (std::fs::read(a.join(file)).unwrap(), std::fs::read(b.join(file)).unwrap());
        assert!(!x.is_empty());
        assert!(x == y, "{file} differs between two runs");
    }
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ticks"], 1001);
    assert_eq!(summary["limit_cycle"], false);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn compare_prints_runs_side_by_side_with_the_chattering_ratio() {
    let dir = temp_dir("compare");
    let o = silrig(&["compare", &config("paper-ideal"), &config("paper-ideal-sign"), "--out", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let ratio_line = text.lines().find(|l| l.trim_start().starts_with("ratio to first run")).unwrap();
    let ratio: f64 = ratio_line.split_whitespace().last().unwrap().trim_end_matches('x').parse().unwrap();
    assert!(ratio > 10.0, "{ratio_line}");
    assert!(dir.join("paper-ideal-sign").join("trace.csv").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_flight_leaving_the_models_envelope_exits_1_saying_when_and_keeps_its_files() {
    let dir = temp_dir("envelope");
    let tumble = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenarios/tumble.toml");
    let o = silrig(&["sim", tumble.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("the state left the model's envelope at t = 2.18 s: `beta_rad`"), "{err}");
    let trace = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
    assert_eq!(trace.lines().count() - 1, 218, "rows t = 0 to 2.17 s");
    assert!(!trace.contains("NaN"));
    for file in ["summary.json", "fig1_states.png"] {
        assert!(dir.join(file).exists(), "{file}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bad_scenario_file_exits_2_naming_the_file_and_key() {
    let dir = temp_dir("bad-config");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    let text = std::fs::read_to_string(config("paper-ideal")).unwrap().replace("dt_s = 0.01", "dt_s = -0.01");
    std::fs::write(&bad, text).unwrap();
    let o = silrig(&["sim", bad.to_str().unwrap(), "--out", dir.join("out").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml") && err.contains("timing.dt_s"), "{err}");
    assert!(!dir.join("out").exists(), "nothing is written for a refused scenario");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_negative_number_gets_the_range_message_not_an_unknown_flag() {
    for (args, needle) in [
        (vec!["run", "--duration-s", "-1"], "`timing.duration_s`: must be within (0, 3600] s, got -1"),
        (vec!["timer-baseline", "--duration-s", "-5"], "--duration-s must be within 0.01..3600 s, got -5"),
    ] {
        let o = silrig(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle) && !stderr.contains("unexpected argument"), "{args:?}: {stderr}");
    }
}
