//! The quadrotor as a scenario flies it (`[plant] model = "quad"`): its parameters and start values from
//! `[plant.parameters]` over RotorS's Hummingbird ([`silrig_model::quad::params`]), its announcement (the model's
//! output and input tables, the failsafe holding the hover command), the set points our controller flies, and what
//! only the quadrotor can check: every key of the F-16's refused, saying what to use instead.

use crate::scenario::{BuiltinVehicle, PlantOptions, Scenario};
use crate::signal_chain::SignalChain;
use crate::signals::{InputSignal, OutputSignal, PlantSignals};
use silrig_model::control::quad::QuadSetpoint;
use silrig_model::quad::QuadVehicle;
use silrig_model::quad::outputs::{INPUT_RANGE, INPUTS, OUTPUTS, PLANT_NAME};
use silrig_model::quad::params::{PARAMS, QuadParams};

pub use silrig_model::quad::params::START_VALUES;

/// An error as the scenario's other checks give it: (dotted key, problem).
type KeyError = (String, String);

/// Whether the scenario flies the built-in quadrotor.
pub fn is_quad(s: &Scenario) -> bool {
    s.plant.model == BuiltinVehicle::Quad
}

/// A start value of `[plant.parameters]`, its default when not given, range-checked.
fn start_value(s: &Scenario, name: &str) -> Result<f64, KeyError> {
    let info = START_VALUES.iter().find(|v| v.name == name).expect("a start value's name");
    let (unit, min, max) = (info.unit, info.min, info.max);
    let Some(&value) = s.plant.parameters.get(name) else { return Ok(0.0) };
    if !(value >= min && value <= max) {
        return Err((format!("plant.parameters.{name}"), format!("must be within {min}..={max} {unit}, got {value}")));
    }
    Ok(value)
}

/// The vehicle's parameters: the Hummingbird's with those `[plant.parameters]` gives over them, checked as a set.
pub fn quad_params(s: &Scenario) -> Result<QuadParams, KeyError> {
    let mut params = QuadParams::default();
    for (name, value) in &s.plant.parameters {
        if START_VALUES.iter().any(|v| v.name == name) {
            continue;
        }
        params.set(name, *value).map_err(|e| {
            let starts: Vec<&str> = START_VALUES.iter().map(|v| v.name).collect();
            let also = if PARAMS.iter().any(|p| p.name == name) { String::new() } else { starts.join(", ") };
            let also = if also.is_empty() { also } else { format!("; its start values: {also}") };
            (format!("plant.parameters.{name}"), format!("{e}{also}"))
        })?;
    }
    params.validate().map_err(|e| ("plant.parameters".to_string(), e.to_string()))?;
    Ok(params)
}

/// The quadrotor at the scenario's start: on the ground (`start_alt_m` = 0) or hovering at `start_alt_m`.
pub fn quad_vehicle(s: &Scenario) -> Result<QuadVehicle, KeyError> {
    let params = quad_params(s)?;
    let alt_m = start_value(s, "start_alt_m")?;
    let psi_rad = start_value(s, "start_psi_deg")?.to_radians();
    QuadVehicle::at_start(params, alt_m, psi_rad).map_err(|e| ("plant.parameters".to_string(), e.to_string()))
}

/// The quadrotor's announcement: the model's outputs and its four motor commands (0..1), whose failsafe holds the
/// hover command of `params` (in the air it keeps the vehicle up while a controller restarts).
pub fn quad_signals(params: &QuadParams) -> PlantSignals {
    let outputs =
        OUTPUTS.iter().map(|(name, unit)| OutputSignal { name: (*name).into(), unit: (*unit).into(), in_trace: true });
    let inputs = INPUTS.iter().map(|(name, unit)| InputSignal {
        name: (*name).into(),
        unit: (*unit).into(),
        min: INPUT_RANGE.0,
        max: INPUT_RANGE.1,
        hold: params.hover_command(),
        held_output: None,
        command_in_trace: true,
    });
    PlantSignals { plant: PLANT_NAME.into(), outputs: outputs.collect(), inputs: inputs.collect() }
}

/// The announcement of the built-in vehicle the scenario flies: the quadrotor's, or the F-16's (with no hold
/// values: what a controller is checked against before the plant runs).
pub fn builtin_signals(s: &Scenario) -> Result<PlantSignals, KeyError> {
    if !is_quad(s) {
        return Ok(crate::f16_signals::f16_signals([0.0; 4]));
    }
    quad_params(s).map(|params| quad_signals(&params))
}

/// The set points our controller flies: roll, pitch and heading (`phi_deg`, `theta_deg`, `psi_deg`) and the height
/// `alt_m` (the start height when the scenario gives none).
pub fn quad_setpoint(s: &Scenario) -> Result<QuadSetpoint, KeyError> {
    let sp = &s.setpoint;
    let alt_m = match sp.get("alt_m") {
        Some(alt) => alt,
        None => start_value(s, "start_alt_m")?,
    };
    Ok(QuadSetpoint { euler_rad: [sp.phi_deg, sp.theta_deg, sp.psi_deg].map(f64::to_radians), alt_m })
}

/// The first key of `actual`'s table whose value differs from `default`'s, if any.
fn changed_key<T: serde::Serialize>(actual: &T, default: &T) -> Option<String> {
    let table = |v: &T| toml::Value::try_from(v).ok().and_then(|v| v.as_table().cloned()).unwrap_or_default();
    let (actual, default) = (table(actual), table(default));
    actual.iter().find(|(k, v)| default.get(*k) != Some(v)).map(|(k, _)| k.clone())
}

/// What only the quadrotor can check: no key of the F-16's given (its initial condition, disturbance, plant
/// options, our F-16 controller's gains, dispersions of those), no plant FMU beside it, parameters and start values
/// it has, set points of its outputs, and `[actuators]` and sensor and actuator faults on its own signals.
pub fn check_for_quad(s: &Scenario) -> Result<(), KeyError> {
    let quad = "the scenario flies the built-in quadrotor (`plant.model = \"quad\"`)";
    if let Some(fmu) = &s.plant.fmu {
        return Err((
            "plant.fmu".into(),
            format!("{quad}, which {} would replace: give `plant.model` or `plant.fmu`, not both", fmu.display()),
        ));
    }
    let starts = "it starts from `plant.parameters.start_alt_m` and `plant.parameters.start_psi_deg`";
    // Named by section: a section given fills the keys it leaves out with serde's defaults, not the section's, so
    // the first key that differs need not be one the file wrote.
    if changed_key(&s.initial, &Default::default()).is_some() {
        return Err(("initial".into(), format!("is the F-16's initial condition; {quad}: {starts}")));
    }
    if changed_key(&s.disturbance, &Default::default()).is_some() {
        return Err(("disturbance".into(), format!("acts on the F-16 alone; {quad}")));
    }
    let own = PlantOptions {
        model: s.plant.model,
        parameters: s.plant.parameters.clone(),
        outputs_held_fraction_max: s.plant.outputs_held_fraction_max,
        ..Default::default()
    };
    if let Some(k) = changed_key(&s.plant, &own) {
        return Err((
            format!("plant.{k}"),
            format!("is the F-16's; {quad}: its parameters are `[plant.parameters]` by name"),
        ));
    }
    if let Some(k) = changed_key(&s.controller.gains, &Default::default()) {
        return Err((
            format!("controller.{k}"),
            format!("is a gain of the F-16's controller; {quad}, which our quadrotor controller flies with its own"),
        ));
    }
    if let Some(key) = s.dispersions.keys().find(|k| crate::dispersion::is_f16_only(k)) {
        return Err((
            format!("dispersions.\"{key}\""),
            format!("{quad}, which does not read `{key}`: disperse its parameters as `plant.parameters.<name>`"),
        ));
    }
    let vehicle = quad_vehicle(s)?;
    let signals = quad_signals(&vehicle.params);
    // A device's layout may send set points that are no output (Betaflight's sticks and switches, `rc_*`): its
    // binding names any it does not find.
    let device = s.controller.device.is_some();
    if let Some(name) = s.setpoint.outputs.keys().find(|n| !device && signals.output(n).is_err()) {
        let names: Vec<&str> = OUTPUTS.iter().map(|o| o.0).collect();
        return Err((
            format!("setpoint.{name}"),
            format!("the quadrotor has no output `{name}`; its outputs: {}", names.join(", ")),
        ));
    }
    SignalChain::new(s, &signals, &vehicle.motor_commands)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(extra: &str) -> Result<Scenario, String> {
        let text = format!(
            "name = \"q\"\n{extra}\n[plant]\nmodel = \"quad\"\n[timing]\ndt_s = 0.001\nduration_s = 1.0\n\
             command_timing = \"same-tick\"\n"
        );
        let s = Scenario::from_toml(&text, "test").map_err(|e| e.to_string())?;
        check_for_quad(&s).map_err(|(k, p)| format!("`{k}`: {p}"))?;
        Ok(s)
    }

    fn quad_with(parameters: &str) -> Result<Scenario, String> {
        let text = format!(
            "name = \"q\"\n[plant]\nmodel = \"quad\"\n[plant.parameters]\n{parameters}\n[timing]\ndt_s = 0.001\n\
             duration_s = 1.0\ncommand_timing = \"same-tick\"\n"
        );
        let s = Scenario::from_toml(&text, "test").map_err(|e| e.to_string())?;
        check_for_quad(&s).map_err(|(k, p)| format!("`{k}`: {p}"))?;
        Ok(s)
    }

    #[test]
    fn the_model_key_round_trips_and_the_f16_writes_none() {
        let s = quad("").unwrap();
        assert!(is_quad(&s) && s.to_toml().contains("model = \"quad\""));
        assert_eq!(Scenario::from_toml(&s.to_toml(), "again").unwrap(), s);
        assert!(!Scenario::embedded_default().to_toml().contains("model"));
        let e = Scenario::from_toml("name = \"x\"\n[plant]\nmodel = \"heli\"\n[timing]\ndt_s = 0.01\n", "t");
        assert!(e.unwrap_err().to_string().contains("unknown variant `heli`, expected `f16` or `quad`"));
    }

    #[test]
    fn it_starts_on_the_ground_or_hovering_with_parameters_by_name() {
        let ground = quad_vehicle(&quad("").unwrap()).unwrap();
        assert!(ground.on_ground && ground.state.rotor_speeds_radps() == [0.0; 4]);
        let s = quad_with("start_alt_m = 2.5\nstart_psi_deg = 30.0\nmass_kg = 0.8").unwrap();
        let v = quad_vehicle(&s).unwrap();
        assert!(!v.on_ground && v.state.position_ned_m()[2] == -2.5 && v.params.mass_kg == 0.8);
        assert!((v.state.attitude().euler_angles().2.to_degrees() - 30.0).abs() < 1e-9);
        let sp = quad_setpoint(&s).unwrap();
        assert_eq!(sp.alt_m, 2.5, "no alt_m set point: the start height is held");
        let signals = quad_signals(&v.params);
        assert_eq!(signals.inputs.len(), 4);
        assert!(signals.inputs.iter().all(|i| i.hold == v.params.hover_command()));
        assert_eq!(signals.check(256, 16), Ok(()));
    }

    #[test]
    fn f16_keys_and_unknown_names_are_refused_in_words() {
        for (extra, said) in [
            ("[initial]\nairspeed_mps = 100.0\naltitude_ft = 25000.0", "`initial`: is the F-16's initial condition"),
            ("[disturbance]\namplitude_radps2 = 1.0", "`disturbance`: acts on the F-16 alone"),
            ("[setpoint]\nalt_ft = 10.0", "the quadrotor has no output `alt_ft`; its outputs: phi_deg"),
            ("[actuators.elevator]\nmin = 0.0\nmax = 1.0", "has no input `elevator`; its inputs: motor1"),
        ] {
            let e = quad(extra).unwrap_err();
            assert!(e.contains(said), "{extra}: {e}");
        }
        // Set points that are no output are a device's to send (Betaflight's sticks), and its binding checks them.
        quad("[setpoint]\nrc_arm = 1.0\n[controller]\ndevice = \"devices/betaflight-sitl.toml\"").unwrap();
        let mut s = quad("").unwrap();
        s.controller.gains.switching_gain_radps2[0] = 9.0;
        let (key, e) = check_for_quad(&s).unwrap_err();
        assert!(key == "controller.switching_gain_radps2" && e.contains("is a gain of the F-16's"), "{key}: {e}");
        s.controller.gains = Default::default();
        s.dispersions.insert("plant.xcg".into(), crate::dispersion::Distribution::Uniform { min: 0.3, max: 0.4 });
        let (key, e) = check_for_quad(&s).unwrap_err();
        assert!(key == "dispersions.\"plant.xcg\"" && e.contains("`plant.parameters.<name>`"), "{key}: {e}");
        let e = quad("[plant.aero_scale]\ncl = 1.2").unwrap_err();
        assert!(e.contains("`plant.aero_scale`: is the F-16's"), "{e}");
        let e = quad_with("mass = 1.0").unwrap_err();
        assert!(e.contains("no parameter `mass`") && e.contains("its start values: start_alt_m"), "{e}");
        let e = quad_with("start_alt_m = -1.0").unwrap_err();
        assert!(e.contains("`plant.parameters.start_alt_m`: must be within 0..=1000 m, got -1"), "{e}");
        let e = quad_with("mass_kg = 5.0").unwrap_err();
        assert!(e.contains("cannot hover"), "{e}");
    }
}
