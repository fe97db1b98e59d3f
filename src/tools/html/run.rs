//! The page of one `silrig run` (also of each run a check flies), answer first: the verdict (what passed, what
//! failed, the faults the rig saw and how it came back), the response of every output with a set point and the
//! control quality as tables, the faults on a timeline, timing against the OS floor, every other figure, the flight
//! in 3-D, then the processes, counters and the run's metadata, the events and the files folded away. The same
//! order for every plant: the figures are drawn from the plant's signals by name. Built from `report.json`'s
//! [`RigReport`] and the folder it names.

use super::{Page, Tone, esc, facts, figure_stems, figure_with, table};
use silrig_launch::fault_report::FaultRecord;
use silrig_launch::run_report::{RigReport, command_age_buckets};
use silrig_wire::timing::LatencySummary;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The figure the response section shows.
const RESPONSE_FIGURE: &str = "response";
/// Figures the timing section shows.
const TIMING_FIGURES: [&str; 2] = ["latency", "latency_histogram"];
/// The figure the fault section shows.
const FAULT_FIGURE: &str = "faults";

/// What to look for in each figure a run draws: the one line under it.
const LOOK_FOR: [(&str, &str); 9] = [
    (
        "response",
        "Each output with a set point (solid) against it (dashed): how fast it gets there, and whether it stays.",
    ),
    ("faults", "Red bands: each fault from injection to recovery; the lines show what the flight did meanwhile."),
    ("latency", "Each latency by percentile, log scale: the bulk on the left, the rare worst ticks on the right."),
    (
        "latency_histogram",
        "How many ticks fell in each bucket (log count): a tail far right of the bulk is late wake-ups.",
    ),
    ("fig1_states", "The F-16's states, set points dashed; the surfaces' deflections against their commands (dashed)."),
    ("fig2_sliding", "Sliding surfaces should fall to zero and stay; the RBF estimate should follow the true f."),
    ("fig3_weights", "The RBF weights of each channel: they should settle, not drift or grow."),
    ("signals", "Every signal the plant announced; commands dashed over the positions they move."),
    ("overlay", "The runs compared: where the lines part is where the runs differ."),
];

/// The figure `stem` of the run's folder with what to look for in it.
fn run_figure(out: &Path, stem: &str) -> Option<String> {
    let look_for = LOOK_FOR.iter().find(|(s, _)| *s == stem).map_or("", |(_, l)| l);
    figure_with(out, out, stem, look_for)
}

/// Write `<out>/report.html` for `report` (its folder is `report.out_dir`); `command` is the command that flies
/// the run again, as the reader should type it.
pub fn write(report: &RigReport, command: &str) -> anyhow::Result<PathBuf> {
    let out = Path::new(&report.out_dir);
    page(report, command).write(out)
}

/// The command line this process was started with, as a shell reads it back (`silrig` for the program).
pub fn this_command() -> String {
    let mut words = vec!["silrig".to_string()];
    words.extend(std::env::args_os().skip(1).map(|a| silrig_launch::program::shell_quote(&a.to_string_lossy())));
    words.join(" ")
}

/// The badge: the tone and the words of the run's outcome.
fn status(report: &RigReport) -> (Tone, String) {
    if !report.failures.is_empty() {
        let n = report.failures.len();
        (Tone::Bad, format!("FAILED: {n} failure{}", if n == 1 { "" } else { "s" }))
    } else if let Some(s) = &report.stopped_by {
        (
            Tone::Unsure,
            format!("stopped by the user ({}) at t = {:.2} s of {:.2} s", s.signal, s.at_s, report.duration_s),
        )
    } else if !report.discontinuities.is_empty() {
        (Tone::Unsure, "all processes ended cleanly; the logged flight has a discontinuity".to_string())
    } else {
        (Tone::Good, "all processes ended cleanly".to_string())
    }
}

/// The page of `report`.
pub fn page(report: &RigReport, command: &str) -> Page {
    let out = Path::new(&report.out_dir);
    let (tone, status) = status(report);
    let title = format!("silrig run {}: {} ({})", report.run_id, report.scenario, report.mode);
    let mut page = Page::new(title, tone, status);
    page.section("verdict", "Verdict", command, verdict(report));
    page.section("response", "Response", command, response(report, out));
    page.section("faults", "Faults", command, faults(report, out));
    page.section("timing", "Timing", command, timing(report, out));
    let shown: Vec<&str> = TIMING_FIGURES.iter().chain(&[FAULT_FIGURE, RESPONSE_FIGURE]).copied().collect();
    let others: String =
        figure_stems(out).iter().filter(|s| !shown.contains(&s.as_str())).filter_map(|s| run_figure(out, s)).collect();
    let others = if others.is_empty() {
        "<p>No other figures: the run was flown with --no-figures, or left no trace to draw.</p>\n".to_string()
    } else {
        others
    };
    let others = left_out(report) + &others;
    page.section("figures", "Figures", command, others);
    page.section("view3d-section", "The flight in 3-D", command, super::view3d::section(out));
    page.section(
        "run",
        "Run, processes and counters",
        command,
        folded("The run, its processes and their counters", &details(report)),
    );
    page.section("events", "Events", command, folded("Every event of the run", &super::events(out)));
    page.section_with("files", "Files", Vec::new(), folded("Every file of the run's folder", &super::files(out, out)));
    page
}

/// `body` folded under a line that opens it.
fn folded(summary: &str, body: &str) -> String {
    format!("<details><summary>{}</summary>\n{body}</details>\n", esc(summary))
}

/// The figures the run did not draw, each with why: said here once, not in every run's printed report.
fn left_out(r: &RigReport) -> String {
    if r.figures_left_out.is_empty() {
        return String::new();
    }
    let mut out = "<ul class=\"notes\">".to_string();
    for f in &r.figures_left_out {
        let _ = write!(out, "<li>{} not drawn: {}</li>", esc(&f.figure), esc(&f.reason));
    }
    out + "</ul>\n"
}

/// One line of the verdict: a tag (passed, failed, unsure) and what it says, HTML.
fn line(tone: Tone, tag: &str, html: &str) -> String {
    format!("<li><span class=\"tag {}\">{}</span>{html}</li>", tone.class(), esc(tag))
}

/// What passed, what failed, and what the rig saw and survived: the processes' ends, each fault with its detection
/// and recovery, discontinuities and leftovers, then the failures and notes in words.
fn verdict(r: &RigReport) -> String {
    let flown = r.control.as_ref().map(|s| s.ticks.saturating_sub(1) as f64 * s.dt_s);
    let plant = r.control.as_ref().map_or(String::new(), |s| format!(", plant {}", s.plant));
    let mut out = format!(
        "<p>Scenario {}{plant}, {} mode: {}.</p>\n<ul class=\"verdict\">",
        esc(&r.scenario),
        esc(&r.mode),
        match flown {
            Some(f) => format!("flown from t = 0 to {f:.2} s of {:.2} s", r.duration_s),
            None => format!("no trace was logged (the scenario's {:.2} s)", r.duration_s),
        }
    );
    let lives = r.lives.len().max(r.processes.len());
    if r.failures.is_empty() {
        out += &line(Tone::Good, "passed", &format!("every process ended cleanly ({lives} process lives)"));
    }
    for f in &r.failures {
        out += &line(Tone::Bad, "failed", &esc(f));
    }
    for f in &r.faults {
        out += &fault_line(f);
    }
    for p in r.unplanned_plant_resumes() {
        out += &line(Tone::Unsure, "plant restarted", &esc(&format!("outside the fault plan: {}", p.describe())));
    }
    for d in &r.discontinuities {
        let text = format!("the logged flight jumps at t = {:.2} s: {}", d.at_s, d.detail);
        out += &line(Tone::Unsure, "discontinuity", &esc(&text));
    }
    for l in &r.leftovers {
        out += &line(Tone::Bad, "leftover", &esc(&format!("iceoryx2 leftover after cleanup: {l}")));
    }
    if let Some(s) = &r.stopped_by {
        out += &line(Tone::Unsure, "stopped", &esc(&format!("by the user ({}) at t = {:.2} s", s.signal, s.at_s)));
    }
    out += "</ul>\n";
    if !r.notes.is_empty() {
        out += "<ul class=\"notes\">";
        for n in &r.notes {
            let _ = write!(out, "<li>note: {}</li>", esc(n));
        }
        out += "</ul>\n";
    }
    out
}

/// One fault as the verdict reads it: injected, detected by whom, failsafe, recovered (or not) and what was lost.
fn fault_line(f: &FaultRecord) -> String {
    let Some(injected) = f.injected_at_s else {
        return line(Tone::Unsure, "not injected", &esc(&format!("{}: its target was not running", f.fault)));
    };
    let mut text = format!("{}: injected at {injected:.2} s", f.fault);
    if let Some(d) = f.detected_at_s {
        let by = f.detected_by.as_deref().map_or(String::new(), |b| format!(" by {b}"));
        let _ = write!(text, ", detected {:.2} s later{by}", d - injected);
    }
    if let Some(t) = f.failsafe_at_s {
        let _ = write!(text, ", failsafe at {t:.2} s");
    }
    if let Some(r) = &f.plant_resume {
        let _ = write!(text, ", plant {}", r.describe());
    }
    let lost = format!("{} plant samples and {} commands lost", f.plant_samples_lost, f.command_samples_lost);
    match f.recovered_at_s {
        Some(t) => {
            let _ = write!(text, ", recovered at {t:.2} s ({:.2} s after injection); {lost}", t - injected);
            line(Tone::Good, "survived", &esc(&text))
        }
        // A plant-model fault ends with its window and a one-off delay has none: the rig logs no recovery for either,
        // so no recovery is not a failure here; the run's failures above say when one is.
        None => line(Tone::Unsure, "no recovery", &esc(&format!("{text}; no recovery logged; {lost}"))),
    }
}

/// The response figure and the control quality as tables.
fn response(r: &RigReport, out: &Path) -> String {
    let mut html = run_figure(out, RESPONSE_FIGURE).unwrap_or_default();
    if let Some(f) = r.figures_left_out.iter().find(|f| f.figure == format!("{RESPONSE_FIGURE}.png")) {
        let _ = writeln!(html, "<p>No response figure: {}.</p>", esc(&f.reason));
    }
    html += "<h3>Control quality of the logged trace</h3>\n";
    match &r.control {
        Some(s) => html += &super::control::tables(s),
        None => html += "<p>No trace to summarise.</p>\n",
    }
    html
}

/// The run and the machine, the processes and their lives, and every process's counters.
fn details(r: &RigReport) -> String {
    let (c0, c1) = (&r.conditions_start, &r.conditions_end);
    let mut out = facts(&[
        ("run id", r.run_id.clone()),
        ("scenario", r.scenario.clone()),
        ("mode", r.mode.clone()),
        ("wall time", format!("{:.3} s, {:.0} plant cycles/s", r.wall_s, r.cycles_per_s)),
        (
            "machine",
            format!(
                "{} CPUs, load average {:.2} {:.2} {:.2} at the start, {:.2} at the end, kernel {}",
                c0.cpu_count, c0.load_average[0], c0.load_average[1], c0.load_average[2], c1.load_average[0], c0.kernel
            ),
        ),
        ("folder", r.out_dir.clone()),
    ]);
    out += "<h3>Processes</h3>\n";
    out += &processes(r);
    out += "<h3>Counters</h3>\n";
    let rows: Vec<Vec<String>> = r
        .processes
        .iter()
        .map(|p| {
            let counters: Vec<String> = p.counters.iter().map(|(k, v)| format!("{k} {v}")).collect();
            vec![esc(&p.process), esc(&counters.join(", ")), esc(&command_age_buckets(&p.command_age_ticks).join(", "))]
        })
        .collect();
    out + &table(&["process", "counters", "command age at use (ticks: count)"], &rows)
}

/// One row per life of each process the launcher started (a process started by hand: its report's).
fn processes(r: &RigReport) -> String {
    let mut rows = Vec::new();
    for p in r.processes.iter().filter(|p| !r.lives.iter().any(|l| l.process == p.process)) {
        rows.push(vec![
            esc(&p.process),
            p.pid.to_string(),
            esc(&p.scheduling),
            "-".into(),
            "-".into(),
            esc(&p.ended),
            "not started by the launcher".into(),
        ]);
    }
    for l in &r.lives {
        let several = r.lives.iter().filter(|o| o.process == l.process).count() > 1;
        let own = r.processes.iter().find(|p| p.process == l.process && p.pid == l.pid);
        let name = if several { format!("{} #{}", l.process, l.life) } else { l.process.clone() };
        rows.push(vec![
            esc(&name),
            l.pid.to_string(),
            esc(own.map_or("-", |p| p.scheduling.as_str())),
            format!("{:.2}", l.started_at_s),
            l.ended_at_s.map_or("-".into(), |t| format!("{t:.2}")),
            esc(&own.map_or_else(|| l.exit.clone(), |p| p.ended.clone())),
            l.report.as_ref().map_or("none".into(), |f| format!("<a href=\"{}\">{}</a>", esc(f), esc(f))),
        ]);
    }
    table(&["process", "pid", "scheduling", "started (s)", "ended (s)", "how it ended", "its report"], &rows)
}

fn latency_row(name: &str, s: &LatencySummary) -> Vec<String> {
    let mut row = vec![esc(name), s.count.to_string()];
    row.extend([s.min_us, s.avg_us, s.p50_us, s.p90_us, s.p99_us, s.p999_us, s.max_us].map(|v| format!("{v:.1}")));
    row
}

const LATENCY_HEADER: [&str; 9] = ["(µs)", "count", "min", "avg", "p50", "p90", "p99", "p99.9", "max"];

/// Timing against the OS floor: the plant's wake-up lateness against the floor's in one sentence, the latency
/// figures, then every distribution (the floor's beside them) and the warm-up apart from steady state as tables.
fn timing(r: &RigReport, out: &Path) -> String {
    let mut html = String::new();
    if let (Some(b), Some(plant)) = (&r.timer_baseline, r.latency("plant.wake_lateness")) {
        let _ = writeln!(
            html,
            "<p>Plant wake-up lateness p99 is {:.2}x the OS floor's p99 measured beside it ({}, {}).</p>",
            plant.p99_us / b.lateness.p99_us,
            esc(&b.source.to_string()),
            esc(&b.policy.to_string())
        );
    } else if let Some(why) = &r.timer_baseline_missing {
        html += &format!("<p>No OS floor to read the plant's wake-up lateness against: {}.</p>\n", esc(why));
    } else if r.mode == "realtime" && r.timer_baseline.is_none() {
        html += "<p>No OS floor was measured beside this run (--no-baseline, or the floor could not be taken).</p>\n";
    }
    let floor = r.timer_baseline.as_ref().and_then(|b| b.lateness_steady);
    if let (Some(floor), Some(plant)) = (&floor, r.phases.iter().find(|p| p.name == "plant.wake_lateness")) {
        let _ = writeln!(
            html,
            "<p>Steady state: plant wake-up lateness p99 is {:.2}x the OS floor's.</p>",
            plant.steady.p99_us / floor.p99_us
        );
    }
    for stem in TIMING_FIGURES {
        html += &run_figure(out, stem).unwrap_or_default();
    }
    let mut rows: Vec<Vec<String>> = r
        .processes
        .iter()
        .flat_map(|p| &p.latencies)
        .filter(|l| l.summary.count > 0)
        .map(|l| latency_row(&l.name, &l.summary))
        .collect();
    if let Some(b) = &r.timer_baseline {
        rows.push(latency_row("os-floor.wake_lateness", &b.lateness));
    }
    if rows.is_empty() {
        html += "<p>No timing was recorded.</p>\n";
    } else {
        html += &table(&LATENCY_HEADER, &rows);
    }
    if !r.phases.is_empty() {
        html += "<h3>Warm-up (the first second) apart from steady state (after it)</h3>\n";
        let mut rows = Vec::new();
        for p in &r.phases {
            rows.push(latency_row(&format!("{} warm-up", p.name), &p.warm_up));
            rows.push(latency_row(&format!("{} steady", p.name), &p.steady));
        }
        if let Some(floor) = &floor {
            rows.push(latency_row("os-floor.wake_lateness steady", floor));
        }
        html += &table(&LATENCY_HEADER, &rows);
    }
    html
}

/// The timeline figure, the fault table and the discontinuities.
fn faults(r: &RigReport, out: &Path) -> String {
    let mut html = run_figure(out, FAULT_FIGURE).unwrap_or_default();
    if r.faults.is_empty() {
        html += "<p>No faults were planned. Add one to a run with e.g. <code>--fault controller:kill@3s,restart_after=0.5s</code> \
                 or the scenario's <code>[[faults]]</code>.</p>\n";
    } else {
        let t = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.3}"));
        let rows: Vec<Vec<String>> = r
            .faults
            .iter()
            .map(|f| {
                vec![
                    esc(&f.fault),
                    t(f.injected_at_s),
                    t(f.injected_at_wall_s),
                    t(f.detected_at_s),
                    esc(f.detected_by.as_deref().unwrap_or("-")),
                    t(f.failsafe_at_s),
                    t(f.recovered_at_s),
                    f.plant_samples_lost.to_string(),
                    f.command_samples_lost.to_string(),
                ]
            })
            .collect();
        html += "<p>Times in simulated seconds (injection also in wall-clock seconds from the plant's tick 0).</p>\n";
        html += &table(
            &[
                "fault",
                "injected",
                "injected (wall)",
                "detected",
                "by",
                "failsafe",
                "recovered",
                "plant samples lost",
                "commands lost",
            ],
            &rows,
        );
    }
    for d in &r.discontinuities {
        let _ = writeln!(html, "<p>Flight discontinuity at t = {:.3} s: {}</p>", d.at_s, esc(&d.detail));
    }
    html
}
