//! Latency statistics: the HdrHistogram every timing figure of the rig is recorded into, its summary
//! (cyclictest-style min/avg/percentiles/max), and its text outputs (a table line and the `.hgrm` percentile
//! distribution that HdrHistogram's plotter reads).

use crate::clock;
use hdrhistogram::Histogram;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// The first second of a run is its warm-up (caches, page faults, the peers' first wake-ups); the report shows it
/// apart from the steady state after it, ns.
pub const WARM_UP_NS: u64 = 1_000_000_000;

/// Smallest value the histogram resolves, ns.
pub const HISTOGRAM_LOW_NS: u64 = 1;
/// Largest value the histogram holds, ns (60 s); larger values are recorded as this.
pub const HISTOGRAM_HIGH_NS: u64 = 60 * clock::NS_PER_S;
/// Significant decimal digits kept.
pub const HISTOGRAM_SIGFIG: u8 = 3;

/// A latency histogram in nanoseconds, 1 ns .. 60 s at 3 significant digits. Recording never fails and never
/// allocates: out-of-range values saturate.
#[derive(Debug, Clone)]
pub struct LatencyHistogram {
    hist: Histogram<u64>,
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self::new()
    }
}

/// Summary of a histogram, in µs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LatencySummary {
    /// Values recorded.
    pub count: u64,
    /// Smallest value, µs.
    pub min_us: f64,
    /// Mean, µs.
    pub avg_us: f64,
    /// Median, µs.
    pub p50_us: f64,
    /// 90th percentile, µs.
    pub p90_us: f64,
    /// 99th percentile, µs.
    pub p99_us: f64,
    /// 99.9th percentile, µs.
    pub p999_us: f64,
    /// Largest value, µs.
    pub max_us: f64,
}

fn ns_to_us(ns: u64) -> f64 {
    ns as f64 / 1e3
}

impl LatencyHistogram {
    /// An empty histogram.
    pub fn new() -> Self {
        // The bounds are constants that hdrhistogram accepts; a failure here is a programming error caught by the
        // first test that builds one.
        let hist = Histogram::new_with_bounds(HISTOGRAM_LOW_NS, HISTOGRAM_HIGH_NS, HISTOGRAM_SIGFIG)
            .expect("constant histogram bounds are valid");
        Self { hist }
    }

    /// Record one value, ns; negative values (an early wake-up) record as 0, values beyond 60 s as 60 s.
    #[inline]
    pub fn record_ns(&mut self, value_ns: i64) {
        self.hist.saturating_record(value_ns.max(0) as u64);
    }

    /// Values recorded.
    pub fn count(&self) -> u64 {
        self.hist.len()
    }

    /// Value at `quantile` (0..=1), ns (the highest value equivalent to the bucket, as HdrHistogram reports).
    pub fn value_at_quantile_ns(&self, quantile: f64) -> u64 {
        self.hist.value_at_quantile(quantile)
    }

    /// Add all values of `other`.
    pub fn merge(&mut self, other: &LatencyHistogram) {
        // Same bounds on both sides, so the addition cannot fail; saturate anyway rather than panic.
        if self.hist.add(&other.hist).is_err() {
            for v in other.hist.iter_recorded() {
                self.hist.saturating_record_n(v.value_iterated_to(), v.count_at_value());
            }
        }
    }

    /// Every bucket that holds values: (a value of the bucket, ns; how many values it holds), in value order. A
    /// histogram rebuilt from them ([`LatencyHistogram::from_buckets`]) is this one, so reports written by separate
    /// processes (a restarted process's lives) merge exactly.
    pub fn buckets(&self) -> Vec<(u64, u64)> {
        self.hist.iter_recorded().map(|v| (v.value_iterated_to(), v.count_at_value())).collect()
    }

    /// The histogram whose [`buckets`](LatencyHistogram::buckets) these are.
    pub fn from_buckets(buckets: &[(u64, u64)]) -> Self {
        let mut h = Self::new();
        for (value_ns, count) in buckets {
            h.hist.saturating_record_n(*value_ns, *count);
        }
        h
    }

    /// Forget all values.
    pub fn reset(&mut self) {
        self.hist.reset();
    }

    /// The summary, µs. All zero when empty.
    pub fn summary(&self) -> LatencySummary {
        if self.hist.is_empty() {
            return LatencySummary::default();
        }
        let q = |quantile: f64| ns_to_us(self.hist.value_at_quantile(quantile));
        LatencySummary {
            count: self.hist.len(),
            min_us: ns_to_us(self.hist.min()),
            avg_us: self.hist.mean() / 1e3,
            p50_us: q(0.5),
            p90_us: q(0.9),
            p99_us: q(0.99),
            p999_us: q(0.999),
            // `max()` is the highest equivalent of the largest value, the same rounding as the quantiles, so
            // p99.9 <= max holds.
            max_us: ns_to_us(self.hist.max()),
        }
    }

    /// (percentile 0..=100, value µs) pairs along HdrHistogram's percentile iteration (5 ticks per half distance),
    /// for plotting latency against 1/(1-p). Both coordinates are non-decreasing. Empty when nothing was recorded.
    pub fn percentile_points(&self) -> Vec<(f64, f64)> {
        self.hist
            .iter_quantiles(5)
            .map(|v| (v.quantile_iterated_to() * 100.0, ns_to_us(v.value_iterated_to())))
            .collect()
    }

    /// The percentile distribution in HdrHistogram's `outputPercentileDistribution` text format (`.hgrm`), values
    /// in µs (output scaling ratio 1000), 5 ticks per half distance, as the HdrHistogram plotter reads it.
    pub fn hgrm(&self) -> String {
        let digits = usize::from(HISTOGRAM_SIGFIG);
        let mut out = String::new();
        // `write!` into a String cannot fail.
        let _ = write!(out, "{:>12} {:>14} {:>10} {:>14}\n\n", "Value", "Percentile", "TotalCount", "1/(1-Percentile)");
        let mut total: u64 = 0;
        for v in self.hist.iter_quantiles(5) {
            total += v.count_since_last_iteration();
            let value_us = ns_to_us(v.value_iterated_to());
            let quantile = v.quantile_iterated_to();
            if quantile < 1.0 {
                let _ = writeln!(
                    out,
                    "{value_us:>12.digits$} {quantile:>2.12} {total:>10} {:>14.2}",
                    1.0 / (1.0 - quantile)
                );
            } else {
                let _ = writeln!(out, "{value_us:>12.digits$} {quantile:>2.12} {total:>10}");
            }
        }
        let (mean_us, stdev_us, max_us) = if self.hist.is_empty() {
            (0.0, 0.0, 0.0)
        } else {
            (self.hist.mean() / 1e3, self.hist.stdev() / 1e3, ns_to_us(self.hist.max()))
        };
        let _ = writeln!(out, "#[Mean    = {mean_us:>12.digits$}, StdDeviation   = {stdev_us:>12.digits$}]");
        let _ = writeln!(out, "#[Max     = {max_us:>12.digits$}, Total count    = {:>12}]", self.hist.len());
        let _ = writeln!(out, "#[Buckets = {:>12}, SubBuckets     = {:>12}]", self.hist.buckets(), sub_bucket_count());
        out
    }
}

/// HdrHistogram's sub-bucket count for [`HISTOGRAM_SIGFIG`] (the Rust crate keeps it private; this is its formula:
/// the power of two covering 2 * 10^sigfig).
fn sub_bucket_count() -> u64 {
    (2 * 10u64.pow(u32::from(HISTOGRAM_SIGFIG))).next_power_of_two()
}

/// Header of [`summary_table`].
pub fn summary_table_header() -> String {
    format!(
        "{:<36} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "(us)", "count", "min", "avg", "p50", "p90", "p99", "p99.9", "max"
    )
}

/// One cyclictest-style line for a named summary.
pub fn summary_line(name: &str, s: &LatencySummary) -> String {
    format!(
        "{:<36} {:>8} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1}",
        name, s.count, s.min_us, s.avg_us, s.p50_us, s.p90_us, s.p99_us, s.p999_us, s.max_us
    )
}

/// A header plus one line per named histogram.
pub fn summary_table(rows: &[(&str, &LatencyHistogram)]) -> String {
    let mut out = summary_table_header();
    out.push('\n');
    for (name, hist) in rows {
        out.push_str(&summary_line(name, &hist.summary()));
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_model::rng::SplitMix64;

    fn sample_histogram() -> LatencyHistogram {
        let mut rng = SplitMix64::new(7);
        let mut h = LatencyHistogram::new();
        for _ in 0..20_000 {
            // Heavy-tailed: mostly tens of µs, a few ms.
            let u = rng.uniform();
            let v_ns = 20_000.0 / (1.0 - u).max(1e-4).sqrt();
            h.record_ns(v_ns as i64);
        }
        h
    }

    #[test]
    fn summary_is_ordered_and_saturates_instead_of_failing() {
        let mut h = sample_histogram();
        h.record_ns(-5);
        h.record_ns(i64::MAX);
        let s = h.summary();
        assert_eq!(s.count, 20_002);
        assert!(s.min_us <= s.p50_us, "{s:?}");
        assert!(s.p50_us <= s.p90_us && s.p90_us <= s.p99_us && s.p99_us <= s.p999_us && s.p999_us <= s.max_us);
        assert!(s.min_us <= s.avg_us && s.avg_us <= s.max_us);
        assert!((s.max_us - 60e6).abs() / 60e6 < 1e-3, "saturated at 60 s: {}", s.max_us);
        assert_eq!(LatencyHistogram::new().summary(), LatencySummary::default());
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<LatencySummary>(&json).unwrap(), s);
    }

    #[test]
    fn hgrm_output_parses() {
        let h = sample_histogram();
        let text = h.hgrm();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), "       Value     Percentile TotalCount 1/(1-Percentile)");
        assert_eq!(lines.next().unwrap(), "");
        let mut rows = Vec::new();
        let mut footer = Vec::new();
        for line in lines {
            if line.starts_with("#[") {
                footer.push(line.to_string());
                continue;
            }
            let cols: Vec<&str> = line.split_whitespace().collect();
            assert!(cols.len() == 4 || cols.len() == 3, "{line}");
            let value: f64 = cols[0].parse().unwrap();
            let pct: f64 = cols[1].parse().unwrap();
            let total: u64 = cols[2].parse().unwrap();
            if cols.len() == 4 {
                let inv: f64 = cols[3].parse().unwrap();
                assert!((inv - 1.0 / (1.0 - pct)).abs() <= 0.01 * inv.max(1.0), "{line}");
            }
            rows.push((value, pct, total));
        }
        assert!(rows.len() > 20);
        for w in rows.windows(2) {
            assert!(w[0].0 <= w[1].0 && w[0].1 <= w[1].1 && w[0].2 <= w[1].2, "{w:?}");
        }
        let last = rows.last().unwrap();
        assert_eq!((last.1, last.2), (1.0, 20_000));
        assert_eq!(footer.len(), 3, "{footer:?}");
        assert!(footer[0].starts_with("#[Mean    = ") && footer[0].contains(", StdDeviation   = "));
        assert!(footer[1].starts_with("#[Max     = ") && footer[1].ends_with("Total count    =        20000]"));
        assert!(footer[2].starts_with("#[Buckets = ") && footer[2].contains("SubBuckets     =         2048]"));
        let max: f64 = footer[1]["#[Max     = ".len()..].split(',').next().unwrap().trim().parse().unwrap();
        assert_eq!(max, h.summary().max_us);
    }

    #[test]
    fn percentile_points_are_monotonic() {
        let points = sample_histogram().percentile_points();
        assert!(points.len() > 20);
        for w in points.windows(2) {
            assert!(w[0].0 <= w[1].0 && w[0].1 <= w[1].1, "{w:?}");
        }
        assert_eq!(points.last().unwrap().0, 100.0);
        assert!(LatencyHistogram::new().percentile_points().is_empty());
    }

    #[test]
    fn table_has_one_line_per_histogram() {
        let h = sample_histogram();
        let table = summary_table(&[("plant wake-up", &h), ("controller wake-up", &h)]);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].contains("p99.9") && lines[1].starts_with("plant wake-up"));
        assert_eq!(lines[1].split_whitespace().count(), 2 + 8);
    }
}
