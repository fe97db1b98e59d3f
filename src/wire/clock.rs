//! Time for the real-time loops: the monotonic clock, absolute-deadline sleeps, the request for SCHED_FIFO and
//! locked memory, and the pure tick schedule that decides which tick a wake-up belongs to and what was skipped.
//!
//! Every process of the rig stamps and schedules with `CLOCK_MONOTONIC`, the one clock that is shared by all
//! processes of a machine and never jumps (iceoryx2 #1000 is what happens with the wall clock).

use serde::{Deserialize, Serialize};

/// Nanoseconds per second.
pub const NS_PER_S: u64 = 1_000_000_000;

/// How long a process waiting for its peers to join pauses between looks, `waited_ns` into the wait: 0.5 ms for
/// the first 100 ms, then `later`. Peers started together (a sweep's case forked from warm programs) join within
/// milliseconds of each other, and every look's pause is paid once per case on the way to its first tick; a peer
/// started by hand, or an interpreter importing its modules, is waited for at the slower pace.
pub fn join_look_pause(waited_ns: u64, later: std::time::Duration) -> std::time::Duration {
    const QUICK_FOR_NS: u64 = 100_000_000;
    if waited_ns < QUICK_FOR_NS { std::time::Duration::from_micros(500) } else { later }
}

/// `CLOCK_MONOTONIC` now, ns.
#[inline]
pub fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // Safety: `ts` is a valid out-pointer. CLOCK_MONOTONIC cannot fail on Linux, so the return value is not checked
    // (keeps this callable on the hot path without a Result).
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * NS_PER_S + ts.tv_nsec as u64
}

/// A `timespec` for an absolute `CLOCK_MONOTONIC` time in ns.
pub fn timespec_from_ns(t_ns: u64) -> libc::timespec {
    libc::timespec { tv_sec: (t_ns / NS_PER_S) as libc::time_t, tv_nsec: (t_ns % NS_PER_S) as libc::c_long }
}

/// Sleep until `CLOCK_MONOTONIC` reaches `deadline_ns` (absolute, so no drift accumulates). Signals (EINTR, e.g.
/// SIGSTOP/SIGCONT from fault injection) resume the sleep toward the same deadline. Returns at once if the deadline
/// has passed.
pub fn sleep_until_ns(deadline_ns: u64) {
    let ts = timespec_from_ns(deadline_ns);
    loop {
        // Safety: `ts` is valid; the remaining-time pointer may be null with TIMER_ABSTIME.
        let rc =
            unsafe { libc::clock_nanosleep(libc::CLOCK_MONOTONIC, libc::TIMER_ABSTIME, &ts, std::ptr::null_mut()) };
        // clock_nanosleep returns the error number instead of setting errno. EINVAL is impossible with a normalised
        // timespec, so anything but EINTR ends the wait.
        if rc != libc::EINTR {
            return;
        }
    }
}

/// Scheduling policy of the calling thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SchedPolicy {
    /// `SCHED_OTHER` (the default time-sharing policy).
    Other,
    /// `SCHED_FIFO` with this priority (1..=99).
    Fifo(i32),
    /// `SCHED_RR` with this priority.
    RoundRobin(i32),
    /// Anything else (batch, idle, deadline), as the raw policy number.
    Unknown(i32),
}

impl std::fmt::Display for SchedPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SchedPolicy::Other => write!(f, "SCHED_OTHER"),
            SchedPolicy::Fifo(p) => write!(f, "SCHED_FIFO {p}"),
            SchedPolicy::RoundRobin(p) => write!(f, "SCHED_RR {p}"),
            SchedPolicy::Unknown(p) => write!(f, "policy {p}"),
        }
    }
}

/// The scheduling policy of the calling process (its main thread's policy, as `sched_getscheduler(0)` reports).
pub fn current_policy() -> SchedPolicy {
    // Safety: plain syscalls on the calling process with a valid out-pointer.
    let policy = unsafe { libc::sched_getscheduler(0) };
    let mut param = libc::sched_param { sched_priority: 0 };
    unsafe { libc::sched_getparam(0, &mut param) };
    match policy {
        libc::SCHED_OTHER => SchedPolicy::Other,
        libc::SCHED_FIFO => SchedPolicy::Fifo(param.sched_priority),
        libc::SCHED_RR => SchedPolicy::RoundRobin(param.sched_priority),
        other => SchedPolicy::Unknown(other),
    }
}

/// What [`try_realtime`] obtained.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RealtimeStatus {
    /// The policy in force afterwards.
    pub policy: SchedPolicy,
    /// `mlockall(MCL_CURRENT | MCL_FUTURE)` succeeded: every page, now and later, stays in RAM.
    pub memory_locked: bool,
    /// What was locked, for the report: "memory locked", "memory locked at start only (limit 8192 KiB)" (the
    /// locked-memory limit: what was mapped when it fitted), "memory not locked (...)".
    pub memory: String,
    /// One line for stderr when something was refused; `None` when everything asked for was obtained.
    pub warning: Option<String>,
}

impl RealtimeStatus {
    /// SCHED_FIFO is in force.
    pub fn is_fifo(&self) -> bool {
        matches!(self.policy, SchedPolicy::Fifo(_))
    }
}

/// Put the calling thread back on the normal scheduler: a helper thread of a real-time process (it inherited
/// SCHED_FIFO) must not compete with the loop.
pub fn leave_realtime_scheduling() {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: sched_setscheduler on the calling thread (0) with a valid parameter struct.
    unsafe { libc::sched_setscheduler(0, libc::SCHED_OTHER, &param) };
}

/// CAP_IPC_LOCK's bit in the capability sets of `/proc/self/status`.
const CAP_IPC_LOCK_BIT: u32 = 14;

/// The locked-memory limit in bytes, `None` when nothing limits it (unlimited, or CAP_IPC_LOCK, which the kernel
/// lets lock past the limit).
fn memlock_limit_bytes() -> Option<u64> {
    let has_cap_ipc_lock = std::fs::read_to_string("/proc/self/status").ok().is_some_and(|status| {
        status
            .lines()
            .find_map(|l| l.strip_prefix("CapEff:"))
            .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())
            .is_some_and(|caps| caps & (1 << CAP_IPC_LOCK_BIT) != 0)
    });
    let mut limit = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
    // SAFETY: getrlimit fills the struct it is given.
    let read = unsafe { libc::getrlimit(libc::RLIMIT_MEMLOCK, &mut limit) } == 0;
    match has_cap_ipc_lock || (read && limit.rlim_cur == libc::RLIM_INFINITY) {
        true => None,
        false => Some(if read { limit.rlim_cur } else { 0 }),
    }
}

/// How to get what was refused, once for both privileges (the book: docs/src/guides/without-root.md).
const PRIVILEGE_HINT: &str = "for both: `sudo setcap cap_sys_nice,cap_ipc_lock+ep` on the silrig binaries, or \
     rtprio and memlock lines for your group in /etc/security/limits.d/ (docs/src/guides/without-root.md)";

/// Ask for `SCHED_FIFO` at `priority` (1..=99) for the calling process and lock its memory. Never fails: a refusal
/// (non-root without `ulimit -r`/`-l`, a container without CAP_SYS_NICE) leaves the process as it was and says so in
/// `warning`, so the caller can print it and carry on (as dora's `--rt` and copper do). Pages the process maps later
/// are locked only when nothing limits locked memory: under the usual 8 MiB limit `MCL_FUTURE` would make every
/// allocation past it fail (the process aborts), so only what is mapped now is locked, if it fits.
pub fn try_realtime(priority: i32) -> RealtimeStatus {
    let mut refused = Vec::new();
    let param = libc::sched_param { sched_priority: priority };
    // Safety: plain syscalls on the calling process with valid arguments.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        let why = std::io::Error::last_os_error();
        refused.push(format!("SCHED_FIFO {priority} refused ({why}): expect ms-scale wake-up outliers"));
    }
    let (memory_locked, memory) = match memlock_limit_bytes() {
        // SAFETY: mlockall with valid flags on the calling process.
        None => match unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0 {
            true => (true, "memory locked".to_string()),
            false => (false, format!("memory not locked ({})", std::io::Error::last_os_error())),
        },
        Some(limit) => {
            let kib = limit / 1024;
            // SAFETY: as above.
            match unsafe { libc::mlockall(libc::MCL_CURRENT) } == 0 {
                true => (false, format!("memory locked at start only (limit {kib} KiB)")),
                false => (false, format!("memory not locked (limit {kib} KiB)")),
            }
        }
    };
    if !memory_locked {
        refused.push(format!("{memory}: pages the loop touches later may fault (`ulimit -l`)"));
    }
    let policy = current_policy();
    let warning =
        (!refused.is_empty()).then(|| format!("running with {policy}; {}; {PRIVILEGE_HINT}", refused.join("; ")));
    RealtimeStatus { policy, memory_locked, memory, warning }
}

/// A fixed-period tick grid: tick `k` is due at `t0_ns + k * period_ns`. Pure: it never reads a clock, so every
/// decision is unit-testable with made-up wake times.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct TickSchedule {
    /// Due time of tick 0, CLOCK_MONOTONIC ns.
    pub t0_ns: u64,
    /// Period, ns (> 0).
    pub period_ns: u64,
}

/// What a wake-up turned out to be.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct TickOutcome {
    /// The tick to run now.
    pub tick: u64,
    /// Due time of that tick, ns.
    pub ideal_ns: u64,
    /// Wake time minus due time of the tick being run, ns (negative only for an early wake-up).
    pub lateness_ns: i64,
    /// Lateness against the tick that was expected (before skipping), ns: the figure a cyclictest-style histogram
    /// records.
    pub wake_lateness_ns: i64,
    /// Ticks skipped because the wake-up came a whole period or more late (an overrun when > 0).
    pub skipped: u64,
    /// The tick to wait for next.
    pub next_tick: u64,
    /// Due time of `next_tick`, ns.
    pub next_deadline_ns: u64,
}

impl TickOutcome {
    /// The wake-up came a whole period or more late and ticks were skipped.
    pub fn is_overrun(&self) -> bool {
        self.skipped > 0
    }
}

impl TickSchedule {
    /// A grid with tick 0 due at `t0_ns`.
    pub fn new(t0_ns: u64, period_ns: u64) -> Self {
        assert!(period_ns > 0, "tick period must be positive");
        Self { t0_ns, period_ns }
    }

    /// Due time of `tick`, ns.
    #[inline]
    pub fn deadline_ns(&self, tick: u64) -> u64 {
        self.t0_ns + tick * self.period_ns
    }

    /// Decide what to run after waking at `now_ns` while waiting for `expected_tick`.
    ///
    /// A wake-up one whole period or more late means tick `expected_tick + 1` is already due: rather than run the
    /// missed ticks back to back (a burst that hands the peers stale, bunched samples), the schedule jumps to the
    /// newest due tick `floor((now - t0) / T)`, runs it now, and reports the ticks in between as skipped. Exactly
    /// one period late therefore counts as an overrun (the next tick's due time has come).
    pub fn on_wake(&self, expected_tick: u64, now_ns: u64) -> TickOutcome {
        let expected_ideal = self.deadline_ns(expected_tick);
        let wake_lateness_ns = now_ns as i64 - expected_ideal as i64;
        let newest_due = if now_ns >= self.t0_ns { (now_ns - self.t0_ns) / self.period_ns } else { 0 };
        let tick = newest_due.max(expected_tick);
        let ideal_ns = self.deadline_ns(tick);
        TickOutcome {
            tick,
            ideal_ns,
            lateness_ns: now_ns as i64 - ideal_ns as i64,
            wake_lateness_ns,
            skipped: tick - expected_tick,
            next_tick: tick + 1,
            next_deadline_ns: self.deadline_ns(tick + 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: u64 = 10_000_000;

    #[test]
    fn on_time_tick_runs_as_expected() {
        let s = TickSchedule::new(1_000, T);
        let o = s.on_wake(5, s.deadline_ns(5));
        assert_eq!((o.tick, o.lateness_ns, o.skipped, o.next_tick), (5, 0, 0, 6));
        assert_eq!(o.next_deadline_ns, 1_000 + 6 * T);
        assert!(!o.is_overrun());
    }

    #[test]
    fn late_within_a_period_is_late_not_skipped() {
        let s = TickSchedule::new(0, T);
        let o = s.on_wake(7, s.deadline_ns(7) + T - 1);
        assert_eq!((o.tick, o.lateness_ns, o.skipped, o.next_tick), (7, T as i64 - 1, 0, 8));
    }

    #[test]
    fn three_and_a_half_periods_late_skips_three_without_a_burst() {
        let s = TickSchedule::new(123, T);
        let now = s.deadline_ns(10) + 3 * T + T / 2;
        let o = s.on_wake(10, now);
        assert_eq!(o.tick, 13);
        assert_eq!(o.skipped, 3);
        assert!(o.is_overrun());
        assert_eq!(o.lateness_ns, (T / 2) as i64);
        assert_eq!(o.wake_lateness_ns, (3 * T + T / 2) as i64);
        // No burst: the next tick is due in the future, half a period from now.
        assert_eq!(o.next_tick, 14);
        assert!(o.next_deadline_ns > now);
        assert_eq!(o.next_deadline_ns - now, T / 2);
    }

    #[test]
    fn exactly_one_period_late_is_an_overrun_and_early_wake_is_negative() {
        let s = TickSchedule::new(0, T);
        let o = s.on_wake(2, s.deadline_ns(3));
        assert_eq!((o.tick, o.skipped, o.lateness_ns), (3, 1, 0));
        let o = s.on_wake(4, s.deadline_ns(4) - 5);
        assert_eq!((o.tick, o.skipped, o.lateness_ns), (4, 0, -5));
    }

    #[test]
    fn schedule_is_pure() {
        let s = TickSchedule::new(42, T);
        let now = s.deadline_ns(3) + 17;
        assert_eq!(s.on_wake(3, now), s.on_wake(3, now));
    }

    #[test]
    fn monotonic_clock_does_not_go_back_and_sleep_until_a_past_deadline_returns() {
        let a = monotonic_ns();
        sleep_until_ns(a.saturating_sub(1_000_000));
        sleep_until_ns(monotonic_ns() + 100_000);
        let b = monotonic_ns();
        assert!(b >= a + 100_000);
    }
}
