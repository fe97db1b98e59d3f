//! Actuator models for the control surfaces and the throttle. Each actuator applies, in this order (as JSBSim's
//! FGActuator documents): a first-order lag on the command (switchable), then a rate limit, then a position limit.
//! The lag acts on the error between command and position, so the state is the actual position and nothing winds
//! up while a limit is active. Pure math: the caller supplies the step.
//!
//! An actuator can also be failed ([`ActuatorFault`]): stuck, hard-over or with its rate frozen. The position limit
//! holds in every mode, and no mode moves the surface faster than its rate limit.

use serde::{Deserialize, Serialize};

/// Stevens & Lewis actuator time constant, s (1/20.2).
pub const BOOK_LAG_TIME_CONSTANT_S: f64 = 1.0 / 20.2;

/// Limits and dynamics of one actuator, in the unit of its position (deg for surfaces, 0..1 for the throttle).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuatorLimits {
    /// Lowest position.
    pub min: f64,
    /// Highest position.
    pub max: f64,
    /// Largest rate, units/s; `None` for no rate limit.
    pub rate_limit_per_s: Option<f64>,
    /// Time constant of the first-order lag, s; `None` to switch the lag off.
    pub lag_time_constant_s: Option<f64>,
}

impl ActuatorLimits {
    /// Position limits only: no rate limit, no lag.
    pub fn position_only(min: f64, max: f64) -> Self {
        Self { min, max, rate_limit_per_s: None, lag_time_constant_s: None }
    }

    /// Check the limits make sense; the error names the problem.
    pub fn validate(&self, travel: (f64, f64)) -> Result<(), String> {
        if !(self.min.is_finite() && self.max.is_finite() && self.min < self.max) {
            return Err(format!("position limits must be finite with min < max, got {}..{}", self.min, self.max));
        }
        if self.min < travel.0 || self.max > travel.1 {
            return Err(format!(
                "position limits must lie within {}..{}, got {}..{}",
                travel.0, travel.1, self.min, self.max
            ));
        }
        if let Some(r) = self.rate_limit_per_s
            && !(r > 0.0 && r <= MAX_RATE_LIMIT_PER_S)
        {
            return Err(format!("rate limit must be within (0, {MAX_RATE_LIMIT_PER_S}] per s, got {r}"));
        }
        if let Some(tau) = self.lag_time_constant_s
            && !(tau > 0.0 && tau <= MAX_LAG_S)
        {
            return Err(format!("lag time constant must be within (0, {MAX_LAG_S}] s, got {tau}"));
        }
        Ok(())
    }
}

/// A surface command beyond this many degrees either way is refused on the wire, and no scenario may set a travel
/// beyond it: no control surface deflects that far, so it is a bug (units, an
/// uninitialised value), not a saturation the actuator model should quietly clip.
pub const SURFACE_CMD_LIMIT_DEG: f64 = 90.0;

/// Largest rate limit, units (deg or throttle fraction) per second.
pub const MAX_RATE_LIMIT_PER_S: f64 = 10_000.0;
/// Largest first-order lag time constant, s.
pub const MAX_LAG_S: f64 = 10.0;

/// Which limits bound one update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LimitHits {
    /// The rate limit cut the motion.
    pub rate: bool,
    /// The position limit cut the motion.
    pub position: bool,
}

/// One actuator: its limits and its current position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuator {
    /// Limits and dynamics.
    pub limits: ActuatorLimits,
    /// Current position.
    pub position: f64,
}

impl Actuator {
    /// An actuator resting at `position` (clamped into its limits).
    pub fn new(limits: ActuatorLimits, position: f64) -> Self {
        Self { limits, position: position.clamp(limits.min, limits.max) }
    }

    /// `delta` cut to what the rate limit allows in `dt_s`, and whether it had to be cut.
    #[inline]
    fn rate_limited(&self, delta: f64, dt_s: f64) -> (f64, bool) {
        match self.limits.rate_limit_per_s {
            Some(rate) if delta.abs() > rate * dt_s => ((rate * dt_s).copysign(delta), true),
            _ => (delta, false),
        }
    }

    /// Advance the actuator over `dt_s` seconds with `command` held, and return which limits were active.
    /// The lag is integrated exactly for a held command.
    #[inline]
    pub fn update(&mut self, command: f64, dt_s: f64) -> LimitHits {
        let target = match self.limits.lag_time_constant_s {
            Some(tau) => command + (self.position - command) * (-dt_s / tau).exp(),
            None => command,
        };
        let (delta, rate_limited) = self.rate_limited(target - self.position, dt_s);
        let mut hits = LimitHits { rate: rate_limited, position: false };
        let unclamped = self.position + delta;
        self.position = unclamped.clamp(self.limits.min, self.limits.max);
        let pinned = (self.position == self.limits.max && command > self.limits.max)
            || (self.position == self.limits.min && command < self.limits.min);
        hits.position = unclamped != self.position || pinned;
        hits
    }

    /// Advance the actuator over `dt_s` seconds in failure mode `fault`, with `command` held, and return which
    /// limits were active. [`ActuatorFault::None`] is exactly [`Actuator::update`]. The lag state is the position
    /// itself, so when the fault clears the actuator resumes from wherever the fault left it, with nothing wound up.
    #[inline]
    pub fn update_with_fault(&mut self, command: f64, dt_s: f64, fault: ActuatorFault) -> LimitHits {
        match fault {
            ActuatorFault::None => self.update(command, dt_s),
            // A jammed surface: nothing limits it, it just does not move.
            ActuatorFault::Stuck => LimitHits::default(),
            // The rate channel is frozen at zero: report the rate limit as active whenever the command asks for
            // motion, so the rig's rate-limited flag shows the cause.
            ActuatorFault::RateFrozen => LimitHits { rate: command != self.position, position: false },
            ActuatorFault::HardOver { to_max } => {
                // A runaway servo drives at full rate, not through the command lag; without a rate limit the fastest
                // motion is instant.
                let stop = if to_max { self.limits.max } else { self.limits.min };
                let (delta, rate_limited) = self.rate_limited(stop - self.position, dt_s);
                let mut hits = LimitHits { rate: rate_limited, position: false };
                self.position = (self.position + delta).clamp(self.limits.min, self.limits.max);
                // Snap onto the stop when the step reaches it, so rounding never leaves it a hair short.
                if !hits.rate {
                    self.position = stop;
                }
                hits.position = self.position == stop;
                hits
            }
        }
    }
}

/// A failure mode of one actuator, as the plant applies it for a fault window (see `silrig_flight::fault`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ActuatorFault {
    /// Healthy: lag, rate limit and position limit as configured.
    #[default]
    None,
    /// Jammed: the surface stays where it is, whatever the command.
    Stuck,
    /// Runaway: the surface drives to its upper (`to_max`) or lower stop at its rate limit (instantly if it has
    /// none), ignoring the command, and stays there.
    HardOver {
        /// Toward `max` (true) or `min` (false).
        to_max: bool,
    },
    /// The rate is forced to zero: the surface cannot move while the command changes. Moves like
    /// [`ActuatorFault::Stuck`] but reports the rate limit as active whenever the command asks for motion.
    RateFrozen,
}

/// The book's limits for the four actuators.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuatorSetLimits {
    /// Elevator, deg.
    pub elevator_deg: ActuatorLimits,
    /// Aileron, deg.
    pub aileron_deg: ActuatorLimits,
    /// Rudder, deg.
    pub rudder_deg: ActuatorLimits,
    /// Throttle, 0..1.
    pub throttle: ActuatorLimits,
}

impl Default for ActuatorSetLimits {
    /// Stevens & Lewis: elevator +-25 deg and 60 deg/s, aileron +-21.5 deg and 80 deg/s, rudder +-30 deg and
    /// 120 deg/s, each behind a 1/20.2 s lag; throttle 0..1 with no rate limit and no lag.
    fn default() -> Self {
        let surface = |limit: f64, rate: f64| ActuatorLimits {
            min: -limit,
            max: limit,
            rate_limit_per_s: Some(rate),
            lag_time_constant_s: Some(BOOK_LAG_TIME_CONSTANT_S),
        };
        Self {
            elevator_deg: surface(25.0, 60.0),
            aileron_deg: surface(21.5, 80.0),
            rudder_deg: surface(30.0, 120.0),
            throttle: ActuatorLimits::position_only(0.0, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Not a whole number of 0.6 deg steps from either stop, so the step count below does not hinge on rounding.
    const START: f64 = 2.1;

    fn elevator() -> Actuator {
        Actuator::new(ActuatorSetLimits::default().elevator_deg, START)
    }

    #[test]
    fn no_fault_is_exactly_the_healthy_update() {
        let (mut a, mut b) = (elevator(), elevator());
        for k in 0..300 {
            let command = 30.0 * (0.05 * k as f64).sin();
            assert_eq!(a.update(command, 0.01), b.update_with_fault(command, 0.01, ActuatorFault::None));
            assert_eq!(a.position.to_bits(), b.position.to_bits());
        }
    }

    #[test]
    fn stuck_and_rate_frozen_surfaces_do_not_move() {
        for fault in [ActuatorFault::Stuck, ActuatorFault::RateFrozen] {
            let mut a = elevator();
            for k in 0..100 {
                let hits = a.update_with_fault(-40.0 + k as f64, 0.01, fault);
                assert_eq!(a.position, START);
                assert!(!hits.position);
                assert_eq!(hits.rate, fault == ActuatorFault::RateFrozen);
            }
            // Commanding where it already is asks for no motion: nothing is reported.
            assert_eq!(a.update_with_fault(START, 0.01, fault), LimitHits::default());
        }
    }

    #[test]
    fn hard_over_moves_at_the_rate_limit_and_stays_at_the_stop() {
        let dt = 0.01;
        for (to_max, stop) in [(true, 25.0), (false, -25.0)] {
            let mut a = elevator();
            let mut steps = 0;
            while a.position != stop {
                let before = a.position;
                // The command pulls the other way: it must not matter.
                let hits = a.update_with_fault(-stop, dt, ActuatorFault::HardOver { to_max });
                let moved = (a.position - before).abs();
                assert!(moved <= 60.0 * dt * (1.0 + 1e-12), "{moved}");
                if a.position != stop {
                    assert!(hits.rate && !hits.position && (moved - 0.6).abs() < 1e-9, "{hits:?} {moved}");
                }
                steps += 1;
                assert!(steps < 1000);
            }
            // 22.9 deg (or 27.1 deg) of travel at 0.6 deg a step.
            assert_eq!(steps, ((stop - START).abs() / 0.6).ceil() as i32);
            for _ in 0..50 {
                let hits = a.update_with_fault(0.0, dt, ActuatorFault::HardOver { to_max });
                assert_eq!(a.position, stop);
                assert!(hits.position && !hits.rate);
            }
        }
    }

    #[test]
    fn hard_over_without_a_rate_limit_is_instant() {
        let mut a = Actuator::new(ActuatorLimits::position_only(-10.0, 10.0), 3.0);
        let hits = a.update_with_fault(0.0, 0.01, ActuatorFault::HardOver { to_max: false });
        assert_eq!(a.position, -10.0);
        assert!(hits.position && !hits.rate);
    }

    #[test]
    fn a_cleared_fault_resumes_from_where_it_left_the_surface() {
        let mut a = elevator();
        for _ in 0..10 {
            a.update_with_fault(20.0, 0.01, ActuatorFault::Stuck);
        }
        let mut healthy = elevator();
        a.update(20.0, 0.01);
        healthy.update(20.0, 0.01);
        assert_eq!(a.position, healthy.position);
    }
}
