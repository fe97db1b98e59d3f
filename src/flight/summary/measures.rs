//! Measures on one signal of a trace: settling time into a band, overshoot past a set point, RMS, and the
//! oscillation left at the end of a flight. What the summary's rows and the criteria of [`crate::judge`] share.

use crate::setpoints::Segment;
use serde::{Deserialize, Serialize};

/// The time after which `x` stays within `band` of `target`; `None` if it is outside at the end.
pub fn settle_time(t: &[f64], x: &[f64], target: f64, band: f64) -> Option<f64> {
    let last_outside = x.iter().rposition(|v| !((v - target).abs() <= band));
    match last_outside {
        None => t.first().copied(),
        Some(i) if i + 1 < x.len() => Some(t[i + 1]),
        Some(_) => None,
    }
}

/// RMS of the finite values; `None` without any. Rows without a command (a lost controller) carry NaN: they are
/// gaps, not data.
pub fn rms(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in values.filter(|v| v.is_finite()) {
        sum += v * v;
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// Largest excursion of `x` past `setpoint` in the direction of the step from its first value (0 without a step;
/// infinite once a value is NaN, a flight that is no longer a number).
pub fn overshoot(x: &[f64], setpoint: f64) -> f64 {
    let Some(first) = x.first() else { return 0.0 };
    let step = setpoint - first;
    if step == 0.0 {
        return 0.0;
    }
    // f64::signum gives 1 for 0: the step's direction is taken explicitly.
    let direction = if step > 0.0 { 1.0 } else { -1.0 };
    x.iter().map(|v| (v - setpoint) * direction).fold(0.0_f64, |m, v| if v.is_nan() { f64::INFINITY } else { m.max(v) })
}

/// The rows of `t` (ascending) each segment of a set point's history covers: from its `from_s` to the next's.
pub fn segment_rows(t: &[f64], segments: &[Segment]) -> Vec<std::ops::Range<usize>> {
    let start = |s: &Segment| t.partition_point(|v| *v < s.from_s);
    let starts: Vec<usize> = segments.iter().map(start).collect();
    starts.iter().enumerate().map(|(k, &a)| a..starts.get(k + 1).copied().unwrap_or(t.len())).collect()
}

/// A set point that steps, met or not: the segment, and when `x` came within the band of its value and stayed
/// there until the segment ended (`None`: it did not).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSettled {
    /// The segment: its step's time and value.
    pub segment: Segment,
    /// When `x` settled, s of the run.
    pub at_s: Option<f64>,
}

impl StepSettled {
    /// How long after its step it settled, s (infinite: never).
    pub fn after_step_s(&self) -> f64 {
        self.at_s.map_or(f64::INFINITY, |a| a - self.segment.from_s)
    }
}

/// The segment `x` took longest to settle into after its step ([`settle_time`] per segment, each judged on its own
/// rows; a step after the trace's end is left out); with one segment, [`settle_time`] over the run.
pub fn slowest_settle(t: &[f64], x: &[f64], segments: &[Segment], band: f64) -> StepSettled {
    let rows = segment_rows(t, segments);
    let flown = rows.into_iter().zip(segments).filter(|(rows, _)| !rows.is_empty());
    let per_segment = flown.map(|(rows, segment)| StepSettled {
        segment: *segment,
        at_s: settle_time(&t[rows.clone()], &x[rows], segment.value, band),
    });
    let slowest = per_segment.max_by(|a, b| a.after_step_s().total_cmp(&b.after_step_s()));
    slowest.unwrap_or(StepSettled { segment: segments[0], at_s: None })
}

/// The largest [`overshoot`] of `x` past any segment's value, each measured from the value `x` had at its step,
/// and that segment (the first when none overshoots).
pub fn largest_overshoot(t: &[f64], x: &[f64], segments: &[Segment]) -> (f64, Segment) {
    let rows = segment_rows(t, segments);
    let each = rows.into_iter().zip(segments).map(|(rows, s)| (overshoot(&x[rows], s.value), *s));
    each.fold((0.0, segments[0]), |worst, c| if c.0 > worst.0 { c } else { worst })
}

/// The first row of `t` inside the last `window_s` of the trace (the late window).
pub fn late_start(t: &[f64], window_s: f64) -> usize {
    let t_end = t.last().copied().unwrap_or(0.0);
    t.iter().position(|v| *v >= t_end - window_s).unwrap_or(0)
}

/// An oscillation found at the end of the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Oscillation {
    /// Signal (trace column).
    pub signal: String,
    /// Half the peak-to-peak swing in the window, in the signal's unit.
    pub amplitude: f64,
    /// Mean period from zero crossings of the de-meaned signal, s (absent: fewer than two crossings).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_s: Option<f64>,
    /// The amplitude from which it counts, in the signal's unit.
    #[serde(default)]
    pub threshold: f64,
    /// Whether it counts as a sustained oscillation (see [`oscillation_above`]).
    pub sustained: bool,
}

/// The oscillation of `x` in the last `window_s` of the trace, sustained when it swings at least `threshold` (in
/// the signal's unit) either way, at least two whole periods, without decaying.
pub fn oscillation_above(signal: &str, t: &[f64], x: &[f64], threshold: f64, window_s: f64) -> Oscillation {
    let start = late_start(t, window_s);
    let (tw, xw) = (&t[start..], &x[start..]);
    let mean = xw.iter().sum::<f64>() / xw.len().max(1) as f64;
    let (lo, hi) = xw.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    let amplitude = if xw.is_empty() { 0.0 } else { (hi - lo) / 2.0 };
    // Zero crossings of the de-meaned signal with a 10 % hysteresis, so noise around the mean is not counted.
    let hysteresis = 0.1 * amplitude;
    let (mut side, mut crossings) = (0i8, Vec::new());
    for (ti, xi) in tw.iter().zip(xw) {
        let d = xi - mean;
        let s = if d > hysteresis {
            1
        } else if d < -hysteresis {
            -1
        } else {
            0
        };
        if s != 0 {
            if side != 0 && s != side {
                crossings.push(*ti);
            }
            side = s;
        }
    }
    let period_s = (crossings.len() >= 2)
        .then(|| 2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64);
    // Sustained: at least two full periods in the window and not decaying (the second half swings at least half
    // as much as the first).
    let half = xw.len() / 2;
    let swing =
        |s: &[f64]| s.iter().fold(f64::NEG_INFINITY, |a, v| a.max(*v)) - s.iter().fold(f64::INFINITY, |a, v| a.min(*v));
    let not_decaying = half > 0 && swing(&xw[half..]) >= 0.5 * swing(&xw[..half]);
    let sustained = crossings.len() >= 4 && amplitude >= threshold && not_decaying;
    Oscillation { signal: signal.into(), amplitude, period_s, threshold, sustained }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sine_is_sustained_in_any_window_and_a_decaying_one_is_not() {
        let t: Vec<f64> = (0..=1000).map(|k| k as f64 * 0.01).collect();
        let sine: Vec<f64> = t.iter().map(|t| (std::f64::consts::TAU * t).sin()).collect();
        for window_s in [2.5, 3.0, 6.0] {
            let o = oscillation_above("x", &t, &sine, 0.5, window_s);
            assert!(o.sustained && (o.amplitude - 1.0).abs() < 1e-3, "{o:?}");
            assert!((o.period_s.unwrap() - 1.0).abs() < 0.02, "{o:?}");
        }
        assert!(!oscillation_above("x", &t, &sine, 1.5, 3.0).sustained, "below its threshold");
        let decaying: Vec<f64> = t.iter().zip(&sine).map(|(t, s)| s * (-t).exp()).collect();
        assert!(!oscillation_above("x", &t, &decaying, 0.0, 3.0).sustained);
        // A window of one period cannot hold two.
        assert!(!oscillation_above("x", &t, &sine, 0.5, 1.0).sustained);
    }

    #[test]
    fn settling_overshoot_and_rms() {
        let t = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(settle_time(&t, &[0.0, 1.2, 0.99, 1.0], 1.0, 0.05), Some(2.0));
        assert_eq!(settle_time(&t, &[0.0, 1.0, 1.0, 2.0], 1.0, 0.05), None);
        assert_eq!(overshoot(&[0.0, 1.2, 0.9], 1.0), 0.19999999999999996);
        assert_eq!(overshoot(&[1.0, 1.2], 1.0), 0.0, "no step, no overshoot");
        assert_eq!(overshoot(&[0.0, f64::NAN], 1.0), f64::INFINITY);
        assert_eq!(rms([3.0, f64::NAN, -4.0].into_iter()), Some((12.5f64).sqrt()));
        assert_eq!(rms([f64::NAN].into_iter()), None);
        assert_eq!(late_start(&[0.0, 0.5, 1.0, 1.5, 2.0], 1.0), 2);
    }
}
