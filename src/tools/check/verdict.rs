//! The verdict of a check and its three forms: the table a person reads, `check.json`, and `check.junit.xml` (one
//! `<testsuite>` per case, one `<testcase>` per criterion) for GitLab, Jenkins and GitHub test reporters.

use super::criteria::Judgement;
use super::suite::Case;
use serde::{Deserialize, Serialize};
use silrig_flight::criteria::Outcome;
use std::fmt::Write as _;
use std::path::Path;

/// The verdict file.
pub const JSON_FILE: &str = "check.json";
/// The JUnit XML file.
pub const JUNIT_FILE: &str = "check.junit.xml";

/// One case judged.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CaseVerdict {
    /// The case's name.
    pub name: String,
    /// Why it is in the suite.
    pub why: String,
    /// realtime or lockstep.
    pub mode: String,
    /// The faults injected (`--fault` syntax).
    pub faults: Vec<String>,
    /// Whether every criterion passed.
    pub passed: bool,
    /// No criterion failed and one or more were inconclusive (in its last flight).
    #[serde(default)]
    pub inconclusive: bool,
    /// How many times it was flown: more than once when a flight was inconclusive (`--retries`).
    #[serde(default = "one")]
    pub attempts: u32,
    /// Wall time of the case, s.
    pub wall_s: f64,
    /// The run folders (plots, report, trace), one per run.
    pub run_dirs: Vec<String>,
    /// The command that runs just this case again.
    pub reproduce: String,
    /// Each criterion, `run_completed` first (none for a case not flown).
    pub judgements: Vec<Judgement>,
    /// Why the case was not flown: an earlier case's flight never started (its controller or plant never joined
    /// or exited at once), so no case could fly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub not_flown: Option<String>,
}

/// The whole check (`check.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Verdict {
    /// Suite name.
    pub suite: String,
    /// Suite file (None: the embedded default suite).
    pub suite_file: Option<String>,
    /// What the suite is for.
    pub description: String,
    /// The controller judged: `silrig-controller` or the `--controller-cmd` command.
    pub controller: String,
    /// Output folder.
    pub out_dir: String,
    /// Start, s since the Unix epoch.
    pub started_unix_s: u64,
    /// Wall time of the whole check, s.
    pub wall_s: f64,
    /// Stopped by SIGINT/SIGTERM before every case ran.
    pub interrupted: bool,
    /// Cases selected to run (fewer ran if interrupted).
    pub cases_in_suite: usize,
    /// True only if every selected case ran and passed.
    pub passed: bool,
    /// Every selected case ran, none failed, and one or more were inconclusive: exit status 3.
    #[serde(default)]
    pub inconclusive: bool,
    /// The cases, in suite order.
    pub cases: Vec<CaseVerdict>,
}

fn one() -> u32 {
    1
}

impl CaseVerdict {
    /// A case judged by its criteria, in its folders.
    pub fn judged(
        case: &Case,
        mode: String,
        attempts: u32,
        wall_s: f64,
        run_dirs: Vec<String>,
        reproduce: String,
        judgements: Vec<Judgement>,
    ) -> Self {
        let outcome = case_outcome(&judgements);
        CaseVerdict {
            name: case.name.clone(),
            why: case.why.clone(),
            mode,
            faults: case.fault_flags.clone(),
            passed: outcome == Outcome::Pass,
            inconclusive: outcome == Outcome::Inconclusive,
            attempts,
            wall_s,
            run_dirs,
            reproduce,
            judgements,
            not_flown: None,
        }
    }

    /// A case not flown, and why: a failure of the check, with no criterion judged.
    pub fn not_flown(case: &Case, reproduce: String, why: String) -> Self {
        let mode = if case.sweep.is_some() { "sweep".into() } else { case.mode.label().into() };
        CaseVerdict {
            attempts: 0,
            not_flown: Some(why),
            ..Self::judged(case, mode, 0, 0.0, Vec::new(), reproduce, Vec::new())
        }
        .failed()
    }

    /// Not passed: a case with no judgement would otherwise count as passed.
    fn failed(mut self) -> Self {
        self.passed = false;
        self
    }

    /// The case's answer: fail if a criterion failed, else inconclusive if one was, else pass.
    pub fn outcome(&self) -> Outcome {
        match (self.passed, self.inconclusive) {
            (true, _) => Outcome::Pass,
            (false, true) => Outcome::Inconclusive,
            (false, false) => Outcome::Fail,
        }
    }
}

/// A case's answer from its criteria's.
pub fn case_outcome(judgements: &[Judgement]) -> Outcome {
    let outcomes = judgements.iter().map(Judgement::outcome);
    if outcomes.clone().any(|o| o == Outcome::Fail) {
        Outcome::Fail
    } else if outcomes.clone().any(|o| o == Outcome::Inconclusive) {
        Outcome::Inconclusive
    } else {
        Outcome::Pass
    }
}

/// Seconds since the Unix epoch.
pub fn unix_now_s() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs())
}

/// `YYYYMMDD-HHMMSS` in UTC, of `unix_s` or now.
pub fn utc_stamp(unix_s: Option<u64>) -> String {
    let s = unix_s.unwrap_or_else(unix_now_s);
    let (days, secs) = ((s / 86_400) as i64, s % 86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}{month:02}{day:02}-{:02}{:02}{:02}", secs / 3600, secs / 60 % 60, secs % 60)
}

fn xml_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out += "&amp;",
            '<' => out += "&lt;",
            '>' => out += "&gt;",
            '"' => out += "&quot;",
            '\'' => out += "&apos;",
            // XML 1.0 forbids most control characters, even escaped.
            c if (c as u32) < 0x20 && !matches!(c, '\n' | '\r' | '\t') => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

impl Verdict {
    /// Set `passed` (every selected case ran and passed) and `inconclusive` (every one ran, none failed, one or
    /// more inconclusive).
    pub fn concluded(mut self) -> Self {
        let whole = !self.interrupted && self.cases.len() == self.cases_in_suite;
        self.passed = whole && self.cases.iter().all(|c| c.passed);
        self.inconclusive = whole
            && !self.passed
            && self.cases.iter().all(|c| c.outcome() != Outcome::Fail)
            && self.cases.iter().any(|c| c.inconclusive);
        self
    }

    /// The check's answer.
    pub fn outcome(&self) -> Outcome {
        match (self.passed, self.inconclusive) {
            (true, _) => Outcome::Pass,
            (false, true) => Outcome::Inconclusive,
            (false, false) => Outcome::Fail,
        }
    }

    /// The cases not flown.
    pub fn not_flown(&self) -> usize {
        self.cases.iter().filter(|c| c.not_flown.is_some()).count()
    }

    /// Criteria judged, how many failed and how many were inconclusive.
    pub fn counts(&self) -> (usize, usize, usize) {
        let all = self.cases.iter().flat_map(|c| &c.judgements);
        let of = |o: Outcome| all.clone().filter(|j| j.outcome() == o).count();
        (all.clone().count(), of(Outcome::Fail), of(Outcome::Inconclusive))
    }

    /// The table a person reads, each failure explained with the command that reproduces it, and the verdict.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "silrig check: suite {} ({} case{}), controller {}\n\n",
            self.suite,
            self.cases.len(),
            if self.cases.len() == 1 { "" } else { "s" },
            self.controller
        );
        let w_case = self.cases.iter().map(|c| c.name.len()).max().unwrap_or(4).max(4);
        let rows: Vec<(&str, &Judgement)> =
            self.cases.iter().flat_map(|c| c.judgements.iter().map(move |j| (c.name.as_str(), j))).collect();
        let w_crit = rows.iter().map(|(_, j)| j.criterion.len()).max().unwrap_or(9).max(9);
        let w_meas = rows.iter().map(|(_, j)| j.measured.len()).max().unwrap_or(8).max(8);
        let w_lim = rows.iter().map(|(_, j)| j.limit.len()).max().unwrap_or(5).max(5);
        let _ = writeln!(
            out,
            "{:<w_case$}  {:<w_crit$}  {:<w_meas$}  {:<w_lim$}  result",
            "case", "criterion", "measured", "limit"
        );
        for case in &self.cases {
            if case.not_flown.is_some() {
                let _ = writeln!(
                    out,
                    "{:<w_case$}  {:<w_crit$}  {:<w_meas$}  {:<w_lim$}  not flown",
                    case.name, "-", "-", "-"
                );
            }
            for (i, j) in case.judgements.iter().enumerate() {
                let name = if i == 0 { case.name.as_str() } else { "" };
                let result = j.outcome().label();
                let _ = writeln!(
                    out,
                    "{name:<w_case$}  {:<w_crit$}  {:<w_meas$}  {:<w_lim$}  {result}",
                    j.criterion, j.measured, j.limit
                );
            }
        }
        for case in self.cases.iter().filter(|c| !c.passed && c.not_flown.is_none()) {
            let why = if case.why.is_empty() { String::new() } else { format!(": {}", case.why) };
            let (heading, flown) = match case.outcome() {
                Outcome::Inconclusive => ("INCONCLUSIVE", format!(" (flown {} times)", case.attempts)),
                _ => ("FAILED", String::new()),
            };
            let _ = writeln!(out, "\n{heading} {}{why}{flown}", case.name);
            for j in case.judgements.iter().filter(|j| !j.passed) {
                let said = j.why_failed.as_deref().or(j.inconclusive.as_deref()).unwrap_or("failed");
                let _ = writeln!(out, "  {}: {said}", j.criterion);
            }
            let _ = writeln!(out, "  run folder: {}", case.run_dirs.join(", "));
            let _ = writeln!(out, "  reproduce:  {}", case.reproduce);
        }
        let not_flown: Vec<&CaseVerdict> = self.cases.iter().filter(|c| c.not_flown.is_some()).collect();
        if let Some(first) = not_flown.first() {
            let names: Vec<&str> = not_flown.iter().map(|c| c.name.as_str()).collect();
            let _ =
                writeln!(out, "\nNOT FLOWN {}: {}", names.join(", "), first.not_flown.as_deref().unwrap_or_default());
        }
        let (criteria, failed, inconclusive) = self.counts();
        let passed_cases = self.cases.iter().filter(|c| c.passed).count();
        let _ = writeln!(out);
        if self.interrupted {
            let _ = writeln!(out, "interrupted after {} of {} cases", self.cases.len(), self.cases_in_suite);
        }
        let not_flown = match self.not_flown() {
            0 => String::new(),
            n => format!(", {n} case{} not flown", if n == 1 { "" } else { "s" }),
        };
        let _ = writeln!(
            out,
            "verdict: {}: {passed_cases} of {} cases passed, {failed} of {criteria} criteria failed, {inconclusive} \
             inconclusive{not_flown}, {:.1} s",
            self.outcome().label().to_uppercase(),
            self.cases_in_suite,
            self.wall_s
        );
        let _ = writeln!(out, "wrote {}/{JSON_FILE} and {}/{JUNIT_FILE}", self.out_dir, self.out_dir);
        out
    }

    /// JUnit XML: one `<testsuite>` per case, one `<testcase>` per criterion, a `<failure>` with the explanation
    /// and the reproducing command.
    pub fn to_junit(&self) -> String {
        let (judged, failures, inconclusive) = self.counts();
        // A case not flown is one skipped test of its own, with the reason.
        let (tests, skipped) = (judged + self.not_flown(), inconclusive + self.not_flown());
        let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let _ = writeln!(
            out,
            "<testsuites name=\"silrig check {}\" tests=\"{tests}\" failures=\"{failures}\" errors=\"0\" skipped=\"{skipped}\" time=\"{:.3}\">",
            xml_escape(&self.suite),
            self.wall_s
        );
        for case in &self.cases {
            let of = |o: Outcome| case.judgements.iter().filter(|j| j.outcome() == o).count();
            let not_flown = usize::from(case.not_flown.is_some());
            let (failed, skipped) = (of(Outcome::Fail), of(Outcome::Inconclusive) + not_flown);
            let _ = writeln!(
                out,
                "  <testsuite name=\"{}.{}\" tests=\"{}\" failures=\"{failed}\" errors=\"0\" skipped=\"{skipped}\" time=\"{:.3}\" timestamp=\"{}\">",
                xml_escape(&self.suite),
                xml_escape(&case.name),
                case.judgements.len() + not_flown,
                case.wall_s,
                xml_escape(&utc_iso(self.started_unix_s)),
            );
            let _ = writeln!(out, "    <properties>");
            for (name, value) in [
                ("controller", self.controller.as_str()),
                ("why", case.why.as_str()),
                ("mode", case.mode.as_str()),
                ("run_dir", &case.run_dirs.join(", ")),
                ("reproduce", case.reproduce.as_str()),
            ] {
                let _ = writeln!(out, "      <property name=\"{name}\" value=\"{}\"/>", xml_escape(value));
            }
            let _ = writeln!(out, "    </properties>");
            if let Some(why) = &case.not_flown {
                let _ = writeln!(
                    out,
                    "    <testcase classname=\"{}.{}\" name=\"not_flown\" time=\"0\">\n      <skipped message=\"{}\"/>\n    </testcase>",
                    xml_escape(&self.suite),
                    xml_escape(&case.name),
                    xml_escape(&format!("not flown: {why}"))
                );
            }
            for j in &case.judgements {
                let _ = write!(
                    out,
                    "    <testcase classname=\"{}.{}\" name=\"{}\" time=\"0\"",
                    xml_escape(&self.suite),
                    xml_escape(&case.name),
                    xml_escape(&j.criterion)
                );
                if j.passed {
                    let _ = writeln!(out, "/>");
                } else if let Some(why) = &j.inconclusive {
                    // A CI test reporter's third state: neither passed nor failed.
                    let _ = writeln!(
                        out,
                        ">\n      <skipped message=\"{}\"/>\n    </testcase>",
                        xml_escape(&format!("inconclusive: measured {}, limit {}: {why}", j.measured, j.limit))
                    );
                } else {
                    let why = j.why_failed.as_deref().unwrap_or("failed");
                    let _ = writeln!(
                        out,
                        ">\n      <failure type=\"criterion\" message=\"{}\">measured: {}\nlimit: {}\n{}\nrun folder: {}\nreproduce: {}</failure>\n    </testcase>",
                        xml_escape(&format!("{}: measured {}, limit {}", j.criterion, j.measured, j.limit)),
                        xml_escape(&j.measured),
                        xml_escape(&j.limit),
                        xml_escape(why),
                        xml_escape(&case.run_dirs.join(", ")),
                        xml_escape(&case.reproduce)
                    );
                }
            }
            let _ = writeln!(out, "  </testsuite>");
        }
        out += "</testsuites>\n";
        out
    }

    /// Write `check.json` and `check.junit.xml` into `out`.
    pub fn write(&self, out: &Path) -> anyhow::Result<()> {
        std::fs::create_dir_all(out)?;
        std::fs::write(out.join(JSON_FILE), serde_json::to_string_pretty(self)? + "\n")?;
        std::fs::write(out.join(JUNIT_FILE), self.to_junit())?;
        Ok(())
    }
}

/// ISO 8601 UTC time of `unix_s` (JUnit's `timestamp`, the check's page).
pub fn utc_iso(unix_s: u64) -> String {
    let s = utc_stamp(Some(unix_s));
    format!("{}-{}-{}T{}:{}:{}", &s[0..4], &s[4..6], &s[6..8], &s[9..11], &s[11..13], &s[13..15])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_stamp_matches_known_dates() {
        assert_eq!(utc_stamp(Some(0)), "19700101-000000");
        // 2000-02-29 12:34:56 UTC, a leap day.
        assert_eq!(utc_stamp(Some(951_827_696)), "20000229-123456");
        assert_eq!(utc_iso(1_795_000_000), "2026-11-18T11:06:40");
    }

    fn case(name: &str, judgements: Vec<Judgement>) -> CaseVerdict {
        let outcome = case_outcome(&judgements);
        CaseVerdict {
            name: name.into(),
            why: String::new(),
            mode: "realtime".into(),
            faults: Vec::new(),
            passed: outcome == Outcome::Pass,
            inconclusive: outcome == Outcome::Inconclusive,
            attempts: 3,
            wall_s: 1.0,
            run_dirs: vec!["out/x".into()],
            reproduce: "silrig check --case x".into(),
            judgements,
            not_flown: None,
        }
    }

    fn verdict(cases: Vec<CaseVerdict>) -> Verdict {
        Verdict {
            suite: "s".into(),
            suite_file: None,
            description: String::new(),
            controller: "c".into(),
            out_dir: "out".into(),
            started_unix_s: 0,
            wall_s: 1.0,
            interrupted: false,
            cases_in_suite: cases.len(),
            passed: false,
            inconclusive: false,
            cases,
        }
        .concluded()
    }

    #[test]
    fn an_inconclusive_criterion_is_neither_pass_nor_fail_in_every_form_and_a_failure_outranks_it() {
        use silrig_flight::judge::{inconclusive, judgement};
        let pass = judgement("run_completed", "10 s".into(), "10 s".into(), None);
        let unsure =
            inconclusive("sense_to_actuate_p99", "900 us".into(), "650 us".into(), "the machine stalled".into());
        let fail = judgement("settled", "never".into(), "8 s".into(), Some("never settled".into()));
        let v = verdict(vec![case("a", vec![pass.clone(), unsure.clone()]), case("b", vec![pass.clone()])]);
        assert_eq!(v.outcome(), Outcome::Inconclusive);
        assert_eq!(super::super::exit_status(v.outcome()), 3);
        assert_eq!(v.counts(), (3, 0, 1));
        let text = v.to_text();
        assert!(text.contains("INCONCLUSIVE a (flown 3 times)") && text.contains("the machine stalled"), "{text}");
        assert!(text.contains("verdict: INCONCLUSIVE: 1 of 2 cases passed, 0 of 3 criteria failed, 1 inconclusive"));
        let junit = v.to_junit();
        assert!(junit.contains("failures=\"0\" errors=\"0\" skipped=\"1\""), "{junit}");
        assert!(
            junit.contains("<skipped message=\"inconclusive: measured 900 us, limit 650 us: the machine stalled\"/>")
        );
        let json: serde_json::Value = serde_json::from_str(&serde_json::to_string(&v).unwrap()).unwrap();
        assert_eq!(json["inconclusive"], true);
        assert_eq!(json["cases"][0]["judgements"][1]["inconclusive"], "the machine stalled");
        // One failure anywhere makes the whole check fail.
        let v = verdict(vec![case("a", vec![unsure, fail]), case("b", vec![pass])]);
        assert_eq!((v.outcome(), super::super::exit_status(v.outcome())), (Outcome::Fail, 1));
    }

    #[test]
    fn xml_escape_handles_markup_and_control_characters() {
        assert_eq!(xml_escape("a<b & \"c\" 'd'\u{1}"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos; ");
    }

    #[test]
    fn a_case_not_flown_fails_the_check_and_says_why_in_the_table_and_as_a_skipped_junit_test() {
        use silrig_flight::judge::judgement;
        let failed = judgement("run_completed", "0.00 s flown".into(), "10 s".into(), Some("never joined".into()));
        let suite = super::super::suite::Suite::embedded_default();
        let why = "the flight never started in case `a`: controller: exit status 0 before the plant's first tick";
        let rest = CaseVerdict::not_flown(&suite.cases[1], "silrig check --case b".into(), why.into());
        assert_eq!((rest.outcome(), rest.attempts, rest.judgements.len()), (Outcome::Fail, 0, 0));
        let v = verdict(vec![case("a", vec![failed]), rest]);
        assert_eq!((v.outcome(), v.not_flown()), (Outcome::Fail, 1));
        let text = v.to_text();
        assert!(text.contains(&format!("NOT FLOWN realtime-deadline: {why}")), "{text}");
        assert!(
            text.contains(
                "verdict: FAIL: 0 of 2 cases passed, 1 of 1 criteria failed, 0 inconclusive, 1 case not flown"
            ),
            "{text}"
        );
        let junit = v.to_junit();
        assert!(junit.contains("tests=\"2\" failures=\"1\" errors=\"0\" skipped=\"1\""), "{junit}");
        assert!(
            junit.contains(
                "name=\"not_flown\" time=\"0\">\n      <skipped message=\"not flown: the flight never started"
            ),
            "{junit}"
        );
    }
}
