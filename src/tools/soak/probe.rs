//! What the soak measures of the run's processes from outside, through `/proc`: each long-lived process's
//! resident memory, open file descriptors and the run's shared-memory files it holds (mapped or open), the run's
//! `/dev/shm` entries, and what of the run is left once it has ended (processes, shared memory, lock files).

use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::Path;

/// One process as measured at one moment.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ProcessProbe {
    /// `launcher`, `plant`, `controller`, `logger`, `timer-baseline`, or the program's name.
    pub process: String,
    /// Its pid at that moment (a restarted process has another at the end).
    pub pid: u32,
    /// Resident set size, KiB (`VmRSS`).
    pub rss_kib: u64,
    /// Open file descriptors.
    pub fds: u64,
    /// The run's `/dev/shm` files it has mapped or open.
    pub shm_files: u64,
    /// Their names.
    pub shm_names: Vec<String>,
}

/// Each process's life as measured: settled (after its start-up) and last seen before the run's end. A restarted
/// process is a new life, which may hold other files than its predecessor (a restarted plant maps two more
/// shared-memory files than the first from its start, and keeps them); growth is judged within a life.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct LifeProbe {
    /// The process.
    pub process: String,
    /// Its pid.
    pub pid: u32,
    /// When it was first seen, wall s from the plant's tick 0.
    pub first_seen_s: f64,
    /// As measured once settled (SETTLE_S after it was first seen).
    pub settled: ProcessProbe,
    /// As measured last.
    pub last: ProcessProbe,
    /// As measured the look before the last (None: seen once).
    #[serde(default)]
    pub before_last: Option<ProcessProbe>,
}

impl LifeProbe {
    /// What the life held to its end: the descriptors and shared-memory files of its last two looks, the fewer of
    /// each. A life the plan ends writes its report and checkpoint on the way out, and a look that lands then finds a
    /// file more (seed 1's hour of 2026-11-29: one controller life of 182, SIGTERMed, held 53 against 52); a leak
    /// holds it at both.
    pub fn held_to_the_end(&self) -> (u64, u64) {
        let before = self.before_last.as_ref().unwrap_or(&self.last);
        (self.last.fds.min(before.fds), self.last.shm_files.min(before.shm_files))
    }
}

/// A life is measured as settled this long after it was first seen, s: after its start-up, before the next fault.
pub const SETTLE_S: f64 = 2.0;

/// Every life seen while a run went.
#[derive(Debug, Default)]
pub struct Lives {
    lives: std::collections::BTreeMap<u32, Life>,
}

/// One life as seen so far: first seen at (s), settled, the look before the last, the last.
type Life = (f64, Option<ProcessProbe>, Option<ProcessProbe>, ProcessProbe);

impl Lives {
    /// Take in a measurement of the run's processes at `now_s` (wall s from tick 0).
    pub fn observe(&mut self, probes: &[ProcessProbe], now_s: f64) {
        for p in probes {
            let life = self.lives.entry(p.pid).or_insert_with(|| (now_s, None, None, p.clone()));
            if life.1.is_none() && now_s >= life.0 + SETTLE_S {
                life.1 = Some(p.clone());
            }
            life.2 = Some(std::mem::replace(&mut life.3, p.clone()));
        }
    }

    /// The lives that were measured settled, by first sight.
    pub fn into_vec(self) -> Vec<LifeProbe> {
        let mut v: Vec<LifeProbe> = self
            .lives
            .into_iter()
            .filter_map(|(pid, (first_seen_s, settled, before_last, last))| {
                let process = last.process.clone();
                Some(LifeProbe { process, pid, first_seen_s, settled: settled?, last, before_last })
            })
            .collect();
        v.sort_by(|a, b| a.first_seen_s.total_cmp(&b.first_seen_s));
        v
    }
}

/// The launcher and each of its children.
pub fn probe_run(launcher_pid: u32, shm_prefix: &str) -> Vec<ProcessProbe> {
    let mut out: Vec<ProcessProbe> = probe(launcher_pid, "launcher", shm_prefix).into_iter().collect();
    for pid in children(launcher_pid) {
        if let Some(p) = probe(pid, &process_name(pid), shm_prefix) {
            out.push(p);
        }
    }
    out
}

/// Pids whose parent is `parent` (zombies left out).
pub fn children(parent: u32) -> Vec<u32> {
    let Ok(dir) = std::fs::read_dir("/proc") else { return Vec::new() };
    dir.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| stat(*pid).is_some_and(|(state, ppid)| ppid == parent && state != 'Z'))
        .collect()
}

/// `pid` and its ancestors up to init, by their parents in `/proc`.
pub fn lineage(pid: u32) -> BTreeSet<u32> {
    let mut line = BTreeSet::from([pid]);
    let mut at = pid;
    while let Some((_, parent)) = stat(at).filter(|(_, parent)| *parent > 0 && line.insert(*parent)) {
        at = parent;
    }
    line
}

/// (state, ppid) from `/proc/<pid>/stat` (the command name may hold spaces and parentheses: read past the last `)`).
fn stat(pid: u32) -> Option<(char, u32)> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let mut rest = text[text.rfind(')')? + 1..].split_whitespace();
    let state = rest.next()?.chars().next()?;
    Some((state, rest.next()?.parse().ok()?))
}

/// A process of the rig by its role: `silrig-plant` is `plant`; `silrig timer-baseline` is `timer-baseline`.
fn process_name(pid: u32) -> String {
    let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
    let args: Vec<String> = cmdline.split(|b| *b == 0).map(|a| String::from_utf8_lossy(a).into_owned()).collect();
    let program = args.first().map(|a| a.rsplit('/').next().unwrap_or(a).to_string()).unwrap_or_default();
    match program.strip_prefix("silrig-") {
        Some(role) => role.to_string(),
        None if program == "silrig" => args.get(1).cloned().unwrap_or(program),
        None => program,
    }
}

/// Measure process `pid` as `name`, counting the shared-memory files whose names start with `shm_prefix` (None:
/// it has gone).
pub fn probe(pid: u32, name: &str, shm_prefix: &str) -> Option<ProcessProbe> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let rss_kib = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    let fd_links: Vec<String> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .ok()?
        .filter_map(|e| Some(std::fs::read_link(e.ok()?.path()).ok()?.to_string_lossy().into_owned()))
        .collect();
    let shm = format!("/dev/shm/{shm_prefix}");
    // A file removed while still open or mapped shows as "<path> (deleted)": the same file.
    let file = |l: &str| l.trim_end_matches(" (deleted)").trim_start_matches("/dev/shm/").to_string();
    let mut files: BTreeSet<String> = fd_links.iter().filter(|l| l.starts_with(&shm)).map(|l| file(l)).collect();
    let maps = std::fs::read_to_string(format!("/proc/{pid}/maps")).unwrap_or_default();
    files.extend(maps.lines().filter_map(|l| l.find(&shm).map(|i| file(&l[i..]))));
    Some(ProcessProbe {
        process: name.to_string(),
        pid,
        rss_kib,
        fds: fd_links.len() as u64,
        shm_files: files.len() as u64,
        shm_names: files.into_iter().collect(),
    })
}

/// The run's entries in `/dev/shm` (names starting with `shm_prefix`).
pub fn shm_entries(shm_prefix: &str) -> Vec<String> {
    let Ok(dir) = std::fs::read_dir("/dev/shm") else { return Vec::new() };
    let mut names: Vec<String> = dir
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .filter(|n| n.starts_with(shm_prefix))
        .collect();
    names.sort();
    names
}

/// Every process of a run the soak saw, by pid, with the time it started (clock ticks since boot, `/proc/<pid>/stat`
/// field 22): a pid an hour's soak saw may belong to another process by its end (pids wrap; one soak blamed two
/// processes of a test run that had taken them), and only the same start time is the same process.
pub type SeenPids = std::collections::BTreeMap<u32, u64>;

/// Note `pid` as seen, with its start time when first seen (0 when it has gone already: never a leftover then).
pub fn note_seen(seen: &mut SeenPids, pid: u32) {
    seen.entry(pid).or_insert_with(|| start_time(pid).unwrap_or(0));
}

/// When process `pid` started, clock ticks since boot.
fn start_time(pid: u32) -> Option<u64> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    text[text.rfind(')')? + 1..].split_whitespace().nth(19)?.parse().ok()
}

/// What of a run is left after it ended: processes still alive among `pids` (every process of the run the soak
/// saw) or naming the run id on their command line, its `/dev/shm` entries, its lock files and iceoryx2 folder.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Leftovers {
    /// Live processes of the run: "pid (name)".
    pub processes: Vec<String>,
    /// `/dev/shm` entries of the run.
    pub shm_files: Vec<String>,
    /// Lock files and the iceoryx2 folder of the run.
    pub lock_files: Vec<String>,
}

impl Leftovers {
    /// Look for what `run_id` (run folder `out`) left; `seen`: every process of the run seen while it ran.
    pub fn find(run_id: &str, out: &Path, seen: &SeenPids) -> Leftovers {
        let mut processes: BTreeSet<String> = BTreeSet::new();
        for (&pid, &started) in seen {
            let same = started != 0 && start_time(pid) == Some(started);
            if same && stat(pid).is_some_and(|(state, _)| state != 'Z') {
                processes.insert(format!("{pid} ({})", process_name(pid)));
            }
        }
        // The soak and whatever started it (`timeout`, `/usr/bin/time`, a CI runner's shell) may name the run id
        // too, and are alive by design: only what the run started counts.
        let mine = lineage(std::process::id());
        if let Ok(dir) = std::fs::read_dir("/proc") {
            let all = dir.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok());
            for pid in all.filter(|p| !mine.contains(p)) {
                let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
                let named = cmdline.split(|b| *b == 0).any(|a| a == run_id.as_bytes());
                if named && stat(pid).is_some_and(|(state, _)| state != 'Z') {
                    processes.insert(format!("{pid} ({})", process_name(pid)));
                }
            }
        }
        let lock_files = [
            format!("/tmp/silrig_{run_id}.lock"),
            out.join(".silrig-run.lock").to_string_lossy().into_owned(),
            format!("{}/silrig_{run_id}", silrig_wire::ipc::SHM_DIR),
        ]
        .into_iter()
        .filter(|p| Path::new(p).exists())
        .collect();
        Leftovers {
            processes: processes.into_iter().collect(),
            shm_files: shm_entries(&format!("sr_{run_id}_")),
            lock_files,
        }
    }

    /// What is left, in words (empty when nothing is).
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if !self.processes.is_empty() {
            parts.push(format!("processes of the run still alive: {}", self.processes.join(", ")));
        }
        if !self.shm_files.is_empty() {
            parts.push(format!("shared-memory files in /dev/shm: {}", self.shm_files.join(", ")));
        }
        if !self.lock_files.is_empty() {
            parts.push(format!("lock files and folders: {}", self.lock_files.join(", ")));
        }
        parts.join("; ")
    }

    /// Add what another namespace of the run left (the controller's host of a soak with the bridge).
    pub fn extend(&mut self, other: Leftovers) {
        self.processes.extend(other.processes);
        self.shm_files.extend(other.shm_files);
        self.lock_files.extend(other.lock_files);
    }

    /// How many things are left in all.
    pub fn count(&self) -> usize {
        self.processes.len() + self.shm_files.len() + self.lock_files.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn look(fds: u64, shm_files: u64) -> ProcessProbe {
        let process = "controller".to_string();
        ProcessProbe { process, pid: 7, rss_kib: 1, fds, shm_files, shm_names: Vec::new() }
    }

    #[test]
    fn a_file_held_at_one_look_on_the_way_out_is_not_a_leak_one_held_at_two_is() {
        let life = |looks: &[(f64, u64)]| {
            let mut lives = Lives::default();
            looks.iter().for_each(|&(t, fds)| lives.observe(&[look(fds, 22)], t));
            lives.into_vec().remove(0)
        };
        // Settled at 52; the last look, while the plan's SIGTERM ends it, finds 53.
        let ending = life(&[(0.0, 50), (2.0, 52), (2.25, 52), (2.5, 53)]);
        assert_eq!((ending.settled.fds, ending.last.fds, ending.held_to_the_end()), (52, 53, (52, 22)));
        // Held at both last looks: it grew.
        assert_eq!(life(&[(0.0, 52), (2.0, 52), (2.25, 53), (2.5, 53)]).held_to_the_end(), (53, 22));
        // Seen once only: never settled, not judged.
        let mut once = Lives::default();
        once.observe(&[look(52, 22)], 0.0);
        assert!(once.into_vec().is_empty());
    }

    #[test]
    fn a_process_is_measured_and_its_children_found() {
        let me = std::process::id();
        let p = probe(me, "me", "no-such-prefix-").unwrap();
        assert!(p.rss_kib > 0 && p.fds >= 3, "{p:?}");
        assert_eq!(p.shm_files, 0);
        let mut child = std::process::Command::new("sleep").arg("30").spawn().unwrap();
        let found = children(me).contains(&child.id());
        child.kill().unwrap();
        child.wait().unwrap();
        assert!(found);
        assert!(!process_name(me).is_empty());
    }

    #[test]
    fn what_started_the_soak_is_never_a_leftover_though_it_names_the_run_id() {
        let me = std::process::id();
        let line = lineage(me);
        assert!(line.contains(&me) && line.contains(&1), "up to init: {line:?}");
        assert!(line.contains(&stat(me).unwrap().1), "the parent: {line:?}");
        // A process that names the run id and is not of the soak's lineage is one.
        let run_id = format!("leftover-test-{me}");
        let mut stray =
            std::process::Command::new("python3").args(["-c", "import time; time.sleep(30)", &run_id]).spawn().unwrap();
        // Until it has exec'd, the child's command line is this test's.
        let named = || std::fs::read(format!("/proc/{}/cmdline", stray.id())).unwrap_or_default();
        let start = std::time::Instant::now();
        while !named().split(|b| *b == 0).any(|a| a == run_id.as_bytes()) {
            assert!(start.elapsed() < std::time::Duration::from_secs(10), "the stray process never started");
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        let out = std::env::temp_dir();
        let left = Leftovers::find(&run_id, &out, &SeenPids::new());
        stray.kill().unwrap();
        stray.wait().unwrap();
        // By its program's name (python3, or the launcher of a python3 shim).
        assert!(left.processes.len() == 1 && left.processes[0].starts_with(&format!("{} (", stray.id())), "{left:?}");
        let said = left.describe();
        assert!(said.starts_with("processes of the run still alive: ") && !said.contains('{'), "{said}");
        assert_eq!(Leftovers::default().describe(), "");
    }

    #[test]
    fn a_pid_seen_during_the_run_is_a_leftover_only_while_it_is_the_same_process() {
        let mut sleeper = std::process::Command::new("sleep").arg("30").spawn().unwrap();
        let pid = sleeper.id();
        let mut seen = SeenPids::new();
        note_seen(&mut seen, pid);
        let out = std::env::temp_dir();
        let left = Leftovers::find("pid-reuse-test", &out, &seen);
        assert!(left.processes.len() == 1 && left.processes[0].starts_with(&format!("{pid} (")), "{left:?}");
        // The same pid with another start time: another process that took the pid since (pids wrap in an hour).
        let reused = SeenPids::from([(pid, seen[&pid] + 1)]);
        assert!(Leftovers::find("pid-reuse-test", &out, &reused).processes.is_empty());
        sleeper.kill().unwrap();
        sleeper.wait().unwrap();
    }
}
