//! The controller on another host: two network namespaces joined by a veth pair stand for two hosts, the plant and
//! the logger under `silrig run --bridge-listen` in one, `silrig-bridge --connect` and the unmodified
//! `silrig-controller` in the other, which also gets a /dev/shm and /tmp of its own (a private mount namespace), so
//! the run's iceoryx2 namespace exists twice, as on two machines. A realtime run flies with every command accounted
//! for; a link cut trips the plant's failsafe and the flight recovers when the link returns; a restarted
//! controller-side bridge resumes the flight, and so does a plant-side one the launcher restarts; an unreachable
//! address, another run id and a second controller-side bridge get a clear error while the plant side flies on.
//! With the bridges' test impairment (`SILRIG_BRIDGE_TEST_*`: added delay, loss), same-tick across hosts is held to
//! its budget and lost commands are counted as misses; a bridge that says it speaks another wire layout is refused.
//! Each test creates its namespaces, veth and processes and removes them in `Drop`, also when it fails; addresses
//! exist only inside the namespaces. Needs root and iproute2; no timing bound is asserted.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

mod common;
use common::no_shared_memory_left;

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const BRIDGE: &str = env!("CARGO_BIN_EXE_silrig-bridge");
const CONTROLLER: &str = env!("CARGO_BIN_EXE_silrig-controller");
const PLANT_ADDR: &str = "10.217.0.1:7447";

/// One realtime rig at a time: two cores are not enough for several with their timing intact.
static ONE_RIG: Mutex<()> = Mutex::new(());

fn ip(args: &[&str]) {
    let o = Command::new("ip").args(args).output().expect("iproute2's `ip` (apt-get install iproute2)");
    assert!(o.status.success(), "ip {}: {}", args.join(" "), String::from_utf8_lossy(&o.stderr));
}

/// Two namespaces and the veth pair between them, and the bridge key both hosts hold (off the loopback a bridge
/// needs one); removed on drop (deleting a namespace removes its veth end).
struct Hosts {
    plant: String,
    controller: String,
    controller_if: String,
    key: PathBuf,
}

/// A new bridge key from `silrig-bridge keygen`, in the target folder (visible on both hosts).
fn keygen(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("bridge-{}-{name}.key", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let o = Command::new(BRIDGE).arg("keygen").arg(&path).output().unwrap();
    assert!(o.status.success(), "keygen: {}", String::from_utf8_lossy(&o.stderr));
    path
}

impl Hosts {
    fn new(tag: &str) -> Self {
        let base = format!("b{}{tag}", std::process::id() % 100_000);
        let hosts = Hosts {
            plant: format!("{base}p"),
            controller: format!("{base}c"),
            controller_if: format!("{base}c"),
            key: keygen(tag),
        };
        let plant_if = format!("{base}p");
        ip(&["netns", "add", &hosts.plant]);
        ip(&["netns", "add", &hosts.controller]);
        ip(&[
            "link",
            "add",
            &plant_if,
            "netns",
            &hosts.plant,
            "type",
            "veth",
            "peer",
            "name",
            &hosts.controller_if,
            "netns",
            &hosts.controller,
        ]);
        for (ns, dev, addr) in
            [(&hosts.plant, &plant_if, "10.217.0.1/24"), (&hosts.controller, &hosts.controller_if, "10.217.0.2/24")]
        {
            ip(&["-n", ns, "addr", "add", addr, "dev", dev]);
            ip(&["-n", ns, "link", "set", dev, "up"]);
            ip(&["-n", ns, "link", "set", "lo", "up"]);
        }
        hosts
    }

    fn link(&self, up: bool) {
        ip(&["-n", &self.controller, "link", "set", &self.controller_if, if up { "up" } else { "down" }]);
    }
}

impl Drop for Hosts {
    fn drop(&mut self) {
        for ns in [&self.plant, &self.controller] {
            let _ = Command::new("ip").args(["netns", "del", ns]).status();
        }
        let _ = std::fs::remove_file(&self.key);
    }
}

/// A process this test started: killed by its pid and reaped on drop, unless it ended already.
struct Proc(Option<Child>);

impl Proc {
    fn spawn(command: &mut Command) -> Self {
        Self(Some(command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap()))
    }

    fn pid(&self) -> u32 {
        self.0.as_ref().unwrap().id()
    }

    fn running(&mut self) -> bool {
        self.0.as_mut().unwrap().try_wait().unwrap().is_none()
    }

    fn signal(&self, signal: libc::c_int) {
        // SAFETY: kill(2) on our child's pid, not reaped yet (we hold the Child).
        unsafe { libc::kill(self.pid() as libc::pid_t, signal) };
    }

    /// Wait up to `limit` for it to end; past that it is killed and the test fails.
    fn wait(mut self, limit: Duration) -> (ExitStatus, String) {
        let child = self.0.take().unwrap();
        let o: Output = common::wait_with_watchdog(child, limit);
        (o.status, String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr))
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if let Some(mut child) = self.0.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// A folder for one side of a test, in the target folder, which stays visible on the controller's host (see
/// [`PRIVATE_TMP`]).
fn folder(test: &str, side: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("bridge-{}-{test}-{side}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run_id(test: &str) -> String {
    format!("b{}-{test}", std::process::id())
}

/// `silrig run --bridge-listen` on the plant's host.
fn plant_host(hosts: &Hosts, run: &str, out: &Path, duration_s: &str) -> Proc {
    plant_host_with(hosts, run, out, duration_s, &[], &[])
}

/// The same with more flags, and environment variables (the bridge's test impairment) for the launcher and so for
/// the plant-side bridge it starts.
fn plant_host_with(
    hosts: &Hosts,
    run: &str,
    out: &Path,
    duration_s: &str,
    flags: &[&str],
    env: &[(&str, &str)],
) -> Proc {
    let mut command = Command::new("ip");
    command.args(["netns", "exec", &hosts.plant, SILRIG, "run", "--no-baseline"]).args([
        "--run-id",
        run,
        "--out",
        out.to_str().unwrap(),
        "--duration-s",
        duration_s,
        "--external-timeout-s",
        "30",
        "--bridge-listen",
        PLANT_ADDR,
        "--bridge-key",
        hosts.key.to_str().unwrap(),
    ]);
    Proc::spawn(command.args(flags).envs(env.iter().copied()))
}

/// Mounts a private /dev/shm and /tmp, then execs its arguments. A checkout under /tmp (a CI clone) is bound back
/// into the new /tmp through a mount point in the new /dev/shm, so the binaries and the test's folders stay
/// visible while the run's iceoryx2 files are the controller host's own.
const PRIVATE_TMP: &str = r#"keep="$1"; shift
mount -t tmpfs tmpfs /dev/shm || exit 1
case "$keep" in /tmp/*) mkdir /dev/shm/keep && mount --bind "$keep" /dev/shm/keep || exit 1;; *) keep="";; esac
mount -t tmpfs tmpfs /tmp || exit 1
if [ -n "$keep" ]; then
  mkdir -p "$keep" && mount --bind /dev/shm/keep "$keep" && umount /dev/shm/keep && rmdir /dev/shm/keep || exit 1
fi
exec "$@""#;

/// `silrig-bridge --connect` on the controller's host, in a mount namespace of its own with a private /dev/shm and
/// /tmp (the exec chain keeps the pid: it is the bridge's).
fn controller_bridge(hosts: &Hosts, run: &str, out: &Path) -> Proc {
    controller_bridge_with(hosts, run, out, &[])
}

/// The same with environment variables (the bridge's test impairment).
fn controller_bridge_with(hosts: &Hosts, run: &str, out: &Path, env: &[(&str, &str)]) -> Proc {
    Proc::spawn(third_host(hosts, &["--key", hosts.key.to_str().unwrap()], run, out).envs(env.iter().copied()))
}

/// `silrig-bridge --connect` with `security` (a key, none, `--insecure`) from the controller's host, in a mount
/// namespace of its own: the controller's, or a third host's.
fn third_host(hosts: &Hosts, security: &[&str], run: &str, out: &Path) -> Command {
    let mut command = Command::new("ip");
    command
        .args(["netns", "exec", &hosts.controller, "unshare", "--mount", "sh", "-c", PRIVATE_TMP, "sh"])
        .arg(env!("CARGO_MANIFEST_DIR"))
        .args([BRIDGE, "--connect", PLANT_ADDR, "--run-id", run, "--out", out.to_str().unwrap()])
        .args(security);
    command
}

/// A program run inside the namespaces (network and mount) of process `pid` on the controller's host.
fn beside(pid: u32, program: &str) -> Command {
    let mut c = Command::new("nsenter");
    c.args(["-t", &pid.to_string(), "-m", "-n", program]);
    c
}

/// The unmodified controller beside the bridge `bridge_pid`, once the bridge has written the run's scenario.
fn controller(bridge_pid: u32, run: &str, out: &Path) -> Proc {
    wait_for(Duration::from_secs(30), "the controller-side bridge writes controller.env", || {
        out.join("controller.env").exists()
    });
    let scenario = out.join("scenario.toml");
    Proc::spawn(beside(bridge_pid, CONTROLLER).arg(scenario).args(["--run-id", run, "--out", out.to_str().unwrap()]))
}

fn wait_for(limit: Duration, what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < limit, "{what}: not within {limit:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn events(out: &Path) -> Vec<Value> {
    let text = std::fs::read_to_string(out.join("events.jsonl")).unwrap_or_default();
    text.lines().filter_map(|l| serde_json::from_str(l).ok()).collect()
}

fn has_event(out: &Path, process: &str, kind: &str) -> bool {
    events(out).iter().any(|e| e["process"] == process && e["kind"] == kind)
}

fn first_after(events: &[Value], process: &str, kind: &str, after_ns: u64) -> Option<u64> {
    events
        .iter()
        .filter(|e| e["process"] == process && e["kind"] == kind)
        .filter_map(|e| e["t_ns"].as_u64())
        .find(|t| *t >= after_ns)
}

fn report(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap()
}

fn counter(report: &Value, process: &str, name: &str) -> u64 {
    let p = report["processes"].as_array().unwrap().iter().find(|p| p["process"] == process).unwrap();
    p["counters"][name].as_u64().unwrap_or_else(|| panic!("{process} has no counter {name}: {p}"))
}

fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: a valid timespec to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

#[test]
fn a_controller_on_the_other_host_flies_the_plant_and_every_command_is_accounted_for() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("a");
    let (run, out, ctl_out) = (run_id("answers"), folder("answers", "plant"), folder("answers", "controller"));
    let launcher = plant_host(&hosts, &run, &out, "10");
    let mut bridge = controller_bridge(&hosts, &run, &ctl_out);
    let ctl = controller(bridge.pid(), &run, &ctl_out);
    let (status, text) = launcher.wait(Duration::from_secs(120));
    assert!(status.success(), "{text}");
    // The report, for `-- --nocapture` (the README's figures come from here).
    eprintln!("{text}");
    // Next-tick by default across hosts, and the network leg beside sense-to-actuate.
    assert!(text.contains("bridge.network_rtt") && text.contains("plant.sense_to_actuate"), "{text}");
    let r = report(&out);
    let ticks = counter(&r, "plant", "ticks");
    let misses = counter(&r, "plant", "command_misses");
    assert_eq!(ticks, 1001, "{text}");
    // How many ticks went unanswered is a timing figure (CI once saw 83 of 1001, most in the first second on a
    // loaded machine), printed for the measurements and never bounded here. What is asserted is the accounting:
    // every command the controller sent on its host reached the plant here or is counted lost, and every one the
    // plant-side bridge took from the network went on to the plant.
    eprintln!("across hosts: {misses} of {ticks} ticks without their command");
    let (received, lost) = (counter(&r, "plant", "commands_received"), counter(&r, "plant", "commands_lost"));
    let sent = counter(&r, "controller", "commands_sent");
    assert!(received > 0 && received + lost <= sent && sent <= received + lost + 1, "{sent} sent: {text}");
    let relayed = counter(&r, "bridge", "commands_in");
    assert!(received <= relayed && relayed <= received + lost, "{relayed} relayed: {text}");
    assert_eq!(counter(&r, "controller", "samples_unanswered"), 0, "{text}");
    assert!(counter(&r, "bridge", "plant_samples_out") >= ticks, "{text}");
    let rtt = r["processes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|p| p["latencies"].as_array().unwrap())
        .find(|l| l["name"] == "bridge.network_rtt")
        .unwrap();
    // Timed for each relayed command whose sample's stamps both bridges still held.
    let timed = rtt["summary"]["count"].as_u64().unwrap();
    assert!(timed > 0 && timed <= relayed, "{relayed} relayed: {rtt}");
    // The controller's report came back from its host: the run's report here has it, with its compute time.
    assert!(has_event(&out, "bridge", "controller-report-received"), "{text}");
    assert!(r["processes"].as_array().unwrap().iter().any(|p| p["process"] == "controller"), "{text}");
    assert!(text.contains("controller.compute"), "{text}");
    let scenario = std::fs::read_to_string(ctl_out.join("scenario.toml")).unwrap();
    assert!(scenario.contains("command_timing = \"next-tick\""), "{scenario}");
    // The controller side ends by itself with the flight, and so does the controller.
    let (status, said) = ctl.wait(Duration::from_secs(30));
    assert!(status.success(), "{said}");
    let (status, said) = std::mem::replace(&mut bridge, Proc(None)).wait(Duration::from_secs(30));
    assert!(status.success(), "{said}");
    assert!(said.contains("sent the controller's report") && !said.contains("did not confirm"), "{said}");
    let ctl_report: Value =
        serde_json::from_str(&std::fs::read_to_string(ctl_out.join("bridge.report.json")).unwrap()).unwrap();
    assert_eq!(ctl_report["ended"], "completed", "{ctl_report}");
    no_shared_memory_left(&run);
    for dir in [out, ctl_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn a_link_cut_trips_the_failsafe_and_the_flight_recovers_also_after_a_bridge_restart() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("b");
    let (run, out, ctl_out) = (run_id("cut"), folder("cut", "plant"), folder("cut", "controller"));
    let launcher = plant_host(&hosts, &run, &out, "12");
    let mut bridge = controller_bridge(&hosts, &run, &ctl_out);
    let mut ctl = controller(bridge.pid(), &run, &ctl_out);
    wait_for(Duration::from_secs(60), "the plant ticks", || has_event(&out, "plant", "ticking"));
    std::thread::sleep(Duration::from_secs(2));

    let cut_ns = monotonic_ns();
    hosts.link(false);
    std::thread::sleep(Duration::from_millis(500));
    hosts.link(true);
    let up_ns = monotonic_ns();
    wait_for(Duration::from_secs(20), "the flight recovers after the cut", || {
        first_after(&events(&out), "plant", "controller-recovered", up_ns).is_some()
    });
    let e = events(&out);
    let failsafe = first_after(&e, "plant", "failsafe-engaged", cut_ns).expect("the cut trips the failsafe");
    let lost = first_after(&e, "bridge", "bridge-peer-lost", cut_ns).expect("the plant side reports the lost peer");
    let recovered = first_after(&e, "plant", "controller-recovered", up_ns).unwrap();
    assert!(failsafe < recovered && lost < recovered);
    eprintln!(
        "link cut: failsafe {:.0} ms and peer lost {:.0} ms after the cut; flight recovered {:.0} ms after the link \
         came back",
        (failsafe - cut_ns) as f64 / 1e6,
        (lost - cut_ns) as f64 / 1e6,
        (recovered - up_ns) as f64 / 1e6
    );

    // The controller side's bridge dies; a new one beside the same controller resumes the flight.
    assert!(bridge.running());
    bridge.signal(libc::SIGKILL);
    let _ = std::mem::replace(&mut bridge, Proc(None)).wait(Duration::from_secs(10));
    let killed_ns = monotonic_ns();
    let mut restarted = Proc::spawn(beside(ctl.pid(), BRIDGE).args([
        "--connect",
        PLANT_ADDR,
        "--run-id",
        &run,
        "--out",
        ctl_out.to_str().unwrap(),
        "--key",
        hosts.key.to_str().unwrap(),
    ]));
    wait_for(Duration::from_secs(20), "the flight resumes with the restarted bridge", || {
        let e = events(&out);
        e.iter().any(|e| e["kind"] == "bridge-peer-joined" && e["detail"].as_str().unwrap().contains("replacing"))
            && first_after(&e, "plant", "controller-recovered", killed_ns).is_some()
    });
    let (status, text) = launcher.wait(Duration::from_secs(120));
    assert!(status.success(), "{text}");
    assert!(counter(&report(&out), "plant", "failsafe_ticks") > 0);
    assert!(ctl.running() || ctl.wait(Duration::from_secs(1)).0.success());
    let _ = restarted.wait_ended(Duration::from_secs(10));
    no_shared_memory_left(&run);
    for dir in [out, ctl_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// `name`'s summary in the report (a distribution of any process).
fn latency<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["processes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|p| p["latencies"].as_array().unwrap())
        .find(|l| l["name"] == name)
        .map(|l| &l["summary"])
        .unwrap_or_else(|| panic!("no {name} in the report"))
}

/// One flight across the hosts with the bridges' test impairment `env` on both sides and `flags` for `silrig run`;
/// returns the plant side's report, its text and the controller-side bridge's report.
fn impaired_flight(
    hosts: &Hosts,
    test: &str,
    duration_s: &str,
    flags: &[&str],
    env: &[(&str, &str)],
) -> (Value, String, Value) {
    let (run, out, ctl_out) = (run_id(test), folder(test, "plant"), folder(test, "controller"));
    let launcher = plant_host_with(hosts, &run, &out, duration_s, flags, env);
    let mut bridge = controller_bridge_with(hosts, &run, &ctl_out, env);
    let ctl = controller(bridge.pid(), &run, &ctl_out);
    let (status, text) = launcher.wait(Duration::from_secs(120));
    assert!(status.success(), "{text}");
    let _ = ctl.wait(Duration::from_secs(30));
    let (status, said) = std::mem::replace(&mut bridge, Proc(None)).wait(Duration::from_secs(30));
    assert!(status.success(), "{said}");
    // Both bridges said that their figures are a test's, not a network's.
    assert!(said.contains("TEST impairment"), "{said}");
    assert!(has_event(&out, "bridge", "bridge-test-impairment"));
    let r = report(&out);
    let ctl_report: Value =
        serde_json::from_str(&std::fs::read_to_string(ctl_out.join("bridge.report.json")).unwrap()).unwrap();
    no_shared_memory_left(&run);
    for dir in [out, ctl_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
    (r, text, ctl_report)
}

#[test]
fn same_tick_across_hosts_is_held_to_its_budget_when_the_network_adds_delay() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("d");
    // 1 ms more each way: no command can come back within a 1 ms budget, so the ticks hold the last command ...
    let delay = [("SILRIG_BRIDGE_TEST_DELAY_MS", "1")];
    let same_tick = |budget: &'static str| ["--command-timing", "same-tick", "--command-budget-ms", budget];
    let (r, text, _) = impaired_flight(&hosts, "budget1", "3", &same_tick("1"), &delay);
    // The plant's own sample-to-command time holds both delays, and so does the network's share of it, every tick
    // (the last tick, which goes out twice, was once timed from its second copy: 2 ms short).
    let round_trip = latency(&r, "plant.sense_to_actuate");
    assert!(round_trip["min_us"].as_f64().unwrap() >= 2000.0, "the round trip has both delays: {round_trip}");
    let network = latency(&r, "bridge.network_rtt");
    assert!(network["min_us"].as_f64().unwrap() >= 2000.0, "the network's round trip has both delays: {network}");
    let (ticks, misses) = (counter(&r, "plant", "ticks"), counter(&r, "plant", "command_misses"));
    assert_eq!(ticks, 301, "{text}");
    // A plant descheduled for longer than the round trip between sending its sample and looking for the answer
    // finds it there and rightly applies it (CI saw 2 such ticks of 301 under load): nearly every tick, not all.
    assert!(misses * 10 >= ticks * 9, "no command within 1 ms of its sample across 2 ms: {misses} of {ticks}; {text}");
    assert!(counter(&r, "plant", "failsafe_ticks") > 0, "the plant flew its failsafe: {text}");
    // ... and a budget that covers the delay gets its commands on their own tick.
    let misses_1ms = misses;
    let (r, text, _) = impaired_flight(&hosts, "budget9", "3", &same_tick("9"), &delay);
    let (ticks, misses) = (counter(&r, "plant", "ticks"), counter(&r, "plant", "command_misses"));
    // Set beside the 1 ms flight, not bounded on its own: a stall of the machine misses ticks in either.
    assert!(
        misses * 2 < misses_1ms,
        "with a 9 ms budget far fewer ticks miss their own command than with 1 ms: {misses} against {misses_1ms} \
         of {ticks}; {text}"
    );
    eprintln!("same-tick across hosts with 1 ms added each way and a 9 ms budget: {misses} of {ticks} missed");
}

#[test]
fn losses_on_the_network_are_counted_as_misses_and_the_flight_goes_on() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("e");
    let loss = [("SILRIG_BRIDGE_TEST_LOSS", "0.2"), ("SILRIG_BRIDGE_TEST_SEED", "11")];
    let (r, text, ctl_report) = impaired_flight(&hosts, "loss", "3", &[], &loss);
    let ticks = counter(&r, "plant", "ticks");
    assert_eq!(ticks, 301, "{text}");
    // 20 % of the plant samples lost on the way out and 20 % of the commands on the way back: about 36 % of the
    // ticks miss their command (expected 108, standard deviation about 8).
    let (misses, lost_commands) = (counter(&r, "plant", "command_misses"), counter(&r, "bridge", "test_losses"));
    let lost_samples = ctl_report["counters"]["test_losses"].as_u64().expect("the controller side counts its losses");
    assert!(lost_commands >= 20 && lost_samples >= 20, "{lost_commands} commands, {lost_samples} samples lost");
    assert!(misses >= lost_commands, "every lost command is a miss: {misses} misses, {lost_commands} lost; {text}");
    assert!(misses * 10 >= ticks, "{misses} of {ticks}");
}

#[test]
fn the_launcher_restarts_a_killed_plant_side_bridge_and_the_flight_resumes() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("f");
    let (run, out, ctl_out) = (run_id("restart"), folder("restart", "plant"), folder("restart", "controller"));
    let launcher = plant_host(&hosts, &run, &out, "8");
    let mut bridge = controller_bridge(&hosts, &run, &ctl_out);
    let ctl = controller(bridge.pid(), &run, &ctl_out);
    wait_for(Duration::from_secs(60), "the plant ticks", || has_event(&out, "plant", "ticking"));
    std::thread::sleep(Duration::from_secs(1));
    let started = events(&out)
        .iter()
        .find(|e| {
            e["process"] == "launcher"
                && e["kind"] == "process-started"
                && e["detail"].as_str().unwrap().starts_with("bridge as pid ")
        })
        .map(|e| e["detail"].as_str().unwrap().to_string())
        .expect("the launcher says which pid the plant-side bridge has");
    let pid: i32 = started["bridge as pid ".len()..].split(',').next().unwrap().parse().unwrap();
    let killed_ns = monotonic_ns();
    // SAFETY: kill(2) on the plant-side bridge our launcher started and still supervises (it reaps it).
    assert_eq!(unsafe { libc::kill(pid, libc::SIGKILL) }, 0);
    wait_for(Duration::from_secs(30), "the launcher restarts the bridge and the flight resumes", || {
        let e = events(&out);
        first_after(&e, "launcher", "process-restarted", killed_ns).is_some()
            && first_after(&e, "plant", "controller-recovered", killed_ns).is_some()
    });
    let e = events(&out);
    assert!(first_after(&e, "launcher", "process-died", killed_ns).is_some());
    assert!(first_after(&e, "plant", "failsafe-engaged", killed_ns).is_some(), "commands stopped meanwhile");
    let (status, text) = launcher.wait(Duration::from_secs(120));
    assert!(status.success(), "a restarted bridge is not a failed run: {text}");
    controller_host_ends(ctl, &mut bridge, &ctl_out);
    no_shared_memory_left(&run);
    for dir in [out, ctl_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// The controller ends with the flight; if it has not within 30 s, the test fails with what its host said: its
/// events (the controller's and the bridge's) and the bridge's output, once it is stopped.
fn controller_host_ends(mut ctl: Proc, bridge: &mut Proc, ctl_out: &Path) {
    if ctl.wait_ended(Duration::from_secs(30)) {
        return;
    }
    let events = std::fs::read_to_string(ctl_out.join("events.jsonl")).unwrap_or_default();
    bridge.signal(libc::SIGTERM);
    let (_, said) = std::mem::replace(bridge, Proc(None)).wait(Duration::from_secs(10));
    panic!(
        "the controller did not end within 30 s of the flight; its host's events:\n{events}\nits bridge said:\n{said}"
    );
}

impl Proc {
    /// Give it up to `limit` to end by itself (the run is over); whether it did (the drop kills it otherwise).
    fn wait_ended(&mut self, limit: Duration) -> bool {
        let start = Instant::now();
        while self.0.is_some() && self.running() && start.elapsed() < limit {
            std::thread::sleep(Duration::from_millis(20));
        }
        self.0.is_some() && !self.running()
    }
}

#[test]
fn an_unreachable_address_is_named() {
    let out = common::temp_dir("bridge", "unreachable");
    let run = run_id("unreachable");
    // Port 1 on the loopback: nobody listens there.
    let o = Command::new(BRIDGE)
        .args(["--connect", "127.0.0.1:1", "--connect-timeout-s", "1", "--run-id", &run, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{said}");
    assert!(said.contains("no plant-side bridge answered at tcp/127.0.0.1:1 within 1 s"), "{said}");
    assert!(said.contains("firewall"), "{said}");
    // In the events too: on the controller's host no launcher quotes the bridge's stderr.
    let failed = events(&out).into_iter().find(|e| e["kind"] == "bridge-failed").expect("a bridge-failed event");
    assert!(failed["detail"].as_str().unwrap().contains("no plant-side bridge answered"), "{failed}");
    let o = Command::new(BRIDGE).args(["--connect", "127.0.0.1", "--run-id", &run]).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("HOST:PORT"));
    no_shared_memory_left(&run);
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn another_run_id_and_a_second_controller_side_bridge_are_refused_while_the_plant_flies_on() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("c");
    let (run, out, ctl_out) = (run_id("refuse"), folder("refuse", "plant"), folder("refuse", "controller"));
    let launcher = plant_host(&hosts, &run, &out, "8");
    let bridge = controller_bridge(&hosts, &run, &ctl_out);
    let _ctl = controller(bridge.pid(), &run, &ctl_out);
    wait_for(Duration::from_secs(60), "the plant ticks", || has_event(&out, "plant", "ticking"));

    let other_out = folder("refuse", "other");
    let (status, said) = controller_bridge(&hosts, "someone-else", &other_out).wait(Duration::from_secs(30));
    assert_eq!(status.code(), Some(2), "{said}");
    assert!(said.contains(&format!("serves run `{run}`, not `someone-else`")), "{said}");

    // A second controller-side bridge of the run, as from a third host (its own mount namespace).
    let (status, said) = controller_bridge(&hosts, &run, &other_out).wait(Duration::from_secs(30));
    assert_eq!(status.code(), Some(2), "{said}");
    assert!(said.contains(&format!("run `{run}` already has a controller-side bridge")), "{said}");

    // A controller-side bridge that speaks another wire layout, as a build of another commit would (a test-only
    // setting makes it say so; the refusal is the real one).
    let other_build = [("SILRIG_BRIDGE_TEST_LAYOUT_VERSION", "999")];
    let (status, said) = controller_bridge_with(&hosts, &run, &other_out, &other_build).wait(Duration::from_secs(30));
    assert_eq!(status.code(), Some(2), "{said}");
    assert!(said.contains("speaks wire layout version") && said.contains("this build speaks 999"), "{said}");
    assert!(said.contains("build silrig on both hosts from the same commit"), "{said}");

    let (status, text) = launcher.wait(Duration::from_secs(120));
    assert!(status.success(), "{text}");
    let r = report(&out);
    let (ticks, misses) = (counter(&r, "plant", "ticks"), counter(&r, "plant", "command_misses"));
    assert!(misses * 100 <= ticks, "the first bridge's flight went on: {misses} of {ticks} missed; {text}");
    assert!(has_event(&out, "bridge", "bridge-peer-refused"));
    no_shared_memory_left(&run);
    for dir in [out, ctl_out, other_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Both hosts' halves on one machine (no network namespaces): the controller side in a namespace of its own
/// (`--local-run-id`), its controller started with the command the bridge prints. The flight is answered, the
/// controller's report comes back, and the controller-side bridge leaves nothing of its host's namespace.
#[test]
fn both_hosts_on_one_machine_fly_with_a_local_run_id_and_leave_nothing() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let (run, out, ctl_out) = (run_id("local"), folder("local", "plant"), folder("local", "controller"));
    let local = format!("{run}-c");
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let launcher = Proc::spawn(Command::new(SILRIG).args(["run", "--no-baseline", "--duration-s", "3"]).args([
        "--run-id",
        &run,
        "--out",
        out.to_str().unwrap(),
        "--bridge-listen",
        &addr,
    ]));
    let bridge = Proc::spawn(Command::new(BRIDGE).args(["--connect", &addr, "--run-id", &run]).args([
        "--local-run-id",
        &local,
        "--out",
        ctl_out.to_str().unwrap(),
    ]));
    wait_for(Duration::from_secs(30), "the controller-side bridge writes controller.env", || {
        ctl_out.join("controller.env").exists()
    });
    let env = std::fs::read_to_string(ctl_out.join("controller.env")).unwrap();
    assert!(env.contains(&format!("export SILRIG_RUN_ID='{local}'")), "{env}");
    let ctl = Proc::spawn(
        Command::new(CONTROLLER)
            .arg(ctl_out.join("scenario.toml"))
            .args(["--run-id", &local])
            .args(["--out", ctl_out.to_str().unwrap()]),
    );
    // Reaped as soon as it ends, before the bridge looks for live processes in its namespace.
    let (status, text) = ctl.wait(Duration::from_secs(60));
    assert!(status.success(), "{text}");
    let (status, text) = launcher.wait(Duration::from_secs(60));
    assert!(status.success(), "{text}");
    let (status, said) = bridge.wait(Duration::from_secs(30));
    assert!(status.success(), "{said}");
    let r = report(&out);
    assert_eq!(counter(&r, "plant", "ticks"), 301, "{text}");
    assert!(counter(&r, "plant", "command_misses") < 30, "{text}");
    let ctl_report = r["processes"].as_array().unwrap().iter().find(|p| p["process"] == "controller").unwrap();
    assert_eq!(ctl_report["run_id"], local.as_str(), "the controller's report came back from its host");
    no_shared_memory_left(&run);
    no_shared_memory_left(&local);
    for dir in [out, ctl_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// What [`stranger_peer`] is told, in [`STRANGER`]: where to connect, the run, the key (none: plain TCP) and how
/// long to try.
const STRANGER: &str = "SILRIG_TEST_STRANGER";

/// A raw Zenoh peer, as a stranger on the network would write one against a run whose id it knows: connects to the
/// plant's address, says hello as the run's controller-side bridge with a controller connected, publishes commands
/// with that hello's epoch, asks for the run's scenario and listens to every key of the run; prints what it got.
/// This test binary runs itself as that peer (`--exact stranger_peer`) in the controller's network namespace, with
/// [`STRANGER`] set; run without it, as by `cargo test`, it is not a test and returns at once.
#[test]
fn stranger_peer() {
    use silrig::bridge::frame::{CommandTrailer, Hello, Side};
    use silrig::bridge::zenoh::Wait;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, Ordering};
    let Ok(spec) = std::env::var(STRANGER) else { return };
    let spec: Value = serde_json::from_str(&spec).unwrap();
    let (endpoint, run) = (spec["endpoint"].as_str().unwrap(), spec["run"].as_str().unwrap().to_string());
    let key = spec["key"].as_str().map(|k| silrig::bridge::key::BridgeKey::read(Path::new(k)).unwrap());
    let session = silrig::bridge::net::open_session(Side::Controller, endpoint, key.as_ref()).unwrap();
    let samples = Arc::new(AtomicU64::new(0));
    let counted = samples.clone();
    let _all = session
        .declare_subscriber(format!("silrig/{run}/**"))
        .callback(move |sample| {
            // Its own puts come back to it: only what the plant side sent counts.
            let key = sample.key_expr().as_str();
            if !key.ends_with("/command") && !key.ends_with("/hello/controller") {
                counted.fetch_add(1, Ordering::Relaxed);
            }
        })
        .wait()
        .unwrap();
    let epoch = 0x5157_4e47_4552_0001;
    let layout_version = silrig::wire::WIRE_LAYOUT_VERSION;
    let hello = Hello {
        side: Side::Controller,
        run_id: run.clone(),
        layout_version,
        epoch,
        serving: None,
        controller_connected: true,
    };
    let trailer = CommandTrailer { bridge_epoch: epoch, residence_ns: 1 }.to_bytes().to_vec();
    let (mut replies, start) = (0, Instant::now());
    while start.elapsed().as_secs_f64() < spec["seconds"].as_f64().unwrap() {
        let _ = session.put(format!("silrig/{run}/hello/controller"), hello.to_bytes()).wait();
        let _ = session.put(format!("silrig/{run}/command"), vec![0xab; 64]).attachment(trailer.clone()).wait();
        if let Ok(answers) = session.get(format!("silrig/{run}/run")).timeout(Duration::from_millis(100)).wait() {
            while let Ok(answer) = answers.recv() {
                replies += usize::from(answer.result().is_ok());
            }
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    println!("STRANGER {}", serde_json::json!({"samples": samples.load(Ordering::Relaxed), "run_infos": replies}));
}

/// [`stranger_peer`] from the controller's host for `seconds`, with `key` or none; what it got.
fn stranger(hosts: &Hosts, run: &str, key: Option<&Path>, seconds: f64) -> Value {
    let endpoint = if key.is_some() { format!("tls/{PLANT_ADDR}") } else { format!("tcp/{PLANT_ADDR}") };
    let spec = serde_json::json!({"endpoint": endpoint, "run": run, "key": key, "seconds": seconds});
    let exe = std::env::current_exe().unwrap();
    let o = Command::new("ip")
        .args(["netns", "exec", &hosts.controller])
        .arg(exe)
        .args(["--exact", "stranger_peer", "--nocapture", "--test-threads", "1"])
        .env(STRANGER, spec.to_string())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    // After the harness's "test stranger_peer ... " on the same line.
    let line = text.lines().find_map(|l| l.split_once("STRANGER ")).unwrap_or_else(|| panic!("{text}")).1;
    serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {text}"))
}

fn peer_joins(out: &Path) -> usize {
    events(out).iter().filter(|e| e["process"] == "bridge" && e["kind"] == "bridge-peer-joined").count()
}

/// A run flying with its controller behind the key; strangers from the network knock: our own bridge without a key
/// (refused before it tries), with `--insecure` (plain TCP: the plant side refuses the link) and with another key
/// (stopped at once, in words, on both hosts), and a raw Zenoh peer without the key and with another one, which
/// says hello as the run's controller side, publishes commands and listens to every key: it reads nothing, its
/// hello and commands never reach the plant side, the plant side's only peer is the run's own bridge. The same raw
/// peer with the run's key does read samples and is heard (refused as a second controller side), so the test sees
/// a peer that gets in.
#[test]
fn a_stranger_without_the_key_can_neither_join_nor_read_nor_command_and_a_wrong_key_is_named_on_both_hosts() {
    let _one = ONE_RIG.lock().unwrap_or_else(|e| e.into_inner());
    let hosts = Hosts::new("s");
    let (run, out, ctl_out) = (run_id("stranger"), folder("stranger", "plant"), folder("stranger", "controller"));
    let launcher = plant_host(&hosts, &run, &out, "14");
    let bridge = controller_bridge(&hosts, &run, &ctl_out);
    let _ctl = controller(bridge.pid(), &run, &ctl_out);
    wait_for(Duration::from_secs(60), "the plant ticks", || has_event(&out, "plant", "ticking"));
    let log = || std::fs::read_to_string(out.join("bridge.stderr.log")).unwrap_or_default();
    let other_out = folder("stranger", "other");
    let timeout = ["--connect-timeout-s", "3"];

    // No key: refused before it tries, saying what the key is for and how to make one.
    let (status, said) = Proc::spawn(&mut third_host(&hosts, &timeout, &run, &other_out)).wait(Duration::from_secs(30));
    assert_eq!(status.code(), Some(2), "{said}");
    assert!(said.contains("refused to connect to tcp/10.217.0.1:7447 without a bridge key"), "{said}");
    assert!(said.contains("silrig-bridge keygen") && said.contains("--insecure"), "{said}");

    // --insecure, plain TCP: the plant side takes no link that is not TLS with the key.
    let insecure = [&timeout[..], &["--insecure"]].concat();
    let (status, said) =
        Proc::spawn(&mut third_host(&hosts, &insecure, &run, &other_out)).wait(Duration::from_secs(30));
    assert_eq!(status.code(), Some(2), "{said}");
    assert!(said.contains("NO bridge key") && said.contains("no plant-side bridge answered"), "{said}");
    assert!(!other_out.join("scenario.toml").exists(), "the stranger read the run's scenario");
    wait_for(Duration::from_secs(10), "the plant side says it refused a link without TLS", || {
        log().contains("refused a connection from the network") && log().contains("did not speak TLS")
    });

    // Another key: stopped at once, in words, on both hosts.
    let wrong = keygen("stranger-wrong");
    let with_wrong = [&timeout[..], &["--key", wrong.to_str().unwrap()]].concat();
    let started = Instant::now();
    let (status, said) =
        Proc::spawn(&mut third_host(&hosts, &with_wrong, &run, &other_out)).wait(Duration::from_secs(30));
    assert_eq!(status.code(), Some(2), "{said}");
    assert!(said.contains("holds another bridge key, or refused this one"), "{said}");
    assert!(said.contains("give both hosts the same key file"), "{said}");
    eprintln!("a wrong key stopped the controller side after {:.1} s: {said}", started.elapsed().as_secs_f64());
    wait_for(Duration::from_secs(10), "the plant side says a peer without the key knocked", || {
        log().contains("does not hold this run's bridge key")
    });

    // A raw Zenoh peer without the key, then with another: reads nothing, heard by nobody.
    for key in [None, Some(wrong.as_path())] {
        let got = stranger(&hosts, &run, key, 2.0);
        assert_eq!(got["samples"], 0, "a stranger ({key:?}) read the run: {got}");
        assert_eq!(got["run_infos"], 0, "a stranger ({key:?}) read the run's scenario: {got}");
    }
    assert_eq!(peer_joins(&out), 1, "only the run's own controller side joined: {:?}", events(&out));
    assert!(!has_event(&out, "bridge", "bridge-peer-refused"), "a stranger's hello reached the plant side");

    // The same peer with the run's key gets in: it reads, and its hello is heard (and refused: one controller).
    let got = stranger(&hosts, &run, Some(&hosts.key), 2.0);
    assert!(got["samples"].as_u64().unwrap() > 0 && got["run_infos"].as_u64().unwrap() > 0, "{got}");
    assert!(has_event(&out, "bridge", "bridge-peer-refused"), "the keyed peer's hello was not heard");

    let (status, text) = launcher.wait(Duration::from_secs(120));
    assert!(status.success(), "{text}");
    let r = report(&out);
    let (ticks, misses) = (counter(&r, "plant", "ticks"), counter(&r, "plant", "command_misses"));
    // The strangers cost the flight nothing it would notice: its ticks, and its misses within what a loaded machine
    // gives any flight across the bridge (4 % at a load average of 32 on 2 CPUs, steady from the first second).
    assert_eq!(ticks, 1401, "{text}");
    assert!(misses * 10 <= ticks, "the run's own flight went on: {misses} of {ticks} missed; {text}");
    // Only the keyed peer's commands reached the plant side at all, and none was passed to the plant.
    assert!(counter(&r, "bridge", "samples_from_unserved_bridges") > 0, "{text}");
    assert!(counter(&r, "bridge", "connections_refused") >= 2, "{text}");
    assert!(counter(&r, "bridge", "commands_in") <= ticks, "{text}");
    no_shared_memory_left(&run);
    for dir in [out, ctl_out, other_out] {
        let _ = std::fs::remove_dir_all(dir);
    }
    let _ = std::fs::remove_file(wrong);
}

/// Without a key a bridge serves the loopback only, unless told `--insecure`; a key others can read, or one over
/// UDP, is refused; `silrig run --bridge-listen` says each before anything starts. No namespaces needed.
#[test]
fn without_a_key_only_the_loopback_is_served_and_a_key_others_can_read_is_refused() {
    let run = run_id("nokey");
    let check = |args: &[&str]| {
        let o = Command::new(BRIDGE).args(["--check", "--run-id", &run]).args(args).output().unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).to_string())
    };
    let (code, said) = check(&["--listen", "0.0.0.0:7447"]);
    assert_eq!(code, Some(2), "{said}");
    assert!(said.contains("refused to listen on tcp/0.0.0.0:7447 without a bridge key"), "{said}");
    assert!(said.contains(&format!("could join run `{run}` as its controller")), "{said}");
    let (code, said) = check(&["--listen", "127.0.0.1:7447"]);
    assert_eq!(code, Some(0), "{said}");
    assert!(said.contains("no bridge key, on the loopback"), "{said}");
    let (code, said) = check(&["--listen", "0.0.0.0:7447", "--insecure"]);
    assert_eq!(code, Some(0), "{said}");
    assert!(said.contains("NO bridge key (--insecure)"), "{said}");

    let key = keygen("nokey");
    let (code, said) = check(&["--listen", "0.0.0.0:7447", "--key", key.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{said}");
    assert!(said.contains("would listen on tls/0.0.0.0:7447 with TLS with bridge key"), "{said}");
    let (code, said) = check(&["--listen", "udp/0.0.0.0:7447", "--key", key.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{said}");
    assert!(said.contains("needs TCP"), "{said}");
    let o = Command::new(BRIDGE).arg("keygen").arg(&key).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("never overwritten"));

    // silrig run says it before anything starts, in the bridge's words, and leaves no folder.
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o644)).unwrap();
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("bridge-{}-nokey-run", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run_with = |flags: &[&str]| {
        let o = Command::new(SILRIG)
            .args(["run", "--no-baseline", "--run-id", &run, "--out", out.to_str().unwrap()])
            .args(["--bridge-listen", "0.0.0.0:7447"])
            .args(flags)
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).to_string())
    };
    let (code, said) = run_with(&[]);
    assert_eq!(code, Some(2), "{said}");
    assert!(
        said.contains("--bridge-listen 0.0.0.0:7447: refused to listen on") && said.contains("--bridge-key"),
        "{said}"
    );
    let (code, said) = run_with(&["--bridge-key", key.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{said}");
    assert!(said.contains("its group or others may read it (mode 644)") && said.contains("chmod 600"), "{said}");
    assert!(!out.exists(), "a refused run left its folder");
    no_shared_memory_left(&run);
    let _ = std::fs::remove_file(key);
}
