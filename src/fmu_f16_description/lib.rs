//! silrig-fmu-f16-description: what the F-16 FMU (and the quadrotor's, [`quad`]) is, apart from its binary, so that the binary
//! (`silrig-fmu-f16`, a cdylib) and `silrig export-fmu` share it without linking each other: a crate that is both a
//! cdylib and an rlib is written to one unhashed file that every build context overwrites, and the crates linked
//! against an earlier one no longer load.
//!
//! - [`variables`]: the variables (the rig's outputs and inputs, the parameters named after their scenario keys)
//!   and the parameters' start values as text.
//! - [`description`]: `modelDescription.xml`, generated, with a GUID hashed from its content.
//! - [`quad`]: the same for the quadrotor, whose FMU the same binary serves.

#![forbid(unsafe_code)]

pub mod description;
pub mod quad;
pub mod variables;
