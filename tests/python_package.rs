//! The `silrig` Python package (python/), installed two ways, each then running the package's pytest suite
//! (python/tests/: the example PID through the package flying lockstep every tick, a toy plant through the package,
//! `silrig.sim` equal to `silrig sim` column by column, a small `silrig.sweep` equal to `silrig sweep`, a Python
//! controller in process equal to the lockstep rig's trace, the Python guide's examples, and the errors):
//! - `pip install ./python` from the source into target/py-venv (maturin, pytest, NumPy and matplotlib; made here
//!   when `.ci/run` has not made it), the way the guide installs it: the build shares this workspace's target/
//!   folder and profile, so it compiles the package's own crate and PyO3 and reuses the rest;
//! - the abi3 wheel, built with maturin into target/python-wheel/, installed into a venv made afresh for each run
//!   (target/py-wheel-venv) whose PATH holds no cargo or rustc: what a user without Rust gets.
//!
//! A pytest that collects no test fails here like one that fails; every run a suite started must leave no shared
//! memory behind. And the package's build shares every crate `cargo build --release` compiles, with the same
//! features (`cargo tree`), so `pip install ./python` after it compiles PyO3 and the package alone.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;
use std::time::Instant;

mod common;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The runs the suite starts, by the names it gives them (python/tests/test_*.py).
const RUNS: [&str; 5] = ["pid", "toy", "twice", "inproc", "hold"];

/// Held while maturin builds: two builds at once in one target folder clash over maturin's copy of the library
/// (target/maturin/).
static BUILDING: Mutex<()> = Mutex::new(());

/// What the suite imports beside the package: pytest, NumPy (`numpy=True`) and matplotlib (the guide's plot).
const TEST_PACKAGES: [&str; 3] = ["pytest", "numpy", "matplotlib"];

/// `python -m pip`: the venv's own pip whatever path its scripts were written for (a copied venv's `bin/pip`
/// names the interpreter of the folder it was made in).
fn pip(python: &Path) -> Command {
    let mut pip = Command::new(python);
    pip.args(["-m", "pip"]);
    pip
}

fn said(o: &Output) -> String {
    format!("{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// target/py-venv with maturin and the test packages, made if it is not there.
fn venv() -> PathBuf {
    let venv = Path::new(ROOT).join("target/py-venv");
    let python = venv.join("bin/python3");
    let ready = || {
        Command::new(&python)
            .args(["-c", "import maturin, pytest, numpy, matplotlib"])
            .status()
            .is_ok_and(|s| s.success())
    };
    if !ready() {
        let made = Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 runs");
        assert!(made.success(), "python3 -m venv {} failed (Debian: apt-get install python3-venv)", venv.display());
        let o = pip(&python).args(["install", "-q", "maturin"]).args(TEST_PACKAGES).output().expect("pip runs");
        assert!(o.status.success(), "pip install maturin and the test packages failed:\n{}", said(&o));
    }
    venv
}

/// The package's pytest suite run by `python`, its runs named `<prefix>-<name>`; each must leave no shared memory.
fn pytest(python: &Path, path: &str, prefix: &str) {
    let o = Command::new(python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(Path::new(ROOT).join("python/tests"))
        .env("PATH", path)
        .env("SILRIG_BIN", SILRIG)
        .env("SILRIG_TEST_RUN_PREFIX", prefix)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .env("MPLBACKEND", "Agg")
        .current_dir(std::env::temp_dir())
        .output()
        .expect("pytest runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    // Exit 5 (no test collected) fails here as any status but 0 does.
    assert_eq!(o.status.code(), Some(0), "pytest:\n{}", said(&o));
    let last = stdout.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or_default();
    assert!(last.contains(" passed") && !last.contains("failed"), "pytest's last line: {last}");
    assert!(!last.contains("skipped"), "every test must run here (NumPy and matplotlib installed): {last}");
    eprintln!("pytest: {last}");
    for run in RUNS {
        common::no_shared_memory_left(&format!("{prefix}-{run}"));
    }
}

#[test]
fn pip_install_builds_the_package_and_its_pytest_suite_passes() {
    let venv = venv();
    // maturin's command is found on PATH, as in an activated venv.
    let path = format!("{}:{}", venv.join("bin").display(), std::env::var("PATH").unwrap_or_default());
    let building = BUILDING.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let started = Instant::now();
    // No build isolation: maturin comes from the venv, not from a download per build.
    let o = pip(&venv.join("bin/python3"))
        .env("PATH", &path)
        .args(["install", "-q", "--no-build-isolation", "--force-reinstall", "--no-deps"])
        .arg(Path::new(ROOT).join("python"))
        .output()
        .expect("pip runs");
    assert!(o.status.success(), "pip install ./python failed:\n{}", said(&o));
    eprintln!("pip install ./python: {:.1} s", started.elapsed().as_secs_f64());
    drop(building);
    pytest(&venv.join("bin/python3"), &path, &format!("py{}-src", std::process::id()));
}

/// The abi3 wheel, built with maturin into target/python-wheel/ (emptied first, so the wheel found is this build's).
fn build_wheel(maturin_venv: &Path) -> PathBuf {
    let out = Path::new(ROOT).join("target/python-wheel");
    let _ = std::fs::remove_dir_all(&out);
    let _building = BUILDING.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let o = Command::new(maturin_venv.join("bin/maturin"))
        .args(["build", "--quiet", "--out"])
        .arg(&out)
        .current_dir(Path::new(ROOT).join("python"))
        .output()
        .expect("maturin runs");
    assert!(o.status.success(), "maturin build failed:\n{}", said(&o));
    let wheels: Vec<PathBuf> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(wheels.len(), 1, "one wheel in {}: {wheels:?}", out.display());
    let name = wheels[0].file_name().unwrap().to_string_lossy().to_string();
    // One wheel for every CPython from 3.9 on: the stable ABI's tag.
    assert!(name.contains("-cp39-abi3-"), "not an abi3 wheel: {name}");
    wheels[0].clone()
}

#[test]
fn the_abi3_wheel_installs_without_rust_and_its_pytest_suite_passes() {
    let wheel = build_wheel(&venv());
    let fresh = Path::new(ROOT).join("target/py-wheel-venv");
    let _ = std::fs::remove_dir_all(&fresh);
    let made = Command::new("python3").args(["-m", "venv"]).arg(&fresh).status().expect("python3 runs");
    assert!(made.success(), "python3 -m venv {} failed", fresh.display());
    // The venv's own programs and the system's, nothing of Rust's (rustup puts it in ~/.cargo/bin).
    let path = format!("{}:/usr/local/bin:/usr/bin:/bin", fresh.join("bin").display());
    for tool in ["cargo", "rustc"] {
        let found = Command::new("sh").args(["-c", &format!("command -v {tool}")]).env("PATH", &path).output();
        assert!(!found.unwrap().status.success(), "{tool} is on the wheel venv's PATH {path}");
    }
    let python = fresh.join("bin/python3");
    let o = pip(&python).env("PATH", &path).args(["install", "-q"]).arg(&wheel).args(TEST_PACKAGES).output();
    let o = o.expect("pip runs");
    assert!(o.status.success(), "pip install {} and the test packages failed:\n{}", wheel.display(), said(&o));
    // The package is the wheel's, not a source tree's.
    let o = Command::new(&python)
        .args(["-c", "import silrig; print(silrig.__file__)"])
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stdout).starts_with(&fresh.display().to_string()), "{}", said(&o));
    pytest(&python, &path, &format!("py{}-whl", std::process::id()));
    let _ = std::fs::remove_dir_all(&fresh);
}

/// Each package's features in a `cargo tree` of `args` (`name version` to the sets it is compiled with).
fn features_in_tree(args: &[&str]) -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    let o = Command::new(env!("CARGO"))
        .args(["tree", "--locked", "--edges", "normal,build", "--prefix", "none", "--format", "{p}|{f}"])
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("cargo tree runs");
    assert!(o.status.success(), "cargo tree {args:?}:\n{}", said(&o));
    let mut features = std::collections::BTreeMap::<String, std::collections::BTreeSet<String>>::new();
    for line in String::from_utf8_lossy(&o.stdout).lines() {
        let Some((package, set)) = line.split_once('|') else { continue };
        // `name v1.2.3 (/path)`: the name and version say which package it is.
        let package = package.split(' ').take(2).collect::<Vec<_>>().join(" ");
        features.entry(package).or_default().insert(set.trim_end_matches(" (*)").to_string());
    }
    features
}

/// What `pip install ./python` compiles beyond `cargo build --release` (the README's first command) is PyO3 and the
/// package alone: every crate both builds share is resolved with the same features (the workspace's Cargo.toml asks
/// for `syn`'s features PyO3's macros need), or else that crate and all above it would compile a second time.
#[test]
fn the_package_shares_every_crate_of_cargo_build_release_with_the_same_features() {
    let workspace = features_in_tree(&[]);
    let package = features_in_tree(&["-p", "silrig-python"]);
    let differing: Vec<String> = package
        .iter()
        .filter_map(|(name, theirs)| {
            workspace
                .get(name)
                .filter(|ours| *ours != theirs)
                .map(|ours| format!("{name}: {ours:?} in `cargo build --release`, {theirs:?} in the package's build"))
        })
        .collect();
    assert!(differing.is_empty(), "crates that would compile twice:\n{}", differing.join("\n"));
    let only_package: Vec<&String> = package.keys().filter(|name| !workspace.contains_key(*name)).collect();
    assert!(
        only_package.iter().all(|name| name.starts_with("pyo3")
            || name.starts_with("silrig-python")
            || name.starts_with("target-lexicon")),
        "{only_package:?}"
    );
    // Both trees were read: the package's holds the rig's crates.
    assert!(package.contains_key("silrig-rig v0.1.0") && workspace.contains_key("silrig-rig v0.1.0"), "{package:?}");
}
