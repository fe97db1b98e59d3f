//! What most users run, as they run it: not root. The binaries (and the client library, and the Python example)
//! are copied into a folder every user can read, and each run is started as uid/gid 65534 (`nobody`) through
//! `setpriv`, with the usual 8 MiB locked-memory limit and no capabilities. Realtime then gets neither SCHED_FIFO nor
//! all its memory locked: the run must still fly to the end, say once per process what it lacks and how to get it,
//! and record in its report what each process had. When the tests themselves run unprivileged, they run the same
//! commands directly.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

mod common;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const NOBODY: &str = "65534";

/// A folder of this test everyone may enter, with the rig's binaries in `bin/` and a writable `runs/`.
fn world_readable_rig(test: &str) -> PathBuf {
    let dir = common::temp_dir("unprivileged", test);
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let built = Path::new(SILRIG).parent().unwrap();
    for name in ["silrig", "silrig-plant", "silrig-controller", "silrig-logger"] {
        common::copy_program(&built.join(name), &bin.join(name));
    }
    std::fs::copy(common::client_lib(SILRIG), bin.join("libsilrig_client.so")).unwrap();
    let python = dir.join("python");
    std::fs::create_dir_all(&python).unwrap();
    for name in ["silrig_client.py", "silrig_contract.py", "pid_attitude.py"] {
        std::fs::copy(Path::new(ROOT).join("examples/python").join(name), python.join(name)).unwrap();
    }
    std::fs::create_dir_all(dir.join("runs")).unwrap();
    for (path, mode) in [(dir.clone(), 0o755), (bin, 0o755), (python, 0o755), (dir.join("runs"), 0o777)] {
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
    }
    // The temp folder's own parents are world-enterable (/tmp); the test folder was made by us.
    dir
}

/// `silrig ARGS` as an unprivileged user with the usual limits, from the copied binaries.
fn silrig_as_user(dir: &Path, args: &[&str]) -> std::process::Output {
    let silrig = dir.join("bin/silrig");
    // SAFETY: geteuid has no preconditions.
    let root = unsafe { libc::geteuid() } == 0;
    let mut command = if root {
        let mut c = Command::new("sh");
        c.arg("-c")
            .arg("ulimit -l 8192 2>/dev/null; exec setpriv --reuid \"$0\" --regid \"$0\" --clear-groups --inh-caps=-all \"$@\"")
            .arg(NOBODY)
            .arg(&silrig);
        c
    } else {
        Command::new(&silrig)
    };
    let child = command
        .args(args)
        .current_dir(dir.join("runs"))
        .env("SILRIG_CLIENT_LIB", dir.join("bin/libsilrig_client.so"))
        .env("HOME", dir.join("runs"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_with_watchdog(child, Duration::from_secs(120))
}

fn report(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap()
}

fn scheduling(report: &serde_json::Value, process: &str) -> String {
    let p = report["processes"].as_array().unwrap().iter().find(|p| p["process"] == process).unwrap();
    p["scheduling"].as_str().unwrap().to_string()
}

#[test]
fn the_readme_main_command_flies_realtime_for_an_ordinary_user() {
    let dir = world_readable_rig("realtime");
    let out = dir.join("runs/r");
    let o = silrig_as_user(&dir, &["run", "--duration-s", "2", "--out", out.to_str().unwrap()]);
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("all processes ended cleanly"), "{stdout}");
    let r = report(&out);
    assert_eq!(r["failures"].as_array().unwrap().len(), 0);
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } == 0 {
        for process in ["plant", "controller"] {
            let s = scheduling(&r, process);
            assert!(s.starts_with("SCHED_OTHER, memory "), "{process}: {s}");
            let log = std::fs::read_to_string(out.join(format!("{process}.stderr.log"))).unwrap();
            assert_eq!(log.matches("warning").count(), 1, "one warning, said once: {log}");
            assert!(log.contains("SCHED_FIFO") && log.contains("setcap cap_sys_nice,cap_ipc_lock+ep"), "{log}");
        }
    }
    let rows = std::fs::read_to_string(out.join("trace.csv")).unwrap().lines().count() - 1;
    assert_eq!(rows, 201);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_ordinary_user_flies_lockstep_a_python_controller_and_a_killed_controller_restarting() {
    let dir = world_readable_rig("lockstep");
    let python_pid = format!("python3 {}", dir.join("python/pid_attitude.py").display());
    for (name, extra) in [
        ("lockstep", vec!["--mode", "lockstep"]),
        ("python", vec!["--duration-s", "2", "--controller-cmd", python_pid.as_str()]),
        ("fault", vec!["--duration-s", "3", "--fault", "controller:kill@1s,restart_after=0.3s"]),
    ] {
        let out = dir.join("runs").join(name);
        let args: Vec<&str> = ["run", "--out", out.to_str().unwrap()].into_iter().chain(extra).collect();
        let o = silrig_as_user(&dir, &args);
        let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert_eq!(o.status.code(), Some(0), "{name}: {stdout}\n{stderr}");
        assert_eq!(report(&out)["failures"].as_array().unwrap().len(), 0, "{name}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `cmd ARGS` as user `uid` (directly when the tests are not root: then both "users" are the same, and the test
/// only checks what one user sees).
fn as_user(uid: &str, dir: &Path, cmd: &Path, args: &[&str]) -> std::process::Command {
    let mut c = Command::new("setpriv");
    c.args(["--reuid", uid, "--regid", uid, "--clear-groups", "--inh-caps=-all"])
        .arg(cmd)
        .args(args)
        .current_dir(dir.join("runs"))
        .env("HOME", dir.join("runs"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    c
}

#[test]
fn two_users_side_by_side_can_neither_read_nor_join_nor_take_the_others_run() {
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        eprintln!("two users need root to become them: skipped as uid {}", unsafe { libc::geteuid() });
        return;
    }
    let dir = world_readable_rig("two-users");
    let silrig = dir.join("bin/silrig");
    let id = format!("u{}-alice", std::process::id());
    let alice_out = dir.join("runs/alice");
    let alice = as_user(
        NOBODY,
        &dir,
        &silrig,
        &["run", "--duration-s", "4", "--run-id", &id, "--out", alice_out.to_str().unwrap()],
    )
    .spawn()
    .unwrap();
    let start = std::time::Instant::now();
    while !std::fs::read_to_string(alice_out.join("events.jsonl")).is_ok_and(|t| t.contains("\"ticking\"")) {
        assert!(start.elapsed() < Duration::from_secs(30), "alice's run never started ticking");
        std::thread::sleep(Duration::from_millis(20));
    }
    let bob = "65533";
    // Bob cannot read Alice's files ...
    let read = as_user(bob, &dir, Path::new("/bin/cat"), &[alice_out.join("events.jsonl").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!read.status.success(), "bob read alice's events");
    // ... nor take her run id ...
    let bob_out = dir.join("runs/bob");
    let take =
        as_user(bob, &dir, &silrig, &["run", "--duration-s", "1", "--run-id", &id, "--out", bob_out.to_str().unwrap()])
            .output()
            .unwrap();
    let said = String::from_utf8_lossy(&take.stderr);
    assert_eq!(take.status.code(), Some(2), "{said}");
    let lock = format!("run id {id} is claimed by /tmp/silrig_{id}.lock of user nobody (uid {NOBODY})");
    assert!(said.contains(&lock), "{said}");
    // ... nor join it as its controller.
    let join = as_user(
        bob,
        &dir,
        &dir.join("bin/silrig-controller"),
        &["--run-id", &id, "--out", bob_out.to_str().unwrap(), "--startup-timeout-s", "1"],
    )
    .output()
    .unwrap();
    let said = String::from_utf8_lossy(&join.stderr);
    assert!(!join.status.success() && said.contains("cannot create iceoryx2 node"), "bob joined alice's run: {said}");
    // In words: whose run it is and what to do, no internal type (`NodeCreationFailure::...`).
    let words =
        format!("the run's files (/dev/shm/silrig_{id}) belong to uid {NOBODY}, and a run is its owner's alone");
    assert!(said.contains(&words) && !said.contains("::"), "{said}");
    // Alice's run is untouched by all of it.
    let o = common::wait_with_watchdog(alice, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stdout));
    let rows = std::fs::read_to_string(alice_out.join("trace.csv")).unwrap().lines().count() - 1;
    assert_eq!(rows, 401);
    common::no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_id_lock_of_another_user_is_refused_naming_it_and_one_of_a_dead_launcher_is_taken_over() {
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        eprintln!("skipped: planting another user's lock needs root, as CI runs");
        return;
    }
    let dir = world_readable_rig("foreign-lock");
    let id = format!("u{}-lock", std::process::id());
    let lock = PathBuf::from(format!("/tmp/silrig_{id}.lock"));
    // Root's launcher SIGKILLed: its lock stays, owner-only, naming a pid that has gone.
    let mut gone = Command::new("true").spawn().unwrap();
    gone.wait().unwrap();
    std::fs::write(&lock, gone.id().to_string()).unwrap();
    std::fs::set_permissions(&lock, std::fs::Permissions::from_mode(0o600)).unwrap();
    let o = silrig_as_user(&dir, &["run", "--mode", "lockstep", "--duration-s", "0.3", "--run-id", &id]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "run id {id} is claimed by {} of user root (uid 0), which only that user or root can remove",
            lock.display()
        )),
        "{stderr}"
    );
    assert!(lock.exists(), "another user's lock is never removed by this one");
    // Its owner, whose launcher is dead, takes it over.
    let out = dir.join("runs/by-root");
    let o = Command::new(SILRIG)
        .args(["run", "--mode", "lockstep", "--duration-s", "0.3", "--run-id", &id, "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!lock.exists(), "removed at the end of the run that took it over");
    common::no_shared_memory_left(&id);
    std::fs::remove_dir_all(&dir).unwrap();
}
