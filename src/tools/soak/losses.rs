//! The soak's lost rows: ticks missing from the log, counted into the fault whose window holds them, and those
//! outside every window set beside the OS floor's stalls. A row lost while the OS floor's own loop (SCHED_FIFO,
//! beside the run) woke late was lost to the machine, as `silrig check` judges an unanswered tick
//! ([`crate::check::timing::held_in_stalls`], the one judgement of the two); one lost with no stall seen is the rig's.

use crate::check::timing::held_in_stalls;
use silrig_launch::floor::timer_baseline::Stall;
use std::collections::BTreeMap;

/// Ticks missing from the log between tick 0 and the last tick flown (`flown_to`, when known: a logger silent
/// before the end left the flight's last stretch unlogged; else the last logged tick), counted into the first of
/// the faults' windows (simulated s; None: a fault not injected) that holds them; (the rows lost in each window,
/// the ticks lost outside every window).
pub fn losses(
    logged: &[(u64, bool)],
    windows_s: &[Option<(f64, f64)>],
    dt_s: f64,
    flown_to: Option<u64>,
) -> (Vec<u64>, Vec<u64>) {
    let mut ticks: Vec<u64> = logged.iter().map(|r| r.0).collect();
    ticks.sort_unstable();
    ticks.dedup();
    let mut inside = vec![0; windows_s.len()];
    let mut outside = Vec::new();
    let mut lost = |missing: u64| {
        let t = missing as f64 * dt_s;
        match windows_s.iter().position(|w| w.is_some_and(|(a, b)| t >= a && t <= b)) {
            Some(i) => inside[i] += 1,
            None => outside.push(missing),
        }
    };
    let mut expected = 0u64;
    for &k in &ticks {
        (expected..k).for_each(&mut lost);
        expected = k + 1;
    }
    if let Some(last) = flown_to {
        (expected..=last).for_each(&mut lost);
    }
    (inside, outside)
}

/// The OS floor's stalls of a run, as its report gives them.
pub struct FloorStalls<'a> {
    /// The stalls (the first [`silrig_launch::floor::timer_baseline::MAX_STALLS`] of the run).
    pub stalls: &'a [Stall],
    /// The floor loop's period, ns.
    pub period_ns: u64,
}

/// The lost ticks outside the faults' windows split by the floor's stalls: (those in a stall, the floor's worst
/// lateness among them in µs, those in none). A lost tick was never logged, so its publish time is estimated
/// from the logged ticks on either side of it (`sends`: tick to the plant's send time, ns), between them in
/// proportion, or one loop period `dt_ns` a tick from the one side there is.
pub fn split_by_stalls(
    lost: &[u64],
    sends: &BTreeMap<u64, u64>,
    dt_ns: u64,
    floor: Option<&FloorStalls<'_>>,
) -> (Vec<u64>, f64, Vec<u64>) {
    let Some(floor) = floor else { return (Vec::new(), 0.0, lost.to_vec()) };
    let (mut machine, mut rig, mut worst_us) = (Vec::new(), Vec::new(), 0.0f64);
    for &k in lost {
        let at_ns = estimated_send_ns(k, sends, dt_ns);
        match at_ns.map(|t| held_in_stalls(&[t], floor.stalls, floor.period_ns)) {
            Some((1, stall_us)) => {
                machine.push(k);
                worst_us = worst_us.max(stall_us);
            }
            _ => rig.push(k),
        }
    }
    (machine, worst_us, rig)
}

/// When the plant sent tick `k`, which the log lacks, estimated from the logged ticks around it.
fn estimated_send_ns(k: u64, sends: &BTreeMap<u64, u64>, dt_ns: u64) -> Option<u64> {
    let before = sends.range(..k).next_back();
    let after = sends.range(k + 1..).next();
    match (before, after) {
        (Some((&a, &ta)), Some((&b, &tb))) => {
            let share = (k - a) as f64 / (b - a) as f64;
            Some(ta + (tb.saturating_sub(ta) as f64 * share) as u64)
        }
        (Some((&a, &ta)), None) => Some(ta + (k - a) * dt_ns),
        (None, Some((&b, &tb))) => tb.checked_sub((b - k) * dt_ns),
        (None, None) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn losses_inside_and_outside_the_windows() {
        // Ticks 0..100 logged except 20..25 (inside a window at 0.2..0.3 s) and 80 (outside).
        let logged: Vec<(u64, bool)> =
            (0..100).filter(|k| !(20..25).contains(k) && *k != 80).map(|k| (k, true)).collect();
        assert_eq!(losses(&logged, &[None, Some((0.2, 0.3))], 0.01, None), (vec![0, 5], vec![80]));
        assert_eq!(losses(&logged, &[None, Some((0.2, 0.3))], 0.01, Some(99)), (vec![0, 5], vec![80]));
    }

    #[test]
    fn a_logger_silent_before_the_end_loses_the_flights_last_stretch() {
        // The plant flew to tick 120; the log stops at 99.
        let logged: Vec<(u64, bool)> = (0..100).map(|k| (k, true)).collect();
        let (inside, outside) = losses(&logged, &[Some((1.095, 1.155))], 0.01, Some(120));
        assert_eq!(inside, vec![6]);
        assert_eq!(outside, (100..=120).filter(|k| !(110..=115).contains(k)).collect::<Vec<u64>>());
    }

    /// A run at 100 Hz from t0, every tick sent on its grid point but the ones in `gap`, which were lost.
    fn sends(t0: u64, gap: std::ops::Range<u64>) -> BTreeMap<u64, u64> {
        (0..1000).filter(|k| !gap.contains(k)).map(|k| (k, t0 + k * P)).collect()
    }
    const P: u64 = 10_000_000;

    #[test]
    fn rows_lost_in_a_stall_the_os_floor_saw_are_the_machines_the_others_the_rigs() {
        let t0: u64 = 5_000_000_000;
        // The machine stalled for 2 s from tick 300's time (the floor woke 2 s late); the logger lost 300..500.
        let stalls = [Stall { at_ns: t0 + 300 * P, lateness_us: 2_000_000.0 }];
        let floor = FloorStalls { stalls: &stalls, period_ns: P };
        let lost: Vec<u64> = (300..500).collect();
        let (machine, worst_us, rig) = split_by_stalls(&lost, &sends(t0, 300..500), P, Some(&floor));
        assert_eq!((machine.len(), worst_us, rig.len()), (200, 2_000_000.0, 0));
        // The same loss with the floor on time throughout: the rig's.
        let quiet = FloorStalls { stalls: &[], period_ns: P };
        let (machine, _, rig) = split_by_stalls(&lost, &sends(t0, 300..500), P, Some(&quiet));
        assert_eq!((machine.len(), rig), (0, lost.clone()));
        // No floor beside the run (--no-baseline, or it died): nothing is put down to the machine.
        assert_eq!(split_by_stalls(&lost, &sends(t0, 300..500), P, None).2, lost);
        // A stall of 50 ms inside a 2 s loss excuses the ticks around it only (two periods before, one after).
        let short = [Stall { at_ns: t0 + 400 * P, lateness_us: 50_000.0 }];
        let floor = FloorStalls { stalls: &short, period_ns: P };
        let (machine, worst_us, rig) = split_by_stalls(&lost, &sends(t0, 300..500), P, Some(&floor));
        assert_eq!(machine, (398..=406).collect::<Vec<_>>());
        assert_eq!((worst_us, rig.len()), (50_000.0, 191));
    }

    #[test]
    fn a_lost_ticks_send_time_comes_from_the_ticks_around_it() {
        let logged: BTreeMap<u64, u64> = [(10, 1_000), (20, 3_000)].into_iter().collect();
        assert_eq!(estimated_send_ns(15, &logged, 100), Some(2_000));
        // Past the last logged tick, or before the first: a loop period a tick.
        assert_eq!(estimated_send_ns(25, &logged, 100), Some(3_500));
        assert_eq!(estimated_send_ns(5, &logged, 100), Some(500));
        assert_eq!(estimated_send_ns(0, &logged, 1_000), None, "before the clock's zero: not a time");
        assert_eq!(estimated_send_ns(3, &BTreeMap::new(), 100), None);
    }
}
