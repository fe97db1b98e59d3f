//! The rig's actuators and sensors around a plant of your own: the scenario's `[actuators.<input>]` (lag, rate
//! and position limits) and actuator faults (stuck, hard-over, rate-frozen) on named inputs, sensor noise and bias
//! on named outputs. The built-in F-16 models its own inside [`crate::sim::PlantRunner`]; a plant that only
//! announces signals gets the same models here, between the command and the model's inputs and between the
//! model's outputs and the sample the controller reads. Pure: no I/O, no clock; the caller supplies the step.

use crate::fault::{Fault, FaultAction};
use crate::scenario::Scenario;
use crate::signals::PlantSignals;
use silrig_model::actuator::{Actuator, ActuatorFault, ActuatorLimits, LimitHits};
use silrig_model::rng::SplitMix64;

/// Seed offset of the sensor-noise stream, so it never repeats another random source seeded from the scenario.
const SENSOR_NOISE_STREAM: u64 = 0x5EA5_0125;

/// A sensor fault resolved to its output.
#[derive(Debug, Clone)]
struct SensorFault {
    fault: Fault,
    output: usize,
    bias: f64,
    noise_std: f64,
}

/// An actuator fault resolved to its input.
#[derive(Debug, Clone)]
struct InputFault {
    fault: Fault,
    input: usize,
    mode: ActuatorFault,
}

/// The actuators and sensors the rig models for one plant.
#[derive(Debug, Clone)]
pub struct SignalChain {
    dt_s: f64,
    /// One per input: the scenario's actuator, a position-only one over the announced range where only a fault
    /// needs one, or none (the command passes through).
    actuators: Vec<Option<Actuator>>,
    /// What the model is stepped with: the actuators' positions, or the commands where there is no actuator.
    positions: Vec<f64>,
    sensor_faults: Vec<SensorFault>,
    input_faults: Vec<InputFault>,
    noise: SplitMix64,
}

impl SignalChain {
    /// The chain for `plant` under `scenario`, its actuators resting at `initial_inputs`. Names that the plant does
    /// not have, and actuator limits outside an input's announced range, are errors: (dotted key, problem naming
    /// the plant's list).
    pub fn new(scenario: &Scenario, plant: &PlantSignals, initial_inputs: &[f64]) -> Result<Self, (String, String)> {
        let input_names: Vec<&str> = plant.inputs.iter().map(|i| i.name.as_str()).collect();
        let output_names: Vec<&str> = plant.outputs.iter().map(|o| o.name.as_str()).collect();
        let mut actuators: Vec<Option<Actuator>> = vec![None; plant.inputs.len()];
        for (name, limits) in &scenario.actuators {
            let Some(k) = input_names.iter().position(|n| n == name) else {
                return Err((
                    format!("actuators.{name}"),
                    format!("plant {} has no input `{name}`; its inputs: {}", plant.plant, input_names.join(", ")),
                ));
            };
            let input = &plant.inputs[k];
            limits.validate((input.min, input.max)).map_err(|e| {
                (format!("actuators.{name}"), format!("{e} (the announced range of input {name} {})", input.unit))
            })?;
            actuators[k] = Some(Actuator::new(*limits, initial_inputs[k]));
        }
        // A set point is in an output's own unit, so it must name one (the attitude our controller flies excepted:
        // it is always there, 0 when not given); a device's layout may also send set points that are no output
        // (Betaflight's sticks, `rc_*`), and its binding names any it does not find.
        let device = scenario.controller.device.is_some();
        if let Some(name) = scenario.setpoint.outputs.keys().find(|n| !device && !output_names.contains(&n.as_str())) {
            return Err((
                format!("setpoint.{name}"),
                format!("plant {} has no output `{name}`; its outputs: {}", plant.plant, output_names.join(", ")),
            ));
        }
        let plant_label = format!("plant {}", plant.plant);
        let (mut sensor_faults, mut input_faults) = (Vec::new(), Vec::new());
        for (i, f) in scenario.faults.iter().enumerate() {
            if !f.action().is_plant_model_fault() {
                continue;
            }
            let at = |(key, problem): (String, String)| (format!("faults[{i}].{key}"), problem);
            f.validate(scenario.timing.duration_s).map_err(at)?;
            f.check_names(&plant_label, &output_names, &input_names).map_err(at)?;
            if let Some(channel) = &f.channel {
                let output = output_names.iter().position(|n| n == channel).expect("checked above");
                let (bias, noise_std) = match f.action() {
                    FaultAction::SensorBias => (f.bias.unwrap_or(0.0), 0.0),
                    _ => (0.0, f.std.unwrap_or(0.0)),
                };
                sensor_faults.push(SensorFault { fault: f.clone(), output, bias, noise_std });
            }
            if let Some(surface) = &f.surface {
                let input = input_names.iter().position(|n| n == surface).expect("checked above");
                let mode = match f.action() {
                    FaultAction::ActuatorStuck => ActuatorFault::Stuck,
                    FaultAction::ActuatorRateFrozen => ActuatorFault::RateFrozen,
                    _ => ActuatorFault::HardOver { to_max: f.limit.as_deref() == Some("max") },
                };
                // A fault needs an actuator to act on: without `[actuators.<input>]` the input's announced range
                // is its travel, with no lag and no rate limit (a hard-over is then instant).
                let range = &plant.inputs[input];
                actuators[input].get_or_insert_with(|| {
                    Actuator::new(ActuatorLimits::position_only(range.min, range.max), initial_inputs[input])
                });
                input_faults.push(InputFault { fault: f.clone(), input, mode });
            }
        }
        let positions =
            actuators.iter().zip(initial_inputs).map(|(a, v)| a.as_ref().map_or(*v, |a| a.position)).collect();
        Ok(Self {
            dt_s: scenario.timing.dt_s,
            actuators,
            positions,
            sensor_faults,
            input_faults,
            noise: SplitMix64::new(scenario.seed ^ SENSOR_NOISE_STREAM),
        })
    }

    /// Whether the chain changes nothing (no actuator, no fault): the model sees the commands and the controller
    /// the model's outputs.
    pub fn is_transparent(&self) -> bool {
        self.actuators.iter().all(Option::is_none) && self.sensor_faults.is_empty()
    }

    /// The outputs as the controller measures them at `t_s`: each active sensor fault's bias or noise added.
    pub fn measure(&mut self, t_s: f64, outputs: &mut [f64]) {
        for f in &self.sensor_faults {
            if f.fault.active_at(t_s) {
                outputs[f.output] += f.bias + f.noise_std * self.noise.normal();
            }
        }
    }

    /// Move the actuators under `commanded` over the step that starts at `t_s`; [`Self::positions`] then holds
    /// what the model is stepped with. Returns whether any actuator sat on a position limit or moved at its rate
    /// limit. Where fault windows overlap on one input, the fault that started last wins (the later entry on a
    /// tie), as on the F-16.
    pub fn actuate(&mut self, t_s: f64, commanded: &[f64]) -> LimitHits {
        let mut hits = LimitHits::default();
        for (k, actuator) in self.actuators.iter_mut().enumerate() {
            let Some(a) = actuator else {
                self.positions[k] = commanded[k];
                continue;
            };
            let mut mode = ActuatorFault::None;
            let mut since = f64::NEG_INFINITY;
            for f in self.input_faults.iter().filter(|f| f.input == k && f.fault.active_at(t_s)) {
                if f.fault.at_s >= since {
                    (mode, since) = (f.mode, f.fault.at_s);
                }
            }
            let h = a.update_with_fault(commanded[k], self.dt_s, mode);
            hits.rate |= h.rate;
            hits.position |= h.position;
            self.positions[k] = a.position;
        }
        hits
    }

    /// Put the actuators where a checkpoint found them (a restarted plant), one position per input.
    pub fn set_positions(&mut self, positions: &[f64]) {
        for ((a, p), v) in self.actuators.iter_mut().zip(&mut self.positions).zip(positions) {
            *p = *v;
            if let Some(a) = a {
                a.position = v.clamp(a.limits.min, a.limits.max);
            }
        }
    }

    /// What the model is stepped with over the current step, one per input.
    pub fn positions(&self) -> &[f64] {
        &self.positions
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fault::parse_fault_flag;
    use crate::signals::{InputSignal, OutputSignal};

    fn plant() -> PlantSignals {
        let output = |name: &str| OutputSignal { name: name.into(), unit: "m".into(), in_trace: true };
        let input = |name: &str| InputSignal {
            name: name.into(),
            unit: "1".into(),
            min: -1.0,
            max: 1.0,
            hold: 0.0,
            held_output: None,
            command_in_trace: true,
        };
        PlantSignals {
            plant: "toy".into(),
            outputs: vec![output("x"), output("v")],
            inputs: vec![input("u"), input("w")],
        }
    }

    fn scenario(extra: &str) -> Scenario {
        let text =
            format!("name = \"t\"\n[timing]\ndt_s = 0.01\nduration_s = 2.0\ncommand_timing = \"next-tick\"\n{extra}");
        Scenario::from_toml(&text, "test").unwrap()
    }

    #[test]
    fn without_actuators_or_faults_the_chain_is_transparent() {
        let mut c = SignalChain::new(&scenario(""), &plant(), &[0.0, 0.0]).unwrap();
        assert!(c.is_transparent());
        assert_eq!(c.actuate(0.0, &[0.7, -0.3]), LimitHits::default());
        assert_eq!(c.positions(), &[0.7, -0.3]);
        let mut y = [1.0, 2.0];
        c.measure(0.0, &mut y);
        assert_eq!(y, [1.0, 2.0]);
    }

    #[test]
    fn a_named_actuator_limits_the_rate_and_position_of_its_input_only() {
        let s = scenario("[actuators.u]\nmin = -0.5\nmax = 0.5\nrate_limit_per_s = 10.0\n");
        let mut c = SignalChain::new(&s, &plant(), &[0.0, 0.0]).unwrap();
        let hits = c.actuate(0.0, &[1.0, 0.9]);
        // 10 per s over 0.01 s: 0.1 of travel a step; w passes through.
        assert!(hits.rate);
        assert!((c.positions()[0] - 0.1).abs() < 1e-12);
        assert_eq!(c.positions()[1], 0.9);
        for k in 1..10 {
            c.actuate(k as f64 * 0.01, &[1.0, 0.9]);
        }
        assert_eq!(c.positions()[0], 0.5);
        assert!(c.actuate(0.1, &[1.0, 0.9]).position);
    }

    #[test]
    fn faults_act_on_named_signals_in_their_windows() {
        let mut s = scenario("");
        for flag in
            ["plant:sensor-bias@0.5s,channel=v,bias=2.0,for=0.5s", "plant:actuator-hard-over@1s,surface=w,limit=min"]
        {
            s.faults.push(parse_fault_flag(flag).unwrap());
        }
        let mut c = SignalChain::new(&s, &plant(), &[0.0, 0.25]).unwrap();
        let mut y = [1.0, 1.0];
        c.measure(0.4, &mut y);
        assert_eq!(y, [1.0, 1.0]);
        c.measure(0.5, &mut y);
        assert_eq!(y, [1.0, 3.0]);
        c.actuate(0.99, &[0.0, 0.5]);
        assert_eq!(c.positions()[1], 0.5);
        // No `[actuators.w]`: the announced range is the travel and a hard-over is instant.
        c.actuate(1.0, &[0.0, 0.5]);
        assert_eq!(c.positions()[1], -1.0);
    }

    #[test]
    fn names_the_plant_lacks_are_refused_with_its_list() {
        let s = scenario("[actuators.flap]\nmin = 0.0\nmax = 1.0\n");
        let e = SignalChain::new(&s, &plant(), &[0.0, 0.0]).unwrap_err();
        assert_eq!(e.0, "actuators.flap");
        assert!(e.1.contains("plant toy has no input `flap`; its inputs: u, w"), "{}", e.1);
        let s = scenario("[setpoint]\naltitude = 3.0\n");
        let e = SignalChain::new(&s, &plant(), &[0.0, 0.0]).unwrap_err();
        assert_eq!(e.0, "setpoint.altitude");
        assert!(e.1.contains("plant toy has no output `altitude`; its outputs: x, v"), "{}", e.1);
        let s = scenario("[actuators.u]\nmin = -2.0\nmax = 1.0\n");
        let e = SignalChain::new(&s, &plant(), &[0.0, 0.0]).unwrap_err();
        assert!(e.1.contains("within -1..1") && e.1.contains("announced range of input u"), "{}", e.1);
        let mut s = scenario("");
        s.faults.push(parse_fault_flag("plant:sensor-noise@0.5s,channel=altitude,std=1").unwrap());
        let e = SignalChain::new(&s, &plant(), &[0.0, 0.0]).unwrap_err();
        assert_eq!(e.0, "faults[0].channel");
        assert!(e.1.contains("plant toy has no channel \"altitude\"; one of x, v"), "{}", e.1);
    }
}
