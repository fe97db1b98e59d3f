//! Live status of a running rig: each process's snapshot (tick, simulated time, counters, p99 so far of each of its
//! distributions), written about once a second by a thread of its own at normal priority, atomically, to
//! `/dev/shm/silrig_<run>/status/<process>.json`. The real-time loop only hands values over through a bounded channel
//! (never blocking: a full channel drops the value from the live figure, never from the report), so watching costs
//! the loop nothing. The folder is inside the run's iceoryx2 root, so the run's cleanup removes it with the rest;
//! `silrig run`'s live line and `silrig top` only read it.

use serde::{Deserialize, Serialize};
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::RunId;
use silrig_wire::timing::LatencyHistogram;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError};
use std::time::Duration;

/// A snapshot is written this often, ns.
pub const STATUS_EVERY_NS: u64 = 1_000_000_000;
/// The status thread takes what the loop handed over this often, so the channel never fills at 100 Hz and rarely
/// in lockstep.
const DRAIN_EVERY: Duration = Duration::from_millis(50);
/// Values the channel holds between two drains.
const CHANNEL_VALUES: usize = 4096;

/// One process's status, as written to its file.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ProcessStatus {
    /// plant, controller or logger.
    pub process: String,
    /// Process id.
    pub pid: u32,
    /// The newest tick the process handled.
    pub tick: u64,
    /// Simulated time of that tick, s.
    pub sim_s: f64,
    /// The scenario's duration, s.
    pub duration_s: f64,
    /// The 99th percentile so far of each distribution with values (short name, e.g. `wake_lateness`), µs.
    pub p99_us: BTreeMap<String, f64>,
    /// The process's counters so far.
    pub counters: BTreeMap<String, u64>,
    /// Plant: flying the failsafe surfaces now.
    pub failsafe: bool,
    /// When the snapshot was taken, CLOCK_MONOTONIC ns.
    pub taken_ns: u64,
}

/// The folder of a run's status files.
pub fn status_dir(run: &RunId) -> PathBuf {
    run.root_dir().join("status")
}

enum Update {
    Value { index: usize, ns: i64 },
    Snapshot(Box<ProcessStatus>),
}

/// The loop's end of the status channel (owned by the process's [`super::report::Recorder`]).
#[derive(Debug)]
pub struct StatusFeed {
    tx: Option<SyncSender<Update>>,
    thread: Option<std::thread::JoinHandle<()>>,
    next_snapshot_ns: u64,
}

impl StatusFeed {
    /// A feed for `process` of `run`, with the names of its distributions (in [`super::report::Recorder`] order);
    /// starts the writer thread.
    pub fn start(run: &RunId, process: &str, distributions: Vec<String>) -> Self {
        let (tx, rx) = std::sync::mpsc::sync_channel(CHANNEL_VALUES);
        let dir = status_dir(run);
        let path = dir.join(format!("{process}.json"));
        let thread = std::thread::Builder::new()
            .name("status".into())
            .stack_size(256 * 1024)
            .spawn(move || {
                silrig_wire::clock::leave_realtime_scheduling();
                write_statuses(rx, &dir, &path, distributions);
            })
            .ok();
        Self { tx: Some(tx), thread, next_snapshot_ns: 0 }
    }

    /// Hand a value of distribution `index` over (never blocks).
    #[inline]
    pub fn value(&self, index: usize, ns: i64) {
        if let Some(tx) = &self.tx {
            let _ = tx.try_send(Update::Value { index, ns });
        }
    }

    /// Whether a snapshot is due (at most one a second).
    #[inline]
    pub fn snapshot_due(&self) -> bool {
        monotonic_ns() >= self.next_snapshot_ns
    }

    /// Hand a snapshot over (the thread adds the percentiles); never blocks.
    pub fn snapshot(&mut self, status: ProcessStatus) {
        self.next_snapshot_ns = monotonic_ns() + STATUS_EVERY_NS;
        if let Some(tx) = &self.tx {
            let _ = tx.try_send(Update::Snapshot(Box::new(status)));
        }
    }
}

impl Drop for StatusFeed {
    /// Ends the thread and waits for it, so no status file is written after the process's own cleanup. The thread
    /// is woken rather than waited out (it sleeps up to [`DRAIN_EVERY`] between drains): a process's end, and so
    /// every case of a sweep, would otherwise wait 25 ms on average for it.
    fn drop(&mut self) {
        self.tx.take();
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

fn write_statuses(rx: Receiver<Update>, dir: &Path, path: &Path, distributions: Vec<String>) {
    let mut histograms: Vec<LatencyHistogram> = distributions.iter().map(|_| LatencyHistogram::new()).collect();
    let mut latest: Option<Box<ProcessStatus>> = None;
    loop {
        let mut open = true;
        loop {
            match rx.try_recv() {
                Ok(Update::Value { index, ns }) => {
                    if let Some(h) = histograms.get_mut(index) {
                        h.record_ns(ns);
                    }
                }
                Ok(Update::Snapshot(s)) => latest = Some(s),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    open = false;
                    break;
                }
            }
        }
        if let Some(mut status) = latest.take() {
            for (name, h) in distributions.iter().zip(&histograms) {
                if h.count() > 0 {
                    status.p99_us.insert(name.clone(), h.value_at_quantile_ns(0.99) as f64 / 1e3);
                }
            }
            // Only inside a run's root that exists: a run already cleaned up gets no folder back.
            if dir.parent().is_some_and(Path::is_dir) {
                let _ = std::fs::create_dir(dir);
                if let Ok(text) = serde_json::to_string(&status) {
                    let _ = silrig_flight::files::write_atomically(path, &text);
                }
            }
        }
        if !open {
            return;
        }
        // Woken early by the feed's drop (a spurious wake-up only drains again).
        std::thread::park_timeout(DRAIN_EVERY);
    }
}

/// The status files of a run, by process (empty when the run has none, or none yet).
pub fn read_statuses(run: &RunId) -> Vec<ProcessStatus> {
    let mut statuses: Vec<ProcessStatus> = std::fs::read_dir(status_dir(run))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
        .filter_map(|e| serde_json::from_str(&std::fs::read_to_string(e.path()).ok()?).ok())
        .collect();
    let order = |p: &ProcessStatus| silrig_flight::role::Role::ALL.iter().position(|r| r.label() == p.process);
    statuses.sort_by_key(order);
    statuses
}

/// The runs of this machine that have status files now (what `silrig top` can attach to).
pub fn live_runs() -> Vec<String> {
    let mut runs: Vec<String> = std::fs::read_dir(silrig_wire::ipc::SHM_DIR)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let run = name.strip_prefix("silrig_")?.to_string();
            e.path().join("status").is_dir().then_some(run)
        })
        .collect();
    runs.sort();
    runs
}

fn counter(s: &ProcessStatus, name: &str) -> u64 {
    s.counters.get(name).copied().unwrap_or(0)
}

/// Samples lost so far, over every stream and reader.
fn lost(statuses: &[ProcessStatus]) -> u64 {
    let names = ["commands_lost", "plant_samples_lost", "command_samples_lost"];
    statuses.iter().map(|s| names.iter().map(|n| counter(s, n)).sum::<u64>()).sum()
}

/// The launcher's live line: sim time, ticks, the plant's wake-up p99 so far, misses, lost samples, failsafe state
/// and restarts (`restarts` from the launcher, which sees every life).
pub fn live_line(statuses: &[ProcessStatus], restarts: u32) -> Option<String> {
    let plant = statuses.iter().find(|s| s.process == "plant")?;
    let wake = plant.p99_us.get("wake_lateness").map_or("-".to_string(), |p| format!("{p:.0} us"));
    Some(format!(
        "t {:.1}/{:.1} s  ticks {}  wake p99 {wake}  misses {}  lost {}  failsafe {}  restarts {restarts}",
        plant.sim_s,
        plant.duration_s,
        counter(plant, "ticks"),
        counter(plant, "command_misses"),
        lost(statuses),
        if plant.failsafe { "ON" } else { "off" },
    ))
}

/// `silrig top`'s view: one block per process, its counters and p99s so far, and how old its snapshot is.
pub fn top_text(run: &str, statuses: &[ProcessStatus]) -> String {
    let now = monotonic_ns();
    let mut out = format!("silrig top {run}: {} process(es) reporting\n", statuses.len());
    for s in statuses {
        let age_s = now.saturating_sub(s.taken_ns) as f64 / 1e9;
        out += &format!(
            "  {:<10} pid {:<7} tick {:<7} t {:.2}/{:.2} s{}  (snapshot {age_s:.1} s old)\n",
            s.process,
            s.pid,
            s.tick,
            s.sim_s,
            s.duration_s,
            if s.failsafe { "  FAILSAFE" } else { "" }
        );
        let p99: Vec<String> = s.p99_us.iter().map(|(k, v)| format!("{k} {v:.1}")).collect();
        if !p99.is_empty() {
            out += &format!("  {:<10} p99 (us): {}\n", "", p99.join(", "));
        }
        let counters: Vec<String> = s.counters.iter().map(|(k, v)| format!("{k} {v}")).collect();
        out += &format!("  {:<10} {}\n", "", counters.join(", "));
    }
    out
}

/// `silrig top RUN_ID`: print the run's processes' status every second (redrawn in place on a terminal) until the
/// run ends, or `iterations` times. Reads files only: attaching creates nothing and touches no iceoryx2 resource.
pub fn top(run: &RunId, iterations: Option<u64>) -> anyhow::Result<()> {
    use std::io::{IsTerminal, Write};
    if !status_dir(run).is_dir() {
        let runs = live_runs();
        let seen = if runs.is_empty() { "none".to_string() } else { runs.join(", ") };
        anyhow::bail!("no running rig with run id `{run}` on this machine; running rigs it can see: {seen}");
    }
    let tty = std::io::stdout().is_terminal();
    let mut shown = 0u64;
    let mut lines_drawn = 0usize;
    loop {
        let statuses = read_statuses(run);
        if !status_dir(run).is_dir() {
            println!("run {run} has ended");
            return Ok(());
        }
        let text = top_text(run.as_str(), &statuses);
        let mut stdout = std::io::stdout().lock();
        if tty && lines_drawn > 0 {
            // Back to the top of the last drawing, and clear below.
            write!(stdout, "\x1b[{lines_drawn}A\x1b[J")?;
        }
        write!(stdout, "{text}")?;
        if !tty {
            writeln!(stdout)?;
        }
        stdout.flush()?;
        lines_drawn = text.lines().count();
        shown += 1;
        if iterations.is_some_and(|n| shown >= n) || crate::signals::termination_requested() {
            return Ok(());
        }
        std::thread::sleep(Duration::from_secs(1));
    }
}

/// `silrig run`'s live line, once a second from the processes' status files: redrawn in place on a terminal,
/// one line a second otherwise (a CI log), on stderr, so the report on stdout stays as it was.
pub struct LiveLine {
    run: RunId,
    bar: Option<indicatif::ProgressBar>,
    next_ns: u64,
}

impl LiveLine {
    /// A live line for `run`.
    pub fn new(run: &RunId) -> Self {
        use std::io::IsTerminal;
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new_spinner();
            bar.set_style(indicatif::ProgressStyle::with_template("{msg}").expect("a constant template"));
            bar
        });
        Self { run: run.clone(), bar, next_ns: monotonic_ns() + STATUS_EVERY_NS }
    }

    /// Show the line if a second has passed since the last (`restarts` as the launcher counts them).
    pub fn update(&mut self, restarts: u32) {
        if monotonic_ns() < self.next_ns {
            return;
        }
        self.next_ns = monotonic_ns() + STATUS_EVERY_NS;
        let Some(line) = live_line(&read_statuses(&self.run), restarts) else { return };
        match &self.bar {
            Some(bar) => bar.set_message(line),
            None => eprintln!("{line}"),
        }
    }

    /// Take the line off the terminal before the report is printed.
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}
