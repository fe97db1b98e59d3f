//! The soak's report as text, as `silrig soak` prints it: the totals, each kind of fault, the rows (those the
//! machine's own stalls cost said apart), the processes, what was left and the verdict.

use super::figures::{Rows, SoakReport};

/// The processes' table (pid, RSS, descriptors and shared-memory files at the start and the end), the lives that
/// held more at last, and the run's /dev/shm entries.
fn processes_text(r: &SoakReport) -> String {
    let mut s = String::new();
    s += &format!(
        "  {:<16} {:>8} {:>8} {:>10} {:>10} {:>6} {:>6} {:>5} {:>5}\n",
        "process", "pid", "pid", "RSS KiB", "RSS KiB", "fds", "fds", "shm", "shm"
    );
    s += &format!(
        "  {:<16} {:>8} {:>8} {:>10} {:>10} {:>6} {:>6} {:>5} {:>5}\n",
        "", "start", "end", "start", "end", "start", "end", "start", "end"
    );
    for a in &r.processes_start {
        let e = r.processes_end.iter().find(|e| e.process == a.process);
        let f = |v: Option<u64>| v.map_or("-".to_string(), |v| v.to_string());
        s += &format!(
            "  {:<16} {:>8} {:>8} {:>10} {:>10} {:>6} {:>6} {:>5} {:>5}\n",
            a.process,
            a.pid,
            f(e.map(|e| e.pid as u64)),
            a.rss_kib,
            f(e.map(|e| e.rss_kib)),
            a.fds,
            f(e.map(|e| e.fds)),
            a.shm_files,
            f(e.map(|e| e.shm_files))
        );
    }
    let grew = r.lives.iter().filter(|l| {
        let (fds, shm_files) = l.held_to_the_end();
        fds > l.settled.fds || shm_files > l.settled.shm_files
    });
    s += &format!(
        "  {} lives measured settled and last: {} held more descriptors or shared-memory files at their last two looks\n",
        r.lives.len(),
        grew.count()
    );
    s += &format!(
        "  the run's /dev/shm entries: {} at the start, {} at the end\n",
        r.run_shm_start.len(),
        r.run_shm_end.len()
    );
    s
}

/// The rows lost outside the windows in the OS floor's stalls, in words after the count (empty when none).
fn machines_share(rows: &Rows) -> String {
    match rows.lost_in_machine_stalls {
        0 => String::new(),
        n => format!(
            " ({n} of them in stalls the OS floor beside the run saw too, its wake-ups up to {:.1} ms late: the \
             machine's)",
            rows.worst_machine_stall_us / 1e3
        ),
    }
}

/// The report as text: the totals, each kind, the rows, the processes, the leftovers and the verdict.
pub fn to_text(r: &SoakReport) -> String {
    let mut s = format!(
        "silrig soak: seed {}, {} s realtime, run {} ({}), load average {:?} at the start, {:?} at the end\n",
        r.seed, r.duration_s, r.run_id, r.out_dir, r.load_average_start, r.load_average_end
    );
    if let Some(h) = &r.controller_host {
        s += &format!(
            "the controller behind the bridge, its host on this machine: namespace {}, folder {}; its bridge \
             started {} times, its controller {}\n",
            h.local_run_id, h.folder, h.bridge_starts, h.controller_starts
        );
    }
    s += &format!(
        "faults: {} scheduled, {} injected ({} fault-injected events), {} detected ({} of kinds the rig watches), \
         {} recovered, the flight back after {}; failsafe engaged {} times\n",
        r.scheduled,
        r.injected,
        r.fault_events,
        r.detected,
        r.watched,
        r.recovered,
        r.flight_back,
        r.failsafe_engagements
    );
    s += &format!("  {:<30} {:>8} {:>8} {:>9} {:>11}\n", "kind", "injected", "detected", "recovered", "flight back");
    for k in &r.kinds {
        let detected = if k.watched { k.detected.to_string() } else { format!("({})", k.detected) };
        s += &format!("  {:<30} {:>8} {:>8} {:>9} {:>11}\n", k.kind, k.injected, detected, k.recovered, k.flight_back);
    }
    s += "  (detected in parentheses: the rig has no detector for that kind, so it is not required)\n";
    let rows = &r.rows;
    s += &format!(
        "rows: {} logged; lost {} inside the faults' windows, {} outside them{}; {} torn, {} logged twice\n",
        rows.trace_rows,
        rows.lost_in_fault_windows,
        rows.lost_outside_fault_windows,
        machines_share(rows),
        rows.torn,
        rows.duplicated
    );
    s += &processes_text(r);
    s += &format!(
        "left after the run: {} processes, {} shared-memory files, {} lock files\n",
        r.leftovers.processes.len(),
        r.leftovers.shm_files.len(),
        r.leftovers.lock_files.len()
    );
    s + &verdict(&r.problems, rows)
}

/// The soak's last lines: passed (saying the rows the machine's stalls cost, if any), or failed with each problem.
fn verdict(problems: &[String], rows: &Rows) -> String {
    match (problems, rows.lost_in_machine_stalls) {
        ([], 0) => "soak passed\n".into(),
        ([], n) => format!(
            "soak passed; the {n} rows lost in stalls of the machine that the OS floor saw too are not held against \
             the rig\n"
        ),
        (p, _) => {
            let mut s = format!("soak FAILED ({} problems):\n", p.len());
            for p in p {
                s += &format!("  {p}\n");
            }
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_lost_in_the_machines_stalls_are_said_beside_the_count_and_in_the_verdict() {
        let mut rows = Rows { trace_rows: 1000, timing_rows: 1000, ..Rows::default() };
        assert_eq!((machines_share(&rows), verdict(&[], &rows)), (String::new(), "soak passed\n".into()));
        (rows.lost_outside_fault_windows, rows.lost_in_machine_stalls, rows.worst_machine_stall_us) =
            (195, 195, 2_000_000.0);
        assert_eq!(
            machines_share(&rows),
            " (195 of them in stalls the OS floor beside the run saw too, its wake-ups up to 2000.0 ms late: the \
             machine's)"
        );
        assert!(verdict(&[], &rows).starts_with("soak passed; the 195 rows lost in stalls of the machine"));
        let failed = verdict(&["121 rows lost".into()], &rows);
        assert_eq!(failed, "soak FAILED (1 problems):\n  121 rows lost\n");
    }
}
