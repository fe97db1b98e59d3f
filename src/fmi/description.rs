//! `modelDescription.xml` as the rig needs it: the FMI version, the model's name and identity (FMI 2 `guid`, FMI 3
//! `instantiationToken`), what its co-simulation interface offers (state saving), its default step, and its
//! variables with causality, variability, unit, range and start. FMI 2.0 and 3.0 are read into one shape; every
//! other version, and an FMU without co-simulation, is refused by name.

use crate::FmiError;
use std::collections::BTreeMap;

/// The FMI standard an FMU follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FmiVersion {
    /// FMI 2.0.
    V2,
    /// FMI 3.0.
    V3,
}

impl FmiVersion {
    /// As the standard writes it.
    pub fn label(self) -> &'static str {
        match self {
            FmiVersion::V2 => "FMI 2.0",
            FmiVersion::V3 => "FMI 3.0",
        }
    }

    /// Where the standard puts the Linux x86-64 binary inside the archive.
    pub fn binary_folder(self) -> &'static str {
        match self {
            FmiVersion::V2 => "binaries/linux64",
            FmiVersion::V3 => "binaries/x86_64-linux",
        }
    }
}

/// A variable's causality (the FMI standard's words).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialization, fixed or tunable.
    Parameter,
    /// Computed from parameters.
    CalculatedParameter,
    /// Set by the importer every step.
    Input,
    /// Read by the importer every step.
    Output,
    /// Internal.
    Local,
    /// The independent variable (time).
    Independent,
    /// FMI 3's structural parameter.
    StructuralParameter,
}

impl Causality {
    fn parse(text: &str) -> Option<Self> {
        Some(match text {
            "parameter" => Causality::Parameter,
            "calculatedParameter" => Causality::CalculatedParameter,
            "input" => Causality::Input,
            "output" => Causality::Output,
            "local" => Causality::Local,
            "independent" => Causality::Independent,
            "structuralParameter" => Causality::StructuralParameter,
            _ => return None,
        })
    }

    /// As `modelDescription.xml` writes it.
    pub fn label(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
            Causality::StructuralParameter => "structuralParameter",
        }
    }
}

/// A variable's type, as far as the rig reads values: numbers (FMI 2 `Real`, `Integer` and `Boolean`, FMI 3
/// `Float64`, `Int32` and `Boolean`) are read and set as doubles; the rest are listed so an error can say what a
/// name is and why it is not a signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueKind {
    /// FMI 2 `Real`, FMI 3 `Float64`.
    Real,
    /// FMI 2 `Integer`, FMI 3 `Int32`: a double holds every value exactly.
    Integer,
    /// FMI 2 and 3 `Boolean`: 0 or 1.
    Boolean,
    /// Any other type (its element name: `Float32`, `Int64`, `String`, `Enumeration`, `array`, ...).
    Other(&'static str),
}

impl ValueKind {
    /// Whether the rig reads and sets it as a number (a signal, a parameter, a controller FMU's input or output).
    pub fn is_number(self) -> bool {
        !matches!(self, ValueKind::Other(_))
    }

    /// As `modelDescription.xml` names it, for messages.
    pub fn label(self) -> &'static str {
        match self {
            ValueKind::Real => "Real",
            ValueKind::Integer => "Integer",
            ValueKind::Boolean => "Boolean",
            ValueKind::Other(name) => name,
        }
    }

    /// Why a variable of this type is not a signal, or None when it is one.
    pub fn refusal(self) -> Option<String> {
        let why = match self {
            ValueKind::Real | ValueKind::Integer | ValueKind::Boolean => return None,
            ValueKind::Other("Float32") => "a Float32 is not read (silrig reads Float64, Int32 and Boolean)",
            ValueKind::Other("Int8" | "UInt8" | "Int16" | "UInt16" | "UInt32" | "Int64" | "UInt64") => {
                "of the FMI 3 integers silrig reads Int32 alone (64-bit ones do not fit a double exactly)"
            }
            ValueKind::Other("String") => "a String is text, not a number",
            ValueKind::Other("Binary") => "a Binary is bytes, not a number",
            ValueKind::Other("Enumeration") => "an Enumeration is not read (declare it an Integer)",
            ValueKind::Other("Clock") => "a Clock ticks events, which silrig does not use",
            ValueKind::Other("array") => "an array holds several values behind one value reference",
            ValueKind::Other(_) => "its type is not read",
        };
        Some(format!("{} is not a signal: {why}", self.label()))
    }
}

/// One variable of `ModelVariables`.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Its name as the FMU writes it (`body.w[1]` is allowed here; the rig maps it to a signal name).
    pub name: String,
    /// Its value reference.
    pub value_reference: u32,
    /// Its causality.
    pub causality: Causality,
    /// `constant`, `fixed`, `tunable`, `discrete` or `continuous`.
    pub variability: String,
    /// Its type.
    pub kind: ValueKind,
    /// Its unit (from the variable or its declared type), if any.
    pub unit: Option<String>,
    /// Its declared minimum, if any.
    pub min: Option<f64>,
    /// Its declared maximum, if any.
    pub max: Option<f64>,
    /// Its start value, if any.
    pub start: Option<f64>,
    /// Its description, if any.
    pub description: Option<String>,
    /// The attributes of its silrig annotation, `<Annotations><Tool name="silrig"><Signal .../></Tool>` (empty
    /// without one): how a variable tells the rig its signal's name and role.
    pub silrig: BTreeMap<String, String>,
}

/// What the co-simulation interface offers.
#[derive(Debug, Clone, PartialEq)]
pub struct CoSimulation {
    /// The binary's base name (`binaries/<platform>/<modelIdentifier>.so`).
    pub model_identifier: String,
    /// Whether its state can be taken and put back (FMI 2 `canGetAndSetFMUstate`, FMI 3 `canGetAndSetFMUState`).
    pub can_get_and_set_state: bool,
    /// Whether that state can be serialized to bytes (what a checkpoint on disk needs).
    pub can_serialize_state: bool,
    /// `canBeInstantiatedOnlyOncePerProcess`: its binary keeps state outside its instances (globals), so one
    /// process must never hold two of its instances at once.
    pub one_instance_per_process: bool,
}

/// The parts of `modelDescription.xml` the rig uses.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelDescription {
    /// FMI 2.0 or 3.0.
    pub version: FmiVersion,
    /// `modelName`.
    pub model_name: String,
    /// FMI 2 `guid`, FMI 3 `instantiationToken`: the binary checks it when instantiated.
    pub token: String,
    /// The co-simulation interface.
    pub co_simulation: CoSimulation,
    /// `DefaultExperiment/@stepSize`, s, if given.
    pub default_step_s: Option<f64>,
    /// Every variable, in document order.
    pub variables: Vec<Variable>,
    /// The plant name a silrig vendor annotation gives (`<VendorAnnotations><Tool name="silrig"><Plant
    /// name=".."/>`), if any.
    pub silrig_plant_name: Option<String>,
}

impl ModelDescription {
    /// Read `modelDescription.xml`'s text; `file` names the FMU in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, FmiError> {
        let bad = |problem: String| FmiError::Description { file: file.to_string(), problem };
        let doc = roxmltree::Document::parse(text).map_err(|e| bad(format!("not well-formed XML: {e}")))?;
        let root = doc.root_element();
        if root.tag_name().name() != "fmiModelDescription" {
            return Err(bad(format!("the root element is <{}>, not <fmiModelDescription>", root.tag_name().name())));
        }
        let version = version_of(root, file)?;
        let required = |name: &str| {
            root.attribute(name)
                .map(str::to_string)
                .ok_or_else(|| bad(format!("<fmiModelDescription> has no {name} attribute")))
        };
        let model_name = required("modelName")?;
        let token = required(match version {
            FmiVersion::V2 => "guid",
            FmiVersion::V3 => "instantiationToken",
        })?;
        let child = |name: &str| root.children().find(|n| n.has_tag_name(name));
        let co_simulation = co_simulation_of(root, file)?;
        let default_step_s = child("DefaultExperiment").and_then(|d| d.attribute("stepSize")).and_then(number);
        let units = declared_units(&root);
        let variables = match child("ModelVariables") {
            None => Vec::new(),
            Some(list) => match version {
                FmiVersion::V2 => list
                    .children()
                    .filter(|n| n.has_tag_name("ScalarVariable"))
                    .map(|n| variable_v2(n, &units).map_err(&bad))
                    .collect::<Result<_, _>>()?,
                FmiVersion::V3 => list
                    .children()
                    .filter(|n| n.is_element())
                    .map(|n| variable_v3(n).map_err(&bad))
                    .collect::<Result<_, _>>()?,
            },
        };
        let silrig_plant_name = child("VendorAnnotations")
            .into_iter()
            .flat_map(|v| v.children())
            .filter(|t| t.has_tag_name("Tool") && t.attribute("name") == Some("silrig"))
            .flat_map(|t| t.children())
            .find(|p| p.has_tag_name("Plant"))
            .and_then(|p| p.attribute("name"))
            .map(str::to_string);
        Ok(Self { version, model_name, token, co_simulation, default_step_s, variables, silrig_plant_name })
    }

    /// The variable called `name`.
    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }
}

/// The FMI version `<fmiModelDescription>` declares: 2.x or 3.x, anything else refused saying what silrig imports.
fn version_of(root: roxmltree::Node, file: &str) -> Result<FmiVersion, FmiError> {
    let version_text = root.attribute("fmiVersion").unwrap_or("");
    if version_text.starts_with("2.") {
        Ok(FmiVersion::V2)
    } else if version_text.starts_with("3.") {
        Ok(FmiVersion::V3)
    } else {
        Err(FmiError::Unsupported {
            file: file.to_string(),
            what: format!(
                "fmiVersion {version_text:?}: silrig imports FMI 2.0 and 3.0 co-simulation FMUs (FMI 1.0 is not \
                 supported; re-export the model as FMI 2.0 or 3.0)"
            ),
        })
    }
}

/// The `<CoSimulation>` interface, or a refusal naming the interfaces the FMU offers instead.
fn co_simulation_of(root: roxmltree::Node, file: &str) -> Result<CoSimulation, FmiError> {
    let child = |name: &str| root.children().find(|n| n.has_tag_name(name));
    let Some(cs) = child("CoSimulation") else {
        let offers: Vec<&str> =
            ["ModelExchange", "ScheduledExecution"].into_iter().filter(|k| child(k).is_some()).collect();
        return Err(FmiError::Unsupported {
            file: file.to_string(),
            what: match offers.is_empty() {
                true => "no <CoSimulation> interface: silrig steps co-simulation FMUs".into(),
                false => format!(
                    "{} only, no <CoSimulation> interface: silrig steps co-simulation FMUs (export the model \
                     for co-simulation, with its own solver)",
                    offers.join(" and ")
                ),
            },
        });
    };
    let flag = |names: [&str; 2]| names.iter().any(|n| cs.attribute(*n) == Some("true"));
    Ok(CoSimulation {
        model_identifier: cs.attribute("modelIdentifier").map(str::to_string).ok_or_else(|| FmiError::Description {
            file: file.to_string(),
            problem: "<CoSimulation> has no modelIdentifier".into(),
        })?,
        can_get_and_set_state: flag(["canGetAndSetFMUstate", "canGetAndSetFMUState"]),
        can_serialize_state: flag(["canSerializeFMUstate", "canSerializeFMUState"]),
        one_instance_per_process: flag(["canBeInstantiatedOnlyOncePerProcess", "canBeInstantiatedOnlyOncePerProcess"]),
    })
}

/// A number as FMI writes one (xs:double: `INF`, `-INF` and `NaN` included).
fn number(text: &str) -> Option<f64> {
    match text.trim() {
        "INF" => Some(f64::INFINITY),
        "-INF" => Some(f64::NEG_INFINITY),
        t => t.parse().ok(),
    }
}

/// FMI 2's `TypeDefinitions`: a declared type's unit, min and max, by the type's name.
type DeclaredTypes = Vec<(String, Option<String>, Option<f64>, Option<f64>)>;

fn declared_units(root: &roxmltree::Node) -> DeclaredTypes {
    let Some(defs) = root.children().find(|n| n.has_tag_name("TypeDefinitions")) else { return Vec::new() };
    defs.children()
        .filter(|n| n.has_tag_name("SimpleType"))
        .filter_map(|t| {
            let real = t.children().find(|n| n.has_tag_name("Real"))?;
            Some((
                t.attribute("name")?.to_string(),
                real.attribute("unit").map(str::to_string),
                real.attribute("min").and_then(number),
                real.attribute("max").and_then(number),
            ))
        })
        .collect()
}

fn attribute_number(node: roxmltree::Node, name: &str, variable: &str) -> Result<Option<f64>, String> {
    match node.attribute(name) {
        None => Ok(None),
        Some(text) => {
            number(text).map(Some).ok_or_else(|| format!("variable {variable:?}: {name}={text:?} is not a number"))
        }
    }
}

/// A Boolean's start value as a number: `true` and `1` are 1, `false` and `0` are 0 (xs:boolean).
fn boolean_start(node: roxmltree::Node, variable: &str) -> Result<Option<f64>, String> {
    match node.attribute("start").map(str::trim) {
        None => Ok(None),
        Some("true" | "1") => Ok(Some(1.0)),
        Some("false" | "0") => Ok(Some(0.0)),
        Some(text) => Err(format!("variable {variable:?}: start={text:?} is not a Boolean (true or false)")),
    }
}

/// The attributes of a variable's `<Annotations><Tool name="silrig"><Signal .../>`.
fn silrig_annotation(node: roxmltree::Node) -> BTreeMap<String, String> {
    node.children()
        .filter(|n| n.has_tag_name("Annotations"))
        .flat_map(|a| a.children())
        .filter(|t| t.has_tag_name("Tool") && t.attribute("name") == Some("silrig"))
        .flat_map(|t| t.children())
        .filter(|s| s.has_tag_name("Signal"))
        .flat_map(|s| s.attributes().map(|a| (a.name().to_string(), a.value().to_string())).collect::<Vec<_>>())
        .collect()
}

fn common(node: roxmltree::Node) -> Result<(String, u32, Causality, String), String> {
    let name = node.attribute("name").ok_or("a variable without a name")?.to_string();
    let vr = node.attribute("valueReference").ok_or_else(|| format!("variable {name:?} has no valueReference"))?;
    let value_reference =
        vr.parse().map_err(|_| format!("variable {name:?}: valueReference {vr:?} is not an unsigned integer"))?;
    let causality_text = node.attribute("causality").unwrap_or("local");
    let causality = Causality::parse(causality_text)
        .ok_or_else(|| format!("variable {name:?}: unknown causality {causality_text:?}"))?;
    let variability = node.attribute("variability").unwrap_or("continuous").to_string();
    Ok((name, value_reference, causality, variability))
}

fn variable_v2(node: roxmltree::Node, types: &DeclaredTypes) -> Result<Variable, String> {
    let (name, value_reference, causality, variability) = common(node)?;
    let typed = node
        .children()
        .find(|n| n.is_element() && !n.has_tag_name("Annotations"))
        .ok_or_else(|| format!("variable {name:?} has no type element (<Real>, <Integer>, ...)"))?;
    let kind = match typed.tag_name().name() {
        "Real" => ValueKind::Real,
        "Integer" => ValueKind::Integer,
        "Boolean" => ValueKind::Boolean,
        "String" => ValueKind::Other("String"),
        "Enumeration" => ValueKind::Other("Enumeration"),
        other => return Err(format!("variable {name:?}: unknown type <{other}>")),
    };
    let declared = typed.attribute("declaredType").and_then(|t| types.iter().find(|(n, ..)| n == t));
    let (min, max, start) = match kind {
        ValueKind::Real | ValueKind::Integer => (
            attribute_number(typed, "min", &name)?.or(declared.and_then(|d| d.2)),
            attribute_number(typed, "max", &name)?.or(declared.and_then(|d| d.3)),
            attribute_number(typed, "start", &name)?,
        ),
        ValueKind::Boolean => (Some(0.0), Some(1.0), boolean_start(typed, &name)?),
        ValueKind::Other(_) => (None, None, None),
    };
    Ok(Variable {
        silrig: silrig_annotation(node),
        unit: typed.attribute("unit").map(str::to_string).or_else(|| declared.and_then(|d| d.1.clone())),
        description: node.attribute("description").map(str::to_string),
        name,
        value_reference,
        causality,
        variability,
        kind,
        min,
        max,
        start,
    })
}

fn variable_v3(node: roxmltree::Node) -> Result<Variable, String> {
    let (name, value_reference, causality, variability) = common(node)?;
    let kind = match node.tag_name().name() {
        "Float64" => ValueKind::Real,
        "Float32" => ValueKind::Other("Float32"),
        "Int32" => ValueKind::Integer,
        "Int8" => ValueKind::Other("Int8"),
        "UInt8" => ValueKind::Other("UInt8"),
        "Int16" => ValueKind::Other("Int16"),
        "UInt16" => ValueKind::Other("UInt16"),
        "UInt32" => ValueKind::Other("UInt32"),
        "Int64" => ValueKind::Other("Int64"),
        "UInt64" => ValueKind::Other("UInt64"),
        "Boolean" => ValueKind::Boolean,
        "String" => ValueKind::Other("String"),
        "Binary" => ValueKind::Other("Binary"),
        "Enumeration" => ValueKind::Other("Enumeration"),
        "Clock" => ValueKind::Other("Clock"),
        other => return Err(format!("variable {name:?}: unknown type <{other}>")),
    };
    // An array variable (with <Dimension>) holds several values behind one reference: not a scalar signal.
    let array = node.children().any(|n| n.has_tag_name("Dimension"));
    let (min, max, start) = match kind {
        _ if array => (None, None, None),
        ValueKind::Real | ValueKind::Integer => (
            attribute_number(node, "min", &name)?,
            attribute_number(node, "max", &name)?,
            attribute_number(node, "start", &name)?,
        ),
        ValueKind::Boolean => (Some(0.0), Some(1.0), boolean_start(node, &name)?),
        ValueKind::Other(_) => (None, None, None),
    };
    Ok(Variable {
        silrig: silrig_annotation(node),
        kind: if array { ValueKind::Other("array") } else { kind },
        unit: node.attribute("unit").map(str::to_string),
        description: node.attribute("description").map(str::to_string),
        name,
        value_reference,
        causality,
        variability,
        min,
        max,
        start,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const V2: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="toy" guid="{abc}">
  <CoSimulation modelIdentifier="toy" canGetAndSetFMUstate="true" canSerializeFMUstate="true"/>
  <UnitDefinitions><Unit name="deg"/></UnitDefinitions>
  <TypeDefinitions><SimpleType name="Angle"><Real unit="deg" min="-30" max="30"/></SimpleType></TypeDefinitions>
  <DefaultExperiment stopTime="10" stepSize="0.01"/>
  <VendorAnnotations><Tool name="other"/><Tool name="silrig"><Plant name="toy_plant"/></Tool></VendorAnnotations>
  <ModelVariables>
    <ScalarVariable name="k" valueReference="0" causality="parameter" variability="fixed"><Real start="2"/></ScalarVariable>
    <ScalarVariable name="u" valueReference="1" causality="input"><Real declaredType="Angle" start="0"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="2" causality="output" initial="calculated"><Real unit="m"/>
      <Annotations><Tool name="silrig"><Signal name="y_m" trace="false"/></Tool><Tool name="other"><Signal name="no"/></Tool></Annotations>
    </ScalarVariable>
    <ScalarVariable name="n" valueReference="3" causality="output" variability="discrete"><Integer/></ScalarVariable>
  </ModelVariables>
</fmiModelDescription>"#;

    #[test]
    fn an_fmi2_description_is_read_with_declared_types() {
        let d = ModelDescription::parse(V2, "toy.fmu").unwrap();
        assert_eq!(d.version, FmiVersion::V2);
        assert_eq!((d.model_name.as_str(), d.token.as_str()), ("toy", "{abc}"));
        assert!(d.co_simulation.can_get_and_set_state && d.co_simulation.can_serialize_state);
        assert_eq!(d.default_step_s, Some(0.01));
        assert_eq!(d.silrig_plant_name.as_deref(), Some("toy_plant"));
        let u = d.variable("u").unwrap();
        assert_eq!(
            (u.causality, u.unit.as_deref(), u.min, u.max, u.start),
            (Causality::Input, Some("deg"), Some(-30.0), Some(30.0), Some(0.0))
        );
        assert_eq!(d.variable("k").unwrap().start, Some(2.0));
        let y = &d.variable("y").unwrap().silrig;
        assert_eq!((y["name"].as_str(), y["trace"].as_str(), y.len()), ("y_m", "false", 2));
        assert_eq!(d.variable("n").unwrap().kind, ValueKind::Integer);
    }

    #[test]
    fn an_fmi3_description_is_read() {
        let text = r#"<fmiModelDescription fmiVersion="3.0" modelName="q" instantiationToken="{t}">
  <CoSimulation modelIdentifier="q" canGetAndSetFMUState="true"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent"/>
    <Float64 name="u" valueReference="1" causality="input" start="1" min="-2" max="2" unit="N"/>
    <Float64 name="y" valueReference="2" causality="output"/>
    <Float64 name="v" valueReference="3" causality="output"><Dimension start="3"/></Float64>
  </ModelVariables>
</fmiModelDescription>"#;
        let d = ModelDescription::parse(text, "q.fmu").unwrap();
        assert_eq!(d.version, FmiVersion::V3);
        assert_eq!(d.token, "{t}");
        assert!(d.co_simulation.can_get_and_set_state && !d.co_simulation.can_serialize_state);
        assert_eq!(d.variable("u").unwrap().min, Some(-2.0));
        assert_eq!(d.variable("v").unwrap().kind, ValueKind::Other("array"));
    }

    #[test]
    fn fmi1_and_model_exchange_only_are_refused_by_name() {
        let fmi1 = r#"<fmiModelDescription fmiVersion="1.0" modelName="old" guid="x"/>"#;
        let e = ModelDescription::parse(fmi1, "old.fmu").unwrap_err().to_string();
        assert!(e.contains("old.fmu") && e.contains("FMI 1.0 is not supported"), "{e}");
        let me = r#"<fmiModelDescription fmiVersion="2.0" modelName="me" guid="x"><ModelExchange modelIdentifier="me"/></fmiModelDescription>"#;
        let e = ModelDescription::parse(me, "me.fmu").unwrap_err().to_string();
        assert!(e.contains("me.fmu") && e.contains("ModelExchange only"), "{e}");
        let e = ModelDescription::parse("<a", "bad.fmu").unwrap_err().to_string();
        assert!(e.contains("bad.fmu") && e.contains("not well-formed"), "{e}");
    }
}
