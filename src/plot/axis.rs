//! Axes: our own tick positions and labels, linear ("nice" ticks) or on the percentile number-of-nines scale, as a
//! plotters coordinate so that the mesh draws exactly our ticks.

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};

/// The "number of nines" of a percentile: 90% -> 1, 99% -> 2, 99.9% -> 3.
pub(super) fn nines(percentile: f64) -> f64 {
    (1.0 / (1.0 - percentile / 100.0)).log10()
}

/// A linear axis with precomputed ticks and their labels (plotters' own key points are not tunable enough).
#[derive(Clone)]
pub(super) struct Axis {
    pub(super) lo: f64,
    pub(super) hi: f64,
    ticks: Vec<f64>,
    pub(super) labels: Vec<String>,
}

impl Axis {
    /// "Nice" ticks (1, 2 or 5 times a power of ten), about `target` of them.
    pub(super) fn linear(lo: f64, hi: f64, target: usize) -> Self {
        let raw = (hi - lo) / target.max(1) as f64;
        let magnitude = 10f64.powf(raw.log10().floor());
        let norm = raw / magnitude;
        let mantissa = if norm < 1.5 {
            1.0
        } else if norm < 3.0 {
            2.0
        } else if norm < 7.5 {
            5.0
        } else {
            10.0
        };
        let step = mantissa * magnitude;
        let first = (lo / step - 1e-9).ceil() as i64;
        let last = (hi / step + 1e-9).floor() as i64;
        if !(step.is_finite() && step > 0.0) || last.saturating_sub(first) > 100 {
            // Spans no f64 arithmetic handles (near f64::MAX): just the ends.
            return Self { lo, hi, ticks: vec![lo, hi], labels: vec![format!("{lo:.3e}"), format!("{hi:.3e}")] };
        }
        let ticks: Vec<f64> = (first..=last).map(|n| n as f64 * step).collect();
        let biggest = lo.abs().max(hi.abs());
        let labels = if step < 1e-3 || biggest >= 1e6 {
            let digits = (biggest.log10().floor() - step.log10().floor()).max(0.0) as usize;
            ticks
                .iter()
                .map(|&v| if v.abs() < step * 1e-6 { "0".to_string() } else { format!("{v:.digits$e}") })
                .collect()
        } else {
            let decimals = (-step.log10().floor()).max(0.0) as usize;
            ticks.iter().map(|&v| format!("{:.decimals$}", if v.abs() < step * 1e-6 { 0.0 } else { v })).collect()
        };
        Self { lo, hi, ticks, labels }
    }

    /// Percentile ticks at whole numbers of nines: 0%, 90%, 99%, 99.9%, ...
    pub(super) fn nines(hi: f64) -> Self {
        let ticks: Vec<f64> = (0..=hi as i64).map(|n| n as f64).collect();
        let labels = ticks
            .iter()
            .map(|&n| match n as i64 {
                0 => "0%".to_string(),
                n => format!("{:.*}%", (n - 2).max(0) as usize, 100.0 - 10f64.powi(2 - n as i32)),
            })
            .collect();
        Self { lo: 0.0, hi, ticks, labels }
    }

    /// A log axis over decades `lo..hi` (log10 of the values): a tick at each whole power of ten, labelled with the
    /// value itself (1, 10, 100, 1,000), never with its logarithm; where the range holds fewer than two powers of
    /// ten, also at 2 and 5 times them.
    pub(super) fn decades(lo: f64, hi: f64) -> Self {
        let whole = (lo.ceil() as i64..=hi.floor() as i64).map(|n| n as f64);
        let mut ticks: Vec<f64> = whole.clone().collect();
        if ticks.len() < 2 {
            let between = (lo.floor() as i64..=hi.floor() as i64)
                .flat_map(|n| [2.0f64, 5.0].map(|m| n as f64 + m.log10()))
                .filter(|t| (lo..=hi).contains(t));
            ticks.extend(between);
            ticks.sort_by(f64::total_cmp);
        }
        let labels = ticks.iter().map(|&t| count_text(10f64.powf(t))).collect();
        Self { lo, hi, ticks, labels }
    }

    /// The same axis without ticks below `value` (a decade axis of counts has no tick at 0.1 of a tick).
    pub(super) fn without_ticks_below(self, value: f64) -> Self {
        let (ticks, labels) = self
            .ticks
            .iter()
            .zip(self.labels)
            .filter(|(t, _)| 10f64.powf(**t) >= value * (1.0 - 1e-9))
            .map(|(t, l)| (*t, l))
            .unzip();
        Self { ticks, labels, ..self }
    }

    /// The tick labels, in order.
    pub(super) fn tick_labels(&self) -> &[String] {
        &self.labels
    }

    pub(super) fn label(&self, v: f64) -> String {
        let tol = 1e-9 * (self.hi / 2.0 - self.lo / 2.0).abs();
        self.ticks.iter().position(|t| (t - v).abs() <= tol).map_or_else(String::new, |i| self.labels[i].clone())
    }
}

/// A power of ten (or 2 or 5 times one) as a person writes it: 0.01, 0.5, 20, 1,000, 100,000.
fn count_text(v: f64) -> String {
    if v < 1.0 {
        let decimals = (-v.log10().floor()).max(0.0) as usize;
        return format!("{v:.decimals$}");
    }
    let digits = format!("{:.0}", v);
    let mut out = String::new();
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let span = self.hi - self.lo;
        let actual = limit.1 - limit.0;
        if span == 0.0 || actual == 0 {
            return limit.0;
        }
        // Halves keep spans near f64::MAX finite.
        let logic = ((*v / 2.0 - self.lo / 2.0) / (self.hi / 2.0 - self.lo / 2.0)).clamp(-10.0, 11.0);
        if actual > 0 {
            limit.0 + (actual as f64 * logic + 1e-3).floor() as i32
        } else {
            limit.0 + (actual as f64 * logic - 1e-3).ceil() as i32
        }
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        // Bold points are the ticks; no light (minor) grid.
        if hint.weight().allow_light_points() { Vec::new() } else { self.ticks.clone() }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ticks_and_labels() {
        let a = Axis::linear(-1.05, 10.5, 5);
        assert_eq!(a.labels, ["0", "2", "4", "6", "8", "10"]);
        let a = Axis::linear(0.0, 1.0, 4);
        assert_eq!(a.labels, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let a = Axis::linear(-0.3, 0.3, 3);
        assert!(a.labels.contains(&"0.0".to_string()), "{:?}", a.labels);
        let a = Axis::linear(0.0, 3e-5, 3);
        assert!(a.labels.iter().all(|l| l == "0" || l.contains('e')), "{:?}", a.labels);
    }

    #[test]
    fn decade_axes_label_the_values_not_their_logarithms() {
        let a = Axis::decades(-1.0, 4.2);
        assert_eq!(a.labels, ["0.1", "1", "10", "100", "1,000", "10,000"]);
        // Less than two decades: 2 and 5 times the powers of ten too.
        let a = Axis::decades(0.9, 1.9);
        assert_eq!(a.labels, ["10", "20", "50"]);
        assert_eq!(count_text(1_000_000.0), "1,000,000");
        assert_eq!(Axis::decades(-1.0, 2.5).without_ticks_below(1.0).labels, ["1", "10", "100"]);
    }

    #[test]
    fn nines_axis_labels() {
        let a = Axis::nines(5.0);
        assert_eq!(a.labels, ["0%", "90%", "99%", "99.9%", "99.99%", "99.999%"]);
        assert!((nines(99.9) - 3.0).abs() < 1e-9);
        assert_eq!(nines(0.0), 0.0);
    }
}
