//! A PID attitude controller in Rust: the "bring your own controller" example for Rust, the law of
//! `examples/python/pid_attitude.py` with the F-16's gains. Each channel is a PID on the Euler angle error with the
//! body rate as the derivative: roll on the aileron, pitch on the elevator, yaw on the rudder (Stevens & Lewis
//! signs: a positive deflection makes a negative moment). Its integrators start from the surfaces' positions at the
//! first step, so taking over is bumpless. It implements silrig's `Controller` trait; `serve` gives it the run's
//! session (transport, clock, faults, checkpoints, report), as `silrig-controller` has.
//!
//!     cargo build --release && silrig run --controller-cmd target/release/pid_controller

use silrig_flight::setpoints::SetpointTrack;
use silrig_flight::signals::PlantSignals;
use silrig_rig::ProcessArgs;
use silrig_rig::controller::{Controller, serve};
use silrig_wire::wire::PlantSample;
use std::process::ExitCode;

/// Per channel (aileron, elevator, rudder): deg of surface per deg of error, per deg/s of rate, per deg*s of
/// integral, and the travel each command is kept within, deg.
const KP: [f64; 3] = [2.0, 4.0, 8.0];
const KD: [f64; 3] = [0.6, 1.5, 3.0];
const KI: [f64; 3] = [1.5, 3.0, 8.0];
const TRAVEL_DEG: [f64; 3] = [21.5, 25.0, 30.0];
const ANGLES: [&str; 3] = ["phi_deg", "theta_deg", "psi_deg"];
const RATES: [&str; 3] = ["p_dps", "q_dps", "r_dps"];
const INPUTS: [&str; 3] = ["aileron", "elevator", "rudder"];

struct Pid {
    /// phi, theta and psi's set points over the run, deg (a scenario's `[[setpoint_steps]]` change them).
    setpoint_deg: [SetpointTrack; 3],
    /// Where the plant's angles, rates and surfaces are in its sample and command, found by name at connect.
    angles: [usize; 3],
    rates: [usize; 3],
    inputs: [usize; 3],
    /// The command each integrator carries (None until the first step).
    integral_deg: Option<[f64; 3]>,
}

impl Controller for Pid {
    fn diagnostic_names(&self) -> Vec<String> {
        ["err_phi_deg", "err_theta_deg", "err_psi_deg"].map(String::from).to_vec()
    }

    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String> {
        for c in 0..3 {
            self.angles[c] = plant.output(ANGLES[c])?;
            self.rates[c] = plant.output(RATES[c])?;
            self.inputs[c] = plant.input(INPUTS[c])?;
        }
        Ok(())
    }

    fn step(&mut self, sample: &PlantSample, dt_s: f64, command: &mut [f64], diagnostics: &mut [f64]) {
        let outputs = sample.outputs();
        let held = self.inputs.map(|k| command[k]);
        let integral_deg = self.integral_deg.get_or_insert(held);
        for c in 0..3 {
            let error_deg = self.setpoint_deg[c].at(sample.t_sim_s) - outputs[self.angles[c]];
            let rate_dps = outputs[self.rates[c]];
            let integral = integral_deg[c] - KI[c] * error_deg * dt_s;
            let surface = integral - KP[c] * error_deg + KD[c] * rate_dps;
            // Anti-windup: an integrator pushing a surface past its travel stops integrating.
            if surface.abs() <= TRAVEL_DEG[c] || integral.abs() < integral_deg[c].abs() {
                integral_deg[c] = integral;
            }
            let surface = integral_deg[c] - KP[c] * error_deg + KD[c] * rate_dps;
            command[self.inputs[c]] = surface.clamp(-TRAVEL_DEG[c], TRAVEL_DEG[c]);
            diagnostics[c] = error_deg;
        }
    }
}

fn main() -> ExitCode {
    // The launcher hands the run over in SILRIG_* variables (`silrig run --controller external` prints them).
    let args = match ProcessArgs::from_env(std::env::vars()) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("pid_controller: {e}");
            return ExitCode::from(2);
        }
    };
    let run = args.scenario().and_then(|scenario| {
        let setpoint_deg = scenario.attitude_setpoints();
        let pid = Pid { setpoint_deg, angles: [0; 3], rates: [0; 3], inputs: [0; 3], integral_deg: None };
        serve(&args, scenario, Box::new(pid))
    });
    silrig_rig::finish_process("controller", &args, run)
}
