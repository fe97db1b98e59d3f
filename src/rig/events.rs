//! The run's event log, `events.jsonl`: one JSON object per line, appended by every process of the run (one
//! `write` per line on an O_APPEND file, so lines from different processes never interleave). Faults injected,
//! detected, failsafe engaged, recovered, processes started and restarted: the fault report is built from it.

use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// One event.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// CLOCK_MONOTONIC, ns (one clock for every process on the machine).
    pub t_ns: u64,
    /// Plant tick the event belongs to, when the process knows it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tick: Option<u64>,
    /// Who wrote it: plant, controller, logger or launcher.
    pub process: String,
    /// What happened, kebab-case (e.g. `controller-stale`, `failsafe-engaged`, `fault-injected`).
    pub kind: String,
    /// Details for a person.
    #[serde(default)]
    pub detail: String,
}

/// Appends events of one process to the run's log.
#[derive(Debug, Clone)]
pub struct EventLog {
    path: PathBuf,
    process: &'static str,
}

impl EventLog {
    /// The log in `out_dir` for `process`.
    pub fn new(out_dir: &Path, process: &'static str) -> Self {
        Self { path: out_dir.join("events.jsonl"), process }
    }

    /// Append an event now. Failing to log is reported on stderr, never fatal: the loop matters more.
    pub fn emit(&self, tick: Option<u64>, kind: &str, detail: impl Into<String>) {
        self.emit_at(silrig_wire::clock::monotonic_ns(), tick, kind, detail);
    }

    /// Append an event that happened at `t_ns` (CLOCK_MONOTONIC), before it could be told: a child started, whose
    /// own first events may reach the log before its parent has its pid to say so.
    pub fn emit_at(&self, t_ns: u64, tick: Option<u64>, kind: &str, detail: impl Into<String>) {
        let event = Event { t_ns, tick, process: self.process.into(), kind: kind.into(), detail: detail.into() };
        let line = serde_json::to_string(&event).expect("an event serialises") + "\n";
        let written = std::fs::OpenOptions::new().create(true).append(true).open(&self.path).and_then(|mut f| {
            let before = f.metadata()?.len();
            f.write_all(line.as_bytes()).inspect_err(|_| {
                // A full disk may have taken part of the line: the log keeps whole lines only.
                let _ = f.set_len(before);
            })
        });
        if let Err(e) = written {
            eprintln!("silrig-{}: cannot append to {}: {e}", self.process, self.path.display());
        }
    }
}

/// Read a run's events, oldest first; torn or foreign lines are skipped.
pub fn read_events(out_dir: &Path) -> Vec<Event> {
    let text = std::fs::read_to_string(out_dir.join("events.jsonl")).unwrap_or_default();
    let mut events: Vec<Event> = text.lines().filter_map(|l| serde_json::from_str(l).ok()).collect();
    events.sort_by_key(|e| e.t_ns);
    events
}
