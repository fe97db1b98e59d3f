//! The OS floor, `silrig timer-baseline`: a bare absolute-deadline loop with no work, recording how late the OS
//! wakes it, cyclictest-style, with the rig's skip-on-overrun rule. `silrig run` starts it beside a realtime rig
//! (with [`BaselineArgs::to_argv`]) so the plant's wake-up lateness is read against the floor measured under the
//! same conditions.

use serde::{Deserialize, Serialize};
use silrig_wire::clock::{self, SchedPolicy, TickSchedule};
use silrig_wire::timing::{LatencyHistogram, LatencySummary, summary_line, summary_table_header};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The `silrig` subcommand that runs [`run`].
pub const SUBCOMMAND: &str = "timer-baseline";

/// Arguments of `silrig timer-baseline`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct BaselineArgs {
    /// How long to run, s.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub duration_s: f64,
    /// Period, ms.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub period_ms: f64,
    /// SCHED_FIFO priority to ask for (1..=99); 0 stays with SCHED_OTHER.
    #[arg(long, default_value_t = 80, allow_negative_numbers = true)]
    pub fifo_priority: i32,
    /// Wait on an absolute timerfd in an iceoryx2 WaitSet instead of clock_nanosleep.
    #[arg(long)]
    pub timerfd: bool,
    /// Also write the HdrHistogram percentile distribution (.hgrm, µs) to this file.
    #[arg(long)]
    pub hgrm: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

impl BaselineArgs {
    /// The command line (after the subcommand) that gives these arguments.
    pub fn to_argv(&self) -> Vec<String> {
        let mut argv = vec![
            "--duration-s".into(),
            self.duration_s.to_string(),
            "--period-ms".into(),
            self.period_ms.to_string(),
            "--fifo-priority".into(),
            self.fifo_priority.to_string(),
        ];
        if self.timerfd {
            argv.push("--timerfd".into());
        }
        if let Some(h) = &self.hgrm {
            argv.extend(["--hgrm".into(), h.display().to_string()]);
        }
        if self.json {
            argv.push("--json".into());
        }
        argv
    }
}

/// `silrig timer-baseline`: validate, ask for the scheduling, measure, write the `.hgrm` file if asked; returns
/// what to print (text or JSON).
pub fn run(args: &BaselineArgs) -> anyhow::Result<String> {
    let BaselineArgs { duration_s, period_ms, fifo_priority, .. } = *args;
    // Bounded so the loop's nanosecond arithmetic cannot overflow into an instant, empty "measurement".
    silrig_rig::flag_in_range("duration-s", duration_s, 0.01, 3600.0, "s").map_err(|e| anyhow::anyhow!(e))?;
    silrig_rig::flag_in_range("period-ms", period_ms, 0.1, 1000.0, "ms").map_err(|e| anyhow::anyhow!(e))?;
    anyhow::ensure!((0..=99).contains(&fifo_priority), "--fifo-priority must be 0..=99, got {fifo_priority}");
    if fifo_priority > 0
        && let Some(warning) = clock::try_realtime(fifo_priority).warning
    {
        eprintln!("silrig timer-baseline: warning: {warning}");
    }
    let source = if args.timerfd { TickSource::TimerfdWaitSet } else { TickSource::Nanosleep };
    let report = timer_baseline_with(source, duration_s, (period_ms * 1e6).round() as u64)?;
    if let Some(path) = &args.hgrm {
        silrig_flight::files::write_atomically(path, &report.hgrm)?;
    }
    Ok(if args.json { serde_json::to_string_pretty(&report)? + "\n" } else { report.to_text() })
}

/// One late wake-up of the baseline loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Outlier {
    /// Tick that was expected.
    pub tick: u64,
    /// Its wake-up lateness, µs.
    pub lateness_us: f64,
}

/// A wake-up of the baseline loop late by a tenth of its period or more: the machine stalled, and when.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stall {
    /// The deadline it woke late for, CLOCK_MONOTONIC ns (the clock of the rig's stamps and events).
    pub at_ns: u64,
    /// How late it woke, µs.
    pub lateness_us: f64,
}

/// Most stalls a report keeps (the first ones): a machine stalling more often than this is disturbed throughout.
pub const MAX_STALLS: usize = 1000;

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
    /// The same after the first second (steady state, as the rig's report separates it from warm-up), µs.
    #[serde(default)]
    pub lateness_steady: Option<LatencySummary>,
    /// The five latest wake-ups, latest first, with their tick numbers.
    pub worst: Vec<Outlier>,
    /// Every wake-up late by a tenth of the period or more, in order (up to [`MAX_STALLS`]): when the machine
    /// stalled, so that a rig tick missed at the same time can be told apart from one the controller missed alone.
    #[serde(default)]
    pub stalls: Vec<Stall>,
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
    /// A [`silrig_wire::ipc::TickTimer`] (absolute timerfd) attached to an iceoryx2 WaitSet: what a loop that also
    /// waits on listeners gets.
    TimerfdWaitSet,
    /// cyclictest (rt-tests) itself, run beside the rig by `silrig run --floor cyclictest`.
    Cyclictest,
}

impl std::fmt::Display for TickSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TickSource::Nanosleep => "clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)",
            TickSource::TimerfdWaitSet => "absolute timerfd in an iceoryx2 WaitSet",
            TickSource::Cyclictest => "cyclictest (rt-tests)",
        })
    }
}

/// Accumulates wake-ups of a baseline loop.
struct BaselineRecorder {
    schedule: TickSchedule,
    hist: LatencyHistogram,
    /// Wake-ups after the first second.
    steady: LatencyHistogram,
    worst: Vec<Outlier>,
    stalls: Vec<Stall>,
    overruns: u64,
    skipped_ticks: u64,
}

impl BaselineRecorder {
    fn new(schedule: TickSchedule) -> Self {
        Self {
            schedule,
            hist: LatencyHistogram::new(),
            steady: LatencyHistogram::new(),
            worst: Vec::with_capacity(6),
            stalls: Vec::new(),
            overruns: 0,
            skipped_ticks: 0,
        }
    }

    /// Record a wake-up at `now_ns` for `tick`; returns the tick to wait for next.
    fn record(&mut self, tick: u64, now_ns: u64) -> u64 {
        let outcome = self.schedule.on_wake(tick, now_ns);
        self.hist.record_ns(outcome.wake_lateness_ns);
        if tick * self.schedule.period_ns >= silrig_wire::timing::WARM_UP_NS {
            self.steady.record_ns(outcome.wake_lateness_ns);
        }
        if outcome.is_overrun() {
            self.overruns += 1;
            self.skipped_ticks += outcome.skipped;
        }
        let lateness_us = outcome.wake_lateness_ns as f64 / 1e3;
        // A tenth of the period: the default suite's round-trip budget, and far above a quiet machine's wake-ups.
        if outcome.wake_lateness_ns >= (self.schedule.period_ns / 10) as i64 && self.stalls.len() < MAX_STALLS {
            self.stalls.push(Stall { at_ns: self.schedule.deadline_ns(tick), lateness_us });
        }
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
            lateness_steady: (self.steady.count() > 0).then(|| self.steady.summary()),
            worst: self.worst,
            stalls: self.stalls,
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
) -> Result<BaselineReport, silrig_wire::ipc::IpcError> {
    use iceoryx2::prelude::CallbackProgression;
    if source == TickSource::Nanosleep {
        return Ok(timer_baseline(duration_s, period_ns));
    }
    let start_ns = clock::monotonic_ns();
    let (mut rec, end_ns) = baseline_grid(start_ns, duration_s, period_ns);
    let timer = silrig_wire::ipc::TickTimer::new(rec.schedule)?;
    let waitset = silrig_wire::ipc::rig_waitset()?;
    let guard = waitset
        .attach_notification(&timer)
        .map_err(|e| silrig_wire::ipc::IpcError::WaitSet(format!("attaching the timerfd: {e:?}")))?;
    let mut tick = 0u64;
    let mut failure = None;
    silrig_wire::ipc::run_waitset(&waitset, |id| {
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
    use clap::Parser;

    #[derive(Parser)]
    struct Baseline {
        #[command(flatten)]
        args: BaselineArgs,
    }

    #[test]
    fn baseline_arguments_survive_their_command_line() {
        let args = BaselineArgs {
            duration_s: 3.5,
            period_ms: 2.5,
            fifo_priority: 0,
            timerfd: true,
            hgrm: Some("a dir/x.hgrm".into()),
            json: true,
        };
        let argv = std::iter::once(SUBCOMMAND.to_string()).chain(args.to_argv());
        assert_eq!(Baseline::parse_from(argv).args, args);
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

    #[test]
    fn a_wake_up_late_by_a_tenth_of_the_period_is_a_stall_with_its_time() {
        let (mut rec, _) = baseline_grid(1_000_000_000, 1.0, 10_000_000);
        let due = |tick| rec.schedule.deadline_ns(tick);
        let (d0, d1, d2) = (due(0), due(1), due(2));
        let next = rec.record(0, d0 + 50_000);
        assert_eq!(next, 1);
        rec.record(1, d1 + 999_000);
        rec.record(2, d2 + 2_500_000);
        let r = rec.report(TickSource::Nanosleep, 1_000_000_000);
        assert_eq!(r.stalls, [Stall { at_ns: d2, lateness_us: 2500.0 }], "only the wake-up 1 ms late or more");
    }
}
