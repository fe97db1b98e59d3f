//! The soak's fault schedule: a pure function of the seed, the run's length and whether the controller flies
//! behind the bridge. Every kind of fault the rig knows for its processes (a target and an action) comes up once in
//! each round, in an order shuffled per round, a few seconds apart, with its parameters drawn from ranges the rig
//! must survive. The faults are plain `--fault` flags of `silrig run`, so the soak injects them through the rig's
//! own fault plan.

use silrig_flight::fault::{Fault, FaultAction, FaultTarget, SURFACES, parse_fault_flag};
use silrig_model::rng::SplitMix64;

/// Every (target, action) the soak injects: each process fault on every process, each loop fault on every process
/// it applies to, each plant-model fault.
pub const KINDS: [(FaultTarget, FaultAction); 22] = [
    (FaultTarget::Plant, FaultAction::Kill),
    (FaultTarget::Plant, FaultAction::Term),
    (FaultTarget::Plant, FaultAction::Stop),
    (FaultTarget::Plant, FaultAction::Delay),
    (FaultTarget::Plant, FaultAction::Jitter),
    (FaultTarget::Plant, FaultAction::Drop),
    (FaultTarget::Controller, FaultAction::Kill),
    (FaultTarget::Controller, FaultAction::Term),
    (FaultTarget::Controller, FaultAction::Stop),
    (FaultTarget::Controller, FaultAction::Delay),
    (FaultTarget::Controller, FaultAction::Jitter),
    (FaultTarget::Controller, FaultAction::Drop),
    (FaultTarget::Logger, FaultAction::Kill),
    (FaultTarget::Logger, FaultAction::Term),
    (FaultTarget::Logger, FaultAction::Stop),
    (FaultTarget::Logger, FaultAction::Delay),
    (FaultTarget::Logger, FaultAction::Jitter),
    (FaultTarget::Plant, FaultAction::SensorNoise),
    (FaultTarget::Plant, FaultAction::SensorBias),
    (FaultTarget::Plant, FaultAction::ActuatorStuck),
    (FaultTarget::Plant, FaultAction::ActuatorHardOver),
    (FaultTarget::Plant, FaultAction::ActuatorRateFrozen),
];

/// The kinds of a soak: [`KINDS`], or with the controller behind the bridge ([`super::SoakArgs::bridge`]) the
/// plant-side bridge killed, terminated and stopped in place of the controller's faults. The launcher cannot
/// signal a controller on the other host, and the controller's own loop faults would be said in that host's
/// events, which the run's fault table does not read.
pub fn kinds(bridge: bool) -> Vec<(FaultTarget, FaultAction)> {
    if !bridge {
        return KINDS.to_vec();
    }
    let mut kinds: Vec<_> = KINDS.iter().copied().filter(|(t, _)| *t != FaultTarget::Controller).collect();
    kinds.extend([FaultAction::Kill, FaultAction::Term, FaultAction::Stop].map(|a| (FaultTarget::Bridge, a)));
    kinds
}

/// Wall seconds from tick 0 before the first fault (the processes' start is measured first).
pub const FIRST_FAULT_S: f64 = 5.0;
/// No fault in the last seconds of the run, so the last one's recovery is seen and the end is measured quietly.
pub const QUIET_END_S: f64 = 6.0;
/// Seconds between two faults (uniform): each fault's detection and recovery are over before the next.
pub const GAP_S: (f64, f64) = (4.0, 7.0);
/// The measured channels sensor faults hit: attitude and rates, where the controller feels them.
const SENSOR_CHANNELS: [&str; 6] = ["phi_rad", "theta_rad", "psi_rad", "p_radps", "q_radps", "r_radps"];

/// Whether the rig has a detector that must fire for this kind of fault. Nobody watches the logger (nothing waits
/// for it: its 128-sample queues absorb a stop, delay or jitter), and the rig has no detection of sensor or
/// actuator faults; those are injected and their windows checked for losses, but their detection is not required.
pub fn watched(target: FaultTarget, action: FaultAction) -> bool {
    let logger_stalled =
        target == FaultTarget::Logger && matches!(action, FaultAction::Stop | FaultAction::Delay | FaultAction::Jitter);
    !(logger_stalled || action.is_plant_model_fault())
}

/// `target:action` of a fault, the name of its kind in the soak's figures.
pub fn kind_label(target: FaultTarget, action: FaultAction) -> String {
    format!("{}:{}", target.label(), action.label())
}

/// The `--fault` flags of a soak of `duration_s` from `seed`, in time order.
pub fn flags(seed: u64, duration_s: f64, bridge: bool) -> Vec<String> {
    let kinds = kinds(bridge);
    let mut rng = SplitMix64::new(seed);
    let mut out = Vec::new();
    let mut round: Vec<usize> = Vec::new();
    let mut at_s = FIRST_FAULT_S;
    while at_s <= duration_s - QUIET_END_S {
        if round.is_empty() {
            round = (0..kinds.len()).collect();
            // Fisher-Yates; popped from the back.
            for i in (1..round.len()).rev() {
                round.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
            }
        }
        let (target, action) = kinds[round.pop().unwrap_or(0)];
        out.push(flag(&mut rng, target, action, at_s));
        at_s = ms(at_s + rng.range(GAP_S.0, GAP_S.1));
    }
    out
}

/// The schedule as faults (the flags parsed as `silrig run` parses them, so their descriptions are the ones the
/// run's fault table and events carry).
pub fn schedule(seed: u64, duration_s: f64, bridge: bool) -> Vec<Fault> {
    flags(seed, duration_s, bridge)
        .iter()
        .map(|f| parse_fault_flag(f).unwrap_or_else(|e| unreachable!("the soak wrote a bad flag: {e}")))
        .collect()
}

/// Rounded to the millisecond, so the flag's text is short and exact.
fn ms(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

fn flag(rng: &mut SplitMix64, target: FaultTarget, action: FaultAction, at_s: f64) -> String {
    let mut r = |lo: f64, hi: f64| ms(rng.range(lo, hi));
    let keys = match action {
        FaultAction::Kill | FaultAction::Term => format!("restart_after={}s", r(0.1, 1.0)),
        // A logger stopped past its 1.28 s queues would lose rows by design: 1 s at most.
        FaultAction::Stop => format!("for={}s", r(0.2, 1.0)),
        // The plant: past its 10 ms period (an overrun); the controller: past the plant's 50 ms watchdog (a
        // shorter one only costs held commands, which no event reports).
        FaultAction::Delay if target == FaultTarget::Controller => format!("delay={}ms", r(60.0, 200.0).round()),
        FaultAction::Delay => format!("delay={}ms", r(15.0, 60.0).round()),
        FaultAction::Jitter if target == FaultTarget::Controller => {
            format!("max={}ms,for={}s", r(40.0, 80.0).round(), r(0.5, 1.5))
        }
        FaultAction::Jitter => format!("max={}ms,for={}s", r(15.0, 30.0).round(), r(0.5, 1.5)),
        // Past the watchdogs' 5 periods.
        FaultAction::Drop => format!("ticks={}", r(10.0, 40.0).round()),
        FaultAction::SensorNoise => {
            let c = SENSOR_CHANNELS[(r(0.0, 6.0) as usize).min(5)];
            format!("channel={c},std={},for={}s", r(0.001, 0.005), r(0.3, 1.0))
        }
        FaultAction::SensorBias => {
            let c = SENSOR_CHANNELS[(r(0.0, 6.0) as usize).min(5)];
            let sign = if r(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
            format!("channel={c},bias={},for={}s", sign * r(0.002, 0.01), r(0.3, 1.0))
        }
        // Short: a surface held at its limit for long can take the aircraft out of the model's envelope.
        FaultAction::ActuatorStuck | FaultAction::ActuatorRateFrozen | FaultAction::ActuatorHardOver => {
            let s = SURFACES[(r(0.0, 3.0) as usize).min(2)];
            let limit = if action == FaultAction::ActuatorHardOver {
                if r(0.0, 1.0) < 0.5 { ",limit=min" } else { ",limit=max" }
            } else {
                ""
            };
            format!("surface={s}{limit},for={}s", r(0.2, 0.4))
        }
        FaultAction::Cut => unreachable!("the soak flies the F-16 without a device: KINDS has no cut"),
    };
    format!("{}:{}@{}s,{keys}", target.label(), action.label(), at_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schedule_is_a_pure_function_of_the_seed() {
        assert_eq!(flags(1, 600.0, false), flags(1, 600.0, false));
        assert_ne!(flags(1, 600.0, false), flags(2, 600.0, false));
        // A shorter soak is the longer one's beginning.
        let long = flags(7, 600.0, true);
        let short = flags(7, 60.0, true);
        assert_eq!(short[..], long[..short.len()]);
    }

    #[test]
    fn every_kind_comes_up_in_each_round_and_every_fault_is_valid() {
        let duration_s = 600.0;
        for bridge in [false, true] {
            let kinds = kinds(bridge);
            let plan = schedule(3, duration_s, bridge);
            assert!(plan.len() >= 2 * kinds.len(), "{} faults", plan.len());
            for round in plan.chunks(kinds.len()).filter(|c| c.len() == kinds.len()) {
                for &(target, action) in &kinds {
                    assert!(round.iter().any(|f| f.target() == target && f.action() == action), "{target}:{action:?}");
                }
            }
            for w in plan.windows(2) {
                assert!(w[1].at_s - w[0].at_s >= GAP_S.0 - 1e-9, "{} then {}", w[0].at_s, w[1].at_s);
            }
            for f in &plan {
                f.validate(duration_s).unwrap_or_else(|e| panic!("{}: {e:?}", f.describe()));
                assert!(f.at_s >= FIRST_FAULT_S && f.at_s <= duration_s - QUIET_END_S);
                // Behind the bridge the launcher has no controller to signal.
                let process_fault_of_controller = f.target() == FaultTarget::Controller;
                assert!(!(bridge && process_fault_of_controller), "{}", f.describe());
                assert_eq!(bridge, plan.iter().any(|f| f.target() == FaultTarget::Bridge));
            }
        }
    }
}
