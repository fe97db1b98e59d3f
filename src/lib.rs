//! silrig: a real-time software-in-the-loop rig for flight control. This crate is the facade over the workspace's
//! library crates (in `src/`, one per layer), so the binaries in `bins/` and the tests use one name,
//! `silrig::<module>`, while the compiler keeps the layers apart:
//!
//! - `silrig-model` ([`plant`], [`control`], [`actuator`], [`integrator`], [`units`], [`rng`], [`vehicle`],
//!   [`f16_outputs`]): the math, no I/O.
//! - `silrig-flight` ([`scenario`], [`fault`], [`role`], [`dispersion`], [`sim`], [`trace`], [`summary`],
//!   [`f_true`], [`criteria`], [`judge`], [`files`]): a flight as data and as one deterministic process.
//! - `silrig-wire` ([`wire`], [`topology`], [`ipc`], [`clock`], [`timing`]): the contract and the transport.
//! - `silrig-recording` ([`recording`]): what the logger writes (CSV, MCAP) and replay reads.
//! - `silrig-plot` ([`plot`]): every figure.
//! - `silrig-rig` ([`rig`]): the plant, controller and logger processes and the plant and controller sessions.
//! - `silrig-adapters` ([`adapters`]): what turns the F-16, our law, an FMU or a device into a plant or a
//!   controller, the one-process flight, and which adapter a process flies.
//! - `silrig-launch` ([`launch`]): `silrig run`, supervision, faults, the run's report.
//! - `silrig-tools` ([`check`], [`campaign`], [`replay`], [`bench`], [`contract`], [`outputs`],
//!   [`derivative_csv`], [`export_fmu`], [`html`], [`soak`]): the tools on top.
//! - `silrig-bridge` ([`bridge`], feature `bridge`): the rig's streams between two hosts over Zenoh.

#![warn(missing_docs)]

#[cfg(feature = "bridge")]
pub use silrig_bridge as bridge;

pub use silrig_adapters as adapters;
pub use silrig_flight::{
    criteria, dispersion, f_true, f16_signals, fault, files, judge, role, scenario, signals, sim, summary, trace,
};
pub use silrig_launch as launch;
pub use silrig_model::{actuator, control, f16_outputs, integrator, plant, quad, rng, units, vehicle};
pub use silrig_plot as plot;
pub use silrig_recording as recording;
pub use silrig_rig as rig;
pub use silrig_tools::{
    bench, campaign, check, contract, derivative_csv, export_fmu, html, new_project, outputs, replay, soak,
};
pub use silrig_wire::{clock, ipc, timing, topology, wire};
