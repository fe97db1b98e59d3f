//! What a sweep says: `cases.csv` (one row per case: the sampled values, the figures, each criterion), `sweep.json`
//! (outcomes, the pass rate with its 95 % Wilson interval, the worst cases by each criterion with the command that
//! flies each alone, every infeasible case with its reason) and the text a person reads. Built from the cases alone,
//! in index order, so the same cases give the same bytes however they were flown (one machine, threads, shards).

use super::case::{CaseResult, Outcome};
use serde::{Deserialize, Serialize};
use silrig_flight::criteria::Criteria;
use std::fmt::Write as _;

/// Cases listed per criterion among the worst.
pub const WORST_LISTED: usize = 10;

/// The 95 % Wilson score interval of `successes` out of `n` ((0, 1) for n = 0).
pub fn wilson_95(successes: u64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054_f64;
    let (n, p) = (n as f64, successes as f64 / n as f64);
    let denominator = 1.0 + z * z / n;
    let centre = (p + z * z / (2.0 * n)) / denominator;
    let half = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / denominator;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// One of the worst cases by a criterion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorstCase {
    /// Sample index.
    pub index: u64,
    /// The measured figure, as printed.
    pub measured: String,
    /// Whether the case met this criterion.
    pub passed: bool,
    /// The command that flies this case alone and prints the same numbers.
    pub reproduce: String,
}

/// A flown case that left the model's data (the F-16's aerodynamic tables) or whose plant or controller stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DepartedCase {
    /// Sample index.
    pub index: u64,
    /// When, s.
    pub at_s: f64,
    /// What left the data.
    pub reason: String,
    /// The command that flies it alone.
    pub reproduce: String,
}

/// An infeasible case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InfeasibleCase {
    /// Sample index.
    pub index: u64,
    /// Why it could not be flown.
    pub reason: String,
}

/// `sweep.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepSummary {
    /// Scenario name.
    pub scenario: String,
    /// The scenario file as given.
    pub config: String,
    /// Seed of the dispersions.
    pub seed: u64,
    /// Cases in the sweep (when it was interrupted, those flown before it).
    pub runs: u64,
    /// The dispersed keys, in the order of the values in `cases.csv`.
    pub parameters: Vec<String>,
    /// The criteria every case was judged by.
    pub criteria: Criteria,
    /// Cases that passed.
    pub passed: u64,
    /// Cases flown that failed a criterion.
    pub failed: u64,
    /// Cases that could not be flown.
    pub infeasible: u64,
    /// Flown cases that left the model's data or stopped (each also failed).
    pub departed: u64,
    /// passed / (passed + failed): the pass rate of the cases that could be flown.
    pub pass_rate: f64,
    /// 95 % Wilson interval of `pass_rate`.
    pub pass_rate_95: (f64, f64),
    /// Per criterion: how many flown cases failed it.
    pub failures_by_criterion: Vec<(String, u64)>,
    /// Per criterion: how many of those failures were departed cases (listed in `departed_cases`, not among the
    /// worst), so the worst cases and the failure counts agree.
    #[serde(default)]
    pub departed_failures_by_criterion: Vec<u64>,
    /// Per criterion: the worst `WORST_LISTED` flown cases that stayed within the aerodynamic data (largest figure
    /// first; never settled counts as worst). Departed cases are listed apart: past their departure no figure
    /// means anything.
    pub worst: Vec<(String, Vec<WorstCase>)>,
    /// The departed cases, in index order: the first `CASES_LISTED_MAX` (`departed` counts them all).
    pub departed_cases: Vec<DepartedCase>,
    /// The infeasible cases, in index order: the first `CASES_LISTED_MAX` (`infeasible` counts them all).
    pub infeasible_cases: Vec<InfeasibleCase>,
    /// A sweep stopped before its last case (SIGINT or SIGTERM): by what, and that `runs` counts the cases flown
    /// before it (`cases.csv` holds them, cases 0 to `runs` - 1); absent when every case asked was flown.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<String>,
}

/// The command that flies case `index` alone.
pub fn reproduce_command(config: &str, seed: u64, index: u64) -> String {
    format!("silrig sim {config} --sample {index} --seed {seed}")
}

/// Departed and infeasible cases listed in `sweep.json`, at most (the first ones, by index): `departed` and
/// `infeasible` count them all, and `cases.csv` holds every one with its reason.
pub const CASES_LISTED_MAX: usize = 1000;

/// One of the worst cases by a criterion, as ranked: its figure (never settled as infinite) and what is listed.
struct Ranked {
    key: f64,
    case: WorstCase,
}

/// `sweep.json` built case by case in index order, in memory bounded whatever the number of cases: counts, the
/// `WORST_LISTED` worst cases by each criterion, the first `CASES_LISTED_MAX` departed and infeasible cases.
pub struct Tally {
    summary: SweepSummary,
    worst: Vec<Vec<Ranked>>,
}

impl Tally {
    /// An empty summary of a sweep of `scenario` (the file `config`, as the printed commands name it) under `seed`,
    /// whose flown cases are judged by `criteria` as `criterion_names` (in the order of their judgements).
    pub fn new(
        scenario: &str,
        config: &str,
        seed: u64,
        parameters: &[String],
        criteria: &Criteria,
        criterion_names: &[String],
    ) -> Self {
        Self {
            summary: SweepSummary {
                scenario: scenario.into(),
                config: config.into(),
                seed,
                runs: 0,
                parameters: parameters.to_vec(),
                criteria: criteria.clone(),
                passed: 0,
                failed: 0,
                infeasible: 0,
                departed: 0,
                pass_rate: 0.0,
                pass_rate_95: (0.0, 1.0),
                failures_by_criterion: criterion_names.iter().map(|n| (n.clone(), 0)).collect(),
                departed_failures_by_criterion: vec![0; criterion_names.len()],
                worst: Vec::new(),
                departed_cases: Vec::new(),
                infeasible_cases: Vec::new(),
                interrupted: None,
            },
            worst: criterion_names.iter().map(|_| Vec::new()).collect(),
        }
    }

    /// Cases counted so far.
    pub fn cases(&self) -> u64 {
        self.summary.runs
    }

    /// Count the next case (cases come in index order).
    pub fn add(&mut self, c: &CaseResult) {
        let s = &mut self.summary;
        s.runs += 1;
        match c.outcome {
            Outcome::Pass => s.passed += 1,
            Outcome::Fail => s.failed += 1,
            Outcome::Infeasible => {
                s.infeasible += 1;
                if s.infeasible_cases.len() < CASES_LISTED_MAX {
                    s.infeasible_cases.push(InfeasibleCase { index: c.index, reason: c.reason.clone() });
                }
                return;
            }
        }
        for ((_, failures), j) in s.failures_by_criterion.iter_mut().zip(&c.judgements) {
            *failures += u64::from(!j.passed);
        }
        if let Some(at_s) = c.figures.as_ref().and_then(|f| f.departed_at_s) {
            s.departed += 1;
            for (failures, j) in s.departed_failures_by_criterion.iter_mut().zip(&c.judgements) {
                *failures += u64::from(!j.passed);
            }
            if s.departed_cases.len() < CASES_LISTED_MAX {
                s.departed_cases.push(DepartedCase {
                    index: c.index,
                    at_s,
                    reason: c.reason.split(';').next().unwrap_or_default().to_string(),
                    reproduce: reproduce_command(&s.config, s.seed, c.index),
                });
            }
            return;
        }
        // Worst first: no figure (never settled) before the largest figure; ties by index, so the order is stable.
        for (ranked, j) in self.worst.iter_mut().zip(&c.judgements) {
            let key = j.value.unwrap_or(f64::INFINITY);
            let at = ranked.partition_point(|r| r.key.total_cmp(&key).then(c.index.cmp(&r.case.index)).is_gt());
            if at < WORST_LISTED {
                let case = WorstCase {
                    index: c.index,
                    measured: j.measured.clone(),
                    passed: j.passed,
                    reproduce: reproduce_command(&s.config, s.seed, c.index),
                };
                ranked.insert(at, Ranked { key, case });
                ranked.truncate(WORST_LISTED);
            }
        }
    }

    /// The summary of the cases counted; `interrupted` says why it stopped short of the cases asked, if it did.
    pub fn finish(mut self, interrupted: Option<String>) -> SweepSummary {
        let s = &mut self.summary;
        s.pass_rate = if s.passed + s.failed > 0 { s.passed as f64 / (s.passed + s.failed) as f64 } else { 0.0 };
        s.pass_rate_95 = wilson_95(s.passed, s.passed + s.failed);
        s.worst = s
            .failures_by_criterion
            .iter()
            .zip(self.worst)
            .map(|((name, _), ranked)| (name.clone(), ranked.into_iter().map(|r| r.case).collect()))
            .collect();
        s.interrupted = interrupted;
        self.summary
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

/// The header of `cases.csv`: one row per case follows ([`case_csv_row`]): the sampled values, the summary's
/// `figures` (named by the plant's signals: [`silrig_flight::summary::case_columns`]), the limit cycle, the departure
/// and each criterion. Numbers are written in Rust's shortest round-trip form; an empty cell is a figure that does
/// not exist (never settled, or a case that was not flown).
pub fn cases_csv_header(parameters: &[String], figures: &[String], criterion_names: &[String]) -> String {
    let mut out = String::from("index,outcome,reason");
    for name in parameters.iter().chain(figures) {
        out += &format!(",{name}");
    }
    out += ",limit_cycle,departed_at_s";
    for c in criterion_names {
        out += &format!(",{c},{c}_passed");
    }
    out.push('\n');
    out
}

/// A case's row of `cases.csv` under the header of `figures` and `criteria` criteria, appended to `out`.
pub fn case_csv_row(out: &mut String, case: &CaseResult, figures: &[String], criteria: usize) {
    // Reasons may hold commas; quote them as CSV does.
    let _ = write!(out, "{},{},\"{}\"", case.index, case.outcome.label(), case.reason.replace('"', "\"\""));
    for v in &case.values {
        let _ = write!(out, ",{v}");
    }
    match &case.figures {
        Some(f) => {
            // By name: a case whose trace lacks a column (a controller that died before the first tick) leaves
            // its cells empty.
            for name in figures {
                let _ = write!(out, ",{}", opt(f.figure(name)));
            }
            let _ = write!(out, ",{},{}", u8::from(f.limit_cycle), opt(f.departed_at_s));
        }
        None => *out += &",".repeat(figures.len() + 2),
    }
    for k in 0..criteria {
        match case.judgements.get(k) {
            Some(j) => {
                let _ = write!(out, ",{},{}", opt(j.value), u8::from(j.passed));
            }
            None => *out += ",,",
        }
    }
    out.push('\n');
}

impl SweepSummary {
    /// The summary a person reads.
    pub fn to_text(&self) -> String {
        let flown = self.passed + self.failed;
        let mut out = format!(
            "sweep {}: {} cases of {} dispersed parameter(s), seed {}\n",
            self.scenario,
            self.runs,
            self.parameters.len(),
            self.seed
        );
        if let Some(why) = &self.interrupted {
            let _ = writeln!(out, "  interrupted: {why}");
        }
        let _ = writeln!(
            out,
            "  passed {} of {} flown: {:.1} % (95 % Wilson interval {:.1} .. {:.1} %); {} departed (left the \
             model's data or stopped); {} infeasible (not flown)",
            self.passed,
            flown,
            self.pass_rate * 100.0,
            self.pass_rate_95.0 * 100.0,
            self.pass_rate_95.1 * 100.0,
            self.departed,
            self.infeasible
        );
        // One column for every table, as wide as its widest figure listed.
        let width = self.worst.iter().flat_map(|(_, w)| w.iter().take(3)).map(|w| w.measured.chars().count()).max();
        let width = width.unwrap_or(0).max(34);
        for (k, ((name, failures), (_, worst))) in self.failures_by_criterion.iter().zip(&self.worst).enumerate() {
            let departed = self.departed_failures_by_criterion.get(k).copied().unwrap_or(0);
            let _ = match departed {
                0 => writeln!(out, "  {name}: failed in {failures} of {flown}"),
                d if d == *failures => writeln!(out, "  {name}: failed in {failures} of {flown}, all departed (below)"),
                d => writeln!(out, "  {name}: failed in {failures} of {flown}, {d} of them departed (below)"),
            };
            for w in worst.iter().take(3) {
                let verdict = if w.passed { "pass" } else { "FAIL" };
                let _ = writeln!(out, "    case {:<6} {:<width$} {verdict}   {}", w.index, w.measured, w.reproduce);
            }
        }
        if !self.departed_cases.is_empty() {
            let _ = writeln!(
                out,
                "  departed (left the model's data or stopped; the worst cases above are of the others):"
            );
        }
        for c in self.departed_cases.iter().take(3) {
            let _ = writeln!(out, "    case {:<6} {}   {}", c.index, c.reason, c.reproduce);
        }
        for c in self.infeasible_cases.iter().take(3) {
            let _ = writeln!(out, "  infeasible case {}: {}", c.index, c.reason);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_matches_published_values() {
        // Newcombe (1998), table I: 81 of 263 gives 0.2553 .. 0.3662.
        let (lo, hi) = wilson_95(81, 263);
        assert!((lo - 0.2553).abs() < 5e-4 && (hi - 0.3662).abs() < 5e-4, "{lo} {hi}");
        let (lo, hi) = wilson_95(10, 10);
        assert!((lo - 0.7225).abs() < 5e-4 && (hi - 1.0).abs() < 1e-12, "{lo} {hi}");
        assert_eq!(wilson_95(0, 0), (0.0, 1.0));
    }
}

/// Spearman's rank correlation of two equally long samples (ties get their mean rank).
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    fn ranks(v: &[f64]) -> Vec<f64> {
        let mut order: Vec<usize> = (0..v.len()).collect();
        order.sort_by(|a, b| v[*a].total_cmp(&v[*b]));
        let mut r = vec![0.0; v.len()];
        let mut i = 0;
        while i < order.len() {
            let mut j = i;
            while j + 1 < order.len() && v[order[j + 1]] == v[order[i]] {
                j += 1;
            }
            for k in i..=j {
                r[order[k]] = (i + j) as f64 / 2.0;
            }
            i = j + 1;
        }
        r
    }
    let (rx, ry) = (ranks(x), ranks(y));
    let n = x.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let cov: f64 = rx.iter().zip(&ry).map(|(a, b)| (a - mx) * (b - my)).sum();
    let (vx, vy): (f64, f64) = (rx.iter().map(|a| (a - mx).powi(2)).sum(), ry.iter().map(|b| (b - my).powi(2)).sum());
    if vx == 0.0 || vy == 0.0 { 0.0 } else { cov / (vx * vy).sqrt() }
}

#[cfg(test)]
mod rank_tests {
    use super::spearman;

    #[test]
    fn spearman_is_one_for_any_increasing_relation_and_handles_ties() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert!((spearman(&x, &[1.0, 4.0, 9.0, 16.0, 100.0]) - 1.0).abs() < 1e-12);
        assert!((spearman(&x, &[5.0, 4.0, 3.0, 2.0, 1.0]) + 1.0).abs() < 1e-12);
        // With a tie (mean ranks), as scipy.stats.spearmanr([1, 2, 3, 4, 5], [2, 1, 4, 3, 3]) gives: 0.5642880936.
        let rho = spearman(&x, &[2.0, 1.0, 4.0, 3.0, 3.0]);
        assert!((rho - 0.564_288_093_6).abs() < 1e-9, "{rho}");
        assert_eq!(spearman(&x, &[1.0; 5]), 0.0);
    }
}
