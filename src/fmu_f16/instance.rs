//! One FMU instance in safe Rust: its phase (FMI 2.0's state machine for co-simulation), its variables' values,
//! the vehicle once initialised, and its state saved, restored, serialised and read back. The C functions
//! (`ffi.rs`) only translate to and from this; every error is a message for the importer's logger.

use crate::description::{DEFAULT_STEP_S, input_starts};
use crate::variables::{BOOLEAN_PARAMETERS, FIRST_INPUT_VR, FIRST_PARAMETER_VR, Parameters, REAL_PARAMETERS};
use crate::variables::{check_real, inputs};
use silrig_model::control::SurfaceCommand;
use silrig_model::f16_outputs::{OUTPUTS_LEN, f16_outputs};
use silrig_model::plant::{F16State, STATE_LEN};
use silrig_model::vehicle::{ActuatorCommand, F16Vehicle};

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
#[derive(Debug, Clone)]
pub struct Instance {
    /// The GUID it was instantiated with (a serialised state of another description is refused).
    guid: String,
    /// The start values it was instantiated with (fmi2Reset returns to them).
    starts: Parameters,
    parameters: Parameters,
    /// Commands: aileron, elevator, rudder (deg), throttle.
    inputs: [f64; 4],
    phase: Phase,
    /// The F-16 once initialised (in initialization mode: built when the outputs are first read).
    vehicle: Option<F16Vehicle>,
    /// The communication point the next step starts at, s.
    time_s: f64,
    /// The step, fixed by the first fmi2DoStep: one doStep is one tick.
    step_s: Option<f64>,
}

/// The tag a serialised state starts with (format version 1).
const MAGIC: &[u8] = b"silrig-fmu-f16 state 1\n";

impl Instance {
    /// A new instance at these start values, under `guid` (already checked by the caller).
    pub fn new(guid: &str, starts: Parameters) -> Result<Self, String> {
        let inputs = input_starts(&starts)?;
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

    /// The GUID it was instantiated with.
    pub fn guid(&self) -> &str {
        &self.guid
    }

    /// Its phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// fmi2SetupExperiment: the start time.
    pub fn setup_experiment(&mut self, start_time_s: f64) -> Result<(), String> {
        if self.phase != Phase::Instantiated {
            return Err("fmi2SetupExperiment is only allowed after fmi2Instantiate".into());
        }
        if !start_time_s.is_finite() {
            return Err(format!("start time {start_time_s} is not a number"));
        }
        self.time_s = start_time_s;
        Ok(())
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization(&mut self) -> Result<(), String> {
        if self.phase != Phase::Instantiated {
            return Err("fmi2EnterInitializationMode is only allowed after fmi2Instantiate".into());
        }
        self.phase = Phase::Initialization;
        Ok(())
    }

    /// The vehicle of the current parameters, trimmed as `PlantRunner::new` trims it.
    fn build_vehicle(&self) -> Result<F16Vehicle, String> {
        let p = &self.parameters;
        p.check()?;
        F16Vehicle::new(p.model(), &p.initial(), &p.actuators(), p.forcing(), self.step_s.unwrap_or(DEFAULT_STEP_S))
            .map_err(|e| format!("initial condition: {e}"))
    }

    /// fmi2ExitInitializationMode: build and trim the F-16 with the parameters as set.
    pub fn exit_initialization(&mut self) -> Result<(), String> {
        if self.phase != Phase::Initialization {
            return Err("fmi2ExitInitializationMode is only allowed in initialization mode".into());
        }
        if self.vehicle.is_none() {
            self.vehicle = Some(self.build_vehicle()?);
        }
        self.phase = Phase::StepMode;
        Ok(())
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Result<(), String> {
        if !matches!(self.phase, Phase::StepMode | Phase::Failed) {
            return Err("fmi2Terminate is only allowed after initialization".into());
        }
        self.phase = Phase::Terminated;
        Ok(())
    }

    /// fmi2Reset: back to the start values, as just instantiated.
    pub fn reset(&mut self) -> Result<(), String> {
        *self = Self::new(&self.guid, self.starts)?;
        Ok(())
    }

    /// The outputs now, in value-reference order (the vehicle is built first in initialization mode).
    fn outputs(&mut self) -> Result<[f64; OUTPUTS_LEN], String> {
        if self.phase == Phase::Instantiated {
            return Err("outputs can be read from initialization mode on".into());
        }
        if self.vehicle.is_none() {
            self.vehicle = Some(self.build_vehicle()?);
        }
        let v = self.vehicle.as_ref().ok_or("no vehicle")?;
        // What PlantRunner::snapshot reports with no sensor fault and no disturbance.
        Ok(f16_outputs(&v.snapshot(v.state(), [0.0; 3])))
    }

    /// fmi2GetReal: the values of Real variables `vrs`, into `values` (as long).
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), String> {
        let outputs = if vrs.iter().any(|vr| (*vr as usize) < OUTPUTS_LEN) { Some(self.outputs()?) } else { None };
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            let k = *vr as usize;
            *value = match (k.checked_sub(FIRST_INPUT_VR as usize), k.checked_sub(FIRST_PARAMETER_VR as usize)) {
                (None, _) => outputs.map_or(f64::NAN, |o| o[k]),
                (Some(i), None) => self.inputs[i],
                (_, Some(p)) if p < REAL_PARAMETERS.len() => self.parameters.reals[p],
                _ => return Err(format!("no Real variable has value reference {vr}")),
            };
        }
        Ok(())
    }

    /// fmi2SetReal: inputs any time before fmi2Terminate, each within its range; parameters before
    /// fmi2ExitInitializationMode, each within its range. Nothing is set when one is refused.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), String> {
        let mut next = (self.parameters, self.inputs);
        for (vr, value) in vrs.iter().zip(values) {
            let k = *vr as usize;
            match (k.checked_sub(FIRST_INPUT_VR as usize), k.checked_sub(FIRST_PARAMETER_VR as usize)) {
                (None, _) => return Err(format!("{} is an output: it cannot be set", output_name(k))),
                (Some(i), None) => {
                    if matches!(self.phase, Phase::Terminated | Phase::Failed) {
                        return Err("inputs cannot be set after fmi2Terminate or an error".into());
                    }
                    let (name, _, (min, max)) = inputs()[i];
                    if !(*value >= min && *value <= max) {
                        return Err(format!("input {name} = {value} is outside {min}..{max}"));
                    }
                    next.1[i] = *value;
                }
                (_, Some(p)) if p < REAL_PARAMETERS.len() => {
                    if !matches!(self.phase, Phase::Instantiated | Phase::Initialization) {
                        return Err(format!(
                            "parameter {} is fixed: it can only be set before fmi2ExitInitializationMode",
                            REAL_PARAMETERS[p].name
                        ));
                    }
                    check_real(&REAL_PARAMETERS[p], *value).map_err(|e| format!("parameter {e}"))?;
                    next.0.reals[p] = *value;
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

    /// fmi2GetBoolean.
    pub fn get_boolean(&self, vrs: &[u32], values: &mut [bool]) -> Result<(), String> {
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            *value = *self
                .parameters
                .booleans
                .get(*vr as usize)
                .ok_or_else(|| format!("no Boolean variable has value reference {vr}"))?;
        }
        Ok(())
    }

    /// fmi2SetBoolean: parameters, before fmi2ExitInitializationMode.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<(), String> {
        let mut next = self.parameters;
        for (vr, value) in vrs.iter().zip(values) {
            let k = *vr as usize;
            let Some((name, _)) = BOOLEAN_PARAMETERS.get(k) else {
                return Err(format!("no Boolean variable has value reference {vr}"));
            };
            if !matches!(self.phase, Phase::Instantiated | Phase::Initialization) {
                return Err(format!("parameter {name} is fixed: it can only be set before fmi2ExitInitializationMode"));
            }
            next.booleans[k] = *value;
        }
        if next != self.parameters {
            self.vehicle = None;
        }
        self.parameters = next;
        Ok(())
    }

    /// fmi2DoStep: one tick, as the rig's plant flies it (`PlantRunner::step`: the actuators move under the inputs,
    /// then RK4 over the step with their positions held). The first step fixes the step size; later ones must be
    /// the same within 1e-9 relative, and are flown with exactly it. A state that leaves
    /// the model's envelope ends the flight: the instance keeps the last state inside and fails.
    pub fn do_step(&mut self, current_time_s: f64, step_s: f64) -> Result<(), String> {
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
        let [aileron_deg, elevator_deg, rudder_deg, throttle] = self.inputs;
        let command = ActuatorCommand { surfaces: SurfaceCommand { aileron_deg, elevator_deg, rudder_deg }, throttle };
        let vehicle = self.vehicle.as_mut().ok_or("no vehicle after initialization")?;
        vehicle.set_dt_s(fixed);
        match vehicle.step(&command) {
            Ok(_) => {
                self.time_s = current_time_s + step_s;
                Ok(())
            }
            Err(exit) => {
                self.phase = Phase::Failed;
                Err(exit.to_string())
            }
        }
    }

    /// The time of the last communication point reached, s.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// The state as bytes (fmi2SerializeFMUstate), which [`Instance::deserialize`] reads back into the same state.
    pub fn serialize(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(512);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&(self.guid.len() as u32).to_le_bytes());
        b.extend_from_slice(self.guid.as_bytes());
        b.push(self.phase.code());
        let reals = self.starts.reals.iter().chain(&self.parameters.reals).chain(&self.inputs);
        for v in reals.chain([&self.time_s, &self.step_s.unwrap_or(f64::NAN)]) {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend(self.starts.booleans.iter().chain(&self.parameters.booleans).map(|v| u8::from(*v)));
        match &self.vehicle {
            None => b.push(0),
            Some(v) => {
                b.push(1);
                b.extend_from_slice(&v.tick().to_le_bytes());
                let held = v.held();
                let positions = [held.surfaces_deg[0], held.surfaces_deg[1], held.surfaces_deg[2], held.throttle];
                for x in v.state().to_array().iter().chain(&positions) {
                    b.extend_from_slice(&x.to_le_bytes());
                }
            }
        }
        b
    }

    /// A state from [`Instance::serialize`]'s bytes, for an instance of the same description (`guid`). The vehicle
    /// is built again from the saved parameters (the same trim: it is a function of them) and set to the saved
    /// tick, state and actuator positions.
    pub fn deserialize(guid: &str, bytes: &[u8]) -> Result<Self, String> {
        let mut r = Reader { bytes, at: 0 };
        if r.take(MAGIC.len())? != MAGIC {
            return Err("not a serialised state of this FMU".into());
        }
        let len = u32::from_le_bytes(r.array()?) as usize;
        let saved_guid = std::str::from_utf8(r.take(len)?).map_err(|_| "a GUID that is not text")?;
        if saved_guid != guid {
            return Err(format!("a serialised state of another model description: GUID {saved_guid}, not {guid}"));
        }
        let phase = Phase::from_code(r.byte()?).ok_or("an unknown phase")?;
        let mut starts = Parameters::default();
        let mut parameters = Parameters::default();
        for v in starts.reals.iter_mut().chain(parameters.reals.iter_mut()) {
            *v = r.f64()?;
        }
        let inputs = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
        let time_s = r.f64()?;
        let step_s = Some(r.f64()?).filter(|s| !s.is_nan());
        for v in starts.booleans.iter_mut().chain(parameters.booleans.iter_mut()) {
            *v = r.byte()? != 0;
        }
        let mut instance = Self { guid: guid.into(), starts, parameters, inputs, phase, vehicle: None, time_s, step_s };
        if r.byte()? == 1 {
            let tick = u64::from_le_bytes(r.array()?);
            let mut x = [0.0; STATE_LEN];
            for v in x.iter_mut() {
                *v = r.f64()?;
            }
            let positions = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
            let mut vehicle = instance.build_vehicle()?;
            vehicle.restore(tick, F16State::from_array(&x), positions);
            instance.vehicle = Some(vehicle);
        }
        if r.at != bytes.len() {
            return Err(format!("{} bytes after the state", bytes.len() - r.at));
        }
        Ok(instance)
    }
}

/// The name of output `k`, for messages.
fn output_name(k: usize) -> &'static str {
    crate::variables::outputs()[k].0
}

/// Reads a serialised state front to back; running short is an error, never a panic.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|e| *e <= self.bytes.len()).ok_or("the state is cut short")?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    fn byte(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stepping() -> Instance {
        let mut i = Instance::new("{g}", Parameters::default()).unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        i
    }

    fn outputs(i: &mut Instance) -> Vec<f64> {
        let vrs: Vec<u32> = (0..OUTPUTS_LEN as u32).collect();
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
        let mut b = Instance::deserialize("{g}", &bytes).unwrap();
        assert_eq!(b.serialize(), bytes);
        for _ in 0..50 {
            let t = a.time_s();
            a.do_step(t, 0.01).unwrap();
            b.do_step(t, 0.01).unwrap();
            let (oa, ob) = (outputs(&mut a), outputs(&mut b));
            assert!(oa.iter().zip(&ob).all(|(x, y)| x.to_bits() == y.to_bits()), "{oa:?} {ob:?}");
        }
        assert!(Instance::deserialize("{other}", &bytes).unwrap_err().contains("another model description"));
        assert_eq!(Instance::deserialize("{g}", &bytes[..bytes.len() - 1]).unwrap_err(), "the state is cut short");
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
}
