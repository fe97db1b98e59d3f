//! The page of one `silrig sweep` (also of a merged sweep and of a check's sweep case): the pass rate with its
//! interval and the failures by criterion, the sweep's figures (histograms, scatter, envelope), the worst cases by
//! each criterion with the command that flies each alone, and the departed and infeasible cases. Built from
//! `sweep.json`'s [`SweepSummary`].

use super::{Page, Tone, esc, facts, figure, figure_stems, table};
use crate::campaign::report::SweepSummary;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The command that flies the same cases again (the same bytes on any number of threads or machines).
pub fn command(summary: &SweepSummary) -> String {
    format!("silrig sweep {} --runs {} --seed {}", summary.config, summary.runs, summary.seed)
}

/// Write `<out>/report.html` for `summary`, whose files and figures are in `out`.
pub fn write(summary: &SweepSummary, out: &Path) -> anyhow::Result<PathBuf> {
    page(summary, out).write(out)
}

/// The page of `summary`.
pub fn page(s: &SweepSummary, out: &Path) -> Page {
    let command = command(s);
    let flown = s.passed + s.failed;
    let (low, high) = s.pass_rate_95;
    let rate = format!(
        "pass rate {:.1} % ({} of {flown} flown cases passed; 95 % Wilson interval {:.1} .. {:.1} %)",
        s.pass_rate * 100.0,
        s.passed,
        low * 100.0,
        high * 100.0
    );
    let tone = match (s.passed, s.failed) {
        (_, 0) if flown > 0 => Tone::Good,
        (0, _) => Tone::Bad,
        _ => Tone::Unsure,
    };
    let mut page = Page::new(format!("silrig sweep: {} ({} cases, seed {})", s.scenario, s.runs, s.seed), tone, &rate);
    let mut body = facts(&[
        ("scenario", s.scenario.clone()),
        ("scenario file", s.config.clone()),
        ("seed", s.seed.to_string()),
        ("cases", s.runs.to_string()),
        (
            "outcome",
            format!(
                "{} passed, {} failed ({} of them departed), {} infeasible",
                s.passed, s.failed, s.departed, s.infeasible
            ),
        ),
        ("pass rate", rate.clone()),
        ("dispersed", format!("{} keys: {}", s.parameters.len(), s.parameters.join(", "))),
        ("folder", out.display().to_string()),
    ]);
    body += "<h3>Failures by criterion</h3>\n";
    let rows: Vec<Vec<String>> =
        s.failures_by_criterion.iter().map(|(name, n)| vec![esc(name), n.to_string(), flown.to_string()]).collect();
    body += &table(&["criterion", "failed", "of flown cases"], &rows);
    page.section("summary", "Summary", &command, body);

    let figures: String = figure_stems(out).iter().filter_map(|stem| figure(out, out, stem)).collect();
    let figures = if figures.is_empty() { "<p>No figures: no case could be flown.</p>\n".to_string() } else { figures };
    page.section("figures", "Figures", &command, figures);
    page.section("worst", "Worst cases", &command, worst_cases(s));

    page.section_with("files", "Files", Vec::new(), super::files(out, out));
    page
}

/// Each criterion's worst cases with the command that flies each alone, then the departed and the infeasible cases.
fn worst_cases(s: &SweepSummary) -> String {
    let mut worst = String::from(
        "<p>Each criterion's worst cases that stayed within the model's data, worst first; each command flies that \
         case alone and prints the same numbers.</p>\n",
    );
    for (criterion, cases) in &s.worst {
        let _ = writeln!(worst, "<h3>{}</h3>", esc(criterion));
        let rows: Vec<Vec<String>> = cases
            .iter()
            .map(|c| {
                vec![
                    c.index.to_string(),
                    esc(&c.measured),
                    format!(
                        "<span class=\"tag {}\">{}</span>",
                        if c.passed { "pass" } else { "fail" },
                        if c.passed { "pass" } else { "FAIL" }
                    ),
                    format!("<code>{}</code>", esc(&c.reproduce)),
                ]
            })
            .collect();
        worst += &table(&["case", "measured", "result", "reproduce"], &rows);
    }
    if !s.departed_cases.is_empty() {
        worst += "<h3>Departed cases (left the model's data or stopped; each failed)</h3>\n";
        let rows: Vec<Vec<String>> = s
            .departed_cases
            .iter()
            .map(|c| {
                vec![
                    c.index.to_string(),
                    format!("{:.2}", c.at_s),
                    esc(&c.reason),
                    format!("<code>{}</code>", esc(&c.reproduce)),
                ]
            })
            .collect();
        worst += &table(&["case", "at (s)", "why", "reproduce"], &rows);
    }
    if !s.infeasible_cases.is_empty() {
        worst += "<h3>Infeasible cases (not flown)</h3>\n";
        let rows: Vec<Vec<String>> =
            s.infeasible_cases.iter().map(|c| vec![c.index.to_string(), esc(&c.reason)]).collect();
        worst += &table(&["case", "why"], &rows);
    }
    worst
}
