//! The F-16 engine: throttle gearing to commanded power, the power-lag dynamics, and thrust from the idle,
//! military and maximum tables (Stevens & Lewis `TGEAR`, `PDOT`, `RTAU`, `THRUST`).

use super::tables::F16Tables;

/// Commanded power level, percent, for a throttle position in 0..1 (throttle gearing).
#[inline]
pub fn commanded_power_pct(throttle: f64) -> f64 {
    if throttle <= 0.77 { 64.94 * throttle } else { 217.38 * throttle - 117.38 }
}

/// Reciprocal time constant of the power lag, 1/s, for a power difference in percent.
#[inline]
fn reciprocal_time_constant(dp_pct: f64) -> f64 {
    if dp_pct <= 25.0 {
        1.0
    } else if dp_pct >= 50.0 {
        0.1
    } else {
        1.9 - 0.036 * dp_pct
    }
}

/// Rate of change of the engine power state, percent/s. Crossing into or out of the afterburner range aims the
/// power at 60 or 40 percent until it crosses 50.
#[inline]
pub fn power_rate_pctps(power_pct: f64, commanded_pct: f64) -> f64 {
    let (target, rate) = match (commanded_pct >= 50.0, power_pct >= 50.0) {
        (true, true) => (commanded_pct, 5.0),
        (true, false) => (60.0, reciprocal_time_constant(60.0 - power_pct)),
        (false, true) => (40.0, 5.0),
        (false, false) => (commanded_pct, reciprocal_time_constant(commanded_pct - power_pct)),
    };
    rate * (target - power_pct)
}

/// Thrust along body x, lbf, at a power level (percent), altitude (ft) and Mach number.
#[inline]
pub fn thrust_lbf(tables: &F16Tables, power_pct: f64, alt_ft: f64, mach: f64) -> f64 {
    let alt_ft = if alt_ft < 0.0 { 0.01 } else { alt_ft };
    let mil = tables.thrust_mil.lookup(alt_ft, mach);
    if power_pct < 50.0 {
        let idle = tables.thrust_idle.lookup(alt_ft, mach);
        idle + (mil - idle) * power_pct * 0.02
    } else {
        let max = tables.thrust_max.lookup(alt_ft, mach);
        mil + (max - mil) * (power_pct - 50.0) * 0.02
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::tables::F16_TABLES;

    #[test]
    fn gearing_reaches_military_and_full_afterburner() {
        assert!((commanded_power_pct(0.77) - 50.0038).abs() < 1e-4);
        assert!((commanded_power_pct(1.0) - 100.0).abs() < 1e-12);
        assert_eq!(commanded_power_pct(0.0), 0.0);
    }

    #[test]
    fn power_lag_follows_the_four_cases() {
        assert_eq!(power_rate_pctps(30.0, 30.0), 0.0);
        assert_eq!(power_rate_pctps(20.0, 30.0), 10.0); // R(10) = 1
        assert_eq!(power_rate_pctps(60.0, 80.0), 100.0); // 5 * 20
        assert_eq!(power_rate_pctps(70.0, 20.0), -150.0); // aims at 40 with rate 5
        assert!((power_rate_pctps(10.0, 80.0) - 0.1 * 50.0).abs() < 1e-12); // aims at 60, R(50) = 0.1
        assert!((power_rate_pctps(0.0, 30.0) - (1.9 - 0.036 * 30.0) * 30.0).abs() < 1e-12);
    }

    #[test]
    fn thrust_blends_the_tables_at_breakpoints() {
        let t = &*F16_TABLES;
        assert_eq!(thrust_lbf(t, 0.0, 0.0, 0.0), 1060.0);
        assert_eq!(thrust_lbf(t, 50.0, 10_000.0, 0.2), 9150.0);
        assert_eq!(thrust_lbf(t, 100.0, 20_000.0, 0.4), 12250.0);
        // halfway between idle and military at sea level, Mach 0
        assert!((thrust_lbf(t, 25.0, 0.0, 0.0) - (1060.0 + 12680.0) / 2.0).abs() < 1e-9);
        // negative altitude is read as sea level
        assert_eq!(thrust_lbf(t, 50.0, -100.0, 0.0), thrust_lbf(t, 50.0, 0.01, 0.0));
    }
}
