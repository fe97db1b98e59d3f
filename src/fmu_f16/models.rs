//! The two built-in vehicles as the FMU flies them ([`VehicleModel`]): [`F16`], over the very
//! [`F16Vehicle`] `silrig sim` and the plant process fly, and [`Quad`], over the [`QuadVehicle`] the quadrotor's
//! plant flies. Each says its variables, builds its vehicle from its parameters, steps it and saves its state.

use crate::description::input_starts;
use crate::instance::{Reader, VehicleModel};
use crate::variables::{BOOLEAN_PARAMETERS, Parameters, REAL_PARAMETERS, RealParameter, inputs, outputs};
use silrig_fmu_f16_description::quad::{QuadStarts, quad_parameters};
use silrig_model::control::SurfaceCommand;
use silrig_model::f16_outputs::f16_outputs;
use silrig_model::plant::{F16State, STATE_LEN};
use silrig_model::quad::QuadVehicle;
use silrig_model::quad::outputs::{INPUT_RANGE, INPUTS, OUTPUTS, quad_outputs};
use silrig_model::vehicle::{ActuatorCommand, F16Vehicle};

/// The Stevens & Lewis F-16 with its actuators, trimmed as `PlantRunner::new` trims it.
#[derive(Debug)]
pub struct F16;

impl VehicleModel for F16 {
    const MAGIC: &'static [u8] = b"silrig-fmu-f16 state 1\n";
    type Params = Parameters;
    type Vehicle = F16Vehicle;

    fn output_names() -> Vec<&'static str> {
        outputs().iter().map(|o| o.0).collect()
    }

    fn inputs() -> [(&'static str, (f64, f64)); 4] {
        inputs().map(|(name, _, range)| (name, range))
    }

    fn real_parameters() -> Vec<RealParameter> {
        REAL_PARAMETERS.to_vec()
    }

    fn boolean_parameters() -> &'static [(&'static str, &'static str)] {
        &BOOLEAN_PARAMETERS
    }

    fn reals(p: &Parameters) -> &[f64] {
        &p.reals
    }

    fn reals_mut(p: &mut Parameters) -> &mut [f64] {
        &mut p.reals
    }

    fn booleans(p: &Parameters) -> &[bool] {
        &p.booleans
    }

    fn booleans_mut(p: &mut Parameters) -> &mut [bool] {
        &mut p.booleans
    }

    fn input_starts(p: &Parameters) -> Result<[f64; 4], String> {
        input_starts(p)
    }

    fn build(p: &Parameters, step_s: f64) -> Result<F16Vehicle, String> {
        p.check()?;
        F16Vehicle::new(p.model(), &p.initial(), &p.actuators(), p.forcing(), step_s)
            .map_err(|e| format!("initial condition: {e}"))
    }

    /// What PlantRunner::snapshot reports with no sensor fault and no disturbance.
    fn outputs(v: &F16Vehicle) -> Vec<f64> {
        f16_outputs(&v.snapshot(v.state(), [0.0; 3])).to_vec()
    }

    /// As `PlantRunner::step`: the actuators move under the inputs, then RK4 over the step with their positions
    /// held; a state that leaves the model's envelope is an error (the vehicle keeps the last state inside).
    fn step(v: &mut F16Vehicle, inputs: &[f64; 4], step_s: f64) -> Result<(), String> {
        let [aileron_deg, elevator_deg, rudder_deg, throttle] = *inputs;
        let command = ActuatorCommand { surfaces: SurfaceCommand { aileron_deg, elevator_deg, rudder_deg }, throttle };
        v.set_dt_s(step_s);
        v.step(&command).map(|_| ()).map_err(|exit| exit.to_string())
    }

    fn save(v: &F16Vehicle, b: &mut Vec<u8>) {
        b.extend_from_slice(&v.tick().to_le_bytes());
        let held = v.held();
        let positions = [held.surfaces_deg[0], held.surfaces_deg[1], held.surfaces_deg[2], held.throttle];
        for x in v.state().to_array().iter().chain(&positions) {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// Built again from the saved parameters (the same trim: it is a function of them), then set to the saved
    /// tick, state and actuator positions.
    fn restore(p: &Parameters, step_s: f64, r: &mut Reader) -> Result<F16Vehicle, String> {
        let tick = u64::from_le_bytes(r.array()?);
        let mut x = [0.0; STATE_LEN];
        for v in x.iter_mut() {
            *v = r.f64()?;
        }
        let positions = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
        let mut vehicle = Self::build(p, step_s)?;
        vehicle.restore(tick, F16State::from_array(&x), positions);
        Ok(vehicle)
    }
}

/// The X quadrotor, its parameters those of `[plant.parameters]`. Its motors take the inputs as the rig's
/// actuators pass commands within 0..1 through: one tick commands them and integrates the step (`QuadPlant::step`).
#[derive(Debug)]
pub struct Quad;

impl VehicleModel for Quad {
    const MAGIC: &'static [u8] = b"silrig-fmu-quad state 1\n";
    type Params = QuadStarts;
    type Vehicle = QuadVehicle;

    fn output_names() -> Vec<&'static str> {
        OUTPUTS.iter().map(|o| o.0).collect()
    }

    fn inputs() -> [(&'static str, (f64, f64)); 4] {
        INPUTS.map(|(name, _)| (name, INPUT_RANGE))
    }

    fn real_parameters() -> Vec<RealParameter> {
        quad_parameters().to_vec()
    }

    fn boolean_parameters() -> &'static [(&'static str, &'static str)] {
        &[]
    }

    fn reals(p: &QuadStarts) -> &[f64] {
        &p.reals
    }

    fn reals_mut(p: &mut QuadStarts) -> &mut [f64] {
        &mut p.reals
    }

    fn booleans(_: &QuadStarts) -> &[bool] {
        &[]
    }

    fn booleans_mut(_: &mut QuadStarts) -> &mut [bool] {
        &mut []
    }

    fn input_starts(p: &QuadStarts) -> Result<[f64; 4], String> {
        p.input_starts()
    }

    fn build(p: &QuadStarts, _step_s: f64) -> Result<QuadVehicle, String> {
        p.vehicle()
    }

    fn outputs(v: &QuadVehicle) -> Vec<f64> {
        quad_outputs(v).to_vec()
    }

    fn step(v: &mut QuadVehicle, inputs: &[f64; 4], step_s: f64) -> Result<(), String> {
        v.command(*inputs);
        v.step(step_s);
        Ok(())
    }

    fn save(v: &QuadVehicle, b: &mut Vec<u8>) {
        let numbers = v.state.x.iter().chain(&v.motor_commands).chain([&v.touchdown_speed_mps]);
        for x in numbers {
            b.extend_from_slice(&x.to_le_bytes());
        }
        b.push(u8::from(v.on_ground));
    }

    fn restore(p: &QuadStarts, _step_s: f64, r: &mut Reader) -> Result<QuadVehicle, String> {
        let mut vehicle = p.vehicle()?;
        for x in vehicle.state.x.iter_mut().chain(vehicle.motor_commands.iter_mut()) {
            *x = r.f64()?;
        }
        vehicle.touchdown_speed_mps = r.f64()?;
        vehicle.on_ground = r.byte()? != 0;
        Ok(vehicle)
    }
}
