//! The timing criteria of a check (`compute_p99`, `sense_to_actuate_p99`, `every_tick_answered`,
//! `deadline_misses_max`) and the one judgement of the machine they share: a figure, a missed deadline or an
//! unanswered tick that the machine's own disturbance during the run explains (the plant's late wake-ups, the OS
//! floor's p99 and stalls beside the run, the load) is inconclusive and flown again, not failed.

use silrig_flight::criteria::{Budget, Judgement, Outcome};
use silrig_flight::judge::{inconclusive, judgement, no_evidence};
use silrig_flight::role::Role;
use silrig_flight::scenario::Scenario;
use silrig_launch::floor::timer_baseline::Stall;
use silrig_launch::run_report::RigReport;
use silrig_wire::timing::LatencySummary;

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
pub(super) fn budget(
    report: &RigReport,
    scenario: &Scenario,
    criterion: &str,
    latency: &str,
    steady: &str,
    b: &Budget,
) -> Judgement {
    let floor = report.timer_baseline.as_ref().map(|t| t.lateness_steady.as_ref().unwrap_or(&t.lateness).p99_us);
    let (limit, limit_us) = budget_limit(b, scenario, floor);
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
            let because = inconclusive_because(disturbed.as_deref(), noise.as_ref().map(|n| n.1.as_str()), own_work);
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

/// The budget's limit in words, and in µs: the tightest of its parts (µs, a fraction of the period, a multiple of the
/// OS floor's p99 when it was measured).
fn budget_limit(b: &Budget, scenario: &Scenario, floor: Option<f64>) -> (String, f64) {
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
    (limit, limit_us)
}

/// Why a budget missed by a run on a disturbed or noisy machine is inconclusive: how the machine was disturbed
/// (`disturbed`) beside the controller's own compute time, or what the machine added to every wake-up (`noise`).
fn inconclusive_because(disturbed: Option<&str>, noise: Option<&str>, own_work: Option<&LatencySummary>) -> String {
    match (disturbed, noise) {
        (Some(how), _) => format!(
            "while the machine was disturbed ({how}) and the controller's own compute time fit the budget (p99 {:.1} \
             us)",
            own_work.map_or(f64::NAN, |c| c.p99_us)
        ),
        (None, Some(figures)) => {
            format!("by no more than the machine itself added to every wake-up during the run ({figures})")
        }
        (None, None) => "while the machine was disturbed".into(),
    }
}

/// A counter of one process's report (None: it wrote none, or not this counter).
pub(super) fn counter(report: &RigReport, role: Role, name: &str) -> Option<u64> {
    report.processes.iter().find(|p| p.process == role.label()).and_then(|p| p.counters.get(name).copied())
}

/// The plant's unanswered ticks of one run, set beside the OS floor's stalls.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Misses {
    /// Ticks the plant flew.
    ticks: u64,
    /// Ticks whose answer was not there when the plant needed it (refusals apart).
    unanswered: u64,
    /// How many of them fell in a stall the OS floor saw too ([`held_in_stalls`]).
    in_stalls: u64,
    /// The latest of the floor's wake-ups in those stalls, µs.
    worst_stall_us: f64,
}

/// How many of the moments `held_ns` (CLOCK_MONOTONIC ns) fall in a stall of the OS floor, and the floor's worst
/// lateness among those stalls, µs: here the held commands' plant send times
/// ([`silrig_launch::run_report::held_command_times_ns`]), in the soak the lost rows' ticks. A stall spans its
/// deadline to its late wake-up, widened by two periods before it (the answer was due within the period before
/// the plant needed it) and one after (the floor's loop and the rig run on CPUs of their own, so the same stall
/// may reach them a tick apart).
pub(crate) fn held_in_stalls(held_ns: &[u64], stalls: &[Stall], period_ns: u64) -> (u64, f64) {
    let mut count = 0;
    let mut worst_us: f64 = 0.0;
    for &t in held_ns {
        let hit = stalls.iter().filter(|s| {
            let end_ns = s.at_ns + (s.lateness_us * 1e3) as u64;
            t + 2 * period_ns >= s.at_ns && t <= end_ns + period_ns
        });
        if let Some(worst) = hit.map(|s| s.lateness_us).reduce(f64::max) {
            count += 1;
            worst_us = worst_us.max(worst);
        }
    }
    (count, worst_us)
}

/// The run's unanswered ticks from the plant's counters, beside the floor's stalls (None: the plant wrote no
/// report). A refused command is held too, but the timing cannot tell which held tick it was: with refusals
/// nothing is put down to the machine.
fn misses(report: &RigReport, held_ns: &[u64]) -> Option<Misses> {
    let misses = counter(report, Role::Plant, "command_misses")?;
    let ticks = counter(report, Role::Plant, "ticks")?;
    let refused = counter(report, Role::Plant, "commands_refused_held").unwrap_or(0);
    let unanswered = misses.saturating_sub(refused);
    let (in_stalls, worst_stall_us) = match &report.timer_baseline {
        Some(b) if refused == 0 => held_in_stalls(held_ns, &b.stalls, b.period_ns),
        _ => (0, 0.0),
    };
    Some(Misses { ticks, unanswered, in_stalls: in_stalls.min(unanswered), worst_stall_us })
}

/// Pass at or under `max`; over it, inconclusive when the misses outside the floor's stalls are within `max` (the
/// machine stalled under the rig and under the floor alike), else fail.
fn miss_outcome(m: Misses, max: u64) -> Outcome {
    if m.unanswered <= max {
        Outcome::Pass
    } else if m.unanswered - m.in_stalls <= max {
        Outcome::Inconclusive
    } else {
        Outcome::Fail
    }
}

/// `every_tick_answered` (`max` 0, its own words) and `deadline_misses_max` judged on the same misses.
fn judge_misses(criterion: &str, m: Misses, max: u64, failure: String) -> Judgement {
    let limit = if criterion == "every_tick_answered" { "0 ticks unanswered".into() } else { format!("at most {max}") };
    let stalled = if m.in_stalls > 0 { format!(", {} in stalls of the OS floor", m.in_stalls) } else { String::new() };
    let measured = if criterion == "every_tick_answered" {
        format!("{} of {} ticks unanswered{stalled}", m.unanswered, m.ticks)
    } else {
        format!("{}{stalled}", m.unanswered)
    };
    match miss_outcome(m, max) {
        Outcome::Pass => judgement(criterion, measured, limit, None),
        Outcome::Fail => judgement(criterion, measured, limit, Some(failure)),
        Outcome::Inconclusive => {
            let why = format!(
                "{failure}; but {} of them fell in stalls that the OS floor beside the run saw too (its wake-ups late \
                 by up to {:.1} ms), and the other {} are within the {max} allowed: the machine, not the controller, \
                 may have made the difference. Fly it again on a quieter machine (silrig check re-flies it up to \
                 --retries times)",
                m.in_stalls,
                m.worst_stall_us / 1e3,
                m.unanswered - m.in_stalls
            );
            inconclusive(criterion, measured, limit, why)
        }
    }
}

/// `every_tick_answered`: the plant found the controller's answer for every tick it flew.
pub(super) fn every_tick_answered(report: &RigReport, held_ns: &[u64]) -> Judgement {
    let Some(m) = misses(report, held_ns) else {
        return no_evidence("every_tick_answered", "0 ticks unanswered".into(), "the plant wrote no report");
    };
    let failure = format!(
        "{} of {} plant ticks found no answer from the controller when the plant needed it, so the plant held the \
         previous command (or flew its failsafe); a controller that is too slow, stalled or gone leaves ticks \
         unanswered",
        m.unanswered, m.ticks
    );
    judge_misses("every_tick_answered", m, 0, failure)
}

/// `deadline_misses_max`: at most `max` ticks without the controller's command when the plant needed it.
pub(super) fn deadline_misses(report: &RigReport, held_ns: &[u64], max: u64) -> Judgement {
    let Some(m) = misses(report, held_ns) else {
        return no_evidence("deadline_misses_max", format!("at most {max}"), "the plant wrote no report");
    };
    let failure = format!(
        "on {} ticks the controller's command had not reached the plant when the plant needed it (at most {max} \
         allowed); the plant held the previous command. The report's `command age at use` says by how many ticks",
        m.unanswered
    );
    judge_misses("deadline_misses_max", m, max, failure)
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

    #[test]
    fn a_miss_inside_a_stall_the_os_floor_saw_is_inconclusive_one_outside_fails() {
        const P: u64 = 10_000_000;
        let t0: u64 = 1_000_000_000;
        // The floor woke 4 ms late for its deadline at 3 s: the machine stalled from 3.000 to 3.004 s.
        let stalls =
            [Stall { at_ns: t0 + 300 * P, lateness_us: 4000.0 }, Stall { at_ns: t0 + 900 * P, lateness_us: 1000.0 }];
        // The plant needed tick 300's answer at 3.01 s, tick 500's at 5.01 s.
        let inside = [t0 + 301 * P];
        let outside = [t0 + 501 * P];
        assert_eq!(held_in_stalls(&inside, &stalls, P), (1, 4000.0));
        assert_eq!(held_in_stalls(&outside, &stalls, P).0, 0);
        // Two periods before the stall and one after it still count; more is another moment.
        assert_eq!(held_in_stalls(&[t0 + 298 * P, t0 + 300 * P + 4_000_000 + P], &stalls, P).0, 2);
        assert_eq!(held_in_stalls(&[t0 + 297 * P, t0 + 302 * P], &stalls, P).0, 0);
        let m = |unanswered, in_stalls| Misses { ticks: 1000, unanswered, in_stalls, worst_stall_us: 4000.0 };
        assert_eq!(miss_outcome(m(1, 1), 0), Outcome::Inconclusive);
        assert_eq!(miss_outcome(m(1, 0), 0), Outcome::Fail);
        assert_eq!(miss_outcome(m(3, 2), 0), Outcome::Fail, "one miss the machine does not explain");
        assert_eq!(miss_outcome(m(5, 2), 3), Outcome::Inconclusive, "3 allowed, and 2 of 5 in stalls");
        assert_eq!(miss_outcome(m(0, 0), 0), Outcome::Pass);
        let j = judge_misses("every_tick_answered", m(1, 1), 0, "1 of 1000 plant ticks found no answer".into());
        assert_eq!(j.outcome(), Outcome::Inconclusive);
        assert_eq!(j.measured, "1 of 1000 ticks unanswered, 1 in stalls of the OS floor");
        assert!(j.inconclusive.unwrap().contains("late by up to 4.0 ms"));
        let j = judge_misses("deadline_misses_max", m(1, 0), 0, "on 1 ticks".into());
        assert_eq!(
            (j.outcome(), j.measured.as_str(), j.why_failed.as_deref()),
            (Outcome::Fail, "1", Some("on 1 ticks"))
        );
    }
}
