//! The book's fault matrix (docs/src/guides/faults.md) is what the rig does: every row is flown here (a 3 s realtime
//! run with one fault) and the table built from the runs' reports must equal the one in the book, between its
//! markers. After a change in behaviour, `SILRIG_UPDATE_DOCS=1 cargo test --release --test fault_matrix` writes the
//! new table; the diff then shows what changed. Only what does not depend on the machine's timing is in the table: the
//! exit status, which process detected the fault, whether the failsafe engaged, whether the loop recovered, what a
//! restarted process resumed from, and the report's verdict line. Not in it: a delay (whether its samples come late
//! enough for the peers to flag them depends on the machine's load), and whether a restarted plant's flight shows as
//! a discontinuity in the log: that depends on whether the logger had taken the ticks the plant flies again before it
//! died (a CI run on a loaded machine: it had not, and the log was continuous), so the verdict is cut before it.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

mod common;
use common::{no_shared_memory_left, wait_with_watchdog};

const SILRIG: &str = env!("CARGO_BIN_EXE_silrig");
const START: &str = "<!-- fault-matrix: written by tests/fault_matrix.rs -->";
const END: &str = "<!-- fault-matrix end -->";

/// (fault flags, what an engineer should expect)
const ROWS: [(&str, &str); 8] = [
    (
        "controller:kill@1s,restart_after=0.3s",
        "plant holds, then trim failsafe; the restarted controller resumes its weights and blends in",
    ),
    ("controller:kill@1s", "plant flies the rest in failsafe; the plan ended the controller, so the run is whole"),
    ("controller:stop@1s,for=0.5s", "failsafe while stopped; commands resume when continued"),
    (
        "plant:kill@1.05s,restart_after=0.3s",
        "restarted plant resumes its checkpoint; ticks it flies again that the logger had written are marked as a discontinuity",
    ),
    ("plant:kill@1s", "nothing flies without a plant: the run fails, saying when the flight ended"),
    ("plant:stop@1s,for=0.5s", "controller idles on a silent plant; simulated time pauses, no tick is skipped"),
    (
        "logger:kill@1s,restart_after=0.3s",
        "the restarted logger appends after the last row; the rows of its absence are a gap",
    ),
    ("logger:stop@1s,for=0.5s", "nothing lost: its queues hold 4.1 s at 1 kHz, 41 s at 100 Hz"),
];

fn observe(i: usize, fault: &str) -> String {
    let id = format!("m{}-{i}", std::process::id());
    let dir = common::temp_dir("fault-matrix", &i.to_string());
    let out = dir.join("run");
    let child = Command::new(SILRIG)
        .args(["run", "--no-baseline", "--duration-s", "3", "--run-id", &id, "--out", out.to_str().unwrap()])
        .args(["--fault", fault])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let o = wait_with_watchdog(child, Duration::from_secs(90));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
        .unwrap_or_else(|e| panic!("{fault}: {e}\n{stdout}{}", String::from_utf8_lossy(&o.stderr)));
    let f = &report["faults"][0];
    let yes = |v: &serde_json::Value| if v.is_null() { "no" } else { "yes" };
    let by = f["detected_by"].as_str().map_or("-", |b| b.split(' ').next().unwrap());
    let verdict = stdout
        .lines()
        .filter(|l| l.starts_with("FAILED") || l.starts_with("all processes"))
        // Up to the first time, which varies from run to run, and without the discontinuities (see above).
        .map(|l| l.split(" at t = ").next().unwrap().split("; the logged flight has").next().unwrap())
        .collect::<Vec<_>>()
        .join("; ");
    let events = std::fs::read_to_string(out.join("events.jsonl")).unwrap_or_default();
    let resumed = if events.contains(r#""kind":"plant-resumed""#) || events.contains("checkpointed state") {
        "its checkpoint"
    } else if events.contains(r#""kind":"logger-resumed""#) {
        "the last row"
    } else {
        "-"
    };
    let row = format!(
        "| `{fault}` | {} | {by} | {} | {} | {resumed} | {verdict} |",
        o.status.code().map_or("signal".into(), |c| c.to_string()),
        yes(&f["failsafe_at_s"]),
        yes(&f["recovered_at_s"]),
    );
    no_shared_memory_left(&id);
    let _ = std::fs::remove_dir_all(&dir);
    row
}

#[test]
fn the_books_fault_matrix_is_what_the_rig_does() {
    // Two at a time: each run is three realtime processes on a 2-core machine.
    let mut observed = vec![String::new(); ROWS.len()];
    for pair in (0..ROWS.len()).collect::<Vec<_>>().chunks(2) {
        let runs: Vec<_> = pair.iter().map(|&i| (i, std::thread::spawn(move || observe(i, ROWS[i].0)))).collect();
        for (i, run) in runs {
            observed[i] = run.join().unwrap();
        }
    }
    let mut table = String::from(
        "| fault (`--fault`, 3 s run) | exit | detected by | failsafe | recovered | restarted from | report says |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for line in &observed {
        table += line;
        table.push('\n');
    }
    let mut expected = String::from("| fault | what to expect |\n|---|---|\n");
    for (fault, expect) in ROWS {
        expected += &format!("| `{fault}` | {expect} |\n");
    }
    let block = format!("{START}\n{expected}\n{table}{END}");
    let page_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/src/guides/faults.md");
    let page = std::fs::read_to_string(&page_path).unwrap();
    let (Some(a), Some(b)) = (page.find(START), page.find(END)) else {
        panic!("docs/src/guides/faults.md has no fault-matrix markers")
    };
    let current = &page[a..b + END.len()];
    if std::env::var_os("SILRIG_UPDATE_DOCS").is_some() {
        std::fs::write(&page_path, page.replace(current, &block)).unwrap();
    } else {
        assert_eq!(
            current, block,
            "the rig's behaviour differs from the book's fault matrix (SILRIG_UPDATE_DOCS=1 rewrites it)"
        );
    }
}
