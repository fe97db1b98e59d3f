//! Our controller as a [`Controller`]: [`AttitudeLaw`], the paper's adaptive SMC/RBF law
//! ([`silrig_model::control::AttitudeController`], the same as `silrig sim`) flown by the rig's session
//! ([`silrig_rig::controller::serve`]). With a fault plan the session asks for its checkpoint every few ticks;
//! restarted with `--resume`, it restores its RBF weights, so it need not re-learn them.

use silrig_flight::f16_signals::F16Outputs;
use silrig_flight::scenario::Scenario;
use silrig_flight::setpoints::SetpointTrack;
use silrig_flight::signals::PlantSignals;
use silrig_flight::sim::{measurement, setpoint_rad, write_attitude_diagnostics};
use silrig_model::control::AttitudeController;
use silrig_rig::controller::Controller;
use silrig_wire::wire::PlantSample;

/// The paper's adaptive SMC/RBF controller behind the [`Controller`] trait; its checkpoint is its RBF weights. It
/// reads the F-16's states by name ([`F16Outputs`]) and commands the inputs `aileron`, `elevator` and `rudder`,
/// leaving any other input (the throttle) where it is.
pub struct AttitudeLaw {
    controller: AttitudeController,
    /// phi, theta and psi's set points over the run, deg: read at each sample's time.
    attitude: [SetpointTrack; 3],
    outputs: Option<F16Outputs>,
    surfaces: [usize; 3],
    /// The plant's accepted range of each of `surfaces`, deg.
    ranges: [(f64, f64); 3],
}

impl AttitudeLaw {
    /// The scenario's controller, with zero weights.
    pub fn new(scenario: &Scenario) -> Self {
        let tables = silrig_model::plant::F16Model::new(scenario.plant.xcg).tables();
        Self {
            controller: silrig_flight::sim::attitude_controller(scenario, tables),
            attitude: scenario.attitude_setpoints(),
            outputs: None,
            surfaces: [0, 1, 2],
            ranges: [(f64::NEG_INFINITY, f64::INFINITY); 3],
        }
    }
}

impl Controller for AttitudeLaw {
    fn diagnostic_names(&self) -> Vec<String> {
        silrig_flight::trace::attitude_diagnostic_names(self.controller.gains().rbf.nodes())
    }

    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String> {
        self.outputs = Some(F16Outputs::resolve(plant)?);
        self.surfaces = [plant.input("aileron")?, plant.input("elevator")?, plant.input("rudder")?];
        self.ranges = self.surfaces.map(|i| (plant.inputs[i].min, plant.inputs[i].max));
        Ok(())
    }

    fn step(&mut self, sample: &PlantSample, dt_s: f64, command: &mut [f64], diagnostics: &mut [f64]) {
        let outputs = self.outputs.as_ref().expect("connect comes before the first step");
        let snap = outputs.snapshot(sample.header.tick, sample.t_sim_s, sample.outputs());
        let (surfaces, diag) = self.controller.step(&measurement(&snap), &setpoint_rad(&self.attitude, snap.t_s), dt_s);
        write_attitude_diagnostics(diagnostics, &diag, &self.controller);
        // Limited to the range the plant accepts, as a flight computer limits its commands: a surface stuck
        // hard-over drives the sliding surface, and with it the demand, past any travel (the soak's elevator
        // hard-over: -91.8 deg against a ±90 range), and a refused command would leave the plant on its failsafe
        // trim. The actuator saturates long before either limit; a NaN stays NaN and is refused.
        let limited = surfaces.limited(self.ranges);
        let [a, e, r] = self.surfaces;
        (command[a], command[e], command[r]) = (limited.aileron_deg, limited.elevator_deg, limited.rudder_deg);
    }

    fn checkpoint(&self) -> Option<String> {
        let weights: [&Vec<f64>; 3] = std::array::from_fn(|c| &self.controller.networks()[c].weights);
        serde_json::to_string(&weights).ok()
    }

    fn restore(&mut self, saved: &str) -> Result<(), String> {
        let weights =
            serde_json::from_str::<[Vec<f64>; 3]>(saved).map_err(|e| format!("not three lists of RBF weights: {e}"))?;
        self.controller.set_weights(&weights)
    }
}
