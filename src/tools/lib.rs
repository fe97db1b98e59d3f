//! silrig-tools: the tools built on the rig, each a subcommand of `silrig`.
//!
//! - [`check`]: a verdict a CI pipeline can gate on (suites, criteria, JUnit); [`campaign`]: sweeps of dispersed
//!   cases (plan, run, shard, merge, Slurm).
//! - [`replay`]: a recorded flight fed to a controller, commands compared; [`bench`]: model micro-benchmarks and the
//!   transport's ceiling.
//! - [`contract`]: the wire contract rendered as text, a C header and a Python module.
//! - [`outputs`]: `silrig sim` and `silrig compare` and the files they write; [`derivative_csv`]:
//!   `silrig plant derivative`.
//! - [`export_fmu`]: `silrig export-fmu`, the built-in F-16 or quadrotor as an FMI 2.0 co-simulation FMU.
//! - [`html`]: `report.html`, one self-contained page per run, check and sweep.
//! - [`new_project`]: `silrig new`, a controller or plant of the user's own started from the examples.
//! - [`soak`]: `silrig soak`, a long realtime run under faults drawn from a seed, and its figures.
//!
//! Layers: the top; uses every crate below.

pub mod bench;
pub mod campaign;
pub mod check;
pub mod contract;
pub mod derivative_csv;
pub mod export_fmu;
pub mod html;
pub mod new_project;
pub mod outputs;
pub mod replay;
pub mod soak;
