//! The `silrig` Python package (python/): `pip install ./python` into the venv target/py-venv (created here with
//! maturin and pytest when `.ci/run` has not made it), then its pytest suite (python/tests/): the example PID through
//! the package flying lockstep every tick, a toy plant through the package, `silrig.sim` equal to `silrig sim` column
//! by column, a small `silrig.sweep` equal to `silrig sweep`, and the errors. The build shares this workspace's
//! target/ folder and the release profile, so it compiles the package's own crate and PyO3 and reuses the rest. A
//! pytest that collects no test fails here like one that fails; every run the suite started must leave no shared
//! memory behind.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

mod common;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The runs the suite starts, by the names it gives them (python/tests/test_*.py).
const RUNS: [&str; 3] = ["pid", "toy", "twice"];

/// target/py-venv with maturin and pytest, made if it is not there.
fn venv() -> PathBuf {
    let venv = Path::new(ROOT).join("target/py-venv");
    let python = venv.join("bin/python3");
    let ready = || Command::new(&python).args(["-c", "import maturin, pytest"]).status().is_ok_and(|s| s.success());
    if !ready() {
        let made = Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 runs");
        assert!(made.success(), "python3 -m venv {} failed (Debian: apt-get install python3-venv)", venv.display());
        let pip = Command::new(venv.join("bin/pip")).args(["install", "-q", "maturin", "pytest"]).status();
        assert!(pip.expect("pip runs").success(), "pip install maturin pytest failed");
    }
    venv
}

#[test]
fn pip_install_builds_the_package_and_its_pytest_suite_passes() {
    let venv = venv();
    // maturin's command is found on PATH, as in an activated venv.
    let path = format!("{}:{}", venv.join("bin").display(), std::env::var("PATH").unwrap_or_default());
    let started = Instant::now();
    // No build isolation: maturin comes from the venv, not from a download per build.
    let o = Command::new(venv.join("bin/pip"))
        .env("PATH", &path)
        .args(["install", "-q", "--no-build-isolation", "--force-reinstall", "--no-deps"])
        .arg(Path::new(ROOT).join("python"))
        .output()
        .expect("pip runs");
    assert!(
        o.status.success(),
        "pip install ./python failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("pip install ./python: {:.1} s", started.elapsed().as_secs_f64());

    let prefix = format!("py{}", std::process::id());
    let o = Command::new(venv.join("bin/python3"))
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(Path::new(ROOT).join("python/tests"))
        .env("SILRIG_BIN", SILRIG)
        .env("SILRIG_TEST_RUN_PREFIX", &prefix)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .current_dir(std::env::temp_dir())
        .output()
        .expect("pytest runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    // Exit 5 (no test collected) fails here as any status but 0 does.
    assert_eq!(o.status.code(), Some(0), "pytest:\n{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    let last = stdout.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or_default();
    assert!(last.contains(" passed") && !last.contains("failed"), "pytest's last line: {last}");
    eprintln!("pytest: {last}");
    for run in RUNS {
        common::no_shared_memory_left(&format!("{prefix}-{run}"));
    }
}
