//! Pass/fail criteria of a closed-loop run as data: what a suite case or a sweep may ask for, their ranges, and the
//! judgement of one. Shared by `silrig check` and the sweeps; judging a flight is [`crate::judge`], the rig's own
//! criteria `silrig_tools::check::criteria`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What a run must meet (`[cases.criteria]` of a check suite, `[criteria]` of a sweep). Every key is optional;
/// only what is named is judged. The rig's timing and fault criteria need `silrig check`; a sweep judges the
/// flight ones ([`crate::judge::judge_flight`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Criteria {
    /// The plant found an answer (a command, or a refusal) from the controller for every tick it flew.
    #[serde(default)]
    pub every_tick_answered: bool,
    /// No command was NaN, infinite or out of range (refused by the controller's session or by the plant).
    #[serde(default)]
    pub no_invalid_command: bool,
    /// The controller's compute time per tick, p99.
    pub compute_p99: Option<Budget>,
    /// From the plant publishing a sample to the answering command arriving at the plant, p99.
    pub sense_to_actuate_p99: Option<Budget>,
    /// Ticks whose command did not reach the plant by the time it needed it (refusals not counted), at most.
    pub deadline_misses_max: Option<u64>,
    /// phi, theta and psi each stay within `band_deg` of the set point from `within_s` on.
    pub settled: Option<Settled>,
    /// Every set point of the scenario that names an output of the plant flown stays within `band` of it (in that
    /// output's unit) from `within_s` on: `settled` for any plant.
    pub setpoints_held: Option<SettledBand>,
    /// Largest overshoot of phi, theta or psi past its set point (in the direction of its step), deg.
    pub overshoot_max_deg: Option<f64>,
    /// Largest |angle - set point| of phi, theta, psi at the end of the run, deg.
    pub final_error_max_deg: Option<f64>,
    /// Largest angle of attack over the run, deg.
    pub alpha_max_deg: Option<f64>,
    /// Largest |p|, |q|, |r| from `after_s` on.
    pub body_rate_max_dps: Option<BodyRateLimit>,
    /// Ticks in which a surface's rate limit cut its motion, as a fraction of the ticks flown (worst surface).
    pub rate_limit_fraction_max: Option<f64>,
    /// Ticks in which a surface sat at a position limit, as a fraction of the ticks flown (worst surface).
    pub position_limit_fraction_max: Option<f64>,
    /// No sustained oscillation of an output with a set point or an actuator in the late window (the summary's
    /// limit-cycle detector; `timing.late_window_s`, the last 3 s of a 10 s run by default).
    #[serde(default)]
    pub no_sustained_oscillation: bool,
    /// After each restarted or resumed process (kill/term with `restart_after`, stop), the loop flies again within
    /// this many seconds of the process coming back: of a restarted one joining the flight, of a stopped one being
    /// continued.
    pub recovered_within_s: Option<f64>,
    /// After each restart (kill/term with `restart_after`), the process joined the flight again (the controller's
    /// first sample, the plant's first tick) within this many seconds of being started: its start-up, judged apart
    /// from the loop's recovery.
    pub restart_join_within_s: Option<f64>,
    /// The plant's failsafe engaged during a fault and released when the controller came back.
    #[serde(default)]
    pub failsafe_engaged_and_released: bool,
    /// Bumpless resume: after each controller fault it comes back from, how far its first command is from where
    /// the surface actually was, deg (worst surface).
    pub resume_jump_max_deg: Option<f64>,
    /// Two runs of the case give bit-identical commands (lockstep only).
    #[serde(default)]
    pub deterministic: bool,
    /// Criteria on any output of the plant by name (`[criteria.outputs.alt_ft]`), each in that output's unit.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub outputs: BTreeMap<String, OutputCriteria>,
}

/// What one output must meet (`[criteria.outputs.<name>]`), in the output's own unit. Set points come from the
/// scenario's `[setpoint]` by the same name.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputCriteria {
    /// From `within_s` on, within `band` of its set point.
    pub settled: Option<SettledBand>,
    /// Largest excursion past the set point in the direction of the step.
    pub overshoot_max: Option<f64>,
    /// Largest |last value - set point|.
    pub final_error_max: Option<f64>,
    /// Highest value over the run.
    pub max: Option<f64>,
    /// Lowest value over the run.
    pub min: Option<f64>,
    /// Largest |value| from `after_s` on.
    pub abs_max: Option<AbsMax>,
    /// No oscillation in the late window (`timing.late_window_s`) that swings more than this either way, sustained
    /// (at least two whole periods, not decaying: the summary's limit-cycle detector with this amplitude).
    pub oscillation_max: Option<f64>,
    /// From `from_s` for `for_s` seconds, within `band` of its own value at `from_s`: a hold judged where it began
    /// (an autopilot's altitude hold switched on in flight holds the altitude it was engaged at, not a set point).
    pub held: Option<HeldBand>,
}

/// `held = { from_s = T, for_s = D, band = B }` of an output, B in its unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldBand {
    /// When the hold begins, s: the output's value then is the reference.
    pub from_s: f64,
    /// How long it must hold, s.
    pub for_s: f64,
    /// Half-width of the band around the value at `from_s`.
    pub band: f64,
}

/// `settled = { within_s = T, band = B }` of an output, B in its unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettledBand {
    /// From this time on, s.
    pub within_s: f64,
    /// Half-width of the band around the set point.
    pub band: f64,
}

/// `abs_max = { after_s = T, max = X }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AbsMax {
    /// From this time on, s.
    pub after_s: f64,
    /// Largest |value|.
    pub max: f64,
}

impl OutputCriteria {
    /// Whether it asks for its output's set point.
    pub fn needs_setpoint(&self) -> bool {
        self.settled.is_some() || self.overshoot_max.is_some() || self.final_error_max.is_some()
    }

    /// Whether any criterion is set.
    fn any(&self) -> bool {
        self.needs_setpoint()
            || self.max.is_some()
            || self.min.is_some()
            || self.abs_max.is_some()
            || self.oscillation_max.is_some()
            || self.held.is_some()
    }

    /// Refuse what cannot be judged over a run of `duration_s`; `at` is the table's key below `criteria`
    /// (`outputs.alt_ft`).
    fn validate(&self, at: &str, duration_s: f64) -> Result<(), String> {
        let key = |k: &str| format!("{at}.{k}");
        let within_run = |k: &str, t: f64| {
            if t >= 0.0 && t < duration_s {
                Ok(())
            } else {
                Err(format!("`criteria.{}` must be within 0..{duration_s} s, got {t}", key(k)))
            }
        };
        if let Some(s) = self.settled {
            positive(&key("settled.band"), s.band)?;
            within_run("settled.within_s", s.within_s)?;
        }
        for (k, v) in [
            ("overshoot_max", self.overshoot_max),
            ("final_error_max", self.final_error_max),
            ("oscillation_max", self.oscillation_max),
            ("abs_max.max", self.abs_max.map(|a| a.max)),
        ] {
            if let Some(v) = v {
                positive(&key(k), v)?;
            }
        }
        if let Some(a) = self.abs_max {
            within_run("abs_max.after_s", a.after_s)?;
        }
        if let Some(h) = self.held {
            positive(&key("held.band"), h.band)?;
            positive(&key("held.for_s"), h.for_s)?;
            within_run("held.from_s", h.from_s)?;
            if h.from_s + h.for_s > duration_s {
                return Err(format!(
                    "`criteria.{}` ends at {} s, after the run's {duration_s} s: shorten `for_s` or start earlier",
                    key("held"),
                    h.from_s + h.for_s
                ));
            }
        }
        for (k, v) in [("max", self.max), ("min", self.min)] {
            if let Some(v) = v
                && !v.is_finite()
            {
                return Err(format!("`criteria.{}` must be a finite number, got {v}", key(k)));
            }
        }
        if let (Some(lo), Some(hi)) = (self.min, self.max)
            && lo >= hi
        {
            return Err(format!("`criteria.{}` ({lo}) must be below `criteria.{}` ({hi})", key("min"), key("max")));
        }
        if !self.any() {
            return Err(format!("`criteria.{at}` sets no criterion"));
        }
        Ok(())
    }
}

/// A time budget, judged on the steady state (after the first second): an absolute time, a fraction of the
/// scenario's period, or a multiple of the OS floor (the p99 wake-up lateness of a bare timer loop measured beside
/// the same run); the tightest of those given holds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Budget {
    /// At most this many µs.
    pub max_us: Option<f64>,
    /// At most this fraction of the scenario's period (`timing.dt_s`): 0.1 is 1 ms at 100 Hz.
    pub max_period_fraction: Option<f64>,
    /// At most this multiple of the OS floor's p99.
    pub max_os_floor_ratio: Option<f64>,
}

/// `settled = { within_s = T, band_deg = B }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settled {
    /// From this time on, s.
    pub within_s: f64,
    /// Half-width of the band around the set point, deg.
    pub band_deg: f64,
}

/// `body_rate_max_dps = { after_s = T, max = X }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyRateLimit {
    /// From this time on, s.
    pub after_s: f64,
    /// Largest |p|, |q|, |r|, deg/s.
    pub max: f64,
}

/// One criterion judged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Judgement {
    /// The criterion's key.
    pub criterion: String,
    /// What was measured, with its unit.
    pub measured: String,
    /// The limit, with its unit.
    pub limit: String,
    /// Whether the run met it.
    pub passed: bool,
    /// On failure: what went wrong, in words, and where to look.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why_failed: Option<String>,
    /// Neither pass nor fail: the figure missed its limit by no more than the machine's own disturbance during the
    /// run explains; why, with the figures (`passed` is false, `why_failed` None).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inconclusive: Option<String>,
    /// The measured figure as a number in the limit's unit, larger being worse (for ranking cases); None where
    /// nothing was measured, or the figure never settled (infinite).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
}

/// What a judgement says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// The limit was met.
    Pass,
    /// It was not.
    Fail,
    /// The machine disturbed the measurement too much to tell.
    Inconclusive,
}

impl Outcome {
    /// As the verdict's table shows it.
    pub fn label(self) -> &'static str {
        match self {
            Outcome::Pass => "pass",
            Outcome::Fail => "FAIL",
            Outcome::Inconclusive => "inconclusive",
        }
    }
}

impl Judgement {
    /// Pass, fail or inconclusive.
    pub fn outcome(&self) -> Outcome {
        match (self.passed, &self.inconclusive) {
            (true, _) => Outcome::Pass,
            (false, Some(_)) => Outcome::Inconclusive,
            (false, None) => Outcome::Fail,
        }
    }

    /// With the measured figure as a number (non-finite values are kept out: JSON has no infinity).
    pub(crate) fn with_value(mut self, value: f64) -> Self {
        self.value = value.is_finite().then_some(value);
        self
    }
}

/// `Err` naming the criterion when `v` is not a positive finite number.
pub fn positive(key: &str, v: f64) -> Result<(), String> {
    if v > 0.0 && v.is_finite() { Ok(()) } else { Err(format!("`criteria.{key}` must be a positive number, got {v}")) }
}

/// Criteria only the three-process rig can measure (timing, the contract, process faults, two runs).
const RIG_CRITERIA: [&str; 10] = [
    "every_tick_answered",
    "no_invalid_command",
    "compute_p99",
    "sense_to_actuate_p99",
    "deadline_misses_max",
    "recovered_within_s",
    "restart_join_within_s",
    "failsafe_engaged_and_released",
    "resume_jump_max_deg",
    "deterministic",
];

impl Criteria {
    /// The keys set that only the rig can judge.
    pub fn rig_criteria_set(&self) -> Vec<&'static str> {
        let set = [
            self.every_tick_answered,
            self.no_invalid_command,
            self.compute_p99.is_some(),
            self.sense_to_actuate_p99.is_some(),
            self.deadline_misses_max.is_some(),
            self.recovered_within_s.is_some(),
            self.restart_join_within_s.is_some(),
            self.failsafe_engaged_and_released,
            self.resume_jump_max_deg.is_some(),
            self.deterministic,
        ];
        RIG_CRITERIA.iter().zip(set).filter(|(_, on)| *on).map(|(k, _)| *k).collect()
    }

    /// Refuse flight criteria that cannot be judged over a run of `duration_s`; `has_setpoint` says whether the
    /// scenario gives an output a set point (its settling, overshoot and final error need one).
    pub fn validate_flight(&self, duration_s: f64, has_setpoint: &dyn Fn(&str) -> bool) -> Result<(), String> {
        for (name, c) in &self.outputs {
            let at = format!("outputs.{name}");
            if !crate::signals::valid_name(name) {
                return Err(format!("`criteria.{at}`: `{name}` is not an output name"));
            }
            c.validate(&at, duration_s)?;
            if c.needs_setpoint() && !has_setpoint(name) {
                return Err(format!(
                    "`criteria.{at}` judges against a set point, and the scenario gives none: add `{name} = ...` to \
                     [setpoint]"
                ));
            }
        }
        if let Some(s) = self.setpoints_held {
            positive("setpoints_held.band", s.band)?;
            if !(s.within_s >= 0.0 && s.within_s < duration_s) {
                return Err(format!(
                    "`criteria.setpoints_held.within_s` must be within 0..{duration_s} s, got {}",
                    s.within_s
                ));
            }
        }
        if let Some(s) = self.settled {
            positive("settled.band_deg", s.band_deg)?;
            if !(s.within_s >= 0.0 && s.within_s < duration_s) {
                return Err(format!(
                    "`criteria.settled.within_s` must be within 0..{duration_s} s, got {}",
                    s.within_s
                ));
            }
        }
        for (key, v) in [
            ("alpha_max_deg", self.alpha_max_deg),
            ("overshoot_max_deg", self.overshoot_max_deg),
            ("final_error_max_deg", self.final_error_max_deg),
        ] {
            if let Some(v) = v {
                positive(key, v)?;
            }
        }
        if let Some(b) = self.body_rate_max_dps {
            positive("body_rate_max_dps.max", b.max)?;
            if !(b.after_s >= 0.0 && b.after_s < duration_s) {
                return Err(format!(
                    "`criteria.body_rate_max_dps.after_s` must be within 0..{duration_s} s, got {}",
                    b.after_s
                ));
            }
        }
        for (key, v) in [
            ("rate_limit_fraction_max", self.rate_limit_fraction_max),
            ("position_limit_fraction_max", self.position_limit_fraction_max),
        ] {
            if let Some(f) = v
                && !(0.0..=1.0).contains(&f)
            {
                return Err(format!("`criteria.{key}` must be a fraction in 0..1, got {f}"));
            }
        }
        Ok(())
    }

    /// Whether any flight criterion is set.
    pub fn has_flight_criteria(&self) -> bool {
        !self.outputs.is_empty()
            || self.settled.is_some()
            || self.setpoints_held.is_some()
            || self.alpha_max_deg.is_some()
            || self.overshoot_max_deg.is_some()
            || self.final_error_max_deg.is_some()
            || self.body_rate_max_dps.is_some()
            || self.rate_limit_fraction_max.is_some()
            || self.position_limit_fraction_max.is_some()
            || self.no_sustained_oscillation
    }
}
