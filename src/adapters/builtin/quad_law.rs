//! Our quadrotor controller as the rig flies it: [`QuadLaw`], the model's [`QuadController`] (cascaded altitude,
//! attitude and rate loops with the X mixer) behind the [`Controller`] trait, reading the quadrotor's outputs by
//! name and commanding `motor1`..`motor4`; its checkpoint is its integrators. It is tuned for the nominal
//! Hummingbird whatever `[plant.parameters]` says, as a flight computer knows its vehicle only nominally: a sweep
//! over the parameters tests it against vehicles it was not tuned for.

use silrig_flight::quad::{QuadSetpoints, quad_setpoints};
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_model::control::quad::{QuadController, QuadGains, QuadMeasurement};
use silrig_model::quad::params::QuadParams;
use silrig_model::quad::rotors::ROTORS;
use silrig_rig::controller::Controller;
use silrig_wire::wire::PlantSample;

/// The outputs the law reads, in the order [`QuadLaw::measure`] takes them.
const READS: [&str; 8] = ["phi_deg", "theta_deg", "psi_deg", "p_dps", "q_dps", "r_dps", "alt_m", "vd_mps"];

/// The inputs it commands, in motor order.
const MOTORS: [&str; ROTORS] = ["motor1", "motor2", "motor3", "motor4"];

/// Our quadrotor controller with the scenario's set points.
pub struct QuadLaw {
    controller: QuadController,
    /// The set points over the run, read at each sample's time.
    setpoints: QuadSetpoints,
    reads: [usize; READS.len()],
    motors: [usize; ROTORS],
}

impl QuadLaw {
    /// The controller for the scenario's set points (`phi_deg`, `theta_deg`, `psi_deg`, `alt_m`, with their
    /// steps), with empty integrators; an error names the key that gives no set point.
    pub fn new(scenario: &Scenario) -> Result<Self, String> {
        let setpoints = quad_setpoints(scenario).map_err(|(key, problem)| format!("`{key}`: {problem}"))?;
        let controller = QuadController::new(QuadGains::default(), QuadParams::default());
        Ok(Self { controller, setpoints, reads: [0; READS.len()], motors: [0; ROTORS] })
    }

    fn measure(&self, outputs: &[f64]) -> QuadMeasurement {
        let at = |k: usize| outputs[self.reads[k]];
        QuadMeasurement {
            euler_rad: [at(0), at(1), at(2)].map(f64::to_radians),
            body_rates_radps: [at(3), at(4), at(5)].map(f64::to_radians),
            alt_m: at(6),
            vd_mps: at(7),
        }
    }
}

impl Controller for QuadLaw {
    fn diagnostic_names(&self) -> Vec<String> {
        Vec::new()
    }

    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String> {
        for (slot, name) in self.reads.iter_mut().zip(READS) {
            *slot = plant.output(name)?;
        }
        for (slot, name) in self.motors.iter_mut().zip(MOTORS) {
            *slot = plant.input(name)?;
        }
        Ok(())
    }

    fn step(&mut self, sample: &PlantSample, dt_s: f64, command: &mut [f64], _diagnostics: &mut [f64]) {
        let m = self.measure(sample.outputs());
        let motors = self.controller.step(&m, &self.setpoints.at(sample.t_sim_s), dt_s);
        for (&input, value) in self.motors.iter().zip(motors) {
            command[input] = value;
        }
    }

    fn checkpoint(&self) -> Option<String> {
        serde_json::to_string(&self.controller.integrators()).ok()
    }

    fn restore(&mut self, saved: &str) -> Result<(), String> {
        let integrators =
            serde_json::from_str::<[f64; 4]>(saved).map_err(|e| format!("not the four integrators: {e}"))?;
        self.controller.set_integrators(integrators)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::quad_plant::QuadPlant;
    use silrig_rig::plant_model::PlantModel;

    fn scenario(body: &str) -> Scenario {
        let text = format!(
            "name = \"q\"\n{body}\n[plant]\nmodel = \"quad\"\n[timing]\ndt_s = 0.001\nduration_s = 4.0\n\
             command_timing = \"same-tick\"\n"
        );
        Scenario::from_toml(&text, "test").unwrap()
    }

    /// Flies `ticks` of the plant against the law, each step answering the tick's sample; the last sample.
    fn fly(plant: &mut QuadPlant, law: &mut QuadLaw, ticks: usize) -> PlantSample {
        let mut command = plant.initial_inputs();
        let mut sample = PlantSample::with_outputs(&plant.outputs());
        for _ in 0..ticks {
            sample = PlantSample::with_outputs(&plant.outputs());
            law.step(&sample, 0.001, &mut command, &mut []);
            plant.step(&command, false).unwrap();
        }
        sample
    }

    #[test]
    fn it_takes_the_quadrotor_off_to_its_altitude_set_point_by_name() {
        let s = scenario("[setpoint]\nalt_m = 1.5\npsi_deg = 20.0");
        let mut plant = QuadPlant::new(&s).unwrap();
        let mut law = QuadLaw::new(&s).unwrap();
        law.connect(plant.signals()).unwrap();
        let last = fly(&mut plant, &mut law, 4000);
        let m = law.measure(last.outputs());
        assert!((m.alt_m - 1.5).abs() < 0.05, "{m:?}");
        assert!((m.euler_rad[2].to_degrees() - 20.0).abs() < 0.5, "{m:?}");
    }

    #[test]
    fn its_checkpoint_resumes_the_integrators_and_refuses_what_is_not_theirs() {
        let s = scenario("[setpoint]\nalt_m = 1.0");
        let mut plant = QuadPlant::new(&s).unwrap();
        let mut law = QuadLaw::new(&s).unwrap();
        law.connect(plant.signals()).unwrap();
        fly(&mut plant, &mut law, 1500);
        let saved = law.checkpoint().unwrap();
        let mut resumed = QuadLaw::new(&s).unwrap();
        resumed.restore(&saved).unwrap();
        assert_eq!(resumed.controller, law.controller);
        assert!(resumed.restore("[1, 2]").unwrap_err().starts_with("not the four integrators"));
        assert!(resumed.restore("[1e999, 0, 0, 0]").is_err());
    }

    #[test]
    fn a_plant_without_its_signals_is_refused_by_name() {
        let mut law = QuadLaw::new(&scenario("")).unwrap();
        let f16 = silrig_flight::f16_signals::f16_signals([0.0; 4]);
        let e = law.connect(&f16).unwrap_err();
        assert!(e.contains("p_dps"), "{e}");
    }
}
