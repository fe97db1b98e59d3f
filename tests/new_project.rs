//! `silrig new controller|plant --lang python|c|rust DIR`: what it writes builds (C with the system `cc`, Rust with
//! cargo against this checkout) and flies its own check suite from DIR, as its README says: each controller against
//! the built-in F-16, each plant under the example Python PID, every verdict a pass. The two Rust projects share one
//! target folder (their `target` a link to this checkout's `target/new-rust`), so silrig's crates are compiled once
//! for both; that build is slow the first time. A folder that is not empty is refused with exit status 2. `silrig --help` describes the rig.

use std::path::Path;
use std::process::{Command, Output, Stdio};

mod common;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SUITE: &str = "new-project";

/// `program args` in `dir`, within the watchdog's limit (a first Rust build takes minutes).
fn run_in(dir: &Path, program: &str, args: &[&str]) -> Output {
    let child = Command::new(program)
        .args(args)
        .current_dir(dir)
        .env("CARGO_PROFILE_RELEASE_DEBUG", "0")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_with_watchdog(child, std::time::Duration::from_secs(1800))
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Write `kind` in `lang`, build it as its summary says, and fly its check suite: the verdict must pass.
fn new_builds_and_passes_its_own_check(kind: &str, lang: &str) {
    let dir = common::temp_dir(SUITE, &format!("{kind}-{lang}"));
    let project = dir.join("project");
    let o = run_in(&dir, SILRIG, &["new", kind, "--lang", lang, project.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let summary = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(project.join("README.md").exists() && project.join("check.toml").exists(), "{summary}");
    // The summary's next steps, run as a user would: build (if any), then the check line.
    let steps: Vec<&str> = summary.lines().skip_while(|l| !l.starts_with("next, in ")).skip(1).map(str::trim).collect();
    let check = steps.iter().find(|s| s.starts_with("silrig check ")).expect("a check line");
    if lang == "rust" {
        // Its target folder is the one both Rust projects share, so the commands stay the README's.
        let shared = Path::new(ROOT).join("target/new-rust");
        std::fs::create_dir_all(&shared).unwrap();
        std::os::unix::fs::symlink(&shared, project.join("target")).unwrap();
    }
    if let Some(build) = steps.iter().find(|s| !s.starts_with("silrig ")) {
        let o = run_in(&project, "sh", &["-c", build]);
        assert!(o.status.success(), "{build}: {}", text(&o));
    }
    common::client_lib(SILRIG);
    let o = run_in(&project, "sh", &["-c", &format!("{SILRIG} {} --out out", &check["silrig ".len()..])]);
    assert_eq!(o.status.code(), Some(0), "{check}: {}", text(&o));
    let verdict: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(project.join("out/check.json")).unwrap()).unwrap();
    assert_eq!(verdict["passed"], true, "{verdict}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_python_controller_and_plant_fly_their_own_checks() {
    new_builds_and_passes_its_own_check("controller", "python");
    new_builds_and_passes_its_own_check("plant", "python");
}

#[test]
fn a_c_controller_and_plant_build_and_fly_their_own_checks() {
    new_builds_and_passes_its_own_check("controller", "c");
    new_builds_and_passes_its_own_check("plant", "c");
}

#[test]
fn a_rust_controller_and_plant_build_against_this_checkout_and_fly_their_own_checks() {
    new_builds_and_passes_its_own_check("controller", "rust");
    new_builds_and_passes_its_own_check("plant", "rust");
}

#[test]
fn a_folder_that_is_not_empty_is_refused_and_the_help_describes_the_rig() {
    let dir = common::temp_dir(SUITE, "not-empty");
    std::fs::write(dir.join("mine.txt"), "mine").unwrap();
    let o = run_in(&dir, SILRIG, &["new", "plant", "--lang", "c", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("is not empty: give a new folder"), "{}", text(&o));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "it wrote into a folder that was not empty");
    let help = run_in(&dir, SILRIG, &["--help"]);
    let help = String::from_utf8_lossy(&help.stdout).to_string();
    assert!(help.starts_with("Software-in-the-loop rig for flight control: your plant and your controller"), "{help}");
    assert!(help.contains("the Stevens & Lewis F-16 and an adaptive sliding-mode controller are its reference pair"));
    std::fs::remove_dir_all(dir).unwrap();
}
