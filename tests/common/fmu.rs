//! The FMUs this repository builds from C, for the tests that fly or break them: `airframe` (the example vehicle,
//! `examples/fmu/airframe`), `misbehave` (the importer's error fixture, `tests/fmu/misbehave`), `lag3` (a
//! first-order lag in FMI 3.0, `tests/fmu/lag3`), `attitude` (a foreign three-axis attitude vehicle, inputs named
//! with their unit and no surface positions, `tests/fmu/attitude`), `pid` (the example PID as a controller FMU,
//! `examples/fmu/pid`), and `stair` and `resource` (FMI 3.0, the Reference FMUs' interfaces with Int32 outputs,
//! `tests/fmu/stair` and `tests/fmu/resource`), each built by `examples/fmu/build.sh` with the system `cc` against
//! the FMI headers of the test venv's `fmpy`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The Python of `target/test-venv` with FMPy installed (by the first caller of this test process, so that tests
/// running in parallel do not pip-install it into the venv at the same time).
pub fn fmpy_python() -> PathBuf {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| super::venv_python("fmpy", "fmpy")).clone()
}

/// The folder of FMI headers inside the venv's `fmpy` package (`fmpy/c-code`, holding `fmi2Functions.h`).
pub fn fmi_headers() -> &'static Path {
    static HEADERS: OnceLock<PathBuf> = OnceLock::new();
    HEADERS.get_or_init(|| {
        let o = Command::new(fmpy_python())
            .args(["-c", "import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), 'c-code'))"])
            .output()
            .expect("the venv's python runs");
        assert!(o.status.success(), "locating fmpy's headers: {}", String::from_utf8_lossy(&o.stderr));
        let dir = PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
        assert!(dir.join("fmi2Functions.h").exists(), "{} has no fmi2Functions.h", dir.display());
        dir
    })
}

/// The source folder (C files and `modelDescription.xml`) of an FMU this repository builds.
pub fn fmu_source(name: &str) -> PathBuf {
    match name {
        "airframe" => Path::new(ROOT).join("examples/fmu/airframe"),
        "misbehave" => Path::new(ROOT).join("tests/fmu/misbehave"),
        "lag3" => Path::new(ROOT).join("tests/fmu/lag3"),
        "attitude" => Path::new(ROOT).join("tests/fmu/attitude"),
        "pid" => Path::new(ROOT).join("examples/fmu/pid"),
        "stair" => Path::new(ROOT).join("tests/fmu/stair"),
        "resource" => Path::new(ROOT).join("tests/fmu/resource"),
        other => panic!("no FMU named {other}: airframe, misbehave, lag3, attitude, pid, stair or resource"),
    }
}

/// `examples/fmu/build.sh SRC OUT` with the venv's headers and Python: its output, whatever the outcome.
pub fn run_build_sh(src: &Path, out: &Path) -> std::process::Output {
    Command::new("sh")
        .arg(Path::new(ROOT).join("examples/fmu/build.sh"))
        .arg(src)
        .arg(out)
        .env("FMI_HEADERS", fmi_headers())
        .env("PYTHON", fmpy_python())
        .output()
        .expect("sh runs")
}

/// Build FMU `name` ("airframe", "misbehave", "lag3", the FMI 3.0 one, "attitude" or "pid", the controller) into `out_dir/<name>.fmu` and return that path.
pub fn build_fmu(name: &str, out_dir: &Path) -> PathBuf {
    build(&fmu_source(name), &out_dir.join(format!("{name}.fmu")))
}

/// `misbehave` with a GUID in its `modelDescription.xml` that its binary does not know: `out_dir/wrong_guid.fmu`
/// (built from the same C source; its `fmi2Instantiate` logs "wrong GUID ..." and returns NULL).
pub fn build_wrong_guid_fmu(out_dir: &Path) -> PathBuf {
    let src = out_dir.join("wrong_guid_src");
    std::fs::create_dir_all(&src).unwrap();
    let original = fmu_source("misbehave");
    std::fs::copy(original.join("misbehave.c"), src.join("misbehave.c")).unwrap();
    let xml = std::fs::read_to_string(original.join("modelDescription.xml")).unwrap();
    let start = xml.find("guid=\"").expect("misbehave's modelDescription.xml has a guid") + "guid=\"".len();
    let end = start + xml[start..].find('"').unwrap();
    let wrong = "{00000000-0000-4000-8000-000000000bad}";
    assert_ne!(&xml[start..end], wrong);
    std::fs::write(src.join("modelDescription.xml"), format!("{}{wrong}{}", &xml[..start], &xml[end..])).unwrap();
    build(&src, &out_dir.join("wrong_guid.fmu"))
}

fn build(src: &Path, out: &Path) -> PathBuf {
    let o = run_build_sh(src, out);
    assert!(
        o.status.success(),
        "building {} from {}: {}{}",
        out.display(),
        src.display(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.exists(), "build.sh succeeded but wrote no {}", out.display());
    out.to_path_buf()
}

/// FMU `name` built once per test process (of test suite `suite`) into a folder of its own, shared by its tests:
/// built beside and renamed into place, so tests running in parallel never see half an FMU.
pub fn cached_fmu(suite: &str, name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("silrig-{suite}-{}-fmus", std::process::id()));
    let path = dir.join(format!("{name}.fmu"));
    if !path.exists() {
        std::fs::create_dir_all(&dir).unwrap();
        let own = dir.join(format!("{name}-{:?}", std::thread::current().id()).replace(['(', ')'], ""));
        std::fs::create_dir_all(&own).unwrap();
        let built = build_fmu(name, &own);
        std::fs::rename(built, &path).unwrap();
    }
    path.display().to_string()
}

/// `libsilrig_fmu_f16.so` beside `silrig`, built once (a test binary does not build the workspace's cdylibs): the
/// binary `silrig export-fmu` packs for either built-in vehicle.
pub fn export_library(silrig: &str) -> &'static Path {
    static LIB: OnceLock<PathBuf> = OnceLock::new();
    LIB.get_or_init(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let o = Command::new(cargo)
            .args(["build", "--release", "-p", "silrig-fmu-f16"])
            .current_dir(ROOT)
            .output()
            .unwrap();
        assert!(o.status.success(), "building libsilrig_fmu_f16.so: {}", String::from_utf8_lossy(&o.stderr));
        let lib = Path::new(silrig).parent().unwrap().join("libsilrig_fmu_f16.so");
        assert!(lib.exists(), "{} was not built", lib.display());
        lib
    })
}

/// `silrig export-fmu --out DIR/NAME [SCENARIO]` of a built-in vehicle; the FMU's path and what it printed.
pub fn export_builtin(silrig: &str, dir: &Path, name: &str, scenario: Option<&str>) -> (PathBuf, String) {
    export_library(silrig);
    let out = dir.join(name);
    let o = Command::new(silrig).arg("export-fmu").arg("--out").arg(&out).args(scenario).output().unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "export-fmu failed: {stdout}{stderr}");
    assert!(out.is_file(), "{} not written", out.display());
    (out, format!("{stdout}{stderr}"))
}
