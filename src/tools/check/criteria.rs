//! The rig's side of a check case's criteria (`[cases.criteria]`): the timing, contract and fault criteria judged
//! from the run's report (`report.json`) and trace, beside the flight criteria of [`silrig_flight::criteria`], so the
//! rig's controller and a user's are judged by the same code.

use silrig_flight::criteria::Budget;
use silrig_flight::criteria::positive;
pub use silrig_flight::criteria::{Criteria, Judgement, Outcome};
use silrig_flight::fault::FaultAction;
use silrig_flight::judge::{inconclusive, judge_flight, judgement, no_evidence};
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
}

/// Faults of the case after which a process comes back: (index in the plan, when it comes back, s).
fn comebacks(scenario: &Scenario, target: Option<Role>) -> Vec<(usize, f64)> {
    let mut order: Vec<(usize, &silrig_flight::fault::Fault)> = scenario.faults.iter().enumerate().collect();
    order.sort_by(|a, b| a.1.at_s.total_cmp(&b.1.at_s));
    order
        .into_iter()
        .filter(|(_, f)| target.is_none_or(|t| f.target() == t))
        .filter_map(|(i, f)| match f.action() {
            FaultAction::Kill | FaultAction::Term => f.restart_after_s.map(|r| (i, f.at_s + r)),
            FaultAction::Stop => f.duration_s.map(|d| (i, f.at_s + d)),
            _ => None,
        })
        .collect()
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
            out.push(every_tick_answered(report));
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
            out.push(deadline_misses(report, n));
        }
        out.extend(judge_flight(self, scenario, trace, report.control.as_ref()));
        if let Some(t) = self.recovered_within_s {
            out.push(recovered_within(scenario, report, t));
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

fn counter(report: &RigReport, role: Role, name: &str) -> Option<u64> {
    report.processes.iter().find(|p| p.process == role.label()).and_then(|p| p.counters.get(name).copied())
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

fn every_tick_answered(report: &RigReport) -> Judgement {
    let limit = "0 ticks unanswered".to_string();
    let (Some(misses), Some(ticks)) =
        (counter(report, Role::Plant, "command_misses"), counter(report, Role::Plant, "ticks"))
    else {
        return no_evidence("every_tick_answered", limit, "the plant wrote no report");
    };
    let refused = counter(report, Role::Plant, "commands_refused_held").unwrap_or(0);
    let unanswered = misses.saturating_sub(refused);
    let failure = (unanswered > 0).then(|| {
        format!(
            "{unanswered} of {ticks} plant ticks found no answer from the controller when the plant needed it, so \
             the plant held the previous command (or flew its failsafe); a controller that is too slow, stalled or \
             gone leaves ticks unanswered"
        )
    });
    judgement("every_tick_answered", format!("{unanswered} of {ticks} ticks unanswered"), limit, failure)
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

/// What the machine itself added to every latency during a realtime run, µs: the p99 of the plant's own wake-up
/// lateness (it sleeps to absolute deadlines: nothing but the OS makes it late) and of the OS floor's timer loop
/// beside the run, whichever is larger, over the steady state. None in lockstep.
fn machine_noise_us(report: &RigReport) -> Option<(f64, String)> {
    let plant = report.steady("plant.wake_lateness").map(|l| l.p99_us);
    let floor = report.timer_baseline.as_ref().and_then(|b| b.lateness_steady.as_ref().or(Some(&b.lateness)));
    let floor = floor.filter(|l| l.count > 0).map(|l| l.p99_us);
    let noise = plant.into_iter().chain(floor).fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))?;
    let said = |v: Option<f64>| v.map_or("not measured".to_string(), |v| format!("{v:.1} us"));
    Some((
        noise,
        format!(
            "p99 of the plant's own wake-up lateness {}, of the OS floor beside the run {}",
            said(plant),
            said(floor)
        ),
    ))
}

/// What was judged, against what, and what the machine was doing meanwhile.
#[derive(Debug, Clone, Copy)]
struct Timing {
    /// The p99 judged, µs.
    p99_us: f64,
    /// Its budget, µs.
    limit_us: f64,
    /// What the machine itself added to every wake-up ([`machine_noise_us`]), µs.
    noise_us: Option<f64>,
    /// The machine was disturbed during the run by more than the budget allows ([`disturbance`]).
    disturbed: bool,
    /// The controller's own work (its compute p99) fits the budget.
    own_work_fits: bool,
}

/// Pass within the budget. Over it: inconclusive when the machine alone explains the miss (over by no more than
/// its own noise; or, for a figure that is more than the controller's own work, a disturbed machine while that
/// work fits the budget), else fail.
fn budget_outcome(t: Timing) -> Outcome {
    if t.p99_us <= t.limit_us {
        Outcome::Pass
    } else if t.noise_us.is_some_and(|n| t.p99_us - n <= t.limit_us) || (t.disturbed && t.own_work_fits) {
        Outcome::Inconclusive
    } else {
        Outcome::Fail
    }
}

/// Whether the machine was disturbed during a realtime run by more than a budget of `limit_us` can stand, and
/// how: more runnable work than CPUs (the 1-minute load average at the start or the end), or the plant's own
/// wake-ups or the OS floor's late by half the budget or more at p99 (steady state).
fn disturbance(report: &RigReport, limit_us: f64) -> Option<String> {
    let mut seen = Vec::new();
    for (when, c) in [("start", &report.conditions_start), ("end", &report.conditions_end)] {
        if c.cpu_count > 0 && c.load_average[0] >= c.cpu_count as f64 {
            seen.push(format!("load average {:.2} on {} CPUs at the {when}", c.load_average[0], c.cpu_count));
        }
    }
    let floor = report.timer_baseline.as_ref().and_then(|b| b.lateness_steady.as_ref().or(Some(&b.lateness)));
    for (what, p99) in [
        ("the plant's own wake-ups", report.steady("plant.wake_lateness").map(|l| l.p99_us)),
        ("the OS floor's wake-ups", floor.filter(|l| l.count > 0).map(|l| l.p99_us)),
    ] {
        if let Some(p99) = p99.filter(|p| *p >= limit_us / 2.0) {
            seen.push(format!("{what} late by {p99:.1} us at p99"));
        }
    }
    (!seen.is_empty()).then(|| seen.join(", "))
}

/// A timing budget on the steady state of a latency (`steady`, else the whole run's `latency` for a run too short
/// to have one); see [`budget_outcome`] for when a miss is inconclusive.
fn budget(
    report: &RigReport,
    scenario: &Scenario,
    criterion: &str,
    latency: &str,
    steady: &str,
    b: &Budget,
) -> Judgement {
    let floor = report.timer_baseline.as_ref().map(|t| t.lateness_steady.as_ref().unwrap_or(&t.lateness).p99_us);
    let mut limits = Vec::new();
    let mut limit_us = f64::INFINITY;
    if let Some(us) = b.max_us {
        limits.push(format!("{us:.1} us"));
        limit_us = limit_us.min(us);
    }
    if let Some(f) = b.max_period_fraction {
        let us = f * scenario.timing.dt_s * 1e6;
        limits.push(format!("{f} of the period ({us:.1} us)"));
        limit_us = limit_us.min(us);
    }
    if let Some(r) = b.max_os_floor_ratio {
        match floor {
            Some(f) => {
                limits.push(format!("{r}x OS floor p99 ({:.1} us)", r * f));
                limit_us = limit_us.min(r * f);
            }
            None => limits.push(format!("{r}x OS floor p99 (not measured)")),
        }
    }
    let limit = format!("p99 after 1 s: {}", limits.join(" and "));
    let (l, phase) = match report.steady(steady).or_else(|| report.latency(steady)).filter(|l| l.count > 0) {
        Some(l) => (l, "steady"),
        None => match report.latency(latency).filter(|l| l.count > 0) {
            Some(l) => (l, "whole run"),
            None => return no_evidence(criterion, limit, &format!("no `{latency}` values were recorded")),
        },
    };
    // The OS-floor ratio is context beside the figure, whatever the budget is.
    let ratio = floor.map(|f| format!(", {:.1}x OS floor", l.p99_us / f)).unwrap_or_default();
    let measured = format!("{:.1} us ({phase}{ratio})", l.p99_us);
    if b.max_os_floor_ratio.is_some() && floor.is_none() {
        return judgement(
            criterion,
            measured,
            limit,
            Some("the OS floor was not measured beside this run (the timer-baseline loop wrote no report)".into()),
        );
    }
    let compute = latency == "controller.compute";
    let noise = machine_noise_us(report);
    let disturbed = if compute { None } else { disturbance(report, limit_us) };
    let own_work = report.steady("controller.compute").or_else(|| report.latency("controller.compute"));
    let timing = Timing {
        p99_us: l.p99_us,
        limit_us,
        noise_us: noise.as_ref().map(|n| n.0),
        disturbed: disturbed.is_some(),
        own_work_fits: own_work.is_some_and(|c| c.p99_us <= limit_us),
    };
    let what = if compute {
        "the controller's compute time per tick"
    } else {
        "the time from the plant publishing a sample to the controller's answer arriving at the plant"
    };
    let over = format!(
        "{what} exceeded its budget in more than 1 % of the ticks after the first second (p99 {:.1} us against \
         {limit_us:.1} us, max {:.1} us over {} ticks)",
        l.p99_us, l.max_us, l.count
    );
    match budget_outcome(timing) {
        Outcome::Pass => judgement(criterion, measured, limit, None),
        Outcome::Inconclusive => {
            let because = match (&disturbed, &noise) {
                (Some(how), _) => format!(
                    "while the machine was disturbed ({how}) and the controller's own compute time fit the budget \
                     (p99 {:.1} us)",
                    own_work.map_or(f64::NAN, |c| c.p99_us)
                ),
                (None, Some((_, figures))) => {
                    format!("by no more than the machine itself added to every wake-up during the run ({figures})")
                }
                (None, None) => "while the machine was disturbed".into(),
            };
            inconclusive(
                criterion,
                measured,
                limit,
                format!(
                    "{over}, {because}: the machine, not the controller, may have made the difference. Fly it again \
                     on a quieter machine (silrig check re-flies it up to --retries times)"
                ),
            )
        }
        Outcome::Fail => judgement(
            criterion,
            measured,
            limit,
            Some(format!("{over}; latency.png in the run folder shows the whole distribution")),
        ),
    }
}

fn deadline_misses(report: &RigReport, max: u64) -> Judgement {
    let limit = format!("at most {max}");
    let Some(misses) = counter(report, Role::Plant, "command_misses") else {
        return no_evidence("deadline_misses_max", limit, "the plant wrote no report");
    };
    let late = misses.saturating_sub(counter(report, Role::Plant, "commands_refused_held").unwrap_or(0));
    let failure = (late > max).then(|| {
        format!(
            "on {late} ticks the controller's command had not reached the plant when the plant needed it (at most \
             {max} allowed); the plant held the previous command. The report's `command age at use` says by how \
             many ticks"
        )
    });
    judgement("deadline_misses_max", format!("{late}"), limit, failure)
}

fn recovered_within(scenario: &Scenario, report: &RigReport, max_s: f64) -> Judgement {
    let limit = format!("{max_s} s after each comeback");
    let mut worst: Option<(String, f64)> = None;
    let mut never = Vec::new();
    for (i, back_s) in comebacks(scenario, None) {
        let desc = scenario.faults[i].describe();
        let record = report.faults.iter().find(|r| r.fault == desc);
        match record.and_then(|r| r.recovered_at_s) {
            Some(rec) => {
                let took = (rec - back_s).max(0.0);
                if worst.as_ref().is_none_or(|w| took > w.1) {
                    worst = Some((desc, took));
                }
            }
            None => never.push(desc),
        }
    }
    if !never.is_empty() {
        return judgement(
            "recovered_within_s",
            "never".into(),
            limit,
            Some(format!(
                "the loop never recovered from: {}; the fault table of the report and events.jsonl say what was \
                 seen",
                never.join("; ")
            )),
        );
    }
    let (desc, took) = worst.unwrap_or_default();
    let failure = (took > max_s).then(|| {
        format!(
            "after `{desc}` the loop took {took:.3} s from the process coming back to flying again ({max_s} s allowed)"
        )
    });
    judgement("recovered_within_s", format!("{took:.3} s"), limit, failure)
}

fn failsafe_engaged_and_released(report: &RigReport) -> Judgement {
    let limit = "engaged, then released".to_string();
    let engaged = report.faults.iter().find_map(|r| r.failsafe_at_s.map(|f| (r, f)));
    let Some((record, at)) = engaged else {
        return judgement(
            "failsafe_engaged_and_released",
            "never engaged".into(),
            limit,
            Some(
                "no fault made the plant engage its failsafe (the controller was never silent for longer than \
                  --controller-hold-ms)"
                    .into(),
            ),
        );
    };
    match record.recovered_at_s.filter(|r| *r >= at) {
        Some(rel) => {
            judgement("failsafe_engaged_and_released", format!("engaged {at:.3} s, released {rel:.3} s"), limit, None)
        }
        None => judgement(
            "failsafe_engaged_and_released",
            format!("engaged {at:.3} s, never released"),
            limit,
            Some(format!(
                "the failsafe engaged at {at:.3} s during `{}` and the controller never took over again",
                record.fault
            )),
        ),
    }
}

const COMMAND_COLUMNS: [&str; 3] = ["aileron_cmd_deg", "elevator_cmd_deg", "rudder_cmd_deg"];
const SURFACE_COLUMNS: [&str; 3] = ["aileron_deg", "elevator_deg", "rudder_deg"];

fn resume_jump(scenario: &Scenario, report: &RigReport, trace: Option<&Trace>, max_deg: f64) -> Judgement {
    let limit = format!("{max_deg} deg");
    let Some(trace) = trace else { return no_evidence("resume_jump_max_deg", limit, "no trace was logged") };
    let t = trace.column("t_s").unwrap_or_default();
    let column = |name: &str| trace.column(name).unwrap_or_default();
    let commands: Vec<Vec<f64>> = COMMAND_COLUMNS.iter().map(|c| column(c)).collect();
    let actual: Vec<Vec<f64>> = SURFACE_COLUMNS.iter().map(|c| column(c)).collect();
    let has_command = |k: usize| commands.iter().all(|c| c.get(k).is_some_and(|v| v.is_finite()));
    // Per comeback: the first command after it against where the surface actually was when it came (the deflection
    // held up to that tick: the row before's).
    let mut worst: Option<(f64, &str, f64)> = None;
    let mut resumed = 0;
    for (i, back_s) in comebacks(scenario, Some(Role::Controller)) {
        let fault = &scenario.faults[i];
        if report.faults.iter().find(|r| r.fault == fault.describe()).and_then(|r| r.recovered_at_s).is_none() {
            continue;
        }
        let Some(k) = (0..t.len()).find(|&k| t[k] >= back_s - 1e-9 && has_command(k)) else { continue };
        resumed += 1;
        for (c, name) in COMMAND_COLUMNS.iter().enumerate() {
            let step = (commands[c][k] - actual[c][k.saturating_sub(1)]).abs();
            if worst.is_none_or(|w| step > w.0) {
                worst = Some((step, name, t[k]));
            }
        }
    }
    let Some((step, column, at)) = worst.filter(|_| resumed > 0) else {
        return judgement(
            "resume_jump_max_deg",
            "no resume".into(),
            limit,
            Some("the controller never commanded again after its fault; see recovered_within_s".into()),
        );
    };
    let failure = (step > max_deg).then(|| {
        format!(
            "the controller's first command after it came back ({column} at {at:.2} s) was {step:.2} deg away from \
             where the surface was: the takeover was not bumpless (a restarted controller should start from its \
             checkpoint and blend in from the surfaces' positions)"
        )
    });
    judgement("resume_jump_max_deg", format!("{column} {step:.2} deg"), limit, failure)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_timing_miss_the_machine_explains_is_inconclusive_one_the_controller_explains_fails() {
        let t = |p99_us, limit_us, noise_us, disturbed, own_work_fits| {
            budget_outcome(Timing { p99_us, limit_us, noise_us, disturbed, own_work_fits })
        };
        // The flake of issue 27: sense-to-actuate p99 892 us against 650 us while the machine stalled by 300 us.
        assert_eq!(t(892.0, 650.0, Some(300.0), false, true), Outcome::Inconclusive);
        assert_eq!(t(121.9, 1000.0, Some(300.0), false, true), Outcome::Pass);
        // A round trip of 10 ms under a load of 4.9 on 2 CPUs, the controller computing in 17 us.
        assert_eq!(t(10_051.0, 1000.0, Some(2308.0), true, true), Outcome::Inconclusive);
        // A controller that computes for 15 ms fails whatever the machine did.
        assert_eq!(t(15_278.0, 1000.0, Some(300.0), true, false), Outcome::Fail);
        assert_eq!(t(30_097.0, 1000.0, Some(2308.0), true, false), Outcome::Fail);
        // Lockstep, or nothing measured beside: nothing is excused.
        assert_eq!(t(1001.0, 1000.0, None, false, true), Outcome::Fail);
        assert_eq!(t(1000.0, 1000.0, None, false, true), Outcome::Pass);
    }
}
