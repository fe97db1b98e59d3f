//! silrig-flight: a closed-loop flight as data and as one deterministic process: what to fly, what may go wrong,
//! how it went and whether that was good enough. Files yes, IPC and clocks no.
//!
//! - [`scenario`]: TOML scenarios (initial condition, set points, [`disturbance`], plant and controller options,
//!   actuator limits, [`timing`]) with `validate`; [`setpoints`]: `[setpoint]` and the steps that change it during
//!   a run, the value in force at a time; [`fault`]: the fault plan as data, targeting a [`role`] (a rig process); [`dispersion`]: seeded per-key distributions for sweeps; [`controller_map`]: `[controller.map]`'s
//!   values (a plant signal or a constant).
//! - [`sim`]: the single-process loop (plant, actuators, controller in lockstep), whose pieces the rig's processes
//!   reuse so both give the same trace; [`trace`]: the trace rows and `trace.csv`.
//! - [`signals`]: a plant's named signals as data (what it announces, the checks, lookups by name, the trace's
//!   columns of any plant); [`f16_signals`]: the F-16's table, and its snapshot read back by name;
//!   [`signal_chain`]: the rig's actuators and sensor faults on the named signals of a plant of your own;
//!   [`quad`]: the built-in quadrotor as a scenario flies it (`[plant] model = "quad"`).
//! - [`summary`]: control-quality figures; [`f_true`]: the true lumped function the RBF networks estimate;
//!   [`criteria`] and [`judge`]: pass/fail criteria and how a flight is judged against them.
//! - [`files`]: writing a run's files without ever leaving a torn one.
//!
//! Layers: uses `silrig-model` only.

pub mod controller_map;
pub mod criteria;
pub mod dispersion;
pub mod disturbance;
pub mod f16_signals;
pub mod f_true;
pub mod fault;
pub mod files;
pub mod judge;
pub mod quad;
pub mod role;
pub mod scenario;
pub mod setpoints;
pub mod signal_chain;
pub mod signals;
pub mod sim;
pub mod summary;
pub mod timing;
pub mod trace;
