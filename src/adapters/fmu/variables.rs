//! What an FMU as the plant ([`super::plant`]) and an FMU as the controller ([`super::controller`]) share:
//! a variable's signal name, which of its inputs and outputs are signals (numbers: Real, Integer, Boolean) and why
//! the others are not, a scenario's parameters table checked against the FMU's variables and set by value
//! reference, whether its state can be checkpointed, and that state as hex text.

use silrig_fmi::Instance;
use silrig_fmi::description::{Causality, ModelDescription, ValueKind, Variable};
use silrig_fmi::numbers::Numbers;

/// The signal name of an FMU variable: its name with every character other than an ASCII letter, digit or '_'
/// turned into '_'.
pub fn signal_name(variable: &str) -> String {
    variable.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect()
}

/// The FMU's variables of `causality` that are signals (numbers), in the description's order, and those that are
/// not, each as `"name" (why)`: what the rig says of each variable it leaves out.
pub fn signal_variables(d: &ModelDescription, causality: Causality) -> (Vec<&Variable>, Vec<String>) {
    let mut refused = Vec::new();
    let numbers = d
        .variables
        .iter()
        .filter(|v| v.causality == causality)
        .filter(|v| match v.kind.refusal() {
            None => true,
            Some(why) => {
                refused.push(format!("{:?} ({why})", v.name));
                false
            }
        })
        .collect();
    (numbers, refused)
}

/// A parameter to set before initialization: its kind, value reference and value.
pub type Parameter = (ValueKind, u32, f64);

/// Set `parameters` (none is no call).
pub fn set_parameters(instance: &mut Instance, parameters: &[Parameter]) -> Result<(), silrig_fmi::FmiError> {
    if parameters.is_empty() {
        return Ok(());
    }
    let mut numbers = Numbers::new(parameters.iter().map(|&(kind, vr, _)| (kind, vr)));
    let values: Vec<f64> = parameters.iter().map(|p| p.2).collect();
    instance.set_numbers(&mut numbers, &values)
}

/// A scenario's parameters table (`table` is its key, `plant.parameters` or `controller.parameters`) as value
/// references and values to set before initialization: each must name a parameter (Real, Integer or Boolean), or an
/// input whose start value it sets, within the variable's range. Errors name the FMU, the key and what the FMU has.
pub fn parameters<'a>(
    file: &str,
    d: &ModelDescription,
    table: &str,
    given: impl IntoIterator<Item = (&'a String, &'a f64)>,
) -> Result<Vec<Parameter>, String> {
    let bad = |problem: String| format!("FMU {file}: {problem}");
    let settable = || -> String {
        d.variables
            .iter()
            .filter(|v| v.kind.is_number() && matches!(v.causality, Causality::Parameter | Causality::Input))
            .map(|v| v.name.clone())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut out = Vec::new();
    for (name, value) in given {
        let variable = d.variable(name).or_else(|| d.variables.iter().find(|v| signal_name(&v.name) == *name));
        let Some(v) = variable else {
            return Err(bad(format!(
                "`{table}.{name}`: no variable of that name; its parameters and inputs: {}",
                settable()
            )));
        };
        if let Some(why) = v.kind.refusal() {
            return Err(bad(format!("`{table}.{name}`: variable {:?} cannot be set: {why}", v.name)));
        }
        if !matches!(v.causality, Causality::Parameter | Causality::Input) || v.variability == "constant" {
            return Err(bad(format!(
                "`{table}.{name}`: variable {:?} has causality {} (variability {}): only a parameter's value or an \
                 input's start value can be set; settable: {}",
                v.name,
                v.causality.label(),
                v.variability,
                settable()
            )));
        }
        if v.min.is_some_and(|m| *value < m) || v.max.is_some_and(|m| *value > m) {
            return Err(bad(format!(
                "`{table}.{name}` = {value} is outside the variable's range {}..{}",
                v.min.unwrap_or(f64::NEG_INFINITY),
                v.max.unwrap_or(f64::INFINITY)
            )));
        }
        if v.kind != ValueKind::Real && value.fract() != 0.0 {
            return Err(bad(format!(
                "`{table}.{name}` = {value}: variable {:?} is {} {}, so its value is a whole number{}",
                v.name,
                if v.kind == ValueKind::Integer { "an" } else { "a" },
                v.kind.label(),
                if v.kind == ValueKind::Boolean { " (0 for false, 1 for true)" } else { "" }
            )));
        }
        out.push((v.kind, v.value_reference, *value));
    }
    Ok(out)
}

/// Whether a restarted process can resume from the FMU's serialized state, or why not.
pub fn can_checkpoint(d: &ModelDescription) -> Result<(), String> {
    let cs = &d.co_simulation;
    match (cs.can_get_and_set_state, cs.can_serialize_state) {
        (true, true) => Ok(()),
        (false, _) => Err("the FMU cannot get and set its state (canGetAndSetFMUstate is not true)".into()),
        (true, false) => Err("the FMU cannot serialize its state (canSerializeFMUstate is not true)".into()),
    }
}

/// Bytes as lower-case hex, two digits each (an FMU's serialized state inside a JSON checkpoint).
pub fn to_hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// [`to_hex`]'s text back as bytes; an error when it is not hex bytes (a torn or edited checkpoint).
pub fn from_hex(hex: &str) -> Result<Vec<u8>, String> {
    let hex = hex.as_bytes();
    if !hex.len().is_multiple_of(2) || !hex.iter().all(u8::is_ascii_hexdigit) {
        return Err("its FMU state is not hex bytes".into());
    }
    Ok(hex
        .chunks(2)
        .map(|pair| u8::from_str_radix(std::str::from_utf8(pair).expect("ASCII hex digits"), 16).expect("hex digits"))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_round_trips_and_refuses_what_is_not_hex() {
        let bytes = [0u8, 1, 0x7f, 0x80, 0xff];
        assert_eq!(to_hex(&bytes), "00017f80ff");
        assert_eq!(from_hex(&to_hex(&bytes)).unwrap(), bytes);
        assert!(from_hex("abc").is_err());
        assert!(from_hex("zz").is_err());
    }

    #[test]
    fn integer_and_boolean_parameters_take_whole_numbers_and_strings_none() {
        let text = r#"<fmiModelDescription fmiVersion="3.0" modelName="q" instantiationToken="{t}">
  <CoSimulation modelIdentifier="q"/>
  <ModelVariables>
    <Int32 name="n" valueReference="1" causality="parameter" variability="fixed" start="1" min="0" max="9"/>
    <Boolean name="b" valueReference="2" causality="parameter" variability="fixed" start="false"/>
    <String name="s" valueReference="3" causality="parameter" variability="fixed"/>
    <Int64 name="big" valueReference="4" causality="output"/>
  </ModelVariables>
</fmiModelDescription>"#;
        let d = ModelDescription::parse(text, "q.fmu").unwrap();
        let set = |name: &str, value: f64| {
            let given = [(name.to_string(), value)];
            parameters("q.fmu", &d, "plant.parameters", given.iter().map(|(n, v)| (n, v)))
        };
        assert_eq!(set("n", 3.0).unwrap(), [(ValueKind::Integer, 1, 3.0)]);
        assert_eq!(set("b", 1.0).unwrap(), [(ValueKind::Boolean, 2, 1.0)]);
        let e = set("n", 2.5).unwrap_err();
        assert!(e.contains("`plant.parameters.n` = 2.5: variable \"n\" is an Integer, so its value is a whole"), "{e}");
        assert!(set("b", 2.0).unwrap_err().contains("outside the variable's range 0..1"));
        assert!(set("s", 1.0).unwrap_err().contains("cannot be set: String is not a signal"));
        let (outputs, left_out) = signal_variables(&d, Causality::Output);
        assert!(outputs.is_empty());
        assert_eq!(
            left_out,
            [
                "\"big\" (Int64 is not a signal: of the FMI 3 integers silrig reads Int32 alone (64-bit ones do not fit a double exactly))"
            ]
        );
    }

    #[test]
    fn signal_names_keep_letters_digits_and_underscores() {
        assert_eq!(signal_name("body.w[1]"), "body_w_1_");
        assert_eq!(signal_name("err_phi_deg"), "err_phi_deg");
    }
}
