//! silrig-fmu-f16: the built-in F-16 (with its actuators, trim and parameters) as an FMI 2.0 co-simulation FMU,
//! over `silrig-model` alone; the same library is the quadrotor's FMU too (packed as `silrig_fmu_quad.so`, its
//! start file saying which vehicle to fly), so both share one FMI glue. One `fmi2DoStep` is one tick of the rig's
//! plant, flown with the very code `silrig sim` and the plant process fly ([`silrig_model::vehicle::F16Vehicle`]:
//! the actuators move under the inputs, then RK4 with their positions held; [`silrig_model::quad::QuadVehicle`]),
//! so the outputs are the built-in plant's, bit for bit.
//!
//! - [`variables`], [`description`]: what the FMU is (from `silrig-fmu-f16-description`, which `silrig export-fmu`
//!   shares).
//! - [`instance`]: one instance in safe Rust (FMI's phases, values, stepping, saved and serialised states), for
//!   either vehicle of [`models`] (what each says, builds, steps and saves).
//! - `ffi`: the `fmi2*` C functions of the shared library, the crate's only unsafe code.
//!
//! `silrig export-fmu` (in `silrig-tools`) packs the shared library this crate builds with the description.

#![deny(unsafe_code)]

#[allow(unsafe_code)]
mod ffi;
pub mod instance;
pub mod models;

pub use silrig_fmu_f16_description::{description, variables};
