//! `silrig check --repeat N`: the flake benchmark. The suite is flown N times in a row, each check into a folder of
//! its own, and every criterion's answers are counted: a verdict to gate on gives the same answer every time, so
//! the table shows which criteria changed their answer and how often. Figures for the book, never a test bound.

use super::verdict::{self, Verdict};
use super::{CheckError, CheckOptions};
use serde::Serialize;
use silrig_flight::criteria::Outcome;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The file the repeated check writes beside its checks.
pub const JSON_FILE: &str = "repeat.json";

/// One criterion of one case over the repeated checks.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Tally {
    /// How many checks it passed, failed, was inconclusive in.
    pub pass: u32,
    /// Failed.
    pub fail: u32,
    /// Inconclusive.
    pub inconclusive: u32,
    /// Its measured figure in each check, in order.
    pub measured: Vec<String>,
}

impl Tally {
    /// Whether its answer was not the same every time.
    pub fn changed(&self) -> bool {
        [self.pass, self.fail, self.inconclusive].iter().filter(|n| **n > 0).count() > 1
    }
}

/// The repeated check (`repeat.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Repeated {
    /// Suite name.
    pub suite: String,
    /// The controller judged.
    pub controller: String,
    /// Checks flown (fewer than asked if interrupted).
    pub checks: u32,
    /// How many checks ended pass, fail, inconclusive.
    pub verdicts: BTreeMap<String, u32>,
    /// Per `case/criterion`, in suite order.
    pub criteria: Vec<(String, Tally)>,
    /// The checks' folders.
    pub out_dirs: Vec<String>,
}

impl Repeated {
    fn new(verdicts: &[Verdict]) -> Self {
        let mut criteria: Vec<(String, Tally)> = Vec::new();
        let mut outcomes = BTreeMap::new();
        for v in verdicts {
            *outcomes.entry(v.outcome().label().to_lowercase()).or_insert(0) += 1;
            for case in &v.cases {
                for j in &case.judgements {
                    let key = format!("{}/{}", case.name, j.criterion);
                    let at = match criteria.iter().position(|(k, _)| *k == key) {
                        Some(at) => at,
                        None => {
                            criteria.push((key, Tally::default()));
                            criteria.len() - 1
                        }
                    };
                    let tally = &mut criteria[at].1;
                    match j.outcome() {
                        Outcome::Pass => tally.pass += 1,
                        Outcome::Fail => tally.fail += 1,
                        Outcome::Inconclusive => tally.inconclusive += 1,
                    }
                    tally.measured.push(j.measured.clone());
                }
            }
        }
        let first = verdicts.first();
        Self {
            suite: first.map(|v| v.suite.clone()).unwrap_or_default(),
            controller: first.map(|v| v.controller.clone()).unwrap_or_default(),
            checks: verdicts.len() as u32,
            verdicts: outcomes,
            criteria,
            out_dirs: verdicts.iter().map(|v| v.out_dir.clone()).collect(),
        }
    }

    /// The worst answer of the checks: fail, else inconclusive, else pass.
    pub fn outcome(&self) -> Outcome {
        let count = |o: &str| self.verdicts.get(o).copied().unwrap_or(0);
        if count("fail") > 0 {
            Outcome::Fail
        } else if count("inconclusive") > 0 {
            Outcome::Inconclusive
        } else {
            Outcome::Pass
        }
    }

    /// The table: every criterion's answers over the checks, those that changed marked.
    pub fn to_text(&self) -> String {
        let w = self.criteria.iter().map(|(k, _)| k.len()).max().unwrap_or(9).max(9);
        let mut out = format!(
            "silrig check --repeat {}: suite {}, controller {}\n\n{:<w$}  {:>5}  {:>5}  {:>12}  answer\n",
            self.checks, self.suite, self.controller, "criterion", "pass", "fail", "inconclusive"
        );
        for (key, t) in &self.criteria {
            let answer = if t.changed() { "CHANGED" } else { "same every time" };
            let _ = writeln!(out, "{key:<w$}  {:>5}  {:>5}  {:>12}  {answer}", t.pass, t.fail, t.inconclusive);
        }
        let changed = self.criteria.iter().filter(|(_, t)| t.changed()).count();
        let verdicts: Vec<String> = self.verdicts.iter().map(|(k, n)| format!("{n} {k}")).collect();
        let _ = writeln!(
            out,
            "\n{} checks: {}; {changed} of {} criteria changed their answer",
            self.checks,
            verdicts.join(", "),
            self.criteria.len()
        );
        out
    }
}

/// Fly the suite `n` times, each check into `<out>/repeat-<k>`, and write `repeat.json` into `<out>`.
pub fn run(opts: &CheckOptions, n: u32) -> Result<(Repeated, PathBuf), CheckError> {
    let suite = opts.load_suite()?;
    let base = opts
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("check-repeat-{}-{}", suite.name, verdict::utc_stamp(None))));
    if base.join(JSON_FILE).exists() {
        return Err(CheckError::Usage(format!(
            "{} already holds a repeated check ({JSON_FILE}); choose another --out or move it away: nothing is \
             overwritten",
            base.display()
        )));
    }
    let mut verdicts = Vec::new();
    for k in 1..=n {
        eprintln!("silrig check --repeat: check {k} of {n}");
        let one = CheckOptions { out: Some(base.join(format!("repeat-{k}"))), repeat: None, ..opts.clone() };
        let v = super::run(&one)?;
        let interrupted = v.interrupted;
        verdicts.push(v);
        if interrupted {
            break;
        }
    }
    let repeated = Repeated::new(&verdicts);
    let file = base.join(JSON_FILE);
    std::fs::write(&file, serde_json::to_string_pretty(&repeated).expect("serialisable") + "\n").map_err(|e| {
        CheckError::Setup { case: "(repeat.json)".into(), problem: anyhow::anyhow!("{}: {e}", file.display()) }
    })?;
    Ok((repeated, file))
}
