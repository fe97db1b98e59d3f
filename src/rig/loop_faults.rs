//! Loop faults a process injects into itself, from the scenario's fault plan: `delay` (sleep inside the loop,
//! once or every k ticks), `jitter` (a random extra sleep each tick) and `drop` (skip publishing for N ticks, or
//! with a probability). Judged on simulated time `tick * dt`; announced in the event log when they first act.

use crate::events::EventLog;
use silrig_flight::fault::{Fault, FaultAction};
use silrig_flight::role::Role;
use silrig_model::rng::SplitMix64;

/// What the loop must do at one tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoopFaultEffect {
    /// Sleep this long before publishing, ns.
    pub sleep_ns: u64,
    /// Do not publish this tick.
    pub drop: bool,
}

/// The loop faults of one process.
#[derive(Debug)]
pub struct LoopFaults {
    faults: Vec<(Fault, bool)>,
    dt_s: f64,
    rng: SplitMix64,
    events: EventLog,
}

impl LoopFaults {
    /// The delay, jitter and drop faults of `target` from `plan`.
    pub fn new(plan: &[Fault], target: Role, dt_s: f64, seed: u64, events: EventLog) -> Self {
        let faults = plan
            .iter()
            .filter(|f| {
                f.target() == target
                    && matches!(f.action(), FaultAction::Delay | FaultAction::Jitter | FaultAction::Drop)
            })
            .map(|f| (f.clone(), false))
            .collect();
        Self { faults, dt_s, rng: SplitMix64::new(seed ^ (target as u64 + 1).wrapping_mul(0x9E37_79B9)), events }
    }

    /// Whether there is anything to do at all (skips the per-tick work when not).
    pub fn is_empty(&self) -> bool {
        self.faults.is_empty()
    }

    /// The effect at `tick`.
    pub fn at(&mut self, tick: u64) -> LoopFaultEffect {
        let mut effect = LoopFaultEffect::default();
        let t_s = tick as f64 * self.dt_s;
        for (f, announced) in self.faults.iter_mut() {
            if !f.active_at(t_s) {
                continue;
            }
            // The first tick the window covers (`active_at`: t >= at_s): a time between two ticks starts at the
            // later one. Rounding to the nearer one made a once-only delay at such a time never act (its first
            // active tick came one after the rounded one, so `since` was never 0).
            let first_tick = (f.at_s / self.dt_s - 1e-9).ceil().max(0.0) as u64;
            let since = tick.saturating_sub(first_tick);
            let acts = match f.action() {
                FaultAction::Delay => {
                    let hit = match f.every_ticks {
                        None => since == 0,
                        Some(k) => since.is_multiple_of(k),
                    };
                    if hit {
                        effect.sleep_ns += (f.delay_ms.unwrap_or(0.0) * 1e6) as u64;
                    }
                    hit
                }
                FaultAction::Jitter => {
                    effect.sleep_ns += (self.rng.uniform() * f.max_us.unwrap_or(0.0) * 1e3) as u64;
                    true
                }
                FaultAction::Drop => {
                    let hit = match (f.ticks, f.probability) {
                        (Some(n), _) => since < n,
                        (None, Some(p)) => self.rng.uniform() < p,
                        _ => false,
                    };
                    effect.drop |= hit;
                    hit
                }
                _ => false,
            };
            if acts && !*announced {
                *announced = true;
                self.events.emit(Some(tick), "fault-injected", f.describe());
            }
        }
        effect
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_flight::fault::parse_fault_flag;

    #[test]
    fn a_once_only_delay_acts_once_whether_or_not_its_time_is_on_a_tick() {
        let dir = std::env::temp_dir().join(format!("silrig-loop-faults-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (flag, tick) in [("plant:delay@28.483s,delay=42ms", 2849), ("plant:delay@5s,delay=42ms", 500)] {
            let plan = [parse_fault_flag(flag).unwrap()];
            let mut faults = LoopFaults::new(&plan, Role::Plant, 0.01, 1, EventLog::new(&dir, "plant"));
            let acting: Vec<u64> = (0..4000).filter(|k| faults.at(*k).sleep_ns > 0).collect();
            assert_eq!(acting, [tick], "{flag}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
