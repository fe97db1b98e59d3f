//! silrig-model: the math of the reference pair, with no I/O, no clock, no IPC and no allocation in the loop, so it
//! can be linked alone (by an FMU, a test, another rig) and unit-tested against published numbers.
//!
//! - [`plant`]: the Stevens & Lewis nonlinear 6-DOF F-16 (tables, atmosphere, aero build-up, engine, equations of
//!   motion, flight envelope, trim).
//! - [`control`]: the paper's adaptive sliding-mode attitude controller with one RBF network per channel.
//! - [`actuator`]: surface and throttle actuators (lag, rate and position limits, failure modes).
//! - [`integrator`]: fixed-step RK4, apart from any equations of motion.
//! - [`vehicle`]: the F-16 with its actuators stepped tick by tick (initial condition and trim, RK4, envelope);
//!   [`f16_outputs`]: what it reports and takes, as tables (the snapshot, output and input names, units, ranges).
//! - [`quad`]: the second built-in vehicle, an X quadrotor (rigid body, four rotors with speed dynamics, rotor drag,
//!   ground contact), with its parameters by name and its outputs and inputs as tables.
//! - [`units`]: every unit conversion; [`rng`]: the seeded generator behind every random source.
//!
//! Layers: nothing here knows of scenarios, processes or files (`silrig-flight` and above).

#![forbid(unsafe_code)]

pub mod actuator;
pub mod control;
pub mod f16_outputs;
pub mod integrator;
pub mod plant;
pub mod quad;
pub mod rng;
pub mod units;
pub mod vehicle;
