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
    /// Cases in the sweep.
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
    /// Per criterion: the worst `WORST_LISTED` flown cases that stayed within the aerodynamic data (largest figure
    /// first; never settled counts as worst). Departed cases are listed apart: past their departure no figure
    /// means anything.
    pub worst: Vec<(String, Vec<WorstCase>)>,
    /// Every departed case, in index order.
    pub departed_cases: Vec<DepartedCase>,
    /// Every infeasible case.
    pub infeasible_cases: Vec<InfeasibleCase>,
}

/// The command that flies case `index` alone.
pub fn reproduce_command(config: &str, seed: u64, index: u64) -> String {
    format!("silrig sim {config} --sample {index} --seed {seed}")
}

/// Summarise `cases` (sorted by index).
pub fn summarize(
    cases: &[CaseResult],
    scenario: &str,
    config: &str,
    seed: u64,
    parameters: &[String],
    criteria: &Criteria,
) -> SweepSummary {
    let count = |o: Outcome| cases.iter().filter(|c| c.outcome == o).count() as u64;
    let (passed, failed, infeasible) = (count(Outcome::Pass), count(Outcome::Fail), count(Outcome::Infeasible));
    let flown: Vec<&CaseResult> = cases.iter().filter(|c| c.outcome != Outcome::Infeasible).collect();
    let departure = |c: &CaseResult| c.figures.as_ref().and_then(|f| f.departed_at_s);
    let in_data: Vec<&CaseResult> = flown.iter().copied().filter(|c| departure(c).is_none()).collect();
    let names: Vec<String> =
        flown.first().map(|c| c.judgements.iter().map(|j| j.criterion.clone()).collect()).unwrap_or_default();
    let mut failures_by_criterion = Vec::new();
    let mut worst = Vec::new();
    for (k, name) in names.iter().enumerate() {
        failures_by_criterion.push((name.clone(), flown.iter().filter(|c| !c.judgements[k].passed).count() as u64));
        let mut ranked: Vec<&&CaseResult> = in_data.iter().collect();
        // Worst first: no figure (never settled) before the largest figure; ties by index, so the order is stable.
        ranked.sort_by(|a, b| {
            let key = |c: &CaseResult| c.judgements[k].value.unwrap_or(f64::INFINITY);
            key(b).total_cmp(&key(a)).then(a.index.cmp(&b.index))
        });
        let listed = ranked
            .iter()
            .take(WORST_LISTED)
            .map(|c| WorstCase {
                index: c.index,
                measured: c.judgements[k].measured.clone(),
                passed: c.judgements[k].passed,
                reproduce: reproduce_command(config, seed, c.index),
            })
            .collect();
        worst.push((name.clone(), listed));
    }
    let pass_rate = if passed + failed > 0 { passed as f64 / (passed + failed) as f64 } else { 0.0 };
    SweepSummary {
        scenario: scenario.into(),
        config: config.into(),
        seed,
        runs: cases.len() as u64,
        parameters: parameters.to_vec(),
        criteria: criteria.clone(),
        passed,
        failed,
        infeasible,
        departed: (flown.len() - in_data.len()) as u64,
        pass_rate,
        pass_rate_95: wilson_95(passed, passed + failed),
        failures_by_criterion,
        worst,
        departed_cases: flown
            .iter()
            .filter_map(|c| {
                departure(c).map(|at_s| DepartedCase {
                    index: c.index,
                    at_s,
                    reason: c.reason.split(';').next().unwrap_or_default().to_string(),
                    reproduce: reproduce_command(config, seed, c.index),
                })
            })
            .collect(),
        infeasible_cases: cases
            .iter()
            .filter(|c| c.outcome == Outcome::Infeasible)
            .map(|c| InfeasibleCase { index: c.index, reason: c.reason.clone() })
            .collect(),
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

/// `cases.csv`: one row per case. Numbers are written in Rust's shortest round-trip form; an empty cell is a figure
/// that does not exist (never settled, or a case that was not flown).
pub fn cases_csv(cases: &[CaseResult], parameters: &[String]) -> String {
    let criteria: Vec<String> = cases
        .iter()
        .find(|c| c.outcome != Outcome::Infeasible)
        .map(|c| c.judgements.iter().map(|j| j.criterion.clone()).collect())
        .unwrap_or_default();
    let mut out = String::from("index,outcome,reason");
    for p in parameters {
        out += &format!(",{p}");
    }
    out += ",phi_settle_s,theta_settle_s,psi_settle_s,phi_final_error_deg,theta_final_error_deg,psi_final_error_deg,\
            alpha_peak_deg,p_max_late_dps,q_max_late_dps,r_max_late_dps,rate_limit_fraction,limit_cycle,departed_at_s";
    for c in &criteria {
        out += &format!(",{c},{c}_passed");
    }
    out.push('\n');
    for case in cases {
        // Reasons may hold commas; quote them as CSV does.
        let _ = write!(out, "{},{},\"{}\"", case.index, case.outcome.label(), case.reason.replace('"', "\"\""));
        for v in &case.values {
            let _ = write!(out, ",{v}");
        }
        match &case.figures {
            Some(f) => {
                for s in f.settle_0p5deg_s {
                    let _ = write!(out, ",{}", opt(s));
                }
                for v in
                    f.final_error_deg.iter().chain([f.alpha_peak_deg].iter()).chain(f.body_rate_max_late_dps.iter())
                {
                    let _ = write!(out, ",{}", opt(*v));
                }
                let _ = write!(out, ",{},{},{}", f.rate_limit_fraction, u8::from(f.limit_cycle), opt(f.departed_at_s));
            }
            None => out += &",".repeat(13),
        }
        for k in 0..criteria.len() {
            match case.judgements.get(k) {
                Some(j) => {
                    let _ = write!(out, ",{},{}", opt(j.value), u8::from(j.passed));
                }
                None => out += ",,",
            }
        }
        out.push('\n');
    }
    out
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
        for ((name, failures), (_, worst)) in self.failures_by_criterion.iter().zip(&self.worst) {
            let _ = writeln!(out, "  {name}: failed in {failures} of {flown}");
            for w in worst.iter().take(3) {
                let _ = writeln!(
                    out,
                    "    case {:<6} {:<34} {}   {}",
                    w.index,
                    w.measured,
                    if w.passed { "pass" } else { "FAIL" },
                    w.reproduce
                );
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
