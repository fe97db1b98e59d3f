//! The rig's side of a check case's criteria (`[cases.criteria]`): the timing, contract and fault criteria judged
//! from the run's report (`report.json`) and trace, beside the flight criteria of [`silrig_flight::criteria`], so the
//! rig's controller and a user's are judged by the same code.

use super::recovery::{
    comebacks, failsafe_engaged_and_released, recovered_within, restart_join_within, restarts, resume_jump,
};
use super::timing::{budget, counter, deadline_misses, every_tick_answered};
use silrig_flight::criteria::positive;
pub use silrig_flight::criteria::{Criteria, Judgement, Outcome};
use silrig_flight::judge::{judge_flight, judgement, no_evidence};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::trace::Trace;
use silrig_launch::run_report::RigReport;
use silrig_rig::RigMode;

/// One run of a case: its merged report and its logged trace (None if it logged nothing).
pub struct RunEvidence {
    /// `report.json`.
    pub report: RigReport,
    /// `trace.csv`.
    pub trace: Option<Trace>,
    /// When the plant held a command for want of an answer (the plant's send times of the samples after those
    /// ticks, `timing.csv`), to set beside the OS floor's stalls.
    pub held_ns: Vec<u64>,
}

impl RunEvidence {
    /// Why the flight never started (the logger recorded no tick and the plant flew none): the run's first
    /// failure, which names the controller or plant that never joined or exited at once. None once it flew.
    pub fn never_started(&self) -> Option<String> {
        let flew = self.trace.is_some() || counter(&self.report, Role::Plant, "ticks").is_some_and(|t| t > 0);
        (!flew).then(|| self.report.failures.first().cloned().unwrap_or_else(|| "no process said why".into()))
    }
}

/// The rig's criteria of a case, judged from its runs' reports and traces: what `silrig check` adds to the flight
/// criteria of [`Criteria`], which live below the rig.
pub trait RigCriteria {
    /// Whether the case must be flown twice.
    fn runs(&self) -> usize;

    /// Refuse what cannot be judged for a case of this mode and scenario (before anything flies).
    fn validate(&self, mode: RigMode, scenario: &Scenario) -> Result<(), String>;

    /// Judge the case's runs: `run_completed` first, then each criterion the case names, in a fixed order.
    fn judge(&self, scenario: &Scenario, runs: &[RunEvidence]) -> Vec<Judgement>;
}

impl RigCriteria for Criteria {
    fn runs(&self) -> usize {
        if self.deterministic { 2 } else { 1 }
    }

    fn validate(&self, mode: RigMode, scenario: &Scenario) -> Result<(), String> {
        let duration = scenario.timing.duration_s;
        for (key, budget) in [("compute_p99", &self.compute_p99), ("sense_to_actuate_p99", &self.sense_to_actuate_p99)]
        {
            let Some(b) = budget else { continue };
            if b.max_us.is_none() && b.max_period_fraction.is_none() && b.max_os_floor_ratio.is_none() {
                return Err(format!(
                    "`criteria.{key}` needs one or more of `max_us`, `max_period_fraction` and `max_os_floor_ratio`"
                ));
            }
            if let Some(us) = b.max_us {
                positive(&format!("{key}.max_us"), us)?;
            }
            if let Some(f) = b.max_period_fraction {
                positive(&format!("{key}.max_period_fraction"), f)?;
            }
            if let Some(r) = b.max_os_floor_ratio {
                positive(&format!("{key}.max_os_floor_ratio"), r)?;
                if mode == RigMode::Lockstep {
                    return Err(format!(
                        "`criteria.{key}.max_os_floor_ratio` needs `mode = \"realtime\"` (the OS floor is measured \
                         beside a realtime run)"
                    ));
                }
            }
        }
        self.validate_flight(duration, &|name| scenario.setpoint.get(name).is_some())?;
        if let Some(t) = self.recovered_within_s {
            positive("recovered_within_s", t)?;
            if comebacks(scenario, None).is_empty() {
                return Err("`criteria.recovered_within_s` needs a fault a process comes back from (kill or term \
                            with restart_after, or stop) in `faults`"
                    .into());
            }
        }
        if let Some(t) = self.restart_join_within_s {
            positive("restart_join_within_s", t)?;
            if restarts(scenario).is_empty() {
                return Err("`criteria.restart_join_within_s` needs a process restarted in `faults` (kill or term \
                            with restart_after)"
                    .into());
            }
        }
        if let Some(j) = self.resume_jump_max_deg {
            positive("resume_jump_max_deg", j)?;
            if comebacks(scenario, Some(Role::Controller)).is_empty() {
                return Err("`criteria.resume_jump_max_deg` needs a controller fault it comes back from (kill or \
                            term with restart_after, or stop) in `faults`"
                    .into());
            }
        }
        if self.failsafe_engaged_and_released && scenario.faults.is_empty() {
            return Err("`criteria.failsafe_engaged_and_released` needs a fault in `faults`".into());
        }
        if self.deterministic && mode != RigMode::Lockstep {
            return Err("`criteria.deterministic` needs `mode = \"lockstep\"` (realtime runs differ by design)".into());
        }
        Ok(())
    }

    fn judge(&self, scenario: &Scenario, runs: &[RunEvidence]) -> Vec<Judgement> {
        let first = &runs[0];
        let mut out = vec![run_completed(scenario, runs)];
        let report = &first.report;
        let trace = first.trace.as_ref();
        if self.every_tick_answered {
            out.push(every_tick_answered(report, &first.held_ns));
        }
        if self.no_invalid_command {
            out.push(no_invalid_command(report));
        }
        if let Some(b) = &self.compute_p99 {
            out.push(budget(report, scenario, "compute_p99", "controller.compute", "controller.compute", b));
        }
        if let Some(b) = &self.sense_to_actuate_p99 {
            out.push(budget(
                report,
                scenario,
                "sense_to_actuate_p99",
                "plant.sense_to_actuate",
                "plant.sense_to_actuate_steady",
                b,
            ));
        }
        if let Some(n) = self.deadline_misses_max {
            out.push(deadline_misses(report, &first.held_ns, n));
        }
        out.extend(judge_flight(self, scenario, trace, report.control.as_ref()));
        if let Some(t) = self.recovered_within_s {
            out.push(recovered_within(scenario, report, t));
        }
        if let Some(t) = self.restart_join_within_s {
            out.push(restart_join_within(scenario, report, t));
        }
        if self.failsafe_engaged_and_released {
            out.push(failsafe_engaged_and_released(report));
        }
        if let Some(j) = self.resume_jump_max_deg {
            out.push(resume_jump(scenario, report, trace, j));
        }
        if self.deterministic {
            out.push(deterministic(runs));
        }
        out
    }
}

fn run_completed(scenario: &Scenario, runs: &[RunEvidence]) -> Judgement {
    let duration = scenario.timing.duration_s;
    let limit = format!("{duration:.2} s flown, no process failed");
    let mut problems = Vec::new();
    let mut flown_s = f64::INFINITY;
    for (i, run) in runs.iter().enumerate() {
        let which = if runs.len() > 1 { format!("run {}: ", i + 1) } else { String::new() };
        problems.extend(run.report.failures.iter().map(|f| format!("{which}{f}")));
        let last_t = run.trace.as_ref().and_then(|t| t.column("t_s")).and_then(|t| t.last().copied());
        // The trace's last row is the end of the flight (t = duration for a whole one).
        flown_s = flown_s.min(last_t.unwrap_or(0.0));
        match last_t {
            None => problems.push(format!("{which}the logger recorded no tick")),
            Some(t) if t < duration - 0.5 * scenario.timing.dt_s => {
                problems.push(format!("{which}the logged flight ended at {t:.2} s of {duration:.2} s"))
            }
            Some(_) => {}
        }
    }
    let measured =
        format!("{flown_s:.2} s flown, {} failure(s)", runs.iter().map(|r| r.report.failures.len()).sum::<usize>());
    let failure = (!problems.is_empty()).then(|| {
        format!(
            "the run did not finish cleanly: {}. The processes' stderr logs and events.jsonl in the run folder say \
             what happened",
            problems.join("; ")
        )
    });
    judgement("run_completed", measured, limit, failure)
}

fn no_invalid_command(report: &RigReport) -> Judgement {
    let limit = "0 invalid commands".to_string();
    if counter(report, Role::Plant, "ticks").is_none() {
        return no_evidence("no_invalid_command", limit, "the plant wrote no report");
    }
    let held = counter(report, Role::Plant, "commands_refused_held").unwrap_or(0);
    let refused = counter(report, Role::Controller, "commands_refused").unwrap_or(0).max(held);
    let invalid = counter(report, Role::Plant, "commands_invalid").unwrap_or(0);
    let n = refused + invalid;
    let failure = (n > 0).then(|| {
        format!(
            "the controller produced {n} command(s) that were NaN, infinite or out of range ({refused} refused \
             before sending, {invalid} rejected by the plant); the plant held the previous command each time. \
             events.jsonl has a `command-refused` event naming the field and value"
        )
    });
    judgement("no_invalid_command", format!("{n} invalid"), limit, failure)
}

fn deterministic(runs: &[RunEvidence]) -> Judgement {
    deterministic_traces(runs[0].trace.as_ref(), runs.get(1).and_then(|r| r.trace.as_ref()))
}

/// `deterministic`: the commands of two flights of the same case, tick by tick, bit for bit.
pub fn deterministic_traces(a: Option<&Trace>, b: Option<&Trace>) -> Judgement {
    let limit = "2 runs, identical commands".to_string();
    let (Some(a), Some(b)) = (a, b) else {
        return no_evidence("deterministic", limit, "a run logged no trace");
    };
    // The command columns of whatever plant flew: the F-16's `<surface>_cmd_deg`, any plant's `<input>_cmd[_unit]`.
    let names: Vec<&String> = a.columns.iter().filter(|c| c.contains("_cmd")).collect();
    let columns = |t: &Trace| -> Vec<Vec<f64>> {
        names.iter().map(|c| t.column(c).unwrap_or_else(|| vec![f64::NAN; t.rows.len()])).collect()
    };
    let (ca, cb) = (columns(a), columns(b));
    let t = a.column("t_s").unwrap_or_default();
    let rows = a.rows.len().min(b.rows.len());
    for k in 0..rows {
        for (c, name) in names.iter().enumerate() {
            if ca[c][k].to_bits() != cb[c][k].to_bits() {
                return judgement(
                    "deterministic",
                    format!("differ from tick {k}"),
                    limit,
                    Some(format!(
                        "the same scenario flown twice gave different commands: at tick {k} (t = {:.2} s) {name} was \
                         {} in run 1 and {} in run 2; a controller that reads the clock, a random source without a \
                         fixed seed or uninitialised memory cannot be replayed or regression-tested",
                        t[k], ca[c][k], cb[c][k]
                    )),
                );
            }
        }
    }
    if a.rows.len() != b.rows.len() {
        return judgement(
            "deterministic",
            format!("{} vs {} ticks", a.rows.len(), b.rows.len()),
            limit,
            Some("the two runs logged a different number of ticks".into()),
        );
    }
    judgement("deterministic", format!("identical over {rows} ticks"), limit, None)
}
