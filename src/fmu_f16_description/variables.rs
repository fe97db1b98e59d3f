//! The FMU's variables: the F-16's outputs and inputs as the rig announces them ([`silrig_model::f16_outputs`]),
//! and its parameters ([`Parameters`]): CG, uncertainty scales, holds, the initial condition and the actuators'
//! limits, each named after its scenario key, so start values by name reproduce a scenario. Also the text the
//! exported FMU carries its parameters' start values in (`resources/start_values.txt`), since the binary must start
//! from them whether or not the importer sets them.

use silrig_model::actuator::{ActuatorLimits, ActuatorSetLimits, MAX_LAG_S, MAX_RATE_LIMIT_PER_S};
use silrig_model::f16_outputs::{INPUTS, OUTPUTS_LEN, input_range, output_signals};
use silrig_model::plant::{ExternalForcing, F16Model, ModelScales};
use silrig_model::vehicle::{InitialCondition, InitialMode};

/// Value reference of the first input (the outputs come first, 0.., in the rig's announced order).
pub const FIRST_INPUT_VR: u32 = OUTPUTS_LEN as u32;
/// Value reference of the first Real parameter (after the four inputs).
pub const FIRST_PARAMETER_VR: u32 = FIRST_INPUT_VR + INPUTS.len() as u32;

/// A Real parameter: its name (the scenario key with `_` for `.`), unit, range and what it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RealParameter {
    /// Variable name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// What it is, and the scenario key it stands for.
    pub description: &'static str,
}

const fn real(name: &'static str, unit: &'static str, min: f64, max: f64, description: &'static str) -> RealParameter {
    RealParameter { name, unit, min, max, description }
}

/// Index of each Real parameter in [`REAL_PARAMETERS`] (and in [`Parameters::reals`]).
mod at {
    pub const XCG: usize = 0;
    pub const MASS_SCALE: usize = 1;
    /// cx, cy, cz, cl, cm, cn follow.
    pub const AERO_SCALE: usize = 2;
    pub const AIRSPEED: usize = 8;
    pub const ALTITUDE: usize = 9;
    /// alpha, beta, phi, theta, psi (deg), p, q, r (deg/s) follow.
    pub const ANGLES: usize = 10;
    pub const THROTTLE: usize = 18;
    /// Per actuator (aileron, elevator, rudder, throttle): min, max, rate limit, lag.
    pub const ACTUATORS: usize = 19;
}

/// Surfaces' travel as a scenario may set it, deg.
const TRAVEL: f64 = silrig_model::actuator::SURFACE_CMD_LIMIT_DEG;

/// The Real parameters, in value-reference order from [`FIRST_PARAMETER_VR`], with the ranges `silrig` accepts
/// in a scenario.
pub const REAL_PARAMETERS: [RealParameter; 35] = [
    real("xcg", "1", 0.0, 1.0, "CG position, fraction of the mean aerodynamic chord (plant.xcg)"),
    real("mass_scale", "1", 0.5, 2.0, "multiplier on the mass and inertias (plant.mass_scale)"),
    real("aero_scale_cx", "1", 0.0, 3.0, "multiplier on Cx (plant.aero_scale.cx)"),
    real("aero_scale_cy", "1", 0.0, 3.0, "multiplier on Cy (plant.aero_scale.cy)"),
    real("aero_scale_cz", "1", 0.0, 3.0, "multiplier on Cz (plant.aero_scale.cz)"),
    real("aero_scale_cl", "1", 0.0, 3.0, "multiplier on Cl (plant.aero_scale.cl)"),
    real("aero_scale_cm", "1", 0.0, 3.0, "multiplier on Cm (plant.aero_scale.cm)"),
    real("aero_scale_cn", "1", 0.0, 3.0, "multiplier on Cn (plant.aero_scale.cn)"),
    real("initial_airspeed_mps", "m/s", 0.0, 400.0, "true airspeed, above 0 (initial.airspeed_mps)"),
    real("initial_altitude_ft", "ft", 0.0, 50_000.0, "altitude (initial.altitude_ft)"),
    real("initial_alpha_deg", "deg", -45.0, 45.0, "angle of attack, explicit mode (initial.alpha_deg)"),
    real("initial_beta_deg", "deg", -30.0, 30.0, "sideslip (initial.beta_deg)"),
    real("initial_phi_deg", "deg", -180.0, 180.0, "roll angle (initial.phi_deg)"),
    real("initial_theta_deg", "deg", -80.0, 80.0, "pitch angle, explicit mode (initial.theta_deg)"),
    real("initial_psi_deg", "deg", -180.0, 180.0, "heading (initial.psi_deg)"),
    real("initial_p_dps", "deg/s", -360.0, 360.0, "body roll rate (initial.p_dps)"),
    real("initial_q_dps", "deg/s", -360.0, 360.0, "body pitch rate (initial.q_dps)"),
    real("initial_r_dps", "deg/s", -360.0, 360.0, "body yaw rate (initial.r_dps)"),
    real(
        "initial_throttle",
        "1",
        -1.0,
        1.0,
        "initial throttle 0..1; below 0: not given, the trim throttle or the one that holds the airspeed (initial.throttle)",
    ),
    real("aileron_min", "deg", -TRAVEL, TRAVEL, "aileron position limit (actuators.aileron.min)"),
    real("aileron_max", "deg", -TRAVEL, TRAVEL, "aileron position limit (actuators.aileron.max)"),
    real("aileron_rate_limit_per_s", "deg/s", 0.0, MAX_RATE_LIMIT_PER_S, "aileron rate limit, 0: none"),
    real("aileron_lag_time_constant_s", "s", 0.0, MAX_LAG_S, "aileron first-order lag, 0: none"),
    real("elevator_min", "deg", -TRAVEL, TRAVEL, "elevator position limit (actuators.elevator.min)"),
    real("elevator_max", "deg", -TRAVEL, TRAVEL, "elevator position limit (actuators.elevator.max)"),
    real("elevator_rate_limit_per_s", "deg/s", 0.0, MAX_RATE_LIMIT_PER_S, "elevator rate limit, 0: none"),
    real("elevator_lag_time_constant_s", "s", 0.0, MAX_LAG_S, "elevator first-order lag, 0: none"),
    real("rudder_min", "deg", -TRAVEL, TRAVEL, "rudder position limit (actuators.rudder.min)"),
    real("rudder_max", "deg", -TRAVEL, TRAVEL, "rudder position limit (actuators.rudder.max)"),
    real("rudder_rate_limit_per_s", "deg/s", 0.0, MAX_RATE_LIMIT_PER_S, "rudder rate limit, 0: none"),
    real("rudder_lag_time_constant_s", "s", 0.0, MAX_LAG_S, "rudder first-order lag, 0: none"),
    real("throttle_min", "1", 0.0, 1.0, "throttle position limit (actuators.throttle.min)"),
    real("throttle_max", "1", 0.0, 1.0, "throttle position limit (actuators.throttle.max)"),
    real("throttle_rate_limit_per_s", "1/s", 0.0, MAX_RATE_LIMIT_PER_S, "throttle rate limit, 0: none"),
    real("throttle_lag_time_constant_s", "s", 0.0, MAX_LAG_S, "throttle first-order lag, 0: none"),
];

/// The Boolean parameters, in value-reference order from 0 (Booleans have their own value references).
pub const BOOLEAN_PARAMETERS: [(&str, &str); 3] = [
    ("speed_hold", "freeze the airspeed, VT_dot = 0 (plant.speed_hold)"),
    ("sideslip_hold", "freeze the sideslip, beta_dot = 0 (plant.sideslip_hold)"),
    ("initial_trim", "true: level-flight trim at the initial airspeed and altitude; false: explicit (initial.mode)"),
];

/// Index of each Boolean parameter.
const SPEED_HOLD: usize = 0;
const SIDESLIP_HOLD: usize = 1;
const INITIAL_TRIM: usize = 2;

/// The parameters' values: what `PlantRunner::new` takes from a scenario to build and trim the F-16, less what the
/// FMU leaves to its importer (faults, the disturbance, the step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameters {
    /// In [`REAL_PARAMETERS`] order.
    pub reals: [f64; REAL_PARAMETERS.len()],
    /// In [`BOOLEAN_PARAMETERS`] order.
    pub booleans: [bool; BOOLEAN_PARAMETERS.len()],
}

/// An optional limit as a parameter: 0 for none.
fn or_zero(v: Option<f64>) -> f64 {
    v.unwrap_or(0.0)
}

/// A parameter's 0 as no limit.
fn positive(v: f64) -> Option<f64> {
    (v > 0.0).then_some(v)
}

impl Default for Parameters {
    /// The book's aircraft (xcg 0.35, scales 1, the book's actuators, no holds) at the model's default initial
    /// condition (explicit, 150 m/s at 25,000 ft, alpha, phi, theta and psi 5 deg).
    fn default() -> Self {
        Self::new(&F16Model::default(), &InitialCondition::default(), &ActuatorSetLimits::default(), false, false)
    }
}

impl Parameters {
    /// The parameters of a model, an initial condition, actuators and the holds (what a scenario gives).
    pub fn new(
        model: &F16Model,
        initial: &InitialCondition,
        actuators: &ActuatorSetLimits,
        speed_hold: bool,
        sideslip_hold: bool,
    ) -> Self {
        let mut reals = [0.0; REAL_PARAMETERS.len()];
        reals[at::XCG] = model.xcg;
        reals[at::MASS_SCALE] = model.scales.mass;
        reals[at::AERO_SCALE..at::AERO_SCALE + 6].copy_from_slice(&model.scales.aero);
        reals[at::AIRSPEED] = initial.airspeed_mps;
        reals[at::ALTITUDE] = initial.altitude_ft;
        let i = initial;
        reals[at::ANGLES..at::ANGLES + 8].copy_from_slice(&[
            i.alpha_deg,
            i.beta_deg,
            i.phi_deg,
            i.theta_deg,
            i.psi_deg,
            i.p_dps,
            i.q_dps,
            i.r_dps,
        ]);
        reals[at::THROTTLE] = i.throttle.unwrap_or(-1.0);
        let a = actuators;
        for (k, limits) in [a.aileron_deg, a.elevator_deg, a.rudder_deg, a.throttle].iter().enumerate() {
            let base = at::ACTUATORS + 4 * k;
            reals[base..base + 4].copy_from_slice(&[
                limits.min,
                limits.max,
                or_zero(limits.rate_limit_per_s),
                or_zero(limits.lag_time_constant_s),
            ]);
        }
        let trim = initial.mode == InitialMode::Trim;
        Self { reals, booleans: [speed_hold, sideslip_hold, trim] }
    }

    /// The F-16 model (CG and uncertainty scales).
    pub fn model(&self) -> F16Model {
        let r = &self.reals;
        let aero = std::array::from_fn(|k| r[at::AERO_SCALE + k]);
        F16Model::new(r[at::XCG]).with_scales(ModelScales { aero, mass: r[at::MASS_SCALE] })
    }

    /// The initial condition.
    pub fn initial(&self) -> InitialCondition {
        let r = &self.reals;
        let angle = |k: usize| r[at::ANGLES + k];
        InitialCondition {
            mode: if self.booleans[INITIAL_TRIM] { InitialMode::Trim } else { InitialMode::Explicit },
            airspeed_mps: r[at::AIRSPEED],
            altitude_ft: r[at::ALTITUDE],
            alpha_deg: angle(0),
            beta_deg: angle(1),
            phi_deg: angle(2),
            theta_deg: angle(3),
            psi_deg: angle(4),
            p_dps: angle(5),
            q_dps: angle(6),
            r_dps: angle(7),
            throttle: (r[at::THROTTLE] >= 0.0).then_some(r[at::THROTTLE]),
        }
    }

    /// The four actuators' limits.
    pub fn actuators(&self) -> ActuatorSetLimits {
        let limits = |k: usize| {
            let p = &self.reals[at::ACTUATORS + 4 * k..at::ACTUATORS + 4 * k + 4];
            ActuatorLimits {
                min: p[0],
                max: p[1],
                rate_limit_per_s: positive(p[2]),
                lag_time_constant_s: positive(p[3]),
            }
        };
        ActuatorSetLimits {
            aileron_deg: limits(0),
            elevator_deg: limits(1),
            rudder_deg: limits(2),
            throttle: limits(3),
        }
    }

    /// The holds as the equations of motion take them (no disturbance).
    pub fn forcing(&self) -> ExternalForcing {
        ExternalForcing {
            speed_hold: self.booleans[SPEED_HOLD],
            sideslip_hold: self.booleans[SIDESLIP_HOLD],
            ..Default::default()
        }
    }

    /// Check every value against its range and the actuators' limits against each other; the error names the
    /// variable.
    pub fn check(&self) -> Result<(), String> {
        for (p, v) in REAL_PARAMETERS.iter().zip(self.reals) {
            check_real(p, v)?;
        }
        if !(self.reals[at::AIRSPEED] > 0.0) {
            return Err(format!("initial_airspeed_mps = {} must be above 0", self.reals[at::AIRSPEED]));
        }
        for (k, (input, _)) in INPUTS.iter().enumerate() {
            let limits = &self.reals[at::ACTUATORS + 4 * k..];
            if !(limits[0] < limits[1]) {
                return Err(format!("{input}_min = {} must be below {input}_max = {}", limits[0], limits[1]));
            }
        }
        Ok(())
    }

    /// The start-values text the exported FMU carries (`name = value` a line, Reals then Booleans), which
    /// [`Parameters::from_text`] reads back bit for bit.
    pub fn to_text(&self) -> String {
        values_text(&REAL_PARAMETERS, &self.reals, &BOOLEAN_PARAMETERS, &self.booleans)
    }

    /// Parameters from [`Parameters::to_text`]'s text: every parameter exactly once, each within its range; the
    /// error names the line.
    pub fn from_text(text: &str) -> Result<Self, String> {
        let (reals, booleans) = read_values(text, &REAL_PARAMETERS, &BOOLEAN_PARAMETERS)?;
        let p = Parameters {
            reals: reals.try_into().map_err(|_| "the F-16's Real parameters")?,
            booleans: booleans.try_into().map_err(|_| "the F-16's Boolean parameters")?,
        };
        p.check()?;
        Ok(p)
    }
}

/// Parameters' values as start-values text: `name = value` a line, Reals then Booleans.
pub fn values_text(reals: &[RealParameter], real_values: &[f64], booleans: &[(&str, &str)], flags: &[bool]) -> String {
    let mut text = String::new();
    for (p, v) in reals.iter().zip(real_values) {
        // `{:?}` is the shortest text that reads back as the same f64.
        text.push_str(&format!("{} = {v:?}\n", p.name));
    }
    for ((name, _), v) in booleans.iter().zip(flags) {
        text.push_str(&format!("{name} = {v}\n"));
    }
    text
}

/// The values of [`values_text`]'s text, in the tables' orders: every parameter exactly once, each Real within
/// its range; the error names the line or the parameter missing.
pub fn read_values(
    text: &str,
    real_table: &[RealParameter],
    boolean_table: &[(&str, &str)],
) -> Result<(Vec<f64>, Vec<bool>), String> {
    let mut reals = vec![None; real_table.len()];
    let mut booleans = vec![None; boolean_table.len()];
    for (n, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let bad = |why: &str| format!("line {}: {why}: {line:?}", n + 1);
        let (name, value) = line.split_once('=').ok_or_else(|| bad("not `name = value`"))?;
        let (name, value) = (name.trim(), value.trim());
        if let Some(k) = real_table.iter().position(|p| p.name == name) {
            let v: f64 = value.parse().map_err(|_| bad("not a number"))?;
            check_real(&real_table[k], v).map_err(|e| bad(&e))?;
            if reals[k].replace(v).is_some() {
                return Err(bad("given twice"));
            }
        } else if let Some(k) = boolean_table.iter().position(|(b, _)| *b == name) {
            let v: bool = value.parse().map_err(|_| bad("not true or false"))?;
            if booleans[k].replace(v).is_some() {
                return Err(bad("given twice"));
            }
        } else {
            return Err(bad("no such parameter"));
        }
    }
    let missing = |name: &str| format!("parameter {name} not given");
    let reals = reals.iter().zip(real_table).map(|(v, p)| v.ok_or_else(|| missing(p.name)));
    let booleans = booleans.iter().zip(boolean_table).map(|(v, (name, _))| v.ok_or_else(|| missing(name)));
    Ok((reals.collect::<Result<_, _>>()?, booleans.collect::<Result<_, _>>()?))
}

/// `v` as a value of `p`: finite and within its range.
pub fn check_real(p: &RealParameter, v: f64) -> Result<(), String> {
    if !(v >= p.min && v <= p.max) {
        return Err(format!("{} = {v} is outside {}..{}", p.name, p.min, p.max));
    }
    Ok(())
}

/// An output: name, unit, and whether `trace.csv` shows it (the rig's announcement).
pub fn outputs() -> [(&'static str, &'static str, bool); OUTPUTS_LEN] {
    output_signals()
}

/// The inputs' variable names: the rig's input names ([`INPUTS`]), but `throttle_cmd` for its `throttle`, since
/// FMI needs one name per variable and `throttle` is the output that reports the throttle's position (in the rig,
/// inputs and outputs have names of their own). An importer that announces the FMU as the rig's plant names it
/// `throttle` again ([`rig_input_name`]).
pub const INPUT_NAMES: [&str; 4] = ["aileron", "elevator", "rudder", "throttle_cmd"];

/// The rig's name of the FMU input named `fmu_name` (`throttle` for `throttle_cmd`), if it is one.
pub fn rig_input_name(fmu_name: &str) -> Option<&'static str> {
    INPUT_NAMES.iter().position(|n| *n == fmu_name).map(|k| INPUTS[k].0)
}

/// The inputs: variable name, unit and the range of a command.
pub fn inputs() -> [(&'static str, &'static str, (f64, f64)); 4] {
    std::array::from_fn(|k| (INPUT_NAMES[k], INPUTS[k].1, input_range(k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_variable_name_is_unique() {
        let mut names: Vec<&str> = outputs().iter().map(|o| o.0).collect();
        names.extend(inputs().iter().map(|i| i.0));
        names.extend(REAL_PARAMETERS.iter().map(|p| p.name));
        names.extend(BOOLEAN_PARAMETERS.iter().map(|b| b.0));
        let count = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), count, "a name twice");
        assert_eq!(rig_input_name("throttle_cmd"), Some("throttle"));
        assert_eq!(rig_input_name("aileron"), Some("aileron"));
        assert_eq!(rig_input_name("throttle"), None);
    }

    #[test]
    fn parameters_survive_their_text_bit_for_bit() {
        let mut initial = InitialCondition { mode: InitialMode::Trim, throttle: Some(0.1 + 0.2), ..Default::default() };
        initial.phi_deg = 1.0 / 3.0;
        let model = F16Model::new(0.3).with_scales(ModelScales { aero: [1.1, 0.9, 1.0, 1.0, 1.2, 0.7], mass: 1.3 });
        let p = Parameters::new(&model, &initial, &ActuatorSetLimits::default(), true, false);
        let back = Parameters::from_text(&p.to_text()).unwrap();
        assert_eq!(back, p);
        assert_eq!(back.initial(), initial);
        assert_eq!(back.actuators(), ActuatorSetLimits::default());
        assert_eq!(back.model().scales, model.scales);
        assert!(back.forcing().speed_hold && !back.forcing().sideslip_hold);
    }

    #[test]
    fn a_bad_start_value_is_named() {
        let text = Parameters::default().to_text().replace("xcg = 0.35", "xcg = 1.5");
        assert_eq!(Parameters::from_text(&text).unwrap_err(), "line 1: xcg = 1.5 is outside 0..1: \"xcg = 1.5\"");
        let text = Parameters::default().to_text().replace("speed_hold = false\n", "");
        assert_eq!(Parameters::from_text(&text).unwrap_err(), "parameter speed_hold not given");
        let text = Parameters::default().to_text() + "flaps = 1\n";
        assert!(Parameters::from_text(&text).unwrap_err().contains("no such parameter"));
        let mut p = Parameters::default();
        p.reals[at::ACTUATORS + 1] = -30.0;
        assert_eq!(p.check().unwrap_err(), "aileron_min = -21.5 must be below aileron_max = -30");
    }
}
