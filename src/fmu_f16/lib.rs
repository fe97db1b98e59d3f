//! silrig-fmu-f16: the built-in F-16 (with its actuators, trim and parameters) as an FMI 2.0 co-simulation FMU,
//! over `silrig-model` alone. One `fmi2DoStep` is one tick of the rig's plant: the actuators move under the inputs
//! and RK4 integrates the step with their positions held, with the very code `silrig sim` and the plant process
//! fly ([`silrig_model::vehicle::F16Vehicle`]), so the outputs are the built-in plant's, bit for bit.
//!
//! - [`variables`], [`description`]: what the FMU is (from `silrig-fmu-f16-description`, which `silrig export-fmu`
//!   shares).
//! - [`instance`]: one instance in safe Rust (FMI's phases, values, stepping, saved and serialised states).
//! - `ffi`: the `fmi2*` C functions of the shared library, the crate's only unsafe code.
//!
//! `silrig export-fmu` (in `silrig-tools`) packs the shared library this crate builds with the description.

#![deny(unsafe_code)]

#[allow(unsafe_code)]
mod ffi;
pub mod instance;

pub use silrig_fmu_f16_description::{description, variables};
