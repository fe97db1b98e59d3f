//! silrig-adapters: what turns a foreign or built-in thing into a plant or a controller of the rig, behind the
//! rig's [`silrig_rig::plant_model::PlantModel`] and [`silrig_rig::controller::Controller`] traits. Each adapter is
//! a folder or a file:
//!
//! - [`builtin`]: the built-in F-16 as a plant model and our law (the paper's adaptive SMC/RBF) as a controller.
//! - [`fmu`]: a co-simulation FMU as the plant or the controller, and what the two share.
//! - [`udp`]: a device reached over UDP with its packet layouts declared in a file (Betaflight's SITL ships with
//!   silrig as `configs/devices/betaflight-sitl.toml`).
//! - [`in_process`]: any of these plants against any of these controllers in one process, no clock and no
//!   transport (what `silrig sim`, `sweep` and `check --in-process` fly FMUs with).
//! - [`process`]: which adapter `silrig-plant` and `silrig-controller` fly, a match on the scenario's plant and
//!   controller kind; a new adapter is one arm there.
//!
//! Layers: above `silrig-rig`, whose process bodies and sessions fly whatever plant model or controller they are
//! handed and do not know which adapter that is; `silrig-launch` uses the FMU adapters' checks before a run.

pub mod builtin;
pub mod fmu;
pub mod in_process;
pub mod process;
pub mod udp;
