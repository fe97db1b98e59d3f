//! The scenario's `[disturbance]`: a sine on the Euler-angle accelerations of the F-16, its channels, and the
//! ranges its values must keep (refused naming the key, as every scenario value is).

use serde::{Deserialize, Serialize};

/// d(t) = amplitude * sin(frequency * t) on the chosen Euler-angle accelerations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Disturbance {
    /// Amplitude, rad/s^2.
    #[serde(default)]
    pub amplitude_radps2: f64,
    /// Angular frequency, rad/s.
    #[serde(default)]
    pub frequency_radps: f64,
    /// Channels it acts on: any of "phi", "theta", "psi".
    #[serde(default = "all_channels")]
    pub channels: Vec<String>,
}

fn all_channels() -> Vec<String> {
    silrig_model::control::CHANNEL_NAMES.iter().map(|s| s.to_string()).collect()
}

impl Default for Disturbance {
    fn default() -> Self {
        Self { amplitude_radps2: 0.0, frequency_radps: 0.0, channels: all_channels() }
    }
}

impl Disturbance {
    /// The disturbance at time `t_s`, per channel, rad/s^2.
    #[inline]
    pub fn at(&self, t_s: f64, mask: &[bool; 3]) -> [f64; 3] {
        if self.amplitude_radps2 == 0.0 {
            return [0.0; 3];
        }
        let d = self.amplitude_radps2 * (self.frequency_radps * t_s).sin();
        mask.map(|on| if on { d } else { 0.0 })
    }

    /// Check its values; on error return (dotted key, problem), as [`crate::scenario::Scenario::validate`] does.
    pub fn validate(&self) -> Result<(), (String, String)> {
        if !(self.amplitude_radps2.abs() <= 100.0) {
            return refuse(
                "disturbance.amplitude_radps2",
                format!("must be within -100..100 rad/s^2, got {}", self.amplitude_radps2),
            );
        }
        if self.frequency_radps > 1000.0 {
            return refuse(
                "disturbance.frequency_radps",
                format!("must be at most 1000 rad/s, got {}", self.frequency_radps),
            );
        }
        if !(self.frequency_radps >= 0.0 && self.frequency_radps.is_finite()) {
            return refuse("disturbance.frequency_radps", format!("must be >= 0, got {}", self.frequency_radps));
        }
        if let Some(c) = self.channels.iter().find(|c| !silrig_model::control::CHANNEL_NAMES.contains(&c.as_str())) {
            return refuse("disturbance.channels", format!("unknown channel {c:?}; use \"phi\", \"theta\" or \"psi\""));
        }
        Ok(())
    }

    /// Which channels are disturbed.
    pub fn channel_mask(&self) -> [bool; 3] {
        silrig_model::control::CHANNEL_NAMES.map(|n| self.channels.iter().any(|c| c == n))
    }
}

/// The key refused with its problem, in the (dotted key, problem) form the scenario's checks return.
fn refuse(key: &str, problem: String) -> Result<(), (String, String)> {
    Err((key.to_string(), problem))
}
