//! Set points: `[setpoint]`, their values at the start (the F-16 controller's attitude and any output by name), and
//! `[[setpoint_steps]]`, set points that change during a run, each step an `at_s` and the set points it changes from
//! then on (`{ at_s = 20.0, rc_roll = 0.3 }`). Owns their shapes, their validation in words, and the one answer
//! every reader of set points asks: the value in force at a time (piecewise constant, as a stick moved and held;
//! [`crate::scenario::Scenario::setpoint_at`], or a [`SetpointTrack`] a reader keeps). Pure: no I/O, no clock.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The F-16 controller's attitude set points and the largest |value| each takes, deg.
const ANGLE_LIMITS_DEG: [(&str, f64); 3] = [("phi_deg", 90.0), ("theta_deg", 60.0), ("psi_deg", 180.0)];

/// The set points at the start (`[[setpoint_steps]]` may change them later): the attitude our controller flies (`phi_deg`, `theta_deg`, `psi_deg`, 0 when not given),
/// and any other plant output by its name, in that output's unit (`alt_ft = 4000.0`), which a controller of your
/// own reads by name and the criteria judge against.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Setpoint {
    /// Roll, deg.
    #[serde(default)]
    pub phi_deg: f64,
    /// Pitch, deg.
    #[serde(default)]
    pub theta_deg: f64,
    /// Heading, deg.
    #[serde(default)]
    pub psi_deg: f64,
    /// Set points of other outputs, by output name.
    #[serde(flatten)]
    pub outputs: BTreeMap<String, f64>,
}

impl Setpoint {
    /// The set point of output `name`, if the scenario gives one (the three angles always).
    pub fn get(&self, name: &str) -> Option<f64> {
        match name {
            "phi_deg" => Some(self.phi_deg),
            "theta_deg" => Some(self.theta_deg),
            "psi_deg" => Some(self.psi_deg),
            _ => self.outputs.get(name).copied(),
        }
    }

    /// Every value a finite number, the outputs' names names, the angles within [`ANGLE_LIMITS_DEG`]; an error
    /// names the key under `[setpoint]` and the problem.
    pub(crate) fn validate(&self) -> Result<(), (String, String)> {
        for name in self.outputs.keys() {
            if !crate::signals::valid_name(name) {
                let max = crate::signals::MAX_NAME_LEN;
                let problem = format!("is not an output name: use 1..={max} of ASCII letters, digits and '_'");
                return Err((name.clone(), problem));
            }
        }
        for (name, v) in self.all() {
            value_problem(name, v).map_err(|problem| (name.to_string(), problem))?;
        }
        Ok(())
    }

    /// Every set point, the three angles first.
    pub fn all(&self) -> Vec<(&str, f64)> {
        [("phi_deg", self.phi_deg), ("theta_deg", self.theta_deg), ("psi_deg", self.psi_deg)]
            .into_iter()
            .chain(self.outputs.iter().map(|(k, v)| (k.as_str(), *v)))
            .collect()
    }
}

/// What is wrong with `v` as set point `name`: not finite, or an angle beyond its range.
fn value_problem(name: &str, v: f64) -> Result<(), String> {
    if !v.is_finite() {
        return Err(format!("must be a finite number, got {v}"));
    }
    match ANGLE_LIMITS_DEG.iter().find(|(n, _)| *n == name) {
        Some((_, limit)) if v.abs() > *limit => Err(format!("must be within -{limit}..{limit} deg, got {v}")),
        _ => Ok(()),
    }
}

/// One step of the schedule: from `at_s` on, each named set point takes its value here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetpointStep {
    /// When the step takes effect, s of simulated time: from the first tick whose time (tick × `dt_s`, as a fault's
    /// `at_s`) is at or after it.
    pub at_s: f64,
    /// The set points it changes, by the names `[setpoint]` gives them, in their units.
    #[serde(flatten)]
    pub values: BTreeMap<String, f64>,
}

/// One stretch of a set point's history: from `from_s` on, `value` is in force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// When the value takes effect, s (0 for `[setpoint]`'s own).
    pub from_s: f64,
    /// The set point in force from then on, in the output's unit.
    pub value: f64,
}

/// A set point's history over a run, for a reader that holds no scenario (a controller, a device, a figure): its
/// segments in time order, the first from 0.
#[derive(Debug, Clone, PartialEq)]
pub struct SetpointTrack {
    segments: Vec<Segment>,
}

impl SetpointTrack {
    /// Set point `name`'s history: `setpoint`'s value from 0, then each of `steps` that changes it; `None` when
    /// `setpoint` gives no `name`.
    pub fn of(setpoint: &Setpoint, steps: &[SetpointStep], name: &str) -> Option<Self> {
        let first = Segment { from_s: 0.0, value: setpoint.get(name)? };
        let later = steps.iter().filter_map(|s| Some(Segment { from_s: s.at_s, value: *s.values.get(name)? }));
        Some(Self { segments: std::iter::once(first).chain(later).collect() })
    }

    /// A set point that never changes.
    pub fn constant(value: f64) -> Self {
        Self { segments: vec![Segment { from_s: 0.0, value }] }
    }

    /// The value in force at `t_s` (the first segment's before it starts).
    pub fn at(&self, t_s: f64) -> f64 {
        let later = self.segments[1..].iter().take_while(|s| s.from_s <= t_s).last();
        later.unwrap_or(&self.segments[0]).value
    }

    /// The segments, the first from 0; one when the set point never changes.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Whether a step changes it during the run.
    pub fn steps(&self) -> bool {
        self.segments.len() > 1
    }
}

/// Set point `name` in force at `t_s` under `steps` (what [`SetpointTrack::at`] answers, without keeping one).
pub fn value_at(setpoint: &Setpoint, steps: &[SetpointStep], name: &str, t_s: f64) -> Option<f64> {
    let initial = setpoint.get(name)?;
    let stepped = steps.iter().take_while(|s| s.at_s <= t_s).filter_map(|s| s.values.get(name));
    Some(stepped.last().copied().unwrap_or(initial))
}

/// `[[setpoint_steps]]` of a run of `duration_s`: each step inside the run, later than the one before, changing only
/// set points `setpoint` gives, to values `[setpoint]` would take. Errors name the key (`setpoint_steps[1].at_s`).
pub(crate) fn validate_steps(
    setpoint: &Setpoint,
    steps: &[SetpointStep],
    duration_s: f64,
) -> Result<(), (String, String)> {
    let mut previous_s = 0.0;
    for (i, step) in steps.iter().enumerate() {
        let key = |k: &str| format!("setpoint_steps[{i}].{k}");
        let t = step.at_s;
        if !(t > 0.0 && t < duration_s) {
            let why = if t == 0.0 { "; a set point from t = 0 goes in [setpoint] itself" } else { "" };
            return Err((key("at_s"), format!("must be within (0, {duration_s}) s, inside the run, got {t}{why}")));
        }
        if i > 0 && t <= previous_s {
            let problem =
                format!("{t} s is not after the step before it ({previous_s} s): list the steps in time order");
            return Err((key("at_s"), problem));
        }
        previous_s = t;
        if step.values.is_empty() {
            return Err((key("at_s"), "the step changes no set point: name one beside `at_s`".into()));
        }
        for (name, v) in &step.values {
            if setpoint.get(name).is_none() {
                let given: Vec<&str> = setpoint.all().into_iter().map(|(n, _)| n).collect();
                let problem = format!(
                    "[setpoint] gives no set point `{name}`, so no step can change it: add `{name} = <value at the \
                     start>` to [setpoint] (it gives: {})",
                    given.join(", ")
                );
                return Err((key(name), problem));
            }
            value_problem(name, *v).map_err(|problem| (key(name), problem))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    fn scenario(extra: &str) -> Result<Scenario, String> {
        let text = format!(
            "name = \"s\"\n[setpoint]\nphi_deg = 1.0\nalt_ft = 100.0\n{extra}\n[timing]\ndt_s = 0.01\nduration_s = 10.0\n\
             command_timing = \"next-tick\"\n"
        );
        Scenario::from_toml(&text, "test").map_err(|e| e.to_string())
    }

    #[test]
    fn the_value_in_force_is_the_last_step_at_or_before_the_time() {
        let s = scenario(
            "[[setpoint_steps]]\nat_s = 2.0\nphi_deg = 5.0\n[[setpoint_steps]]\nat_s = 4.0\nalt_ft = 200.0\n\
             [[setpoint_steps]]\nat_s = 6.0\nphi_deg = -3.0\n",
        )
        .unwrap();
        let phi: Vec<f64> =
            [0.0, 1.99, 2.0, 3.0, 4.0, 5.99, 6.0, 10.0].map(|t| s.setpoint_at("phi_deg", t).unwrap()).into();
        assert_eq!(phi, [1.0, 1.0, 5.0, 5.0, 5.0, 5.0, -3.0, -3.0]);
        let alt: Vec<f64> = [0.0, 3.99, 4.0, 9.0].map(|t| s.setpoint_at("alt_ft", t).unwrap()).into();
        assert_eq!(alt, [100.0, 100.0, 200.0, 200.0]);
        // An angle [setpoint] leaves out is 0 and stays 0: no step names it.
        assert_eq!(s.setpoint_at("theta_deg", 7.0), Some(0.0));
        assert_eq!(s.setpoint_at("vt_mps", 7.0), None);
        let seg = |from_s, value| Segment { from_s, value };
        let phi = s.setpoint_track("phi_deg").unwrap();
        assert_eq!(phi.segments(), [seg(0.0, 1.0), seg(2.0, 5.0), seg(6.0, -3.0)]);
        assert_eq!(s.setpoint_track("theta_deg").unwrap(), SetpointTrack::constant(0.0));
        assert!(phi.steps() && !s.setpoint_track("theta_deg").unwrap().steps());
        assert_eq!(s.setpoint_track("vt_mps"), None);
        // The track a reader keeps answers as the scenario does, at every tick.
        let alt = s.setpoint_track("alt_ft").unwrap();
        for k in 0..=1000 {
            let t = k as f64 * 0.01;
            assert_eq!(phi.at(t), s.setpoint_at("phi_deg", t).unwrap(), "{t}");
            assert_eq!(alt.at(t), s.setpoint_at("alt_ft", t).unwrap(), "{t}");
        }
    }

    #[test]
    fn without_steps_the_set_point_is_the_same_at_every_time_and_the_scenario_writes_no_steps() {
        let s = scenario("").unwrap();
        for t in [0.0, 5.0, 1e9] {
            assert_eq!(s.setpoint_at("phi_deg", t), Some(1.0));
        }
        assert!(!s.to_toml().contains("setpoint_steps"), "{}", s.to_toml());
        let stepped = scenario("[[setpoint_steps]]\nat_s = 2.0\nphi_deg = 5.0\n").unwrap();
        assert_eq!(Scenario::from_toml(&stepped.to_toml(), "again").unwrap(), stepped);
    }

    #[test]
    fn a_bad_schedule_is_refused_in_words_naming_the_key() {
        let refused = |extra: &str| scenario(extra).unwrap_err();
        let e = refused("[[setpoint_steps]]\nat_s = 2.0\nrc_roll = 0.3\n");
        assert!(e.contains("setpoint_steps[0].rc_roll") && e.contains("add `rc_roll = <value at the start>`"), "{e}");
        assert!(e.contains("it gives: phi_deg, theta_deg, psi_deg, alt_ft"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = 10.0\nphi_deg = 3.0\n");
        assert!(e.contains("setpoint_steps[0].at_s") && e.contains("must be within (0, 10) s"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = 0.0\nphi_deg = 3.0\n");
        assert!(e.contains("goes in [setpoint] itself"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = -1.0\nphi_deg = 3.0\n");
        assert!(e.contains("got -1"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = nan\nphi_deg = 3.0\n");
        assert!(e.contains("setpoint_steps[0].at_s"), "{e}");
        let e =
            refused("[[setpoint_steps]]\nat_s = 4.0\nphi_deg = 3.0\n[[setpoint_steps]]\nat_s = 4.0\nphi_deg = 2.0\n");
        assert!(e.contains("setpoint_steps[1].at_s") && e.contains("not after the step before it (4 s)"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = 4.0\nalt_ft = inf\n");
        assert!(e.contains("setpoint_steps[0].alt_ft") && e.contains("finite"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = 4.0\nphi_deg = 95.0\n");
        assert!(e.contains("setpoint_steps[0].phi_deg") && e.contains("-90..90"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = 4.0\n");
        assert!(e.contains("changes no set point"), "{e}");
        let e = refused("[[setpoint_steps]]\nat_s = 4.0\nphi_deg = \"up\"\n");
        assert!(e.contains("setpoint_steps"), "{e}");
    }
}
