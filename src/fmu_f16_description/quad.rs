//! What the quadrotor's FMU is: its variables (the outputs and motor commands the rig announces for `[plant] model
//! = "quad"`, and the parameters of `[plant.parameters]` by the same names), their start values as the exported FMU
//! carries them, and its generated `modelDescription.xml`. The binary is the F-16's (one library serves both
//! vehicles); the start file's first line, [`MODEL_LINE`], tells it which vehicle to fly.

use crate::description::{Experiment, Header, experiment_text, guid_of, render_xml, scalar_variable, split_experiment};
use crate::variables::{RealParameter, check_real, read_values, values_text};
use silrig_model::quad::QuadVehicle;
use silrig_model::quad::outputs::{INPUT_RANGE, INPUTS, OUTPUTS, PLANT_NAME};
use silrig_model::quad::params::{PARAMS, QuadParams, START_VALUES};

/// The model identifier: the binary's file name in `binaries/<platform>/` and the FMU's name.
pub const QUAD_MODEL_IDENTIFIER: &str = "silrig_fmu_quad";

/// The first line of the quadrotor FMU's start file: the F-16's has none.
pub const MODEL_LINE: &str = "model = quad";

/// Value reference of the first input (the outputs come first, 0.., in the rig's announced order).
pub const QUAD_FIRST_INPUT_VR: u32 = OUTPUTS.len() as u32;
/// Value reference of the first parameter (after the four motor commands).
pub const QUAD_FIRST_PARAMETER_VR: u32 = QUAD_FIRST_INPUT_VR + INPUTS.len() as u32;

/// Number of parameters: the vehicle's, then its start values.
const N_PARAMETERS: usize = PARAMS.len() + START_VALUES.len();

/// The parameters, in value-reference order from [`QUAD_FIRST_PARAMETER_VR`]: the vehicle's ([`PARAMS`]) and its
/// start values ([`START_VALUES`]), named and ranged as `[plant.parameters]` takes them.
pub fn quad_parameters() -> [RealParameter; N_PARAMETERS] {
    std::array::from_fn(|k| {
        let p = if k < PARAMS.len() { &PARAMS[k] } else { &START_VALUES[k - PARAMS.len()] };
        RealParameter { name: p.name, unit: p.unit, min: p.min, max: p.max, description: p.description }
    })
}

/// The quadrotor's parameters' values, in [`quad_parameters`] order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadStarts {
    /// The values.
    pub reals: [f64; N_PARAMETERS],
}

impl Default for QuadStarts {
    /// RotorS's Hummingbird at rest on the ground, heading north.
    fn default() -> Self {
        Self::new(&QuadParams::default(), 0.0, 0.0)
    }
}

impl QuadStarts {
    /// The vehicle's parameters with its start height (m) and heading (deg).
    pub fn new(params: &QuadParams, start_alt_m: f64, start_psi_deg: f64) -> Self {
        let mut reals = [0.0; N_PARAMETERS];
        for (r, p) in reals.iter_mut().zip(&PARAMS) {
            *r = params.get(p.name).unwrap_or(f64::NAN);
        }
        reals[PARAMS.len()] = start_alt_m;
        reals[PARAMS.len() + 1] = start_psi_deg;
        Self { reals }
    }

    /// The vehicle at t = 0, as `silrig_flight::quad::quad_vehicle` builds it from a scenario; the error names the
    /// parameter.
    pub fn vehicle(&self) -> Result<QuadVehicle, String> {
        let table = quad_parameters();
        for (p, v) in table.iter().zip(self.reals) {
            check_real(p, v)?;
        }
        let mut params = QuadParams::default();
        for (p, v) in PARAMS.iter().zip(self.reals) {
            params.set(p.name, v).map_err(|e| e.to_string())?;
        }
        let (alt_m, psi_deg) = (self.reals[PARAMS.len()], self.reals[PARAMS.len() + 1]);
        QuadVehicle::at_start(params, alt_m, psi_deg.to_radians()).map_err(|e| e.to_string())
    }

    /// The inputs' start values: the motor commands at t = 0 (0 on the ground, the hover command in the air).
    pub fn input_starts(&self) -> Result<[f64; 4], String> {
        Ok(self.vehicle()?.motor_commands)
    }

    /// `name = value` a line, which [`QuadStarts::from_text`] reads back bit for bit.
    pub fn to_text(&self) -> String {
        values_text(&quad_parameters(), &self.reals, &[], &[])
    }

    /// The values of [`QuadStarts::to_text`]'s text, every one once and within its range, the set able to fly; the
    /// error names the line or the parameter.
    pub fn from_text(text: &str) -> Result<Self, String> {
        let (reals, _) = read_values(text, &quad_parameters(), &[])?;
        let starts = Self { reals: reals.try_into().map_err(|_| "the quadrotor's parameters")? };
        starts.vehicle()?;
        Ok(starts)
    }
}

/// The quadrotor FMU's start file: [`MODEL_LINE`], the parameters' start values and the default experiment.
pub fn quad_start_file(s: &QuadStarts, e: &Experiment) -> String {
    format!("{MODEL_LINE}\n{}{}", s.to_text(), experiment_text(e))
}

/// Read [`quad_start_file`]'s text back, bit for bit; `None` when it is not the quadrotor's (no [`MODEL_LINE`]
/// first).
pub fn read_quad_start_file(text: &str) -> Option<Result<(QuadStarts, Experiment), String>> {
    let rest = text.strip_prefix(MODEL_LINE)?.strip_prefix('\n')?;
    Some(split_experiment(rest).and_then(|(values, e)| Ok((QuadStarts::from_text(&values)?, e))))
}

const HEADER: Header = Header {
    model_name: "silrig_quad",
    description: "The X quadrotor of silrig (RotorS's AscTec Hummingbird by default): the built-in plant of `[plant] model = \"quad\"`, one doStep one tick",
    model_identifier: QUAD_MODEL_IDENTIFIER,
    plant: PLANT_NAME,
};

/// Every `<ScalarVariable>` (outputs, inputs, parameters) and the units they use.
fn model_variables(s: &QuadStarts, input_starts: &[f64; 4]) -> (String, Vec<&'static str>) {
    let mut units = Vec::new();
    let mut variables = String::new();
    for (vr, (name, unit)) in OUTPUTS.iter().enumerate() {
        let what = format!("output of the built-in quadrotor, {unit}; a trace.csv column");
        let element = format!("<Real unit=\"{unit}\"/>");
        variables.push_str(&scalar_variable(name, vr as u32, "output", "continuous", &what, &element));
        units.push(*unit);
    }
    let (min, max) = INPUT_RANGE;
    for (k, (name, unit)) in INPUTS.iter().enumerate() {
        let what = format!(
            "{name} command, 0..1 of the rotor's top speed (the rig's input `{name}`); start: the command at t = 0"
        );
        let start = input_starts[k];
        let element = format!("<Real unit=\"{unit}\" min=\"{min:?}\" max=\"{max:?}\" start=\"{start:?}\"/>");
        variables.push_str(&scalar_variable(
            name,
            QUAD_FIRST_INPUT_VR + k as u32,
            "input",
            "continuous",
            &what,
            &element,
        ));
        units.push(*unit);
    }
    for (k, (p, v)) in quad_parameters().iter().zip(s.reals).enumerate() {
        let what = format!("{} (plant.parameters.{})", p.description, p.name);
        let element = format!("<Real unit=\"{}\" min=\"{:?}\" max=\"{:?}\" start=\"{v:?}\"/>", p.unit, p.min, p.max);
        let vr = QUAD_FIRST_PARAMETER_VR + k as u32;
        variables.push_str(&scalar_variable(p.name, vr, "parameter", "fixed", &what, &element));
        units.push(p.unit);
    }
    (variables, units)
}

fn render(s: &QuadStarts, e: &Experiment, guid: &str) -> Result<String, String> {
    let (variables, units) = model_variables(s, &s.input_starts()?);
    Ok(render_xml(&HEADER, &variables, units, OUTPUTS.len(), e, guid))
}

/// The GUID of the quadrotor's description of these start values and experiment (the hash of its text with the
/// GUID left empty).
pub fn quad_guid(s: &QuadStarts, e: &Experiment) -> Result<String, String> {
    Ok(guid_of(&render(s, e, "")?))
}

/// The quadrotor's `modelDescription.xml`; the error says why the start values give no vehicle.
pub fn quad_model_description(s: &QuadStarts, e: &Experiment) -> Result<String, String> {
    render(s, e, &quad_guid(s, e)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_start_file_reads_back_and_the_guid_follows_it() {
        let e = Experiment { stop_time_s: 10.0, step_s: 0.001 };
        let mut params = QuadParams::default();
        params.set("mass_kg", 0.1 + 0.2 + 0.4).unwrap();
        let s = QuadStarts::new(&params, 2.5, 1.0 / 3.0);
        let text = quad_start_file(&s, &e);
        assert_eq!(read_quad_start_file(&text), Some(Ok((s, e))));
        assert_eq!(read_quad_start_file("xcg = 0.35\n"), None, "the F-16's has no model line");
        let xml = quad_model_description(&s, &e).unwrap();
        let g = quad_guid(&s, &e).unwrap();
        assert!(xml.contains(&format!("guid=\"{g}\"")) && xml.contains("modelIdentifier=\"silrig_fmu_quad\""));
        assert_ne!(quad_guid(&QuadStarts::default(), &e).unwrap(), g);
        assert_eq!(xml.matches("<ScalarVariable").count(), 27 + 4 + 18);
        assert!(xml.contains("<Tool name=\"silrig\"><Plant name=\"quad\"/></Tool>"), "{xml}");
        // In the air the motors start at the hover command; on the ground, stopped.
        let hover = params.hover_command();
        assert_eq!(s.input_starts().unwrap(), [hover; 4]);
        assert_eq!(QuadStarts::default().input_starts().unwrap(), [0.0; 4]);
    }

    #[test]
    fn a_start_file_that_cannot_fly_is_named() {
        let e = Experiment { stop_time_s: 1.0, step_s: 0.001 };
        let text = quad_start_file(&QuadStarts::default(), &e);
        let bad = text.replace("mass_kg = 0.68", "mass_kg = 5.0");
        let err = read_quad_start_file(&bad).unwrap().unwrap_err();
        assert!(err.contains("cannot hover"), "{err}");
        let bad = text.replace("start_alt_m = 0.0", "start_alt_m = -2.0");
        let err = read_quad_start_file(&bad).unwrap().unwrap_err();
        assert!(err.contains("start_alt_m = -2 is outside 0..1000"), "{err}");
        let bad = text.replace("arm_m = 0.17\n", "");
        assert_eq!(read_quad_start_file(&bad).unwrap().unwrap_err(), "parameter arm_m not given");
    }
}
