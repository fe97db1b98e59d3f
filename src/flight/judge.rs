//! Judging a flight: what each flight criterion of [`crate::criteria`] measures in a trace and its summary, the
//! limit it is held to, and the sentence that explains a failure to someone who has not read the code. Pure: the
//! same code judges `silrig check` runs and sweep cases.

use crate::criteria::{AbsMax, BodyRateLimit, Criteria, Judgement, OutputCriteria, Settled, SettledBand};
use crate::scenario::Scenario;
use crate::setpoints::Segment;
use crate::summary::Summary;
use crate::summary::measures::{StepSettled, largest_overshoot, slowest_settle};
use crate::trace::Trace;

mod held;

/// A judgement of `criterion`: what was measured against what limit, failed when `failure` says why.
pub fn judgement(criterion: &str, measured: String, limit: String, failure: Option<String>) -> Judgement {
    Judgement {
        criterion: criterion.into(),
        measured,
        limit,
        passed: failure.is_none(),
        why_failed: failure,
        inconclusive: None,
        value: None,
    }
}

/// A judgement that cannot say pass or fail, and why (the machine, not what is judged).
pub fn inconclusive(criterion: &str, measured: String, limit: String, why: String) -> Judgement {
    Judgement { passed: false, inconclusive: Some(why), ..judgement(criterion, measured, limit, None) }
}

/// A judgement that could not be made because the run left no evidence for it: a failure, saying why.
pub fn no_evidence(criterion: &str, limit: String, what: &str) -> Judgement {
    judgement(criterion, "-".into(), limit, Some(format!("nothing to judge: {what}")))
}

/// A figure for people: two decimals, or three significant digits in powers of ten once it is absurdly large (a
/// flight that left the model's data).
fn figure(v: f64) -> String {
    if v.abs() < 1e5 { format!("{v:.2}") } else { format!("{v:.2e}") }
}

/// Judge the flight criteria of `criteria` that are set, in a fixed order, from a trace and its summary.
pub fn judge_flight(
    criteria: &Criteria,
    scenario: &Scenario,
    trace: Option<&Trace>,
    summary: Option<&Summary>,
) -> Vec<Judgement> {
    let mut out = Vec::new();
    if let Some(s) = criteria.settled {
        out.push(settled(scenario, trace, s));
    }
    if let Some(s) = criteria.setpoints_held {
        out.push(setpoints_held(scenario, trace, s));
    }
    if let Some(o) = criteria.overshoot_max_deg {
        out.push(overshoot_max(scenario, trace, o));
    }
    if let Some(e) = criteria.final_error_max_deg {
        out.push(final_error_max(scenario, trace, e));
    }
    if let Some(a) = criteria.alpha_max_deg {
        out.push(alpha_max(trace, a));
    }
    if let Some(b) = criteria.body_rate_max_dps {
        out.push(body_rate_max(trace, b));
    }
    if let Some(f) = criteria.rate_limit_fraction_max {
        out.push(saturation_fraction(summary, f, Saturation::Rate));
    }
    if let Some(f) = criteria.position_limit_fraction_max {
        out.push(saturation_fraction(summary, f, Saturation::Position));
    }
    if criteria.no_sustained_oscillation {
        out.push(no_sustained_oscillation(summary, scenario));
    }
    for (name, c) in &criteria.outputs {
        out.extend(judge_output(name, c, scenario, trace));
    }
    out
}

/// The criteria on one named output, in a fixed order, each labelled `outputs.<name>.<key>`. An output the trace
/// lacks fails every one of them, naming the trace's columns.
fn judge_output(name: &str, c: &OutputCriteria, scenario: &Scenario, trace: Option<&Trace>) -> Vec<Judgement> {
    let setpoint = scenario.setpoint.get(name).unwrap_or(f64::NAN);
    let segments = segments_of(scenario, name);
    let asked = asked_of_output(c, setpoint, segments.len() > 1, scenario);
    let label = |key: &str| format!("outputs.{name}.{key}");
    let (t, x) = match trace.map(|tr| (tr.column("t_s"), tr.column(name), tr)) {
        Some((Some(t), Some(x), _)) => (t, x),
        Some((_, _, tr)) => {
            let what = format!("the trace has no column `{name}`; its columns: {}", tr.columns.join(", "));
            return asked.into_iter().map(|(key, limit)| no_evidence(&label(key), limit, &what)).collect();
        }
        None => {
            return asked
                .into_iter()
                .map(|(key, limit)| no_evidence(&label(key), limit, "no trace was logged"))
                .collect();
        }
    };
    let output = OutputSeries { name, segments: &segments, t: &t, x: &x };
    asked
        .into_iter()
        .map(|(key, limit)| {
            let (measured, failure, value) = match key {
                "settled" => output.settled(c.settled.expect("asked")),
                "overshoot_max" => output.overshoot(c.overshoot_max.expect("asked")),
                "final_error_max" => output.final_error(c.final_error_max.expect("asked")),
                "max" => output.beyond(true, c.max.expect("asked")),
                "min" => output.beyond(false, c.min.expect("asked")),
                "abs_max" => match output.abs_max(c.abs_max.expect("asked")) {
                    Some(m) => m,
                    None => return no_evidence(&label(key), limit, "the trace ends before `after_s`"),
                },
                "held" => match held::held(name, output.t, output.x, c.held.expect("asked")) {
                    Some(m) => m,
                    None => return no_evidence(&label(key), limit, "the trace ends before `from_s + for_s`"),
                },
                _ => output.oscillation(c.oscillation_max.expect("asked"), scenario.timing.late_window_s()),
            };
            judgement(&label(key), measured, limit, failure).with_value(value)
        })
        .collect()
}

/// The criteria asked of one output, in their fixed order, each with its limit in words.
fn asked_of_output(c: &OutputCriteria, setpoint: f64, steps: bool, scenario: &Scenario) -> Vec<(&'static str, String)> {
    let mut asked: Vec<(&str, String)> = Vec::new();
    // A set point that steps is judged against each value from its step on.
    let then = if steps { " and each of its steps" } else { "" };
    if let Some(s) = c.settled {
        let after = if steps { "s after each step" } else { " s" };
        asked.push(("settled", format!("within {} of {setpoint}{then} from {}{after}", s.band, s.within_s)));
    }
    if let Some(o) = c.overshoot_max {
        asked.push(("overshoot_max", format!("{o} past {setpoint}{then}")));
    }
    if let Some(e) = c.final_error_max {
        let at_end = if steps { " (the value in force at the end)" } else { "" };
        asked.push(("final_error_max", format!("{e} from {setpoint}{at_end}")));
    }
    if let Some(m) = c.max {
        asked.push(("max", format!("at most {m}")));
    }
    if let Some(m) = c.min {
        asked.push(("min", format!("at least {m}")));
    }
    if let Some(a) = c.abs_max {
        asked.push(("abs_max", format!("|value| at most {} after {} s", a.max, a.after_s)));
    }
    if let Some(h) = c.held {
        asked.push(("held", held::limit_words(h)));
    }
    if let Some(o) = c.oscillation_max {
        let late = crate::summary::seconds(scenario.timing.late_window_s());
        asked.push(("oscillation_max", format!("none sustained beyond +-{o} in the last {late} s")));
    }
    asked
}

/// One criterion measured on an output: the measurement in words, why it failed (if it did) and its value.
type Measured = (String, Option<String>, f64);

/// One output of the trace over time, with its set point's history: what each of its criteria measures.
struct OutputSeries<'a> {
    name: &'a str,
    segments: &'a [Segment],
    t: &'a [f64],
    x: &'a [f64],
}

impl OutputSeries<'_> {
    fn settled(&self, s: SettledBand) -> Measured {
        let settled = slowest_settle(self.t, self.x, self.segments, s.band);
        let of = format!("its set point {}", settled.segment.value);
        let failure = settle_failure(self.name, &s.band.to_string(), &of, &settled, s.within_s);
        (settled_words(&settled), failure, settled.after_step_s())
    }

    fn overshoot(&self, max: f64) -> Measured {
        let name = self.name;
        let (over, segment) = largest_overshoot(self.t, self.x, self.segments);
        let failure = (over > max).then(|| {
            format!(
                "{name} went {} past its set point {}{}, more than the {max} allowed",
                figure(over),
                segment.value,
                step_at(&segment)
            )
        });
        (figure(over), failure, over)
    }

    fn final_error(&self, max: f64) -> Measured {
        let name = self.name;
        let setpoint = in_force_at_end(self.t, self.segments);
        let e = self.x.last().map_or(f64::INFINITY, |v| (v - setpoint).abs());
        let e = if e.is_nan() { f64::INFINITY } else { e };
        let failure = (e > max)
            .then(|| format!("{name} ended {} from its set point {setpoint}, more than the {max} allowed", figure(e)));
        (figure(e), failure, e)
    }

    /// Above `bound` (`upper`) or below it: the highest (or lowest) value and when; NaN, a flight that is no longer
    /// a number, is beyond every bound.
    fn beyond(&self, upper: bool, bound: f64) -> Measured {
        let extreme = self.t.iter().zip(self.x).map(|(ti, v)| (*v, *ti)).reduce(|w, c| {
            let beats = !w.0.is_nan() && (c.0.is_nan() || if upper { c.0 > w.0 } else { c.0 < w.0 });
            if beats { c } else { w }
        });
        let (v, at) = extreme.unwrap_or((f64::NAN, 0.0));
        let beyond = v.is_nan() || if upper { v > bound } else { v < bound };
        let word = if upper { "above" } else { "below" };
        let failure =
            beyond.then(|| format!("{} reached {} at {at:.2} s, {word} the {bound} allowed", self.name, figure(v)));
        let excess = if upper { v - bound } else { bound - v };
        (format!("{} at {at:.2} s", figure(v)), failure, excess)
    }

    /// None when the trace ends before `after_s`.
    fn abs_max(&self, a: AbsMax) -> Option<Measured> {
        let (v, at) = self
            .t
            .iter()
            .zip(self.x)
            .filter(|(ti, _)| **ti >= a.after_s)
            .map(|(ti, v)| (if v.is_nan() { f64::INFINITY } else { v.abs() }, *ti))
            .max_by(|p, q| p.0.total_cmp(&q.0))?;
        let failure = (v > a.max).then(|| {
            format!(
                "|{}| reached {} at {at:.2} s, after the {} s by which it should stay within {}",
                self.name,
                figure(v),
                a.after_s,
                a.max
            )
        });
        Some((format!("{} at {at:.2} s", figure(v)), failure, v))
    }

    fn oscillation(&self, threshold: f64, window_s: f64) -> Measured {
        let o = crate::summary::oscillation_above(self.name, self.t, self.x, threshold, window_s);
        let period_s = o.period_s.unwrap_or(f64::NAN);
        let failure = o.sustained.then(|| {
            format!(
                "{} did not come to rest: +-{} every {period_s:.2} s in the last {} s of the run, not decaying",
                self.name,
                figure(o.amplitude),
                crate::summary::seconds(window_s)
            )
        });
        let measured = if o.sustained {
            format!("+-{} every {period_s:.2} s", figure(o.amplitude))
        } else {
            format!("none sustained (swing +-{})", figure(o.amplitude))
        };
        (measured, failure, o.amplitude)
    }
}

fn settled(scenario: &Scenario, trace: Option<&Trace>, s: Settled) -> Judgement {
    let limit = format!("within {} deg from {} s", s.band_deg, s.within_s);
    let Some(trace) = trace else { return no_evidence("settled", limit, "no trace was logged") };
    let t = trace.column("t_s").unwrap_or_default();
    let settled = angles(scenario, trace)
        .into_iter()
        .map(|(name, segments, x)| (name, slowest_settle(&t, &x, &segments, s.band_deg)));
    // The axis that settled last after its step, or one that never did.
    let (axis, settled) = settled.max_by(|a, b| a.1.after_step_s().total_cmp(&b.1.after_step_s())).expect("three axes");
    let measured = format!("{axis} {}", settled_words(&settled));
    let of = if settled.segment.from_s > 0.0 {
        format!("its set point {} deg", settled.segment.value)
    } else {
        "its set point".into()
    };
    let failure = settle_failure(axis, &format!("{} deg", s.band_deg), &of, &settled, s.within_s)
        .map(|why| why + "; fig1_states.png in the run folder shows the response");
    judgement("settled", measured, limit, failure).with_value(settled.after_step_s())
}

/// A set point's history by name, or a NaN set point from 0 when the scenario gives none (judged as never met).
fn segments_of(scenario: &Scenario, name: &str) -> Vec<Segment> {
    let nan = || crate::setpoints::SetpointTrack::constant(f64::NAN);
    scenario.setpoint_track(name).unwrap_or_else(nan).segments().to_vec()
}

/// The set point in force at the trace's last time.
fn in_force_at_end(t: &[f64], segments: &[Segment]) -> f64 {
    let end_s = t.last().copied().unwrap_or(0.0);
    segments.iter().take_while(|s| s.from_s <= end_s).last().unwrap_or(&segments[0]).value
}

/// " (its step at 2 s)" for a segment a step started, nothing for `[setpoint]`'s own.
fn step_at(segment: &Segment) -> String {
    if segment.from_s > 0.0 { format!(" (its step at {} s)", segment.from_s) } else { String::new() }
}

/// What was measured of a settling: "settled at 3.10 s", with how long after its step when a step started it.
fn settled_words(s: &StepSettled) -> String {
    match (s.at_s, s.segment.from_s > 0.0) {
        (Some(a), false) => format!("settled at {a:.2} s"),
        (Some(a), true) => {
            format!("settled at {a:.2} s, {:.2} s after its step at {} s", s.after_step_s(), s.segment.from_s)
        }
        (None, false) => "never settled".into(),
        (None, true) => format!("never settled after its step at {} s", s.segment.from_s),
    }
}

/// Why `who` failed to settle within `band` (with its unit) of `of` (its set point, in words) by `within_s` after
/// its step (after 0 for `[setpoint]`'s own); `None` when it did.
fn settle_failure(who: &str, band: &str, of: &str, s: &StepSettled, within_s: f64) -> Option<String> {
    if s.after_step_s() <= within_s {
        return None;
    }
    let from = s.segment.from_s;
    Some(match (s.at_s, from > 0.0) {
        (Some(a), false) => {
            format!("{who} only stayed within {band} of {of} from {a:.2} s on, later than the {within_s} s allowed")
        }
        (Some(a), true) => format!(
            "{who} only stayed within {band} of {of} from {a:.2} s on, {:.2} s after its step at {from} s, later than \
             the {within_s} s allowed",
            s.after_step_s()
        ),
        (None, false) => format!("{who} was still more than {band} from {of} at the end of the run"),
        (None, true) => format!(
            "{who} never stayed within {band} of {of} after its step at {from} s (until its next step or the end of \
             the run)"
        ),
    })
}

/// `setpoints_held`: every set point of the scenario that names a column of the trace (an output of whatever plant
/// flew) stays within the band of it, in that output's unit, from `within_s` on; judged on the one that settled
/// last. A scenario none of whose set points the plant has fails: there is nothing to hold.
fn setpoints_held(scenario: &Scenario, trace: Option<&Trace>, s: SettledBand) -> Judgement {
    let limit = format!("each within {} of its set point from {} s", s.band, s.within_s);
    let Some(trace) = trace else { return no_evidence("setpoints_held", limit, "no trace was logged") };
    let t = trace.column("t_s").unwrap_or_default();
    let all = scenario.setpoint.all();
    let held: Vec<(&str, StepSettled)> = all
        .iter()
        .filter_map(|&(name, _)| {
            Some((name, slowest_settle(&t, &trace.column(name)?, &segments_of(scenario, name), s.band)))
        })
        .collect();
    let Some(&(name, settled)) = held.iter().max_by(|a, b| a.1.after_step_s().total_cmp(&b.1.after_step_s())) else {
        let names: Vec<&str> = all.iter().map(|(n, _)| *n).collect();
        let why = format!(
            "the scenario's set points ({}) name no output of this plant (the trace's columns: {}); fly a suite whose \
             scenario gives your outputs set points in its [setpoint]",
            names.join(", "),
            trace.columns.join(", ")
        );
        return judgement("setpoints_held", "no set point".into(), limit, Some(why));
    };
    let of = format!("{} set point{}", held.len(), if held.len() == 1 { "" } else { "s" });
    let measured = match settled.at_s {
        Some(_) => format!("{name} {} (last of {of})", settled_words(&settled)),
        None => format!("{name} {} (of {of})", settled_words(&settled)),
    };
    let its = format!("its set point {}", settled.segment.value);
    let failure = settle_failure(name, &s.band.to_string(), &its, &settled, s.within_s)
        .map(|why| why + "; signals.png in the run folder shows the response");
    judgement("setpoints_held", measured, limit, failure).with_value(settled.after_step_s())
}

/// Largest |column| over rows with t >= from_s (NaN-free), with the time it happened.
fn peak_abs(trace: &Trace, column: &str, from_s: f64) -> Option<(f64, f64)> {
    let t = trace.column("t_s")?;
    let x = trace.column(column)?;
    t.iter()
        .zip(&x)
        .filter(|(ti, v)| **ti >= from_s && v.is_finite())
        .map(|(ti, v)| (v.abs(), *ti))
        .max_by(|a, b| a.0.total_cmp(&b.0))
}

/// (axis, its set point's history, values) of phi, theta, psi.
fn angles(scenario: &Scenario, trace: &Trace) -> Vec<(&'static str, Vec<Segment>, Vec<f64>)> {
    ["phi", "theta", "psi"]
        .into_iter()
        .map(|name| {
            let column = format!("{name}_deg");
            (name, segments_of(scenario, &column), trace.column(&column).unwrap_or_default())
        })
        .collect()
}

fn overshoot_max(scenario: &Scenario, trace: Option<&Trace>, max: f64) -> Judgement {
    let limit = format!("{max} deg");
    let Some(trace) = trace else { return no_evidence("overshoot_max_deg", limit, "no trace was logged") };
    // Past the set point in the direction of the step; an axis already at its set point has no step to overshoot.
    // An axis already at its set point has no step to overshoot: left out.
    let t = trace.column("t_s").unwrap_or_default();
    let worst = angles(scenario, trace)
        .into_iter()
        .filter(|(_, segments, x)| {
            segments.len() > 1 || x.first().is_some_and(|first| segments[0].value - first != 0.0)
        })
        .map(|(name, segments, x)| (name, largest_overshoot(&t, &x, &segments).0))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let (axis, over) = worst.unwrap_or(("-", 0.0));
    let failure = (over > max).then(|| {
        format!("{axis} went {} deg past its set point on the way there, more than the {max} deg allowed", figure(over))
    });
    judgement("overshoot_max_deg", format!("{axis} {} deg", figure(over)), limit, failure).with_value(over)
}

fn final_error_max(scenario: &Scenario, trace: Option<&Trace>, max: f64) -> Judgement {
    let limit = format!("{max} deg");
    let Some(trace) = trace else { return no_evidence("final_error_max_deg", limit, "no trace was logged") };
    let t = trace.column("t_s").unwrap_or_default();
    let (axis, error) = angles(scenario, trace)
        .into_iter()
        .map(|(name, segments, x)| {
            let setpoint = in_force_at_end(&t, &segments);
            let e = x.last().map_or(f64::INFINITY, |v| (v - setpoint).abs());
            (name, if e.is_nan() { f64::INFINITY } else { e })
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("three axes");
    let failure = (error > max)
        .then(|| format!("{axis} ended {} deg from its set point, more than the {max} deg allowed", figure(error)));
    judgement("final_error_max_deg", format!("{axis} {} deg", figure(error)), limit, failure).with_value(error)
}

fn alpha_max(trace: Option<&Trace>, max: f64) -> Judgement {
    let limit = format!("{max} deg");
    let Some((alpha, at)) = trace.and_then(|t| peak_abs(t, "alpha_deg", f64::NEG_INFINITY)) else {
        return no_evidence("alpha_max_deg", limit, "no trace was logged");
    };
    let failure = (alpha > max).then(|| {
        format!("the angle of attack reached {} deg at {at:.2} s, beyond the {max} deg allowed", figure(alpha))
    });
    judgement("alpha_max_deg", format!("{} deg", figure(alpha)), limit, failure).with_value(alpha)
}

fn body_rate_max(trace: Option<&Trace>, b: BodyRateLimit) -> Judgement {
    let limit = format!("{} deg/s after {} s", b.max, b.after_s);
    let Some(trace) = trace else { return no_evidence("body_rate_max_dps", limit, "no trace was logged") };
    let peaks: Vec<(&str, f64, f64)> = ["p", "q", "r"]
        .iter()
        .filter_map(|n| peak_abs(trace, &format!("{n}_dps"), b.after_s).map(|(v, t)| (*n, v, t)))
        .collect();
    let Some(&(name, rate, at)) = peaks.iter().max_by(|a, c| a.1.total_cmp(&c.1)) else {
        return no_evidence("body_rate_max_dps", limit, "the trace ends before `after_s`");
    };
    let failure = (rate > b.max).then(|| {
        format!(
            "|{name}| reached {} deg/s at {at:.2} s, after the {} s by which rates should be below {} deg/s",
            figure(rate),
            b.after_s,
            b.max
        )
    });
    judgement("body_rate_max_dps", format!("|{name}| {} deg/s", figure(rate)), limit, failure).with_value(rate)
}

/// Which limit a saturation criterion counts.
#[derive(Clone, Copy)]
enum Saturation {
    Rate,
    Position,
}

fn saturation_fraction(summary: Option<&Summary>, max: f64, kind: Saturation) -> Judgement {
    let (criterion, what, why) = match kind {
        Saturation::Rate => (
            "rate_limit_fraction_max",
            "rate limit",
            "the controller asks for more than the actuator can give, which costs phase margin and can drive a limit \
             cycle",
        ),
        Saturation::Position => (
            "position_limit_fraction_max",
            "position limit",
            "the controller asks for more deflection than the surface has: no authority left for a disturbance",
        ),
    };
    let limit = format!("{:.1} % of ticks", max * 100.0);
    let Some(s) = summary else { return no_evidence(criterion, limit, "no trace was logged") };
    let ticks_at = |f: &crate::summary::ActuatorFigures| match kind {
        Saturation::Rate => f.ticks_at_rate_limit,
        Saturation::Position => f.ticks_at_position_limit,
    };
    let Some(worst) = s.actuators.iter().max_by_key(|f| ticks_at(f)) else {
        return no_evidence(
            criterion,
            limit,
            "no actuator in the summary (an input under [actuators.<input>] whose command is in the trace)",
        );
    };
    let fraction = ticks_at(worst) as f64 / s.ticks.max(1) as f64;
    let failure = (fraction > max).then(|| {
        format!(
            "the {} spent {} of {} ticks ({:.1} %) at its {what}: {why}",
            worst.name,
            ticks_at(worst),
            s.ticks,
            fraction * 100.0
        )
    });
    judgement(criterion, format!("{} {:.1} %", worst.name, fraction * 100.0), limit, failure).with_value(fraction)
}

fn no_sustained_oscillation(summary: Option<&Summary>, scenario: &Scenario) -> Judgement {
    let late = crate::summary::seconds(summary.map_or(scenario.timing.late_window_s(), |s| s.late_window_s));
    let limit = format!("none in the last {late} s");
    let Some(s) = summary else {
        return no_evidence("no_sustained_oscillation", limit, "no trace was logged");
    };
    let mut oscillating: Vec<&crate::summary::Oscillation> = s.oscillations.iter().filter(|o| o.sustained).collect();
    // The strongest first, relative to what counts for its kind of signal.
    oscillating.sort_by(|a, b| {
        let strength = |o: &crate::summary::Oscillation| o.amplitude / o.threshold;
        strength(b).total_cmp(&strength(a))
    });
    let sustained: Vec<String> = oscillating
        .iter()
        .map(|o| format!("{} +-{:.2} every {:.2} s", o.signal, o.amplitude, o.period_s.unwrap_or(f64::NAN)))
        .collect();
    let measured = match sustained.len() {
        0 => "none".to_string(),
        1 => sustained[0].clone(),
        n => format!("{} (+{} more)", sustained[0], n - 1),
    };
    let failure = (!sustained.is_empty()).then(|| {
        format!(
            "the loop did not come to rest: {} in the last {late} s of the run, not decaying (a limit cycle, \
             typically from too much gain against the actuators' rate limits or the loop's delay)",
            sustained.join(", ")
        )
    });
    // How far past what counts the strongest sustained oscillation is (0 without one).
    let strength = oscillating.first().map_or(0.0, |o| o.amplitude / o.threshold);
    judgement("no_sustained_oscillation", measured, limit, failure).with_value(strength)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trace of phi, theta, psi (deg) at 0.01 s steps.
    fn trace(rows: &[[f64; 3]]) -> Trace {
        let mut t = Trace::new(["t_s", "phi_deg", "theta_deg", "psi_deg"].map(String::from).to_vec());
        t.rows = rows.iter().enumerate().map(|(k, r)| vec![k as f64 * 0.01, r[0], r[1], r[2]]).collect();
        t
    }

    /// A scenario with `alt_ft = 4000` among its set points, and a trace of `alt_ft` at 0.01 s steps.
    fn altitude(values: &[f64]) -> (Scenario, Trace) {
        let mut s = Scenario::embedded_default();
        s.setpoint.outputs.insert("alt_ft".into(), 4000.0);
        let mut t = Trace::new(["t_s", "alt_ft"].map(String::from).to_vec());
        t.rows = values.iter().enumerate().map(|(k, v)| vec![k as f64 * 0.01, *v]).collect();
        (s, t)
    }

    fn criteria(toml_table: &str) -> Criteria {
        toml::from_str(&format!("[outputs.alt_ft]\n{toml_table}")).unwrap()
    }

    fn judged(c: &Criteria, s: &Scenario, t: &Trace) -> Vec<(String, bool, String)> {
        judge_flight(c, s, Some(t), None).into_iter().map(|j| (j.criterion, j.passed, j.measured)).collect()
    }

    #[test]
    fn a_named_output_is_judged_against_its_own_set_point_in_its_own_unit() {
        // A climb from 3,900 ft past 4,000 to 4,030, settling at 4,002 from 0.04 s on.
        let (s, t) = altitude(&[3900.0, 3980.0, 4030.0, 4010.0, 4002.0, 4002.0, 4001.5]);
        let c = criteria(
            "settled = { within_s = 0.05, band = 5.0 }\novershoot_max = 20.0\nfinal_error_max = 1.0\nmax = 4050.0\n\
             min = 3800.0\nabs_max = { after_s = 0.03, max = 4020.0 }",
        );
        let j = judged(&c, &s, &t);
        let keys: Vec<&str> = j.iter().map(|(k, _, _)| k.as_str()).collect();
        assert_eq!(
            keys,
            [
                "outputs.alt_ft.settled",
                "outputs.alt_ft.overshoot_max",
                "outputs.alt_ft.final_error_max",
                "outputs.alt_ft.max",
                "outputs.alt_ft.min",
                "outputs.alt_ft.abs_max"
            ]
        );
        assert_eq!(j[0], ("outputs.alt_ft.settled".into(), true, "settled at 0.04 s".into()));
        assert_eq!((j[1].1, j[1].2.as_str()), (false, "30.00"), "30 ft past 4,000 on the way up");
        assert_eq!((j[2].1, j[2].2.as_str()), (false, "1.50"));
        assert_eq!((j[3].1, j[4].1), (true, true));
        assert_eq!((j[5].1, j[5].2.as_str()), (true, "4010.00 at 0.03 s"));
        let tight = criteria("max = 4020.0\nmin = 3950.0\nsettled = { within_s = 0.02, band = 5.0 }");
        let j = judged(&tight, &s, &t);
        assert!(j.iter().all(|(_, passed, _)| !passed), "{j:?}");
        // An output the trace lacks fails, naming what the trace has.
        let mut no_alt = criteria("max = 1.0");
        no_alt.outputs = [("vt_mps".to_string(), no_alt.outputs["alt_ft"].clone())].into();
        let missing = judge_flight(&no_alt, &s, Some(&t), None);
        assert!(!missing[0].passed);
        assert!(missing[0].why_failed.as_ref().unwrap().contains("no column `vt_mps`; its columns: t_s, alt_ft"));
    }

    #[test]
    fn a_named_output_that_keeps_swinging_fails_its_oscillation_bound() {
        // 4,000 ft +- 12 ft at 1 Hz for 6 s: sustained beyond 10 ft, within 15.
        let values: Vec<f64> =
            (0..600).map(|k| 4000.0 + 12.0 * (2.0 * std::f64::consts::PI * k as f64 * 0.01).sin()).collect();
        let (s, t) = altitude(&values);
        let j = judged(&criteria("oscillation_max = 10.0"), &s, &t);
        assert!(!j[0].1 && j[0].2.starts_with("+-12.00 every 1.00 s"), "{j:?}");
        assert!(judged(&criteria("oscillation_max = 15.0"), &s, &t)[0].1);
    }

    #[test]
    fn criteria_on_named_outputs_are_checked_before_anything_flies() {
        let s = Scenario::embedded_default();
        let has = |name: &str| s.setpoint.get(name).is_some();
        let e = |table: &str| criteria(table).validate_flight(10.0, &has).unwrap_err();
        assert!(e("settled = { within_s = 2.0, band = 5.0 }").contains("add `alt_ft = ...` to [setpoint]"));
        assert!(e("min = 5.0\nmax = 1.0").contains("`criteria.outputs.alt_ft.min` (5) must be below"));
        assert!(e("abs_max = { after_s = 20.0, max = 1.0 }").contains("abs_max.after_s` must be within 0..10"));
        assert!(e("oscillation_max = -1.0").contains("`criteria.outputs.alt_ft.oscillation_max` must be a positive"));
        let empty: Criteria = toml::from_str("[outputs.alt_ft]\n").unwrap();
        assert!(empty.validate_flight(10.0, &has).unwrap_err().contains("sets no criterion"));
        assert!(toml::from_str::<Criteria>("[outputs.alt_ft]\nmaximum = 3.0\n").is_err(), "unknown keys refused");
        criteria("max = 4100.0").validate_flight(10.0, &has).unwrap();
    }

    #[test]
    fn overshoot_is_measured_past_the_set_point_in_the_direction_of_the_step() {
        // Set points 0, 10, 0 (the default scenario). theta steps up from 5 and peaks at 12.5: 2.5 deg over;
        // phi steps down from 5 and dips to -1: 1 deg over; psi starts at its set point: no step, no overshoot.
        let s = Scenario::embedded_default();
        let t = trace(&[[5.0, 5.0, 0.0], [-1.0, 12.5, 3.0], [0.2, 10.1, -0.4]]);
        let j = overshoot_max(&s, Some(&t), 2.0);
        assert_eq!((j.measured.as_str(), j.passed, j.value), ("theta 2.50 deg", false, Some(2.5)));
        assert!(overshoot_max(&s, Some(&t), 3.0).passed);
        let e = final_error_max(&s, Some(&t), 0.3);
        assert_eq!((e.measured.as_str(), e.passed), ("psi 0.40 deg", false));
        assert!((e.value.unwrap() - 0.4).abs() < 1e-12);
        assert!(final_error_max(&s, Some(&t), 0.5).passed);
        // A flight that is no longer a number fails both.
        let lost = trace(&[[5.0, 5.0, 5.0], [f64::NAN, f64::NAN, f64::NAN]]);
        assert!(!overshoot_max(&s, Some(&lost), 100.0).passed && !final_error_max(&s, Some(&lost), 100.0).passed);
    }

    #[test]
    fn every_set_point_the_plant_has_is_held_and_one_it_lacks_is_not_asked_for() {
        // A plant with pitch and altitude only: the default scenario's phi and psi set points are not its outputs.
        let mut s = Scenario::embedded_default();
        s.setpoint.outputs.insert("alt_ft".into(), 4000.0);
        let mut t = Trace::new(["t_s", "theta_deg", "alt_ft"].map(String::from).to_vec());
        t.rows = (0..100)
            .map(|k| vec![k as f64 * 0.1, if k < 30 { 0.0 } else { 10.2 }, 4000.0 + (50 - k).max(0) as f64])
            .collect();
        let held = |within_s: f64, band: f64| setpoints_held(&s, Some(&t), SettledBand { within_s, band });
        let j = held(6.0, 5.0);
        assert_eq!((j.passed, j.measured.as_str()), (true, "alt_ft settled at 4.50 s (last of 2 set points)"), "{j:?}");
        let j = held(4.0, 5.0);
        assert!(!j.passed && j.why_failed.unwrap().contains("alt_ft only stayed within 5 of its set point 4000"));
        let j = held(8.0, 0.1);
        assert_eq!(j.measured, "theta_deg never settled (of 2 set points)");
        // A plant none of whose outputs has a set point fails, saying what to do.
        let mut other = Trace::new(["t_s", "speed_mps"].map(String::from).to_vec());
        other.rows = vec![vec![0.0, 1.0]];
        let j = setpoints_held(&s, Some(&other), SettledBand { within_s: 1.0, band: 1.0 });
        assert!(
            !j.passed
                && j.why_failed.unwrap().contains("name no output of this plant (the trace's columns: t_s, speed_mps)")
        );
    }

    #[test]
    fn a_set_point_that_steps_is_judged_from_each_step_on_against_its_value() {
        // alt_ft held at 4000, then a step to 4100 at 0.05 s: up to 4120 and settled at 4101 from 0.08 s on.
        let (mut s, t) =
            altitude(&[4000.0, 4000.0, 4000.0, 4000.0, 4000.0, 4000.0, 4060.0, 4120.0, 4101.0, 4101.0, 4101.0]);
        s.setpoint_steps =
            vec![crate::setpoints::SetpointStep { at_s: 0.05, values: [("alt_ft".to_string(), 4100.0)].into() }];
        let c = criteria(
            "settled = { within_s = 0.03, band = 5.0 }
overshoot_max = 15.0
final_error_max = 1.0",
        );
        let j = judge_flight(&c, &s, Some(&t), None);
        let by = |key: &str| j.iter().find(|j| j.criterion == format!("outputs.alt_ft.{key}")).unwrap();
        // Settled 0.03 s after the step, not at 0.08 s from t = 0: within the 0.03 s allowed.
        let settled = by("settled");
        assert!(settled.passed, "{settled:?}");
        assert_eq!(settled.measured, "settled at 0.08 s, 0.03 s after its step at 0.05 s");
        assert!(settled.limit.contains("and each of its steps"), "{}", settled.limit);
        // 20 past the new value 4100, measured from 4000 at the step: more than the 15 allowed.
        let over = by("overshoot_max");
        assert!(!over.passed && over.value.unwrap() == 20.0, "{over:?}");
        assert!(over.why_failed.as_ref().unwrap().contains("past its set point 4100 (its step at 0.05 s)"), "{over:?}");
        assert!(by("final_error_max").passed, "1 from the 4100 in force at the end: {:?}", by("final_error_max"));
        // 0.02 s allowed after the step: too slow, said with the step.
        let strict = criteria("settled = { within_s = 0.02, band = 5.0 }");
        let j = judge_flight(&strict, &s, Some(&t), None);
        let why = j[0].why_failed.clone().unwrap();
        assert!(
            why.contains("from 0.08 s on, 0.03 s after its step at 0.05 s, later than the 0.02 s allowed"),
            "{why}"
        );
        // The same criteria held over the whole schedule: setpoints_held names the step too.
        let held: Criteria = toml::from_str("setpoints_held = { within_s = 0.03, band = 5.0 }").unwrap();
        let j = judge_flight(&held, &s, Some(&t), None);
        assert!(j[0].measured.starts_with("alt_ft settled at 0.08 s, 0.03 s after its step at 0.05 s"), "{:?}", j[0]);
    }

    #[test]
    fn an_attitude_step_is_judged_from_its_time_by_settled_overshoot_and_final_error() {
        // theta held at 0, a step to 10 deg at 0.03 s reached at 0.05 s, past it to 11 on the way.
        let rows: Vec<[f64; 3]> = [0.0, 0.0, 0.0, 5.0, 11.0, 10.0, 10.0, 10.0].map(|th| [0.0, th, 0.0]).into();
        let mut s = Scenario::embedded_default();
        s.setpoint.theta_deg = 0.0;
        s.setpoint_steps =
            vec![crate::setpoints::SetpointStep { at_s: 0.03, values: [("theta_deg".to_string(), 10.0)].into() }];
        let c: Criteria = toml::from_str(
            "overshoot_max_deg = 0.5
final_error_max_deg = 0.1
settled = { within_s = 0.03, band_deg = 0.5 }",
        )
        .unwrap();
        let j = judge_flight(&c, &s, Some(&trace(&rows)), None);
        let by = |key: &str| j.iter().find(|j| j.criterion == key).unwrap();
        assert_eq!(by("settled").measured, "theta settled at 0.05 s, 0.02 s after its step at 0.03 s");
        assert!(by("settled").passed);
        assert_eq!((by("overshoot_max_deg").value, by("overshoot_max_deg").passed), (Some(1.0), false));
        assert!(by("final_error_max_deg").passed, "{:?}", by("final_error_max_deg"));
    }
}
