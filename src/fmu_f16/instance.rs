//! One FMU instance in safe Rust, for either built-in vehicle ([`VehicleModel`], in `models.rs`): its phase (FMI
//! 2.0's state machine for co-simulation), its variables' values, the vehicle once initialised, and its state
//! saved, restored, serialised and read back. The C functions (`ffi.rs`) only translate to and from
//! [`FmuInstance`]; every error is a message for the importer's logger.

use silrig_fmu_f16_description::variables::{RealParameter, check_real};
use std::fmt::Debug;

/// A vehicle as the FMU flies it: its variables (outputs, then four inputs, then Real parameters, from value
/// reference 0; Booleans from 0 of their own), how it is built from its parameters, stepped and saved.
pub trait VehicleModel: Debug + 'static {
    /// The tag a serialised state starts with.
    const MAGIC: &'static [u8];
    /// The parameters' values.
    type Params: Copy + PartialEq + Debug + Default;
    /// The vehicle once built.
    type Vehicle: Clone + Debug;
    /// The outputs' names, in value-reference order from 0.
    fn output_names() -> Vec<&'static str>;
    /// The inputs' names and ranges, in value-reference order after the outputs.
    fn inputs() -> [(&'static str, (f64, f64)); 4];
    /// The Real parameters, in value-reference order after the inputs.
    fn real_parameters() -> Vec<RealParameter>;
    /// The Boolean parameters (name, what), in value-reference order from 0.
    fn boolean_parameters() -> &'static [(&'static str, &'static str)];
    /// The Real parameters' values.
    fn reals(p: &Self::Params) -> &[f64];
    /// The same, writable.
    fn reals_mut(p: &mut Self::Params) -> &mut [f64];
    /// The Boolean parameters' values.
    fn booleans(p: &Self::Params) -> &[bool];
    /// The same, writable.
    fn booleans_mut(p: &mut Self::Params) -> &mut [bool];
    /// The inputs' start values for these parameters; the error says why they give no vehicle.
    fn input_starts(p: &Self::Params) -> Result<[f64; 4], String>;
    /// The vehicle of these parameters at t = 0, flown at `step_s`.
    fn build(p: &Self::Params, step_s: f64) -> Result<Self::Vehicle, String>;
    /// Its outputs now, in value-reference order.
    fn outputs(v: &Self::Vehicle) -> Vec<f64>;
    /// One tick of `step_s` with `inputs` held over it; an error ends the flight.
    fn step(v: &mut Self::Vehicle, inputs: &[f64; 4], step_s: f64) -> Result<(), String>;
    /// Its state after the tick counter, as bytes.
    fn save(v: &Self::Vehicle, out: &mut Vec<u8>);
    /// The vehicle of `p` set to the state [`VehicleModel::save`] wrote.
    fn restore(p: &Self::Params, step_s: f64, r: &mut Reader) -> Result<Self::Vehicle, String>;
}

/// The communication step an instance builds its vehicle with before the first fmi2DoStep fixes it, s.
pub const DEFAULT_STEP_S: f64 = silrig_fmu_f16_description::description::DEFAULT_STEP_S;

/// Where an instance is in FMI 2.0's co-simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// After fmi2Instantiate (and fmi2SetupExperiment): parameters and inputs may be set.
    Instantiated,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode: as above, and the outputs are computed.
    Initialization,
    /// Stepping: inputs may be set, outputs read, fmi2DoStep called.
    StepMode,
    /// After fmi2Terminate: values may be read.
    Terminated,
    /// After an error (the flight left the model's envelope): values may be read, the instance reset or freed.
    Failed,
}

impl Phase {
    fn code(self) -> u8 {
        match self {
            Phase::Instantiated => 0,
            Phase::Initialization => 1,
            Phase::StepMode => 2,
            Phase::Terminated => 3,
            Phase::Failed => 4,
        }
    }

    fn from_code(code: u8) -> Option<Self> {
        [Phase::Instantiated, Phase::Initialization, Phase::StepMode, Phase::Terminated, Phase::Failed]
            .into_iter()
            .find(|p| p.code() == code)
    }
}

/// An instance's whole state: what fmi2GetFMUstate copies, so a copy set back continues bit for bit.
#[derive(Debug)]
pub struct Instance<M: VehicleModel> {
    /// The GUID it was instantiated with (a serialised state of another description is refused).
    guid: String,
    /// The start values it was instantiated with (fmi2Reset returns to them).
    starts: M::Params,
    parameters: M::Params,
    /// The four inputs' values.
    inputs: [f64; 4],
    phase: Phase,
    /// The vehicle once initialised (in initialization mode: built when the outputs are first read).
    vehicle: Option<M::Vehicle>,
    /// The communication point the next step starts at, s.
    time_s: f64,
    /// The step, fixed by the first fmi2DoStep: one doStep is one tick.
    step_s: Option<f64>,
}

impl<M: VehicleModel> Clone for Instance<M> {
    fn clone(&self) -> Self {
        Self { guid: self.guid.clone(), vehicle: self.vehicle.clone(), ..*self }
    }
}

/// What the C functions call on an instance of either vehicle.
pub trait FmuInstance: Debug {
    /// The GUID it was instantiated with.
    fn guid(&self) -> &str;
    /// Its phase.
    fn phase(&self) -> Phase;
    /// fmi2SetupExperiment: the start time.
    fn setup_experiment(&mut self, start_time_s: f64) -> Result<(), String>;
    /// fmi2EnterInitializationMode.
    fn enter_initialization(&mut self) -> Result<(), String>;
    /// fmi2ExitInitializationMode: the vehicle is built with the parameters as set.
    fn exit_initialization(&mut self) -> Result<(), String>;
    /// fmi2Terminate.
    fn terminate(&mut self) -> Result<(), String>;
    /// fmi2Reset: back to the start values, as just instantiated.
    fn reset(&mut self) -> Result<(), String>;
    /// fmi2GetReal: the values of Real variables `vrs`, into `values` (as long).
    fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), String>;
    /// fmi2SetReal: inputs any time before fmi2Terminate, each within its range; parameters before
    /// fmi2ExitInitializationMode, each within its range. Nothing is set when one is refused.
    fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), String>;
    /// fmi2GetBoolean.
    fn get_boolean(&self, vrs: &[u32], values: &mut [bool]) -> Result<(), String>;
    /// fmi2SetBoolean: parameters, before fmi2ExitInitializationMode.
    fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<(), String>;
    /// fmi2DoStep: one tick, as the rig's plant flies it. The first step fixes the step size; later ones must be
    /// the same within 1e-9 relative, and are flown with exactly it. A vehicle whose step fails (the F-16 leaving
    /// its envelope) ends the flight: the instance keeps the last state and fails.
    fn do_step(&mut self, current_time_s: f64, step_s: f64) -> Result<(), String>;
    /// The time of the last communication point reached, s.
    fn time_s(&self) -> f64;
    /// The state as bytes (fmi2SerializeFMUstate), which [`FmuInstance::deserialize_same`] reads back.
    fn serialize(&self) -> Vec<u8>;
    /// A state of this instance's vehicle and description from [`FmuInstance::serialize`]'s bytes.
    fn deserialize_same(&self, bytes: &[u8]) -> Result<Box<dyn FmuInstance>, String>;
    /// A copy (fmi2GetFMUstate).
    fn boxed(&self) -> Box<dyn FmuInstance>;
}

impl<M: VehicleModel> Instance<M> {
    /// A new instance at these start values, under `guid` (already checked by the caller).
    pub fn new(guid: &str, starts: M::Params) -> Result<Self, String> {
        let inputs = M::input_starts(&starts)?;
        Ok(Self {
            guid: guid.to_string(),
            starts,
            parameters: starts,
            inputs,
            phase: Phase::Instantiated,
            vehicle: None,
            time_s: 0.0,
            step_s: None,
        })
    }

    /// The vehicle of the current parameters.
    fn build_vehicle(&self) -> Result<M::Vehicle, String> {
        M::build(&self.parameters, self.step_s.unwrap_or(DEFAULT_STEP_S))
    }

    /// The outputs now, in value-reference order (the vehicle is built first in initialization mode).
    fn outputs(&mut self) -> Result<Vec<f64>, String> {
        if self.phase == Phase::Instantiated {
            return Err("outputs can be read from initialization mode on".into());
        }
        if self.vehicle.is_none() {
            self.vehicle = Some(self.build_vehicle()?);
        }
        Ok(M::outputs(self.vehicle.as_ref().ok_or("no vehicle")?))
    }

    /// A state from [`FmuInstance::serialize`]'s bytes, for an instance of the same description (`guid`). The
    /// vehicle is built again from the saved parameters and set to the saved state.
    pub fn deserialize(guid: &str, bytes: &[u8]) -> Result<Self, String> {
        let mut r = Reader { bytes, at: 0 };
        if r.take(M::MAGIC.len())? != M::MAGIC {
            return Err("not a serialised state of this FMU".into());
        }
        let len = u32::from_le_bytes(r.array()?) as usize;
        let saved_guid = std::str::from_utf8(r.take(len)?).map_err(|_| "a GUID that is not text")?;
        if saved_guid != guid {
            return Err(format!("a serialised state of another model description: GUID {saved_guid}, not {guid}"));
        }
        let phase = Phase::from_code(r.byte()?).ok_or("an unknown phase")?;
        // Every value is overwritten by the saved one.
        let (mut starts, mut parameters) = (M::Params::default(), M::Params::default());
        for v in M::reals_mut(&mut starts).iter_mut().chain(M::reals_mut(&mut parameters).iter_mut()) {
            *v = r.f64()?;
        }
        let inputs = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
        let time_s = r.f64()?;
        let step_s = Some(r.f64()?).filter(|s| !s.is_nan());
        for v in M::booleans_mut(&mut starts).iter_mut().chain(M::booleans_mut(&mut parameters).iter_mut()) {
            *v = r.byte()? != 0;
        }
        let vehicle = match r.byte()? {
            1 => Some(M::restore(&parameters, step_s.unwrap_or(DEFAULT_STEP_S), &mut r)?),
            _ => None,
        };
        if r.at != bytes.len() {
            return Err(format!("{} bytes after the state", bytes.len() - r.at));
        }
        Ok(Self { guid: guid.into(), starts, parameters, inputs, phase, vehicle, time_s, step_s })
    }
}

impl<M: VehicleModel> FmuInstance for Instance<M> {
    fn guid(&self) -> &str {
        &self.guid
    }

    fn phase(&self) -> Phase {
        self.phase
    }

    fn setup_experiment(&mut self, start_time_s: f64) -> Result<(), String> {
        if self.phase != Phase::Instantiated {
            return Err("fmi2SetupExperiment is only allowed after fmi2Instantiate".into());
        }
        if !start_time_s.is_finite() {
            return Err(format!("start time {start_time_s} is not a number"));
        }
        self.time_s = start_time_s;
        Ok(())
    }

    fn enter_initialization(&mut self) -> Result<(), String> {
        if self.phase != Phase::Instantiated {
            return Err("fmi2EnterInitializationMode is only allowed after fmi2Instantiate".into());
        }
        self.phase = Phase::Initialization;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), String> {
        if self.phase != Phase::Initialization {
            return Err("fmi2ExitInitializationMode is only allowed in initialization mode".into());
        }
        if self.vehicle.is_none() {
            self.vehicle = Some(self.build_vehicle()?);
        }
        self.phase = Phase::StepMode;
        Ok(())
    }

    fn terminate(&mut self) -> Result<(), String> {
        if !matches!(self.phase, Phase::StepMode | Phase::Failed) {
            return Err("fmi2Terminate is only allowed after initialization".into());
        }
        self.phase = Phase::Terminated;
        Ok(())
    }

    fn reset(&mut self) -> Result<(), String> {
        *self = Self::new(&self.guid, self.starts)?;
        Ok(())
    }

    fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), String> {
        let n_outputs = M::output_names().len();
        let first_parameter = n_outputs + self.inputs.len();
        let outputs = if vrs.iter().any(|vr| (*vr as usize) < n_outputs) { Some(self.outputs()?) } else { None };
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            let k = *vr as usize;
            *value = match (k.checked_sub(n_outputs), k.checked_sub(first_parameter)) {
                (None, _) => outputs.as_ref().map_or(f64::NAN, |o| o[k]),
                (Some(i), None) => self.inputs[i],
                (_, Some(p)) if p < M::reals(&self.parameters).len() => M::reals(&self.parameters)[p],
                _ => return Err(format!("no Real variable has value reference {vr}")),
            };
        }
        Ok(())
    }

    fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), String> {
        let (outputs, reals) = (M::output_names(), M::real_parameters());
        let first_parameter = outputs.len() + self.inputs.len();
        let mut next = (self.parameters, self.inputs);
        for (vr, value) in vrs.iter().zip(values) {
            let k = *vr as usize;
            match (k.checked_sub(outputs.len()), k.checked_sub(first_parameter)) {
                (None, _) => return Err(format!("{} is an output: it cannot be set", outputs[k])),
                (Some(i), None) => {
                    if matches!(self.phase, Phase::Terminated | Phase::Failed) {
                        return Err("inputs cannot be set after fmi2Terminate or an error".into());
                    }
                    let (name, (min, max)) = M::inputs()[i];
                    if !(*value >= min && *value <= max) {
                        return Err(format!("input {name} = {value} is outside {min}..{max}"));
                    }
                    next.1[i] = *value;
                }
                (_, Some(p)) if p < reals.len() => {
                    if !matches!(self.phase, Phase::Instantiated | Phase::Initialization) {
                        return Err(format!(
                            "parameter {} is fixed: it can only be set before fmi2ExitInitializationMode",
                            reals[p].name
                        ));
                    }
                    check_real(&reals[p], *value).map_err(|e| format!("parameter {e}"))?;
                    M::reals_mut(&mut next.0)[p] = *value;
                }
                _ => return Err(format!("no Real variable has value reference {vr}")),
            }
        }
        if next.0 != self.parameters {
            // Outputs read in initialization mode came from the old parameters.
            self.vehicle = None;
        }
        (self.parameters, self.inputs) = next;
        Ok(())
    }

    fn get_boolean(&self, vrs: &[u32], values: &mut [bool]) -> Result<(), String> {
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            *value = *M::booleans(&self.parameters)
                .get(*vr as usize)
                .ok_or_else(|| format!("no Boolean variable has value reference {vr}"))?;
        }
        Ok(())
    }

    fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<(), String> {
        let mut next = self.parameters;
        for (vr, value) in vrs.iter().zip(values) {
            let k = *vr as usize;
            let Some((name, _)) = M::boolean_parameters().get(k) else {
                return Err(format!("no Boolean variable has value reference {vr}"));
            };
            if !matches!(self.phase, Phase::Instantiated | Phase::Initialization) {
                return Err(format!("parameter {name} is fixed: it can only be set before fmi2ExitInitializationMode"));
            }
            M::booleans_mut(&mut next)[k] = *value;
        }
        if next != self.parameters {
            self.vehicle = None;
        }
        self.parameters = next;
        Ok(())
    }

    fn do_step(&mut self, current_time_s: f64, step_s: f64) -> Result<(), String> {
        if self.phase != Phase::StepMode {
            return Err("fmi2DoStep is only allowed after fmi2ExitInitializationMode".into());
        }
        if !(step_s > 0.0 && step_s.is_finite()) {
            return Err(format!("communication step {step_s} s: must be above 0"));
        }
        // Importers that compute the step as a difference of communication points hand in 0.01 give or take an
        // ulp: that is the same tick, flown with the fixed step.
        let fixed = *self.step_s.get_or_insert(step_s);
        if (step_s - fixed).abs() > 1e-9 * fixed {
            return Err(format!(
                "communication step {step_s} s: this FMU steps at a fixed {fixed} s (one step is one tick of the rig)"
            ));
        }
        if (current_time_s - self.time_s).abs() > 1e-9 * step_s.max(current_time_s.abs()) {
            return Err(format!("fmi2DoStep from t = {current_time_s} s, but the FMU is at t = {} s", self.time_s));
        }
        let vehicle = self.vehicle.as_mut().ok_or("no vehicle after initialization")?;
        match M::step(vehicle, &self.inputs, fixed) {
            Ok(()) => {
                self.time_s = current_time_s + step_s;
                Ok(())
            }
            Err(e) => {
                self.phase = Phase::Failed;
                Err(e)
            }
        }
    }

    fn time_s(&self) -> f64 {
        self.time_s
    }

    fn serialize(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(512);
        b.extend_from_slice(M::MAGIC);
        b.extend_from_slice(&(self.guid.len() as u32).to_le_bytes());
        b.extend_from_slice(self.guid.as_bytes());
        b.push(self.phase.code());
        let reals = M::reals(&self.starts).iter().chain(M::reals(&self.parameters)).chain(&self.inputs);
        for v in reals.chain([&self.time_s, &self.step_s.unwrap_or(f64::NAN)]) {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let booleans = M::booleans(&self.starts).iter().chain(M::booleans(&self.parameters));
        b.extend(booleans.map(|v| u8::from(*v)));
        match &self.vehicle {
            None => b.push(0),
            Some(v) => {
                b.push(1);
                M::save(v, &mut b);
            }
        }
        b
    }

    fn deserialize_same(&self, bytes: &[u8]) -> Result<Box<dyn FmuInstance>, String> {
        Ok(Box::new(Self::deserialize(&self.guid, bytes)?))
    }

    fn boxed(&self) -> Box<dyn FmuInstance> {
        Box::new(self.clone())
    }
}

/// Reads a serialised state front to back; running short is an error, never a panic.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|e| *e <= self.bytes.len()).ok_or("the state is cut short")?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    /// The next `N` bytes.
    pub fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    /// The next byte.
    pub fn byte(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    /// The next little-endian f64.
    pub fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::{F16, Quad};
    use crate::variables::{FIRST_INPUT_VR, FIRST_PARAMETER_VR, Parameters};
    use silrig_fmu_f16_description::quad::{QUAD_FIRST_INPUT_VR, QuadStarts};
    use silrig_model::f16_outputs::OUTPUTS_LEN;
    use silrig_model::quad::outputs::{OUTPUTS, output_index};

    fn stepping() -> Instance<F16> {
        let mut i = Instance::<F16>::new("{g}", Parameters::default()).unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        i
    }

    fn outputs(i: &mut dyn FmuInstance, n: usize) -> Vec<f64> {
        let vrs: Vec<u32> = (0..n as u32).collect();
        let mut out = vec![0.0; vrs.len()];
        i.get_real(&vrs, &mut out).unwrap();
        out
    }

    #[test]
    fn a_serialised_state_continues_bit_for_bit() {
        let mut a = stepping();
        a.set_real(&[FIRST_INPUT_VR + 1], &[-3.0]).unwrap();
        for k in 0..50 {
            a.do_step(k as f64 * 0.01, 0.01).unwrap();
        }
        let bytes = a.serialize();
        let mut b = Instance::<F16>::deserialize("{g}", &bytes).unwrap();
        assert_eq!(b.serialize(), bytes);
        for _ in 0..50 {
            let t = a.time_s();
            a.do_step(t, 0.01).unwrap();
            b.do_step(t, 0.01).unwrap();
            let (oa, ob) = (outputs(&mut a, OUTPUTS_LEN), outputs(&mut b, OUTPUTS_LEN));
            assert!(oa.iter().zip(&ob).all(|(x, y)| x.to_bits() == y.to_bits()), "{oa:?} {ob:?}");
        }
        assert!(Instance::<F16>::deserialize("{other}", &bytes).unwrap_err().contains("another model description"));
        assert_eq!(
            Instance::<F16>::deserialize("{g}", &bytes[..bytes.len() - 1]).unwrap_err(),
            "the state is cut short"
        );
    }

    #[test]
    fn parameters_are_fixed_after_initialization_and_inputs_keep_their_range() {
        let mut i = stepping();
        let e = i.set_real(&[FIRST_PARAMETER_VR], &[0.3]).unwrap_err();
        assert_eq!(e, "parameter xcg is fixed: it can only be set before fmi2ExitInitializationMode");
        let e = i.set_real(&[FIRST_INPUT_VR + 3], &[1.5]).unwrap_err();
        assert_eq!(e, "input throttle_cmd = 1.5 is outside 0..1");
        assert!(i.set_real(&[3], &[0.0]).unwrap_err().starts_with("alpha_deg is an output"));
        let e = i.do_step(0.0, 0.02).and_then(|_| i.do_step(0.02, 0.01)).unwrap_err();
        assert!(e.contains("fixed 0.02 s"), "{e}");
    }

    #[test]
    fn the_quadrotor_climbs_and_a_serialised_state_continues_bit_for_bit() {
        let mut a = Instance::<Quad>::new("{q}", QuadStarts::default()).unwrap();
        a.enter_initialization().unwrap();
        let mut hover_alt = vec![0.0; 1];
        let alt_vr = output_index("alt_m").unwrap() as u32;
        a.exit_initialization().unwrap();
        a.get_real(&[alt_vr], &mut hover_alt).unwrap();
        assert_eq!(hover_alt, [0.0], "it starts on the ground");
        a.set_real(
            &[QUAD_FIRST_INPUT_VR, QUAD_FIRST_INPUT_VR + 1, QUAD_FIRST_INPUT_VR + 2, QUAD_FIRST_INPUT_VR + 3],
            &[0.8; 4],
        )
        .unwrap();
        for k in 0..300 {
            a.do_step(k as f64 * 0.001, 0.001).unwrap();
        }
        let bytes = a.serialize();
        let mut b = Instance::<Quad>::deserialize("{q}", &bytes).unwrap();
        assert_eq!(b.serialize(), bytes);
        for _ in 0..200 {
            let t = a.time_s();
            a.do_step(t, 0.001).unwrap();
            b.do_step(t, 0.001).unwrap();
            let (oa, ob) = (outputs(&mut a, OUTPUTS.len()), outputs(&mut b, OUTPUTS.len()));
            assert!(oa.iter().zip(&ob).all(|(x, y)| x.to_bits() == y.to_bits()), "{oa:?} {ob:?}");
        }
        assert!(outputs(&mut a, OUTPUTS.len())[alt_vr as usize] > 0.1, "full motors lift it");
        let e = a.set_real(&[QUAD_FIRST_INPUT_VR], &[1.5]).unwrap_err();
        assert_eq!(e, "input motor1 = 1.5 is outside 0..1");
        let e = Instance::<F16>::deserialize("{q}", &bytes).unwrap_err();
        assert_eq!(e, "not a serialised state of this FMU", "a quadrotor's state is not the F-16's");
    }
}
