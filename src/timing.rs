//! Latency statistics: the HdrHistogram every timing figure of the rig is recorded into, its summary
//! (cyclictest-style min/avg/percentiles/max), its text outputs (a table line and the `.hgrm` percentile
//! distribution that HdrHistogram's plotter reads), and the timer baseline: the OS wake-up floor the rig is compared
//! against.

use crate::clock::{self, SchedPolicy, TickSchedule};
use hdrhistogram::Histogram;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

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

/// One late wake-up of the baseline loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Outlier {
    /// Tick that was expected.
    pub tick: u64,
    /// Its wake-up lateness, µs.
    pub lateness_us: f64,
}

/// Result of [`timer_baseline`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BaselineReport {
    /// How the loop waited.
    pub source: TickSource,
    /// Period, ns.
    pub period_ns: u64,
    /// Wall time the loop ran, s.
    pub duration_s: f64,
    /// Wake-ups recorded.
    pub wakeups: u64,
    /// Wake-ups a whole period or more late.
    pub overruns: u64,
    /// Ticks skipped by those overruns.
    pub skipped_ticks: u64,
    /// Scheduling policy the loop ran under.
    pub policy: SchedPolicy,
    /// Wake-up lateness (wake time minus due time), µs.
    pub lateness: LatencySummary,
    /// The five latest wake-ups, latest first, with their tick numbers.
    pub worst: Vec<Outlier>,
    /// `(percentile, µs)` points of the lateness distribution, for plots.
    #[serde(default)]
    pub percentile_points: Vec<(f64, f64)>,
    /// The lateness distribution as `.hgrm` text.
    #[serde(skip)]
    pub hgrm: String,
}

impl BaselineReport {
    /// Human-readable report: one table line plus overruns and outliers.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "timer baseline: {}, period {:.3} ms, {:.1} s, {}\n",
            self.source,
            self.period_ns as f64 / 1e6,
            self.duration_s,
            self.policy
        );
        out.push_str(&summary_table_header());
        out.push('\n');
        out.push_str(&summary_line("wake-up lateness", &self.lateness));
        out.push('\n');
        let _ = writeln!(out, "overruns {} ({} ticks skipped)", self.overruns, self.skipped_ticks);
        let worst: Vec<String> =
            self.worst.iter().map(|o| format!("tick {} {:.1} us", o.tick, o.lateness_us)).collect();
        let _ = writeln!(out, "worst: {}", worst.join(", "));
        out
    }
}

/// How the baseline loop waits for its ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TickSource {
    /// `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`: the floor for a loop that waits on nothing else.
    Nanosleep,
    /// A [`crate::ipc::TickTimer`] (absolute timerfd) attached to an iceoryx2 WaitSet: what a loop that also waits
    /// on listeners gets.
    TimerfdWaitSet,
}

impl std::fmt::Display for TickSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TickSource::Nanosleep => "clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)",
            TickSource::TimerfdWaitSet => "absolute timerfd in an iceoryx2 WaitSet",
        })
    }
}

/// Accumulates wake-ups of a baseline loop.
struct BaselineRecorder {
    schedule: TickSchedule,
    hist: LatencyHistogram,
    worst: Vec<Outlier>,
    overruns: u64,
    skipped_ticks: u64,
}

impl BaselineRecorder {
    fn new(schedule: TickSchedule) -> Self {
        Self { schedule, hist: LatencyHistogram::new(), worst: Vec::with_capacity(6), overruns: 0, skipped_ticks: 0 }
    }

    /// Record a wake-up at `now_ns` for `tick`; returns the tick to wait for next.
    fn record(&mut self, tick: u64, now_ns: u64) -> u64 {
        let outcome = self.schedule.on_wake(tick, now_ns);
        self.hist.record_ns(outcome.wake_lateness_ns);
        if outcome.is_overrun() {
            self.overruns += 1;
            self.skipped_ticks += outcome.skipped;
        }
        let lateness_us = outcome.wake_lateness_ns as f64 / 1e3;
        if self.worst.len() < 5 || self.worst.last().is_some_and(|w| lateness_us > w.lateness_us) {
            self.worst.push(Outlier { tick, lateness_us });
            self.worst.sort_by(|a, b| b.lateness_us.total_cmp(&a.lateness_us));
            self.worst.truncate(5);
        }
        outcome.next_tick
    }

    fn report(self, source: TickSource, start_ns: u64) -> BaselineReport {
        BaselineReport {
            source,
            period_ns: self.schedule.period_ns,
            duration_s: (clock::monotonic_ns() - start_ns) as f64 / 1e9,
            wakeups: self.hist.count(),
            overruns: self.overruns,
            skipped_ticks: self.skipped_ticks,
            policy: clock::current_policy(),
            lateness: self.hist.summary(),
            worst: self.worst,
            percentile_points: self.hist.percentile_points(),
            hgrm: self.hist.hgrm(),
        }
    }
}

/// The OS floor: a bare absolute-deadline loop (no work) at `period_ns` for `duration_s`, recording how late each
/// wake-up is, with the rig's skip-on-overrun rule. Runs under whatever policy the caller set (see
/// [`clock::try_realtime`]).
pub fn timer_baseline(duration_s: f64, period_ns: u64) -> BaselineReport {
    let start_ns = clock::monotonic_ns();
    let (mut rec, end_ns) = baseline_grid(start_ns, duration_s, period_ns);
    let mut tick = 0u64;
    while rec.schedule.deadline_ns(tick) <= end_ns {
        clock::sleep_until_ns(rec.schedule.deadline_ns(tick));
        tick = rec.record(tick, clock::monotonic_ns());
    }
    rec.report(TickSource::Nanosleep, start_ns)
}

fn baseline_grid(start_ns: u64, duration_s: f64, period_ns: u64) -> (BaselineRecorder, u64) {
    let period_ns = period_ns.max(1);
    let schedule = TickSchedule::new(start_ns + period_ns, period_ns);
    (BaselineRecorder::new(schedule), start_ns + (duration_s.max(0.0) * 1e9) as u64)
}

/// The same measurement with the tick from `source`; [`TickSource::TimerfdWaitSet`] measures the tick a rig loop
/// gets when it also waits on iceoryx2 listeners.
pub fn timer_baseline_with(
    source: TickSource,
    duration_s: f64,
    period_ns: u64,
) -> Result<BaselineReport, crate::ipc::IpcError> {
    use iceoryx2::prelude::CallbackProgression;
    if source == TickSource::Nanosleep {
        return Ok(timer_baseline(duration_s, period_ns));
    }
    let start_ns = clock::monotonic_ns();
    let (mut rec, end_ns) = baseline_grid(start_ns, duration_s, period_ns);
    let timer = crate::ipc::TickTimer::new(rec.schedule)?;
    let waitset = crate::ipc::rig_waitset()?;
    let guard = waitset
        .attach_notification(&timer)
        .map_err(|e| crate::ipc::IpcError::WaitSet(format!("attaching the timerfd: {e:?}")))?;
    let mut tick = 0u64;
    let mut failure = None;
    crate::ipc::run_waitset(&waitset, |id| {
        if id.has_event_from(&guard) {
            let now_ns = clock::monotonic_ns();
            match timer.read_expirations() {
                // Readiness without an expiration (a spurious wake-up) is not a tick.
                Ok(0) => {}
                Ok(_) => tick = rec.record(tick, now_ns),
                Err(e) => {
                    failure = Some(e);
                    return CallbackProgression::Stop;
                }
            }
        }
        if rec.schedule.deadline_ns(tick) > end_ns { CallbackProgression::Stop } else { CallbackProgression::Continue }
    })?;
    if let Some(e) = failure {
        return Err(e);
    }
    drop(guard);
    Ok(rec.report(source, start_ns))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

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

    #[test]
    fn baseline_runs_and_counts_every_wakeup() {
        let r = timer_baseline(0.05, 5_000_000);
        // Only counts and orderings: never timing upper bounds on a shared machine.
        assert!(r.wakeups >= 1);
        assert!(r.wakeups + r.skipped_ticks <= 11, "{r:?}");
        assert!(r.lateness.p50_us <= r.lateness.max_us);
        assert!(r.hgrm.contains("#[Max"));
        assert!(r.to_text().contains("wake-up lateness"));
    }

    #[test]
    fn timerfd_baseline_runs_and_counts_every_wakeup() {
        let r = timer_baseline_with(TickSource::TimerfdWaitSet, 0.05, 5_000_000).unwrap();
        assert_eq!(r.source, TickSource::TimerfdWaitSet);
        assert!(r.wakeups >= 1);
        assert!(r.wakeups + r.skipped_ticks <= 11, "{r:?}");
        assert!(r.lateness.min_us >= 0.0 && r.lateness.p50_us <= r.lateness.max_us);
    }
}
