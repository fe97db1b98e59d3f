//! Scenario files: everything a closed-loop run needs (initial condition, set points, disturbance, plant options,
//! controller gains, actuator limits, timing), as TOML with unit-suffixed keys. Unknown keys are errors; `validate`
//! names the key and the problem of any out-of-range value.

use crate::criteria::Criteria;
use crate::dispersion::Distribution;
use serde::{Deserialize, Serialize};
use silrig_model::actuator::{ActuatorLimits, ActuatorSetLimits, SURFACE_CMD_LIMIT_DEG};
use silrig_model::control::ControllerGains;
use std::collections::BTreeMap;
use std::path::Path;

/// The embedded default scenario (what `silrig sim` and `silrig run` use without a file).
pub const DEFAULT_SCENARIO_TOML: &str = include_str!("../../configs/robust.toml");
/// The embedded scenario for a plant of the user's own (what `silrig run` and `silrig check` fly it with without a
/// file): set points and timing, nothing of the F-16.
pub const ANY_PLANT_SCENARIO_TOML: &str = include_str!("../../configs/any-plant.toml");

/// A whole scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name, used for output folders and plot titles.
    pub name: String,
    /// What the scenario shows.
    #[serde(default)]
    pub description: String,
    /// Seed for every random source of the run.
    #[serde(default)]
    pub seed: u64,
    /// The F-16's initial condition (default: the embedded default's, explicit at 150 m/s and 25,000 ft); a plant
    /// of your own takes its start values from `[plant.parameters]`.
    #[serde(default)]
    pub initial: InitialCondition,
    /// Set points: the F-16 controller's attitude, and any other output by name.
    #[serde(default)]
    pub setpoint: Setpoint,
    /// Set points that change during the run (`[[setpoint_steps]]`), in time order; none: `[setpoint]` throughout.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub setpoint_steps: Vec<SetpointStep>,
    /// Disturbance on the Euler-angle accelerations.
    #[serde(default)]
    pub disturbance: Disturbance,
    /// Plant options.
    #[serde(default)]
    pub plant: PlantOptions,
    /// Controller gains (our controller's), or the controller FMU the controller process flies instead.
    #[serde(default)]
    pub controller: ControllerOptions,
    /// Actuator limits and lags by input name (`[actuators.<input>]`): for the F-16 any of its four, the book's for
    /// those not given; for a plant of your own, the rig's actuator model on exactly the inputs named.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub actuators: BTreeMap<String, ActuatorLimits>,
    /// Step, duration and command timing.
    pub timing: Timing,
    /// The fault plan (`[[faults]]`), in any order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<crate::fault::Fault>,
    /// Monte Carlo dispersions (`silrig sweep`): a distribution per dotted scenario key. A single run flies the
    /// nominal values.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub dispersions: BTreeMap<String, Distribution>,
    /// What each case of a sweep must meet (the flight criteria of `silrig check`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub criteria: Option<Criteria>,
}

/// How the run starts, and its mode: the vehicle's own ([`silrig_model::vehicle`]), kept here under their old names.
pub use silrig_model::vehicle::{InitialCondition, InitialMode};

pub use crate::setpoints::{Setpoint, SetpointStep, SetpointTrack};

pub use crate::disturbance::Disturbance;

/// The built-in vehicle a scenario flies (`[plant] model`) when no plant of your own replaces it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BuiltinVehicle {
    /// The Stevens & Lewis F-16 (the default).
    #[default]
    F16,
    /// The X quadrotor ([`crate::quad`]): its parameters and start values in `[plant.parameters]`.
    Quad,
}

impl BuiltinVehicle {
    fn is_f16(&self) -> bool {
        *self == BuiltinVehicle::F16
    }
}

/// Plant options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlantOptions {
    /// Which built-in vehicle flies: `"f16"` (default) or `"quad"`. Left out of a scenario written down when it is
    /// the F-16, so the F-16's scenarios read as they always have.
    #[serde(default, skip_serializing_if = "BuiltinVehicle::is_f16")]
    pub model: BuiltinVehicle,
    /// Freeze the airspeed (VT_dot = 0), as the paper assumes.
    #[serde(default)]
    pub speed_hold: bool,
    /// Freeze the sideslip (beta_dot = 0), as the paper's derivation assumes: for reproducing its figures only (see
    /// [`silrig_model::plant::ExternalForcing::sideslip_hold`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sideslip_hold: bool,
    /// CG position, fraction of the mean chord.
    #[serde(default = "default_xcg")]
    pub xcg: f64,
    /// Multipliers on the total aerodynamic coefficients (uncertainty; 1: the book's data).
    #[serde(default)]
    pub aero_scale: AeroScale,
    /// Multiplier on the mass and the inertias together (uncertainty; 1: the book's aircraft).
    #[serde(default = "one")]
    pub mass_scale: f64,
    /// Parameters and start values of a plant of your own, by the names it reads them with
    /// (`silrig_plant_parameter`; an FMU's: its variables' names; numbers only): dispersions reach them as
    /// `plant.parameters.<name>`. The F-16's are the keys above.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, f64>,
    /// A co-simulation FMU (FMI 2.0 or 3.0) the plant process flies in place of the F-16; a relative path is
    /// relative to the scenario file's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fmu: Option<std::path::PathBuf>,
    /// The largest fraction of ticks whose outputs the rig may refuse (NaN, infinity) and hold at the last valid
    /// ones before the run fails: past it, the flight is more the rig's stand-in than the model's.
    #[serde(default = "default_outputs_held", skip_serializing_if = "is_default_outputs_held")]
    pub outputs_held_fraction_max: f64,
}

/// One tick in a hundred: a model's rare hiccup passes, one that broke down does not.
const OUTPUTS_HELD_FRACTION_MAX: f64 = 0.01;

fn default_outputs_held() -> f64 {
    OUTPUTS_HELD_FRACTION_MAX
}

fn is_default_outputs_held(v: &f64) -> bool {
    *v == OUTPUTS_HELD_FRACTION_MAX
}

fn default_xcg() -> f64 {
    silrig_model::plant::aero::XCG_REF
}

fn one() -> f64 {
    1.0
}

impl Default for PlantOptions {
    fn default() -> Self {
        Self {
            model: BuiltinVehicle::F16,
            speed_hold: false,
            sideslip_hold: false,
            xcg: default_xcg(),
            aero_scale: AeroScale::default(),
            mass_scale: 1.0,
            parameters: BTreeMap::new(),
            fmu: None,
            outputs_held_fraction_max: OUTPUTS_HELD_FRACTION_MAX,
        }
    }
}

/// `[controller]`: our controller's gains (the keys of [`ControllerGains`], which it dereferences to), or a
/// controller FMU flown in its place with the keys `fmu`, `[controller.map]` and `[controller.parameters]`, or a
/// device over UDP with the key `device` (its layout file).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ControllerOptions {
    /// The paper's controller's gains (what `silrig-controller` flies without an FMU).
    #[serde(flatten)]
    pub gains: ControllerGains,
    /// A co-simulation FMU (FMI 2.0 or 3.0) the controller process flies in place of ours; a relative path is
    /// relative to the scenario file's folder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fmu: Option<std::path::PathBuf>,
    /// A device over UDP flown in place of ours: its layout file (`configs/devices/*.toml`); a relative path is
    /// relative to the scenario file's folder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub device: Option<std::path::PathBuf>,
    /// FMU variable name = plant signal name, for the variables whose names differ from the plant's signals (an
    /// FMU input takes the plant output, or the set point `<output>_sp`, it is mapped to, or a constant; an FMU
    /// output commands the plant input it is mapped to).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub map: BTreeMap<String, crate::controller_map::MapTarget>,
    /// The controller FMU's parameters by variable name, set before its initialization.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, f64>,
}

impl std::ops::Deref for ControllerOptions {
    type Target = ControllerGains;
    fn deref(&self) -> &ControllerGains {
        &self.gains
    }
}

impl std::ops::DerefMut for ControllerOptions {
    fn deref_mut(&mut self) -> &mut ControllerGains {
        &mut self.gains
    }
}

// By hand, not with `#[serde(flatten)]`: a flattened struct never sees the keys it does not know, so a misspelt
// gain would pass silently. The FMU's keys are taken out and the rest must be exactly the gains' keys.
impl<'de> Deserialize<'de> for ControllerOptions {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut table = toml::Table::deserialize(deserializer)?;
        let mut take = |key: &str| table.remove(key);
        let fmu = take("fmu")
            .map(|v| v.try_into::<std::path::PathBuf>())
            .transpose()
            .map_err(|e| D::Error::custom(format!("controller.fmu: {e}")))?;
        let device = take("device")
            .map(|v| v.try_into::<std::path::PathBuf>())
            .transpose()
            .map_err(|e| D::Error::custom(format!("controller.device: {e}")))?;
        if fmu.is_some() && device.is_some() {
            return Err(D::Error::custom("controller: `fmu` and `device` each name the controller; keep one of them"));
        }
        let map = take("map")
            .map(crate::controller_map::from_toml)
            .transpose()
            .map_err(|e| D::Error::custom(format!("controller.map: {e}")))?
            .unwrap_or_default();
        let parameters = take("parameters")
            .map(|v| v.try_into::<BTreeMap<String, f64>>())
            .transpose()
            .map_err(|e| D::Error::custom(format!("controller.parameters: {e}")))?
            .unwrap_or_default();
        // A `[controller]` that only names an FMU leaves our controller's gains at their defaults (unused); one
        // that gives any gain gives them as before.
        let gains = if table.is_empty() {
            ControllerGains::default()
        } else {
            toml::Value::Table(table)
                .try_into::<ControllerGains>()
                .map_err(|e| D::Error::custom(format!("controller: {e}")))?
        };
        Ok(Self { gains, fmu, device, map, parameters })
    }
}

/// Multipliers on the total body-axis aerodynamic coefficients, each within 0..3 (1: the book's data).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AeroScale {
    /// Axial force.
    #[serde(default = "one")]
    pub cx: f64,
    /// Side force.
    #[serde(default = "one")]
    pub cy: f64,
    /// Normal force.
    #[serde(default = "one")]
    pub cz: f64,
    /// Rolling moment.
    #[serde(default = "one")]
    pub cl: f64,
    /// Pitching moment.
    #[serde(default = "one")]
    pub cm: f64,
    /// Yawing moment.
    #[serde(default = "one")]
    pub cn: f64,
}

impl Default for AeroScale {
    fn default() -> Self {
        Self { cx: 1.0, cy: 1.0, cz: 1.0, cl: 1.0, cm: 1.0, cn: 1.0 }
    }
}

impl PlantOptions {
    /// The F-16 model these options describe (CG and uncertainty scales): the one place a model is built from a
    /// scenario.
    pub fn model(&self) -> silrig_model::plant::F16Model {
        let a = &self.aero_scale;
        silrig_model::plant::F16Model::new(self.xcg).with_scales(silrig_model::plant::ModelScales {
            aero: [a.cx, a.cy, a.cz, a.cl, a.cm, a.cn],
            mass: self.mass_scale,
        })
    }
}

pub use crate::timing::{CommandTiming, MAX_TICKS, MAX_TRANSPORT_DELAY_TICKS, Timing};

/// Find the value at a dotted key (`initial.phi_deg`, `actuators.elevator_deg.rate_limit_per_s`,
/// `controller.adaptation_gain.0`, `faults.1.std`) in a scenario's TOML tree.
/// (see [`Scenario::with_values`])
fn lookup<'a>(root: &'a mut toml::Table, key: &str) -> Result<&'a mut toml::Value, String> {
    let mut parts = key.split('.');
    let first = parts.next().unwrap_or_default();
    let mut node = root.get_mut(first).ok_or_else(|| format!("`{key}`: the scenario has no `{first}`"))?;
    for part in parts {
        node = match node {
            toml::Value::Table(t) => {
                t.get_mut(part).ok_or_else(|| format!("`{key}`: the scenario has no `{part}` there"))?
            }
            toml::Value::Array(a) => {
                let i: usize = part.parse().map_err(|_| format!("`{key}`: `{part}` must be an index into a list"))?;
                let len = a.len();
                a.get_mut(i).ok_or_else(|| format!("`{key}`: index {i} is beyond the list's {len} entries"))?
            }
            _ => return Err(format!("`{key}`: `{part}` is below a value, not a table or list")),
        };
    }
    Ok(node)
}

impl Scenario {
    /// The scenario with each dotted key set to a value (a dispersion sample), without dispersions of its own,
    /// validated; an error names the key.
    pub fn with_values(&self, values: &[(String, f64)]) -> Result<Scenario, String> {
        let mut tree: toml::Table = toml::from_str(&self.to_toml()).map_err(|e| e.to_string())?;
        for (key, value) in values {
            let node = lookup(&mut tree, key)?;
            match node {
                toml::Value::Float(_) => *node = toml::Value::Float(*value),
                // A count (ticks) takes the sampled value rounded to the nearest whole number.
                toml::Value::Integer(_) => *node = toml::Value::Integer(value.round() as i64),
                other => return Err(format!("`{key}` is a {}, not a number", other.type_str())),
            }
        }
        let mut scenario: Scenario = toml::Table::try_into(tree).map_err(|e: toml::de::Error| e.to_string())?;
        // A sampled scenario is one case: it carries no dispersions of its own.
        scenario.dispersions.clear();
        scenario.validate().map_err(|(key, problem)| format!("`{key}`: {problem}"))?;
        Ok(scenario)
    }

    /// Check every dispersion: its distribution, and that its key names a number in the scenario.
    fn validate_dispersions(&self) -> Result<(), (String, String)> {
        if self.dispersions.is_empty() {
            return Ok(());
        }
        let mut tree: toml::Table = toml::from_str(&self.to_toml()).map_err(|e| (String::new(), e.to_string()))?;
        for (key, dist) in &self.dispersions {
            let at = format!("dispersions.\"{key}\"");
            dist.validate().map_err(|e| (at.clone(), e))?;
            let node =
                lookup(&mut tree, key).map_err(|e| (at.clone(), format!("no such key in the scenario ({e})")))?;
            if !matches!(node, toml::Value::Float(_) | toml::Value::Integer(_)) {
                return Err((at, format!("is a {}, not a number", node.type_str())));
            }
        }
        Ok(())
    }
}

/// The F-16's inputs as `[actuators.<input>]` names them (its input's name, or the key its scenarios have always
/// used), with the travel each may be given.
pub const F16_ACTUATORS: [(&str, &str, (f64, f64)); 4] = [
    ("aileron", "aileron_deg", (-SURFACE_CMD_LIMIT_DEG, SURFACE_CMD_LIMIT_DEG)),
    ("elevator", "elevator_deg", (-SURFACE_CMD_LIMIT_DEG, SURFACE_CMD_LIMIT_DEG)),
    ("rudder", "rudder_deg", (-SURFACE_CMD_LIMIT_DEG, SURFACE_CMD_LIMIT_DEG)),
    ("throttle", "throttle", (0.0, 1.0)),
];

impl Scenario {
    /// The F-16's four actuators: those `[actuators]` names, the book's for the others.
    pub fn f16_actuators(&self) -> ActuatorSetLimits {
        let book = ActuatorSetLimits::default();
        let get = |k: usize, default: ActuatorLimits| {
            let (input, key, _) = F16_ACTUATORS[k];
            self.actuators.get(input).or_else(|| self.actuators.get(key)).copied().unwrap_or(default)
        };
        ActuatorSetLimits {
            aileron_deg: get(0, book.aileron_deg),
            elevator_deg: get(1, book.elevator_deg),
            rudder_deg: get(2, book.rudder_deg),
            throttle: get(3, book.throttle),
        }
    }
}

/// A scenario that cannot be used, with where the problem is.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        cause: std::io::Error,
    },
    /// Malformed TOML or an unknown or mistyped key.
    #[error("{origin}: {message}")]
    Parse {
        /// File name or "embedded default".
        origin: String,
        /// The parser's message, which names the key and position.
        message: String,
    },
    /// A value out of range.
    #[error("{origin}: `{key}`: {problem}")]
    Invalid {
        /// File name or "embedded default".
        origin: String,
        /// The key, dotted.
        key: String,
        /// What is wrong.
        problem: String,
    },
}

impl Scenario {
    /// Parse and validate TOML text; `origin` names the source in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, ScenarioError> {
        let scenario: Scenario = toml::from_str(text)
            .map_err(|e| ScenarioError::Parse { origin: origin.into(), message: e.to_string().trim_end().into() })?;
        scenario.validate().map_err(|(key, problem)| ScenarioError::Invalid { origin: origin.into(), key, problem })?;
        Ok(scenario)
    }

    /// Read, parse and validate a scenario file.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path)
            .map_err(|cause| ScenarioError::Io { path: path.display().to_string(), cause })?;
        let mut scenario = Self::from_toml(&text, &path.display().to_string())?;
        scenario.files_beside(path);
        Ok(scenario)
    }

    /// Make the files the scenario names (plant and controller FMUs, a device's layout) absolute, a relative one
    /// read beside the scenario file `path`: so the scenario means the same files wherever a run (or a check's
    /// case) writes it down.
    pub fn files_beside(&mut self, path: &Path) {
        let dir = path.parent().unwrap_or(Path::new(""));
        let controller = &mut self.controller;
        let files = self.plant.fmu.iter_mut().chain(controller.fmu.iter_mut()).chain(controller.device.iter_mut());
        for file in files.filter(|f| f.is_relative()) {
            let beside = dir.join(&*file);
            *file = std::path::absolute(&beside).unwrap_or(beside);
        }
    }

    /// The embedded default scenario.
    pub fn embedded_default() -> Self {
        Self::from_toml(DEFAULT_SCENARIO_TOML, "embedded default").expect("the embedded default scenario is valid")
    }

    /// The embedded scenario for a plant of the user's own ([`ANY_PLANT_SCENARIO_TOML`]).
    pub fn embedded_any_plant() -> Self {
        Self::from_toml(ANY_PLANT_SCENARIO_TOML, "embedded any-plant")
            .expect("the embedded any-plant scenario is valid")
    }

    /// The set point `name` in force at `t_s`: the last of `[[setpoint_steps]]` at or before `t_s` that changes it,
    /// else `[setpoint]`'s; `None` when the scenario gives no set point `name`. Without steps it is `[setpoint]`'s
    /// value itself, the same number at every time.
    pub fn setpoint_at(&self, name: &str, t_s: f64) -> Option<f64> {
        crate::setpoints::value_at(&self.setpoint, &self.setpoint_steps, name, t_s)
    }

    /// The history of set point `name` over the run, for a reader that keeps it (`None`: no set point `name`).
    pub fn setpoint_track(&self, name: &str) -> Option<SetpointTrack> {
        SetpointTrack::of(&self.setpoint, &self.setpoint_steps, name)
    }

    /// phi, theta and psi's set points over the run, deg: the attitude our controllers fly.
    pub fn attitude_setpoints(&self) -> [SetpointTrack; 3] {
        ["phi_deg", "theta_deg", "psi_deg"].map(|n| self.setpoint_track(n).expect("the three angles always have one"))
    }

    /// The scenario as TOML (what a run records next to its outputs).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scenario serialises")
    }

    /// Check every value; on error return (dotted key, problem).
    pub fn validate(&self) -> Result<(), (String, String)> {
        if self.name.trim().is_empty() || !self.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return refuse("name", format!("must be non-empty letters, digits, '-' or '_', got {:?}", self.name));
        }
        self.validate_initial()?;
        self.setpoint.validate().map_err(|(key, problem)| (format!("setpoint.{key}"), problem))?;
        self.validate_plant()?;
        self.validate_named_values()?;
        let t = &self.timing;
        t.validate()?;
        crate::setpoints::validate_steps(&self.setpoint, &self.setpoint_steps, t.duration_s)?;
        for (i, f) in self.faults.iter().enumerate() {
            f.validate(t.duration_s).map_err(|(key, problem)| (format!("faults[{i}].{key}"), problem))?;
            // The same fault twice would be injected twice; a plan that means it twice gives two times.
            if let Some(j) = self.faults[..i].iter().position(|g| g == f) {
                return refuse(&format!("faults[{i}]"), format!("{} is faults[{j}] again: give it once", f.describe()));
            }
        }
        if let Some(c) = &self.criteria {
            if let Some(rig) = c.rig_criteria_set().first() {
                return refuse(
                    &format!("criteria.{rig}"),
                    "is judged by `silrig check` on the rig; a scenario's [criteria] (for sweeps) takes the flight \
                     criteria only"
                        .into(),
                );
            }
            c.validate_flight(t.duration_s, &|name| self.setpoint.get(name).is_some())
                .map_err(|e| ("criteria".to_string(), e))?;
        }
        self.validate_dispersions()?;
        Ok(())
    }

    /// `[initial]`: the F-16's initial state within the ranges its tables and equations cover.
    fn validate_initial(&self) -> Result<(), (String, String)> {
        let i = &self.initial;
        if !(i.airspeed_mps > 0.0 && i.airspeed_mps <= 400.0) {
            return refuse("initial.airspeed_mps", format!("must be within (0, 400], got {}", i.airspeed_mps));
        }
        if !(0.0..=50_000.0).contains(&i.altitude_ft) {
            return refuse("initial.altitude_ft", format!("must be within 0..50000, got {}", i.altitude_ft));
        }
        for (key, v, limit) in [
            ("initial.alpha_deg", i.alpha_deg, 45.0),
            ("initial.beta_deg", i.beta_deg, 30.0),
            ("initial.phi_deg", i.phi_deg, 180.0),
            ("initial.theta_deg", i.theta_deg, 80.0),
            ("initial.psi_deg", i.psi_deg, 180.0),
            ("initial.p_dps", i.p_dps, 360.0),
            ("initial.q_dps", i.q_dps, 360.0),
            ("initial.r_dps", i.r_dps, 360.0),
        ] {
            finite(key, v)?;
            if v.abs() > limit {
                return refuse(key, format!("must be within -{limit}..{limit}, got {v}"));
            }
        }
        if let Some(t) = i.throttle
            && !(0.0..=1.0).contains(&t)
        {
            return refuse("initial.throttle", format!("must be within 0..1, got {t}"));
        }
        Ok(())
    }

    /// `[disturbance]` and `[plant]`: what acts on the F-16 and how it differs from the tables.
    fn validate_plant(&self) -> Result<(), (String, String)> {
        self.disturbance.validate()?;
        if !(0.0..=1.0).contains(&self.plant.xcg) {
            return refuse("plant.xcg", format!("must be a fraction of the chord in 0..1, got {}", self.plant.xcg));
        }
        let a = &self.plant.aero_scale;
        for (key, v) in [("cx", a.cx), ("cy", a.cy), ("cz", a.cz), ("cl", a.cl), ("cm", a.cm), ("cn", a.cn)] {
            if !(0.0..=3.0).contains(&v) {
                return refuse(&format!("plant.aero_scale.{key}"), format!("must be within 0..3, got {v}"));
            }
        }
        if !(self.plant.mass_scale >= 0.5 && self.plant.mass_scale <= 2.0) {
            return refuse("plant.mass_scale", format!("must be within 0.5..2, got {}", self.plant.mass_scale));
        }
        let held = self.plant.outputs_held_fraction_max;
        if !(0.0..=1.0).contains(&held) {
            return refuse(
                "plant.outputs_held_fraction_max",
                format!("must be a fraction of the ticks in 0..1, got {held}"),
            );
        }
        Ok(())
    }

    /// The controller's options, the actuators, parameters and the controller map: values by name.
    fn validate_named_values(&self) -> Result<(), (String, String)> {
        self.controller.validate().map_err(|e| {
            let key = e.split([' ', '[', ':']).next().unwrap_or("").to_string();
            (format!("controller.{key}"), e)
        })?;
        for (name, a) in &self.actuators {
            // Any travel here: the plant's own ranges are known when it announces them ([`crate::sim::check_for_f16`],
            // `silrig_flight::signal_chain`).
            a.validate((f64::NEG_INFINITY, f64::INFINITY)).map_err(|e| (format!("actuators.{name}"), e))?;
        }
        for (name, v) in &self.plant.parameters {
            finite(&format!("plant.parameters.{name}"), *v)?;
        }
        for (name, v) in &self.controller.parameters {
            finite(&format!("controller.parameters.{name}"), *v)?;
        }
        for (variable, target) in &self.controller.map {
            target.check().map_err(|e| (format!("controller.map.{variable}"), e))?;
        }
        Ok(())
    }
}

/// A scenario refused: the dotted key and the problem.
pub(crate) fn refuse(key: &str, problem: String) -> Result<(), (String, String)> {
    Err((key.to_string(), problem))
}

/// `v` is a finite number, or the key is refused saying so.
fn finite(key: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() { Ok(()) } else { refuse(key, format!("must be a finite number, got {v}")) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controller_options_without_an_fmu_write_exactly_the_gains() {
        // The effective scenario a run writes down, and every dispersion applied through TOML, must not change
        // because the gains now sit inside `ControllerOptions`.
        let s = Scenario::embedded_default();
        assert_eq!(toml::to_string(&s.controller).unwrap(), toml::to_string(&s.controller.gains).unwrap());
    }

    #[test]
    fn controller_fmu_keys_round_trip_and_unknown_keys_are_still_refused() {
        // The default scenario's [controller] table, with the FMU's keys added to it.
        assert!(DEFAULT_SCENARIO_TOML.contains("\n[controller]\n"));
        let text = DEFAULT_SCENARIO_TOML.replace(
            "\n[controller]\n",
            "\n[controller]\nfmu = \"pid.fmu\"\nmap = { pitch = \"theta_deg\" }\nparameters = { kp_phi = 1.5 }\n",
        );
        let s = Scenario::from_toml(&text, "test").unwrap();
        assert_eq!(s.controller.fmu.as_deref(), Some(Path::new("pid.fmu")));
        assert_eq!(s.controller.map["pitch"], crate::controller_map::MapTarget::Signal("theta_deg".into()));
        assert_eq!(s.controller.parameters["kp_phi"], 1.5);
        assert_eq!(Scenario::from_toml(&s.to_toml(), "again").unwrap(), s);
        let typo = text.replace("fmu = \"pid.fmu\"", "fmu = \"pid.fmu\"\nswitching_gain = 3");
        let e = Scenario::from_toml(&typo, "typo").unwrap_err().to_string();
        assert!(e.contains("switching_gain"), "{e}");
        // Naming only the FMU leaves the gains at their defaults.
        let only = "name = \"x\"\n[timing]\ndt_s = 0.01\nduration_s = 1.0\ncommand_timing = \"next-tick\"\n\
                    [controller]\nfmu = \"pid.fmu\"\n";
        let s = Scenario::from_toml(only, "only").unwrap();
        assert_eq!(s.controller.gains, ControllerGains::default());
        let bad = text.replace("pitch = \"theta_deg\"", "pitch = \"theta deg\"");
        let e = Scenario::from_toml(&bad, "bad").unwrap_err().to_string();
        assert!(e.contains("controller.map.pitch"), "{e}");
    }

    #[test]
    fn a_device_is_one_controller_key_and_not_beside_an_fmu() {
        let only = "name = \"x\"\n[timing]\ndt_s = 0.01\nduration_s = 1.0\ncommand_timing = \"same-tick\"\n\
                    [controller]\ndevice = \"devices/fake.toml\"\n";
        let s = Scenario::from_toml(only, "only").unwrap();
        assert_eq!(s.controller.device.as_deref(), Some(Path::new("devices/fake.toml")));
        assert_eq!(s.controller.gains, ControllerGains::default());
        assert_eq!(Scenario::from_toml(&s.to_toml(), "again").unwrap(), s);
        let both = only.replace("[controller]\n", "[controller]\nfmu = \"pid.fmu\"\n");
        let e = Scenario::from_toml(&both, "both").unwrap_err().to_string();
        assert!(e.contains("`fmu` and `device` each name the controller; keep one of them"), "{e}");
    }
}
