//! Actuator models for the control surfaces and the throttle. Each actuator applies, in this order (as JSBSim's
//! FGActuator documents): a first-order lag on the command (switchable), then a rate limit, then a position limit.
//! The lag acts on the error between command and position, so the state is the actual position and nothing winds
//! up while a limit is active. Pure math: the caller supplies the step.

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
    pub fn validate(&self) -> Result<(), String> {
        if !(self.min.is_finite() && self.max.is_finite() && self.min < self.max) {
            return Err(format!("position limits must be finite with min < max, got {}..{}", self.min, self.max));
        }
        if let Some(r) = self.rate_limit_per_s
            && !(r > 0.0)
        {
            return Err(format!("rate limit must be positive, got {r}"));
        }
        if let Some(tau) = self.lag_time_constant_s
            && !(tau > 0.0 && tau.is_finite())
        {
            return Err(format!("lag time constant must be positive, got {tau}"));
        }
        Ok(())
    }
}

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

    /// Advance the actuator over `dt_s` seconds with `command` held, and return which limits were active.
    /// The lag is integrated exactly for a held command.
    #[inline]
    pub fn update(&mut self, command: f64, dt_s: f64) -> LimitHits {
        let target = match self.limits.lag_time_constant_s {
            Some(tau) => command + (self.position - command) * (-dt_s / tau).exp(),
            None => command,
        };
        let mut delta = target - self.position;
        let mut hits = LimitHits::default();
        if let Some(rate) = self.limits.rate_limit_per_s {
            let max_step = rate * dt_s;
            if delta.abs() > max_step {
                delta = max_step.copysign(delta);
                hits.rate = true;
            }
        }
        let unclamped = self.position + delta;
        self.position = unclamped.clamp(self.limits.min, self.limits.max);
        let pinned = (self.position == self.limits.max && command > self.limits.max)
            || (self.position == self.limits.min && command < self.limits.min);
        hits.position = unclamped != self.position || pinned;
        hits
    }
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
