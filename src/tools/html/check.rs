//! The page of one `silrig check`: the verdict, every case's criteria in one table, then each case with what failed,
//! its run folders (each with its own `report.html`), the figures of a case that did not pass, and the command that
//! flies it again. Built from `check.json`'s [`Verdict`].

use super::{Page, Tone, esc, facts, figure, figure_stems, outcome_cell, table_with};
use crate::check::verdict::{CaseVerdict, Verdict, utc_iso};
use silrig_flight::criteria::Outcome;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Write `<out>/report.html` for `verdict` (its folder is `verdict.out_dir`); `command` is the whole check's command.
pub fn write(verdict: &Verdict, command: &str) -> anyhow::Result<PathBuf> {
    page(verdict, command).write(Path::new(&verdict.out_dir))
}

/// The page of `verdict`.
pub fn page(verdict: &Verdict, command: &str) -> Page {
    let out = Path::new(&verdict.out_dir);
    let (criteria, failed, inconclusive) = verdict.counts();
    let passed_cases = verdict.cases.iter().filter(|c| c.passed).count();
    let tone = match verdict.outcome() {
        Outcome::Pass => Tone::Good,
        Outcome::Fail => Tone::Bad,
        Outcome::Inconclusive => Tone::Unsure,
    };
    let status = format!(
        "{}: {passed_cases} of {} cases passed, {failed} of {criteria} criteria failed, {inconclusive} inconclusive{}",
        verdict.outcome().label().to_uppercase(),
        verdict.cases_in_suite,
        if verdict.interrupted { " (interrupted)" } else { "" }
    );
    let mut page = Page::new(format!("silrig check: suite {}", verdict.suite), tone, status);
    let mut body = facts(&[
        ("suite", verdict.suite.clone()),
        ("suite file", verdict.suite_file.clone().unwrap_or_else(|| "the embedded default suite".into())),
        ("what it is for", verdict.description.clone()),
        ("controller", verdict.controller.clone()),
        ("started", format!("{} UTC", utc_iso(verdict.started_unix_s))),
        ("wall time", format!("{:.1} s", verdict.wall_s)),
        ("cases", format!("{} run of {} in the suite", verdict.cases.len(), verdict.cases_in_suite)),
        ("folder", verdict.out_dir.clone()),
    ]);
    body += "<h3>Every criterion</h3>\n";
    body += &criteria_table(verdict);
    page.section("verdict", "Verdict", command, body);
    for case in &verdict.cases {
        page.section(&format!("case-{}", case.name), &case.name, &case.reproduce, case_body(out, case));
    }
    page.section_with("files", "Files", Vec::new(), super::files(out, out));
    page
}

/// One row per criterion of every case, coloured by its outcome.
fn criteria_table(verdict: &Verdict) -> String {
    let rows: Vec<(&str, Vec<String>)> = verdict
        .cases
        .iter()
        .flat_map(|c| {
            c.judgements.iter().enumerate().map(move |(i, j)| {
                let name = if i == 0 {
                    format!("<a href=\"#case-{}\">{}</a>", esc(&c.name), esc(&c.name))
                } else {
                    String::new()
                };
                let class = match j.outcome() {
                    Outcome::Pass => "",
                    Outcome::Fail => "fail",
                    Outcome::Inconclusive => "warn",
                };
                (class, vec![name, esc(&j.criterion), esc(&j.measured), esc(&j.limit), outcome_cell(j.outcome())])
            })
        })
        .collect();
    let rows: Vec<(&str, &[String])> = rows.iter().map(|(c, r)| (*c, r.as_slice())).collect();
    table_with(None, &["case", "criterion", "measured", "limit", "result"], &rows)
}

/// A case: why it is in the suite, its outcome, what failed, its run folders and (unless it passed) their figures.
fn case_body(out: &Path, case: &CaseVerdict) -> String {
    let mut html = format!("<p>{} ", outcome_cell(case.outcome()));
    if !case.why.is_empty() {
        html += &esc(&case.why);
    }
    html += "</p>\n";
    if let Some(why) = &case.not_flown {
        let _ = writeln!(html, "<ul class=\"problems\"><li><b>not flown</b>: {}</li></ul>", esc(why));
    }
    let mut rows = vec![("mode", case.mode.clone())];
    if !case.faults.is_empty() {
        rows.push(("faults", case.faults.join("; ")));
    }
    rows.push(("flown", format!("{} time{}", case.attempts, if case.attempts == 1 { "" } else { "s" })));
    rows.push(("wall time", format!("{:.1} s", case.wall_s)));
    html += &facts(&rows);
    let explained: Vec<String> = case
        .judgements
        .iter()
        .filter(|j| !j.passed)
        .map(|j| {
            let said = j.why_failed.as_deref().or(j.inconclusive.as_deref()).unwrap_or("failed");
            format!("<li><b>{}</b>: {}</li>", esc(&j.criterion), esc(said))
        })
        .collect();
    if !explained.is_empty() {
        let _ = writeln!(html, "<ul class=\"problems\">{}</ul>", explained.concat());
    }
    html += "<h3>Run folders</h3>\n<ul>";
    for dir in &case.run_dirs {
        let dir = Path::new(dir);
        let rel = dir.strip_prefix(out).unwrap_or(dir);
        let page = dir.join(super::FILE);
        let link = if page.exists() {
            format!(" (<a href=\"{}\">its report.html</a>)", esc(&rel.join(super::FILE).display().to_string()))
        } else {
            String::new()
        };
        let _ = write!(
            html,
            "<li><a href=\"{}\">{}</a>{link}</li>",
            esc(&rel.display().to_string()),
            esc(&dir.display().to_string())
        );
    }
    html += "</ul>\n";
    if case.outcome() != Outcome::Pass {
        for dir in &case.run_dirs {
            let dir = Path::new(dir);
            for stem in figure_stems(dir) {
                html += &figure(out, dir, &stem).unwrap_or_default();
            }
        }
    }
    html
}
