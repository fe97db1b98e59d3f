//! `[controller.map]`'s values: what one variable of a controller FMU is connected to, a plant signal by name
//! (`pitch = "theta_deg"`) or, for an input, a constant held every tick (`aileron_deg = 0.0`). Read from TOML by
//! hand, so that a value of another type is refused in words.

use serde::Serialize;
use std::collections::BTreeMap;

/// What `[controller.map]` connects an FMU variable to.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum MapTarget {
    /// A plant signal (an output, `<output>_sp` for its set point, or an input the FMU output commands).
    Signal(String),
    /// A constant value an FMU input takes every tick.
    Constant(f64),
}

impl MapTarget {
    /// A string is a signal's name, a number (integer or float) a constant; anything else is refused.
    fn from_toml(value: toml::Value) -> Result<Self, String> {
        match value {
            toml::Value::String(name) => Ok(MapTarget::Signal(name)),
            toml::Value::Float(v) => Ok(MapTarget::Constant(v)),
            toml::Value::Integer(v) => Ok(MapTarget::Constant(v as f64)),
            other => Err(format!(
                "{other} is a {}: give a plant signal's name as a string (\"theta_deg\") or a constant as a number \
                 (0.0)",
                other.type_str()
            )),
        }
    }

    /// The name is a signal name and the constant finite.
    pub fn check(&self) -> Result<(), String> {
        match self {
            MapTarget::Signal(name) if !crate::signals::valid_name(name) => {
                Err(format!("{name:?} is not a signal name (1 to 31 ASCII letters, digits and '_')"))
            }
            MapTarget::Constant(v) if !v.is_finite() => Err(format!("the constant {v} is not a finite number")),
            _ => Ok(()),
        }
    }
}

impl std::fmt::Display for MapTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MapTarget::Signal(name) => write!(f, "{name:?}"),
            MapTarget::Constant(v) => write!(f, "{v}"),
        }
    }
}

/// `[controller.map]` as a table of targets; an entry of another type is refused naming its key.
pub fn from_toml(value: toml::Value) -> Result<BTreeMap<String, MapTarget>, String> {
    let toml::Value::Table(table) = value else {
        return Err(format!("must be a table of `variable = \"signal\"` or `variable = number`, got {value}"));
    };
    table
        .into_iter()
        .map(|(key, v)| MapTarget::from_toml(v).map(|t| (key.clone(), t)).map_err(|e| format!("`{key}`: {e}")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strings_are_signals_numbers_constants_and_the_rest_refused() {
        let table: toml::Value = toml::from_str("a = \"theta_deg\"\nb = 0.5\nc = 2").unwrap();
        let map = from_toml(table).unwrap();
        assert_eq!(map["a"], MapTarget::Signal("theta_deg".into()));
        assert_eq!((map["b"].clone(), map["c"].clone()), (MapTarget::Constant(0.5), MapTarget::Constant(2.0)));
        let e = from_toml(toml::from_str("d = true").unwrap()).unwrap_err();
        assert!(e.contains("`d`: true is a boolean: give a plant signal's name as a string"), "{e}");
        assert!(MapTarget::Signal("theta deg".into()).check().unwrap_err().contains("not a signal name"));
        assert!(MapTarget::Constant(f64::NAN).check().unwrap_err().contains("not a finite number"));
        assert_eq!((map["a"].to_string(), map["b"].to_string()), ("\"theta_deg\"".into(), "0.5".into()));
    }
}
