//! The FMU's `modelDescription.xml`, generated (never hand-written) from the variables ([`crate::variables`]) and
//! the parameters' start values, with a GUID that is a hash of the rest of the text: the binary computes it from
//! the start values it carries and refuses to be instantiated under another.

use crate::variables::{
    BOOLEAN_PARAMETERS, FIRST_INPUT_VR, FIRST_PARAMETER_VR, Parameters, REAL_PARAMETERS, inputs, outputs,
};
use silrig_model::f16_outputs::{HELD_OUTPUT, INPUTS, PLANT_NAME};
use silrig_model::vehicle::{F16Vehicle, failsafe_command};

/// The model identifier: the binary's file name in `binaries/<platform>/` and the FMU's name.
pub const MODEL_IDENTIFIER: &str = "silrig_fmu_f16";

/// The communication step the rig flies, s (the default experiment's step; one doStep is one tick).
pub const DEFAULT_STEP_S: f64 = 0.01;

/// The default experiment: its duration and step, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    /// Stop time, s.
    pub stop_time_s: f64,
    /// Communication step, s.
    pub step_s: f64,
}

impl Default for Experiment {
    /// 10 s at the rig's 0.01 s.
    fn default() -> Self {
        Self { stop_time_s: 10.0, step_s: DEFAULT_STEP_S }
    }
}

/// The inputs' start values: what the built-in plant announces as its failsafe's hold values for these parameters
/// (the level-flight trim surfaces with the initial throttle), so an importer holding them flies what the rig's
/// failsafe flies. The error says why the parameters give no flight (no trim, outside the envelope).
pub fn input_starts(p: &Parameters) -> Result<[f64; 4], String> {
    p.check()?;
    let model = p.model();
    let initial = p.initial();
    let vehicle = F16Vehicle::new(model, &initial, &p.actuators(), p.forcing(), DEFAULT_STEP_S)
        .map_err(|e| format!("initial condition: {e}"))?;
    let hold = failsafe_command(&model, &initial, vehicle.initial_command());
    let s = &hold.surfaces;
    Ok([s.aileron_deg, s.elevator_deg, s.rudder_deg, hold.throttle])
}

/// The name of the file in the FMU's `resources/` that carries the parameters' start values and the default
/// experiment ([`start_file`]): the binary starts from them, and computes the GUID it accepts from them.
pub const START_FILE: &str = "start_values.txt";

/// Keys of the default experiment in the start file.
const STOP_TIME_KEY: &str = "default_stop_time_s";
const STEP_KEY: &str = "default_step_s";

/// The text of [`START_FILE`]: the parameters' start values ([`Parameters::to_text`]) and the default experiment.
pub fn start_file(p: &Parameters, e: &Experiment) -> String {
    format!("{}{}", p.to_text(), experiment_text(e))
}

/// Read [`start_file`]'s text back, bit for bit; the error names the line or the key.
pub fn read_start_file(text: &str) -> Result<(Parameters, Experiment), String> {
    let (rest, experiment) = split_experiment(text)?;
    Ok((Parameters::from_text(&rest)?, experiment))
}

/// The default experiment of a start file's text, and the rest of its lines (the parameters).
pub(crate) fn split_experiment(text: &str) -> Result<(String, Experiment), String> {
    let mut experiment = [None, None];
    let mut rest = String::new();
    for line in text.lines() {
        let key = line.split('=').next().unwrap_or("").trim();
        match [STOP_TIME_KEY, STEP_KEY].iter().position(|k| *k == key) {
            Some(k) => {
                let v: f64 = line
                    .split_once('=')
                    .map_or("", |(_, v)| v)
                    .trim()
                    .parse()
                    .map_err(|_| format!("{key}: not a number"))?;
                if !(v > 0.0 && v.is_finite()) {
                    return Err(format!("{key} = {v}: must be above 0"));
                }
                experiment[k] = Some(v);
            }
            None => {
                rest.push_str(line);
                rest.push('\n');
            }
        }
    }
    let [Some(stop_time_s), Some(step_s)] = experiment else {
        return Err(format!("{STOP_TIME_KEY} and {STEP_KEY} must both be given"));
    };
    Ok((rest, Experiment { stop_time_s, step_s }))
}

/// The default experiment's lines of a start file.
pub(crate) fn experiment_text(e: &Experiment) -> String {
    format!("{STOP_TIME_KEY} = {:?}\n{STEP_KEY} = {:?}\n", e.stop_time_s, e.step_s)
}

/// Text for an XML attribute value.
pub(crate) fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// What an FMU of a built-in vehicle says about itself in `modelDescription.xml` besides its variables.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Header {
    /// `modelName`.
    pub model_name: &'static str,
    /// `description` (plain text: escaped here).
    pub description: &'static str,
    /// `modelIdentifier`: the binary's file name.
    pub model_identifier: &'static str,
    /// The plant name silrig announces it under (its vendor annotation).
    pub plant: &'static str,
}

/// The F-16's header.
const F16_HEADER: Header = Header {
    model_name: "silrig_f16",
    description: "The Stevens & Lewis F-16 of silrig with its actuators, trimmed as silrig trims it: the built-in plant of `silrig run`, one doStep one tick",
    model_identifier: MODEL_IDENTIFIER,
    plant: PLANT_NAME,
};

/// The description with `guid` in its place.
fn render(p: &Parameters, experiment: &Experiment, input_starts: &[f64; 4], guid: &str) -> String {
    let (variables, units) = model_variables(p, input_starts);
    render_xml(&F16_HEADER, &variables, units, outputs().len(), experiment, guid)
}

/// A `modelDescription.xml` of a built-in vehicle: its `<ScalarVariable>`s (the first `outputs` of them its
/// outputs) and the units they use, with `guid` in its place. Every such FMU is a fixed-step co-simulation FMU
/// whose state can be saved and serialised.
pub(crate) fn render_xml(
    h: &Header,
    variables: &str,
    mut units: Vec<&str>,
    outputs: usize,
    experiment: &Experiment,
    guid: &str,
) -> String {
    units.sort_unstable();
    units.dedup();
    let unit_definitions: String = units.iter().map(|u| format!("    <Unit name=\"{}\"/>\n", escape(u))).collect();
    // ModelStructure indices are 1-based positions in ModelVariables; the outputs come first.
    let unknowns: String = (1..=outputs).map(|i| format!("      <Unknown index=\"{i}\"/>\n")).collect();
    let Experiment { stop_time_s, step_s } = experiment;
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription
  fmiVersion="2.0"
  modelName="{model_name}"
  guid="{guid}"
  description="{description}"
  generationTool="silrig-fmu-f16 {version}"
  variableNamingConvention="flat"
  numberOfEventIndicators="0">
  <CoSimulation
    modelIdentifier="{model_identifier}"
    canHandleVariableCommunicationStepSize="false"
    canGetAndSetFMUstate="true"
    canSerializeFMUstate="true"
    canNotUseMemoryManagementFunctions="true"
    providesDirectionalDerivative="false"/>
  <UnitDefinitions>
{unit_definitions}  </UnitDefinitions>
  <DefaultExperiment startTime="0.0" stopTime="{stop_time_s:?}" stepSize="{step_s:?}"/>
  <VendorAnnotations>
    <Tool name="silrig"><Plant name="{plant}"/></Tool>
  </VendorAnnotations>
  <ModelVariables>
{variables}  </ModelVariables>
  <ModelStructure>
    <Outputs>
{unknowns}    </Outputs>
    <InitialUnknowns>
{unknowns}    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"#,
        model_name = escape(h.model_name),
        description = escape(h.description),
        model_identifier = escape(h.model_identifier),
        plant = escape(h.plant),
        version = env!("CARGO_PKG_VERSION"),
    )
}

/// One `<ScalarVariable>` with its type's `element`, as `render_xml` lists them.
pub(crate) fn scalar_variable(
    name: &str,
    vr: u32,
    causality: &str,
    variability: &str,
    description: &str,
    element: &str,
) -> String {
    format!(
        "    <ScalarVariable name=\"{}\" valueReference=\"{vr}\" causality=\"{causality}\" variability=\"{variability}\" description=\"{}\">\n      {element}\n    </ScalarVariable>\n",
        escape(name),
        escape(description)
    )
}

/// Every `<ScalarVariable>` (outputs first, then inputs, real and boolean parameters) and the units they use, in
/// that order, each unit once per use.
fn model_variables(p: &Parameters, input_starts: &[f64; 4]) -> (String, Vec<&'static str>) {
    let mut units: Vec<&str> = Vec::new();
    let mut variables = String::new();
    let mut add = |name: &str, vr: u32, causality: &str, variability: &str, description: &str, element: String| {
        variables.push_str(&scalar_variable(name, vr, causality, variability, description, &element));
    };
    // How the rig announces this plant beyond what FMI says (`f16_signals` in silrig-flight), as a silrig
    // annotation on each variable an importer would otherwise announce differently: outputs `trace.csv` does not
    // show, the output that reports each input's actuator, and the throttle command, which FMI cannot call
    // `throttle` (the output of its position has that name) and whose command is not traced.
    let signal = |attributes: String| {
        format!("\n      <Annotations><Tool name=\"silrig\"><Signal {attributes}/></Tool></Annotations>")
    };
    let outputs = outputs();
    let inputs = inputs();
    for (vr, (name, unit, in_trace)) in outputs.iter().enumerate() {
        let shown = if *in_trace { "; a trace.csv column" } else { "" };
        let what = format!("output of the built-in F-16, {unit}{shown}");
        let mut element = format!("<Real unit=\"{}\"/>", escape(unit));
        if !in_trace {
            element += &signal("trace=\"false\"".into());
        }
        if let Some(k) = HELD_OUTPUT.iter().position(|h| *h == vr) {
            element += &signal(format!("position_of=\"{}\"", inputs[k].0));
        }
        add(name, vr as u32, "output", "continuous", &what, element);
        units.push(unit);
    }
    for (k, (name, unit, (min, max))) in inputs.iter().enumerate() {
        let rig = crate::variables::rig_input_name(name).unwrap_or(name);
        let what = format!(
            "{rig} command, {unit}, through the F-16's {rig} actuator (the rig's input `{rig}`); start: the failsafe's hold"
        );
        let start = input_starts[k];
        let mut element =
            format!("<Real unit=\"{}\" min=\"{min:?}\" max=\"{max:?}\" start=\"{start:?}\"/>", escape(unit));
        if rig != *name || k >= 3 {
            element += &signal(format!("name=\"{}\" trace=\"{}\"", INPUTS[k].0, k < 3));
        }
        add(name, FIRST_INPUT_VR + k as u32, "input", "continuous", &what, element);
        units.push(unit);
    }
    for (k, (param, v)) in REAL_PARAMETERS.iter().zip(p.reals).enumerate() {
        let (min, max) = (param.min, param.max);
        let element =
            format!("<Real unit=\"{}\" min=\"{min:?}\" max=\"{max:?}\" start=\"{v:?}\"/>", escape(param.unit));
        add(param.name, FIRST_PARAMETER_VR + k as u32, "parameter", "fixed", param.description, element);
        units.push(param.unit);
    }
    for (k, ((name, description), v)) in BOOLEAN_PARAMETERS.iter().zip(p.booleans).enumerate() {
        add(name, k as u32, "parameter", "fixed", description, format!("<Boolean start=\"{v}\"/>"));
    }
    (variables, units)
}

/// 128-bit FNV-1a: a fixed, dependency-free hash (not for security: the GUID only tells descriptions apart).
fn fnv1a_128(bytes: &[u8]) -> u128 {
    const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
    const PRIME: u128 = 0x0000000001000000000000000000013B;
    bytes.iter().fold(OFFSET, |h, b| (h ^ u128::from(*b)).wrapping_mul(PRIME))
}

/// The GUID of the description of these parameters' start values and experiment: the hash of its text with the
/// GUID left empty, as `{8-4-4-4-12}` hex.
pub fn guid(p: &Parameters, experiment: &Experiment) -> Result<String, String> {
    Ok(guid_of(&render(p, experiment, &input_starts(p)?, "")))
}

/// A description's GUID from its text with the GUID left empty.
pub(crate) fn guid_of(text: &str) -> String {
    let hex = format!("{:032x}", fnv1a_128(text.as_bytes()));
    format!("{{{}-{}-{}-{}-{}}}", &hex[..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..])
}

/// `modelDescription.xml` for these parameters' start values and experiment; the error says why the parameters
/// give no flight.
pub fn model_description(p: &Parameters, experiment: &Experiment) -> Result<String, String> {
    Ok(render(p, experiment, &input_starts(p)?, &guid(p, experiment)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_guid_follows_the_start_values() {
        let p = Parameters::default();
        let e = Experiment::default();
        let xml = model_description(&p, &e).unwrap();
        let g = guid(&p, &e).unwrap();
        assert!(xml.contains(&format!("guid=\"{g}\"")), "{xml}");
        assert_eq!(guid(&p, &e).unwrap(), g, "the same description, the same GUID");
        let mut q = p;
        q.reals[0] = 0.3;
        assert_ne!(guid(&q, &e).unwrap(), g);
        assert_ne!(guid(&p, &Experiment { stop_time_s: 20.0, step_s: 0.01 }).unwrap(), g);
        assert_eq!(xml.matches("<ScalarVariable").count(), 28 + 4 + 35 + 3);
        assert_eq!(read_start_file(&start_file(&q, &e)).unwrap(), (q, e));
        assert!(xml.contains("<Signal name=\"throttle\" trace=\"false\"/>"), "{xml}");
        assert!(xml.contains("<Signal position_of=\"throttle_cmd\"/>"), "{xml}");
        assert!(xml.contains("<Signal position_of=\"elevator\"/>"), "{xml}");
        assert_eq!(xml.matches("<Signal trace=\"false\"/>").count(), 12, "the states are not traced");
        assert!(xml.contains("<Tool name=\"silrig\"><Plant name=\"f16\"/></Tool>"), "{xml}");
    }

    #[test]
    fn a_flight_condition_with_no_trim_gives_no_description() {
        let mut p = Parameters::default();
        p.booleans[2] = true;
        // Far too slow for level flight: the trim's alpha is beyond the data.
        p.reals[8] = 30.0;
        let e = model_description(&p, &Experiment::default()).unwrap_err();
        assert!(e.starts_with("initial condition: "), "{e}");
    }
}
