//! The quadrotor as the plant process flies it: [`QuadPlant`], the [`PlantModel`] over the model's
//! [`QuadVehicle`] (`[plant] model = "quad"`), with the rig's actuators and sensor faults on its named signals
//! ([`SignalChain`], as for a plant of your own) and its state as the checkpoint a restarted plant resumes from.

use serde::{Deserialize, Serialize};
use silrig_flight::quad::{check_for_quad, quad_signals, quad_vehicle};
use silrig_flight::scenario::Scenario;
use silrig_flight::signal_chain::SignalChain;
use silrig_flight::signals::PlantSignals;
use silrig_model::quad::outputs::{INPUT_RANGE, quad_outputs};
use silrig_model::quad::{QUAD_STATE_LEN, QuadVehicle};
use silrig_rig::plant_model::{ActuatorFlags, PlantModel};

/// The scenario's quadrotor at its start, behind the rig's actuators and sensors.
pub struct QuadPlant {
    vehicle: QuadVehicle,
    chain: SignalChain,
    signals: PlantSignals,
    initial_inputs: Vec<f64>,
    /// The outputs of the current tick as the sensors report them (measured once a tick: sensor noise draws).
    measured: Vec<f64>,
    tick: u64,
    dt_s: f64,
}

/// What a restarted quadrotor resumes from.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct QuadCheckpoint {
    tick: u64,
    state: Vec<f64>,
    on_ground: bool,
    motor_commands: [f64; 4],
    touchdown_speed_mps: f64,
    /// The rig's actuator positions, one per input.
    positions: Vec<f64>,
}

impl QuadPlant {
    /// The scenario's quadrotor (on the ground or hovering, as `[plant.parameters]` says); an error names the key.
    pub fn new(scenario: &Scenario) -> anyhow::Result<Self> {
        let said = |(key, problem): (String, String)| anyhow::anyhow!("the scenario: `{key}`: {problem}");
        check_for_quad(scenario).map_err(said)?;
        let vehicle = quad_vehicle(scenario).map_err(said)?;
        let signals = quad_signals(&vehicle.params);
        let initial_inputs = vehicle.motor_commands.to_vec();
        let chain = SignalChain::new(scenario, &signals, &initial_inputs).map_err(said)?;
        let mut plant =
            Self { vehicle, chain, measured: Vec::new(), signals, initial_inputs, tick: 0, dt_s: scenario.timing.dt_s };
        plant.measure();
        Ok(plant)
    }

    fn measure(&mut self) {
        self.measured = quad_outputs(&self.vehicle).to_vec();
        let t_s = self.t_s();
        self.chain.measure(t_s, &mut self.measured);
    }
}

impl PlantModel for QuadPlant {
    fn signals(&self) -> &PlantSignals {
        &self.signals
    }

    fn tick(&self) -> u64 {
        self.tick
    }

    fn t_s(&self) -> f64 {
        self.tick as f64 * self.dt_s
    }

    fn outputs(&self) -> Vec<f64> {
        self.measured.clone()
    }

    fn initial_inputs(&self) -> Vec<f64> {
        self.initial_inputs.clone()
    }

    /// A motor counts as saturated when its command sits at either end of 0..1 (stopped or at full speed), or the
    /// rig's actuator holds it on a limit.
    fn step(&mut self, inputs: &[f64], last: bool) -> Result<ActuatorFlags, String> {
        let hits = self.chain.actuate(self.t_s(), inputs);
        let positions = self.chain.positions();
        let at_stop = positions.iter().any(|p| *p <= INPUT_RANGE.0 || *p >= INPUT_RANGE.1);
        let flags = ActuatorFlags { saturated: hits.position || at_stop, rate_limited: hits.rate };
        if last {
            return Ok(flags);
        }
        self.vehicle.command(std::array::from_fn(|k| positions[k]));
        self.vehicle.step(self.dt_s);
        self.tick += 1;
        self.measure();
        Ok(flags)
    }

    fn checkpoint(&self) -> Option<String> {
        let v = &self.vehicle;
        let saved = QuadCheckpoint {
            tick: self.tick,
            state: v.state.x.to_vec(),
            on_ground: v.on_ground,
            motor_commands: v.motor_commands,
            touchdown_speed_mps: v.touchdown_speed_mps,
            positions: self.chain.positions().to_vec(),
        };
        serde_json::to_string(&saved).ok()
    }

    fn restore(&mut self, text: &str, ticks: u64) -> Result<u64, String> {
        let c = serde_json::from_str::<QuadCheckpoint>(text).map_err(|e| format!("not a quadrotor checkpoint: {e}"))?;
        if c.tick >= ticks {
            return Err(format!("tick {} is beyond the run's {ticks} ticks", c.tick));
        }
        let state: [f64; QUAD_STATE_LEN] = c.state.as_slice().try_into().map_err(|_| {
            format!("the saved state has {} numbers; the quadrotor's has {QUAD_STATE_LEN}", c.state.len())
        })?;
        if let Some(v) = state.iter().chain(&c.motor_commands).chain(&c.positions).find(|v| !v.is_finite()) {
            return Err(format!("the saved state holds {v}, not a finite number"));
        }
        if c.positions.len() != self.signals.inputs.len() {
            return Err(format!("the saved state has {} actuator positions; the quadrotor has 4", c.positions.len()));
        }
        self.vehicle.state.x = state;
        self.vehicle.on_ground = c.on_ground;
        self.vehicle.motor_commands = c.motor_commands;
        self.vehicle.touchdown_speed_mps = c.touchdown_speed_mps;
        self.chain.set_positions(&c.positions);
        self.tick = c.tick;
        self.measure();
        Ok(c.tick)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_model::quad::outputs::output_index;

    fn scenario(parameters: &str) -> Scenario {
        let text = format!(
            "name = \"q\"\n[plant]\nmodel = \"quad\"\n[plant.parameters]\n{parameters}\n[timing]\ndt_s = 0.001\n\
             duration_s = 2.0\ncommand_timing = \"same-tick\"\n"
        );
        Scenario::from_toml(&text, "test").unwrap()
    }

    fn at(plant: &QuadPlant, name: &str) -> f64 {
        plant.outputs()[output_index(name).unwrap()]
    }

    #[test]
    fn it_rests_on_the_ground_and_climbs_on_full_motors() {
        let mut plant = QuadPlant::new(&scenario("")).unwrap();
        assert_eq!(plant.initial_inputs(), vec![0.0; 4]);
        let flags = plant.step(&[0.0; 4], false).unwrap();
        assert!(flags.saturated, "stopped motors sit at their stop");
        assert_eq!((at(&plant, "alt_m"), at(&plant, "on_ground")), (0.0, 1.0));
        for _ in 0..300 {
            assert!(!plant.step(&[0.9; 4], false).unwrap().saturated);
        }
        assert!(at(&plant, "alt_m") > 0.05 && at(&plant, "on_ground") == 0.0 && at(&plant, "vd_mps") < 0.0);
        assert_eq!(plant.tick(), 301);
        assert!((plant.t_s() - 0.301).abs() < 1e-12);
    }

    #[test]
    fn hovering_it_holds_with_the_failsafe_command_and_resumes_from_its_checkpoint() {
        let mut plant = QuadPlant::new(&scenario("start_alt_m = 3.0")).unwrap();
        let hold = plant.signals().hold();
        assert_eq!(plant.initial_inputs(), hold);
        for _ in 0..500 {
            plant.step(&hold, false).unwrap();
        }
        assert!((at(&plant, "alt_m") - 3.0).abs() < 1e-6, "{}", at(&plant, "alt_m"));
        let saved = plant.checkpoint().unwrap();
        let mut resumed = QuadPlant::new(&scenario("start_alt_m = 3.0")).unwrap();
        assert_eq!(resumed.restore(&saved, 2000), Ok(500));
        let climb = [0.6; 4];
        plant.step(&climb, false).unwrap();
        resumed.step(&climb, false).unwrap();
        assert_eq!(plant.outputs(), resumed.outputs());
        let e = resumed.restore(&saved, 400).unwrap_err();
        assert!(e.contains("tick 500 is beyond the run's 400 ticks"), "{e}");
        let e = resumed.restore(&saved.replace("\"tick\"", "\"tock\""), 2000).unwrap_err();
        assert!(e.starts_with("not a quadrotor checkpoint"), "{e}");
    }

    #[test]
    fn the_rigs_actuators_and_sensor_faults_act_on_its_signals() {
        let mut s = scenario("start_alt_m = 1.0");
        s.actuators.insert("motor1".into(), silrig_model::actuator::ActuatorLimits::position_only(0.0, 0.5));
        s.faults.push(silrig_flight::fault::parse_fault_flag("plant:sensor-bias@0s,channel=alt_m,bias=2").unwrap());
        let mut plant = QuadPlant::new(&s).unwrap();
        assert!((at(&plant, "alt_m") - 3.0).abs() < 1e-12, "the bias is measured from t = 0");
        assert!(plant.step(&[0.7, 0.5, 0.5, 0.5], false).unwrap().saturated, "motor1 held at its 0.5 stop");
        s.actuators.clear();
        s.actuators.insert("rotor9".into(), silrig_model::actuator::ActuatorLimits::position_only(0.0, 1.0));
        let e = QuadPlant::new(&s).err().unwrap().to_string();
        assert!(e.contains("`actuators.rotor9`: plant quad has no input `rotor9`; its inputs: motor1"), "{e}");
    }
}
