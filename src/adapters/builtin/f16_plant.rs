//! The F-16 as the plant process flies it: [`F16Plant`], the [`PlantModel`] over the same
//! [`PlantRunner`] as `silrig sim` (actuators, sensor faults, RK4), announcing the F-16's signals
//! ([`silrig_flight::f16_signals`]) with the scenario's trim as its failsafe's hold values.

use silrig_flight::f16_signals::{f16_outputs, f16_signals};
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_flight::sim::{ActuatorCommand, PlantCheckpoint, PlantRunner, SetupError, StepHits};
use silrig_model::control::SurfaceCommand;
use silrig_rig::plant_model::{ActuatorFlags, PlantModel};

/// The F-16 of the scenario, at its initial condition.
pub struct F16Plant {
    runner: PlantRunner,
    signals: PlantSignals,
}

impl F16Plant {
    /// The scenario's F-16, trimmed as the scenario asks; its failsafe holds the trim surfaces of the scenario's
    /// flight condition.
    pub fn new(scenario: &Scenario) -> Result<Self, SetupError> {
        let runner = PlantRunner::new(scenario)?;
        let hold = failsafe_command(scenario, runner.initial_command());
        let s = &hold.surfaces;
        let signals = f16_signals([s.aileron_deg, s.elevator_deg, s.rudder_deg, hold.throttle]);
        Ok(Self { runner, signals })
    }
}

/// A command as the actuators take it, its inputs in the order of [`f16_signals`].
fn actuator_command(inputs: &[f64]) -> ActuatorCommand {
    let [aileron_deg, elevator_deg, rudder_deg, throttle] = [0, 1, 2, 3].map(|k| inputs[k]);
    ActuatorCommand { surfaces: SurfaceCommand { aileron_deg, elevator_deg, rudder_deg }, throttle }
}

/// The trim surfaces of the scenario's initial airspeed and altitude with the throttle `hold` holds, or `hold`
/// when level flight has no trim there ([`silrig_model::vehicle::failsafe_command`]).
fn failsafe_command(scenario: &Scenario, hold: ActuatorCommand) -> ActuatorCommand {
    silrig_model::vehicle::failsafe_command(&scenario.plant.model(), &scenario.initial, hold)
}

/// The surfaces' limits (the throttle's are not flagged, as before named signals).
fn flags(hits: &StepHits) -> ActuatorFlags {
    ActuatorFlags { saturated: hits[..3].iter().any(|h| h.position), rate_limited: hits[..3].iter().any(|h| h.rate) }
}

impl PlantModel for F16Plant {
    fn signals(&self) -> &PlantSignals {
        &self.signals
    }

    fn tick(&self) -> u64 {
        self.runner.snapshot().tick
    }

    fn t_s(&self) -> f64 {
        self.runner.snapshot().t_s
    }

    fn outputs(&self) -> Vec<f64> {
        f16_outputs(&self.runner.snapshot()).to_vec()
    }

    fn initial_inputs(&self) -> Vec<f64> {
        let c = self.runner.initial_command();
        vec![c.surfaces.aileron_deg, c.surfaces.elevator_deg, c.surfaces.rudder_deg, c.throttle]
    }

    fn step(&mut self, inputs: &[f64], last: bool) -> Result<ActuatorFlags, String> {
        let command = actuator_command(inputs);
        if last {
            return Ok(flags(&self.runner.actuate(&command)));
        }
        self.runner.step(&command).map(|hits| flags(&hits)).map_err(|exit| exit.to_string())
    }

    fn checkpoint(&self) -> Option<String> {
        serde_json::to_string(&self.runner.checkpoint()).ok()
    }

    fn restore(&mut self, text: &str, ticks: u64) -> Result<u64, String> {
        let checkpoint =
            serde_json::from_str::<PlantCheckpoint>(text).map_err(|e| format!("not a plant checkpoint: {e}"))?;
        self.runner.restore(&checkpoint, ticks)?;
        Ok(checkpoint.tick)
    }
}
