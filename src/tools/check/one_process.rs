//! A lockstep case of `silrig check --in-process`: flown in one process as `silrig sim` flies a scenario (the
//! built-in F-16 or a plant FMU against our controller or a controller FMU), its folder written as `silrig sim`
//! writes one, and judged by the same flight criteria as a rig run plus the contract criteria a flight in one
//! process answers (every tick answered, no invalid command, determinism). The generic loop keeps the lockstep
//! rig's rules, so both give the same `trace.csv` (tests/check.rs); a suite gates an FMU at in-process speed. What
//! only the rig measures (timing, process and loop faults, recovery) is refused for such a case before anything
//! flies.

use super::suite::Case;
use silrig_flight::criteria::Judgement;
use silrig_flight::judge::{judge_flight, judgement};
use silrig_flight::scenario::Scenario;
use silrig_flight::trace::Trace;
use silrig_rig::RigMode;
use silrig_rig::in_process::{EndedBy, Models};
use std::path::Path;

/// Whether `--in-process` flies this case in one process: a lockstep case that is not a sweep (a sweep case flies
/// in one process anyway). Realtime cases are about the wall clock and fly the rig.
pub fn flies_in_one_process(case: &Case) -> bool {
    case.mode == RigMode::Lockstep && case.sweep.is_none()
}

/// Refuse a case `--in-process` would fly in one process but that needs the rig: a fault the processes carry out
/// (kill, term, stop, delay, jitter, drop) or a criterion measured on the rig's processes.
pub fn refuse_rig_only(case: &Case) -> Result<(), String> {
    if let Some(f) = case.scenario.faults.iter().find(|f| !f.action().is_plant_model_fault()) {
        return Err(format!(
            "case `{}`: the fault `{}` is carried out by the rig's processes; --in-process flies only plant-model \
             faults (sensor noise and bias, actuator faults): fly this case without --in-process",
            case.name,
            f.describe()
        ));
    }
    let c = &case.criteria;
    let rig_only = [
        ("compute_p99", c.compute_p99.is_some()),
        ("sense_to_actuate_p99", c.sense_to_actuate_p99.is_some()),
        ("deadline_misses_max", c.deadline_misses_max.is_some()),
        ("recovered_within_s", c.recovered_within_s.is_some()),
        ("failsafe_engaged_and_released", c.failsafe_engaged_and_released),
        ("resume_jump_max_deg", c.resume_jump_max_deg.is_some()),
    ];
    if let Some((name, _)) = rig_only.iter().find(|(_, asked)| *asked) {
        return Err(format!(
            "case `{}`: `criteria.{name}` is measured on the rig's processes, which --in-process does not start: \
             fly this case without --in-process",
            case.name
        ));
    }
    Ok(())
}

/// One flight in one process: what the case is judged on.
struct Flight {
    trace: Trace,
    /// When, why and by which side it ended before the scenario's end.
    ended_early: Option<(f64, EndedBy, String)>,
    /// Commands the controller's session would have refused (NaN, infinite, out of range), and the first.
    commands_refused: (u64, Option<String>),
}

fn fly(models: &Models, scenario: &Scenario) -> anyhow::Result<(Flight, Option<silrig_flight::signals::PlantSignals>)> {
    if models.flies_reference_loop() {
        // The reference loop: our controller never sends an invalid command (its law saturates at the stops).
        let (trace, left) = silrig_flight::sim::fly(scenario)?;
        let ended_early = left.map(|exit| (exit.t_s, EndedBy::Plant, exit.to_string()));
        return Ok((Flight { trace, ended_early, commands_refused: (0, None) }, None));
    }
    let flown = models.fly(scenario)?;
    let ended_early = flown.ended_early.as_ref().map(|e| (e.t_s, e.by, e.to_string()));
    let flight = Flight { trace: flown.trace, ended_early, commands_refused: flown.commands_refused };
    Ok((flight, models.own_plant(flown.plant)))
}

/// Fly the case (twice when it must be deterministic, the second into `run-2/`) into `case_dir` and judge it.
/// Returns the judgements and the folders written. An error: it could not start (an FMU that does not open, a
/// signal the controller needs that the plant lacks).
pub fn fly_and_judge(case: &Case, case_dir: &Path) -> anyhow::Result<(Vec<Judgement>, Vec<String>)> {
    let scenario = &case.scenario;
    let models = Models::open(scenario)?;
    let runs = if case.criteria.deterministic { 2 } else { 1 };
    let mut flights = Vec::new();
    let mut dirs = Vec::new();
    for i in 1..=runs {
        let dir = if runs == 1 { case_dir.to_path_buf() } else { case_dir.join(format!("run-{i}")) };
        let (flight, plant) = fly(&models, scenario)?;
        let summary = silrig_flight::summary::summarize(&flight.trace, scenario, plant.as_ref());
        crate::outputs::write_run(&dir, scenario, &flight.trace, &summary, plant.as_ref())?;
        dirs.push(dir.display().to_string());
        flights.push((flight, summary));
    }
    let (first, summary) = &flights[0];
    let c = &case.criteria;
    let mut out = vec![run_completed(scenario, &flights.iter().map(|(f, _)| f).collect::<Vec<_>>())];
    if c.every_tick_answered {
        out.push(every_tick_answered(scenario, first));
    }
    if c.no_invalid_command {
        out.push(no_invalid_command(first));
    }
    out.extend(judge_flight(c, scenario, Some(&first.trace), Some(summary)));
    if c.deterministic {
        out.push(super::criteria::deterministic_traces(Some(&first.trace), Some(&flights[1].0.trace)));
    }
    Ok((out, dirs))
}

fn run_completed(scenario: &Scenario, flights: &[&Flight]) -> Judgement {
    let duration = scenario.timing.duration_s;
    let problems: Vec<String> = flights
        .iter()
        .filter_map(|f| f.ended_early.as_ref())
        .map(|(t, _, why)| format!("ended at {t:.2} s: {why}"))
        .collect();
    // The trace's last row is the end of the flight (t = duration for a whole one).
    let last_t = |f: &Flight| f.trace.column("t_s").and_then(|t| t.last().copied()).unwrap_or(0.0);
    let flown_s = flights.iter().map(|f| last_t(f)).fold(f64::INFINITY, f64::min);
    judgement(
        "run_completed",
        format!("{flown_s:.2} s flown in one process, {} failure(s)", problems.len()),
        format!("{duration:.2} s flown, nothing failed"),
        (!problems.is_empty()).then(|| format!("the flight did not finish: {}", problems.join("; "))),
    )
}

fn every_tick_answered(scenario: &Scenario, flight: &Flight) -> Judgement {
    let ticks = scenario.timing.ticks() + 1;
    let unanswered = match &flight.ended_early {
        Some((_, EndedBy::Controller, _)) => ticks.saturating_sub(flight.trace.rows.len() as u64),
        _ => 0,
    };
    let failure = (unanswered > 0).then(|| {
        format!(
            "the controller stopped answering: {}; {unanswered} of {ticks} ticks were left unanswered",
            flight.ended_early.as_ref().map_or(String::new(), |(_, _, why)| why.clone())
        )
    });
    judgement(
        "every_tick_answered",
        format!("{unanswered} of {ticks} ticks unanswered"),
        "0 ticks unanswered".into(),
        failure,
    )
}

fn no_invalid_command(flight: &Flight) -> Judgement {
    let (n, first) = &flight.commands_refused;
    let failure = (*n > 0).then(|| {
        format!(
            "the controller produced {n} command(s) that were NaN, infinite or out of range, which the rig's session \
             would refuse (the plant holds the last valid command); the first: {}",
            first.as_deref().unwrap_or("-")
        )
    });
    judgement("no_invalid_command", format!("{n} invalid"), "0 invalid commands".into(), failure)
}
