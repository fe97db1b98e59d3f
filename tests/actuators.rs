//! Actuators: limits hold under arbitrary commands, and the lag matches its analytic step response.

use silrig::actuator::{Actuator, ActuatorLimits, ActuatorSetLimits, BOOK_LAG_TIME_CONSTANT_S};
use silrig::rng::SplitMix64;

#[test]
fn random_commands_never_break_the_rate_or_position_limit() {
    let book = ActuatorSetLimits::default();
    let mut rng = SplitMix64::new(7);
    for limits in [book.elevator_deg, book.aileron_deg, book.rudder_deg] {
        for lag in [limits.lag_time_constant_s, None] {
            let limits = ActuatorLimits { lag_time_constant_s: lag, ..limits };
            let mut a = Actuator::new(limits, 0.0);
            let rate = limits.rate_limit_per_s.unwrap();
            let (mut rate_hits, mut position_hits) = (0, 0);
            for _ in 0..200_000 {
                let dt = rng.range(0.001, 0.05);
                let command = rng.range(-3.0 * limits.max, 3.0 * limits.max);
                let before = a.position;
                let hits = a.update(command, dt);
                assert!(a.position >= limits.min && a.position <= limits.max, "{}", a.position);
                assert!((a.position - before).abs() <= rate * dt * (1.0 + 1e-12), "rate broken");
                rate_hits += hits.rate as u32;
                position_hits += hits.position as u32;
            }
            // The commands span three times the travel, so both limits must have acted (the lag rarely lets the
            // surface reach its stop under a random command, hence the lower count).
            assert!(rate_hits > 1000 && position_hits > 100, "{rate_hits} {position_hits}");
        }
    }
}

#[test]
fn small_step_follows_the_lag_analytic_solution() {
    // A 1 deg step moves at most 1 / 0.0495 = 20 deg/s, below the 60 deg/s rate limit: pure lag.
    let limits = ActuatorSetLimits::default().elevator_deg;
    let mut a = Actuator::new(limits, 0.0);
    let dt = 0.01;
    for k in 1..=100 {
        let hits = a.update(1.0, dt);
        let t = k as f64 * dt;
        let exact = 1.0 - (-t / BOOK_LAG_TIME_CONSTANT_S).exp();
        assert!((a.position - exact).abs() < 1e-12, "t={t}: {} vs {exact}", a.position);
        assert!(!hits.rate && !hits.position);
    }
}

#[test]
fn large_step_is_rate_limited_then_position_limited() {
    let limits = ActuatorLimits { lag_time_constant_s: None, ..ActuatorSetLimits::default().elevator_deg };
    let mut a = Actuator::new(limits, 0.0);
    for k in 1..=45 {
        let hits = a.update(40.0, 0.01);
        let expected = (60.0 * 0.01 * k as f64).min(25.0);
        assert!((a.position - expected).abs() < 1e-9, "tick {k}: {}", a.position);
        assert!(hits.rate || hits.position);
    }
    assert_eq!(a.position, 25.0);
    // Reversal starts at once: the state is the position, so nothing wound up beyond the limit.
    a.update(-40.0, 0.01);
    assert!((a.position - 24.4).abs() < 1e-9, "{}", a.position);
}

#[test]
fn limits_are_validated() {
    let surface = (-90.0, 90.0);
    assert!(ActuatorLimits::position_only(1.0, -1.0).validate(surface).is_err());
    let bad_rate = ActuatorLimits { rate_limit_per_s: Some(-5.0), ..ActuatorLimits::position_only(-1.0, 1.0) };
    assert!(bad_rate.validate(surface).unwrap_err().contains("rate limit"));
    let huge_rate = ActuatorLimits { rate_limit_per_s: Some(1e9), ..ActuatorLimits::position_only(-1.0, 1.0) };
    assert!(huge_rate.validate(surface).unwrap_err().contains("within (0, 10000]"));
    let bad_lag = ActuatorLimits { lag_time_constant_s: Some(0.0), ..ActuatorLimits::position_only(-1.0, 1.0) };
    assert!(bad_lag.validate(surface).unwrap_err().contains("lag"));
    // An elevator that travels a million degrees, a throttle that goes to 2: beyond the physical range.
    assert!(ActuatorLimits::position_only(-25.0, 1e6).validate(surface).unwrap_err().contains("within -90..90"));
    assert!(ActuatorLimits::position_only(0.0, 2.0).validate((0.0, 1.0)).unwrap_err().contains("within 0..1"));
    assert!(ActuatorSetLimits::default().elevator_deg.validate(surface).is_ok());
}
