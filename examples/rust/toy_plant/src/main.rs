//! A plant of your own in Rust: the toy of `examples/python/toy_plant.py` and `examples/c/toy_plant.c`, three
//! decoupled rotational axes (roll, pitch, yaw), each a damped double integrator driven by its surface with the
//! F-16's sign convention and signal names, so the example PID flies it. It announces its signals and hands its
//! outputs to silrig's plant session each tick, which gives it the rig's clock, actuators, faults, watchdog and
//! failsafe, logger and report.
//!
//!     cargo build --release && silrig run --plant-cmd target/release/toy_plant \
//!         --controller-cmd "python3 pid.py" scenario.toml

use silrig_flight::signals::{InputSignal, OutputSignal, PlantSignals};
use silrig_rig::ProcessArgs;
use silrig_rig::plant_session::{PlantSession, PlantTick};
use std::process::ExitCode;

/// Angular acceleration per deg of surface, deg/s^2.
const GAIN_DPS2_PER_DEG: f64 = 4.0;
/// Rate damping, 1/s.
const DAMPING_PER_S: f64 = 1.0;

fn signals() -> PlantSignals {
    let output = |name: &str, unit: &str| OutputSignal { name: name.into(), unit: unit.into(), in_trace: true };
    let surface = |name: &str, position: usize| InputSignal {
        name: name.into(),
        unit: "deg".into(),
        min: -30.0,
        max: 30.0,
        hold: 0.0,
        held_output: Some(position),
        command_in_trace: true,
    };
    let mut outputs: Vec<OutputSignal> = ["phi_deg", "theta_deg", "psi_deg"].map(|n| output(n, "deg")).into();
    outputs.extend(["p_dps", "q_dps", "r_dps"].map(|n| output(n, "deg/s")));
    outputs.extend(["aileron_deg", "elevator_deg", "rudder_deg"].map(|n| output(n, "deg")));
    let inputs = vec![surface("aileron", 6), surface("elevator", 7), surface("rudder", 8)];
    PlantSignals { plant: "toy".into(), outputs, inputs }
}

fn fly(args: &ProcessArgs) -> anyhow::Result<silrig_rig::report::ProcessReport> {
    let mut session = PlantSession::open(args.clone(), args.scenario()?, &signals())?;
    let dt_s = session.dt_s();
    let (mut angle_deg, mut rate_dps, mut surface_deg) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    loop {
        let outputs: Vec<f64> = angle_deg.iter().chain(&rate_dps).chain(&surface_deg).copied().collect();
        let inputs = match session.tick(&outputs)? {
            PlantTick::Inputs(inputs) => inputs,
            PlantTick::RunEnded | PlantTick::Stopped => break,
        };
        for c in 0..3 {
            surface_deg[c] = inputs[c];
            rate_dps[c] += (-GAIN_DPS2_PER_DEG * inputs[c] - DAMPING_PER_S * rate_dps[c]) * dt_s;
            angle_deg[c] += rate_dps[c] * dt_s;
        }
    }
    session.finish(None)
}

fn main() -> ExitCode {
    // The launcher hands the run over in SILRIG_* variables (`silrig run --plant external` prints them).
    let args = match ProcessArgs::from_env(std::env::vars()) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("toy_plant: {e}");
            return ExitCode::from(2);
        }
    };
    let run = fly(&args);
    silrig_rig::finish_process("plant", &args, run)
}
