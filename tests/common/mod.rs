//! Helpers the tests that start the rig's processes share: a fresh folder per test, a watchdog that kills and reaps
//! only the child it was given, and the check that a run left no shared memory behind.

#[allow(dead_code)]
pub mod fmu;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Copy a program to be run from `to` with `cp`, not `std::fs::copy`: a copy this process held open for writing is
/// inherited by every child another test thread forks meanwhile, until that child execs, and running the copy then
/// fails with "Text file busy" (ETXTBSY).
#[allow(dead_code)]
pub fn copy_program(from: &Path, to: &Path) {
    let status = Command::new("cp").arg(from).arg(to).status().expect("cp runs");
    assert!(status.success(), "cp {} {} failed", from.display(), to.display());
}

/// `libsilrig_client.so` beside the binary `silrig` under test (cargo test builds the binaries, not the cdylib):
/// built once per test binary with `cargo build --release -p silrig-client`.
#[allow(dead_code)]
pub fn client_lib(silrig: &str) -> &'static Path {
    static LIB: OnceLock<PathBuf> = OnceLock::new();
    LIB.get_or_init(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let o = Command::new(cargo)
            .args(["build", "--release", "-p", "silrig-client"])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(o.status.success(), "building libsilrig_client.so: {}", String::from_utf8_lossy(&o.stderr));
        let lib = Path::new(silrig).parent().unwrap().join("libsilrig_client.so");
        assert!(lib.exists(), "{} was not built", lib.display());
        lib
    })
}

/// `examples/c/pid_attitude.c` compiled once per test process (of suite `suite`) against `libsilrig_client.so`
/// beside `silrig` (see [`c_example`]).
#[allow(dead_code)]
pub fn c_pid(silrig: &str, suite: &str) -> String {
    c_example(silrig, suite, "pid_attitude")
}

/// `examples/c/<name>.c` compiled once per test process (of suite `suite`) with the system compiler, warnings as
/// errors, against `libsilrig_client.so` beside `silrig`, built beside and renamed into place for tests running in
/// parallel.
#[allow(dead_code)]
pub fn c_example(silrig: &str, suite: &str, name: &str) -> String {
    let root = env!("CARGO_MANIFEST_DIR");
    let exe = std::env::temp_dir().join(format!("silrig-{suite}-{}-{name}", std::process::id()));
    if !exe.exists() {
        let partial = exe.with_extension(format!("{:?}", std::thread::current().id()).replace(['(', ')'], ""));
        compile_c(silrig, Path::new(&format!("{root}/examples/c/{name}.c")), &partial);
        std::fs::rename(partial, &exe).unwrap();
    }
    exe.display().to_string()
}

/// Compile the C program `source` into `exe` with the system compiler, warnings as errors, against
/// `libsilrig_client.so` beside `silrig` and the header in `examples/c`.
#[allow(dead_code)]
pub fn compile_c(silrig: &str, source: &Path, exe: &Path) {
    let lib_dir = client_lib(silrig).parent().unwrap().to_path_buf();
    let o = Command::new("cc")
        .args(["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
        .arg(format!("{}/examples/c", env!("CARGO_MANIFEST_DIR")))
        .arg(source)
        .arg("-L")
        .arg(&lib_dir)
        .args(["-lsilrig_client", "-lm"])
        .arg(format!("-Wl,-rpath,{}", lib_dir.display()))
        .arg("-o")
        .arg(exe)
        .output()
        .unwrap();
    assert!(o.status.success(), "cc {}: {}", source.display(), String::from_utf8_lossy(&o.stderr));
}

/// The Python of `target/test-venv` (which `.ci/run` creates), with `package` installed there if `module` does not
/// import yet.
#[allow(dead_code)]
pub fn venv_python(module: &str, package: &str) -> PathBuf {
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-venv");
    let python = venv.join("bin/python3");
    let imports =
        || Command::new(&python).args(["-c", &format!("import {module}")]).status().is_ok_and(|s| s.success());
    if !imports() {
        let made = Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 runs");
        assert!(made.success(), "python3 -m venv {} failed (Debian: apt-get install python3-venv)", venv.display());
        let installed = Command::new(venv.join("bin/pip")).args(["install", "-q", package]).status().expect("pip runs");
        assert!(installed.success(), "pip install {package} failed");
    }
    python
}

/// An empty folder of this test process and test: `<tmp>/silrig-<suite>-<pid>-<test>`.
pub fn temp_dir(suite: &str, test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("silrig-{suite}-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Wait for a child with a watchdog: past `limit` it is killed (by its pid) and reaped, and the test fails.
pub fn wait_with_watchdog(mut child: Child, limit: Duration) -> Output {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!("no end within {limit:?}; stderr: {}", String::from_utf8_lossy(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// No shared memory, run folder or scratch folder is left of the runs a sweep of process `pid` started (named
/// `r<pid in hex>-...`).
pub fn assert_sweep_left_nothing(pid: u32) {
    let runs = format!("r{pid:x}-");
    let named = |dir: &Path, prefixes: &[String]| -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| prefixes.iter().any(|p| n.starts_with(p)))
            .collect()
    };
    let shm = named(Path::new("/dev/shm"), &[format!("sr_{runs}"), format!("silrig_{runs}")]);
    assert!(shm.is_empty(), "shared memory left behind: {shm:?}");
    let tmp = named(&std::env::temp_dir(), &[format!("silrig-sweep-{runs}")]);
    assert!(tmp.is_empty(), "run or scratch folders left behind: {tmp:?}");
}

/// `program ARGS` (`silrig` running rigs: a sweep, a case through the rig) from the repository root, to its end (5
/// minutes at most): (exit code, stdout, stderr). The rigs it flew (run ids `r<its pid>-...`) left no shared
/// memory, and its run and scratch folders are gone.
#[allow(dead_code)]
pub fn run_leaving_nothing(program: &str, args: &[&str]) -> (Option<i32>, String, String) {
    let child = Command::new(program)
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let o = wait_with_watchdog(child, Duration::from_secs(300));
    assert_sweep_left_nothing(pid);
    (o.status.code(), String::from_utf8_lossy(&o.stdout).into(), String::from_utf8_lossy(&o.stderr).into())
}

/// The run's `/dev/shm` files and iceoryx2 root folder are gone.
pub fn no_shared_memory_left(run_id: &str) {
    let prefix = format!("sr_{run_id}_");
    let left: Vec<String> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with(&prefix))
        .collect();
    assert!(left.is_empty(), "shared memory left behind: {left:?}");
    assert!(!Path::new(&format!("/dev/shm/silrig_{run_id}")).exists(), "iceoryx2 root folder left behind");
}

/// A message a person reads is in words: no Rust path (`Type::Variant`), no Debug dump of a value or an error
/// (`Some(`, `Err(`, `Os {`, `kind:`, a `Name { field: ` struct). `what` says whose message it is when it fails.
#[allow(dead_code)]
pub fn assert_in_words(what: &str, message: &str) {
    for (at, _) in message.match_indices("::") {
        let before = message[..at].chars().next_back().is_some_and(|c| c.is_ascii_alphanumeric());
        let after = message[at + 2..].chars().next().is_some_and(|c| c.is_ascii_alphabetic());
        assert!(!(before && after), "{what}: a Rust path in its message: {message}");
    }
    for dump in ["Some(", "Err(", "Ok(", "Os {", "kind:", "{:?}"] {
        assert!(!message.contains(dump), "{what}: a Debug dump (`{dump}`) in its message: {message}");
    }
    for (at, _) in message.match_indices(" { ") {
        let rest = &message[at + 3..];
        let field = rest.chars().take_while(|c| c.is_ascii_lowercase() || *c == '_').count();
        assert!(field == 0 || !rest[field..].starts_with(": "), "{what}: a Debug struct in its message: {message}");
    }
}

/// A finished `silrig run` of a test: its exit code, output, report and folders.
#[allow(dead_code)]
pub struct Run {
    /// The launcher's exit code.
    pub code: Option<i32>,
    /// What it printed.
    pub stdout: String,
    /// What it said on stderr.
    pub stderr: String,
    /// `report.json` (Null when none was written).
    pub report: serde_json::Value,
    /// The run's folder.
    pub out: PathBuf,
    /// The test's folder (the run's parent).
    pub dir: PathBuf,
    /// The run id.
    pub id: String,
}

#[allow(dead_code)]
impl Run {
    /// `silrig run ARGS` with its own run id (`<id_prefix><pid>-<test>`) and folder, to the end (120 s at most).
    pub fn start(silrig: &str, suite: &str, id_prefix: &str, test: &str, args: &[&str]) -> Run {
        let dir = temp_dir(suite, test);
        let id = format!("{id_prefix}{}-{test}", std::process::id());
        let out = dir.join("out");
        let child = Command::new(silrig)
            .arg("run")
            .args(args)
            .args(["--run-id", &id, "--out", out.to_str().unwrap(), "--no-baseline"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let o = wait_with_watchdog(child, Duration::from_secs(120));
        let report = std::fs::read_to_string(out.join("report.json"))
            .map(|t| serde_json::from_str(&t).unwrap())
            .unwrap_or(serde_json::Value::Null);
        Run {
            code: o.status.code(),
            stdout: String::from_utf8_lossy(&o.stdout).into(),
            stderr: String::from_utf8_lossy(&o.stderr).into(),
            report,
            out,
            dir,
            id,
        }
    }

    /// One process's report.
    pub fn process(&self, name: &str) -> &serde_json::Value {
        let processes = self.report["processes"].as_array().unwrap_or_else(|| panic!("no report: {}", self.stdout));
        processes.iter().find(|p| p["process"] == name).unwrap_or_else(|| panic!("no {name} report"))
    }

    /// One of a process's counters (0 when it has none of that name).
    pub fn counter(&self, process: &str, counter: &str) -> u64 {
        self.process(process)["counters"][counter].as_u64().unwrap_or(0)
    }

    /// The report's failures, as JSON text.
    pub fn failures(&self) -> String {
        self.report["failures"].to_string()
    }

    /// Every event of the run.
    pub fn events(&self) -> Vec<serde_json::Value> {
        let text = std::fs::read_to_string(self.out.join("events.jsonl")).unwrap_or_default();
        text.lines().filter_map(|l| serde_json::from_str(l).ok()).collect()
    }

    /// The first event of `process` of this kind.
    pub fn event(&self, process: &str, kind: &str) -> Option<serde_json::Value> {
        self.events().into_iter().find(|e| e["process"] == process && e["kind"] == kind)
    }

    /// `silrig run ARGS` that must be refused before any process starts: exit 2, no run folder left, the refusal in
    /// words ([`assert_in_words`]); its stderr.
    pub fn refused(silrig: &str, suite: &str, id_prefix: &str, test: &str, args: &[&str]) -> String {
        let r = Run::start(silrig, suite, id_prefix, test, args);
        assert_eq!(r.code, Some(2), "{}\n{}", r.stdout, r.stderr);
        assert!(!r.out.exists(), "a refused run left {}", r.out.display());
        assert_in_words(&format!("silrig run {}", args.join(" ")), &r.stderr);
        let stderr = r.stderr.clone();
        r.finish();
        stderr
    }

    /// The index of trace column `name` in `header`.
    pub fn column(header: &[String], name: &str) -> usize {
        header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    }

    /// The trace: header and rows.
    pub fn trace(&self) -> (Vec<String>, Vec<Vec<f64>>) {
        let text = std::fs::read_to_string(self.out.join("trace.csv")).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap().split(',').map(String::from).collect();
        let rows = lines.map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect();
        (header, rows)
    }

    /// The run left no shared memory; its folder goes.
    pub fn finish(self) {
        no_shared_memory_left(&self.id);
        std::fs::remove_dir_all(&self.dir).unwrap();
    }
}
