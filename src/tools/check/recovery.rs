//! The fault criteria of a check: a process that comes back (`recovered_within_s`, and `restart_join_within_s` for
//! its start-up apart), the plant's failsafe covering the outage, and a bumpless takeover (`resume_jump_max_deg`),
//! judged from the run's fault table and trace.

use silrig_flight::criteria::Judgement;
use silrig_flight::fault::FaultAction;
use silrig_flight::judge::{judgement, no_evidence};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_flight::trace::Trace;
use silrig_launch::fault_report::FaultRecord;
use silrig_launch::run_report::RigReport;

/// Faults of the case after which a process comes back: (index in the plan, when it comes back, s).
pub(super) fn comebacks(scenario: &Scenario, target: Option<Role>) -> Vec<(usize, f64)> {
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

/// Faults of the case whose process is started again (kill or term with `restart_after`): their indices in the plan.
pub(super) fn restarts(scenario: &Scenario) -> Vec<usize> {
    let restarted = |f: &silrig_flight::fault::Fault| {
        matches!(f.action(), FaultAction::Kill | FaultAction::Term) && f.restart_after_s.is_some()
    };
    scenario.faults.iter().enumerate().filter(|(_, f)| restarted(f)).map(|(i, _)| i).collect()
}

/// How long the loop took to fly again after one comeback, and how long a restarted process took to join before
/// that (s); Err: it never did, in words. A restarted process is timed from its join, so that its start-up is not
/// judged as control; a stopped one from its planned continue (simulated time).
fn recovery_after(record: Option<&FaultRecord>, back_s: f64) -> Result<(f64, Option<f64>), String> {
    match record.and_then(|r| r.rejoin) {
        Some(j) => match (j.joined_at_wall_s, j.closed_at_wall_s) {
            (Some(joined), Some(closed)) => Ok(((closed - joined).max(0.0), Some(joined - j.restarted_at_wall_s))),
            (Some(joined), None) => Err(format!(
                "joined {:.3} s after its restart, and the loop never closed again",
                joined - j.restarted_at_wall_s
            )),
            (None, _) => Err("never joined the flight after its restart".into()),
        },
        None => match record.and_then(|r| r.recovered_at_s) {
            Some(rec) => Ok(((rec - back_s).max(0.0), None)),
            None => Err("the loop never recovered".into()),
        },
    }
}

/// `recovered_within_s`: after each comeback the loop flies again within `max_s`, counted from a restarted
/// process's join (its start-up is shown beside, and judged by `restart_join_within_s`).
pub(super) fn recovered_within(scenario: &Scenario, report: &RigReport, max_s: f64) -> Judgement {
    let limit = format!("{max_s} s after each return (a restart: after its join)");
    let mut worst: Option<(String, f64, Option<f64>)> = None;
    let mut never = Vec::new();
    for (i, back_s) in comebacks(scenario, None) {
        let desc = scenario.faults[i].describe();
        match recovery_after(report.faults.iter().find(|r| r.fault == desc), back_s) {
            Ok((took, join_s)) => {
                if worst.as_ref().is_none_or(|w| took > w.1) {
                    worst = Some((desc, took, join_s));
                }
            }
            Err(why) => never.push(format!("`{desc}`: {why}")),
        }
    }
    if !never.is_empty() {
        return judgement(
            "recovered_within_s",
            "never".into(),
            limit,
            Some(format!(
                "the loop never flew again after {}; the fault table of the report and events.jsonl say what was seen",
                never.join("; ")
            )),
        );
    }
    let (desc, took, join_s) = worst.unwrap_or_default();
    let joined = join_s.map(|j| format!(", joined {j:.3} s after its restart")).unwrap_or_default();
    let failure = (took > max_s).then(|| {
        let from = if join_s.is_some() { "the restarted process joining" } else { "the process coming back" };
        format!("after `{desc}` the loop took {took:.3} s from {from} to flying again ({max_s} s allowed)")
    });
    judgement("recovered_within_s", format!("{took:.3} s{joined}"), limit, failure)
}

/// `restart_join_within_s`: each restarted process joined the flight within `max_s` of being started.
pub(super) fn restart_join_within(scenario: &Scenario, report: &RigReport, max_s: f64) -> Judgement {
    let limit = format!("{max_s} s from each restart to its join");
    let mut worst: Option<(String, f64)> = None;
    for i in restarts(scenario) {
        let fault = &scenario.faults[i];
        let desc = fault.describe();
        let Some(j) = report.faults.iter().find(|r| r.fault == desc).and_then(|r| r.rejoin) else {
            return no_evidence(
                "restart_join_within_s",
                limit,
                &format!("the launcher recorded no restart after `{desc}` (events.jsonl)"),
            );
        };
        let Some(joined) = j.joined_at_wall_s else {
            return judgement(
                "restart_join_within_s",
                "never".into(),
                limit,
                Some(format!(
                    "after `{desc}` the {} was started again and never joined the flight: its stderr log in the run \
                     folder says why",
                    fault.target()
                )),
            );
        };
        let took = joined - j.restarted_at_wall_s;
        if worst.as_ref().is_none_or(|w| took > w.1) {
            worst = Some((desc, took));
        }
    }
    let (desc, took) = worst.unwrap_or_default();
    let failure = (took > max_s).then(|| {
        format!(
            "after `{desc}` the restarted process took {took:.3} s from being started to joining the flight ({max_s} \
             s allowed): its start-up (interpreter, imports, loading a model) while the plant flew its failsafe"
        )
    });
    judgement("restart_join_within_s", format!("{took:.3} s"), limit, failure)
}

pub(super) fn failsafe_engaged_and_released(report: &RigReport) -> Judgement {
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

pub(super) fn resume_jump(scenario: &Scenario, report: &RigReport, trace: Option<&Trace>, max_deg: f64) -> Judgement {
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

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_launch::fault_report::Rejoin;

    fn record(rejoin: Option<Rejoin>, recovered_at_s: Option<f64>) -> FaultRecord {
        serde_json::from_value(serde_json::json!({
            "fault": "controller kill at 3 s, restart after 0.5 s",
            "injected_at_s": 3.0, "detected_at_s": 3.06, "detected_by": "plant (controller-stale)",
            "failsafe_at_s": 3.1, "recovered_at_s": recovered_at_s, "plant_samples_lost": 0,
            "command_samples_lost": 60, "rejoin": rejoin,
        }))
        .unwrap()
    }

    #[test]
    fn a_restarted_process_is_judged_from_its_join_and_a_stopped_one_from_its_continue() {
        // The README's Python PID on a loaded machine: started at 3.52 s, joined 0.82 s later, commands 12 ms after.
        let slow = Rejoin { restarted_at_wall_s: 3.52, joined_at_wall_s: Some(4.34), closed_at_wall_s: Some(4.352) };
        let (took, join) = recovery_after(Some(&record(Some(slow), Some(4.34))), 3.5).unwrap();
        assert!((took - 0.012).abs() < 1e-9 && (join.unwrap() - 0.82).abs() < 1e-9, "{took} {join:?}");
        let lost = Rejoin { joined_at_wall_s: None, closed_at_wall_s: None, ..slow };
        assert_eq!(
            recovery_after(Some(&record(Some(lost), None)), 3.5).unwrap_err(),
            "never joined the flight after its restart"
        );
        let open = Rejoin { closed_at_wall_s: None, ..slow };
        assert!(recovery_after(Some(&record(Some(open), None)), 3.5).unwrap_err().contains("never closed again"));
        // A stop: from its planned continue, in simulated time.
        let (took, join) = recovery_after(Some(&record(None, Some(3.7))), 3.5).unwrap();
        assert!((took - 0.2).abs() < 1e-9 && join.is_none());
        assert!(recovery_after(None, 3.5).is_err());
    }
}
