//! Dispersions (`[dispersions]` of a scenario): named scenario keys with a distribution each, sampled from a seed.
//! Sample i is a pure function of (seed, i, key), independent of how many samples there are, how they are split
//! over workers or machines, and of which other keys are dispersed. Applying a sample to a scenario is
//! [`crate::scenario::Scenario::with_values`]. Pure: no I/O.

use serde::{Deserialize, Serialize};
use silrig_model::rng::SplitMix64;
use std::collections::BTreeMap;

/// A distribution of one scenario key (`{ dist = "normal", mean = 0.0, std = 1.0 }` and so on).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "dist", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Distribution {
    /// Uniform on [min, max].
    Uniform {
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// Normal, optionally truncated to [min, max] (by rejection: the shape inside the bounds is kept).
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (0: always the mean).
        std: f64,
        /// Lower truncation bound.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        min: Option<f64>,
        /// Upper truncation bound.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max: Option<f64>,
    },
    /// One of `values`, equally likely or with `weights`.
    Choice {
        /// The values.
        values: Vec<f64>,
        /// Relative weights, one per value (default: equal).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        weights: Option<Vec<f64>>,
    },
}

/// Standard normal CDF (Abramowitz & Stegun 7.1.26 for erf, |error| < 1.5e-7): enough to tell a truncation that
/// keeps almost no mass.
fn normal_cdf(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly =
        t * (0.254_829_592 + t * (-0.284_496_736 + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-x * x).exp();
    if z >= 0.0 { 0.5 * (1.0 + erf) } else { 0.5 * (1.0 - erf) }
}

/// Smallest probability mass a truncated normal may keep (rejection sampling needs about 1/mass draws).
const MIN_TRUNCATED_MASS: f64 = 1e-4;

impl Distribution {
    /// Check the parameters; on error, what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let finite =
            |name: &str, v: f64| if v.is_finite() { Ok(()) } else { Err(format!("`{name}` must be finite, got {v}")) };
        match self {
            Distribution::Uniform { min, max } => {
                finite("min", *min)?;
                finite("max", *max)?;
                if min > max {
                    return Err(format!("`min` ({min}) is above `max` ({max})"));
                }
            }
            Distribution::Normal { mean, std, min, max } => {
                finite("mean", *mean)?;
                finite("std", *std)?;
                if *std < 0.0 {
                    return Err(format!("`std` must be >= 0, got {std}"));
                }
                let (lo, hi) = (min.unwrap_or(f64::NEG_INFINITY), max.unwrap_or(f64::INFINITY));
                if lo.is_nan() || hi.is_nan() || lo >= hi {
                    return Err(format!("the truncation [{lo}, {hi}] is empty"));
                }
                let mass = if *std == 0.0 {
                    if (lo..=hi).contains(mean) { 1.0 } else { 0.0 }
                } else {
                    normal_cdf((hi - mean) / std) - normal_cdf((lo - mean) / std)
                };
                if mass < MIN_TRUNCATED_MASS {
                    return Err(format!(
                        "the truncation [{lo}, {hi}] keeps {mass:.1e} of the distribution's mass (mean {mean}, std {std}); \
                         it must keep at least {MIN_TRUNCATED_MASS:e}"
                    ));
                }
            }
            Distribution::Choice { values, weights } => {
                if values.is_empty() {
                    return Err("`values` is empty".into());
                }
                if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                    return Err(format!("`values` must be finite, got {v}"));
                }
                if let Some(w) = weights {
                    if w.len() != values.len() {
                        return Err(format!("`weights` has {} entries for {} values", w.len(), values.len()));
                    }
                    if w.iter().any(|x| !(x.is_finite() && *x >= 0.0)) || w.iter().sum::<f64>() <= 0.0 {
                        return Err("`weights` must be finite, >= 0 and not all 0".into());
                    }
                }
            }
        }
        Ok(())
    }

    /// One draw.
    fn sample(&self, rng: &mut SplitMix64) -> f64 {
        match self {
            Distribution::Uniform { min, max } => min + (max - min) * rng.uniform(),
            Distribution::Normal { mean, std, min, max } => {
                let (lo, hi) = (min.unwrap_or(f64::NEG_INFINITY), max.unwrap_or(f64::INFINITY));
                // `validate` guarantees a mass of at least 1e-4, so this ends within a few thousand draws in
                // practice; the cap only keeps a pathological case finite (clamped to the bounds).
                for _ in 0..10_000_000 {
                    let x = mean + std * rng.normal();
                    if (lo..=hi).contains(&x) {
                        return x;
                    }
                }
                mean.clamp(lo, hi)
            }
            Distribution::Choice { values, weights } => {
                let u = rng.uniform();
                match weights {
                    None => values[((u * values.len() as f64) as usize).min(values.len() - 1)],
                    Some(w) => {
                        let total: f64 = w.iter().sum();
                        let mut acc = 0.0;
                        for (v, wi) in values.iter().zip(w) {
                            acc += wi / total;
                            if u < acc {
                                return *v;
                            }
                        }
                        values[values.len() - 1]
                    }
                }
            }
        }
    }
}

/// Whether the scenario key `key` is read by the built-in F-16 alone: its initial condition (`initial.*`), its
/// disturbance (`disturbance.*`) and its plant options (`plant.xcg`, `plant.mass_scale`, `plant.aero_scale.*`). A
/// plant of your own (a process or an FMU) reads none of them: it reads its parameters and start values by name,
/// `plant.parameters.<name>`.
pub fn is_f16_only(key: &str) -> bool {
    key.starts_with("initial.")
        || key.starts_with("disturbance.")
        || key.starts_with("plant.") && !key.starts_with("plant.parameters.")
}

/// FNV-1a: a stable hash of a key name (the stream of each key does not depend on the other keys).
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// The values of sample `index` of `dispersions` under `seed`, in key order.
pub fn sample(dispersions: &BTreeMap<String, Distribution>, seed: u64, index: u64) -> Vec<(String, f64)> {
    dispersions
        .iter()
        .map(|(key, dist)| {
            let mut stream = SplitMix64::new(seed ^ fnv1a(key));
            // Skip to the sample's own stream: one more SplitMix64 mixing of (seed, key, index).
            let mut rng = SplitMix64::new(stream.next_u64() ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
            (key.clone(), dist.sample(&mut rng))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dispersions() -> BTreeMap<String, Distribution> {
        BTreeMap::from([
            (
                "initial.phi_deg".to_string(),
                Distribution::Normal { mean: 5.0, std: 2.0, min: Some(0.0), max: Some(9.0) },
            ),
            ("initial.airspeed_mps".to_string(), Distribution::Uniform { min: 140.0, max: 160.0 }),
        ])
    }

    #[test]
    fn a_sample_depends_only_on_seed_index_and_key() {
        let a = sample(&dispersions(), 7, 42);
        assert_eq!(a, sample(&dispersions(), 7, 42));
        assert_ne!(a, sample(&dispersions(), 7, 43));
        assert_ne!(a, sample(&dispersions(), 8, 42));
        // Adding a key leaves the others' values as they were.
        let mut more = dispersions();
        more.insert("plant.xcg".into(), Distribution::Uniform { min: 0.3, max: 0.4 });
        let b = sample(&more, 7, 42);
        assert_eq!(b.iter().filter(|(k, _)| k != "plant.xcg").cloned().collect::<Vec<_>>(), a);
    }

    #[test]
    fn draws_follow_their_distributions() {
        let n = 20_000;
        let d = dispersions();
        let phi: Vec<f64> = (0..n).map(|i| sample(&d, 1, i)[1].1).collect();
        assert!(phi.iter().all(|v| (0.0..=9.0).contains(v)), "truncation holds");
        let mean = phi.iter().sum::<f64>() / n as f64;
        assert!((mean - 4.9).abs() < 0.1, "truncated mean {mean}");
        let v: Vec<f64> = (0..n).map(|i| sample(&d, 1, i)[0].1).collect();
        assert!(v.iter().all(|x| (140.0..=160.0).contains(x)));
        let below = v.iter().filter(|x| **x < 145.0).count() as f64 / n as f64;
        assert!((below - 0.25).abs() < 0.02, "uniform quartile {below}");
        let c = Distribution::Choice { values: vec![1.0, 2.0], weights: Some(vec![3.0, 1.0]) };
        let ones = (0..n).filter(|i| sample(&BTreeMap::from([("k".to_string(), c.clone())]), 3, *i)[0].1 == 1.0).count()
            as f64
            / n as f64;
        assert!((ones - 0.75).abs() < 0.02, "weighted choice {ones}");
    }

    #[test]
    fn bad_distributions_say_what_is_wrong() {
        let bad = |d: Distribution| d.validate().unwrap_err();
        assert!(
            bad(Distribution::Normal { mean: 0.0, std: -1.0, min: None, max: None }).contains("`std` must be >= 0")
        );
        assert!(bad(Distribution::Normal { mean: 0.0, std: 1.0, min: Some(8.0), max: Some(9.0) }).contains("keeps"));
        assert!(bad(Distribution::Uniform { min: 2.0, max: 1.0 }).contains("above"));
        assert!(bad(Distribution::Choice { values: vec![], weights: None }).contains("empty"));
        assert!((normal_cdf(1.0) - 0.841_344_746).abs() < 1e-6);
    }

    #[test]
    fn the_f16s_own_keys_are_told_from_those_any_plant_reads() {
        for key in ["initial.phi_deg", "disturbance.amplitude_radps2", "plant.xcg", "plant.aero_scale.cm"] {
            assert!(is_f16_only(key), "{key}");
        }
        for key in ["plant.parameters.altitude_ft", "setpoint.theta_deg", "actuators.elevator.min", "timing.dt_s"] {
            assert!(!is_f16_only(key), "{key}");
        }
    }

    #[test]
    fn applying_a_sample_rewrites_exactly_its_keys() {
        let base = crate::scenario::Scenario::embedded_default();
        let s = base
            .with_values(&[("initial.phi_deg".into(), 7.5), ("actuators.elevator_deg.rate_limit_per_s".into(), 40.0)])
            .unwrap();
        assert_eq!(s.initial.phi_deg, 7.5);
        assert_eq!(s.actuators["elevator_deg"].rate_limit_per_s, Some(40.0));
        assert_eq!(s.initial.theta_deg, base.initial.theta_deg);
        assert!(base.with_values(&[("initial.phi_dge".into(), 1.0)]).unwrap_err().contains("initial.phi_dge"));
        assert!(base.with_values(&[("initial.phi_deg".into(), 500.0)]).unwrap_err().contains("initial.phi_deg"));
        assert!(base.with_values(&[("name".into(), 1.0)]).unwrap_err().contains("not a number"));
        // A plant of your own's parameters are dotted keys like any other.
        let mut own = base.clone();
        own.plant.parameters.insert("altitude_ft".into(), 4000.0);
        let s = own.with_values(&[("plant.parameters.altitude_ft".into(), 5500.0)]).unwrap();
        assert_eq!(s.plant.parameters["altitude_ft"], 5500.0);
        assert!(own.with_values(&[("plant.parameters.mass_kg".into(), 1.0)]).unwrap_err().contains("mass_kg"));
    }
}
