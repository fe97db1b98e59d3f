//! The OS floor taken by cyclictest itself (rt-tests), for `silrig run --floor cyclictest`: the reference tool's
//! own loop beside the rig, at the scenario's period and the plant's priority, its histogram read into the same
//! report as `silrig timer-baseline`'s, so a reader who trusts only cyclictest gets cyclictest's figure.

use super::timer_baseline::{BaselineReport, TickSource};
use silrig_wire::clock::SchedPolicy;
use silrig_wire::timing::LatencyHistogram;
use std::process::Command;

/// Histogram range asked of cyclictest, µs; later wake-ups are counted as overflows.
pub const HISTOGRAM_US: u64 = 20_000;

/// The cyclictest command that measures the floor for `duration_s` at `period_ns` and SCHED_FIFO `priority`: one
/// thread, memory locked, the histogram only (`-q -h`).
pub fn command(duration_s: f64, period_ns: u64, priority: i32) -> Result<Command, String> {
    let program = crate::program::find_program("cyclictest")
        .ok_or("--floor cyclictest: cyclictest is not installed (Debian: apt-get install rt-tests)")?;
    let period_us = (period_ns / 1000).max(1);
    let loops = ((duration_s * 1e9) as u64 / period_ns.max(1)).max(1);
    let mut command = Command::new(program);
    command.args([
        "-q".to_string(),
        "-m".to_string(),
        "-t1".to_string(),
        format!("-p{priority}"),
        format!("-i{period_us}"),
        format!("-l{loops}"),
        format!("-h{HISTOGRAM_US}"),
    ]);
    Ok(command)
}

fn header_value(text: &str, key: &str) -> Option<u64> {
    text.lines().find_map(|l| l.strip_prefix(key)).and_then(|v| v.split_whitespace().next()?.parse().ok())
}

/// cyclictest's `-q -h` output as a baseline report. Its buckets are whole microseconds; an overflow (a wake-up
/// beyond [`HISTOGRAM_US`]) is counted at cyclictest's maximum. cyclictest's histogram covers its whole run, so
/// there is no steady-state figure apart from warm-up.
pub fn parse(text: &str, period_ns: u64, duration_s: f64, priority: i32) -> Result<BaselineReport, String> {
    let mut hist = LatencyHistogram::new();
    let mut late_by_a_period = 0u64;
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
        let mut fields = line.split_whitespace().map(str::parse::<u64>);
        let (Some(Ok(us)), Some(Ok(count))) = (fields.next(), fields.next()) else {
            return Err(format!("cyclictest printed a histogram line that is not two numbers: {line:?}"));
        };
        for _ in 0..count {
            hist.record_ns((us * 1000) as i64);
        }
        if us * 1000 >= period_ns {
            late_by_a_period += count;
        }
    }
    // cyclictest's total counts the histogram's buckets; the overflows come on top of it.
    let total = header_value(text, "# Total:").ok_or("cyclictest printed no histogram (no `# Total:` line)")?;
    if hist.count() != total {
        return Err(format!("cyclictest's histogram holds {} wake-ups, its total says {total}", hist.count()));
    }
    let overflows = header_value(text, "# Histogram Overflows:").unwrap_or(0);
    let max_us = header_value(text, "# Max Latencies:").unwrap_or(HISTOGRAM_US);
    for _ in 0..overflows {
        hist.record_ns((max_us * 1000) as i64);
    }
    Ok(BaselineReport {
        source: TickSource::Cyclictest,
        period_ns,
        duration_s,
        wakeups: hist.count(),
        overruns: late_by_a_period + overflows * u64::from(max_us * 1000 >= period_ns),
        skipped_ticks: 0,
        policy: SchedPolicy::Fifo(priority),
        lateness: hist.summary(),
        lateness_steady: None,
        worst: Vec::new(),
        // cyclictest prints no time of its late wake-ups: no rig miss can be placed in one of them.
        stalls: Vec::new(),
        percentile_points: hist.percentile_points(),
        hgrm: hist.hgrm(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const OUTPUT: &str = "# /dev/cpu_dma_latency set to 0us\n# Histogram\n000040 000002\n000041 000001\n\
                          000073 000001\n# Total: 000000004\n# Min Latencies: 00040\n# Avg Latencies: 00039\n\
                          # Max Latencies: 25000\n# Histogram Overflows: 00001\n# Histogram Overflow at cycle number:\n\
                          # Thread 0: 00017\n";

    #[test]
    fn the_histogram_and_its_overflows_become_the_floor() {
        let r = parse(OUTPUT, 10_000_000, 0.05, 80).expect("parses");
        assert_eq!(r.wakeups, 5);
        assert_eq!(r.source, TickSource::Cyclictest);
        assert!((r.lateness.min_us - 40.0).abs() < 0.1, "{}", r.lateness.min_us);
        // The overflow counts at cyclictest's maximum, 25 ms: a period late, so an overrun.
        assert!((r.lateness.max_us - 25_000.0).abs() / 25_000.0 < 0.01, "{}", r.lateness.max_us);
        assert_eq!(r.overruns, 1);
    }

    #[test]
    fn output_that_is_not_cyclictest_histogram_is_refused() {
        assert!(parse("000040 x\n# Total: 1\n", 10_000_000, 1.0, 80).unwrap_err().contains("not two numbers"));
        assert!(parse("# Histogram\n000040 000002\n", 10_000_000, 1.0, 80).unwrap_err().contains("# Total:"));
        assert!(parse("000040 000002\n# Total: 3\n", 10_000_000, 1.0, 80).unwrap_err().contains("total says 3"));
    }
}
